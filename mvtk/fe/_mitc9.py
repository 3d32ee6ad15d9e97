"""MITC9: nine-node curved shell with mixed interpolation of tensorial components.

Geometry and kinematics (continuum-based, or degenerated, shell): with the 9-node
Lagrange functions ``N_i(r, s)``, nodal mid-surface points ``x_i`` and unit nodal
directors ``n_i`` (averaged surface normals), a point at distance ``z`` from the node
surface along the director is ``x = sum N_i (x_i + z n_i)`` and its displacement
``u = sum N_i (u_i + z theta_i x n_i)``; the six nodal DOFs (ux, uy, uz, rx, ry, rz) are
global. The covariant strains ``e_ij = (g_i . u_,j + g_j . u_,i)/2`` (``i, j`` in
``r, s, z``) are not used directly: the in-plane and transverse shear components are
interpolated from tying points (Bucalem & Bathe 1993), with ``a = 1/sqrt(3)``,
``b = sqrt(3/5)``:

- ``e_rr``, ``e_rz``: at ``r = +-a`` (linear in r) and ``s = -b, 0, b`` (quadratic in s);
- ``e_ss``, ``e_sz``: the same with r and s exchanged;
- ``e_rs``: at ``(+-a, +-a)``, bilinear.

The tied tensor is transformed to the lamina frame ``(e1, e2, e3)`` of each integration
point (``e3`` the surface normal, ``e1`` the projection of the material axis) with the
contravariant base vectors. In-plane strains are evaluated at ``z = +-t/(2 sqrt 3)``
and split into membrane strains ``e`` and curvatures ``kappa`` (``eps(z) = e + z kappa``),
which enter the laminate's ``ABD`` matrix; transverse shear strains at ``z = 0`` enter
``H``. 3 x 3 Gauss points over the surface. The rotation about the normal gets the
Hughes-Brezzi drilling penalty of :mod:`mvtk.fe._shell` (``DRILL_FACTOR * A66``),
tying it to the in-plane rotation of the surface, so rigid-body motions stay free.

Mass: consistent, ``I0`` (translations), ``I1`` (coupling), ``I2`` (rotary), plus the
token drilling inertia of :mod:`mvtk.fe._shell`.

Node order: corners 1-4 counter-clockwise about the intended normal, mid-side nodes 5
(1-2), 6 (2-3), 7 (3-4), 8 (4-1), centre 9 (Gmsh, Abaqus S9R5 and Nastran CQUAD9 order).

References
----------
M. L. Bucalem, K.-J. Bathe, "Higher-order MITC general shell elements", International
Journal for Numerical Methods in Engineering 36 (1993) 3729-3754.
K.-J. Bathe, *Finite Element Procedures*, 2nd ed. (2014), section 5.4.
"""

from __future__ import annotations

import numpy as np

from ._shell import DRILL_FACTOR, DRILL_INERTIA_FACTOR

__all__ = ["mitc9_matrices", "NODE_RS"]

#: Natural coordinates of the nine nodes.
NODE_RS = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0],
                    [0, 0]], dtype=float)
_A = 1.0 / np.sqrt(3.0)
_B = np.sqrt(0.6)
_GP = np.array([-_B, 0.0, _B])
_GW = np.array([5.0, 8.0, 5.0]) / 9.0
# 1-D index (0: -1, 1: 0, 2: +1) of each node in r and s
_IR = np.array([0, 2, 2, 0, 1, 2, 1, 0, 1])
_IS = np.array([0, 0, 2, 2, 0, 1, 2, 1, 1])


def _lag3(x: float) -> tuple[np.ndarray, np.ndarray]:
    return (np.array([x * (x - 1) / 2, 1 - x * x, x * (x + 1) / 2]),
            np.array([x - 0.5, -2 * x, x + 0.5]))


def _shape(r: float, s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    lr, dr = _lag3(r)
    ls, ds = _lag3(s)
    return lr[_IR] * ls[_IS], dr[_IR] * ls[_IS], lr[_IR] * ds[_IS]


def _lag(x: float, pts: np.ndarray) -> np.ndarray:
    """Lagrange weights of the points ``pts`` at x."""
    w = np.ones(len(pts))
    for i, p in enumerate(pts):
        for j, q in enumerate(pts):
            if i != j:
                w[i] *= (x - q) / (p - q)
    return w


def _cross(n: np.ndarray) -> np.ndarray:
    """[n]x for n (k, 3) -> (k, 3, 3)."""
    out = np.zeros(n.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -n[..., 2], n[..., 1]
    out[..., 1, 0], out[..., 1, 2] = n[..., 2], -n[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -n[..., 1], n[..., 0]
    return out


def _point(x, nx, ncross, r, s, z):
    """Shape functions, base vectors g_i (rows) and covariant strain rows E_ij (54) at
    (r, s, z) of every element: N (9,), g (n, 3, 3), U (n, 3, 3, 54), E (n, 3, 3, 54)."""
    N, dNr, dNs = _shape(r, s)
    xz = x + z * nx
    g = np.stack([np.einsum("i,eij->ej", dNr, xz), np.einsum("i,eij->ej", dNs, xz),
                  np.einsum("i,eij->ej", N, nx)], axis=1)
    n = len(x)
    U = np.zeros((n, 3, 3, 9, 6))
    eye = np.eye(3)
    for k, dN in enumerate((dNr, dNs)):
        U[:, k, :, :, :3] = np.einsum("i,ab->aib", dN, eye)[None]
        U[:, k, :, :, 3:] = -z * np.einsum("i,eiab->eaib", dN, ncross)
    U[:, 2, :, :, 3:] = -np.einsum("i,eiab->eaib", N, ncross)
    U = U.reshape(n, 3, 3, 54)
    E = np.einsum("eia,ejab->eijb", g, U)
    return N, g, U, 0.5 * (E + E.transpose(0, 2, 1, 3))


def _frames(g: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Lamina frames (n, 3, 3), rows e1 e2 e3, from g_r x g_s and the material axis."""
    e3 = np.cross(g[:, 0], g[:, 1])
    e3 /= np.linalg.norm(e3, axis=1)[:, None]
    ax = np.broadcast_to(axis, e3.shape)
    a = ax - np.einsum("ej,ej->e", ax, e3)[:, None] * e3
    bad = np.linalg.norm(a, axis=1) < 1e-3 * np.linalg.norm(ax, axis=1)
    for alt in np.eye(3):
        if not np.any(bad):
            break
        b = alt - (e3[bad] @ alt)[:, None] * e3[bad]
        ok = np.linalg.norm(b, axis=1) > 0.1
        idx = np.flatnonzero(bad)[ok]
        a[idx] = b[ok]
        bad[idx] = False
    e1 = a / np.linalg.norm(a, axis=1)[:, None]
    return np.stack([e1, np.cross(e3, e1), e3], axis=1)


def _vec(t: np.ndarray) -> np.ndarray:
    """Engineering in-plane strain rows (n, 3, 54) of a strain tensor (n, 3, 3, 54)."""
    return np.stack([t[:, 0, 0], t[:, 1, 1], 2 * t[:, 0, 1]], axis=1)


def mitc9_matrices(xyz, directors, abd, h_shear, inertia, thickness,
                   material_axis=(1.0, 0.0, 0.0), drill_factor: float = DRILL_FACTOR
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass (global DOFs) of MITC9 shell elements.

    Parameters
    ----------
    xyz : ndarray (n_el, 9, 3)
        Node coordinates (m), order in the module notes.
    directors : ndarray (n_el, 9, 3)
        Unit nodal directors (normals of the node surface, on the side of the
        counter-clockwise normal).
    abd : ndarray (6, 6), h_shear : (2, 2), inertia : (3,)
        Laminate matrices (:class:`mvtk.fe.Laminate` ``ABD``, ``H``, ``I0 I1 I2``) with
        ply angles from the material axis; or one per element (leading axis n_el).
    thickness : float
        Laminate thickness (m): sets the two levels ``z = +-t/(2 sqrt 3)`` at which the
        in-plane strains are split into membrane strains and curvatures.
    material_axis : (3,) or (n_el, 3)
        Global direction whose projection is the lamina ``e1``.
    drill_factor : float

    Returns
    -------
    K, M : ndarray (n_el, 54, 54)
        DOFs (ux, uy, uz, rx, ry, rz) per node, nodes in element order.
    """
    x = np.asarray(xyz, dtype=float)
    nx = np.asarray(directors, dtype=float)
    n = len(x)
    axis = np.asarray(material_axis, dtype=float)
    abd = np.broadcast_to(np.asarray(abd, float), (n, 6, 6))
    hs = np.broadcast_to(np.asarray(h_shear, float), (n, 2, 2))
    I0, I1, I2 = (np.broadcast_to(np.asarray(inertia, float), (n, 3))[:, k] for k in range(3))
    zg = thickness / (2 * np.sqrt(3.0))
    gamma_d = drill_factor * abd[:, 2, 2]
    ncross = _cross(nx)
    ta, tb = np.array([-_A, _A]), _GP
    tie_r = [(r, s) for r in ta for s in tb]  # e_rr, e_rz
    tie_s = [(r, s) for s in ta for r in tb]  # e_ss, e_sz
    tie_rs = [(r, s) for r in ta for s in ta]
    tied = {z: tuple(np.stack([_point(x, nx, ncross, r, s, z)[3] for r, s in pts])
                     for pts in (tie_r, tie_s, tie_rs)) for z in (-zg, zg, 0.0)}
    K = np.zeros((n, 54, 54))
    M = np.zeros((n, 54, 54))
    eye = np.eye(3)
    for a, r in enumerate(_GP):
        for b, s in enumerate(_GP):
            w = _GW[a] * _GW[b]
            wr = np.outer(_lag(r, ta), _lag(s, tb)).ravel()
            ws = np.outer(_lag(s, ta), _lag(r, tb)).ravel()
            wrs = np.outer(_lag(r, ta), _lag(s, ta)).ravel()
            N0, g0, U0, _ = _point(x, nx, ncross, r, s, 0.0)
            R = _frames(g0, axis)
            dA = np.linalg.norm(np.cross(g0[:, 0], g0[:, 1]), axis=1) * w
            strains = {}
            for z in (-zg, zg, 0.0):
                _, g, _, E = _point(x, nx, ncross, r, s, z)
                Er, Es, Ers = tied[z]
                E = E.copy()
                E[:, 0, 0] = np.einsum("t,tek->ek", wr, Er[:, :, 0, 0])
                E[:, 0, 2] = E[:, 2, 0] = np.einsum("t,tek->ek", wr, Er[:, :, 0, 2])
                E[:, 1, 1] = np.einsum("t,tek->ek", ws, Es[:, :, 1, 1])
                E[:, 1, 2] = E[:, 2, 1] = np.einsum("t,tek->ek", ws, Es[:, :, 1, 2])
                E[:, 0, 1] = E[:, 1, 0] = np.einsum("t,tek->ek", wrs, Ers[:, :, 0, 1])
                E[:, 2, 2] = 0.0
                gcon = np.swapaxes(np.linalg.inv(g), 1, 2)  # rows g^i
                C = np.einsum("eik,eak->eia", gcon, R)  # g^i . e_a
                strains[z] = np.einsum("eia,ejb,eijk->eabk", C, C, E)
            Bm = 0.5 * (_vec(strains[-zg]) + _vec(strains[zg]))
            Bk = (_vec(strains[zg]) - _vec(strains[-zg])) / (2 * zg)
            Bmk = np.concatenate([Bm, Bk], axis=1)
            Bs = 2 * strains[0.0][:, [0, 1], 2]
            K += np.einsum("eki,ekl,elj,e->eij", Bmk, abd, Bmk, dA, optimize=True)
            K += np.einsum("eki,ekl,elj,e->eij", Bs, hs, Bs, dA, optimize=True)
            # drilling: rotation about e3 minus the in-plane rotation of the surface
            gcon0 = np.swapaxes(np.linalg.inv(g0), 1, 2)
            C0 = np.einsum("eik,eak->eia", gcon0, R)
            du = np.einsum("eia,eijk->eajk", C0[:, :, :2], U0)  # u_,1 and u_,2
            rot = np.zeros((n, 9, 6))
            rot[:, :, 3:] = N0[None, :, None] * R[:, None, 2]
            Bd = rot.reshape(n, 54) - 0.5 * (np.einsum("ej,ejk->ek", R[:, 1], du[:, 0])
                                             - np.einsum("ej,ejk->ek", R[:, 0], du[:, 1]))
            K += np.einsum("ei,ej,e->eij", Bd, Bd, gamma_d * dA)
            Nu = np.zeros((n, 3, 9, 6))
            Nu[:, :, :, :3] = np.einsum("i,ab->aib", N0, eye)[None]
            Nt = np.zeros((n, 3, 9, 6))
            Nt[:, :, :, 3:] = -np.einsum("i,eiab->eaib", N0, ncross)
            Nu, Nt = Nu.reshape(n, 3, 54), Nt.reshape(n, 3, 54)
            uu = np.einsum("eki,ekj->eij", Nu, Nu)
            ut = np.einsum("eki,ekj->eij", Nu, Nt)
            tt = np.einsum("eki,ekj->eij", Nt, Nt)
            dd = np.einsum("ei,ej->eij", rot.reshape(n, 54), rot.reshape(n, 54))
            M += ((I0 * dA)[:, None, None] * uu + (I1 * dA)[:, None, None]
                  * (ut + np.swapaxes(ut, 1, 2)) + (I2 * dA)[:, None, None] * tt
                  + (DRILL_INERTIA_FACTOR * I2 * dA)[:, None, None] * dd)
    return 0.5 * (K + np.swapaxes(K, 1, 2)), 0.5 * (M + np.swapaxes(M, 1, 2))
