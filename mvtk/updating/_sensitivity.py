"""Eigenvalue sensitivities from finite differences of the assembled matrices.

For a mass-normalised mode ``phi`` of ``K phi = omega^2 M phi`` (distinct eigenvalue),

    d(omega^2)/dp = phi' (dK/dp - omega^2 dM/dp) phi        (Fox & Kapoor 1968)

``dK/dp`` and ``dM/dp`` are finite differences of the matrices returned by the model
builder, no extra eigen solve. Forward differences (one extra build per parameter) are
exact for parameters on which the matrices depend linearly (moduli, densities, spring
stiffnesses) up to round-off. For geometry they are only first-order accurate and
the error is amplified by the cancellation inside ``phi' dK phi`` (element terms in
1/le^3 and 1/le nearly cancel): on a 20-element beam a length derivative with a 1e-6
forward step is 6e-4 off. Central differences (two builds per parameter, the default,
step 1e-4) make the truncation error second order, and the larger step keeps the
round-off of ``K(p + h) - K(p - h)`` small where a small term (a clamp spring) sits on
a large stiffness entry.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import DimensionError, ParameterError
from ..fe._model import FEModel
from ..fe._solvers import eigsh_lowest
from ._parameters import Parameter, with_values

__all__ = ["eigen_sensitivity", "Sensitivity", "d_omega2"]


def d_omega2(omega2: np.ndarray, vectors: np.ndarray, dK, dM) -> np.ndarray:
    """``phi_i' (dK - omega_i^2 dM) phi_i`` for every column of ``vectors``.

    Parameters
    ----------
    omega2 : ndarray, shape (n,)
        Eigenvalues in (rad/s)^2.
    vectors : ndarray, shape (n_dof, n)
        Mass-normalised eigenvectors.
    dK, dM : sparse or dense matrix, shape (n_dof, n_dof)
        Derivatives of stiffness and mass with respect to one parameter.

    Returns
    -------
    ndarray, shape (n,)
        d(omega^2)/dp in (rad/s)^2 per parameter unit.
    """
    kk = np.einsum("ij,ij->j", vectors, dK @ vectors)
    mm = np.einsum("ij,ij->j", vectors, dM @ vectors)
    return kk - omega2 * mm


def check_difference(difference: str) -> None:
    """Raise ParameterError for an unknown difference scheme."""
    if difference not in ("central", "forward"):
        raise ParameterError(
            f"difference must be 'central' or 'forward', got {difference!r}"
        )


def matrix_derivative(model: FEModel, built: Sequence[FEModel], h: float):
    """dK/dp, dM/dp from ``[model(p + h)]`` (forward) or ``[model(p + h), model(p - h)]``."""
    if len(built) == 2:
        return (built[0].K - built[1].K) / (2 * h), (built[0].M - built[1].M) / (2 * h)
    return (built[0].K - model.K) / h, (built[0].M - model.M) / h


def same_dofs(a: FEModel, b: FEModel) -> bool:
    """True when two models share the free-DOF map (so their matrices can be subtracted)."""
    return (
        a.n_dof == b.n_dof
        and np.array_equal(a.dof_node, b.dof_node)
        and np.array_equal(a.dof_component, b.dof_component)
    )


def check_model(model: Any, where: str) -> FEModel:
    """Raise a clear error when a builder did not return an FEModel."""
    if not isinstance(model, FEModel):
        raise ParameterError(
            f"the model builder must return an mvtk.fe.FEModel, got {type(model).__name__} "
            f"({where})"
        )
    return model


@dataclass(frozen=True)
class Sensitivity:
    """Natural frequencies of a model and their derivatives with respect to parameters.

    Attributes
    ----------
    paths : tuple of str
        Parameter paths (columns).
    values : ndarray, shape (n_params,)
        Parameter values at which the derivatives hold.
    fn_hz : ndarray, shape (n_modes,)
        Natural frequencies in Hz.
    d_omega2 : ndarray, shape (n_modes, n_params)
        d(omega^2)/dp in (rad/s)^2 per parameter unit.
    d_fn_hz : ndarray, shape (n_modes, n_params)
        df/dp in Hz per parameter unit.
    normalised : ndarray, shape (n_modes, n_params)
        (p / f) df/dp: relative frequency change per relative parameter change.

    Examples
    --------
    Returned by :func:`eigen_sensitivity`: ``d_fn_hz`` in Hz per parameter unit; for
    ``f ~ sqrt(E)``, ``df/dE = f / (2 E)``:

    >>> from mvtk.fe import build_model
    >>> beam = {"name": "beam",
    ...         "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}},
    ...         "structure": {"type": "beam", "length": 0.3, "width": 0.02,
    ...                       "layers": [{"material": "steel", "thickness": 2e-3}]},
    ...         "mesh": {"n_elements": 20}, "boundary": {"clamp": "x0"}}
    >>> s = eigen_sensitivity(beam, ["materials.steel.E"], builder=build_model, n_modes=1)
    >>> round(float(s.d_fn_hz[0, 0] * 2 * 2.1e11 / s.fn_hz[0]), 4)
    1.0
    """

    paths: tuple[str, ...]
    values: np.ndarray
    fn_hz: np.ndarray
    d_omega2: np.ndarray
    d_fn_hz: np.ndarray
    normalised: np.ndarray


def eigen_sensitivity(
    description: Mapping[str, Any],
    parameters: Sequence[Parameter | str],
    *,
    builder: Callable[[Mapping[str, Any]], FEModel],
    n_modes: int,
    rel_step: float | None = None,
    difference: str = "central",
) -> Sensitivity:
    """Frequencies and eigenvalue sensitivities of the model built from ``description``.

    Parameters
    ----------
    description : mapping
        Structure description (values of ``parameters`` are read from it unless a
        :class:`Parameter` gives ``initial``).
    parameters : sequence of Parameter or str
        Fields to differentiate with respect to.
    builder : callable
        ``builder(description) -> FEModel``.
    n_modes : int
        Number of lowest modes.
    rel_step : float, optional
        Finite-difference step relative to the parameter's scale (default 1e-4 for
        central, 1e-6 for forward differences).
    difference : {"central", "forward"}
        Difference scheme for the matrix derivatives (see module notes).

    Returns
    -------
    Sensitivity

    Raises
    ------
    DimensionError
        If a perturbed build changes the free-DOF map (e.g. a remeshed geometry);
        differentiate the eigenvalues by finite differences instead.

    Examples
    --------
    Normalised sensitivities ``(p / f) df/dp`` of a steel cantilever: ``f ~ sqrt(E)``
    gives 0.5 and ``f ~ t`` (bending, thickness t) gives 1.0:

    >>> from mvtk.fe import build_model
    >>> beam = {"name": "beam",
    ...         "materials": {"steel": {"E": 2.1e11, "nu": 0.3, "rho": 7850.0}},
    ...         "structure": {"type": "beam", "length": 0.3, "width": 0.02,
    ...                       "layers": [{"material": "steel", "thickness": 2e-3}]},
    ...         "mesh": {"n_elements": 20}, "boundary": {"clamp": "x0"}}
    >>> s = eigen_sensitivity(beam, ["materials.steel.E", "structure.layers.0.thickness"],
    ...                       builder=build_model, n_modes=2)
    >>> np.round(s.normalised, 2)
    array([[0.5, 1. ],
           [0.5, 1. ]])
    """
    check_difference(difference)
    if rel_step is None:
        rel_step = 1e-4 if difference == "central" else 1e-6
    params = [p if isinstance(p, Parameter) else Parameter(p) for p in parameters]
    resolved = [p.resolve(description) for p in params]
    values = np.array([v for v, _ in resolved])
    base_desc = with_values(description, {p.path: v for p, v in zip(params, values)})
    model = check_model(builder(base_desc), "base build")
    eig = eigsh_lowest(model.K, model.M, n_modes)
    w2 = eig.omega2
    dw2 = np.zeros((n_modes, len(params)))
    for j, (p, (v, s)) in enumerate(zip(params, resolved)):
        h = rel_step * s
        steps = (h, -h) if difference == "central" else (h,)
        built = []
        for step in steps:
            pert = check_model(builder(with_values(base_desc, {p.path: v + step})), p.path)
            if not same_dofs(model, pert):
                raise DimensionError(
                    f"perturbing {p.path!r} changed the model's free DOFs "
                    f"({model.n_dof} -> {pert.n_dof}); matrix sensitivities need a fixed mesh"
                )
            built.append(pert)
        dK, dM = matrix_derivative(model, built, h)
        dw2[:, j] = d_omega2(w2, eig.vectors, dK, dM)
    omega = np.sqrt(np.maximum(w2, 0.0))
    fn = omega / (2 * np.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        dfn = dw2 / (8 * np.pi**2 * fn[:, None])
        norm = dfn * values[None, :] / fn[:, None]
    return Sensitivity(
        paths=tuple(p.path for p in params), values=values, fn_hz=fn, d_omega2=dw2,
        d_fn_hz=dfn, normalised=norm,
    )
