"""``mvtk report DIR --pdf``: check a written report and print it to PDF."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from ..errors import ParameterError
from ._commands import COMMANDS

__all__ = ["add_parser"]

_VERDICT = re.compile(r'id="(?:summary-verdict|verdict)"[^>]*>([^<]*)<')


def _report(args: argparse.Namespace) -> int:
    folder = Path(args.dir)
    page = folder / "index.html" if folder.is_dir() else folder
    if not page.is_file():
        raise ParameterError(f"{args.dir!r} is not a report: no index.html there (write one "
                             "with `mvtk run STUDY.toml --out DIR`)")
    text = page.read_text(encoding="utf-8", errors="replace")
    verdicts = _VERDICT.findall(text)
    print(f"report: {page}")
    if verdicts:
        print(f"verdict: {verdicts[0].strip()}")
    if args.pdf:
        from ..report._pdf import to_pdf

        out = to_pdf(page, args.output, timeout=args.timeout)
        print(f"pdf: {out} ({out.stat().st_size / 1024:.0f} kB)")
    return 0


def add_parser(subparsers) -> None:
    """Register ``mvtk report``."""
    p = subparsers.add_parser(
        "report", help=COMMANDS["report"].help,
        description=__doc__,
    )
    p.add_argument("dir", help="report folder (with index.html), e.g. the --out of mvtk run")
    p.add_argument("--pdf", action="store_true",
                   help="print the report to PDF with headless Chromium (Debian package "
                        "'chromium')")
    p.add_argument("--output", default=None,
                   help="PDF file (default: DIR/report.pdf)")
    p.add_argument("--timeout", type=float, default=180.0,
                   help="seconds allowed for Chromium (default 180)")
    p.set_defaults(func=_report)
