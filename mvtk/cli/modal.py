"""``mvtk modal FILE... [--json]``: modes, damping and shapes from measured FRFs or records."""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

from ._commands import COMMANDS

__all__ = ["add_parser", "load_frf"]


def add_parser(subparsers) -> None:
    """Register the ``modal`` sub-command."""
    from ._common import add_reader_options

    p = subparsers.add_parser(
        "modal",
        help=COMMANDS["modal"].help,
        description="Read measurement files (mvtk.io.read) and identify modes. FRF files "
        "(UFF 58 FRF records, complex FRF columns) are merged into one FRF matrix by "
        "response and reference node/direction and "
        "identified by pLSCF + LSFD; time histories with a force channel give H1 FRFs "
        "(several files = several measurement sets, merged by node/direction; impact sets "
        "share one record and window, double hits and clipping are reported; a roving "
        "hammer is turned by reciprocity); time "
        "histories without force are identified output-only by SSI-cov. Prints the mode "
        "table with quality columns (stability count, MPC, MPD, reliable, reason).",
    )
    p.add_argument("files", nargs="+", metavar="FILE", help="measurement file(s)")
    p.add_argument("--fmin", type=float, default=None, help="band start in Hz (default: "
                   "from the data, where the excitation is strong and the response has "
                   "resonances; the reason is printed)")
    p.add_argument("--fmax", type=float, default=None, help="band end in Hz (default: "
                   "from the data)")
    p.add_argument("--orders", type=int, default=None, metavar="N",
                   help="highest model order (pLSCF polynomial order / SSI state order); "
                   "pLSCF default: from the number of peaks in the band (see "
                   "docs/guide/modal.md)")
    p.add_argument("--fn", type=float, nargs="+", metavar="HZ", default=None,
                   help="select the poles nearest these frequencies instead of clustering")
    p.add_argument("--reference", default=None,
                   help="force channel(s) of time histories (default: quantity force)")
    p.add_argument("--excitation", choices=("auto", "random", "impact", "sweep"),
                   default="auto", help="time histories: default auto, impact if the "
                   "reference is a pulse, sweep if it sweeps, else random")
    p.add_argument("--impact", action="store_true", help="same as --excitation impact")
    p.add_argument("--nperseg", type=int, default=None, help="FRF segment/record length")
    p.add_argument("--df-hz", type=float, default=None,
                   help="line spacing for text files of complex FRF values without a "
                   "frequency column")
    p.add_argument("--frf-type", choices=("receptance", "mobility", "accelerance", "other"),
                   default=None, help="FRF type when the file does not state it")
    p.add_argument("--uff-modes", default=None, metavar="PATH",
                   help="write the identified modes as UFF 55 (complex shapes)")
    p.add_argument("--uff-frf", default=None, metavar="PATH",
                   help="write the synthesised FRFs as UFF 58")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    add_reader_options(p)
    p.set_defaults(func=run)


def _read_options(path, df_hz=None, options=None) -> dict:
    """Reader options for one file: ``options`` plus ``df_hz`` for text files."""
    opts = dict(options or {})
    if df_hz is not None and Path(path).suffix.lower() in (".txt", ".csv", ".tsv", ".dat",
                                                           ".asc"):
        opts["df_hz"] = df_hz
    return opts


def load_frf(paths, *, df_hz=None, frf_type=None, options=None):
    """FRF matrix from one or several FRF files, merged by node/direction
    (:func:`mvtk.modal.merge_frf`: one file per reference, or per response group).

    ``options`` are reader options (:func:`mvtk.io.read` keywords) applied to every file.
    """
    from .. import io
    from ..modal._frf import as_frf_matrix, merge_frf

    mats = [as_frf_matrix(io.read(p, **_read_options(p, df_hz, options)), frf_type=frf_type)
            for p in paths]
    return merge_frf(mats, [Path(p).name for p in paths])


#: Highest ``--orders x n_reference`` accepted (pLSCF): the stabilisation diagram's cost
#: grows about as the order squared to cubed (300 poles per order: about a minute for
#: 13 FRFs of 3201 lines on one core); the default orders stop at 160.
MAX_POLES_PER_ORDER = 400
#: Fewest samples per FRF segment (``--nperseg``): N samples give N/2 + 1 lines.
MIN_NPERSEG = 8


def _check_orders(h, args) -> None:
    """Refuse ``--orders`` the band's lines cannot support, or beyond the runtime cap."""
    from ..errors import ParameterError

    if args.orders is None:
        return
    from ..modal._identify import default_band

    f = h["frequency"].values
    # the band identify will fit: the bounds given, the rest from the data
    lo, hi, _ = default_band(h, args.fmin, args.fmax)
    lines = int(((f >= lo) & (f <= hi)).sum())
    ni = h.sizes["reference"]
    most = min(lines // (2 * ni), MAX_POLES_PER_ORDER // ni)
    if args.orders > most:
        why = (f"the band {lo:.5g}..{hi:.5g} Hz holds {lines} lines for {ni} reference(s) "
               "and pLSCF needs at "
               "least 2 lines per pole" if lines // (2 * ni) <= MAX_POLES_PER_ORDER // ni
               else f"above {MAX_POLES_PER_ORDER} poles per order the stabilisation "
               "diagram takes many minutes to hours (without --orders the order is "
               "chosen from the peaks of the band)")
        raise ParameterError(f"--orders {args.orders}: {why}; expected --orders <= {most}")


def _check_output_only(args, th) -> None:
    """Refuse what SSI-cov cannot use: more files, --uff-frf, constant channels."""
    import numpy as np

    from ..errors import ParameterError

    if len(args.files) > 1:
        raise ParameterError(
            f"{args.files[0]} has no force channel: output-only identification (SSI-cov) "
            f"uses one record, got {len(args.files)} files ({', '.join(args.files[1:])} "
            "would be ignored); run them one at a time, or name the force channel with "
            "--reference for a multi-set FRF test")
    if args.uff_frf:
        raise ParameterError(
            f"--uff-frf: {args.files[0]} has no force channel, so output-only "
            "identification gives no FRFs to write; use --uff-modes for the modes")
    data = np.asarray(th.values, dtype=float)
    cdim = th.dims[0]
    flat = [str(c) for c, row in zip(th[cdim].values, data)
            if not np.all(np.isfinite(row)) or np.ptp(row) == 0]
    if flat and len(flat) == data.shape[0]:
        raise ParameterError(f"{args.files[0]}: every channel is constant or not finite "
                             f"({', '.join(flat)}); no vibration to identify")
    if flat:
        raise ParameterError(f"{args.files[0]}: channel(s) {', '.join(flat)} are constant or "
                             "hold non-finite values; drop them (e.g. --set channels=...) "
                             "for output-only identification")


def _identify(args):
    from .. import io
    from ..errors import ParameterError
    from ..modal._frf import frf_of_sets
    from ..modal._identify import identify
    from ..modal._ssi import identify_output_only
    from ._common import reader_options

    if args.nperseg is not None and args.nperseg < MIN_NPERSEG:
        raise ParameterError(f"--nperseg {args.nperseg}: expected at least {MIN_NPERSEG} "
                             "samples per segment (N samples give N/2 + 1 frequency lines)")
    if args.orders is not None and args.orders < 2:
        raise ParameterError(f"--orders {args.orders}: expected a model order >= 2")
    options = reader_options(args)
    first = io.read(args.files[0], **_read_options(args.files[0], args.df_hz, options))
    orders = None if args.orders is None else range(2, args.orders + 1)
    if "time_history" in first.data_vars:
        th = first["time_history"]
        has_force = "quantity" in th.coords and "force" in {str(q) for q in
                                                            th["quantity"].values}
        if has_force or args.reference is not None:
            sets = [first] + [io.read(p, **options) for p in args.files[1:]]
            # the study's path: a roving hammer is turned by reciprocity
            h = frf_of_sets(sets, args.reference,
                            excitation="impact" if args.impact else args.excitation,
                            nperseg=args.nperseg)
            _check_orders(h, args)
            return identify(h, args.fmin, args.fmax, orders=orders, fn_hz=args.fn)
        _check_output_only(args, th)
        ssi_orders = range(2, 61, 2) if args.orders is None else range(2, args.orders + 1, 2)
        return identify_output_only(first, args.fmin, args.fmax, orders=ssi_orders,
                                    fn_hz=args.fn)
    h = load_frf(args.files, df_hz=args.df_hz, frf_type=args.frf_type, options=options)
    _check_orders(h, args)
    return identify(h, args.fmin, args.fmax, orders=orders, fn_hz=args.fn)


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk modal``; returns the exit code (errors propagate as MvtkError)."""
    from ._common import spare_dask_probe

    spare_dask_probe()
    from ._common import check_output_file, refuse_inputs, refuse_study_as_data

    refuse_study_as_data(args.files, "modal")
    outputs = [("--uff-modes", args.uff_modes), ("--uff-frf", args.uff_frf)]
    for opt, path in outputs:
        if path:
            check_output_file(path, opt)
    refuse_inputs(outputs, args.files)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        modes = _identify(args)
        if args.uff_modes:
            from ..modal._export import write_modes_uff

            write_modes_uff(modes, args.uff_modes)
        if args.uff_frf and modes.synthesised is not None:
            from ..modal._export import write_frf_uff

            write_frf_uff(modes.synthesised, args.uff_frf)
    for w in caught:
        sys.stderr.write(f"{w.category.__name__}: {w.message}\n")
    table = modes.to_dataframe()
    if args.json:
        out = {"method": modes.method, "band_hz": list(modes.diagram.band_hz),
               "band_reason": getattr(modes, "band_reason", ""),
               "modes": json.loads(table.to_json(orient="records")),
               "shapes": json.loads(modes.shape_table().to_json(orient="records",
                                                         double_precision=15)),
               "shape_normalisation": modes.shapes.attrs.get("normalisation"),
               "frf_correlation": (None if modes.correlation is None
                                   else modes.correlation.attrs["overall"])}
        if modes.frf is not None and modes.frf.attrs.get("set_quality"):
            out["set_quality"] = json.loads(modes.frf.attrs["set_quality"])
            out["window_policy"] = modes.frf.attrs.get("window_policy", "")
        sys.stdout.write(json.dumps(out) + "\n")
        return 0
    sys.stdout.write(f"{modes.method}: {modes.n_modes} mode(s) in "
                     f"{modes.diagram.band_hz[0]:g}..{modes.diagram.band_hz[1]:g} Hz\n")
    if getattr(modes, "band_reason", ""):
        sys.stdout.write(f"band: {modes.band_reason}\n")
    if modes.n_modes:
        sys.stdout.write(table.to_string(index=False) + "\n")
    else:
        sys.stdout.write("no pole is stable over enough model orders in this band (more "
                         "data, another band or --orders)\n")
    if modes.correlation is not None:
        sys.stdout.write(f"measured vs synthesised FRF correlation: "
                         f"{modes.correlation.attrs['overall']:.4f}\n")
    return 0
