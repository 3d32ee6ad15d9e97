"""Levenberg-Marquardt for tall least-squares problems with few parameters.

The pole refinement (:mod:`mvtk.modal._refine`) has ``2 n_modes`` parameters (2-10)
and ``10^4-10^6`` residuals. MINPACK's ``lmder`` (scipy's ``method="lm"``) factorises
the whole Jacobian by Householder QR with column pivoting in unblocked Fortran, half the
refinement's time. Here each step solves the damped normal equations
``(J'J + mu D^2) dx = -J'r`` of size ``n x n``; ``J'J`` is one BLAS-3 product. For the
well-conditioned, small-``n`` problems of the refinement the normal equations lose
nothing that matters (the pole covariance is formed from ``J'J`` anyway).

Step control after Moré (1978), "The Levenberg-Marquardt algorithm: implementation and
theory", with Nielsen's update of the damping (Madsen, Nielsen & Tingleff 2004,
"Methods for non-linear least squares problems", sec. 3.2): gain ratio ``rho`` of the
actual to the predicted reduction; ``mu *= max(1/3, 1 - (2 rho - 1)^3)`` on success,
``mu *= nu, nu *= 2`` on failure. Scaling ``D = diag(J'J)^(1/2)`` (running maximum, as
MINPACK's ``mode=1`` and scipy's ``x_scale="jac"``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["LMResult", "levenberg_marquardt"]


@dataclass(frozen=True)
class LMResult:
    """Solution ``x``, ``cost = |r|^2 / 2``, function evaluations ``nfev``, and why it
    stopped (``message``)."""

    x: np.ndarray
    cost: float
    nfev: int
    message: str


def levenberg_marquardt(fun, jac, x0, *, max_nfev: int = 50, ftol: float = 1e-8,
                        xtol: float = 1e-8, gtol: float = 1e-8) -> LMResult:
    """Minimise ``|fun(x)|^2 / 2`` from ``x0`` with the Jacobian ``jac(x)``.

    Parameters
    ----------
    fun, jac : callable
        Residual vector ``(m,)`` and its Jacobian ``(m, n)`` at ``x``.
    x0 : array_like, shape (n,)
    max_nfev : int
        Most evaluations of ``fun`` (> 0).
    ftol, xtol, gtol : float
        Stop when the relative reduction of the cost (actual and predicted) is below
        ``ftol``, the scaled step below ``xtol`` of the scaled ``x``, or the largest
        scaled gradient component below ``gtol`` (MINPACK's tests).

    Returns
    -------
    LMResult

    Examples
    --------
    Fit ``y = a exp(b t)`` to exact data (``a = 2``, ``b = -1.5``):

    >>> t = np.linspace(0, 2, 50)
    >>> y = 2 * np.exp(-1.5 * t)
    >>> fun = lambda p: p[0] * np.exp(p[1] * t) - y
    >>> jac = lambda p: np.column_stack([np.exp(p[1] * t), p[0] * t * np.exp(p[1] * t)])
    >>> np.round(levenberg_marquardt(fun, jac, [1.0, -1.0]).x, 6)
    array([ 2. , -1.5])
    """
    x = np.asarray(x0, dtype=float).copy()
    r = np.asarray(fun(x), dtype=float)
    nfev = 1
    cost = 0.5 * float(r @ r)
    J = np.asarray(jac(x), dtype=float)
    A = J.T @ J
    g = J.T @ r
    d = np.sqrt(np.diag(A))
    d[d == 0] = 1.0
    # Nielsen's start, tau max(diag of the scaled J'J) with tau = 1e-3: the scaled
    # diagonal is 1 here (D^2 = diag(J'J)), so the damping starts at tau
    mu = 1e-3
    nu = 2.0
    message = "max_nfev reached"
    while nfev < max_nfev:
        if cost == 0 or np.max(np.abs(g) / (d * np.sqrt(2 * cost))) <= gtol:
            message = "gradient below gtol"
            break
        try:
            step = np.linalg.solve(A + mu * np.diag(d**2), -g)
        except np.linalg.LinAlgError:
            mu, nu = mu * nu, nu * 2
            continue
        x_new = x + step
        r_new = np.asarray(fun(x_new), dtype=float)
        nfev += 1
        cost_new = 0.5 * float(r_new @ r_new)
        predicted = -(g @ step) - 0.5 * float(step @ (A @ step))
        rho = (cost - cost_new) / predicted if predicted > 0 else -1.0
        small_step = np.linalg.norm(d * step) <= xtol * (np.linalg.norm(d * x) + xtol)
        if rho > 1e-4 and np.isfinite(cost_new):
            converged = (cost - cost_new <= ftol * cost and predicted <= ftol * cost)
            x, r, cost = x_new, r_new, cost_new
            J = np.asarray(jac(x), dtype=float)
            A = J.T @ J
            g = J.T @ r
            d = np.maximum(d, np.sqrt(np.diag(A)))
            mu *= max(1 / 3, 1 - (2 * rho - 1) ** 3)
            nu = 2.0
            if converged or small_step:
                message = "cost or step below tolerance"
                break
        else:
            if small_step:
                message = "step below xtol"
                break
            mu, nu = mu * nu, nu * 2
    return LMResult(x=x, cost=cost, nfev=nfev, message=message)
