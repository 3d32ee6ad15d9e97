"""Sparse linear and eigen solvers tuned for structural matrices.

See PHYSICS.md section 6: scipy's ``splu`` with its default partial pivoting destroys
the fill-reducing ordering on FE stiffness matrices. For symmetric positive (semi)
definite matrices we factorise with a symmetric ordering and diagonal pivots.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..errors import ConvergenceError, DimensionError, ParameterError

__all__ = ["factorize", "eigsh_lowest", "EigenSolution"]


def factorize(A) -> spla.SuperLU:
    """LU factorisation of a sparse symmetric matrix with a symmetric ordering.

    Parameters
    ----------
    A : sparse matrix, shape (n, n)
        Symmetric, typically a stiffness matrix or ``K - sigma M``.

    Returns
    -------
    scipy.sparse.linalg.SuperLU
        Use ``.solve(b)``.

    Raises
    ------
    ParameterError
        If the matrix is singular (e.g. an unconstrained structure without a shift).
    """
    A = sp.csc_matrix(A)
    if A.shape[0] != A.shape[1]:
        raise DimensionError(f"matrix must be square, got {A.shape}")
    try:
        return spla.splu(
            A,
            permc_spec="MMD_AT_PLUS_A",
            diag_pivot_thresh=0.0,
            options={"SymmetricMode": True},
        )
    except RuntimeError as err:
        raise ParameterError(
            f"matrix of size {A.shape[0]} is singular: is the structure under-constrained "
            "(rigid-body modes) or an element degenerate?"
        ) from err


def _default_shift(K, M, singular_shift=None) -> tuple[float, spla.SuperLU | None]:
    """Shift for :func:`eigsh_lowest`: 0 if K is safely invertible, else slightly negative.

    Returns the shift and, when it is 0, the factorisation of K (to be reused).
    """
    x0 = np.random.default_rng(0).standard_normal(K.shape[0])
    try:
        lu = factorize(K)
        x = lu.solve(K @ x0)
        piv = np.abs(lu.U.diagonal())
        if (
            piv.min() > 1e-12 * piv.max()
            and np.all(np.isfinite(x))
            and np.linalg.norm(x - x0) <= 1e-2 * np.linalg.norm(x0)
        ):
            return 0.0, lu
    except ParameterError:
        pass
    if singular_shift is not None:
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
    """

    omega2: np.ndarray
    vectors: np.ndarray


def eigsh_lowest(
    K, M, n: int, sigma: float | None = None, tol: float = 0.0,
    singular_shift: float | None = None,
) -> EigenSolution:
    """Lowest ``n`` eigenpairs of the generalised symmetric problem by shift-invert.

    One factorisation of ``K - sigma M`` is made and passed to ``eigsh`` as
    ``OPinv``. For free-free structures pass a negative ``sigma`` (default: a small
    negative shift scaled to the problem, so rigid-body modes are found too).

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
        Singularity is detected by the LU pivots and a solve round trip.
    tol : float
        Tolerance passed to ``eigsh`` (0 = machine precision).
    singular_shift : float, optional
        Shift to use instead of the default one when K turns out singular (a caller that
        knows the scale of the first elastic mode, e.g. from a trial field, passes it).

    Returns
    -------
    EigenSolution
    """
    K = sp.csc_matrix(K)
    M = sp.csc_matrix(M)
    ndof = K.shape[0]
    if K.shape != M.shape or K.shape[0] != K.shape[1]:
        raise DimensionError(f"K {K.shape} and M {M.shape} must be square and equal")
    if not 1 <= n <= ndof:
        raise ParameterError(f"number of modes must be in 1..{ndof}, got {n}")
    if n >= ndof - 1:
        import scipy.linalg as sla

        w, v = sla.eigh(K.toarray(), M.toarray())
        w, v = w[:n], v[:, :n]
    else:
        lu = None
        if sigma is None:
            sigma, lu = _default_shift(K, M, singular_shift)
        if lu is None:
            lu = factorize(K - sigma * M)
        opinv = spla.LinearOperator((ndof, ndof), matvec=lu.solve, dtype=float)
        try:
            w, v = spla.eigsh(
                K, k=n, M=M, sigma=sigma, which="LM", OPinv=opinv, tol=tol,
                ncv=min(ndof, max(2 * n + 1, 20)),
            )
        except spla.ArpackNoConvergence as err:
            raise ConvergenceError(
                f"eigsh did not converge for {n} modes of a {ndof}-DOF model"
            ) from err
        order = np.argsort(w)
        w, v = w[order], v[:, order]
    # mass-normalise explicitly (eigsh returns M-orthonormal vectors already, up to
    # round-off; the dense path does too, but be explicit and fix a sign convention)
    mnorm = np.sqrt(np.einsum("ij,ij->j", v, M @ v))
    v = v / mnorm
    big = np.argmax(np.abs(v), axis=0)
    v = v * np.sign(v[big, np.arange(v.shape[1])])
    return EigenSolution(omega2=w, vectors=v)
