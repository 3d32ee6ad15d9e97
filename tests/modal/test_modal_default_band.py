"""The default analysis band of ``mvtk.modal.identify``, chosen from the data.

External truths:

- ``../shared/data/hdf5/view_0.hdf5`` (PROVENANCE.md): a 60..500 Hz swept sine on a
  plate, H1 peaks near 77, 127, 214..226, 265, 350, 455..466 Hz of a 0..12.8 kHz FRF;
- a simply supported rectangular plate (closed-form shapes ``sin(m pi x / a) sin(n pi
  y / b)``, frequencies ``~ (m/a)^2 + (n/b)^2``), 3 references x 40 responses, 5 %
  noise, on a 0..4 kHz axis of which the modes fill 143..960 Hz, with a hammer whose
  force rolls off above 1.5 kHz;
- closed-form single-mode FRFs whose peaks lie at known places against the band's edges.

The LVM hammer tests with defaults are in ``test_modal_default_orders.py``.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
import xarray as xr

from mvtk import io, modal, signal

MN = [(1, 1), (2, 1), (1, 2), (3, 1), (2, 2), (1, 3), (3, 2)]
ZETA = np.array([0.012, 0.01, 0.009, 0.011, 0.013, 0.01, 0.012])
REFS = [3, 17, 30]


def _plate(nx=8, ny=5, a=1.1, b=0.7):
    x = (np.arange(nx) + 0.5) / nx * a
    y = (np.arange(ny) + 0.5) / ny * b
    X, Y = (g.ravel() for g in np.meshgrid(x, y, indexing="ij"))
    phi = np.array([np.sin(m * np.pi * X / a) * np.sin(n * np.pi * Y / b) for m, n in MN])
    phi /= np.sqrt(np.sum(phi**2, axis=1, keepdims=True))       # unit modal mass
    fn = np.array([50 * ((m / a) ** 2 + (n / b) ** 2) for m, n in MN])
    return fn, phi


@pytest.fixture(scope="module")
def plate_set(msys):
    """3 x 40 accelerances, 5 % noise, with a hammer's force level per line."""
    fn, phi = _plate()
    f = np.arange(0, 4000.0001, 0.5)
    h = msys.add_noise(msys.modal_frf(fn, ZETA, phi, f, REFS), 0.05,
                       np.random.default_rng(27))
    # a half-sine hammer pulse of 0.5 ms: its spectrum falls 35 dB below its maximum
    # near 2.9 kHz (first zero at 3 kHz)
    T = 0.5e-3
    w = 2 * np.pi * f
    with np.errstate(divide="ignore", invalid="ignore"):
        spec = np.abs(np.cos(w * T / 2) / (1 - (w * T / np.pi) ** 2))
    spec[~np.isfinite(spec)] = 0.5
    level = 20 * np.log10(np.maximum(spec / spec[1:].max(), 1e-12))
    h = h.assign_coords(reference_level_db=(("reference", "frequency"),
                                            np.tile(level, (len(REFS), 1))))
    h.attrs.update(excitation="impact")
    return fn, phi, h


def test_plate_3x40_noisy_defaults_find_every_mode(plate_set, msys):
    fn, phi, h = plate_set
    assert fn.min() > 140 and fn.max() < 970
    res = modal.identify(h)                       # no band, no orders
    lo, hi = res.band_hz
    # the band: x/1.25 below the first and x1.25 above the last resonance, inside the
    # lines the hammer excited (within 35 dB of its maximum)
    assert fn.min() / 1.3 < lo < fn.min() / 1.2 and fn.max() * 1.2 < hi < fn.max() * 1.3
    assert "impact force within 35 dB" in res.band_reason
    assert f"{len(fn)} resonance peak(s)" in res.band_reason
    k = msys.match(res.fn_hz, fn)
    np.testing.assert_allclose(res.fn_hz[k], fn, rtol=1e-3)
    np.testing.assert_allclose(res.zeta[k], ZETA, rtol=0.10)
    assert res.reliable[k].all(), res.to_dataframe()
    for j, kk in enumerate(k):
        m = modal.mac(np.vstack([res.real_shapes.values[kk], phi[j]]))[0, 1]
        assert m > 0.98, (j, m)


def test_band_given_is_kept(plate_set):
    _, _, h = plate_set
    fmin, fmax, why = modal.default_band(h, 100.0, 900.0)
    assert (fmin, fmax, why) == (100.0, 900.0, "given")
    fmin, fmax, why = modal.default_band(h, 100.0, None)
    assert fmin == 100.0 and 1150 < fmax < 1250 and why.startswith("fmin 100 Hz given")


def _single(fn_list, f, zeta=0.01, band=None, level=None):
    h = sum(1 / (fn**2 - f**2 + 2j * zeta * fn * f) for fn in fn_list)
    coords = {"frequency": f}
    da = xr.DataArray(h[None, None], dims=("response", "reference", "frequency"),
                      coords=coords, attrs={} if band is None else
                      {"excitation_band_hz": band})
    if level is not None:
        da = da.assign_coords(reference_level_db=(("reference", "frequency"), level[None]))
        da.attrs["excitation"] = "impact"
    return da


def test_edge_cutting_a_peak_is_named():
    f = np.arange(0, 1000.0, 0.1)
    # a random test whose shaker drives 0..300 Hz: the 298 Hz mode's -3 dB band
    # (+-3 Hz) crosses the band's top; the 600 Hz mode lies outside
    b = signal.analysis_band(_single([100.0, 298.0, 600.0], f, band=[0.0, 300.0]))
    assert b.fmax_hz == 300.0 and b.excited_hz[1] == 300.0
    np.testing.assert_allclose(b.cut_hz, [298.0], atol=0.5)
    np.testing.assert_allclose(b.left_out_hz, [600.0], atol=0.5)
    assert "cuts the peak(s) at 298" in b.reason and "left out: 600" in b.reason
    # driven up to 800 Hz: the band reaches x1.25 beyond the outer peaks, cutting none
    b = signal.analysis_band(_single([100.0, 600.0], f, band=[0.0, 800.0]))
    assert b.fmax_hz == pytest.approx(750.0, rel=1e-3) and b.cut_hz.size == 0
    assert b.fmin_hz == pytest.approx(80.0, rel=1e-3)
    assert b.left_out_hz.size == 0 and "left out" not in b.reason


def test_impact_band_stops_where_the_force_is_35_db_down():
    f = np.arange(0, 2000.0, 0.25)
    level = -40.0 * f / 1000.0                    # 35 dB down at 875 Hz
    b = signal.analysis_band(_single([200.0, 700.0, 1200.0], f, level=level))
    assert b.excited_hz[1] == pytest.approx(875.0, abs=0.3)
    assert b.fmax_hz == pytest.approx(875.0, abs=0.3)      # 700 x 1.25 = 875
    np.testing.assert_allclose(b.left_out_hz, [1200.0], atol=0.5)
    assert re.search(r"left out: 1200\.\d Hz \(excitation -48 dB\)", b.reason), b.reason
    # find_peaks uses the same excited band by default
    assert signal.find_peaks(_single([200.0, 700.0, 1200.0], f, level=level)).fn_hz.max() \
        < 875


def test_incoherent_peaks_do_not_widen_the_band():
    # a 900 Hz peak where the coherence is 0.2 (noise over no input) is no resonance:
    # the band stops x1.25 above the coherent 300 Hz mode
    f = np.arange(0, 1000.0, 0.25)
    da = _single([100.0, 300.0, 900.0], f)
    coh = np.where(f > 700, 0.2, 0.99)
    b = signal.analysis_band(da.assign_coords(
        coherence=(("response", "reference", "frequency"), coh[None, None])))
    assert b.fmax_hz == pytest.approx(375.0, rel=1e-3)
    assert b.left_out_hz.size == 0      # incoherent: not a spectral peak at all
    # without the coherence the 900 Hz peak is a resonance and the band reaches it
    assert signal.analysis_band(da).fmax_hz > 900


def test_an_incoherent_spike_does_not_hide_the_modes():
    # an H1 spike 97 dB above the modes where the coherence is 0.3 (a dip of the force
    # in a hammer's excited band) used to set the 60 dB dynamic range and hide the modes
    f = np.arange(0, 1000.0, 0.25)
    da = _single([100.0, 300.0], f)
    v = da.values.copy()
    v[..., 3200] *= 1e8
    coh = np.where(np.abs(f - 800) < 2, 0.3, 0.99)
    ds = xr.Dataset({"frf": da.copy(data=v),
                     "coherence": (("response", "reference", "frequency"), coh[None, None])})
    np.testing.assert_allclose(signal.find_peaks(ds).fn_hz, [100.0, 300.0], atol=0.1)


def test_analysis_band_refuses_a_bad_margin():
    from mvtk.errors import ParameterError

    with pytest.raises(ParameterError, match="margin must be > 1"):
        signal.analysis_band(_single([10.0], np.arange(0, 50.0, 0.1)), margin=1.0)


@pytest.mark.shared_data
@pytest.mark.slow
def test_view0_swept_sine_defaults(modal_data, capsys):
    """Defaults on the swept-sine plate find every PROVENANCE.md peak; the band is the
    swept band (52..479 Hz) trimmed x/1.25 below the 77 Hz resonance."""
    ds = io.read(modal_data / "hdf5" / "view_0.hdf5", units=["N", "m/s^2", "V"],
                 quantity=["force", "acceleration", "voltage"])
    h = modal.frf_matrix(ds, "force", "acc", window="boxcar", nperseg=ds.sizes["time"],
                         detrend=False)
    assert h.attrs["excitation_band_hz"] == [52.0, 479.0]
    res = modal.identify(h)
    lo, hi = res.band_hz
    assert 60 < lo < 63 and hi == 479.0, res.band_reason
    assert "swept band 52..479 Hz" in res.band_reason
    for f0, tol in ((77, 0.02), (127, 0.02), (220, 0.03), (265, 0.02), (350, 0.02),
                    (460, 0.03)):
        k = int(np.argmin(np.abs(res.fn_hz - f0)))
        assert abs(res.fn_hz[k] / f0 - 1) <= tol, (f0, res.to_dataframe())
        if f0 != 220:          # 214..226 Hz ripples (see test_modal_real_data.py)
            assert res.reliable[k], res.to_dataframe()
    # the command line prints the band and why
    import argparse

    from mvtk.cli import modal as cli

    p = argparse.ArgumentParser()
    cli.add_parser(p.add_subparsers(dest="command"))
    args = p.parse_args(["modal", str(modal_data / "hdf5" / "view_0.hdf5"), "--units", "N",
                         "m/s^2", "V", "--quantity", "force", "acceleration", "voltage"])
    assert cli.run(args) == 0
    out = capsys.readouterr().out
    assert "band: from the data: swept band" in out
    args = p.parse_args(["modal", str(modal_data / "hdf5" / "view_0.hdf5"), "--units", "N",
                         "m/s^2", "V", "--quantity", "force", "acceleration", "voltage",
                         "--fmax", "400", "--json"])
    assert cli.run(args) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["band_hz"][1] == 400.0 and 60 < out["band_hz"][0] < 63
    assert out["band_reason"].startswith("fmax 400 Hz given; from the data: swept band")
