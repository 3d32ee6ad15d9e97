"""Materials and plies: the shared vocabulary of sections, shells, beams and piezo patches.

All values in SI: Pa, kg/m^3, m, C/N = m/V (d31, d32), F/m (permittivity).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["IsotropicMaterial", "OrthotropicMaterial", "PiezoMaterial",
           "OrthotropicPiezoMaterial", "is_piezo", "Ply"]


def _positive(name: str, **values: float) -> None:
    for key, v in values.items():
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(f"material {name!r}: {key} must be a positive number, got {v!r}")


@dataclass(frozen=True)
class OrthotropicMaterial:
    """Orthotropic (transversely isotropic or general) ply material in its own axes.

    Parameters
    ----------
    name : str
    E1, E2 : float
        Young's moduli along and across the fibre (Pa).
    G12, G13, G23 : float
        Shear moduli (Pa); G13, G23 are the transverse shear moduli.
    nu12 : float
        Major Poisson ratio (nu21 = nu12 E2 / E1).
    rho : float
        Density (kg/m^3).

    Examples
    --------
    A unidirectional carbon/epoxy ply; the minor Poisson ratio is ``nu12 E2 / E1``:

    >>> cfrp = OrthotropicMaterial("T300/5208", E1=181e9, E2=10.3e9, G12=7.17e9,
    ...                            G13=7.17e9, G23=3.4e9, nu12=0.28, rho=1600.0)
    >>> round(cfrp.nu21, 5)
    0.01593
    """

    name: str
    E1: float
    E2: float
    G12: float
    G13: float
    G23: float
    nu12: float
    rho: float

    def __post_init__(self) -> None:
        _positive(self.name, E1=self.E1, E2=self.E2, G12=self.G12, G13=self.G13,
                  G23=self.G23, rho=self.rho)
        if not (-1.0 < self.nu12 < np.sqrt(self.E1 / self.E2)):
            raise ParameterError(
                f"material {self.name!r}: nu12 = {self.nu12} violates positive definiteness "
                f"(-1 < nu12 < sqrt(E1/E2) = {np.sqrt(self.E1 / self.E2):.4g})"
            )

    @property
    def nu21(self) -> float:
        return self.nu12 * self.E2 / self.E1

    def plane_stress_q(self) -> np.ndarray:
        """Reduced in-plane stiffness Q (3x3, Pa) in material axes (Voigt: 11, 22, 12)."""
        d = 1.0 - self.nu12 * self.nu21
        return np.array([
            [self.E1 / d, self.nu12 * self.E2 / d, 0.0],
            [self.nu12 * self.E2 / d, self.E2 / d, 0.0],
            [0.0, 0.0, self.G12],
        ])

    def transverse_shear_q(self) -> np.ndarray:
        """Transverse shear stiffness (2x2, Pa) in material axes (order 23, 13)."""
        return np.diag([self.G23, self.G13])


@dataclass(frozen=True)
class IsotropicMaterial(OrthotropicMaterial):
    """Isotropic material from E (Pa), nu and rho (kg/m^3).

    Examples
    --------
    Steel in SI units (Pa, -, kg/m^3); the shear modulus is ``E / (2 (1 + nu))``:

    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> round(steel.G / 1e9, 3)       # GPa
    80.769
    """

    def __init__(self, name: str, E: float, nu: float, rho: float):
        if not (-1.0 < nu < 0.5):
            raise ParameterError(f"material {name!r}: Poisson ratio must be in (-1, 0.5), got {nu}")
        G = E / (2.0 * (1.0 + nu))
        super().__init__(name=name, E1=E, E2=E, G12=G, G13=G, G23=G, nu12=nu, rho=rho)

    @property
    def E(self) -> float:
        return self.E1

    @property
    def nu(self) -> float:
        return self.nu12

    @property
    def G(self) -> float:
        return self.G12


def _piezo_constants(name: str, d31: float, d32: float | None, eps33: float | None
                     ) -> tuple[float, float, float | None]:
    d31 = float(d31)
    d32 = d31 if d32 is None else float(d32)
    for key, v in (("d31", d31), ("d32", d32)):
        if not np.isfinite(v):
            raise ParameterError(f"material {name!r}: {key} must be a finite number (m/V), "
                                 f"got {v!r}")
    if d31 == 0.0 and d32 == 0.0:
        raise ParameterError(f"material {name!r}: d31 and d32 are both zero; a piezo "
                             "material needs a non-zero d31 (m/V)")
    if eps33 is not None:
        eps33 = float(eps33)
        _positive(name, eps33=eps33)
    return d31, d32, eps33


@dataclass(frozen=True)
class PiezoMaterial(IsotropicMaterial):
    """Piezoceramic layer: isotropic elastic solid poled through its thickness.

    Parameters
    ----------
    name, E, nu, rho : see :class:`IsotropicMaterial` (E = 1/s11^E, Pa, at constant
        electric field, i.e. short circuit)
    d31 : float
        Piezoelectric charge constant (m/V = C/N), negative for PZT: in-plane strain
        along material axis 1 per unit electric field along the poling direction.
    d32 : float, optional
        The same along material axis 2 (m/V); default ``d31`` (a poled ceramic is
        transversely isotropic about its poling axis).
    eps33 : float, optional
        Permittivity at constant stress ``eps33^T`` (F/m), needed for the capacitance
        and every electrical condition other than a driven voltage. Default: unknown.

    Examples
    --------
    PIC 151-like ceramic: E = 67 GPa (short circuit), d31 = -210 pm/V, eps33 = 21 nF/m:

    >>> pzt = PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10, eps33=2.1e-8)
    >>> pzt.d32 == pzt.d31, is_piezo(pzt)
    (True, True)
    """

    d31: float = 0.0
    d32: float = 0.0
    eps33: float | None = None

    def __init__(self, name: str, E: float, nu: float, rho: float, d31: float,
                 d32: float | None = None, eps33: float | None = None):
        super().__init__(name, E, nu, rho)
        d31, d32, eps33 = _piezo_constants(name, d31, d32, eps33)
        object.__setattr__(self, "d31", d31)
        object.__setattr__(self, "d32", d32)
        object.__setattr__(self, "eps33", eps33)


@dataclass(frozen=True)
class OrthotropicPiezoMaterial(OrthotropicMaterial):
    """Orthotropic piezo ply poled through its thickness (e.g. a d31 macro-fibre composite).

    Parameters
    ----------
    name, E1, E2, G12, G13, G23, nu12, rho : see :class:`OrthotropicMaterial` (at
        constant electric field)
    d31, d32 : float
        In-plane strains along material axes 1 and 2 per unit field along the poling
        direction (m/V).
    eps33 : float, optional
        Permittivity at constant stress (F/m).

    Examples
    --------
    A d31-type macro-fibre composite (elastic constants in Pa, d31/d32 in m/V):

    >>> mfc = OrthotropicPiezoMaterial("MFC", E1=30.336e9, E2=15.857e9, G12=5.515e9,
    ...                                G13=5.515e9, G23=5.515e9, nu12=0.31, rho=5440.0,
    ...                                d31=-1.7e-10, d32=1.3e-10)
    >>> is_piezo(mfc), round(mfc.nu21, 4)
    (True, 0.162)
    """

    d31: float = 0.0
    d32: float = 0.0
    eps33: float | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        d31, d32, eps33 = _piezo_constants(self.name, self.d31, self.d32, self.eps33)
        object.__setattr__(self, "d31", d31)
        object.__setattr__(self, "d32", d32)
        object.__setattr__(self, "eps33", eps33)


def is_piezo(material) -> bool:
    """True for a material poled through the thickness (with d31/d32).

    Examples
    --------
    >>> is_piezo(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0))
    False
    >>> is_piezo(PiezoMaterial("PIC151", 6.7e10, 0.34, 7800.0, d31=-2.1e-10))
    True
    """
    return isinstance(material, PiezoMaterial | OrthotropicPiezoMaterial)


@dataclass(frozen=True)
class Ply:
    """One layer of a laminate.

    Parameters
    ----------
    material : OrthotropicMaterial
    thickness : float
        Ply thickness (m).
    angle_deg : float
        Orientation of material axis 1 from the element/global x axis (degrees).

    Examples
    --------
    A 0.125 mm ply of steel at 45 degrees:

    >>> ply = Ply(IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0), 1.25e-4, angle_deg=45.0)
    >>> ply.thickness, ply.angle_deg
    (0.000125, 45.0)
    """

    material: OrthotropicMaterial
    thickness: float
    angle_deg: float = 0.0

    def __post_init__(self) -> None:
        _positive(self.material.name, thickness=self.thickness)
