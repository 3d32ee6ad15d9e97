"""mvtk.scale.open_campaign: lazy stacking, contiguity, every bad file reported at once."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("dask")

import mvtk.io  # noqa: E402
from mvtk.errors import (  # noqa: E402
    DataRepairWarning,
    FormatError,
    MissingDependencyError,
    ParameterError,
)
from mvtk.scale import open_campaign  # noqa: E402

FS = 512.0
CHANNELS = ["a", "b"]


def _write(path, x, fs=FS, t0=None, channels=CHANNELS, units="m/s^2"):
    th = mvtk.io.time_history(x, fs, channels=channels, units=units)
    if t0 is not None:
        th.attrs["t0_s"] = float(t0)
    mvtk.io.write(th, path)
    return path


def _records(rng, n_files=3, n=2000):
    return [rng.standard_normal((2, n)) for _ in range(n_files)]


def test_record_stack_is_lazy_and_equals_each_file(tmp_path, rng):
    import dask.array as dsa

    xs = _records(rng)
    paths = [_write(tmp_path / f"r{i}.nc", x, t0=10.0 * i) for i, x in enumerate(xs)]
    ds = open_campaign(str(tmp_path / "*.nc"), chunks=700)
    th = ds["time_history"]
    assert th.dims == ("record", "channel", "time")
    assert isinstance(th.data, dsa.Array)
    assert th.data.chunks[-1][0] == 700
    assert list(ds["source"].values) == [str(p) for p in paths]
    np.testing.assert_array_equal(ds["t0_s"].values, [0.0, 10.0, 20.0])
    assert list(ds["units"].values) == ["m/s^2", "m/s^2"]
    np.testing.assert_array_equal(ds["time"].values, np.arange(2000) / FS)
    assert ds.attrs["fs"] == FS and ds.attrs["n_files"] == 3
    assert ds.attrs["skipped_files"] == []
    for i, p in enumerate(paths):
        ref = mvtk.io.read(p)["time_history"]
        np.testing.assert_array_equal(th.isel(record=i).values, ref.values)


def test_time_concat_orders_by_t0_and_joins_exactly(tmp_path, rng):
    x = rng.standard_normal((2, 3000))
    # names in reverse time order: the order must come from t0_s, not from the names
    _write(tmp_path / "a.nc", x[:, 2000:], t0=2000 / FS + 5.0)
    _write(tmp_path / "b.nc", x[:, 1000:2000], t0=1000 / FS + 5.0)
    _write(tmp_path / "c.nc", x[:, :1000], t0=5.0)
    ds = open_campaign(tmp_path, concat="time", chunks=256)
    np.testing.assert_array_equal(ds["time_history"].values, x)
    assert ds.attrs["t0_s"] == 5.0
    np.testing.assert_array_equal(ds["file_start_sample"].values, [0, 1000, 2000])
    assert [Path(s).stem for s in ds["file_source"].values] == ["c", "b", "a"]


def test_time_concat_gap_is_an_error_naming_the_file(tmp_path, rng):
    x = rng.standard_normal((2, 2000))
    _write(tmp_path / "a.nc", x[:, :1000], t0=0.0)
    _write(tmp_path / "b.nc", x[:, 1000:], t0=1000 / FS + 0.5)
    match = r"(?s)not contiguous.*b\.nc: starts at t0_s=2\.453125 s.*gap \+0\.5 s"
    with pytest.raises(FormatError, match=match):
        open_campaign(tmp_path, concat="time")


def test_bad_files_are_all_reported_in_one_error(tmp_path, rng):
    xs = _records(rng, 3)
    for i, x in enumerate(xs):
        _write(tmp_path / f"good{i}.nc", x)
    (tmp_path / "empty.nc").write_bytes(b"")
    (tmp_path / "garbage.nc").write_bytes(b"\x89HDF\r\n\x1a\n" + b"\0" * 100)
    _write(tmp_path / "rate.nc", xs[0], fs=2 * FS)
    _write(tmp_path / "short.nc", xs[0][:, :1500])
    _write(tmp_path / "chan.nc", xs[0], channels=["a", "c"])
    paths = sorted(tmp_path.iterdir()) + [tmp_path / "missing.nc"]
    with pytest.raises(FormatError) as info:
        open_campaign(paths)
    msg = str(info.value)
    assert "6 of 9 files are bad" in msg
    for name, reason in [("empty.nc", "empty"), ("garbage.nc", "FormatError"),
                         ("rate.nc", "sampling rate 1024.0 Hz differs"),
                         ("short.nc", "1500 samples"), ("chan.nc", "channels ['a', 'c']"),
                         ("missing.nc", "no such file")]:
        line = next(ln for ln in msg.splitlines() if name in ln)
        assert reason in line, (name, line)
    assert "on_error='skip'" in msg


def test_skip_warns_lists_and_keeps_the_good_files(tmp_path, rng):
    xs = _records(rng, 2)
    for i, x in enumerate(xs):
        _write(tmp_path / f"good{i}.nc", x)
    (tmp_path / "zz_bad.nc").write_text("not a measurement")
    with pytest.warns(DataRepairWarning, match=r"skipped 1 of 3 files:\n.*zz_bad\.nc"):
        ds = open_campaign(tmp_path, on_error="skip")
    assert ds.sizes["record"] == 2
    assert ds.attrs["skipped_files"] == [str(tmp_path / "zz_bad.nc")]
    assert len(ds.attrs["skipped_reasons"]) == 1


def test_skip_with_no_usable_file_still_raises(tmp_path):
    (tmp_path / "a.nc").write_bytes(b"")
    (tmp_path / "b.nc").write_bytes(b"")
    with pytest.raises(FormatError, match=r"no usable file.*\n.*a\.nc: the file is empty"):
        open_campaign(tmp_path, on_error="skip")


def test_text_files_are_checked_through_delayed_reads(tmp_path, rng):
    xs = _records(rng, 2, n=400)
    t = np.arange(400) / FS
    for i, x in enumerate(xs):
        np.savetxt(tmp_path / f"r{i}.csv", np.column_stack([t, x.T]), delimiter=",",
                   header="time [s],a [m/s^2],b [m/s^2]", comments="")
    np.savetxt(tmp_path / "r9.csv", np.column_stack([t, xs[0].T]), delimiter=",",
               header="time [s],a [m/s^2],b [V]", comments="")
    with pytest.raises(FormatError, match=r"r9\.csv: channel units \['m/s\^2', 'V'\] differ"):
        open_campaign(tmp_path / "*.csv")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataRepairWarning)
        ds = open_campaign(tmp_path / "*.csv", on_error="skip", chunks=100)
    for i, x in enumerate(xs):
        np.testing.assert_allclose(ds["time_history"].isel(record=i).values, x, rtol=1e-12)
    assert list(ds["record_format"].values) == ["text", "text"]


def test_read_options_force_the_read_path(tmp_path, rng):
    x = rng.standard_normal((2, 300))
    t = np.arange(300) / FS
    np.savetxt(tmp_path / "r0.csv", np.column_stack([t, x.T]), delimiter=",",
               header="time [s],a,b", comments="")
    with pytest.raises(FormatError, match="has no units"):
        open_campaign(tmp_path / "r0.csv")
    ds = open_campaign(tmp_path / "r0.csv", units=["V", "V"])
    assert list(ds["units"].values) == ["V", "V"]


@pytest.mark.parametrize(
    "kwargs, match",
    [({"concat": "channel"}, "concat must be 'record' or 'time', got 'channel'"),
     ({"on_error": "ignore"}, "on_error must be 'raise' or 'skip', got 'ignore'"),
     ({"chunks": -5}, "chunks must be a positive number of time samples"),
     ({"chunks": {"time": 0}}, "chunks must be a positive number of time samples")],
)
def test_bad_parameters(tmp_path, rng, kwargs, match):
    _write(tmp_path / "a.nc", rng.standard_normal((2, 100)))
    with pytest.raises(ParameterError, match=match):
        open_campaign(tmp_path, **kwargs)


def test_nothing_to_open(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"no file matches .*\*\.nc"):
        open_campaign(str(tmp_path / "*.nc"))
    with pytest.raises(ParameterError, match="list of paths is empty"):
        open_campaign([])
    with pytest.raises(ParameterError, match="expected a glob pattern.*got int"):
        open_campaign(3)


def test_without_dask_the_error_names_the_pip_command(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "dask", None)
    match = r'open_campaign needs dask.*pip install "mvtk\[scale\]"'
    with pytest.raises(MissingDependencyError, match=match):
        open_campaign(tmp_path)


def test_import_does_not_import_dask_or_matplotlib():
    import subprocess

    code = ("import sys, mvtk, mvtk.scale; "
            "print([m for m in sys.modules if m.split('.')[0] in "
            "('dask', 'distributed', 'matplotlib')])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"


def test_every_dask_function_names_the_pip_command_without_dask(monkeypatch, rng):
    import mvtk.scale

    th = mvtk.io.time_history(rng.standard_normal((2, 64)), FS, channels=CHANNELS, units="V")
    monkeypatch.setitem(sys.modules, "dask", None)
    for name, call in [("mvtk.scale.psd", lambda: mvtk.scale.psd(th)),
                       ("mvtk.scale.csd", lambda: mvtk.scale.csd(th)),
                       ("mvtk.scale.frf", lambda: mvtk.scale.frf(th, "a")),
                       ("mvtk.scale.map_channels", lambda: mvtk.scale.map_channels(np.std, th))]:
        with pytest.raises(MissingDependencyError, match=rf"{name} needs dask.*pip install"):
            call()


def test_cluster_without_distributed_names_the_pip_command(monkeypatch):
    import mvtk.scale

    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    with pytest.raises(MissingDependencyError, match=r"needs dask.distributed.*pip install"):
        mvtk.scale.parameter_study({"materials": {}}, {"materials": [1.0]}, client="local")
