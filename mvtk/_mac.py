"""The modal assurance criterion (MAC): the one implementation behind every ``mac``.

:func:`mvtk.modal.mac` (rows, test shapes), :func:`mvtk.correlation.mac` (DataArrays),
:func:`mvtk.updating.mac` (columns, model shapes) and :func:`mvtk.reduction.mac`
(columns, optionally mass-weighted) check and lay out their inputs, then call
:func:`mac_columns`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["mac_columns"]


def _column_scale(x: np.ndarray) -> np.ndarray:
    """Largest magnitude of each column (1 for an all-zero or empty column)."""
    if x.shape[0] == 0:
        return np.ones(x.shape[1])
    s = np.max(np.abs(x), axis=0)
    return np.where(np.isfinite(s) & (s > 0), s, 1.0)


def mac_columns(a: np.ndarray, b: np.ndarray, weight=None) -> np.ndarray:
    """MAC matrix between the columns of ``a`` (n, ka) and ``b`` (n, kb).

    ``MAC_ij = |a_i^H W b_j|^2 / ((a_i^H W a_i)(b_j^H W b_j))`` (Allemang & Brown 1982),
    ``W`` the identity or ``weight`` (n, n; e.g. a mass matrix), for real or complex
    shapes. Each column is first divided by its largest magnitude: the MAC does not
    depend on the scale of a shape, and shapes of magnitude 1e-160 or 1e+160 then
    neither underflow nor overflow in the squares.

    Returns
    -------
    ndarray, shape (ka, kb)
        Values in [0, 1]; 0 where a shape is identically zero.
    """
    a = np.asarray(a)
    b = np.asarray(b)
    a = a / _column_scale(a)
    b = b / _column_scale(b)
    wa = a if weight is None else weight @ a
    wb = b if weight is None else weight @ b
    num = np.abs(np.conj(a).T @ wb) ** 2
    na = np.real(np.einsum("ij,ij->j", np.conj(a), wa))
    nb = np.real(np.einsum("ij,ij->j", np.conj(b), wb))
    den = np.outer(na, nb)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = np.where(den > 0, num / np.where(den > 0, den, 1.0), 0.0)
    return np.clip(out, 0.0, 1.0)
