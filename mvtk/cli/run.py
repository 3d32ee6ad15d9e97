"""``mvtk run STUDY.toml --out DIR``: run a validation study and write its report.
"""

from __future__ import annotations

import argparse
import sys
import time

from ._commands import COMMANDS
from ._common import json_document, waiting

__all__ = ["add_parser"]


def _run(args: argparse.Namespace) -> int:
    from ..study import run, study_checks

    t0 = time.perf_counter()
    res = run(args.study, args.out, use_cache=not args.no_cache,
              progress=None if not args.quiet else False, on_wait=waiting)
    dt = time.perf_counter() - t0
    checks = study_checks(res) if res.results else []
    failed_checks = [c for c in checks if not c.passed]
    if args.json:
        from ..validation import check_table

        stages = res.to_dataframe().to_dict(orient="records")
        table = check_table(checks).to_dict(orient="records") if checks else []
        sys.stdout.write(json_document("run", args.study, {
            "report": str(res.report_path) if res.report_path else None,
            "time_s": dt, "cached_stages": list(res.cache_hits),
            "stages": stages, "checks": table,
            "passed": res.ok and not failed_checks}) + "\n")
    for stage, reason in res.unavailable.items():
        print(f"mvtk run: stage {stage} not available: {reason}", file=sys.stderr)
    for stage, reason in res.failed.items():
        print(f"mvtk run: stage {stage} FAILED: {reason}", file=sys.stderr)
    for c in failed_checks:
        print(f"mvtk run: check FAILED: {c.name}: {c.value:.6g} vs {c.reference:.6g} "
              f"{c.unit}".rstrip(), file=sys.stderr)
    if res.report_path is not None and not args.json:
        print(f"report: {res.report_path} ({dt:.1f} s; cached stages: "
              f"{', '.join(res.cache_hits) or 'none'})")
    if args.pdf and res.report_path is not None:
        from ..report import to_pdf

        pdf = to_pdf(res.report_path)
        if not args.json:
            print(f"pdf: {pdf}")
    if res.failed:
        return 2
    return 1 if failed_checks else 0


def add_parser(subparsers) -> None:
    """Register ``mvtk run``."""
    p = subparsers.add_parser(
        "run", help=COMMANDS["run"].help,
        description="Run every stage of a study (cached in OUT/cache) and write the HTML "
        "report. Exit status: 0 all checks passed, 1 a check failed, 2 an error (bad "
        "input, a failed stage), 130 interrupted.",
    )
    p.add_argument("study", help="study TOML file, e.g. data/smart_beam/study.toml")
    p.add_argument("--out", required=True, help="output folder (index.html, tables/, cache/)")
    p.add_argument("--no-cache", action="store_true", help="recompute every stage")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true",
                   help="print the stage and check tables as JSON (schemas/run.schema.json)")
    p.add_argument("--pdf", action="store_true",
                   help="also print the report to DIR/report.pdf with headless Chromium "
                   "(Debian package chromium)")
    p.set_defaults(func=_run)
