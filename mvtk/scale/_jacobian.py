"""Eigenvalue sensitivity (updating Jacobian) columns evaluated as parallel tasks."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from ..errors import DimensionError
from ._study import _connect, _default_builder, _load_description

__all__ = ["eigen_sensitivity"]


def _column(base, description, path, value, h, difference, builder):
    """d(omega^2)/dp of one parameter from the scattered ``(model, eig)`` base."""
    from ..updating import with_values
    from ..updating._sensitivity import check_model, d_omega2, matrix_derivative, same_dofs

    model, eig = base
    steps = (h, -h) if difference == "central" else (h,)
    built = []
    for step in steps:
        pert = check_model(builder(with_values(description, {path: value + step})), path)
        if not same_dofs(model, pert):
            raise DimensionError(
                f"perturbing {path!r} changed the model's free DOFs ({model.n_dof} -> "
                f"{pert.n_dof}); matrix sensitivities need a fixed mesh"
            )
        built.append(pert)
    dK, dM = matrix_derivative(model, built, h)
    return d_omega2(eig.omega2, eig.vectors, dK, dM)


def eigen_sensitivity(
    description: Mapping[str, Any],
    parameters: Sequence,
    *,
    builder: Callable | None = None,
    n_modes: int = 6,
    rel_step: float | None = None,
    difference: str = "central",
    client=None,
    n_workers: int | None = None,
):
    """:func:`mvtk.updating.eigen_sensitivity` with one task per Jacobian column.

    The base model is built and solved here once; ``(model, eigensolution)`` is
    scattered to the workers once, and each task builds only its perturbed model(s)
    and returns one column ``d(omega^2)/dp`` (n_modes floats). Without ``client`` the
    columns are computed in process.

    Parameters
    ----------
    description, parameters, builder, n_modes, rel_step, difference
        As in :func:`mvtk.updating.eigen_sensitivity` (``builder`` defaults to
        :func:`mvtk.fe.build_model`).
    client, n_workers
        As in :func:`mvtk.scale.parameter_study`.

    Returns
    -------
    mvtk.updating.Sensitivity
    """
    from ..fe import eigsh_lowest
    from ..updating import Parameter, Sensitivity, with_values
    from ..updating._sensitivity import check_difference, check_model

    check_difference(difference)
    if rel_step is None:
        rel_step = 1e-4 if difference == "central" else 1e-6
    builder = builder or _default_builder
    description = _load_description(description)
    params = [p if isinstance(p, Parameter) else Parameter(p) for p in parameters]
    resolved = [p.resolve(description) for p in params]
    values = np.array([v for v, _ in resolved])
    base_desc = with_values(description, {p.path: v for p, v in zip(params, values)})
    model = check_model(builder(base_desc), "base build")
    eig = eigsh_lowest(model.K, model.M, n_modes)
    args = [(p.path, v, rel_step * s) for p, (v, s) in zip(params, resolved)]
    cl, owned = _connect(client, n_workers)
    try:
        if cl is None:
            cols = [_column((model, eig), base_desc, path, v, h, difference, builder)
                    for path, v, h in args]
        else:
            base = cl.scatter((model, eig), broadcast=True)
            desc = cl.scatter(base_desc, broadcast=True)
            futures = [cl.submit(_column, base, desc, path, v, h, difference, builder,
                                 pure=False) for path, v, h in args]
            cols = cl.gather(futures)
            cl.cancel([base, desc])
    finally:
        if owned:
            cluster = getattr(cl, "cluster", None)
            cl.close()
            if cluster is not None:
                cluster.close()
    dw2 = np.column_stack(cols) if cols else np.zeros((n_modes, 0))
    w2 = eig.omega2
    fn = np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        dfn = dw2 / (8 * np.pi**2 * fn[:, None])
        norm = dfn * values[None, :] / fn[:, None]
    return Sensitivity(paths=tuple(p.path for p in params), values=values, fn_hz=fn,
                       d_omega2=dw2, d_fn_hz=dfn, normalised=norm)
