"""Test geometry: nodes, coordinate systems, trace lines and sensor DOFs.

The layout follows ``docs/conventions.md`` (section *Test geometry*): a table of test
nodes (``node`` label, global ``x y z`` in m, ``cs`` = id of the node's displacement
coordinate system, 0 = global), coordinate systems as a rotation (columns = local axes in
global) plus an origin, trace lines as sequences of node labels, and sensor DOFs as
``(node, direction)`` pairs read in the node's system or as an explicit unit vector
(skewed sensors).

Readers: UFF datasets 15 / 2411 (nodes), 18 and 2420 (Cartesian, cylindrical and
spherical coordinate systems), 82 (trace lines), 2412 (elements, drawn as trace lines)
through pyuff (imported lazily), and a simple CSV or TOML table.
:meth:`TestGeometry.to_toml` writes the TOML form back.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from .._interrupt import deferred_interrupt
from ..errors import (
    ConfigError,
    DimensionError,
    FormatError,
    MissingDependencyError,
    ParameterError,
    UnsupportedFormatError,
)

__all__ = [
    "CoordinateSystem",
    "CS_KINDS",
    "Sensor",
    "TestGeometry",
    "DIRECTIONS",
    "read_test_geometry",
    "direction_label",
]

#: Direction names of the conventions (node system axes; translations then rotations).
DIRECTIONS: tuple[str, ...] = (
    "+x", "-x", "+y", "-y", "+z", "-z", "+rx", "-rx", "+ry", "-ry", "+rz", "-rz",
)
_AXIS = {"x": 0, "y": 1, "z": 2, "rx": 3, "ry": 4, "rz": 5}
#: UFF direction codes 1..6 / -1..-6.
_UFF_DIR = {1: "+x", 2: "+y", 3: "+z", 4: "+rx", 5: "+ry", 6: "+rz",
            -1: "-x", -2: "-y", -3: "-z", -4: "-rx", -5: "-ry", -6: "-rz"}


def direction_label(code: int | str) -> str:
    """Convention direction name of a UFF code (``3`` -> ``"+z"``) or a name (``"z"``).

    Examples
    --------
    UFF direction codes 1..6 are +x..+rz, negative codes the opposite directions:

    >>> direction_label(3), direction_label("z"), direction_label(-4)
    ('+z', '+z', '-rx')
    """
    if isinstance(code, str):
        s = code.strip().lower()
        if s and s[0] not in "+-":
            s = "+" + s
        if s in DIRECTIONS:
            return s
        raise ParameterError(f"unknown direction {code!r}; expected one of {DIRECTIONS}")
    try:
        return _UFF_DIR[int(code)]
    except (KeyError, ValueError, TypeError):
        raise ParameterError(
            f"unknown UFF direction code {code!r}; expected 1..6 or -1..-6"
        ) from None


#: Coordinate system kinds and their UFF type codes (datasets 18 and 2420).
CS_KINDS: tuple[str, ...] = ("cartesian", "cylindrical", "spherical")


@dataclass(frozen=True, eq=False)
class CoordinateSystem:
    """A Cartesian, cylindrical or spherical coordinate system.

    Parameters
    ----------
    id : int
        Label (0 is the global system and is always defined).
    rotation : ndarray (3, 3)
        Columns are the local x, y, z unit axes expressed in the global system (for a
        curvilinear system: the axes of its underlying Cartesian frame, ``z`` = the
        cylinder axis / the polar axis of the sphere).
    origin : ndarray (3,)
        Origin in global coordinates (m).
    name : str
    kind : {"cartesian", "cylindrical", "spherical"}
        How coordinates and displacement directions are read (UFF type 0, 1, 2):

        - cylindrical: coordinates ``(r, theta, z)`` with ``theta`` in degrees from the
          local x axis towards y; directions 1, 2, 3 are the radial, tangential
          (increasing ``theta``) and axial unit vectors *at the node*;
        - spherical: coordinates ``(r, theta, phi)`` with the polar angle ``theta``
          from the local z axis and the azimuth ``phi`` from x towards y, both in
          degrees; directions 1, 2, 3 are the unit vectors of increasing ``r``,
          ``theta`` and ``phi`` at the node (a right-handed triad, as NASTRAN CORD2S).

    Examples
    --------
    A cylindrical system about global z, origin 1 m up: (r = 1 m, theta = 90 deg,
    z = 0.5 m) is (0, 1, 1.5) m in global coordinates:

    >>> cyl = CoordinateSystem(1, np.eye(3), np.array([0.0, 0.0, 1.0]), kind="cylindrical")
    >>> np.round(cyl.to_global(np.array([1.0, 90.0, 0.5])), 6) + 0.0
    array([0. , 1. , 1.5])
    """

    id: int
    rotation: np.ndarray
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = ""
    kind: str = "cartesian"

    def __post_init__(self) -> None:
        R = np.asarray(self.rotation, dtype=float)
        o = np.asarray(self.origin, dtype=float).ravel()
        if R.shape != (3, 3):
            raise DimensionError(
                f"coordinate system {self.id}: rotation must be 3 x 3, got shape {R.shape}"
            )
        if o.shape != (3,):
            raise DimensionError(
                f"coordinate system {self.id}: origin must have 3 values, got {o.size}"
            )
        err = float(np.max(np.abs(R.T @ R - np.eye(3))))
        if err > 1e-6 or np.linalg.det(R) < 0:
            raise ParameterError(
                f"coordinate system {self.id}: rotation is not a proper orthonormal matrix "
                f"(|R'R - I| = {err:.2g}, det = {np.linalg.det(R):.3g}); expected the local "
                "axes as orthonormal right-handed columns"
            )
        if self.kind not in CS_KINDS:
            raise ParameterError(f"coordinate system {self.id}: unknown kind {self.kind!r}; "
                                 f"expected one of {CS_KINDS}")
        object.__setattr__(self, "id", int(self.id))
        object.__setattr__(self, "rotation", R)
        object.__setattr__(self, "origin", o)

    @classmethod
    def from_points(cls, id: int, origin, x_point, xz_point, name: str = "",
                    reference: CoordinateSystem | None = None,
                    kind: str = "cartesian") -> CoordinateSystem:
        """System from its origin, a point on +x and a point in the +xz plane (UFF 18).

        Points are given as coordinates of ``reference`` (default global; cylindrical
        or spherical coordinates when ``reference`` is such a system).
        """
        pts = [np.asarray(v, dtype=float).ravel() for v in (origin, x_point, xz_point)]
        if reference is not None:
            pts = [reference.to_global(v) for v in pts]
        o, px, pxz = pts
        ex = px - o
        v = pxz - o
        nx = np.linalg.norm(ex)
        ey = np.cross(v, ex)
        if nx == 0 or np.linalg.norm(ey) <= 1e-12 * nx * max(np.linalg.norm(v), 1e-300):
            raise ParameterError(
                f"coordinate system {id}: origin, +x point and +xz point are collinear or "
                "coincident; expected three points spanning a plane"
            )
        ex /= nx
        ey /= np.linalg.norm(ey)
        ez = np.cross(ex, ey)
        return cls(id, np.column_stack([ex, ey, ez]), o, name, kind)

    def local_cartesian(self, coords) -> np.ndarray:
        """Cartesian coordinates in the system's own frame of point(s) given in its
        coordinates (``(x, y, z)``, ``(r, theta, z)`` or ``(r, theta, phi)``; angles in
        degrees), shape (..., 3)."""
        c = np.asarray(coords, dtype=float)
        if self.kind == "cartesian":
            return c.copy()
        r = c[..., 0]
        t = np.deg2rad(c[..., 1])
        if self.kind == "cylindrical":
            return np.stack([r * np.cos(t), r * np.sin(t), c[..., 2]], axis=-1)
        f = np.deg2rad(c[..., 2])
        return np.stack([r * np.sin(t) * np.cos(f), r * np.sin(t) * np.sin(f),
                         r * np.cos(t)], axis=-1)

    def to_global(self, coords, scale: float = 1.0) -> np.ndarray:
        """Global coordinates (m) of point(s) given in this system.

        ``scale`` multiplies the lengths of ``coords`` (not the angles, not the origin),
        e.g. 1e-3 for coordinates in mm.
        """
        return (scale * self.local_cartesian(coords)) @ self.rotation.T + self.origin

    def axes_at(self, point) -> np.ndarray:
        """Displacement directions of the system at a global point.

        Returns a (3, 3) matrix whose columns are the global unit vectors of directions
        1, 2, 3 (x y z; r theta z; r theta phi) at ``point``; for a Cartesian system
        this is :attr:`rotation` everywhere. On the axis of a cylindrical system (or at
        the centre of a spherical one) the angles are taken as 0.
        """
        if self.kind == "cartesian":
            return self.rotation
        q = self.rotation.T @ (np.asarray(point, dtype=float).ravel() - self.origin)
        f = np.arctan2(q[1], q[0])
        cf, sf = np.cos(f), np.sin(f)
        if self.kind == "cylindrical":
            L = np.array([[cf, -sf, 0.0], [sf, cf, 0.0], [0.0, 0.0, 1.0]])
        else:
            rho = np.linalg.norm(q)
            t = np.arccos(np.clip(q[2] / rho, -1.0, 1.0)) if rho > 0 else 0.0
            ct, st = np.cos(t), np.sin(t)
            L = np.array([[st * cf, ct * cf, -sf], [st * sf, ct * sf, cf], [ct, -st, 0.0]])
        return self.rotation @ L


GLOBAL = CoordinateSystem(0, np.eye(3), np.zeros(3), "global")


@dataclass(frozen=True)
class Sensor:
    """One measured DOF.

    Parameters
    ----------
    node : int
        Test node label.
    direction : str
        Convention direction (``"+z"``, ``"-rx"`` ...) in the node's coordinate system,
        or the name of a skewed sensor (``"s1"``) whose ``vector`` is given.
    vector : tuple of 3 floats, optional
        Unit vector of a skewed sensor in the *node's* coordinate system; ``rotation``
        says whether it acts on rotations.
    rotation : bool
        True for a rotational sensor.
    source : str
        Where the direction comes from: ``"file"`` (read from a geometry file),
        ``"default +z"`` (a CSV table without a ``directions`` column: one global +z
        sensor per node assumed) or ``"user"`` (given in code: :meth:`TestGeometry.with_sensors`,
        ``read_test_geometry(..., sensors=...)``, e.g. the DOFs of a measurement).

    Examples
    --------
    An accelerometer at test node 3 measuring along +z of the node's system:

    >>> Sensor(3, "+z")
    Sensor(node=3, direction='+z', vector=None, rotation=False, source='user')
    """

    node: int
    direction: str
    vector: tuple[float, float, float] | None = None
    rotation: bool = False
    source: str = "user"

    def __post_init__(self) -> None:
        object.__setattr__(self, "node", int(self.node))
        if self.vector is None:
            if self.direction not in DIRECTIONS:
                raise ParameterError(
                    f"sensor at node {self.node}: unknown direction {self.direction!r}; "
                    f"expected one of {DIRECTIONS} (or a named skewed sensor with a vector)"
                )
            object.__setattr__(self, "rotation", self.direction[1] == "r")

    @property
    def label(self) -> str:
        """DOF label ``"<node><direction>"``."""
        return f"{self.node}{self.direction}"

    def local_vector(self) -> np.ndarray:
        """Unit vector of the sensing axis in the node's coordinate system."""
        if self.vector is not None:
            v = np.asarray(self.vector, dtype=float)
            return v / np.linalg.norm(v)
        d = self.direction
        axis = _AXIS[d[1:]] % 3
        v = np.zeros(3)
        v[axis] = 1.0 if d[0] == "+" else -1.0
        return v


def _make_sensor(node: int, direction: Any, where: str, source: str = "user") -> Sensor:
    if isinstance(direction, str | int | np.integer) and not isinstance(direction, bool):
        try:
            d = direction_label(direction)
        except ParameterError as err:
            raise ParameterError(f"{where}: {err}") from None
        return Sensor(int(node), d, None, d[1] == "r", source)
    raise ParameterError(f"{where}: direction must be a name such as '+z' or a UFF code, got "
                         f"{direction!r}")


@dataclass(frozen=True, eq=False)
class TestGeometry:
    """Test nodes, coordinate systems, trace lines and sensor DOFs.

    Parameters
    ----------
    node : ndarray of int (n_nodes,)
        Test node labels (unique).
    xyz : ndarray (n_nodes, 3)
        Global coordinates (m).
    cs : ndarray of int (n_nodes,)
        Displacement coordinate system of each node (0 = global); sensor directions are
        read in it (for a cylindrical or spherical system: its directions at the node,
        :meth:`CoordinateSystem.axes_at`).
    coordinate_systems : mapping of int to CoordinateSystem
        Local systems (0 is added when absent).
    lines : tuple of ndarray of int
        Trace lines (polylines of node labels) for the wireframe.
    sensors : tuple of Sensor
        Measured DOFs, in the order of the ``dof`` dimension of test shapes.
    name : str

    Examples
    --------
    Built by :func:`read_test_geometry` (or directly); sensor DOFs are labelled
    ``<node><direction>``:

    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> geo.n_nodes, geo.dof_labels
    (3, ['1+z', '2+z', '3+z'])
    """

    __test__ = False  # not a pytest test class

    node: np.ndarray
    xyz: np.ndarray
    cs: np.ndarray | None = None
    coordinate_systems: Mapping[int, CoordinateSystem] = field(default_factory=dict)
    lines: tuple[np.ndarray, ...] = ()
    sensors: tuple[Sensor, ...] = ()
    name: str = ""

    def __post_init__(self) -> None:
        node = np.asarray(self.node).ravel()
        if node.size and not np.all(np.equal(np.mod(node.astype(float), 1), 0)):
            raise ParameterError("test node labels must be integers")
        node = node.astype(np.int64)
        xyz = np.asarray(self.xyz, dtype=float)
        if xyz.shape != (node.size, 3):
            raise DimensionError(
                f"test geometry: xyz must have shape ({node.size}, 3) for {node.size} nodes, "
                f"got {xyz.shape}"
            )
        if not np.all(np.isfinite(xyz)):
            bad = node[~np.all(np.isfinite(xyz), axis=1)]
            raise ParameterError(f"test geometry: non-finite coordinates at nodes {bad.tolist()}")
        u, c = np.unique(node, return_counts=True)
        if np.any(c > 1):
            raise ParameterError(f"test geometry: duplicated node labels {u[c > 1].tolist()}")
        cs = np.zeros(node.size, np.int64) if self.cs is None else np.asarray(
            self.cs, dtype=np.int64).ravel()
        if cs.shape != node.shape:
            raise DimensionError(f"test geometry: cs must have {node.size} entries, got {cs.size}")
        systems = {0: GLOBAL}
        for k, s in dict(self.coordinate_systems).items():
            if not isinstance(s, CoordinateSystem):
                raise ParameterError(f"coordinate system {k}: expected a CoordinateSystem, got "
                                     f"{type(s).__name__}")
            systems[int(k)] = s
        missing = sorted(set(cs.tolist()) - set(systems))
        if missing:
            raise ParameterError(
                f"test geometry: nodes refer to undefined coordinate systems {missing}; "
                f"defined: {sorted(systems)}"
            )
        known = set(node.tolist())
        lines = []
        for i, ln in enumerate(self.lines):
            ln = np.asarray(ln, dtype=np.int64).ravel()
            bad = sorted(set(ln[ln != 0].tolist()) - known)
            if bad:
                raise ParameterError(f"trace line {i + 1}: unknown nodes {bad}")
            lines.append(ln)
        sensors = tuple(self.sensors)
        labels = []
        for s in sensors:
            if not isinstance(s, Sensor):
                raise ParameterError(f"sensors must be Sensor objects, got {type(s).__name__}")
            if s.node not in known:
                raise ParameterError(f"sensor {s.label}: node {s.node} is not a test node")
            labels.append(s.label)
        dup = sorted({lab for lab in labels if labels.count(lab) > 1})
        if dup:
            raise ParameterError(f"test geometry: sensor DOFs listed twice: {dup}")
        object.__setattr__(self, "node", node)
        object.__setattr__(self, "xyz", xyz)
        object.__setattr__(self, "cs", cs)
        object.__setattr__(self, "coordinate_systems", systems)
        object.__setattr__(self, "lines", tuple(lines))
        object.__setattr__(self, "sensors", sensors)
        object.__setattr__(self, "_row", {int(n): i for i, n in enumerate(node)})

    # ------------------------------------------------------------------ basics
    @property
    def n_nodes(self) -> int:
        return int(self.node.size)

    @property
    def dof_labels(self) -> list[str]:
        """Sensor DOF labels ``"<node><direction>"`` in sensor order."""
        return [s.label for s in self.sensors]

    def row(self, node: int) -> int:
        """Row index of a node label."""
        try:
            return self._row[int(node)]
        except KeyError:
            raise ParameterError(f"node {node} is not a test node") from None

    def coordinates(self, nodes: Iterable[int]) -> np.ndarray:
        """Global coordinates (m) of node labels, shape (n, 3)."""
        return self.xyz[[self.row(n) for n in nodes]]

    def sensor_vectors(self) -> np.ndarray:
        """Global unit vectors of the sensing axes, shape (n_sensors, 3)."""
        out = np.zeros((len(self.sensors), 3))
        for i, s in enumerate(self.sensors):
            r = self.row(s.node)
            axes = self.coordinate_systems[int(self.cs[r])].axes_at(self.xyz[r])
            out[i] = axes @ s.local_vector()
        return out

    def with_sensors(self, sensors: Iterable[Sensor | tuple]) -> TestGeometry:
        """Copy with ``sensors`` replaced; tuples are ``(node, direction)`` or
        ``(node, name, (vx, vy, vz))`` for a skewed sensor."""
        out = []
        for i, s in enumerate(sensors):
            if isinstance(s, Sensor):
                out.append(s)
            elif len(s) == 2:
                out.append(_make_sensor(s[0], s[1], f"sensor {i + 1}"))
            elif len(s) == 3:
                out.append(_skewed(s[0], s[1], s[2], False, f"sensor {i + 1}"))
            else:
                raise ParameterError(f"sensor {i + 1}: expected (node, direction) or "
                                     f"(node, name, vector), got {s!r}")
        return replace(self, sensors=tuple(out))

    def triaxial(self, nodes: Iterable[int] | None = None) -> TestGeometry:
        """Copy with +x, +y, +z sensors (node systems) at ``nodes`` (default all)."""
        nodes = self.node if nodes is None else nodes
        return self.with_sensors([(int(n), d) for n in nodes for d in ("+x", "+y", "+z")])

    # ------------------------------------------------------------------ tables
    def nodes_table(self):
        """``pandas.DataFrame`` with columns node, x, y, z, cs."""
        import pandas as pd

        return pd.DataFrame({"node": self.node, "x": self.xyz[:, 0], "y": self.xyz[:, 1],
                             "z": self.xyz[:, 2], "cs": self.cs})

    def sensor_table(self):
        """``pandas.DataFrame``: dof, node, direction, rotation and global vector dx dy dz."""
        import pandas as pd

        v = self.sensor_vectors()
        return pd.DataFrame({
            "dof": self.dof_labels,
            "node": [s.node for s in self.sensors],
            "direction": [s.direction for s in self.sensors],
            "rotation": [s.rotation for s in self.sensors],
            "dx": v[:, 0], "dy": v[:, 1], "dz": v[:, 2],
        })

    def to_dataframe(self):
        """The node table (see :meth:`nodes_table`)."""
        return self.nodes_table()

    def edges(self) -> np.ndarray:
        """Wireframe segments as pairs of node rows, shape (n_segments, 2)."""
        segs = []
        for ln in self.lines:
            prev = None
            for n in ln:
                if n == 0:
                    prev = None
                    continue
                r = self.row(n)
                if prev is not None and prev != r:
                    segs.append((prev, r))
                prev = r
        return np.array(segs, dtype=np.int64).reshape(-1, 2)

    # ------------------------------------------------------------------ output
    def to_dict(self) -> dict:
        """TOML-ready description (see :func:`read_test_geometry`)."""
        d: dict[str, Any] = {"name": self.name} if self.name else {}
        cs = [
            {"id": k, "origin": s.origin.tolist(), "axes": s.rotation.T.tolist(),
             **({"type": s.kind} if s.kind != "cartesian" else {}),
             **({"name": s.name} if s.name else {})}
            for k, s in sorted(self.coordinate_systems.items()) if k != 0
        ]
        if cs:
            d["coordinate_systems"] = cs
        d["nodes"] = [
            {"node": int(n), "x": float(p[0]), "y": float(p[1]), "z": float(p[2]),
             "cs": int(c)}
            for n, p, c in zip(self.node, self.xyz, self.cs)
        ]
        if self.lines:
            d["lines"] = [{"nodes": [int(v) for v in ln]} for ln in self.lines]
        sens = []
        for s in self.sensors:
            e: dict[str, Any] = {"node": s.node, "direction": s.direction}
            if s.vector is not None:
                e["vector"] = [float(v) for v in s.vector]
                e["rotation"] = s.rotation
            sens.append(e)
        if sens:
            d["sensors"] = sens
        return d

    def to_toml(self, path: str | Path | None = None) -> str:
        """TOML text of :meth:`to_dict`; also written to ``path`` when given."""
        import tomli_w

        text = tomli_w.dumps(self.to_dict())
        if path is not None:
            from .._atomic import write_text

            write_text(Path(path), text)
        return text


def _skewed(node, name, vector, rotation, where, source="user") -> Sensor:
    v = np.asarray(vector, dtype=float).ravel()
    if v.shape != (3,) or not np.all(np.isfinite(v)) or np.linalg.norm(v) == 0:
        raise ParameterError(f"{where}: skewed sensor vector must be 3 finite numbers, not all "
                             f"zero, got {vector!r}")
    name = str(name)
    if not name or name in DIRECTIONS or name[0] in "+-0123456789":
        raise ParameterError(
            f"{where}: a skewed sensor needs a name such as 's1' (not a node-axis direction "
            f"and not starting with a sign or digit), got {name!r}"
        )
    v = v / np.linalg.norm(v)
    return Sensor(int(node), name, (float(v[0]), float(v[1]), float(v[2])), bool(rotation),
                  source)


# ---------------------------------------------------------------------- readers
def read_test_geometry(source: str | Path | Mapping[str, Any], *, units_scale: float = 1.0,
                       sensors: Sequence[tuple] | None = None) -> TestGeometry:
    """Read a test geometry from UFF, TOML or CSV (or a parsed TOML mapping).

    Parameters
    ----------
    source : path or mapping
        ``.uff``/``.unv``: datasets 15 or 2411 (nodes, given in their definition system
        ``def_cs``; field ``disp_cs`` = the node's displacement system), 18 (coordinate
        systems, origin / +x point / +xz point, chained through their reference system)
        and 2420 (coordinate systems as local axes and origin in global), both
        Cartesian, cylindrical or spherical (see :class:`CoordinateSystem`), 82 (trace
        lines) and 2412 (elements, drawn as closed trace lines). Other datasets are
        ignored.
        ``.toml`` (or a mapping): tables ``[[coordinate_systems]]`` (``id``, ``origin``,
        ``axes`` = the three local axes as rows, or ``x_point`` and ``xz_point``),
        ``[[nodes]]`` (``node x y z [cs]``), ``[[lines]]`` (``nodes``) and
        ``[[sensors]]`` (``node`` and ``direction`` such as ``"+z"``; or ``triaxial =
        true``; or a skewed sensor with a ``direction`` name and a ``vector``).
        ``.csv``: columns ``node, x, y, z`` and optionally ``cs`` and ``directions``
        (space-separated, e.g. ``"+x +y +z"``; an empty cell = no sensor at the node).
        Without a ``directions`` column every node gets one global ``+z`` sensor,
        marked ``source = "default +z"`` (the ``direction_source`` column of the
        mapping report).
    units_scale : float
        Factor applied to coordinates and origins (e.g. 1e-3 for a file in mm).
    sensors : sequence, optional
        Sensor DOFs ``(node, direction)`` to use instead of those in the file (UFF files
        carry none: the measured DOFs come with the data).

    Returns
    -------
    TestGeometry

    Raises
    ------
    FormatError
        Unreadable file; the message names the file and the record, row or key.
    UnsupportedFormatError
        Unknown file extension.

    Examples
    --------
    A geometry given as a mapping (the layout of a TOML file): three nodes along x (m)
    with one +z sensor each:

    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> geo.node.tolist(), [(s.node, s.direction) for s in geo.sensors]
    ([1, 2, 3], [(1, '+z'), (2, '+z'), (3, '+z')])
    """
    if isinstance(units_scale, bool) or not isinstance(units_scale, int | float) or not (
            np.isfinite(units_scale) and units_scale > 0):
        raise ParameterError(f"units_scale: expected a positive factor (1 for m, 1e-3 for mm), "
                             f"got {units_scale!r}")
    if isinstance(source, Mapping):
        geo = _from_mapping(source, "test geometry", units_scale)
    else:
        path = Path(source)
        ext = path.suffix.lower()
        if not path.is_file():
            from .._atomic import special_file

            kind = special_file(path)
            raise FormatError(f"{path}: test geometry file " + (
                "not found" if kind is None else f"is {kind}, expected a regular file"))
        if ext in (".uff", ".unv", ".uf"):
            geo = _from_uff(path, units_scale)
        elif ext == ".toml":
            import tomllib

            try:
                d = tomllib.loads(path.read_text(encoding="utf-8"))
            except (tomllib.TOMLDecodeError, UnicodeDecodeError) as err:
                raise FormatError(f"{path}: not valid TOML ({err})") from err
            try:
                geo = _from_mapping(d, str(path), units_scale)
            except ConfigError as err:
                raise FormatError(str(err)) from err
        elif ext == ".csv":
            geo = _from_csv(path, units_scale)
        else:
            raise UnsupportedFormatError(
                f"{path}: unknown test geometry format {ext!r}; expected .uff, .unv, .toml "
                "or .csv"
            )
    if sensors is not None:
        geo = geo.with_sensors(sensors)
    return geo


def _num(v: Any, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ConfigError(f"{where}: expected a number, got {v!r}")
    return float(v)


def _vec3(v: Any, where: str) -> np.ndarray:
    if not isinstance(v, Sequence) or isinstance(v, str) or len(v) != 3:
        raise ConfigError(f"{where}: expected 3 numbers, got {v!r}")
    return np.array([_num(x, f"{where}[{i}]") for i, x in enumerate(v)])


_ENTRY_KEYS = {
    "coordinate_systems": {"id", "origin", "type", "axes", "x_point", "xz_point", "name"},
    "nodes": {"node", "x", "y", "z", "cs"},
    "lines": {"nodes"},
    "sensors": {"node", "direction", "vector", "rotation", "triaxial"},
}


def _from_mapping(d: Mapping[str, Any], where: str, scale: float) -> TestGeometry:
    allowed = {"name", "coordinate_systems", "nodes", "lines", "sensors"}
    unknown = set(d) - allowed
    if unknown:
        raise ConfigError(f"{where}: unknown keys {sorted(unknown)}; allowed: {sorted(allowed)}")
    for table, keys in _ENTRY_KEYS.items():
        entries = d.get(table, [])
        for i, e in enumerate(entries if isinstance(entries, Sequence) else []):
            extra = sorted(set(e) - keys) if isinstance(e, Mapping) else []
            if extra:
                raise ConfigError(f"{where}: {table}[{i}]: unknown keys {extra}; allowed: "
                                  f"{sorted(keys)}")
    systems: dict[int, CoordinateSystem] = {}
    for i, c in enumerate(d.get("coordinate_systems", [])):
        w = f"{where}: coordinate_systems[{i}]"
        if not isinstance(c, Mapping) or "id" not in c:
            raise ConfigError(f"{w}: expected a table with an 'id' key, got {c!r}")
        cid = int(_num(c["id"], f"{w}.id"))
        origin = _vec3(c.get("origin", [0, 0, 0]), f"{w}.origin") * scale
        kind = c.get("type", "cartesian")
        if kind not in CS_KINDS:
            raise ConfigError(f"{w}.type: expected one of {CS_KINDS}, got {kind!r}")
        try:
            if "axes" in c:
                axes = c["axes"]
                if not isinstance(axes, Sequence) or len(axes) != 3:
                    raise ConfigError(f"{w}.axes: expected 3 rows (local x, y, z axes), got "
                                      f"{axes!r}")
                R = np.column_stack([_vec3(a, f"{w}.axes[{k}]") for k, a in enumerate(axes)])
                systems[cid] = CoordinateSystem(cid, R, origin, str(c.get("name", "")), kind)
            elif "x_point" in c and "xz_point" in c:
                systems[cid] = CoordinateSystem.from_points(
                    cid, origin, _vec3(c["x_point"], f"{w}.x_point") * scale,
                    _vec3(c["xz_point"], f"{w}.xz_point") * scale, str(c.get("name", "")),
                    kind=kind)
            else:
                raise ConfigError(f"{w}: give 'axes' (3 rows) or 'x_point' and 'xz_point'")
        except ParameterError as err:
            raise ConfigError(f"{w}: {err}") from None
    nodes = d.get("nodes")
    if not isinstance(nodes, Sequence) or not nodes:
        raise ConfigError(f"{where}: missing or empty [[nodes]] table")
    lab, xyz, cs = [], [], []
    for i, n in enumerate(nodes):
        w = f"{where}: nodes[{i}]"
        if not isinstance(n, Mapping) or not {"node", "x", "y", "z"} <= set(n):
            raise ConfigError(f"{w}: expected keys node, x, y, z (and optional cs), got {n!r}")
        lab.append(int(_num(n["node"], f"{w}.node")))
        xyz.append([_num(n[k], f"{w}.{k}") * scale for k in ("x", "y", "z")])
        cs.append(int(_num(n.get("cs", 0), f"{w}.cs")))
    lines = []
    for i, ln in enumerate(d.get("lines", [])):
        nl = ln.get("nodes") if isinstance(ln, Mapping) else ln
        if not isinstance(nl, Sequence) or isinstance(nl, str):
            raise ConfigError(f"{where}: lines[{i}]: expected a list of node labels")
        lines.append(np.array([int(_num(v, f"{where}: lines[{i}]")) for v in nl]))
    sens: list[Sensor] = []
    for i, s in enumerate(d.get("sensors", [])):
        w = f"{where}: sensors[{i}]"
        if not isinstance(s, Mapping) or "node" not in s:
            raise ConfigError(f"{w}: expected a table with a 'node' key, got {s!r}")
        node = int(_num(s["node"], f"{w}.node"))
        try:
            if s.get("triaxial", False):
                sens += [Sensor(node, a, None, False, "file") for a in ("+x", "+y", "+z")]
            elif "vector" in s:
                sens.append(_skewed(node, s.get("direction", ""), s["vector"],
                                    bool(s.get("rotation", False)), w, "file"))
            elif "direction" in s:
                sens.append(_make_sensor(node, s["direction"], w, "file"))
            else:
                raise ConfigError(f"{w}: give 'direction', 'vector' or 'triaxial = true'")
        except ParameterError as err:
            raise ConfigError(str(err)) from None
    try:
        return TestGeometry(np.array(lab), np.array(xyz).reshape(-1, 3), np.array(cs), systems,
                            tuple(lines), tuple(sens), str(d.get("name", "")))
    except (ParameterError, DimensionError) as err:
        raise ConfigError(f"{where}: {err}") from None


def _from_csv(path: Path, scale: float) -> TestGeometry:
    text = path.read_text(encoding="utf-8-sig")
    # '#' lines are comments (a header saying what the table is); line numbers in
    # messages stay those of the file
    kept = [(n, ln) for n, ln in enumerate(text.splitlines(), start=1)
            if not ln.lstrip().startswith("#")]
    line_no = [n for n, _ in kept]
    reader = csv.DictReader(io.StringIO("\n".join(ln for _, ln in kept)))
    cols = [c.strip().lower() for c in (reader.fieldnames or [])]
    if not {"node", "x", "y", "z"} <= set(cols):
        raise FormatError(f"{path}: header must have columns node, x, y, z (optional cs, "
                          f"directions); found {cols}")
    lab, xyz, cs, sens = [], [], [], []
    for i, row in enumerate(reader):
        line = line_no[i + 1] if i + 1 < len(line_no) else i + 2
        row = {k.strip().lower(): (v or "").strip() for k, v in row.items() if k is not None}
        try:
            node = int(row["node"])
            p = [float(row[k]) * scale for k in ("x", "y", "z")]
            c = int(row["cs"]) if row.get("cs") else 0
        except ValueError as err:
            raise FormatError(f"{path}, line {line}: expected an integer node, numeric x y z "
                              f"and integer cs ({err})") from None
        lab.append(node)
        xyz.append(p)
        cs.append(c)
        if "directions" not in cols:
            # no directions column: one sensor per node along global +z (CSV nodes are
            # in the global system), marked as a default in Sensor.source
            sens.append(Sensor(node, "+z", None, False, "default +z"))
        for dname in row.get("directions", "").split():
            try:
                sens.append(_make_sensor(node, dname, f"{path}, line {line}", "file"))
            except ParameterError as err:
                raise FormatError(str(err)) from None
    if not lab:
        raise FormatError(f"{path}: no node rows")
    try:
        return TestGeometry(np.array(lab), np.array(xyz), np.array(cs), {}, (), tuple(sens),
                            path.stem)
    except (ParameterError, DimensionError) as err:
        raise FormatError(f"{path}: {err}") from None


def _from_uff(path: Path, scale: float) -> TestGeometry:
    try:
        import pyuff
    except ImportError as err:  # pragma: no cover - pyuff is a base dependency
        raise MissingDependencyError("reading UFF geometry needs pyuff: pip install pyuff") from err
    try:
        with deferred_interrupt():
            uff = pyuff.UFF(str(path))
            types = [int(t) for t in uff.get_set_types()]
    except Exception as err:
        raise FormatError(f"{path}: not a readable UFF file ({type(err).__name__}: {err})"
                          ) from err
    recs = []
    for i, t in enumerate(types):
        if t not in (15, 18, 82, 2411, 2412, 2420):
            continue
        try:
            with deferred_interrupt():
                recs.append((i + 1, t, uff.read_sets(i)))
        except Exception as err:
            raise FormatError(f"{path}, record {i + 1} (dataset {t}): could not be parsed "
                              f"({type(err).__name__}: {err})") from err
    if not any(t in (15, 2411) for _, t, _ in recs):
        raise FormatError(f"{path}: no node dataset (15 or 2411) found; datasets present: "
                          f"{sorted(set(types))}")
    # coordinate systems: 18 (three points in a reference system, resolved through it)
    # and 2420 (local axes as rows plus the origin, in global)
    raw: dict[int, tuple] = {}
    systems: dict[int, CoordinateSystem] = {0: GLOBAL}
    for idx, t, r in recs:
        if t not in (18, 2420):
            continue
        if t == 18:
            ids, kinds = r["cs_num"], r["cs_type"]
        else:
            ids, kinds = r["CS_sys_labels"], r["CS_types"]
        for k in range(len(ids)):
            cid, ctype = int(ids[k]), int(kinds[k])
            where = f"{path}, record {idx} (dataset {t})"
            if ctype not in (0, 1, 2):
                raise FormatError(f"{where}: coordinate system {cid} has type {ctype}; "
                                  "expected 0 (Cartesian), 1 (cylindrical) or 2 (spherical)")
            if cid == 0 or cid in raw or cid in systems:
                raise FormatError(f"{where}: coordinate system {cid} is defined more than "
                                  "once (label 0 is the global system)")
            if t == 18:
                raw[cid] = (where, int(r["ref_cs_num"][k]), ctype, r["ref_o"][k],
                            r["x_point"][k], r["xz_point"][k], r["cs_name"][k])
                continue
            T = np.asarray(r["CS_matrices"][k], dtype=float)
            try:
                systems[cid] = CoordinateSystem(cid, T[:3].T, T[3] * scale,
                                                str(r["CS_names"][k]).strip(), CS_KINDS[ctype])
            except ParameterError as err:
                raise FormatError(f"{where}: {err}") from None

    def resolve(cid: int, stack: tuple[int, ...] = ()) -> CoordinateSystem:
        if cid in systems:
            return systems[cid]
        if cid not in raw:
            raise FormatError(f"{path}: coordinate system {cid} is used but not defined "
                              "(datasets 18 / 2420)")
        if cid in stack:
            raise FormatError(f"{path}: coordinate systems {list(stack)} refer to each other "
                              "in a cycle")
        where, ref, ctype, o, px, pxz, name = raw[cid]
        rcs = resolve(ref, stack + (cid,))
        try:
            cs = CoordinateSystem.from_points(
                cid, *(rcs.to_global(v, scale) for v in (o, px, pxz)), str(name).strip(),
                kind=CS_KINDS[ctype])
        except ParameterError as err:
            raise FormatError(f"{where}: {err}") from None
        systems[cid] = cs
        return cs

    for cid in raw:
        resolve(cid)
    lab, xyz, cs_out, lines = [], [], [], []
    for idx, t, r in recs:
        if t in (15, 2411):
            nn = np.asarray(r["node_nums"], dtype=float)
            p = np.column_stack([r["x"], r["y"], r["z"]]).astype(float)
            dcs = np.asarray(r["def_cs"], dtype=float).astype(int)
            pcs = np.asarray(r["disp_cs"], dtype=float).astype(int)
            for k in range(nn.size):
                try:
                    p[k] = resolve(int(dcs[k])).to_global(p[k], scale)
                    resolve(int(pcs[k]))
                except FormatError as err:
                    raise FormatError(f"{err} (node {int(nn[k])}, record {idx})") from None
            lab += nn.astype(int).tolist()
            xyz += p.tolist()
            cs_out += pcs.tolist()
        elif t == 82:
            lines.append(np.asarray(r["nodes"], dtype=float).astype(np.int64))
        elif t == 2412:
            for key, els in r.items():
                if not isinstance(key, int):
                    continue
                for e in els:
                    nodes = [int(v) for v in e["nodes_nums"]]
                    if len(nodes) > 2:
                        nodes = nodes + nodes[:1]
                    lines.append(np.array(nodes, dtype=np.int64))
    try:
        return TestGeometry(np.array(lab), np.array(xyz).reshape(-1, 3), np.array(cs_out),
                            systems, tuple(lines), (), path.stem)
    except (ParameterError, DimensionError) as err:
        raise FormatError(f"{path}: {err}") from None

