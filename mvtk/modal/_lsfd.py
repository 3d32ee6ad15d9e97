"""Least-squares frequency-domain residue fit (LSFD) with lower and upper residuals."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..errors import ParameterError
from ._frf import FRF_TYPES

__all__ = ["lsfd", "LsfdFit", "synthesise"]


@dataclass(frozen=True)
class LsfdFit:
    """Residues and residuals of an LSFD fit (receptance residues, rad/s poles).

    ``H(w) = (i w)^k [ sum_m A_m / (i w - lambda_m) + conj(A_m) / (i w - conj(lambda_m))
    + LR / (i w)^2 + UR ]`` with ``k`` = 0, 1, 2 for receptance, mobility, accelerance.
    """

    pole: np.ndarray          # (n_modes,) complex, rad/s
    residue: np.ndarray       # (n_modes, n_response, n_reference) complex
    lower: np.ndarray         # (n_response, n_reference) real
    upper: np.ndarray         # (n_response, n_reference) real
    power: int                # k


def _basis(w, poles, power, residuals):
    iw = 1j * w
    cols = []
    for lam in poles:
        a = 1.0 / (iw - lam)
        b = 1.0 / (iw - np.conj(lam))
        cols += [a + b, 1j * (a - b)]
    if residuals:
        with np.errstate(divide="ignore", invalid="ignore"):
            cols += [1.0 / iw**2, np.ones_like(iw)]
    B = np.column_stack(cols) * (iw ** power)[:, None]
    return B


def synthesise(fit: LsfdFit, f_hz) -> np.ndarray:
    """FRFs ``(n_response, n_reference, n_frequency)`` of the fitted model at ``f_hz``."""
    w = 2 * np.pi * np.asarray(f_hz, dtype=float)
    iw = 1j * w
    nm = fit.pole.size
    shape = fit.residue.shape[1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        # modal terms as one product: (n_FRF, 2 n_modes + 2) coefficients times the
        # (2 n_modes + 2, n_frequency) basis of poles, conjugate poles and residuals
        basis = np.empty((2 * nm + 2, w.size), complex)
        basis[:nm] = 1.0 / (iw[None, :] - fit.pole[:, None])
        basis[nm:2 * nm] = 1.0 / (iw[None, :] - np.conj(fit.pole)[:, None])
        basis[-2] = 1.0 / iw**2
        basis[-1] = 1.0
        coef = np.concatenate([fit.residue.reshape(nm, -1).T,
                               np.conj(fit.residue).reshape(nm, -1).T,
                               fit.lower.reshape(-1, 1), fit.upper.reshape(-1, 1)], axis=1)
        out = (coef.astype(complex) @ basis) * iw**fit.power
    return out.reshape(shape + (w.size,))


def lsfd(H, f_hz, poles, frf_type: str = "receptance", *, residuals: bool = True) -> LsfdFit:
    """Residues of given poles by linear least squares on every FRF at once.

    The real and imaginary parts of all lines are stacked so that the conjugate pole
    carries the conjugate residue exactly (real-valued impulse response) and the
    residuals are real; all response/reference pairs share one factorisation of the
    basis (one ``lstsq`` with ``n_response * n_reference`` right-hand sides). The fit
    is made in the FRF's own type (no division by ``omega^2`` that would weight the low
    lines), but the residues are receptance residues.

    Parameters
    ----------
    H : array_like, shape (n_response, n_reference, n_frequency)
        Complex FRFs.
    f_hz : array_like
        Frequency lines in Hz (a 0 Hz line is skipped when residuals are fitted).
    poles : array_like of complex
        Poles ``-zeta w_n + i w_d`` in rad/s (one of each conjugate pair).
    frf_type : str
        ``receptance``, ``mobility``, ``accelerance`` (``other`` is fitted as receptance).
    residuals : bool
        Fit the lower (``LR / (i w)^2``, modes below the band) and upper (``UR``, modes
        above) residual terms.
    """
    H = np.asarray(H)
    f = np.asarray(f_hz, dtype=float)
    lam = np.atleast_1d(np.asarray(poles, dtype=complex))
    power = FRF_TYPES.get(frf_type, 0)
    keep = f > 0 if residuals else np.ones(f.size, bool)
    w = 2 * np.pi * f[keep]
    nm = lam.size
    ncoef = 2 * nm + (2 if residuals else 0)
    if 2 * w.size < ncoef:
        raise ParameterError(
            f"lsfd: {w.size} lines cannot determine {ncoef} real coefficients per FRF"
        )
    B = _basis(w, lam, power, residuals)
    A = np.vstack([B.real, B.imag])
    colnorm = np.linalg.norm(A, axis=0)
    colnorm[colnorm == 0] = 1.0
    no, ni = H.shape[:2]
    Y = H[:, :, keep].reshape(no * ni, -1).T
    rhs = np.vstack([Y.real, Y.imag])
    # one complete orthogonal factorisation (QR with column pivoting, LAPACK gelsy) of
    # the shared basis serves all n_response * n_reference right-hand sides
    x = scipy.linalg.lstsq(A / colnorm, rhs, lapack_driver="gelsy",
                           check_finite=False)[0] / colnorm[:, None]
    x = x.T.reshape(no, ni, ncoef)
    res = x[..., 0:2 * nm:2] + 1j * x[..., 1:2 * nm:2]        # (no, ni, nm)
    if residuals:
        lower, upper = x[..., -2], x[..., -1]
    else:
        lower = upper = np.zeros((no, ni))
    return LsfdFit(lam, np.moveaxis(res, -1, 0), lower, upper, power)
