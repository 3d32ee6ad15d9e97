"""Coordinate systems, node frames and load cases of structure descriptions.

Used by :func:`mvtk.fe.build_model` for ``structure.type = "mesh"`` (imported meshes and
Nastran decks)::

    [coordinate_systems.ring]            # rectangular | cylindrical | spherical
    type = "cylindrical"
    origin = [0, 0, 0]                   # m
    z_axis = [0, 0, 1]                   # direction of the z (cylinder) axis
    x_axis = [1, 0, 0]                   # a direction in the x-z plane (theta = 0)

    [boundary]
    frames = { rim = "ring" }            # DOFs of these nodes in the system's local
    supports = { rim = ["ux"] }          # axes: here ux is radial (a radial support)

    [[loads]]                            # load cases, summed per case name
    case = "self weight"                 # optional, default "load"
    type = "gravity"                     # gravity | pressure | force | line
    acceleration = [0, 0, -9.81]         # m/s^2

    [[loads]]
    type = "pressure"
    pressure = 2e3                       # Pa along the shell normal
    element_set = "skin:quad4"           # optional: one shell set (default all shells)

    [[loads]]
    type = "force"                       # on every node of the set
    node_set = "tip"
    force = [0, 0, -10]                  # N (optional)
    moment = [0, 0, 0]                   # N m (optional)
    system = "ring"                      # optional: components in the local axes

    [[loads]]
    type = "line"                        # N/m along the edges of the set
    node_set = "free_edge"
    force = [0, 0, -50]

The load cases are stored as global nodal forces ``(n_nodes, 6)`` in
``model.meta["load_cases"]``; :func:`load_vector` maps one to the free DOFs.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import ConfigError, MvtkError
from ._frames import CoordinateSystem
from ._general import BeamSet, ShellSet
from ._loads import gravity_nodal, nodal_load, pressure_nodal
from ._model import FEModel

__all__ = ["coordinate_systems", "node_frames", "load_cases", "load_vector"]

_LOAD_KEYS = {
    "gravity": ("acceleration",),
    "pressure": ("pressure", "element_set"),
    "force": ("node_set", "force", "moment", "system"),
    "line": ("node_set", "force"),
}


def _vec(d: Mapping, key: str, where: str, default=None) -> np.ndarray:
    v = d.get(key, default)
    if (not isinstance(v, list | tuple) or len(v) != 3
            or not all(isinstance(x, int | float) and not isinstance(x, bool) for x in v)
            or not np.all(np.isfinite(np.asarray(v, float)))):
        raise ConfigError(f"{where}.{key}: expected 3 finite numbers [x, y, z], got {v!r}")
    return np.asarray(v, dtype=float)


def coordinate_systems(s: Mapping) -> dict[str, CoordinateSystem]:
    """``[coordinate_systems.<name>]`` tables."""
    raw = s.get("coordinate_systems", {})
    if not isinstance(raw, Mapping):
        raise ConfigError("coordinate_systems: expected tables [coordinate_systems.<name>]")
    out = {}
    for name, d in raw.items():
        w = f"coordinate_systems.{name}"
        if not isinstance(d, Mapping):
            raise ConfigError(f"{w}: expected a table")
        unknown = set(d) - {"type", "origin", "z_axis", "x_axis"}
        if unknown:
            raise ConfigError(f"{w}: unknown keys {sorted(unknown)}; accepted: type, origin, "
                              "z_axis, x_axis")
        o = _vec(d, "origin", w, [0.0, 0.0, 0.0])
        z = _vec(d, "z_axis", w, [0.0, 0.0, 1.0])
        x = _vec(d, "x_axis", w, [1.0, 0.0, 0.0])
        try:
            out[str(name)] = CoordinateSystem.from_points(str(d.get("type", "rectangular")),
                                                          o, o + z, o + x)
        except MvtkError as err:
            raise ConfigError(f"{w}: {err} (z_axis and x_axis must not be parallel; type "
                              "rectangular, cylindrical or spherical)") from err
    return out


def node_frames(b: Mapping, systems: Mapping[str, CoordinateSystem], nodes: np.ndarray,
                node_sets: Mapping[str, np.ndarray]) -> dict[int, np.ndarray]:
    """``boundary.frames = { <node set> = "<system>" }``: node index -> local axes."""
    raw = b.get("frames", {})
    if not isinstance(raw, Mapping):
        raise ConfigError("boundary.frames: expected a table { <node set> = '<system>' }")
    out: dict[int, np.ndarray] = {}
    for set_name, sys_name in raw.items():
        w = f"boundary.frames.{set_name}"
        if set_name not in node_sets:
            raise ConfigError(f"{w}: node set {set_name!r} not found; available: "
                              f"{sorted(node_sets)}")
        if sys_name not in systems:
            raise ConfigError(f"{w}: coordinate system {sys_name!r} is not defined; "
                              f"defined: {sorted(systems)}")
        for n in node_sets[set_name]:
            R = systems[sys_name].axes_at(nodes[int(n)])
            if int(n) in out and not np.allclose(out[int(n)], R):
                raise ConfigError(f"{w}: node {int(n)} already has another frame")
            out[int(n)] = R
    return out


def _line_lengths(model: FEModel, nodes: np.ndarray, where: str) -> np.ndarray:
    """Half the length of every element edge with both ends in ``nodes``, per node."""
    inset = np.zeros(model.n_nodes, dtype=bool)
    inset[nodes] = True
    edges, quad_edges = [], []
    for m in model.meta.get("members", ()):
        if isinstance(m, ShellSet) and m.elements.shape[1] == 9:  # corner, mid, corner
            el = m.elements
            quad_edges += [el[:, [j, 4 + j, (j + 1) % 4]] for j in range(4)]
        elif isinstance(m, ShellSet):
            el = m.elements
            k = el.shape[1]
            edges += [el[:, [j, (j + 1) % k]] for j in range(k)]
        elif isinstance(m, BeamSet):
            edges.append(m.elements)
    if not edges and not quad_edges:
        raise ConfigError(f"{where}: the model has no element edges")
    out = np.zeros(model.n_nodes)
    found = False
    if edges:
        e = np.sort(np.concatenate(edges), axis=1)
        e = np.unique(e[inset[e[:, 0]] & inset[e[:, 1]]], axis=0)
        length = np.linalg.norm(model.nodes[e[:, 1]] - model.nodes[e[:, 0]], axis=1)
        np.add.at(out, e[:, 0], length / 2)
        np.add.at(out, e[:, 1], length / 2)
        found = len(e) > 0
    if quad_edges:  # consistent for a quadratic edge: L/6, 4 L/6, L/6
        q = np.concatenate(quad_edges)
        q = q[inset[q].all(axis=1)]
        q[:, [0, 2]] = np.sort(q[:, [0, 2]], axis=1)
        q = np.unique(q, axis=0)
        x = model.nodes
        length = (np.linalg.norm(x[q[:, 1]] - x[q[:, 0]], axis=1)
                  + np.linalg.norm(x[q[:, 2]] - x[q[:, 1]], axis=1))
        for j, share in enumerate((1 / 6, 4 / 6, 1 / 6)):
            np.add.at(out, q[:, j], share * length)
        found = found or len(q) > 0
    if not found:
        raise ConfigError(f"{where}: no element edge joins two nodes of the set")
    return out


def load_cases(s: Mapping, model: FEModel, systems: Mapping[str, CoordinateSystem]
               ) -> dict[str, np.ndarray]:
    """``[[loads]]`` entries summed per ``case``: global nodal forces (n_nodes, 6)."""
    raw = s.get("loads", [])
    if not isinstance(raw, list):
        raise ConfigError("loads: expected a list of tables ([[loads]])")
    out: dict[str, np.ndarray] = {}
    for i, d in enumerate(raw):
        w = f"loads[{i}]"
        if not isinstance(d, Mapping):
            raise ConfigError(f"{w}: expected a table")
        kind = d.get("type")
        if kind not in _LOAD_KEYS:
            raise ConfigError(f"{w}.type: expected one of {', '.join(_LOAD_KEYS)}, got "
                              f"{kind!r}")
        accepted = ("type", "case") + _LOAD_KEYS[kind]
        unknown = set(d) - set(accepted)
        if unknown:
            raise ConfigError(f"{w}: unknown keys {sorted(unknown)} for type {kind!r}; "
                              f"accepted: {', '.join(accepted)}")
        case = str(d.get("case", "load"))
        f = np.zeros((model.n_nodes, 6))
        try:
            if kind == "gravity":
                f = gravity_nodal(model, _vec(d, "acceleration", w))
            elif kind == "pressure":
                p = d.get("pressure")
                if isinstance(p, bool) or not isinstance(p, int | float):
                    raise ConfigError(f"{w}.pressure: expected a number (Pa), got {p!r}")
                es = d.get("element_set")
                f = pressure_nodal(model, float(p), None if es is None else str(es))
            else:
                ns = d.get("node_set")
                if ns not in model.node_sets:
                    raise ConfigError(f"{w}.node_set: {ns!r} not found; available: "
                                      f"{sorted(model.node_sets)}")
                nodes = model.node_sets[ns]
                if kind == "line":
                    q = _vec(d, "force", w)
                    f[:, :3] = _line_lengths(model, nodes, w)[:, None] * q[None, :]
                else:
                    if "force" not in d and "moment" not in d:
                        raise ConfigError(f"{w}: give force and/or moment")
                    F = _vec(d, "force", w, [0.0, 0.0, 0.0])
                    Mo = _vec(d, "moment", w, [0.0, 0.0, 0.0])
                    sysn = d.get("system")
                    if sysn is not None and sysn not in systems:
                        raise ConfigError(f"{w}.system: {sysn!r} is not defined; defined: "
                                          f"{sorted(systems)}")
                    for n in nodes:
                        R = np.eye(3) if sysn is None else systems[sysn].axes_at(
                            model.nodes[n])
                        f[n, :3] += R.T @ F
                        f[n, 3:] += R.T @ Mo
        except ConfigError:
            raise
        except MvtkError as err:
            raise ConfigError(f"{w}: {err}") from err
        out[case] = out.get(case, np.zeros((model.n_nodes, 6))) + f
    return out


def load_vector(model: FEModel, case: str = "load") -> np.ndarray:
    """Free-DOF load vector (N, N m) of a load case of a structure description.

    Parameters
    ----------
    model : FEModel
        Built by :func:`mvtk.fe.build_model` from a description with ``[[loads]]``.
    case : str
        Load case name (``case`` of the ``[[loads]]`` entries, default ``"load"``).

    Returns
    -------
    ndarray (n_dof,)

    Examples
    --------
    Load set 7 of a Nastran deck: 1 N along z on the free end of the 2-mass chain
    (springs of 1e5 N/m); statically the masses move ``F / k`` and ``2 F / k``:

    >>> import pathlib, tempfile
    >>> from mvtk.fe import read_nastran, static_solve
    >>> deck = pathlib.Path(tempfile.mkdtemp()) / "chain.bdf"
    >>> _ = deck.write_text("BEGIN BULK\\n"
    ...                     "GRID,1,,0.,0.,0.\\nGRID,2,,0.1,0.,0.\\nGRID,3,,0.2,0.,0.\\n"
    ...                     "CONM2,10,2,,1.0\\nCONM2,11,3,,1.0\\n"
    ...                     "CELAS2,20,1.0e5,1,3,2,3\\nCELAS2,21,1.0e5,2,3,3,3\\n"
    ...                     "SPC1,1,123456,1\\nSPC1,1,12456,2,3\\n"
    ...                     "FORCE,7,3,,1.0,0.,0.,1.\\nENDDATA\\n")
    >>> model = read_nastran(deck)
    >>> f = load_vector(model, "7")
    >>> f, static_solve(model, f) * 1e5          # N; m x 1e5
    (array([0., 1.]), array([1., 2.]))
    """
    cases: dict[str, Any] = model.meta.get("load_cases") or {}
    if case not in cases:
        raise ConfigError(f"model {model.name!r} has no load case {case!r}; load cases: "
                          f"{sorted(cases)}")
    return nodal_load(model, cases[case])
