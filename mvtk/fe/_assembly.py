"""Vectorised sparse assembly of layered shell models into an :class:`FEModel`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import DimensionError, ParameterError
from ._laminate import Laminate
from ._model import FEModel
from ._shell import DRILL_FACTOR, mitc4_matrices

__all__ = ["assemble_shell_model", "assemble_element_matrices"]


class _Pattern:
    """Sparsity pattern shared by several element matrices on the same DOF map.

    One sort of the (row, col) keys serves K and M; each matrix is then summed with
    ``np.bincount`` (no per-matrix COO -> CSR conversion).
    """

    def __init__(self, dofs: np.ndarray, free_index: np.ndarray, n_free: int):
        f = free_index[dofs]
        n = dofs.shape[1]
        rows = np.broadcast_to(f[:, :, None], (len(f), n, n)).ravel()
        cols = np.broadcast_to(f[:, None, :], (len(f), n, n)).ravel()
        self.keep = np.flatnonzero((rows >= 0) & (cols >= 0))
        key = rows[self.keep] * np.int64(n_free) + cols[self.keep]
        uniq, self.inverse = np.unique(key, return_inverse=True)
        self.indices = (uniq % n_free).astype(np.int32 if n_free < 2**31 else np.int64)
        row_of = uniq // n_free
        self.indptr = np.searchsorted(row_of, np.arange(n_free + 1)).astype(self.indices.dtype)
        self.n_free = n_free
        self.n_unique = len(uniq)

    def assemble(self, Ke: np.ndarray) -> sp.csr_matrix:
        data = np.bincount(self.inverse, weights=Ke.reshape(-1)[self.keep],
                           minlength=self.n_unique)
        return sp.csr_matrix((data, self.indices, self.indptr),
                             shape=(self.n_free, self.n_free))


def assemble_element_matrices(
    Ke: np.ndarray, dofs: np.ndarray, free_index: np.ndarray, n_free: int
) -> sp.csr_matrix:
    """Sum element matrices into a CSR matrix over the free DOFs.

    Parameters
    ----------
    Ke : ndarray (n_el, n, n)
    dofs : ndarray (n_el, n)
        Global (all-DOF) index of each element DOF.
    free_index : ndarray (n_all,)
        Free DOF number of every global DOF, -1 for constrained ones.
    n_free : int
    """
    return _Pattern(dofs, free_index, n_free).assemble(Ke)


def _unique_elements(xy: np.ndarray, section: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices of geometrically distinct elements (shape relative to node 0 + section)
    and, for every element, the index of its representative."""
    rel = xy - xy[:, :1, :]
    scale = max(float(np.abs(rel).max()), 1e-300)
    key = np.column_stack([np.round(rel.reshape(len(xy), -1) / (1e-10 * scale)),
                           section[:, None]]).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return first, inverse.ravel()


def assemble_shell_model(
    nodes: np.ndarray,
    elements: np.ndarray,
    element_section: np.ndarray,
    sections: Sequence[Laminate],
    fixed_dofs: np.ndarray | None = None,
    springs: np.ndarray | None = None,
    node_sets: Mapping[str, np.ndarray] | None = None,
    name: str = "",
    meta: Mapping[str, Any] | None = None,
    drill_factor: float = DRILL_FACTOR,
) -> FEModel:
    """Assemble MITC4 shell elements into a constrained :class:`FEModel`.

    Parameters
    ----------
    nodes : ndarray (n_nodes, 3)
        Node coordinates (m); the elements must lie in the plane z = const.
    elements : ndarray (n_el, 4)
        Counter-clockwise node indices.
    element_section : ndarray (n_el,)
        Index into ``sections`` for each element.
    sections : sequence of Laminate
    fixed_dofs : ndarray of int, optional
        Global DOF indices ``node * 6 + component`` to remove (zero displacement).
    springs : ndarray (n_nodes * 6,), optional
        Grounded spring stiffness added to the diagonal of each global DOF (N/m or
        N m/rad).
    node_sets, name, meta
        Passed to :class:`FEModel`.
    drill_factor : float
        See :mod:`mvtk.fe._shell`.

    Returns
    -------
    FEModel
        ``elements["mitc4"]`` holds the connectivity; ``meta["element_section"]`` the
        section index per element. Nodes that belong to no element are constrained.
    """
    nodes = np.asarray(nodes, dtype=float)
    elements = np.asarray(elements, dtype=np.int64)
    element_section = np.asarray(element_section, dtype=np.int64)
    n_nodes = len(nodes)
    if elements.ndim != 2 or elements.shape[1] != 4:
        raise DimensionError(f"elements must have shape (n_el, 4), got {elements.shape}")
    if element_section.shape != (len(elements),):
        raise DimensionError(
            f"element_section must have shape ({len(elements)},), got {element_section.shape}"
        )
    if elements.size and (elements.min() < 0 or elements.max() >= n_nodes):
        raise DimensionError(f"element connectivity refers to nodes outside 0..{n_nodes - 1}")
    if element_section.size and (element_section.min() < 0
                                 or element_section.max() >= len(sections)):
        raise ParameterError(
            f"element_section values must be in 0..{len(sections) - 1}, got "
            f"{element_section.min()}..{element_section.max()}"
        )
    z = nodes[elements, 2]
    if np.ptp(z) > 1e-12 * max(1.0, float(np.ptp(nodes[:, :2]))):
        raise ParameterError("MITC4 shells here are flat: all element nodes need one z")

    # element matrices depend only on the element shape and section: compute each
    # distinct one once (structured meshes have a handful)
    xy = nodes[elements, :2]
    first, rep = _unique_elements(xy, element_section)
    sec = element_section[first]
    abd = np.stack([s.ABD for s in sections])[sec]
    hs = np.stack([s.H for s in sections])[sec]
    inertia = np.array([[s.I0, s.I1, s.I2] for s in sections])[sec]
    Ku, Mu = mitc4_matrices(xy[first], abd, hs, inertia, drill_factor)
    Ke, Me = Ku[rep], Mu[rep]

    n_all = n_nodes * 6
    fixed = np.zeros(n_all, dtype=bool)
    used = np.zeros(n_nodes, dtype=bool)
    used[elements.ravel()] = True
    fixed.reshape(n_nodes, 6)[~used] = True
    if fixed_dofs is not None:
        fd = np.asarray(fixed_dofs, dtype=np.int64).ravel()
        if fd.size and (fd.min() < 0 or fd.max() >= n_all):
            raise ParameterError(f"fixed DOF index out of range 0..{n_all - 1}")
        fixed[fd] = True
    free = np.flatnonzero(~fixed)
    free_index = np.full(n_all, -1, dtype=np.int64)
    free_index[free] = np.arange(len(free))
    dofs = (elements[:, :, None] * 6 + np.arange(6)[None, None, :]).reshape(len(elements), 24)
    pattern = _Pattern(dofs, free_index, len(free))
    K = pattern.assemble(Ke)
    M = pattern.assemble(Me)
    if springs is not None:
        k = np.asarray(springs, dtype=float)
        if k.shape != (n_all,):
            raise DimensionError(f"springs must have shape ({n_all},), got {k.shape}")
        if np.any(k < 0) or not np.all(np.isfinite(k)):
            raise ParameterError("spring stiffnesses must be finite and >= 0")
        K = K + sp.diags(k[free]).tocsr()
    meta = dict(meta or {})
    meta.setdefault("element_section", element_section)
    meta.setdefault("sections", tuple(sections))
    return FEModel(
        nodes=nodes, M=M, K=K, dof_node=free // 6, dof_component=free % 6,
        node_sets=dict(node_sets or {}), elements={"mitc4": elements}, name=name, meta=meta,
    )
