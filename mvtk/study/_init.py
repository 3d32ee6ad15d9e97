"""``mvtk init``: a first study (and structure) TOML from the user's own files.

:func:`init_study` reads each measurement file with :func:`mvtk.io.read`, decides what
test it is from what it holds, and writes a commented ``study.toml`` whose every value
comes from the files (channel names, record length, the resonances the default damping
estimator finds) or is a stated placeholder to edit. The written file is validated with
:func:`mvtk.study.load_study` before the command reports success, so what ``init``
writes is always accepted by ``mvtk run``.

``--structure`` takes a structure TOML (referenced as it is) or a bare mesh file (Gmsh
``.msh``, Abaqus ``.inp``, VTK, ... through meshio; a Nastran deck ``.bdf``/``.dat``/``.nas``):
for a mesh, :func:`mesh_structure_toml` writes ``structure.toml`` around it with one shell
section per element set (physical group) of surface cells and every other set listed as a
commented candidate for a beam section or a support.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._atomic import write_text
from ..errors import ConfigError, MvtkError

__all__ = ["init_study", "InitResult", "STRUCTURE_TEMPLATE", "PLACEHOLDER_MARK",
           "mesh_structure_toml", "placeholder_structure"]

#: Suffixes of Nastran bulk-data decks (the whole model, sections included, in the file).
_NASTRAN = (".bdf", ".dat", ".nas")

#: The line that marks init's placeholder structure: ``mvtk run`` refuses a structure
#: file that still holds it.
PLACEHOLDER_MARK = "# mvtk: PLACEHOLDER structure"

#: Structure file written when the user gives none: a clamped steel plate to edit.
STRUCTURE_TEMPLATE = f'''\
{PLACEHOLDER_MARK} -- EDIT it to your structure, then delete this line
# (`mvtk run` refuses the study while it is here).
# Structure description (mvtk.fe.build_model; reference: docs, "Structure TOML").
# A PLACEHOLDER written by `mvtk init`: replace the geometry, materials, layers, mesh and
# boundary conditions with those of your structure (SI units: m, Pa, kg/m^3), then check
# it with `mvtk modes structure.toml -n 6`.
name = "my structure (edit me)"

[materials.steel]
E = 210e9
nu = 0.30
rho = 7850

[structure]
type = "plate"            # "plate" (MITC4 shells), "beam", or "mesh" (Gmsh/Abaqus/Nastran file)
length = 0.30             # along x (m)
width = 0.20              # along y (m)

[[structure.layers]]
material = "steel"
thickness = 1.0e-3

[mesh]
element_size = 0.01       # m

[boundary]
clamp = "x0"              # clamped edge (x0, x1, y0, y1)
'''


@dataclass(frozen=True)
class InitResult:
    """What ``mvtk init`` wrote and found.

    Attributes
    ----------
    study : Path
        The study TOML written.
    structure : Path
        The structure TOML the study uses (written from the template or given).
    tests : list of dict
        One entry per measurement file: ``file``, ``kind`` (``impact``, ``decay``,
        ``modal`` or ``skipped``), what was found and why.
    next_command : str
        The command to run next.
    pairing : list of dict
        Each measured resonance (``fn_hz``) with the FE mode it was paired with by
        frequency (``fe_mode``, 1-based among the elastic modes, ``fe_fn_hz``,
        ``df_pct``; also ``fe_fn_refined_hz`` and ``refined_change_pct`` on a refined
        mesh: a generated mesh refined twice in each direction, an imported one with
        every element split into four); empty when the structure was not
        solved (placeholder, mesh to edit, or a multi-point test whose shapes pair the
        modes when the study runs).
    mesh_hint : list of str
        A mesh-convergence hint (lines) when the refined mesh changes a paired FE mode by
        more than the default ``checks.updated_fn_rel``; empty otherwise.
    """

    study: Path
    structure: Path
    tests: list = field(default_factory=list)
    next_command: str = ""
    pairing: list = field(default_factory=list)
    mesh_hint: list = field(default_factory=list)


def _rel(path: Path, start: Path) -> str:
    return Path(os.path.relpath(path.resolve(), start.resolve())).as_posix()


def _toml(value) -> str:
    """``value`` as a TOML value, written by tomli-w (strings escaped, never formatted)."""
    import tomli_w

    return tomli_w.dumps({"v": value}).split("=", 1)[1].strip()


def _inline_table(options: dict) -> str:
    """A TOML inline table of reader options (strings, numbers, booleans, lists)."""
    return "{" + ", ".join(f"{_toml_key(str(k))} = {_toml(v)}" for k, v in options.items()) + "}"


def placeholder_structure(path: str | Path) -> bool:
    """True when ``path`` is ``mvtk init``'s placeholder structure, not yet edited."""
    try:
        return PLACEHOLDER_MARK in Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError:
        return False


def _classify(path: Path, options: dict | None = None) -> dict:
    """What test a file holds: an impact test, a free decay, or a multi-point FRF set."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            ds, used, note = _read_with_options(path, options)
            out = _classify_dataset(path, ds)
        except MvtkError as err:
            return {"file": path, "kind": "skipped", "why": f"not readable: {err}",
                    "warnings": [f"{w.category.__name__}: {w.message}" for w in caught]}
    out["warnings"] = [f"{w.category.__name__}: {w.message}" for w in caught]
    out["read_options"] = used
    if note:
        out["note"] = note
    return out


def _read_with_options(path: Path, options: dict | None):
    """``(dataset, options used or None, note)``: the reader options given to ``mvtk
    init`` are used for the files that take them. A file that refuses them but reads
    without them (it states its own units, sampling rate, ...) is read without them,
    and the note says so; a file that reads neither way raises the first error."""
    import mvtk.io

    if not options:
        return mvtk.io.read(path), None, ""
    try:
        return mvtk.io.read(path, **options), options, ""
    except MvtkError as err:
        try:
            ds = mvtk.io.read(path)
        except MvtkError:
            raise err from None
        return ds, None, f"read without the reader options, which it refuses ({err})"


def _classify_dataset(path: Path, ds) -> dict:
    """What test a dataset read from ``path`` holds (see :func:`_classify`)."""
    import mvtk.damping
    import mvtk.signal

    if "frf" in ds and "time_history" not in ds:
        frf = ds["frf"]
        if frf.sizes.get("response", 1) > 1:
            f = frf["frequency"].values
            return {"file": path, "kind": "modal", "fmin": float(max(f[1], 0.02 * f[-1])),
                    "fmax": float(0.95 * f[-1]), "n_responses": int(frf.sizes["response"])}
        return {"file": path, "kind": "skipped",
                "why": "a single FRF: use `mvtk damping` on it (a study needs time histories "
                       "or a multi-point FRF set)"}
    if "time_history" not in ds:
        return {"file": path, "kind": "skipped", "why": "no time history or FRF matrix found"}
    th = ds["time_history"]
    names = [str(c) for c in th["channel"].values]
    qty = [str(q) for q in th["quantity"].values] if "quantity" in th.coords else []
    forces = [n for n, q in zip(names, qty) if q == "force"]
    others = [n for n, q in zip(names, qty) if q != "force"]
    if forces and others:
        sel = th.sel(channel=[forces[0], others[0]])
        res = mvtk.signal.frf(sel, reference=forces[0], response=others[0])
        out = {"file": path, "kind": "impact", "reference": forces[0], "response": others[0]}
        if res.attrs.get("excitation") != "impact":
            out.update(kind="skipped", why=f"force channel {forces[0]!r} is not a hammer "
                       "test (random or swept excitation): run `mvtk damping` on it")
            return out
        res_hz = float(res.attrs.get("resolution_hz", np.nan))
        fs = 1.0 / float(th["time"].values[1] - th["time"].values[0])
        if "node" in th.coords:  # node numbers: a candidate set of a roving test
            nodes = [int(n) for n in th["node"].values]
            if all(n >= 0 for n in nodes):
                band = res.attrs.get("excitation_band_hz") or [0.0, fs / 2]
                out["nodes"] = (int(th["node"].sel(channel=forces[0])),
                                int(th["node"].sel(channel=others[0])))
                out["band_hz"] = (float(band[0]), float(min(band[1], fs / 2)))
        out["record_s"] = float(1.0 / res_hz) if np.isfinite(res_hz) and res_hz > 0 else float(
            th.sizes["time"] / fs)
        try:
            # the estimator of `mvtk damping` and of the study's damping stage
            tab = mvtk.damping.estimate(sel, method="half_power", reference=forces[0],
                                        channel=[others[0]], excitation="impact").table
            keep = tab[tab["reliable"].astype(bool)] if "reliable" in tab else tab.iloc[:0]
            out["fn_hz"] = sorted(float(f) for f in keep["fn_hz"] if np.isfinite(f))
            out["n_peaks"] = int(len(tab))
        except MvtkError as err:
            out["fn_hz"] = []
            out["why"] = f"no resonance found by the default estimator ({err})"
        return out
    if others:
        return {"file": path, "kind": "decay", "channel": others[0]}
    return {"file": path, "kind": "skipped", "why": "only force channels"}


def _roving_groups(tests: list[dict]) -> list[list[dict]]:
    """The impact files that form roving tests (hammer or sensor moves between sets).

    Hammer-test files whose force and response channels carry node numbers are grouped
    by folder, in the order given. Within a folder, when every (hammer node, sensor
    node) pair occurs the same number of times k >= 2, the test was repeated: the j-th
    file of each pair belongs to the j-th test. Otherwise the folder is one test, and a
    pair measured in several files (a point hit again) is averaged over them by
    :func:`mvtk.modal.frf_matrix`. Each group of at least two files is one roving test:
    a roving hammer (the hammer node changes) or a roving sensor. Empty when there is
    none.
    """
    from collections import Counter

    cand = [t for t in tests if t["kind"] == "impact" and "nodes" in t]
    folders: dict = {}
    for t in cand:
        folders.setdefault(Path(t["file"]).resolve().parent, []).append(t)
    groups = []
    for members in folders.values():
        times = set(Counter(t["nodes"] for t in members).values())
        repeats = times.pop() if len(times) == 1 else 1
        if repeats < 2:
            groups.append(members)
            continue
        seen: Counter = Counter()
        split: list[list[dict]] = [[] for _ in range(repeats)]
        for t in members:
            split[seen[t["nodes"]]].append(t)
            seen[t["nodes"]] += 1
        groups += split
    return [g for g in groups if len(g) >= 2]


def _roving_band(group: list[dict]) -> tuple[float, float, str]:
    """Identification band of a roving test from its data: ``(fmin, fmax, why)``."""
    lo = max(max(t["band_hz"][0] for t in group), 0.0)
    hi = 0.95 * min(t["band_hz"][1] for t in group)
    # the band from the data: around the reliable resonances any set showed (a mode on
    # a nodal line of one hammer point is seen at another), inside the excited band
    peaks = sorted({f for t in group for f in (t.get("fn_hz") or [])})
    note = "excited band of the sets (no reliable resonance found)"
    if peaks:
        lo, hi = max(lo, 0.7 * peaks[0]), min(hi, 1.2 * peaks[-1])
        note = (f"0.7 x the lowest and 1.2 x the highest of the reliable resonances of the "
                f"sets ({peaks[0]:.5g}..{peaks[-1]:.5g} Hz)")
    return max(lo, 0.02 * hi), hi, note


def _fmt_list(values) -> str:
    return "[" + ", ".join(f"{v:.6g}" for v in values) + "]"


def init_study(folder: str | Path, *, structure: str | Path | None = None,
               measurements=(), name: str | None = None, overwrite: bool = False,
               read_options: dict | None = None, geometry: str | Path | None = None
               ) -> InitResult:
    """Write ``folder/study.toml`` (and ``folder/structure.toml`` without ``structure``).

    Parameters
    ----------
    folder : path
        Output folder (created); existing files are refused unless ``overwrite``.
    structure : path, optional
        The user's structure TOML (referenced, not copied), or a mesh file (any format
        :func:`mvtk.fe.read_mesh` reads, or a Nastran deck): then ``folder/structure.toml``
        is written around it by :func:`mesh_structure_toml`. Default: a commented
        placeholder plate written to ``folder/structure.toml``.
    measurements : sequence of path
        Measurement files: the first impact test becomes ``[measurements.impact]`` (its
        reliable resonances ``[damping] fn_hz`` and the ``[[updating.targets]]``, each
        paired with an FE mode of ``structure`` by frequency), every other hammer test
        ``[measurements.impact_2]``, ... (with its own reliable resonances), the free
        decays ``[measurements.decay]``, ``[measurements.decay_2]``, ..., a multi-point
        FRF set (UFF 58 with node numbers) ``[modal]``. Hammer-test files with node
        numbers form roving tests (grouped by folder; a repeated hammer/sensor node pair
        starts another test): the first is ``[modal]`` (``sets``), every further one a
        ``[measurements.roving_<k>]`` of kind ``multi-point`` (as every further
        multi-point FRF file, ``[measurements.multipoint_<k>]``), identified on its own
        and compared with ``[modal]``. Files that fit none are listed in the result with
        the reason.
    name : str, optional
        Study name (default: the folder name).
    overwrite : bool
    read_options : dict, optional
        Reader options (:func:`mvtk.io.read` keywords, e.g. ``units``, ``quantity``,
        ``fs``) for files that do not state them. Every file is read with them; a file
        that refuses them but reads without them (it states its own) is read without
        them (its ``tests`` entry has a ``note``). They are written as ``read_options``
        into the sections of the files that took them.
    geometry : path, optional
        Test geometry of a multi-point test (UFF 15/2411, or a CSV/TOML table of node,
        x, y, z in m), written as ``[modal] geometry``; without it the line is left
        commented (a UFF FRF file usually holds its geometry, CSV sets do not).

    Returns
    -------
    InitResult

    Raises
    ------
    ConfigError
        A file to write exists (without ``overwrite``), a given file is missing, or the
        written study does not validate (the message says why).
    """
    from ._config import load_study

    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise ConfigError(f"mvtk init: {str(folder)!r} is a file, expected a folder")
    folder.mkdir(parents=True, exist_ok=True)
    study_path = folder / "study.toml"
    is_toml = structure is not None and Path(structure).suffix.lower() == ".toml"
    targets = [study_path] + ([] if is_toml else [folder / "structure.toml"])
    for t in targets:
        if t.exists() and not overwrite:
            raise ConfigError(f"mvtk init: {str(t)!r} exists; use --force to overwrite it")
    for m in measurements:
        if not Path(m).is_file():
            raise ConfigError(f"mvtk init: measurement file {str(m)!r} not found")
    if geometry is not None and not Path(geometry).is_file():
        raise ConfigError(f"mvtk init: geometry file {str(geometry)!r} not found")
    if structure is not None:
        s_path = Path(structure)
        if not s_path.is_file():
            raise ConfigError(f"mvtk init: structure file {str(s_path)!r} not found")
        if not is_toml:
            text = mesh_structure_toml(s_path, folder)
            s_path = folder / "structure.toml"
            write_text(s_path, text)
    else:
        s_path = folder / "structure.toml"
        write_text(s_path, STRUCTURE_TEMPLATE)

    tests = [_classify(Path(m), read_options) for m in measurements]

    def opts_line(*ts) -> list[str]:
        used = [t.get("read_options") for t in ts]
        if not any(used):
            return []
        line = f"read_options = {_inline_table(read_options)}   # given to mvtk init"
        if all(used):
            return [line]
        return [f"# {line} (EDIT: not every set takes them)"]
    impact = next((t for t in tests if t["kind"] == "impact"), None)
    decay = next((t for t in tests if t["kind"] == "decay"), None)
    modal = next((t for t in tests if t["kind"] == "modal"), None)
    def geometry_line(commented: str) -> list[str]:
        if geometry is None:
            return [commented]
        return [f"geometry = {_toml(_rel(Path(geometry), folder))}"]

    groups = _roving_groups(tests)
    roving = groups[0] if groups and modal is None else []
    # further roving tests: multi-point measurements compared with the first
    further = groups[1:] if roving else groups
    for g in ([roving] if roving else []) + further:
        for t in g:
            t["kind"] = "impact" if t is impact else "roving set"
            t["roving"] = True
    more_impacts = [t for t in tests if t["kind"] == "impact" and t is not impact
                    and not t.get("roving")]
    more_decays = [t for t in tests if t["kind"] == "decay" and t is not decay]
    more_modal = [t for t in tests if t["kind"] == "modal" and t is not modal]

    lines = [
        f"# Validation study written by `mvtk init` from {len(tests)} measurement file(s).",
        "# Every value below was read from your files or is marked EDIT. Reference of every",
        "# section and key: the docs' 'Study file reference'. Paths are relative to this file.",
        "",
        "[study]",
        f"name = {_toml(name or folder.resolve().name)}",
        "",
        "[structure]",
        f"file = {_toml(_rel(s_path, folder))}"
        + ("   # EDIT: a placeholder plate" if structure is None else
           "   # EDIT: written around your mesh" if not is_toml else ""),
        "",
        "[fe]",
        "n_modes = 6",
        "",
    ]
    if impact or decay or more_impacts or further or more_modal:
        lines.append("[measurements]")
        lines.append("")
    if impact:
        lines += [
            "[measurements.impact]   # hammer test found by its force channel",
            f"file = {_toml(_rel(impact['file'], folder))}",
            f"reference = {_toml(impact['reference'])}",
            f"response = {_toml(impact['response'])}",
            f"# record_s = {impact['record_s']:.6g}   # default: chosen from the data, as "
            "`mvtk damping` does",
            *opts_line(impact),
            "",
        ]
    for k, t in enumerate(more_impacts):
        own = t.get("fn_hz") or []
        lines += [
            f"[measurements.impact_{k + 2}]   # another hammer test: its modes are a "
            "consistency check",
            'kind = "impact"',
            f"file = {_toml(_rel(t['file'], folder))}",
            f"reference = {_toml(t['reference'])}",
            f"response = {_toml(t['response'])}",
            (f"fn_hz = {_fmt_list(own)}   # its reliable resonances" if own else
             "# fn_hz: none reliable in this file; the modes of [damping] fn_hz are searched"),
            *opts_line(t),
            "",
        ]
    for k, t in enumerate(([decay] if decay else []) + more_decays):
        lines += [
            ("[measurements.decay]    # free decay (no force channel)" if k == 0 else
             f"[measurements.decay_{k + 1}]   # another free decay"),
            *([] if k == 0 else ['kind = "decay"']),
            f"file = {_toml(_rel(t['file'], folder))}",
            f"channel = {_toml(t['channel'])}",
            *opts_line(t),
            "",
        ]
    for k, g in enumerate(further):
        lo, hi, band_note = _roving_band(g)
        lines += [
            f"[measurements.roving_{k + 2}]   # another roving test of the specimen "
            f"({len(g)} sets): identified on its own and compared with [modal]",
            'kind = "multi-point"',
            f"sets = {_toml([_rel(t['file'], folder) for t in g])}",
            f"fmin_hz = {lo:.6g}   # {band_note}",
            f"fmax_hz = {hi:.6g}",
            *geometry_line("# geometry: that of [modal]"),
            *opts_line(*g),
            "",
        ]
    for k, t in enumerate(more_modal):
        lines += [
            f"[measurements.multipoint_{k + 2}]   # another multi-point FRF set: identified "
            "on its own and compared with [modal]",
            'kind = "multi-point"',
            f"file = {_toml(_rel(t['file'], folder))}",
            f"fmin_hz = {t['fmin']:.6g}",
            f"fmax_hz = {t['fmax']:.6g}",
            *opts_line(t),
            "",
        ]
    fn = (impact or {}).get("fn_hz") or []
    pairing: list[dict] = []
    pair_note = mesh_note = ""
    mesh_hint: list[str] = []
    if impact and len(fn) >= 2:
        lines += [
            "[damping]",
            f"fn_hz = {_fmt_list(fn)}   # resonances the default half-power estimator "
            "(mvtk damping) found reliable",
            "",
        ]
    elif impact:
        lines += [f"# [damping] not written: the default half-power estimator found "
                  f"{len(fn)} reliable resonance(s) in {_rel(impact['file'], folder)}; the "
                  "stage needs two (run `mvtk damping` on the file to see why)", ""]
    if impact and fn:
        shaped = bool(modal or roving)
        if is_toml:
            from ._config import CHECK_KEYS

            rows, pair_note, mesh_hint, mesh_note = _pair_with_model(
                s_path, fn, float(CHECK_KEYS["updated_fn_rel"]))
            pairing = [] if shaped else rows
        material = _first_material(s_path)
        updating = ["[updating]", ""]
        if pair_note:
            updating.insert(1, f"# {pair_note}")
        if mesh_hint:
            updating[1:1] = [f"# {x}" for x in mesh_hint]
        if pairing:
            updating += ["# Each measured resonance paired one-to-one with the FE mode of the "
                         "structure nearest in", "# frequency (a mode the sensor missed "
                         "does not shift the others):",
                         "#   measured (Hz)   FE mode   FE (Hz)   difference (%)"]
            updating += [f"#   {r['fn_hz']:13.6g}   {r['fe_mode']:7d}   {r['fe_fn_hz']:8.6g}"
                         f"   {r['df_pct']:+.3g}" for r in pairing]
            updating.append("")
        for i, f in enumerate(fn):
            updating += ["[[updating.targets]]   # EDIT: keep the modes the model should "
                         "match" if i == 0 else "[[updating.targets]]",
                         f"fn_hz = {f:.6g}"]
            row = next((r for r in pairing if r["fn_hz"] == f), None)
            if row is not None:
                updating.append(f"mode = {row['fe_mode']}   # FE mode paired by frequency")
            elif shaped:
                updating.append("# mode: paired by MAC with the multi-point test's shape "
                                "when the study runs")
            else:
                updating.append("# mode: paired by frequency on the nominal model when the "
                                "study runs")
            updating.append(f"label = {_toml(f'f{i + 1}')}")
            updating.append("")
        updating += [
            "[[updating.parameters]]   # EDIT: the uncertain parameters of your model",
            f"path = {_toml('materials.' + (material[0] if material else 'steel') + '.E')}",
        ]
        if material:
            e = material[1]
            updating += [f"lower = {0.5 * e:.6g}   # EDIT: bounds (half and twice the "
                         "structure's value)", f"upper = {2.0 * e:.6g}"]
            lines += updating + [""]
        else:  # a Nastran deck: its materials are cards, not structure-TOML paths
            lines += ["# The structure has no [materials] table (a Nastran deck): give the",
                      "# updating parameters as paths into a structure TOML, or a builder.",
                      *(f"# {x}" for x in updating), ""]
    if modal:
        lines += [
            "[modal]                 # multi-point FRF set (mvtk.modal)",
            f"file = {_toml(_rel(modal['file'], folder))}",
            f"fmin_hz = {modal['fmin']:.6g}",
            f"fmax_hz = {modal['fmax']:.6g}",
            *opts_line(modal),
*geometry_line(
                "# geometry = \"test_geometry.csv\"   # EDIT: node, x, y, z (m) unless the file "
                "has UFF 15 nodes"),
            "",
        ]
    if roving:
        lo, hi, band_note = _roving_band(roving)
        sets = _toml([_rel(t["file"], folder) for t in roving])
        kind = ("roving hammer" if len({t["nodes"][0] for t in roving}) > 1
                else "roving sensor")
        lines += [
            f"[modal]                 # {kind} test: {len(roving)} sets with node numbers "
            "(mvtk.modal)",
            f"sets = {sets}",
            f"fmin_hz = {lo:.6g}   # {band_note}",
            f"fmax_hz = {hi:.6g}",
*geometry_line("# geometry = \"test_geometry.csv\"   # EDIT: node, x, y, z (m): "
                           "needed to correlate with the FE model"),
            *opts_line(*roving),
            "",
        ]
    write_text(study_path, "\n".join(lines))
    log = [f"{t['file']}: {w}" for t in tests for w in t.get("warnings", [])]
    if mesh_note:
        log.append(f"mesh-convergence hint not computed: {mesh_note}")
    log += [f"mesh-convergence hint: {x}" for x in mesh_hint]
    if log:
        write_text(folder / "init.log", "\n".join(log) + "\n")
    try:
        load_study(study_path)
    except ConfigError as err:
        raise ConfigError(f"mvtk init wrote {study_path} but it does not validate: {err}. "
                          "Edit it (or the structure file) and run `mvtk run` again.") from err
    out_dir = folder / "report"
    return InitResult(study_path, s_path, tests,
                      f"mvtk run {study_path.as_posix()} --out {out_dir.as_posix()}",
                      pairing, mesh_hint)


def split_mesh(mesh):
    """An imported mesh with every element split into four (lines into two).

    Each edge gets its midpoint (shared by the cells and lines on it), each quadrilateral
    its centre; ``quad4`` -> 4 ``quad4``, ``tri3`` -> 4 ``tri3`` (corner triangles and
    the middle one), ``line2`` -> 2 ``line2``, the orientation of every cell kept. An
    element set holds the children of its cells; a node set gains the midpoints of the
    edges and the centres of the quadrilaterals whose corners are all in it. The new
    nodes lie on the straight edges: a faceted curved surface keeps its facets.

    Parameters
    ----------
    mesh : mvtk.fe.ImportedMesh
        First-order cells only (``tri3``, ``quad4``, ``line2``, ``vertex``).

    Returns
    -------
    mvtk.fe.ImportedMesh

    Raises
    ------
    ConfigError
        The mesh holds nine-node quadrilaterals (not split).
    """
    from ..fe import ImportedMesh

    if "quad9" in mesh.cells:
        raise ConfigError("the mesh holds nine-node quadrilaterals (quad9), which mvtk init "
                          "does not split")
    nodes = [np.asarray(mesh.nodes, dtype=float)]
    n0 = len(mesh.nodes)
    mid: dict = {}
    new: list = []

    def midpoint(a: int, b: int) -> int:
        key = (min(a, b), max(a, b))
        if key not in mid:
            mid[key] = n0 + len(new)
            new.append(0.5 * (mesh.nodes[a] + mesh.nodes[b]))
        return mid[key]

    cells, centre = {}, {}
    for kind, conn in mesh.cells.items():
        conn = np.asarray(conn, dtype=int)
        if kind == "quad4":
            out = []
            for i, (a, b, c, d) in enumerate(conn):
                ab, bc, cd, da = midpoint(a, b), midpoint(b, c), midpoint(c, d), midpoint(d, a)
                o = centre[i] = n0 + len(new)
                new.append(0.25 * mesh.nodes[[a, b, c, d]].sum(axis=0))
                out += [[a, ab, o, da], [ab, b, bc, o], [o, bc, c, cd], [da, o, cd, d]]
        elif kind == "tri3":
            out = []
            for a, b, c in conn:
                ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
                out += [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
        elif kind == "line2":
            out = []
            for a, b in conn:
                m = midpoint(a, b)
                out += [[a, m], [m, b]]
        else:
            cells[kind] = conn
            continue
        cells[kind] = np.asarray(out, dtype=int).reshape(-1, conn.shape[1])
    n_child = {"quad4": 4, "tri3": 4, "line2": 2}
    element_sets = {}
    for name, members in mesh.element_sets.items():
        element_sets[name] = {}
        for kind, idx in members.items():
            k = n_child.get(kind, 1)
            idx = np.asarray(idx, dtype=int)
            element_sets[name][kind] = (k * idx[:, None] + np.arange(k)).ravel()
    quads = np.asarray(mesh.cells.get("quad4", np.zeros((0, 4))), dtype=int)
    node_sets = {}
    for name, idx in mesh.node_sets.items():
        inside = set(int(i) for i in idx)
        more = [m for (a, b), m in mid.items() if a in inside and b in inside]
        more += [centre[i] for i, q in enumerate(quads) if all(int(x) in inside for x in q)]
        node_sets[name] = np.concatenate([np.asarray(idx, dtype=int),
                                          np.asarray(sorted(more), dtype=int)])
    all_nodes = np.vstack(nodes + ([np.asarray(new)] if new else []))
    return ImportedMesh(all_nodes, cells, element_sets, node_sets,
                        source=f"{mesh.source} (every element split into four)")


def _write_inp(mesh, path: Path) -> None:
    """Write an imported mesh as an Abaqus input file through meshio (element sets as
    *ELSET, node sets as *NSET: :func:`mvtk.fe.read_mesh` reads them back)."""
    import meshio

    names = {"quad4": "quad", "tri3": "triangle", "line2": "line", "vertex": "vertex"}
    kinds = list(mesh.cells)
    out = meshio.Mesh(
        mesh.nodes, [(names[k], mesh.cells[k]) for k in kinds],
        cell_sets={n: [np.asarray(m.get(k, []), dtype=int) for k in kinds]
                   for n, m in mesh.element_sets.items()},
        point_sets={n: np.asarray(v, dtype=int) for n, v in mesh.node_sets.items()})
    out.write(str(path), file_format="abaqus")


def _refined(desc: dict, workdir: Path | None = None) -> tuple[dict | None, str]:
    """``(description, why)``: ``desc`` with its mesh refined (None and the reason
    when it cannot be).

    A generated plate or beam: the mesh refined twice in each direction. An imported
    mesh: every element split into four (:func:`split_mesh`), written as an Abaqus file
    into ``workdir``. A Nastran deck or a mesh of nine-node elements is not refined.
    """
    import copy

    st = desc.get("structure") or {}
    mesh = desc.get("mesh") or {}
    kind = st.get("type", "plate")
    if kind == "mesh" or "file" in mesh:
        f = Path(str(mesh.get("file", "")))
        if f.suffix.lower() in _NASTRAN:
            return None, (f"the structure is a Nastran deck ({f.name}): mvtk init does not "
                          "refine it; refine it in the pre-processor and compare")
        if workdir is None:
            return None, "no folder to write the refined mesh into"
        from ..fe import read_mesh

        try:
            fine = split_mesh(read_mesh(f))
        except MvtkError as err:
            return None, f"the mesh {f.name} was not refined: {err}"
        path = Path(workdir) / (f.stem + "_split.inp")
        _write_inp(fine, path)
        out = copy.deepcopy(desc)
        out["mesh"]["file"] = str(path)
        return out, ""
    if kind not in ("plate", "beam"):
        return None, f"structure type {kind!r}: not refined"
    out = copy.deepcopy(desc)
    m = out.setdefault("mesh", {})
    if "element_size" in m:
        m["element_size"] = 0.5 * float(m["element_size"])
    elif kind == "beam":
        key = "n_elements" if "n_elements" in m else "nx" if "nx" in m else "n_elements"
        m[key] = 2 * int(m.get(key, 40))
    elif "nx" in m or "ny" in m:
        for k in ("nx", "ny"):
            if k in m:
                m[k] = 2 * int(m[k])
    else:
        return None, "the plate's [mesh] gives neither element_size nor nx/ny"
    return out, ""


def _pair_with_model(structure: Path, fn_hz: list[float], tol: float
                     ) -> tuple[list[dict], str, list[str], str]:
    """Pair measured resonances with the FE modes of ``structure`` by frequency.

    Returns ``(rows, note, mesh_hint, mesh_note)``: one row per paired resonance
    (``fn_hz``, ``fe_mode`` 1-based among the elastic modes, ``fe_fn_hz``, ``df_pct``,
    and ``fe_fn_refined_hz``, ``refined_change_pct`` on the refined mesh of
    :func:`_refined`), or no rows and a note saying why the model could not be solved
    (the pairing is then done when the study runs); ``mesh_hint`` holds the lines of a
    mesh-convergence hint when the refined mesh changes a paired mode by more than
    ``tol`` (relative); ``mesh_note`` says why no refined mesh was solved (empty when
    one was).
    """
    import tempfile

    from ..fe import build_model, load_structure
    from ..updating import pair_by_frequency
    from ._stages import nominal_modes

    try:
        desc = load_structure(structure)
        model = build_model(desc)
        modes = nominal_modes(model, 1.3 * max(fn_hz), n_min=len(fn_hz) + 4)
    except MvtkError as err:
        return [], (f"the structure could not be solved ({err}): the targets are paired by "
                    "frequency when the study runs"), [], ""
    f = np.asarray(modes.fn_hz, dtype=float)
    elastic = f[f >= 0.01 * min(fn_hz)]
    got = pair_by_frequency(fn_hz, elastic)
    rows = [{"fn_hz": float(fm), "fe_mode": int(m) + 1, "fe_fn_hz": float(elastic[m]),
             "df_pct": 100.0 * (elastic[m] / fm - 1.0)}
            for fm, m in zip(fn_hz, got) if m >= 0]
    hint: list[str] = []
    imported = (desc.get("structure") or {}).get("type") == "mesh"
    how = ("the mesh with every element split into four (its facets kept: a curved "
           "surface is not refined, remesh it in the mesher to see that too)" if imported
           else "a mesh refined twice in each direction")
    with tempfile.TemporaryDirectory(prefix="mvtk-init-") as tmp:
        fine, mesh_note = _refined(desc, Path(tmp))
        if fine is not None and not rows:
            fine, mesh_note = None, "no resonance paired with an FE mode"
        if fine is not None and model.n_dof >= 60000:
            fine, mesh_note = None, (f"the model has {model.n_dof} DOFs: a refined mesh "
                                     "is not solved by mvtk init")
        fm_ = np.zeros(0)
        if fine is not None:
            try:
                fm_ = np.asarray(nominal_modes(build_model(fine), 1.3 * max(fn_hz),
                                               n_min=len(elastic) + 2).fn_hz, dtype=float)
            except MvtkError as err:
                mesh_note = f"the refined mesh could not be solved ({err})"
    fe_fine = fm_[fm_ >= 0.01 * min(fn_hz)]
    for r in rows:
        k = r["fe_mode"] - 1
        if k < fe_fine.size:
            r["fe_fn_refined_hz"] = float(fe_fine[k])
            r["refined_change_pct"] = 100.0 * (fe_fine[k] / r["fe_fn_hz"] - 1.0)
    worst = [r for r in rows if abs(r.get("refined_change_pct", 0.0)) > 100 * tol]
    if worst:
        hint = [f"MESH: {how} changes the paired FE mode(s) by more than the target "
                f"tolerance ({100 * tol:g} %):"]
        hint += [f"  FE mode {r['fe_mode']}: {r['fe_fn_hz']:.6g} Hz -> "
                 f"{r['fe_fn_refined_hz']:.6g} Hz ({r['refined_change_pct']:+.2g} %)"
                 for r in worst]
        hint.append("EDIT the structure's mesh (finer) before updating: otherwise the "
                    "update compensates the discretisation error with the parameters")
    return rows, "", hint, mesh_note


def _first_material(structure: Path) -> tuple[str, float] | None:
    """Name and Young's modulus (Pa) of the structure's first material (None: none)."""
    from ..fe import load_structure

    try:
        mats = load_structure(structure).get("materials") or {}
    except MvtkError:
        return None
    for name, m in mats.items():
        e = m.get("E", m.get("E1")) if isinstance(m, dict) else None
        if isinstance(e, int | float) and e > 0:
            return str(name), float(e)
    return None


def _toml_key(name: str) -> str:
    """A TOML key: bare when it can be, else quoted."""
    import re

    if re.fullmatch(r"[A-Za-z0-9_-]+", name):
        return name
    return '"' + name.replace("\\", "\\\\").replace('"', '\\"') + '"'


def _section_name(set_name: str, taken: set) -> str:
    import re

    base = re.sub(r"[^A-Za-z0-9_]+", "_", set_name).strip("_") or "section"
    name, k = base, 2
    while name in taken:
        name, k = f"{base}_{k}", k + 1
    taken.add(name)
    return name


#: Cell kinds listed surfaces first, whatever order the mesh file stores them in.
_CELL_ORDER = {"quad4": 0, "tri3": 1, "line2": 2}


def _cell_kinds(cells) -> list[str]:
    return sorted(cells, key=lambda k: _CELL_ORDER.get(k, len(_CELL_ORDER)))


def mesh_structure_toml(mesh: str | Path, folder: str | Path) -> str:
    """Text of a structure TOML around a mesh file, written into ``folder``.

    Every element set (Gmsh physical group, Abaqus ``*ELSET``, ...) holding only surface
    cells (``tri3``/``quad4``) gets its own shell section (a placeholder 1 mm steel layer
    marked EDIT); sets with line cells are listed, commented, as candidates for a beam
    section (with a template ``[sections.*]`` table) or for a support, and every node
    set as a candidate for ``boundary.supports``. Without a chosen support the model is
    free-free (the file says so). A Nastran deck carries its own sections: the TOML then
    only references it.

    Parameters
    ----------
    mesh : path
        The mesh file (referenced relative to ``folder``, not copied).
    folder : path
        Where the structure TOML will be written (for the relative path).

    Returns
    -------
    str

    Raises
    ------
    ConfigError
        The mesh cannot be read, or has no element set of surface cells to give a section
        to (the message lists the sets found).
    """
    from ..fe import read_mesh

    mesh, folder = Path(mesh), Path(folder)
    rel = _rel(mesh, folder)
    if mesh.suffix.lower() in _NASTRAN:
        return "\n".join([
            f"# Structure written by `mvtk init` around the Nastran deck {mesh.name}: nodes,",
            "# elements, properties, materials and SPCs all come from the deck. Check it with",
            "# `mvtk modes structure.toml -n 6`.",
            f"name = {_toml(mesh.stem + ' (Nastran deck)')}",
            "",
            "[structure]",
            'type = "mesh"',
            "",
            "[mesh]",
            f"file = {_toml(rel)}",
            "# spc_id = 1             # EDIT: the SPC set to apply (default: all SPCs)",
            ""])
    try:
        m = read_mesh(mesh)
    except MvtkError as err:
        raise ConfigError(f"mvtk init: --structure {str(mesh)!r} is neither a structure TOML "
                          f"nor a readable mesh: {err}") from err
    kinds = {n: set(k) for n, k in m.element_sets.items()}
    shells = [n for n, k in kinds.items() if k and k <= {"tri3", "quad4"}]
    lines_ = [n for n, k in kinds.items() if "line2" in k and not k & {"tri3", "quad4"}]
    mixed = [n for n, k in kinds.items() if "line2" in k and k & {"tri3", "quad4"}]
    if not shells:
        found = ", ".join(f"{n} ({'/'.join(sorted(k))})" for n, k in kinds.items()) or "none"
        raise ConfigError(
            f"mvtk init: mesh {str(mesh)!r} has no element set (physical group) of only "
            f"triangle/quad cells to give a shell section to; sets found: {found}. Add a "
            "physical surface in Gmsh (or an *ELSET) for the shell, or write the structure "
            "TOML by hand (docs: 'Structure TOML')")
    counts = ", ".join(f"{len(m.cells[k])} {k}" for k in _cell_kinds(m.cells))
    lo, hi = m.nodes.min(axis=0), m.nodes.max(axis=0)
    box = ", ".join(f"{a} {lo[i]:.4g}..{hi[i]:.4g}" for i, a in enumerate("xyz"))
    taken: set = set()
    shell_sec = {n: _section_name(n, taken) for n in shells}
    beam_sec = {n: _section_name(n + "_beam", taken) for n in lines_}

    def size(n: str) -> str:
        sets = m.element_sets[n]
        return ", ".join(f"{len(sets[k])} {k}" for k in _cell_kinds(sets))

    out = [
        f"# Structure written by `mvtk init` around the mesh {mesh.name} (read with meshio):",
        f"# {len(m.nodes)} nodes, {counts};",
        f"# bounding box {box} (file units, taken as m).",
        "# EDIT the material, the section of each element set and the supports (SI units),",
        "# then check it with `mvtk modes structure.toml -n 6`. Reference: docs, 'Structure",
        "# TOML'.",
        f"name = {_toml(mesh.stem + ' (imported mesh)')}",
        "",
        "[materials.steel]        # EDIT: your material",
        "E = 210e9",
        "nu = 0.30",
        "rho = 7850",
        "",
        "[structure]",
        'type = "mesh"',
        "",
        "[mesh]",
        f"file = {_toml(rel)}",
        "# element set (physical group) -> section; sets not listed are left out of the model",
        "sections = { " + ", ".join(f'{_toml_key(n)} = "{shell_sec[n]}"' for n in shells)
        + " }",
    ]
    if lines_:
        out.append("# candidates with line cells (a beam section, or only an edge to support):")
        out += [f"#   {_toml_key(n)} = \"{beam_sec[n]}\"   ({size(n)})" for n in lines_]
    if mixed:
        out.append("# sets mixing surface and line cells (split them in the mesher to use them): "
                   + ", ".join(f"{n} ({size(n)})" for n in mixed))
    out.append("")
    for n in shells:
        out += [f"[sections.{shell_sec[n]}]   # element set {n!r}: {size(n)}",
                "layers = [{ material = \"steel\", thickness = 1.0e-3 }]   # EDIT", ""]
    for n in lines_:
        out += [f"# [sections.{beam_sec[n]}]   # element set {n!r} as beams: {size(n)}",
                '# shape = "rectangle"',
                '# material = "steel"',
                "# width = 0.01            # m, along the orientation vector",
                "# height = 0.01           # m",
                "# orientation = [0, 0, 1] # EDIT: a direction not along the beam",
                ""]
    example = shells[0] if shells else "<element set>"
    out += [
        "# Piezo patches (optional): bonded on an element set of surface cells or on a",
        "# region of the surface (box, circle or polygon in the tangent plane at origin);",
        "# their piezo plies become electrodes (docs: 'Piezo patches on any shell').",
        "# [materials.pic151]       # PI Ceramic PIC 151 datasheet values",
        "# E = 66.667e9",
        "# nu = 0.34",
        "# rho = 7800",
        "# d31 = -210e-12          # m/V",
        "# eps33 = 2.125e-8        # F/m (2400 eps0)",
        "# [[patches]]",
        '# name = "pzt"',
        f"# element_set = {json.dumps(example)}   # or:",
        '# # region = { shape = "box", origin = [x, y, z], u = [-0.02, 0.02], v = [-0.01, 0.01] }',
        '# layers = [{ material = "pic151", thickness = 0.25e-3 }]   # from the base outwards',
        '# side = "top"',
        "",
    ]
    node_sets = sorted(m.node_sets)
    out += [
        "[boundary]",
        "# No support chosen: the model is FREE-FREE (six rigid-body modes). Candidates (node",
        f"# sets of the mesh): {', '.join(node_sets) if node_sets else 'none'}.",
        "# Types: clamped, pinned, simply_supported, symmetry_z, ... or a list of DOFs.",
    ]
    out += [f'# supports = {{ {_toml_key(n)} = "clamped" }}' for n in node_sets[:1]]
    out.append("")
    return "\n".join(out)
