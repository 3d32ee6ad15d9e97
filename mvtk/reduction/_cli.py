"""``mvtk reduce STUDY.toml [--json] [-n N]``: Craig-Bampton super element and its
FE-vs-SE tables (sizes as the paper's Table 4, frequencies as its Table 5).

The TOML either is a study file with ``[structure] file = "structure.toml"`` (path
relative to the study file) or a structure description with the structure tables inline;
either way it has a ``[reduction]`` section (see :mod:`mvtk.reduction._config`).
"""

from __future__ import annotations

import argparse
import json
import sys
import tomllib
from pathlib import Path

from ..errors import ConfigError

__all__ = ["add_parser", "run", "load_reduction_input"]

_STRUCTURE_KEYS = ("name", "materials", "structure", "patches", "mesh", "boundary", "points")


def add_parser(subparsers) -> None:
    """Register the ``reduce`` sub-command."""
    p = subparsers.add_parser(
        "reduce",
        help="Craig-Bampton super element and FE-vs-SE tables of a study TOML",
        description="Build the FE model of a study (or structure) TOML, reduce it to a "
        "Craig-Bampton super element as its [reduction] section says, and print the "
        "size table (nodes, elements, DOF), the FE vs SE eigenfrequencies with %% error "
        "and MAC, and the static check of boundary loads.",
    )
    p.add_argument("study", help="study TOML with [structure] and [reduction] sections")
    p.add_argument("-n", "--n-compare", type=int, default=None,
                   help="number of modes compared (default: reduction.n_compare or 4)")
    p.add_argument("--json", action="store_true", help="print the tables as JSON")
    p.set_defaults(func=run)


def load_reduction_input(path: str | Path):
    """Read a study/structure TOML: returns ``(model, reduction_table)``.

    Raises
    ------
    ConfigError
        Missing file, invalid TOML, no ``[reduction]`` or no structure.
    """
    from ..fe import build_model

    path = Path(path)
    try:
        with path.open("rb") as fh:
            cfg = tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"study file {str(path)!r} not found") from None
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{path}: invalid TOML: {err}") from err
    if "reduction" not in cfg:
        raise ConfigError(f"{path}: no [reduction] section")
    st = cfg.get("structure")
    if isinstance(st, dict) and "file" in st:
        rel = st["file"]
        if not isinstance(rel, str):
            raise ConfigError(f"{path}: structure.file: expected a path string, got {rel!r}")
        spath = (path.parent / rel).resolve()
        if not spath.is_file():
            raise ConfigError(f"{path}: structure.file {rel!r} not found (looked for {spath})")
        model = build_model(spath)
    elif isinstance(st, dict):
        model = build_model({k: cfg[k] for k in _STRUCTURE_KEYS if k in cfg})
    else:
        raise ConfigError(
            f"{path}: expected a [structure] table with 'file' (study) or the structure "
            "tables inline (structure TOML)"
        )
    return model, cfg["reduction"]


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk reduce``; returns the exit code (errors propagate as MvtkError)."""
    from ._config import super_element_from_config
    from ._verify import verify

    model, red = load_reduction_input(args.study)
    se, points = super_element_from_config(model, red)
    n = args.n_compare if args.n_compare is not None else red.get("n_compare", 4)
    if isinstance(n, bool) or not isinstance(n, int) or n < 1:
        raise ConfigError(f"reduction.n_compare: expected an integer >= 1, got {n!r}")
    n = min(n, se.n_dof)
    ver = verify(model, se, n)
    if args.json:
        out = {
            "study": str(args.study),
            "model": model.name,
            "retained": [
                {"name": p.name, "nodes": list(p.nodes), "free_dofs": p.n_free_dofs}
                for p in points
            ],
            "n_boundary": se.n_boundary,
            "n_modes": se.n_modes,
            "interior_fn_hz": [float(f) for f in se.interior_fn_hz],
            **ver.to_dict(),
        }
        sys.stdout.write(json.dumps(out) + "\n")
        return 0
    title = model.name or str(args.study)
    lines = [f"{title}: Craig-Bampton super element, {se.n_boundary} boundary DOF + "
             f"{se.n_modes} fixed-interface modes", ""]
    for p in points:
        lines.append(f"  retained {p.name:<16} nodes {list(p.nodes)}  free DOF {p.n_free_dofs}")
    lines += ["", ver.sizes.to_dataframe().to_string(), "",
              ver.modes.to_dataframe().to_string(index=False, float_format="{:.6g}".format),
              "", f"static check (unit loads on boundary DOF): max relative error "
              f"{ver.static.max_rel_error:.3e}"]
    sys.stdout.write("\n".join(lines) + "\n")
    return 0
