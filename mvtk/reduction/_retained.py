"""Resolve a user's choice of retained (boundary) nodes or DOFs to free-DOF indices."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import numpy as np

from ..errors import DimensionError, ParameterError
from ..fe import FEModel

__all__ = ["resolve_retained"]


def _is_point(item) -> bool:
    if isinstance(item, (str, bytes)) or not isinstance(item, Sequence | np.ndarray):
        return False
    arr = np.asarray(item)
    return arr.shape == (3,) and np.issubdtype(arr.dtype, np.number)


def _nodes_of(model: FEModel, item) -> np.ndarray:
    if isinstance(item, str):
        return np.asarray(model.node_set(item), dtype=np.int64)
    if _is_point(item):
        return np.array([model.nearest_node(np.asarray(item, dtype=float))], dtype=np.int64)
    if isinstance(item, (bool, np.bool_)) or not isinstance(item, (int, np.integer)):
        raise ParameterError(
            f"retained item {item!r} is not understood; expected a node index (int), "
            "a node set name (str) or a point [x, y, z] in m"
        )
    node = int(item)
    if not 0 <= node < model.n_nodes:
        raise ParameterError(
            f"retained node {node} does not exist (model has {model.n_nodes} nodes)"
        )
    return np.array([node], dtype=np.int64)


def resolve_retained(
    model: FEModel,
    retained: Iterable | None = None,
    retained_dofs: Iterable[int] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Boundary free-DOF indices and named nodes of a super element.

    Parameters
    ----------
    model : FEModel
    retained : iterable, optional
        Items, each a node index (int), a node set name (str) or a point ``[x, y, z]``
        in m (its nearest node); a single int or str is one item. A point must be an
        item of the iterable: ``[[0.18, 0.0, 0.0]]``, not ``[0.18, 0.0, 0.0]``. All
        *free* DOFs of those nodes are retained; fully constrained nodes (e.g. a clamp)
        contribute nothing.
    retained_dofs : iterable of int, optional
        Explicit free-DOF indices (rows of ``model.K``), added to the above.

    Returns
    -------
    dofs : ndarray of int
        Ascending unique free-DOF indices.
    nodes : ndarray of int
        Ascending unique nodes named in ``retained`` (including fully constrained ones)
        plus the nodes of ``retained_dofs``.

    Raises
    ------
    ParameterError
        Unknown node, node set or item; DOF index out of range.
    """
    parts: list[np.ndarray] = []
    nodes: list[np.ndarray] = []
    if retained is not None:
        if isinstance(retained, (str, int, np.integer)):
            retained = [retained]
        for item in retained:
            item_nodes = _nodes_of(model, item)
            nodes.append(item_nodes)
            parts.append(model.node_dofs(item_nodes))
    if retained_dofs is not None:
        dofs = np.atleast_1d(np.asarray(retained_dofs))
        if dofs.size and not np.issubdtype(dofs.dtype, np.integer):
            raise ParameterError(
                f"retained_dofs must be integer free-DOF indices, got dtype {dofs.dtype}"
            )
        if dofs.ndim != 1:
            raise DimensionError(f"retained_dofs must be 1-D, got shape {dofs.shape}")
        if dofs.size and (dofs.min() < 0 or dofs.max() >= model.n_dof):
            raise ParameterError(
                f"retained_dofs must be in 0..{model.n_dof - 1}, "
                f"got values from {dofs.min()} to {dofs.max()}"
            )
        parts.append(dofs.astype(np.int64))
        nodes.append(model.dof_node[dofs.astype(np.int64)])
    if not parts:
        raise ParameterError("no boundary given: pass retained nodes/sets or retained_dofs")
    idx = np.unique(np.concatenate(parts)).astype(np.int64)
    all_nodes = np.unique(np.concatenate(nodes)).astype(np.int64)
    return idx, all_nodes
