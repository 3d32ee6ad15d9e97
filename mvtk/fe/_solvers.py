"""Sparse linear and eigen solvers tuned for structural matrices.

See PHYSICS.md section 6: scipy's ``splu`` with its default partial pivoting destroys
the fill-reducing ordering on FE stiffness matrices. For symmetric positive (semi)
definite matrices we factorise with a symmetric fill-reducing ordering and diagonal
pivots:

* ``backend="superlu"`` (default install, BSD): scipy's SuperLU on the matrix permuted
  by a nested-dissection ordering computed by METIS (``pymetis``, MIT/Apache-2.0) on
  the compressed graph (DOFs with identical sparsity rows, i.e. the DOFs of one node,
  are ordered as one vertex). On a 49 140-DOF shell plate this cuts the fill from
  10.3 M (SuperLU's own MMD) to 8.8 M entries, about CHOLMOD's. The ordering is cached
  per sparsity pattern, so model updating and Monte Carlo (new values, same mesh)
  compute it once.
* ``backend="cholmod"`` (optional ``mvtk[cholmod]`` extra, ``sksparse-minimal``):
  SuiteSparse CHOLMOD's supernodal Cholesky, 1.2-2x faster to factorise (measured). Its
  Supernodal module is GPL-2.0-or-later, which is why it is not a default dependency.
  ``backend="auto"`` uses it when installed and when the matrix is positive definite,
  SuperLU otherwise.

BLAS threads are limited (threadpoolctl) around factorisations and eigen solves: the
second OpenBLAS thread made the small dense kernels of sparse triangular solves 2-3x
slower on a loaded 2-core machine.
"""

from __future__ import annotations

import hashlib
import math
import os
import sys
from collections import OrderedDict
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.csgraph  # noqa: F401  (sp.csgraph)
import scipy.sparse.linalg as spla

from .._blas import blas_limits as _blas_limits
from ..errors import ConvergenceError, DimensionError, MissingDependencyError, ParameterError
from ._block_eigen import block_lanczos

__all__ = [
    "factorize",
    "eigsh_lowest",
    "EigenSolution",
    "Factorization",
    "fill_reducing_ordering",
    "estimate_eigen_memory",
    "MemoryEstimate",
    "BACKENDS",
    "sparse_backend",
]

BACKENDS = ("auto", "superlu", "cholmod")
#: Block width of the block Lanczos method of :func:`eigsh_lowest` (the default method).
#: Measured on the 49 140-DOF plate (CHOLMOD, simplicial solves, iteration only, CPU,
#: load 4-5): 10 modes, ARPACK 34 solves 0.99-1.12 s; blocks of 1, 2, 3, 4: 27, 36, 45,
#: 52 vectors, 0.76, 0.75, 0.71-0.82, 0.77-0.85 s; 4 modes: ARPACK 21 solves 0.74 s,
#: blocks of 1, 2: 15, 22 vectors, 0.49, 0.50 s. A block of 2 finds both copies of a
#: double eigenvalue (symmetric structures) without relying on round-off, at the cost of
#: one with single vectors. (With the supernodal solves of the CHOLMOD wheel, before
#: :data:`CHOLMOD_SIMPLICIAL`, a block of k right-hand sides cost 0.7-0.9 of k single
#: solves and the block method lost to ARPACK.) Blocks of 3 for 20 modes, measured:
#: 199 836-DOF plate 31 -> 22 solves and 10-20 % less CPU at load 12-14 (noisy); 499 392-DOF
#: plate at load 2.4, 60 vectors in 30 solves 12.0-13.2 s against 69 in 23 solves
#: 11.9-13.7 s (a solve of 3 right-hand sides costs 1.0-1.2 times one of 2, and the
#: larger basis the rest): no gain, so the width stays 2.
BLOCK_SIZE = 2
#: Default relative eigenvalue tolerance of :func:`eigsh_lowest` (see its docstring).
#: 0 is ARPACK's machine precision. A looser 1e-10 (28 instead of 34-41 solves on the
#: 90 x 90 plate) converged before every copy of a repeated eigenvalue had emerged (the
#: 7-fold 17.709 Hz mode of NAFEMS FV2 came out 6-fold): Lanczos from one start vector
#: finds the copies of a repeated eigenvalue only through round-off, so it must run on.
#: (The block method of the default finds up to :data:`BLOCK_SIZE` copies without
#: round-off; the Sturm check covers the others.)
DEFAULT_TOL = 0.0
#: Solve with CHOLMOD's simplicial form of the factor: after the supernodal
#: factorisation, the factor is converted in place to simplicial LL' (the same entries,
#: copied; ~20 ms on the 49 140-DOF plate, and a transient second copy of the factor).
#: None (default): only when CHOLMOD runs on the reference BLAS its wheel bundles
#: (:func:`mvtk._blas.load_system_blas` found no OpenBLAS), whose supernodal triangular
#: sweeps are slow. Measured on the 49 140-DOF plate, one BLAS thread, per solve of
#: 1 / 2 / 4 right-hand sides: reference BLAS supernodal 27-30 / 40-50 / - ms against
#: simplicial 21 / 26 / 38 ms; OpenBLAS supernodal 14 / 22 / 26 ms (and a factorisation
#: of 0.26 s against 0.41 s with the conversion). On the 1 M-DOF plate both forms solve
#: at the same speed with OpenBLAS (0.49 s for one right-hand side, 0.6-0.7 s for 2).
#: Residuals equal to round-off either way.
CHOLMOD_SIMPLICIAL: bool | None = None


def _simplicial_solves() -> bool:
    if CHOLMOD_SIMPLICIAL is not None:
        return CHOLMOD_SIMPLICIAL
    from .._blas import load_system_blas

    return load_system_blas()[0] is None

_ORDER_CACHE: OrderedDict[bytes, np.ndarray] = OrderedDict()
_ORDER_CACHE_SIZE = 8




def _cholmod_module():
    from .._blas import load_system_blas

    load_system_blas()
    try:
        from sksparse_minimal import SparseCholesky
    except ImportError:
        return None
    return SparseCholesky


def sparse_backend(detail: bool = False) -> str:
    """The factorisation backend :func:`factorize` uses by default in this installation.

    ``"cholmod"`` when ``sksparse-minimal`` (the ``mvtk[cholmod]`` extra) is importable,
    else ``"superlu"``; the environment variable ``MVTK_SPARSE_BACKEND`` overrides it,
    as in :func:`factorize`. (``"auto"`` still uses SuperLU for a matrix CHOLMOD cannot
    factorise: indefinite, or singular without a shift.) Timings and reports name it,
    because the two differ in speed (CHOLMOD's factorisation 1.2-2x faster, measured).

    Parameters
    ----------
    detail : bool, default False
        Also name the library versions and, for SuperLU, the fill-reducing ordering,
        e.g. ``"superlu (scipy 1.17.1, METIS ordering: pymetis 2025.2)"``.

    Returns
    -------
    str

    Examples
    --------
    >>> sparse_backend() in ("superlu", "cholmod")
    True
    """
    env = os.environ.get("MVTK_SPARSE_BACKEND", "auto")
    if env not in BACKENDS:
        raise ParameterError(
            f"environment variable MVTK_SPARSE_BACKEND must be one of {BACKENDS}, got {env!r}")
    chol = _cholmod_module() if env in ("auto", "cholmod") else None
    name = "cholmod" if chol is not None else "superlu"
    if not detail:
        return name
    from importlib import metadata

    def version(dist: str) -> str:
        try:
            return metadata.version(dist)
        except metadata.PackageNotFoundError:
            return "unknown version"

    if name == "cholmod":
        from .._blas import load_system_blas

        return (f"cholmod (SuiteSparse CHOLMOD via sksparse-minimal "
                f"{version('sksparse-minimal')}; BLAS: {load_system_blas()[1]})")
    try:
        import pymetis  # noqa: F401  (availability check)
    except ImportError:
        ordering = "MMD ordering"
    else:
        ordering = f"METIS ordering: pymetis {version('pymetis')}"
    return f"superlu (scipy {version('scipy')}, {ordering})"


def _pattern_key(A: sp.csc_matrix) -> bytes:
    h = hashlib.blake2b(digest_size=20)
    h.update(np.array(A.shape, dtype=np.int64).tobytes())
    h.update(str(A.indices.dtype).encode())
    h.update(np.ascontiguousarray(A.indptr).tobytes())
    h.update(np.ascontiguousarray(A.indices).tobytes())
    return h.digest()


def fill_reducing_ordering(A, method: str = "auto") -> np.ndarray | None:
    """Symmetric fill-reducing permutation ``p`` (factorise ``A[p][:, p]``).

    Parameters
    ----------
    A : sparse matrix (n, n)
        Structurally symmetric; only its pattern is used.
    method : {"auto", "metis", "mmd"}
        ``"metis"``: METIS nested dissection (``pymetis``) on the graph compressed to
        supervariables (columns with identical patterns, i.e. the DOFs of a node), which
        keeps node DOFs together. ``"mmd"``: return None (SuperLU orders the matrix itself
        with multiple minimum degree on A'+A). ``"auto"``: METIS when ``pymetis`` is
        importable, else MMD.

    Returns
    -------
    ndarray of int or None
        Cached per sparsity pattern.

    Examples
    --------
    The permutation is None (SuperLU's own ordering) or a permutation of the rows:

    >>> import scipy.sparse as sp
    >>> K = sp.diags([-np.ones(49), 2 * np.ones(50), -np.ones(49)], [-1, 0, 1], format="csc")
    >>> p = fill_reducing_ordering(K)
    >>> p is None or sorted(p) == list(range(50))
    True
    """
    if method not in ("auto", "metis", "mmd"):
        raise ParameterError(f"ordering must be 'auto', 'metis' or 'mmd', got {method!r}")
    if method == "mmd":
        return None
    try:
        import pymetis  # noqa: F401  (availability check)
    except ImportError as err:
        if method == "metis":
            raise MissingDependencyError(
                "METIS ordering needs pymetis, which is not installed; install it with: "
                "pip install pymetis"
            ) from err
        return None
    A = sp.csc_matrix(A)
    n = A.shape[0]
    if n < 64:
        return None
    key = _pattern_key(A)
    perm = _ORDER_CACHE.get(key)
    if perm is not None:
        _ORDER_CACHE.move_to_end(key)
        return perm
    members, gptr, _, seq = _node_ordering(A)
    perm = _group_perm(members, gptr, seq)
    _ORDER_CACHE[key] = perm
    while len(_ORDER_CACHE) > _ORDER_CACHE_SIZE:
        _ORDER_CACHE.popitem(last=False)
    return perm


def _pattern_groups(A: sp.csc_matrix) -> tuple[np.ndarray, np.ndarray]:
    """Columns with identical row patterns (supervariables: the DOFs of a node, or once
    the stored zeros of uncoupled DOF pairs are dropped, the membrane and the bending
    DOFs of a flat-shell node), consecutive or not.

    Returns
    -------
    members : ndarray of int (n,)
        Columns sorted by group, ascending within a group; groups are numbered in the
        order of their first column.
    gptr : ndarray of int (n_groups + 1,)
        Group ``g`` is ``members[gptr[g]:gptr[g + 1]]``.
    """
    n = A.shape[0]
    indptr = A.indptr.astype(np.int64)
    length = np.diff(indptr)
    rng = np.random.default_rng(20261201)
    w1 = rng.integers(1, 2**62, size=n, dtype=np.int64).astype(np.uint64)
    w2 = rng.integers(1, 2**62, size=n, dtype=np.int64).astype(np.uint64)
    h1 = np.zeros(n, dtype=np.uint64)
    h2 = np.zeros(n, dtype=np.uint64)
    nz = length > 0
    if A.nnz:
        starts = indptr[:-1][nz]
        with np.errstate(over="ignore"):
            h1[nz] = np.add.reduceat(w1[A.indices], starts)
            h2[nz] = np.add.reduceat(w2[A.indices], starts)
    order = np.lexsort((np.arange(n), h2, h1, length))
    new = np.r_[True, (np.diff(length[order]) != 0) | (np.diff(h1[order]) != 0)
                | (np.diff(h2[order]) != 0)]
    gid = np.empty(n, dtype=np.int64)
    gid[order] = np.cumsum(new) - 1
    # exact check against the group's first column (a hash collision splits the group)
    rep = order[new][gid]
    ln = length
    pos = _ranges(indptr[:-1], indptr[1:])
    pos_rep = _ranges(indptr[rep], indptr[rep] + ln)
    bad = np.bincount(np.repeat(np.arange(n), ln),
                      weights=A.indices[pos] != A.indices[pos_rep], minlength=n) > 0
    if np.any(bad):
        gid[bad] = gid.max() + 1 + np.arange(int(bad.sum()))
    # number the groups by their first column
    _, first_col = np.unique(gid, return_index=True)
    rank = np.empty(len(first_col), dtype=np.int64)
    rank[np.argsort(first_col, kind="stable")] = np.arange(len(first_col))
    g = rank[np.searchsorted(np.unique(gid), gid)]
    members = np.lexsort((np.arange(n), g))
    gptr = np.r_[0, np.cumsum(np.bincount(g, minlength=len(first_col)))]
    return members, gptr


def _node_ordering(A: sp.csc_matrix):
    """METIS nested dissection of the graph compressed to supervariables (needs pymetis).

    Returns
    -------
    members, gptr : ndarray of int
        Supervariables (see :func:`_pattern_groups`).
    G : scipy.sparse.csr_matrix
        Compressed graph (no diagonal).
    seq : ndarray of int
        Elimination order of the supervariables.
    """
    import pymetis

    members, gptr = _pattern_groups(A)
    ng = len(gptr) - 1
    group = np.empty(A.shape[0], dtype=np.int64)
    group[members] = np.repeat(np.arange(ng), np.diff(gptr))
    first = members[gptr[:-1]]
    # adjacency of the compressed graph: groups of the rows of each group's first column
    cols = np.repeat(np.arange(ng), np.diff(A.indptr)[first])
    rows = group[A.indices[_ranges(A.indptr[first].astype(np.int64),
                                   A.indptr[first + 1].astype(np.int64))]]
    G = sp.csr_matrix((np.ones(len(rows), dtype=np.int8), (cols, rows)), shape=(ng, ng))
    G = G.maximum(G.T).tocsr()
    G.setdiag(0)
    G.eliminate_zeros()
    # METIS_NodeND: row k of the permuted matrix is row seq[k] of the original
    if ng < 2 or G.nnz == 0:
        return members, gptr, G, np.arange(ng, dtype=np.int64)
    seq, _ = pymetis.nested_dissection(adjacency=pymetis.CSRAdjacency(G.indptr, G.indices))
    return members, gptr, G, np.asarray(seq, dtype=np.int64)


def _group_perm(members, gptr, seq) -> np.ndarray:
    """DOF permutation listing the members of groups ``seq`` in turn."""
    return members[_ranges(gptr[seq], gptr[seq + 1])]


def _ranges(start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(start[i], stop[i])``."""
    ln = stop - start
    return np.repeat(start - np.r_[0, np.cumsum(ln)[:-1]], ln) + np.arange(int(ln.sum()))


class Factorization:
    """Factorisation of a sparse symmetric matrix ``A``, returned by :func:`factorize`.

    Attributes
    ----------
    backend : str
        ``"superlu"`` or ``"cholmod"``.
    shape : tuple
    nnz_factor, nnz_storage : int or None
        Nonzero entries of L and U, and entries SuperLU stores (None for CHOLMOD,
        whose minimal binding does not report them).
    perm : ndarray or None
        Symmetric permutation applied before SuperLU (None: SuperLU's own ordering).
    n_solves : int
        Number of right-hand sides solved so far.

    Examples
    --------
    Returned by :func:`factorize`; ``solve`` takes a vector or a matrix of right-hand sides:

    >>> import scipy.sparse as sp
    >>> K = sp.diags([-np.ones(49), 2 * np.ones(50), -np.ones(49)], [-1, 0, 1], format="csc")
    >>> fac = factorize(K)
    >>> fac.solve(np.ones((50, 2))).shape, fac.shape
    ((50, 2), (50, 50))
    """

    def __init__(self, backend: str, shape, solver, perm=None, lu=None):
        self.backend = backend
        self.shape = shape
        self._solver = solver
        self.perm = perm
        self._lu = lu
        self.n_solves = 0

    @property
    def nnz_factor(self) -> int | None:
        """Numerically nonzero entries of L and U (SuperLU only; builds both: slow)."""
        if self._lu is None:
            return None
        return int(self._lu.L.nnz + self._lu.U.nnz)

    @property
    def nnz_storage(self) -> int | None:
        """Entries stored by SuperLU (supernodal L and U, with zeros inside blocks)."""
        if self._lu is None:
            return None
        return int(self._lu.nnz)

    @property
    def L(self):
        """SuperLU's unit lower factor (of the permuted matrix); SuperLU backend only."""
        if self._lu is None:
            raise AttributeError("the CHOLMOD backend does not expose its factor")
        return self._lu.L

    @property
    def U(self):
        """SuperLU's upper factor (of the permuted matrix); SuperLU backend only."""
        if self._lu is None:
            raise AttributeError("the CHOLMOD backend does not expose its factor")
        return self._lu.U

    def solve(self, b: np.ndarray) -> np.ndarray:
        """``A^-1 b`` for ``b`` of shape (n,) or (n, k)."""
        b = np.asarray(b, dtype=float)
        if b.shape[:1] != self.shape[:1] or b.ndim > 2:
            raise DimensionError(
                f"right-hand side must have shape ({self.shape[0]},) or "
                f"({self.shape[0]}, k), got {b.shape}"
            )
        self.n_solves += 1 if b.ndim == 1 else b.shape[1]
        with _blas_limits():
            return self._solver(b)


def _permute(A: sp.csc_matrix, perm: np.ndarray) -> sp.csc_matrix:
    """``A[perm][:, perm]`` for a CSC matrix, without scipy's two fancy-index copies."""
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(perm))
    length = np.diff(A.indptr)[perm]
    indptr = np.zeros(len(perm) + 1, dtype=np.int64)
    np.cumsum(length, out=indptr[1:])
    take = _ranges(A.indptr[perm].astype(np.int64), A.indptr[perm + 1].astype(np.int64))
    itype = A.indices.dtype
    Ap = sp.csc_matrix((A.data[take], inv[A.indices[take]].astype(itype),
                        indptr.astype(itype)), shape=A.shape)
    Ap.sort_indices()
    return Ap


def _drop_uncoupled(A: sp.csc_matrix) -> sp.csc_matrix:
    """``A`` without the stored zeros between DOF kinds that never couple.

    Assembled shell matrices store the zero coupling of DOF pairs that do not interact
    (membrane and bending DOFs of a flat shell): 55 % of the entries of a flat plate's
    K. Left in, they double the fill and quadruple the flops of every backend (CHOLMOD:
    2.7 s of CPU for the 49 140-DOF plate with them, 0.7-1.1 s without). A DOF's kind
    is its position within its supervariable (consecutive columns with identical
    stored pattern: a node) and the supervariable's size; kinds are joined when any
    nonzero entry links them, and entries between kinds of different joined classes
    (all zero, by construction) are dropped. Zeros inside a class (e.g. couplings that
    vanish by the symmetry of a regular mesh) are kept, so the pattern depends on the
    mesh, not on the values.
    """
    if A.nnz == 0 or np.all(A.data != 0):
        return A
    n = A.shape[0]
    # groups of consecutive columns with the same stored pattern, told by its length
    # and its first and last row (columns of different patterns with the same three
    # can only merge two groups, which keeps more entries: the entries dropped below
    # are zero whatever the grouping)
    length = np.diff(A.indptr)
    nzc = length > 0
    lo = np.full(n, -1, dtype=np.int64)
    hi = np.full(n, -1, dtype=np.int64)
    lo[nzc] = A.indices[A.indptr[:-1][nzc]]
    hi[nzc] = A.indices[A.indptr[1:][nzc] - 1]
    new = np.r_[True, (length[1:] != length[:-1]) | (lo[1:] != lo[:-1])
                | (hi[1:] != hi[:-1])]
    group = np.cumsum(new) - 1
    first = np.flatnonzero(new)[group]             # first column of each column's group
    size = np.bincount(group)[group]
    pos = np.arange(n) - first
    kinds, kind = np.unique(size * 64 + np.minimum(pos, 63), return_inverse=True)
    nk = len(kinds)
    if nk < 2:
        return A
    kind = kind.ravel().astype(np.int32 if nk * nk < 2**31 else np.int64)
    # the kind pair (row kind, column kind) of every entry
    pair = kind[A.indices]
    pair *= nk
    pair += np.repeat(kind, length)
    # kind pairs linked by a nonzero entry
    link = np.bincount(pair[A.data != 0], minlength=nk * nk).reshape(nk, nk) > 0
    _, comp = sp.csgraph.connected_components(sp.csr_matrix(link | link.T),
                                              directed=False)
    same = (comp[:, None] == comp[None, :]).ravel()
    if np.all(same):
        return A
    keep = same[pair]
    if keep.all():              # already without them (an assembly that left them out)
        return A
    take = np.flatnonzero(keep)
    # entries kept before each column's start: the new column pointers
    indptr = np.searchsorted(take, A.indptr)
    out = sp.csc_matrix((A.data[take], A.indices[take], indptr.astype(A.indptr.dtype)),
                        shape=A.shape)
    out.has_sorted_indices = True
    return out


def _superlu(A: sp.csc_matrix, perm):
    Ap = A if perm is None else _permute(A, perm)
    lu = spla.splu(
        Ap,
        permc_spec="MMD_AT_PLUS_A" if perm is None else "NATURAL",
        diag_pivot_thresh=0.0,
        options={"SymmetricMode": True},
    )
    if perm is None:
        return lu.solve, lu
    inv = np.empty_like(perm)
    inv[perm] = np.arange(len(perm))

    def solve(b):
        # np.take along rows: 3-8x faster than b[perm] on a block of right-hand sides
        # (numpy's general fancy-index path), measured on the 49 140-DOF plate
        x = lu.solve(np.take(b, perm, axis=0))
        return np.take(x, inv, axis=0)

    return solve, lu


def factorize(A, backend: str = "auto", ordering: str = "auto") -> Factorization:
    """Factorisation of a sparse symmetric matrix with a symmetric fill-reducing ordering.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        Symmetric, typically a stiffness matrix or ``K - sigma M``.
    backend : {"auto", "superlu", "cholmod"}
        ``"superlu"``: scipy's SuperLU (LU with diagonal pivots, symmetric mode) on the
        matrix reordered by :func:`fill_reducing_ordering`. ``"cholmod"``: CHOLMOD
        supernodal Cholesky (``pip install "mvtk[cholmod]"``; GPL component), positive
        definite matrices only. ``"auto"``: CHOLMOD when installed and the matrix is
        positive definite, SuperLU otherwise. The environment variable
        ``MVTK_SPARSE_BACKEND`` (one of these names) overrides ``"auto"``.
    ordering : {"auto", "metis", "mmd"}
        Ordering for SuperLU (see :func:`fill_reducing_ordering`); CHOLMOD orders itself.

    Returns
    -------
    Factorization
        Use ``.solve(b)``.

    Raises
    ------
    ParameterError
        If the matrix is singular (e.g. an unconstrained structure without a shift), or
        not positive definite with ``backend="cholmod"``.
    MissingDependencyError
        ``backend="cholmod"`` without ``sksparse-minimal`` installed.

    Notes
    -----
    Before factorising, the stored zeros between DOF kinds that never couple (the
    membrane and bending DOFs of a flat shell) are dropped (:func:`_drop_uncoupled`):
    on a flat plate this halves the factor and quarters its flops, for every backend.

    Examples
    --------
    Solve ``K x = 1`` for the fixed-fixed chain of 50 unit springs; closed form
    ``x_i = i (51 - i) / 2``:

    >>> import scipy.sparse as sp
    >>> K = sp.diags([-np.ones(49), 2 * np.ones(50), -np.ones(49)], [-1, 0, 1], format="csc")
    >>> fac = factorize(K)
    >>> np.round(fac.solve(np.ones(50))[:3], 9)
    array([25., 49., 72.])
    """
    if backend not in BACKENDS:
        raise ParameterError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if backend == "auto":
        env = os.environ.get("MVTK_SPARSE_BACKEND", "auto")
        if env not in BACKENDS:
            raise ParameterError(
                f"environment variable MVTK_SPARSE_BACKEND must be one of {BACKENDS}, "
                f"got {env!r}")
        backend = env
    if sp.issparse(A) and A.format == "csr":
        # the stored zeros are dropped first (on the transpose's CSC arrays, the same
        # as A's CSR arrays: no copy), so that only the kept entries are transposed
        if A.shape[0] != A.shape[1]:
            raise DimensionError(f"matrix must be square, got {A.shape}")
        At = A.T
        if not At.has_sorted_indices:
            At = At.sorted_indices()
        A = _drop_uncoupled(At).T.tocsc()
        if not A.has_sorted_indices:
            A = A.sorted_indices()
    else:
        A = sp.csc_matrix(A)
        if A.shape[0] != A.shape[1]:
            raise DimensionError(f"matrix must be square, got {A.shape}")
        if not A.has_sorted_indices:
            A = A.sorted_indices()
        A = _drop_uncoupled(A)
    chol = _cholmod_module() if backend in ("auto", "cholmod") else None
    if backend == "cholmod" and chol is None:
        raise MissingDependencyError(
            "backend='cholmod' needs sksparse-minimal, which is not installed; install it "
            'with: pip install "mvtk[cholmod]"'
        )
    singular = (
        f"matrix of size {A.shape[0]} is singular: is the structure under-constrained "
        "(rigid-body modes) or an element degenerate?"
    )
    with _blas_limits():
        if chol is not None and A.shape[0] > 1 and _positive_diagonal(A):
            try:
                with _quiet_c_output():
                    f = chol(A)
            except ValueError as err:   # "Matrix is not positive definite!"
                if backend == "cholmod":
                    raise ParameterError(
                        f"matrix of size {A.shape[0]} is not positive definite "
                        "(CHOLMOD): " + singular) from err
            else:
                if _simplicial_solves():
                    _to_simplicial(f)
                # CHOLMOD may factorise a singular matrix with a round-off pivot; a solve
                # round trip tells (then SuperLU decides, with its exact-zero pivots)
                x0 = np.random.default_rng(1).standard_normal(A.shape[0])
                x = f.solve_A(A @ x0)
                if np.all(np.isfinite(x)) and (
                        np.linalg.norm(x - x0) <= 1e-2 * np.linalg.norm(x0)):
                    # CHOLMOD's binding takes C-ordered right-hand sides only
                    return Factorization(
                        "cholmod", A.shape,
                        lambda b: f.solve_A(np.ascontiguousarray(b)))
                if backend == "cholmod":
                    raise ParameterError(singular)
        elif backend == "cholmod":
            raise ParameterError(
                f"matrix of size {A.shape[0]} has a non-positive diagonal entry: not "
                "positive definite (singular or indefinite), CHOLMOD cannot factorise it")
        perm = fill_reducing_ordering(A, ordering)
        try:
            solve, lu = _superlu(A, perm)
        except RuntimeError as err:
            raise ParameterError(singular) from err
    return Factorization("superlu", A.shape, solve, perm=perm, lu=lu)


def _to_simplicial(f) -> None:
    """Convert a CHOLMOD supernodal LL' factor to simplicial LL' in place (a copy of
    the same entries, no arithmetic; see :data:`CHOLMOD_SIMPLICIAL`). A binding
    without ``change_factor`` keeps the supernodal factor."""
    solver = getattr(f, "_solver", None)
    if solver is None or not hasattr(solver, "change_factor"):
        return
    if solver.is_super():
        solver.change_factor(1, 0)


@contextmanager
def _quiet_c_output():
    """Silence the C library's stdout/stderr (CHOLMOD prints "not positive definite"
    warnings with printf, which would corrupt a CLI's output)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = []
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
    except OSError:
        yield
        return
    try:
        for fd in (1, 2):
            try:
                saved.append((fd, os.dup(fd)))
                os.dup2(devnull, fd)
            except OSError:
                pass
        yield
    finally:
        for fd, copy in saved:
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)


def _positive_diagonal(A) -> bool:
    d = A.diagonal()
    return bool(np.all(d > 0))


def _default_shift(K, M, singular_shift=None, backend="auto") -> tuple[float, Factorization | None]:
    """Shift for :func:`eigsh_lowest`: 0 if K is safely invertible, else slightly negative.

    Returns the shift and, when it is 0, the factorisation of K (to be reused).
    """
    x0 = np.random.default_rng(0).standard_normal(K.shape[0])
    try:
        lu = factorize(K, backend=backend)
        if lu.backend == "cholmod":
            return 0.0, lu    # factorize made the same round trip check already
        x = lu.solve(K @ x0)
        lu.n_solves = 0
        # a singular K (rigid-body modes) factorises with round-off pivots, whose
        # inverse amplifies the round-off of K x0 along the null space to O(|x0|)
        if np.all(np.isfinite(x)) and np.linalg.norm(x - x0) <= 1e-2 * np.linalg.norm(x0):
            return 0.0, lu
    except ParameterError:
        pass
    if callable(singular_shift):
        singular_shift = singular_shift()
    if singular_shift is not None and np.isfinite(singular_shift):
        return float(singular_shift), None
    mdiag = M.diagonal()
    ratio = K.diagonal()[mdiag > 0] / mdiag[mdiag > 0]
    ratio = ratio[ratio > 0]
    if ratio.size == 0:
        raise ParameterError("K has no positive diagonal entry with mass: cannot pick a shift")
    # The shift only has to make K - sigma M invertible; the closer it is to zero, the
    # better the rigid-body modes separate from the elastic ones in shift-invert. A
    # shift of -(2 pi 0.5 Hz)^2 works for lab structures (tested down to cond(K) ~ 1e16);
    # min_i K_ii/M_ii bounds the lowest elastic eigenvalue from above (Rayleigh quotient
    # of a unit vector), which caps the shift for very soft models.
    return -min((2.0 * np.pi * 0.5) ** 2, 1e-4 * float(ratio.min())), None


@dataclass(frozen=True)
class EigenSolution:
    """Lowest eigenpairs of ``K phi = omega^2 M phi``.

    Attributes
    ----------
    omega2 : ndarray, shape (n,)
        Eigenvalues omega^2 in (rad/s)^2, ascending.
    vectors : ndarray, shape (n_dof, n)
        Mass-normalised eigenvectors (``phi' M phi = I``).
    n_factorizations : int
        Sparse factorisations made (0 for the dense path).
    n_solves : int
        Solves with the factorisation inside the Lanczos iteration.
    backend : str
        Factorisation backend (``"superlu"``, ``"cholmod"`` or ``"dense"``).
    method : str
        Eigen solver: ``"arpack"``, ``"block"`` (block Lanczos) or ``"dense"``.

    Examples
    --------
    Returned by :func:`eigsh_lowest`, with the work done:

    >>> import scipy.sparse as sp
    >>> K = sp.diags([-np.ones(49), 2 * np.ones(50), -np.ones(49)], [-1, 0, 1], format="csc")
    >>> sol = eigsh_lowest(K, sp.identity(50, format="csc"), 3)
    >>> sol.vectors.shape, sol.n_factorizations
    ((50, 3), 1)
    """

    omega2: np.ndarray
    vectors: np.ndarray
    n_factorizations: int = 0
    n_solves: int = 0
    backend: str = ""
    method: str = ""


def _previous_vectors(ndof: int, v0, M) -> np.ndarray:
    """Previous eigenvectors ``v0`` checked and M-normalised, shape (n_dof, k)."""
    V = np.asarray(v0, dtype=float)
    if V.ndim == 1:
        V = V[:, None]
    if V.ndim != 2 or V.shape[0] != ndof:
        raise DimensionError(
            f"v0 must have shape ({ndof},) or ({ndof}, k) (previous eigenvectors), got "
            f"{np.shape(v0)}"
        )
    if not np.all(np.isfinite(V)):
        raise ParameterError("v0 contains non-finite values")
    norms = np.sqrt(np.abs(np.einsum("ij,ij->j", V, M @ V)))
    norms[norms == 0] = 1.0
    return V / norms


def _start_vector(ndof: int, v0, M) -> np.ndarray:
    """Deterministic Lanczos start vector, or one built from previous eigenvectors.

    Without ``v0``: a fixed pseudo-random vector (seed 0), so the solve count and the
    result do not change from run to run. With previous eigenvectors ``V`` (n_dof, k):
    ``sum_j V_j / ||V_j||_M`` plus 1e-4 of the fixed vector, which keeps a component along
    every mode (a mode of the new model missing from ``V`` is still found; tested).
    """
    base = np.random.default_rng(0).standard_normal(ndof)
    if v0 is None:
        return base
    x = _previous_vectors(ndof, v0, M).sum(axis=1)
    nx = math.sqrt(abs(float(x @ (M @ x)))) or 1.0
    nb = math.sqrt(abs(float(base @ (M @ base)))) or 1.0
    return x / nx + 1e-4 * base / nb


def _start_block(ndof: int, v0, M, width: int, seed: int = 0) -> np.ndarray:
    """Deterministic start block of ``width`` columns (seeded pseudo-random), whose
    first columns are the previous eigenvectors ``v0`` when given (warm start; more
    columns than ``width`` are summed into ``width`` M-normalised groups)."""
    base = np.random.default_rng(seed).standard_normal((ndof, width))
    if v0 is None:
        return base
    V = _previous_vectors(ndof, v0, M)
    if V.shape[1] > width:
        # column j of the block: sum of the previous vectors j, j + width, ...
        V = np.column_stack([V[:, j::width].sum(axis=1) for j in range(width)])
    nb = np.sqrt(np.abs(np.einsum("ij,ij->j", base, M @ base)))
    nb[nb == 0] = 1.0
    out = 1e-4 * base / nb
    out[:, : V.shape[1]] += V
    return out


def eigsh_lowest(
    K, M, n: int, sigma: float | None = None, tol: float | None = None,
    singular_shift: float | None = None, v0: np.ndarray | None = None,
    backend: str = "auto", method: str = "auto", factorization: Factorization | None = None,
) -> EigenSolution:
    """Lowest ``n`` eigenpairs of the generalised symmetric problem by shift-invert.

    One factorisation of ``K - sigma M`` is made and used by a shift-invert Lanczos
    (by default the block Lanczos of :mod:`mvtk.fe._block_eigen`, or ARPACK's
    ``scipy.sparse.linalg.eigsh`` with ``OPinv``), with a deterministic start and
    BLAS threads limited to :data:`mvtk._blas.BLAS_THREADS`. For free-free structures pass a
    negative ``sigma`` (default: a small negative shift scaled to the problem, so
    rigid-body modes are found too).

    Parameters
    ----------
    K, M : sparse matrix, shape (n_dof, n_dof)
    n : int
        Number of eigenpairs wanted (``1 <= n <= n_dof``; a dense solver is used only
        when ``n >= n_dof - 1``, because a dense ``eigh(K, M)`` loses the lowest
        eigenvalues to round-off when M is ill-conditioned, as with the token drilling
        inertia of shells).
    sigma : float, optional
        Shift in (rad/s)^2. By default ``sigma = 0`` when ``K`` is non-singular
        (constrained structures: the fastest and most accurate choice) and a small
        negative shift ``-min((2 pi 0.5 Hz)^2, 1e-4 min_i(K_ii/M_ii))`` when it is
        singular (free-free structures; rigid-body modes then come out near zero).
        Singularity is detected by a solve round trip.
    tol : float, optional
        Relative accuracy requested for the eigenvalues: ARPACK stops when every Ritz
        value ``theta`` of ``(K - sigma M)^-1 M`` has a residual below ``tol |theta|``,
        which bounds the relative error of ``omega2 - sigma`` by ``tol`` (in practice
        the error is quadratic in the residual, far smaller); the block method stops at
        residuals below ``sqrt(tol)`` (see ``method``). Default :data:`DEFAULT_TOL` = 0,
        machine precision: with ARPACK a looser tolerance saves a few solves but can stop
        before every copy of a repeated eigenvalue has emerged.
    singular_shift : float or callable, optional
        Shift to use instead of the default one when K turns out singular (a caller that
        knows the scale of the first elastic mode, e.g. from a trial field, passes it),
        or a function returning it (or None / nan for the default), called only then.
    v0 : ndarray, shape (n_dof,) or (n_dof, k), optional
        Warm start: eigenvectors of a nearby model (model updating, Monte Carlo,
        parameter studies). The Lanczos start vector is built from them (see
        :func:`_start_vector` and :func:`_start_block`), which cuts the number of solves.
    backend : {"auto", "superlu", "cholmod"}
        See :func:`factorize`.
    method : {"auto", "arpack", "block"}
        ``"arpack"``: ARPACK's implicitly restarted Lanczos, one solve per step.
        ``"block"``: block Lanczos of :mod:`mvtk.fe._block_eigen` (:data:`BLOCK_SIZE`
        vectors per solve, full M-orthogonalisation, no restart), accepted when every
        Ritz residual is below ``sqrt(tol)`` (1e-10 for ``tol=0``) relative to its Ritz
        value; the returned Rayleigh quotients are then as accurate as ARPACK's with
        ``tol=0``, at the round-off floor of the factorisation (on the 49 140-DOF plate
        both differ from each other by
        5e-11-6e-10, as ARPACK's own results do between the two backends, 8e-11, and
        between 4 and 10 modes requested, 3e-10).
        ``"auto"``: the block method, which measured faster (see :data:`BLOCK_SIZE`).
        Both keep the Sturm check for missed copies of repeated eigenvalues.
    factorization : Factorization, optional
        A factorisation of ``K - sigma M`` already made (:func:`factorize`; ``sigma`` 0
        when not given), used instead of factorising again (Craig-Bampton reuses the
        one of its interior stiffness). ``n_factorizations`` then counts none for it.

    Returns
    -------
    EigenSolution

    Examples
    --------
    A chain of 50 unit masses and springs fixed at both ends; closed form
    ``omega_k**2 = 2 - 2 cos(k pi / 51)``:

    >>> import scipy.sparse as sp
    >>> n = 50
    >>> K = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csc")
    >>> sol = eigsh_lowest(K, sp.identity(n, format="csc"), 3)
    >>> np.round(sol.omega2, 6)
    array([0.003793, 0.015159, 0.034054])
    >>> np.round(2 - 2 * np.cos(np.arange(1, 4) * np.pi / 51), 6)
    array([0.003793, 0.015159, 0.034054])
    """
    # CSR or CSC: M is only multiplied, K factorised (and converted there)
    K = K if sp.issparse(K) and K.format in ("csr", "csc") else sp.csr_matrix(K)
    M = M if sp.issparse(M) and M.format in ("csr", "csc") else sp.csr_matrix(M)
    ndof = K.shape[0]
    if K.shape != M.shape or K.shape[0] != K.shape[1]:
        raise DimensionError(f"K {K.shape} and M {M.shape} must be square and equal")
    if not 1 <= n <= ndof:
        raise ParameterError(f"number of modes must be in 1..{ndof}, got {n}")
    if tol is None:
        tol = DEFAULT_TOL
    if not (np.isfinite(tol) and 0 <= tol < 1):
        raise ParameterError(f"tol must be in [0, 1), got {tol!r}")
    if method not in ("auto", "arpack", "block"):
        raise ParameterError(f"method must be 'auto', 'arpack' or 'block', got {method!r}")
    n_fact, n_solves, used, used_method = 0, 0, "dense", "dense"
    if n >= ndof - 1:
        import scipy.linalg as sla

        w, v = sla.eigh(K.toarray(), M.toarray())
        w, v = w[:n], v[:, :n]
    else:
        lu, solves0 = factorization, getattr(factorization, "n_solves", 0)
        if lu is not None and sigma is None:
            sigma = 0.0
        if sigma is None:
            sigma, lu = _default_shift(K, M, singular_shift, backend)
            n_fact += 1
        if lu is None:
            lu = factorize(K - sigma * M, backend=backend)
            n_fact += 1
        used = lu.backend
        opinv = spla.LinearOperator((ndof, ndof), matvec=lu.solve, dtype=float)
        # assembled shell matrices store the zeros of uncoupled DOF pairs (membrane and
        # bending of a flat element): drop them for the ~2 n_solves products with M
        if M.nnz and np.count_nonzero(M.data) < 0.9 * M.nnz:
            M = M.copy()
            M.eliminate_zeros()
        if method == "auto":
            method = "block"
        used_method = method
        k = n
        if method == "block":
            width = min(BLOCK_SIZE, max(1, ndof // 4))
            start = _start_block(ndof, v0, M, width)
            # the eigenvalue error of a Ritz pair is about the square of its residual
            res_tol = 1e-10 if tol == 0 else float(np.clip(np.sqrt(tol), 1e-10, 1e-2))
        else:
            start = _start_vector(ndof, v0, M)
        for attempt in range(3):
            if method == "block":
                with _blas_limits():
                    theta, v, _ = block_lanczos(
                        lu.solve, M, k, start, res_tol,
                        max_basis=min(ndof, max(60 * start.shape[1], 8 * k + 40)))
                w = sigma + 1.0 / theta
            else:
                try:
                    with _blas_limits():
                        w, v = spla.eigsh(
                            K, k=k, M=M, sigma=sigma, which="LM", OPinv=opinv, tol=tol,
                            ncv=min(ndof, max(2 * k + 1, 20)), v0=start,
                        )
                except spla.ArpackNoConvergence as err:
                    raise ConvergenceError(
                        f"eigsh did not converge for {k} modes of a {ndof}-DOF model"
                    ) from err
            order = np.argsort(w)
            w, v = w[order], v[:, order]
            missing = _missed_copies(K, M, w[:n], sigma)
            n_fact += missing is not None
            if not missing:
                break
            # Lanczos finds more copies of a repeated eigenvalue than its block width only
            # through round-off: ask for more modes, from another start
            k = min(ndof - 2, k + missing + 2)
            if method == "block":
                start = _start_block(ndof, v[:, :n], M, start.shape[1] + missing,
                                     seed=attempt + 1)
            else:
                start = _start_vector(ndof, None, M) + v[:, :n].sum(axis=1)
        else:
            raise ConvergenceError(
                f"the lowest {n} modes of a {ndof}-DOF model: {missing} copies of a "
                "repeated eigenvalue were still missing after 3 Lanczos runs (Sturm count "
                "of K - tau M); request more modes")
        w, v = w[:n], v[:, :n]
        n_solves = lu.n_solves - solves0
    # mass-normalise explicitly (eigsh returns M-orthonormal vectors already, up to
    # round-off; the dense path does too, but be explicit and fix a sign convention);
    # C-ordered: scipy's sparse product with a block of vectors is 15-30 % faster on
    # rows than on Fortran-ordered columns (measured, 49 140 and 199 836 DOF)
    v = np.array(v, order="C")
    v /= np.sqrt(np.einsum("ij,ij->j", v, M @ v))
    if used != "dense":
        # Rayleigh quotients: their error is quadratic in the eigenvector residual, while
        # the Ritz values of the shift-inverted operator carry the factorisation's
        # round-off (a few 1e-9 on an ill-conditioned shell model, and different for each
        # backend and ordering; the Rayleigh quotients agree across them to 2e-10)
        # ... but only where the quotient refines the Ritz value: with a singular M (massless
        # rotations of springs and links) a Ritz vector may carry components in M's null
        # space that K sees and M does not, and its quotient is then wrong, not refined
        rq = np.einsum("ij,ij->j", v, K @ v)
        close = np.abs(rq - w) <= 1e-6 * np.maximum(np.abs(w), np.abs(w).max() * 1e-12)
        w = np.where(close, rq, w)
        order = np.argsort(w, kind="stable")
        w, v = w[order], v[:, order]
    big = np.argmax(np.abs(v), axis=0)
    v = v * np.sign(v[big, np.arange(v.shape[1])])
    return EigenSolution(omega2=w, vectors=v, n_factorizations=n_fact, n_solves=n_solves,
                         backend=used, method=used_method)


def _cluster_scale(w: np.ndarray, sigma: float) -> np.ndarray:
    """Distance of each eigenvalue from the shift (floored): closeness is judged relative
    to it, as the shift-inverted operator sees the eigenvalues (``1 / (w - sigma)``), so
    the round-off values of rigid-body modes near 0 below a negative shift cluster too."""
    d = np.abs(w - sigma)
    return np.maximum(d, d.max() * 1e-12)


def _clustered(w: np.ndarray, sigma: float = 0.0) -> bool:
    """True when two eigenvalues agree to 1e-6 relative to their distance from the shift
    ``sigma``: a repeated eigenvalue."""
    if w.size < 2:
        return False
    return bool(np.any(np.diff(w) <= 1e-6 * _cluster_scale(w, sigma)[1:]))


def _missed_copies(K, M, w: np.ndarray, sigma: float = 0.0) -> int | None:
    """Eigenvalues of ``(K, M)`` below the highest cluster of ``w`` that Lanczos missed.

    Checked only when ``w`` holds a repeated eigenvalue (a symmetric structure, rigid
    modes: see :func:`_clustered`), the case in which Lanczos can return fewer copies than
    exist (single-vector Lanczos finds them only through round-off, a block of ``b``
    vectors ``b`` of them).
    Sylvester's law of inertia: the number of negative pivots of the symmetric
    factorisation of ``K - tau M`` (SuperLU, diagonal pivots in a symmetric ordering)
    is the number of eigenvalues below ``tau``. ``tau`` is just below the highest
    eigenvalue of ``w`` and its copies (copies beyond the ``n`` requested are not
    missing). Returns None when not checked (no cluster, nothing below the top cluster,
    or ``K - tau M`` singular).
    """
    if not _clustered(w, sigma):
        return None
    scale = _cluster_scale(w, sigma)
    top = w.size - 1
    while top > 0 and w[top] - w[top - 1] <= 1e-6 * scale[top]:
        top -= 1
    if top == 0:
        return None
    tau = float(w[top] - 1e-7 * scale[top])
    try:
        lu = factorize((K - tau * M).tocsc(), backend="superlu")
    except ParameterError:
        return None
    below = int(np.count_nonzero(lu.U.diagonal() < 0))
    return max(below - top, 0)


@dataclass(frozen=True)
class MemoryEstimate:
    """Memory needed by :func:`eigsh_lowest` (bytes), from :func:`estimate_eigen_memory`.

    Attributes
    ----------
    n_dof : int
    nnz_matrix : int
        Stored entries of K (M has the same pattern).
    nnz_factor : int
        Predicted entries stored by SuperLU (``Factorization.nnz_storage``) with the
        METIS ordering: its supernodal L and U including the zeros inside node blocks
        (about twice the numerically nonzero ``nnz_factor`` for a flat shell).
    matrices : int
        Bytes of K and M themselves (CSR), held by the model before the solve.
    solve : int
        Bytes the eigen step adds on top: SuperLU's storage
        (:data:`FACTOR_BYTES_PER_NNZ` per stored entry), two working copies of K
        (CSC and permuted) and the Lanczos basis (with its M-image) and returned
        vectors.
    total : int
        ``matrices + solve``.

    Examples
    --------
    Returned by :func:`estimate_eigen_memory` (bytes):

    >>> import scipy.sparse as sp
    >>> K = sp.diags([-np.ones(49), 2 * np.ones(50), -np.ones(49)], [-1, 0, 1], format="csc")
    >>> est = estimate_eigen_memory(K, 3)
    >>> est.total == est.matrices + est.solve
    True
    """

    n_dof: int
    nnz_matrix: int
    nnz_factor: int
    matrices: int
    solve: int
    total: int

    @property
    def total_gib(self) -> float:
        return self.total / 2**30

    def to_dataframe(self):
        """One row per component (``part``, ``bytes``, ``GiB``)."""
        import pandas as pd

        parts = {"matrices": self.matrices, "solve": self.solve, "total": self.total}
        return pd.DataFrame({"part": list(parts), "bytes": list(parts.values()),
                             "GiB": [v / 2**30 for v in parts.values()]})


#: Bytes per entry stored by SuperLU (8-byte value, 4-byte row index); with the other
#: terms of :class:`MemoryEstimate` this over-predicts the measured resident-memory
#: growth of the eigen step of 22 000- and 49 000-DOF shell plates by 5-15 %.
FACTOR_BYTES_PER_NNZ = 12.0


def estimate_eigen_memory(
    A, n_modes: int, dofs_per_vertex: int | np.ndarray = 1,
) -> MemoryEstimate:
    """Predict the memory of :func:`eigsh_lowest` (SuperLU backend) before running it.

    The fill of the factor is computed exactly for the METIS ordering that
    :func:`factorize` uses, by factorising a diagonally dominant proxy with the pattern
    of the compressed graph (one vertex per group of DOFs with identical sparsity,
    e.g. a node), whose cost is about ``1/b^3`` of the real factorisation for ``b``
    DOFs per vertex; each vertex-level entry stands for a ``b_i x b_j`` block.
    CHOLMOD (``backend="cholmod"``) stores only L and needs about 2/3 of this.

    Parameters
    ----------
    A : sparse matrix
        Either the stiffness matrix (its pattern), with ``dofs_per_vertex=1``, or the
        node adjacency graph of the mesh (an entry per pair of nodes that share an
        element) with ``dofs_per_vertex`` = free DOFs per node, which needs no
        assembly. Both give the same prediction for the same mesh.
    n_modes : int
        Number of modes to be computed.
    dofs_per_vertex : int or ndarray
        DOFs of each vertex of ``A`` (scalar or one value per vertex).

    Returns
    -------
    MemoryEstimate

    Examples
    --------
    Memory of the three lowest modes of a 50-DOF chain, before solving:

    >>> import scipy.sparse as sp
    >>> K = sp.diags([-np.ones(49), 2 * np.ones(50), -np.ones(49)], [-1, 0, 1], format="csc")
    >>> est = estimate_eigen_memory(K, 3)
    >>> est.n_dof, est.nnz_matrix, est.total > 0
    (50, 148, True)
    """
    A = sp.csc_matrix(A)
    if A.shape[0] != A.shape[1]:
        raise DimensionError(f"matrix must be square, got {A.shape}")
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ParameterError(f"n_modes must be a positive integer, got {n_modes!r}")
    nv = A.shape[0]
    size = np.asarray(dofs_per_vertex, dtype=np.int64)
    if size.ndim > 1 or (size.ndim == 1 and len(size) != nv):
        raise DimensionError(
            f"dofs_per_vertex must be a scalar or have shape ({nv},), got {size.shape}")
    size = np.broadcast_to(size, (nv,)).copy()
    if np.any(size < 0):
        raise ParameterError("dofs_per_vertex must be >= 0")
    if np.all(size == 1) and A.nnz:
        # the stored zeros factorize drops (uncoupled DOF kinds) are dropped here too
        A = _drop_uncoupled(A.sorted_indices() if not A.has_sorted_indices else A)
    # structure only, symmetric, with a diagonal
    G = sp.csc_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    G = (G + G.T + sp.eye(nv, format="csc")).tocsc()
    G.sort_indices()
    if np.all(size == 1):
        members, gptr = _pattern_groups(G)
        first = members[gptr[:-1]]
        size = np.diff(gptr)
        G = G[first][:, first].tocsc()
    keep = np.flatnonzero(size > 0)
    if len(keep) < nv:
        G, size = G[keep][:, keep].tocsc(), size[keep]
    n_dof = int(size.sum())
    Gc = G.tocoo()
    nnz_matrix = int(np.sum(size[Gc.row] * size[Gc.col]))
    deg = np.diff(G.indptr)
    proxy = (-G).tocsc()
    proxy.setdiag(deg + 1.0)
    proxy.sort_indices()
    perm = fill_reducing_ordering(proxy, "metis") if G.shape[0] >= 64 else None
    with _blas_limits():
        _, lu = _superlu(proxy, perm)
    s = size if perm is None else size[perm]
    L, U = lu.L.tocoo(), lu.U.tocoo()
    off_l = L.row != L.col
    off_u = U.row != U.col
    nnz_factor = int(np.sum(s[L.row[off_l]] * s[L.col[off_l]])
                     + np.sum(s[U.row[off_u]] * s[U.col[off_u]])
                     + np.sum(s * s + s))
    # the block Lanczos basis and its M-image (first allocation; it grows only when
    # the convergence needs more)
    basis = 2 * min(n_dof, max(4 * n_modes + 4 * BLOCK_SIZE, 32))
    matrices = 2 * (nnz_matrix * 12 + (n_dof + 1) * 4)
    solve = (int(FACTOR_BYTES_PER_NNZ * nnz_factor) + 2 * nnz_matrix * 12
             + (basis + 3 * n_modes + 6) * n_dof * 8)
    return MemoryEstimate(n_dof=n_dof, nnz_matrix=nnz_matrix, nnz_factor=nnz_factor,
                          matrices=matrices, solve=solve, total=matrices + solve)
