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

_METHODS = ("auto", "half_power", "envelope", "log_decrement")
_VARIANTS = {"half_power": ("fit", "interpolate"), "envelope": ("hilbert", "peaks")}


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
    dec = p.add_argument_group("free decay")
    dec.add_argument("--band", type=float, nargs=2, metavar=("LOW", "HIGH"), default=None,
                     help="band-pass edges in Hz for the decay fits (one mode)")
    dec.add_argument("--t-start", type=float, default=None, help="start of the time window (s)")
    dec.add_argument("--t-end", type=float, default=None, help="end of the time window (s)")
    p.add_argument("--json", action="store_true", help="print the result table as JSON")
    p.set_defaults(func=run)


def _has_reference(ds, args) -> bool:
    th = ds["time_history"]
    if args.reference is not None:
        return True
    return "quantity" in th.coords and "force" in [str(q) for q in th["quantity"].values]


_MOTION = ("displacement", "velocity", "acceleration")


def _half_power_input(ds, args, notes):
    from .. import signal

    if "time_history" in ds.data_vars and not any(v in ds.data_vars for v in
                                                  ("frf", "psd", "auto_spectrum", "spectrum")):
        ref = args.reference if args.reference is not None else {"quantity": "force"}
        excitation = "impact" if args.impact else args.excitation
        resp = args.channel
        th = ds["time_history"]
        if resp is None and "quantity" in th.coords:
            # a trigger or monitoring voltage is not a response: motion channels only
            motion = [str(c) for c, q in zip(th["channel"].values, th["quantity"].values)
                      if str(q) in _MOTION and str(c) != args.reference]
            if motion and len(motion) < th.sizes["channel"] - 1:
                resp = motion
                notes.append(f"responses: the motion channels {motion}")
        fr = signal.frf(ds, ref, response=resp, excitation=excitation, nperseg=args.nperseg)
        notes.append(f"FRF: H1, {fr.attrs['excitation']} excitation, "
                     f"{fr.attrs['n_averages']} average(s); {fr.attrs['resolution_reason']}"
                     + ("; peaks searched in the excited band {:.5g}..{:.5g} Hz".format(
                         *fr.attrs["excitation_band_hz"])
                        if fr.attrs.get("excitation") == "sweep" else ""))
        return fr
    if args.channel is not None:
        for name in ("frf", "psd", "auto_spectrum", "spectrum"):
            if name in ds.data_vars:
                var = ds[name]
                dim = "response" if "response" in var.dims else "channel"
                return ds[[name]].sel({dim: args.channel})
    return ds


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk damping``; returns the exit code (errors propagate as MvtkError)."""
    from ._common import spare_dask_probe

    spare_dask_probe()
    import pandas as pd

    from .. import io
    from ..damping._common import NoEstimateError
    from ..damping._decay import envelope_fit, log_decrement
    from ..damping._half_power import half_power
    from ..errors import ParameterError
    from ._common import reader_options

    method = args.method
    variant = args.variant
    notes: list[str] = []
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            ds = io.read(args.file, **reader_options(args))
            if method == "auto":
                method = "half_power"
                if "time_history" in ds.data_vars and not _has_reference(ds, args) and not any(
                        v in ds.data_vars for v in ("frf", "psd", "auto_spectrum", "spectrum")):
                    method = "envelope"
                notes.append(f"method: {method} (auto)")
            if variant is not None and variant not in _VARIANTS.get(method, ()):
                raise ParameterError(
                    f"--variant {variant!r} is not a variant of {method}; expected one of "
                    f"{list(_VARIANTS.get(method, ()))}")
            if method == "half_power":
                res = half_power(_half_power_input(ds, args, notes), fn_hz=args.fn,
                                 n_modes=args.n_modes, fmin=args.fmin, fmax=args.fmax,
                                 method=variant or "fit")
                table = res.to_dataframe()
            else:
                th = ds
                if "time_history" in ds.data_vars and args.channel is None \
                        and "quantity" in ds["time_history"].coords:
                    # a decay fit of the hammer or of a voltage makes no sense by default
                    q = [str(v) for v in ds["time_history"]["quantity"].values]
                    keep = [i for i, v in enumerate(q) if v != "force"]
                    if keep and len(keep) < len(q):
                        th = ds["time_history"].isel(channel=keep)
                kw = dict(channel=args.channel, band_hz=args.band, t_start_s=args.t_start,
                          t_end_s=args.t_end)
                if method == "envelope":
                    kw["method"] = variant or "hilbert"
                    est = envelope_fit
                else:
                    est = log_decrement
                fns = args.fn or [None]
                table = pd.concat([est(th, fn_hz=f, **kw).to_dataframe() for f in fns],
                                  ignore_index=True)
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
        sys.stdout.write(table.to_json(orient="records") + "\n")
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
