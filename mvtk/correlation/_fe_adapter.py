"""FE shapes in the ``("mode", "dof")`` layout of the conventions.

A private adapter until ``FEModel.node_ids`` and ``ModalResult.to_xarray()`` are on the
main branch: node labels come from ``model.node_ids`` when the model has that attribute,
else they are the row index + 1; direction names are ``+x +y +z +rx +ry +rz``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import xarray as xr

from ..errors import DimensionError, ParameterError
from ..fe._model import FEModel

__all__ = ["fe_node_ids", "fe_shapes", "FE_DIRECTIONS", "modal_arrays"]

#: Direction name of each FE DOF component (``DOF_NAMES`` order ux uy uz rx ry rz).
FE_DIRECTIONS = ("+x", "+y", "+z", "+rx", "+ry", "+rz")


def fe_node_ids(model: FEModel) -> np.ndarray:
    """Node labels of an FE model (``model.node_ids`` if present, else ``1..n_nodes``).

    Examples
    --------
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> fe_node_ids(cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=4)).tolist()
    [1, 2, 3, 4, 5]
    """
    ids = getattr(model, "node_ids", None)
    if ids is None:
        return np.arange(1, model.n_nodes + 1, dtype=np.int64)
    ids = np.asarray(ids, dtype=np.int64).ravel()
    if ids.size != model.n_nodes:
        raise DimensionError(f"model.node_ids has {ids.size} labels for {model.n_nodes} nodes")
    return ids


def modal_arrays(modal: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(shapes (n_dof, n_modes), fn_hz (n_modes,))`` of a ModalResult or EigenSolution."""
    shapes = getattr(modal, "shapes", None)
    if shapes is None:
        shapes = getattr(modal, "vectors", None)
    if shapes is None:
        raise ParameterError(
            f"expected an mvtk.fe.ModalResult (or EigenSolution), got {type(modal).__name__}"
        )
    fn = getattr(modal, "fn_hz", None)
    if fn is None:
        w2 = np.asarray(modal.omega2, dtype=float)
        fn = np.sqrt(np.maximum(w2, 0.0)) / (2 * np.pi)
    return np.asarray(shapes), np.asarray(fn, dtype=float)


def fe_shapes(model: FEModel, modal: Any, *, modes: Any = None) -> xr.DataArray:
    """Mode shapes of an FE model over all its free DOFs as a ``("mode", "dof")`` array.

    Parameters
    ----------
    model : FEModel
    modal : ModalResult or EigenSolution
        Mass-normalised shapes ``(n_dof, n_modes)`` of ``model``.
    modes : sequence of int, optional
        1-based modes to keep (default all).

    Returns
    -------
    xarray.DataArray
        dims ``("mode", "dof")``; ``mode`` 1-based with coordinates ``fn_hz`` and
        ``zeta`` (NaN); ``dof`` labels ``"<node><direction>"`` with ``node`` and
        ``direction`` coordinates; ``attrs`` ``normalisation="mass"``, ``source="fe"``.

    Examples
    --------
    The two lowest modes of a steel cantilever (20 elements, 120 free DOFs):

    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=20)
    >>> shapes = fe_shapes(beam, modal_analysis(beam, 2))
    >>> shapes.dims, shapes.shape, np.round(shapes["fn_hz"].values, 1)
    (('mode', 'dof'), (2, 120), array([ 18.6, 116.3]))
    """
    shapes, fn = modal_arrays(modal)
    if shapes.shape[0] != model.n_dof:
        raise DimensionError(
            f"modal shapes have {shapes.shape[0]} rows but the model has {model.n_dof} free DOFs"
        )
    ids = fe_node_ids(model)
    nodes = ids[model.dof_node]
    dirs = [FE_DIRECTIONS[c] for c in model.dof_component]
    mode = np.arange(1, shapes.shape[1] + 1)
    da = xr.DataArray(
        shapes.T, dims=("mode", "dof"),
        coords={"mode": mode, "fn_hz": ("mode", fn), "zeta": ("mode", np.full(fn.size, np.nan)),
                "dof": [f"{n}{d}" for n, d in zip(nodes, dirs)], "node": ("dof", nodes),
                "direction": ("dof", dirs)},
        attrs={"normalisation": "mass", "source": "fe"},
    )
    if modes is not None:
        da = da.sel(mode=list(modes))
    return da
