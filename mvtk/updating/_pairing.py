"""Pairing of measured targets with model modes: MAC, Hungarian assignment, mode types."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._mac import mac_columns
from ..errors import DimensionError, ParameterError
from ..fe._model import DOF_NAMES, FEModel
from ._targets import FrequencyTarget

__all__ = ["mac", "classify_modes", "pair_modes", "pair_by_frequency", "Pairing"]


def mac(phi_a: np.ndarray, phi_b: np.ndarray) -> np.ndarray:
    """Modal assurance criterion between two sets of real shapes.

    ``MAC_ij = (a_i . b_j)^2 / ((a_i . a_i)(b_j . b_j))`` (Allemang & Brown 1982).

    Parameters
    ----------
    phi_a : ndarray, shape (n_sensors,) or (n_sensors, n_a)
    phi_b : ndarray, shape (n_sensors,) or (n_sensors, n_b)

    Returns
    -------
    ndarray, shape (n_a, n_b)
        Values in [0, 1]; 0 where a shape is identically zero.

    Examples
    --------
    Shapes in columns; a scaled copy gives 1:

    >>> mac(np.array([1.0, 2.0, 3.0]), np.array([-2.0, -4.0, -6.0]))
    array([[1.]])
    """
    a = np.asarray(phi_a, dtype=float)
    b = np.asarray(phi_b, dtype=float)
    a = a[:, None] if a.ndim == 1 else a
    b = b[:, None] if b.ndim == 1 else b
    if a.ndim != 2 or b.ndim != 2 or a.shape[0] != b.shape[0]:
        raise DimensionError(
            f"MAC needs shapes over the same sensors, got {a.shape} and {b.shape}"
        )
    return mac_columns(a, b)


def classify_modes(model: FEModel, vectors: np.ndarray) -> list[str]:
    """Label each mode ``"bending"``, ``"torsion"``, ``"lateral"``, ``"axial"`` or ``"in-plane"``.

    Rules (documented heuristics, assuming the structure's length along x, width along y
    and thickness/out-of-plane direction z):

    - Plate-like models (nodes spread in y): modes whose kinetic-energy share in uz is
      below one half are ``"in-plane"``. Otherwise the uz shape is split into parts
      symmetric and antisymmetric about the mid-width line ``y = (ymin + ymax)/2``
      (each node paired with its mirror node); an antisymmetric energy fraction above
      one half means ``"torsion"``, else ``"bending"``.
    - Line models (beams along x): the DOF component with the largest kinetic-energy
      share decides: uz or ry -> ``"bending"``, uy or rz -> ``"lateral"``, rx ->
      ``"torsion"``, ux -> ``"axial"``.

    Energy shares use ``phi_i (M phi)_i`` summed per component (mass-normalised shapes).

    Parameters
    ----------
    model : FEModel
    vectors : ndarray, shape (n_dof, n_modes)

    Returns
    -------
    list of str

    Examples
    --------
    The lowest modes of a cantilever strip 20 mm wide: two flapwise bending modes, then
    bending in the plane of the width (``"lateral"``):

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(IsotropicMaterial("steel", 2.1e11, 0.3,
    ...                                                          7850.0), 2e-3)])
    >>> classify_modes(beam, modal_analysis(beam, 3).shapes)
    ['bending', 'bending', 'lateral']
    """
    v = np.asarray(vectors, dtype=float)
    if v.ndim == 1:
        v = v[:, None]
    if v.shape[0] != model.n_dof:
        raise DimensionError(f"expected {model.n_dof} rows of mode shapes, got {v.shape[0]}")
    energy = v * (model.M @ v)
    share = np.zeros((6, v.shape[1]))
    for c in range(6):
        sel = model.dof_component == c
        if sel.any():
            share[c] = energy[sel].sum(axis=0)
    share /= np.where(share.sum(axis=0) > 0, share.sum(axis=0), 1.0)
    xyz = model.nodes
    extent = np.ptp(xyz, axis=0) if len(xyz) else np.zeros(3)
    plate = extent[1] > 1e-6 * max(extent[0], extent[1], 1e-300)
    uz = model.dof_component == DOF_NAMES.index("uz")
    if not plate or not uz.any():
        names = {0: "axial", 1: "lateral", 2: "bending", 3: "torsion", 4: "bending",
                 5: "lateral"}
        return [names[int(np.argmax(share[:, j]))] for j in range(v.shape[1])]
    from scipy.spatial import cKDTree

    nodes_uz = model.dof_node[uz]
    pts = xyz[nodes_uz]
    ymid = 0.5 * (xyz[:, 1].min() + xyz[:, 1].max())
    mirror = pts.copy()
    mirror[:, 1] = 2 * ymid - mirror[:, 1]
    tree = cKDTree(pts)
    dist, partner = tree.query(mirror)
    tol = 1e-6 * max(float(extent.max()), 1e-300)
    ok = dist <= tol
    labels = []
    for j in range(v.shape[1]):
        if share[2, j] < 0.5:
            labels.append("in-plane")
            continue
        u = v[uz, j]
        um = u[partner]
        sym = 0.5 * (u + um)[ok]
        anti = 0.5 * (u - um)[ok]
        e_s, e_a = float(sym @ sym), float(anti @ anti)
        labels.append("torsion" if e_a > e_s else "bending")
    return labels


@dataclass(frozen=True)
class Pairing:
    """Result of pairing targets with model modes.

    Attributes
    ----------
    modes : ndarray of int, shape (n_targets,)
        0-based model mode index paired with each target.
    mac : ndarray, shape (n_targets,)
        MAC of each pair (NaN for targets without a measured shape).
    method : tuple of str
        How each target was paired: ``"fixed"``, ``"mac"``, ``"frequency"`` or
        ``"order"``.

    Examples
    --------
    Returned by :func:`pair_modes`:

    >>> p = pair_modes([FrequencyTarget(18.0, mode=2)], np.array([18.5, 116.3]))
    >>> p.modes, p.method
    (array([1]), ('fixed',))
    """

    modes: np.ndarray
    mac: np.ndarray
    method: tuple[str, ...]


def _sensor_rows(model: FEModel, target: FrequencyTarget, i: int) -> np.ndarray:
    try:
        return np.array([model.dof_index(n, c) for n, c in target.sensors], dtype=np.int64)
    except ParameterError as err:
        raise ParameterError(f"target {target.label or i + 1}: sensor DOF: {err}") from err


def target_rows(model: FEModel, vectors: np.ndarray, target: FrequencyTarget, i: int):
    """Model shapes at the sensors of a shape-bearing target, shape (n_sensors, n_modes)."""
    C = getattr(target, "observation", None)
    if C is not None:
        if C.shape[1] != model.n_dof:
            raise DimensionError(
                f"target {target.label or i + 1}: observation has {C.shape[1]} columns but "
                f"the model has {model.n_dof} free DOFs (map the sensors on this mesh)"
            )
        return np.asarray(C @ vectors)
    return vectors[_sensor_rows(model, target, i)]


def target_mac(model: FEModel, vectors: np.ndarray, targets: Sequence[FrequencyTarget]):
    """MAC of each shape-bearing target against every model mode, shape (n_targets, n_modes).

    Rows of targets without a shape are NaN.

    Examples
    --------
    A target carrying the second mode's shape at three nodes has MAC 1 with mode 2; a
    target without a shape gives NaN:

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(IsotropicMaterial("steel", 2.1e11, 0.3,
    ...                                                          7850.0), 2e-3)])
    >>> modes = modal_analysis(beam, 2)
    >>> nodes = [7, 14, 20]
    >>> values = [modes.shapes[beam.dof_index(n, "uz"), 1] for n in nodes]
    >>> targets = [FrequencyTarget(116.0, shape={"nodes": nodes, "components": "uz",
    ...                                          "values": values}), FrequencyTarget(18.0)]
    >>> np.round(target_mac(beam, modes.shapes, targets), 3)
    array([[0.24, 1.  ],
           [ nan,  nan]])
    """
    out = np.full((len(targets), vectors.shape[1]), np.nan)
    for i, t in enumerate(targets):
        if t.has_shape:
            out[i] = mac(t.shape_values, target_rows(model, vectors, t, i))[0]
    return out


def pair_by_frequency(
    target_hz: Sequence[float],
    model_hz: Sequence[float],
    *,
    target_kinds: Sequence[str | None] | None = None,
    model_kinds: Sequence[str] | None = None,
    exclude: Sequence[int] = (),
    max_rel: float | None = None,
) -> np.ndarray:
    """Pair measured frequencies with distinct model modes by frequency (one-to-one).

    The Hungarian algorithm (:func:`scipy.optimize.linear_sum_assignment`) minimises the
    sum of ``|ln(f_model / f_target)|`` over the pairs, so a measurement that missed a
    mode (a sensor on its nodal line) is paired with the model mode nearest in frequency,
    not with the next one in order. A target with a kind is only paired with model
    modes of that kind (when ``model_kinds`` are given).

    Parameters
    ----------
    target_hz : sequence of float
        Measured natural frequencies (Hz), any order.
    model_hz : sequence of float
        Model natural frequencies (Hz), ascending (mode ``k`` is index ``k``).
    target_kinds : sequence of str or None, optional
        Mode type of each target (None: any).
    model_kinds : sequence of str, optional
        Mode type of each model mode (:func:`classify_modes`).
    exclude : sequence of int
        0-based model modes that are taken already.
    max_rel : float, optional
        Largest accepted ``|f_model / f_target - 1|``: a target farther from every free
        mode is left unpaired (-1).

    Returns
    -------
    ndarray of int, shape (n_targets,)
        0-based model mode of each target, -1 when unpaired (more targets than free
        modes of their kind, or beyond ``max_rel``).

    Examples
    --------
    A test that missed the second mode: 185 Hz pairs with model mode 2 (0-based), not 1:

    >>> pair_by_frequency([18.0, 185.0], [18.5, 116.3, 185.0])
    array([0, 2])
    """
    from scipy.optimize import linear_sum_assignment

    ft = np.asarray(target_hz, dtype=float).reshape(-1)
    fm = np.asarray(model_hz, dtype=float).reshape(-1)
    out = np.full(ft.size, -1, dtype=np.int64)
    free = [m for m in range(fm.size) if m not in set(exclude) and fm[m] > 0]
    if not ft.size or not free:
        return out
    with np.errstate(divide="ignore", invalid="ignore"):
        cost = np.abs(np.log(fm[free][None, :] / ft[:, None]))
    big = 1e6
    cost = np.where(np.isfinite(cost), cost, big)
    if target_kinds is not None and model_kinds is not None:
        for i, k in enumerate(target_kinds):
            if k is not None:
                cost[i, [model_kinds[m] != k for m in free]] = big
    rows, cols = linear_sum_assignment(cost)
    for r, c in zip(rows, cols):
        if cost[r, c] >= big:
            continue
        if max_rel is not None and abs(fm[free[c]] / ft[r] - 1.0) > max_rel:
            continue
        out[r] = free[c]
    return out


def pair_modes(
    targets: Sequence[FrequencyTarget],
    fn_hz: np.ndarray,
    mac_matrix: np.ndarray | None = None,
    kinds: Sequence[str] | None = None,
    rest: str = "order",
) -> Pairing:
    """Pair each target with a distinct model mode.

    Order of rules: (1) targets with an explicit ``mode`` take that mode; (2) targets
    with a measured shape are assigned one-to-one by the Hungarian algorithm
    (:func:`scipy.optimize.linear_sum_assignment`) on ``1 - MAC`` among the remaining
    modes; (3) the other targets, with ``rest="order"``, in ascending measured frequency,
    take the lowest remaining mode, restricted to modes of the same ``kind`` when the
    target has a kind and ``kinds`` (model mode labels) are given; with
    ``rest="frequency"`` they are paired one-to-one with the remaining modes nearest in
    frequency (:func:`pair_by_frequency`, kinds respected), which is right when the
    measurement may have missed modes. Order pairing is the one to use *during* an
    update (the pairing must not jump between evaluations); frequency pairing is the
    one to fix the modes on the nominal model beforehand.

    Parameters
    ----------
    targets : sequence of FrequencyTarget
    fn_hz : ndarray, shape (n_modes,)
        Model natural frequencies (ascending).
    mac_matrix : ndarray, shape (n_targets, n_modes), optional
        From :func:`target_mac`; required when targets carry shapes.
    kinds : sequence of str, optional
        Model mode labels (see :func:`classify_modes`).

    Raises
    ------
    ParameterError
        Not enough model modes, duplicated/out-of-range fixed modes, or no model mode of
        a requested kind left.

    Examples
    --------
    Targets without shapes take the model modes in order:

    >>> p = pair_modes([FrequencyTarget(18.0), FrequencyTarget(116.0)],
    ...                np.array([18.5, 116.3, 185.0]))
    >>> p.modes, p.method
    (array([0, 1]), ('order', 'order'))
    """
    from scipy.optimize import linear_sum_assignment

    n_t, n_m = len(targets), len(fn_hz)
    if n_t > n_m:
        raise ParameterError(f"{n_t} targets need at least as many model modes, got {n_m}")
    modes = np.full(n_t, -1, dtype=np.int64)
    method = [""] * n_t
    used: set[int] = set()
    for i, t in enumerate(targets):
        if t.mode is not None:
            m = t.mode - 1
            if m >= n_m:
                raise ParameterError(
                    f"target {t.label or i + 1} asks for model mode {t.mode} but only "
                    f"{n_m} modes are computed (raise n_modes)"
                )
            if m in used:
                raise ParameterError(f"model mode {t.mode} is requested by two targets")
            modes[i], method[i] = m, "fixed"
            used.add(m)
    shaped = [i for i, t in enumerate(targets) if modes[i] < 0 and t.has_shape]
    if shaped:
        if mac_matrix is None:
            raise ParameterError("targets carry shapes but no MAC matrix was given")
        free = [m for m in range(n_m) if m not in used]
        cost = 1.0 - mac_matrix[np.ix_(shaped, free)]
        rows, cols = linear_sum_assignment(cost)
        for r, c in zip(rows, cols):
            modes[shaped[r]], method[shaped[r]] = free[c], "mac"
            used.add(free[c])
    if rest not in ("order", "frequency"):
        raise ParameterError(f"rest must be 'order' or 'frequency', got {rest!r}")
    left = sorted((i for i in range(n_t) if modes[i] < 0), key=lambda i: targets[i].fn_hz)
    if rest == "frequency" and left:
        got = pair_by_frequency([targets[i].fn_hz for i in left], fn_hz,
                                target_kinds=[targets[i].kind for i in left],
                                model_kinds=kinds, exclude=sorted(used))
        for i, m in zip(left, got):
            if m >= 0:
                modes[i], method[i] = int(m), "frequency"
                used.add(int(m))
        left = [i for i in left if modes[i] < 0]
    for i in left:
        t = targets[i]
        want = t.kind if (t.kind is not None and kinds is not None) else None
        cands = [m for m in range(n_m) if m not in used and (want is None or kinds[m] == want)]
        if not cands:
            found = "" if kinds is None else f"; model mode kinds: {list(kinds)}"
            raise ParameterError(
                f"target {t.label or i + 1} ({t.fn_hz:g} Hz"
                f"{', ' + t.kind if t.kind else ''}) has no free model mode to pair with"
                f"{found} (raise n_modes)"
            )
        modes[i], method[i] = cands[0], "order"
        used.add(cands[0])
    pm = np.full(n_t, np.nan)
    if mac_matrix is not None:
        has = ~np.isnan(mac_matrix[:, 0]) if n_m else np.zeros(n_t, bool)
        pm[has] = mac_matrix[np.flatnonzero(has), modes[has]]
    return Pairing(modes=modes, mac=pm, method=tuple(method))
