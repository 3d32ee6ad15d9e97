"""General 3-D models: shells, beams, point masses, springs, rigid links, supports.

:func:`assemble_model` turns a node table and a list of *members* into an
:class:`~mvtk.fe.FEModel`:

- :class:`ShellSet`: MITC4 quadrilaterals or MITC3 triangles at any orientation
  (:mod:`mvtk.fe._shell3d`), one laminate per set, ply angles from a material axis,
  optional offset of the laminate from the node surface;
- :class:`BeamSet`: 3-D Timoshenko beams (:func:`mvtk.fe.timoshenko_element_matrices`)
  with an orientation vector (the section's local y) and an offset of the beam axis
  from the nodes (stiffeners on shells);
- :class:`PointMass`: mass and rotary inertia, optionally offset from its node;
- :class:`Spring`: grounded (one node) or two-node springs, 6x6 or per DOF;
- :class:`RigidLink`: RBE2-like rigid bodies and RBE3-like interpolation.

Constraints are imposed by **elimination**: the full displacement vector is
``u = T q`` with ``q`` the independent, unsupported DOFs; ``K = T' K_full T`` and
``M = T' M_full T`` stay symmetric and sparse. Supports remove DOFs (columns of ``T``);
rigid links express dependent DOFs through independent ones (rows of ``T``).
DOFs that carry neither stiffness nor mass after that (nodes of no member, rotations of
nodes reached only by RBE3 or springs) are removed too and listed in
``meta["unused_dofs"]``.

Support types (:data:`GENERAL_SUPPORTS`), on any node set; rotations are about global
axes:

=======================  ====================================================
``clamped``              ux uy uz rx ry rz
``pinned``               ux uy uz
``simply_supported_soft``  ux uy uz (alias ``simply_supported``: see ``_hard``)
``simply_supported_hard``  ux uy uz and the rotation about the in-plane normal of
                         the edge (the *twist* of the edge, which a hard simple
                         support prevents); needs a straight node line whose
                         in-plane normal (edge direction x shell normal) is a
                         global axis
``roller_x|y|z``         the translation along that global axis
``symmetry_x|y|z``       symmetry about the plane normal to that axis:
                         the translation along it and the two rotations about
                         the other axes (e.g. symmetry_x: ux ry rz)
``antisymmetry_x|y|z``   the two in-plane translations and the rotation about
                         the axis (e.g. antisymmetry_x: uy uz rx)
``free``                 nothing
list of DOF names        those components, e.g. ``["uz", "rx"]``
=======================  ====================================================
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import DimensionError, ParameterError
from ._assembly import assemble_element_matrices, sparsity_pattern
from ._beam import BeamSection, _global_matrices, _section_array
from ._laminate import Laminate
from ._mitc9 import mitc9_matrices
from ._model import DOF_NAMES, FEModel
from ._shell import DRILL_FACTOR
from ._shell3d import shell_element_matrices, shell_frames

__all__ = [
    "GENERAL_SUPPORTS",
    "ShellSet",
    "BeamSet",
    "PointMass",
    "Spring",
    "RigidLink",
    "assemble_model",
    "support_dofs",
]

_CHUNK = 8192  # shell elements per assembly chunk

GENERAL_SUPPORTS: dict[str, tuple[str, ...]] = {
    "clamped": ("ux", "uy", "uz", "rx", "ry", "rz"),
    "pinned": ("ux", "uy", "uz"),
    "simply_supported_soft": ("ux", "uy", "uz"),
    "simply_supported_hard": ("ux", "uy", "uz", "twist"),
    "simply_supported": ("ux", "uy", "uz", "twist"),
    "hinged": ("ux", "uy", "uz"),
    "roller_x": ("ux",),
    "roller_y": ("uy",),
    "roller_z": ("uz",),
    "symmetry_x": ("ux", "ry", "rz"),
    "symmetry_y": ("uy", "rx", "rz"),
    "symmetry_z": ("uz", "rx", "ry"),
    "antisymmetry_x": ("uy", "uz", "rx"),
    "antisymmetry_y": ("ux", "uz", "ry"),
    "antisymmetry_z": ("ux", "uy", "rz"),
    "free": (),
}


def _cross_matrix(r: np.ndarray) -> np.ndarray:
    """[r]x with [r]x v = r x v; r (..., 3) -> (..., 3, 3)."""
    r = np.asarray(r, dtype=float)
    out = np.zeros(r.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -r[..., 2], r[..., 1]
    out[..., 1, 0], out[..., 1, 2] = r[..., 2], -r[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -r[..., 1], r[..., 0]
    return out


def _offset_matrix(e: np.ndarray) -> np.ndarray:
    """6x6 map from node DOFs to those of a point rigidly offset by e (..., 3)."""
    e = np.asarray(e, dtype=float)
    W = np.zeros(e.shape[:-1] + (6, 6))
    W[..., :3, :3] = np.eye(3)
    W[..., 3:, 3:] = np.eye(3)
    W[..., :3, 3:] = -_cross_matrix(e)  # u_p = u + theta x e = u - [e]x theta
    return W


def _vector3(v, where: str) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ParameterError(f"{where}: expected 3 finite numbers, got {v!r}")
    return a


@dataclass(frozen=True, eq=False)
class ShellSet:
    """Shell elements sharing one section.

    Parameters
    ----------
    elements : array_like of int, shape (n_el, 3), (n_el, 4) or (n_el, 9)
        Node indices: triangles (MITC3), quadrilaterals (MITC4) or nine-node curved
        quadrilaterals (MITC9, :mod:`mvtk.fe._mitc9`: corners, mid-sides, centre),
        counter-clockwise about the intended normal.
    section : Laminate
        Layers bottom (-normal side) to top; ply angles from the material axis.
    material_axis : array_like (3,) or (n_el, 3)
        Global direction whose projection on each element is the ply reference
        direction ``e1`` (default global x), or one direction per element.
    offset : float
        Distance (m) from the node surface to the laminate mid-plane along the element
        normal (e.g. ``+t/2`` puts the nodes on the bottom face).
    name : str
        Element set name.

    Examples
    --------
    A 300 x 200 mm steel plate, 2 mm, as one shell set on a generated mesh:

    >>> from mvtk.fe import IsotropicMaterial, Laminate, Ply, rectangular_plate_mesh
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> plate = ShellSet(mesh.elements, Laminate((Ply(steel, 2e-3),)))
    >>> model = assemble_model(mesh.nodes, [plate])
    >>> from mvtk.fe import gravity_nodal
    >>> round(-float(gravity_nodal(model, (0.0, 0.0, -1.0))[:, 2].sum()), 3)  # kg: rho h A
    0.942
    """

    elements: np.ndarray
    section: Laminate
    material_axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    offset: float = 0.0
    name: str = "shell"

    def __post_init__(self) -> None:
        el = np.asarray(self.elements, dtype=np.int64)
        if el.ndim != 2 or el.shape[1] not in (3, 4, 9):
            raise DimensionError(
                f"shell set {self.name!r}: elements must have shape (n, 3) or (n, 4) "
                "(or (n, 9): MITC9), "
                f"got {el.shape}"
            )
        if not isinstance(self.section, Laminate):
            raise ParameterError(f"shell set {self.name!r}: section must be a Laminate")
        if not np.isfinite(self.offset):
            raise ParameterError(f"shell set {self.name!r}: offset must be finite")
        object.__setattr__(self, "elements", el)
        axis = np.asarray(self.material_axis, dtype=float)
        if axis.ndim == 2:
            if axis.shape != (len(el), 3) or not np.all(np.isfinite(axis)):
                raise ParameterError(
                    f"shell set {self.name!r}: material_axis must be 3 numbers or finite "
                    f"({len(el)}, 3) per element, got shape {axis.shape}")
            object.__setattr__(self, "material_axis", axis)
        else:
            object.__setattr__(self, "material_axis", tuple(
                _vector3(self.material_axis, f"shell set {self.name!r}")))

    def laminate(self) -> Laminate:
        """The section with the offset applied (reference surface = node surface)."""
        lam = self.section
        if self.offset == 0.0:
            return lam
        zb = (-lam.thickness / 2 if lam.z_bottom is None else lam.z_bottom) + self.offset
        return Laminate(lam.plies, z_bottom=zb, shear_correction=lam.shear_correction)


@dataclass(frozen=True, eq=False)
class BeamSet:
    """Two-node Timoshenko beam elements sharing one section.

    Parameters
    ----------
    elements : array_like of int, shape (n_el, 2)
    section : BeamSection
        See :func:`mvtk.fe.beam_section` and :mod:`mvtk.fe._sections`.
    orientation : array_like (3,)
        Vector in the local x-y plane: the section's width axis (local y) is its part
        normal to the beam axis (as Nastran's CBAR orientation vector).
    offset : array_like (3,)
        Global vector (m) from each node to the beam axis (e.g. a stiffener's
        centroid below the shell nodes); the axis is tied rigidly to the nodes.
    name : str

    Examples
    --------
    Twenty elements along x with a 20 x 2 mm steel section (see :func:`assemble_model`):

    >>> from mvtk.fe import IsotropicMaterial, rectangle_section
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beams = BeamSet(np.c_[np.arange(20), np.arange(1, 21)],
    ...                 rectangle_section(steel, width=0.02, height=0.002), name="strip")
    >>> beams.elements.shape, beams.name
    ((20, 2), 'strip')
    """

    elements: np.ndarray
    section: BeamSection
    orientation: tuple[float, float, float] = (0.0, 1.0, 0.0)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "beam"

    def __post_init__(self) -> None:
        el = np.asarray(self.elements, dtype=np.int64)
        if el.ndim != 2 or el.shape[1] != 2:
            raise DimensionError(
                f"beam set {self.name!r}: elements must have shape (n, 2), got {el.shape}"
            )
        if not isinstance(self.section, BeamSection):
            raise ParameterError(f"beam set {self.name!r}: section must be a BeamSection")
        object.__setattr__(self, "elements", el)
        object.__setattr__(self, "orientation",
                           tuple(_vector3(self.orientation, f"beam set {self.name!r}")))
        object.__setattr__(self, "offset",
                           tuple(_vector3(self.offset, f"beam set {self.name!r}")))


@dataclass(frozen=True)
class PointMass:
    """A rigid mass attached to a node.

    Parameters
    ----------
    node : int
    mass : float
        kg.
    inertia : array_like, (3,) or (3, 3)
        Rotary inertia about the mass centre in global axes (kg m^2); a (3,) value is
        the diagonal.
    offset : array_like (3,)
        Vector from the node to the mass centre (m).
    frame : array_like (3, 3), optional
        Axes (rows, global components) in which ``inertia`` is given; the global
        tensor is ``R' J R``. Default: global axes.

    Examples
    --------
    The 2-mass chain along z: node 0 grounded, 1 kg at nodes 1 and 2, springs of 1e5 N/m
    between them; closed form ``f1 = sqrt(k (3 - sqrt(5)) / 2) / (2 pi)`` = 31.105 Hz:

    >>> from mvtk.fe import modal_analysis
    >>> nodes = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]])   # m
    >>> members = [PointMass(1, 1.0), PointMass(2, 1.0),                        # kg
    ...            Spring(0, {"uz": 1e5}, node_b=1), Spring(1, {"uz": 1e5}, node_b=2)]
    >>> model = assemble_model(nodes, members, supports={"ground": "clamped",
    ...                                                  "masses": ["ux", "uy"]},
    ...                        node_sets={"ground": [0], "masses": [1, 2]})
    >>> np.round(modal_analysis(model, 1).fn_hz, 3)
    array([31.105])
    """

    node: int
    mass: float
    inertia: Any = (0.0, 0.0, 0.0)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame: Any = None

    def matrix(self) -> np.ndarray:
        """6x6 mass matrix at the node (global DOFs)."""
        if not (np.isfinite(self.mass) and self.mass >= 0):
            raise ParameterError(f"point mass at node {self.node}: mass must be >= 0")
        J = np.asarray(self.inertia, dtype=float)
        if J.shape == (3,):
            J = np.diag(J)
        if J.shape != (3, 3) or not np.allclose(J, J.T) or np.any(np.linalg.eigvalsh(J) < 0):
            raise ParameterError(
                f"point mass at node {self.node}: inertia must be 3 values or a symmetric "
                f"positive semi-definite 3x3 matrix, got {self.inertia!r}"
            )
        if self.frame is not None:
            R = np.asarray(self.frame, dtype=float)
            if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
                raise ParameterError(f"point mass at node {self.node}: frame must be an "
                                     f"orthonormal (3, 3) matrix (rows = axes), got {R!r}")
            J = R.T @ J @ R
        m = np.zeros((6, 6))
        m[:3, :3] = self.mass * np.eye(3)
        m[3:, 3:] = J
        W = _offset_matrix(_vector3(self.offset, f"point mass at node {self.node}"))
        return W.T @ m @ W


def _spring_matrix(k: Any, where: str) -> np.ndarray:
    if isinstance(k, Mapping):
        out = np.zeros((6, 6))
        for name, v in k.items():
            if name not in DOF_NAMES:
                raise ParameterError(f"{where}: unknown DOF {name!r}; expected {DOF_NAMES}")
            if not (np.isfinite(v) and v >= 0):
                raise ParameterError(f"{where}: stiffness of {name} must be >= 0, got {v!r}")
            out[DOF_NAMES.index(name), DOF_NAMES.index(name)] = float(v)
        return out
    a = np.asarray(k, dtype=float)
    if a.shape == (6,):
        a = np.diag(a)
    if a.shape != (6, 6) or not np.allclose(a, a.T) or np.any(np.linalg.eigvalsh(a) < -1e-12
                                                              * np.abs(a).max()):
        raise ParameterError(
            f"{where}: k must be a dict of DOF stiffnesses, 6 values or a symmetric positive "
            "semi-definite 6x6 matrix"
        )
    return a


@dataclass(frozen=True)
class Spring:
    """A grounded (``node_b=None``) or two-node spring.

    Parameters
    ----------
    node_a : int
    k : dict, (6,) or (6, 6)
        ``{"uz": 1e4}`` (N/m, N m/rad), a diagonal, or a full symmetric 6x6 matrix in
        global axes.
    node_b : int, optional
        Second node; the spring acts on the relative displacement ``u_b - u_a``.

    Examples
    --------
    A grounded spring of 1e5 N/m along z under a 1 N load deflects ``F / k`` = 10 um (a
    two-node spring, ``node_b=...``, is shown in :class:`PointMass`):

    >>> from mvtk.fe import static_solve
    >>> model = assemble_model(np.zeros((1, 3)), [PointMass(0, 2.0), Spring(0, {"uz": 1e5})],
    ...                        supports={"base": ["ux", "uy"]}, node_sets={"base": [0]})
    >>> round(float(static_solve(model, np.array([1.0]))[0]) * 1e6, 6)    # um
    10.0
    """

    node_a: int
    k: Any
    node_b: int | None = None

    def matrix(self) -> np.ndarray:
        """6x6 (grounded) or 12x12 stiffness."""
        k6 = _spring_matrix(self.k, f"spring at node {self.node_a}")
        if self.node_b is None:
            return k6
        return np.block([[k6, -k6], [-k6, k6]])


@dataclass(frozen=True)
class RigidLink:
    """A rigid body (RBE2-like) or a weighted interpolation (RBE3-like).

    Parameters
    ----------
    independent : int
        ``"rbe2"``: the independent (master) node. ``"rbe3"``: the *reference* node,
        whose 6 DOFs become dependent.
    nodes : sequence of int
        ``"rbe2"``: the dependent nodes, whose components ``dofs`` follow the rigid
        motion ``u = u_m + theta_m x (x - x_m)``, ``theta = theta_m``. ``"rbe3"``: the
        independent nodes whose translations define the reference motion.
    kind : {"rbe2", "rbe3"}
    dofs : sequence of str
        RBE2 dependent components (default all six).
    weights : sequence of float, optional
        RBE3 weights (default 1): the reference translation and rotation are the
        weighted least-squares rigid motion ``(S' W S)^-1 S' W u`` fitted to the
        translations ``u`` of ``nodes`` (``S_j = [I, -[x_j - x_ref]x]``). This keeps the
        stiffness of the structure (no added stiffness) and carries forces and moments
        applied at the reference node to the nodes, as Nastran's RBE3 with translational
        components (123) at the independent nodes.

    Examples
    --------
    A 2 kg mass at node 1, carried rigidly by node 0 on a 1e5 N/m spring (only uz of
    node 0 free): node 1 follows node 0, one DOF remains, and its own weight deflects
    it by ``m g / k`` = 0.196 mm:

    >>> from mvtk.fe import gravity_load, static_solve
    >>> nodes = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]])
    >>> model = assemble_model(nodes, [PointMass(1, 2.0), Spring(0, {"uz": 1e5}),
    ...                                RigidLink(0, [1])],
    ...                        supports={"base": ["ux", "uy", "rx", "ry", "rz"]},
    ...                        node_sets={"base": [0]})
    >>> model.n_dof, round(float(static_solve(model, gravity_load(model))[0]) * 1e3, 4)
    (1, -0.1961)
    """

    independent: int
    nodes: Sequence[int]
    kind: str = "rbe2"
    dofs: Sequence[str] = DOF_NAMES
    weights: Sequence[float] | None = None


def _support_components(kind: Any, where: str) -> list[str]:
    if isinstance(kind, str):
        if kind not in GENERAL_SUPPORTS:
            raise ParameterError(
                f"{where}: unknown support type {kind!r}; expected one of "
                f"{sorted(GENERAL_SUPPORTS)} or a list of DOF names {list(DOF_NAMES)}"
            )
        return list(GENERAL_SUPPORTS[kind])
    if isinstance(kind, Sequence):
        names = [str(k) for k in kind]
        for n in names:
            if n not in DOF_NAMES:
                raise ParameterError(
                    f"{where}: unknown DOF name {n!r}; expected names from {list(DOF_NAMES)}"
                )
        return names
    raise ParameterError(f"{where}: support must be a type name or a list of DOF names, "
                         f"got {kind!r}")


def support_dofs(nodes: np.ndarray, node_set: np.ndarray, kind: Any, where: str = "support",
                 normal: np.ndarray | None = None) -> np.ndarray:
    """Global DOF indices ``node * 6 + component`` fixed by a support on a node set.

    Parameters
    ----------
    nodes : ndarray (n_nodes, 3)
        All node coordinates (m).
    node_set : ndarray of int
    kind : str or list of str
        See :data:`GENERAL_SUPPORTS`.
    where : str
        Name used in error messages.
    normal : ndarray (3,), optional
        Shell normal at the set (needed by ``simply_supported_hard``).

    Examples
    --------
    Clamping nodes 0 and 4 fixes their six components each (``node * 6 + component``):

    >>> from mvtk.fe import rectangular_plate_mesh
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> support_dofs(mesh.nodes, np.array([0, 4]), "clamped")
    array([ 0,  1,  2,  3,  4,  5, 24, 25, 26, 27, 28, 29])
    """
    node_set = np.asarray(node_set, dtype=np.int64)
    comps = []
    for name in _support_components(kind, where):
        if name != "twist":
            comps.append(DOF_NAMES.index(name))
            continue
        pts = nodes[node_set]
        if len(pts) < 2 or normal is None:
            raise ParameterError(
                f"{where}: a hard simple support needs a line of >= 2 shell nodes; use "
                "an explicit DOF list instead"
            )
        _, s, vt = np.linalg.svd(pts - pts.mean(axis=0))
        if s.size > 1 and s[1] > 1e-6 * s[0]:
            raise ParameterError(f"{where}: a hard simple support needs a straight node "
                                 "line; give an explicit DOF list for curved edges")
        axis = np.cross(vt[0], normal)
        axis /= np.linalg.norm(axis)
        k = int(np.argmax(np.abs(axis)))
        if abs(abs(axis[k]) - 1) > 1e-6:
            raise ParameterError(
                f"{where}: the edge's in-plane normal {np.round(axis, 4).tolist()} is not a "
                "global axis; give an explicit DOF list"
            )
        comps.append(3 + k)
    comps = np.unique(np.asarray(comps, dtype=np.int64))
    return (node_set[:, None] * 6 + comps[None, :]).ravel()


def _rigid_rows(xm: np.ndarray, xd: np.ndarray) -> np.ndarray:
    """6x6 map from master DOFs to the rigid-body DOFs at point xd."""
    return _offset_matrix(xd - xm)


def _constraint_matrix(nodes: np.ndarray, links: Sequence[RigidLink]) -> tuple[
        sp.csr_matrix, np.ndarray]:
    """``C`` with ``u = C u`` expressing dependent DOFs, and the dependent mask."""
    n_all = len(nodes) * 6
    dependent = np.zeros(n_all, dtype=bool)
    rows, cols, vals = [np.arange(n_all)], [np.arange(n_all)], [np.ones(n_all)]
    for i, link in enumerate(links):
        where = f"rigid link {i} ({link.kind})"
        m = int(link.independent)
        dep = np.asarray(list(link.nodes), dtype=np.int64)
        if dep.size == 0:
            raise ParameterError(f"{where}: no nodes given")
        if m < 0 or m >= len(nodes) or dep.min() < 0 or dep.max() >= len(nodes):
            raise ParameterError(f"{where}: node index outside 0..{len(nodes) - 1}")
        if m in dep:
            raise ParameterError(f"{where}: node {m} is both independent and dependent")
        if link.kind == "rbe2":
            comps = [DOF_NAMES.index(c) if c in DOF_NAMES else -1 for c in link.dofs]
            if -1 in comps or not comps:
                raise ParameterError(f"{where}: dofs must be names from {list(DOF_NAMES)}, "
                                     f"got {list(link.dofs)}")
            for d in dep:
                W = _rigid_rows(nodes[m], nodes[d])
                for c in comps:
                    g = 6 * d + c
                    if dependent[g]:
                        raise ParameterError(f"{where}: DOF {DOF_NAMES[c]} of node {d} is "
                                             "already dependent in another link")
                    dependent[g] = True
                    nz = np.flatnonzero(W[c])
                    rows.append(np.full(len(nz), g))
                    cols.append(6 * m + nz)
                    vals.append(W[c, nz])
        elif link.kind == "rbe3":
            w = np.ones(len(dep)) if link.weights is None else np.asarray(link.weights, float)
            if w.shape != dep.shape or np.any(w <= 0):
                raise ParameterError(f"{where}: expected {len(dep)} positive weights")
            S = np.zeros((3 * len(dep), 6))
            for j, d in enumerate(dep):
                S[3 * j:3 * j + 3] = _offset_matrix(nodes[d] - nodes[m])[:3]
            Wd = np.repeat(w, 3)
            A = S.T @ (Wd[:, None] * S)
            if np.linalg.cond(A) > 1e12:
                raise ParameterError(
                    f"{where}: the nodes {dep.tolist()} do not define a rigid motion "
                    "(collinear or fewer than 3 nodes); use rbe2 or add nodes"
                )
            G = np.linalg.solve(A, S.T * Wd[None, :])  # (6, 3 n)
            tcols = (6 * dep[:, None] + np.arange(3)[None, :]).ravel()
            for c in range(6):
                g = 6 * m + c
                if dependent[g]:
                    raise ParameterError(f"{where}: reference node {m} is already dependent")
                dependent[g] = True
                rows.append(np.full(len(tcols), g))
                cols.append(tcols)
                vals.append(G[c])
        else:
            raise ParameterError(f"{where}: kind must be 'rbe2' or 'rbe3', got {link.kind!r}")
    r = np.concatenate(rows)
    c = np.concatenate(cols)
    v = np.concatenate(vals)
    keep = ~dependent[r] | (r != c)  # dependent rows lose their identity entry
    C = sp.csr_matrix((v[keep], (r[keep], c[keep])), shape=(n_all, n_all))
    # resolve chains (a dependent DOF used as an independent one by another link)
    for _ in range(len(links) + 1):
        if not np.any(C[:, np.flatnonzero(dependent)].getnnz()):
            break
        C = (C @ C).tocsr()
    else:
        raise ParameterError("rigid links form a cycle of dependencies")
    return C, dependent


def _check_conforming(nine: Sequence[np.ndarray], first: Sequence[ShellSet]) -> None:
    """Refuse nine-node and first-order shells that share an edge (not conforming: the
    nine-node edge is quadratic, the other linear)."""
    if not nine or not first:
        return
    quad = np.concatenate([el[:, [j, (j + 1) % 4]] for el in nine for j in range(4)])
    lin = np.concatenate([m.elements[:, [j, (j + 1) % m.elements.shape[1]]]
                          for m in first for j in range(m.elements.shape[1])])
    a = {tuple(e) for e in np.sort(quad, axis=1).tolist()}
    shared = [e for e in np.sort(lin, axis=1).tolist() if tuple(e) in a]
    if shared:
        raise ParameterError(
            f"{len(shared)} edges (e.g. nodes {shared[0]}) are shared by nine-node (MITC9) "
            "and first-order shells; the two do not conform along an edge: mesh the whole "
            "surface with one order")


def _directors(nodes: np.ndarray, sets: Sequence[np.ndarray]) -> np.ndarray:
    """Unit nodal directors of nine-node shells: the average of the surface normals of
    the elements at each node (zero rows for other nodes)."""
    out = np.zeros((len(nodes), 3))
    if not sets:
        return out
    from ._mitc9 import NODE_RS, _shape

    for el in sets:
        x = nodes[el]
        for i, (r, s) in enumerate(NODE_RS):
            _, dr, ds = _shape(r, s)
            n = np.cross(np.einsum("k,ekj->ej", dr, x), np.einsum("k,ekj->ej", ds, x))
            np.add.at(out, el[:, i], n / np.linalg.norm(n, axis=1)[:, None])
    norm = np.linalg.norm(out, axis=1)
    used = norm > 0
    out[used] /= norm[used, None]
    return out


def _frame_matrix(n_nodes: int, node_frames: Mapping[int, Any] | None,
                  dependent: np.ndarray) -> sp.csr_matrix | None:
    """Block-diagonal map from node-frame DOFs to global DOFs (None without frames)."""
    if not node_frames:
        return None
    framed = np.zeros(6 * n_nodes, dtype=bool)
    rows, cols, vals = [], [], []
    for n, R in node_frames.items():
        n = int(n)
        if not 0 <= n < n_nodes:
            raise ParameterError(f"node_frames: node {n} outside 0..{n_nodes - 1}")
        R = np.asarray(R, dtype=float)
        if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
            raise ParameterError(f"node_frames: the frame of node {n} must be a (3, 3) "
                                 f"orthonormal matrix (rows = axes), got {R!r}")
        if np.any(dependent[6 * n:6 * n + 6]):
            raise ParameterError(f"node {n} has a displacement frame and is dependent in a "
                                 "rigid link; give it global axes")
        framed[6 * n:6 * n + 6] = True
        for off in (0, 3):  # u_global = R' u_local for translations and rotations
            r, c = np.meshgrid(6 * n + off + np.arange(3), 6 * n + off + np.arange(3),
                               indexing="ij")
            rows.append(r.ravel())
            cols.append(c.ravel())
            vals.append(R.T.ravel())
    plain = np.flatnonzero(~framed)
    r, c, v = (np.concatenate([p] + a) for p, a in ((plain, rows), (plain, cols),
                                                     (np.ones(len(plain)), vals)))
    return sp.csr_matrix((v, (r, c)), shape=(6 * n_nodes, 6 * n_nodes))


def assemble_model(
    nodes: np.ndarray,
    members: Sequence[ShellSet | BeamSet | PointMass | Spring | RigidLink],
    *,
    supports: Mapping[str, Any] | None = None,
    node_sets: Mapping[str, Sequence[int]] | None = None,
    node_ids: Sequence[int] | None = None,
    drill_factor: float = DRILL_FACTOR,
    name: str = "",
    meta: Mapping[str, Any] | None = None,
    node_frames: Mapping[int, Any] | None = None,
) -> FEModel:
    """Assemble a general 3-D model of shells, beams, masses, springs and rigid links.

    Parameters
    ----------
    nodes : ndarray (n_nodes, 3)
        Node coordinates (m).
    members : sequence
        :class:`ShellSet`, :class:`BeamSet`, :class:`PointMass`, :class:`Spring`,
        :class:`RigidLink` in any order.
    supports : mapping of node-set name to support, optional
        Support type (:data:`GENERAL_SUPPORTS`) or list of DOF names per node set.
    node_sets : mapping of str to node indices, optional
    node_ids : sequence of int, optional
        External node labels (default 1..n), kept in :attr:`FEModel.node_ids`.
    drill_factor : float
        Shell drilling penalty, see :mod:`mvtk.fe._shell`.
    name : str
    meta : mapping, optional
    node_frames : mapping of node index to (3, 3) array, optional
        Displacement frames: the rows are the unit axes (in global coordinates) in which
        that node's six DOFs are measured (Nastran's GRID ``CD``). Supports, the
        components of springs at that node and the model's DOFs of that node
        (``dof_component``) refer to these axes: a support ``["ux"]`` on a node whose
        frame is rotated is a skewed roller, ``["ux"]`` in a cylindrical frame a radial
        support. Point masses and element matrices stay global; :meth:`FEModel.expand`
        returns global components. Nodes with a frame cannot be dependent in a rigid link.

    Returns
    -------
    FEModel
        ``elements`` holds ``"mitc4"``, ``"mitc3"``, ``"mitc9"``, ``"beam2"``
        connectivities;
        ``meta["element_sets"]`` maps each member set name to ``(type, indices)`` into
        those arrays; ``meta["unused_dofs"]`` the global DOFs removed for carrying
        neither stiffness nor mass; ``meta["recovery"]`` (with rigid links) the sparse
        ``T`` (n_nodes * 6, n_dof) giving every nodal DOF, dependent ones included, as
        ``u = T q`` (used by :meth:`FEModel.expand`).

    Examples
    --------
    The steel cantilever (300 x 20 x 2 mm) built from 20 beam elements; the first
    frequency is the Euler-Bernoulli ``1.87510**2 / (2 pi) sqrt(E I / (rho A L**4))``
    = 18.567 Hz:

    >>> from mvtk.fe import IsotropicMaterial, modal_analysis, rectangle_section
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> nodes = np.c_[np.linspace(0.0, 0.3, 21), np.zeros(21), np.zeros(21)]   # m
    >>> beams = BeamSet(np.c_[np.arange(20), np.arange(1, 21)],
    ...                 rectangle_section(steel, width=0.02, height=0.002))
    >>> model = assemble_model(nodes, [beams], supports={"root": "clamped"},
    ...                        node_sets={"root": [0], "tip": [20]})
    >>> model.n_dof, np.round(modal_analysis(model, 1).fn_hz, 1)
    (120, array([18.6]))
    """
    nodes = np.asarray(nodes, dtype=float)
    if nodes.ndim != 2 or nodes.shape[1] != 3 or not np.all(np.isfinite(nodes)):
        raise DimensionError(f"nodes must be a finite (n_nodes, 3) array, got {nodes.shape}")
    n_nodes = len(nodes)
    n_all = 6 * n_nodes
    node_sets = {str(k): np.asarray(v, dtype=np.int64) for k, v in (node_sets or {}).items()}
    for k, v in node_sets.items():
        if v.size and (v.min() < 0 or v.max() >= n_nodes):
            raise ParameterError(f"node set {k!r} refers to nodes outside 0..{n_nodes - 1}")
    conn: dict[str, list[np.ndarray]] = {"mitc4": [], "mitc3": [], "mitc9": [],
                                         "beam2": []}
    counts = {"mitc4": 0, "mitc3": 0, "mitc9": 0, "beam2": 0}
    element_sets: dict[str, tuple[str, np.ndarray]] = {}
    links = []
    shell_groups: list = []
    beam_groups: list = []
    normals = np.zeros((n_nodes, 3))
    # pass 1: check the members, element sets and the shell normals (which supports of
    # type simply_supported_hard need), so that the DOFs to keep are known before any
    # assembly and every matrix is assembled directly on them
    for i, mbr in enumerate(members):
        if isinstance(mbr, ShellSet | BeamSet):
            el = mbr.elements
            what = "shell" if isinstance(mbr, ShellSet) else "beam"
            if el.size and (el.min() < 0 or el.max() >= n_nodes):
                raise ParameterError(f"{what} set {mbr.name!r}: node index outside "
                                     f"0..{n_nodes - 1}")
            if isinstance(mbr, ShellSet):
                kind = {3: "mitc3", 4: "mitc4", 9: "mitc9"}[el.shape[1]]
                for start in range(0, len(el), _CHUNK):
                    c = el[start:start + _CHUNK, :min(el.shape[1], 4)]
                    np.add.at(normals, c.ravel(),
                              np.repeat(shell_frames(nodes[c])[:, 2], c.shape[1], axis=0))
                shell_groups.append((kind, counts[kind] + np.arange(len(el)), mbr.laminate(),
                                     mbr.material_axis))
            else:
                kind = "beam2"
                beam_groups.append((counts[kind] + np.arange(len(el)), mbr.section,
                                    mbr.orientation, mbr.offset))
            name_ = getattr(mbr, "name", kind)
            if name_ in element_sets:
                raise ParameterError(f"element set name {name_!r} used twice")
            element_sets[name_] = (kind, counts[kind] + np.arange(len(el)))
            conn[kind].append(el)
            counts[kind] += len(el)
        elif isinstance(mbr, PointMass):
            if not 0 <= int(mbr.node) < n_nodes:
                raise ParameterError(f"point mass: node {mbr.node} outside 0..{n_nodes - 1}")
        elif isinstance(mbr, Spring):
            nn = [mbr.node_a] if mbr.node_b is None else [mbr.node_a, mbr.node_b]
            if any(not 0 <= int(n) < n_nodes for n in nn):
                raise ParameterError(f"spring: node {nn} outside 0..{n_nodes - 1}")
        elif isinstance(mbr, RigidLink):
            links.append(mbr)
        else:
            raise ParameterError(f"member {i}: unsupported type {type(mbr).__name__}")

    fixed = np.zeros(n_all, dtype=bool)
    for set_name, kind in (supports or {}).items():
        if set_name not in node_sets:
            raise ParameterError(
                f"support on unknown node set {set_name!r}; available: {sorted(node_sets)}"
            )
        ns = node_sets[set_name]
        nrm = normals[ns].sum(axis=0)
        nrm = nrm / np.linalg.norm(nrm) if np.linalg.norm(nrm) > 0 else None
        fixed[support_dofs(nodes, ns, kind, f"support {set_name!r}", nrm)] = True
    C, dependent = _constraint_matrix(nodes, links)
    clash = fixed & dependent
    if np.any(clash):
        g = int(np.flatnonzero(clash)[0])
        raise ParameterError(f"DOF {DOF_NAMES[g % 6]} of node {g // 6} is both supported and "
                             "dependent in a rigid link; support the independent node instead")
    keep = np.flatnonzero(~fixed & ~dependent)
    frames = _frame_matrix(n_nodes, node_frames, dependent)
    # with rigid links or frames: assemble on all DOFs, then K = T' K_full T; without:
    # directly on the kept DOFs (entries on supported DOFs are dropped by the pattern)
    if links or frames is not None:
        index, n_idx = np.arange(n_all), n_all
    else:
        index = np.full(n_all, -1, dtype=np.int64)
        index[keep] = np.arange(len(keep))
        n_idx = len(keep)

    # pass 2: assembly. Element matrices are symmetrised (they are symmetric to
    # round-off), so the assembled matrices are exactly symmetric
    def sym(A):
        return 0.5 * (A + np.swapaxes(A, 1, 2))

    K_parts, M_parts = [], []
    nine = [m.elements for m in members if isinstance(m, ShellSet) and m.elements.shape[1] == 9]
    _check_conforming(nine, [m for m in members if isinstance(m, ShellSet)
                             and m.elements.shape[1] != 9])
    directors = _directors(nodes, nine)
    for mbr in members:
        if isinstance(mbr, ShellSet):
            el = mbr.elements
            lam = mbr.laminate()
            axis = np.asarray(mbr.material_axis, dtype=float)
            nd = 6 * el.shape[1]
            dofs = (el[:, :, None] * 6 + np.arange(6)).reshape(len(el), nd)
            pattern = sparsity_pattern(dofs, index, n_idx)
            dk = np.zeros(pattern.nnz + 1)
            dm = np.zeros(pattern.nnz + 1)
            # in chunks: element matrices of large meshes never exist all at once
            for start in range(0, len(el), _CHUNK):
                c = el[start:start + _CHUNK]
                ax = axis[start:start + _CHUNK] if axis.ndim == 2 else axis
                if el.shape[1] == 9:
                    Ke, Me = mitc9_matrices(nodes[c], directors[c], lam.ABD, lam.H,
                                            (lam.I0, lam.I1, lam.I2), lam.thickness, ax,
                                            drill_factor)
                else:
                    Ke, Me = shell_element_matrices(
                        nodes[c], lam.ABD[None], lam.H[None],
                        np.array([[lam.I0, lam.I1, lam.I2]]), np.full(len(c), lam.thickness),
                        ax, drill_factor)
                pos = pattern.position[start * nd * nd:(start + len(c)) * nd * nd]
                dk += np.bincount(pos, weights=sym(Ke).ravel(), minlength=pattern.nnz + 1)
                dm += np.bincount(pos, weights=sym(Me).ravel(), minlength=pattern.nnz + 1)
            for parts, d in ((K_parts, dk), (M_parts, dm)):
                parts.append(sp.csr_matrix((d[:pattern.nnz], pattern.indices, pattern.indptr),
                                           shape=pattern.shape))
        elif isinstance(mbr, BeamSet):
            el = mbr.elements
            off = np.asarray(mbr.offset)
            xa, xb = nodes[el[:, 0]] + off, nodes[el[:, 1]] + off
            props = np.repeat(_section_array([mbr.section]), len(el), axis=0)
            try:
                Ke, Me = _global_matrices(xa, xb, props, mbr.orientation)
            except ParameterError as err:
                raise ParameterError(f"beam set {mbr.name!r}: {err}") from err
            if np.any(off):
                W = np.zeros((12, 12))
                W[:6, :6] = W[6:, 6:] = _offset_matrix(off)
                Ke, Me = W.T @ Ke @ W, W.T @ Me @ W
            dofs = (el[:, :, None] * 6 + np.arange(6)).reshape(len(el), -1)
            K_parts.append(assemble_element_matrices(sym(Ke), dofs, index, n_idx))
            M_parts.append(assemble_element_matrices(sym(Me), dofs, index, n_idx))
        elif isinstance(mbr, PointMass):
            dofs = 6 * int(mbr.node) + np.arange(6)
            M_parts.append(assemble_element_matrices(sym(mbr.matrix()[None]), dofs[None],
                                                     index, n_idx))
        elif isinstance(mbr, Spring):
            nn = [mbr.node_a] if mbr.node_b is None else [mbr.node_a, mbr.node_b]
            dofs = (6 * np.asarray(nn)[:, None] + np.arange(6)).ravel()
            ke = mbr.matrix()
            if frames is not None:  # spring components are those of the node frames
                S = frames[dofs][:, dofs].toarray()
                ke = S @ ke @ S.T
            K_parts.append(assemble_element_matrices(sym(ke[None]), dofs[None],
                                                     index, n_idx))

    def total(parts):
        out = sp.csr_matrix((n_idx, n_idx))
        for A in parts:
            out = A if out.nnz == 0 else out + A
        return out.tocsr()

    K, M = total(K_parts), total(M_parts)
    if links or frames is not None:
        T = (C @ frames if frames is not None else C)[:, keep].tocsc()
        Kr = (T.T @ K @ T).tocsr()
        Mr = (T.T @ M @ T).tocsr()
    else:
        T = None
        Kr, Mr = K, M
    scale_k = max(float(np.abs(Kr.diagonal()).max(initial=0.0)), 1e-300)
    scale_m = max(float(np.abs(Mr.diagonal()).max(initial=0.0)), 1e-300)
    alive = (np.abs(Kr.diagonal()) > 1e-14 * scale_k) | (np.abs(Mr.diagonal())
                                                          > 1e-14 * scale_m)
    unused = keep[~alive]
    if not np.all(alive):
        sel = np.flatnonzero(alive)
        Kr, Mr, keep = Kr[sel][:, sel], Mr[sel][:, sel], keep[sel]
        if T is not None:
            T = T[:, sel]
    if links or frames is not None:  # T' K T is symmetric to round-off only
        Kr = ((Kr + Kr.T) * 0.5).tocsr()
        Mr = ((Mr + Mr.T) * 0.5).tocsr()
    elements = {k: np.concatenate(v) for k, v in conn.items() if v}
    out_meta = {"element_sets": element_sets, "unused_dofs": unused,
                "recovery": T.tocsr() if T is not None else None,
                "supports": dict(supports or {}), "members": tuple(members),
                "shell_groups": shell_groups, "beam_groups": beam_groups,
                "drill_factor": drill_factor,
                "node_frames": {int(k): np.asarray(v, float) for k, v in
                                (node_frames or {}).items()}}
    out_meta.update(meta or {})
    return FEModel(nodes=nodes, M=Mr, K=Kr, dof_node=keep // 6, dof_component=keep % 6,
                   node_sets=node_sets, elements=elements, name=name, meta=out_meta,
                   node_ids=node_ids)

