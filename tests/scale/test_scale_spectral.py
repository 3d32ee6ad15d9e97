"""mvtk.scale.psd / map_channels: dask chunked results equal the in-memory estimators."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("dask")

import scipy.signal  # noqa: E402
import xarray as xr  # noqa: E402

import mvtk.io  # noqa: E402
import mvtk.signal  # noqa: E402
from mvtk.errors import DimensionError, FormatError, ParameterError  # noqa: E402
from mvtk.scale import map_channels, psd  # noqa: E402

FS = 1000.0


@pytest.fixture
def history(rng):
    t = np.arange(20_011) / FS
    x = rng.standard_normal((3, t.size))
    x[1] += 3 * np.sin(2 * np.pi * 50.0 * t) + 0.5 * t  # a line and a drift
    return mvtk.io.time_history(x, FS, channels=["a", "b", "c"], units=["m/s^2", "m/s", "N"])


@pytest.mark.parametrize(
    "chunk, kwargs",
    [
        (4096, {"nperseg": 512}),                                  # 50 % overlap, chunks % step
        (3001, {"nperseg": 1000, "noverlap": 300}),                # chunks not a step multiple
        (1500, {"nperseg": 2048, "noverlap": 0}),                  # chunk shorter than nperseg
        (2500, {"nperseg": 777, "noverlap": 600, "window": "boxcar", "detrend": "linear"}),
        (5000, {"nperseg": 256, "detrend": False, "scaling": "spectrum"}),
        (20_011, {"nperseg": 20_011, "window": "boxcar"}),         # one segment
        (999, {"nperseg": 1024, "window": ("tukey", 0.25)}),
    ],
)
def test_chunked_psd_equals_in_memory_psd(history, chunk, kwargs):
    ref = mvtk.signal.psd(history, **kwargs)
    out = psd(history.chunk({"time": chunk}), **kwargs)
    np.testing.assert_allclose(out.values, ref.values, rtol=1e-10, atol=1e-13 * ref.values.max())
    np.testing.assert_array_equal(out["frequency"].values, ref["frequency"].values)
    assert list(out["units"].values) == list(ref["units"].values)
    for key in ("nperseg", "noverlap", "n_averages", "df_hz", "scaling", "fs"):
        assert out.attrs[key] == ref.attrs[key], key


def test_psd_matches_scipy_welch_directly(history):
    out = psd(history.chunk({"time": 4000}), nperseg=1024)
    f, ref = scipy.signal.welch(history.values, fs=FS, nperseg=1024, axis=-1)
    np.testing.assert_allclose(out.values, ref, rtol=1e-10)
    np.testing.assert_allclose(out["frequency"].values, f)


def test_psd_on_numpy_backed_input_and_lazy_output(history):
    import dask.array as dsa

    lazy = psd(history, nperseg=500, compute=False)
    assert isinstance(lazy.data, dsa.Array)
    np.testing.assert_allclose(lazy.values, mvtk.signal.psd(history, nperseg=500).values,
                               rtol=1e-10)


def test_psd_of_a_record_campaign_and_the_record_average(history, rng):
    recs = [history.copy(data=rng.standard_normal(history.shape)) for _ in range(3)]
    stacked = xr.concat(recs, dim="record").chunk({"time": 3000})
    per = psd(stacked, nperseg=400)
    assert per.dims == ("record", "channel", "frequency")
    for i, r in enumerate(recs):
        np.testing.assert_allclose(per.isel(record=i).values,
                                   mvtk.signal.psd(r, nperseg=400).values, rtol=1e-10)
    comb = psd(stacked, nperseg=400, combine_records=True)
    assert comb.dims == ("channel", "frequency")
    # equal-length records: Welch over all segments = mean of the record spectra
    mean = np.mean([mvtk.signal.psd(r, nperseg=400).values for r in recs], axis=0)
    np.testing.assert_allclose(comb.values, mean, rtol=1e-10)
    assert comb.attrs["n_averages"] == 3 * per.attrs["n_averages"]


def test_psd_bad_inputs(history):
    with pytest.raises(ParameterError, match="scaling must be 'density' or 'spectrum'"):
        psd(history, scaling="power")
    with pytest.raises(ParameterError, match="detrend must be 'constant', 'linear' or False"):
        psd(history, detrend="quadratic")
    with pytest.raises(ParameterError, match=r"nperseg must be in \[2, 20011\]"):
        psd(history, nperseg=30_000)
    with pytest.raises(DimensionError, match="combine_records=True needs a 'record' dim"):
        psd(history, combine_records=True)
    with pytest.raises(FormatError, match="with a 'time_history' variable"):
        psd(xr.Dataset({"x": history}))
    with pytest.raises(DimensionError, match=r"expected dims \(..., 'channel', 'time'\)"):
        psd(history.rename(time="t"))
    with pytest.raises(ParameterError, match="got ndarray"):
        psd(history.values)
    with pytest.raises(ParameterError, match=r"fs=999\.0 Hz disagrees"):
        psd(history, fs=999.0)


def _percentiles(x, q=(5.0, 50.0, 95.0)):
    return np.percentile(x, q)


def test_map_channels_equals_numpy_per_channel(history, rng):
    recs = xr.concat([history, history * 2], dim="record").chunk({"time": 5000})
    std = map_channels(np.std, recs).compute()
    assert std.dims == ("record", "channel")
    np.testing.assert_allclose(std.values, np.std(recs.values, axis=-1), rtol=1e-12)
    pct = map_channels(_percentiles, recs, output_dims=("q",), output_sizes={"q": 3})
    np.testing.assert_allclose(pct.compute().values,
                               np.percentile(recs.values, [5, 50, 95], axis=-1).transpose(1, 2, 0))


def test_map_channels_runs_a_damping_estimator_per_channel(rng):
    # free decays with known damping: log decrement per channel through map_channels
    fs, fn = 2000.0, 40.0
    t = np.arange(8000) / fs
    zetas = np.array([0.01, 0.02, 0.005])
    wd = 2 * np.pi * fn * np.sqrt(1 - zetas[:, None] ** 2)
    x = np.exp(-zetas[:, None] * 2 * np.pi * fn * t) * np.cos(wd * t)
    th = mvtk.io.time_history(x, fs, channels=["p", "q", "r"], units="m")
    est = map_channels(_zeta_log_decrement, th.chunk({"time": 1000}), kwargs={"fs": fs})
    np.testing.assert_allclose(est.compute().values, zetas, rtol=1e-3)


def _zeta_log_decrement(x, fs):
    import mvtk.damping

    th = mvtk.io.time_history(x[None, :], fs, channels=["x"], units="m")
    return float(mvtk.damping.log_decrement(th).to_dataframe()["zeta"].iloc[0])


def test_map_channels_bad_inputs(history):
    with pytest.raises(ParameterError, match="func must be callable, got int"):
        map_channels(3, history)
    with pytest.raises(ParameterError, match=r"output_sizes must give the length .*\['q'\]"):
        map_channels(_percentiles, history.chunk({"time": 100}), output_dims=("q",))


@pytest.mark.parametrize(
    "chunk, kwargs",
    [(1500, {"nperseg": 512}),
     (3001, {"nperseg": 1000, "noverlap": 300, "reference": "a"}),
     (999, {"nperseg": 256, "reference": [0, 2], "detrend": "linear", "window": "boxcar"}),
     (4000, {"nperseg": 640, "reference": {"units": "N"}, "scaling": "spectrum"})],
)
def test_chunked_csd_equals_in_memory_csd(history, chunk, kwargs):
    from mvtk.scale import csd

    ref = mvtk.signal.csd(history, **kwargs)
    out = csd(history.chunk({"time": chunk}), **kwargs)
    assert out.dims == ref.dims
    np.testing.assert_allclose(out.values, ref.values, rtol=1e-10,
                               atol=1e-13 * np.abs(ref.values).max())
    for c in ("response", "reference", "reference_units", "response_quantity"):
        assert list(out[c].values) == list(ref[c].values), c
    assert out.attrs["n_averages"] == ref.attrs["n_averages"]


def test_csd_keeps_the_record_dim(history, rng):
    from mvtk.scale import csd

    recs = [history.copy(data=rng.standard_normal(history.shape)) for _ in range(2)]
    out = csd(xr.concat(recs, dim="record").chunk({"time": 2500}), nperseg=300, reference="c")
    assert out.dims == ("record", "response", "reference", "frequency")
    for i, r in enumerate(recs):
        np.testing.assert_allclose(out.isel(record=i).values,
                                   mvtk.signal.csd(r, nperseg=300, reference="c").values,
                                   rtol=1e-10, atol=1e-16)


def test_csd_bad_inputs(history):
    from mvtk.scale import csd

    with pytest.raises(ParameterError, match="reference: no channel matches"):
        csd(history, reference={"quantity": "pressure"})
    with pytest.raises(ParameterError, match="scaling must be 'density' or 'spectrum'"):
        csd(history, scaling="psd")
    with pytest.raises(ParameterError, match="detrend must be"):
        csd(history, detrend="cubic")


@pytest.fixture
def shaker(rng):
    n = 20_000
    force = rng.standard_normal(n)
    b, a = scipy.signal.butter(2, 0.1)
    y1 = scipy.signal.lfilter(b, a, force) + 0.01 * rng.standard_normal(n)
    y2 = scipy.signal.lfilter([1, 0.5], [1, -0.3], force)
    return mvtk.io.time_history(np.vstack([force, y1, y2]), FS, channels=["F", "a1", "a2"],
                                units=["N", "m/s^2", "m/s^2"])


@pytest.mark.parametrize(
    "kwargs, rtol",
    [({"reference": "F", "nperseg": 512}, 1e-10),
     ({"reference": "F", "estimator": "H2", "nperseg": 1000, "noverlap": 300}, 1e-10),
     ({"reference": ["F", "a2"], "response": "a1", "nperseg": 256}, 1e-8)],  # 2x2 solve
)
def test_chunked_frf_equals_in_memory_frf(shaker, kwargs, rtol):
    from mvtk.scale import frf

    ref = mvtk.signal.frf(shaker, **kwargs)
    out = frf(shaker.chunk({"time": 3000}), **kwargs)
    scale = np.abs(ref["frf"].values).max()
    np.testing.assert_allclose(out["frf"].values, ref["frf"].values, rtol=rtol,
                               atol=rtol * scale)
    np.testing.assert_allclose(out["coherence"].values, ref["coherence"].values, atol=1e-12)
    assert out.attrs == ref.attrs
    assert list(out.coords) == list(ref.coords)
    np.testing.assert_array_equal(out["units"].values, ref["units"].values)


def test_frf_per_record(shaker):
    from mvtk.scale import frf

    stacked = xr.concat([shaker, shaker * 3.0], dim="record").chunk({"time": 4000})
    out = frf(stacked, "F", nperseg=512)
    assert out["frf"].dims == ("record", "response", "reference", "frequency")
    ref = mvtk.signal.frf(shaker, "F", nperseg=512)
    for i in range(2):  # scaling every channel by 3 leaves the FRF unchanged
        np.testing.assert_allclose(out["frf"].isel(record=i).values, ref["frf"].values,
                                   rtol=1e-10, atol=1e-12)


def test_frf_bad_inputs(shaker):
    from mvtk.scale import frf

    with pytest.raises(ParameterError, match="estimator must be 'H1' or 'H2', got 'H3'"):
        frf(shaker, "F", estimator="H3")
    with pytest.raises(ParameterError, match="'H2' needs exactly one reference, got 2"):
        frf(shaker, ["F", "a1"], estimator="H2")
    with pytest.raises(ParameterError, match="every channel is a reference"):
        frf(shaker, ["F", "a1", "a2"])
    with pytest.raises(ParameterError, match="reference: no channel matches"):
        frf(shaker, {"quantity": "pressure"})
