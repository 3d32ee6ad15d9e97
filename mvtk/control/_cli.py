"""``mvtk control STUDY.toml [--json]``: the controller comparison of a study."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile

__all__ = ["add_parser", "plant_from_arrays"]


def add_parser(subparsers) -> None:
    """Register the ``control`` sub-command."""
    p = subparsers.add_parser(
        "control",
        help="compare the controllers of a study's [control] section on its SE plant",
        description="Build the study's super-element plant (stages up to reduction, cached "
        "in --out) and run the [control] section: settling time, closed-loop damping of "
        "mode 1, FFT peak reduction and actuator peak/RMS per controller.",
    )
    p.add_argument("study", help="study TOML file")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    p.add_argument("--out", default=None,
                   help="folder for the stage cache (default: a temporary folder)")
    p.set_defaults(func=_main)


def plant_from_arrays(pa):
    """The SE plant from the study's reduction-stage arrays (M, C, K, B, Cq, Cv, D)."""
    from ._plant import StructuralPlant

    return StructuralPlant(
        pa["M"].values, pa["C"].values, pa["K"].values, pa["B"].values, pa["Cq"].values,
        pa["Cv"].values, inputs=[str(v) for v in pa["input"].values],
        outputs=[str(v) for v in pa["output"].values],
        coords=[str(v) for v in pa["coord"].values], D=pa["D"].values,
    )


def _main(args: argparse.Namespace) -> int:
    from ..errors import ConfigError
    from ..study import run
    from ._compare import run_control_section

    with tempfile.TemporaryDirectory() as tmp:
        res = run(args.study, args.out or tmp, report=False, progress=False)
    if "reduction" not in res.arrays:
        why = res.failed.get("reduction") or res.unavailable.get("reduction", "unknown")
        raise ConfigError(f"{args.study}: no super-element plant ({why})")
    section = res.study.config.get("control")
    if section is None:
        raise ConfigError(f"{args.study}: no [control] section")
    result = run_control_section(plant_from_arrays(res.arrays["reduction"]), section)
    if args.json:
        json.dump(result.to_dict(), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        sys.stdout.write(result.to_dataframe().to_string() + "\n")
    return 0
