"""Sensor mapping: shape-function interpolation, projection on sensor axes, off-model error."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from correlation_helpers import cantilever_plate, grid_points

from mvtk.correlation import Sensor, TestGeometry, map_sensors, shape_functions
from mvtk.errors import ParameterError
from mvtk.fe import FEModel


def _patch_model():
    """A distorted quad (nodes 0-3) and a triangle (nodes 1, 4, 2) in 3-D (tilted plane)."""
    xy = np.array([[0.0, 0.0], [1.1, 0.1], [1.3, 0.9], [-0.1, 1.2], [2.2, 0.6]])
    n = np.array([0.2, -0.1, 1.0])  # tilted plane z = 0.2 x - 0.1 y
    nodes = np.column_stack([xy, xy @ n[:2]])
    nd = len(nodes) * 6
    eye = sp.identity(nd, format="csr")
    return FEModel(nodes=nodes, M=eye, K=eye, dof_node=np.repeat(np.arange(5), 6),
                   dof_component=np.tile(np.arange(6), 5),
                   elements={"mitc4": np.array([[0, 1, 2, 3]]), "tri3": np.array([[1, 4, 2]])})


def test_interpolation_exact_in_element_span():
    model = _patch_model()
    rng = np.random.default_rng(1)
    u = rng.normal(size=model.n_dof)  # arbitrary nodal field: in the span by definition
    U = u.reshape(5, 6)
    cases = [("quad4", [0, 1, 2, 3], (0.3, -0.7)), ("quad4", [0, 1, 2, 3], (-0.95, 0.9)),
             ("tri3", [1, 4, 2], (0.2, 0.5))]
    for kind, conn, (xi, eta) in cases:
        N, _ = shape_functions(kind, xi, eta)
        p = N @ model.nodes[conn]
        geo = TestGeometry([1], [p], sensors=(Sensor(1, "+x"), Sensor(1, "+y"),
                                              Sensor(1, "+z"), Sensor(1, "+ry")))
        mp = map_sensors(geo, model, method="shape")
        expected = N @ U[conn][:, [0, 1, 2, 4]]
        np.testing.assert_allclose(mp.observe(u), expected, rtol=1e-12, atol=1e-12)
        assert mp.report["method"].eq("shape").all()
        np.testing.assert_allclose(mp.report[["xi", "eta"]].iloc[0], [xi, eta], atol=1e-10)
        assert mp.report["surface_distance_m"].max() < 1e-12


def test_linear_field_exact_on_distorted_quad_and_skewed_sensor():
    model = _patch_model()
    a = np.array([0.3, -1.2, 0.5])
    g = np.array([[1.0, 2.0, -0.5], [0.2, -0.4, 1.5], [0.7, 0.1, 0.3]])  # du_i/dx_j
    disp = a[None, :] + model.nodes @ g.T  # translations: linear in x, y, z
    u = np.zeros((5, 6))
    u[:, :3] = disp
    p = np.array([0.55, 0.6, 0.0])
    p[2] = 0.2 * p[0] - 0.1 * p[1]
    v = np.array([0.36, 0.48, 0.8])
    geo = TestGeometry([1], [p], sensors=(Sensor(1, "s1", tuple(v)),))
    mp = map_sensors(geo, model)
    assert mp.observe(u.ravel())[0] == pytest.approx(v @ (a + g @ p), rel=1e-12)


def test_rotated_system_and_nearest_node_report():
    model, modal = cantilever_plate()
    pts = grid_points()
    R = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1.0]])  # local x = global y
    from mvtk.correlation import CoordinateSystem

    geo = TestGeometry(np.arange(1, 13), pts, np.ones(12, int), {1: CoordinateSystem(1, R)})
    geo = geo.with_sensors([(n, "+x") for n in geo.node])
    mp = map_sensors(geo, model, method="nearest")
    ref = map_sensors(geo.with_sensors([(n, "+y") for n in geo.node]).__class__(
        geo.node, geo.xyz, sensors=tuple(Sensor(int(n), "+y") for n in geo.node)),
        model, method="nearest")
    np.testing.assert_array_equal(mp.matrix.toarray(), ref.matrix.toarray())
    rep = mp.report
    assert set(rep.columns) >= {"dof", "fe_node", "node_distance_m", "surface_distance_m"}
    assert rep["node_distance_m"].max() <= np.hypot(0.0125, 0.0125) + 1e-12
    shapes = mp.project(modal)
    assert shapes.dims == ("mode", "dof")
    assert shapes["dof"].values.tolist() == geo.dof_labels
    assert np.isfinite(shapes["fn_hz"]).all()


def test_sensor_off_the_model_is_an_error():
    model, _ = cantilever_plate()
    geo = TestGeometry([1, 2], [[0.1, 0.1, 0.0], [0.1, 0.1, 0.05]],
                       sensors=(Sensor(1, "+z"), Sensor(2, "+z")))
    with pytest.raises(ParameterError, match=r"1 sensor\(s\) lie off the FE model .*2\+z "
                                             r"\(0\.05 m\)"):
        map_sensors(geo, model, tol=0.01)
    outside = TestGeometry([1], [[0.5, 0.1, 0.0]], sensors=(Sensor(1, "+z"),))
    with pytest.raises(ParameterError, match=r"1\+z \(0\.2 m\)"):
        map_sensors(outside, model)
    with pytest.raises(ParameterError, match="method must be 'shape' or 'nearest'"):
        map_sensors(geo, model, method="closest")
    with pytest.raises(ParameterError, match="has no sensors"):
        map_sensors(TestGeometry([1], [[0, 0, 0]]), model)
