"""Sanity checks of a structural model before any solve.

:func:`check_model` runs on every model :func:`mvtk.fe.build_model` returns. Errors
(:class:`~mvtk.errors.ConfigError`) for what cannot be meant: two ``[[points]]`` or
``[[patches]]`` with one name, the same element twice, a point farther from the mesh
than the local element size. Warnings (:class:`~mvtk.errors.ModelWarning`, also kept in
``model.meta["sanity"]`` so the result carries them) for what is most likely a mistake:
a geometry or material in the wrong unit (with the likely factor), a mesh too coarse to
represent a bending half-wave, coincident nodes that nothing connects (a crack).
:func:`check_matrices` refuses complex or non-finite mass and stiffness matrices and
negative diagonal terms (an indefinite matrix), naming the DOF. :func:`check_size`
refuses a model whose assembly would not fit in memory before anything is allocated.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError, ModelWarning, ParameterError

__all__ = ["check_model", "check_matrices", "check_size", "local_element_size",
           "ELEMENTS_PER_HALF_WAVE"]

#: Elements needed along a bending half-wave for frequencies within a few per cent
#: (linear shells and beams; fewer give errors of tens of per cent).
ELEMENTS_PER_HALF_WAVE = 4
#: Span (m) above which a laboratory model is suspected to be in millimetres.
_SPAN_MM_M = 20.0
#: Bytes per element of a beam assembly (12x12 element matrices, keys, K and M).
_BYTES_PER_BEAM_ELEMENT = 12_000
#: Bytes per element of a shell assembly of an imported or general model (element
#: matrices in chunks, a CSR position per element-matrix entry, K and M; the figure
#: measured for the 24x24 MITC4 assembly that formed every element matrix, kept for this
#: path, which still does).
_BYTES_PER_SHELL_ELEMENT = 55_000


def _warn(model, text: str) -> None:
    meta = model.meta if isinstance(model.meta, dict) else None
    if meta is not None:
        meta.setdefault("sanity", []).append(text)
    # _warn <- check <- check_model <- build_model <- the caller
    warnings.warn(text, ModelWarning, stacklevel=5)


def _who(model) -> str:
    """The model's name, else its source file name, for messages."""
    if model.name:
        return str(model.name)
    src = model.meta.get("source") if isinstance(model.meta, Mapping) else None
    return Path(str(src)).name if src else "the model"


# ----------------------------------------------------------------------- sizes
def check_size(n_nodes: int, n_elements: int, what: str, *, beam: bool = False,
               max_bytes: int | None = None) -> None:
    """Refuse a model whose assembly would exceed the memory limit, before allocating.

    Parameters
    ----------
    n_nodes, n_elements : int
        Size of the mesh to assemble.
    what : str
        Where the size comes from (a key or file), for the message.
    beam : bool
        Beam elements (2 nodes, 12 DOFs) instead of shells.
    max_bytes : int, optional
        Limit; default :func:`mvtk.fe.memory_limit_bytes` (half the physical memory).

    Raises
    ------
    ParameterError
        The estimate exceeds the limit; the message gives nodes, elements and GB.
    """
    from ._mesh import memory_limit_bytes

    per = _BYTES_PER_BEAM_ELEMENT if beam else _BYTES_PER_SHELL_ELEMENT
    need = int(n_elements) * per + int(n_nodes) * 6 * 8 * 4
    limit = memory_limit_bytes() if max_bytes is None else int(max_bytes)
    if need > limit:
        raise ParameterError(
            f"{what}: the model would have {n_nodes} nodes and {n_elements} elements; its "
            f"estimated assembly memory {need / 1e9:.3g} GB exceeds the limit "
            f"{limit / 1e9:.3g} GB: use a coarser mesh")


# -------------------------------------------------------------------- matrices
def check_matrices(K, M, labels=None, *, where: str = "model") -> None:
    """Refuse complex, non-finite or indefinite-looking stiffness and mass matrices.

    A complex stiffness (structural damping ``K (1 + i eta)``) has no real eigenproblem:
    give the real part as K and the loss factor to the damping model. A negative
    diagonal term makes the matrix indefinite (``e_i' A e_i < 0``).

    Parameters
    ----------
    K, M : sparse or dense matrices
    labels : sequence of str, optional
        Name of each DOF (e.g. ``"n12:uz"``) for the message.
    where : str
        What the matrices belong to, for the message.

    Raises
    ------
    ParameterError
        Naming the matrix, the DOF and the value.
    """
    import scipy.sparse as sp

    for name, A in (("K", K), ("M", M)):
        data = A.data if sp.issparse(A) else np.asarray(A)
        if np.iscomplexobj(data):
            imag = float(np.abs(np.imag(data)).max(initial=0.0))
            if imag > 0:
                raise ParameterError(
                    f"{where}: {name} is complex (max |imag| {imag:.3g}); the eigenproblem "
                    f"needs real K and M: give the real part as {name} and a complex "
                    "stiffness's ratio imag/real as the structural loss factor of the "
                    "damping model")
        if not np.all(np.isfinite(data)):
            raise ParameterError(f"{where}: {name} holds NaN or infinite values")
        diag = np.real(A.diagonal() if sp.issparse(A) else np.diagonal(np.asarray(A)))
        neg = np.flatnonzero(diag < 0)
        if neg.size:
            i = int(neg[np.argmin(diag[neg])])
            lab = labels[i] if labels is not None else f"DOF {i}"
            raise ParameterError(
                f"{where}: {name} has {neg.size} negative diagonal term(s), e.g. {lab}: "
                f"{diag[i]:.4g}; a {'mass' if name == 'M' else 'stiffness'} matrix must be "
                "positive (semi-)definite")


# ------------------------------------------------------------------- the model
def _extent(nodes: np.ndarray) -> float:
    return float(np.ptp(nodes, axis=0).max()) if len(nodes) else 0.0


def _duplicate_names(desc: Mapping, table: str) -> None:
    items = desc.get(table)
    if not isinstance(items, list):
        return
    names = [str(p.get("name")) for p in items if isinstance(p, Mapping) and "name" in p]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        first = [i for i, n in enumerate(names) if n == dup[0]]
        raise ConfigError(f"{table}: the name {dup[0]!r} is given {len(first)} times "
                          f"({', '.join(f'{table}[{i}]' for i in first)}); every entry "
                          "needs its own name" + (f" (also repeated: {dup[1:]})"
                                                  if len(dup) > 1 else ""))


def _duplicate_elements(model) -> None:
    ids = np.asarray(model.node_ids)
    for kind, conn in model.elements.items():
        conn = np.asarray(conn)
        if conn.ndim != 2 or len(conn) < 2:
            continue
        key = np.sort(conn, axis=1)
        _, first, counts = np.unique(key, axis=0, return_index=True, return_counts=True)
        if np.any(counts > 1):
            rows = np.flatnonzero(np.all(key == key[first[np.argmax(counts)]], axis=1))
            n_dup = int((counts - 1).sum())
            raise ConfigError(
                f"{_who(model)}: {n_dup} duplicated {kind} element(s), e.g. "
                f"elements {', '.join(str(int(r) + 1) for r in rows)} on nodes "
                f"{ids[conn[rows[0]]].tolist()}: each would add its stiffness and mass "
                "again; remove the copies from the mesh")


def _coincident_unconnected(model) -> None:
    """Warn about coincident nodes that no element, spring or link couples (a crack)."""
    from scipy.spatial import cKDTree

    nodes = model.nodes
    span = _extent(nodes)
    if len(nodes) < 2 or span <= 0:
        return
    pairs = cKDTree(nodes).query_pairs(1e-9 * span, output_type="ndarray")
    if len(pairs) == 0:
        return
    K = model.K.tocsr()
    dn = np.asarray(model.dof_node)
    by_node: dict[int, np.ndarray] = {}
    order = np.argsort(dn, kind="stable")
    bounds = np.searchsorted(dn[order], np.arange(len(nodes) + 1))
    for n in np.unique(pairs):
        by_node[int(n)] = order[bounds[n]:bounds[n + 1]]
    loose = []
    for a, b in pairs:
        da, db = by_node[int(a)], by_node[int(b)]
        if da.size == 0 or db.size == 0:
            continue   # a node without free DOFs (eliminated by a link or support)
        if K[da][:, db].count_nonzero() == 0:
            loose.append((int(a), int(b)))
    if loose:
        loose.sort(key=lambda ab: (model.node_ids[ab[0]], model.node_ids[ab[1]]))
        ids = np.asarray(model.node_ids)
        shown = ", ".join(f"{ids[a]}/{ids[b]} at {np.round(nodes[a], 6).tolist()}"
                          for a, b in loose[:8])
        more = f" and {len(loose) - 8} more" if len(loose) > 8 else ""
        _warn(model, f"{_who(model)}: {len(loose)} pair(s) of coincident nodes "
                     f"that no element, spring or link connects (a crack in the mesh): "
                     f"{shown}{more}; merge them if the structure is continuous there")


def _far_points(model, desc: Mapping) -> None:
    """Refuse ``[[points]]`` of an imported mesh farther than the local element size."""
    pts = desc.get("points")
    if not isinstance(pts, list):
        return
    for i, p in enumerate(pts):
        if not isinstance(p, Mapping) or not all(k in p for k in ("name", "x", "y", "z")):
            continue
        nodes = model.node_sets.get(str(p["name"]))
        if nodes is None or len(nodes) != 1:
            continue
        xyz = np.array([float(p[k]) for k in "xyz"])
        node = int(nodes[0])
        dist = float(np.linalg.norm(model.nodes[node] - xyz))
        tol = local_element_size(model, node)
        if dist > tol * (1 + 1e-9):
            lo, hi = model.nodes.min(axis=0), model.nodes.max(axis=0)
            raise ConfigError(
                f"points[{i}] ({p['name']!r}): {xyz.tolist()} m is {dist:.4g} m from the "
                f"nearest node {int(model.node_ids[node])} at "
                f"{np.round(model.nodes[node], 6).tolist()}, beyond the local element size "
                f"{tol:.4g} m: the point is off the structure (its nodes span "
                f"{np.round(lo, 6).tolist()} to {np.round(hi, 6).tolist()} m)")


def local_element_size(model, node: int) -> float:
    """Longest edge (m) of the elements around ``node`` (the local mesh size).

    Falls back to the distance to the nearest other node when the model lists no
    element connectivity.
    """
    edges = []
    for conn in model.elements.values():
        conn = np.asarray(conn)
        if conn.ndim != 2 or conn.size == 0:
            continue
        rows = conn[np.any(conn == node, axis=1)]
        if rows.size:
            edges.append(np.linalg.norm(model.nodes[rows] - model.nodes[np.roll(rows, -1,
                                                                                axis=1)],
                                        axis=-1).ravel())
    if edges:
        return float(np.max(np.concatenate(edges)))
    d = np.linalg.norm(model.nodes - model.nodes[node], axis=1)
    d = d[d > 0]
    return float(d.min()) if d.size else 0.0


def _coarse_mesh(model) -> None:
    """Warn when fewer than ELEMENTS_PER_HALF_WAVE elements span the structure."""
    for kind, conn in model.elements.items():
        conn = np.asarray(conn)
        if conn.ndim != 2 or len(conn) == 0:
            continue
        used = np.unique(conn)
        xyz = model.nodes[used]
        span = np.ptp(xyz, axis=0)
        if span.max() <= 0:
            continue
        # element extent along each axis: the largest of its nodes' spread
        el = np.ptp(model.nodes[conn], axis=1).max(axis=0)
        longest = int(np.argmax(span))
        axes = [longest] if conn.shape[1] == 2 else [a for a in range(3)
                                                      if span[a] >= 0.25 * span[longest]]
        for a in axes:
            if el[a] <= 0:
                continue
            across = span[a] / el[a]
            if across < ELEMENTS_PER_HALF_WAVE - 1e-9:
                _warn(model, f"{_who(model)}: {kind} mesh has {across:.3g} "
                             f"element(s) along {'xyz'[a]} over {span[a]:.4g} m (element "
                             f"{el[a]:.4g} m); a bending half-wave needs about "
                             f"{ELEMENTS_PER_HALF_WAVE}, so even the first frequencies "
                             "can be tens of per cent off: refine the mesh")
                return


def _units(model, desc: Mapping) -> None:
    """Warn about a geometry or material that looks like it is in the wrong unit."""
    span = _extent(model.nodes)
    if span > _SPAN_MM_M and 1e-3 * span <= _SPAN_MM_M:
        _warn(model, f"{_who(model)}: the structure spans {span:.4g} m; with SI "
                     "materials such a model has its first modes near 0 Hz. A geometry in "
                     f"millimetres? (likely factor 1e-3: {span * 1e-3:.4g} m); mvtk takes "
                     "lengths, thicknesses and coordinates in m")
    mats = desc.get("materials")
    if not isinstance(mats, Mapping):
        return
    for name, m in mats.items():
        if not isinstance(m, Mapping):
            continue
        for key in ("E", "E1", "E2", "G12"):
            v = m.get(key)
            if isinstance(v, int | float) and not isinstance(v, bool) and 0 < v < 5e5 \
                    and 1e8 <= v * 1e6 <= 2e12:
                _warn(model, f"materials.{name}.{key} = {v:g} Pa is far below any "
                             f"structural material: a value in MPa? (likely factor 1e6: "
                             f"{v * 1e6:.4g} Pa)")
        rho = m.get("rho")
        if isinstance(rho, int | float) and not isinstance(rho, bool) and 0 < rho < 20:
            factor = 1e3 if 300 <= rho * 1e3 <= 25000 else (
                1e12 if 300 <= rho * 1e12 <= 25000 else None)
            unit = {1e3: "g/cm^3", 1e12: "t/mm^3"}.get(factor)
            if factor is not None:
                _warn(model, f"materials.{name}.rho = {rho:g} kg/m^3 is far below any "
                             f"structural material: a value in {unit}? (likely factor "
                             f"{factor:g}: {rho * factor:.4g} kg/m^3)")


def check_model(model) -> Any:
    """Run the sanity checks on a built model; return it (see the module docstring).

    Raises
    ------
    ConfigError
        Duplicate point or patch names, duplicated elements, a point off the mesh.
    ParameterError
        Complex, non-finite or indefinite K or M.
    """
    desc = model.meta.get("structure") if isinstance(model.meta, Mapping) else None
    desc = desc if isinstance(desc, Mapping) else {}
    for table in ("points", "patches"):
        _duplicate_names(desc, table)
    check_matrices(model.K, model.M, where=_who(model))
    _duplicate_elements(model)
    _far_points(model, desc)
    _units(model, desc)
    _coarse_mesh(model)
    _coincident_unconnected(model)
    return model


# --------------------------------------------------------------- mode resolution
#: Elements per half-wave a cubic (Hermite) beam element needs for about 1 % accuracy.
BEAM_ELEMENTS_PER_HALF_WAVE = 2


def elements_per_half_wave(model, vectors: np.ndarray, rigid: np.ndarray) -> np.ndarray:
    """Elements per half-wave of each mode, relative to what its elements need.

    A nodal line of a mode crosses about one element per half-wave along it, so the
    share of elements inside which the mode changes sign is about one over the elements
    per half-wave (summed over the directions of a plate mode). The dominant translation
    of each mode is used; values below 1e-3 of its largest count as zero. Per element
    kind, the result is ``1 / (share x needed)`` with ``needed`` =
    ``ELEMENTS_PER_HALF_WAVE`` (4, linear shells) or ``BEAM_ELEMENTS_PER_HALF_WAVE`` (2,
    cubic beams); the smallest over the kinds is returned (below 1: too coarse).
    Rigid modes get ``inf``.

    Returns
    -------
    ndarray, shape (n_modes,)
    """
    n_modes = vectors.shape[1]
    out = np.full(n_modes, np.inf)
    conns = [np.asarray(c) for c in model.elements.values()
             if np.asarray(c).ndim == 2 and len(c)]
    if not conns:
        return out
    dn, dc = np.asarray(model.dof_node), np.asarray(model.dof_component)
    trans = dc < 3
    for k in range(n_modes):
        if rigid[k]:
            continue
        u = np.zeros((model.n_nodes, 3))
        u[dn[trans], dc[trans]] = np.real(vectors[trans, k])
        v = u[:, int(np.argmax((u ** 2).sum(axis=0)))]
        tol = 1e-3 * float(np.abs(v).max(initial=0.0))
        if tol <= 0:
            continue
        for conn in conns:
            need = BEAM_ELEMENTS_PER_HALF_WAVE if conn.shape[1] == 2 else \
                ELEMENTS_PER_HALF_WAVE
            # a quad's two edge directions apart (its two mesh directions), else the
            # element as a whole
            groups = ([[0, 1], [3, 2]], [[1, 2], [0, 3]]) if conn.shape[1] == 4 else \
                ([list(range(conn.shape[1]))],)
            for edges in groups:
                crossed = np.zeros(len(conn), dtype=bool)
                for e in edges:
                    ve = v[conn[:, e]]
                    crossed |= (ve.max(axis=1) > tol) & (ve.min(axis=1) < -tol)
                share = np.count_nonzero(crossed) / len(conn)
                if share > 0:
                    out[k] = min(out[k], 1.0 / (share * need))
    return out


def warn_under_resolved(model, vectors, fn_hz, rigid) -> list[int]:
    """Warn (ModelWarning) about modes the mesh resolves with too few elements per
    half-wave (:func:`elements_per_half_wave` below 1); return their 1-based numbers."""
    rel = elements_per_half_wave(model, vectors, rigid)
    bad = np.flatnonzero(rel < 1.0)
    if bad.size:
        shown = ", ".join(f"{k + 1} ({fn_hz[k]:.4g} Hz)" for k in bad[:6]) + (
            f" and {bad.size - 6} more" if bad.size > 6 else "")
        warnings.warn(
            f"{_who(model)}: mode(s) {shown} have fewer elements per half-wave than their "
            f"elements need (about {ELEMENTS_PER_HALF_WAVE} for shells, "
            f"{BEAM_ELEMENTS_PER_HALF_WAVE} for beams), so these frequencies can be tens "
            "of per cent off: refine the mesh or ask for fewer modes",
            ModelWarning, stacklevel=3)
    return [int(k) + 1 for k in bad]
