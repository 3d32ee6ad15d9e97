"""The stage cache: keys from what a stage reads, checksums, atomic writes, the lock."""

from __future__ import annotations

import json
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from mvtk.errors import ConfigError
from mvtk.study import load_study
from mvtk.study._cache import (
    CacheWarning,
    OutputBusyError,
    OutputLock,
    ReadTracker,
    StageCache,
    TrackedStudy,
)
from mvtk.study._run import check_output_dir

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"


@pytest.fixture(scope="module")
def study():
    return load_study(STUDY)


def _with(study, section: str, key: str, value):
    import dataclasses

    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in study.config.items()}
    cfg[section][key] = value
    return dataclasses.replace(study, config=cfg)


def _reads_patch(s):
    """A stage like the reduction stage: reads control.patch and the reduction keys."""
    ctl = s.section("control") or {}
    red = s.section("reduction")
    return {"patch": ctl.get("patch"), "n": red["n_modes"]}, None


def _cached(cache, study, compute=_reads_patch, base="k"):
    tracker = ReadTracker(study)
    return cache.get("reduction", base, lambda: compute(TrackedStudy(study, tracker)), tracker)


def test_key_follows_what_the_stage_read(tmp_path, study):
    """Issue 16: changing control.patch reused the reduction stage (a key it read but that
    was not in its key). Keys are now derived from the reads themselves."""
    cache = StageCache(tmp_path)
    calls = []

    def compute(s):
        calls.append(1)
        return _reads_patch(s)

    assert _cached(cache, study, compute)[0] == {"patch": "pzt", "n": 10}
    _cached(cache, study, compute)
    assert len(calls) == 1
    # a key the stage did not read (a controller gain) does not invalidate it
    _cached(cache, _with(study, "control", "t_end_s", 3.0), compute)
    assert len(calls) == 1
    # the patch it read does, and so does a key it found absent when it appears
    res, _ = _cached(cache, _with(study, "control", "patch", "other"), compute)
    assert len(calls) == 2 and res["patch"] == "other"
    _cached(cache, study, compute)
    assert len(calls) == 3
    # the base key (code, version, upstream keys) still counts
    _cached(cache, study, compute, base="k2")
    assert len(calls) == 4
    stored = json.loads((tmp_path / "reduction.json").read_text())
    assert '["value", ["control", "patch"]]' in stored["reads"]


def test_structure_description_is_a_read(tmp_path, study):
    import dataclasses

    cache = StageCache(tmp_path)

    def compute(s):
        return {"E": s.description()["materials"]["steel"]["E"]}, None

    assert _cached(cache, study, compute)[0]["E"] == 2.1e11
    desc = study.description()
    desc["materials"]["steel"]["E"] = 2.0e11
    res, _ = _cached(cache, dataclasses.replace(study, structure=desc), compute)
    assert res["E"] == 2.0e11 and cache.misses == ["reduction", "reduction"]


def _ds():
    return xr.Dataset({"y": ("t", np.arange(5.0))})


@pytest.mark.parametrize("damage", ["truncate", "garble", "delete"])
@pytest.mark.parametrize("which", ["json", "nc"])
def test_damaged_entry_recomputed_with_a_warning_naming_it(tmp_path, damage, which):
    """Issue 16: a truncated fe.nc failed every rerun; 64 garbled bytes in control.nc gave
    a report with 8.4e+186 in a time history."""
    cache = StageCache(tmp_path)
    cache.get("stage", "k", lambda: ({"x": 1.5}, _ds()))
    f = tmp_path / f"stage.{which}"
    data = f.read_bytes()
    if damage == "truncate":
        f.write_bytes(data[: len(data) // 2])
    elif damage == "garble":
        mid = len(data) // 2
        f.write_bytes(data[:mid] + bytes(b ^ 0xFF for b in data[mid:mid + 64])
                      + data[mid + 64:])
    else:
        f.unlink()
    calls = []

    def compute():
        calls.append(1)
        return {"x": 1.5}, _ds()

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res, ds = StageCache(tmp_path).get("stage", "k", compute)
    assert calls == [1] and res == {"x": 1.5} and ds["y"].values.tolist() == [0, 1, 2, 3, 4]
    if not (which == "json" and damage == "delete"):  # a missing sidecar is a plain miss
        msgs = [str(w.message) for w in caught if issubclass(w.category, CacheWarning)]
        assert len(msgs) == 1 and str(f) in msgs[0] and "--no-cache" in msgs[0], msgs
    # the entry is whole again
    again = StageCache(tmp_path)
    again.get("stage", "k", compute)
    assert again.hits == ["stage"] and calls == [1]


@pytest.mark.parametrize(("ds", "magic"), [
    # netCDF3 holds these exactly (int64 within int32, unicode, names with spaces)
    (xr.Dataset({"a b": ("x", np.arange(3, dtype=np.int64)),
                 "label": ("x", ["\u00b5m", "", "\u03a9 long label"])},
                coords={"x": np.array([10, 20, 30]), "node": ("x", np.array([4, 5, 6]))}),
     b"CDF"),
    # and not these: the HDF5 (netCDF4) file keeps them
    (xr.Dataset({"h": ("f", np.array([1 + 2j, 3 - 1j]))}), b"\x89HD"),
    (xr.Dataset({"n": ("x", np.array([1, 2**40]))}), b"\x89HD"),
    (xr.Dataset({"ok": ("x", np.array([True, False]))}), b"\x89HD"),
])
def test_arrays_round_trip_exactly_in_either_file_format(tmp_path, ds, magic):
    """The cache writes small netCDF3-safe datasets as netCDF3 (about 10x faster than
    HDF5) and restores the dtypes netCDF3 changes; everything else as netCDF4."""
    StageCache(tmp_path).get("stage", "k", lambda: ({"x": 1}, ds))
    assert (tmp_path / "stage.nc").read_bytes()[:len(magic)] == magic
    cache = StageCache(tmp_path)
    _, back = cache.get("stage", "k", lambda: pytest.fail("recomputed"))
    assert cache.hits == ["stage"]
    assert back.identical(ds)
    for name, var in ds.variables.items():
        assert back[name].dtype == var.dtype, name
    assert set(back.coords) == set(ds.coords)


def test_result_tampering_is_detected(tmp_path):
    cache = StageCache(tmp_path)
    cache.get("stage", "k", lambda: ({"x": 1.5}, None))
    js = tmp_path / "stage.json"
    js.write_text(js.read_text().replace("1.5", "2.5"))
    with pytest.warns(CacheWarning, match="does not match its checksum"):
        res, _ = StageCache(tmp_path).get("stage", "k", lambda: ({"x": 1.5}, None))
    assert res == {"x": 1.5}


def test_writes_are_atomic_and_leave_no_temporaries(tmp_path, monkeypatch):
    cache = StageCache(tmp_path)
    cache.get("stage", "k", lambda: ({"x": 1}, _ds()))
    before = (tmp_path / "stage.json").read_bytes()

    def boom(*a, **k):
        raise KeyboardInterrupt

    # interrupted while writing the new arrays: the old entry is untouched
    monkeypatch.setattr(xr.Dataset, "to_netcdf", boom)
    with pytest.raises(KeyboardInterrupt):
        cache.get("stage", "k2", lambda: ({"x": 2}, _ds()))
    monkeypatch.undo()
    assert (tmp_path / "stage.json").read_bytes() == before
    cache.clean_temporaries()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["stage.json", "stage.nc"]
    fresh = StageCache(tmp_path)
    assert fresh.get("stage", "k", lambda: ({"x": 3}, None))[0] == {"x": 1}


def test_lock_serialises_runs_with_a_clear_message(tmp_path):
    """Issue 16: two runs into one --out: one died with BlockingIOError."""
    with OutputLock(tmp_path):
        with pytest.raises(OutputBusyError, match=f"output folder {tmp_path} is in use by "
                                                  r"another mvtk run \(pid \d+\)"):
            with OutputLock(tmp_path, timeout_s=0):
                pass
    messages, order = [], []
    first = OutputLock(tmp_path).__enter__()

    def release():
        time.sleep(0.5)
        order.append("released")
        first.__exit__(None, None, None)

    t = threading.Thread(target=release)
    t.start()
    with OutputLock(tmp_path, on_wait=messages.append):
        order.append("acquired")
    t.join()
    assert order == ["released", "acquired"]
    assert len(messages) == 1 and "waiting for it to finish" in messages[0]


def test_output_folder_checked_before_work(tmp_path):
    (tmp_path / "cache").write_text("not a folder")
    with pytest.raises(ConfigError, match=f"'{tmp_path / 'cache'}' is a file; the stage "
                                          "cache needs this name for a folder"):
        check_output_dir(tmp_path)
    f = tmp_path / "file.txt"
    f.write_text("x")
    with pytest.raises(ConfigError, match="is a file, expected a folder"):
        check_output_dir(f)
    with pytest.raises(ConfigError, match="cannot create the output folder '/proc/mvtk"):
        check_output_dir("/proc/mvtk-out")
    with pytest.raises(ConfigError, match="cannot create the output folder"):
        check_output_dir(f / "sub")


def test_measurement_files_are_keyed_by_content_and_name(tmp_path, study):
    """A copy of the study with absolute paths to the same files reuses the ingest-like
    stage; a changed file reruns it."""
    import dataclasses
    import shutil

    cache = StageCache(tmp_path / "c")
    calls = []

    def compute(s):
        calls.append(1)
        return {"files": sorted(p.name for p in s.measurement_files.values())}, None

    def cached(st):
        tracker = ReadTracker(st)
        return cache.get("ingest", "k", lambda: compute(TrackedStudy(st, tracker)), tracker)

    cached(study)
    moved = {k: tmp_path / p.name for k, p in study.measurement_files.items()}
    for k, p in study.measurement_files.items():
        shutil.copy(p, moved[k])
    cached(dataclasses.replace(study, measurement_files=moved))
    assert len(calls) == 1
    moved["decay"].write_bytes(moved["decay"].read_bytes() + b"\n")
    cached(dataclasses.replace(study, measurement_files=moved))
    assert len(calls) == 2
