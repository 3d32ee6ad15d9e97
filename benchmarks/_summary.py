"""One JSON summary of every benchmark: ``make bench`` -> reports/bench.json.

Run as a script, it runs every ``benchmarks/bench_*.py`` in a fresh process (one after
the other, so they do not compete for the cores), with the environment variable
``MVTK_BENCH_JSON`` naming a per-benchmark JSON file. A benchmark that supports it
(through :func:`write_result`) writes its figures and peer ratios there; for the others
the summary keeps the last lines of their output. The machine load (1-minute load
average before and after each benchmark, and the core count) is recorded beside every
figure, because the machine is shared.

    python benchmarks/_summary.py [--out reports/bench.json] [--only fe,study] [--quick]
    python benchmarks/_summary.py --collect     # gather reports/bench/*.json only

``--quick`` passes ``--quick`` to benchmarks that accept it (smaller problems).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENV_KEY = "MVTK_BENCH_JSON"


def write_result(name: str, payload: dict) -> None:
    """Write a benchmark's figures to ``$MVTK_BENCH_JSON`` (no-op when unset).

    ``payload`` should hold plain numbers/strings; by convention the keys ``figures``
    (dict of name -> value, SI units in the names: ``_s``, ``_mib``, ``_hz``),
    ``peer`` (name of the peer library or method) and ``ratios`` (dict of name ->
    peer time / mvtk time, > 1 means mvtk is faster).
    """
    path = os.environ.get(ENV_KEY)
    if not path:
        return
    out = {"benchmark": name, "load_avg_1min": os.getloadavg()[0],
           "cpu_count": os.cpu_count(), **payload}
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps(out, indent=2, default=_plain))


def _plain(x):
    try:
        return x.tolist()
    except AttributeError:
        return str(x)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "reports" / "bench.json"))
    ap.add_argument("--only", default="", help="comma-separated names (fe, study, ...)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--collect", action="store_true",
                    help="run nothing: gather the per-benchmark JSON files already in "
                         "reports/bench/ (from runs with MVTK_BENCH_JSON set)")
    args = ap.parse_args()
    out = Path(args.out)
    parts = out.parent / "bench"
    parts.mkdir(parents=True, exist_ok=True)
    only = {s.strip() for s in args.only.split(",") if s.strip()}
    summary = {"created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
               "python": platform.python_version(), "machine": platform.machine(),
               "cpu_count": os.cpu_count(), "benchmarks": {}}
    for script in sorted((ROOT / "benchmarks").glob("bench_*.py")):
        name = script.stem.removeprefix("bench_")
        if only and name not in only:
            continue
        part = parts / f"{name}.json"
        if args.collect:
            for found in sorted(parts.glob(f"{name}*.json")):
                summary["benchmarks"][found.stem] = json.loads(found.read_text())
            continue
        part.unlink(missing_ok=True)
        env = dict(os.environ, **{ENV_KEY: str(part)})
        env["PYTHONPATH"] = str(ROOT) + os.pathsep + env.get("PYTHONPATH", "")
        cmd = [sys.executable, str(script)]
        if args.quick and "--quick" in script.read_text():
            cmd.append("--quick")
        load0 = os.getloadavg()[0]
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT)
        entry = {"returncode": proc.returncode, "wall_s": time.perf_counter() - t0,
                 "load_avg_1min_before": load0, "load_avg_1min_after": os.getloadavg()[0]}
        if part.exists():
            entry.update(json.loads(part.read_text()))
        entry["stdout_tail"] = proc.stdout.strip().splitlines()[-15:]
        if proc.returncode:
            entry["stderr_tail"] = proc.stderr.strip().splitlines()[-15:]
        summary["benchmarks"][name] = entry
        print(f"{name:12s} rc={proc.returncode} {entry['wall_s']:7.1f} s "
              f"(load {load0:.1f} -> {entry['load_avg_1min_after']:.1f})", flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(summary, indent=2, default=_plain))
    print(f"wrote {out}")
    if any(b.get("returncode") for b in summary["benchmarks"].values()):
        sys.exit(1)


if __name__ == "__main__":
    main()
