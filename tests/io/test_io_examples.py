"""The example files in data/io_examples read back the signals their script wrote."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import mvtk.io as mio

EXAMPLES = Path(__file__).resolve().parents[2] / "data" / "io_examples"


def _script():
    spec = importlib.util.spec_from_file_location("make_examples", EXAMPLES / "make_examples.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


CASES = [
    ("daq_export.csv", {}, 0.0, 512.0),
    ("daq_export_de.csv", {}, 0.0, 512.0),
    ("accel_58.uff", {}, 1e-11, 1 / 1.95312e-3),
    ("accel_58b.uff", {}, 0.0, 1 / 1.95312e-3),
    ("matlab_v5.mat", {"data": "y", "fs": "fs", "units": ["m/s^2", "N"]}, 0.0, 512.0),
    ("recording.wav", {"calibration": 1e-3, "units": ["m/s^2", "N"]}, 5e-4, 512.0),
    ("example.nc", {}, 0.0, 512.0),
]


@pytest.mark.parametrize(("name", "options", "atol", "fs"), CASES, ids=[c[0] for c in CASES])
def test_example_file(tmp_path, name, options, atol, fs):
    expected = _script().signals()
    ds = mio.read(EXAMPLES / name, **options)
    th = ds["time_history"]
    np.testing.assert_allclose(th.values, expected, rtol=0, atol=atol)
    assert th.attrs["fs"] == pytest.approx(fs, rel=1e-9)
    assert list(th.units.values) == ["m/s^2", "N"]
    assert list(th.quantity.values) == ["acceleration", "force"]
    again = mio.read(mio.write(ds, tmp_path / "copy.nc"))
    for obj in [ds, again, *ds.data_vars.values(), *again.data_vars.values()]:
        for key in ("source", "format", "original_source", "original_format"):
            obj.attrs.pop(key, None)
    xr.testing.assert_identical(ds, again)
