"""Expansion of measured shapes to all FE DOFs: SEREP and regularised least squares.

Both work in the basis of FE mode shapes ``Phi`` (n_dof x m) seen through the
observation matrix ``C`` of the sensor mapping: the measured shape ``y`` is modelled as
``C Phi q`` and the expanded shape is ``Phi q``.

- SEREP (O'Callahan, Avitabile & Riemer, Proc. 7th IMAC, 1989): ``q = (C Phi)^+ y``;
  with m <= n_sensors it is the least-squares fit in the span of the retained modes, and
  FE shapes sampled at the sensors come back exactly.
- Regularised least squares: more basis modes than a plain fit can carry
  (m may exceed the number of sensors), with a Tikhonov penalty
  ``||C Phi q - y||^2 + lambda^2 ||W q||^2``, ``W = diag(omega_r / omega_1)`` (stiff,
  high-frequency modes cost more: the expansion prefers smooth, low-strain-energy
  shapes). ``lambda`` is chosen from the data by generalised cross-validation (Golub,
  Heath & Wahba, Technometrics 21(2), 1979) or given.

The residual ``||C Phi q - y|| / ||y||`` is reported per mode: what of the measurement
the expanded shape does not reproduce (noise, or a shape outside the FE basis).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from ..errors import DimensionError, ParameterError
from ._fe_adapter import fe_node_ids, modal_arrays
from ._mapping import DofMapping
from ._metrics import _as_shapes

__all__ = ["ExpansionResult", "expand_serep", "expand_lsq"]


@dataclass(frozen=True, eq=False)
class ExpansionResult:
    """Expanded shapes and their fit to the measurement.

    Attributes
    ----------
    shapes : xarray.DataArray ("mode", "dof")
        Expanded shapes over the FE model's free DOFs (FE labels).
    coefficients : ndarray (n_modes_test, m)
        Modal coordinates ``q`` of each expanded shape in the FE basis.
    residual : ndarray (n_modes_test,)
        ``||C Phi q - y|| / ||y||`` per test mode.
    smoothing : float
        ``lambda`` (0 for SEREP).
    method : str
    gcv : ndarray or None
        ``(lambda, GCV)`` grid searched (regularised method).

    Examples
    --------
    Returned by :func:`expand_serep` and :func:`expand_lsq`:

    >>> from mvtk.correlation import correlate, read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> fe = modal_analysis(beam, 2)
    >>> res = correlate(geo, beam, fe)
    >>> out = expand_serep(res.fe, beam, fe, res.mapping)
    >>> out.method, out.coefficients.shape, out.smoothing
    ('serep', (2, 2), 0.0)
    """

    shapes: xr.DataArray
    coefficients: np.ndarray
    residual: np.ndarray
    smoothing: float
    method: str
    gcv: np.ndarray | None = None

    def to_dataframe(self):
        """One row per test mode: residual, smoothing and method."""
        import pandas as pd

        return pd.DataFrame({"mode": self.shapes["mode"].values, "residual": self.residual,
                             "smoothing": self.smoothing, "method": self.method})


def _inputs(test: Any, model, modal, mapping: DofMapping, modes):
    if not isinstance(mapping, DofMapping):
        raise ParameterError(f"mapping must be a DofMapping (map_sensors), got "
                             f"{type(mapping).__name__}")
    T = _as_shapes(test, "test shapes")
    labels = [str(v) for v in T["dof"].values]
    if labels != list(mapping.dof):
        rows = {d: i for i, d in enumerate(mapping.dof)}
        missing = [lab for lab in labels if lab not in rows]
        if missing:
            raise DimensionError(f"test DOFs {missing[:6]} are not in the sensor mapping")
        C = mapping.matrix[[rows[lab] for lab in labels]]
    else:
        C = mapping.matrix
    Phi, fn = modal_arrays(modal)
    if Phi.shape[0] != mapping.n_fe_dof or Phi.shape[0] != model.n_dof:
        raise DimensionError(f"FE shapes have {Phi.shape[0]} rows; model and mapping have "
                             f"{model.n_dof} and {mapping.n_fe_dof} free DOFs")
    if modes is not None:
        idx = [int(k) - 1 for k in modes]
        Phi, fn = Phi[:, idx], fn[idx]
    return T, C, np.asarray(Phi, dtype=float), fn


def _result(T, model, Phi, q, y, A, lam, method, gcv=None) -> ExpansionResult:
    x = q @ Phi.T  # (n_test, n_dof)
    r = np.linalg.norm(q @ A.T - y, axis=1) / np.linalg.norm(y, axis=1)
    ids = fe_node_ids(model)
    from ._fe_adapter import FE_DIRECTIONS

    dirs = [FE_DIRECTIONS[c] for c in model.dof_component]
    nodes = ids[model.dof_node]
    coords = {"mode": T["mode"].values, "dof": [f"{n}{d}" for n, d in zip(nodes, dirs)],
              "node": ("dof", nodes), "direction": ("dof", dirs)}
    for c in ("fn_hz", "zeta"):
        if c in T.coords:
            coords[c] = ("mode", T[c].values)
    da = xr.DataArray(x, dims=("mode", "dof"), coords=coords,
                      attrs={**T.attrs, "expansion": method})
    return ExpansionResult(da, q, r, float(lam), method, gcv)


def expand_serep(test: Any, model, modal, mapping: DofMapping, *,
                 modes=None) -> ExpansionResult:
    """SEREP expansion of test shapes to all FE DOFs.

    Parameters
    ----------
    test : DataArray ("mode", "dof")
        Measured shapes on the mapped sensor DOFs.
    model : FEModel
    modal : ModalResult or EigenSolution
        FE shapes of ``model`` (the basis).
    mapping : DofMapping
        From :func:`map_sensors` on the same model.
    modes : sequence of int, optional
        1-based FE modes of the basis (default all; keep m <= n_sensors for a unique
        fit, else the minimum-norm solution is returned).

    Returns
    -------
    ExpansionResult

    Examples
    --------
    Shapes measured at three sensors of a steel cantilever, expanded to its 72 free DOFs
    (here the FE shapes themselves scaled by -2: the fit is exact):

    >>> from mvtk.correlation import correlate, read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> fe = modal_analysis(beam, 2)
    >>> res = correlate(geo, beam, fe)
    >>> out = expand_serep(-2.0 * res.fe, beam, fe, res.mapping)
    >>> out.shapes.shape, np.round(out.residual, 9)
    ((2, 72), array([0., 0.]))
    """
    T, C, Phi, _ = _inputs(test, model, modal, mapping, modes)
    A = np.asarray(C @ Phi)
    y = T.values
    q = (np.linalg.pinv(A) @ y.T).T
    return _result(T, model, Phi, q, y, A, 0.0, "serep")


def expand_lsq(test: Any, model, modal, mapping: DofMapping, *, modes=None,
               smoothing: float | None = None, n_grid: int = 60) -> ExpansionResult:
    """Tikhonov-regularised least-squares expansion with the smoothing from GCV.

    Minimises ``||C Phi q - y||^2 + lambda^2 ||W q||^2`` with
    ``W = diag(omega_r / omega_1)`` for each test mode. ``lambda`` minimises
    ``GCV(lambda) = ||r||^2 / trace(I - H)^2`` summed over the test modes (H the
    influence matrix) on a log grid spanning the singular values of ``C Phi W^-1``,
    unless ``smoothing`` is given.

    Parameters
    ----------
    test, model, modal, mapping, modes
        As :func:`expand_serep`; the basis may hold more modes than sensors.
    smoothing : float, optional
        Fixed ``lambda`` (dimensionless, in the units of the scaled problem).
    n_grid : int
        Number of grid values for the GCV search.

    Returns
    -------
    ExpansionResult
        ``gcv`` holds the searched ``(lambda, GCV)`` pairs.

    Examples
    --------
    Same data as :func:`expand_serep`; the smoothing is chosen by GCV and the fit stays
    within 0.1 %:

    >>> from mvtk.correlation import correlate, read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> fe = modal_analysis(beam, 2)
    >>> res = correlate(geo, beam, fe)
    >>> out = expand_lsq(-2.0 * res.fe, beam, fe, res.mapping)
    >>> out.method, bool(np.all(out.residual < 1e-3))
    ('lsq-gcv', True)
    """
    T, C, Phi, fn = _inputs(test, model, modal, mapping, modes)
    A = np.asarray(C @ Phi)
    y = T.values
    if np.any(fn <= 0):
        raise ParameterError("the regularised expansion needs elastic FE modes (fn > 0); "
                             "drop rigid-body modes with modes=")
    w = fn / fn[0]
    As = A / w[None, :]  # standard form: p = W q
    U, s, Vt = np.linalg.svd(As, full_matrices=False)
    b = U.T @ y.T  # (k, n_test)
    n = As.shape[0]
    resid_perp = np.sum(y**2) - np.sum(b**2)  # part of y outside range(As)

    def gcv_of(lam):
        f = s**2 / (s**2 + lam**2)
        r2 = np.sum(((1 - f)[:, None] * b) ** 2) + max(resid_perp, 0.0)
        dof = n - np.sum(f)
        return r2 / max(dof, 1e-300) ** 2

    grid = None
    if smoothing is None:
        lams = np.logspace(np.log10(s[0]) + 1, np.log10(max(s[-1], 1e-8 * s[0])) - 2, n_grid)
        g = np.array([gcv_of(lam) for lam in lams])
        lam = float(lams[int(np.argmin(g))])
        grid = np.column_stack([lams, g])
    else:
        if not (np.isfinite(smoothing) and smoothing >= 0):
            raise ParameterError(f"smoothing must be a finite number >= 0, got {smoothing!r}")
        lam = float(smoothing)
    f = s / (s**2 + lam**2)
    p = (Vt.T @ (f[:, None] * b)).T
    q = p / w[None, :]
    return _result(T, model, Phi, q, y, A, lam, "lsq-gcv" if smoothing is None else "lsq",
                   grid)
