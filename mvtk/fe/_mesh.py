"""Structured rectangular plate meshes with patches, named node sets and supports.

The plate occupies ``0 <= x <= length``, ``0 <= y <= width`` in the x-y plane (z = 0 is
the reference surface). Mesh lines always pass through the patch edges and through the
named points, so patch edges and sensor points are nodes of the mesh.

Node sets created by :func:`rectangular_plate_mesh`:

- ``"x0"``, ``"x1"``, ``"y0"``, ``"y1"``: the plate edges (x = 0, x = length, y = 0,
  y = width);
- ``"patch:<name>:x0"``, ``"patch:<name>:x1"``, ``"patch:<name>:y0"``,
  ``"patch:<name>:y1"``: the node lines on the four edges of each patch;
  ``"patch:<name>"``: every node of the patch;
- ``"<point name>"``: the single node at each named point.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from ._model import DOF_NAMES

__all__ = [
    "Patch",
    "PlateMesh",
    "rectangular_plate_mesh",
    "edge_dofs",
    "SUPPORT_TYPES",
    "support_components",
    "edge_tributary_lengths",
    "ModelSize",
    "estimate_plate_size",
    "memory_limit_bytes",
]

#: Named support types and the DOF components they fix (``"tangential"`` is the rotation
#: about the edge direction, fixed by a hard simple support).
SUPPORT_TYPES: dict[str, tuple[str, ...]] = {
    "clamped": ("ux", "uy", "uz", "rx", "ry", "rz"),
    "simply_supported": ("ux", "uy", "uz", "tangential"),
    "hinged": ("ux", "uy", "uz"),
    "free": (),
}

_EDGES = ("x0", "x1", "y0", "y1")


@dataclass(frozen=True)
class Patch:
    """A rectangular region of the plate carrying a different section.

    Parameters
    ----------
    name : str
    x0, x1, y0, y1 : float
        Extent (m), ``0 <= x0 < x1 <= length`` and ``0 <= y0 < y1 <= width``.

    Examples
    --------
    A 100 x 100 mm region of a plate carrying its own layers (see :func:`mvtk.fe.plate_model`):

    >>> p = Patch("act", x0=0.05, x1=0.15, y0=0.05, y1=0.15)      # m
    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=6, ny=4, patches=[p])
    >>> int((mesh.element_region == 1).sum())                    # elements inside it
    4
    """

    name: str
    x0: float
    x1: float
    y0: float
    y1: float


@dataclass(frozen=True, eq=False)
class PlateMesh:
    """A structured quadrilateral mesh of a rectangular plate.

    Attributes
    ----------
    nodes : ndarray (n_nodes, 3)
        Coordinates (m), z = 0.
    elements : ndarray (n_el, 4)
        Counter-clockwise node indices.
    element_region : ndarray (n_el,)
        0 for the base plate, ``i + 1`` for elements inside ``patches[i]``.
    x_lines, y_lines : ndarray
        Mesh line coordinates (m).
    patches : tuple of Patch
    node_sets : dict of str to ndarray

    Examples
    --------
    Returned by :func:`rectangular_plate_mesh`:

    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> mesh.nodes.shape, mesh.elements[0].tolist(), mesh.y_lines.tolist()
    ((12, 3), [0, 3, 4, 1], [0.0, 0.1, 0.2])
    """

    nodes: np.ndarray
    elements: np.ndarray
    element_region: np.ndarray
    x_lines: np.ndarray
    y_lines: np.ndarray
    patches: tuple[Patch, ...] = ()
    node_sets: Mapping[str, np.ndarray] = field(default_factory=dict)

    @property
    def length(self) -> float:
        return float(self.x_lines[-1])

    @property
    def width(self) -> float:
        return float(self.y_lines[-1])


def _lines(extent: float, breaks: Iterable[float], n_total: int | None,
           size: float | None) -> np.ndarray:
    pts = np.unique(np.concatenate([[0.0, extent], np.asarray(list(breaks), dtype=float)]))
    # merge breakpoints closer than a tiny tolerance
    keep = np.concatenate([[True], np.diff(pts) > 1e-9 * extent])
    pts = pts[keep]
    pts[-1] = extent
    out = [np.array([0.0])]
    for a, b in zip(pts[:-1], pts[1:]):
        if n_total is not None:
            n = max(1, int(round(n_total * (b - a) / extent)))
        else:
            n = max(1, int(np.ceil((b - a) / size - 1e-9)))
        out.append(a + (b - a) * np.arange(1, n + 1) / n)
    lines = np.concatenate(out)
    lines[-1] = extent
    return lines


def _positive_int(name: str, value) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ParameterError(f"{name} must be a positive integer, got {value!r}")
    return int(value)


#: Bytes per element of the assembly peak beyond K and M (node-pair keys and their sort,
#: CSR positions, the node-pair block sums of K and M; tracemalloc peak of plate_model
#: less 12 bytes per stored entry of K and M, 600 and 15 000 elements: 7.1-7.4 kB per
#: element with a symmetric laminate, 8.4-8.6 kB with an unsymmetric one).
_BYTES_PER_ELEMENT = 9_000
#: Bytes per non-zero of K and M in CSR (value + column index, twice).
_BYTES_PER_NNZ = 24


@dataclass(frozen=True)
class ModelSize:
    """Size of a model estimated before meshing.

    Attributes
    ----------
    n_nodes, n_elements, n_dof : int
        Nodes, elements and DOFs (6 per node, before supports).
    nnz : int
        Estimated non-zeros of the stiffness matrix over all DOFs (each node pair
        sharing an element couples 6 x 6 DOFs); an upper bound: a flat plate with a
        symmetric laminate stores half of them (its membrane and bending DOFs do not
        couple, see :class:`mvtk.fe.SparsityPattern`).
    bytes : int
        Estimated peak memory of the assembly (element matrices, sparsity pattern, K and M).

    Examples
    --------
    Returned by :func:`estimate_plate_size`:

    >>> s = estimate_plate_size(0.3, 0.2, nx=3, ny=2)
    >>> s.n_nodes, s.n_elements, s.n_dof
    (12, 6, 72)
    """

    n_nodes: int
    n_elements: int
    n_dof: int
    nnz: int
    bytes: int


def memory_limit_bytes() -> int:
    """Default model-size limit: half the physical memory (4 GB if it is unknown).

    Examples
    --------
    >>> memory_limit_bytes() > 0
    True
    """
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2)
    except (AttributeError, ValueError, OSError):
        return 4 * 1024**3


def estimate_plate_size(length: float, width: float, nx: int | None = None,
                        ny: int | None = None, element_size: float | None = None,
                        patches: Sequence[Patch] = (),
                        points: Mapping[str, tuple[float, float]] | None = None) -> ModelSize:
    """Size of the mesh :func:`rectangular_plate_mesh` would build, without building it.

    Only the mesh lines (1-D arrays) are computed, so the estimate is cheap even for a
    mesh that could not be held in memory.

    Examples
    --------
    Size of a 12 x 12 mesh before building it: 13 x 13 nodes, 6 DOFs each:

    >>> size = estimate_plate_size(0.3, 0.3, nx=12, ny=12)
    >>> size.n_nodes, size.n_elements, size.n_dof
    (169, 144, 1014)
    """
    points = dict(points or {})
    xb = [v for p in patches for v in (p.x0, p.x1)] + [x for x, _ in points.values()]
    yb = [v for p in patches for v in (p.y0, p.y1)] + [y for _, y in points.values()]
    nxl = _line_count(length, xb, nx, element_size)
    nyl = _line_count(width, yb, ny, element_size)
    n_nodes = nxl * nyl
    n_el = (nxl - 1) * (nyl - 1)
    # node pairs sharing an element: self, horizontal, vertical and both diagonals
    pairs = n_nodes + 2 * ((nxl - 1) * nyl + nxl * (nyl - 1)) + 4 * n_el
    nnz = 36 * pairs
    return ModelSize(n_nodes=n_nodes, n_elements=n_el, n_dof=6 * n_nodes, nnz=nnz,
                     bytes=_BYTES_PER_ELEMENT * n_el + _BYTES_PER_NNZ * nnz)


def _line_count(extent: float, breaks: Iterable[float], n_total: int | None,
                size: float | None) -> int:
    """Number of mesh lines :func:`_lines` would return (without allocating them)."""
    pts = np.unique(np.concatenate([[0.0, extent], np.asarray(list(breaks), dtype=float)]))
    keep = np.concatenate([[True], np.diff(pts) > 1e-9 * extent])
    pts = pts[keep]
    pts[-1] = extent
    seg = np.diff(pts)
    if n_total is not None:
        n = np.maximum(1, np.round(n_total * seg / extent).astype(np.int64))
    else:
        n = np.maximum(1, np.ceil(seg / size - 1e-9)).astype(np.int64)
    return int(1 + n.sum())


def rectangular_plate_mesh(
    length: float,
    width: float,
    nx: int | None = None,
    ny: int | None = None,
    element_size: float | None = None,
    patches: Sequence[Patch] = (),
    points: Mapping[str, tuple[float, float]] | None = None,
    max_bytes: int | None = None,
) -> PlateMesh:
    """Mesh a rectangular plate with 4-node quadrilaterals.

    Parameters
    ----------
    length, width : float
        Plate size along x and y (m).
    nx, ny : int, optional
        Approximate number of elements along x and y (the intervals between patch edges
        and points get a share proportional to their length, at least one element).
    element_size : float, optional
        Target element size (m), used when ``nx``/``ny`` are not given.
    patches : sequence of Patch
        Non-overlapping rectangular regions; mesh lines follow their edges.
    points : mapping of name to (x, y), optional
        Named points (m); mesh lines pass through them and each becomes a node set.
    max_bytes : int, optional
        Refuse meshes whose estimated assembly memory (:func:`estimate_plate_size`)
        exceeds this (default :func:`memory_limit_bytes`, half the physical memory).

    Returns
    -------
    PlateMesh

    Raises
    ------
    ParameterError
        For non-positive sizes, missing mesh density, patches outside the plate or
        overlapping, points outside the plate, or a mesh too large for the memory limit
        (the message gives the estimated size and the limit).

    Examples
    --------
    A 300 x 200 mm plate in 3 x 2 quadrilaterals:

    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> mesh.nodes.shape, mesh.elements.shape, sorted(mesh.node_sets)
    ((12, 3), (6, 4), ['x0', 'x1', 'y0', 'y1'])
    >>> mesh.x_lines
    array([0. , 0.1, 0.2, 0.3])
    """
    for key, v in (("length", length), ("width", width)):
        if not (isinstance(v, (int, float, np.floating)) and np.isfinite(v) and v > 0):
            raise ParameterError(f"plate {key} must be a positive number (m), got {v!r}")
    length, width = float(length), float(width)
    if nx is None and ny is None and element_size is None:
        raise ParameterError("mesh density missing: give nx and ny, or element_size")
    if element_size is not None and not (np.isfinite(element_size) and element_size > 0):
        raise ParameterError(f"element_size must be a positive number (m), got {element_size!r}")
    if (nx is None) != (ny is None):
        if element_size is None:
            raise ParameterError("give both nx and ny (or element_size)")
    if nx is not None:
        nx = _positive_int("nx", nx)
    if ny is not None:
        ny = _positive_int("ny", ny)
    patches = tuple(patches)
    points = dict(points or {})
    names = set()
    for p in patches:
        if p.name in names:
            raise ParameterError(f"duplicated patch name {p.name!r}")
        names.add(p.name)
        if not (0 <= p.x0 < p.x1 <= length and 0 <= p.y0 < p.y1 <= width):
            raise ParameterError(
                f"patch {p.name!r} extent x {p.x0}..{p.x1}, y {p.y0}..{p.y1} must satisfy "
                f"0 <= x0 < x1 <= {length} and 0 <= y0 < y1 <= {width}"
            )
    for i, p in enumerate(patches):
        for q in patches[i + 1:]:
            if p.x0 < q.x1 and q.x0 < p.x1 and p.y0 < q.y1 and q.y0 < p.y1:
                raise ParameterError(f"patches {p.name!r} and {q.name!r} overlap")
    for name, (x, y) in points.items():
        if not (0 <= x <= length and 0 <= y <= width):
            raise ParameterError(
                f"point {name!r} at ({x}, {y}) is outside the plate 0..{length} x 0..{width}"
            )
    size = estimate_plate_size(length, width, nx, ny, element_size, patches, points)
    limit = memory_limit_bytes() if max_bytes is None else int(max_bytes)
    if size.bytes > limit:
        raise ParameterError(
            f"the mesh would have {size.n_nodes} nodes, {size.n_elements} elements and "
            f"{size.n_dof} DOFs (nx={nx}, ny={ny}, element_size={element_size}); its "
            f"estimated assembly memory {size.bytes / 1e9:.3g} GB exceeds the limit "
            f"{limit / 1e9:.3g} GB: use a coarser mesh"
        )
    xb = [v for p in patches for v in (p.x0, p.x1)] + [x for x, _ in points.values()]
    yb = [v for p in patches for v in (p.y0, p.y1)] + [y for _, y in points.values()]
    xl = _lines(length, xb, nx, element_size)
    yl = _lines(width, yb, ny, element_size)
    nxl, nyl = len(xl), len(yl)
    X, Y = np.meshgrid(xl, yl, indexing="ij")  # node (i, j) -> i * nyl + j
    nodes = np.column_stack([X.ravel(), Y.ravel(), np.zeros(X.size)])
    i, j = np.meshgrid(np.arange(nxl - 1), np.arange(nyl - 1), indexing="ij")
    i, j = i.ravel(), j.ravel()
    n00 = i * nyl + j
    elements = np.column_stack([n00, n00 + nyl, n00 + nyl + 1, n00 + 1])
    xc = 0.5 * (xl[i] + xl[i + 1])
    yc = 0.5 * (yl[j] + yl[j + 1])
    region = np.zeros(len(elements), dtype=np.int64)
    tol_x, tol_y = 1e-9 * length, 1e-9 * width
    sets: dict[str, np.ndarray] = {
        "x0": np.flatnonzero(np.abs(nodes[:, 0]) <= tol_x),
        "x1": np.flatnonzero(np.abs(nodes[:, 0] - length) <= tol_x),
        "y0": np.flatnonzero(np.abs(nodes[:, 1]) <= tol_y),
        "y1": np.flatnonzero(np.abs(nodes[:, 1] - width) <= tol_y),
    }
    x, y = nodes[:, 0], nodes[:, 1]
    for k, p in enumerate(patches):
        inside = (xc > p.x0) & (xc < p.x1) & (yc > p.y0) & (yc < p.y1)
        region[inside] = k + 1
        in_x = (x >= p.x0 - tol_x) & (x <= p.x1 + tol_x)
        in_y = (y >= p.y0 - tol_y) & (y <= p.y1 + tol_y)
        pre = f"patch:{p.name}"
        sets[pre] = np.flatnonzero(in_x & in_y)
        sets[f"{pre}:x0"] = np.flatnonzero(in_y & (np.abs(x - p.x0) <= tol_x))
        sets[f"{pre}:x1"] = np.flatnonzero(in_y & (np.abs(x - p.x1) <= tol_x))
        sets[f"{pre}:y0"] = np.flatnonzero(in_x & (np.abs(y - p.y0) <= tol_y))
        sets[f"{pre}:y1"] = np.flatnonzero(in_x & (np.abs(y - p.y1) <= tol_y))
    for name, (px, py) in points.items():
        if name in sets:
            raise ParameterError(f"point name {name!r} clashes with a node set of the mesh")
        d = np.hypot(x - px, y - py)
        sets[name] = np.array([int(np.argmin(d))])
    return PlateMesh(nodes=nodes, elements=elements, element_region=region, x_lines=xl,
                     y_lines=yl, patches=patches, node_sets=sets)


def support_components(kind: str | Sequence[str], edge: str) -> tuple[int, ...]:
    """DOF component indices fixed by a support ``kind`` on ``edge``.

    ``kind`` is one of :data:`SUPPORT_TYPES` or an explicit list of DOF names
    (``["uz", "rx"]``). ``"tangential"`` is the rotation that carries the slope along
    the edge (see Notes).

    Notes
    -----
    On an edge x = const (runs along y) the slope along the edge is ``dw/dy``, tied to
    ``beta_y = -rx``; a hard simple support fixes ``rx`` there. On y = const it fixes
    ``ry``.

    Examples
    --------
    A clamped edge fixes all six components (ux, uy, uz, rx, ry, rz):

    >>> support_components("clamped", "x0")
    (0, 1, 2, 3, 4, 5)
    >>> support_components(["uz", "rx"], "x0")
    (2, 3)
    """
    if isinstance(kind, str):
        if kind not in SUPPORT_TYPES:
            raise ParameterError(
                f"unknown support type {kind!r} on edge {edge!r}; expected one of "
                f"{sorted(SUPPORT_TYPES)} or a list of DOF names {DOF_NAMES}"
            )
        names = SUPPORT_TYPES[kind]
    else:
        names = tuple(kind)
    out = []
    for n in names:
        if n == "tangential":
            out.append(DOF_NAMES.index("rx" if edge in ("x0", "x1") else "ry"))
        elif n in DOF_NAMES:
            out.append(DOF_NAMES.index(n))
        else:
            raise ParameterError(
                f"unknown DOF name {n!r} in support of edge {edge!r}; expected {DOF_NAMES}"
            )
    return tuple(sorted(set(out)))


def edge_dofs(mesh: PlateMesh, edge: str, kind: str | Sequence[str]) -> np.ndarray:
    """Global (all-DOF) indices ``node * 6 + component`` fixed by a support on an edge.

    Examples
    --------
    The three nodes of edge x = 0 of a 3 x 2 mesh, clamped: 18 DOFs:

    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> edge_dofs(mesh, "x0", "clamped").size
    18
    """
    if edge not in mesh.node_sets:
        raise ParameterError(
            f"unknown edge or node set {edge!r}; available: {sorted(mesh.node_sets)}"
        )
    comps = support_components(kind, edge)
    nodes = mesh.node_sets[edge]
    return (nodes[:, None] * 6 + np.asarray(comps, dtype=np.int64)[None, :]).ravel()


def edge_tributary_lengths(mesh: PlateMesh, node_set: str) -> np.ndarray:
    """Length (m) of edge attributed to each node of a straight node line.

    Used to turn a stiffness per unit length (e.g. a clamp rotational stiffness in
    N m/rad per m) into nodal springs; the trapezoidal rule, exact for a constant
    distribution.

    Examples
    --------
    The 0.2 m edge x = 0 in two elements: the end nodes carry half an element each:

    >>> mesh = rectangular_plate_mesh(0.3, 0.2, nx=3, ny=2)
    >>> edge_tributary_lengths(mesh, "x0")       # m
    array([0.05, 0.1 , 0.05])
    """
    nodes = mesh.node_sets[node_set]
    xy = mesh.nodes[nodes, :2]
    if len(nodes) == 1:
        return np.zeros(1)
    span = np.ptp(xy, axis=0)
    axis = int(np.argmax(span))
    order = np.argsort(xy[:, axis])
    s = xy[order, axis]
    seg = np.diff(s)
    trib = np.zeros(len(s))
    trib[:-1] += seg / 2
    trib[1:] += seg / 2
    out = np.empty_like(trib)
    out[order] = trib
    return out
