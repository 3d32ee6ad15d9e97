"""FRF matrices from time histories (through mvtk.signal.frf), merging, conversions."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from mvtk import io, modal
from mvtk.errors import DimensionError, UnitsError

FS, NSEG = 256.0, 512


def _records(msys, rng, refs, resp, n_seg=8):
    """Block-periodic random forces at ``refs`` and exact displacements at ``resp``:
    every ``NSEG``-sample block is one period (circular convolution), so H1 with a
    rectangular window and NSEG-sample segments is exact at every line."""
    M, C, K = msys.chain(4)
    f = np.fft.rfftfreq(NSEG, 1 / FS)
    H = modal.exact_frf(M, C, K, f, resp, refs).values  # (n_resp, n_ref, nf)
    force = rng.standard_normal((len(refs), n_seg * NSEG))
    y = np.zeros((len(resp), n_seg * NSEG))
    for s in range(n_seg):
        F = np.fft.rfft(force[:, s * NSEG:(s + 1) * NSEG], axis=1)
        y[:, s * NSEG:(s + 1) * NSEG] = np.fft.irfft(np.einsum("oif,if->of", H, F), NSEG,
                                                     axis=1)
    data = np.vstack([force, y])
    names = [f"F{r + 1}" for r in refs] + [f"a{o + 1}" for o in resp]
    th = io.time_history(data, FS, names, ["N"] * len(refs) + ["m"] * len(resp),
                         ["force"] * len(refs) + ["displacement"] * len(resp),
                         node=[r + 1 for r in refs] + [o + 1 for o in resp], direction="z")
    return th, M, C, K, f


def _kw():
    return dict(window="boxcar", nperseg=NSEG, noverlap=0, detrend=False)


def test_single_and_multi_reference_h1_exact(msys, rng):
    th, M, C, K, f = _records(msys, rng, refs=[0, 2], resp=[0, 1, 2, 3])
    h = modal.frf_matrix(th, {"quantity": "force"}, **_kw())
    exact = modal.exact_frf(M, C, K, f, [0, 1, 2, 3], [0, 2])
    np.testing.assert_allclose(h.values[..., 1:-1], exact.values[..., 1:-1], rtol=1e-8,
                               atol=1e-14)
    assert h.dims == ("response", "reference", "frequency")
    assert h["node"].values.tolist() == [1, 2, 3, 4]
    assert h["direction"].values.tolist() == ["+z"] * 4
    assert h["reference_node"].values.tolist() == [1, 3]
    assert h.attrs["frf_type"] == "receptance" and h.attrs["estimator"] == "H1"
    assert h.attrs["n_averages"] == 8
    assert h["coherence"].dims == h.dims
    one = modal.frf_matrix(th.isel(channel=[0, 2, 3, 4, 5]), "F1", **_kw())
    assert one.sizes["reference"] == 1


def test_roving_sensor_and_roving_hammer_sets_merge_by_node(msys, rng):
    # roving sensor: hammer fixed at node 1, sensors {1, 2} then {3, 4} with node 1 kept
    a, M, C, K, f = _records(msys, rng, refs=[0], resp=[0, 1])
    b, *_ = _records(msys, rng, refs=[0], resp=[0, 2, 3])
    h = modal.frf_matrix([a, b], {"quantity": "force"}, **_kw())
    assert h["node"].values.tolist() == [1, 2, 3, 4]
    assert h.attrs["n_sets"] == 2 and h.attrs["n_averages"] == 16
    exact = modal.exact_frf(M, C, K, f, [0, 1, 2, 3], [0])
    np.testing.assert_allclose(h.values[..., 1:-1], exact.values[..., 1:-1], rtol=1e-8,
                               atol=1e-14)
    # roving hammer: sensor fixed at node 4, hammer at 1, 2, 3 -> 1 x 3, reciprocal 3 x 1
    sets = [_records(msys, rng, refs=[r], resp=[3])[0] for r in (0, 1, 2)]
    hh = modal.frf_matrix(sets, {"quantity": "force"}, **_kw())
    assert hh.shape[:2] == (1, 3)
    rec = modal.reciprocal(hh)
    assert rec.shape[:2] == (3, 1) and rec["node"].values.tolist() == [1, 2, 3]
    exact = modal.exact_frf(M, C, K, f, [0, 1, 2], [3])
    np.testing.assert_allclose(rec.values[..., 1:-1], exact.values[..., 1:-1], rtol=1e-8,
                               atol=1e-14)


def test_merge_errors_name_the_problem(msys, rng):
    a, *_ = _records(msys, rng, refs=[0], resp=[1])
    b, *_ = _records(msys, rng, refs=[2], resp=[3])
    with pytest.raises(DimensionError, match=r"do not measure 2 response/reference pair"):
        modal.frf_matrix([a, b], {"quantity": "force"}, **_kw())
    fast = io.time_history(a.values, 2 * FS, [str(c) for c in a["channel"].values],
                           ["N", "m"], ["force", "displacement"], node=[1, 2], direction="z")
    with pytest.raises(DimensionError, match="measurement set 2: 257 frequency lines up to "
                       "256 Hz; expected the 257 lines of set 1"):
        modal.frf_matrix([a, fast], {"quantity": "force"}, **_kw())


def test_conversions_multiply_by_i_omega(msys):
    M, C, K = msys.chain(3)
    f = np.linspace(1, 100, 200)
    rec = modal.exact_frf(M, C, K, f, [0, 1, 2], [0])
    acc = modal.exact_frf(M, C, K, f, [0, 1, 2], [0], frf_type="accelerance")
    mob = modal.convert_frf(rec, "mobility")
    assert mob.attrs["frf_type"] == "mobility" and mob["units"].values[0] == "m/s/N"
    conv = modal.convert_frf(mob, "accelerance")
    np.testing.assert_allclose(conv.values, acc.values, rtol=1e-12)
    assert conv["units"].values[0] == "m/s^2/N"
    assert conv["quantity"].values[0] == "acceleration"
    np.testing.assert_allclose(modal.convert_frf(acc, "receptance").values, rec.values,
                               rtol=1e-12)
    other = rec.copy()
    other.attrs["frf_type"] = "other"
    with pytest.raises(UnitsError, match="the FRF type is 'other'"):
        modal.convert_frf(other, "mobility")
    with pytest.raises(UnitsError, match="'to' must be one of"):
        modal.convert_frf(rec, "compliance")


def test_adopts_uff_labels_and_per_channel_spectra():
    f = np.linspace(0, 10, 11)
    da = xr.DataArray(np.ones((2, 1, 11), complex), dims=("response", "reference", "frequency"),
                      coords={"response": ["3:z", "4:-x"], "reference": ["3:z"],
                              "frequency": f}, attrs={"units": "m/s^2/N"})
    h = modal.as_frf_matrix(xr.Dataset({"frf": da}))
    assert h["node"].values.tolist() == [3, 4]
    assert h["direction"].values.tolist() == ["+z", "-x"]
    assert h["reference_node"].values.tolist() == [3]
    assert h.attrs["frf_type"] == "accelerance"
    ds = xr.Dataset({"spectrum": (("channel", "frequency"), np.ones((2, 11), complex))},
                    coords={"channel": ["p1", "p2"], "frequency": f})
    h2 = modal.as_frf_matrix(ds, frf_type="mobility")
    assert h2.shape == (2, 1, 11) and h2.attrs["frf_type"] == "mobility"
    with pytest.raises(DimensionError, match="found variables"):
        modal.as_frf_matrix(xr.Dataset({"psd": (("channel", "frequency"), np.ones((2, 11)))},
                                       coords={"frequency": f}))


def test_reference_level_is_the_force_autospectrum(msys, rng):
    # the level per line is the force's own periodogram (rectangular window, summed over
    # the segments) in dB re its largest value above 0 Hz, one row per reference
    th, *_ = _records(msys, rng, refs=[0, 2], resp=[1, 3])
    h = modal.frf_matrix(th, {"quantity": "force"}, **_kw())
    force = th.values[:2].reshape(2, -1, NSEG)
    p = np.sum(np.abs(np.fft.rfft(force, axis=-1)) ** 2, axis=1)
    want = 10 * np.log10(p / p[:, 1:].max(axis=1, keepdims=True))
    lev = h["reference_level_db"]
    assert lev.dims == ("reference", "frequency")
    np.testing.assert_allclose(lev.values[:, 1:-1], want[:, 1:-1], atol=1e-9)
    # carried through band selection and conversion (identify works on the band)
    from mvtk.modal._plscf import band_frf

    b = band_frf(modal.convert_frf(h, "accelerance"), 10, 100)
    np.testing.assert_array_equal(b["reference_level_db"].values,
                                  lev.sel(frequency=b["frequency"]).values)
    # two sets sharing the hammer position: the linear levels are averaged
    a, *_ = _records(msys, rng, refs=[0], resp=[1])
    c, *_ = _records(msys, rng, refs=[0], resp=[2])
    hm = modal.frf_matrix([a, c], {"quantity": "force"}, **_kw())
    la = modal.frf_matrix(a, {"quantity": "force"}, **_kw())["reference_level_db"].values
    lc = modal.frf_matrix(c, {"quantity": "force"}, **_kw())["reference_level_db"].values
    np.testing.assert_allclose(hm["reference_level_db"].values,
                               10 * np.log10((10 ** (la / 10) + 10 ** (lc / 10)) / 2))
