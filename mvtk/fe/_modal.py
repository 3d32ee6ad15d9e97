"""Modal analysis and static solution of an :class:`FEModel`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DimensionError, ParameterError
from ._model import FEModel
from ._solvers import eigsh_lowest, factorize

__all__ = ["ModalResult", "modal_analysis", "static_solve", "mode_type", "energy_split",
           "ENERGY_PARTS"]


@dataclass(frozen=True, eq=False)
class ModalResult:
    """Lowest modes of a structure.

    Attributes
    ----------
    fn_hz : ndarray (n,)
        Natural frequencies (Hz), ascending; rigid-body modes are reported as 0.
    omega2 : ndarray (n,)
        Eigenvalues (rad/s)^2 as solved (rigid-body modes are round-off near 0).
    shapes : ndarray (n_dof, n)
        Mass-normalised mode shapes over the model's free DOFs (``phi' M phi = I``).
    rigid : ndarray of bool (n,)
        True for rigid-body modes.
    mode_type : tuple of str
        ``"rigid"``, ``"bending"``, ``"torsion"``, ``"in-plane"`` or ``"axial"`` (see
        :func:`mode_type`).
    dof_node_id : ndarray of int (n_dof,), optional
        Node label (:attr:`FEModel.node_ids`) of each row of ``shapes``.
    dof_component : ndarray of int (n_dof,), optional
        Component (index into ``DOF_NAMES``) of each row of ``shapes``.

    Examples
    --------
    Returned by :func:`modal_analysis`; the shapes are mass-normalised
    (``phi' M phi = I``):

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> res = modal_analysis(beam, 2)
    >>> res.shapes.shape, bool(res.rigid.any())
    ((120, 2), False)
    >>> np.round(res.shapes.T @ (beam.M @ res.shapes), 9) + 0.0
    array([[1., 0.],
           [0., 1.]])
    """

    fn_hz: np.ndarray
    omega2: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    mode_type: tuple[str, ...]
    dof_node_id: np.ndarray | None = None
    dof_component: np.ndarray | None = None

    def to_xarray(self):
        """Mode shapes as an ``xarray.DataArray`` with dims ``("mode", "dof")``.

        Follows docs/conventions.md: ``mode`` 1-based with coordinates ``fn_hz``,
        ``zeta`` (NaN: undamped FE modes) and ``mode_type``; ``dof`` labels
        ``"<node><direction>"`` (e.g. ``"12+z"``) with coordinates ``node`` (label) and
        ``direction`` (``+x +y +z +rx +ry +rz``); ``attrs`` ``normalisation = "mass"``,
        ``source = "fe"``.

        Raises
        ------
        ParameterError
            If the result carries no DOF table (built by hand without ``dof_node_id``).
        """
        import xarray as xr

        if self.dof_node_id is None or self.dof_component is None:
            raise ParameterError("this ModalResult has no DOF table (dof_node_id, "
                                 "dof_component); build it with modal_analysis")
        dirs = np.array(["+x", "+y", "+z", "+rx", "+ry", "+rz"])[self.dof_component]
        labels = [f"{n}{d}" for n, d in zip(self.dof_node_id, dirs)]
        mode = np.arange(1, self.n_modes + 1)
        return xr.DataArray(
            np.asarray(self.shapes).T, dims=("mode", "dof"),
            coords={"mode": mode, "fn_hz": ("mode", np.asarray(self.fn_hz)),
                    "zeta": ("mode", np.full(self.n_modes, np.nan)),
                    "mode_type": ("mode", list(self.mode_type)),
                    "dof": labels, "node": ("dof", np.asarray(self.dof_node_id)),
                    "direction": ("dof", dirs)},
            attrs={"normalisation": "mass", "source": "fe"},
        )

    @property
    def n_modes(self) -> int:
        return len(self.fn_hz)

    def to_dataframe(self):
        """One row per mode: ``mode`` (1-based), ``fn_hz``, ``mode_type``, ``rigid``."""
        import pandas as pd

        return pd.DataFrame({
            "mode": np.arange(1, self.n_modes + 1),
            "fn_hz": self.fn_hz,
            "mode_type": list(self.mode_type),
            "rigid": self.rigid,
        })

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)


#: Names of the strain-energy parts of :func:`energy_split`, in column order.
ENERGY_PARTS: tuple[str, ...] = ("bending", "torsion", "in-plane", "axial")
_CHUNK = 4096
#: Up to this many distinct element shapes per chunk, energies are summed shape by shape.
_SHARED_SHAPES = 32


def _shell_groups(model: FEModel):
    """(kind, element indices, Laminate, material axis) of every shell group."""
    groups = model.meta.get("shell_groups")
    if groups is not None:
        return groups
    if "mitc4" in model.elements and "sections" in model.meta \
            and "element_section" in model.meta:
        sec = np.asarray(model.meta["element_section"])
        return [("mitc4", np.flatnonzero(sec == i), lam, (1.0, 0.0, 0.0))
                for i, lam in enumerate(model.meta["sections"])]
    return []


def _beam_groups(model: FEModel):
    """(element indices, BeamSection, orientation, offset) of every beam group."""
    groups = model.meta.get("beam_groups")
    if groups is not None:
        return groups
    if "beam2" in model.elements and model.meta.get("kind") == "timoshenko_beam":
        from ._beam import BeamSection

        sec = np.asarray(model.meta["element_section"])
        return [(np.flatnonzero(sec == i), BeamSection(**d), (0.0, 1.0, 0.0), (0.0, 0.0, 0.0))
                for i, d in enumerate(model.meta["sections"])]
    return []


def _part_factors(Kp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Factors ``B`` with ``K_p = B_p' B_p`` of the element matrices of the energy parts.

    Parameters
    ----------
    Kp : ndarray, shape (n_parts, n, n)
        Symmetric positive semi-definite element matrices of one element shape.

    Returns
    -------
    B : ndarray, shape (r, n)
        The rows ``sqrt(lambda) v'`` of every part, from the eigenpairs of its matrix
        with ``lambda > 1e-12 lambda_max`` (the others are round-off of the rigid-body
        and decoupled motions the part does not strain; dropping them changes an
        energy by less than 1e-12 of ``lambda_max |u|^2``).
    S : ndarray, shape (n_parts, r)
        1 where row r of ``B`` belongs to the part: ``u' K_p u = (S @ (B u)**2)[p]``.
    """
    rows, part = [], []
    for p, K in enumerate(Kp):
        w, V = np.linalg.eigh(0.5 * (K + K.T))
        keep = w > 1e-12 * w[-1] if w[-1] > 0 else np.zeros(len(w), dtype=bool)
        rows.append(np.sqrt(w[keep])[:, None] * V[:, keep].T)
        part.append(np.full(int(keep.sum()), p))
    part_of = np.concatenate(part)
    S = (part_of[None, :] == np.arange(len(Kp))[:, None]).astype(float)
    return np.vstack(rows), S


def _part_matrices(xy: np.ndarray, parts, n_nodes: int, lam, drill_df: float) -> np.ndarray:
    """Element stiffness matrices of the energy parts, shape (4, n_shapes, n, n).

    ``parts`` holds the (ABD, H) of each part; the drilling penalty, drill_df x A66,
    is nonzero in the membrane part only."""
    from ._shell import mitc4_matrices
    from ._shell3d import mitc3_matrices

    n_u = len(xy)
    xy_p = np.tile(xy, (4, 1, 1))
    abd_p = np.repeat(np.stack([p[0] for p in parts]), n_u, axis=0)
    h_p = np.repeat(np.stack([p[1] for p in parts]), n_u, axis=0)
    if n_nodes == 4:
        Ku, _ = mitc4_matrices(xy_p, abd_p, h_p, np.zeros((1, 3)), drill_df)
    else:
        Ku, _ = mitc3_matrices(xy_p, abd_p, h_p, np.zeros((1, 3)),
                               np.full(4 * n_u, lam.thickness), drill_df)
    return Ku.reshape(4, n_u, *Ku.shape[1:])


def _mitc9_parts(model, conn, lam, axis, parts, drill_df, u) -> np.ndarray:
    """Bending, torsion, shear and in-plane energies (k, 4) of MITC9 elements."""
    from ._general import _directors
    from ._mitc9 import mitc9_matrices

    directors = _directors(model.nodes, [model.elements["mitc9"]])
    k = u.shape[1]
    out = np.zeros((k, 4))
    for start in range(0, len(conn), _CHUNK):
        c = conn[start:start + _CHUNK]
        ax = np.asarray(axis, dtype=float)
        if ax.ndim == 2:
            ax = ax[start:start + _CHUNK]
        ue = u[(c[:, :, None] * 6 + np.arange(6)).reshape(len(c), -1)]  # (n_el, 54, k)
        e = np.zeros((4, len(c), k))
        for part, (abd, h) in enumerate(parts):
            Kp, _ = mitc9_matrices(model.nodes[c], directors[c], abd, h, (0.0, 0.0, 0.0),
                                   lam.thickness, ax, drill_df if part == 3 else 0.0)
            e[part] = np.einsum("eik,eij,ejk->ek", ue, Kp, ue, optimize=True)
        normal, twist, shear, membrane = e
        to_twist = twist > normal  # transverse shear joins the dominant curvature kind
        out[:, 0] += (normal + np.where(to_twist, 0.0, shear)).sum(axis=0)
        out[:, 1] += (twist + np.where(to_twist, shear, 0.0)).sum(axis=0)
        out[:, 2] += membrane.sum(axis=0)
    return out


def energy_split(model: FEModel, shapes: np.ndarray) -> np.ndarray:
    """Strain energy of mode shapes split into bending, torsion, in-plane and axial parts.

    Parameters
    ----------
    model : FEModel
        A model built by mvtk (plates, beams, :func:`mvtk.fe.assemble_model`, imported
        meshes), whose element groups are recorded in ``meta``.
    shapes : ndarray, shape (n_dof,) or (n_dof, n_modes)

    Returns
    -------
    ndarray, shape (n_modes, 4)
        Energy (J for unit modal amplitude) in the parts :data:`ENERGY_PARTS`:

        - shells (in each element's frame, ply axes from the material axis):
          ``bending`` = normal curvatures ``k' D_n k`` with ``D_n`` the D11, D12, D22
          terms; ``torsion`` = twist ``D66 k12^2``; the transverse shear energy
          ``g' H g`` of an element joins its larger of the two (thick strips twist
          through transverse shear);
          ``in-plane`` = membrane ``e' A e`` plus the drilling penalty. The coupling terms
          (B, D16, D26) belong to no part and are left out.
        - beams: ``bending`` = flexure and shear in both planes, ``torsion`` = GJ,
          ``axial`` = EA.

        Springs, masses and rigid links carry no part. A model without recorded element
        groups (e.g. assembled matrices) gives NaN.

    Examples
    --------
    Fractions of strain energy of the first mode of a plate clamped on one edge (almost
    all bending):

    >>> from mvtk.fe import IsotropicMaterial, Ply, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.3, [Ply(steel, 3e-3)], nx=4, ny=4, clamp="x0")
    >>> e = energy_split(plate, modal_analysis(plate, 1).shapes)
    >>> ENERGY_PARTS, np.round(e[0] / e[0].sum(), 2)
    (('bending', 'torsion', 'in-plane', 'axial'), array([1., 0., 0., 0.]))
    """
    from ._beam import _element_frames, timoshenko_element_matrices
    from ._laminate import Laminate
    from ._shell3d import _local_frames, shell_local_geometry

    phi = np.asarray(shapes, dtype=float)
    if phi.ndim == 1:
        phi = phi[:, None]
    if phi.shape[0] != model.n_dof:
        raise DimensionError(f"expected {model.n_dof} rows of mode shapes, got {phi.shape[0]}")
    k = phi.shape[1]
    out = np.zeros((k, 4))
    shells, beams = _shell_groups(model), _beam_groups(model)
    if not shells and not beams:
        return np.full((k, 4), np.nan)
    u = model.expand(phi).reshape(model.n_nodes * 6, k)
    drill = model.meta.get("drill_factor")
    for kind, idx, lam, axis in shells:
        assert isinstance(lam, Laminate)
        conn = model.elements[kind][idx]
        abd = lam.ABD
        zero2 = np.zeros((2, 2))
        a_only = np.zeros((6, 6))
        a_only[:3, :3] = abd[:3, :3]
        d_n = np.zeros((6, 6))
        d_n[3:5, 3:5] = abd[3:5, 3:5]
        d_t = np.zeros((6, 6))
        d_t[5, 5] = abd[5, 5]
        parts = [(d_n, zero2), (d_t, zero2), (np.zeros((6, 6)), lam.H), (a_only, zero2)]
        drill_df = 1e-3 if drill is None else drill
        factors: dict = {}
        if kind == "mitc9":  # curved nine-node shells: part matrices per element
            out += _mitc9_parts(model, conn, lam, axis, parts, drill_df, u)
            continue
        for start in range(0, len(conn), _CHUNK):
            c = conn[start:start + _CHUNK]
            dofs = (c[:, :, None] * 6 + np.arange(6)).reshape(len(c), -1)
            ax = np.asarray(axis, dtype=float)
            if ax.ndim == 2:
                ax = ax[start:start + _CHUNK]
            local, R = _local_frames(model.nodes[c], ax)
            if np.any(local[:, :, 2] != 0) or np.any(R != R[0]):
                # warped or differently oriented elements: the general transformation
                xy, T = shell_local_geometry(model.nodes[c], ax)
                ue = T @ u[dofs]  # element-frame DOFs
                uT = ue.transpose(1, 0, 2)
            else:
                # exactly flat elements sharing one frame R (a flat plate): T is R on
                # every 3-vector (translations, rotations) of every node, applied as one
                # product, and not at all when R is the identity (a plate in x-y);
                # gathered element DOF first, the layout of the products below
                xy = local[:, :, :2]
                uT = u[dofs.T]                                      # (n_e_dof, n_el, k)
                if not np.array_equal(R[0], np.eye(3)):
                    uT = (R[0] @ uT.reshape(-1, 3, len(c) * k)).reshape(uT.shape)
                ue = uT.transpose(1, 0, 2)
            # identical element shapes share their matrices (structured meshes): the four
            # parts of each distinct shape come from one element-matrix call
            scale = max(float(np.abs(xy).max()), 1e-300)
            key = np.round(xy.reshape(len(c), -1) / (1e-10 * scale)).astype(np.int64)
            _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
            inv = inv.ravel()
            n_u = len(first)
            e = np.empty((4, len(c), k))
            if n_u <= _SHARED_SHAPES:
                # factors of the four part matrices of each distinct shape, computed once
                # for the whole group (chunks of a structured mesh share their shapes)
                tags = [(scale, key[i].tobytes()) for i in first]
                new = [g for g, t in enumerate(tags) if t not in factors]
                if new:
                    Ku = _part_matrices(xy[first[new]], parts, c.shape[1], lam, drill_df)
                    for j, g in enumerate(new):
                        factors[tags[g]] = _part_factors(Ku[:, j])
                for g in range(n_u):
                    sel = np.flatnonzero(inv == g) if n_u > 1 else slice(None)
                    # u' K_p u of every element of this shape as a sum of squares
                    # |B u|^2 with K_p = B' B (see _part_factors): one matrix product
                    # with the few rows of B (20 instead of 4 x 24 for a MITC4 quad)
                    B, S = factors[tags[g]]
                    ug = uT[:, sel].reshape(uT.shape[0], -1)
                    y = B @ ug
                    e[:, sel] = (S @ (y * y)).reshape(4, -1, k)
            else:
                Ku = _part_matrices(xy[first], parts, c.shape[1], lam, drill_df)
                for part in range(4):
                    e[part] = np.einsum("eik,eij,ejk->ek", ue, Ku[part][inv], ue,
                                        optimize=True)
            normal, twist, shear, membrane = e
            # transverse shear goes with the element's dominant curvature kind
            to_twist = twist > normal
            out[:, 0] += (normal + np.where(to_twist, 0.0, shear)).sum(axis=0)
            out[:, 1] += (twist + np.where(to_twist, shear, 0.0)).sum(axis=0)
            out[:, 2] += membrane.sum(axis=0)
    for idx, sec, orient, offset in beams:
        conn = model.elements["beam2"][idx]
        off = np.asarray(offset, dtype=float)
        L, R = _element_frames(model.nodes[conn[:, 0]] + off, model.nodes[conn[:, 1]] + off,
                               orient)
        Kl, _ = timoshenko_element_matrices(L, sec.EA, sec.GJ, sec.EIy, sec.EIz, sec.kGAz,
                                            sec.kGAy, sec.rhoA, sec.rhoIy, sec.rhoIz)
        dofs = (conn[:, :, None] * 6 + np.arange(6)).reshape(len(conn), 12)
        ue = u[dofs]  # global (n_el, 12, k)
        ue = ue.reshape(len(conn), 4, 3, k)
        if np.any(off):
            # translations of the axis: u + theta x e
            th = ue[:, [1, 3]]
            shift = np.cross(th, off[None, None, :, None], axis=2)
            ue = ue.copy()
            ue[:, [0, 2]] += shift
        ul = np.einsum("eij,ebjk->ebik", R, ue).reshape(len(conn), 12, k)
        for col, sel in ((3, [0, 6]), (1, [3, 9]), (0, [1, 2, 4, 5, 7, 8, 10, 11])):
            Ks = Kl[:, sel][:, :, sel]
            us = ul[:, sel]
            out[:, col] += np.einsum("eik,eij,ejk->k", us, Ks, us, optimize=True)
    return out


def mode_type(model: FEModel, shape: np.ndarray) -> str:
    """Label an elastic mode ``"bending"``, ``"torsion"``, ``"in-plane"`` or ``"axial"``.

    The label is the largest part of the mode's strain energy (:func:`energy_split`);
    ties go to the first in :data:`ENERGY_PARTS`. On curved shells a flexural mode can
    store most of its strain energy in membrane stretching: when the membrane part is the
    largest and the motion normal to the shell surface carries at least half of the
    shells' translational kinetic energy, the mode is labelled by the larger of its
    bending and torsion parts (see :mod:`mvtk.fe._mode_labels`); ``"in-plane"`` is left
    for modes that move in the surface. The label depends on no node order, mesh
    symmetry or eigenvector sign, so it is the same for every run and for a rotated copy
    of the model (with the material axis rotated too). Models without element groups
    (assembled matrices) are labelled from the kinetic energy per DOF component:
    ``"in-plane"`` when ux and uy carry more than uz, else ``"bending"``.

    Examples
    --------
    The first mode of a clamped square plate is a bending mode:

    >>> from mvtk.fe import IsotropicMaterial, Ply, plate_model
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> plate = plate_model(0.3, 0.3, [Ply(steel, 3e-3)], nx=4, ny=4, clamp="x0")
    >>> mode_type(plate, modal_analysis(plate, 1).shapes[:, 0])
    'bending'
    """
    from ._mode_labels import label_modes

    phi = np.asarray(shape, dtype=float)
    label = label_modes(model, phi[:, None] if phi.ndim == 1 else phi,
                        energy_split(model, shape), ENERGY_PARTS)[0]
    if label is not None:
        return label
    phi = np.asarray(shape, dtype=float)
    ke = phi * (model.M @ phi)
    comp = np.bincount(model.dof_component, weights=ke, minlength=6)
    return "in-plane" if comp[0] + comp[1] > comp[2] else "bending"


def _smooth_trial_scale(model: FEModel, pairs=None, origins=(0, 1, 2)) -> float:
    """Smallest Rayleigh quotient (rad/s)^2 of smooth quadratic bending trial fields.

    Fields ``u_d = s_a^2`` with the Kirchhoff-consistent rotation
    ``theta = (e_a x e_d) 2 s_a`` for every pair of axes (a, d), with ``s_a`` measured
    from the minimum, the centroid and the maximum of coordinate a (so that a field
    vanishes on a support along a coordinate line). Within a small factor of the first
    elastic eigenvalue of a free or partly supported structure; used to place the
    negative shift of a singular problem.

    ``pairs``, a set of (a, d), and ``origins`` (0: minimum, 1: centroid, 2: maximum)
    restrict the fields: the minimum over fewer fields is an upper bound of the full
    one.
    """
    node, comp = model.dof_node, model.dof_component
    xyz = model.nodes
    fields = []
    for a in range(3):
        if np.ptp(xyz[:, a]) == 0:
            continue
        for o in origins:
            s_a = xyz[:, a] - (xyz[:, a].min(), xyz[:, a].mean(), xyz[:, a].max())[o]
            for d in range(3):
                if d == a or (pairs is not None and (a, d) not in pairs):
                    continue
                full = np.zeros((model.n_nodes, 6))
                full[:, d] = s_a**2
                axis = np.cross(np.eye(3)[a], np.eye(3)[d])
                full[:, 3:] = 2 * s_a[:, None] * axis[None, :]
                fields.append(full[node, comp])
    if not fields:
        return np.inf
    # all trial fields in one pass over K and M (one sparse product per matrix)
    X = np.column_stack(fields)
    mm = np.einsum("ij,ij->j", X, model.M @ X)
    kk = np.einsum("ij,ij->j", X, model.K @ X)
    ok = (mm > 0) & (kk > 0)
    return float(np.min(kk[ok] / mm[ok])) if np.any(ok) else np.inf


def _trial_scale_bound(model: FEModel) -> float:
    """Upper bound of :func:`_smooth_trial_scale` from four of its fields.

    The fields bend each of the two longest extents of the model along the shortest
    (a plate in x-y: along z), from either end (the cantilever shape of a plate or beam
    clamped along one edge): one product with K and M of four vectors instead of twelve
    or more.
    """
    ext = np.ptp(model.nodes, axis=0)
    d = int(np.argmin(ext))
    pairs = {(a, d) for a in range(3) if a != d}
    return _smooth_trial_scale(model, pairs=pairs, origins=(0, 2))


def _rigid_fields(model: FEModel) -> np.ndarray:
    """The six rigid-body motions (translations, rotations about the centroid) over the
    model's free DOFs, shape (n_dof, 6)."""
    xyz = model.nodes
    c = xyz.mean(axis=0)
    full = np.zeros((model.n_nodes, 6, 6))
    for j in range(3):
        full[:, j, j] = 1.0
        axis = np.eye(3)[j]
        full[:, :3, 3 + j] = np.cross(axis, xyz - c)
        full[:, 3 + j, 3 + j] = 1.0
    return full.reshape(model.n_nodes * 6, 6)[model.dof_node * 6 + model.dof_component]


def _unsupported(model: FEModel) -> bool:
    """True when K has no stiffness against any rigid-body motion (a free structure).

    One product of K with a fixed combination of the six rigid-body motions (1.0, 1.1,
    ..., 1.5): below 1e-10 of ``max K_ii`` times its size, K annihilates it to round-off
    and, but for an exact cancellation between the motions' forces, every one of them,
    so K is singular. Either way the answer is only used to choose a negative shift,
    which is valid for any K (the factorisation of ``K - sigma M`` is then positive
    definite); it spares the factorisations that find a singular K out.
    """
    r = _rigid_fields(model) @ (1.0 + 0.1 * np.arange(6))
    size = float(np.abs(r).max(initial=0.0))
    if size == 0.0:
        return False
    kscale = float(np.abs(model.K.diagonal()).max(initial=0.0))
    return bool(np.abs(model.K @ r).max(initial=0.0) <= 1e-10 * kscale * size)


def _rigid_residual(model: FEModel, vectors: np.ndarray) -> np.ndarray:
    """M-weighted share of each vector outside the span of the rigid-body motions.

    ``inf`` when the rigid-body part loads the structure (``|K r| > 1e-8 max K_ii |r|``).
    """
    R = _rigid_fields(model)
    MR = model.M @ R
    G = R.T @ MR
    keep = np.diag(G) > 1e-14 * max(np.diag(G).max(), 1e-300)
    R, MR, G = R[:, keep], MR[:, keep], G[np.ix_(keep, keep)]
    coef = np.linalg.lstsq(G, MR.T @ vectors, rcond=None)[0]
    fit = R @ coef
    r = vectors - fit
    num = np.einsum("ij,ij->j", r, model.M @ r)
    den = np.einsum("ij,ij->j", vectors, model.M @ vectors)
    share = num / np.where(den > 0, den, 1.0)
    # a rigid-body shape that loads the structure (a body on elastic supports) is not a
    # rigid-body mode: its stiffness forces are far above round-off
    kscale = max(float(np.abs(model.K.diagonal()).max(initial=0.0)), 1e-300)
    force = np.abs(model.K @ fit).max(axis=0) / (kscale * np.abs(fit).max(axis=0) + 1e-300)
    return np.where(force < 1e-8, share, np.inf)


def _lowest_modes(model: FEModel, n: int, sigma: float | None, trial=None):
    """Lowest eigenpairs by :func:`mvtk.fe.eigsh_lowest` (one factorisation).

    With ``sigma=None`` the shift is 0 when K is non-singular; otherwise it is -1 % of
    :func:`_smooth_trial_scale` (or of ``trial()``, the same value memoised by the
    caller), a model-aware estimate of the first elastic eigenvalue.
    """
    if trial is None:
        def trial():
            return _smooth_trial_scale(model)

    def singular_shift():  # evaluated by eigsh_lowest only when K is singular
        return -1e-2 * trial()

    return eigsh_lowest(model.K, model.M, n, sigma=sigma, singular_shift=singular_shift)


def modal_analysis(
    model: FEModel, n_modes: int = 6, sigma: float | None = None, rigid_tol_hz: float | None = None
) -> ModalResult:
    """Lowest ``n_modes`` modes by shift-invert Lanczos (:func:`mvtk.fe.eigsh_lowest`).

    Parameters
    ----------
    model : FEModel
    n_modes : int
        Number of modes (1 <= n_modes < n_dof).
    sigma : float, optional
        Shift in (rad/s)^2. Default: a free structure (K annihilates the rigid-body
        motions, :func:`_unsupported`) gets -1 % of the Rayleigh quotient of a smooth
        quadratic bending field, a few times below the first elastic eigenvalue;
        otherwise K is factorised once and, if a solve round trip shows it non-singular,
        that factorisation is reused with shift 0, else (rigid-body modes of a partly
        supported structure) the same negative shift is used.
    rigid_tol_hz : float, optional
        Modes below this frequency are rigid-body modes. Default:
        ``|omega2| < max(1e-7 max|omega2|, (2 pi 1e-3 Hz)^2)``; and also a mode whose
        ``|omega2|`` is below ``1e-5 q`` (``q`` the Rayleigh quotient of smooth trial
        fields, an estimate of the first elastic eigenvalue) and whose shape is a
        rigid-body field (M-weighted residual after projection on the six rigid-body
        motions below 1e-4), so that a free-free model asked for no more modes than it
        has rigid-body modes is still classified. Rigid modes are reported at 0 Hz and
        first; modes are sorted.

    Notes
    -----
    Lanczos shift-invert (ARPACK) on ``(K - sigma M)^-1 M``; it converges quickly only
    when the shift is close to the wanted eigenvalues compared with the rest of the
    spectrum, hence the shift choice above (a shift from matrix diagonals can be 1e9
    times too far for thin plates).

    Returns
    -------
    ModalResult

    Examples
    --------
    A steel cantilever 300 x 20 x 2 mm. Euler-Bernoulli closed form:
    ``f1 = 1.87510**2 / (2 pi) sqrt(E I / (rho A L**4))`` = 18.567 Hz:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)   # Pa, -, kg/m^3
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> res = modal_analysis(beam, 3)
    >>> np.round(res.fn_hz, 1), res.mode_type
    (array([ 18.6, 116.3, 185. ]), ('bending', 'bending', 'bending'))
    >>> E, I, A = 2.1e11, 0.02 * 0.002**3 / 12, 0.02 * 0.002
    >>> round(1.87510407**2 / (2 * np.pi) * float(np.sqrt(E * I / (7850.0 * A * 0.3**4))), 1)
    18.6
    """
    if not isinstance(model, FEModel):
        raise ParameterError(f"model must be an FEModel, got {type(model).__name__}")
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)):
        raise ParameterError(f"n_modes must be an integer, got {n_modes!r}")
    if not 1 <= n_modes < model.n_dof:
        raise ParameterError(f"n_modes must be in 1..{model.n_dof - 1}, got {n_modes}")
    memo: list[float] = []

    def trial() -> float:  # computed once, and only when needed
        if not memo:
            memo.append(_smooth_trial_scale(model))
        return memo[0]

    if sigma is None and _unsupported(model):
        # K is singular (rigid-body modes): the negative shift eigsh_lowest would pick
        # after finding that out by factorising K, without those factorisations
        q = trial()
        if np.isfinite(q) and q > 0:
            sigma = -1e-2 * q
    sol = _lowest_modes(model, int(n_modes), sigma, trial)
    w2 = sol.omega2
    if rigid_tol_hz is None:
        # relative to the elastic scale: the largest computed eigenvalue or, when every
        # computed mode may be rigid (free-free, n_modes <= 6), the Rayleigh quotient of
        # smooth trial fields (an estimate of the first elastic eigenvalue)
        thresh = max(1e-7 * float(np.max(np.abs(w2))) if w2.size else 0.0,
                     (2 * np.pi * 1e-3) ** 2)
        rigid = np.abs(w2) < thresh
        low = np.abs(w2[~rigid])
        bound = _trial_scale_bound(model) if low.size else np.inf
        if np.isfinite(bound) and bound > 0:
            # zero-energy modes by a scale that does not depend on how many modes were
            # asked for (the largest computed eigenvalue does): the pieces of a cracked
            # mesh move rigidly whether -n is 6 or 8
            rigid |= np.abs(w2) < 1e-7 * bound
            low = np.abs(w2[~rigid])
        # the candidates below need |omega2| < 1e-5 q; the minimum over four of the
        # trial fields bounds q from above, and when no mode is below 1e-5 of that
        # bound, none is a candidate and q is not needed (clamped structures)
        if low.size and (memo or low.min() < 1e-5 * bound):
            trial_q = trial()
        else:
            trial_q = np.inf
        if np.isfinite(trial_q):
            # a rigid-body shape with an eigenvalue far below the smooth-field estimate
            # of the first elastic one is rigid too
            cand = ~rigid & (np.abs(w2) < 1e-5 * trial_q)
            if np.any(cand):
                cand[cand] = _rigid_residual(model, sol.vectors[:, cand]) < 1e-4
                rigid |= cand
    else:
        rigid = np.abs(w2) < (2 * np.pi * float(rigid_tol_hz)) ** 2
    fn = np.where(rigid, 0.0, np.sqrt(np.abs(w2)) / (2 * np.pi))
    order = np.lexsort((w2, fn))
    w2, fn, rigid, vecs = w2[order], fn[order], rigid[order], sol.vectors[:, order]
    from ._mode_labels import label_modes

    split = energy_split(model, vecs)
    by_energy = label_modes(model, vecs, split, ENERGY_PARTS)
    labels = []
    for i, r in enumerate(rigid):
        if r:
            labels.append("rigid")
        elif by_energy[i] is not None:
            labels.append(by_energy[i])
        else:
            labels.append(mode_type(model, vecs[:, i]))
    from ._sanity import warn_under_resolved

    warn_under_resolved(model, vecs, fn, rigid)
    return ModalResult(fn_hz=fn, omega2=w2, shapes=vecs, rigid=rigid, mode_type=tuple(labels),
                       dof_node_id=np.asarray(model.node_ids)[model.dof_node],
                       dof_component=np.asarray(model.dof_component))


def static_solve(model: FEModel, f: np.ndarray) -> np.ndarray:
    """Static displacement ``K^-1 f`` over the free DOFs.

    Parameters
    ----------
    model : FEModel
    f : ndarray (n_dof,) or (n_dof, k)
        Load vector(s) in N and N m over the free DOFs.

    Returns
    -------
    ndarray, same shape as ``f``
        Displacements (m) and rotations (rad).

    Raises
    ------
    DimensionError
        If ``f`` does not have ``n_dof`` rows.
    ParameterError
        If K is singular (under-constrained structure).

    Examples
    --------
    Unit tip load on the steel cantilever (300 x 20 x 2 mm); closed form
    ``w = P L**3 / (3 E I)`` = 3.214 mm:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> tip_uz = beam.dof_index(int(beam.node_sets["tip"][0]), "uz")
    >>> f = np.zeros(beam.n_dof)
    >>> f[tip_uz] = 1.0                                   # N
    >>> round(float(static_solve(beam, f)[tip_uz]) * 1e3, 3)     # mm
    3.214
    >>> round(0.3**3 / (3 * 2.1e11 * 0.02 * 0.002**3 / 12) * 1e3, 3)
    3.214
    """
    f = np.asarray(f, dtype=float)
    if f.ndim not in (1, 2) or f.shape[0] != model.n_dof:
        raise DimensionError(
            f"load must have shape ({model.n_dof},) or ({model.n_dof}, k), got {f.shape}"
        )
    lu = factorize(model.K)
    x = lu.solve(f)
    if not np.all(np.isfinite(x)):
        raise ParameterError("static solution is not finite: is the structure constrained?")
    return x
