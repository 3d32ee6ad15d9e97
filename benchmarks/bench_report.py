"""Benchmark of the report of a cached smart-beam study (every stage loaded from cache).

Run on demand: ``.venv/bin/python benchmarks/bench_report.py [--repeats 3] [--out DIR]``.
Fills ``DIR`` (default: a temporary folder) with a cold run first, then times, in fresh
processes (imports paid as in ``mvtk run``), alternating:

- the report with figures rendered in forked processes (the default,
  ``MVTK_REPORT_WORKERS`` unset: one process per usable CPU);
- the report rendered in one process (``MVTK_REPORT_WORKERS=1``, the peer);

each as wall time and CPU time (main process + render processes), with the load
average. Then one in-process table: render CPU time, format and bytes per figure.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))
from _summary import write_result  # noqa: E402

STUDY = ROOT / "data" / "smart_beam" / "study.toml"

_CHILD = """
import json, os, resource, sys, time
from mvtk.study import run
from mvtk.study._report import build_report

def cpu():
    a = resource.getrusage(resource.RUSAGE_SELF)
    b = resource.getrusage(resource.RUSAGE_CHILDREN)
    return a.ru_utime + a.ru_stime, b.ru_utime + b.ru_stime

res = run(sys.argv[1], sys.argv[2], progress=False, report=False)
assert len(res.cache_hits) == len(res.results), "the study is not fully cached"
s0, k0 = cpu()
t0 = time.perf_counter()
page = build_report(res, {})
wall = time.perf_counter() - t0
s1, k1 = cpu()
print(json.dumps({"wall_s": wall, "cpu_main_s": s1 - s0, "cpu_children_s": k1 - k0,
                  "load": os.getloadavg()[0], "page_bytes": page.stat().st_size}))
"""


def _warm(out: str, workers: str | None) -> dict:
    env = dict(os.environ)
    env.pop("MVTK_REPORT_WORKERS", None)
    if workers is not None:
        env["MVTK_REPORT_WORKERS"] = workers
    p = subprocess.run([sys.executable, "-c", _CHILD, str(STUDY), out], env=env,
                       capture_output=True, text=True, check=True)
    return json.loads(p.stdout.strip().splitlines()[-1])


def _per_figure(out: str) -> list[tuple[str, str, int, float]]:
    """(title, mime, bytes, CPU s) of each figure, built (when the report passes a
    function) and rendered in this process."""
    import mvtk.report._render as R
    from mvtk.study import run
    from mvtk.study._report import build_report

    res = run(STUDY, out, progress=False, report=False)
    rows = []
    real = R.render_figure

    def timed(fig, fmt="auto"):
        c0 = time.process_time()
        if not isinstance(fig, bytes | bytearray) and not hasattr(fig, "savefig"):
            fig = fig()    # built in the render process: its time counts here
        mime, data = real(fig, fmt)
        title = "(bytes from a stage)"
        if not isinstance(fig, bytes | bytearray):
            titles = [ax.get_title() for ax in fig.axes if ax.get_title()]
            sup = fig._suptitle.get_text() if fig._suptitle is not None else ""
            title = (titles or [sup or "?"])[0]
        rows.append((title, mime, len(data), time.process_time() - c0))
        return mime, data

    R.render_figure = timed
    os.environ["MVTK_REPORT_WORKERS"] = "1"
    try:
        build_report(res, {})
    finally:
        R.render_figure = real
        os.environ.pop("MVTK_REPORT_WORKERS", None)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", help="study output folder to reuse (cached stages)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or tmp
        from mvtk.study import run

        run(STUDY, out, progress=False)   # fills the cache (cold only the first time)
        par, ser = [], []
        for _ in range(max(1, args.repeats)):
            par.append(_warm(out, None))
            ser.append(_warm(out, "1"))
        rows = _per_figure(out)

    def med(runs, key):
        return float(np.median([r[key] for r in runs]))

    for name, runs in (("forked render processes (default)", par),
                       ("one process (MVTK_REPORT_WORKERS=1, peer)", ser)):
        print(f"warm report, {name}: median {med(runs, 'wall_s'):.2f} s wall, CPU main "
              f"{med(runs, 'cpu_main_s'):.2f} s + render processes "
              f"{med(runs, 'cpu_children_s'):.2f} s  (runs: "
              + ", ".join(f"{r['wall_s']:.1f} s / {r['cpu_main_s'] + r['cpu_children_s']:.1f}"
                          f" s CPU at load {r['load']:.1f}" for r in runs) + ")")
    print(f"page {par[0]['page_bytes'] / 1e6:.2f} MB; target 3 s wall")
    print("per figure, in one process: build (if deferred) + render CPU")
    print(f"{'figure':50s} {'format':>14s} {'bytes':>8s} {'CPU s':>6s}")
    for title, mime, size, cpu in rows:
        print(f"{title[:50]:50s} {mime:>14s} {size:8d} {cpu:6.3f}")
    print(f"{'sum':50s} {'':>14s} {sum(r[2] for r in rows):8d} "
          f"{sum(r[3] for r in rows):6.3f}")
    write_result("report", {
        "figures": {"warm_report_s": med(par, "wall_s"),
                    "warm_report_cpu_s": med(par, "cpu_main_s") + med(par, "cpu_children_s"),
                    "warm_report_serial_s": med(ser, "wall_s"),
                    "warm_report_serial_cpu_s": med(ser, "cpu_main_s"),
                    "target_s": 3.0, "page_mb": par[0]["page_bytes"] / 1e6,
                    "figure_render_cpu_s": {r[0]: r[3] for r in rows}},
        "peer": "the same report rendered in one process (MVTK_REPORT_WORKERS=1)",
        "ratios": {"serial_over_parallel_wall": med(ser, "wall_s") / med(par, "wall_s")}})


if __name__ == "__main__":
    main()
