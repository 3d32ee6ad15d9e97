"""Mapping of test sensor DOFs onto an FE model.

Each sensor becomes one row of an observation matrix ``C`` (n_sensors x n_fe_dof) so
that the FE response seen by the sensor is ``C u``:

- ``method="nearest"``: the sensor reads the nearest FE node;
- ``method="shape"``: the sensor reads the element field at its location, interpolated
  with the element shape functions (4-node quadrilaterals: bilinear, 3-node triangles:
  linear), found by an inverse isoparametric map (Gauss-Newton on the element surface).

In both cases the nodal translations (or rotations, for a rotational sensor) are
projected onto the sensor's global unit vector. A sensor farther than ``tol`` from the
model (from the nearest element surface, or from the nearest node for models without
surface elements) is an error: the geometry and the model do not describe the same
structure, or they use different units or frames.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
import xarray as xr

from ..errors import DimensionError, ParameterError
from ..fe._model import FEModel
from ._fe_adapter import fe_node_ids, modal_arrays
from ._geometry import TestGeometry

__all__ = ["DofMapping", "map_sensors", "QUAD_KEYS", "TRI_KEYS", "shape_functions"]

#: Element keys of ``FEModel.elements`` treated as 4-node quadrilaterals / 3-node triangles.
QUAD_KEYS = ("mitc4", "quad4", "shell4", "cquad4")
TRI_KEYS = ("tri3", "dkt3", "shell3", "ctria3")


def shape_functions(kind: str, xi: float, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Shape functions and their (xi, eta) derivatives.

    ``"quad4"``: bilinear on [-1, 1]^2, nodes counter-clockwise from (-1, -1).
    ``"tri3"``: linear in area coordinates ``(1 - xi - eta, xi, eta)``.

    Returns
    -------
    N : ndarray (n,)
    dN : ndarray (n, 2)

    Examples
    --------
    At the centre of a quad4 every bilinear shape function is 1/4:

    >>> N, dN = shape_functions("quad4", 0.0, 0.0)
    >>> N, dN.shape
    (array([0.25, 0.25, 0.25, 0.25]), (4, 2))
    """
    if kind == "quad4":
        s = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
        N = 0.25 * (1 + s[:, 0] * xi) * (1 + s[:, 1] * eta)
        dN = np.column_stack([0.25 * s[:, 0] * (1 + s[:, 1] * eta),
                              0.25 * s[:, 1] * (1 + s[:, 0] * xi)])
        return N, dN
    if kind == "tri3":
        N = np.array([1 - xi - eta, xi, eta])
        dN = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
        return N, dN
    raise ParameterError(f"unknown element kind {kind!r}; expected 'quad4' or 'tri3'")


def _inverse_map(kind: str, X: np.ndarray, p: np.ndarray) -> tuple[float, float, float, bool]:
    """Natural coordinates of the closest point of an element surface to ``p``.

    Returns ``(xi, eta, distance, inside)``.
    """
    xi = eta = 0.0 if kind == "quad4" else 1.0 / 3.0
    for _ in range(30):
        N, dN = shape_functions(kind, xi, eta)
        r = N @ X - p
        J = X.T @ dN  # (3, 2)
        step, *_ = np.linalg.lstsq(J, -r, rcond=None)
        xi, eta = xi + step[0], eta + step[1]
        if np.max(np.abs(step)) < 1e-13:
            break
    N, _ = shape_functions(kind, xi, eta)
    dist = float(np.linalg.norm(N @ X - p))
    tol = 1e-9
    if kind == "quad4":
        inside = abs(xi) <= 1 + tol and abs(eta) <= 1 + tol
    else:
        inside = xi >= -tol and eta >= -tol and xi + eta <= 1 + tol
    return float(xi), float(eta), dist, inside


def _elements(model: FEModel) -> list[tuple[str, str, np.ndarray]]:
    out = []
    for key, conn in model.elements.items():
        k = key.lower()
        if k in QUAD_KEYS and conn.shape[1] == 4:
            out.append((key, "quad4", conn))
        elif k in TRI_KEYS and conn.shape[1] == 3:
            out.append((key, "tri3", conn))
    return out


@dataclass(frozen=True, eq=False)
class DofMapping:
    """Test sensor DOFs mapped onto an FE model.

    Attributes
    ----------
    matrix : scipy.sparse.csr_matrix (n_sensors, n_fe_dof)
        Observation matrix: sensor readings = ``matrix @ u`` for an FE vector ``u`` over
        the model's free DOFs (units of ``u``: m or rad).
    dof : list of str
        Test DOF labels (rows).
    node, direction : ndarray
        Test node label and direction name of each row.
    report : pandas.DataFrame
        One row per sensor: ``dof``, ``node``, ``direction``, ``direction_source``
        (:attr:`Sensor.source`: ``"file"``, ``"default +z"`` or ``"user"``), ``method``,
        ``fe_node``
        (nearest FE node label), ``node_distance_m``, ``element`` (``"key:index"`` or
        empty), ``xi``, ``eta``, ``surface_distance_m`` (NaN without surface elements),
        ``n_constrained`` (FE DOFs of the row that are constrained, read as zero).
    method : str
    tol : float

    Examples
    --------
    Returned by :func:`map_sensors`; ``report`` says how each sensor was mapped (on a
    beam model: to the nearest node):

    >>> from mvtk.correlation import read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> mapping = map_sensors(geo, beam)
    >>> mapping.report[["dof", "method"]].values.tolist()[0], mapping.n_fe_dof
    (['1+z', 'nearest'], 72)
    """

    matrix: sp.csr_matrix
    dof: list[str]
    node: np.ndarray
    direction: np.ndarray
    report: Any
    method: str
    tol: float
    n_fe_dof: int

    def to_dataframe(self):
        """The mapping report (see :attr:`report`)."""
        return self.report

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.report, caption=type(self).__name__, passed_column=None)

    def observe(self, vectors: np.ndarray) -> np.ndarray:
        """Sensor readings ``C @ vectors`` of FE vectors ``(n_fe_dof, k)``."""
        v = np.asarray(vectors)
        if v.shape[0] != self.n_fe_dof:
            raise DimensionError(
                f"expected FE vectors with {self.n_fe_dof} rows (free DOFs of the mapped model), "
                f"got {v.shape[0]}"
            )
        return self.matrix @ v

    def project(self, modal: Any, *, modes: Sequence[int] | None = None) -> xr.DataArray:
        """FE mode shapes at the test DOFs, ``("mode", "dof")`` with the test labels.

        Parameters
        ----------
        modal : ModalResult, EigenSolution, ndarray (n_fe_dof, n_modes) or DataArray
            FE shapes over the mapped model's free DOFs (a DataArray must have dims
            ``("mode", "dof")`` over those DOFs, e.g. from :func:`fe_shapes`).
        modes : sequence of int, optional
            1-based modes to keep.
        """
        fn = None
        attrs = {"normalisation": "mass", "source": "fe"}
        if isinstance(modal, xr.DataArray):
            if modal.dims != ("mode", "dof"):
                raise DimensionError(f"expected dims ('mode', 'dof'), got {modal.dims}")
            shapes = modal.values.T
            fn = modal["fn_hz"].values if "fn_hz" in modal.coords else None
            attrs = dict(modal.attrs)
        elif isinstance(modal, np.ndarray):
            shapes = modal
        else:
            shapes, fn = modal_arrays(modal)
        y = self.observe(shapes)
        n = y.shape[1]
        fn = np.full(n, np.nan) if fn is None else np.asarray(fn, dtype=float)
        da = xr.DataArray(
            np.asarray(y).T, dims=("mode", "dof"),
            coords={"mode": np.arange(1, n + 1), "fn_hz": ("mode", fn),
                    "zeta": ("mode", np.full(n, np.nan)), "dof": list(self.dof),
                    "node": ("dof", self.node), "direction": ("dof", self.direction)},
            attrs=attrs,
        )
        if modes is not None:
            da = da.sel(mode=list(modes))
        return da


def map_sensors(
    geometry: TestGeometry,
    model: FEModel,
    *,
    method: str = "shape",
    tol: float | None = None,
) -> DofMapping:
    """Map the sensors of a test geometry onto an FE model.

    Parameters
    ----------
    geometry : TestGeometry
        Nodes in the model's global frame and units (m).
    model : FEModel
    method : {"shape", "nearest"}
        ``"shape"`` interpolates with the shape functions of the element under the sensor
        (quad4 bilinear, tri3 linear; the element keys in :data:`QUAD_KEYS` and
        :data:`TRI_KEYS`); falls back to the nearest node when the model has no such
        elements. ``"nearest"`` reads the nearest FE node.
    tol : float, optional
        Largest accepted distance (m) from a sensor to the model (to the nearest element
        surface with surface elements, else to the nearest node). Default: 2 % of the
        diagonal of the model's bounding box.

    Returns
    -------
    DofMapping

    Raises
    ------
    ParameterError
        No sensors, unknown method, or a sensor off the model beyond ``tol`` (the
        message lists each such sensor with its distance).

    Examples
    --------
    Three +z sensors on a steel cantilever: each row of the observation matrix
    interpolates the FE DOFs under the sensor:

    >>> from mvtk.correlation import read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> mapping = map_sensors(geo, beam)
    >>> mapping.dof, mapping.matrix.shape
    (['1+z', '2+z', '3+z'], (3, 72))
    """
    from scipy.spatial import cKDTree

    if not isinstance(geometry, TestGeometry):
        raise ParameterError(f"geometry must be a TestGeometry, got {type(geometry).__name__}")
    if not isinstance(model, FEModel):
        raise ParameterError(f"model must be an FEModel, got {type(model).__name__}")
    if method not in ("shape", "nearest"):
        raise ParameterError(f"method must be 'shape' or 'nearest', got {method!r}")
    if not geometry.sensors:
        raise ParameterError("the test geometry has no sensors to map; add sensor DOFs "
                             "(with_sensors / [[sensors]])")
    diag = float(np.linalg.norm(np.ptp(model.nodes, axis=0)))
    if tol is None:
        tol = 0.02 * diag
    elif not (np.isfinite(tol) and tol >= 0):
        raise ParameterError(f"tol must be a finite distance >= 0 (m), got {tol!r}")
    ids = fe_node_ids(model)
    surf = _elements(model)
    used = np.unique(np.concatenate([c.ravel() for _, _, c in surf])) if surf else None
    if used is not None:
        tree_nodes = used
    elif model.elements:
        tree_nodes = np.unique(np.concatenate([c.ravel() for c in model.elements.values()]))
    else:
        tree_nodes = np.unique(model.dof_node)
    tree = cKDTree(model.nodes[tree_nodes])
    # element centroids and radii for a quick candidate search
    cand = []
    for key, kind, conn in surf:
        X = model.nodes[conn]
        c = X.mean(axis=1)
        rad = np.max(np.linalg.norm(X - c[:, None, :], axis=2), axis=1)
        cand.append((key, kind, conn, c, rad))
    lookup = np.full(model.n_nodes * 6, -1, dtype=np.int64)
    lookup[model.dof_node * 6 + model.dof_component] = np.arange(model.n_dof)
    vecs = geometry.sensor_vectors()
    rows, cols, vals, rep = [], [], [], []
    off = []
    for i, s in enumerate(geometry.sensors):
        p = geometry.xyz[geometry.row(s.node)]
        dn, k = tree.query(p)
        fe_node = int(tree_nodes[k])
        best = None
        for key, kind, conn, c, rad in cand:
            near = np.flatnonzero(np.linalg.norm(c - p, axis=1) <= rad + max(tol, 1e-12 * diag))
            for e in near:
                xi, eta, d, inside = _inverse_map(kind, model.nodes[conn[e]], p)
                if inside and (best is None or d < best[3]):
                    best = (key, kind, int(e), d, xi, eta)
        surface_d = best[3] if best is not None else np.nan
        if surf:
            # no element under the sensor within tol: the nearest node tells how far off
            dist = surface_d if best is not None else dn
        else:
            dist = dn
        if dist > tol:
            off.append((s.label, dist))
        base = 3 if s.rotation else 0
        if method == "shape" and best is not None:
            key, kind, e, _, xi, eta = best
            N, _ = shape_functions(kind, xi, eta)
            nodes = model.elements[key][e]
            weights = N
            el = f"{key}:{e}"
        else:
            nodes = np.array([fe_node])
            weights = np.array([1.0])
            el = ""
            xi = eta = np.nan
        n_con = 0
        for nd, wgt in zip(nodes, weights):
            for a in range(3):
                c = wgt * vecs[i, a]
                if c == 0.0:
                    continue
                j = int(lookup[int(nd) * 6 + base + a])
                if j < 0:
                    n_con += 1
                    continue
                rows.append(i)
                cols.append(j)
                vals.append(c)
        rep.append({
            "dof": s.label, "node": s.node, "direction": s.direction,
            "direction_source": s.source, "method": "shape" if el else "nearest",
            "fe_node": int(ids[fe_node]),
            "node_distance_m": float(dn), "element": el, "xi": xi, "eta": eta,
            "surface_distance_m": float(surface_d), "n_constrained": n_con,
        })
    if off:
        lst = ", ".join(f"{lab} ({d:.4g} m)" for lab, d in off)
        raise ParameterError(
            f"{len(off)} sensor(s) lie off the FE model by more than tol = {tol:.4g} m: {lst}; "
            "check that the test geometry uses the model's frame and units (m)"
        )
    import pandas as pd

    C = sp.csr_matrix((vals, (rows, cols)), shape=(len(geometry.sensors), model.n_dof))
    C.sum_duplicates()
    return DofMapping(
        matrix=C, dof=geometry.dof_labels,
        node=np.array([s.node for s in geometry.sensors], dtype=np.int64),
        direction=np.array([s.direction for s in geometry.sensors]),
        report=pd.DataFrame(rep), method=method, tol=float(tol), n_fe_dof=model.n_dof,
    )

