"""Standard homogeneous beam sections (rectangle, tube, I, box, generic) as BeamSection.

Local section axes follow :mod:`mvtk.fe._beam`: the beam axis is x, the section's
``width`` runs along local y (the orientation vector) and its ``height`` along local z.
``EIy`` is bending about local y (deflection along z), ``EIz`` about local z.

Formulas (homogeneous, linear elastic, shear centre = centroid, warping neglected):

- rectangle ``b x h``: ``A = b h``, ``Iy = b h^3/12``, ``Iz = h b^3/12``, ``J`` the
  Saint-Venant series of a rectangle (Timoshenko & Goodier 1970, section 109), Cowper's
  (1966) shear factor ``k = 10 (1 + nu) / (12 + 11 nu)`` by default (0.850 for
  nu = 0.3; 5/6 is its nu = 0 value);
- tube (outer radius ``r_o``, inner ``r_i``): ``A = pi (r_o^2 - r_i^2)``,
  ``I = pi (r_o^4 - r_i^4)/4``, ``J = 2 I``, Cowper's (1966) shear factor
  ``k = 6 (1 + nu)(1 + m^2)^2 / ((7 + 6 nu)(1 + m^2)^2 + (20 + 12 nu) m^2)``,
  ``m = r_i/r_o``;
- I (height ``h``, flange width ``b``, flange thickness ``tf``, web thickness ``tw``):
  exact ``A, Iy, Iz`` of the three rectangles, thin-walled open-section
  ``J = (2 b tf^3 + (h - tf) tw^3)/3``, shear areas ``(h - tf) tw`` along z and
  ``5/6 * 2 b tf`` along y (Pilkey, *Formulas for Stress, Strain and Structural
  Matrices*, 2005, table 2-5); warping torsion is neglected;
- box (height ``h``, width ``b``, web thickness ``tw``, flange thickness ``tf``): exact
  ``A, Iy, Iz``, Bredt's closed-section ``J = 2 tw tf (b - tw)^2 (h - tf)^2 /
  (b tw + h tf - tw^2 - tf^2)``, shear areas ``2 (h - tf) tw`` (z) and ``2 (b - tw) tf`` (y);
- generic: ``A, Iy, Iz, J`` given, shear factor given (default 5/6 of A).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ._beam import BeamSection, _rect_torsion_factor
from ._materials import OrthotropicMaterial

__all__ = ["rectangle_section", "tube_section", "i_section", "box_section",
           "generic_section"]


def _positive(where: str, **values: float) -> None:
    for k, v in values.items():
        if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)) \
                or not np.isfinite(v) or v <= 0:
            raise ParameterError(f"{where}: {k} must be a positive number (SI), got {v!r}")


def _moduli(material: OrthotropicMaterial, where: str) -> tuple[float, float, float]:
    if not isinstance(material, OrthotropicMaterial):
        raise ParameterError(f"{where}: material must be a mvtk.fe material, "
                             f"got {type(material).__name__}")
    E = float(material.E1)
    G = float(material.G12)
    return E, G, float(material.rho)


def _section(E, G, rho, A, Iy, Iz, J, Asz, Asy, width, height) -> BeamSection:
    return BeamSection(
        width=float(width), thickness=float(height), neutral_axis=float(height) / 2,
        EA=E * A, EIy=E * Iy, EIz=E * Iz, GJ=G * J, kGAz=G * Asz, kGAy=G * Asy,
        rhoA=rho * A, rhoIy=rho * Iy, rhoIz=rho * Iz, mass_offset=0.0,
    )


def rectangle_section(material: OrthotropicMaterial, width: float, height: float,
                      shear_correction: float | None = None) -> BeamSection:
    """Solid rectangle, ``width`` along local y and ``height`` along local z (m).

    ``shear_correction`` defaults to Cowper's ``10 (1 + nu) / (12 + 11 nu)`` (Cowper,
    J. Appl. Mech. 33 (1966) 335-340, table 1), ``nu = E / (2 G) - 1``.

    Examples
    --------
    Steel 20 x 2 mm; bending about the width axis ``E b h**3 / 12`` = 2.8 N m^2:

    >>> from mvtk.fe import IsotropicMaterial
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> round(rectangle_section(steel, width=0.02, height=0.002).EIy, 6)
    2.8
    """
    _positive("rectangle_section", width=width, height=height)
    E, G, rho = _moduli(material, "rectangle_section")
    if shear_correction is None:
        nu = E / (2 * G) - 1
        shear_correction = 10 * (1 + nu) / (12 + 11 * nu)
    _positive("rectangle_section", shear_correction=shear_correction)
    b, h = float(width), float(height)
    J = _rect_torsion_factor(max(b, h), min(b, h))
    A = b * h
    return _section(E, G, rho, A, b * h**3 / 12, h * b**3 / 12, J,
                    shear_correction * A, shear_correction * A, b, h)


def tube_section(material: OrthotropicMaterial, outer_radius: float,
                 inner_radius: float = 0.0) -> BeamSection:
    """Circular tube (or solid bar with ``inner_radius = 0``), radii in m.

    Examples
    --------
    Steel tube 20 mm outer, 16 mm inner diameter: ``EA = E pi (ro**2 - ri**2)``:

    >>> from mvtk.fe import IsotropicMaterial
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> s = tube_section(steel, outer_radius=0.01, inner_radius=0.008)
    >>> round(s.EA / 1e6, 3), round(2.1e11 * np.pi * (0.01**2 - 0.008**2) / 1e6, 3)   # MN
    (23.75, 23.75)
    """
    _positive("tube_section", outer_radius=outer_radius)
    ro, ri = float(outer_radius), float(inner_radius)
    if not (np.isfinite(ri) and 0 <= ri < ro):
        raise ParameterError(
            f"tube_section: inner_radius must be in [0, outer_radius={ro}), got {inner_radius!r}"
        )
    E, G, rho = _moduli(material, "tube_section")
    nu = E / (2 * G) - 1
    m = ri / ro
    k = 6 * (1 + nu) * (1 + m**2) ** 2 / ((7 + 6 * nu) * (1 + m**2) ** 2
                                         + (20 + 12 * nu) * m**2)
    A = np.pi * (ro**2 - ri**2)
    inertia = np.pi * (ro**4 - ri**4) / 4
    return _section(E, G, rho, A, inertia, inertia, 2 * inertia, k * A, k * A, 2 * ro, 2 * ro)


def i_section(material: OrthotropicMaterial, height: float, flange_width: float,
              flange_thickness: float, web_thickness: float) -> BeamSection:
    """Doubly symmetric I section, web along local z (m).

    Examples
    --------
    I beam 100 mm high, flanges 50 x 5 mm, web 3 mm: ``A = 2 b tf + (h - 2 tf) tw``:

    >>> from mvtk.fe import IsotropicMaterial
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> s = i_section(steel, height=0.1, flange_width=0.05, flange_thickness=0.005,
    ...               web_thickness=0.003)
    >>> round(s.EA / 2.1e11 * 1e6, 3)      # area, mm^2
    770.0
    """
    _positive("i_section", height=height, flange_width=flange_width,
              flange_thickness=flange_thickness, web_thickness=web_thickness)
    h, b, tf, tw = map(float, (height, flange_width, flange_thickness, web_thickness))
    if 2 * tf >= h or tw >= b:
        raise ParameterError(
            f"i_section: need 2 flange_thickness < height and web_thickness < flange_width, "
            f"got h={h}, b={b}, tf={tf}, tw={tw}"
        )
    E, G, rho = _moduli(material, "i_section")
    hw = h - 2 * tf
    A = 2 * b * tf + hw * tw
    Iy = b * h**3 / 12 - (b - tw) * hw**3 / 12
    Iz = 2 * tf * b**3 / 12 + hw * tw**3 / 12
    J = (2 * b * tf**3 + (h - tf) * tw**3) / 3
    return _section(E, G, rho, A, Iy, Iz, J, (h - tf) * tw, 5 / 6 * 2 * b * tf, b, h)


def box_section(material: OrthotropicMaterial, height: float, width: float,
                web_thickness: float, flange_thickness: float) -> BeamSection:
    """Rectangular hollow (box) section; webs along local z, flanges along local y (m).

    Examples
    --------
    Box 100 x 50 mm, webs 3 mm, flanges 4 mm: ``A = 2 b tf + 2 (h - 2 tf) tw``:

    >>> from mvtk.fe import IsotropicMaterial
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> s = box_section(steel, height=0.1, width=0.05, web_thickness=0.003,
    ...                 flange_thickness=0.004)
    >>> round(s.EA / 2.1e11 * 1e6, 3)      # area, mm^2
    952.0
    """
    _positive("box_section", height=height, width=width, web_thickness=web_thickness,
              flange_thickness=flange_thickness)
    h, b, tw, tf = map(float, (height, width, web_thickness, flange_thickness))
    if 2 * tf >= h or 2 * tw >= b:
        raise ParameterError(
            f"box_section: walls too thick for the outer size (h={h}, b={b}, tw={tw}, tf={tf})"
        )
    E, G, rho = _moduli(material, "box_section")
    hi, bi = h - 2 * tf, b - 2 * tw
    A = b * h - bi * hi
    Iy = (b * h**3 - bi * hi**3) / 12
    Iz = (h * b**3 - hi * bi**3) / 12
    J = 2 * tw * tf * (b - tw) ** 2 * (h - tf) ** 2 / (b * tw + h * tf - tw**2 - tf**2)
    return _section(E, G, rho, A, Iy, Iz, J, 2 * (h - tf) * tw, 2 * (b - tw) * tf, b, h)


def generic_section(material: OrthotropicMaterial, A: float, Iy: float, Iz: float, J: float,
                    shear_factor_y: float = 5.0 / 6.0,
                    shear_factor_z: float = 5.0 / 6.0) -> BeamSection:
    """Section from its area (m^2), second moments and torsion constant (m^4).

    ``width`` and ``thickness`` of the returned section are NaN (no shape is known).

    Examples
    --------
    From tabulated properties (m^2, m^4): ``EA``, ``EIy``, ``rho A`` follow directly:

    >>> from mvtk.fe import IsotropicMaterial
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> s = generic_section(steel, A=1e-4, Iy=2e-9, Iz=3e-9, J=1e-9)
    >>> round(s.EA / 1e6, 3), round(s.EIy, 3), round(s.rhoA, 4)
    (21.0, 420.0, 0.785)
    """
    _positive("generic_section", A=A, Iy=Iy, Iz=Iz, J=J, shear_factor_y=shear_factor_y,
              shear_factor_z=shear_factor_z)
    E, G, rho = _moduli(material, "generic_section")
    s = _section(E, G, rho, A, Iy, Iz, J, shear_factor_z * A, shear_factor_y * A, np.nan,
                 np.nan)
    return s
