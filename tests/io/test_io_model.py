"""The time-history data model: builder, unit vocabulary and validator."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import mvtk.io as mio
from mvtk.errors import DimensionError, FormatError, ParameterError, UnitsError


def _th(rng, n=16, fs=100.0):
    return mio.time_history(
        rng.standard_normal((2, n)),
        fs,
        ["a1", "f1"],
        ["m/s2", "N"],
        node=[3, 4],
        direction=["z", "-x"],
        attrs={"instrument": "sim"},
    )


def test_time_history_conventions(rng):
    da = _th(rng, n=1000, fs=3.0)
    assert da.dims == ("channel", "time") and da.name == "time_history"
    # exactly np.arange(n) / fs, not a float arange with a step
    np.testing.assert_array_equal(da.time.values, np.arange(1000) / 3.0)
    assert da.time.values[999] != pytest.approx(0.0) and da.attrs["fs"] == 3.0
    assert list(da.units.values) == ["m/s^2", "N"]
    assert list(da.quantity.values) == ["acceleration", "force"]
    assert list(da.node.values) == [3, 4] and list(da.direction.values) == ["z", "-x"]
    assert da.attrs["instrument"] == "sim"
    assert mio.validate(da) is da


def test_time_history_keeps_float32_and_converts_ints(rng):
    x32 = rng.standard_normal((1, 5)).astype(np.float32)
    assert mio.time_history(x32, 1.0, ["a"], "V").dtype == np.float32
    assert mio.time_history(np.arange(5), 1.0, ["a"], "V").dtype == np.float64
    big = np.arange(5.0).astype(">f8")
    assert mio.time_history(big, 1.0, ["a"], "V").dtype.isnative


@pytest.mark.parametrize(
    ("raw", "canon", "quantity"),
    [
        ("m/s²", "m/s^2", "acceleration"),
        ("m/s**2", "m/s^2", "acceleration"),
        ("g", "g", "acceleration"),
        ("µm", "um", "displacement"),
        ("microstrain", "um/m", "strain"),
        ("v", "V", "voltage"),
        ("kPa", "kPa", "pressure"),
        ("Nm", "Nm", "other"),
        ("rpm", "rpm", "other"),
    ],
)
def test_units_vocabulary(raw, canon, quantity):
    assert mio.normalize_units(raw) == canon
    assert mio.infer_quantity(canon) == quantity


def test_fs_from_dt():
    assert mio.fs_from_dt(1 / 30) == 30.0
    assert mio.fs_from_dt(0.0333333333333) == 30.0
    with pytest.raises(ParameterError, match="sample interval must be a positive"):
        mio.fs_from_dt(0.0)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        (dict(data=np.zeros((2, 3, 4))), DimensionError, r"expected a 1-D or 2-D"),
        (dict(channels=["a"]), DimensionError, r"one channel name per row \(2\), got 1"),
        (dict(fs=-1.0), ParameterError, r"fs must be a positive finite rate in Hz, got -1.0"),
        (dict(units=["V"]), DimensionError, r"units: expected one entry per channel \(2\)"),
        (dict(data=np.zeros((2, 4), complex)), ParameterError, "expected real samples"),
        (dict(data=np.array([["a", "b"]] * 2)), ParameterError, "expected numeric samples"),
        (dict(units=[3, "V"]), UnitsError, "units must be a string, got int 3"),
        (
            dict(channels=["a", "a"]),
            FormatError,
            r"duplicate channel name 'a' at positions 0 and 1",
        ),
        (dict(quantity=["mass", "force"]), FormatError, r"channel 'a' has quantity 'mass'"),
        (dict(quantity=["force", "force"]), FormatError, r"channel 'a' is force in 'm/s\^2'"),
        (dict(units=["", "N"]), FormatError, r"channel 'a' has no units"),
        (dict(channels=[" ", "b"]), FormatError, r"channel 0 has an empty name"),
    ],
)
def test_time_history_bad_input(kwargs, exc, match):
    args = dict(data=np.zeros((2, 4)), fs=10.0, channels=["a", "b"], units=["m/s^2", "N"])
    args.update(kwargs)
    with pytest.raises(exc, match=match):
        mio.time_history(**args)


def test_validate_time_axis(rng):
    da = _th(rng)
    stepped = da.assign_coords(time=np.arange(0, 0.16, 0.01 + 1e-6)[:16])
    with pytest.raises(FormatError, match=r"time axis is not np.arange\(n\) / fs with fs = 100 Hz"):
        mio.validate(stepped)
    late = da.assign_coords(time=da.time.values + 1.0)
    with pytest.raises(FormatError, match=r"sample 0 is at 1.0 s, expected 0.0 s"):
        mio.validate(late)
    no_fs = da.copy()
    no_fs.attrs = {}
    mio.validate(no_fs)  # fs derived from the axis
    with pytest.raises(FormatError, match="expected float seconds on 'time'"):
        mio.validate(da.assign_coords(time=np.arange(16)))


def test_validate_values_and_missing(rng):
    da = _th(rng)
    bad = da.copy(data=da.values.copy())
    bad.values[1, 5] = np.nan
    with pytest.raises(
        FormatError, match=r"channel 'f1' holds 1 NaN samples but the source marks 0"
    ):
        mio.validate(bad)
    marked = bad.assign_coords(n_missing=("channel", [0, 1]))
    mio.validate(marked)
    bad.values[1, 5] = np.inf
    with pytest.raises(FormatError, match=r"infinite value in channel 'f1' at sample 5"):
        mio.validate(bad)


def test_validate_structure(rng):
    da = _th(rng)
    with pytest.raises(
        DimensionError, match=r"expected dims \('channel', 'time'\), got \('time', 'channel'\)"
    ):
        mio.validate(da.T)
    with pytest.raises(FormatError, match="expected a per-channel 'quantity' coordinate"):
        mio.validate(da.drop_vars("quantity"))
    with pytest.raises(
        FormatError, match="expected an xarray.DataArray or xarray.Dataset, got ndarray"
    ):
        mio.validate(np.zeros(3))
    ds = xr.Dataset({"other": da})
    with pytest.raises(FormatError, match="no primary 'time_history' variable"):
        mio.validate(ds)
    with pytest.raises(FormatError, match=r"in /x/y.csv: channel 'a1' has no units"):
        mio.validate(da.assign_coords(units=("channel", ["", "N"])), source="/x/y.csv")


def test_validate_spectrum():
    f = np.array([0.0, 1.0, 1.0])
    ds = xr.Dataset({"psd": (("channel", "frequency"), np.ones((1, 3)))}, coords={"frequency": f})
    with pytest.raises(
        FormatError, match=r"'frequency' must increase strictly; line 2 is at 1.0 Hz"
    ):
        mio.validate(ds)
    ok = ds.assign_coords(frequency=np.arange(3.0))
    mio.validate(ok)
    nan = ok.copy(deep=True)
    nan["psd"][0, 1] = np.nan
    with pytest.raises(FormatError, match="non-finite spectral values"):
        mio.validate(nan)


def test_import_does_not_load_optional_heavy_modules():
    import subprocess
    import sys

    code = (
        "import sys, mvtk, mvtk.io; "
        "print([m for m in ('pyuff', 'matplotlib', 'dask', 'nptdms', 'h5py') if m in sys.modules])"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
