"""Least-squares frequency-domain residue fit (LSFD) with lower and upper residuals."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..errors import ParameterError
from ._frf import FRF_TYPES
from ._line_noise import correlated_gram

__all__ = ["lsfd", "LsfdFit", "synthesise", "local_misfit"]


@dataclass(frozen=True)
class LsfdFit:
    """Residues and residuals of an LSFD fit (receptance residues, rad/s poles).

    ``H(w) = (i w)^k [ sum_m A_m / (i w - lambda_m) + conj(A_m) / (i w - conj(lambda_m))
    + LR / (i w)^2 + UR ]`` with ``k`` = 0, 1, 2 for receptance, mobility, accelerance.

    Examples
    --------
    Returned by :func:`lsfd`: receptance residues (mode, response, reference) and the
    lower and upper residuals per pair:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> f = np.arange(0.25, 120.0, 0.25)
    >>> poles, _ = modal.exact_modes(np.eye(2), 0.5 * np.eye(2), K)
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, f, [0, 1], [0])
    >>> fit = lsfd(h.values, f, poles)
    >>> fit.residue.shape, fit.lower.shape, fit.power          # power 0: receptance
    ((2, 2, 1), (2, 1), 0)
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
    """FRFs ``(n_response, n_reference, n_frequency)`` of the fitted model at ``f_hz``.

    Examples
    --------
    The model fitted by :func:`lsfd` reproduces the exact FRF:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> f = np.arange(0.25, 120.0, 0.25)
    >>> poles, _ = modal.exact_modes(np.eye(2), 0.5 * np.eye(2), K)
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, f, [0, 1], [0]).values
    >>> err = np.abs(synthesise(lsfd(h, f, poles), f) - h).max() / np.abs(h).max()
    >>> bool(err < 1e-6)
    True
    """
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
        nfrf = int(np.prod(shape))
        coef = np.concatenate([fit.residue.reshape(nm, nfrf).T,
                               np.conj(fit.residue).reshape(nm, nfrf).T,
                               fit.lower.reshape(-1, 1), fit.upper.reshape(-1, 1)], axis=1)
        out = (coef.astype(complex) @ basis) * iw**fit.power
    return out.reshape(shape + (w.size,))


def _system(H, f_hz, lam, frf_type, residuals):
    """Real least-squares system of LSFD: column-normalised basis, right-hand sides.

    Returns ``(A / colnorm, colnorm, rhs, keep)``: rows are the real then the imaginary
    parts of the kept lines ``keep``, columns the real/imaginary residue parts of each
    pole then the lower and upper residuals; ``rhs`` has one column per FRF.
    """
    f = np.asarray(f_hz, dtype=float)
    power = FRF_TYPES.get(frf_type, 0)
    keep = f > 0 if residuals else np.ones(f.size, bool)
    w = 2 * np.pi * f[keep]
    ncoef = 2 * lam.size + (2 if residuals else 0)
    if 2 * w.size < ncoef:
        raise ParameterError(
            f"lsfd: {w.size} lines cannot determine {ncoef} real coefficients per FRF"
        )
    B = _basis(w, lam, power, residuals)
    A = np.vstack([B.real, B.imag])
    colnorm = np.linalg.norm(A, axis=0)
    colnorm[colnorm == 0] = 1.0
    Y = H[:, :, keep].reshape(H.shape[0] * H.shape[1], -1).T
    return A / colnorm, colnorm, np.vstack([Y.real, Y.imag]), keep


def local_misfit(H, f_hz, poles, frf_type, windows, *, residuals: bool = True):
    """LSFD misfit within each mode's window, with and without that mode in the model.

    For mode ``m`` the FRFs are fitted once with all poles and once with every pole but
    ``m`` (same residual terms, all lines of the band); both fits are then compared
    with the measured FRFs on the lines of ``windows[m]`` only. One QR factorisation of
    the shared basis serves all modes: dropping the two columns of mode ``m`` leaves a
    small ``(n_coef, n_coef - 2)`` least-squares problem in the triangular factor.

    Parameters
    ----------
    H, f_hz, poles, frf_type, residuals
        As for :func:`lsfd`.
    windows : sequence of bool arrays, one per pole
        Lines (of ``f_hz``) on which the misfit of that mode is measured.

    Returns
    -------
    with_mode, without_mode, energy : numpy.ndarray
        ``sum |H - H_fit|^2`` over the window for the full model and for the model
        without the mode, and ``sum |H|^2`` over the window (units of ``|H|^2``).
    """
    H = np.asarray(H)
    lam = np.atleast_1d(np.asarray(poles, dtype=complex))
    A, _, rhs, keep = _system(H, f_hz, lam, frf_type, residuals)
    return _misfits(_factor(A, rhs), A, rhs, keep, windows)


def _factor(A, rhs):
    """``(R, Q^T rhs, x)``: economic QR of the basis and the least-squares solution."""
    Q, R = np.linalg.qr(A)
    c = Q.T @ rhs
    # rank-revealing solve (QR with column pivoting) on the small triangular factor
    x = scipy.linalg.lstsq(R, c, lapack_driver="gelsy", check_finite=False)[0]
    return R, c, x


def _misfits(qr, A, rhs, keep, windows):
    R, c, x_all = qr
    nk = int(keep.sum())
    out = np.zeros((3, len(windows)))
    for m, win in enumerate(windows):
        lines = np.flatnonzero(np.asarray(win)[keep])
        rows = np.concatenate([lines, lines + nk])
        cols = np.setdiff1d(np.arange(A.shape[1]), [2 * m, 2 * m + 1])
        x0 = scipy.linalg.lstsq(R[:, cols], c, lapack_driver="gelsy", check_finite=False)[0]
        out[0, m] = np.sum((A[rows] @ x_all - rhs[rows]) ** 2)
        out[1, m] = np.sum((A[rows][:, cols] @ x0 - rhs[rows]) ** 2)
        out[2, m] = np.sum(rhs[rows] ** 2)
    return out[0], out[1], out[2]


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

    Examples
    --------
    Residues of the exact poles of the 2-mass chain; for a receptance the residue of mode
    m between DOFs o and i is ``phi_o phi_i`` of the unit-modal-A shapes:

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> f = np.arange(0.25, 120.0, 0.25)
    >>> poles, shapes = modal.exact_modes(np.eye(2), 0.5 * np.eye(2), K)
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, f, [0, 1], [0])
    >>> fit = lsfd(h.values, f, poles)
    >>> fit.residue.shape            # (mode, response, reference)
    (2, 2, 1)
    >>> bool(np.allclose(fit.residue[:, :, 0], shapes * shapes[:, :1], atol=1e-9))
    True
    """
    return _fit(H, f_hz, poles, frf_type, residuals)[0]


def _fit(H, f_hz, poles, frf_type, residuals):
    """LSFD fit plus what :func:`_misfits` needs (basis, right-hand sides, QR)."""
    H = np.asarray(H)
    lam = np.atleast_1d(np.asarray(poles, dtype=complex))
    A, colnorm, rhs, keep = _system(H, f_hz, lam, frf_type, residuals)
    power = FRF_TYPES.get(frf_type, 0)
    nm = lam.size
    ncoef = A.shape[1]
    no, ni = H.shape[:2]
    # one QR factorisation of the shared basis serves all n_response * n_reference
    # right-hand sides
    qr = _factor(A, rhs)
    x = qr[2] / colnorm[:, None]
    x = x.T.reshape(no, ni, ncoef)
    res = x[..., 0:2 * nm:2] + 1j * x[..., 1:2 * nm:2]        # (no, ni, nm)
    if residuals:
        lower, upper = x[..., -2], x[..., -1]
    else:
        lower = upper = np.zeros((no, ni))
    fit = LsfdFit(lam, np.moveaxis(res, -1, 0), lower, upper, power)
    return fit, A, rhs, keep, qr, colnorm


def lsfd_with_misfit(H, f_hz, poles, frf_type, windows, *, residuals=True,
                     coef_variance=False, record_window=None):
    """:func:`lsfd` and :func:`local_misfit` from one factorisation of the basis.

    With ``coef_variance`` a third item: the diagonal of ``(B^T B)^-1`` of the real
    basis (one entry per real coefficient, residue real/imaginary parts first): the
    variance of each fitted coefficient per unit noise variance of the real and
    imaginary parts of an FRF line; with ``record_window`` (``(w, fs)``, see
    :mod:`mvtk.modal._line_noise`) that of the lines' correlated noise,
    ``diag((B^T B)^-1 B^T S B (B^T B)^-1)``.
    """
    fit, A, rhs, keep, qr, colnorm = _fit(H, f_hz, poles, frf_type, residuals)
    out = (fit, _misfits(qr, A, rhs, keep, windows))
    if coef_variance:
        try:
            Rinv = scipy.linalg.solve_triangular(qr[0], np.eye(qr[0].shape[0]))
            if record_window is None:
                d = np.sum(Rinv**2, axis=1) / colnorm**2
            else:
                # (B^T B)^-1 B^T = R^-1 Q^T: the sandwich is R^-1 (Q^T S Q) R^-T
                G = correlated_gram(A @ Rinv, np.asarray(f_hz, float)[keep], record_window)
                d = np.einsum("ij,jk,ik->i", Rinv, G, Rinv) / colnorm**2
        except (np.linalg.LinAlgError, ValueError):
            d = np.full(A.shape[1], np.nan)
        out = out + (d,)
    return out

