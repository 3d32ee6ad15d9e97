"""``mvtk init DIR [--structure FILE] [--measurements FILE ...]``: a first study."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._commands import COMMANDS

__all__ = ["add_parser"]


def _init(args: argparse.Namespace) -> int:
    from ..study._init import init_study
    from ._common import reader_options, refuse_inputs

    folder = Path(args.folder)
    writes = [("study.toml", folder / "study.toml")]
    if args.structure is None or Path(args.structure).suffix.lower() != ".toml":
        writes.append(("structure.toml", folder / "structure.toml"))
    refuse_inputs([("output", p) for _, p in writes],
                  [args.structure, *args.measurements, args.geometry])

    res = init_study(args.folder, structure=args.structure, measurements=args.measurements,
                     name=args.name, overwrite=args.force, read_options=reader_options(args),
                     geometry=args.geometry)
    print(f"wrote {res.study}")
    if args.structure is None:
        print(f"wrote {res.structure} (a placeholder plate: edit it to your structure)")
    elif res.structure.resolve() != Path(args.structure).resolve():
        print(f"wrote {res.structure} around {args.structure}: edit what it marks EDIT, then "
              f"check it with `mvtk modes {res.structure} -n 6`")
    for t in res.tests:
        what = t["kind"] if t["kind"] != "skipped" else f"skipped: {t['why']}"
        if t.get("note"):
            what += f" ({t['note']})"
        if t.get("n_peaks") is not None:
            what += f"; {len(t.get('fn_hz') or [])} of {t['n_peaks']} peaks reliable"
        if t.get("warnings"):
            what += f"; {len(t['warnings'])} warning(s) in {res.study.parent / 'init.log'}"
        print(f"  {t['file']}: {what}")
    if res.pairing:
        print("  targets paired with FE modes by frequency: " + ", ".join(
            f"{r['fn_hz']:.5g} Hz -> mode {r['fe_mode']} ({r['fe_fn_hz']:.5g} Hz)"
            for r in res.pairing))
    for line in res.mesh_hint:
        print(f"  {line}")
    print(f"next: {res.next_command}")
    return 0


def add_parser(subparsers) -> None:
    """Register ``mvtk init``."""
    p = subparsers.add_parser(
        "init", help=COMMANDS["init"].help,
        description="Read the measurement files, recognise the tests they hold (hammer "
        "test, free decay, multi-point FRF set) and write DIR/study.toml with the channels, "
        "record lengths and resonances found, plus DIR/structure.toml (a placeholder) when "
        "no --structure is given. Hammer-test files whose channels carry node numbers and "
        "differ in hammer or sensor node form a roving test ([modal] sets), grouped by "
        "folder (a node pair seen again starts another test); every further roving test "
        "or multi-point FRF file becomes a measurement of kind multi-point, compared with "
        "[modal]. The study is validated before the command returns.")
    p.add_argument("folder", help="folder to write study.toml (and structure.toml) into")
    p.add_argument("--structure", default=None, metavar="FILE",
                   help="your structure TOML (referenced), or a mesh file (Gmsh .msh, Abaqus "
                   ".inp, VTK, ..., or a Nastran .bdf): DIR/structure.toml is then written "
                   "around it, its element sets listed as section and support candidates")
    p.add_argument("--measurements", nargs="*", default=[], metavar="FILE",
                   help="measurement files (any format of mvtk read)")
    p.add_argument("--geometry", default=None, metavar="FILE",
                   help="test geometry of a multi-point test (UFF 15/2411, or CSV/TOML of "
                   "node, x, y, z in m), written as [modal] geometry")
    p.add_argument("--name", default=None, help="study name (default: the folder name)")
    p.add_argument("--force", action="store_true", help="overwrite existing files")
    from ._common import add_reader_options

    add_reader_options(p)
    p.set_defaults(func=_init)
