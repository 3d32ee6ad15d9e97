"""Family "cache damage": truncate, garble or delete every cache file of a run; the rerun
must give the same numbers as the clean run and name every damaged file in a warning.

Three reruns cover every (file, damage) pair: in rotation r, the sidecar of stage i gets
damage (i + r) mod 3 and its arrays damage (i + r + 1) mod 3.
"""

from __future__ import annotations

import json
import warnings

import pytest
from robust_helpers import assert_same_numbers, copy_run

from mvtk.study import run
from mvtk.study._cache import CacheWarning

pytestmark = pytest.mark.slow

DAMAGES = ("truncate", "garble", "delete")


def _damage(path, how: str) -> None:
    data = path.read_bytes()
    if how == "truncate":
        path.write_bytes(data[: len(data) // 3])
    elif how == "garble":
        mid = len(data) // 2
        path.write_bytes(data[:mid] + bytes(b ^ 0x5A for b in data[mid:mid + 64])
                         + data[mid + 64:])
    else:
        path.unlink()


@pytest.mark.parametrize("rotation", range(3))
def test_damaged_cache_gives_the_clean_numbers(clean_run, tmp_path, rotation):
    study, out = copy_run(clean_run, tmp_path)
    cache = out / "cache"
    stages = sorted(p.stem for p in cache.glob("*.json"))
    assert len(stages) == 9  # ingest, modal, fe, updating, correlation, ... control
    damaged = {}
    for i, stage in enumerate(stages):
        js, nc = cache / f"{stage}.json", cache / f"{stage}.nc"
        has_nc = nc.exists()
        damaged[js] = DAMAGES[(i + rotation) % 3]
        if has_nc:
            damaged[nc] = DAMAGES[(i + rotation + 1) % 3]
    for f, how in damaged.items():
        _damage(f, how)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run(study, out, progress=False, report=False)
    assert not res.failed and not res.unavailable
    assert_same_numbers(clean_run[2].results, res.results)
    msgs = " | ".join(str(w.message) for w in caught if issubclass(w.category, CacheWarning))
    for f, how in damaged.items():
        js_deleted = f.suffix == ".json" and how == "delete"
        nc_of_deleted_json = (f.suffix == ".nc"
                              and damaged.get(f.with_suffix(".json")) == "delete")
        if not (js_deleted or nc_of_deleted_json or (f.suffix == ".nc" and damaged.get(
                f.with_suffix(".json")) in ("truncate", "garble"))):
            # a damaged sidecar hides the state of its arrays: the stage is recomputed
            # because of the sidecar, which is the file named
            assert str(f) in msgs, (f, how, msgs)
    # everything is whole again: a third run is served from the cache
    again = run(study, out, progress=False, report=False)
    assert set(again.cache_hits) == set(stages)
    stored = json.loads((cache / "control.json").read_text())
    assert stored["arrays_sha256"] and stored["result_sha256"]


def test_damaged_arrays_behind_intact_sidecars(clean_run, tmp_path):
    """Issue 16: a truncated or deleted fe.nc next to a valid .json failed every rerun
    ("stage FAILED: OSError"); 64 garbled bytes in control.nc gave 8.4e+186 in the
    report. Now the checksum in the sidecar catches it and the stage is recomputed."""
    study, out = copy_run(clean_run, tmp_path)
    cache = out / "cache"
    ncs = sorted(cache.glob("*.nc"))
    assert len(ncs) == 7
    for i, nc in enumerate(ncs):
        _damage(nc, DAMAGES[i % 3])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = run(study, out, progress=False, report=False)
    assert not res.failed and not res.unavailable
    assert_same_numbers(clean_run[2].results, res.results)
    for a, b in zip(clean_run[2].arrays["control"].data_vars.values(),
                    res.arrays["control"].data_vars.values()):
        assert abs(b.values).max() < 1e3 and a.shape == b.shape
    msgs = [str(w.message) for w in caught if issubclass(w.category, CacheWarning)]
    assert len(msgs) == 7
    for nc in ncs:
        assert any(str(nc) in m and "--no-cache" in m for m in msgs), (nc, msgs)
    # the only stages without arrays
    assert sorted(res.cache_hits) == ["correlation", "updating"]
