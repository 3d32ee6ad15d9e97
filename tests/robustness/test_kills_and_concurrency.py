"""Families "kills" and "concurrency": `mvtk run` killed (SIGKILL) at random points and
rerun, and two runs into one --out at once, must end with the report numbers of a clean
run."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from robust_helpers import write_fast_study

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]
#: Tables whose content is not a result (timings, dates, cache status).
_VOLATILE = {"run_stages.csv", "provenance_versions.csv", "provenance_files.csv",
             "provenance_inputs.csv"}


def _cmd(study: Path, out: Path) -> list[str]:
    return [sys.executable, "-m", "mvtk", "run", str(study), "--out", str(out), "--quiet"]


def _env():
    return {**os.environ, "PYTHONPATH": str(ROOT) + os.pathsep + os.environ.get(
        "PYTHONPATH", "")}


def _same_tables(a: Path, b: Path) -> None:
    names = sorted(p.name for p in (a / "tables").glob("*.csv"))
    assert names == sorted(p.name for p in (b / "tables").glob("*.csv"))
    for name in names:
        if name in _VOLATILE:
            continue
        ta, tb = pd.read_csv(a / "tables" / name), pd.read_csv(b / "tables" / name)
        assert list(ta.columns) == list(tb.columns) and ta.shape == tb.shape, name
        for col in ta.columns:
            x, y = ta[col], tb[col]
            if pd.api.types.is_numeric_dtype(x) and pd.api.types.is_numeric_dtype(y):
                # see conftest.assert_same_numbers for the tolerance; errors of nearly
                # exact values (an updated f1 off by 1e-7 %) move at the column's scale
                v = np.abs(x.to_numpy(float))
                scale = float(np.max(v[np.isfinite(v)], initial=0.0))
                if "%" in col or "error" in col:  # errors in % of nearly exact values
                    scale = max(scale, 10.0)
                assert np.allclose(x, y, rtol=1e-4, atol=1e-7 + 1e-5 * scale,
                                   equal_nan=True), (name, col)
            elif col not in ("note", "source"):
                assert (x.fillna("").astype(str) == y.fillna("").astype(str)).all(), (name, col)


def test_killed_runs_then_rerun_give_the_clean_report(clean_run, tmp_path):
    study = write_fast_study(tmp_path / "in")
    out = tmp_path / "out"
    rng = np.random.default_rng(16)
    kills = sorted(rng.uniform(2.0, 30.0, size=3))
    states = []
    for t_kill in kills:
        proc = subprocess.Popen(_cmd(study, out), env=_env(), stdout=subprocess.DEVNULL,
                                stderr=subprocess.PIPE)
        time.sleep(t_kill)
        proc.kill()  # SIGKILL: no cleanup, possibly mid-write
        proc.wait(timeout=60)
        states.append(sorted(p.name for p in (out / "cache").glob("*"))
                      if (out / "cache").is_dir() else [])
    done = subprocess.run(_cmd(study, out), env=_env(), capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, (states, done.stderr)
    assert "Traceback" not in done.stderr
    _same_tables(clean_run[1], out)
    assert not list((out / "cache").glob(".*.tmp"))  # temporaries of killed runs removed


def test_two_concurrent_runs_into_one_folder(clean_run, tmp_path):
    """Issue 16: two runs into one --out at once: one died with BlockingIOError."""
    study = write_fast_study(tmp_path / "in")
    out = tmp_path / "out"
    procs = [subprocess.Popen(_cmd(study, out), env=_env(), stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [p.communicate(timeout=900) for p in procs]
    codes = [p.returncode for p in procs]
    errs = [r[1] for r in results]
    assert codes == [0, 0], errs
    assert not any("BlockingIOError" in e or "Traceback" in e for e in errs), errs
    assert sum("is in use by another mvtk run" in e and "waiting" in e for e in errs) == 1
    # the second run was served from the first one's cache
    cached = "cached stages: ingest, modal, fe, updating, correlation"
    assert sum(cached in r[0] for r in results) == 1
    _same_tables(clean_run[1], out)


def _children(pid: int) -> list[int]:
    """Process ids whose parent is ``pid`` (Linux /proc)."""
    kids = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            kids.append(int(stat.parent.name))
    return kids


def _running(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state not in ("Z", "X")


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_a_killed_run_leaves_no_worker_holding_the_folder(tmp_path):
    """A forked stage worker (ingest, Monte Carlo) of a run killed with SIGKILL used to
    live on holding the output folder's lock, and the rerun waited for ever. The worker
    now dies with its parent and never holds the lock itself."""
    from mvtk.study._cache import OutputLock

    study = write_fast_study(tmp_path / "in")
    out = tmp_path / "out"
    proc = subprocess.Popen(_cmd(study, out), env=_env(), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    t0, kids = time.monotonic(), []
    while not kids and proc.poll() is None and time.monotonic() - t0 < 120:
        kids = [k for k in _children(proc.pid) if _running(k)]
        time.sleep(0.02)
    assert kids, "the run started no worker process"
    proc.kill()
    proc.wait(timeout=60)
    t0 = time.monotonic()
    while any(_running(k) for k in kids) and time.monotonic() - t0 < 20:
        time.sleep(0.1)
    assert not any(_running(k) for k in kids), "a worker outlived the killed run"
    with OutputLock(out, timeout_s=5.0):   # the folder is free at once
        pass
