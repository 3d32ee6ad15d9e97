"""The ``mvtk`` command line.

Each stage contributes its sub-command from a private ``_cli`` module exposing
``add_parser(subparsers)``:

- ``mvtk read PATH``             (:mod:`mvtk.io`)
- ``mvtk damping FILE``          (:mod:`mvtk.damping`)
- ``mvtk modes STRUCTURE.toml``  (:mod:`mvtk.fe`)
- ``mvtk update STUDY.toml``     (:mod:`mvtk.updating`)
- ``mvtk reduce STUDY.toml``     (:mod:`mvtk.reduction`)
- ``mvtk control STUDY.toml``    (:mod:`mvtk.control`)
- ``mvtk run STUDY.toml --out DIR`` (:mod:`mvtk.study`)
"""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import sys

from . import __version__
from .errors import MvtkError

#: Modules that register sub-commands, in the order they appear in ``mvtk --help``.
COMMAND_MODULES = (
    "mvtk._run_cli",
    "mvtk.io._cli",
    "mvtk.damping._cli",
    "mvtk.fe._cli",
    "mvtk.updating._cli",
    "mvtk.reduction._cli",
    "mvtk.control._cli",
    "mvtk.report._cli",
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mvtk", description="mvtk: structural dynamics model validation"
    )
    parser.add_argument("--version", action="version", version=f"mvtk {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        if importlib.util.find_spec(name) is None:
            continue
        importlib.import_module(name).add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_help()
        return 0
    try:
        return int(args.func(args) or 0)
    except MvtkError as err:
        print(f"mvtk {args.command}: error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
