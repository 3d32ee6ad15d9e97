"""``mvtk read``: read a measurement file, print its layout, optionally write netCDF."""

from __future__ import annotations

import argparse
import json

__all__ = ["add_parser", "add_reader_options", "parse_option", "reader_options", "summary"]


def parse_option(text: str) -> tuple[str, object]:
    """``"key=value"`` -> (key, value); the value is JSON when it parses, else a string."""
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    try:
        return key, json.loads(value)
    except json.JSONDecodeError:
        return key, value


def add_reader_options(parser: argparse.ArgumentParser) -> None:
    """Add the reader options group shared by ``mvtk read``, ``damping`` and ``modal``.

    Every option of :func:`mvtk.io.read` is reachable as ``--set KEY=VALUE``; the common
    ones (the ones a reader's error message asks for when a file does not state them)
    have their own flags: ``--units``, ``--quantity``, ``--fs`` and ``--variable``
    (the reader option ``data=``).
    """
    rd = parser.add_argument_group("reader options (mvtk.io.read)")
    rd.add_argument("--format", default=None, help="force a reader (default: detect)")
    rd.add_argument("--set", action="append", type=parse_option, metavar="KEY=VALUE",
                    help="reader option, value as JSON or text (repeatable), e.g. "
                    "--set units='[\"N\", \"m/s^2\"]'")
    rd.add_argument("--variable", nargs="+", default=None, metavar="NAME",
                    help="variable(s) of the file holding the data (reader option data=)")
    rd.add_argument("--units", nargs="+", default=None, metavar="UNIT",
                    help="units per channel, for files that store none (reader option "
                    "units=), e.g. --units N m/s^2 V")
    rd.add_argument("--quantity", nargs="+", default=None, metavar="Q",
                    help="quantity per channel, e.g. force acceleration (reader option "
                    "quantity=)")
    rd.add_argument("--fs", type=float, default=None, metavar="HZ",
                    help="sampling rate in Hz, for files that store none (reader option fs=)")


def reader_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`mvtk.io.read` given by :func:`add_reader_options`.

    The named flags win over the same key given with ``--set``; ``format`` is included
    when given.
    """
    opts = dict(args.set or [])
    for key, val in (("units", args.units), ("quantity", args.quantity), ("fs", args.fs)):
        if val is not None:
            opts[key] = val
    if args.variable is not None:
        opts["data"] = args.variable[0] if len(args.variable) == 1 else args.variable
    if args.format is not None:
        opts["format"] = args.format
    return opts


def summary(ds) -> str:
    """A plain-text description of a Dataset returned by ``mvtk.io.read``."""
    out = [f"{ds.attrs.get('source', '?')} ({ds.attrs.get('format', '?')})"]
    for name, var in ds.data_vars.items():
        dims = ", ".join(f"{d}={n}" for d, n in var.sizes.items())
        line = f"  {name} ({dims}) {var.dtype}"
        if "fs" in var.attrs:
            line += f"  fs={var.attrs['fs']:g} Hz"
        out.append(line)
        cdim = var.dims[0]
        if str(name).startswith("time_history"):
            suffix = cdim[len("channel") :]
            for k, ch in enumerate(var[cdim].values):
                q = var["quantity" + suffix].values[k]
                u = var["units" + suffix].values[k]
                out.append(f"    {ch}: {q} [{u}]")
    for key, value in ds.attrs.items():
        if key not in ("source", "format"):
            out.append(f"  attr {key} = {value!r}")
    return "\n".join(out)


def _run(args: argparse.Namespace) -> int:
    """Run ``mvtk read``: 0, or 2 with one line naming the file on any input error."""
    import sys

    from .._run_cli import check_output_file
    from ..errors import MvtkError
    from . import read, write

    try:
        if args.output:
            check_output_file(args.output, "--output")  # before reading
        ds = read(args.path, **reader_options(args))
        print(summary(ds))
        if args.output:
            write(ds, args.output)
            print(f"written: {args.output}")
    except (MvtkError, OSError) as err:
        msg = " ".join(str(err).split("\n"))
        if isinstance(err, OSError) and err.filename is not None and err.strerror:
            msg = f"{err.filename}: {err.strerror}"
        print(f"mvtk read: error: {msg}", file=sys.stderr)
        return 2
    return 0


def add_parser(subparsers) -> None:
    """Register ``mvtk read PATH [--format F] [--set key=value ...] [--output OUT.nc]``."""
    p = subparsers.add_parser(
        "read",
        help="read a measurement file (CSV, UFF, MAT, HDF5, netCDF, TDMS, WAV) and describe it",
        description="Read a measurement file with mvtk.io.read, print its layout, and "
        "optionally write it to netCDF.",
    )
    p.add_argument("path", help="measurement file")
    add_reader_options(p)
    p.add_argument("--output", "-o", default=None, help="write the Dataset to this netCDF file")
    p.set_defaults(func=_run)
