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
    python benchmarks/_summary.py --markdown    # print the latest summary as a table

``--markdown`` runs nothing: it renders ``--out`` (default ``reports/bench.json``) as a
markdown table (one row per benchmark: headline figures, peer, ratios, machine load),
ready to paste into the README.

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
           "cpu_count": os.cpu_count(), "sparse_backend": _sparse_backend(), **payload}
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps(out, indent=2, default=_plain))


def _sparse_backend() -> str:
    """The factorisation backend of this installation (``mvtk.fe.sparse_backend``)."""
    try:
        from mvtk.fe import sparse_backend
    except ImportError as err:  # a benchmark run outside the project
        return f"unknown ({err})"
    return sparse_backend(detail=True)


def _plain(x):
    try:
        return x.tolist()
    except AttributeError:
        return str(x)


#: Further runs of a benchmark script with options, each its own entry in the summary.
EXTRA_RUNS = {"fe_million": ("bench_fe.py", ["--million"])}

#: Figures shown in the markdown table per benchmark (others: the first scalar ones).
HEADLINE = {
    "fe": ("n_dof", "median_total_s", "median_eigsh_s", "limit_ratio",
           "opensees_median_eigen_s", "fn_max_rel_diff_vs_opensees"),
    "fe_million": ("n_dof", "total_s", "process_wall_s", "peak_rss_mib"),
    "study": ("cold_s", "cold_cpu_s", "warm_s", "target_cold_s"),
}
_MAX_FIGURES = 4


def _fmt(x) -> str:
    """A number with 3 significant digits (thousands separated for integers)."""
    if isinstance(x, bool) or not isinstance(x, int | float):
        return str(x)
    if isinstance(x, int) or float(x).is_integer() and abs(x) >= 1000:
        return f"{int(x):,}"
    if x != x:  # NaN
        return "n/a"
    return f"{x:.3g}"


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def markdown_table(summary: dict) -> str:
    """Markdown table of a summary written by :func:`main` (one row per benchmark).

    The heading names the run's date, Python, cores and the sparse factorisation
    backend the benchmarks ran with (:func:`mvtk.fe.sparse_backend`, with versions).
    Columns: benchmark, headline figures (:data:`HEADLINE`, else the first scalar
    figures; ``_s`` seconds, ``_mib`` MiB), the peer, the ratios (peer time / mvtk time:
    > 1 means mvtk is faster, unless the name says otherwise) and the 1-minute load
    average when it ran (the machine is shared). A benchmark that failed shows its
    return code.
    """
    backends = sorted({str(b["sparse_backend"]) for b in
                       summary.get("benchmarks", {}).values() if b.get("sparse_backend")})
    head = (f"Benchmarks of {summary.get('created_utc', '?')} (Python "
            f"{summary.get('python', '?')}, {summary.get('cpu_count', '?')} cores; "
            f"sparse factorisation {' / '.join(backends) or 'not recorded'}; "
            "`make bench`, reports/bench.json)")
    rows = ["| benchmark | figures | peer | ratios | load |", "|---|---|---|---|---|"]
    for name, b in summary.get("benchmarks", {}).items():
        figs = b.get("figures") or {}
        scalar = {k: v for k, v in figs.items()
                  if isinstance(v, int | float) and not isinstance(v, bool)}
        keys = [k for k in HEADLINE.get(name, ()) if k in scalar] \
            or list(scalar)[:_MAX_FIGURES]
        shown = ", ".join(f"{k} {_fmt(scalar[k])}" for k in keys)
        if b.get("returncode"):
            shown = f"FAILED (return code {b['returncode']}) " + shown
        elif not figs:
            tail = b.get("stdout_tail") or []
            shown = tail[-1] if tail else ""
        ratios = ", ".join(f"{k} {_fmt(v)}" for k, v in (b.get("ratios") or {}).items()
                           if isinstance(v, int | float))
        load = b.get("load_avg_1min_before", b.get("load_avg_1min"))
        rows.append(f"| {_cell(name)} | {_cell(shown)} | {_cell(b.get('peer', ''))} | "
                    f"{_cell(ratios)} | {_fmt(load) if load is not None else ''} |")
    return head + "\n\n" + "\n".join(rows) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "reports" / "bench.json"))
    ap.add_argument("--only", default="", help="comma-separated names (fe, study, ...)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--collect", action="store_true",
                    help="run nothing: gather the per-benchmark JSON files already in "
                         "reports/bench/ (from runs with MVTK_BENCH_JSON set)")
    ap.add_argument("--markdown", action="store_true",
                    help="run nothing: print --out as a markdown table (for the README)")
    args = ap.parse_args()
    out = Path(args.out)
    if args.markdown:
        if not out.is_file():
            sys.exit(f"{out} does not exist: run `make bench` (or this script) first")
        try:
            summary = json.loads(out.read_text())
        except ValueError as err:
            sys.exit(f"{out} is not a JSON summary: {err}")
        sys.stdout.write(markdown_table(summary))
        return
    parts = out.parent / "bench"
    parts.mkdir(parents=True, exist_ok=True)
    only = {s.strip() for s in args.only.split(",") if s.strip()}
    summary = {"created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
               "python": platform.python_version(), "machine": platform.machine(),
               "cpu_count": os.cpu_count(), "benchmarks": {}}
    runs = [(s.stem.removeprefix("bench_"), s, [])
            for s in sorted((ROOT / "benchmarks").glob("bench_*.py"))]
    runs += [(name, ROOT / "benchmarks" / script, extra) for name, (script, extra)
             in EXTRA_RUNS.items()]
    for name, script, extra in runs:
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
        cmd = [sys.executable, str(script), *extra]
        if args.quick and not extra and "--quick" in script.read_text():
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
