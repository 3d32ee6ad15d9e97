"""Roots of a monic real matrix polynomial by the Ehrlich-Aberth iteration.

pLSCF needs the roots of ``det D(z)``, ``D(z) = I z^p + sum_{r<p} alpha_r z^r``
(``n_i x n_i`` real coefficients), for every model order ``p`` of a stabilisation
diagram. The block companion matrix ``(p n_i)^2`` costs ``O((p n_i)^3)`` with LAPACK's
dense QR; the roots of order ``p`` are close to those of the order before, and the
Ehrlich-Aberth iteration started there converges in 10-30 sweeps of ``O((p n_i)^2)``
each (Bini & Noferini, "Solving polynomial eigenvalue problems by means of the
Ehrlich-Aberth method", Linear Algebra Appl. 439 (2013) 1130-1149).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

__all__ = ["companion_roots", "aberth_roots", "block_companion", "roots_by_order"]

ABERTH_MIN_SIZE = 90
"""Below this number of roots the dense companion eigenvalues are as cheap."""
ABERTH_MAX_SWEEPS = 80
"""Sweeps before the iteration gives up (the companion eigenvalues are used instead)."""
ABERTH_TOL = 4e-15
"""A root is converged when its Aberth correction is below this fraction of ``|z|``..."""
ABERTH_STALL = 1e-10
"""... or below this fraction and no smaller than half the previous one (the correction
has reached the rounding level of evaluating ``D``, which grows with its coefficients)."""


def block_companion(coef: np.ndarray) -> np.ndarray:
    """Companion matrix of ``I z^p + sum_{r<p} coef[r] z^r`` (``coef``: ``(p, n, n)``)."""
    p, ni, _ = coef.shape
    comp = np.zeros((p * ni, p * ni))
    if p > 1:
        comp[:-ni, ni:] = np.eye((p - 1) * ni)
    comp[-ni:, :] = -np.concatenate(list(coef), axis=1)
    return comp


def companion_roots(coef: np.ndarray) -> np.ndarray:
    """All ``p n`` roots of ``det(I z^p + sum coef[r] z^r)`` from the companion matrix."""
    return scipy.linalg.eigvals(block_companion(coef), overwrite_a=True, check_finite=False)


def _log_derivative(z, cf, p, ni):
    """``d/dz log det D(z) = trace(D^-1 D')`` at each ``z`` (``cf``: ``(p+1, ni*ni)``).

    Inside the unit circle ``D`` is evaluated in powers of ``z``; outside, the scaled
    ``z^-p D(z)`` in powers of ``1/z`` (no overflow), whose log-derivative is that of
    ``D`` minus ``p n_i / z``.
    """
    out = np.empty(z.size, complex)
    big = np.abs(z) > 1
    k = np.arange(p + 1)
    for sel, rev in ((~big, False), (big, True)):
        m = z[sel]
        if m.size == 0:
            continue
        if rev:
            y = 1.0 / m
            pw = np.vander(y, p + 1)                      # y^(p-r), r = 0..p
            dpw = pw * ((k - p) * 1.0)[None, :] * y[:, None]
            add = p * ni / m
        else:
            pw = np.vander(m, p + 1, increasing=True)     # z^r
            dpw = np.zeros_like(pw)
            dpw[:, 1:] = pw[:, :-1] * k[1:]
            add = 0.0
        # entries of D and D' as rows (ni*ni, m): contiguous for the cofactor formulas
        out[sel] = _trace_solve(cf.T @ pw.T, cf.T @ dpw.T, ni) + add
    return out


def _trace_solve(d, dp, ni):
    """``trace(D^-1 D')`` for a batch given as rows ``d[i*ni+j] = D_ij`` (``(ni*ni, m)``).

    Jacobi's formula ``trace(adj(D) D') / det D`` up to 3 x 3 (an exactly singular
    ``D``, a sweep landed on a root, gives an infinite value: the Aberth step there is
    zero); batched solves above.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        if ni == 1:
            return dp[0] / d[0]
        if ni == 2:
            a, b, c, e = d
            return (e * dp[0] - b * dp[2] - c * dp[1] + a * dp[3]) / (a * e - b * c)
        if ni == 3:
            a, b, c, e, f, g, h, i, j = d
            cof = (f * j - g * i, g * h - e * j, e * i - f * h,
                   c * i - b * j, a * j - c * h, b * h - a * i,
                   b * g - c * f, c * e - a * g, a * f - b * e)
            num = sum(x * y for x, y in zip(cof, dp))
            return num / (a * cof[0] + b * cof[1] + c * cof[2])
    dm = d.T.reshape(-1, ni, ni)
    dpm = dp.T.reshape(-1, ni, ni)
    try:
        return np.trace(np.linalg.solve(dm, dpm), axis1=1, axis2=2)
    except np.linalg.LinAlgError:
        return np.trace(np.linalg.pinv(dm) @ dpm, axis1=1, axis2=2)


def aberth_roots(coef: np.ndarray, start: np.ndarray) -> np.ndarray | None:
    """Roots of ``det(I z^p + sum coef[r] z^r)`` by Ehrlich-Aberth from ``start``.

    Parameters
    ----------
    coef : numpy.ndarray, shape (p, n, n)
        Real coefficients of ``z^0 .. z^(p-1)``.
    start : numpy.ndarray of complex, shape (p n,)
        Initial approximations (e.g. the roots of the previous model order).

    Returns
    -------
    numpy.ndarray of complex or None
        The ``p n`` roots (real roots with a zero imaginary part), or None when the
        iteration did not converge or two roots coincide (the caller then uses
        :func:`companion_roots`).
    """
    p, ni, _ = coef.shape
    cf = np.concatenate([coef, np.eye(ni)[None]], axis=0).reshape(p + 1, ni * ni)
    cf = cf.astype(complex)
    z = np.asarray(start, complex).copy()
    active = np.arange(z.size)
    last = np.full(z.size, np.inf)
    for _ in range(ABERTH_MAX_SWEEPS):
        g = _log_derivative(z[active], cf, p, ni)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            diff = z[active][:, None] - z[None, :]
            diff[np.arange(active.size), active] = np.inf
            s = np.sum(1.0 / diff, axis=1)
            step = 1.0 / (g - s)                          # N / (1 - N s), N = 1 / g
        step[~np.isfinite(step)] = 0.0
        z[active] -= step
        size, scale = np.abs(step), np.abs(z[active])
        done = (size <= ABERTH_TOL * scale) | (
            (size <= ABERTH_STALL * scale) & (size >= 0.5 * last[active]))
        last[active] = size
        active = active[~done]
        if active.size == 0:
            break
    else:
        return None
    if not np.all(np.isfinite(z)):
        return None
    # coincident roots mean the iteration lost one: let the companion decide
    zs = np.sort_complex(z)
    gap = np.abs(np.diff(zs))
    if gap.size and np.any(gap <= 1e-9 * np.maximum(np.abs(zs[1:]), 1e-300)):
        return None
    # a real polynomial: roots with |Im z| at rounding level are real
    z.imag[np.abs(z.imag) <= 1e-12 * np.abs(z)] = 0.0
    return z


def roots_by_order(coefs) -> list[np.ndarray]:
    """Roots of the denominators of increasing model orders, each seeded by the last.

    ``coefs``: list of ``(p, n, n)`` coefficient arrays with increasing ``p``. Small
    problems (fewer than ``ABERTH_MIN_SIZE`` roots) and any order whose iteration
    fails use the companion eigenvalues.
    """
    out = []
    prev = None
    for coef in coefs:
        p, ni, _ = coef.shape
        n = p * ni
        z = None
        if prev is not None and n >= ABERTH_MIN_SIZE and prev.size <= n:
            new = n - prev.size
            r = float(np.median(np.abs(prev))) if prev.size else 1.0
            ang = np.pi * (np.arange(new) + 0.5) / max(new, 1) + 0.1
            z = aberth_roots(coef, np.concatenate([prev, r * np.exp(1j * ang)]))
        if z is None:
            z = companion_roots(coef)
        out.append(z)
        prev = z
    return out
