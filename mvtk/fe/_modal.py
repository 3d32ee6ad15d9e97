"""Modal analysis and static solution of an :class:`FEModel`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import DimensionError, ParameterError
from ._model import FEModel
from ._solvers import eigsh_lowest, factorize

__all__ = ["ModalResult", "modal_analysis", "static_solve", "mode_type"]


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
        ``"rigid"``, ``"bending"``, ``"torsion"`` or ``"in-plane"`` (see
        :func:`mode_type`).
    """

    fn_hz: np.ndarray
    omega2: np.ndarray
    shapes: np.ndarray
    rigid: np.ndarray
    mode_type: tuple[str, ...]

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
        return self.to_dataframe().to_html(index=False)


def _mirror_map(nodes: np.ndarray) -> np.ndarray | None:
    """Index of each node's mirror image about the plane y = mid-width (None if absent)."""
    y = nodes[:, 1]
    mid = 0.5 * (y.min() + y.max())
    scale = max(float(np.ptp(nodes[:, :2])), 1e-300)
    key = np.round(nodes[:, :2] / (1e-7 * scale)).astype(np.int64)
    mkey = np.round(np.column_stack([nodes[:, 0], 2 * mid - y]) / (1e-7 * scale)).astype(
        np.int64)
    lookup = {tuple(k): i for i, k in enumerate(key)}
    out = np.empty(len(nodes), dtype=np.int64)
    for i, k in enumerate(mkey):
        j = lookup.get(tuple(k))
        if j is None:
            return None
        out[i] = j
    return out


def mode_type(model: FEModel, shape: np.ndarray, mirror: np.ndarray | None = None) -> str:
    """Label an elastic mode shape of a plate or beam model lying along x in the x-y plane.

    The modal kinetic energy ``phi_i (M phi)_i`` is summed per DOF component.
    ``"in-plane"`` when ux and uy carry more of it than uz. Otherwise, for a plate (nodes
    spread in y) ``"torsion"`` when the uz field is mainly antisymmetric about the
    mid-width line y = (y_min + y_max)/2, else ``"bending"`` (without a mirror-symmetric
    node layout: ``"torsion"`` when the rotations rx outweigh ry); for a beam (all nodes on
    a line) ``"torsion"`` when rx carries more energy than uz. A heuristic for strips and
    plates clamped on an x edge; it does not distinguish bending directions.
    """
    phi = np.asarray(shape, dtype=float)
    e = phi * (model.M @ phi)
    comp = np.bincount(model.dof_component, weights=e, minlength=6)
    if comp[0] + comp[1] > comp[2]:
        return "in-plane"
    if np.ptp(model.nodes[:, 1]) == 0:
        return "torsion" if comp[3] > comp[2] else "bending"
    if mirror is None:
        mirror = _mirror_map(model.nodes)
    u = model.expand(phi)
    if mirror is None:
        # no mirror-symmetric node layout: twist (rx, slope across the width) against
        # bending rotation (ry, slope along x)
        return "torsion" if np.sum(u[:, 3] ** 2) > np.sum(u[:, 4] ** 2) else "bending"
    w = u[:, 2]
    anti = float(np.sum((w - w[mirror]) ** 2))
    sym = float(np.sum((w + w[mirror]) ** 2))
    return "torsion" if anti > sym else "bending"


def _smooth_trial_scale(model: FEModel) -> float:
    """Smallest Rayleigh quotient (rad/s)^2 of smooth quadratic bending trial fields.

    Fields ``u_d = s_a^2`` with the Kirchhoff-consistent rotation
    ``theta = (e_a x e_d) 2 s_a`` for every pair of axes (a, d), with ``s_a`` measured
    from the minimum, the centroid and the maximum of coordinate a (so that a field
    vanishes on a support along a coordinate line). Within a small factor of the first
    elastic eigenvalue of a free or partly supported structure; used to place the
    negative shift of a singular problem.
    """
    node, comp = model.dof_node, model.dof_component
    xyz = model.nodes
    best = np.inf
    for a in range(3):
        if np.ptp(xyz[:, a]) == 0:
            continue
        for origin in (xyz[:, a].min(), xyz[:, a].mean(), xyz[:, a].max()):
            s_a = xyz[:, a] - origin
            for d in range(3):
                if d == a:
                    continue
                full = np.zeros((model.n_nodes, 6))
                full[:, d] = s_a**2
                axis = np.cross(np.eye(3)[a], np.eye(3)[d])
                full[:, 3:] = 2 * s_a[:, None] * axis[None, :]
                x = full[node, comp]
                mm = float(x @ (model.M @ x))
                kk = float(x @ (model.K @ x))
                if mm > 0 and kk > 0:
                    best = min(best, kk / mm)
    return best


def _lowest_modes(model: FEModel, n: int, sigma: float | None):
    """Lowest eigenpairs by :func:`mvtk.fe.eigsh_lowest` (one factorisation).

    With ``sigma=None`` the shift is 0 when K is non-singular; otherwise it is -1 % of
    :func:`_smooth_trial_scale`, a model-aware estimate of the first elastic eigenvalue.
    """
    def singular_shift():  # evaluated by eigsh_lowest only when K is singular
        return -1e-2 * _smooth_trial_scale(model)

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
        Shift in (rad/s)^2. Default: K is factorised once; if it is positive definite
        (all LU pivots > 1e-12 of the largest) that factorisation is reused with shift 0,
        otherwise (rigid-body modes) the shift is -1 % of the Rayleigh quotient of a smooth
        quadratic bending field, a few times below the first elastic eigenvalue.
    rigid_tol_hz : float, optional
        Modes below this frequency are rigid-body modes. Default:
        ``|omega2| < 1e-8 * max(|omega2|)``, and at least below 1e-3 Hz.

    Notes
    -----
    Lanczos shift-invert (ARPACK) on ``(K - sigma M)^-1 M``; it converges quickly only
    when the shift is close to the wanted eigenvalues compared with the rest of the
    spectrum, hence the shift choice above (a shift from matrix diagonals can be 1e9
    times too far for thin plates).

    Returns
    -------
    ModalResult
    """
    if not isinstance(model, FEModel):
        raise ParameterError(f"model must be an FEModel, got {type(model).__name__}")
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)):
        raise ParameterError(f"n_modes must be an integer, got {n_modes!r}")
    if not 1 <= n_modes < model.n_dof:
        raise ParameterError(f"n_modes must be in 1..{model.n_dof - 1}, got {n_modes}")
    sol = _lowest_modes(model, int(n_modes), sigma)
    w2 = sol.omega2
    if rigid_tol_hz is None:
        scale = float(np.max(np.abs(w2))) if w2.size else 0.0
        thresh = max(1e-8 * scale, (2 * np.pi * 1e-3) ** 2)
    else:
        thresh = (2 * np.pi * float(rigid_tol_hz)) ** 2
    rigid = np.abs(w2) < thresh
    fn = np.where(rigid, 0.0, np.sqrt(np.abs(w2)) / (2 * np.pi))
    mirror = _mirror_map(model.nodes)
    labels = tuple(
        "rigid" if r else mode_type(model, sol.vectors[:, i], mirror)
        for i, r in enumerate(rigid)
    )
    return ModalResult(fn_hz=fn, omega2=w2, shapes=sol.vectors, rigid=rigid, mode_type=labels)


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
