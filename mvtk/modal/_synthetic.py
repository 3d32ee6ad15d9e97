"""Exact FRFs and modes of a viscously damped M, C, K system (test truth)."""

from __future__ import annotations

import numpy as np
import scipy.linalg
import xarray as xr

from ..errors import DimensionError, ParameterError
from ._frf import FRF_TYPES, as_frf_matrix

__all__ = ["exact_modes", "exact_frf"]


def exact_modes(M, C, K):
    """Poles and complex mode shapes of ``M q'' + C q' + K q = f`` (state space).

    Returns
    -------
    poles : numpy.ndarray of complex, (n,)
        One of each conjugate pair (``Im > 0``), ascending in frequency, rad/s.
    shapes : numpy.ndarray of complex, (n, n_dof)
        Displacement part of the eigenvectors, one mode per row, scaled to unit modal
        A: the receptance residue is ``A_m = phi_m phi_m^T`` (for proportional damping
        ``phi = phi_mass / sqrt(2 i w_d)``).

    Examples
    --------
    A 2-mass chain (masses 1 kg, springs 1e5 N/m, dampers 0.5 N s/m to ground).
    Closed form: ``w = sqrt(k (3 -+ sqrt(5)) / 2)`` rad/s, ``zeta = c / (2 m w)``:

    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])      # N/m
    >>> poles, shapes = exact_modes(np.eye(2), 0.5 * np.eye(2), K)
    >>> np.round(np.abs(poles) / (2 * np.pi), 3)       # Hz
    array([31.105, 81.434])
    >>> np.round(np.sqrt(1e5 * (3 - np.sqrt(5)) / 2) / (2 * np.pi), 3)
    np.float64(31.105)
    >>> np.round(-poles.real / np.abs(poles), 5)      # 0.5 / (2 w)
    array([0.00128, 0.00049])
    """
    M, C, K = (np.asarray(a, dtype=float) for a in (M, C, K))
    n = M.shape[0]
    if M.shape != (n, n) or C.shape != (n, n) or K.shape != (n, n):
        raise DimensionError(f"exact_modes: M, C, K must be square and equal, got {M.shape}, "
                             f"{C.shape}, {K.shape}")
    A = np.block([[C, M], [M, np.zeros((n, n))]])
    B = np.block([[K, np.zeros((n, n))], [np.zeros((n, n)), -M]])
    lam, V = scipy.linalg.eig(-B, A)
    keep = lam.imag > 0
    lam, V = lam[keep], V[:, keep]
    order = np.argsort(lam.imag)
    lam, V = lam[order], V[:, order]
    phi = V[:n, :]
    a = np.einsum("im,ij,jm->m", V, A, V)  # modal A (non-conjugate transpose)
    phi = phi / np.sqrt(a)[None, :]
    return lam, phi.T


def exact_frf(M, C, K, f_hz, response_dofs, reference_dofs, *, frf_type="receptance",
              nodes=None, directions=None) -> xr.DataArray:
    """FRF matrix ``(i w)^k (K - w^2 M + i w C)^-1`` between chosen DOFs, on the conventions.

    ``nodes``/``directions`` label each DOF of the model (default node ``dof+1``, ``+z``).

    Examples
    --------
    The receptance (m/N) of the 2-mass chain at both masses, force on mass 1:

    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25), [0, 1], [0])
    >>> h.dims, h.shape
    (('response', 'reference', 'frequency'), (2, 1, 480))
    >>> float(h.real[0, 0, 0]) * 1e5     # static flexibility of mass 1: 1 / k
    1.0
    """
    M, C, K = (np.asarray(a, dtype=float) for a in (M, C, K))
    f = np.asarray(f_hz, dtype=float)
    n = M.shape[0]
    for name, a in (("M", M), ("C", C), ("K", K)):
        if a.shape != (n, n):
            raise DimensionError(f"exact_frf: {name} has shape {a.shape}; expected ({n}, {n}) "
                                 "(square, the size of M)")
    nodes = np.arange(1, n + 1) if nodes is None else np.asarray(nodes)
    directions = np.array(["+z"] * n) if directions is None else np.asarray(directions)
    for name, a in (("nodes", nodes), ("directions", directions)):
        if a.shape != (n,):
            raise DimensionError(f"exact_frf: {name} has {a.size} entries; expected one per "
                                 f"DOF of the model ({n})")
    ro, ri = list(response_dofs), list(reference_dofs)
    for name, dofs in (("response_dofs", ro), ("reference_dofs", ri)):
        bad = [d for d in dofs if isinstance(d, bool) or not isinstance(d, int | np.integer)
               or not 0 <= int(d) < n]
        if bad or not dofs:
            raise ParameterError(f"exact_frf: {name} must be DOF indices in 0..{n - 1}, got "
                                 f"{bad if bad else dofs}")
    w = 2 * np.pi * f
    Z = K[None] - (w**2)[:, None, None] * M[None] + 1j * w[:, None, None] * C[None]
    rhs = np.zeros((n, len(ri)))
    rhs[ri, np.arange(len(ri))] = 1.0
    X = np.linalg.solve(Z, np.broadcast_to(rhs, (f.size, n, len(ri))))  # (nf, n, ni)
    H = np.moveaxis(X[:, ro, :], 0, -1) * ((1j * w) ** FRF_TYPES[frf_type])
    q = {"receptance": ("displacement", "m/N"), "mobility": ("velocity", "m/s/N"),
         "accelerance": ("acceleration", "m/s^2/N")}[frf_type]
    da = xr.DataArray(
        H, dims=("response", "reference", "frequency"),
        coords={"response": [f"{nodes[d]}{directions[d]}" for d in ro],
                "reference": [f"{nodes[d]}{directions[d]}" for d in ri],
                "frequency": f,
                "node": ("response", nodes[ro]), "direction": ("response", directions[ro]),
                "quantity": ("response", [q[0]] * len(ro)),
                "units": ("response", [q[1]] * len(ro)),
                "reference_node": ("reference", nodes[ri]),
                "reference_direction": ("reference", directions[ri]),
                "reference_quantity": ("reference", ["force"] * len(ri)),
                "reference_units": ("reference", ["N"] * len(ri))},
        attrs={"frf_type": frf_type, "estimator": "exact"},
    )
    return as_frf_matrix(da)
