"""Small self-contained FE models for tests, examples and the reduction benchmark.

These are *not* the toolkit's element library (see :mod:`mvtk.fe`); they exist so the
reduction can be verified against closed forms independently of it.

- :func:`eb_beam_xz`: Euler-Bernoulli beam along x bending in the x-z plane, DOFs
  ``uz`` and ``ry`` only (cubic Hermite element, consistent mass).
- :func:`frame_grid`: a plate-like grillage of 3-D Euler-Bernoulli frame members along
  x and y with 6 DOFs per node, for large-model timings.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import ParameterError
from ..fe import FEModel

__all__ = ["eb_beam_xz", "frame_grid"]


def _hermite(E, I, rho, A, le):
    """Stiffness and consistent mass of a cubic Hermite element, DOFs (w1, t1, w2, t2).

    Rotation ``t = dw/dx``. With ``ry`` positive about +y, a positive ``ry`` gives
    negative ``uz`` slope (right-hand rule), so the model stores ``ry = -dw/dx``.
    """
    k = E * I / le**3 * np.array(
        [
            [12, 6 * le, -12, 6 * le],
            [6 * le, 4 * le**2, -6 * le, 2 * le**2],
            [-12, -6 * le, 12, -6 * le],
            [6 * le, 2 * le**2, -6 * le, 4 * le**2],
        ]
    )
    m = rho * A * le / 420 * np.array(
        [
            [156, 22 * le, 54, -13 * le],
            [22 * le, 4 * le**2, 13 * le, -3 * le**2],
            [54, 13 * le, 156, -22 * le],
            [-13 * le, -3 * le**2, -22 * le, 4 * le**2],
        ]
    )
    return k, m


def eb_beam_xz(
    n_el: int = 40,
    length: float = 0.2,
    E: float = 210e9,
    rho: float = 7900.0,
    width: float = 0.02,
    thickness: float = 0.5e-3,
    clamped: bool = True,
) -> FEModel:
    """Euler-Bernoulli beam along x in the x-z plane (DOFs ``uz``, ``ry``).

    Parameters
    ----------
    n_el : int
        Number of elements (nodes ``0..n_el`` at ``x = i L / n_el``).
    length, width, thickness : float
        Beam length, width and thickness in m.
    E : float
        Young's modulus in Pa.
    rho : float
        Density in kg/m^3.
    clamped : bool
        Clamp node 0 (remove its two DOFs) or leave the beam free-free.

    Returns
    -------
    FEModel
        Node sets ``"clamp"`` (node 0), ``"tip"`` (last node), ``"mid"`` (middle node).
        ``meta`` holds ``mass_kg``, ``EI``, ``rhoA`` and ``length``.
    """
    if n_el < 1:
        raise ParameterError(f"n_el must be >= 1, got {n_el}")
    A = width * thickness
    inertia = width * thickness**3 / 12
    le = length / n_el
    k, m = _hermite(E, inertia, rho, A, le)
    sign = np.array([1.0, -1.0, 1.0, -1.0])  # theta = dw/dx -> ry = -dw/dx
    k = k * np.outer(sign, sign)
    m = m * np.outer(sign, sign)
    nn = n_el + 1
    rows, cols, kv, mv = [], [], [], []
    for e in range(n_el):
        dofs = np.array([2 * e, 2 * e + 1, 2 * e + 2, 2 * e + 3])
        rows.append(np.repeat(dofs, 4))
        cols.append(np.tile(dofs, 4))
        kv.append(k.ravel())
        mv.append(m.ravel())
    r, c = np.concatenate(rows), np.concatenate(cols)
    K = sp.csr_matrix((np.concatenate(kv), (r, c)), shape=(2 * nn, 2 * nn))
    M = sp.csr_matrix((np.concatenate(mv), (r, c)), shape=(2 * nn, 2 * nn))
    dof_node = np.repeat(np.arange(nn), 2)
    dof_comp = np.tile([2, 4], nn)
    free = np.arange(2 * nn)[2:] if clamped else np.arange(2 * nn)
    nodes = np.zeros((nn, 3))
    nodes[:, 0] = np.linspace(0.0, length, nn)
    return FEModel(
        nodes=nodes,
        M=M[free][:, free],
        K=K[free][:, free],
        dof_node=dof_node[free],
        dof_component=dof_comp[free],
        node_sets={"clamp": [0], "tip": [n_el], "mid": [n_el // 2]},
        elements={"beam2": np.column_stack([np.arange(n_el), np.arange(1, nn)])},
        name=f"Euler-Bernoulli beam, {n_el} elements",
        meta={"mass_kg": rho * A * length, "EI": E * inertia, "rhoA": rho * A,
              "length": length},
    )


def _frame_local(E, G, rho, A, Iy, Iz, J, le):
    """12x12 stiffness and consistent mass of a 3-D frame member along its local x."""
    k = np.zeros((12, 12))
    m = np.zeros((12, 12))
    # axial (0, 6) and torsion (3, 9)
    for a, b, s, mm in ((0, 6, E * A / le, rho * A * le), (3, 9, G * J / le,
                                                             rho * (Iy + Iz) * le)):
        k[np.ix_([a, b], [a, b])] = s * np.array([[1, -1], [-1, 1]])
        m[np.ix_([a, b], [a, b])] = mm / 6 * np.array([[2, 1], [1, 2]])
    kb, mb = _hermite(E, Iz, rho, A, le)
    idx = [1, 5, 7, 11]  # v, rz: rz = dv/dx
    k[np.ix_(idx, idx)] += kb
    m[np.ix_(idx, idx)] += mb
    kb, mb = _hermite(E, Iy, rho, A, le)
    sign = np.array([1.0, -1.0, 1.0, -1.0])  # w, ry: ry = -dw/dx
    idx = [2, 4, 8, 10]
    k[np.ix_(idx, idx)] += kb * np.outer(sign, sign)
    m[np.ix_(idx, idx)] += mb * np.outer(sign, sign)
    return k, m


def frame_grid(
    nx: int = 90,
    ny: int = 92,
    lx: float = 0.18,
    ly: float = 0.133,
    thickness: float = 0.5e-3,
    E: float = 210e9,
    nu: float = 0.3,
    rho: float = 7900.0,
) -> FEModel:
    """Plate-like grillage of frame members, clamped along ``x = 0``, 6 DOFs per node.

    Members along x carry a strip of width ``ly / ny`` and members along y a strip of
    width ``lx / nx``, each with the plate thickness, so the bending stiffness and the
    mass approximate a plate (without Poisson coupling). Used for timings only.

    Returns
    -------
    FEModel
        ``(nx + 1) * (ny + 1)`` nodes, the ``x = 0`` edge clamped; node sets ``"clamp"``,
        ``"tip"`` (nodes at ``x = lx``) and ``"corner"`` (``x = lx, y = ly``).
    """
    if nx < 1 or ny < 1:
        raise ParameterError(f"nx and ny must be >= 1, got {nx}, {ny}")
    G = E / (2 * (1 + nu))
    nn_x, nn_y = nx + 1, ny + 1
    ids = np.arange(nn_x * nn_y).reshape(nn_y, nn_x)  # ids[j, i], node at x_i, y_j
    xs, ys = np.linspace(0, lx, nn_x), np.linspace(0, ly, nn_y)
    X, Y = np.meshgrid(xs, ys)
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    rows, cols, kv, mv = [], [], [], []

    def add(n1, n2, k, m, perm):
        # perm maps local DOF order to global components of a member along y:
        # local x -> global y, local y -> global -x, local z -> z
        dofs = np.concatenate([n1[:, None] * 6 + perm[None, :6],
                               n2[:, None] * 6 + perm[None, 6:]], axis=1)
        rows.append(np.repeat(dofs, 12, axis=1).ravel())
        cols.append(np.tile(dofs, (1, 12)).ravel())
        kv.append(np.broadcast_to(k.ravel(), (len(n1), 144)).ravel())
        mv.append(np.broadcast_to(m.ravel(), (len(n1), 144)).ravel())

    t = thickness
    # members along x, strip width ly/ny
    b = ly / ny
    A, Iy, Iz = b * t, b * t**3 / 12, t * b**3 / 12
    J = b * t**3 / 3
    k, m = _frame_local(E, G, rho, A, Iy, Iz, J, lx / nx)
    add(ids[:, :-1].ravel(), ids[:, 1:].ravel(), k, m, np.tile(np.arange(6), 2))
    # members along y: rotate local (x, y, z) -> global (y, -x, z)
    b = lx / nx
    A, Iy, Iz = b * t, b * t**3 / 12, t * b**3 / 12
    J = b * t**3 / 3
    k, m = _frame_local(E, G, rho, A, Iy, Iz, J, ly / ny)
    R = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])  # columns: local axes in global
    R12 = np.kron(np.eye(4), R)
    k = R12 @ k @ R12.T
    m = R12 @ m @ R12.T
    add(ids[:-1, :].ravel(), ids[1:, :].ravel(), k, m, np.tile(np.arange(6), 2))
    n = 6 * nodes.shape[0]
    r, c = np.concatenate(rows), np.concatenate(cols)
    K = sp.csr_matrix((np.concatenate(kv), (r, c)), shape=(n, n))
    M = sp.csr_matrix((np.concatenate(mv), (r, c)), shape=(n, n))
    clamp = ids[:, 0]
    fixed = np.zeros(n, dtype=bool)
    fixed[(clamp[:, None] * 6 + np.arange(6)).ravel()] = True
    # in-plane drilling rotation rz has stiffness only through member bending in plane,
    # which is present, so no extra constraint is needed.
    free = np.nonzero(~fixed)[0]
    elements = np.concatenate(
        [np.column_stack([ids[:, :-1].ravel(), ids[:, 1:].ravel()]),
         np.column_stack([ids[:-1, :].ravel(), ids[1:, :].ravel()])]
    )
    return FEModel(
        nodes=nodes,
        M=M[free][:, free],
        K=K[free][:, free],
        dof_node=free // 6,
        dof_component=free % 6,
        node_sets={"clamp": clamp, "tip": ids[:, -1], "corner": [ids[-1, -1]]},
        elements={"frame2": elements},
        name=f"frame grid {nx} x {ny}",
    )
