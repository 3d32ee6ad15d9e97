"""Benchmark of the smart-beam study run and of the report's table rendering.

Run on demand: ``.venv/bin/python benchmarks/bench_study.py``. Prints

- the wall time of ``mvtk.study.run`` on ``data/smart_beam/study.toml`` with an empty
  cache (cold) and again with every stage cached (warm), and their ratio;
- the time of :func:`mvtk.report.render_table` against the peer
  ``pandas.DataFrame.to_html`` on the same 5000-row table, and their ratio.
"""

from __future__ import annotations

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


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = run(ROOT / "data" / "smart_beam" / "study.toml", tmp, progress=False)
        cold = time.perf_counter() - t0
        t0 = time.perf_counter()
        run(ROOT / "data" / "smart_beam" / "study.toml", tmp, progress=False)
        warm = time.perf_counter() - t0
    print(f"smart-beam study, cold cache: {cold:7.2f} s  (stages: "
          + ", ".join(f"{k} {v:.1f} s" for k, v in res.timings_s.items()) + ")")
    print(f"smart-beam study, warm cache: {warm:7.2f} s  (ratio warm/cold {warm / cold:.3f})")
    rng = np.random.default_rng(1)
    df = pd.DataFrame({"a": rng.normal(size=5000), "b": rng.normal(size=5000),
                       "name": [f"row {i}" for i in range(5000)],
                       "passed": rng.normal(size=5000) > 0})
    t_mvtk = _best(lambda: render_table(df))
    t_pandas = _best(lambda: df.to_html())
    print(f"render_table 5000 rows: {t_mvtk * 1e3:7.1f} ms; pandas.to_html (peer): "
          f"{t_pandas * 1e3:7.1f} ms; ratio {t_mvtk / t_pandas:.2f}")
    write_result("study", {
        "figures": {"cold_s": cold, "warm_s": warm, "target_cold_s": 10.0,
                    "stages_s": dict(res.timings_s), "render_table_5000_s": t_mvtk},
        "peer": "pandas.DataFrame.to_html (table rendering)",
        "ratios": {"render_table_pandas_over_mvtk": t_pandas / t_mvtk}})


if __name__ == "__main__":
    main()
