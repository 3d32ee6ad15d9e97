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
still makes its Sturm count on clusters.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from ..errors import ConvergenceError

__all__ = ["block_lanczos"]


def _m_orthonormalize(W, MW):
    """M-orthonormal basis of ``W`` (Cholesky QR; rank-deficient directions, an
    invariant subspace reached, are dropped). Returns ``(V, MV, R)`` with ``W = V R``
    (``R`` upper triangular, or with fewer rows than columns when directions are
    dropped)."""
    G = W.T @ MW
    G = 0.5 * (G + G.T)
    try:
        R = sla.cholesky(G, lower=False)
        if np.min(np.abs(np.diag(R))) > 1e-10 * np.max(np.abs(np.diag(R))):
            V = sla.solve_triangular(R, W.T, trans="T", lower=False).T
            MV = sla.solve_triangular(R, MW.T, trans="T", lower=False).T
            return V, MV, R
    except np.linalg.LinAlgError:
        pass
    # rank-deficient: eigen-decomposition of the Gram matrix
    d, Q = np.linalg.eigh(G)
    keep = d > 1e-20 * max(d.max(), 1e-300)
    V = (W @ Q[:, keep]) / np.sqrt(d[keep])
    MV = (MW @ Q[:, keep]) / np.sqrt(d[keep])
    R = np.sqrt(d[keep])[:, None] * Q[:, keep].T
    return V, MV, R


def block_lanczos(solve, M, n: int, start: np.ndarray, tol: float, max_basis: int):
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

    Returns
    -------
    theta : ndarray (n,)
        Ritz values of OP, descending.
    X : ndarray (n_dof, n)
        M-orthonormal Ritz vectors.
    n_steps : int
        Block solves made (including the one applied to the start block).
    """
    # start in the range of OP (as ARPACK's mode 3 does): components in the null space
    # of a singular M would otherwise ride along in the Ritz vectors
    W = solve(M @ start)
    out = _m_orthonormalize(W, M @ W)
    V, MV, _ = out
    blocks_V, blocks_MV = [V], [MV]
    cols: list[np.ndarray] = []         # block columns of T = V' M OP V
    n_steps = 1
    while True:
        Vj, MVj = blocks_V[-1], blocks_MV[-1]
        W = solve(MVj)
        n_steps += 1
        Vall = np.hstack(blocks_V)
        MVall = np.hstack(blocks_MV)
        C = MVall.T @ W
        W = W - Vall @ C
        C2 = MVall.T @ W
        W = W - Vall @ C2
        C = C + C2
        MW = M @ W
        out = _m_orthonormalize(W, MW)
        Vn, MVn, R = out
        m = Vall.shape[1]
        cols.append((C, R[: Vn.shape[1]]))
        # projected matrix on span(Vall): block columns C (rows 0..m), symmetrised
        T = np.zeros((m, m))
        off = 0
        for Cj, Rj in cols[:-1]:
            w = Cj.shape[1]
            T[: Cj.shape[0], off:off + w] = Cj
            T[Cj.shape[0]: Cj.shape[0] + Rj.shape[0], off:off + w] = Rj
            off += w
        T[:, off:] = C
        T = 0.5 * (T + T.T)
        theta, Y = np.linalg.eigh(T)
        theta, Y = theta[::-1], Y[:, ::-1]
        # residual norms: R (rows for the new block) times the last block of y
        last = Y[m - Vj.shape[1]:, :n]
        res = np.linalg.norm(R[: Vn.shape[1]] @ last, axis=0) if Vn.shape[1] else \
            np.zeros(min(n, m))
        if m >= n and np.all(res[:n] <= tol * np.abs(theta[:n])):
            X = Vall @ Y[:, :n]
            return theta[:n], X, n_steps
        if m + Vn.shape[1] > max_basis or Vn.shape[1] == 0:
            if m >= n and Vn.shape[1] == 0:      # invariant subspace: exact
                return theta[:n], Vall @ Y[:, :n], n_steps
            raise ConvergenceError(
                f"block Lanczos: {int(np.sum(res[:n] > tol * np.abs(theta[:n])))} of {n} "
                f"eigenpairs not converged with a basis of {m} vectors")
        blocks_V.append(Vn)
        blocks_MV.append(MVn)
