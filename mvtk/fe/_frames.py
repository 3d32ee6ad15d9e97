"""Coordinate systems: rectangular, cylindrical and spherical.

A :class:`CoordinateSystem` has an origin and three orthonormal axes (rows, global
components). Its coordinates are ``(x, y, z)``, ``(r, theta, z)`` (cylindrical, theta in
degrees from the x axis about z) or ``(r, theta, phi)`` (spherical, theta in degrees from
the z axis, phi about z from the x axis), as Nastran's CORD2R/C/S. At a point its
*local axes* (:meth:`CoordinateSystem.axes_at`) are the system's axes (rectangular),
``(e_r, e_theta, e_z)`` (cylindrical) or ``(e_r, e_theta, e_phi)`` (spherical): node
displacement frames built from them give skewed, radial or tangential supports.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ParameterError

__all__ = ["CoordinateSystem"]

_KINDS = {"R": "rectangular", "C": "cylindrical", "S": "spherical"}


@dataclass(frozen=True, eq=False)
class CoordinateSystem:
    """A rectangular (``"R"``), cylindrical (``"C"``) or spherical (``"S"``) system.

    Parameters
    ----------
    kind : {"R", "C", "S"}
        Also accepted: ``"rectangular"``, ``"cylindrical"``, ``"spherical"``.
    origin : (3,) float
        Global coordinates (m).
    axes : (3, 3) float
        Rows: the unit x, y, z axes in global components (orthonormal, right-handed).

    Examples
    --------
    A cylindrical system about global z: the point (r = 1 m, theta = 90 deg, z = 0.5 m)
    is (0, 1, 0.5) in global coordinates:

    >>> cyl = CoordinateSystem("C", np.zeros(3), np.eye(3))
    >>> np.round(cyl.to_global([1.0, 90.0, 0.5]), 6) + 0.0
    array([0. , 1. , 0.5])
    """

    kind: str
    origin: np.ndarray
    axes: np.ndarray

    def __post_init__(self) -> None:
        kind = {v: k for k, v in _KINDS.items()}.get(str(self.kind).lower(), self.kind)
        if kind not in _KINDS:
            raise ParameterError(f"coordinate system type must be one of "
                                 f"{sorted(_KINDS.values())}, got {self.kind!r}")
        o = np.asarray(self.origin, dtype=float)
        R = np.asarray(self.axes, dtype=float)
        if o.shape != (3,) or R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3),
                                                                    atol=1e-9) \
                or np.linalg.det(R) < 0:
            raise ParameterError("coordinate system: origin must be 3 numbers and axes a "
                                 "right-handed orthonormal (3, 3) matrix")
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "origin", o)
        object.__setattr__(self, "axes", R)

    @classmethod
    def from_points(cls, kind: str, a, b, c) -> CoordinateSystem:
        """Nastran CORD2 definition: origin ``a``, ``b`` on the z axis, ``c`` in the x-z
        plane (all global).

        Raises
        ------
        ParameterError
            If the points are collinear.
        """
        a, b, c = (np.asarray(p, dtype=float) for p in (a, b, c))
        ez = b - a
        ey = np.cross(ez, c - a)
        if np.linalg.norm(ez) == 0 or np.linalg.norm(ey) == 0:
            raise ParameterError("coordinate system: points A, B, C are collinear")
        ez = ez / np.linalg.norm(ez)
        ey = ey / np.linalg.norm(ey)
        return cls(kind, a, np.stack([np.cross(ey, ez), ey, ez]))

    def local_xyz(self, x) -> np.ndarray:
        """Rectangular local coordinates of system coordinates x."""
        x = np.asarray(x, dtype=float)
        if self.kind == "R":
            return x
        if self.kind == "C":
            t = np.radians(x[1])
            return np.array([x[0] * np.cos(t), x[0] * np.sin(t), x[2]])
        t, p = np.radians(x[1]), np.radians(x[2])
        return x[0] * np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])

    def to_global(self, x) -> np.ndarray:
        """Global coordinates (m) of a point given in this system's coordinates."""
        return self.origin + self.axes.T @ self.local_xyz(x)

    def axes_at(self, p) -> np.ndarray:
        """Unit local axes (rows, global components) at the global point ``p``.

        On the axis of a cylindrical system (or the pole of a spherical one) the angle
        is taken as 0.
        """
        if self.kind == "R":
            return self.axes
        q = self.axes @ (np.asarray(p, dtype=float) - self.origin)
        t = np.arctan2(q[1], q[0])
        if self.kind == "C":
            loc = np.array([[np.cos(t), np.sin(t), 0.0], [-np.sin(t), np.cos(t), 0.0],
                            [0.0, 0.0, 1.0]])
        else:
            th = np.arctan2(np.hypot(q[0], q[1]), q[2])
            loc = np.array([
                [np.sin(th) * np.cos(t), np.sin(th) * np.sin(t), np.cos(th)],
                [np.cos(th) * np.cos(t), np.cos(th) * np.sin(t), -np.sin(th)],
                [-np.sin(t), np.cos(t), 0.0]])
        return loc @ self.axes
