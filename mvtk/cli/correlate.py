"""``mvtk correlate GEOMETRY STRUCTURE.toml [--shapes FILE] [--json]`` or
``mvtk correlate STUDY.toml [--json] [--cache DIR]``.

Maps the sensors of a test geometry onto the FE model of a structure description and
prints the mapping, the MAC and pairing table and the COMAC per sensor (with test shapes
from a UFF 55 file or a netCDF ``("mode", "dof")`` DataArray), or the FE AutoMAC at the
sensors (pretest check) without them. Given a study TOML alone, it prints the study's
``correlation`` stage (the identified multi-point test against the updated FE model, as
in the report), run through the cached study pipeline like ``mvtk update``.
"""

from __future__ import annotations

import argparse
import json
import sys

from ._commands import COMMANDS

__all__ = ["add_parser"]


def add_parser(subparsers) -> None:
    """Register the ``correlate`` sub-command."""
    p = subparsers.add_parser(
        "correlate",
        help=COMMANDS["correlate"].help,
        description="Map the sensors of a test geometry (UFF, TOML or CSV) onto the FE "
        "model of a structure TOML and correlate test shapes with the FE modes.",
    )
    from ._common import add_cache_argument

    p.add_argument("geometry", help="test geometry (.uff/.unv, .toml or .csv), or a study "
                   "TOML alone (its correlation stage)")
    p.add_argument("structure", nargs="?", default=None,
                   help="structure description (TOML), see mvtk.fe.build_model")
    p.add_argument("--shapes", metavar="FILE",
                   help="measured shapes: UFF 55 (e.g. from mvtk modal --uff-modes or your "
                   "EMA software; values read along each sensor's axis) or a netCDF "
                   "DataArray (dims mode, dof)")
    p.add_argument("-n", "--n-modes", type=int, default=10, help="FE modes (default 10)")
    p.add_argument("--method", choices=("shape", "nearest"), default="shape")
    p.add_argument("--tol", type=float, default=None, help="off-model tolerance (m)")
    p.add_argument("--units-scale", type=float, default=1.0,
                   help="factor applied to geometry coordinates (1e-3 for mm)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    add_cache_argument(p)
    p.set_defaults(func=run)


def _uff_sensors(path, geo):
    """Sensors of a UFF geometry: the response DOFs of its FRF records (UFF 58) at the
    geometry's nodes, else one global +z sensor per node (marked ``default +z``)."""
    import warnings

    import numpy as np

    from ..correlation._geometry import Sensor, _make_sensor
    from ..errors import MvtkError

    if not str(path).lower().endswith((".uff", ".unv", ".uf")):
        return geo
    dofs = []
    try:
        from .. import io
        from ..modal._frf import as_frf_matrix

        with warnings.catch_warnings():
            warnings.simplefilter("ignore")   # the node datasets are "not measurement data"
            h = as_frf_matrix(io.read(path))
        known = set(np.asarray(geo.node).tolist())
        dofs = sorted({(int(n), str(d)) for n, d in zip(h["node"].values, h["direction"].values)
                       if int(n) in known})
    except (MvtkError, KeyError, ValueError):
        dofs = []
    if dofs:   # measured DOFs of the file itself
        return geo.with_sensors([_make_sensor(n, d, f"{path}: FRF records", "file")
                                 for n, d in dofs])
    return geo.with_sensors([Sensor(int(n), "+z", None, False, "default +z")
                             for n in geo.node])


def _study_view(args: argparse.Namespace) -> int:
    """``mvtk correlate STUDY.toml``: the study's correlation stage."""
    import pandas as pd

    from ._common import json_clean, run_view

    res = run_view(args.geometry, ["correlation"], args.cache)
    cor = {k: v for k, v in res.results["correlation"].items() if k != "figures"}
    if args.json:
        sys.stdout.write(json.dumps(json_clean({"study": str(args.geometry), **cor}),
                                    allow_nan=False) + "\n")
        return 0
    pairs = pd.DataFrame(cor["pairs"]).drop(columns=["index"], errors="ignore")
    dofs = pd.DataFrame(cor["dofs"]).drop(columns=["index"], errors="ignore")
    out = [f"{cor['n_sensors']} sensor DOFs mapped ({cor['mapping']}) onto the "
           f"{'updated ' if 'updating' in res.results else ''}FE model", "",
           pairs.to_string(index=False), "", dofs.to_string(index=False)]
    sys.stdout.write("\n".join(out) + "\n")
    return 0


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk correlate``; errors propagate as MvtkError."""
    if args.structure is None:
        from ..errors import ConfigError
        from ..study._text import read_toml

        if not str(args.geometry).lower().endswith(".toml"):
            raise ConfigError(f"{args.geometry}: a test geometry needs a STRUCTURE TOML "
                              "after it (mvtk correlate GEOMETRY STRUCTURE.toml), or give "
                              "a study TOML alone")
        if "modal" not in read_toml(args.geometry, "study file"):
            raise ConfigError(f"{args.geometry}: no [modal] section (a study's multi-point "
                              "test), so nothing to correlate; for a test geometry and a "
                              "structure: mvtk correlate GEOMETRY STRUCTURE.toml")
        return _study_view(args)
    from ..correlation._correlate import correlate
    from ..correlation._geometry import read_test_geometry
    from ..correlation._shapes import read_test_shapes
    from ..fe import build_model, modal_analysis

    geo = read_test_geometry(args.geometry, units_scale=args.units_scale)
    if not geo.sensors:
        geo = _uff_sensors(args.geometry, geo)
    n_default = sum(s.source == "default +z" for s in geo.sensors)
    if n_default:
        what = "has no 'directions' column"
        if str(args.geometry).lower().endswith((".uff", ".unv", ".uf")):
            what = "holds nodes but no measured DOFs (no UFF 58 records)"
        sys.stderr.write(f"notice: {args.geometry} {what}: one global +z "
                         f"sensor assumed at each of its {n_default} nodes (column "
                         "direction_source)\n")
    model = build_model(args.structure)
    modal = modal_analysis(model, args.n_modes)
    test = read_test_shapes(args.shapes, geo) if args.shapes else None
    res = correlate(geo, model, modal, test, method=args.method, tol=args.tol)
    if args.json:
        sys.stdout.write(json.dumps(res.to_dict()) + "\n")
        return 0
    out = [f"{len(res.mapping.dof)} sensors mapped ({res.mapping.method}) onto "
           f"{model.n_dof} FE DOFs", "", res.dof_table().to_string(index=False), ""]
    if res.pairing is not None:
        out += [res.pairing_table().to_string(index=False), ""]
    else:
        am = res.mac.values.copy()
        for i in range(am.shape[0]):
            am[i, i] = 0.0
        out += [f"FE AutoMAC at the sensors: largest off-diagonal {am.max():.3f}"]
    sys.stdout.write("\n".join(out) + "\n")
    return 0
