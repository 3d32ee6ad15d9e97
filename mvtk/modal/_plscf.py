"""Poly-reference least-squares complex frequency-domain estimator (pLSCF, PolyMAX type)."""

from __future__ import annotations

import numpy as np
import scipy.linalg

from ..errors import ParameterError, ResolutionWarning
from ._frf import as_frf_matrix
from ._polyroots import roots_by_order
from ._quality import cmif
from ._stabilisation import StabilisationDiagram, StabilityCriteria, poles_to_diagram

__all__ = ["plscf", "band_frf"]


def band_frf(frf, fmin: float | None, fmax: float | None):
    """The FRF matrix restricted to ``fmin <= f <= fmax`` (Hz), checked."""
    h = as_frf_matrix(frf)
    f = h["frequency"].values
    lo = f[0] if fmin is None else float(fmin)
    hi = f[-1] if fmax is None else float(fmax)
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 <= lo < hi):
        raise ParameterError(f"the band must satisfy 0 <= fmin < fmax; got {lo!r}..{hi!r} Hz")
    keep = (f >= lo) & (f <= hi)
    if keep.sum() < 8:
        raise ParameterError(
            f"the band {lo:g}..{hi:g} Hz holds {int(keep.sum())} frequency line(s) of the FRF "
            f"({f[0]:g}..{f[-1]:g} Hz); expected at least 8"
        )
    return h.isel(frequency=np.flatnonzero(keep))


#: Frequency lines per block of the lag sums: the block's ``z^k`` table is
#: ``_LAG_BLOCK x (P + 1)`` complex numbers (21 MB at P = 160), whatever the band's length.
_LAG_BLOCK = 8192


def _lag_sums(phase, P, a):
    """``sum_f z_f^k a_f`` for lags ``k = -P..P`` (rows), columns of ``a``.

    ``z_f = exp(i phase_f)``. The powers are built block by block over the frequency
    lines, so the memory stays bounded for long records (a 262 144-line band at
    ``P = 160`` would need a 675 MB table at once).
    """
    pos = np.zeros((P + 1, a.shape[1]), dtype=complex)
    neg = np.zeros_like(pos)
    for start in range(0, len(phase), _LAG_BLOCK):
        blk = slice(start, start + _LAG_BLOCK)
        # z^k by running products (one complex multiply per entry; as accurate as
        # numpy's integer powers here, and 4x faster than exp(i k phase))
        zk = np.empty((len(phase[blk]), P + 1), dtype=complex)
        zk[:, 0] = 1.0
        zk[:, 1:] = np.exp(1j * phase[blk])[:, None]
        np.cumprod(zk, axis=1, out=zk)
        pos += zk.T @ a[blk]
        neg += np.conj(zk).T @ a[blk]
    return np.concatenate([neg[:0:-1], pos], axis=0)


def _toeplitz_blocks(lags, p1, nb):
    """Real block-Toeplitz ``M[(r,i),(s,j)] = Re lags[s - r, i, j]``, r,s < p1."""
    P = (lags.shape[0] - 1) // 2
    r = np.arange(p1)
    k = (r[None, :] - r[:, None]) + P
    blk = np.real(lags[k])  # (p1, p1, nb_i, nb_j)
    return blk.transpose(0, 2, 1, 3).reshape(p1 * nb[0], p1 * nb[1])


def _check_orders(orders):
    o = np.unique(np.asarray(list(orders), dtype=int))
    if o.size == 0 or o.min() < 1:
        raise ParameterError(f"orders must be a non-empty list of model orders >= 1, got "
                             f"{list(np.asarray(list(orders)))}")
    return o


def plscf(
    frf,
    fmin: float | None = None,
    fmax: float | None = None,
    orders=range(2, 41),
    *,
    criteria: StabilityCriteria | None = None,
) -> StabilisationDiagram:
    """Poles of an FRF matrix over a range of model orders (pLSCF / PolyMAX type).

    A right matrix-fraction model ``H_o(w) = N_o(z) D(z)^-1`` (``H_o``: row of the
    ``n_o x n_i`` FRF matrix, ``z = exp(i w dt)``, ``dt = 1 / (2 fmax)``) with real
    matrix-polynomial coefficients ``D(z) = sum_r alpha_r z^r`` (``n_i x n_i``) and
    ``N_o(z) = sum_r beta_or z^r`` is fitted by linear least squares on
    ``N_o - H_o D`` over the band. The numerator coefficients are eliminated
    (reduced normal equations ``M = sum_o (T_o - S_o^T R^-1 S_o)``); with unit weights
    all of ``R``, ``S_o``, ``T_o`` are block-Toeplitz and are built from lag sums
    ``sum_f z_f^k (.)`` computed once for the highest order. With ``R = L L^T``
    (Cholesky), the leading blocks of ``L^-1 S_o`` serve every lower order, so the
    reduced matrices of all orders come from one cumulative sum. The denominator with
    ``alpha_p = I`` gives the poles and participation vectors from a companion
    matrix (left eigenvectors of ``D``): ``lambda = ln(mu) / dt``.

    Parameters
    ----------
    frf : xarray.DataArray or Dataset
        FRF matrix ``("response", "reference", "frequency")``; see
        :func:`mvtk.modal.as_frf_matrix`.
    fmin, fmax : float, optional
        Band in Hz (default: all lines).
    orders : iterable of int
        Model orders ``p`` (polynomial degree); each gives ``p * n_reference`` poles.
    criteria : StabilityCriteria, optional
        Stability tolerances (default 1 % frequency, 5 % damping, MAC 0.98).

    Returns
    -------
    StabilisationDiagram
        With the CMIF of the band behind it.

    References
    ----------
    Peeters, Van der Auweraer, Guillaume, Leuridan, "The PolyMAX frequency-domain method:
    a new standard for modal parameter estimation?", Shock and Vibration 11 (2004).
    Guillaume et al., "A poly-reference implementation of the least-squares complex
    frequency-domain estimator", IMAC XXI (2003).

    Examples
    --------
    The exact receptance of the 2-mass chain (modes at 31.105 and 81.434 Hz), model orders
    2..20:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> diagram = plscf(h, 2.0, 110.0, orders=range(2, 21))
    >>> diagram.method, int(diagram.orders[-1])
    ('pLSCF', 20)
    >>> np.round(np.abs(modal.select_poles(diagram).pole) / (2 * np.pi), 3)
    array([31.105, 81.434])
    """
    import warnings

    crit = criteria or StabilityCriteria()
    h = band_frf(frf, fmin, fmax)
    orders = _check_orders(orders)
    f = h["frequency"].values
    H = h.values
    no, ni, nf = H.shape
    P = int(orders.max())
    if nf < 2 * P:
        warnings.warn(
            f"pLSCF: {nf} lines in the band for model orders up to {P}; fewer than 2 lines "
            "per order make the high orders fit noise", ResolutionWarning, stacklevel=2)
    scale = np.sqrt(np.mean(np.abs(H) ** 2))
    Hs = H / (scale if scale > 0 else 1.0)
    dt = 1.0 / (2.0 * f[-1])
    phase = 2 * np.pi * f * dt  # z_f = exp(i phase_f)
    # lag sums of rho (R), sigma (S_o) and tau (sum_o T_o), in one pass over the lines
    q = np.empty((nf, ni, ni), complex)
    for i in range(ni):
        for j in range(ni):
            q[:, i, j] = np.sum(np.conj(Hs[:, i]) * Hs[:, j], axis=0)
    cols = np.concatenate([np.ones((nf, 1)), Hs.reshape(no * ni, nf).T,
                           q.reshape(nf, ni * ni)], axis=1)
    del q
    sums = _lag_sums(phase, P, cols)
    rho = sums[:, :1, None]                                                 # (2P+1, 1, 1)
    sig = sums[:, 1:1 + no * ni]                                           # (2P+1, no*ni)
    tau = sums[:, 1 + no * ni:].reshape(2 * P + 1, ni, ni)
    R = _toeplitz_blocks(rho, P + 1, (1, 1))
    R[np.diag_indices_from(R)] += 1e-12 * np.trace(R) / R.shape[0]
    L = np.linalg.cholesky(R)
    T = _toeplitz_blocks(tau, P + 1, (ni, ni))
    sig = sig.reshape(2 * P + 1, no, 1, ni).transpose(1, 0, 2, 3)           # (no, lags, 1, ni)
    S = -np.stack([_toeplitz_blocks(sig[o], P + 1, (1, ni)) for o in range(no)])
    rhs = np.ascontiguousarray(S.transpose(1, 0, 2)).reshape(P + 1, -1)
    W = scipy.linalg.solve_triangular(L, rhs, lower=True, check_finite=False,
                                      overwrite_b=True).reshape(P + 1, no, -1)  # (P+1,no,q)
    acc = np.zeros_like(T)
    want = set(orders.tolist())
    comps = []
    for r in range(P + 1):
        acc += W[r].T @ W[r]
        p = r
        if p not in want:
            continue
        n = (p + 1) * ni
        M = T[:n, :n] - acc[:n, :n]
        m11 = M[:p * ni, :p * ni]
        m12 = M[:p * ni, p * ni:n]
        try:
            alpha = -np.linalg.solve(m11, m12)
        except np.linalg.LinAlgError:
            alpha = -np.linalg.lstsq(m11, m12, rcond=None)[0]
        comps.append((p, alpha.reshape(p, ni, ni)))
    # roots of det D(z): each order's Ehrlich-Aberth iteration starts from the roots of
    # the order before (companion eigenvalues for small orders or when it fails)
    mus = roots_by_order([blocks.transpose(0, 2, 1) for _, blocks in comps])
    per_order = []
    for (p, blocks), mu in zip(comps, mus):
        mu = mu[mu.imag > 0]  # one of each conjugate pair (real poles are not modes)
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            lam = np.log(mu) / dt
        good = np.isfinite(lam)
        mu, lam = mu[good], lam[good]
        # only physical poles in the band go further (the diagram marks the rest "x")
        fn_p = np.abs(lam) / (2 * np.pi)
        keep = ((-lam.real > 0) & (-lam.real <= crit.zeta_max * np.abs(lam))
                & (fn_p >= f[0]) & (fn_p <= f[-1]))
        mu, lam = mu[keep], lam[keep]
        # participation vectors: left null vectors of D(mu) = sum alpha_r mu^r
        # (alpha_p = I), from a batched SVD of the n_i x n_i matrices
        if ni > 1 and mu.size:
            pw = mu[:, None] ** np.arange(p + 1)[None, :]
            coef = np.concatenate([blocks, np.eye(ni)[None]], axis=0)   # (p+1, ni, ni)
            dmat = (pw @ coef.reshape(p + 1, ni * ni)).reshape(-1, ni, ni)
            dmat = dmat.transpose(0, 2, 1)                              # D(mu)^T
            vec = np.conj(np.linalg.svd(dmat)[2][:, -1, :])
        else:
            vec = np.ones((mu.size, 1), complex)
        per_order.append((p, lam, vec))
    ind = cmif(H)
    return poles_to_diagram("pLSCF", per_order, (f[0], f[-1]), f, ind, crit)
