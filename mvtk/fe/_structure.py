'''Structure descriptions (TOML or dict) and :func:`build_model`.

Schema
------
All quantities in SI (m, Pa, kg/m^3, degrees for ply angles). A complete example::

    name = "smart beam"                   # optional

    [materials.steel]                     # isotropic: E, nu, rho
    E = 210e9
    nu = 0.3
    rho = 7900

    [materials.cfrp]                      # orthotropic: E1, E2, G12, G13, G23, nu12, rho
    E1 = 140e9
    E2 = 10e9
    G12 = 5e9
    G13 = 5e9
    G23 = 3.5e9
    nu12 = 0.3
    rho = 1600

    [materials.epoxy]
    E = 3.546e9
    nu = 0.35
    rho = 1180

    [materials.pic151]                    # piezo: E, nu, rho, d31 (m/V)
    E = 66.667e9
    nu = 0.34
    rho = 7800
    d31 = -210e-12

    [structure]
    type = "plate"                        # "plate" (MITC4 shells) or "beam" (see below)
    length = 0.18                         # along x (m)
    width = 0.133                         # along y (m)
    shear_correction = 0.8333333          # optional, default 5/6

    [[structure.layers]]                  # base laminate, bottom to top; its mid-plane
    material = "steel"                    # is the reference surface
    thickness = 0.5e-3
    angle = 0.0                           # optional, degrees

    [[patches]]                           # optional; layers bonded on top of the base
    name = "pzt"
    x0 = 0.005
    x1 = 0.055
    y0 = 0.04
    y1 = 0.09
    layers = [{ material = "epoxy", thickness = 36e-6 },
              { material = "pic151", thickness = 0.25e-3 }]

    [mesh]                                # nx and ny, or element_size (m)
    nx = 36
    ny = 26

    [boundary]
    clamp = "x0"                          # clamped edge (x0, x1, y0 or y1), optional
    clamp_stiffness = 5e3                 # optional: elastic clamp rotation, N m/rad per m
    clamp_translational_stiffness = 1e8   # optional: elastic clamp uz, N/m per m
    edges = { y0 = "free" }               # optional: clamped, simply_supported, hinged,
                                          # free, or a list of DOF names ["uz", "rx"]

    [[boundary.springs]]                  # optional grounded springs
    node_set = "tip"                      # any node set (edges, patch edges, points)
    dof = "uz"
    k = 100.0                             # N/m (or N m/rad) per node ...
    per_length = false                    # ... or per metre of edge when true

    [[points]]                            # named points: nodes and node sets
    name = "tip"
    x = 0.18
    y = 0.0665

A ``type = "beam"`` structure (layered Timoshenko beam along x,
:func:`mvtk.fe.cantilever_beam`) takes the same materials, ``structure.length``,
``width``, ``layers``; patches use ``x0``, ``x1``, ``layers`` and optionally ``y0``/``y1``
(only their difference, the patch width, matters); ``[mesh]`` one of ``n_elements``,
``nx`` or ``element_size``; ``[boundary] clamp = "x0" | "x1" | "free"`` and
``clamp_stiffness`` / ``clamp_translational_stiffness`` per metre of clamp edge as for
plates (multiplied by the width to the beam's total spring), ``supports`` and
``[[boundary.springs]]`` (per node) on the node sets ``x0 x1 all``, points and patch
ends; points by ``x`` (``y``, if given, within the width).

Both plates and beams take ``boundary.supports = { <node set> = "<type>" | [DOFs] }`` with
the types of :data:`mvtk.fe.GENERAL_SUPPORTS` (docs/fe.md), and, like meshes,
``[[masses]]`` (an accelerometer, an added mass)::

    [[masses]]
    point = "tip"                         # a [[points]] name or a one-node set
    mass = 0.020                          # kg
    inertia = [1e-7, 1e-7, 2e-7]          # kg m^2 about the mass centre: 3 values (diagonal),
                                          # 6 [Jxx, Jyy, Jzz, Jxy, Jyz, Jxz] or 3x3
    axes = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]  # optional: body axes (rows, global coords)
                                          # in which inertia is given; rotated to global
    offset = [0.0, 0.0, 0.005]            # m, node to mass centre

A ``type = "mesh"``
structure imports a mesh file (``[mesh] file``, ``sections``), with ``[sections.*]``,
``[[masses]]``, ``[[rigid_links]]``, ``[[points]]`` with x, y, z,
``[coordinate_systems.*]``, ``boundary.frames`` and ``[[loads]]``
(:mod:`mvtk.fe._structure_loads`); its schema is in data/structures/README.md; its
``[[patches]]`` take ``name``, ``element_set`` (a set of
the mesh) or ``region`` (``shape`` box/circle/polygon, ``origin``, ``axis``, ``u``, ``v``,
``radius``, ``points``: see :func:`mvtk.fe.select_region`), ``layers`` (from the base
outwards), ``side`` (top/bottom) and ``electrodes`` (``name``, ``plies``, ``signs``); the
piezo plies become electrodes of ``meta['piezo_patches']`` (:func:`mvtk.fe.piezo_coupling`,
docs/guide/fe.md). Every unknown or inapplicable key raises
:class:`~mvtk.errors.ConfigError` naming the key and the accepted ones.

Node sets of the (plate) model: the edges ``x0 x1 y0 y1``, ``patch:<name>`` and its edges
``patch:<name>:x0`` ... ``:y1``, and one set per point.

:func:`build_model` is deterministic: the same description gives the same model, so a
model updater can perturb any numeric field by its dotted path (``materials.steel.E``,
``structure.length``, ``boundary.clamp_stiffness``) and rebuild (see
:func:`set_by_path`).
'''

from __future__ import annotations

import copy
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import ConfigError, MvtkError
from ._general import GENERAL_SUPPORTS, support_dofs
from ._laminate import Laminate
from ._materials import (
    IsotropicMaterial,
    OrthotropicMaterial,
    OrthotropicPiezoMaterial,
    PiezoMaterial,
    Ply,
)
from ._mesh import Patch
from ._model import DOF_NAMES, FEModel
from ._plate import SpringSupport, plate_model
from ._structure_loads import coordinate_systems, load_cases, node_frames

__all__ = ["build_model", "load_structure", "set_by_path", "get_by_path", "constrain_model"]

_ORTHO_KEYS = ("E1", "E2", "G12", "G13", "G23", "nu12", "rho")


def resolve_mesh_file(desc: dict, base_dir: str | Path) -> dict:
    """Make a relative ``[mesh] file`` absolute, relative to ``base_dir`` (the folder of
    the structure TOML that names it), so the description works from any directory."""
    mesh = desc.get("mesh")
    if isinstance(mesh, dict) and isinstance(mesh.get("file"), str):
        f = Path(mesh["file"])
        if not f.is_absolute():
            mesh["file"] = str((Path(base_dir) / f).resolve())
    return desc


def load_structure(path: str | Path) -> dict:
    """Read a structure TOML file into a dict.

    Raises
    ------
    ConfigError
        If the file is missing or not valid TOML (message names the file).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "beam.toml"
    >>> _ = path.write_text('name = "beam"\\n[materials.steel]\\nE = 2.1e11\\nnu = 0.3\\n')
    >>> load_structure(path)
    {'name': 'beam', 'materials': {'steel': {'E': 210000000000.0, 'nu': 0.3}}}
    """
    path = Path(path)
    from .._atomic import special_file

    kind = special_file(path)
    if kind is not None:
        raise ConfigError(f"structure file {str(path)!r} is {kind}, expected a TOML file")
    try:
        with path.open("rb") as fh:
            return resolve_mesh_file(tomllib.load(fh), path.parent)
    except FileNotFoundError:
        raise ConfigError(f"structure file {str(path)!r} not found") from None
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"structure file {str(path)!r} is not valid TOML: {err}") from err


def _step(node: Any, part: str, done: list[str]) -> Any:
    """One step of a dotted-path walk; ConfigError says why it cannot go on."""
    where = ".".join(done) or "<root>"
    if isinstance(node, Mapping):
        if part not in node:
            raise ConfigError(
                f"no key {part!r} under {where}; available keys: {sorted(map(str, node))}"
            )
        return node[part]
    if isinstance(node, list | tuple):
        try:
            i = int(part)
        except ValueError:
            raise ConfigError(
                f"{where} is a list, expected an integer index, got {part!r}"
            ) from None
        if not -len(node) <= i < len(node):
            raise ConfigError(
                f"index {i} out of range for {where} (list of length {len(node)})"
            )
        return node[i]
    raise ConfigError(
        f"{where} is a {type(node).__name__} value, not a table or list, "
        f"so it has no field {part!r}"
    )


def walk_path(d: Mapping, parts: list[str]) -> Any:
    """Value reached by the path ``parts`` in nested dicts/lists (ConfigError otherwise)."""
    node: Any = d
    done: list[str] = []
    for part in parts:
        node = _step(node, part, done)
        done.append(part)
    return node


def get_by_path(d: Mapping, path: str) -> Any:
    """Value at a dotted path (``"materials.steel.E"``; list items by index ``layers.0``).

    Examples
    --------
    >>> d = {"materials": {"steel": {"E": 2.1e11}}, "layers": [{"thickness": 2e-3}]}
    >>> get_by_path(d, "materials.steel.E"), get_by_path(d, "layers.0.thickness")
    (210000000000.0, 0.002)
    """
    try:
        return walk_path(d, path.split("."))
    except ConfigError as err:
        raise ConfigError(f"no entry {path!r} in the structure: {err}") from None


def set_by_path(d: Mapping, path: str, value: Any, create: bool = False) -> dict:
    """Copy of ``d`` with the entry at dotted ``path`` replaced by ``value``.

    With ``create=True`` a missing last key is added to an existing table (e.g.
    ``boundary.clamp_stiffness`` for a structure with a rigid clamp); unknown keys are
    still rejected by :func:`build_model`.

    Examples
    --------
    The original is left unchanged:

    >>> d = {"layers": [{"thickness": 2e-3}]}
    >>> set_by_path(d, "layers.0.thickness", 3e-3), d
    ({'layers': [{'thickness': 0.003}]}, {'layers': [{'thickness': 0.002}]})
    """
    out = copy.deepcopy(dict(d))
    parts = path.split(".")
    try:
        parent = get_by_path(out, ".".join(parts[:-1])) if len(parts) > 1 else out
    except ConfigError as err:
        raise ConfigError(f"no entry {path!r} in the structure ({err})") from None
    last = parts[-1]
    if isinstance(parent, list):
        try:
            parent[int(last)] = value
        except (IndexError, ValueError):
            raise ConfigError(f"no entry {path!r} in the structure") from None
    elif isinstance(parent, dict) and (last in parent or create):
        parent[last] = value
    else:
        raise ConfigError(f"no entry {path!r} in the structure")
    return out


def _table(d: Mapping, key: str, where: str) -> Mapping:
    v = d.get(key)
    if not isinstance(v, Mapping):
        raise ConfigError(f"{where}{key}: expected a table, got {type(v).__name__}")
    return v


def _number(d: Mapping, key: str, where: str, positive: bool = True,
            required: bool = True, default: float | None = None) -> float | None:
    if key not in d:
        if required:
            raise ConfigError(f"{where}{key}: required number missing")
        return default
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not np.isfinite(v):
        raise ConfigError(f"{where}{key}: expected a number, got {v!r}")
    if positive and v <= 0:
        raise ConfigError(f"{where}{key}: expected a positive number, got {v!r}")
    return float(v)


def _material(name: str, d: Any):
    where = f"materials.{name}."
    if not isinstance(d, Mapping):
        raise ConfigError(f"materials.{name}: expected a table, got {type(d).__name__}")
    try:
        piezo_keys = ("d31", "d32", "eps33")
        if "d32" in d and "d31" not in d:
            raise ConfigError(f"{where}d31: a piezo material needs d31 (m/V) with d32")
        if "eps33" in d and "d31" not in d:
            raise ConfigError(f"{where}d31: a piezo material needs d31 (m/V) with eps33")
        piezo = {k: _number(d, k, where, positive=(k == "eps33"))
                 for k in piezo_keys if k in d}
        if "E1" in d:
            unknown = set(d) - set(_ORTHO_KEYS) - set(piezo_keys)
            if unknown:
                raise ConfigError(f"{where}: unknown keys {sorted(unknown)}; "
                                  f"orthotropic materials take {list(_ORTHO_KEYS)} "
                                  "(and d31, d32, eps33 for piezo)")
            vals = {k: _number(d, k, where, positive=(k != "nu12")) for k in _ORTHO_KEYS}
            if piezo:
                return OrthotropicPiezoMaterial(name=name, **vals, **piezo)
            return OrthotropicMaterial(name=name, **vals)
        allowed = {"E", "nu", "rho", "d31", "d32", "eps33"}
        unknown = set(d) - allowed
        if unknown:
            raise ConfigError(
                f"{where}: unknown keys {sorted(unknown)}; isotropic materials take E, nu, rho "
                "(and d31, d32, eps33 for piezo), orthotropic ones E1, E2, G12, G13, G23, "
                "nu12, rho"
            )
        E = _number(d, "E", where)
        nu = _number(d, "nu", where, positive=False)
        rho = _number(d, "rho", where)
        if piezo:
            return PiezoMaterial(name, E, nu, rho, piezo["d31"], piezo.get("d32"),
                                 piezo.get("eps33"))
        return IsotropicMaterial(name, E, nu, rho)
    except ConfigError:
        raise
    except MvtkError as err:
        raise ConfigError(f"materials.{name}: {err}") from err


def _plies(layers: Any, materials: Mapping, where: str) -> list[Ply]:
    if not isinstance(layers, list) or not layers:
        raise ConfigError(f"{where}: expected a non-empty list of layers")
    out = []
    for i, layer in enumerate(layers):
        w = f"{where}[{i}]."
        if not isinstance(layer, Mapping):
            raise ConfigError(f"{where}[{i}]: expected a table with material and thickness")
        unknown = set(layer) - {"material", "thickness", "angle"}
        if unknown:
            raise ConfigError(f"{w}: unknown keys {sorted(unknown)}; "
                              "expected material, thickness, angle")
        mat = layer.get("material")
        if mat not in materials:
            raise ConfigError(
                f"{w}material: {mat!r} is not defined; defined materials: {sorted(materials)}"
            )
        t = _number(layer, "thickness", w)
        angle = _number(layer, "angle", w, positive=False, required=False, default=0.0)
        out.append(Ply(materials[mat], t, angle))
    return out


def build_model(structure: Mapping | str | Path) -> FEModel:
    """Build an :class:`FEModel` from a structure description, checked before any solve.

    The model passes :func:`mvtk.fe._sanity.check_model`: duplicate names, duplicated
    elements, points off the mesh and complex or indefinite matrices are errors; a
    geometry or material in a suspicious unit, a mesh too coarse for a bending
    half-wave and coincident unconnected nodes are :class:`~mvtk.errors.ModelWarning`
    s, also listed in ``model.meta["sanity"]``.

    Examples
    --------
    A structure description (as in a TOML file): the steel cantilever 300 x 20 x 2 mm,
    first frequency 18.567 Hz (Euler-Bernoulli, see :func:`mvtk.fe.modal_analysis`):

    >>> from mvtk.fe import modal_analysis
    >>> beam = {"name": "beam",
    ...         "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}},
    ...         "structure": {"type": "beam", "length": 0.3, "width": 0.02,
    ...                       "layers": [{"material": "steel", "thickness": 2e-3}]},
    ...         "mesh": {"n_elements": 20}, "boundary": {"clamp": "x0"}}
    >>> np.round(modal_analysis(build_model(beam), 1).fn_hz, 1)
    array([18.6])
    """
    from ._sanity import check_model

    return check_model(_build_model(structure))


def _build_model(structure: Mapping | str | Path) -> FEModel:
    """Build an :class:`FEModel` from a structure description.

    Parameters
    ----------
    structure : dict or path
        A parsed description or the path of a TOML file (schema in the module docstring).

    Returns
    -------
    FEModel
        ``meta["structure"]`` is a deep copy of the description (a dict).

    Raises
    ------
    ConfigError
        For any invalid entry; the message names the dotted key.
    """
    source = None
    if isinstance(structure, (str, Path)):
        source = str(structure)
        structure = load_structure(structure)
    if not isinstance(structure, Mapping):
        raise ConfigError(f"structure must be a dict or a TOML path, got {type(structure)}")
    s = copy.deepcopy(dict(structure))
    known = {"name", "materials", "structure", "patches", "mesh", "boundary", "points",
             "sections", "masses", "rigid_links", "coordinate_systems", "loads"}
    unknown = set(s) - known
    if unknown:
        raise ConfigError(f"unknown top-level keys {sorted(unknown)}; expected {sorted(known)}")
    mats_d = _table(s, "materials", "") if "materials" in s else {}
    materials = {str(k): _material(str(k), v) for k, v in mats_d.items()}
    st = _table(s, "structure", "")
    kind = st.get("type", "plate")
    mesh_d = s.get("mesh")
    if isinstance(mesh_d, Mapping) and "file" in mesh_d and kind != "mesh":
        raise ConfigError(f"mesh.file needs structure.type = 'mesh' (got {kind!r}); an "
                          "imported mesh replaces the built-in plate/beam generator")
    if kind == "mesh":
        return _build_mesh(s, st, materials, source)
    for key, why in (("sections", "for imported meshes"),
                     ("rigid_links", "for imported meshes"),
                     ("coordinate_systems", "for imported meshes and Nastran decks"),
                     ("loads", "for imported meshes and Nastran decks")):
        if key in s:
            raise ConfigError(f"{key}: not applicable to structure.type = {kind!r} ({why}, "
                              "structure.type = 'mesh')")
    if kind == "beam":
        return _build_beam(s, st, materials, source)
    if kind != "plate":
        raise ConfigError(f"structure.type: expected 'plate', 'beam' or 'mesh', got {kind!r}")
    length, width, ks, layers = _base_section(st, materials)

    patches = []
    for i, p in enumerate(s.get("patches", [])):
        w = f"patches[{i}]."
        if not isinstance(p, Mapping):
            raise ConfigError(f"patches[{i}]: expected a table")
        name = p.get("name")
        if not isinstance(name, str) or not name:
            raise ConfigError(f"{w}name: expected a non-empty string, got {name!r}")
        _check_keys(p, f"patches[{i}]", ("name", "x0", "x1", "y0", "y1", "layers",
                                          "electrodes"))
        coords = [_number(p, k, w, positive=False) for k in ("x0", "x1", "y0", "y1")]
        patches.append((Patch(name, *coords), _plies(p.get("layers"), materials, w + "layers")))

    mesh = s.get("mesh", {})
    if not isinstance(mesh, Mapping):
        raise ConfigError("mesh: expected a table")
    _check_keys(mesh, "mesh", ("nx", "ny", "element_size"),
                {"n_elements": "for beams; a plate takes nx and ny"})
    for k in ("nx", "ny"):
        if k in mesh and (isinstance(mesh[k], bool) or not isinstance(mesh[k], int)
                          or mesh[k] < 1):
            raise ConfigError(f"mesh.{k}: expected a positive integer, got {mesh[k]!r}")
    if ("nx" in mesh) != ("ny" in mesh) and "element_size" not in mesh:
        raise ConfigError("mesh: give both nx and ny, or element_size")
    if "element_size" in mesh and ("nx" in mesh or "ny" in mesh):
        raise ConfigError(
            "mesh: give either nx and ny or element_size, not both (one of them would be "
            f"ignored); found keys {sorted(mesh)}"
        )
    if not mesh:
        raise ConfigError("mesh: missing; give nx and ny, or element_size")
    esize = _number(mesh, "element_size", "mesh.", required=False)

    b = s.get("boundary", {})
    if not isinstance(b, Mapping):
        raise ConfigError("boundary: expected a table")
    _check_keys(b, "boundary", _PLATE_BOUNDARY_KEYS)
    clamp = b.get("clamp")
    if clamp is not None and clamp not in ("x0", "x1", "y0", "y1"):
        raise ConfigError(f"boundary.clamp: expected one of x0, x1, y0, y1, got {clamp!r}")
    cs = _number(b, "clamp_stiffness", "boundary.", required=False)
    cts = _number(b, "clamp_translational_stiffness", "boundary.", required=False)
    edges = b.get("edges", {})
    if not isinstance(edges, Mapping):
        raise ConfigError("boundary.edges: expected a table such as { y0 = 'free' }")
    springs = _springs(b, allow_per_length=True)
    general = _supports(b)
    points = {}
    for i, p in enumerate(s.get("points", [])):
        w = f"points[{i}]."
        if not isinstance(p, Mapping) or not isinstance(p.get("name"), str):
            raise ConfigError(f"points[{i}]: expected a table with name, x, y")
        _check_keys(p, f"points[{i}]", ("name", "x", "y"))
        points[p["name"]] = (_number(p, "x", w, positive=False), _number(p, "y", w,
                                                                          positive=False))
    meta = {"structure": s}
    if source is not None:
        meta["source"] = source
    try:
        model = plate_model(
            length, width, layers, patches=patches, nx=mesh.get("nx"), ny=mesh.get("ny"),
            element_size=esize, supports=dict(edges), clamp=clamp, clamp_stiffness=cs,
            clamp_translational_stiffness=cts, springs=springs, points=points,
            shear_correction=ks, name=str(s.get("name", "")), meta=meta,
        )
        model = _plate_piezo(model, s.get("patches", []), patches, len(layers))
        return _with_series(_with_masses(constrain_model(model, general, ()), s))
    except ConfigError:
        raise
    except MvtkError as err:
        raise ConfigError(f"structure description{' ' + source if source else ''}: {err}") \
            from err


def _base_section(st: Mapping, materials: Mapping) -> tuple[float, float, float, list[Ply]]:
    """Length, width (m), shear correction and base plies of the ``[structure]`` table."""
    length = _number(st, "length", "structure.")
    width = _number(st, "width", "structure.")
    ks = _number(st, "shear_correction", "structure.", required=False, default=5.0 / 6.0)
    unknown = set(st) - {"type", "length", "width", "layers", "shear_correction"}
    if unknown:
        raise ConfigError(f"structure: unknown keys {sorted(unknown)}; expected type, length, "
                          "width, layers, shear_correction")
    return length, width, ks, _plies(st.get("layers"), materials, "structure.layers")


_PLATE_BOUNDARY_KEYS = ("clamp", "clamp_stiffness", "clamp_translational_stiffness", "edges",
                        "springs", "supports")
_BEAM_BOUNDARY_KEYS = ("clamp", "clamp_stiffness", "clamp_translational_stiffness", "springs",
                       "supports")
_SPRING_KEYS = ("node_set", "dof", "k", "per_length")


def _check_keys(d: Mapping, where: str, accepted, inapplicable: Mapping[str, str] | None = None
                ) -> None:
    """ConfigError naming the first unknown key of ``d`` and the accepted ones."""
    for key in d:
        if key in accepted:
            continue
        why = (inapplicable or {}).get(key)
        if why:
            raise ConfigError(f"{where}.{key}: not applicable here ({why}); accepted keys: "
                              f"{', '.join(accepted)}")
        raise ConfigError(f"{where}: unknown key {key!r}; accepted keys: {', '.join(accepted)}")


def _springs(b: Mapping, allow_per_length: bool) -> list[SpringSupport]:
    """``boundary.springs`` entries."""
    raw = b.get("springs", [])
    if not isinstance(raw, list):
        raise ConfigError("boundary.springs: expected a list of tables ([[boundary.springs]])")
    out = []
    for i, sp_ in enumerate(raw):
        w = f"boundary.springs[{i}]"
        if not isinstance(sp_, Mapping):
            raise ConfigError(f"{w}: expected a table")
        _check_keys(sp_, w, _SPRING_KEYS if allow_per_length else _SPRING_KEYS[:3],
                    None if allow_per_length else
                    {"per_length": "a beam node is a point, not an edge"})
        for key in ("node_set", "dof"):
            if not isinstance(sp_.get(key), str):
                raise ConfigError(f"{w}.{key}: expected a string, got {sp_.get(key)!r}")
        if sp_["dof"] not in DOF_NAMES:
            raise ConfigError(f"{w}.dof: {sp_['dof']!r} is not a DOF name; expected one of "
                              f"{', '.join(DOF_NAMES)}")
        out.append(SpringSupport(sp_["node_set"], sp_["dof"],
                                 _number(sp_, "k", w + ".", positive=False),
                                 bool(sp_.get("per_length", False))))
    return out


def _supports(b: Mapping) -> dict[str, Any]:
    """``boundary.supports = { node_set = "type" or [DOF names] }``."""
    sup = b.get("supports", {})
    if not isinstance(sup, Mapping):
        raise ConfigError("boundary.supports: expected a table such as "
                          "{ x0 = 'pinned', x1 = ['uy', 'uz'] }")
    out = {}
    for k, v in sup.items():
        if isinstance(v, str):
            if v not in GENERAL_SUPPORTS:
                raise ConfigError(f"boundary.supports.{k}: unknown support type {v!r}; "
                                  f"expected one of {', '.join(sorted(GENERAL_SUPPORTS))} or "
                                  "a list of DOF names")
        elif isinstance(v, list) and all(x in DOF_NAMES for x in v):
            pass
        else:
            raise ConfigError(f"boundary.supports.{k}: expected a support type or a list of "
                              f"DOF names from {', '.join(DOF_NAMES)}, got {v!r}")
        out[str(k)] = v
    return out


def constrain_model(model: FEModel, supports: Mapping[str, Any],
                    springs: Sequence[SpringSupport]) -> FEModel:
    """Copy of ``model`` with further supports (fixed DOFs) and grounded springs.

    Parameters
    ----------
    model : FEModel
    supports : mapping of node-set name to a support type of
        :data:`mvtk.fe.GENERAL_SUPPORTS` or a list of DOF names
    springs : sequence of SpringSupport
        ``per_length`` is not used here (springs per node).

    Examples
    --------
    Propping the tip of the steel cantilever (uz fixed) turns it into a clamped-pinned
    beam: ``f1 = 3.9266**2 / (2 pi) sqrt(E I / (rho A L**4))`` = 81.4 Hz:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> propped = constrain_model(beam, {"tip": ["uz"]}, [])
    >>> propped.n_dof, np.round(modal_analysis(propped, 1).fn_hz, 1)
    (119, array([81.4]))
    >>> E, I, A = 2.1e11, 0.02 * 0.002**3 / 12, 0.02 * 0.002
    >>> round(3.92660231**2 / (2 * np.pi) * float(np.sqrt(E * I / (7850.0 * A * 0.3**4))), 1)
    81.4
    """
    if not supports and not springs:
        return model
    fixed = []
    for name, kind in supports.items():
        ns = model.node_set(name)
        try:
            fixed.append(support_dofs(model.nodes, ns, kind, f"support {name!r}",
                                      np.array([0.0, 0.0, 1.0])))
        except MvtkError as err:
            raise ConfigError(f"boundary.supports.{name}: {err}") from err
    key = model.dof_node * 6 + model.dof_component
    keep = ~np.isin(key, np.concatenate(fixed)) if fixed else np.ones(len(key), bool)
    sel = np.flatnonzero(keep)
    K = model.K[sel][:, sel].tocsr()
    M = model.M[sel][:, sel].tocsr()
    add = np.zeros(len(sel))
    lookup = {int(g): i for i, g in enumerate(key[sel])}
    for set_name, dof, k, _ in springs:
        for n in model.node_set(set_name):
            g = int(n) * 6 + DOF_NAMES.index(dof)
            if g not in lookup:
                raise ConfigError(f"boundary.springs: DOF {dof} of node {int(n)} (set "
                                  f"{set_name!r}) is constrained; a spring there does nothing")
            add[lookup[g]] += k
    if np.any(add):
        K = (K + sp.diags(add)).tocsr()
    meta = dict(model.meta)
    if meta.get("recovery") is not None:
        meta["recovery"] = meta["recovery"][:, sel]
    return replace(model, K=K, M=M, dof_node=model.dof_node[sel],
                   dof_component=model.dof_component[sel], meta=meta)


_SHAPES = {
    "rectangle": ("width", "height"),
    "tube": ("outer_radius", "inner_radius"),
    "i": ("height", "flange_width", "flange_thickness", "web_thickness"),
    "box": ("height", "width", "web_thickness", "flange_thickness"),
    "generic": ("A", "Iy", "Iz", "J"),
}


#: Keys of a ``[[masses]]`` table.
_MASS_KEYS = ("point", "mass", "inertia", "axes", "offset")


def _inertia(m: Mapping, where: str) -> np.ndarray:
    """The 3x3 rotary inertia (kg m^2, about the mass centre, global axes) of a mass.

    ``inertia`` is 3 values (the diagonal), 6 values ``[Jxx, Jyy, Jzz, Jxy, Jyz, Jxz]``
    (the tensor's entries, symmetric) or a 3x3 array; with ``axes`` (3 rows: the unit
    vectors of the body axes in global coordinates, orthonormal and right-handed) the
    tensor is given in the body axes and rotated to the global ones, ``J = R' J_b R``
    with ``R`` the rows of ``axes``.
    """
    v = m.get("inertia", [0.0, 0.0, 0.0])
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        a = np.zeros(0)
    if isinstance(v, bool) or a.shape not in ((3,), (6,), (3, 3)) or not np.isfinite(a).all():
        raise ConfigError(f"{where}inertia: expected 3 numbers (diagonal), 6 numbers [Jxx, "
                          f"Jyy, Jzz, Jxy, Jyz, Jxz] or a 3x3 array in kg m^2, got {v!r}")
    if a.shape == (3,):
        J = np.diag(a)
    elif a.shape == (6,):
        J = np.array([[a[0], a[3], a[5]], [a[3], a[1], a[4]], [a[5], a[4], a[2]]])
    else:
        J = a
    if not np.allclose(J, J.T, rtol=1e-9, atol=1e-12 * max(1.0, np.abs(J).max())):
        raise ConfigError(f"{where}inertia: the 3x3 tensor must be symmetric, got {v!r}")
    if np.linalg.eigvalsh(0.5 * (J + J.T)).min() < -1e-12 * max(np.abs(J).max(), 1e-300):
        raise ConfigError(f"{where}inertia: the tensor must be positive semi-definite "
                          f"(principal values {np.linalg.eigvalsh(J).round(12).tolist()})")
    if "axes" in m:
        try:
            R = np.asarray(m["axes"], dtype=float)
        except (TypeError, ValueError):
            R = np.zeros(0)
        if R.shape != (3, 3) or not np.isfinite(R).all():
            raise ConfigError(f"{where}axes: expected 3 rows of 3 numbers (the body axes "
                              f"in global coordinates), got {m['axes']!r}")
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-6) or np.linalg.det(R) < 0:
            raise ConfigError(f"{where}axes: the rows must be orthonormal unit vectors of a "
                              f"right-handed frame, got {m['axes']!r}")
        J = R.T @ J @ R
    return 0.5 * (J + J.T)


def _with_masses(model, s: Mapping):
    """``model`` with the ``[[masses]]`` of a generated plate or beam added to M.

    Each mass sits at a named point (``[[points]]``) or a one-node set of the model; its
    6x6 matrix (:class:`PointMass`: translation mass, rotary inertia, offset of the mass
    centre) is added on the node's free DOFs (a constrained DOF carries no inertia).
    """
    import dataclasses

    import scipy.sparse as sp

    from ._general import PointMass

    masses = s.get("masses", [])
    if not masses:
        return model
    if not isinstance(masses, list):
        raise ConfigError("masses: expected an array of tables [[masses]]")
    rows, cols, vals = [], [], []
    for i, m in enumerate(masses):
        w = f"masses[{i}]"
        if not isinstance(m, Mapping):
            raise ConfigError(f"{w}: expected a table")
        _check_keys(m, w, _MASS_KEYS)
        name = m.get("point")
        nodes = model.node_sets.get(name) if isinstance(name, str) else None
        if nodes is None or len(nodes) != 1:
            raise ConfigError(f"{w}.point: expected the name of a [[points]] entry or a "
                              f"one-node set, got {name!r}; points and sets: "
                              f"{sorted(k for k, v in model.node_sets.items() if len(v) == 1)}")
        node = int(nodes[0])
        try:
            mat = PointMass(node, _number(m, "mass", w + ".", positive=False),
                            _inertia(m, w + "."),
                            _vec(m, "offset", w + ".", [0.0, 0.0, 0.0])).matrix()
        except MvtkError as err:
            raise ConfigError(f"{w}: {err}") from err
        free = np.flatnonzero(model.dof_node == node)
        comp = model.dof_component[free]
        for a, ia in zip(comp, free):
            for b, ib in zip(comp, free):
                if mat[a, b] != 0.0:
                    rows.append(int(ia))
                    cols.append(int(ib))
                    vals.append(float(mat[a, b]))
    dM = sp.csr_matrix((vals, (rows, cols)), shape=model.M.shape)
    return dataclasses.replace(model, M=(model.M + dM).tocsr())


def _vec(d: Mapping, key: str, where: str, default):
    v = d.get(key, default)
    if (not isinstance(v, list | tuple) or len(v) != 3
            or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in v)):
        raise ConfigError(f"{where}{key}: expected 3 numbers [x, y, z], got {v!r}")
    return tuple(float(x) for x in v)


def _mesh_sections(s: Mapping, materials: Mapping, ks: float) -> dict:
    """``[sections.<name>]`` of an imported mesh: shell laminates or beam sections."""
    from . import _sections as secs
    from ._meshio import BeamProperty, ShellSection

    raw = s.get("sections")
    if not isinstance(raw, Mapping) or not raw:
        raise ConfigError("sections: an imported mesh needs [sections.<name>] tables "
                          "(shell: layers; beam: shape and material)")
    out = {}
    for name, d in raw.items():
        w = f"sections.{name}."
        if not isinstance(d, Mapping):
            raise ConfigError(f"sections.{name}: expected a table")
        if "layers" in d:
            _check_keys(d, f"sections.{name}", ("layers", "material_axis", "offset"))
            lam = Laminate(tuple(_plies(d["layers"], materials, w + "layers")),
                           shear_correction=ks)
            out[name] = ShellSection(lam, _vec(d, "material_axis", w, [1.0, 0.0, 0.0]),
                                     _number(d, "offset", w, positive=False, required=False,
                                             default=0.0))
            continue
        shape = d.get("shape")
        if shape not in _SHAPES:
            raise ConfigError(f"sections.{name}: expected layers (shell) or shape (beam: "
                              f"{', '.join(_SHAPES)}), got shape={shape!r}")
        dims = _SHAPES[shape]
        _check_keys(d, f"sections.{name}", ("shape", "material", "orientation", "offset",
                                             "shear_factor") + dims)
        mat = d.get("material")
        if mat not in materials:
            raise ConfigError(f"{w}material: {mat!r} is not defined; defined materials: "
                              f"{sorted(materials)}")
        vals = {k: _number(d, k, w, positive=(k != "inner_radius"),
                           required=(k != "inner_radius"), default=0.0) for k in dims}
        try:
            section = {"rectangle": secs.rectangle_section, "tube": secs.tube_section,
                       "i": secs.i_section, "box": secs.box_section,
                       "generic": secs.generic_section}[shape](materials[mat], **vals)
        except MvtkError as err:
            raise ConfigError(f"sections.{name}: {err}") from err
        if "shear_factor" in d:  # k of k G A, both bending planes
            sf = _number(d, "shear_factor", w)
            GA = materials[mat].G12 * section.EA / materials[mat].E1
            section = replace(section, kGAz=sf * GA, kGAy=sf * GA)
        out[name] = BeamProperty(section, _vec(d, "orientation", w, [0.0, 0.0, 1.0]),
                                 _vec(d, "offset", w, [0.0, 0.0, 0.0]))
    return out


def _build_mesh(s: dict, st: Mapping, materials: Mapping, source: str | None) -> FEModel:
    """The ``type = "mesh"`` branch of :func:`build_model` (imported mesh file)."""
    from ._general import PointMass, RigidLink, Spring
    from ._meshio import mesh_model, read_mesh

    _check_keys(st, "structure", ("type", "shear_correction"),
                {k: "the geometry comes from mesh.file" for k in ("length", "width",
                                                                   "layers")})
    ks = _number(st, "shear_correction", "structure.", required=False, default=5.0 / 6.0)
    mesh_d = s.get("mesh")
    if not isinstance(mesh_d, Mapping) or "file" not in mesh_d:
        raise ConfigError("mesh.file: an imported structure needs [mesh] file = 'part.msh'")
    path = Path(str(mesh_d["file"]))
    if not path.is_absolute() and source is not None:
        path = Path(source).parent / path
    if path.suffix.lower() in (".bdf", ".dat", ".nas"):
        return _build_nastran(s, mesh_d, path, source)
    _check_keys(mesh_d, "mesh", ("file", "sections"),
                {k: "the mesh comes from mesh.file" for k in ("nx", "ny", "element_size",
                                                              "n_elements")})
    sections = _mesh_sections(s, materials, ks)
    mapping = mesh_d.get("sections")
    if not isinstance(mapping, Mapping) or not mapping:
        raise ConfigError("mesh.sections: expected a table { <element set> = '<section>' }")
    for k, v in mapping.items():
        if v not in sections:
            raise ConfigError(f"mesh.sections.{k}: section {v!r} is not defined; defined "
                              f"sections: {sorted(sections)}")
    try:
        mesh = read_mesh(path)
    except MvtkError as err:
        raise ConfigError(f"mesh.file: {err}") from err
    from ._sanity import check_size

    check_size(len(mesh.nodes), sum(len(c) for c in mesh.cells.values()),
               f"mesh.file {path.name}")
    piezo_patches: list = []
    if "patches" in s:
        mesh, mapping, sections, piezo_patches = _mesh_patches(s, mesh, dict(mapping),
                                                               sections, materials)
    node_sets = dict(mesh.node_sets)
    for i, p in enumerate(s.get("points", [])):
        if not isinstance(p, Mapping) or not isinstance(p.get("name"), str):
            raise ConfigError(f"points[{i}]: expected a table with name, x, y, z")
        _check_keys(p, f"points[{i}]", ("name", "x", "y", "z"))
        xyz = np.array([_number(p, k, f"points[{i}].", positive=False) for k in "xyz"])
        if p["name"] in node_sets:
            raise ConfigError(f"points[{i}].name: {p['name']!r} is already a set of the mesh")
        node_sets[p["name"]] = np.array([int(np.argmin(np.linalg.norm(mesh.nodes - xyz,
                                                                      axis=1)))])

    def one_node(name: Any, where: str) -> int:
        if name not in node_sets or len(node_sets[name]) != 1:
            raise ConfigError(f"{where}: expected the name of a point or a one-node set, got "
                              f"{name!r}")
        return int(node_sets[name][0])

    members: list[Any] = []
    for i, m in enumerate(s.get("masses", [])):
        w = f"masses[{i}]"
        if not isinstance(m, Mapping):
            raise ConfigError(f"{w}: expected a table")
        _check_keys(m, w, (*_MASS_KEYS, "system"))
        node_ = one_node(m.get("point"), w + ".point")
        frame = None
        if "system" in m:
            if "axes" in m:
                raise ConfigError(f"{w}: give the body axes either as axes or as system, "
                                  "not both")
            systems_ = coordinate_systems(s)
            if m["system"] not in systems_:
                raise ConfigError(f"{w}.system: {m['system']!r} is not defined; defined: "
                                  f"{sorted(systems_)}")
            frame = systems_[m["system"]].axes_at(mesh.nodes[node_])
        try:
            members.append(PointMass(node_, _number(m, "mass", w + ".", positive=False),
                                     _inertia(m, w + "."),
                                     _vec(m, "offset", w + ".", [0.0, 0.0, 0.0]), frame))
            members[-1].matrix()
        except MvtkError as err:
            raise ConfigError(f"{w}: {err}") from err
    for i, r in enumerate(s.get("rigid_links", [])):
        w = f"rigid_links[{i}]"
        if not isinstance(r, Mapping):
            raise ConfigError(f"{w}: expected a table")
        _check_keys(r, w, ("independent", "nodes", "kind", "dofs"))
        if r.get("nodes") not in node_sets:
            raise ConfigError(f"{w}.nodes: expected a node set, got {r.get('nodes')!r}; "
                              f"available: {sorted(node_sets)}")
        ind = one_node(r.get("independent"), w + ".independent")
        dep = [n for n in node_sets[r["nodes"]] if n != ind]
        members.append(RigidLink(ind, dep, str(r.get("kind", "rbe2")),
                                 tuple(r.get("dofs", DOF_NAMES))))
    b = s.get("boundary", {})
    if not isinstance(b, Mapping):
        raise ConfigError("boundary: expected a table")
    _check_keys(b, "boundary", ("supports", "springs", "frames"),
                {k: "for the built-in plate/beam; use boundary.supports on a node set"
                 for k in ("clamp", "clamp_stiffness", "clamp_translational_stiffness",
                           "edges")})
    systems = coordinate_systems(s)
    frames = node_frames(b, systems, mesh.nodes, node_sets)
    for sp_ in _springs(b, allow_per_length=False):
        set_name, dof, kval, _ = sp_
        if set_name not in node_sets:
            raise ConfigError(f"boundary.springs: node set {set_name!r} not found; "
                              f"available: {sorted(node_sets)}")
        members += [Spring(int(n), {dof: kval}) for n in node_sets[set_name]]
    meta = {"structure": s}
    if piezo_patches:
        meta["piezo_patches"] = tuple(piezo_patches)
    if source is not None:
        meta["source"] = source
    try:
        model = _with_series(mesh_model(mesh, {k: sections[v] for k, v in mapping.items()},
                                        members=members, supports=_supports(b),
                                        node_sets=node_sets, name=str(s.get("name", "")),
                                        meta=meta, node_frames=frames or None))
    except MvtkError as err:
        raise ConfigError(f"structure description{' ' + source if source else ''}: {err}") \
            from err
    return _with_loads(s, model, systems)


def _with_loads(s: Mapping, model: FEModel, systems) -> FEModel:
    """The model with ``meta["load_cases"]`` from ``[[loads]]`` (when given)."""
    if "loads" not in s:
        return model
    cases = dict(model.meta.get("load_cases") or {})  # a deck's own load sets stay
    cases.update(load_cases(s, model, systems))
    return replace(model, meta=dict(model.meta, load_cases=cases))


def _build_nastran(s: dict, mesh_d: Mapping, path: Path, source: str | None) -> FEModel:
    """``[mesh] file = "deck.bdf"``: the whole model (sections included) from the deck."""
    from ._nastran import read_nastran

    _check_keys(mesh_d, "mesh", ("file", "spc_id"),
                {"sections": "a Nastran deck carries its own properties"})
    for key in ("sections", "masses", "rigid_links"):
        if key in s:
            raise ConfigError(f"{key}: not applicable to a Nastran deck (it carries its own "
                              "properties, CONM2 and RBE2 cards)")
    spc = mesh_d.get("spc_id")
    if spc is not None and (isinstance(spc, bool) or not isinstance(spc, int)):
        raise ConfigError(f"mesh.spc_id: expected an integer SPC1 set id, got {spc!r}")
    b = s.get("boundary", {})
    if not isinstance(b, Mapping):
        raise ConfigError("boundary: expected a table")
    _check_keys(b, "boundary", ("supports", "springs"),
                {"frames": "a Nastran deck gives node frames by GRID CD"})
    systems = coordinate_systems(s)
    try:
        model = read_nastran(path, spc_id=spc, name=str(s.get("name", "")))
    except MvtkError as err:
        raise ConfigError(f"mesh.file: {err}") from err
    sets = dict(model.node_sets)
    for i, p in enumerate(s.get("points", [])):
        if not isinstance(p, Mapping) or not isinstance(p.get("name"), str):
            raise ConfigError(f"points[{i}]: expected a table with name, x, y, z")
        _check_keys(p, f"points[{i}]", ("name", "x", "y", "z"))
        xyz = np.array([_number(p, k, f"points[{i}].", positive=False) for k in "xyz"])
        sets[p["name"]] = np.array([model.nearest_node(xyz)])
    meta = dict(model.meta, structure=s)
    if source is not None:
        meta["source"] = source
    model = replace(model, node_sets=sets, meta=meta)
    model = constrain_model(model, _supports(b), _springs(b, allow_per_length=False))
    return _with_loads(s, model, systems)


def _build_beam(s: dict, st: Mapping, materials: Mapping, source: str | None) -> FEModel:
    """The ``type = "beam"`` branch of :func:`build_model`."""
    from ._beam import BeamPatch, cantilever_beam

    length, width, ks, layers = _base_section(st, materials)
    patches = []
    for i, p in enumerate(s.get("patches", [])):
        w = f"patches[{i}]."
        if not isinstance(p, Mapping) or not isinstance(p.get("name"), str):
            raise ConfigError(f"patches[{i}]: expected a table with a name")
        _check_keys(p, f"patches[{i}]", ("name", "x0", "x1", "y0", "y1", "layers"))
        x0 = _number(p, "x0", w, positive=False)
        x1 = _number(p, "x1", w, positive=False)
        pw = None
        if "y0" in p or "y1" in p:
            pw = _number(p, "y1", w, positive=False) - _number(p, "y0", w, positive=False)
        plies = _plies(p.get("layers"), materials, w + "layers")
        try:
            patches.append(BeamPatch(p["name"], x0, x1, tuple(plies), width=pw))
        except MvtkError as err:
            raise ConfigError(f"patches[{i}]: {err}") from err
    mesh = s.get("mesh", {})
    if not isinstance(mesh, Mapping):
        raise ConfigError("mesh: expected a table")
    _check_keys(mesh, "mesh", ("n_elements", "nx", "element_size"),
                {"ny": "a beam has no elements across its width", "file": "an imported "
                 "mesh is a structure of its own: drop structure.type"})
    given = [k for k in ("n_elements", "nx", "element_size") if k in mesh]
    if len(given) > 1:
        raise ConfigError(f"mesh: give one of n_elements, nx or element_size, not {given} "
                          "(the others would be ignored)")
    if "element_size" in mesh:
        size = _number(mesh, "element_size", "mesh.")
        n_el = max(1, int(np.ceil(length / size - 1e-9)))
    else:
        n_el = mesh.get("n_elements", mesh.get("nx", 40))
    if isinstance(n_el, bool) or not isinstance(n_el, int) or n_el < 1:
        raise ConfigError(f"mesh.{given[0] if given else 'n_elements'}: expected a positive "
                          f"integer, got {n_el!r}")
    from ._sanity import check_size

    check_size(n_el + 1, n_el, f"mesh.{given[0] if given else 'n_elements'}", beam=True)
    b = s.get("boundary", {})
    if not isinstance(b, Mapping):
        raise ConfigError("boundary: expected a table")
    _check_keys(b, "boundary", _BEAM_BOUNDARY_KEYS,
                {"edges": "a beam has no edges; use boundary.supports = { x0 = 'pinned' }"})
    clamp = b.get("clamp", "x0")
    if clamp not in ("x0", "x1", "free"):
        raise ConfigError(f"boundary.clamp: expected x0, x1 or free for a beam, got {clamp!r}")
    cs = _number(b, "clamp_stiffness", "boundary.", required=False)
    cts = _number(b, "clamp_translational_stiffness", "boundary.", required=False)
    springs = _springs(b, allow_per_length=False)
    general = _supports(b)
    points = {}
    for i, p in enumerate(s.get("points", [])):
        if not isinstance(p, Mapping) or not isinstance(p.get("name"), str):
            raise ConfigError(f"points[{i}]: expected a table with name and x")
        _check_keys(p, f"points[{i}]", ("name", "x", "y"))
        if "y" in p:
            y = _number(p, "y", f"points[{i}].", positive=False)
            if not 0 <= y <= width:
                raise ConfigError(f"points[{i}].y: {y} m is outside the beam width 0..{width}")
        points[p["name"]] = _number(p, "x", f"points[{i}].", positive=False)
    meta = {"structure": s}
    if source is not None:
        meta["source"] = source
    try:
        model = cantilever_beam(
            length, width, layers, n_elements=n_el, patches=patches,
            clamp=None if clamp == "free" else clamp,
            clamp_stiffness=None if cs is None else cs * width,
            clamp_translational_stiffness=None if cts is None else cts * width,
            points=points, shear_correction=ks, name=str(s.get("name", "")), meta=meta,
        )
        return _with_masses(constrain_model(model, general, springs), s)
    except ConfigError:
        raise
    except MvtkError as err:
        raise ConfigError(f"structure description{' ' + source if source else ''}: {err}") \
            from err


_MESH_PATCH_KEYS = ("name", "element_set", "region", "layers", "side", "electrodes")
_REGION_KEYS = ("shape", "origin", "axis", "normal", "u", "v", "radius", "points")


def _electrodes(p: Mapping, where: str, name: str, patch_plies, stack_index):
    """``patches[i].electrodes``: Electrode objects (ply indices into the whole stack)."""
    from ._electro import Electrode
    from ._materials import is_piezo

    raw = p.get("electrodes")
    if raw is None:
        return None
    if not isinstance(raw, list) or not raw:
        raise ConfigError(f"{where}electrodes: expected a list of tables "
                          "[{ name = 'a', plies = [1], signs = [1] }]")
    out = []
    for j, e in enumerate(raw):
        w = f"{where}electrodes[{j}]"
        if not isinstance(e, Mapping):
            raise ConfigError(f"{w}: expected a table with name and plies")
        _check_keys(e, w, ("name", "plies", "signs", "wiring"))
        if e.get("wiring", "parallel") not in ("parallel", "series"):
            raise ConfigError(f"{w}.wiring: expected 'parallel' or 'series', got "
                              f"{e.get('wiring')!r}")
        plies = e.get("plies")
        if not isinstance(plies, list) or not plies:
            raise ConfigError(f"{w}.plies: the electrode is wired to no ply; expected a "
                              "non-empty list of indices into the patch's layers")
        for k in plies:
            if isinstance(k, bool) or not isinstance(k, int) or not 0 <= k < len(patch_plies):
                raise ConfigError(f"{w}.plies: {k!r} is not a layer index of the patch "
                                  f"(0..{len(patch_plies) - 1}, from the base outwards)")
            if not is_piezo(patch_plies[k].material):
                raise ConfigError(f"{w}.plies: layer {k} of material "
                                  f"{patch_plies[k].material.name!r} has no d31")
        signs = e.get("signs")
        if signs is not None and (not isinstance(signs, list) or len(signs) != len(plies)
                                  or any(x not in (1, -1) for x in signs)):
            raise ConfigError(f"{w}.signs: expected {len(plies)} values of +1 or -1, "
                              f"got {signs!r}")
        ename = e.get("name", name if len(raw) == 1 else f"{name}:{j}")
        if not isinstance(ename, str) or not ename:
            raise ConfigError(f"{w}.name: expected a non-empty string, got {ename!r}")
        try:
            out.append(Electrode(ename, tuple(stack_index[k] for k in plies),
                                 None if signs is None else tuple(signs),
                                 e.get("wiring", "parallel")))
        except MvtkError as err:
            raise ConfigError(f"{w}: {err}") from err
    return tuple(out)


def _mesh_patches(s: Mapping, mesh, mapping: dict, sections: dict, materials: Mapping):
    """``[[patches]]`` on an imported mesh: each patch's cells (an element set or a
    region) get the base section plus the patch layers; piezo plies become electrodes.

    Returns the mesh with the patch cells moved to element sets ``patch:<name>``, the
    updated set-to-section mapping and sections, and the ShellPiezoPatch list.
    """
    from dataclasses import replace as _replace

    from ._electro import Electrode, ShellPiezoPatch, select_region, stacked_laminate
    from ._materials import is_piezo
    from ._meshio import ShellSection

    raw = s.get("patches")
    if not isinstance(raw, list):
        raise ConfigError("patches: expected a list of tables ([[patches]])")
    esets = {k: dict(v) for k, v in mesh.element_sets.items()}
    owner: dict[tuple[str, int], str] = {}
    out: list = []
    for set_name in mapping:
        for kind, idx in esets.get(set_name, {}).items():
            for c in idx:
                owner[(kind, int(c))] = set_name
    node_sets = dict(mesh.node_sets)
    groups: dict[tuple, dict] = {}   # cells -> {"top": i, "bottom": i}
    cell_group: dict[tuple[str, int], tuple] = {}
    items = []
    for i, p in enumerate(raw):
        w = f"patches[{i}]."
        if not isinstance(p, Mapping):
            raise ConfigError(f"patches[{i}]: expected a table")
        _check_keys(p, f"patches[{i}]", _MESH_PATCH_KEYS,
                    {k: "x0/x1/y0/y1 are for the generated plate; on a mesh give "
                     "element_set or region" for k in ("x0", "x1", "y0", "y1")})
        name = p.get("name")
        if not isinstance(name, str) or not name:
            raise ConfigError(f"{w}name: expected a non-empty string, got {name!r}")
        if any(name == it[1] for it in items):
            raise ConfigError(f"{w}name: {name!r} used twice")
        if ("element_set" in p) == ("region" in p):
            raise ConfigError(f"patches[{i}]: give one of element_set or region")
        if "element_set" in p:
            es = p["element_set"]
            if es not in mesh.element_sets:
                raise ConfigError(f"{w}element_set: {es!r} is not an element set of the "
                                  f"mesh; available: {sorted(mesh.element_sets)}")
            sel = {k: v for k, v in mesh.element_sets[es].items() if k in ("tri3", "quad4")}
            if not sel:
                raise ConfigError(f"{w}element_set: {es!r} has no shell cells")
        else:
            reg = p["region"]
            if not isinstance(reg, Mapping):
                raise ConfigError(f"{w}region: expected a table such as {{ shape = 'circle', "
                                  "origin = [x, y, z], radius = 0.02 }")
            _check_keys(reg, f"patches[{i}].region", _REGION_KEYS)
            try:
                sel = select_region(mesh.nodes, {k: v for k, v in mesh.cells.items()
                                                 if k in ("tri3", "quad4")},
                                    where=f"patches[{i}].region", **dict(reg))
            except MvtkError as err:
                raise ConfigError(str(err)) from err
            except (TypeError, ValueError) as err:
                raise ConfigError(f"{w}region: {err}") from err
        cells = tuple(sorted((k, int(c)) for k, idx in sel.items() for c in idx))
        bases = {owner.get(c) for c in cells}
        if None in bases or len(bases) != 1:
            raise ConfigError(f"{w[:-1]}: its elements must lie on one mapped shell set, "
                              f"found {sorted(map(str, bases))}")
        base_set = bases.pop()
        if not isinstance(sections[mapping[base_set]], ShellSection):
            raise ConfigError(f"{w[:-1]}: element set {base_set!r} is not a shell")
        side = p.get("side", "top")
        if side not in ("top", "bottom"):
            raise ConfigError(f"{w}side: expected 'top' or 'bottom', got {side!r}")
        for c in cells:
            other = cell_group.get(c)
            if other is not None and other != cells:
                raise ConfigError(f"{w[:-1]}: partly overlaps patch "
                                  f"{raw[next(iter(groups[other].values()))]['name']!r}; "
                                  "patches share all of their elements or none")
            cell_group[c] = cells
        g = groups.setdefault(cells, {})
        if side in g:
            raise ConfigError(f"{w[:-1]}: patch {raw[g[side]]['name']!r} already covers "
                              f"the {side} side of these elements")
        g[side] = i
        plies = _plies(p.get("layers"), materials, w + "layers")
        items.append((i, name, sel, base_set, side, plies))
    for g in groups.values():
        first = items[min(g.values())]
        sel, base_set = first[2], first[3]
        base_sec = sections[mapping[base_set]]
        top = items[g["top"]][5] if "top" in g else ()
        bottom = items[g["bottom"]][5] if "bottom" in g else ()
        lam, i_top, i_bot = stacked_laminate(base_sec.laminate, base_sec.offset, top, bottom)
        pname = "patch:" + "+".join(items[j][1] for j in sorted(g.values()))
        for k, idx in sel.items():
            esets[base_set][k] = np.setdiff1d(esets[base_set][k], idx)
            if not len(esets[base_set][k]):
                del esets[base_set][k]
        if not any(k in esets[base_set] for k in ("tri3", "quad4", "line2")):
            del mapping[base_set]
        esets[pname] = {k: np.asarray(v) for k, v in sel.items()}
        sections[pname] = ShellSection(lam, base_sec.material_axis, 0.0)
        mapping[pname] = pname
        nodes_ = np.unique(np.concatenate([mesh.cells[k][v].ravel() for k, v in sel.items()]))
        for side, j in g.items():
            i, name, _, _, _, plies = items[j]
            node_sets[f"patch:{name}"] = nodes_
            index = i_top if side == "top" else i_bot
            w = f"patches[{i}]."
            electrodes = _electrodes(raw[i], w, name, plies, index)
            piezo = [index[k] for k, q in enumerate(plies) if is_piezo(q.material)]
            if electrodes is None and piezo:
                electrodes = tuple(Electrode(name if len(piezo) == 1 else f"{name}:{k}",
                                             (s_,)) for k, s_ in enumerate(piezo))
            if electrodes is None:
                continue
            try:
                out.append(ShellPiezoPatch(name, tuple(mesh.cells[k][v] for k, v in
                                                       sorted(sel.items())),
                                           lam, base_sec.material_axis, electrodes))
            except MvtkError as err:
                raise ConfigError(f"patches[{i}]: {err}") from err
    out.sort(key=lambda pp: [it[1] for it in items].index(pp.name))
    return (_replace(mesh, element_sets=esets, node_sets=node_sets), mapping, sections, out)


def _plate_piezo(model: FEModel, raw: list, patches: list, n_base: int) -> FEModel:
    """``meta["piezo_patches"]`` of a generated plate: the piezo plies of each patch (its
    elements are the plate's region ``i + 1``, its section base + patch plies)."""
    from ._electro import Electrode, ShellPiezoPatch
    from ._materials import is_piezo

    out = []
    region = np.asarray(model.meta["element_region"])
    for i, ((patch, plies), p) in enumerate(zip(patches, raw)):
        index = [n_base + k for k in range(len(plies))]
        electrodes = _electrodes(p, f"patches[{i}].", patch.name, plies, index)
        piezo = [index[k] for k, q in enumerate(plies) if is_piezo(q.material)]
        if electrodes is None and piezo:
            electrodes = tuple(Electrode(patch.name if len(piezo) == 1 else
                                         f"{patch.name}:{k}", (j,))
                               for k, j in enumerate(piezo))
        if electrodes is None:
            continue
        try:
            out.append(ShellPiezoPatch(patch.name, model.elements["mitc4"][region == i + 1],
                                       model.meta["laminates"][i + 1], (1.0, 0.0, 0.0),
                                       electrodes))
        except MvtkError as err:
            raise ConfigError(f"patches[{i}]: {err}") from err
    if not out:
        return model
    return replace(model, meta=dict(model.meta, piezo_patches=tuple(out)))


def _with_series(model: FEModel) -> FEModel:
    """Add the stiffening of series-wired electrodes' floating internal electrodes."""
    from ._electro import series_stiffness

    if not model.meta.get("piezo_patches"):
        return model
    try:
        dK = series_stiffness(model)
    except MvtkError as err:
        raise ConfigError(f"patches: {err}") from err
    if dK is None:
        return model
    return replace(model, K=(model.K + dK).tocsr())
