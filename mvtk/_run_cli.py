"""``mvtk run STUDY.toml --out DIR``: run a validation study and write its report."""

from __future__ import annotations

import argparse
import sys
import time

__all__ = ["add_parser"]


def _run(args: argparse.Namespace) -> int:
    from .study import run

    t0 = time.perf_counter()
    res = run(args.study, args.out, use_cache=not args.no_cache,
              progress=None if not args.quiet else False)
    dt = time.perf_counter() - t0
    for stage, reason in res.unavailable.items():
        print(f"mvtk run: stage {stage} not available: {reason}", file=sys.stderr)
    for stage, reason in res.failed.items():
        print(f"mvtk run: stage {stage} FAILED: {reason}", file=sys.stderr)
    if res.report_path is not None:
        print(f"report: {res.report_path} ({dt:.1f} s; cached stages: "
              f"{', '.join(res.cache_hits) or 'none'})")
    return 0 if res.ok else 1


def add_parser(subparsers) -> None:
    """Register ``mvtk run``."""
    p = subparsers.add_parser(
        "run", help="run a validation study (TOML) and write the HTML report",
        description=__doc__,
    )
    p.add_argument("study", help="study TOML file, e.g. data/smart_beam/study.toml")
    p.add_argument("--out", required=True, help="output folder (index.html, tables/, cache/)")
    p.add_argument("--no-cache", action="store_true", help="recompute every stage")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=_run)
