"""``mvtk damping FILE``: natural frequencies and damping from a measurement, right by default.

With no option the command reads the file, picks the estimator from what the file holds
(an FRF or spectrum -> half-power; time histories with a force/reference channel -> H1 FRF
with the resolution chosen from the record, then half-power; time histories without a
reference -> envelope fit of the free decay per channel), and prints one row per mode
or channel with the ``reliable`` verdict and its ``reason``. Exit code 0 when at least one
estimate is reliable, 1 when none is (the table is still printed), 2 on bad input.
"""

from __future__ import annotations

import argparse
import sys
import warnings

from ._commands import COMMANDS

__all__ = ["add_parser", "run"]

_METHODS = ("auto", "half_power", "envelope", "log_decrement")   # mvtk.damping.METHODS


def add_parser(subparsers) -> None:
    """Register the ``damping`` sub-command."""
    from ._common import add_reader_options

    p = subparsers.add_parser(
        "damping",
        help=COMMANDS["damping"].help,
        description="Read a measurement file (mvtk.io.read) and identify fn and zeta. "
        "With no option: half-power on the file's FRF/spectrum, or on the H1 FRF of time "
        "histories with a force channel (impact or random detected; record, windows and "
        "resolution chosen from the data), or an envelope fit of free decays. Every row "
        "says whether the data support it (reliable, reason). Exit 0 if at least one "
        "estimate is reliable, 1 if none is, 2 on bad input.",
    )
    p.add_argument("file", help="measurement file readable by mvtk.io.read")
    add_reader_options(p)
    est = p.add_argument_group("estimator")
    est.add_argument("--method", choices=_METHODS, default="auto",
                     help="estimator (default auto: half_power on FRFs/spectra and on time "
                     "histories with a reference, envelope on free decays)")
    est.add_argument("--variant", default=None,
                     help="half_power: fit (default) or interpolate; envelope: hilbert "
                     "(default) or peaks")
    est.add_argument("--fn", type=float, nargs="+", metavar="HZ",
                     help="approximate natural frequencies in Hz (default: peak picking)")
    est.add_argument("--fmin", type=float, default=None, help="lowest frequency searched (Hz)")
    est.add_argument("--fmax", type=float, default=None, help="highest frequency searched (Hz)")
    est.add_argument("--n-modes", type=int, default=None, help="peaks to pick without --fn")
    est.add_argument("--channel", nargs="+", default=None,
                     help="channels to analyse (responses for an FRF, decays otherwise)")
    frf = p.add_argument_group("FRF from time histories")
    frf.add_argument("--reference", default=None,
                     help="reference channel (default: channels with quantity force)")
    frf.add_argument("--excitation", choices=("auto", "random", "impact", "sweep"),
                     default="auto", help="default auto: impact if the reference is a pulse, "
                     "sweep if it is a moving narrow-band signal, random otherwise")
    frf.add_argument("--impact", action="store_true", help="same as --excitation impact")
    frf.add_argument("--nperseg", type=int, default=None,
                     help="FRF segment/record length (default: chosen from the data)")
    frf.add_argument("--force-window", type=float, default=None, metavar="S",
                     help="impact: keep the force for S seconds after the hit (default: 4 x "
                     "the measured pulse width)")
    dec = p.add_argument_group("free decay")
    dec.add_argument("--band", type=float, nargs=2, metavar=("LOW", "HIGH"), default=None,
                     help="band-pass edges in Hz for the decay fits (one mode)")
    dec.add_argument("--t-start", type=float, default=None, help="start of the time window (s)")
    dec.add_argument("--t-end", type=float, default=None, help="end of the time window (s)")
    p.add_argument("--json", action="store_true", help="print the result table as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk damping``; returns the exit code (errors propagate as MvtkError)."""
    from ._common import spare_dask_probe

    spare_dask_probe()
    from .. import io
    from ..damping._common import NoEstimateError
    from ..damping._estimate import estimate
    from ..errors import ParameterError
    from ._common import reader_options, refuse_study_as_data

    refuse_study_as_data([args.file], "damping")
    method = args.method
    notes: list[str] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ds = io.read(args.file, **reader_options(args))
            try:
                res = estimate(ds, method=method, variant=args.variant, fn_hz=args.fn,
                               n_modes=args.n_modes, fmin=args.fmin, fmax=args.fmax,
                               channel=args.channel, reference=args.reference,
                               excitation="impact" if args.impact else args.excitation,
                               nperseg=args.nperseg, band_hz=args.band,
                               force_window_s=("auto" if args.force_window is None
                                               else args.force_window),
                               t_start_s=args.t_start, t_end_s=args.t_end)
            except ParameterError as err:
                if isinstance(err, NoEstimateError) or "is not a variant" not in str(err):
                    raise
                raise ParameterError(f"--{err}") from None
            method, table, notes = res.method, res.table, res.notes
    except NoEstimateError as err:
        sys.stderr.write(f"mvtk damping: no reliable estimate: {err}\n")
        if args.json:
            sys.stdout.write("[]\n")
        return 1
    except OSError as err:
        name = getattr(err, "filename", None) or args.file
        sys.stderr.write(f"mvtk damping: error: cannot read {name}: {err.strerror or err}\n")
        return 2
    for w in caught:
        sys.stderr.write(f"{w.category.__name__}: {w.message}\n")
    n_ok = int(table["reliable"].sum())
    verdict = (f"{n_ok} of {len(table)} estimate(s) reliable" if n_ok else
               f"no reliable estimate: the data cannot support the {method} damping "
               f"estimate (see the reason column)")
    if not n_ok and method in ("envelope", "log_decrement") and "reason" in table:
        not_decay = table["reason"].str.contains(
            "not one free decay|falls only|does not decay|no decay")
        if bool(not_decay.all()):
            verdict += ("; the records are not free decays: for ambient or operational "
                        "records use `mvtk modal` (SSI-cov)")
    if args.json:
        sys.stdout.write(table.to_json(orient="records", double_precision=15) + "\n")
    else:
        for note in notes:
            sys.stdout.write(note + "\n")
        cols = [c for c in ("curve", "channel", "mode", "fn_hz", "zeta", "zeta_std", "n_lines",
                            "zeta_early", "zeta_late", "quality", "reliable", "reason")
                if c in table.columns]
        sys.stdout.write(table[cols].to_string(index=False) + "\n")
        sys.stdout.write(verdict + "\n")
    if not n_ok:
        sys.stderr.write(f"mvtk damping: {verdict}\n")
        return 1
    return 0
