"""Start-up time of the ``mvtk`` command line, median of N runs each, in wall and CPU time.

    python benchmarks/bench_startup.py [--runs 10]

Cases: ``mvtk --version``, ``mvtk --help``, ``mvtk read small.csv`` (a 4-channel,
1000-sample CSV written here), and, as peers run in the same script, bare Python
(``python -c pass``) and the same CSV read by ``pandas.read_csv`` in a fresh Python
(the least any reader needs: the interpreter plus pandas). The ratios are
``mvtk time / peer time`` (1 would be as fast as the peer).
Targets: ``--help`` under 0.3 s and ``read`` under 1 s on a 2-core machine.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _summary import write_result  # noqa: E402


def _time(cmd: list[str], runs: int) -> tuple[float, float]:
    """Median wall and CPU (user + sys of the child) seconds of ``runs`` runs."""
    walls, cpus = [], []
    for _ in range(runs):
        r0 = os.times()
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        walls.append(time.perf_counter() - t0)
        r1 = os.times()
        cpus.append((r1.children_user - r0.children_user)
                    + (r1.children_system - r0.children_system))
    return statistics.median(walls), statistics.median(cpus)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10)
    args = ap.parse_args()
    py = sys.executable
    mvtk = [py, "-m", "mvtk"]
    with tempfile.TemporaryDirectory() as tmp:
        csv = Path(tmp) / "small.csv"
        lines = ["time,force,acc1,acc2,acc3"]
        lines += [f"{i / 1000:.6f},{(i % 7) * 0.1:.3f},{(i % 5) * 0.2:.3f},"
                  f"{(i % 3) * 0.3:.3f},{(i % 11) * 0.01:.3f}" for i in range(1000)]
        csv.write_text("\n".join(lines) + "\n")
        read = [*mvtk, "read", str(csv), "--units", "N", "m/s^2", "m/s^2", "m/s^2"]
        cases = {
            "python_pass": [py, "-c", "pass"],
            "pandas_read_csv": [py, "-c", f"import pandas; pandas.read_csv({str(csv)!r})"],
            "mvtk_version": [*mvtk, "--version"],
            "mvtk_help": [*mvtk, "--help"],
            "mvtk_read_small_csv": read,
        }
        subprocess.run(read, check=True, stdout=subprocess.DEVNULL)   # warm the file cache
        res = {name: _time(cmd, args.runs) for name, cmd in cases.items()}
    print(f"start-up, median of {args.runs} runs (load {os.getloadavg()[0]:.2f}, "
          f"{os.cpu_count()} cores)")
    print(f"{'case':22s} {'wall [s]':>9s} {'CPU [s]':>9s}")
    for name, (wall, cpu) in res.items():
        print(f"{name:22s} {wall:9.3f} {cpu:9.3f}")
    ratios = {
        "help_vs_bare_python": res["mvtk_help"][0] / res["python_pass"][0],
        "read_vs_pandas_read_csv": res["mvtk_read_small_csv"][0] / res["pandas_read_csv"][0],
    }
    for k, v in ratios.items():
        print(f"{k}: {v:.2f}x (wall)")
    print(f"targets: --help < 0.3 s: {res['mvtk_help'][0] < 0.3}; "
          f"read < 1 s: {res['mvtk_read_small_csv'][0] < 1.0}")
    write_result("startup", {
        "figures": {f"{k}_wall_s": v[0] for k, v in res.items()}
        | {f"{k}_cpu_s": v[1] for k, v in res.items()},
        "peer": "bare Python; pandas.read_csv in a fresh Python",
        "ratios": ratios,
    })


if __name__ == "__main__":
    main()
