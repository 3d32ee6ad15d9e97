"""Reduced-basis (Rayleigh-Ritz) inner loop of the affine model update.

When K and M are affine in the free parameters, ``K(p) = K0 + sum_j dp_j dK_j`` (same
for M), their projections on a fixed basis ``V`` are affine too:
``V' K(p) V = V' K0 V + sum_j dp_j V' dK_j V``. The least-squares fit then iterates on
the small dense problem ``(V'K(p)V) y = omega^2 (V'M(p)V) y`` (Rayleigh-Ritz: the Ritz
values are upper bounds of the eigenvalues of the full model, exact when the
eigenvectors lie in the span of V) instead of solving the full sparse eigenproblem at
every evaluation.

The basis starts with the full eigenvectors at the initial values and their static
derivatives ``(K - sigma M)^-1 (dK_j - w2_i dM_j) phi_i`` (one factorisation), so the
Ritz values are second-order accurate in the parameter change. A round fits the
reduced model (trust-region least squares, then Gauss-Newton steps on the reduced model)
and makes ONE full eigen solve at its optimum; its full eigenvectors join the basis, so
the next reduced model matches the full one there in value and first derivative (the
derivative of a Ritz value, ``y'(dK_r - w2 dM_r)y``, is Fox & Kapoor's
``phi'(dK - w2 dM)phi`` when ``phi = V y`` is the exact mode). The rounds end at a full
solution whose own Gauss-Newton step (full residuals and Jacobian) is below
:data:`STEP_TOL`: a stationary point of the full problem, whose frequencies, shapes and
Jacobian are then reported. Each round is a Newton-like step on the full problem: the
smart-beam study needs two (three full eigen solves instead of 25).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

__all__ = ["RitzBasis", "ReducedInfo"]

#: Among new vectors (each of unit M0-norm after the projection), combinations whose
#: squared norm is below this fraction of the largest are dependent and dropped.
DEPENDENT = 1e-12


class RitzBasis:
    """M0-orthonormal basis of an affine eigenproblem and the projected matrices.

    Parameters
    ----------
    K0, M0 : sparse matrix, shape (n_dof, n_dof)
        Stiffness (N/m) and mass (kg) at the reference parameter values ``p0``.
    dK, dM : sequence of sparse matrix
        Constant derivatives of K and M with respect to each free parameter (per unit
        of that parameter).
    drop_tol : float
        A new vector is kept only if its part M0-orthogonal to the basis has an M0-norm
        above ``drop_tol`` times its own M0-norm (below that its contribution to any
        Ritz value is below ``drop_tol**2`` relative).
    """

    def __init__(self, K0, M0, dK, dM, drop_tol: float = 1e-8) -> None:
        self._mats = [K0, M0, *dK, *dM]
        # a parameter that enters only K (a modulus, a spring) has dM = 0
        self._zero = [A.count_nonzero() == 0 for A in self._mats]
        self._n_par = len(dK)
        self.drop_tol = float(drop_tol)
        n = K0.shape[0]
        self.V = np.zeros((n, 0))
        self._AV = [np.zeros((n, 0)) for _ in self._mats]   # A @ V of every matrix
        self._P = [np.zeros((0, 0)) for _ in self._mats]    # V' A V

    @property
    def size(self) -> int:
        """Number of basis vectors."""
        return self.V.shape[1]

    @property
    def K0r(self) -> np.ndarray:
        return self._P[0]

    @property
    def M0r(self) -> np.ndarray:
        return self._P[1]

    @property
    def dKr(self) -> list[np.ndarray]:
        return self._P[2:2 + self._n_par]

    @property
    def dMr(self) -> list[np.ndarray]:
        return self._P[2 + self._n_par:]

    def extend(self, W: np.ndarray) -> int:
        """Add the span of the columns of ``W``; return how many vectors were added.

        Block Gram-Schmidt in the M0 inner product, twice ("twice is enough"): the part
        of each column M0-orthogonal to the basis is kept if its norm exceeds
        ``drop_tol`` times the column's own; the kept parts are orthonormalised among
        themselves through the eigen-decomposition of their (unit-diagonal) Gram
        matrix, dropping combinations of squared norm below :data:`DEPENDENT`.
        """
        W = np.array(W, dtype=float, copy=True)
        if W.ndim == 1:
            W = W[:, None]
        M0 = self._mats[1]
        norm0 = np.sqrt(np.maximum(np.einsum("ij,ij->j", W, M0 @ W), 0.0))
        keep = norm0 > 0
        W, norm0 = W[:, keep], norm0[keep]
        for sweep in range(2):
            if self.size:
                W -= self.V @ (self._AV[1].T @ W)
            MW = M0 @ W
            norm = np.sqrt(np.maximum(np.einsum("ij,ij->j", W, MW), 0.0))
            keep = norm > (self.drop_tol * norm0 if sweep == 0 else 0.0)
            W, MW, norm0 = W[:, keep] / norm[keep], MW[:, keep] / norm[keep], norm0[keep]
            if not W.shape[1]:
                return 0
            G = W.T @ MW
            s, U = np.linalg.eigh(0.5 * (G + G.T))
            ok = s > DEPENDENT * s.max()
            T = U[:, ok] / np.sqrt(s[ok])
            W, MW = W @ T, MW @ T
            norm0 = np.ones(W.shape[1])
        self._add(W, MW)
        return W.shape[1]

    def _add(self, Vn: np.ndarray, MVn: np.ndarray) -> None:
        """Append the M0-orthonormal columns ``Vn`` (``MVn = M0 Vn``), extend the projections."""
        V = self.V
        for i, A in enumerate(self._mats):
            if i == 1:
                AVn = MVn
            elif self._zero[i]:
                AVn = np.zeros_like(Vn)
            else:
                AVn = A @ Vn
            P = self._P[i]
            cross = V.T @ AVn                       # V' A Vn
            corner = Vn.T @ AVn
            corner = 0.5 * (corner + corner.T)
            self._P[i] = np.block([[P, cross], [cross.T, corner]])
            self._AV[i] = np.column_stack([self._AV[i], AVn])
        self.V = np.column_stack([V, Vn])

    def matrices(self, dp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Projected ``V'K(p)V`` and ``V'M(p)V`` for the parameter changes ``dp = p - p0``."""
        K, M = self.K0r.copy(), self.M0r.copy()
        for d, dk, dm in zip(dp, self.dKr, self.dMr):
            if d != 0.0:
                K += d * dk
                M += d * dm
        return K, M

    def eig(self, dp: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Lowest ``n`` Ritz values (rad/s)^2 and their coordinates ``y`` (``V'M(p)V``-normal).

        The Ritz vectors in the full space are ``V @ y``, mass-normalised for M(p).
        """
        K, M = self.matrices(dp)
        n = min(n, self.size)
        w, Y = sla.eigh(K, M, subset_by_index=[0, n - 1])
        return w, Y


@dataclass
class ReducedInfo:
    """Diagnostics of the reduced-basis rounds (stored in ``UpdateResult.meta``).

    Attributes
    ----------
    rounds : list of dict
        Per round: reduced evaluations, scaled step from the previous full solution,
        basis size, and the relative mismatch ``max |f_full / f_reduced - 1|`` of the
        paired frequencies at the reduced optimum (before its modes entered the basis).
    n_full_eigen : int
        Full eigen solves made by the rounds (the one at the initial values excluded).
    fallback : str or None
        Why the full least-squares fit took over (no convergence in :data:`MAX_ROUNDS`).
    gauss_newton_step : float or None
        Norm of the full model's Gauss-Newton step (scaled variables) at the end point.
    """

    rounds: list = field(default_factory=list)
    n_full_eigen: int = 0
    fallback: str | None = None
    gauss_newton_step: float | None = None

    def to_meta(self, basis_size: int, n_eigen_total: int, step_tol: float,
                mismatch_final: float | None) -> dict:
        return {
            "used": True,
            "rounds": len(self.rounds),
            "round_details": list(self.rounds),
            "basis_size": int(basis_size),
            "n_full_eigen": int(n_eigen_total),
            "step_tol": float(step_tol),
            "mismatch": mismatch_final,
            "gauss_newton_step": self.gauss_newton_step,
            "fallback": self.fallback,
        }


#: The rounds stop at a full solution whose Gauss-Newton step (from the full model's
#: residuals and Jacobian, bounds respected) is below ``STEP_TOL * (STEP_TOL + |x|)`` in
#: the scaled variables: a stationary point of the full problem to about this accuracy
#: (the step of the smart beam scatters by ~1e-9 between Jacobians from the full modes
#: and from Ritz vectors of differently enriched bases).
STEP_TOL = 1e-8
#: Rounds (full eigen solves) before falling back to the full least-squares fit.
MAX_ROUNDS = 8
#: Gauss-Newton iterations on the reduced model after its trust-region fit.
POLISH_STEPS = 8
#: After the first round, a full Gauss-Newton step below this (scaled variables) means
#: the reduced model (exact in value and slope there) is solved by Gauss-Newton steps
#: alone, without a trust-region fit.
NEAR = 1e-3


def gauss_newton_step(J: np.ndarray, r: np.ndarray, x: np.ndarray, lb: np.ndarray,
                      ub: np.ndarray) -> np.ndarray:
    """Gauss-Newton step ``-pinv(J) r`` in the scaled variables, with the variables on a
    bound that it would push outwards held there, clipped to the bounds.

    Unlike a trust-region step it does not need the cost to decrease measurably, so it
    converges below the round-off of the cost (on the smart beam the trust-region fit,
    full or reduced, stops ~1.5e-7 from the stationary point, where cost changes of
    ~1e-15 drown in the eigenvalue round-off).
    """
    free = np.ones(x.size, dtype=bool)
    span = np.where(np.isfinite(ub - lb), ub - lb, np.abs(x) + 1.0)
    step = np.zeros(x.size)
    for _ in range(x.size + 1):
        step = np.zeros(x.size)
        if free.any():
            step[free] = np.linalg.lstsq(J[:, free], -r, rcond=None)[0]
        out = ((x - lb <= 1e-10 * span) & (step < 0)) | ((ub - x <= 1e-10 * span) & (step > 0))
        if not (out & free).any():
            break
        free &= ~out
    return np.clip(x + step, lb, ub) - x


def static_derivatives(K, M, omega2, vectors, dK, dM) -> np.ndarray:
    """Static approximations of the eigenvector derivatives, one per mode and parameter.

    ``(K - sigma M)^-1 (dK_j - omega_i^2 dM_j) phi_i`` with one factorisation at
    ``sigma = -0.1 omega_1^2`` (positive definite also for a free-free model). Its part
    outside the span of the computed modes is that of the exact derivative (Nelson
    1976) up to the factors ``(omega_k^2 - omega_i^2) / (omega_k^2 - sigma)`` of the
    higher modes k, close to 1: with the modes themselves in the basis, the Ritz values
    are then exact to second order in the parameter change instead of first.

    Returns
    -------
    ndarray, shape (n_dof, n_modes * n_params)
    """
    from ..fe._solvers import factorize

    sigma = -0.1 * float(omega2[0]) if omega2[0] > 0 else -1.0
    F = factorize((K - sigma * M).tocsc())
    rhs = [dk @ vectors - (dm @ vectors) * omega2[None, :] for dk, dm in zip(dK, dM)]
    return F.solve(np.column_stack(rhs))


def _mismatch(st_r, st_f) -> float:
    """``max |f_full / f_reduced - 1|`` over the paired modes (inf if pairs differ)."""
    if not np.array_equal(st_r.pairing.modes, st_f.pairing.modes):
        return math.inf
    m = st_f.pairing.modes
    return float(np.max(np.abs(st_f.fn_all[m] / st_r.fn_all[m] - 1.0)))


def reduced_fit(prob, st0, lb, ub, *, max_iter: int, xtol: float, ftol: float, matched,
                freq_tol: float, step_tol: float = STEP_TOL, max_rounds: int = MAX_ROUNDS):
    """Bounded least squares on reduced models, verified and enriched by full solves.

    Parameters
    ----------
    prob : mvtk.updating._update._Problem
        Affine problem (``prob._aff`` set), evaluated on the full model; ``st0`` is its
        full state at the initial values.
    lb, ub : ndarray
        Bounds of the scaled variables.
    max_iter : int
        Budget of residual evaluations of each reduced fit.
    xtol, ftol : float
        Tolerances of each reduced least-squares fit.
    matched : type
        Exception the residual raises when every frequency error is below ``freq_tol``.
    freq_tol : float
        That tolerance (0: off); a match counts only if the full model confirms it.

    Returns
    -------
    x, status, message, n_evaluations, meta
        Scaled solution (whose full state ``prob.state(x)`` is cached), least-squares
        status and message, model evaluations (reduced plus full) and the diagnostics of
        :class:`ReducedInfo`.
    """
    from scipy.optimize import least_squares

    base, _, dK, dM = prob._aff
    basis = RitzBasis(base.K, base.M, dK, dM)
    info = ReducedInfo()
    x = np.array(st0.x, dtype=float)     # the last point solved on the full model
    st_f = st0
    mismatch = 0.0          # the basis holds the exact modes of the initial model
    n_red, n_eig0 = 0, prob.timing["n_eigen"]
    w = np.where(prob.w > 0, prob.w, 1.0)
    nt = len(prob.targets)
    status, message = 1, "the initial values are stationary for the full model"

    def small(step, x):
        return float(np.linalg.norm(step)) <= step_tol * (step_tol + float(np.linalg.norm(x)))

    while True:
        # the full solution at x: stationary?
        gn = gauss_newton_step(prob.jacobian(x), st_f.residual, x, lb, ub)
        info.gauss_newton_step = float(np.linalg.norm(gn))
        if small(gn, x):
            break
        if status == 0:
            break
        if len(info.rounds) >= max_rounds:
            info.fallback = (f"no convergence after {max_rounds} reduced rounds: full "
                             "least squares from the last full solution")
            try:
                sol = least_squares(
                    prob.residual, x, jac=prob.jacobian, bounds=(lb, ub), method="trf",
                    x_scale=1.0, max_nfev=max_iter, xtol=xtol, ftol=ftol, gtol=1e-12)
                x, status, message = sol.x, int(sol.status), str(sol.message)
                n_red += int(sol.nfev)
            except matched:
                x, status = prob._cache.x.copy(), 5
                message = f"every relative frequency error is below freq_tol = {freq_tol:g}"
            mismatch = None
            break
        basis.extend(st_f.vectors)
        if not info.rounds:
            basis.extend(static_derivatives(base.K, base.M, st0.omega2, st0.vectors, dK, dM))
        prob.use_basis(basis)
        h0 = len(prob.history)
        if info.rounds and info.gauss_newton_step <= NEAR:
            x_r = x          # near the optimum: Gauss-Newton steps alone
        else:
            try:
                sol = least_squares(
                    prob.residual, x, jac=prob.jacobian, bounds=(lb, ub), method="trf",
                    x_scale=1.0, max_nfev=max_iter, xtol=xtol, ftol=ftol, gtol=1e-12)
                x_r, status, message = sol.x, int(sol.status), str(sol.message)
            except matched:
                x_r, status = prob._cache.x.copy(), 5
                message = f"every relative frequency error is below freq_tol = {freq_tol:g}"
        if status != 5:
            # Gauss-Newton on the reduced model down to a tenth of the tolerance
            for _ in range(POLISH_STEPS):
                st_r = prob.state(x_r)
                d = gauss_newton_step(prob.jacobian(x_r), st_r.residual, x_r, lb, ub)
                if small(10 * d, x_r):
                    break
                x_r = x_r + d
        st_r = prob.state(x_r)
        n_red += len(prob.history) - h0
        prob.use_basis(None)         # back to the full model (its state at x is cached)
        st_f = prob.state(x_r)       # the round's one full eigen solve
        mismatch = _mismatch(st_r, st_f)
        info.rounds.append({"reduced_evaluations": len(prob.history) - h0 - 1,
                            "step": float(np.linalg.norm(x_r - x)),
                            "basis_size": basis.size, "mismatch": mismatch})
        x = np.array(x_r, dtype=float)
        if status == 5:
            if np.abs(st_f.residual[:nt] / w).max() <= freq_tol:
                break
            status = 1   # the full model does not confirm the match: go on
    meta = info.to_meta(basis.size, prob.timing["n_eigen"] - n_eig0, step_tol, mismatch)
    return x, status, message, n_red + len(info.rounds), meta
