"""Vectorised sparse assembly of layered shell models into an :class:`FEModel`."""

from __future__ import annotations

import hashlib
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph  # noqa: F401  (sp.csgraph)

from ..errors import DimensionError, ParameterError
from ._laminate import Laminate
from ._model import FEModel
from ._shell import DRILL_FACTOR, mitc4_matrices

__all__ = [
    "assemble_shell_model",
    "assemble_element_matrices",
    "SparsityPattern",
    "sparsity_pattern",
]


_PATTERN_CACHE: OrderedDict[bytes, SparsityPattern] = OrderedDict()
_PATTERN_CACHE_SIZE = 4


class SparsityPattern:
    """CSR sparsity pattern of element matrices summed over a DOF map, reusable.

    Built once per connectivity and constraint set; :meth:`assemble` then sums any
    element matrices of that mesh (K, M, or new values after a parameter change) over
    precomputed positions, without sorting anything.

    When the element DOFs come in node blocks (``dofs[e, b*s:b*s+b] = b*node + 0..b-1``,
    as for 6-DOF shells and beams) and the free DOFs are numbered in global order, the
    pattern is derived from the node graph: only the ``n_el * (n/b)^2`` node pairs are
    sorted (a few hundred thousand for a 50 000-DOF shell model instead of 4.7 million
    matrix entries) and the DOF-level CSR arrays are index arithmetic. Otherwise the
    matrix-entry keys are sorted (``np.unique``). Both give the same CSR matrix with
    sorted column indices.

    Summation: on a node-graph pattern the ``b x b`` blocks of the elements are summed
    per node pair by one sparse product (the pair-by-element-block incidence times the
    blocks), and each pair's block is then written to its CSR positions; with distinct
    element matrices and the index of each element's one (``rep``), the incidence
    counts the elements that share a matrix, so the ``n_el`` element matrices are never
    formed (a 1 000 000-DOF plate would hold 1.5 GB of them). Otherwise the entries
    are summed with one ``np.bincount`` over :attr:`position`, in element order.

    Parameters
    ----------
    dofs : ndarray (n_el, n)
        Global (all-DOF) index of each element DOF.
    free_index : ndarray (n_all,)
        Free DOF number of every global DOF, -1 for constrained ones.
    n_free : int
    kinds : ndarray of int (b,), optional
        Kind of each DOF of a node block (e.g. membrane and bending DOFs of a flat
        shell): entries between DOFs of different kinds are structurally zero and left
        out of a node-graph pattern whose block size is ``b`` (then :meth:`assemble`
        refuses element matrices with a nonzero there). Default: one kind (every entry
        of an element's node-pair blocks). Other patterns keep every entry.

    Attributes
    ----------
    indptr, indices : ndarray
        CSR structure (sorted column indices) of the ``n_free x n_free`` matrix.
    position : ndarray (n_el * n * n,)
        Index into the CSR data of each element-matrix entry (``nnz`` for entries on a
        constrained DOF, which are dropped); for a node-graph pattern computed on
        first use.

    Examples
    --------
    Returned by :func:`sparsity_pattern`; sums element matrices on a fixed pattern:

    >>> pattern = sparsity_pattern(np.array([[0, 1], [1, 2]]), np.array([-1, 0, 1]), 2)
    >>> Ke = np.tile(np.array([[1.0, -1.0], [-1.0, 1.0]]), (2, 1, 1))
    >>> pattern.assemble(Ke).toarray()
    array([[ 2., -1.],
           [-1.,  1.]])
    """

    def __init__(self, dofs: np.ndarray, free_index: np.ndarray, n_free: int,
                 kinds: np.ndarray | None = None):
        dofs = np.asarray(dofs, dtype=np.int64)
        free_index = np.asarray(free_index, dtype=np.int64)
        if dofs.ndim != 2:
            raise DimensionError(f"dofs must have shape (n_el, n), got {dofs.shape}")
        if dofs.size and (dofs.min() < 0 or dofs.max() >= len(free_index)):
            raise DimensionError(
                f"element DOF indices must be in 0..{len(free_index) - 1}, got "
                f"{dofs.min()}..{dofs.max()}"
            )
        self.n_free = int(n_free)
        self.shape = (self.n_free, self.n_free)
        self.element_shape = dofs.shape
        block = _node_block(dofs, free_index, self.n_free)
        if block:
            kinds = (np.zeros(block, dtype=np.int64) if kinds is None
                     else np.asarray(kinds, dtype=np.int64).ravel())
            if kinds.shape != (block,):
                kinds = np.zeros(block, dtype=np.int64)
            self._from_node_graph(dofs, free_index, block, kinds)
        else:
            self._from_entries(dofs, free_index)
        self.nnz = len(self.indices)
        itype = np.int32 if max(self.nnz, self.n_free) < 2**31 - 1 else np.int64
        self.indices = self.indices.astype(itype, copy=False)
        self.indptr = self.indptr.astype(itype, copy=False)

    def _from_entries(self, dofs, free_index):
        n_free = self.n_free
        f = free_index[dofs]
        n = dofs.shape[1]
        rows = np.broadcast_to(f[:, :, None], (len(f), n, n)).ravel()
        cols = np.broadcast_to(f[:, None, :], (len(f), n, n)).ravel()
        keep = (rows >= 0) & (cols >= 0)
        key = rows[keep] * np.int64(n_free) + cols[keep]
        uniq, inverse = np.unique(key, return_inverse=True)
        self.indices = uniq % n_free
        row_of = uniq // n_free
        self.indptr = np.searchsorted(row_of, np.arange(n_free + 1))
        self._position = np.full(rows.shape, len(uniq), dtype=np.intp)
        self._position[keep] = inverse.ravel()
        self._gather = None

    def _from_node_graph(self, dofs, free_index, b, kinds):
        n_el, n = dofs.shape
        s = n // b
        n_nodes = len(free_index) // b
        n_free = self.n_free
        nodes = dofs[:, ::b] // b                                    # (n_el, s)
        fi = free_index.reshape(n_nodes, b)
        pair_key = (nodes[:, :, None] * np.int64(n_nodes) + nodes[:, None, :]).ravel()
        upair, pinv = np.unique(pair_key, return_inverse=True)
        P, Q = upair // n_nodes, upair % n_nodes
        n_pairs = len(upair)
        pstart = np.searchsorted(P, np.arange(n_nodes + 1))         # pairs of node P
        # Per DOF kind k: the row of a free DOF of kind k of node P holds, pair by pair
        # (P, Q) in Q order, the free DOFs of kind k of Q (ascending: sorted columns).
        # Its column list is a run of the kind's template (the free kind-k DOFs of the
        # Q of every pair, in pair order), the same run for every kind-k row of P.
        row_len = np.zeros(n_free, dtype=np.int64)
        row_start = np.zeros(n_free, dtype=np.int64)
        offset = np.zeros((b, n_pairs), dtype=np.int64)   # pair offset in the rows of a
        rank = np.zeros((n_nodes, b), dtype=np.int64)     # column rank within its kind
        templates, t0 = [], 0
        for k in np.unique(kinds):
            cols = np.flatnonzero(kinds == k)
            sub = fi[:, cols]                                        # (n_nodes, b_k)
            ok = sub >= 0
            rank[:, cols] = np.cumsum(ok, axis=1) - 1
            cw = np.zeros(n_pairs + 1, dtype=np.int64)
            np.cumsum(ok.sum(axis=1)[Q], out=cw[1:])
            t = sub[Q].ravel()
            templates.append(t[t >= 0])
            offset[cols] = cw[:-1] - cw[pstart[P]]
            rows, rnode = sub[ok], np.nonzero(ok)[0]
            row_len[rows] = (cw[pstart[1:]] - cw[pstart[:-1]])[rnode]
            row_start[rows] = t0 + cw[pstart[rnode]]
            t0 += cw[-1]
        template = np.concatenate(templates)
        indptr = np.zeros(n_free + 1, dtype=np.int64)
        np.cumsum(row_len, out=indptr[1:])
        nnz = int(indptr[-1])
        self.indices = template[np.repeat(row_start - indptr[:-1], row_len)
                                + np.arange(nnz)]
        self.indptr = indptr
        # CSR position of every entry (a, c) of every node-pair block p = (P, Q), row
        # DOF a of P, column DOF c of Q, made per DOF kind (entries between kinds and on
        # a constrained DOF are not in the pattern): the start of the pair's columns in
        # the row of a, plus the rank of c among the pair's columns of its kind
        itype = np.int32 if max(2 * nnz, n_pairs * b * b) < 2**31 - 1 else np.int64
        rowbase = (indptr[np.maximum(fi, 0)][P] + offset.T).astype(itype)   # (n_pairs, b)
        colrank = rank[Q].astype(itype)
        okp, okq = fi[P] >= 0, fi[Q] >= 0
        flat0 = (np.arange(n_pairs, dtype=itype) * itype(b * b))[:, None, None]
        # the inverse: for every CSR entry, its (pair, a, c) in the pair blocks (each
        # entry is in exactly one pair block), so that the data are one np.take
        # (entries on a constrained DOF are written to a spare slot past the end, which
        # is cheaper than compressing the position and value arrays by a mask)
        gather = np.empty(nnz + 1, dtype=itype)
        for k in np.unique(kinds):
            cols = np.flatnonzero(kinds == k)
            pos = rowbase[:, cols][:, :, None] + colrank[:, cols][:, None, :]
            flat = flat0 + (cols[:, None] * b + cols[None, :]).astype(itype)[None]
            ok = okp[:, cols][:, :, None] & okq[:, cols][:, None, :]
            if not ok.all():
                np.copyto(pos, itype(nnz), where=~ok)
            gather[pos.ravel()] = flat.ravel()
        # np.take converts its indices to intp: kept as intp, they are converted once
        self._gather = gather[:nnz].astype(np.intp)
        self._pair_of = pinv.ravel().astype(itype, copy=False)      # (n_el * s * s,)
        self._n_pairs = n_pairs
        self._block = (s, b)
        self._kinds = kinds
        self._position = None

    @property
    def position(self) -> np.ndarray:
        """Index into the CSR data of each element-matrix entry, shape (n_el * n * n,)
        (``nnz`` for entries on a constrained DOF); computed on first use."""
        if self._position is None:
            s, b = self._block
            n_el = self.element_shape[0]
            pair_position = np.full(self._n_pairs * b * b, self.nnz, dtype=np.intp)
            pair_position[self._gather] = np.arange(self.nnz)
            pos = pair_position.reshape(self._n_pairs, b * b)[self._pair_of]
            pos = pos.reshape(n_el, s, s, b, b)
            self._position = pos.transpose(0, 1, 3, 2, 4).reshape(-1).astype(
                np.intp, copy=False)
        return self._position

    def _pair_sums(self, mats, rep):
        """Node-pair block sums of element matrices (node-graph patterns): for each
        matrix in ``mats``, the sparse product of the (pair x element-block) incidence
        with its element blocks, shape (n_pairs, b * b)."""
        s, b = self._block
        n_el = self.element_shape[0]
        n_u = len(mats[0])
        # blocks (element or distinct element u, node pair si, sj) x (a, c)
        blocks = [m.reshape(n_u, s, b, s, b).transpose(0, 1, 3, 2, 4).reshape(
            n_u * s * s, b * b) for m in mats]
        cross = (self._kinds[:, None] != self._kinds[None, :]).ravel()
        if np.any(cross) and any(np.any(blk[:, cross]) for blk in blocks):
            raise ParameterError(
                "element matrices couple DOFs of different kinds, which this sparsity "
                f"pattern leaves out (kinds {self._kinds.tolist()} per node)")
        owner = np.arange(n_el) if rep is None else rep
        col = (owner[:, None] * (s * s) + np.arange(s * s)).ravel()
        n_pairs = self._n_pairs
        # the incidence summed over elements sharing a distinct matrix (a count per
        # pair and block), so that every distinct block is read, not copied per element
        inc = sp.csr_matrix((np.ones(len(col)), (self._pair_of, col)),
                            shape=(n_pairs, n_u * s * s))
        return [inc @ blk for blk in blocks]

    def assemble_many(self, mats, rep: np.ndarray | None = None) -> list[sp.csr_matrix]:
        """Sum several sets of element matrices (e.g. K and M) into CSR matrices.

        Parameters
        ----------
        mats : sequence of ndarray
            Each of shape (n_el, n, n), the matrix of every element; or, with ``rep``,
            (n_u, n, n), the distinct element matrices.
        rep : ndarray of int (n_el,), optional
            Index into the distinct matrices of each element (structured meshes have a
            handful of distinct elements): they are summed without an array of
            ``n_el`` element matrices.

        Returns
        -------
        list of scipy.sparse.csr_matrix
        """
        n_el, n = self.element_shape
        mats = [np.asarray(m, dtype=float) for m in mats]
        if rep is not None:
            rep = np.asarray(rep, dtype=np.int64)
            if rep.shape != (n_el,):
                raise DimensionError(f"rep must have shape ({n_el},), got {rep.shape}")
        for m in mats:
            n_u = n_el if rep is None else len(mats[0])
            if m.shape != (n_u, n, n):
                raise DimensionError(
                    f"element matrices must have shape ({n_u}, {n}, {n}), got {m.shape}")
        if rep is not None and rep.size and (rep.min() < 0 or rep.max() >= len(mats[0])):
            raise DimensionError(f"rep must index 0..{len(mats[0]) - 1}")
        out = []
        if self._gather is not None:
            # entry j of the block of pair p: sums[p, j], the CSR entry's _gather = p bb + j
            for sums in self._pair_sums(mats, rep):
                data = np.take(sums.ravel(), self._gather)
                out.append(sp.csr_matrix((data, self.indices, self.indptr),
                                         shape=self.shape))
            return out
        for m in mats:
            Ke = m if rep is None else m[rep]
            data = np.bincount(self.position, weights=Ke.reshape(-1),
                               minlength=self.nnz + 1)
            out.append(sp.csr_matrix((data[: self.nnz], self.indices, self.indptr),
                                     shape=self.shape))
        return out

    def assemble(self, Ke: np.ndarray, rep: np.ndarray | None = None) -> sp.csr_matrix:
        """Sum element matrices ``Ke`` (n_el, n, n) into a CSR matrix on this pattern (or
        distinct matrices ``Ke`` (n_u, n, n) with ``rep``: see :meth:`assemble_many`)."""
        return self.assemble_many([Ke], rep)[0]


def _node_block(dofs: np.ndarray, free_index: np.ndarray, n_free: int) -> int:
    """Node block size b of ``dofs`` if the node-graph construction applies, else 0."""
    n = dofs.shape[1]
    free = free_index[free_index >= 0]
    if len(free) != n_free or not np.array_equal(free, np.arange(n_free)):
        return 0
    for b in (6, 3, 2):
        if n % b or len(free_index) % b or not dofs.size:
            continue
        d = dofs.reshape(len(dofs), n // b, b)
        if np.all(d[:, :, :1] % b == 0) and np.array_equal(
                d - d[:, :, :1], np.broadcast_to(np.arange(b), d.shape)):
            return b
    return 0


def sparsity_pattern(dofs: np.ndarray, free_index: np.ndarray, n_free: int,
                     kinds: np.ndarray | None = None) -> SparsityPattern:
    """:class:`SparsityPattern` for a connectivity, from a small cache when seen before.

    The cache key is a hash of ``dofs``, ``free_index``, ``n_free`` and ``kinds`` (the
    connectivity, constraints and uncoupled DOF kinds), so rebuilding a model with new
    material or thickness values (model updating, Monte Carlo) reuses the pattern; the
    last four patterns are kept.

    Examples
    --------
    The pattern of a connectivity is built once and sums any element matrices on it:

    >>> dofs = np.array([[0, 1], [1, 2], [2, 3]])
    >>> pattern = sparsity_pattern(dofs, np.array([-1, 0, 1, 2]), 3)
    >>> Ke = np.tile(np.array([[1.0, -1.0], [-1.0, 1.0]]), (3, 1, 1))
    >>> pattern.assemble(2.0 * Ke).toarray()[0]
    array([ 4., -2.,  0.])
    """
    dofs = np.ascontiguousarray(dofs, dtype=np.int64)
    free_index = np.ascontiguousarray(free_index, dtype=np.int64)
    h = hashlib.blake2b(digest_size=20)
    h.update(np.array([dofs.shape[0], dofs.shape[1] if dofs.ndim == 2 else -1, n_free],
                      dtype=np.int64).tobytes())
    h.update(dofs.tobytes())
    h.update(free_index.tobytes())
    if kinds is not None:
        h.update(b"kinds")
        h.update(np.ascontiguousarray(kinds, dtype=np.int64).tobytes())
    key = h.digest()
    pattern = _PATTERN_CACHE.get(key)
    if pattern is None:
        pattern = SparsityPattern(dofs, free_index, n_free, kinds)
        _PATTERN_CACHE[key] = pattern
        while len(_PATTERN_CACHE) > _PATTERN_CACHE_SIZE:
            _PATTERN_CACHE.popitem(last=False)
    else:
        _PATTERN_CACHE.move_to_end(key)
    return pattern


def assemble_element_matrices(
    Ke: np.ndarray, dofs: np.ndarray, free_index: np.ndarray, n_free: int
) -> sp.csr_matrix:
    """Sum element matrices into a CSR matrix over the free DOFs.

    The sparsity pattern comes from :func:`sparsity_pattern` (cached per connectivity).

    Parameters
    ----------
    Ke : ndarray (n_el, n, n)
    dofs : ndarray (n_el, n)
        Global (all-DOF) index of each element DOF.
    free_index : ndarray (n_all,)
        Free DOF number of every global DOF, -1 for constrained ones.
    n_free : int

    Returns
    -------
    scipy.sparse.csr_matrix, shape (n_free, n_free)
        Sorted column indices, no duplicates.

    Examples
    --------
    Three springs of 1e5 N/m in a chain 0-1-2-3 with DOF 0 fixed (``free_index`` -1):

    >>> Ke = np.tile(np.array([[1.0, -1.0], [-1.0, 1.0]]) * 1e5, (3, 1, 1))
    >>> dofs = np.array([[0, 1], [1, 2], [2, 3]])
    >>> K = assemble_element_matrices(Ke, dofs, np.array([-1, 0, 1, 2]), 3)
    >>> K.toarray() / 1e5
    array([[ 2., -1.,  0.],
           [-1.,  2., -1.],
           [ 0., -1.,  1.]])
    """
    return sparsity_pattern(dofs, free_index, n_free).assemble(Ke)


def _dof_kinds(mats, b: int) -> np.ndarray | None:
    """Classes of the ``b`` DOFs of a node that the element matrices ``mats`` (each
    (n_u, n, n)) never couple, directly or through other DOFs of the class: the
    membrane (ux, uy, rz) and bending (uz, rx, ry) DOFs of flat shells in a plane of
    constant z with a symmetric laminate. None when every DOF couples with every other."""
    n = mats[0].shape[1]
    s = n // b
    link = np.zeros((b, b), dtype=bool)
    for m in mats:
        nz = m.reshape(len(m), s, b, s, b) != 0
        link |= nz.any(axis=(0, 1, 3))
    n_comp, kinds = sp.csgraph.connected_components(sp.csr_matrix(link | link.T),
                                                    directed=False)
    return None if n_comp == 1 else kinds.astype(np.int64)


def _unique_elements(xy: np.ndarray, section: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices of geometrically distinct elements (shape relative to node 0 + section)
    and, for every element, the index of its representative."""
    rel = (xy - xy[:, :1, :]).reshape(len(xy), -1)
    # resolution 1e-10 of each element's own size (octave), not of the largest element,
    # so that slivers at patch edges keep their exact shape
    octave = np.floor(np.log2(np.maximum(np.abs(rel).max(axis=1), 1e-300)))
    key = np.column_stack([np.round(rel / (1e-10 * 2.0**octave[:, None])), octave,
                           section]).astype(np.int64)
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

    Examples
    --------
    A 300 x 200 mm steel plate, 2 mm, in 3 x 2 MITC4 elements, clamped at x = 0:

    >>> from mvtk.fe import IsotropicMaterial, Laminate, Ply, edge_dofs, rectangular_plate_mesh
    >>> lam = Laminate((Ply(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0), 2e-3),))
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> model = assemble_shell_model(mesh.nodes, mesh.elements, np.zeros(6, dtype=int), [lam],
    ...                              fixed_dofs=edge_dofs(mesh, "x0", "clamped"))
    >>> model.n_dof                                   # 9 free nodes x 6
    54
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
    pattern = sparsity_pattern(dofs, free_index, len(free), _dof_kinds([Ku, Mu], 6))
    K, M = pattern.assemble_many([Ku, Mu], rep)
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
