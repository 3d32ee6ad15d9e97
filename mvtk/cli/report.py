"""``mvtk report DIR --pdf``: check a written report and print it to PDF.

The page and the tables and cache next to it are first checked against the
``manifest.json`` the run wrote (size and SHA-256 of each file): a page cut short or a
file changed since is refused (exit status 2) before any verdict is printed.
"""

from __future__ import annotations

import argparse
import re
from pathlib import Path

from ..errors import FormatError, ParameterError
from ._commands import COMMANDS

__all__ = ["add_parser"]

_VERDICT = re.compile(r'id="(?:summary-verdict|verdict)"[^>]*>([^<]*)<')


def _report(args: argparse.Namespace) -> int:
    folder = Path(args.dir)
    page = folder / "index.html" if folder.is_dir() else folder
    if not page.is_file():
        raise ParameterError(f"{args.dir!r} is not a report: no index.html there (write one "
                             "with `mvtk run STUDY.toml --out DIR`)")
    if args.pdf:
        from ._common import refuse_inputs

        pdf = args.output if args.output is not None else page.with_name("report.pdf")
        refuse_inputs([("--output", pdf)], _report_inputs(page))
    checked = _verify(page)
    text = page.read_text(encoding="utf-8", errors="replace")
    if not text.rstrip().lower().endswith("</html>"):
        raise FormatError(f"{page}: the page is cut short (it does not end with </html>, "
                          f"{len(text.encode('utf-8'))} bytes); rerun `mvtk run` to rewrite "
                          "it")
    verdicts = _VERDICT.findall(text)
    print(f"report: {page}")
    print(f"integrity: {checked}")
    if verdicts:
        print(f"verdict: {verdicts[0].strip()}")
    if args.pdf:
        from ..report._pdf import to_pdf

        out = to_pdf(page, args.output, timeout=args.timeout)
        print(f"pdf: {out} ({out.stat().st_size / 1024:.0f} kB)")
    return 0


def _verify(page: Path) -> str:
    """Check the page against the run's manifest; the line printed as ``integrity:``."""
    from ..study._manifest import MANIFEST, verify_manifest

    folder = page.parent
    if page.name != "index.html" or not (folder / MANIFEST).is_file():
        return (f"not verified (no {MANIFEST} next to the page: not written by "
                "`mvtk run`, or by an older version)")
    n = verify_manifest(folder)
    if "index.html" not in _claimed(folder):
        raise FormatError(f"{folder / MANIFEST} does not list index.html; rerun `mvtk run`")
    return f"{n} file(s) match {folder / MANIFEST} (SHA-256)"


def _claimed(folder: Path) -> set[str]:
    import json

    from ..study._manifest import MANIFEST

    return set(json.loads((folder / MANIFEST).read_text(encoding="utf-8"))["files"])


def _report_inputs(page: Path) -> list[Path]:
    """The page and every file its manifest claims (none may be overwritten)."""
    from ..study._manifest import MANIFEST

    files = [page]
    if (page.parent / MANIFEST).is_file():
        files += [page.parent / MANIFEST] + [page.parent / r for r in _claimed(page.parent)]
    return files


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
