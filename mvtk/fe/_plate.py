"""Layered rectangular plate models (base laminate + patches) from Python arguments."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import ParameterError
from ._assembly import assemble_shell_model
from ._laminate import Laminate
from ._materials import Ply
from ._mesh import Patch, edge_dofs, edge_tributary_lengths, rectangular_plate_mesh
from ._model import DOF_NAMES, FEModel
from ._shell import DRILL_FACTOR

__all__ = ["plate_model", "SpringSupport"]


class SpringSupport(tuple):
    """``(node_set, dof, k, per_length)``: grounded springs on a node set.

    ``k`` is N/m (translations) or N m/rad (rotations) per node, or per metre of edge
    when ``per_length`` is True (distributed with the trapezoidal rule).

    Examples
    --------
    A stiff spring (1e9 N/m) under the tip of the steel cantilever acts almost as a pin:
    the first frequency approaches the clamped-pinned 81.4 Hz:

    >>> from mvtk.fe import (IsotropicMaterial, Ply, cantilever_beam, constrain_model,
    ...                      modal_analysis)
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> sprung = constrain_model(beam, {}, [SpringSupport("tip", "uz", 1e9)])
    >>> np.round(modal_analysis(sprung, 1).fn_hz, 1)
    array([81.4])
    """

    def __new__(cls, node_set: str, dof: str, k: float, per_length: bool = False):
        return super().__new__(cls, (node_set, dof, float(k), bool(per_length)))


def plate_model(
    length: float,
    width: float,
    layers: Sequence[Ply],
    *,
    patches: Sequence[tuple[Patch, Sequence[Ply]]] = (),
    nx: int | None = None,
    ny: int | None = None,
    element_size: float | None = None,
    supports: Mapping[str, str | Sequence[str]] | None = None,
    clamp: str | None = None,
    clamp_stiffness: float | None = None,
    clamp_translational_stiffness: float | None = None,
    springs: Sequence[SpringSupport] = (),
    points: Mapping[str, tuple[float, float]] | None = None,
    shear_correction: float = 5.0 / 6.0,
    drill_factor: float = DRILL_FACTOR,
    name: str = "",
    meta: Mapping[str, Any] | None = None,
) -> FEModel:
    """Build a flat layered plate model in the x-y plane (MITC4 shells).

    Parameters
    ----------
    length, width : float
        Plate size along x and y (m); the plate spans ``[0, length] x [0, width]``.
    layers : sequence of Ply
        Base laminate, bottom to top; its mid-plane is the reference surface (z = 0).
    patches : sequence of (Patch, plies)
        Regions with extra plies bonded on top of the base laminate (bottom to top).
    nx, ny, element_size
        Mesh density, see :func:`rectangular_plate_mesh`.
    supports : mapping of edge or node-set name to support type, optional
        E.g. ``{"x0": "clamped", "y0": "simply_supported"}``; types in
        :data:`mvtk.fe.SUPPORT_TYPES` or an explicit list of DOF names. Edges not named
        are free.
    clamp : str, optional
        Shorthand for ``supports[clamp] = "clamped"``.
    clamp_stiffness : float, optional
        Make the clamp elastic in bending: the rotation about the clamp edge (``ry`` on
        x edges, ``rx`` on y edges) is released and held by a rotational spring of this
        stiffness per unit edge length (N m/rad per m).
    clamp_translational_stiffness : float, optional
        Likewise release ``uz`` on the clamp and hold it by springs (N/m per m).
    springs : sequence of SpringSupport
        Further grounded springs.
    points : mapping of name to (x, y), optional
        Named points (m) that become nodes and node sets.
    shear_correction : float
        Shear correction factor of every section (default 5/6).
    drill_factor : float
        Drilling stiffness factor, see :mod:`mvtk.fe._shell`.
    name : str
    meta : mapping, optional
        Extra entries for ``FEModel.meta``.

    Returns
    -------
    FEModel
        ``meta`` holds ``x_lines``, ``y_lines``, ``element_region`` (0 base, i+1 for
        patch i), ``section_names`` and ``laminates``.

    Examples
    --------
    A 0.3 m square steel plate, 3 mm, clamped along x = 0 (Leissa, NASA SP-160,
    Table 4.50: f1 = 3.471 / (2 pi a^2) sqrt(D / (rho h)) = 28.8 Hz):

    >>> from mvtk.fe import IsotropicMaterial, Ply, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> model = plate_model(0.3, 0.3, [Ply(steel, 3e-3)], nx=12, ny=12, clamp="x0")
    >>> np.round(modal_analysis(model, 3).fn_hz, 1)
    array([ 28.9,  70.8, 179.5])
    """
    patches = tuple(patches)
    mesh = rectangular_plate_mesh(
        length, width, nx=nx, ny=ny, element_size=element_size,
        patches=[p for p, _ in patches], points=points,
    )
    base = Laminate(tuple(layers), shear_correction=shear_correction)
    sections = [base]
    for patch, plies in patches:
        plies = tuple(plies)
        if not plies:
            raise ParameterError(f"patch {patch.name!r} has no layers")
        sections.append(Laminate(base.plies + plies, z_bottom=base.z_bottom,
                                 shear_correction=shear_correction))
    supports = dict(supports or {})
    if clamp is not None:
        if clamp in supports and supports[clamp] != "clamped":
            raise ParameterError(f"edge {clamp!r} is both clamped and {supports[clamp]!r}")
        supports[clamp] = "clamped"
    n_all = len(mesh.nodes) * 6
    fixed = [np.zeros(0, dtype=np.int64)]
    k = np.zeros(n_all)
    released: list[int] = []
    if clamp_stiffness is not None or clamp_translational_stiffness is not None:
        if clamp is None:
            raise ParameterError("clamp_stiffness needs a clamp edge (clamp=...)")
        if clamp not in ("x0", "x1", "y0", "y1"):
            raise ParameterError(f"clamp must be one of x0, x1, y0, y1, got {clamp!r}")
        trib = edge_tributary_lengths(mesh, clamp)
        cnodes = mesh.node_sets[clamp]
        for value, comp, what in (
            (clamp_stiffness, DOF_NAMES.index("ry" if clamp[0] == "x" else "rx"),
             "clamp_stiffness"),
            (clamp_translational_stiffness, DOF_NAMES.index("uz"),
             "clamp_translational_stiffness"),
        ):
            if value is None:
                continue
            if not (np.isfinite(value) and value > 0):
                raise ParameterError(f"{what} must be a positive number, got {value!r}")
            released.append(comp)
            k[cnodes * 6 + comp] += float(value) * trib
    for edge, kind in supports.items():
        d = edge_dofs(mesh, edge, kind)
        if edge == clamp and released:
            d = d[~np.isin(d % 6, released)]
        fixed.append(d)
    for spring in springs:
        set_name, dof, kval, per_length = spring
        if set_name not in mesh.node_sets:
            raise ParameterError(
                f"spring node set {set_name!r} not found; available: {sorted(mesh.node_sets)}"
            )
        if dof not in DOF_NAMES:
            raise ParameterError(f"spring dof {dof!r} unknown; expected one of {DOF_NAMES}")
        if not (np.isfinite(kval) and kval >= 0):
            raise ParameterError(f"spring stiffness must be >= 0, got {kval!r}")
        nodes = mesh.node_sets[set_name]
        w = edge_tributary_lengths(mesh, set_name) if per_length else np.ones(len(nodes))
        k[nodes * 6 + DOF_NAMES.index(dof)] += kval * w
    all_meta = {
        "x_lines": mesh.x_lines,
        "y_lines": mesh.y_lines,
        "element_region": mesh.element_region,
        "section_names": ("base",) + tuple(p.name for p, _ in patches),
        "laminates": tuple(sections),
        "supports": supports,
    }
    all_meta.update(meta or {})
    return assemble_shell_model(
        mesh.nodes, mesh.elements, mesh.element_region, sections,
        fixed_dofs=np.concatenate(fixed), springs=k if np.any(k) else None,
        node_sets=mesh.node_sets, name=name, meta=all_meta, drill_factor=drill_factor,
    )
