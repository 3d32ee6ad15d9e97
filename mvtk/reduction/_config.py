"""The ``[reduction]`` section of a study TOML -> a :class:`SuperElement`.

Schema (all keys optional except ``retained``)::

    [reduction]
    n_modes = 10          # fixed-interface modes (0 = Guyan); or one of:
    # mass_fraction = 0.95  (with direction = "uz")
    # f_cut_hz = 500.0
    n_compare = 4         # modes in the FE-vs-SE table
    retained = ["tip", "x0"]           # node set names, and/or tables:

    [[reduction.retained]]
    name = "clamp"                     # label in reports
    xyz = [0.0, 0.0665, 0.0]           # nearest node to this point (m) ...
    # node_set = "tip"                 # ... or a node set of the model

A retained node whose DOFs are all constrained (a clamp node) adds no coordinate but
counts in the size table (paper Table 4).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError, MvtkError
from ..fe import FEModel
from ._craig_bampton import SuperElement, craig_bampton

__all__ = ["RetainedPoint", "resolve_retained_config", "super_element_from_config",
           "snap_point", "local_element_size"]

_KEYS = {"n_modes", "mass_fraction", "f_cut_hz", "direction", "n_compare", "retained",
         "plant_modes"}


@dataclass(frozen=True)
class RetainedPoint:
    """One retained item of the configuration, resolved to model nodes.

    Attributes
    ----------
    name : str
    nodes : tuple of int
    n_free_dofs : int
    snap_distance_m : float
        Distance (m) from a configured point ``xyz`` to the node retained for it (0 for
        node sets and node indices).

    Examples
    --------
    Returned by :func:`resolve_retained_config`:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> resolve_retained_config(beam, ["tip"])[0]
    RetainedPoint(name='tip', nodes=(20,), n_free_dofs=6, snap_distance_m=0.0)
    """

    name: str
    nodes: tuple[int, ...]
    n_free_dofs: int
    snap_distance_m: float = 0.0


def local_element_size(model: FEModel, node: int) -> float:
    """Longest edge (m) of the elements around ``node`` (the local mesh size).

    Falls back to the distance to the nearest other node when the model lists no
    element connectivity (:func:`mvtk.fe._sanity.local_element_size`, which also bounds
    the points of an imported mesh).

    Examples
    --------
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> round(local_element_size(beam, 5), 6)      # m: 0.3 m / 20 elements
    0.015
    """
    from ..fe._sanity import local_element_size as size

    return size(model, node)


def snap_point(model: FEModel, xyz, where: str, tolerance: float | None = None):
    """The node retained for a point: ``(node, distance_m)``.

    The nearest node is taken when it lies within ``tolerance`` of the point (default:
    the local element size, :func:`local_element_size`; a point on the meshed structure
    is never farther than that from a node).

    Raises
    ------
    ConfigError
        The point is farther than the tolerance from every node (off the structure).

    Examples
    --------
    A point 1 mm from node 10 of a cantilever meshed at 15 mm:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> node, dist = snap_point(beam, [0.151, 0.0, 0.0], "retained")
    >>> node, round(dist * 1e3, 6)          # mm
    (10, 1.0)
    """
    p = np.asarray(xyz, dtype=float)
    node = model.nearest_node(p)
    dist = float(np.linalg.norm(model.nodes[node] - p))
    tol = local_element_size(model, node) if tolerance is None else float(tolerance)
    if not np.isfinite(dist) or dist > tol * (1 + 1e-9):
        lo, hi = model.nodes.min(axis=0), model.nodes.max(axis=0)
        raise ConfigError(
            f"{where}: point {p.tolist()} m is {dist:.4g} m from the nearest node "
            f"n{node} at {model.nodes[node].tolist()}, beyond the snap tolerance "
            f"{tol:.4g} m (the local element size): the point is off the structure "
            f"(its nodes span {lo.tolist()} to {hi.tolist()} m)"
        )
    return node, dist


def resolve_retained_config(model: FEModel, retained, where: str = "reduction.retained"):
    """Resolve ``retained`` config items to :class:`RetainedPoint` s.

    Items are node set names (str), points ``[x, y, z]`` (m), or tables with ``name``
    and one of ``xyz`` / ``node_set`` / ``node``. A point is snapped to its nearest node
    (the distance is kept in ``snap_distance_m``) and refused beyond the local element
    size (:func:`snap_point`).

    Raises
    ------
    ConfigError
        Naming the item (``reduction.retained[i]``) and what was expected; a point off
        the structure; two items that resolve to the same node.

    Examples
    --------
    A node set and a point (m) snapped to its nearest node:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> [(p.name, p.nodes) for p in resolve_retained_config(beam, ["tip", [0.15, 0.0, 0.0]])]
    [('tip', (20,)), ('n10', (10,))]
    """
    if isinstance(retained, str) or not isinstance(retained, list | tuple) or not retained:
        raise ConfigError(
            f"{where}: expected a non-empty list of node set names, points [x, y, z] or "
            f"tables with name and xyz/node_set/node, got {retained!r}"
        )
    out = []
    owner: dict[int, str] = {}
    for i, item in enumerate(retained):
        w = f"{where}[{i}]"
        name = None
        snap = 0.0
        if isinstance(item, Mapping):
            unknown = set(item) - {"name", "xyz", "node_set", "node"}
            given = [k for k in ("xyz", "node_set", "node") if k in item]
            if unknown or len(given) != 1:
                raise ConfigError(
                    f"{w}: expected a table with 'name' and exactly one of 'xyz', "
                    f"'node_set', 'node'; got keys {sorted(item)}"
                )
            name = item.get("name")
            spec = item[given[0]]
            kind = given[0]
        elif isinstance(item, str):
            spec, kind = item, "node_set"
        else:
            spec, kind = item, "xyz"
        try:
            if kind == "node_set":
                nodes = model.node_set(str(spec))
            elif kind == "node":
                if isinstance(spec, bool) or not isinstance(spec, int):
                    raise ConfigError(f"{w}.node: expected an integer node index, got {spec!r}")
                if not 0 <= spec < model.n_nodes:
                    raise ConfigError(
                        f"{w}.node: node {spec} does not exist (model has {model.n_nodes})"
                    )
                nodes = np.array([spec])
            else:
                arr = np.asarray(spec)
                if arr.shape != (3,) or not np.issubdtype(arr.dtype, np.number):
                    raise ConfigError(
                        f"{w}: expected a point [x, y, z] in m, got {spec!r}"
                    )
                node, snap = snap_point(model, arr.astype(float), w)
                nodes = np.array([node])
        except ConfigError:
            raise
        except MvtkError as err:
            raise ConfigError(f"{w}: {err}") from err
        nodes = tuple(dict.fromkeys(int(n) for n in nodes))
        label = str(name) if name is not None else (
            str(spec) if kind == "node_set" else f"n{nodes[0]}"
        )
        for n in nodes:
            if n in owner:
                raise ConfigError(
                    f"{w} ({label!r}) and {owner[n]} resolve to the same node n{n} at "
                    f"{model.nodes[n].tolist()} m: retained items would merge; move the "
                    "points apart by more than the element size or refine the mesh"
                )
            owner[n] = f"{w} ({label!r})"
        out.append(RetainedPoint(label, nodes, int(model.node_dofs(list(nodes)).size), snap))
    return out


def super_element_from_config(
    model: FEModel, cfg: Mapping, where: str = "reduction"
) -> tuple[SuperElement, list[RetainedPoint]]:
    """Build the super element described by a ``[reduction]`` table.

    Returns
    -------
    se : SuperElement
    retained : list of RetainedPoint
        The resolved retained items (for reports).

    Raises
    ------
    ConfigError
        Unknown keys, bad values, unknown node sets.

    Examples
    --------
    The ``[reduction]`` table of a study as a mapping:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> se, points = super_element_from_config(beam, {"retained": ["tip"], "n_modes": 4})
    >>> se.K.shape, [(p.name, p.nodes) for p in points]
    ((10, 10), [('tip', (20,))])
    """
    if not isinstance(cfg, Mapping):
        raise ConfigError(f"{where}: expected a table, got {type(cfg).__name__}")
    unknown = set(cfg) - _KEYS
    if unknown:
        raise ConfigError(f"{where}: unknown keys {sorted(unknown)}; expected {sorted(_KEYS)}")
    if "retained" not in cfg:
        raise ConfigError(f"{where}: missing key 'retained'")
    points = resolve_retained_config(model, cfg["retained"], f"{where}.retained")
    kwargs = {}
    for key, typ in (("n_modes", int), ("mass_fraction", float), ("f_cut_hz", float)):
        if cfg.get(key) is not None:
            v = cfg[key]
            ok = isinstance(v, int) if typ is int else isinstance(v, int | float)
            if isinstance(v, bool) or not ok:
                raise ConfigError(f"{where}.{key}: expected a number, got {v!r}")
            kwargs[key] = typ(v)
    if cfg.get("direction") is not None:
        kwargs["direction"] = str(cfg["direction"])
    # the configured order (no node is retained twice, resolve_retained_config refuses it)
    nodes = [n for p in points for n in p.nodes]
    try:
        se = craig_bampton(model, nodes, **kwargs)
    except MvtkError as err:
        raise ConfigError(f"{where}: {err}") from err
    return se, points
