"""3-D shear-deformable (Timoshenko) beam with layered rectangular sections.

The element has two nodes and six DOFs per node (ux, uy, uz, rx, ry, rz). Bending uses
the *interdependent interpolation* shape functions of Friedman & Kosmatka (1993): cubic
deflection and quadratic rotation tied together so that the transverse shear strain is
constant along the element. With them the element stiffness is the exact
shear-deformable stiffness (the classical matrix with the ``phi = 12 EI / (kGA L^2)``
terms, Przemieniecki 1968) and the consistent mass contains translational and rotary
inertia. Element matrices are integrated by 4-point Gauss quadrature, exact for the
polynomial degrees involved, and computed for all elements at once.

Sign conventions (right-handed): a rotation ``ry`` about +y moves a point at height
``z`` above the axis by ``ux = ry * z``, hence ``ry = -d(uz)/dx`` in the x-z plane;
``rz = +d(uy)/dx`` in the x-y plane.

References
----------
Friedman, Z. & Kosmatka, J. B. (1993). An improved two-node Timoshenko beam finite
element. Computers & Structures 47(3), 473-481.
Przemieniecki, J. S. (1968). Theory of Matrix Structural Analysis. McGraw-Hill, ch. 5.
Timoshenko, S. & Goodier, J. N. (1970). Theory of Elasticity, 3rd ed., section 109
(torsion of a rectangular bar).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from ..errors import DimensionError, ParameterError
from ._materials import Ply
from ._model import DOF_NAMES, FEModel

__all__ = [
    "BeamSection",
    "BeamPatch",
    "beam_section",
    "ply_axial_modulus",
    "timoshenko_element_matrices",
    "beam_element_matrices",
    "cantilever_beam",
    "SHEAR_CORRECTION",
]

#: Shear correction factor of a rectangular section (Mindlin / Reissner value).
SHEAR_CORRECTION: float = 5.0 / 6.0

# 4-point Gauss-Legendre rule on [0, 1]: exact up to degree 7 (mass terms are degree 6).
_GX, _GW = np.polynomial.legendre.leggauss(4)
_GX = 0.5 * (_GX + 1.0)
_GW = 0.5 * _GW


# --------------------------------------------------------------------------- sections
def ply_axial_modulus(ply: Ply) -> float:
    """Uniaxial-stress modulus of a ply along the beam axis (Pa).

    For a narrow beam the lateral stress is free, so the modulus along x is
    ``1 / Sbar11`` of the ply's plane-stress compliance rotated by ``angle_deg``
    (equals E1 for a 0 degree ply, E for an isotropic one).
    """
    q = ply.material.plane_stress_q()
    s = np.linalg.inv(q)
    c, si = np.cos(np.radians(ply.angle_deg)), np.sin(np.radians(ply.angle_deg))
    # compliance along a direction at -angle from the material axis 1
    s11 = (s[0, 0] * c**4 + (2.0 * s[0, 1] + s[2, 2]) * c**2 * si**2 + s[1, 1] * si**4)
    return float(1.0 / s11)


def _ply_shear_moduli(ply: Ply) -> tuple[float, float]:
    """(G_xz, G_xy) of a ply in beam axes (Pa): transverse and in-plane shear."""
    m = ply.material
    c, s = np.cos(np.radians(ply.angle_deg)), np.sin(np.radians(ply.angle_deg))
    g_xz = m.G13 * c**2 + m.G23 * s**2
    q = m.plane_stress_q()
    # rotated Q66 (in-plane shear stiffness in beam axes)
    q66 = (q[0, 0] + q[1, 1] - 2.0 * q[0, 1] - 2.0 * q[2, 2]) * c**2 * s**2 + q[2, 2] * (
        c**4 + s**4
    )
    return float(g_xz), float(q66)


def _rect_torsion_factor(width: float, thickness: float) -> float:
    """Saint-Venant torsion constant J of a solid rectangle (m^4), exact series.

    ``J = a b^3 / 3 * (1 - 192 b / (pi^5 a) * sum_{n odd} tanh(n pi a / (2 b)) / n^5)``
    with ``a >= b`` the long and short sides (Timoshenko & Goodier 1970, eq. 171).
    """
    a, b = max(width, thickness), min(width, thickness)
    n = np.arange(1, 200, 2, dtype=float)
    series = np.sum(np.tanh(n * np.pi * a / (2.0 * b)) / n**5)
    return a * b**3 / 3.0 * (1.0 - 192.0 / np.pi**5 * (b / a) * series)


@dataclass(frozen=True)
class BeamSection:
    """Stiffness and inertia of a layered rectangular beam section.

    The beam axis is the neutral axis of axial stress (modulus-weighted centroid) of the
    stack; ``z`` is measured from the bottom of the stack. Bending "about y" (``EIy``,
    in the x-z plane) is bending about the width axis, the plate-like direction.

    Attributes
    ----------
    width, thickness : float
        Section width (along y) and total thickness (along z), m.
    neutral_axis : float
        Height of the neutral axis above the bottom of the stack, m.
    EA : float
        Axial stiffness, N.
    EIy, EIz : float
        Bending stiffness about y (through the thickness, x-z plane) and about z
        (in-plane, x-y plane), N m^2. ``EIy`` is about the neutral axis.
    GJ : float
        Saint-Venant torsion stiffness, N m^2.
    kGAz, kGAy : float
        Shear stiffness for transverse shear in the x-z plane and in the x-y plane, N,
        with the shear correction factor :data:`SHEAR_CORRECTION`.
    rhoA : float
        Mass per length, kg/m.
    rhoIy, rhoIz : float
        Rotary inertia per length about y (through the neutral axis) and about z,
        kg m. The torsional inertia is ``rhoIy + rhoIz``.
    mass_offset : float
        Height of the mass centroid above the neutral axis, m (not used by the element;
        see Notes of :func:`beam_section`).

    Examples
    --------
    Returned by :func:`beam_section` and the section helpers
    (:func:`mvtk.fe.rectangle_section`, ...); stiffness in N, N m^2, inertia in kg/m, kg m:

    >>> from mvtk.fe import IsotropicMaterial, Ply
    >>> s = beam_section([Ply(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0), 2e-3)], 0.02)
    >>> round(s.EA / 1e6, 3), round(s.EIz, 3)      # E b t, E t b**3 / 12
    (8.4, 280.0)
    """

    width: float
    thickness: float
    neutral_axis: float
    EA: float
    EIy: float
    EIz: float
    GJ: float
    kGAz: float
    kGAy: float
    rhoA: float
    rhoIy: float
    rhoIz: float
    mass_offset: float

    def to_dataframe(self):
        """One-row :class:`pandas.DataFrame` of the section properties (SI units)."""
        import pandas as pd

        return pd.DataFrame([self.as_dict()])

    def as_dict(self) -> dict[str, float]:
        """Section properties as a plain dict of floats."""
        return {k: float(getattr(self, k)) for k in self.__dataclass_fields__}


def _check_layers(layers: Sequence[Ply], where: str) -> tuple[Ply, ...]:
    layers = tuple(layers)
    if not layers:
        raise ParameterError(f"{where}: the layer stack is empty; expected at least one Ply")
    for i, p in enumerate(layers):
        if not isinstance(p, Ply):
            raise ParameterError(
                f"{where}: layer {i} must be a mvtk.fe.Ply, got {type(p).__name__}"
            )
    return layers


def beam_section(
    layers: Sequence[Ply],
    width: float,
    shear_correction: float = SHEAR_CORRECTION,
    layer_widths: Sequence[float] | None = None,
) -> BeamSection:
    """Section properties of a stack of plies of equal width, bottom to top.

    Parameters
    ----------
    layers : sequence of Ply
        Layers from the bottom (z = 0) to the top, all of width ``width`` unless
        ``layer_widths`` is given.
    width : float
        Section width along y, m (the width recorded in the section).
    shear_correction : float
        Shear correction factor k applied to both shear areas (default 5/6).
    layer_widths : sequence of float, optional
        Width of each layer (m), all centred on y = 0, e.g. a piezo patch narrower than
        the beam. Every sum below then uses ``b_k`` in place of ``b``.

    Returns
    -------
    BeamSection

    Notes
    -----
    - Axial stiffness ``EA = sum E_k b t_k`` with the uniaxial modulus of each ply
      (:func:`ply_axial_modulus`); neutral axis ``z_n = sum E_k b t_k z_k / EA``
      (the paper's eq. 6 for N layers).
    - An unsymmetric stack couples stretching and bending about the mid-plane. Taking
      the neutral axis as the beam axis removes that coupling exactly for the section
      (``EIy`` is then the bending stiffness about the neutral axis, the standard
      treatment of composite beams). What is neglected: where consecutive segments have
      different neutral axes (patch edges) the axis is taken as straight, i.e. the small
      eccentricity between segments is ignored; and the mass centroid may differ from
      the neutral axis (``mass_offset``), whose axial/rotary mass coupling is ignored.
    - ``EIz = sum E_k t_k b^3 / 12`` (bending in the plane of the width).
    - Torsion: ``GJ = G_eff * J(b, t)`` with ``J`` the exact Saint-Venant series for a
      rectangle and ``G_eff = 12 D66 / t^3``, ``D66`` the laminate twisting stiffness
      about the shear-modulus-weighted centroid. For one isotropic layer this is the
      classical ``G J``; for a thin strip ``J -> b t^3 (1 - 0.630 t/b) / 3``.
    - Shear: ``kGAz = k sum G_xz,k b t_k`` and ``kGAy = k sum G_xy,k b t_k`` with
      ``k = shear_correction`` (default 5/6, the Reissner factor of first-order shear
      deformation; the exact layered shear factor is not computed).
    - Inertia: ``rhoA = sum rho_k b t_k``, ``rhoIy = sum rho_k b int (z - z_n)^2 dz``,
      ``rhoIz = sum rho_k t_k b^3 / 12``.
    - With unequal ``layer_widths`` the torsion stiffness is an approximation:
      ``GJ = 4 sum_k b_k D66_k * J(b_max, t) / (b_max t^3 / 3)`` (layer twisting
      stiffnesses about the common centroid, with the thin-rectangle correction of the
      widest layer); everything else stays exact for the stacked rectangles.

    Examples
    --------
    One steel layer 20 x 2 mm: ``EI = E b t**3 / 12`` = 2.8 N m^2, ``rho A`` = 0.314 kg/m:

    >>> from mvtk.fe import IsotropicMaterial, Ply
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> s = beam_section([Ply(steel, 2e-3)], width=0.02)
    >>> round(s.EIy, 6), round(s.rhoA, 6), s.neutral_axis
    (2.8, 0.314, 0.001)
    """
    layers = _check_layers(layers, "beam_section")
    b = float(width)
    if not (np.isfinite(b) and b > 0):
        raise ParameterError(f"beam_section: width must be a positive length in m, got {width!r}")
    t = np.array([p.thickness for p in layers], dtype=float)
    if layer_widths is None:
        bk = np.full(len(layers), b)
    else:
        bk = np.asarray(layer_widths, dtype=float)
        if bk.shape != (len(layers),):
            raise DimensionError(
                f"beam_section: expected {len(layers)} layer widths, got shape {bk.shape}"
            )
        if not np.all(np.isfinite(bk) & (bk > 0)):
            raise ParameterError(
                f"beam_section: layer widths must be positive lengths in m, got {bk.tolist()}"
            )
    z1 = np.cumsum(t)
    z0 = z1 - t
    E = np.array([ply_axial_modulus(p) for p in layers])
    shear = np.array([_ply_shear_moduli(p) for p in layers])
    g_xz, g_xy = shear[:, 0], shear[:, 1]
    rho = np.array([p.material.rho for p in layers], dtype=float)

    EA = float(np.sum(E * t * bk))
    zn = float(np.sum(E * bk * (z1**2 - z0**2) / 2.0) / EA)
    second = ((z1 - zn) ** 3 - (z0 - zn) ** 3) / 3.0
    EIy = float(np.sum(E * second * bk))
    EIz = float(np.sum(E * t * bk**3) / 12.0)
    # torsion: twisting stiffness 4 b D66 about the G-weighted centroid, thin-rectangle
    # correction of the widest layer (exact Saint-Venant value for equal widths)
    zg = float(np.sum(g_xy * bk * (z1**2 - z0**2) / 2.0) / np.sum(g_xy * bk * t))
    bd66 = float(np.sum(g_xy * bk * ((z1 - zg) ** 3 - (z0 - zg) ** 3) / 3.0))
    h = float(z1[-1])
    bmax = float(bk.max())
    GJ = 4.0 * bd66 * _rect_torsion_factor(bmax, h) / (bmax * h**3 / 3.0)
    k = float(shear_correction)
    if not (np.isfinite(k) and 0 < k <= 1):
        raise ParameterError(
            f"beam_section: shear_correction must be in (0, 1], got {shear_correction!r}"
        )
    kGAz = k * float(np.sum(g_xz * t * bk))
    kGAy = k * float(np.sum(g_xy * t * bk))
    rhoA = float(np.sum(rho * t * bk))
    rhoIy = float(np.sum(rho * second * bk))
    rhoIz = float(np.sum(rho * t * bk**3) / 12.0)
    zm = float(np.sum(rho * bk * (z1**2 - z0**2) / 2.0) / rhoA)
    return BeamSection(
        width=b, thickness=h, neutral_axis=zn, EA=EA, EIy=EIy, EIz=EIz, GJ=GJ,
        kGAz=kGAz, kGAy=kGAy, rhoA=rhoA, rhoIy=rhoIy, rhoIz=rhoIz, mass_offset=zm - zn,
    )


# --------------------------------------------------------------------------- element
def _bending_matrices(L, EI, kGA, rhoA, rhoI):
    """Stiffness and mass (n, 4, 4) of IIE Timoshenko bending, DOFs (v1, t1, v2, t2).

    ``t = dv/dx`` convention (positive rotation turns +x into +v).
    """
    L = L[:, None]
    phi = 12.0 * EI[:, None] / (kGA[:, None] * L**2)
    c = 1.0 / (1.0 + phi)
    x = _GX[None, :]
    zero = np.zeros_like(phi * x)
    # deflection shape functions N_v and their x-derivatives, shape (n, 4, g)
    nv = np.stack([
        c * (2 * x**3 - 3 * x**2 - phi * x + 1 + phi),
        c * L * (x**3 - (2 + phi / 2) * x**2 + (1 + phi / 2) * x),
        -c * (2 * x**3 - 3 * x**2 - phi * x),
        c * L * (x**3 - (1 - phi / 2) * x**2 - (phi / 2) * x),
    ], axis=1)
    dnv = np.stack([
        c * (6 * x**2 - 6 * x - phi) / L,
        c * (3 * x**2 - (4 + phi) * x + (1 + phi / 2)),
        -c * (6 * x**2 - 6 * x - phi) / L,
        c * (3 * x**2 - (2 - phi) * x - phi / 2),
    ], axis=1)
    nt = np.stack([
        6 * c / L * (x**2 - x),
        c * (3 * x**2 - (4 + phi) * x + 1 + phi),
        -6 * c / L * (x**2 - x),
        c * (3 * x**2 - (2 - phi) * x),
    ], axis=1)
    dnt = np.stack([
        6 * c / L**2 * (2 * x - 1) + zero,
        c * (6 * x - (4 + phi)) / L,
        -6 * c / L**2 * (2 * x - 1) + zero,
        c * (6 * x - (2 - phi)) / L,
    ], axis=1)
    gamma = dnv - nt
    w = _GW[None, :] * L  # (n, g) weights times Jacobian
    k = (EI[:, None, None] * np.einsum("eig,ejg,eg->eij", dnt, dnt, w)
         + kGA[:, None, None] * np.einsum("eig,ejg,eg->eij", gamma, gamma, w))
    m = (rhoA[:, None, None] * np.einsum("eig,ejg,eg->eij", nv, nv, w)
         + rhoI[:, None, None] * np.einsum("eig,ejg,eg->eij", nt, nt, w))
    return k, m


def timoshenko_element_matrices(
    length, EA, GJ, EIy, EIz, kGAz, kGAy, rhoA, rhoIy, rhoIz
) -> tuple[np.ndarray, np.ndarray]:
    """Local stiffness and consistent mass of 3-D Timoshenko beam elements.

    All arguments are scalars or arrays of shape (n_el,) (broadcast together); units as
    in :class:`BeamSection`, ``length`` in m.

    Returns
    -------
    K, M : ndarray, shape (n_el, 12, 12)
        In the element frame, DOF order (ux, uy, uz, rx, ry, rz) of node a then node b.

    Notes
    -----
    Axial and torsion: linear interpolation (exact stiffness, consistent mass with
    torsional inertia ``rhoIy + rhoIz``). Bending in x-y uses ``EIz, kGAy, rhoIz`` and
    ``rz = dv/dx``; bending in x-z uses ``EIy, kGAz, rhoIy`` and ``ry = -dw/dx``. The
    bending matrices equal the classical exact Timoshenko stiffness
    ``EI / ((1 + phi) L^3) [[12, 6L, -12, 6L], [6L, (4 + phi) L^2, -6L, (2 - phi) L^2],
    ...]`` with ``phi = 12 EI / (kGA L^2)``.
    """
    arrs = np.broadcast_arrays(*(np.atleast_1d(np.asarray(a, dtype=float)) for a in (
        length, EA, GJ, EIy, EIz, kGAz, kGAy, rhoA, rhoIy, rhoIz)))
    L, EA, GJ, EIy, EIz, kGAz, kGAy, rhoA, rhoIy, rhoIz = (a.ravel() for a in arrs)
    for name, a in (("length", L), ("EA", EA), ("GJ", GJ), ("EIy", EIy), ("EIz", EIz),
                    ("kGAz", kGAz), ("kGAy", kGAy)):
        if not np.all(np.isfinite(a) & (a > 0)):
            raise ParameterError(
                f"timoshenko_element_matrices: {name} must be positive and finite; "
                f"found {a[~(np.isfinite(a) & (a > 0))][:3]}"
            )
    for name, a in (("rhoA", rhoA), ("rhoIy", rhoIy), ("rhoIz", rhoIz)):
        if not np.all(np.isfinite(a) & (a >= 0)):
            raise ParameterError(f"timoshenko_element_matrices: {name} must be >= 0")
    n = L.size
    K = np.zeros((n, 12, 12))
    M = np.zeros((n, 12, 12))
    bar_k = np.array([[1.0, -1.0], [-1.0, 1.0]])
    bar_m = np.array([[2.0, 1.0], [1.0, 2.0]]) / 6.0
    for (i, j), stiff, inertia in (((0, 6), EA, rhoA), ((3, 9), GJ, rhoIy + rhoIz)):
        idx = np.ix_(np.arange(n), [i, j], [i, j])
        K[idx] = (stiff / L)[:, None, None] * bar_k
        M[idx] = (inertia * L)[:, None, None] * bar_m
    # x-y plane: (uy, rz) with rz = dv/dx
    k, m = _bending_matrices(L, EIz, kGAy, rhoA, rhoIz)
    idx = np.ix_(np.arange(n), [1, 5, 7, 11], [1, 5, 7, 11])
    K[idx], M[idx] = k, m
    # x-z plane: (uz, ry) with ry = -dw/dx -> flip the rotation signs
    k, m = _bending_matrices(L, EIy, kGAz, rhoA, rhoIy)
    s = np.array([1.0, -1.0, 1.0, -1.0])
    idx = np.ix_(np.arange(n), [2, 4, 8, 10], [2, 4, 8, 10])
    K[idx] = k * s[:, None] * s[None, :]
    M[idx] = m * s[:, None] * s[None, :]
    return K, M


def _element_frames(xa: np.ndarray, xb: np.ndarray, y_ref) -> tuple[np.ndarray, np.ndarray]:
    """Lengths (n,) and rotation matrices (n, 3, 3) whose rows are local x, y, z."""
    d = xb - xa
    L = np.linalg.norm(d, axis=1)
    if np.any(L <= 0):
        bad = np.flatnonzero(L <= 0)[:3]
        raise DimensionError(f"beam elements {bad.tolist()} have zero length")
    ex = d / L[:, None]
    yr = np.broadcast_to(np.asarray(y_ref, dtype=float), ex.shape)
    ez = np.cross(ex, yr)
    nz = np.linalg.norm(ez, axis=1)
    if np.any(nz < 1e-8 * np.linalg.norm(yr, axis=1)):
        bad = np.flatnonzero(nz < 1e-8)[:3]
        raise ParameterError(
            f"beam elements {bad.tolist()}: the reference y vector {tuple(yr[bad[0]])} is "
            "parallel to the element axis; pass another y_ref"
        )
    ez = ez / nz[:, None]
    ey = np.cross(ez, ex)
    return L, np.stack([ex, ey, ez], axis=1)


def beam_element_matrices(
    xyz_a, xyz_b, sections: Sequence[BeamSection], y_ref=(0.0, 1.0, 0.0)
) -> tuple[np.ndarray, np.ndarray]:
    """Global-frame stiffness and mass (n_el, 12, 12) of Timoshenko beam elements.

    Parameters
    ----------
    xyz_a, xyz_b : array_like, shape (n_el, 3)
        End coordinates of each element, m.
    sections : sequence of BeamSection, length n_el
        Section of each element; its width axis is the element's local y.
    y_ref : array_like, shape (3,) or (n_el, 3)
        A vector in the local x-y plane (the section width direction), default global y.
    """
    xa = np.atleast_2d(np.asarray(xyz_a, dtype=float))
    xb = np.atleast_2d(np.asarray(xyz_b, dtype=float))
    if xa.shape != xb.shape or xa.shape[1] != 3:
        raise DimensionError(
            f"xyz_a and xyz_b must both have shape (n_el, 3), got {xa.shape} and {xb.shape}"
        )
    if len(sections) != len(xa):
        raise DimensionError(f"expected {len(xa)} sections (one per element), got {len(sections)}")
    return _global_matrices(xa, xb, _section_array(sections), y_ref)


_PROPS = ("EA", "GJ", "EIy", "EIz", "kGAz", "kGAy", "rhoA", "rhoIy", "rhoIz")


def _section_array(sections: Sequence[BeamSection]) -> np.ndarray:
    """(n, 9) array of the element-matrix properties of each section, in _PROPS order."""
    return np.array([[getattr(s, k) for k in _PROPS] for s in sections], dtype=float)


def _global_matrices(xa, xb, props, y_ref) -> tuple[np.ndarray, np.ndarray]:
    L, R = _element_frames(xa, xb, y_ref)
    K, M = timoshenko_element_matrices(L, *props.T)
    T = np.zeros((len(L), 12, 12))
    for b in range(4):
        T[:, 3 * b:3 * b + 3, 3 * b:3 * b + 3] = R
    Tt = np.swapaxes(T, 1, 2)
    return Tt @ K @ T, Tt @ M @ T


# --------------------------------------------------------------------------- builder
@dataclass(frozen=True)
class BeamPatch:
    """A segment of the beam carrying extra layers (e.g. bonding layer + piezo patch).

    Parameters
    ----------
    name : str
        Used in node-set names ``patch:<name>:x0`` and ``patch:<name>:x1``.
    x0, x1 : float
        Start and end of the patch along the beam, m, ``0 <= x0 < x1 <= length``.
    layers : tuple of Ply
        Extra layers, listed bottom to top.
    side : {"top", "bottom"}
        Whether the extra layers sit on top of the base stack (listed bottom to top,
        first one touching the base) or below it (listed bottom to top, last one
        touching the base).
    width : float, optional
        Width of the patch layers (m), centred on the beam axis; default the beam width.

    Examples
    --------
    A PZT layer from x = 50 to 100 mm on top of a cantilever: the patch edges become mesh
    points with node sets ``patch:<name>:x0`` and ``patch:<name>:x1``:

    >>> from mvtk.fe import IsotropicMaterial, PiezoMaterial, Ply
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20,
    ...                        patches=[BeamPatch("p", 0.05, 0.10, layers=(Ply(pzt, 2e-4),))])
    >>> sorted(s for s in beam.node_sets if s.startswith("patch"))
    ['patch:p', 'patch:p:x0', 'patch:p:x1']
    """

    name: str
    x0: float
    x1: float
    layers: tuple[Ply, ...] = field(default_factory=tuple)
    side: str = "top"
    width: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "layers", _check_layers(self.layers, f"patch {self.name!r}"))
        if self.side not in ("top", "bottom"):
            raise ParameterError(
                f"patch {self.name!r}: side must be 'top' or 'bottom', got {self.side!r}"
            )
        if self.width is not None and not (
            np.isfinite(_as_float(self.width)) and _as_float(self.width) > 0
        ):
            raise ParameterError(
                f"patch {self.name!r}: width must be a positive length in m, got {self.width!r}"
            )
        x0, x1 = _as_float(self.x0), _as_float(self.x1)
        if not (np.isfinite(x0) and np.isfinite(x1) and x0 < x1):
            raise ParameterError(
                f"patch {self.name!r}: expected x0 < x1 (m), got x0={self.x0!r}, x1={self.x1!r}"
            )


def _as_patch(p) -> BeamPatch:
    if isinstance(p, BeamPatch):
        return p
    if isinstance(p, Mapping):
        try:
            return BeamPatch(**p)
        except TypeError as err:
            raise ParameterError(
                f"patch {dict(p)!r}: expected keys name, x0, x1, layers[, side, width] ({err})"
            ) from err
    raise ParameterError(f"patches must be BeamPatch or mappings, got {type(p).__name__}")


def _mesh_x(length: float, n_elements: int, breaks: np.ndarray) -> np.ndarray:
    """Node x coordinates: every break point is a node, element size about L/n."""
    pts = np.unique(np.concatenate([[0.0, length], breaks]))
    # merge break points closer than a relative tolerance
    tol = 1e-9 * length
    keep = np.concatenate([[True], np.diff(pts) > tol])
    pts = pts[keep]
    pts[-1] = length
    xs = [pts[:1]]
    for a, b in zip(pts[:-1], pts[1:]):
        k = max(1, int(round((b - a) / length * n_elements)))
        xs.append(a + (b - a) * np.arange(1, k + 1) / k)
    return np.concatenate(xs)


def _as_float(value) -> float:
    """float(value), or nan when it is not a number (so range checks fail cleanly)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return float("nan")


def _clamp_springs(clamp_stiffness, clamp_translational_stiffness) -> dict[int, float] | None:
    if clamp_stiffness is None and clamp_translational_stiffness is None:
        return None
    out: dict[int, float] = {}
    if isinstance(clamp_stiffness, Mapping):
        for key, v in clamp_stiffness.items():
            if key not in DOF_NAMES:
                raise ParameterError(
                    f"clamp_stiffness: unknown component {key!r}; expected one of {DOF_NAMES}"
                )
            out[DOF_NAMES.index(key)] = v
    elif clamp_stiffness is not None:
        out[DOF_NAMES.index("ry")] = clamp_stiffness
    if clamp_translational_stiffness is not None:
        out[DOF_NAMES.index("uz")] = clamp_translational_stiffness
    for c, v in out.items():
        v = _as_float(v)
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(
                f"clamp stiffness of {DOF_NAMES[c]!r} must be a positive stiffness "
                f"(N/m or N m/rad), got {out[c]!r}"
            )
        out[c] = v
    return out


def _point_x(key: str, value) -> float:
    """x of a named point given as x or (x, y[, z]) (y, z ignored for a beam)."""
    try:
        v = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError):
        v = np.zeros((0, 0))
    if v.ndim != 1 or not 1 <= v.size <= 3:
        raise ParameterError(
            f"point {key!r}: expected x or (x, y[, z]) in m, got {value!r}"
        )
    return float(v[0])


def cantilever_beam(
    length: float,
    width: float,
    layers: Sequence[Ply],
    n_elements: int = 20,
    patches: Sequence[BeamPatch | Mapping] = (),
    clamp: str | None = "x0",
    clamp_stiffness: float | Mapping[str, float] | None = None,
    clamp_translational_stiffness: float | None = None,
    points: Mapping[str, float] | None = None,
    shear_correction: float = SHEAR_CORRECTION,
    name: str = "",
    meta: Mapping | None = None,
) -> FEModel:
    """Layered Timoshenko beam along x, width along y, thickness along z.

    Parameters
    ----------
    length : float
        Beam length, m.
    width : float
        Width of the base stack (and of patches that do not give their own), m.
    layers : sequence of Ply
        Base stack, bottom to top.
    n_elements : int
        Target number of elements; each interval between mesh break points (ends,
        patch edges, named points) gets ``max(1, round(interval / length * n_elements))``
        elements, so the count is exact when there are no break points inside.
    patches : sequence of BeamPatch (or mappings with its fields)
        Segments with extra layers. Overlapping patches stack in the order given.
    clamp : {"x0", "x1", None}
        Clamped end; ``None`` (or ``"free"``) gives a free-free beam (6 rigid-body modes).
    clamp_stiffness : float or mapping, optional
        ``None`` (and no ``clamp_translational_stiffness``): the clamp node's six DOFs
        are removed (rigid clamp). A float ``k`` (N m/rad): the bending rotation ``ry``
        of the clamp node is held by a spring ``k``, its other DOFs stay fixed (the
        same meaning as the plate's ``clamp_stiffness``, but a total, not per metre of
        edge). A mapping ``{"ry": k, "uz": k2, ...}``: each listed component gets a
        spring (N/m or N m/rad), the others stay fixed.
    clamp_translational_stiffness : float, optional
        Spring on ``uz`` of the clamp node, N/m (total).
    points : mapping of str to float or (x, y[, z]), optional
        Named positions along the beam (m; y and z ignored); each becomes a mesh node and
        a node set of that name (as in :func:`mvtk.fe.plate_model`). A name may equal a
        built-in set (``"tip"``) only if it designates the same node.
    shear_correction : float
        Shear correction factor of every section (default 5/6).
    name : str
        Model name.
    meta : mapping, optional
        Extra entries merged into ``FEModel.meta``.

    Returns
    -------
    FEModel
        Nodes on the line ``y = z = 0`` (the beam axis, i.e. the neutral axis of each
        segment). ``node_sets``: ``"clamp"`` (absent when free-free), ``"x0"``, ``"x1"``,
        ``"tip"`` (the end opposite the clamp, ``"x1"`` when free-free),
        ``patch:<name>:x0``, ``patch:<name>:x1``, ``patch:<name>`` (every node of the
        patch), one set per named point, ``"all"``.
        ``elements["beam2"]`` is the (n_el, 2) connectivity. ``meta`` holds
        ``"kind"``, ``"length"``, ``"width"``, ``"sections"`` (list of
        :meth:`BeamSection.as_dict`), ``"section_layers"`` and ``"section_layer_widths"``
        (the ply stack and layer widths of each section, bottom to top),
        ``"element_section"`` (section index per element),
        ``"clamp"``, ``"clamp_stiffness"`` and ``"patches"``.

    Raises
    ------
    ParameterError
        For non-positive sizes, a patch or point outside the beam, duplicate names, or
        an unknown clamp.

    Notes
    -----
    Beam theory uses the uniaxial modulus and Saint-Venant torsion: for wide strips
    (width comparable to length) a plate model is stiffer (plate modulus, warping
    restraint at the clamp). For the nominal smart beam of ``data/structures`` (180 x
    133 mm) the beam gives 13.95 / 35.4 Hz (bending / torsion) where the MITC4 plate
    gives 14.25 / 42.2 Hz; for a 200 x 20 mm strip with nu = 0 they agree to 1e-4.

    A clamped beam has a non-singular K: for large models solve the eigenproblem with
    ``mvtk.fe.eigsh_lowest(model.K, model.M, n, sigma=0.0)``. (The default negative
    shift of ``eigsh_lowest`` grows like 1/h^2 with the element size h and makes fine
    beam meshes slow to converge.)

    Examples
    --------
    A steel strip 300 x 20 x 2 mm clamped at x = 0, 20 Timoshenko elements (6 DOFs per
    node, the clamped node removed):

    >>> from mvtk.fe import IsotropicMaterial, Ply
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> beam.n_nodes, beam.n_dof, sorted(beam.node_sets)
    (21, 120, ['all', 'clamp', 'tip', 'x0', 'x1'])
    """
    L = _as_float(length)
    if not (np.isfinite(L) and L > 0):
        raise ParameterError(
            f"cantilever_beam: length must be a positive length in m, got {length!r}"
        )
    if not (np.isfinite(_as_float(width)) and _as_float(width) > 0):
        raise ParameterError(
            f"cantilever_beam: width must be a positive length in m, got {width!r}"
        )
    if (isinstance(n_elements, bool) or not np.isfinite(_as_float(n_elements))
            or int(n_elements) != n_elements or n_elements < 1):
        raise ParameterError(
            f"cantilever_beam: n_elements must be an integer >= 1, got {n_elements!r}"
        )
    if clamp == "free":
        clamp = None
    if clamp not in ("x0", "x1", None):
        raise ParameterError(f"cantilever_beam: clamp must be 'x0', 'x1' or None, got {clamp!r}")
    base = _check_layers(layers, "cantilever_beam")
    patches = [_as_patch(p) for p in patches]
    names = [p.name for p in patches]
    if len(set(names)) != len(names):
        raise ParameterError(f"cantilever_beam: duplicate patch names in {names}")
    for p in patches:
        if p.x0 < 0 or p.x1 > L * (1 + 1e-12):
            raise ParameterError(
                f"patch {p.name!r} spans x = {p.x0}..{p.x1} m, outside the beam 0..{L} m"
            )
    points = {str(k): _point_x(str(k), v) for k, v in (points or {}).items()}
    for key, x in points.items():
        if not (np.isfinite(x) and 0 <= x <= L * (1 + 1e-12)):
            raise ParameterError(f"point {key!r} at x = {x!r} m is outside the beam 0..{L} m")
    springs = _clamp_springs(clamp_stiffness, clamp_translational_stiffness)
    if springs is not None and clamp is None:
        raise ParameterError(
            "cantilever_beam: clamp_stiffness given but clamp is None (free-free)"
        )

    breaks = np.array([p.x0 for p in patches] + [p.x1 for p in patches]
                      + list(points.values()), dtype=float)
    x = _mesh_x(L, int(n_elements), breaks)
    nn = len(x)
    nodes = np.column_stack([x, np.zeros(nn), np.zeros(nn)])
    conn = np.column_stack([np.arange(nn - 1), np.arange(1, nn)])
    xm = 0.5 * (x[:-1] + x[1:])

    # section of every element: the base stack plus every patch covering its midpoint
    cover = np.array([(p.x0 < xm) & (xm < p.x1) for p in patches], dtype=bool).reshape(
        len(patches), len(xm)).T
    keys, el_sec = np.unique(cover, axis=0, return_inverse=True)
    el_sec = el_sec.ravel().astype(np.int64)
    sections: list[BeamSection] = []
    stacks: list[tuple[tuple[Ply, ...], tuple[float, ...]]] = []
    for key in keys:
        stack, widths = list(base), [float(width)] * len(base)
        for i in np.flatnonzero(key):
            p = patches[i]
            pw = [float(width if p.width is None else p.width)] * len(p.layers)
            if p.side == "top":
                stack, widths = stack + list(p.layers), widths + pw
            else:
                stack, widths = list(p.layers) + stack, pw + widths
        stacks.append((tuple(stack), tuple(widths)))
        sections.append(beam_section(stack, width, shear_correction, layer_widths=widths))
    props = _section_array(sections)[el_sec]
    ke, me = _global_matrices(nodes[conn[:, 0]], nodes[conn[:, 1]], props, (0.0, 1.0, 0.0))
    edof = (conn[:, :, None] * 6 + np.arange(6)[None, None, :]).reshape(len(conn), 12)
    rows = np.repeat(edof, 12, axis=1).ravel()
    cols = np.tile(edof, (1, 12)).ravel()
    n_all = 6 * nn
    K = sp.coo_matrix((ke.ravel(), (rows, cols)), shape=(n_all, n_all)).tocsr()
    M = sp.coo_matrix((me.ravel(), (rows, cols)), shape=(n_all, n_all)).tocsr()

    def nearest(xv: float) -> int:
        return int(np.argmin(np.abs(x - xv)))

    node_sets: dict[str, np.ndarray] = {
        "x0": np.array([0]), "x1": np.array([nn - 1]), "all": np.arange(nn),
    }
    fixed = np.zeros(n_all, dtype=bool)
    if clamp is not None:
        cn = 0 if clamp == "x0" else nn - 1
        node_sets["clamp"] = np.array([cn])
        node_sets["tip"] = np.array([nn - 1 - cn])
        if springs is None:
            fixed[cn * 6:cn * 6 + 6] = True
        else:
            add = np.zeros(n_all)
            for c in range(6):
                if c in springs:
                    add[cn * 6 + c] = springs[c]
                else:
                    fixed[cn * 6 + c] = True
            K = K + sp.diags(add, format="csr")
    else:
        node_sets["tip"] = np.array([nn - 1])
    for p in patches:
        i0, i1 = nearest(p.x0), nearest(p.x1)
        node_sets[f"patch:{p.name}:x0"] = np.array([i0])
        node_sets[f"patch:{p.name}:x1"] = np.array([i1])
        node_sets[f"patch:{p.name}"] = np.arange(i0, i1 + 1)
    for key, xv in points.items():
        node = np.array([nearest(xv)])
        if key in node_sets and not np.array_equal(node_sets[key], node):
            raise ParameterError(
                f"point {key!r} at x = {xv} m clashes with the built-in node set {key!r} "
                f"(node {int(node_sets[key][0])}); choose another name"
            )
        node_sets[key] = node

    free = np.flatnonzero(~fixed)
    K = K[free][:, free]
    M = M[free][:, free]
    K = ((K + K.T) * 0.5).tocsr()
    M = ((M + M.T) * 0.5).tocsr()
    info = {
        "kind": "timoshenko_beam",
        "length": L,
        "width": float(width),
        "sections": [s.as_dict() for s in sections],
        "section_layers": [st for st, _ in stacks],
        "section_layer_widths": [w for _, w in stacks],
        "element_section": el_sec,
        "clamp": clamp,
        "clamp_stiffness": (
            None if springs is None else {DOF_NAMES[c]: v for c, v in springs.items()}
        ),
        "patches": [
            {"name": p.name, "x0": float(p.x0), "x1": float(p.x1), "side": p.side,
             "width": float(width if p.width is None else p.width),
             "layers": [(q.material.name, float(q.thickness), float(q.angle_deg))
                        for q in p.layers]}
            for p in patches
        ],
        "base_layers": [(q.material.name, float(q.thickness), float(q.angle_deg)) for q in base],
        "shear_correction": float(shear_correction),
        "points": points,
    }
    info.update(meta or {})
    return FEModel(
        nodes=nodes, M=M, K=K, dof_node=free // 6, dof_component=free % 6,
        node_sets=node_sets, elements={"beam2": conn}, name=name or "cantilever_beam", meta=info,
    )
