"""Shape-based updating: twin experiment on a plate with a softened quarter.

A cantilever plate (0.3 m x 0.2 m x 2 mm steel, clamped at x = 0) is split into four
zones (root/tip x left/right); the "test" is the same model with the tip-right zone 30 %
softer, measured by 20 +z sensors. The plate is symmetric about y = 0.1 m, so softening
the tip-left or the tip-right zone gives the *same* frequencies: frequencies alone cannot
locate the change (their Jacobian columns of the mirror zones are equal at a symmetric
point), mode shapes can.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from mvtk import correlation as co
from mvtk.errors import IdentifiabilityWarning, ParameterError
from mvtk.fe import (
    IsotropicMaterial,
    Laminate,
    Ply,
    assemble_shell_model,
    edge_dofs,
    modal_analysis,
    rectangular_plate_mesh,
)
from mvtk.updating import FrequencyTarget, Parameter, targets_from_shapes, update

E0 = 2.1e11
MESH = rectangular_plate_mesh(0.3, 0.2, nx=12, ny=8)
CENTRE = MESH.nodes[MESH.elements].mean(axis=1)
ZONE = (CENTRE[:, 0] > 0.15).astype(int) * 2 + (CENTRE[:, 1] > 0.1).astype(int)
FIXED = edge_dofs(MESH, "x0", "clamped")


def build(d):
    sections = [Laminate((Ply(IsotropicMaterial(f"z{i}", e, 0.3, 7850.0), 2e-3),))
                for i, e in enumerate(d["E"])]
    return assemble_shell_model(MESH.nodes, MESH.elements, ZONE, sections, fixed_dofs=FIXED,
                                node_sets=MESH.node_sets)


NOMINAL = {"E": [E0, E0, E0, E0]}
TRUTH = {"E": [E0, E0, E0, 0.7 * E0]}
PARAMS = [Parameter(f"E.{i}", lower=0.3 * E0, upper=1.5 * E0, label=f"E zone {i}")
          for i in range(4)]


def _test_data(n_modes=6):
    truth = build(TRUTH)
    modal = modal_analysis(truth, n_modes)
    geo = co.TestGeometry(np.arange(1, 21), [[x, y, 0.0] for x in np.linspace(0.06, 0.3, 5)
                                             for y in np.linspace(0.0, 0.2, 4)])
    geo = geo.with_sensors([(n, "+z") for n in geo.node])
    mapping = co.map_sensors(geo, build(NOMINAL))
    shapes = mapping.project(modal)
    return shapes, mapping


@pytest.mark.slow
def test_shapes_locate_a_softened_zone_that_frequencies_cannot():
    shapes, mapping = _test_data()
    freq_only = [FrequencyTarget(float(f)) for f in shapes["fn_hz"].values]
    with pytest.warns(IdentifiabilityWarning, match=r"at the initial values .*E\.2"):
        r_f = update(NOMINAL, PARAMS, freq_only, builder=build, affine=True, n_modes=10)
    # the frequencies are matched, but by softening a zone the diagnostics flagged as
    # inseparable from its mirror: here the tip-left zone instead of the tip-right one
    assert np.max(np.abs(r_f.fn_hz / shapes["fn_hz"].values - 1)) < 1e-6
    assert r_f.initial_identifiable is False
    pairs = [{k for k, v in d.items() if abs(v) > 0.5} for d in r_f.initial_null_directions]
    assert {"E.2", "E.3"} in pairs and {"E.0", "E.1"} in pairs
    assert not np.allclose(r_f.values, TRUTH["E"], rtol=0.05)

    targets = targets_from_shapes(shapes, mapping)
    with warnings.catch_warnings():
        warnings.simplefilter("error", IdentifiabilityWarning)
        r_s = update(NOMINAL, PARAMS, targets, builder=build, affine=True, n_modes=10,
                     eigvec_weight=1.0, max_iter=30)
    np.testing.assert_allclose(r_s.values, TRUTH["E"], rtol=2e-3)
    assert r_s.identifiable_with_shapes is True
    assert r_s.initial_identifiable is False and r_s.initial_identifiable_with_shapes is True
    assert r_s.data_singular_values.min() > 1e-3 * r_s.data_singular_values.max()
    assert r_s.to_dict()["identifiable_with_shapes"] is True
    assert np.all(r_s.mac > 0.999)


def test_nelson_shape_jacobian_matches_finite_differences():
    shapes, mapping = _test_data(4)
    targets = targets_from_shapes(shapes, mapping)
    start = {"E": [1.05 * E0, 0.95 * E0, 1.1 * E0, 0.9 * E0]}
    from mvtk.updating._update import _Problem

    jac = {}
    for how in ("nelson", "fd"):
        prob = _Problem(start, PARAMS, targets, build, 8, np.ones(4), 1.0, 0.0, None, 1e-6,
                        "central", affine=True, eigvec_weight=1.0, shape_derivative=how)
        jac[how] = prob.jacobian(prob.x0)
    # rows: 4 frequencies, 4 (1 - MAC), 4 x 20 eigenvector differences
    assert jac["nelson"].shape == (4 + 4 + 80, 4)
    scale = np.abs(jac["nelson"]).max()
    np.testing.assert_allclose(jac["nelson"], jac["fd"], atol=2e-4 * scale)


def test_weights_from_identification_quality_and_bad_input():
    import pandas as pd

    shapes, mapping = _test_data(3)
    q = pd.DataFrame({"mode": [1, 2, 3], "mpc": [0.99, 0.6, 0.95],
                      "reliable": [True, True, False]})
    t = targets_from_shapes(shapes, mapping, quality=q, min_mpc=0.8)
    assert [x.weight for x in t] == [0.99, 0.0, 0.0]
    assert t[0].observation.shape == (20, build(NOMINAL).n_dof)
    with pytest.raises(ParameterError, match="quality table has no row for mode 3"):
        targets_from_shapes(shapes, mapping, quality=q.iloc[:2])
    with pytest.raises(ParameterError, match="shape_derivative must be 'nelson' or 'fd'"):
        update(NOMINAL, PARAMS, t, builder=build, shape_derivative="exact")
    with pytest.raises(ParameterError, match="eigvec_weight > 0 needs targets with measured"):
        update(NOMINAL, PARAMS, [100.0, 200.0], builder=build, eigvec_weight=1.0)


def test_observed_shape_target_errors():
    C = np.eye(3, 10)
    with pytest.raises(ParameterError, match="observed shape needs keys 'values' and "
                                             "'observation'"):
        FrequencyTarget(10.0, shape={"observation": C, "nodes": [1]})
    from mvtk.errors import DimensionError

    with pytest.raises(DimensionError, match="observation has 3 rows for 2 shape values"):
        FrequencyTarget(10.0, shape={"values": [1.0, 2.0], "observation": C})
    with pytest.raises(ParameterError, match="finite and not all zero"):
        FrequencyTarget(10.0, shape={"values": [0.0, 0.0, 0.0], "observation": C})
    t = FrequencyTarget(10.0, label="m1", shape={"values": [1.0, 2.0, 3.0], "observation": C})
    from mvtk.updating._pairing import target_mac

    model = build(NOMINAL)
    with pytest.raises(DimensionError, match=r"target m1: observation has 10 columns but the "
                                             rf"model has {model.n_dof} free DOFs"):
        target_mac(model, np.ones((model.n_dof, 2)), [t])
    with pytest.raises(DimensionError, match="shapes must be a DataArray with dims"):
        targets_from_shapes(np.ones((2, 3)), C)
