"""One call for a study stage: map, pair, MAC / COMAC tables and figures."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import xarray as xr

from ..errors import ParameterError
from ._geometry import TestGeometry
from ._mapping import DofMapping, map_sensors
from ._metrics import _as_shapes, automac, comac, ecomac, mac
from ._pairing import ModePairing, pair_modes

__all__ = ["CorrelationResult", "correlate"]


@dataclass(frozen=True, eq=False)
class CorrelationResult:
    """Test-analysis correlation of one test against one FE model.

    Attributes
    ----------
    geometry : TestGeometry
    mapping : DofMapping
    fe : xarray.DataArray ("mode", "dof")
        FE shapes mapped on the test DOFs.
    test : xarray.DataArray ("mode", "dof") or None
        Test shapes on the same DOFs (None for a pretest check of the FE model alone).
    mac : xarray.DataArray
        Test x FE MAC (FE AutoMAC at the sensors without test shapes).
    pairing : ModePairing or None
    comac, ecomac : xarray.DataArray or None
        Per test DOF over the accepted pairs (None with fewer than 2 pairs).
    comac_min : float
        Threshold below which a DOF is flagged ``suspect`` in :meth:`dof_table`.

    Examples
    --------
    Returned by :func:`correlate`:

    >>> from mvtk.correlation import read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> res = correlate(geo, beam, modal_analysis(beam, 2))
    >>> res.fe.dims, res.mac.shape, res.test is None
    (('mode', 'dof'), (2, 2), True)
    """

    geometry: TestGeometry
    mapping: DofMapping
    fe: xr.DataArray
    test: xr.DataArray | None
    mac: xr.DataArray
    pairing: ModePairing | None
    comac: xr.DataArray | None
    ecomac: xr.DataArray | None
    comac_min: float

    def dof_table(self):
        """Per test DOF: direction source, mapping distances, COMAC, eCOMAC and a
        ``suspect`` flag."""
        tab = self.mapping.report[["dof", "node", "direction", "direction_source",
                                   "method", "fe_node",
                                   "node_distance_m", "surface_distance_m"]].copy()
        if self.comac is not None:
            tab["comac"] = self.comac.sel(dof=tab["dof"].tolist()).values
            tab["ecomac"] = self.ecomac.sel(dof=tab["dof"].tolist()).values
            tab["suspect"] = tab["comac"] < self.comac_min
        return tab

    def pairing_table(self):
        """The pairing table (empty without test shapes)."""
        import pandas as pd

        return self.pairing.table if self.pairing is not None else pd.DataFrame()

    def to_dataframe(self, table: str = "pairs"):
        """``"pairs"`` (pairing) or ``"dofs"`` (mapping + COMAC) table."""
        if table == "pairs":
            return self.pairing_table()
        if table == "dofs":
            return self.dof_table()
        raise ParameterError(f"unknown table {table!r}; expected 'pairs' or 'dofs'")

    def to_dict(self) -> dict:
        """JSON-serialisable summary."""

        def clean(v):
            if isinstance(v, np.generic):
                v = v.item()
            if isinstance(v, float) and not math.isfinite(v):
                return None
            return v

        def records(df):
            return [{k: clean(v) for k, v in r.items()} for r in df.to_dict("records")]

        return {
            "n_sensors": len(self.mapping.dof),
            "mapping_method": self.mapping.method,
            "mac": [[clean(float(v)) for v in row] for row in self.mac.values],
            "pairs": records(self.pairing_table()),
            "swaps": [list(s) for s in self.pairing.swaps] if self.pairing else [],
            "dofs": records(self.dof_table()),
        }

    def add_to_report(self, section: Any, *, model: Any = None, prefix: str = "correlation",
                      synthetic: bool = False) -> Any:
        """Fill a :class:`mvtk.report.Section`: pairing table, per-DOF table (mapping
        distances, COMAC, eCOMAC, suspect) and the figures of :meth:`figures`.

        Tables are named ``<prefix>_pairs`` and ``<prefix>_dofs``; no pass/fail verdict
        is added (the study decides its acceptance criteria). ``synthetic=True`` adds a
        note that the test data are synthetic.
        """
        if synthetic:
            section.note("The test shapes of this section are synthetic (computed, not "
                         "measured).")
        n_pairs = len(self.pairing.pairs) if self.pairing is not None else 0
        section.text(f"{len(self.mapping.dof)} sensor DOFs mapped onto the FE model "
                     f"({self.mapping.method}); {n_pairs} test-FE mode pairs accepted.")
        if self.pairing is not None:
            section.table(self.pairing_table(), f"{prefix}_pairs",
                          caption="Test-FE mode pairs (MAC, frequency gap, swaps)",
                          passed_column=None)
        section.table(self.dof_table(), f"{prefix}_dofs",
                      caption="Sensor mapping and COMAC per test DOF", passed_column=None)
        captions = {"mac": "MAC matrix", "paired_shapes": "Paired test and FE shapes",
                    "test_on_mesh": "FE mesh with the test wireframe and sensors"}
        for name, fig in self.figures(model).items():
            section.figure(fig, captions[name])
        return section

    def figures(self, model: Any = None) -> dict:
        """Figures keyed by name: ``mac``, ``paired_shapes`` (with test shapes) and
        ``test_on_mesh`` (with ``model``)."""
        from ..plot import plot_mac, plot_paired_shapes, plot_test_on_mesh

        figs = {"mac": plot_mac(self.mac, title="MAC" if self.test is not None
                                else "FE AutoMAC at the sensors")}
        if self.pairing is not None and self.pairing.pairs:
            figs["paired_shapes"] = plot_paired_shapes(self.geometry, self.test, self.fe,
                                                       self.pairing)
        if model is not None:
            figs["test_on_mesh"] = plot_test_on_mesh(model, self.geometry,
                                                     mapping=self.mapping)
        return figs


def correlate(
    geometry: TestGeometry,
    model: Any,
    modal: Any,
    test: Any = None,
    *,
    method: str = "shape",
    tol: float | None = None,
    mac_min: float = 0.6,
    freq_weight: float = 0.0,
    comac_min: float = 0.8,
) -> CorrelationResult:
    """Map the sensors, project the FE shapes, pair with the test and tabulate.

    Parameters
    ----------
    geometry : TestGeometry
        With the sensor DOFs of the test.
    model : FEModel
    modal : ModalResult or EigenSolution
        FE modes of ``model``.
    test : DataArray ("mode", "dof"), optional
        Identified shapes on (a superset of) the geometry's sensor DOFs, with ``fn_hz``.
        Without it the result is a pretest check (FE AutoMAC at the sensors).
    method, tol
        See :func:`map_sensors`.
    mac_min, freq_weight
        See :func:`pair_modes`.
    comac_min : float
        DOFs with a lower COMAC are flagged ``suspect``.

    Returns
    -------
    CorrelationResult

    Examples
    --------
    Three +z accelerometers at x = 0.1, 0.2, 0.3 m on a steel cantilever (300 x 20 x 2
    mm). Without test shapes this is a pretest check (FE AutoMAC at the sensors); with
    test shapes (here the FE shapes scaled by -2, so MAC = 1 by construction) the modes
    are paired:

    >>> from mvtk.correlation import read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> steel = IsotropicMaterial("steel", 2.1e11, 0.3, 7850.0)
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(steel, 2e-3)], n_elements=12)
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> fe = modal_analysis(beam, 2)
    >>> pretest = correlate(geo, beam, fe)
    >>> np.round(pretest.mac.values, 3)
    array([[1.   , 0.222],
           [0.222, 1.   ]])
    >>> res = correlate(geo, beam, fe, test=-2.0 * pretest.fe)
    >>> res.pairing.table[["test_mode", "fe_mode", "mac"]].values.tolist()
    [[1.0, 1.0, 1.0], [2.0, 2.0, 1.0]]
    """
    mp = map_sensors(geometry, model, method=method, tol=tol)
    fe = mp.project(modal)
    if test is None:
        return CorrelationResult(geometry, mp, fe, None, automac(fe), None, None, None,
                                 comac_min)
    t = _as_shapes(test, "test shapes")
    labels = {str(v) for v in t["dof"].values}
    missing = [d for d in mp.dof if d not in labels]
    if missing:
        raise ParameterError(
            f"test shapes lack sensor DOFs of the geometry: {missing[:8]}"
            f"{' ...' if len(missing) > 8 else ''}"
        )
    t = t.sel(dof=list(mp.dof))
    pr = pair_modes(t, fe, mac_min=mac_min, freq_weight=freq_weight)
    c = e = None
    if len(pr.pairs) >= 2:
        a, b = pr.select(t, fe)
        c, e = comac(a, b), ecomac(a, b)
    return CorrelationResult(geometry, mp, fe, t, mac(t, fe), pr, c, e, comac_min)
