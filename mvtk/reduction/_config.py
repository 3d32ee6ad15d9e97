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

__all__ = ["RetainedPoint", "resolve_retained_config", "super_element_from_config"]

_KEYS = {"n_modes", "mass_fraction", "f_cut_hz", "direction", "n_compare", "retained"}


@dataclass(frozen=True)
class RetainedPoint:
    """One retained item of the configuration, resolved to model nodes."""

    name: str
    nodes: tuple[int, ...]
    n_free_dofs: int


def resolve_retained_config(model: FEModel, retained, where: str = "reduction.retained"):
    """Resolve ``retained`` config items to :class:`RetainedPoint` s.

    Items are node set names (str), points ``[x, y, z]`` (m), or tables with ``name``
    and one of ``xyz`` / ``node_set`` / ``node``.

    Raises
    ------
    ConfigError
        Naming the item (``reduction.retained[i]``) and what was expected.
    """
    if isinstance(retained, str) or not isinstance(retained, list | tuple) or not retained:
        raise ConfigError(
            f"{where}: expected a non-empty list of node set names, points [x, y, z] or "
            f"tables with name and xyz/node_set/node, got {retained!r}"
        )
    out = []
    for i, item in enumerate(retained):
        w = f"{where}[{i}]"
        name = None
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
                nodes = np.array([model.nearest_node(arr.astype(float))])
        except ConfigError:
            raise
        except MvtkError as err:
            raise ConfigError(f"{w}: {err}") from err
        nodes = tuple(int(n) for n in nodes)
        label = str(name) if name is not None else (
            str(spec) if kind == "node_set" else f"n{nodes[0]}"
        )
        out.append(RetainedPoint(label, nodes, int(model.node_dofs(list(nodes)).size)))
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
        if key in cfg:
            v = cfg[key]
            ok = isinstance(v, int) if typ is int else isinstance(v, int | float)
            if isinstance(v, bool) or not ok:
                raise ConfigError(f"{where}.{key}: expected a number, got {v!r}")
            kwargs[key] = typ(v)
    if "direction" in cfg:
        kwargs["direction"] = str(cfg["direction"])
    nodes = sorted({n for p in points for n in p.nodes})
    try:
        se = craig_bampton(model, nodes, **kwargs)
    except MvtkError as err:
        raise ConfigError(f"{where}: {err}") from err
    return se, points
