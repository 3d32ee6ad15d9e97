"""Modal quality indicators: MAC, MPC, MPD, CMIF."""

from __future__ import annotations

import numpy as np

from .._mac import mac_columns
from ..errors import DimensionError

__all__ = ["mac", "mpc", "mpd", "cmif"]


def mac(a, b=None) -> np.ndarray:
    """Modal assurance criterion between two sets of shapes (rows).

    Parameters
    ----------
    a, b : array_like, shape (n_modes, n_dof) (or one shape, (n_dof,))
        Real or complex shapes, one mode per row (the ``("mode", "dof")`` layout).
        ``b`` defaults to ``a`` (AutoMAC). DataArrays are taken in their stored order;
        align their ``dof`` coordinates first.

    Returns
    -------
    numpy.ndarray, shape (n_a, n_b)
        ``|a_i^H b_j|^2 / ((a_i^H a_i)(b_j^H b_j))`` in [0, 1].

    Examples
    --------
    Two orthogonal shapes give the identity; a shape against a scaled copy gives 1:

    >>> phi = np.array([[1.0, 0.618], [0.618, -1.0]])
    >>> np.round(mac(phi), 6)
    array([[1., 0.],
           [0., 1.]])
    >>> float(mac([1.0, 2.0], [-3.0, -6.0])[0, 0])
    1.0
    """
    a = np.atleast_2d(np.asarray(a))
    b = a if b is None else np.atleast_2d(np.asarray(b))
    if a.shape[-1] != b.shape[-1]:
        raise DimensionError(
            f"mac: the shapes have {a.shape[-1]} and {b.shape[-1]} DOFs; expected the same dofs"
        )
    return mac_columns(a.T, b.T)


def mpc(shapes) -> np.ndarray:
    """Modal phase collinearity (Pappa et al. 1993) of each complex shape (rows).

    ``((Sxx - Syy)^2 + 4 Sxy^2) / (Sxx + Syy)^2`` with ``x = Re``, ``y = Im``: 1 for a
    mode whose DOFs move in phase or in antiphase (a real normal mode), down to 0.

    Examples
    --------
    A real shape has MPC 1; two DOFs 90 degrees apart have MPC 0:

    >>> np.round(mpc(np.array([[1.0, -0.5], [1.0, 1.0j]])), 6)
    array([1., 0.])
    """
    v = np.atleast_2d(np.asarray(shapes, dtype=complex))
    x, y = v.real, v.imag
    sxx, syy, sxy = (x * x).sum(1), (y * y).sum(1), (x * y).sum(1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return ((sxx - syy) ** 2 + 4 * sxy**2) / (sxx + syy) ** 2


def mpd(shapes) -> np.ndarray:
    """Mean phase deviation in degrees of each complex shape (rows).

    Amplitude-weighted mean of the angle between each DOF's complex value and the best
    straight line through all of them in the complex plane (first principal direction
    of ``[Re, Im]``): 0 deg for a real normal mode.

    Examples
    --------
    Same shapes as for :func:`mpc`: 0 deg for a real shape, 45 deg for two equal DOFs in
    quadrature (each 45 deg from the best line):

    >>> np.round(mpd(np.array([[1.0, -0.5], [1.0, 1.0j]])), 6)
    array([ 0., 45.])
    """
    v = np.atleast_2d(np.asarray(shapes, dtype=complex))
    out = np.empty(v.shape[0])
    for k, row in enumerate(v):
        u = np.column_stack([row.real, row.imag])
        _, _, vt = np.linalg.svd(u, full_matrices=False)
        c, s = vt[0]
        amp = np.abs(row)
        with np.errstate(invalid="ignore", divide="ignore"):
            dev = np.abs(np.arcsin(np.clip((row.imag * c - row.real * s) / amp, -1, 1)))
        w = amp.sum()
        out[k] = np.degrees(np.nansum(amp * dev) / w) if w > 0 else np.nan
    return out


def cmif(h) -> np.ndarray:
    """Complex mode indicator function: singular values of ``H(f)`` at each line.

    Parameters
    ----------
    h : array_like, shape (n_response, n_reference, n_frequency)

    Returns
    -------
    numpy.ndarray, shape (min(n_response, n_reference), n_frequency)
        Singular values, largest first; peaks of the first curve mark modes, peaks of
        the second at the same frequency mark repeated or close modes.

    Examples
    --------
    Two references on the 2-mass chain: the first singular value peaks at each mode:

    >>> from mvtk.modal import exact_frf
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> f = np.arange(0.0, 120.0, 0.25)
    >>> h = exact_frf(np.eye(2), 0.5 * np.eye(2), K, f, [0, 1], [0, 1])
    >>> s = cmif(h.values)
    >>> s.shape, float(f[np.argmax(s[0])])
    ((2, 480), 31.0)
    """
    h = np.asarray(h)
    if h.ndim != 3:
        raise DimensionError(f"cmif: expected (response, reference, frequency), got {h.ndim}-D")
    return np.linalg.svd(np.moveaxis(h, -1, 0), compute_uv=False).T
