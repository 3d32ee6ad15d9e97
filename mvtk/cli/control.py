"""``mvtk control STUDY.toml [--json]``: the controller comparison of a study.

The study is read through the one schema of :mod:`mvtk.study`; the comparison is the
``control`` stage of the cached study pipeline (the same table as the report's), with
the stability verdict of every loop: closed-loop eigenvalues for the linear laws (the
largest real part of the poles), the simulated trajectory for the nonlinear ones.
"""

from __future__ import annotations

import argparse
import sys

from ._commands import COMMANDS

__all__ = ["add_parser", "plant_from_arrays"]

_TEXT_COLUMNS = ("settling_time_s", "zeta_mode1", "fn_mode1_hz", "stable",
                 "max_real_pole_1_per_s", "gain_margin_db", "critical_gain_factor",
                 "peak_voltage_V", "voltage_within_limit", "peak_reduction_db")


def add_parser(subparsers) -> None:
    """Register the ``control`` sub-command."""
    from ._common import add_cache_argument

    p = subparsers.add_parser(
        "control",
        help=COMMANDS["control"].help,
        description="Run the study's stages up to its [control] section (cached) and print "
        "per controller: settling time, closed-loop damping of mode 1, stability (largest "
        "real part of the closed-loop poles), gain margin and critical gain factor of a "
        "single-actuator loop, FFT peak reduction and actuator peak. Exit "
        "status 1 when a closed loop is unstable.",
    )
    p.add_argument("study", help="study TOML file")
    p.add_argument("--json", action="store_true",
                   help="print the table as JSON (schemas/control.schema.json)")
    add_cache_argument(p)
    p.add_argument("--out", dest="cache", default=None, help=argparse.SUPPRESS)
    p.set_defaults(func=_main)


def plant_from_arrays(pa):
    """The SE plant from the study's reduction-stage arrays (M, C, K, B, Cq, Cv, D)."""
    from ..control._plant import StructuralPlant

    return StructuralPlant(
        pa["M"].values, pa["C"].values, pa["K"].values, pa["B"].values, pa["Cq"].values,
        pa["Cv"].values, inputs=[str(v) for v in pa["input"].values],
        outputs=[str(v) for v in pa["output"].values],
        coords=[str(v) for v in pa["coord"].values], D=pa["D"].values,
    )


def _main(args: argparse.Namespace) -> int:
    import pandas as pd

    from ._common import json_document, run_view

    res = run_view(args.study, ["control"], args.cache)
    ctl = res.results["control"]
    rows = ctl["metrics"]
    unstable = [r["controller"] for r in rows if r.get("stable") is False]
    if args.json:
        body = {"rows": rows, "unstable": unstable,
                **{k: ctl[k] for k in ("settle_band", "fs_out", "t_end_s",
                                        "actuator_limit_v", "moment_per_volt")}}
        sys.stdout.write(json_document("control", args.study, body) + "\n")
    else:
        df = pd.DataFrame(rows).set_index("controller")
        cols = [c for c in _TEXT_COLUMNS if c in df.columns]
        with pd.option_context("display.width", 200, "display.max_columns", 20):
            sys.stdout.write(df[cols].to_string() + "\n")
        for name in unstable:
            r = next(r for r in rows if r["controller"] == name)
            print(f"mvtk control: closed loop {name!r} is UNSTABLE ({r['stability_basis']}; "
                  f"largest real part of the poles {r['max_real_pole_1_per_s']:.4g} 1/s)",
                  file=sys.stderr)
    return 1 if unstable else 0
