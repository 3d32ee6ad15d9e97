"""The finite element model container shared by every stage of mvtk.

An :class:`FEModel` is a frozen dataclass holding the sparse mass and stiffness
matrices over the *free* degrees of freedom (constrained DOFs already removed), plus
the map from each free DOF to its node and component. Everything downstream
(updating, reduction, control) only needs this object.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import DimensionError, ParameterError

__all__ = ["FEModel", "DOF_NAMES"]

#: Names of the six nodal degrees of freedom, in storage order.
#: Translations in m, rotations in rad.
DOF_NAMES: tuple[str, ...] = ("ux", "uy", "uz", "rx", "ry", "rz")


def _component_index(component: int | str) -> int:
    if isinstance(component, str):
        try:
            return DOF_NAMES.index(component)
        except ValueError:
            raise ParameterError(
                f"unknown DOF component {component!r}; expected one of {DOF_NAMES}"
            ) from None
    c = int(component)
    if not 0 <= c < len(DOF_NAMES):
        raise ParameterError(f"DOF component index must be in 0..5, got {component}")
    return c


@dataclass(frozen=True, eq=False)
class FEModel:
    """Assembled linear structural model over its free degrees of freedom.

    Parameters
    ----------
    nodes : ndarray, shape (n_nodes, 3)
        Node coordinates in m.
    M, K : scipy.sparse matrix, shape (n_dof, n_dof)
        Symmetric mass (kg, kg m^2) and stiffness (N/m, N m/rad) matrices over the
        free DOFs. Stored as CSR.
    dof_node : ndarray of int, shape (n_dof,)
        Node index (row of ``nodes``) of each free DOF.
    dof_component : ndarray of int, shape (n_dof,)
        Component of each free DOF, an index into :data:`DOF_NAMES`.
    node_sets : mapping of str to ndarray of int
        Named node sets (e.g. ``"clamp"``, ``"tip"``, ``"patch_edge_0"``).
    elements : mapping of str to ndarray of int
        Element connectivity per element type (e.g. ``"shell8"``: (n_el, 8)).
    name : str
        Free text name.
    meta : mapping
        Any further description (structure dict, mesh sizes, ...). Not used by solvers.
        ``meta["recovery"]``, when present, is a sparse (n_nodes * 6, n_dof) matrix
        giving every nodal DOF (including those eliminated by rigid links) from the free
        ones; :meth:`expand` uses it.
    node_ids : ndarray of int, shape (n_nodes,), optional
        External node labels (e.g. the ids of an imported mesh or of test software);
        default ``1..n_nodes``. Must be unique.

    Examples
    --------
    Built by the generators and readers (here a 4-element cantilever, 6 DOFs per node, the
    clamped node removed); DOFs are addressed by node and component:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(IsotropicMaterial("steel", 2.1e11, 0.3,
    ...                                                          7850.0), 2e-3)], n_elements=4)
    >>> beam.n_nodes, beam.n_dof, beam.M.shape
    (5, 24, (24, 24))
    >>> beam.dof_index(4, "uz"), int(beam.node_ids[4])    # free-DOF index; label of node 4
    (20, 5)
    >>> beam.nearest_node([0.29, 0.0, 0.0])
    4
    """

    nodes: np.ndarray
    M: sp.csr_matrix
    K: sp.csr_matrix
    dof_node: np.ndarray
    dof_component: np.ndarray
    node_sets: Mapping[str, np.ndarray] = field(default_factory=dict)
    elements: Mapping[str, np.ndarray] = field(default_factory=dict)
    name: str = ""
    meta: Mapping[str, Any] = field(default_factory=dict)
    node_ids: np.ndarray | None = None

    def __post_init__(self) -> None:
        nodes = np.asarray(self.nodes, dtype=float)
        if nodes.ndim != 2 or nodes.shape[1] != 3:
            raise DimensionError(f"nodes must have shape (n_nodes, 3), got {nodes.shape}")
        if self.node_ids is None:
            ids = np.arange(1, len(nodes) + 1, dtype=np.int64)
        else:
            ids = np.asarray(self.node_ids)
            if ids.shape != (len(nodes),) or not np.issubdtype(ids.dtype, np.integer):
                raise DimensionError(
                    f"node_ids must be {len(nodes)} integers (one per node), got "
                    f"shape {ids.shape} of {ids.dtype}"
                )
            if np.unique(ids).size != ids.size:
                raise DimensionError("node_ids must be unique")
            ids = ids.astype(np.int64)
        object.__setattr__(self, "node_ids", ids)
        M = sp.csr_matrix(self.M)
        K = sp.csr_matrix(self.K)
        n = K.shape[0]
        if K.shape != (n, n) or M.shape != (n, n):
            raise DimensionError(
                f"M and K must be square and of equal size, got M {M.shape}, K {K.shape}"
            )
        dof_node = np.asarray(self.dof_node, dtype=np.int64)
        dof_comp = np.asarray(self.dof_component, dtype=np.int64)
        if dof_node.shape != (n,) or dof_comp.shape != (n,):
            raise DimensionError(
                f"dof_node and dof_component must have shape ({n},), "
                f"got {dof_node.shape} and {dof_comp.shape}"
            )
        if n and (dof_node.min() < 0 or dof_node.max() >= len(nodes)):
            raise DimensionError("dof_node refers to a node index outside nodes")
        if n and (dof_comp.min() < 0 or dof_comp.max() > 5):
            raise DimensionError("dof_component must be in 0..5")
        key = dof_node * 6 + dof_comp
        if n and np.bincount(key).max() > 1:
            raise DimensionError("dof_node/dof_component contain a duplicated DOF")
        sets = {str(k): np.asarray(v, dtype=np.int64) for k, v in self.node_sets.items()}
        els = {str(k): np.asarray(v, dtype=np.int64) for k, v in self.elements.items()}
        object.__setattr__(self, "nodes", nodes)
        object.__setattr__(self, "M", M)
        object.__setattr__(self, "K", K)
        object.__setattr__(self, "dof_node", dof_node)
        object.__setattr__(self, "dof_component", dof_comp)
        object.__setattr__(self, "node_sets", sets)
        object.__setattr__(self, "elements", els)
        lookup = np.full(len(nodes) * 6, -1, dtype=np.int64)
        lookup[key] = np.arange(n)
        object.__setattr__(self, "_lookup", lookup)

    # ------------------------------------------------------------------ sizes
    @property
    def n_dof(self) -> int:
        """Number of free DOFs."""
        return self.K.shape[0]

    @property
    def n_nodes(self) -> int:
        """Number of nodes (including fully constrained ones)."""
        return self.nodes.shape[0]

    @property
    def n_elements(self) -> int:
        """Total number of elements over all element types."""
        return int(sum(len(c) for c in self.elements.values()))

    # ------------------------------------------------------------- DOF lookup
    def node_index(self, node_id: int) -> int:
        """Row of ``nodes`` of the node labelled ``node_id`` (:attr:`node_ids`).

        Raises
        ------
        ParameterError
            No node has that label.
        """
        ids = (np.asarray(self.node_ids) if self.node_ids is not None
               else np.arange(1, self.n_nodes + 1))
        hit = np.flatnonzero(ids == int(node_id))
        if hit.size != 1:
            raise ParameterError(f"no node has the ID {node_id} (IDs {int(ids.min())}.."
                                 f"{int(ids.max())}, {ids.size} nodes)")
        return int(hit[0])

    def dof_index(self, node: int, component: int | str, *, by: str = "index") -> int:
        """Index of the free DOF ``component`` of ``node``.

        Parameters
        ----------
        node : int
            The node: its index (row of :attr:`nodes`, 0-based) with ``by="index"``, its
            label (:attr:`node_ids`, 1-based by default, an imported mesh's own IDs)
            with ``by="id"``.
        component : int or str
            Index into :data:`DOF_NAMES` or its name (``"uz"``).
        by : {"index", "id"}

        Raises
        ------
        ParameterError
            If the node does not exist or that DOF is constrained.
        """
        if by not in ("index", "id"):
            raise ParameterError(f"by must be 'index' or 'id', got {by!r}")
        c = _component_index(component)
        node = int(node) if by == "index" else self.node_index(node)
        if not 0 <= node < self.n_nodes:
            hint = ""
            if self.node_ids is not None and np.any(np.asarray(self.node_ids) == node):
                hint = (f"; {node} is the ID of the node with index "
                        f"{self.node_index(node)}: pass by='id' for node IDs")
            raise ParameterError(f"node index {node} does not exist (model has "
                                 f"{self.n_nodes} nodes, indices 0..{self.n_nodes - 1})"
                                 + hint)
        i = int(self._lookup[node * 6 + c])
        if i < 0:
            raise ParameterError(
                f"DOF {DOF_NAMES[c]} of node {node} is constrained (not a free DOF)"
            )
        return i

    def node_dofs(
        self, nodes: Iterable[int] | int, components: Iterable[int | str] | None = None
    ) -> np.ndarray:
        """Free DOF indices of ``nodes`` (all their free components, or ``components``).

        Constrained DOFs are skipped when ``components`` is None; an explicitly requested
        constrained component raises :class:`ParameterError`.
        """
        nodes = np.atleast_1d(np.asarray(nodes, dtype=np.int64))
        if nodes.size and (nodes.min() < 0 or nodes.max() >= self.n_nodes):
            raise ParameterError(f"node index out of range 0..{self.n_nodes - 1}")
        if components is None:
            idx = self._lookup[(nodes[:, None] * 6 + np.arange(6)[None, :]).ravel()]
            return idx[idx >= 0]
        comps = [_component_index(c) for c in components]
        return np.array([self.dof_index(n, c) for n in nodes for c in comps], dtype=np.int64)

    def node_set(self, name: str) -> np.ndarray:
        """Node indices of the named node set."""
        try:
            return self.node_sets[name]
        except KeyError:
            raise ParameterError(
                f"no node set {name!r}; available: {sorted(self.node_sets)}"
            ) from None

    def nearest_node(self, xyz: Iterable[float]) -> int:
        """Index of the node closest to the point ``xyz`` (m)."""
        p = np.asarray(list(xyz), dtype=float)
        if p.shape != (3,):
            raise DimensionError(f"point must have 3 coordinates, got {p.shape}")
        return int(np.argmin(np.linalg.norm(self.nodes - p, axis=1)))

    @property
    def dof_labels(self) -> list[str]:
        """Readable labels ``"n{node}:{component}"`` of the free DOFs."""
        return [f"n{n}:{DOF_NAMES[c]}" for n, c in zip(self.dof_node, self.dof_component)]

    def expand(self, x: np.ndarray) -> np.ndarray:
        """Expand free-DOF vector(s) to nodal arrays.

        Parameters
        ----------
        x : ndarray, shape (n_dof,) or (n_dof, k)

        Returns
        -------
        ndarray, shape (n_nodes, 6) or (n_nodes, 6, k)
            Constrained DOFs are zero; DOFs eliminated by rigid links are recovered from
            ``meta["recovery"]`` when present.
        """
        x = np.asarray(x)
        if x.shape[0] != self.n_dof:
            raise DimensionError(f"expected {self.n_dof} rows, got {x.shape[0]}")
        T = self.meta.get("recovery")
        if T is not None:
            out = np.asarray(T @ x)
        else:
            out = np.zeros((self.n_nodes * 6, *x.shape[1:]), dtype=x.dtype)
            out[self.dof_node * 6 + self.dof_component] = x
        return out.reshape(self.n_nodes, 6, *x.shape[1:])
