"""Benchmark of the smart-beam study run and of the report's table rendering.

Run on demand: ``.venv/bin/python benchmarks/bench_study.py [--repeats 3] [--serial]``.
Prints

- the wall and CPU time (this process plus its worker processes) of ``mvtk.study.run``
  on ``data/smart_beam/study.toml`` with an empty cache (cold, ``--repeats`` runs, each
  in a fresh folder; median) and again with every stage cached (warm), and their ratio;
  the wall and CPU time of each stage of the first cold run (a stage computed in a
  worker process: the worker's own times). ``--serial`` also times cold runs
  with ``parallel=False`` (the Monte-Carlo stage in process) for comparison;
- the time of :func:`mvtk.report.render_table` against the peer
  ``pandas.DataFrame.to_html`` on the same 5000-row table, and their ratio.
"""

from __future__ import annotations

import argparse
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

from mvtk.report import render_table
from mvtk.study import run

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _summary import write_result  # noqa: E402


def _best(fn, repeat: int = 3) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _cpu() -> float:
    """CPU time (s) of this process and of its finished worker processes."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _cold(parallel: bool, repeats: int):
    """(wall times, CPU times, first result) of ``repeats`` cold runs."""
    walls, cpus, first = [], [], None
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as tmp:
            t0, c0 = time.perf_counter(), _cpu()
            res = run(STUDY, tmp, progress=False, parallel=parallel)
            walls.append(time.perf_counter() - t0)
            cpus.append(_cpu() - c0)
        if res.failed:
            raise SystemExit(f"the study failed: {res.failed}")
        first = first or res
    return walls, cpus, first


STUDY = ROOT / "data" / "smart_beam" / "study.toml"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="cold runs (median)")
    ap.add_argument("--serial", action="store_true",
                    help="also time cold runs with parallel=False")
    ap.add_argument("--quick", action="store_true", help="one cold run")
    args = ap.parse_args()
    repeats = 1 if args.quick else max(1, args.repeats)
    # imports and first-call costs are paid once per process, as in `mvtk run`: the
    # first cold run includes them
    walls, cpus, res = _cold(True, repeats)
    cold, cold_cpu = float(np.median(walls)), float(np.median(cpus))
    with tempfile.TemporaryDirectory() as tmp:
        run(STUDY, tmp, progress=False)
        t0 = time.perf_counter()
        run(STUDY, tmp, progress=False)
        warm = time.perf_counter() - t0
    print(f"smart-beam study, cold cache: median {cold:7.2f} s wall, {cold_cpu:.2f} s CPU "
          f"(runs: {', '.join(f'{w:.1f} s / {c:.1f} s' for w, c in zip(walls, cpus))}; "
          "target 10 s wall)")
    print("  stages of the first run, wall / CPU (ingest, fe, correlation and uncertainty "
          "in worker processes): "
          + ", ".join(f"{k} {v:.1f} / {res.cpu_s.get(k, float('nan')):.1f} s"
                      for k, v in res.timings_s.items()))
    print(f"smart-beam study, warm cache: {warm:7.2f} s  (ratio warm/cold {warm / cold:.3f})")
    serial = {}
    if args.serial:
        sw, sc, _ = _cold(False, repeats)
        serial = {"cold_serial_s": float(np.median(sw)), "cold_serial_cpu_s":
                  float(np.median(sc))}
        print(f"  serial (parallel=False): median {serial['cold_serial_s']:.2f} s wall, "
              f"{serial['cold_serial_cpu_s']:.2f} s CPU")
    rng = np.random.default_rng(1)
    df = pd.DataFrame({"a": rng.normal(size=5000), "b": rng.normal(size=5000),
                       "name": [f"row {i}" for i in range(5000)],
                       "passed": rng.normal(size=5000) > 0})
    t_mvtk = _best(lambda: render_table(df))
    t_pandas = _best(lambda: df.to_html())
    print(f"render_table 5000 rows: {t_mvtk * 1e3:7.1f} ms; pandas.to_html (peer): "
          f"{t_pandas * 1e3:7.1f} ms; ratio {t_mvtk / t_pandas:.2f}")
    write_result("study", {
        "figures": {"cold_s": cold, "cold_cpu_s": cold_cpu, "warm_s": warm,
                    "target_cold_s": 10.0, "cold_runs_s": walls, "cold_runs_cpu_s": cpus,
                    **serial,
                    "stages_s": dict(res.timings_s), "stages_cpu_s": dict(res.cpu_s),
                    "render_table_5000_s": t_mvtk},
        "peer": "pandas.DataFrame.to_html (table rendering)",
        "ratios": {"render_table_pandas_over_mvtk": t_pandas / t_mvtk}})


if __name__ == "__main__":
    main()
