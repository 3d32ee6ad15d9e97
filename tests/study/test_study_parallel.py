"""Stages computed in a forked worker process (``run(parallel=True)``, the default).

The ``ingest`` and ``uncertainty`` stages run beside the others; their results, cache
entries and failure messages must be those of the in-process run (``parallel=False``).
"""

from __future__ import annotations

import dataclasses
import multiprocessing as mp
from pathlib import Path

import numpy as np
import pytest

import mvtk.study._stages as st
from mvtk.study import load_study, run

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"

pytestmark = pytest.mark.skipif("fork" not in mp.get_all_start_methods(),
                                reason="worker processes need the fork start method")


@pytest.fixture(scope="module")
def small():
    """The smart-beam study without updating and with a 4-sample Monte Carlo."""
    study = load_study(STUDY)
    cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in study.config.items()}
    for sec in ("updating", "modal"):
        cfg.pop(sec, None)
    cfg["uncertainty"]["n_samples"] = 4
    cfg["uncertainty"]["n_modes"] = 2
    cfg["damping"]["broadband_fn_hz"] = []
    return dataclasses.replace(study, config=cfg)


def _with_scatter(study, scatter):
    cfg = dict(study.config)
    cfg["uncertainty"] = dict(cfg["uncertainty"], scatter=scatter)
    return dataclasses.replace(study, config=cfg)


STAGES = ["uncertainty", "damping"]   # with fe and ingest, which they need


@pytest.mark.slow
def test_worker_results_equal_in_process_and_are_cached(tmp_path, small):
    par = run(small, tmp_path / "par", stages=STAGES)
    ser = run(small, tmp_path / "ser", stages=STAGES, parallel=False)
    assert par.ok and ser.ok, (par.failed, ser.failed)
    assert set(par.results) == {"ingest", "fe", "uncertainty", "damping"}
    for name in ("ingest", "uncertainty", "damping"):
        assert par.results[name] == ser.results[name], name
    assert par.arrays["uncertainty"].equals(ser.arrays["uncertainty"])
    assert par.arrays["ingest"].equals(ser.arrays["ingest"])
    assert np.isfinite(par.results["uncertainty"]["statistics"][0]["std_hz"])
    # the worker's stage time is its own compute time, in STAGES order
    assert list(par.timings_s)[:2] == ["ingest", "fe"] and par.timings_s["uncertainty"] > 0
    # the cache entries the workers' results went to serve the next run (no worker then)
    again = run(small, tmp_path / "par", stages=STAGES)
    assert set(again.cache_hits) == {"ingest", "fe", "uncertainty", "damping"}
    assert again.results["uncertainty"] == par.results["uncertainty"]


def test_worker_config_error_reported_like_in_process(tmp_path, small):
    bad = _with_scatter(small, {"materials.steel.nope": 0.03})
    par = run(bad, tmp_path / "par", stages=["uncertainty"])
    ser = run(bad, tmp_path / "ser", stages=["uncertainty"], parallel=False)
    assert "uncertainty" in par.failed and "fe" in par.results
    assert par.failed == ser.failed
    assert "uncertainty.scatter.'materials.steel.nope'" in par.failed["uncertainty"]


def test_worker_internal_error_names_its_line(tmp_path, small, monkeypatch):
    def broken(study, description):
        raise RuntimeError("boom in the worker")

    monkeypatch.setattr(st, "uncertainty", broken)
    par = run(small, tmp_path / "par", stages=["uncertainty"])
    ser = run(small, tmp_path / "ser", stages=["uncertainty"], parallel=False)
    msg = par.failed["uncertainty"]
    assert msg.startswith("internal error RuntimeError: boom in the worker (at "
                          "test_study_parallel.py:")
    assert msg.endswith("please report it") and msg == ser.failed["uncertainty"]
    # no result, no cache entry for the failed stage
    assert "uncertainty" not in par.results
    assert not (tmp_path / "par" / "cache" / "uncertainty.json").exists()
