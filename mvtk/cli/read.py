"""``mvtk read``: read a measurement file, print its layout, optionally write netCDF."""

from __future__ import annotations

import argparse

from ._commands import COMMANDS
from ._common import add_reader_options, reader_options

__all__ = ["add_parser", "summary"]


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
    from ._common import spare_dask_probe

    spare_dask_probe()
    import sys

    from ..errors import MvtkError
    from ..io import read, write
    from ._common import check_output_file, refuse_inputs

    try:
        if args.output:
            check_output_file(args.output, "--output")  # before reading
            refuse_inputs([("--output", args.output)], [args.path])
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
        help=COMMANDS["read"].help,
        description="Read a measurement file with mvtk.io.read, print its layout, and "
        "optionally write it to netCDF.",
    )
    p.add_argument("path", help="measurement file")
    add_reader_options(p)
    p.add_argument("--output", "-o", default=None, help="write the Dataset to this netCDF file")
    p.set_defaults(func=_run)
