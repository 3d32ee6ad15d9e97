"""``mvtk modes STRUCTURE.toml -n 6 [--json]``: natural frequencies of a structure."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ._commands import COMMANDS

__all__ = ["add_parser"]

#: Mesh and FE-deck files that a user may pass by mistake instead of a structure TOML.
#: Nastran bulk-data decks: a whole model, taken as it is.
_NASTRAN_SUFFIXES = (".bdf", ".dat", ".nas")
_MESH_SUFFIXES = (".msh", ".inp", ".vtu", ".vtk", ".med", ".xdmf", ".bdf", ".dat", ".nas",
                  ".unv", ".op4", ".mtx")


def add_parser(subparsers) -> None:
    """Register the ``modes`` sub-command."""
    p = subparsers.add_parser(
        "modes",
        help=COMMANDS["modes"].help,
        description="Build the FE model of a structure description (TOML) and print its "
        "lowest natural frequencies (Hz) with mode types.",
    )
    p.add_argument("structure", help="structure description (TOML, see mvtk.fe.build_model), "
                   "a study file (its structure) or a Nastran deck (.bdf/.dat/.nas)")
    p.add_argument("-n", "--n-modes", type=int, default=6, help="number of modes (default 6)")
    p.add_argument("--json", action="store_true",
                   help='print {"fn_hz": [...], "mode_type": [...], "n_dof": N} as JSON')
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Run ``mvtk modes``; returns the exit code (errors propagate as MvtkError)."""
    from ..fe._structure import build_model, resolve_mesh_file
    from ..study._text import read_toml

    path = Path(args.structure)
    if path.suffix.lower() in _NASTRAN_SUFFIXES:
        # a Nastran deck is a whole model (properties, materials, SPCs): the structure
        # TOML `mvtk init` writes around it, with the deck's defaults
        desc = {"name": f"{path.stem} (Nastran deck)", "structure": {"type": "mesh"},
                "mesh": {"file": path.name}}
        return _print_modes(args, build_model(resolve_mesh_file(desc, path.resolve().parent)))
    if path.suffix.lower() in _MESH_SUFFIXES:
        from ..errors import ConfigError

        raise ConfigError(
            f"{str(path)!r} is a mesh file, not a structure TOML: a mesh carries no "
            "materials, sections or supports (a Nastran deck .bdf/.dat/.nas does, and "
            "`mvtk modes DECK` takes it as it is). Write a structure TOML around it with "
            f"`mvtk init DIR --structure {path}`, edit what it marks EDIT, then run "
            "`mvtk modes DIR/structure.toml`")
    # UTF-8, UTF-8 with BOM or UTF-16 with BOM; a clear error naming the byte otherwise
    desc = read_toml(args.structure, "structure file")
    structure_file = desc.get("structure", {}).get("file") if "study" in desc else None
    if isinstance(structure_file, str):
        # a study: its nominal structure ([structure] file, relative to the study)
        path = (path.resolve().parent / structure_file).resolve()
        desc = read_toml(path, "structure file")
        if not args.json:
            print(f"structure of study {args.structure}: {path}")
    return _print_modes(args, build_model(resolve_mesh_file(desc, path.resolve().parent)))


def _print_modes(args: argparse.Namespace, model) -> int:
    """Modal analysis of ``model`` printed as a table (or JSON); exit code 0."""
    from ..fe._modal import modal_analysis

    res = modal_analysis(model, args.n_modes)
    if args.json:
        out = {
            "fn_hz": [float(f) for f in res.fn_hz],
            "mode_type": list(res.mode_type),
            "n_dof": int(model.n_dof),
        }
        sys.stdout.write(json.dumps(out) + "\n")
        return 0
    title = model.name or str(args.structure)
    lines = [f"{title}: {model.n_dof} DOF, {model.n_elements} elements", "",
             f"{'mode':>4}  {'fn_hz':>12}  type"]
    for i, (f, t) in enumerate(zip(res.fn_hz, res.mode_type), start=1):
        lines.append(f"{i:>4}  {f:12.4f}  {t}")
    sys.stdout.write("\n".join(lines) + "\n")
    return 0
