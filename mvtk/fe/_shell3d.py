"""Layered shells at any orientation in space: element frames, MITC4 and MITC3 facets.

Element frames
--------------
Every shell element gets its own right-handed frame ``(e1, e2, e3)``:

- ``e3`` is the unit normal; for a quadrilateral the normalised cross product of its
  diagonals ``(x3 - x1) x (x4 - x2)``, for a triangle ``(x2 - x1) x (x3 - x1)``; node
  order therefore fixes the side of the normal (counter-clockwise seen from ``+e3``).
- ``e1`` is the projection of the user's **material orientation axis** ``a`` onto the
  element plane, ``e1 = (a - (a.e3) e3) / |...|``; ply angles of the section are measured
  from ``e1`` positive about ``e3``. When ``a`` is within 0.1 degree of the normal the
  projection of the next global axis is used (x, then y).
- ``e2 = e3 x e1``.

For a flat plate in the x-y plane with the default axis ``a = (1, 0, 0)`` the frame is the
global one, so these elements reproduce :func:`mvtk.fe.mitc4_matrices` exactly.

Curved surfaces are modelled as facets; the six nodal DOFs (ux, uy, uz, rx, ry, rz) stay
global, with the drilling penalty of :mod:`mvtk.fe._shell` giving the in-plane rotation
``rz`` of each facet a stiffness (needed where facets meet at an angle).

Warped quadrilaterals
---------------------
The four nodes of a warped quad do not lie in one plane. The element is computed on the
flat projection onto its mean plane (through the centroid, normal ``e3``); each node
``a`` lies at the distance ``d_a = (x_a - c).e3`` from that plane. The projected node
is tied to the true node by a rigid offset ``u_flat = u - d_a theta x e3``,
``theta_flat = theta``, so a rigid-body motion of the true nodes is a rigid-body motion
of the flat element and the warped element keeps exactly six zero-energy modes
(tested). This is the rigid-link warping correction used by flat-facet shells
(e.g. MacNeal, *Finite Elements: their design and performance*, 1994, ch. 9).

Triangle (MITC3)
----------------
Three nodes, linear displacements and rotations, FSDT:

- membrane: the constant-strain triangle (plus the Hughes-Brezzi drilling penalty of the
  quadrilateral, 3-point rule);
- bending: constant curvatures of the linear rotations;
- transverse shear: the MITC3 assumed strain of Lee & Bathe (2004). The covariant shear
  strain integrated along each edge, ``g_e = w_j - w_i + 1/2 (beta_i + beta_j).(x_j - x_i)``,
  is interpolated with the lowest-order edge (Whitney / Raviart-Thomas rotated)
  functions ``W_ij = l_i grad l_j - l_j grad l_i``. The field depends on no node
  numbering (the element is *isotropic*, unlike DSG3), which is why it was chosen over
  DSG3: a DSG3 result changes with the choice of the first node.
- MITC3 alone still stiffens slightly for very thin elements. The shear stiffness is
  therefore scaled as in the stabilised MITC elements of Lyly, Stenberg & Vihinen (1993):
  ``H_eff = H t^2 / (t^2 + alpha h_e^2)`` with ``h_e`` the longest edge and
  ``alpha = TRI_SHEAR_ALPHA = 0.1``; the factor tends to 1 as the mesh is refined
  (consistent), and removes shear locking from span/thickness 5 to 1000 (tested against
  the Navier FSDT solution of a simply supported plate).

Mass: consistent (linear shape functions, exact quadrature) with the same inertia terms
``I0, I1, I2`` as the quadrilateral.

References
----------
P.-S. Lee, K.-J. Bathe, "Development of MITC isotropic triangular shell finite elements",
Computers & Structures 82 (2004) 945-962.
M. Lyly, R. Stenberg, T. Vihinen, "A stable bilinear element for the Reissner-Mindlin
plate model", CMAME 110 (1993) 343-357.
"""

from __future__ import annotations

import numpy as np

from ..errors import DimensionError, ParameterError
from ._shell import DRILL_FACTOR, DRILL_INERTIA_FACTOR, mitc4_matrices

__all__ = [
    "TRI_SHEAR_ALPHA",
    "shell_frames",
    "mitc3_matrices",
    "shell_element_matrices",
    "shell_local_geometry",
]

#: Lyly-Stenberg shear stabilisation factor of the triangle (see module notes).
TRI_SHEAR_ALPHA = 0.1

_TRI_GAUSS = np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]])  # (l2, l3)


def shell_frames(xyz: np.ndarray, material_axis=(1.0, 0.0, 0.0)) -> np.ndarray:
    """Element frames of shell elements.

    Parameters
    ----------
    xyz : ndarray, shape (n_el, 3 or 4, 3)
        Node coordinates (m) of triangles or quadrilaterals.
    material_axis : array_like, shape (3,) or (n_el, 3)
        Material orientation axis; its projection on the element plane is ``e1``.

    Returns
    -------
    ndarray, shape (n_el, 3, 3)
        Rows ``e1, e2, e3`` of each element frame.

    Raises
    ------
    ParameterError
        If an element is degenerate (zero area).

    Examples
    --------
    A square in the x-y plane has the global axes as its frame; a square in the y-z plane
    with the material axis along y gets ``e1 = y``, ``e3 = x``:

    >>> np.round(shell_frames(np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.0]]])), 6) + 0.0
    array([[[1., 0., 0.],
            [0., 1., 0.],
            [0., 0., 1.]]])
    >>> square_yz = np.array([[[0, 0, 0], [0, 1, 0], [0, 1, 1], [0, 0, 1.0]]])
    >>> np.round(shell_frames(square_yz, material_axis=(0, 1, 0))[0, 2], 6) + 0.0
    array([1., 0., 0.])
    """
    xyz = np.asarray(xyz, dtype=float)
    if xyz.ndim != 3 or xyz.shape[1] not in (3, 4) or xyz.shape[2] != 3:
        raise DimensionError(f"xyz must have shape (n_el, 3 or 4, 3), got {xyz.shape}")
    if xyz.shape[1] == 4:
        n = np.cross(xyz[:, 2] - xyz[:, 0], xyz[:, 3] - xyz[:, 1])
    else:
        n = np.cross(xyz[:, 1] - xyz[:, 0], xyz[:, 2] - xyz[:, 0])
    nn = np.linalg.norm(n, axis=1)
    size = np.max(np.linalg.norm(xyz - xyz[:, :1], axis=2), axis=1)
    bad = nn <= 1e-12 * np.maximum(size, 1e-300) ** 2
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise ParameterError(f"shell element {i} is degenerate (zero area)")
    e3 = n / nn[:, None]
    a = np.broadcast_to(np.asarray(material_axis, dtype=float), e3.shape)
    e1 = a - np.sum(a * e3, axis=1)[:, None] * e3
    norm_a = np.linalg.norm(a, axis=1)
    if np.any(norm_a == 0):
        raise ParameterError("material_axis must be a non-zero vector")
    tol = np.sin(np.radians(0.1))
    weak = np.linalg.norm(e1, axis=1) < tol * norm_a
    for fallback in (np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        if not np.any(weak):
            break
        e1[weak] = fallback - (e3[weak] @ fallback)[:, None] * e3[weak]
        weak &= np.linalg.norm(e1, axis=1) < tol
    e1 = e1 / np.linalg.norm(e1, axis=1)[:, None]
    e2 = np.cross(e3, e1)
    return np.stack([e1, e2, e3], axis=1)


def _nodal_inertia(inertia: np.ndarray) -> np.ndarray:
    """Nodal 6x6 inertia (n_el, 6, 6) in DOF order (u, v, w, rx, ry, rz)."""
    n_el = len(inertia)
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
    return np.einsum("ki,ekl,lj->eij", P, m6, P)


def mitc3_matrices(
    xy: np.ndarray,
    abd: np.ndarray,
    h_shear: np.ndarray,
    inertia: np.ndarray,
    thickness: np.ndarray,
    drill_factor: float = DRILL_FACTOR,
    alpha: float = TRI_SHEAR_ALPHA,
) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and consistent mass of flat layered MITC3 triangles (local frame).

    Parameters
    ----------
    xy : ndarray, shape (n_el, 3, 2)
        Node coordinates (m) in the element plane, counter-clockwise.
    abd, h_shear, inertia
        Section matrices as in :func:`mvtk.fe.mitc4_matrices`.
    thickness : ndarray, shape (n_el,)
        Section thickness (m), used by the shear stabilisation.
    drill_factor : float
        Drilling penalty relative to ``A66``.
    alpha : float
        Shear stabilisation factor (0 = plain MITC3).

    Returns
    -------
    K, M : ndarray, shape (n_el, 18, 18)
        DOF order per node: ux, uy, uz, rx, ry, rz.

    Examples
    --------
    One right triangle (legs 100 mm) of 2 mm steel: a unit uz translation of its three
    nodes carries the element mass ``rho h A`` = 0.0785 kg:

    >>> from mvtk.fe import IsotropicMaterial, Laminate, Ply
    >>> lam = Laminate((Ply(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0), 2e-3),))
    >>> xy = np.array([[[0.0, 0.0], [0.1, 0.0], [0.0, 0.1]]])
    >>> K, M = mitc3_matrices(xy, lam.ABD[None], lam.H[None],
    ...                       np.array([[lam.I0, lam.I1, lam.I2]]), np.array([2e-3]))
    >>> uz = np.zeros(18)
    >>> uz[2::6] = 1.0
    >>> K.shape, round(float(uz @ M[0] @ uz), 6)
    ((1, 18, 18), 0.0785)
    """
    xy = np.asarray(xy, dtype=float)
    n_el = xy.shape[0]
    if xy.shape != (n_el, 3, 2):
        raise DimensionError(f"xy must have shape (n_el, 3, 2), got {xy.shape}")
    abd = np.broadcast_to(np.asarray(abd, dtype=float), (n_el, 6, 6))
    h_shear = np.broadcast_to(np.asarray(h_shear, dtype=float), (n_el, 2, 2))
    inertia = np.broadcast_to(np.asarray(inertia, dtype=float), (n_el, 3))
    t = np.broadcast_to(np.asarray(thickness, dtype=float), (n_el,))
    x, y = xy[:, :, 0], xy[:, :, 1]
    # gradients of the barycentric coordinates: dl_i/dx = b_i / 2A, dl_i/dy = c_i / 2A
    b = np.stack([y[:, 1] - y[:, 2], y[:, 2] - y[:, 0], y[:, 0] - y[:, 1]], axis=1)
    c = np.stack([x[:, 2] - x[:, 1], x[:, 0] - x[:, 2], x[:, 1] - x[:, 0]], axis=1)
    area2 = x[:, 1] * y[:, 2] - x[:, 2] * y[:, 1] - x[:, 0] * y[:, 2] + x[:, 2] * y[:, 0] \
        + x[:, 0] * y[:, 1] - x[:, 1] * y[:, 0]
    if np.any(area2 <= 0):
        bad = int(np.flatnonzero(area2 <= 0)[0])
        raise ParameterError(
            f"triangle {bad} is degenerate or numbered clockwise (2A = {area2[bad]:.3g})"
        )
    area = area2 / 2
    gx, gy = b / area2[:, None], c / area2[:, None]  # (n_el, 3)

    # membrane + bending (constant)
    Bmb = np.zeros((n_el, 6, 3, 6))
    Bmb[:, 0, :, 0] = gx
    Bmb[:, 1, :, 1] = gy
    Bmb[:, 2, :, 0] = gy
    Bmb[:, 2, :, 1] = gx
    Bmb[:, 3, :, 4] = gx
    Bmb[:, 4, :, 3] = -gy
    Bmb[:, 5, :, 4] = gy
    Bmb[:, 5, :, 3] = -gx
    Bmb = Bmb.reshape(n_el, 6, 18)
    K = np.einsum("eki,ekl,elj,e->eij", Bmb, abd, Bmb, area, optimize=True)

    # MITC3 shear: edge integrals g_e (n_el, 3 edges, 18)
    edges = ((0, 1), (1, 2), (2, 0))
    g = np.zeros((n_el, 3, 3, 6))
    for k, (i, j) in enumerate(edges):
        dx = x[:, j] - x[:, i]
        dy = y[:, j] - y[:, i]
        g[:, k, i, 2] -= 1.0
        g[:, k, j, 2] += 1.0
        for a in (i, j):
            g[:, k, a, 4] += 0.5 * dx   # beta_x = ry
            g[:, k, a, 3] -= 0.5 * dy   # beta_y = -rx
    g = g.reshape(n_el, 3, 18)
    hmax = np.max(np.linalg.norm(xy - np.roll(xy, 1, axis=1), axis=2), axis=1)
    scale = t**2 / (t**2 + alpha * hmax**2)
    hs = h_shear * scale[:, None, None]
    gamma_d = drill_factor * abd[:, 2, 2]
    grad = np.stack([gx, gy], axis=1)  # (n_el, 2, 3)
    S = np.zeros((n_el, 3, 3))
    for l2, l3 in _TRI_GAUSS:
        lam = np.array([1 - l2 - l3, l2, l3])
        W = np.stack([lam[i] * grad[:, :, j] - lam[j] * grad[:, :, i] for i, j in edges],
                     axis=2)  # (n_el, 2, 3 edges)
        Bs = np.einsum("edk,ekj->edj", W, g)
        w = area / 3
        K += np.einsum("eki,ekl,elj,e->eij", Bs, hs, Bs, w, optimize=True)
        Bd = np.zeros((n_el, 3, 6))
        Bd[:, :, 5] = lam[None, :]
        Bd[:, :, 1] -= 0.5 * gx
        Bd[:, :, 0] += 0.5 * gy
        Bd = Bd.reshape(n_el, 18)
        K += np.einsum("ei,ej,e->eij", Bd, Bd, gamma_d * w)
        S += w[:, None, None] * np.outer(lam, lam)[None, :, :]
    M = np.einsum("eab,eij->eaibj", S, _nodal_inertia(inertia)).reshape(n_el, 18, 18)
    return K, M


def _rotation_blocks(R: np.ndarray, n_nodes: int) -> np.ndarray:
    """Block-diagonal (n_el, 6n, 6n) rotation built from the frames R (n_el, 3, 3)."""
    n_el = len(R)
    T = np.zeros((n_el, 6 * n_nodes, 6 * n_nodes))
    for b in range(2 * n_nodes):
        T[:, 3 * b:3 * b + 3, 3 * b:3 * b + 3] = R
    return T


def shell_element_matrices(
    xyz: np.ndarray,
    abd: np.ndarray,
    h_shear: np.ndarray,
    inertia: np.ndarray,
    thickness: np.ndarray,
    material_axis=(1.0, 0.0, 0.0),
    drill_factor: float = DRILL_FACTOR,
) -> tuple[np.ndarray, np.ndarray]:
    """Global-frame stiffness and mass of shell elements at any orientation.

    Parameters
    ----------
    xyz : ndarray, shape (n_el, 3, 3) or (n_el, 4, 3)
        Node coordinates (m): MITC3 triangles or MITC4 quadrilaterals (possibly warped).
    abd, h_shear, inertia
        Section matrices in the element frame (ply angles from ``e1``), see
        :class:`mvtk.fe.Laminate`; shapes (n_el, 6, 6), (n_el, 2, 2), (n_el, 3) or
        broadcastable.
    thickness : ndarray, shape (n_el,)
        Section thickness (m), used by the triangle's shear stabilisation.
    material_axis : array_like, shape (3,) or (n_el, 3)
        See :func:`shell_frames`.
    drill_factor : float
        See :mod:`mvtk.fe._shell`.

    Returns
    -------
    K, M : ndarray, shape (n_el, 6k, 6k)
        Global DOFs (ux, uy, uz, rx, ry, rz) per node, nodes in element order.

    Examples
    --------
    A 100 x 100 mm quad of 2 mm steel standing in the x-z plane: a unit translation along
    its normal (y) carries ``rho h A`` = 0.157 kg and costs no strain energy:

    >>> from mvtk.fe import IsotropicMaterial, Laminate, Ply
    >>> lam = Laminate((Ply(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0), 2e-3),))
    >>> xyz = np.array([[[0, 0, 0], [0.1, 0, 0], [0.1, 0, 0.1], [0, 0, 0.1]]], dtype=float)
    >>> K, M = shell_element_matrices(xyz, lam.ABD[None], lam.H[None],
    ...                               np.array([[lam.I0, lam.I1, lam.I2]]), np.array([2e-3]))
    >>> uy = np.zeros(24)
    >>> uy[1::6] = 1.0
    >>> round(float(uy @ M[0] @ uy), 6), bool(np.abs(K[0] @ uy).max() < 1e-6)
    (0.157, True)
    """
    xyz = np.asarray(xyz, dtype=float)
    n_el, k = xyz.shape[:2]
    local3, R = _local_frames(xyz, material_axis)
    local = local3[:, :, :2]
    # local matrices depend only on the in-plane shape and the section: with one section
    # for all elements, compute each distinct shape once (structured and swept meshes,
    # e.g. a cylinder, have a handful), as the built-in rectangular path does
    first, rep = None, None
    if _shared(abd, 3) and _shared(h_shear, 3) and _shared(inertia, 2) and (
            np.ndim(thickness) == 0 or np.ptp(np.asarray(thickness)) == 0):
        first, rep = _distinct_shapes(local)
        if len(first) == n_el:
            first, rep = None, None
    pick = local if first is None else local[first]
    if k == 4:
        Kl, Ml = mitc4_matrices(pick, abd, h_shear, inertia, drill_factor)
    else:
        th = np.broadcast_to(thickness, (n_el,))
        Kl, Ml = mitc3_matrices(pick, abd, h_shear, inertia,
                                th if first is None else th[first], drill_factor)
    if rep is not None:
        Kl, Ml = Kl[rep], Ml[rep]
    d = local3[:, :, 2]
    size = np.abs(local).max(axis=(1, 2))
    if np.all(np.abs(d).max(axis=1) <= 1e-12 * size):
        # flat elements (to round-off: the nodes of a quad on a cylinder lie in a plane,
        # the computed d is ~1e-17 m): T is block diagonal with R in every 3x3 block
        return _rotate_blocks(Kl, R, k), _rotate_blocks(Ml, R, k)
    T = _warped_transform(R, d, k)
    Tt = np.swapaxes(T, 1, 2)
    return Tt @ Kl @ T, Tt @ Ml @ T


def _shared(a, ndim: int) -> bool:
    """True when a per-element array is one value for all elements (broadcast)."""
    a = np.asarray(a)
    return a.ndim < ndim or a.shape[0] == 1 or bool(np.all(a == a[:1]))


def _distinct_shapes(local: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Representatives of the distinct in-plane shapes (to 1e-10 of each element's own
    size, so graded meshes keep their small elements exact) and, for every element, the
    index of its representative."""
    flat = local.reshape(len(local), -1)
    octave = np.floor(np.log2(np.maximum(np.abs(flat).max(axis=1), 1e-300)))
    key = np.column_stack([np.round(flat / (1e-10 * 2.0**octave[:, None])),
                           octave]).astype(np.int64)
    _, first, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return first, inverse.ravel()


def _rotate_blocks(Kl: np.ndarray, R: np.ndarray, k: int) -> np.ndarray:
    """T' Kl T for T = diag(R, R, ...) (2k blocks of 3x3), without forming T."""
    n_el, m = len(Kl), 2 * k
    # K_ab R for all blocks at once: (e, [a i b], j) @ (e, j, q)
    X = np.matmul(Kl.reshape(n_el, m * 3 * m, 3), R)
    # R' on the row index i: (e, p, i) @ (e, i, [a b q])
    X = X.reshape(n_el, m, 3, m * 3).transpose(0, 2, 1, 3).reshape(n_el, 3, m * m * 3)
    X = np.matmul(np.swapaxes(R, 1, 2), X).reshape(n_el, 3, m, m, 3)
    return np.ascontiguousarray(X.transpose(0, 2, 1, 3, 4)).reshape(n_el, 6 * k, 6 * k)


def _local_frames(xyz: np.ndarray, material_axis) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates in the element frame (n_el, k, 3; origin at the centroid) and the
    frames R (n_el, 3, 3, rows e1 e2 e3)."""
    R = shell_frames(xyz, material_axis)
    c = xyz.mean(axis=1, keepdims=True)
    return np.einsum("eij,eaj->eai", R, xyz - c), R


def _warped_transform(R: np.ndarray, d: np.ndarray, k: int) -> np.ndarray:
    """Rotation blocks times the rigid offset of each node to the mean plane."""
    n_el = len(R)
    T = _rotation_blocks(R, k)
    # u_flat = u + d [e3]x theta  (rigid offset from the true node to the mean plane)
    e3 = R[:, 2]
    cross = np.zeros((n_el, 3, 3))
    cross[:, 0, 1], cross[:, 0, 2] = -e3[:, 2], e3[:, 1]
    cross[:, 1, 0], cross[:, 1, 2] = e3[:, 2], -e3[:, 0]
    cross[:, 2, 0], cross[:, 2, 1] = -e3[:, 1], e3[:, 0]
    W = np.tile(np.eye(6 * k), (n_el, 1, 1))
    for a in range(k):
        W[:, 6 * a:6 * a + 3, 6 * a + 3:6 * a + 6] = d[:, a, None, None] * cross
    return T @ W


def shell_local_geometry(xyz: np.ndarray, material_axis=(1.0, 0.0, 0.0)
                         ) -> tuple[np.ndarray, np.ndarray]:
    """In-plane local coordinates and the global-to-element DOF transformation.

    Returns
    -------
    xy : ndarray (n_el, k, 2)
        Node coordinates in the element frame (origin at the centroid, mean plane).
    T : ndarray (n_el, 6k, 6k)
        ``q_local = T q_global``: frame rotation and, for warped quads, the rigid offset
        of each node to the mean plane (see the module notes).
    """
    xyz = np.asarray(xyz, dtype=float)
    k = xyz.shape[1]
    local, R = _local_frames(xyz, material_axis)
    d = local[:, :, 2]  # distance of each node from the mean plane (warping)
    T = _warped_transform(R, d, k) if np.any(np.abs(d) > 0) else _rotation_blocks(R, k)
    return local[:, :, :2], T
