"""``mvtk damping FILE --fn 13.26 41.14 [--method ...]``: modal damping from a measurement."""

from __future__ import annotations

import argparse
import sys
import warnings

__all__ = ["add_parser"]

_METHODS = ("half_power", "envelope", "log_decrement")


def add_parser(subparsers) -> None:
    """Register the ``damping`` sub-command."""
    p = subparsers.add_parser(
        "damping",
        help="natural frequencies and damping ratios from a measurement file",
        description="Read a measurement file (mvtk.io.read) and identify fn and zeta: "
        "half-power on the H1 FRF (time histories with a force channel) or on the file's "
        "FRF/PSD, or an envelope / log-decrement fit of a free decay. Warnings (too few "
        "lines, overlapping modes, noisy peaks) are printed to stderr.",
    )
    p.add_argument("file", help="measurement file readable by mvtk.io.read")
    p.add_argument("--fn", type=float, nargs="+", metavar="HZ",
                   help="approximate natural frequencies in Hz (default: peak picking)")
    p.add_argument("--method", choices=_METHODS, default="half_power",
                   help="estimator (default half_power)")
    p.add_argument("--reference", default=None,
                   help="reference channel for the FRF (default: channels with quantity force)")
    p.add_argument("--impact", action="store_true", help="impact test: one record per hit")
    p.add_argument("--nperseg", type=int, default=None, help="FRF segment/record length")
    p.add_argument("--band", type=float, nargs=2, metavar=("LOW", "HIGH"), default=None,
                   help="band-pass edges in Hz for the decay fits (one mode)")
    p.add_argument("--n-modes", type=int, default=None, help="peaks to pick without --fn")
    p.add_argument("--json", action="store_true", help="print the result table as JSON")
    p.set_defaults(func=run)


def _frf_source(ds, args):
    from .. import signal

    if "time_history" in ds.data_vars:
        ref = args.reference if args.reference is not None else {"quantity": "force"}
        return signal.frf(ds, ref, excitation="impact" if args.impact else "random",
                          nperseg=args.nperseg)
    return ds


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk damping``; returns the exit code (errors propagate as MvtkError)."""
    from .. import io
    from ._decay import envelope_fit, log_decrement
    from ._half_power import half_power

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = io.read(args.file)
        if args.method == "half_power":
            res = half_power(_frf_source(ds, args), fn_hz=args.fn, n_modes=args.n_modes)
            frames = [res.to_dataframe()]
        else:
            est = envelope_fit if args.method == "envelope" else log_decrement
            fns = args.fn or [None]
            frames = [est(ds, fn_hz=f, band_hz=args.band).to_dataframe() for f in fns]
    import pandas as pd

    table = pd.concat(frames, ignore_index=True)
    for w in caught:
        sys.stderr.write(f"{w.category.__name__}: {w.message}\n")
    if args.json:
        sys.stdout.write(table.to_json(orient="records") + "\n")
        return 0
    cols = [c for c in ("curve", "channel", "mode", "fn_hz", "zeta", "zeta_std", "n_lines",
                        "quality") if c in table.columns]
    sys.stdout.write(table[cols].to_string(index=False) + "\n")
    return 0
