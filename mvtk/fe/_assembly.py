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
    f = free_index[dofs]
    rows = np.broadcast_to(f[:, :, None], Ke.shape).ravel()
    cols = np.broadcast_to(f[:, None, :], Ke.shape).ravel()
    data = Ke.ravel()
    keep = (rows >= 0) & (cols >= 0)
    A = sp.coo_matrix((data[keep], (rows[keep], cols[keep])), shape=(n_free, n_free))
    A = A.tocsr()
    A.sum_duplicates()
    return A


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

    abd = np.stack([s.ABD for s in sections])[element_section]
    hs = np.stack([s.H for s in sections])[element_section]
    inertia = np.array([[s.I0, s.I1, s.I2] for s in sections])[element_section]
    Ke, Me = mitc4_matrices(nodes[elements, :2], abd, hs, inertia, drill_factor)

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
    K = assemble_element_matrices(Ke, dofs, free_index, len(free))
    M = assemble_element_matrices(Me, dofs, free_index, len(free))
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
