"""Flat layered MITC4 shell element (FSDT), vectorised over elements.

Element choice
--------------
A 4-node flat shell with first-order shear deformation and the MITC4 assumed transverse
shear strain field of Bathe & Dvorkin (1985): the covariant transverse shear strains are
sampled at the four edge mid-points (tying points) and interpolated linearly across the
element. This removes shear locking (tested for span/thickness 5 to 1000 against the
Navier FSDT solution in ``tests/fe/test_shell.py``) while every stiffness term is
integrated with the full 2x2 Gauss rule, so the element has no spurious zero-energy
modes: an unconstrained element has exactly the six rigid-body modes (also tested, for a
distorted element). The alternative of the paper, the 8-node serendipity element, needs
reduced (2x2) integration of the shear terms against locking, and reduced integration
is what brings spurious zero-energy modes into Q8/Q9 Mindlin elements (e.g. Hughes,
*The Finite Element Method*, 1987, chapter 5); MITC4 avoids both with a full rule.
MITC4 converges at O(h^2) in frequency (tested), so meshes are finer than with Q8.
The membrane part is the plain bilinear (Q4) field: in-plane bending of a coarse mesh
is slightly stiff (3 % with 4 elements across a strip's depth, tested); this only
affects in-plane modes, which lie far above the bending modes of plates and strips.

Kinematics (z from the reference surface, nodes on the reference surface)::

    u(z) = u0 + z * ry,     v(z) = v0 - z * rx,     w(z) = w0

so the section slopes are ``beta_x = ry`` and ``beta_y = -rx`` (right-handed rotation
vectors about x and y). Generalised strains: membrane ``eps0 = (u,x, v,y, u,y + v,x)``,
curvatures ``kappa = (ry,x, -rx,y, ry,y - rx,x)``, shear ``gamma = (w,x + ry, w,y - rx)``.

Drilling rotation ``rz``: a flat plate has no physical stiffness for it. We add the
Hughes-Brezzi (1989) penalty ``gamma_d * integral (rz - (v,x - u,y)/2)^2 dA`` with
``gamma_d = DRILL_FACTOR * A66`` (``A66`` = in-plane shear stiffness of the section, Pa m),
``DRILL_FACTOR = 1e-3``, integrated 2x2. This ties ``rz`` to the in-plane rotation, keeps
the in-plane rigid rotation a zero-energy mode (free-free plates have 6 rigid-body modes),
and with the small factor changes in-plane stiffness by < 1e-4 (tested). The drilling
rotation has no physical inertia of its own (the in-plane rotation's inertia is carried by
u and v); a token inertia ``DRILL_INERTIA_FACTOR * I2`` with ``DRILL_INERTIA_FACTOR = 1e-6``
keeps the mass matrix positive definite while pushing the drilling modes far above the
structural ones (with inertia ``I2`` they would fall near
``sqrt(12 * 1e-3 * G / rho) / (2 pi h)``, e.g. 280 Hz for a 0.2 m thick steel plate, below
its first bending mode).

Mass: consistent, from the kinetic energy of the FSDT field with the inertia terms
``I0`` (translations), ``I1`` (coupling of u0 with beta_x, v0 with beta_y: non-zero for
offset / unsymmetric sections) and ``I2`` (rotary inertia).

References
----------
K.-J. Bathe, E. N. Dvorkin, "A four-node plate bending element based on Mindlin/Reissner
plate theory and a mixed interpolation", IJNME 21 (1985) 367-383.
T. J. R. Hughes, F. Brezzi, "On drilling degrees of freedom", CMAME 72 (1989) 105-121.
"""

from __future__ import annotations

import numpy as np

from ..errors import DimensionError, ParameterError

__all__ = ["DRILL_FACTOR", "DRILL_INERTIA_FACTOR", "mitc4_matrices"]

#: Drilling penalty factor relative to the section in-plane shear stiffness A66.
DRILL_FACTOR = 1e-3
#: Inertia of the drilling rotation relative to the rotary inertia I2 (see module notes).
DRILL_INERTIA_FACTOR = 1e-6

_XI = np.array([-1.0, 1.0, 1.0, -1.0])
_ETA = np.array([-1.0, -1.0, 1.0, 1.0])
_G = 1.0 / np.sqrt(3.0)
_GAUSS = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])


def _shape(xi: float, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Bilinear shape functions (4,) and natural derivatives (2, 4) at (xi, eta)."""
    N = 0.25 * (1 + _XI * xi) * (1 + _ETA * eta)
    dN = np.vstack([0.25 * _XI * (1 + _ETA * eta), 0.25 * _ETA * (1 + _XI * xi)])
    return N, dN


def _shear_natural(xy: np.ndarray, xi: float, eta: float, direction: int) -> np.ndarray:
    """Row (n_el, 24) of the covariant shear strain gamma_xi (0) or gamma_eta (1)."""
    N, dN = _shape(xi, eta)
    J = np.einsum("ka,eaj->ekj", dN, xy)  # (n_el, 2, 2): J[k, j] = d x_j / d xi_k
    n_el = xy.shape[0]
    row = np.zeros((n_el, 4, 6))
    row[:, :, 2] = dN[direction][None, :]
    row[:, :, 4] = N[None, :] * J[:, direction, 0][:, None]   # beta_x = ry
    row[:, :, 3] = -N[None, :] * J[:, direction, 1][:, None]  # beta_y = -rx
    return row.reshape(n_el, 24)


def mitc4_matrices(
    xy: np.ndarray,
    abd: np.ndarray,
    h_shear: np.ndarray,
    inertia: np.ndarray,
    drill_factor: float = DRILL_FACTOR,
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass matrices of flat MITC4 layered shell elements.

    Parameters
    ----------
    xy : ndarray, shape (n_el, 4, 2)
        Node coordinates (m) of each element in the x-y plane, counter-clockwise.
    abd : ndarray, shape (n_el, 6, 6)
        Section ``[[A, B], [B, D]]`` of each element (see :class:`Laminate`).
    h_shear : ndarray, shape (n_el, 2, 2)
        Transverse shear stiffness (Pa m), order (xz, yz).
    inertia : ndarray, shape (n_el, 3)
        ``I0, I1, I2`` per element.
    drill_factor : float
        Drilling penalty relative to ``A66`` (see module notes).

    Returns
    -------
    K, M : ndarray, shape (n_el, 24, 24)
        DOF order per node: ux, uy, uz, rx, ry, rz; nodes in element order.

    Raises
    ------
    DimensionError
        On inconsistent shapes.
    ParameterError
        If an element is degenerate or numbered clockwise (det J <= 0).

    Examples
    --------
    One 100 x 100 mm element of 2 mm steel: symmetric matrices, and a unit uz translation
    of all four nodes carries the element mass ``rho h A`` = 0.157 kg:

    >>> from mvtk.fe import IsotropicMaterial, Laminate, Ply
    >>> lam = Laminate((Ply(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0), 2e-3),))
    >>> xy = np.array([[[0.0, 0.0], [0.1, 0.0], [0.1, 0.1], [0.0, 0.1]]])     # m
    >>> K, M = mitc4_matrices(xy, lam.ABD[None], lam.H[None], np.array([[lam.I0, lam.I1, lam.I2]]))
    >>> K.shape, bool(np.allclose(K, K.transpose(0, 2, 1)))
    ((1, 24, 24), True)
    >>> uz = np.zeros(24)
    >>> uz[2::6] = 1.0
    >>> round(float(uz @ M[0] @ uz), 6)                                       # kg
    0.157
    """
    xy = np.asarray(xy, dtype=float)
    n_el = xy.shape[0]
    if xy.shape != (n_el, 4, 2):
        raise DimensionError(f"xy must have shape (n_el, 4, 2), got {xy.shape}")
    abd = np.broadcast_to(np.asarray(abd, dtype=float), (n_el, 6, 6))
    h_shear = np.broadcast_to(np.asarray(h_shear, dtype=float), (n_el, 2, 2))
    inertia = np.broadcast_to(np.asarray(inertia, dtype=float), (n_el, 3))
    if not (np.isfinite(drill_factor) and drill_factor >= 0):
        raise ParameterError(f"drill_factor must be >= 0, got {drill_factor!r}")

    # shear rows at the tying points (Bathe-Dvorkin): gamma_xi at eta = -1, +1;
    # gamma_eta at xi = -1, +1 (edge mid-points)
    g_xi_b = _shear_natural(xy, 0.0, -1.0, 0)
    g_xi_t = _shear_natural(xy, 0.0, 1.0, 0)
    g_eta_l = _shear_natural(xy, -1.0, 0.0, 1)
    g_eta_r = _shear_natural(xy, 1.0, 0.0, 1)

    gamma_d = drill_factor * abd[:, 2, 2]
    K = np.zeros((n_el, 24, 24))
    S = np.zeros((n_el, 4, 4))  # integral of N_a N_b dA
    for xi, eta in _GAUSS:
        N, dN = _shape(xi, eta)
        J = np.einsum("ka,eaj->ekj", dN, xy)
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        if np.any(det <= 0):
            bad = int(np.flatnonzero(det <= 0)[0])
            raise ParameterError(
                f"element {bad} is degenerate or numbered clockwise (det J = {det[bad]:.3g}); "
                "expected counter-clockwise nodes in the x-y plane"
            )
        Jinv = np.empty_like(J)
        Jinv[:, 0, 0] = J[:, 1, 1] / det
        Jinv[:, 1, 1] = J[:, 0, 0] / det
        Jinv[:, 0, 1] = -J[:, 0, 1] / det
        Jinv[:, 1, 0] = -J[:, 1, 0] / det
        dNx = np.einsum("eij,ja->eia", Jinv, dN)  # (n_el, 2, 4): d/dx, d/dy
        Nx, Ny = dNx[:, 0, :], dNx[:, 1, :]

        Bmb = np.zeros((n_el, 6, 4, 6))
        Bmb[:, 0, :, 0] = Nx
        Bmb[:, 1, :, 1] = Ny
        Bmb[:, 2, :, 0] = Ny
        Bmb[:, 2, :, 1] = Nx
        Bmb[:, 3, :, 4] = Nx
        Bmb[:, 4, :, 3] = -Ny
        Bmb[:, 5, :, 4] = Ny
        Bmb[:, 5, :, 3] = -Nx
        Bmb = Bmb.reshape(n_el, 6, 24)

        g_xi = 0.5 * (1 - eta) * g_xi_b + 0.5 * (1 + eta) * g_xi_t
        g_eta = 0.5 * (1 - xi) * g_eta_l + 0.5 * (1 + xi) * g_eta_r
        Bs = np.einsum("eij,ejk->eik", Jinv, np.stack([g_xi, g_eta], axis=1))

        Bd = np.zeros((n_el, 4, 6))
        Bd[:, :, 5] = N[None, :]
        Bd[:, :, 1] = -0.5 * Nx
        Bd[:, :, 0] = 0.5 * Ny
        Bd = Bd.reshape(n_el, 24)

        K += np.einsum("eki,ekl,elj,e->eij", Bmb, abd, Bmb, det, optimize=True)
        K += np.einsum("eki,ekl,elj,e->eij", Bs, h_shear, Bs, det, optimize=True)
        K += np.einsum("ei,ej,e->eij", Bd, Bd, gamma_d * det)
        S += det[:, None, None] * np.outer(N, N)[None, :, :]

    # nodal 6x6 inertia: generalised field d = (u, v, w, beta_x, beta_y, rz) = P q
    I0, I1, I2 = inertia[:, 0], inertia[:, 1], inertia[:, 2]
    m6 = np.zeros((n_el, 6, 6))
    m6[:, 0, 0] = m6[:, 1, 1] = m6[:, 2, 2] = I0
    m6[:, 3, 3] = m6[:, 4, 4] = I2
    m6[:, 5, 5] = DRILL_INERTIA_FACTOR * I2
    m6[:, 0, 3] = m6[:, 3, 0] = I1
    m6[:, 1, 4] = m6[:, 4, 1] = I1
    P = np.zeros((6, 6))
    P[0, 0] = P[1, 1] = P[2, 2] = P[5, 5] = 1.0
    P[3, 4] = 1.0   # beta_x = ry
    P[4, 3] = -1.0  # beta_y = -rx
    m_node = np.einsum("ki,ekl,lj->eij", P, m6, P)
    M = np.einsum("eab,eij->eaibj", S, m_node).reshape(n_el, 24, 24)
    return K, M
