"""``mvtk reduce STUDY.toml [--json] [-n N]``: Craig-Bampton super element and its
FE-vs-SE tables (sizes as the paper's Table 4, frequencies as its Table 5).

The study is read through the one schema of :mod:`mvtk.study` and the super element is
the ``reduction`` stage of the cached study pipeline: built from the updated model when
the study has an ``[updating]`` section (as in ``mvtk run``), else from the nominal one.
The structure is ``[structure] file = "structure.toml"`` or written inline.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import ConfigError
from ._commands import COMMANDS

__all__ = ["add_parser", "run", "load_reduction_input"]


def add_parser(subparsers) -> None:
    """Register the ``reduce`` sub-command."""
    from ._common import add_cache_argument

    p = subparsers.add_parser(
        "reduce",
        help=COMMANDS["reduce"].help,
        description="Build the FE model of a study (updated when it has [updating]), "
        "reduce it to a Craig-Bampton super element as its [reduction] section says, and "
        "print the size table (nodes, elements, DOF), the FE vs SE eigenfrequencies with "
        "%% error and MAC, and the static check of boundary loads.",
    )
    p.add_argument("study", help="study TOML with [structure] and [reduction] sections")
    p.add_argument("-n", "--n-compare", type=int, default=None,
                   help="number of modes compared (default: reduction.n_compare or 4)")
    p.add_argument("--json", action="store_true",
                   help="print the tables as JSON (schemas/reduce.schema.json)")
    add_cache_argument(p)
    p.set_defaults(func=run)


def load_reduction_input(path: str | Path):
    """Read a study TOML: returns ``(model, reduction_table)`` (nominal structure).

    Raises
    ------
    ConfigError
        Missing file, invalid TOML, no ``[reduction]`` or no structure.
    """
    from ..fe import build_model
    from ..study import load_study

    study = load_study(path)
    if "reduction" not in study.config:
        raise ConfigError(f"{path}: no [reduction] section")
    return build_model(study.description()), study.config["reduction"]


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk reduce``; returns the exit code (errors propagate as MvtkError)."""
    import pandas as pd

    from ._common import json_document, run_view

    n = args.n_compare
    if n is not None and n < 1:
        raise ConfigError(f"--n-compare: expected an integer >= 1, got {n}")
    res = run_view(args.study, ["reduction"], args.cache,
                   {("reduction", "n_compare"): n} if n is not None else None)
    red = res.results["reduction"]
    ver = red["verify"]
    if args.json:
        out = {
            "model": red["model"],
            "retained": red["retained"],
            "n_boundary": red["n_boundary"],
            "n_modes": red["n_modes"],
            "interior_fn_hz": red["interior_fn_hz"],
            "updated_model": "updating" in res.results,
            **ver,
        }
        sys.stdout.write(json_document("reduce", args.study, out) + "\n")
        return 0
    title = red["model"] or str(args.study)
    lines = [f"{title}: Craig-Bampton super element, {red['n_boundary']} boundary DOF + "
             f"{red['n_modes']} fixed-interface modes"
             + (" (updated model)" if "updating" in res.results else ""), ""]
    for p in red["retained"]:
        snap = (f"  snapped {p['snap_distance_m']:.3g} m" if p["snap_distance_m"] > 0
                else "")
        lines.append(f"  retained {p['name']:<16} nodes {p['nodes']}  free DOF "
                     f"{p['free_dofs']}{snap}")
    sizes = pd.DataFrame(ver["sizes"]).set_index("quantity").rename(
        columns={"fe": "FE model", "se": "SE model"})
    lines += ["", sizes.to_string(), "",
              pd.DataFrame(ver["modes"]).to_string(index=False,
                                                   float_format="{:.6g}".format),
              "", f"static check (unit loads on boundary DOF): max relative error "
              f"{ver['static_max_rel_error']:.3e}"]
    sys.stdout.write("\n".join(lines) + "\n")
    return 0
