"""The ``mvtk`` command line: one thin module per sub-command.

``mvtk read PATH``, ``damping FILE``, ``modes STRUCTURE.toml``, ``modal FILE``,
``correlate``, ``init DIR``, ``run STUDY.toml --out DIR``, ``update``, ``reduce``,
``control`` and ``report DIR`` (the table :data:`mvtk.cli._commands.COMMANDS`). Each
module parses its arguments and calls the library or the study pipeline; ``update``,
``reduce``, ``control`` and ``run`` read the study file through the one schema of
:mod:`mvtk.study` and run the stages they need through its cached pipeline. A command's
module is imported only when that command runs, so ``mvtk --help`` starts at once.

Exit status of every command: 0 success; 1 a check failed (``run``) or the update did
not converge (``update``); 2 an error, reported as one line naming the file, key or
path (any :class:`mvtk.errors.MvtkError` or operating-system error); 130 interrupted
(Ctrl-C).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import os
import sys
import warnings

from .. import __version__
from .._interrupt import check_interrupt, forget_unhandled_interrupt, interrupt_latch
from ..errors import MvtkError
from ._commands import COMMANDS

__all__ = ["main", "build_parser", "plain_warnings"]


def _requested(argv: list[str]) -> str | None:
    """The sub-command named on the command line (the first word that is not an option)."""
    for word in argv:
        if word == "--":
            return None
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(command: str | None = "*") -> argparse.ArgumentParser:
    """The ``mvtk`` argument parser.

    Parameters
    ----------
    command : str or None
        The sub-command whose module is imported to define its arguments; the others
        are listed by name and help only. ``"*"`` (default) imports every command
        module (the full parser, as the documentation prints it); None imports none.
    """
    parser = argparse.ArgumentParser(
        prog="mvtk", description="mvtk: structural dynamics model validation"
    )
    parser.add_argument("--version", action="version", version=f"mvtk {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, cmd in COMMANDS.items():
        if command in ("*", name):
            importlib.import_module(cmd.module).add_parser(subparsers)
        else:
            subparsers.add_parser(name, help=cmd.help, add_help=False)
    return parser


def _one_line(text: str) -> str:
    return " ".join(part.strip() for part in str(text).splitlines() if part.strip())


def _os_message(err: OSError) -> str:
    """``path: reason`` of an operating-system error (both paths of a rename)."""
    reason = err.strerror or type(err).__name__
    paths = [str(p) for p in (err.filename, err.filename2) if p is not None]
    if paths:
        return f"{' -> '.join(paths)}: {reason}"
    return _one_line(str(err)) or reason


@contextlib.contextmanager
def plain_warnings(prog: str):
    """Show warnings that reach the top as one line ``prog: Category: message``.

    Python's default display adds the library's file, line number and source line,
    which tell a command-line user nothing; commands that collect their warnings into
    their output are not affected.
    """
    old = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        stream = file if file is not None else sys.stderr
        with contextlib.suppress(OSError, ValueError):
            print(f"{prog}: {category.__name__}: {_one_line(message)}", file=stream)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = old


def main(argv: list[str] | None = None) -> int:
    """Run the ``mvtk`` command line; returns the exit status (see the module docstring)."""
    try:
        argv = sys.argv[1:] if argv is None else list(argv)
        parser = build_parser(_requested(argv))
        args = parser.parse_args(argv)
    except KeyboardInterrupt:  # during start-up (imports)
        forget_unhandled_interrupt()
        print("mvtk: interrupted", file=sys.stderr)
        return 130
    if args.command is None:
        parser.print_help()
        return 0
    prog = f"mvtk {args.command}"
    try:
        with interrupt_latch(), plain_warnings(prog):
            status = int(args.func(args) or 0)
            check_interrupt()  # received, but swallowed where Python cannot raise it
        return status
    except KeyboardInterrupt:
        forget_unhandled_interrupt()
        print(f"{prog}: interrupted", file=sys.stderr)
        return 130
    except MvtkError as err:
        print(f"{prog}: error: {_one_line(err)}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into a command that stopped reading
        with contextlib.suppress(OSError):
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the final flush
        return 0
    except OSError as err:
        print(f"{prog}: error: {_os_message(err)}", file=sys.stderr)
        return 2
    except UnicodeDecodeError as err:
        print(f"{prog}: error: a file is not UTF-8 text: byte 0x{err.object[err.start]:02x} "
              f"at offset {err.start}; save it as UTF-8", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
