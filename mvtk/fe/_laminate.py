"""Laminate (layered section) stiffness and inertia for first-order shear deformation.

Classical lamination theory with first-order shear deformation (FSDT, Mindlin-Reissner).
The in-plane displacements through the thickness are ``u(z) = u0 + z beta_x`` and
``v(z) = v0 + z beta_y``, with ``z`` measured from the *reference surface* (the surface on
which the shell nodes lie). The section resultants are::

    [N]   [A  B] [eps0 ]        Q = H gamma
    [M] = [B  D] [kappa]

with ``A = sum Qbar_k (z_k+1 - z_k)``, ``B = 1/2 sum Qbar_k (z_k+1^2 - z_k^2)``,
``D = 1/3 sum Qbar_k (z_k+1^3 - z_k^3)`` and the transverse shear stiffness
``H = k_s sum Qs_bar_k (z_k+1 - z_k)``.

Shear correction: ``k_s = 5/6`` (Reissner/Mindlin value, exact in energy for a
homogeneous section) is applied to the integrated transverse shear stiffness of every
stack, homogeneous or layered. For layered stacks this is the usual engineering
simplification; an equilibrium-based per-laminate factor (Whitney 1973; Vlachoutsis 1992)
changes H by a few percent, which matters for thick or strongly heterogeneous stacks
only (for thin plates the shear energy of the low modes is negligible). Pass
``shear_correction`` to use another value.

Inertia per unit area: ``I0 = sum rho_k dz``, ``I1 = sum rho_k d(z^2)/2``,
``I2 = sum rho_k d(z^3)/3`` (kg/m^2, kg/m, kg).

References
----------
J. N. Reddy, *Mechanics of Laminated Composite Plates and Shells*, 2nd ed., CRC 2004,
chapters 3 and 6.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from ._materials import Ply

__all__ = ["Laminate"]


def _rotation_in_plane(theta_deg: float) -> np.ndarray:
    """Transformation of a ply's plane-stress Q to laminate axes: Qbar = T' Q T.

    T maps laminate engineering strains (xx, yy, xy) to ply-axis engineering strains.
    """
    t = np.deg2rad(theta_deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([
        [c * c, s * s, c * s],
        [s * s, c * c, -c * s],
        [-2 * c * s, 2 * c * s, c * c - s * s],
    ])


def _rotation_shear(theta_deg: float) -> np.ndarray:
    """Map of laminate transverse shear strains (yz, xz) to ply axes (23, 13)."""
    t = np.deg2rad(theta_deg)
    c, s = np.cos(t), np.sin(t)
    return np.array([[c, -s], [s, c]])


@dataclass(frozen=True)
class Laminate:
    """A stack of plies with its FSDT section stiffness and inertia.

    Parameters
    ----------
    plies : sequence of Ply
        Plies from the bottom (most negative z) to the top.
    z_bottom : float, optional
        z coordinate (m) of the bottom face of the stack relative to the reference
        surface. Default: ``-h/2`` (reference surface = mid-plane of the stack). For a
        patch bonded on a base plate use the base plate's ``-h_base/2`` so that all
        sections share the base mid-plane as reference surface.
    shear_correction : float
        Shear correction factor ``k_s`` applied to the integrated transverse shear
        stiffness (default 5/6, see the module notes).

    Attributes
    ----------
    A : ndarray (3, 3)
        Membrane stiffness (Pa m), Voigt order xx, yy, xy (engineering shear).
    B : ndarray (3, 3)
        Membrane-bending coupling (Pa m^2).
    D : ndarray (3, 3)
        Bending stiffness (Pa m^3).
    H : ndarray (2, 2)
        Transverse shear stiffness (Pa m), order (xz, yz), including ``k_s``.
    I0, I1, I2 : float
        Mass per area (kg/m^2), first (kg/m) and second (kg) mass moments about the
        reference surface.
    thickness : float
        Total thickness (m).

    Examples
    --------
    A single 2 mm steel ply: bending stiffness ``D = E h**3 / (12 (1 - nu**2))`` and
    mass per area ``I0 = rho h``:

    >>> from mvtk.fe import IsotropicMaterial, Ply
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> lam = Laminate((Ply(steel, 2e-3),))
    >>> round(float(lam.D[0, 0]), 3), round(2.1e11 * 2e-3**3 / (12 * (1 - 0.3**2)), 3)   # N m
    (153.846, 153.846)
    >>> lam.thickness, round(lam.I0, 3)                                         # m, kg/m^2
    (0.002, 15.7)
    """

    plies: tuple[Ply, ...]
    z_bottom: float | None = None
    shear_correction: float = 5.0 / 6.0
    A: np.ndarray = field(init=False, repr=False)
    B: np.ndarray = field(init=False, repr=False)
    D: np.ndarray = field(init=False, repr=False)
    H: np.ndarray = field(init=False, repr=False)
    I0: float = field(init=False, repr=False)
    I1: float = field(init=False, repr=False)
    I2: float = field(init=False, repr=False)
    thickness: float = field(init=False, repr=False)

    def __post_init__(self) -> None:
        plies = tuple(self.plies)
        if not plies:
            raise ParameterError("a laminate needs at least one ply, got an empty list")
        for i, p in enumerate(plies):
            if not isinstance(p, Ply):
                raise ParameterError(f"laminate ply {i} must be a Ply, got {type(p).__name__}")
        if not (np.isfinite(self.shear_correction) and self.shear_correction > 0):
            raise ParameterError(
                f"shear_correction must be a positive number, got {self.shear_correction!r}"
            )
        h = float(sum(p.thickness for p in plies))
        zb = -h / 2 if self.z_bottom is None else float(self.z_bottom)
        if not np.isfinite(zb):
            raise ParameterError(f"z_bottom must be finite, got {self.z_bottom!r}")
        A = np.zeros((3, 3))
        B = np.zeros((3, 3))
        D = np.zeros((3, 3))
        H = np.zeros((2, 2))
        I0 = I1 = I2 = 0.0
        z0 = zb
        for p in plies:
            z1 = z0 + p.thickness
            T = _rotation_in_plane(p.angle_deg)
            Qb = T.T @ p.material.plane_stress_q() @ T
            Ts = _rotation_shear(p.angle_deg)
            # material order (23, 13) -> laminate (yz, xz); reorder to (xz, yz)
            Qs = Ts.T @ p.material.transverse_shear_q() @ Ts
            Qs = Qs[::-1, ::-1]
            A += Qb * (z1 - z0)
            B += Qb * (z1**2 - z0**2) / 2
            D += Qb * (z1**3 - z0**3) / 3
            H += Qs * (z1 - z0)
            rho = p.material.rho
            I0 += rho * (z1 - z0)
            I1 += rho * (z1**2 - z0**2) / 2
            I2 += rho * (z1**3 - z0**3) / 3
            z0 = z1
        H *= self.shear_correction
        for name, value in (("plies", plies), ("z_bottom", zb), ("A", A), ("B", B),
                            ("D", D), ("H", H), ("I0", I0), ("I1", I1), ("I2", I2),
                            ("thickness", h)):
            object.__setattr__(self, name, value)

    @property
    def ABD(self) -> np.ndarray:
        """The 6x6 matrix ``[[A, B], [B, D]]`` (mixed units)."""
        return np.block([[self.A, self.B], [self.B, self.D]])

    @property
    def z_interfaces(self) -> np.ndarray:
        """z coordinates (m) of the ply interfaces, bottom to top (n_plies + 1)."""
        return self.z_bottom + np.concatenate([[0.0], np.cumsum([p.thickness
                                                                   for p in self.plies])])

    @classmethod
    def from_plies(cls, plies: Sequence[Ply], z_bottom: float | None = None,
                   shear_correction: float = 5.0 / 6.0) -> Laminate:
        """Same as the constructor; accepts any sequence of plies."""
        return cls(tuple(plies), z_bottom=z_bottom, shear_correction=shear_correction)
