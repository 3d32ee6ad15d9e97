"""Electromechanical shells: piezo plies of a patch as voltage inputs and charge outputs.

A *patch* is a set of shell elements (MITC4 quads or MITC3 triangles, flat or on a curved
surface) with its own layer stack, e.g. the base skin, a bonding layer and one or more
piezo plies poled through the thickness. The elastic stiffness and mass of every ply are
part of the shell elements (:class:`mvtk.fe.ShellSet`); this module adds the
electromechanical coupling of the piezo plies, in the linear theory of piezoelectric
laminates (e.g. Reddy, *Mechanics of laminated composite plates and shells*, 2004, sec.
3.9; Tzou & Tseng 1990):

Constitutive law of a piezo ply (plane stress, field ``E3`` along the poling direction,
which is the element normal ``+e3`` or ``-e3``; the sign is absorbed in the voltage)::

    sigma = Qbar (eps - dbar E3),        D3 = ebar' eps + eps33_S E3

with ``Qbar`` the ply's plane-stress stiffness rotated by the ply angle (Pa),
``dbar`` the in-plane free strains per unit field ``(d31, d32, 0)`` rotated to the
element axes, ``ebar = Qbar dbar`` (C/m^2; ``e31* = Q11 d31 + Q12 d32`` in ply axes) and
the plane-stress (clamped in-plane, free through the thickness) permittivity
``eps33_S = eps33^T - d' Q d`` (F/m).

Electrodes cover the ply faces, so the field in ply ``j`` is uniform,
``E3 = V_j / t_j`` with ``V_j`` the ply voltage *along its poling*. The electric enthalpy
of the structure is ``H = 1/2 q' K q - q' B V - 1/2 V' C_p V`` with

- ``B`` (n_dof x n_electrodes), column of ply ``j``: the nodal loads of the resultants
  ``N = ebar`` and ``M = z_j ebar`` per volt (``z_j`` the ply's mid-plane distance from the
  node surface): ``f = int B_mb' (N, M) dA``, the membrane and bending parts of the
  induced strain. The resultant is uniform over an element, so the integral reduces to
  the exact edge integral ``int dN_a/dx dA = (y_(a+1) - y_(a-1)) / 2``, for
  quadrilaterals and triangles alike;
- ``C_p`` the (blocked) capacitances ``eps33_S A / t_j`` (F).

Hence the equations ``K q = f + B V`` (a voltage is an input, N per volt) and the charge
collected on the electrodes ``Q = B' q + C_p V`` (C). Electrical conditions:

- short circuit (``V = 0``): the mechanical model as assembled, ``K``;
- open circuit (``Q = 0``): ``K_oc = K + B C_p^-1 B'``;
- charge sensor: ``Q = B' q`` (shorted electrodes);
- voltage sensor: ``V = -C_p^-1 B' q`` (open electrodes).

Wiring: an electrode collects one or more piezo plies in **parallel** (same voltage,
charges add) or in **series** (the same charge flows through every ply, the ply voltages
add up to the electrode's); each ply enters with a sign ``+1`` when the electrode
voltage drives it along its poling, ``-1`` when against. A bimorph bends when its two
plies are driven with opposite signs of the induced strain: plies poled the same way
with signs ``(+1, -1)``, or poled oppositely with ``(+1, +1)`` (the signs are what
matters). In series the internal electrodes float; eliminating their potentials
exactly gives (``b_i`` the signed ply columns, ``C_i`` their capacitances)
``C_s = (sum 1/C_i)^-1``, ``b_s = C_s sum b_i / C_i`` and a stiffening of the
short-circuited structure ``dK = sum b_i b_i' / C_i - b_s b_s' / C_s`` (positive
semi-definite; zero when all ``b_i / C_i`` are equal, e.g. the pure bending of a
symmetric series bimorph). :func:`series_stiffness` gives ``dK``; :func:`mvtk.fe.build_model`
adds it to ``K``.

References
----------
H. S. Tzou, C. I. Tseng, "Distributed piezoelectric sensor/actuator design for dynamic
measurement/control of distributed parameter systems: a piezoelectric finite element
approach", J. Sound Vib. 138 (1990) 17-34.
J. G. Smits, S. I. Dalke, T. K. Cooney, "The constituent equations of piezoelectric
bimorphs", Sensors and Actuators A 28 (1991) 41-61.
IEEE Standard on Piezoelectricity, ANSI/IEEE Std 176-1987 (the length-extensional
resonator of a thin bar, k31).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import DimensionError, ParameterError
from ._laminate import Laminate, _rotation_in_plane
from ._materials import is_piezo
from ._model import FEModel
from ._shell3d import shell_local_geometry

__all__ = [
    "Electrode",
    "ShellPiezoPatch",
    "PiezoCoupling",
    "piezo_coupling",
    "ply_piezo_constants",
    "modal_emcc",
    "series_stiffness",
    "select_region",
    "stacked_laminate",
    "REGION_SHAPES",
]


def ply_piezo_constants(ply) -> tuple[np.ndarray, float | None]:
    """``ebar`` (3,) in laminate axes (C/m^2 = N/(V m)) and ``eps33_S`` (F/m) of a ply.

    ``ebar = T' Q d`` with ``Q`` the plane-stress stiffness in ply axes, ``d = (d31, d32,
    0)`` and ``T`` the strain rotation by the ply angle (see :mod:`mvtk.fe._laminate`);
    ``eps33_S = eps33^T - d' Q d`` (None when the material has no ``eps33``).

    Examples
    --------
    A PZT ply at 0 deg: ``ebar = Q d`` gives ``e31 = E d31 / (1 - nu)`` (C/m^2) in both
    in-plane directions, and ``eps33_S = eps33_T - 2 d31**2 E / (1 - nu)`` (F/m):

    >>> from mvtk.fe import PiezoMaterial, Ply
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10, eps33=2.1e-8)
    >>> ebar, eps33_s = ply_piezo_constants(Ply(pzt, 2e-4))
    >>> np.round(ebar, 3), round(6.7e10 * -2.1e-10 / (1 - 0.34), 3)
    (array([-21.318, -21.318,   0.   ]), -21.318)
    >>> round(eps33_s * 1e9, 4), round((2.1e-8 - 2 * 2.1e-10**2 * 6.7e10 / 0.66) * 1e9, 4)
    (12.0464, 12.0464)
    """
    m = ply.material
    if not is_piezo(m):
        raise ParameterError(f"ply of material {m.name!r} is not piezoelectric (no d31)")
    q = m.plane_stress_q()
    d = np.array([m.d31, m.d32, 0.0])
    T = _rotation_in_plane(ply.angle_deg)
    e = T.T @ (q @ d)
    eps = None if m.eps33 is None else float(m.eps33 - d @ q @ d)
    if eps is not None and eps <= 0:
        raise ParameterError(
            f"material {m.name!r}: the clamped permittivity eps33^T - d'Qd = {eps:.4g} F/m "
            "is not positive; check eps33 (F/m, e.g. 2400 * 8.854e-12) and d31/d32 (m/V)")
    return e, eps


@dataclass(frozen=True)
class Electrode:
    """One electrode pair of a patch: the plies it drives or senses, wired in parallel.

    Parameters
    ----------
    name : str
    plies : tuple of int
        Indices of the piezo plies in the patch's laminate (bottom = 0).
    signs : tuple of float, optional
        ``+1`` (default) or ``-1`` per ply: the ply voltage along its poling is
        ``sign * V`` (parallel), or its share of ``V`` (series).
    wiring : {"parallel", "series"}
        Series needs every ply's ``eps33`` (module notes).

    Examples
    --------
    The electrode of ply 1 of a patch's stack (ply 0 the substrate), voltage along the
    poling:

    >>> Electrode("act", plies=(1,))
    Electrode(name='act', plies=(1,), signs=(1.0,), wiring='parallel')
    """

    name: str
    plies: tuple[int, ...]
    signs: tuple[float, ...] | None = None
    wiring: str = "parallel"

    def __post_init__(self) -> None:
        plies = tuple(int(p) for p in self.plies)
        if not plies:
            raise ParameterError(f"electrode {self.name!r} is wired to no ply")
        signs = (1.0,) * len(plies) if self.signs is None else tuple(float(s)
                                                                      for s in self.signs)
        if len(signs) != len(plies) or any(s not in (1.0, -1.0) for s in signs):
            raise ParameterError(f"electrode {self.name!r}: signs must be +1 or -1, one per "
                                 f"ply ({len(plies)}), got {self.signs!r}")
        if len(set(plies)) != len(plies):
            raise ParameterError(f"electrode {self.name!r}: ply listed twice in {plies}")
        if self.wiring not in ("parallel", "series"):
            raise ParameterError(f"electrode {self.name!r}: wiring must be 'parallel' or "
                                 f"'series', got {self.wiring!r}")
        object.__setattr__(self, "plies", plies)
        object.__setattr__(self, "signs", signs)


@dataclass(frozen=True, eq=False)
class ShellPiezoPatch:
    """Piezo plies on a set of shell elements.

    Parameters
    ----------
    name : str
    elements : array_like of int, shape (n, 3) or (n, 4), or a tuple of such arrays
        Node indices of the patch's elements (as in their :class:`~mvtk.fe.ShellSet`);
        a tuple when the patch holds triangles and quadrilaterals.
    laminate : Laminate
        The whole stack at the patch, with ``z`` measured from the node surface (the
        ShellSet's offset applied, :meth:`mvtk.fe.ShellSet.laminate`).
    material_axis : array_like (3,)
        As the elements' ShellSet: ply angles are measured from its projection.
    electrodes : sequence of Electrode, optional
        Default: one electrode per piezo ply, named after the patch (a single piezo
        ply) or ``"<patch>:<ply index>"``.

    Examples
    --------
    A 100 x 100 mm, 0.2 mm PZT layer bonded on a 1 mm steel plate (300 x 200 mm, clamped
    at x = 0), on the elements of a mesh patch:

    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Patch, PiezoMaterial, Ply,
    ...                      assemble_shell_model, edge_dofs, rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10, eps33=2.1e-8)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4,
    ...                               patches=[Patch("act", 0.05, 0.15, 0.05, 0.15)])
    >>> base = Laminate((Ply(steel, 1e-3),))
    >>> stack = Laminate((Ply(steel, 1e-3), Ply(pzt, 2e-4)), z_bottom=-0.5e-3)
    >>> model = assemble_shell_model(mesh.nodes, mesh.elements, mesh.element_region,
    ...                              [base, stack], fixed_dofs=edge_dofs(mesh, "x0", "clamped"))
    >>> patch = ShellPiezoPatch("act", mesh.elements[mesh.element_region == 1], stack)
    >>> patch.name, round(patch.laminate.thickness * 1e3, 6)        # mm
    ('act', 1.2)
    """

    name: str
    elements: tuple
    laminate: Laminate
    material_axis: tuple = (1.0, 0.0, 0.0)
    electrodes: tuple[Electrode, ...] | None = None

    def __post_init__(self) -> None:
        groups = self.elements if isinstance(self.elements, tuple | list) else (
            self.elements,)
        groups = tuple(np.asarray(g, dtype=np.int64) for g in groups)
        for el in groups:
            if el.ndim != 2 or el.shape[1] not in (3, 4):
                raise DimensionError(f"patch {self.name!r}: elements must be (n, 3) or "
                                     f"(n, 4) arrays, got shape {el.shape}")
        groups = tuple(g for g in groups if len(g))
        if not groups:
            raise ParameterError(f"patch {self.name!r} has no elements")
        object.__setattr__(self, "elements", groups)
        axis = np.asarray(self.material_axis, dtype=float)
        if axis.shape != (3,) or not np.all(np.isfinite(axis)) or not np.any(axis):
            raise ParameterError(f"patch {self.name!r}: material_axis must be a non-zero "
                                 f"3-vector, got {self.material_axis!r}")
        object.__setattr__(self, "material_axis", tuple(axis))
        plies = self.laminate.plies
        piezo = [i for i, p in enumerate(plies) if is_piezo(p.material)]
        if not piezo:
            raise ParameterError(f"patch {self.name!r}: no piezo ply (a material with d31) "
                                 "in its layers")
        if self.electrodes is None:
            ele = tuple(Electrode(self.name if len(piezo) == 1 else f"{self.name}:{i}", (i,))
                        for i in piezo)
        else:
            ele = tuple(self.electrodes)
        used: dict[int, str] = {}
        for e in ele:
            for i in e.plies:
                if not 0 <= i < len(plies):
                    raise ParameterError(f"patch {self.name!r}: electrode {e.name!r} names "
                                         f"ply {i}, the stack has plies 0..{len(plies) - 1}")
                if not is_piezo(plies[i].material):
                    raise ParameterError(
                        f"patch {self.name!r}: electrode {e.name!r} names ply {i} of "
                        f"material {plies[i].material.name!r}, which has no d31")
                if i in used:
                    raise ParameterError(f"patch {self.name!r}: ply {i} is wired to "
                                         f"electrodes {used[i]!r} and {e.name!r}")
                used[i] = e.name
        names = [e.name for e in ele]
        if len(set(names)) != len(names):
            raise ParameterError(f"patch {self.name!r}: electrode names repeat: {names}")
        object.__setattr__(self, "electrodes", ele)


@dataclass(frozen=True, eq=False)
class PiezoCoupling:
    """Electromechanical coupling of a model's electrodes.

    Attributes
    ----------
    names : tuple of str
        Electrode names (``"<patch>"`` or as given).
    patch : tuple of str
        Patch of each electrode.
    B : ndarray (n_dof, n_electrodes)
        Nodal loads per volt (N/V, N m/V) over the model's free DOFs; also the charge per
        unit displacement (C/m, C/rad): ``Q = B' q + C V``.
    C : ndarray (n_electrodes,)
        Blocked (clamped) capacitance (F); NaN where a ply material has no ``eps33``.
    area : ndarray (n_electrodes,)
        Electrode area (m^2, the patch's shell area).

    Examples
    --------
    Returned by :func:`piezo_coupling`: input matrix ``B`` (N/V over the free DOFs),
    capacitance ``C`` (F) and area (m^2) per electrode:

    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Patch, PiezoMaterial, Ply,
    ...                      assemble_shell_model, edge_dofs, rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10, eps33=2.1e-8)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4,
    ...                               patches=[Patch("act", 0.05, 0.15, 0.05, 0.15)])
    >>> base = Laminate((Ply(steel, 1e-3),))
    >>> stack = Laminate((Ply(steel, 1e-3), Ply(pzt, 2e-4)), z_bottom=-0.5e-3)
    >>> model = assemble_shell_model(mesh.nodes, mesh.elements, mesh.element_region,
    ...                              [base, stack], fixed_dofs=edge_dofs(mesh, "x0", "clamped"))
    >>> patch = ShellPiezoPatch("act", mesh.elements[mesh.element_region == 1], stack)
    >>> c = piezo_coupling(model, [patch])
    >>> c.patch, c.area
    (('act',), array([0.01]))
    """

    names: tuple[str, ...]
    patch: tuple[str, ...]
    B: np.ndarray
    C: np.ndarray
    area: np.ndarray
    meta: Mapping = field(default_factory=dict)

    def index(self, names: str | Sequence[str] | None = None) -> np.ndarray:
        """Column indices of electrodes (or of all electrodes of patches) by name."""
        if names is None:
            return np.arange(len(self.names))
        if isinstance(names, str):
            names = [names]
        out = []
        for n in names:
            if n in self.names:
                out.append(self.names.index(n))
                continue
            hit = [i for i, p in enumerate(self.patch) if p == n]
            if not hit:
                raise ParameterError(f"no electrode or patch {n!r}; electrodes: "
                                     f"{list(self.names)}")
            out += hit
        return np.asarray(out, dtype=np.int64)

    def _capacitance(self, idx: np.ndarray) -> np.ndarray:
        c = self.C[idx]
        if np.any(~np.isfinite(c)):
            bad = [self.names[i] for i in idx[~np.isfinite(c)]]
            raise ParameterError(f"electrode(s) {bad}: capacitance unknown; give the piezo "
                                 "material's eps33 (F/m)")
        return c

    def open_circuit_stiffness(self, K, names=None) -> sp.csr_matrix:
        """``K + B_o C_o^-1 B_o'`` with the electrodes ``names`` (default all) open."""
        idx = self.index(names)
        c = self._capacitance(idx)
        Bs = sp.csr_matrix(self.B[:, idx])
        return (sp.csr_matrix(K) + Bs @ sp.diags(1.0 / c) @ Bs.T).tocsr()

    def open_circuit_model(self, model: FEModel, names=None) -> FEModel:
        """Copy of ``model`` with the electrodes ``names`` (default all) left open."""
        from dataclasses import replace

        K = self.open_circuit_stiffness(model.K, names)
        return replace(model, K=((K + K.T) * 0.5).tocsr())


def _polygon_gradients(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact ``int dN_a/dx dA``, ``int dN_a/dy dA`` (n_el, k) and area (n_el,) of linear /
    bilinear elements with straight edges (counter-clockwise nodes)."""
    x, y = xy[:, :, 0], xy[:, :, 1]
    xn, xp = np.roll(x, -1, axis=1), np.roll(x, 1, axis=1)
    yn, yp = np.roll(y, -1, axis=1), np.roll(y, 1, axis=1)
    gx = 0.5 * (yn - yp)
    gy = -0.5 * (xn - xp)
    area = 0.5 * np.sum(x * yn - xn * y, axis=1)
    return gx, gy, area


def _patch_columns(nodes: np.ndarray, patch: ShellPiezoPatch, with_correction: bool = False
                   ) -> tuple:
    """All-DOF load per volt (6 n_nodes, n_e), capacitances (n_e,), area of a patch."""
    zi = patch.laminate.z_interfaces
    plies = patch.laminate.plies
    n_all = 6 * len(nodes)
    geo = []
    for el in patch.elements:
        xy, T = shell_local_geometry(nodes[el], patch.material_axis)
        gx, gy, area = _polygon_gradients(xy)
        if np.any(area <= 0):
            i = int(np.flatnonzero(area <= 0)[0])
            raise ParameterError(f"patch {patch.name!r}: element {i} is degenerate")
        dofs = (el[:, :, None] * 6 + np.arange(6)).reshape(len(el), -1)
        geo.append((el.shape[1], T, gx, gy, area, dofs))
    total_area = float(sum(g[4].sum() for g in geo))
    cols, caps, corr = [], [], []
    for e in patch.electrodes:
        ply_cols, ply_caps = [], []
        for j, s in zip(e.plies, e.signs):
            col = np.zeros(n_all)
            ebar, eps = ply_piezo_constants(plies[j])
            zm = 0.5 * (zi[j] + zi[j + 1])
            N, Mm = s * ebar, s * zm * ebar
            for k, T, gx, gy, _, dofs in geo:
                f = np.zeros((len(dofs), k, 6))
                f[:, :, 0] = N[0] * gx + N[2] * gy
                f[:, :, 1] = N[1] * gy + N[2] * gx
                f[:, :, 4] = Mm[0] * gx + Mm[2] * gy      # beta_x = ry
                f[:, :, 3] = -(Mm[1] * gy + Mm[2] * gx)   # beta_y = -rx
                fg = np.einsum("eji,ej->ei", T, f.reshape(len(dofs), 6 * k))
                np.add.at(col, dofs.ravel(), fg.ravel())
            ply_cols.append(col)
            ply_caps.append(np.nan if eps is None else eps * total_area / plies[j].thickness)
        ply_caps = np.asarray(ply_caps)
        if e.wiring == "parallel" or len(e.plies) == 1:
            cols.append(np.sum(ply_cols, axis=0))
            caps.append(float(np.sum(ply_caps)))
            continue
        if np.any(~np.isfinite(ply_caps)):
            raise ParameterError(f"patch {patch.name!r}: electrode {e.name!r} wired in "
                                 "series needs eps33 of every ply's material (F/m)")
        cs = 1.0 / np.sum(1.0 / ply_caps)
        bs = cs * np.sum([c / ci for c, ci in zip(ply_cols, ply_caps)], axis=0)
        cols.append(bs)
        caps.append(float(cs))
        corr += [(c / np.sqrt(ci), 1.0) for c, ci in zip(ply_cols, ply_caps)]
        corr.append((bs / np.sqrt(cs), -1.0))
    if with_correction:
        return np.column_stack(cols), np.asarray(caps), total_area, corr
    return np.column_stack(cols), np.asarray(caps), total_area


def piezo_coupling(model: FEModel, patches: Sequence[ShellPiezoPatch] | None = None
                   ) -> PiezoCoupling:
    """Voltage input matrix ``B`` and capacitances of a model's piezo patches.

    Parameters
    ----------
    model : FEModel
        The assembled model (its stiffness already holds the patches' plies).
    patches : sequence of ShellPiezoPatch, optional
        Default: ``model.meta["piezo_patches"]`` (set by :func:`mvtk.fe.build_model` for
        ``[[patches]]`` of a structure).

    Returns
    -------
    PiezoCoupling
        ``B`` over the model's free DOFs: constrained DOFs dropped (the support reacts
        them), DOFs eliminated by rigid links carried to their independent DOFs.

    Examples
    --------
    The blocked capacitance of the patch is ``eps33_S A / t`` with
    ``eps33_S = eps33_T - 2 d31**2 E / (1 - nu)`` (:func:`ply_piezo_constants`):
    0.602 uF for A = 0.01 m^2 and t = 0.2 mm:

    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Patch, PiezoMaterial, Ply,
    ...                      assemble_shell_model, edge_dofs, rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10, eps33=2.1e-8)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4,
    ...                               patches=[Patch("act", 0.05, 0.15, 0.05, 0.15)])
    >>> base = Laminate((Ply(steel, 1e-3),))
    >>> stack = Laminate((Ply(steel, 1e-3), Ply(pzt, 2e-4)), z_bottom=-0.5e-3)
    >>> model = assemble_shell_model(mesh.nodes, mesh.elements, mesh.element_region,
    ...                              [base, stack], fixed_dofs=edge_dofs(mesh, "x0", "clamped"))
    >>> patch = ShellPiezoPatch("act", mesh.elements[mesh.element_region == 1], stack)
    >>> c = piezo_coupling(model, [patch])
    >>> c.names, c.B.shape, round(float(c.C[0]) * 1e6, 4)           # electrode, (n_dof, 1), uF
    (('act',), (180, 1), 0.6023)
    >>> round(float(ply_piezo_constants(Ply(pzt, 2e-4))[1]) * 0.01 / 2e-4 * 1e6, 4)
    0.6023
    """
    if patches is None:
        patches = model.meta.get("piezo_patches")
        if not patches:
            raise ParameterError(f"model {model.name!r} has no piezo patches "
                                 "(meta['piezo_patches'])")
    patches = tuple(patches)
    names, owner, cols, caps, areas = [], [], [], [], []
    for p in patches:
        if max(int(g.max()) for g in p.elements) >= model.n_nodes:
            raise ParameterError(f"patch {p.name!r}: node index outside the model")
        b, c, a = _patch_columns(model.nodes, p)
        cols.append(b)
        caps.append(c)
        for e in p.electrodes:
            names.append(e.name)
            owner.append(p.name)
            areas.append(a)
    if len(set(names)) != len(names):
        raise ParameterError(f"electrode names repeat across patches: {names}")
    B = _free(model, np.hstack(cols))
    return PiezoCoupling(tuple(names), tuple(owner), B, np.concatenate(caps),
                         np.asarray(areas, dtype=float))


def _free(model: FEModel, b_all: np.ndarray) -> np.ndarray:
    """All-DOF columns (6 n_nodes, k) to the model's free DOFs."""
    R = model.meta.get("recovery")
    if R is not None:
        return np.asarray(R.T @ b_all)
    return b_all[model.dof_node * 6 + model.dof_component]


def series_stiffness(model: FEModel, patches: Sequence[ShellPiezoPatch] | None = None
                     ) -> sp.csr_matrix | None:
    """Stiffening ``dK`` of the floating internal electrodes of series-wired electrodes.

    Returns None when no electrode is wired in series (module notes for ``dK``).
    """
    if patches is None:
        patches = model.meta.get("piezo_patches") or ()
    us, ws = [], []
    for p in patches:
        if not any(e.wiring == "series" and len(e.plies) > 1 for e in p.electrodes):
            continue
        *_, corr = _patch_columns(model.nodes, p, with_correction=True)
        for u, w in corr:
            us.append(u)
            ws.append(w)
    if not us:
        return None
    U = sp.csr_matrix(_free(model, np.column_stack(us)))
    dK = (U @ sp.diags(ws) @ U.T).tocsr()
    return ((dK + dK.T) * 0.5).tocsr()


def modal_emcc(model: FEModel, coupling: PiezoCoupling | None = None, n_modes: int = 6,
               electrodes=None) -> list[dict]:
    """Modal effective electromechanical coupling of every electrode and mode.

    For each electrode, with every other electrode shorted, the open-circuit modes are
    computed from ``K + b C^-1 b'`` and paired with the short-circuit modes by the
    mass-weighted MAC; ``k^2 = (f_oc^2 - f_sc^2) / f_sc^2``.

    Parameters
    ----------
    model : FEModel
    coupling : PiezoCoupling, optional
        Default :func:`piezo_coupling` of the model.
    n_modes : int
        Short-circuit modes to report.
    electrodes : str or list of str, optional
        Electrode or patch names (default all).

    Returns
    -------
    list of dict
        One row per electrode and mode: ``electrode``, ``patch``, ``mode`` (1-based),
        ``f_sc_hz``, ``f_oc_hz``, ``k2`` (the EMCC squared), ``k2_modal`` (its modal
        estimate ``(phi' b)^2 / (C omega^2)`` with mass-normalised ``phi``), ``mac``
        (of the paired modes; below 0.9 the pairing, and so k2, is doubtful: ``paired``
        False).

    Examples
    --------
    Open- against short-circuit frequency of the first bending mode,
    ``k**2 = (f_oc**2 - f_sc**2) / f_sc**2`` = 1.3 % (on a 24 x 16 mesh, which resolves
    the extra open-circuit modes the function computes):

    >>> from mvtk.fe import (IsotropicMaterial, Laminate, Patch, PiezoMaterial, Ply,
    ...                      assemble_shell_model, edge_dofs, rectangular_plate_mesh)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10, eps33=2.1e-8)
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=24, ny=16,
    ...                               patches=[Patch("act", 0.05, 0.15, 0.05, 0.15)])
    >>> base = Laminate((Ply(steel, 1e-3),))
    >>> stack = Laminate((Ply(steel, 1e-3), Ply(pzt, 2e-4)), z_bottom=-0.5e-3)
    >>> model = assemble_shell_model(mesh.nodes, mesh.elements, mesh.element_region,
    ...                              [base, stack], fixed_dofs=edge_dofs(mesh, "x0", "clamped"))
    >>> patch = ShellPiezoPatch("act", mesh.elements[mesh.element_region == 1], stack)
    >>> rows = modal_emcc(model, piezo_coupling(model, [patch]), n_modes=1)
    >>> [(round(r["f_sc_hz"], 2), round(r["f_oc_hz"], 2), round(r["k2"], 4)) for r in rows]
    [(9.77, 9.83, 0.0129)]
    >>> r = rows[0]
    >>> round((r["f_oc_hz"]**2 - r["f_sc_hz"]**2) / r["f_sc_hz"]**2, 4)
    0.0129
    """
    from .._mac import mac_columns
    from ._modal import modal_analysis

    cp = piezo_coupling(model) if coupling is None else coupling
    sc = modal_analysis(model, n_modes)
    out = []
    n_oc = min(n_modes + 4, model.n_dof - 1)
    for i in cp.index(electrodes):
        c = cp._capacitance(np.array([i]))[0]
        oc = modal_analysis(cp.open_circuit_model(model, [cp.names[i]]), n_oc)
        mac = mac_columns(sc.shapes, oc.shapes, model.M)
        b = cp.B[:, i]
        for m in range(n_modes):
            j = int(np.argmax(mac[m]))
            fs, fo = float(sc.fn_hz[m]), float(oc.fn_hz[j])
            phi = sc.shapes[:, m]
            w2 = float(sc.omega2[m])
            k2 = (fo**2 - fs**2) / fs**2 if fs > 0 else np.nan
            k2m = float((phi @ b) ** 2 / (c * w2)) if w2 > 0 else np.nan
            out.append({"electrode": cp.names[i], "patch": cp.patch[i], "mode": m + 1,
                        "f_sc_hz": fs, "f_oc_hz": fo, "k2": float(k2), "k2_modal": k2m,
                        "mac": float(mac[m, j]), "paired": bool(mac[m, j] >= 0.9)})
    return out


REGION_SHAPES = ("box", "circle", "polygon")


def _inside_polygon(u: np.ndarray, v: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd rule: points (u, v) inside the closed polygon (n, 2)."""
    inside = np.zeros(len(u), dtype=bool)
    pu, pv = poly[:, 0], poly[:, 1]
    qu, qv = np.roll(pu, -1), np.roll(pv, -1)
    for a_u, a_v, b_u, b_v in zip(pu, pv, qu, qv):
        crosses = (a_v > v) != (b_v > v)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = a_u + (v - a_v) * (b_u - a_u) / (b_v - a_v)
        inside ^= crosses & (u < x)
    return inside


def select_region(nodes: np.ndarray, cells: Mapping[str, np.ndarray], *, shape: str,
                  origin, axis=(1.0, 0.0, 0.0), normal=None, u=None, v=None,
                  radius: float | None = None, points=None, where: str = "region"
                  ) -> dict[str, np.ndarray]:
    """Shell cells whose centroid lies in a region drawn on the surface.

    The region lives in the tangent plane of the surface at ``origin``: ``e3`` is
    ``normal`` or the normal of the shell element nearest to ``origin``, ``e1`` the
    projection of ``axis`` on that plane, ``e2 = e3 x e1``; a centroid ``c`` has the surface
    coordinates ``u = (c - origin).e1``, ``v = (c - origin).e2`` (m). On a curved surface
    these are projected lengths: the arc length ``s`` of a cylinder of radius ``R`` maps
    to ``R sin(s / R)``, 0.05 % short for ``s = R / 18``. Only elements facing the same
    way (``|n.e3| > 0.5``) and within the region's size of the tangent plane are taken,
    so the far side of a closed shell is never selected.

    Parameters
    ----------
    nodes : ndarray (n_nodes, 3)
    cells : mapping ``"tri3"`` / ``"quad4"`` (or ``"mitc3"`` / ``"mitc4"``) to connectivity
    shape : {"box", "circle", "polygon"}
    origin : 3 floats (m)
    axis : 3 floats
        Direction of ``u``.
    normal : 3 floats, optional
    u, v : (2,) floats
        Box extent ``[u0, u1]``, ``[v0, v1]`` (m).
    radius : float
        Circle radius about ``origin`` (m).
    points : (n, 2) floats
        Polygon vertices ``[u, v]`` (m), in order.
    where : str
        Prefix of error messages (the TOML key).

    Returns
    -------
    dict of kind to cell indices
        Only kinds with selected cells.

    Raises
    ------
    ParameterError
        Unknown shape, bad dimensions, an origin off the mesh, or no element selected.

    Examples
    --------
    The elements whose centroid lies in a 100 x 100 mm box centred at (0.1, 0.1) m on a
    6 x 4 plate mesh (50 mm elements):

    >>> from mvtk.fe import rectangular_plate_mesh
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4)
    >>> select_region(mesh.nodes, {"quad4": mesh.elements}, shape="box", origin=[0.1, 0.1, 0.0],
    ...               u=[-0.05, 0.05], v=[-0.05, 0.05], normal=[0, 0, 1])
    {'quad4': array([ 5,  6,  9, 10])}
    """
    from ._shell3d import shell_frames

    if shape not in REGION_SHAPES:
        raise ParameterError(f"{where}.shape: expected one of {', '.join(REGION_SHAPES)}, "
                             f"got {shape!r}")
    o = np.asarray(origin, dtype=float)
    if o.shape != (3,) or not np.all(np.isfinite(o)):
        raise ParameterError(f"{where}.origin: expected 3 numbers [x, y, z], got {origin!r}")
    kinds = [k for k in ("tri3", "quad4", "mitc3", "mitc4") if k in cells and len(cells[k])]
    if not kinds:
        raise ParameterError(f"{where}: the mesh has no shell elements")
    cent = {k: nodes[cells[k]].mean(axis=1) for k in kinds}
    nrm = {k: shell_frames(nodes[cells[k]])[:, 2] for k in kinds}
    allc = np.vstack([cent[k] for k in kinds])
    alln = np.vstack([nrm[k] for k in kinds])
    sizes = np.concatenate([np.max(np.linalg.norm(nodes[cells[k]] - cent[k][:, None], axis=2),
                                   axis=1) for k in kinds])
    near = int(np.argmin(np.linalg.norm(allc - o, axis=1)))
    if np.linalg.norm(allc[near] - o) > 2.0 * sizes[near]:
        raise ParameterError(
            f"{where}.origin: {o.tolist()} is off the mesh (nearest element centroid "
            f"{np.round(allc[near], 6).tolist()} is {np.linalg.norm(allc[near] - o):.4g} m away)")
    e3 = alln[near] if normal is None else np.asarray(normal, dtype=float)
    if e3.shape != (3,) or not np.linalg.norm(e3) > 0:
        raise ParameterError(f"{where}.normal: expected a non-zero 3-vector, got {normal!r}")
    e3 = e3 / np.linalg.norm(e3)
    a = np.asarray(axis, dtype=float)
    e1 = a - (a @ e3) * e3
    if a.shape != (3,) or np.linalg.norm(e1) < 1e-6 * max(np.linalg.norm(a), 1e-300):
        raise ParameterError(f"{where}.axis: {axis!r} is not a direction in the surface "
                             f"(normal {np.round(e3, 6).tolist()})")
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(e3, e1)

    def pair(val, key):
        arr = np.asarray(val, dtype=float) if val is not None else None
        if arr is None or arr.shape != (2,) or not np.all(np.isfinite(arr)) or arr[1] <= arr[0]:
            raise ParameterError(f"{where}.{key}: expected [min, max] (m) with min < max, "
                                 f"got {val!r}")
        return arr

    if shape == "box":
        ur, vr = pair(u, "u"), pair(v, "v")
        extent = float(np.max(np.abs(np.concatenate([ur, vr]))))
    elif shape == "circle":
        if radius is None or not (np.isfinite(radius) and radius > 0):
            raise ParameterError(f"{where}.radius: expected a positive number (m), "
                                 f"got {radius!r}")
        extent = float(radius)
    else:
        poly = np.asarray(points, dtype=float) if points is not None else np.zeros((0, 2))
        if poly.ndim != 2 or poly.shape[1] != 2 or len(poly) < 3 or not np.all(
                np.isfinite(poly)):
            raise ParameterError(f"{where}.points: expected at least 3 [u, v] pairs (m), "
                                 f"got {points!r}")
        extent = float(np.max(np.linalg.norm(poly, axis=1)))
    out = {}
    for k in kinds:
        d = cent[k] - o
        uu, vv, ww = d @ e1, d @ e2, d @ e3
        if shape == "box":
            inside = (uu >= ur[0]) & (uu <= ur[1]) & (vv >= vr[0]) & (vv <= vr[1])
        elif shape == "circle":
            inside = uu**2 + vv**2 <= radius**2
        else:
            inside = _inside_polygon(uu, vv, poly)
        inside &= (np.abs(nrm[k] @ e3) > 0.5) & (np.abs(ww) <= extent + sizes.max())
        if np.any(inside):
            out[k] = np.flatnonzero(inside)
    if not out:
        raise ParameterError(f"{where}: selects no element of the mesh (no element centroid "
                             "inside the region); check origin, axis and the region's size")
    return out


def stacked_laminate(base: Laminate, base_offset: float, top=(), bottom=()
                     ) -> tuple[Laminate, list[int], list[int]]:
    """Laminate of patch plies bonded on either side of ``base``.

    ``top`` plies (on the ``+normal`` side) and ``bottom`` plies are each listed from the
    base outwards; ``z`` stays measured from the node surface (the base's offset
    applied), so the reference surface does not move.

    Returns
    -------
    (Laminate, list of int, list of int)
        The stack bottom to top and the stack index of each top and bottom ply.
    """
    top, bottom = tuple(top), tuple(bottom)
    zb = (-base.thickness / 2 if base.z_bottom is None else base.z_bottom) + base_offset
    tb = sum(p.thickness for p in bottom)
    nb, n0 = len(bottom), len(base.plies)
    lam = Laminate(bottom[::-1] + base.plies + top, z_bottom=zb - tb,
                   shear_correction=base.shear_correction)
    return lam, [nb + n0 + i for i in range(len(top))], [nb - 1 - i for i in range(nb)]
