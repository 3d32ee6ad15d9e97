"""Static loads on general models (:func:`mvtk.fe.assemble_model`) and reactions.

Loads are built as global nodal forces and moments (``(n_nodes, 6)``: Fx Fy Fz Mx My Mz,
N and N m) and mapped to the model's free DOFs by virtual work, ``f = T' f_nodal`` with
``T`` the map from free DOFs to all nodal DOFs (supports, rigid links and node frames
included), so a load on a node tied by a rigid link or measured in a rotated frame acts
as it should:

- :func:`nodal_load`: point forces and moments on nodes;
- :func:`gravity_load`: body force ``rho a`` from the consistent mass matrix of every
  member (shells, beams, point masses), ``f = M_full r`` with ``r`` the rigid
  translation ``a`` (m/s^2) of every node;
- :func:`pressure_load`: uniform pressure on shell elements, consistent for their
  bilinear (MITC4) or linear (MITC3) geometry, ``f_i = p int N_i n dA`` along the
  element normal (right-handed with the node order); no follower effect; nine-node
  shells with their quadratic geometry (3 x 3 Gauss points);
- :func:`static_solution`: displacements, and the reactions at the supported DOFs
  ``R = K_full u - f_nodal``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..errors import DimensionError, ParameterError
from ._general import RigidLink, ShellSet, assemble_model
from ._modal import static_solve
from ._model import FEModel
from ._shell import DRILL_FACTOR

__all__ = ["nodal_load", "gravity_load", "gravity_nodal", "pressure_load", "pressure_nodal",
           "static_solution", "StaticSolution"]


def _recovery(model: FEModel) -> sp.csr_matrix:
    T = model.meta.get("recovery")
    if T is not None:
        return sp.csr_matrix(T)
    key = model.dof_node * 6 + model.dof_component
    return sp.csr_matrix((np.ones(model.n_dof), (key, np.arange(model.n_dof))),
                         shape=(model.n_nodes * 6, model.n_dof))


def _members(model: FEModel) -> tuple:
    m = model.meta.get("members")
    if m is None:
        raise ParameterError(f"model {model.name!r} was not built by assemble_model (no "
                             "members in meta): loads need its members")
    return tuple(m)


def nodal_load(model: FEModel, forces: np.ndarray) -> np.ndarray:
    """Free-DOF load vector of global nodal forces and moments.

    Parameters
    ----------
    model : FEModel
    forces : ndarray (n_nodes, 6)
        Fx Fy Fz (N) and Mx My Mz (N m) per node, global axes.

    Returns
    -------
    ndarray (n_dof,)

    Examples
    --------
    A 1 N force along z at node 1 of a 2 kg mass on a spring lands on its uz DOF:

    >>> from mvtk.fe import PointMass, Spring, assemble_model
    >>> model = assemble_model(np.zeros((1, 3)), [PointMass(0, 2.0), Spring(0, {"uz": 1e5})],
    ...                        supports={"base": ["ux", "uy"]}, node_sets={"base": [0]})
    >>> forces = np.zeros((1, 6))
    >>> forces[0, 2] = 1.0                            # N
    >>> nodal_load(model, forces)
    array([1.])
    """
    f = np.asarray(forces, dtype=float)
    if f.shape != (model.n_nodes, 6) or not np.all(np.isfinite(f)):
        raise DimensionError(f"forces must be finite with shape ({model.n_nodes}, 6), got "
                             f"{f.shape}")
    return np.asarray(_recovery(model).T @ f.ravel())


def _unsupported(model: FEModel) -> FEModel:
    """The model's members assembled with no support, link or frame (all nodal DOFs)."""
    members = [m for m in _members(model) if not isinstance(m, RigidLink)]
    return assemble_model(model.nodes, members,
                          drill_factor=model.meta.get("drill_factor", DRILL_FACTOR))


def _full(A_model: FEModel, which: str) -> sp.csr_matrix:
    T = _recovery(A_model)
    A = getattr(A_model, which)
    return (T @ A @ T.T).tocsr()


def gravity_nodal(model: FEModel, acceleration: Sequence[float]) -> np.ndarray:
    """Nodal forces ``(n_nodes, 6)`` of the body force ``rho a`` (a in m/s^2).

    Examples
    --------
    Self weight of the 300 x 20 x 2 mm steel strip: ``rho A L g`` = 0.924 N in total:

    >>> from mvtk.fe import (BeamSet, IsotropicMaterial, assemble_model,
    ...                      rectangle_section)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> nodes = np.c_[np.linspace(0.0, 0.3, 21), np.zeros(21), np.zeros(21)]
    >>> model = assemble_model(nodes, [BeamSet(np.c_[np.arange(20), np.arange(1, 21)],
    ...                                        rectangle_section(steel, 0.02, 0.002))],
    ...                        supports={"root": "clamped"}, node_sets={"root": [0]})
    >>> f = gravity_nodal(model, (0.0, 0.0, -9.81))           # N, N m per node
    >>> f.shape, round(float(f[:, 2].sum()), 4), round(-7850.0 * 0.02 * 0.002 * 0.3 * 9.81, 4)
    ((21, 6), -0.9241, -0.9241)
    """
    a = np.asarray(acceleration, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ParameterError(f"acceleration must be 3 finite numbers (m/s^2), got "
                             f"{acceleration!r}")
    M = _full(_unsupported(model), "M")
    r = np.zeros((model.n_nodes, 6))
    r[:, :3] = a
    return np.asarray(M @ r.ravel()).reshape(model.n_nodes, 6)


def gravity_load(model: FEModel, acceleration: Sequence[float] = (0.0, 0.0, -9.80665)
                 ) -> np.ndarray:
    """Free-DOF load vector of a uniform acceleration field (self weight by default).

    Parameters
    ----------
    model : FEModel
        Built by :func:`mvtk.fe.assemble_model` (or a reader using it).
    acceleration : (3,) float
        m/s^2, global axes; default standard gravity along -z.

    Returns
    -------
    ndarray (n_dof,)

    Examples
    --------
    Standard gravity on a 2 kg point mass on a spring (1e5 N/m along z):
    ``K u = -m g`` gives ``u = -m g / k`` = -0.196 mm:

    >>> from mvtk.fe import PointMass, Spring, assemble_model, static_solve
    >>> model = assemble_model(np.zeros((1, 3)), [PointMass(0, 2.0), Spring(0, {"uz": 1e5})],
    ...                        supports={"base": ["ux", "uy"]}, node_sets={"base": [0]})
    >>> f = gravity_load(model)                       # N over the free DOFs
    >>> round(float(static_solve(model, f)[0]) * 1e3, 4)
    -0.1961
    """
    return nodal_load(model, gravity_nodal(model, acceleration))


def pressure_nodal(model: FEModel, pressure: float, element_set: str | None = None
                   ) -> np.ndarray:
    """Nodal forces ``(n_nodes, 6)`` of a uniform pressure (Pa) on shell elements.

    Examples
    --------
    1 kPa on a 300 x 200 mm plate: the nodal forces add up to ``p A`` = 60 N:

    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Ply, ShellSet, assemble_model,
    ...                      rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> model = assemble_model(mesh.nodes, [ShellSet(mesh.elements, Laminate((Ply(steel, 2e-3),)))])
    >>> round(float(pressure_nodal(model, 1000.0)[:, 2].sum()), 6)    # N
    60.0
    """
    if not np.isfinite(pressure):
        raise ParameterError(f"pressure must be finite (Pa), got {pressure!r}")
    shells = [m for m in _members(model) if isinstance(m, ShellSet)]
    if element_set is not None:
        shells = [m for m in shells if m.name == element_set]
        if not shells:
            names = [m.name for m in _members(model) if isinstance(m, ShellSet)]
            raise ParameterError(f"no shell set {element_set!r}; shell sets: {names}")
    out = np.zeros((model.n_nodes, 6))
    for m in shells:
        out[:, :3] += element_pressure(model.nodes, m.elements, pressure)
    return out


def element_pressure(nodes: np.ndarray, elements: np.ndarray, pressure) -> np.ndarray:
    """Consistent nodal forces (n_nodes, 3) of a pressure (Pa, scalar or one per element)
    along the normals of shell elements (n_el, 3 | 4 | 9)."""
    el = np.asarray(elements, dtype=np.int64)
    p = np.broadcast_to(np.asarray(pressure, dtype=float), (len(el),))[:, None]
    out = np.zeros((len(nodes), 3))
    x = nodes[el]
    if el.shape[1] == 3:
        n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]) / 2  # area * normal
        for k in range(3):
            np.add.at(out, el[:, k], p * n / 3)
        return out
    if el.shape[1] == 9:
        from ._mitc9 import _GP, _GW, _shape

        pts = [(r, s, _GW[a] * _GW[b]) for a, r in enumerate(_GP) for b, s in enumerate(_GP)]
        shape = _shape
    else:
        g = 1.0 / np.sqrt(3.0)

        def shape(xi, eta):
            return (0.25 * np.array([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta),
                                     (1 + xi) * (1 + eta), (1 - xi) * (1 + eta)]),
                    0.25 * np.array([-(1 - eta), (1 - eta), (1 + eta), -(1 + eta)]),
                    0.25 * np.array([-(1 - xi), -(1 + xi), (1 + xi), (1 - xi)]))

        pts = [(xi, eta, 1.0) for xi, eta in ((-g, -g), (g, -g), (g, g), (-g, g))]
    for r, s, w in pts:
        N, dr, ds = shape(r, s)
        n = np.cross(np.einsum("k,ekj->ej", dr, x), np.einsum("k,ekj->ej", ds, x))
        for k in range(el.shape[1]):
            np.add.at(out, el[:, k], p * w * N[k] * n)
    return out


def pressure_load(model: FEModel, pressure: float, element_set: str | None = None
                  ) -> np.ndarray:
    """Free-DOF load vector of a uniform pressure on shells.

    Parameters
    ----------
    model : FEModel
    pressure : float
        Pa, positive along the element normal (right-handed with the node order).
    element_set : str, optional
        Name of one :class:`~mvtk.fe.ShellSet`; default every shell.

    Returns
    -------
    ndarray (n_dof,)

    Examples
    --------
    1 kPa on a 300 x 200 mm plate: the load vector carries ``p A`` = 60 N along z:

    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Ply, ShellSet, assemble_model,
    ...                      rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> model = assemble_model(mesh.nodes, [ShellSet(mesh.elements, Laminate((Ply(steel, 2e-3),)))])
    >>> f = pressure_load(model, 1000.0)
    >>> round(float(f[model.dof_component == 2].sum()), 6)
    60.0
    """
    return nodal_load(model, pressure_nodal(model, pressure, element_set))


@dataclass(frozen=True)
class StaticSolution:
    """Static displacements and support reactions.

    Attributes
    ----------
    displacement : ndarray (n_nodes, 6)
        Global nodal displacements (m) and rotations (rad).
    reaction : ndarray (n_nodes, 6)
        Global reaction forces (N) and moments (N m) at the supports (zero elsewhere).

    Examples
    --------
    Returned by :func:`static_solution`; displacements and reactions per node, global axes:

    >>> from mvtk.fe import PointMass, Spring, assemble_model
    >>> model = assemble_model(np.zeros((1, 3)), [PointMass(0, 2.0), Spring(0, {"uz": 1e5})],
    ...                        supports={"base": ["ux", "uy"]}, node_sets={"base": [0]})
    >>> forces = np.zeros((1, 6))
    >>> forces[0, 2] = -10.0                                     # N
    >>> sol = static_solution(model, forces)
    >>> round(float(sol.displacement[0, 2]) * 1e3, 6), sol.reaction.shape   # mm: F / k
    (-0.1, (1, 6))
    """

    displacement: np.ndarray
    reaction: np.ndarray

    @property
    def total_reaction(self) -> np.ndarray:
        """Sum of the reaction forces (N), (3,)."""
        return self.reaction[:, :3].sum(axis=0)


def static_solution(model: FEModel, forces: np.ndarray) -> StaticSolution:
    """Solve ``K u = T' f`` for global nodal loads and recover the reactions.

    Parameters
    ----------
    model : FEModel
        Built by :func:`mvtk.fe.assemble_model` (without rigid links: their forces are
        internal and would appear as reactions).
    forces : ndarray (n_nodes, 6)
        Global nodal loads, e.g. ``gravity_nodal(...) + pressure_nodal(...)``.

    Returns
    -------
    StaticSolution
        The reactions are ``K_full u - f`` at the DOFs that carry no free DOF, so they
        balance the applied load.

    Examples
    --------
    The steel strip (300 x 20 x 2 mm) under its own weight: the clamp carries the weight
    (0.924 N) and the tip sags ``q L**4 / (8 E I)`` = 1.114 mm:

    >>> from mvtk.fe import (BeamSet, IsotropicMaterial, assemble_model,
    ...                      rectangle_section)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> nodes = np.c_[np.linspace(0.0, 0.3, 21), np.zeros(21), np.zeros(21)]
    >>> model = assemble_model(nodes, [BeamSet(np.c_[np.arange(20), np.arange(1, 21)],
    ...                                        rectangle_section(steel, 0.02, 0.002))],
    ...                        supports={"root": "clamped"}, node_sets={"root": [0]})
    >>> sol = static_solution(model, gravity_nodal(model, (0.0, 0.0, -9.81)))
    >>> round(float(sol.reaction[0, 2]), 4), round(float(sol.displacement[20, 2]) * 1e3, 3)
    (0.9241, -1.114)
    >>> q, EI = 7850.0 * 0.02 * 0.002 * 9.81, 2.1e11 * 0.02 * 0.002**3 / 12
    >>> round(-q * 0.3**4 / (8 * EI) * 1e3, 3)
    -1.114
    """
    f = np.asarray(forces, dtype=float)
    if any(isinstance(m, RigidLink) for m in _members(model)):
        raise ParameterError("static_solution: reactions of models with rigid links are "
                             "not supported; use static_solve for the displacements")
    q = static_solve(model, nodal_load(model, f))
    T = _recovery(model)
    u = np.asarray(T @ q)
    K = _full(_unsupported(model), "K")
    r = (np.asarray(K @ u) - f.ravel()).reshape(model.n_nodes, 6)
    frames = model.meta.get("node_frames") or {}
    for n, R in frames.items():  # to the node's frame, where its supports act
        r[n] = np.concatenate([R @ r[n, :3], R @ r[n, 3:]])
    r[model.dof_node, model.dof_component] = 0.0  # free DOFs carry no reaction
    for n, R in frames.items():
        r[n] = np.concatenate([R.T @ r[n, :3], R.T @ r[n, 3:]])
    return StaticSolution(displacement=u.reshape(model.n_nodes, 6), reaction=r)
