"""Block shift-invert Lanczos for the lowest eigenpairs of ``K phi = lambda M phi``.

The operator is ``OP = (K - sigma M)^-1 M``, self-adjoint in the M inner product, whose
largest eigenvalues ``theta = 1 / (lambda - sigma)`` are the wanted ones. A block of
``b`` vectors is applied at once, so every step is one factorisation solve with ``b``
right-hand sides (the sparse triangular sweeps then run over the factor once per block
instead of once per vector; measured per-vector costs in docs/guide/fe.md), and the
basis is kept fully M-orthogonal (classical block Gram-Schmidt, twice), so the
projected matrix is exact and no spurious copies appear. No restart: the basis grows
by ``b`` vectors per step up to ``max_basis``; for the lowest modes of shift-inverted
structural problems a few steps suffice.

Convergence: a Ritz pair ``(theta, x = V y)`` of the block Krylov space has the
residual ``OP x - theta x = V_{j+1} R_j y_j`` (the last block of ``y`` times the
coefficient of the newest block), whose M-norm is ``||R_j y_j||``; the pair is accepted
when it is below ``tol |theta|``. The eigenvalue error of the Rayleigh quotient is then
of order ``tol^2 |theta| / gap`` (relative to the spectrum of OP), far below ``tol``.

A block method finds up to ``b`` copies of a repeated eigenvalue from a random start
block (single-vector Lanczos only through round-off); :func:`mvtk.fe.eigsh_lowest`
still makes its Sturm count on clusters. When the Krylov space reaches an invariant
subspace (exact repeated eigenvalues of small or symmetric models, or the whole range
of OP when M is singular), the lost directions are replaced by pseudo-random ones, as
ARPACK does, so a start that misses a wanted eigenvector does not end the search.

This is the default eigen solver of :func:`mvtk.fe.eigsh_lowest` (block width
:data:`mvtk.fe._solvers.BLOCK_SIZE`, measured there).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import ConvergenceError

__all__ = ["block_lanczos"]


def _m_orthonormalize(W, MW, floor: float = 0.0):
    """M-orthonormal basis of ``W`` (Cholesky QR; rank-deficient directions, an
    invariant subspace reached, are dropped, as are directions of M-norm below
    ``floor``). Returns ``(V, MV, R)`` with ``W = V R`` (``R`` upper triangular, or with
    fewer rows than columns when directions are dropped)."""
    G = _gemm(1.0, W, MW, trans_a=True)
    G = 0.5 * (G + G.T)
    if not np.all(np.isfinite(G)):
        raise ConvergenceError(
            "block Lanczos: the basis is not finite (the solves returned inf or NaN: is "
            "the shifted matrix singular?)")
    try:
        R = sla.cholesky(G, lower=False, check_finite=False)
        dr = np.abs(np.diag(R))
        if np.min(dr) > max(1e-10 * np.max(dr), floor):
            Rinv = sla.solve_triangular(R, np.eye(R.shape[0]), lower=False,
                                        check_finite=False)
            return _gemm(1.0, W, Rinv), _gemm(1.0, MW, Rinv), R
    except np.linalg.LinAlgError:
        pass
    # rank-deficient: eigen-decomposition of the Gram matrix
    d, Q = np.linalg.eigh(G)
    keep = d > max(1e-20 * max(d.max(), 1e-300), floor**2)
    V = (W @ Q[:, keep]) / np.sqrt(d[keep])
    MV = (MW @ Q[:, keep]) / np.sqrt(d[keep])
    R = np.sqrt(d[keep])[:, None] * Q[:, keep].T
    return V, MV, R


def block_lanczos(solve, M, n: int, start: np.ndarray, tol: float, max_basis: int,
                  seed: int = 0):
    """Largest ``n`` eigenpairs of ``OP = solve(M .)`` by block Lanczos (see module).

    Parameters
    ----------
    solve : callable
        ``solve(B)`` returns ``(K - sigma M)^-1 B`` for ``B`` of shape (n_dof, b).
    M : sparse matrix (n_dof, n_dof)
    n : int
        Number of eigenpairs wanted.
    start : ndarray (n_dof, b)
        Start block (deterministic; its width is the block size).
    tol : float
        Relative residual accepted (see module docstring); > 0.
    max_basis : int
        Largest basis size before :class:`~mvtk.errors.ConvergenceError`.
    seed : int
        Seed of the pseudo-random vectors that replace the directions a block loses when
        the Krylov space reaches an invariant subspace (deterministic).

    Returns
    -------
    theta : ndarray (n,)
        Ritz values of OP, descending.
    X : ndarray (n_dof, n)
        M-orthonormal Ritz vectors.
    n_steps : int
        Block solves made (including the one applied to the start block).

    Notes
    -----
    The basis ``V`` and ``M V`` are kept in preallocated Fortran-ordered arrays (grown
    by doubling), so a step costs one block solve, one product of ``M`` with the block
    and two passes of classical Gram-Schmidt against the basis (BLAS dgemv per column
    of the block: OpenBLAS' dgemm was 1.1-3x slower on 2 columns). When the new
    block loses directions (an invariant subspace: e.g. every copy of a repeated
    eigenvalue in the start block's span already found), pseudo-random directions in
    the range of OP, M-orthogonal to the basis, take their place, as ARPACK does, and
    convergence is not tested on that step (a Ritz pair of an invariant subspace has a
    zero residual but may not be among the largest).
    """
    ndof, b = start.shape
    # start in the range of OP (as ARPACK's mode 3 does): components in the null space
    # of a singular M would otherwise ride along in the Ritz vectors
    W = np.asfortranarray(solve(_mprod(M, start)))
    V0, MV0, _ = _m_orthonormalize(W, _mprod(M, W))
    cap = min(ndof, max_basis + b, max(4 * n + 4 * b, 32))
    V = np.empty((ndof, cap), order="F")
    MV = np.empty((ndof, cap), order="F")
    T = np.zeros((cap, cap))
    m = V0.shape[1]
    V[:, :m], MV[:, :m] = V0, MV0
    lo = prev = 0                        # current block: columns lo:m, previous prev:lo
    n_steps = 1
    rng = np.random.default_rng(seed + 1)
    while True:
        W = np.asfortranarray(solve(np.ascontiguousarray(MV[:, lo:m])))
        n_steps += 1
        Vm, MVm = V[:, :m], MV[:, :m]
        # block Gram-Schmidt as BLAS calls on the Fortran-ordered basis (numpy's V @ C
        # was 3-4x slower on it; see _gemm): first against the current and the previous block (the
        # three-term recurrence: in exact arithmetic W is M-orthogonal to the older
        # ones), then against the whole basis (full reorthogonalisation, which removes
        # what round-off left on the older blocks); half the passes over the basis of
        # classical Gram-Schmidt twice, and the same projected matrix to round-off
        C = np.zeros((m, W.shape[1]))
        C[prev:m] = _gemm(1.0, MV[:, prev:m], W, trans_a=True)
        W = _gemm(-1.0, V[:, prev:m], C[prev:m], beta=1.0, c=W)
        C2 = _gemm(1.0, MVm, W, trans_a=True)
        W = _gemm(-1.0, Vm, C2, beta=1.0, c=W)
        C += C2
        # a direction whose M-norm fell below 1e-10 of the block's norm before the
        # orthogonalisation (|w|^2 = |w_orth|^2 + |C|^2) is in the basis' span: lost
        MW = _mprod(M, W)
        before = np.sqrt(np.einsum("ij,ij->j", W, MW) + np.einsum("ij,ij->j", C, C))
        Vn, MVn, R = _m_orthonormalize(W, MW, floor=1e-10 * float(np.max(before)))
        r = Vn.shape[1]
        T[:m, lo:m] = C
        # projected matrix on span(V[:, :m]), symmetrised
        Tm = 0.5 * (T[:m, :m] + T[:m, :m].T)
        theta, Y = np.linalg.eigh(Tm)
        theta, Y = theta[::-1], Y[:, ::-1]
        # residual norms: R (rows for the new block) times the block lo:m of y
        nn = min(n, m)
        res = (np.linalg.norm(R[:r] @ Y[lo:m, :nn], axis=0) if r else np.zeros(nn))
        lost = r < m - lo
        if m >= n and not (lost and m < ndof) and np.all(res <= tol * np.abs(theta[:n])):
            return theta[:n], _gemm(1.0, Vm, np.asfortranarray(Y[:, :n])), n_steps
        if lost and m + r < ndof:
            # invariant subspace reached in some directions: continue with pseudo-random
            # ones in the range of OP, M-orthogonal to the basis and to the new block
            k = min(m - lo - r, ndof - m - r)
            Z = np.asfortranarray(solve(_mprod(M, rng.standard_normal((ndof, k)))))
            n_steps += 1
            znorm = np.sqrt(np.abs(np.einsum("ij,ij->j", Z, _mprod(M, Z))))
            basis = np.hstack([Vm, Vn]) if r else Vm
            mbasis = np.hstack([MVm, MVn]) if r else MVm
            for _ in range(2):
                Z -= basis @ (mbasis.T @ Z)
            # none left when the basis spans the range of OP (singular M: its rank)
            Vz, MVz, _ = _m_orthonormalize(Z, _mprod(M, Z),
                                           floor=1e-10 * float(np.max(znorm)))
            Vn, MVn = np.hstack([Vn, Vz]), np.hstack([MVn, MVz])
        if m + Vn.shape[1] > max_basis or Vn.shape[1] == 0:
            if m >= n and Vn.shape[1] == 0:      # the whole space: exact
                return theta[:n], _gemm(1.0, Vm, np.asfortranarray(Y[:, :n])), n_steps
            raise ConvergenceError(
                f"block Lanczos: {int(np.sum(res[:n] > tol * np.abs(theta[:n])))} of {n} "
                f"eigenpairs not converged with a basis of {m} vectors")
        mn = m + Vn.shape[1]
        if mn > cap:
            cap = min(ndof, max_basis + b, max(2 * cap, mn))
            V, MV = _grow(V, cap), _grow(MV, cap)
            T2 = np.zeros((cap, cap))
            T2[:m, :m] = T[:m, :m]
            T = T2
        T[m:m + r, lo:m] = R[:r]
        V[:, m:mn], MV[:, m:mn] = Vn, MVn
        prev, lo, m = lo, m, mn


def _mprod(M, W: np.ndarray) -> np.ndarray:
    """``M @ W`` column by column, Fortran-ordered (scipy's product of a CSR matrix with
    a block of vectors was 2-3x slower than one product per column, measured)."""
    out = np.empty(W.shape, order="F")
    for j in range(W.shape[1]):
        out[:, j] = M @ W[:, j]
    return out


#: Widest ``B`` of :func:`_gemm` multiplied column by column (BLAS dgemv): OpenBLAS'
#: dgemm with 2 columns on one thread ran at 7-12 GB/s over a tall basis, two dgemv
#: at 13-30 GB/s (measured on 49 140 rows and 4-36 basis vectors: 1.1-3x faster).
_GEMV_COLUMNS = 4


def _gemm(alpha: float, A: np.ndarray, B: np.ndarray, trans_a: bool = False,
          beta: float = 0.0, c: np.ndarray | None = None) -> np.ndarray:
    """``alpha op(A) B + beta c`` by BLAS (``A`` and ``c`` Fortran-ordered, ``c``
    overwritten): dgemm, or one dgemv per column when ``B`` is narrow."""
    trans = int(trans_a)
    if B.shape[1] > _GEMV_COLUMNS:
        if c is None:
            return sla.blas.dgemm(alpha, A, B, trans_a=trans)
        return sla.blas.dgemm(alpha, A, B, beta=beta, c=c, trans_a=trans, overwrite_c=1)
    if c is None:
        c, beta = np.empty((A.shape[1] if trans else A.shape[0], B.shape[1]), order="F"), 0.0
    for j in range(B.shape[1]):
        col = c[:, j]
        y = sla.blas.dgemv(alpha, A, B[:, j], beta=beta, y=col, trans=trans, overwrite_y=1)
        if not np.shares_memory(y, col):
            col[...] = y
    return c


def _grow(A: np.ndarray, cap: int) -> np.ndarray:
    """Copy of the Fortran-ordered ``A`` with ``cap`` columns (the first ones kept)."""
    out = np.empty((A.shape[0], cap), order="F")
    out[:, :A.shape[1]] = A
    return out
