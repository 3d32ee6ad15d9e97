"""``mvtk modal FILE... [--json]``: modes, damping and shapes from measured FRFs or records."""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

__all__ = ["add_parser", "load_frf"]


def add_parser(subparsers) -> None:
    """Register the ``modal`` sub-command."""
    from ..io._cli import add_reader_options

    p = subparsers.add_parser(
        "modal",
        help="experimental/operational modal analysis (pLSCF+LSFD, SSI-cov)",
        description="Read measurement files (mvtk.io.read) and identify modes. FRF files "
        "(UFF 58 FRF records, complex FRF columns) are merged into one FRF matrix and "
        "identified by pLSCF + LSFD; time histories with a force channel give H1 FRFs "
        "(several files = several measurement sets, merged by node/direction); time "
        "histories without force are identified output-only by SSI-cov. Prints the mode "
        "table with quality columns (stability count, MPC, MPD, reliable, reason).",
    )
    p.add_argument("files", nargs="+", metavar="FILE", help="measurement file(s)")
    p.add_argument("--fmin", type=float, default=None, help="band start in Hz")
    p.add_argument("--fmax", type=float, default=None, help="band end in Hz")
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
    """FRF matrix from one or several FRF files, merged along the responses.

    ``options`` are reader options (:func:`mvtk.io.read` keywords) applied to every file.
    """
    import numpy as np
    import xarray as xr

    from .. import io
    from ..errors import DimensionError
    from ._frf import as_frf_matrix

    mats = []
    for p in paths:
        mats.append((p, as_frf_matrix(io.read(p, **_read_options(p, df_hz, options)),
                                      frf_type=frf_type)))
    if len(mats) == 1:
        return mats[0][1]
    f0 = mats[0][1]["frequency"].values
    nref = mats[0][1].sizes["reference"]
    parts = []
    for p, h in mats:
        f = h["frequency"].values
        if f.shape != f0.shape or not np.allclose(f, f0) or h.sizes["reference"] != nref:
            raise DimensionError(
                f"{p}: {h.sizes['reference']} reference(s) x {f.size} lines up to "
                f"{f[-1]:g} Hz; expected the {nref} reference(s) and {f0.size} lines of "
                f"{mats[0][0]}"
            )
        names = [str(r) for r in h["response"].values]
        if len(mats) > 1:
            names = [f"{Path(p).stem}:{r}" if r in ("", "reference") or int(n) < 0 else r
                     for r, n in zip(names, h["node"].values)]
        parts.append(h.assign_coords(response=names, reference=mats[0][1]["reference"].values,
                                     reference_node=mats[0][1]["reference_node"],
                                     reference_direction=mats[0][1]["reference_direction"],
                                     reference_quantity=mats[0][1]["reference_quantity"],
                                     reference_units=mats[0][1]["reference_units"],
                                     frequency=f0))
    out = xr.concat(parts, dim="response", coords="minimal", compat="override",
                    combine_attrs="override")
    return as_frf_matrix(out)


def _identify(args):
    import numpy as np

    from .. import io
    from ..io._cli import reader_options
    from ._frf import frf_matrix
    from ._identify import identify
    from ._ssi import identify_output_only

    options = reader_options(args)
    first = io.read(args.files[0], **_read_options(args.files[0], args.df_hz, options))
    orders = None if args.orders is None else range(2, args.orders + 1)
    if "time_history" in first.data_vars:
        th = first["time_history"]
        has_force = "quantity" in th.coords and "force" in {str(q) for q in
                                                            th["quantity"].values}
        if has_force or args.reference is not None:
            sets = [first] + [io.read(p, **options) for p in args.files[1:]]
            ref = args.reference if args.reference is not None else {"quantity": "force"}
            h = frf_matrix(sets, ref, excitation="impact" if args.impact else args.excitation,
                           nperseg=args.nperseg)
            return identify(h, args.fmin, args.fmax, orders=orders, fn_hz=args.fn)
        ssi_orders = range(2, 61, 2) if args.orders is None else range(2, args.orders + 1, 2)
        return identify_output_only(first, args.fmin, args.fmax, orders=ssi_orders,
                                    fn_hz=args.fn)
    h = load_frf(args.files, df_hz=args.df_hz, frf_type=args.frf_type, options=options)
    del np
    return identify(h, args.fmin, args.fmax, orders=orders, fn_hz=args.fn)


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk modal``; returns the exit code (errors propagate as MvtkError)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        modes = _identify(args)
        if args.uff_modes:
            from ._export import write_modes_uff

            write_modes_uff(modes, args.uff_modes)
        if args.uff_frf and modes.synthesised is not None:
            from ._export import write_frf_uff

            write_frf_uff(modes.synthesised, args.uff_frf)
    for w in caught:
        sys.stderr.write(f"{w.category.__name__}: {w.message}\n")
    table = modes.to_dataframe()
    if args.json:
        out = {"method": modes.method, "band_hz": list(modes.diagram.band_hz),
               "modes": json.loads(table.to_json(orient="records")),
               "shapes": json.loads(modes.shape_table().to_json(orient="records",
                                                         double_precision=15)),
               "shape_normalisation": modes.shapes.attrs.get("normalisation"),
               "frf_correlation": (None if modes.correlation is None
                                   else modes.correlation.attrs["overall"])}
        sys.stdout.write(json.dumps(out) + "\n")
        return 0
    sys.stdout.write(f"{modes.method}: {modes.n_modes} mode(s) in "
                     f"{modes.diagram.band_hz[0]:g}..{modes.diagram.band_hz[1]:g} Hz\n")
    if modes.n_modes:
        sys.stdout.write(table.to_string(index=False) + "\n")
    else:
        sys.stdout.write("no pole is stable over enough model orders in this band (more "
                         "data, another band or --orders)\n")
    if modes.correlation is not None:
        sys.stdout.write(f"measured vs synthesised FRF correlation: "
                         f"{modes.correlation.attrs['overall']:.4f}\n")
    return 0
