"""Plate meshes: patch edges on mesh lines, node sets, supports and springs."""

import numpy as np
import pytest

from mvtk.errors import ParameterError
from mvtk.fe import (
    IsotropicMaterial,
    Patch,
    Ply,
    SpringSupport,
    edge_tributary_lengths,
    modal_analysis,
    plate_model,
    rectangular_plate_mesh,
    support_components,
)

STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7900.0)


def test_mesh_lines_follow_patch_edges_and_points():
    p = Patch("pzt", 0.013, 0.057, 0.031, 0.071)
    mesh = rectangular_plate_mesh(0.18, 0.133, element_size=0.01, patches=[p],
                                  points={"tip": (0.18, 0.0665)})
    for v in (p.x0, p.x1):
        assert np.min(np.abs(mesh.x_lines - v)) < 1e-15
    for v in (p.y0, p.y1, 0.0665):
        assert np.min(np.abs(mesh.y_lines - v)) < 1e-15
    assert np.all(np.diff(mesh.x_lines) <= 0.01 + 1e-12)
    tip = mesh.nodes[mesh.node_sets["tip"][0]]
    np.testing.assert_allclose(tip, [0.18, 0.0665, 0.0], atol=1e-15)
    nx0 = mesh.nodes[mesh.node_sets["patch:pzt:x0"]]
    np.testing.assert_allclose(nx0[:, 0], p.x0)
    assert nx0[:, 1].min() == pytest.approx(p.y0) and nx0[:, 1].max() == pytest.approx(p.y1)
    # region: patch area is covered exactly by region-1 elements
    xy = mesh.nodes[mesh.elements, :2]
    area = 0.5 * np.abs((xy[:, 2, 0] - xy[:, 0, 0]) * (xy[:, 3, 1] - xy[:, 1, 1])
                        - (xy[:, 2, 1] - xy[:, 0, 1]) * (xy[:, 3, 0] - xy[:, 1, 0]))
    assert area[mesh.element_region == 1].sum() == pytest.approx((p.x1 - p.x0) * (p.y1 - p.y0))
    assert area.sum() == pytest.approx(0.18 * 0.133)
    for e in ("x0", "x1", "y0", "y1"):
        assert len(mesh.node_sets[e]) > 1


def test_tributary_lengths_sum_to_edge_length():
    mesh = rectangular_plate_mesh(0.3, 0.2, nx=7, ny=5, patches=[Patch("p", 0, 0.1, 0.03, 0.05)])
    assert edge_tributary_lengths(mesh, "x0").sum() == pytest.approx(0.2)
    assert edge_tributary_lengths(mesh, "y1").sum() == pytest.approx(0.3)


def test_support_components():
    assert support_components("clamped", "x0") == (0, 1, 2, 3, 4, 5)
    assert support_components("simply_supported", "x0") == (0, 1, 2, 3)
    assert support_components("simply_supported", "y1") == (0, 1, 2, 4)
    assert support_components(["uz"], "y0") == (2,)
    with pytest.raises(ParameterError, match="unknown support type 'glued'"):
        support_components("glued", "x0")
    with pytest.raises(ParameterError, match="unknown DOF name 'wz'"):
        support_components(["wz"], "x0")


@pytest.mark.parametrize("kwargs, message", [
    (dict(length=-1.0, width=1.0, nx=2, ny=2), "length must be a positive"),
    (dict(length=1.0, width=1.0), "mesh density missing"),
    (dict(length=1.0, width=1.0, nx=0, ny=2), "nx must be a positive integer"),
    (dict(length=1.0, width=1.0, nx=2, ny=2, patches=[Patch("a", 0.5, 1.5, 0, 1)]),
     "patch 'a' extent"),
    (dict(length=1.0, width=1.0, nx=2, ny=2,
          patches=[Patch("a", 0, 0.5, 0, 0.5), Patch("b", 0.4, 0.6, 0.4, 0.6)]), "overlap"),
    (dict(length=1.0, width=1.0, nx=2, ny=2, points={"p": (2.0, 0.0)}),
     "point 'p' at"),
])
def test_mesh_bad_inputs(kwargs, message):
    with pytest.raises(ParameterError, match=message):
        rectangular_plate_mesh(**kwargs)


def _strip(**kw):
    return plate_model(0.2, 0.02, [Ply(STEEL, 1e-3)], nx=20, ny=2, **kw)


def test_clamp_stiffness_limits():
    """Stiff elastic clamp -> clamped frequency; soft one -> lower, towards pinned-free."""
    f_clamped = modal_analysis(_strip(clamp="x0"), 1).fn_hz[0]
    f_stiff = modal_analysis(_strip(clamp="x0", clamp_stiffness=1e9), 1).fn_hz[0]
    f_soft = modal_analysis(_strip(clamp="x0", clamp_stiffness=1.0), 1).fn_hz[0]
    assert f_stiff == pytest.approx(f_clamped, rel=1e-4)
    assert f_soft < 0.8 * f_clamped
    # rotational spring k_t on a cantilever: f -> sqrt(k_t b / (I_tip)) as k_t -> 0;
    # at least check monotonicity between the limits
    f_mid = modal_analysis(_strip(clamp="x0", clamp_stiffness=100.0), 1).fn_hz[0]
    assert f_soft < f_mid < f_clamped
    with pytest.raises(ParameterError, match="clamp_stiffness must be a positive"):
        _strip(clamp="x0", clamp_stiffness=-1.0)
    with pytest.raises(ParameterError, match="needs a clamp edge"):
        _strip(clamp_stiffness=10.0)


def test_spring_at_tip_of_free_strip_closed_form():
    """A strip on soft vertical edge springs at both ends: heave omega^2 = 2 k b / m,
    pitch omega^2 = 6 k b / m (rigid-body closed form; first bending mode is ~133 Hz)."""
    m_total = 7900.0 * 0.2 * 0.02 * 1e-3
    k = 300.0  # N/m per m of edge: heave ~3.1 Hz
    model = plate_model(0.2, 0.02, [Ply(STEEL, 1e-3)], nx=20, ny=2,
                        supports={"x0": ["ux", "uy", "rx", "rz"]},
                        springs=[SpringSupport("x0", "uz", k, per_length=True),
                                 SpringSupport("x1", "uz", k, per_length=True)])
    res = modal_analysis(model, 2)
    # total spring 2 k b at the ends; heave mode omega^2 = 2 k b / m
    heave = np.sqrt(2 * k * 0.02 / m_total) / (2 * np.pi)
    assert res.fn_hz[0] == pytest.approx(heave, rel=2e-3)
    assert res.fn_hz[1] == pytest.approx(np.sqrt(3) * heave, rel=2e-3)
    with pytest.raises(ParameterError, match="spring node set 'nope'"):
        plate_model(0.2, 0.02, [Ply(STEEL, 1e-3)], nx=4, ny=2,
                    springs=[SpringSupport("nope", "uz", 1.0)])


def test_size_estimate_matches_a_small_model_and_huge_meshes_are_refused_at_once():
    """Issue 16: element_size = 1e-5 on a small plate ran out of memory after minutes."""
    import time
    import tracemalloc

    from mvtk.fe import IsotropicMaterial, Ply, plate_model
    from mvtk.fe._mesh import estimate_plate_size

    steel = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    est = estimate_plate_size(0.3, 0.2, element_size=0.01)
    tracemalloc.start()
    model = plate_model(0.3, 0.2, [Ply(steel, 1e-3)], element_size=0.01)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert (est.n_nodes, est.n_elements, est.n_dof) == (model.n_nodes, model.n_elements,
                                                        model.n_dof)
    # 6 x 6 DOFs per node pair; the symmetric laminate's membrane and bending DOFs do
    # not couple and are not stored (half of each block)
    assert est.nnz == 2 * model.K.nnz
    # an upper bound (K and M with full node blocks): measured 1.4x the peak
    assert 1.0 < est.bytes / peak < 2.0
    t0 = time.perf_counter()
    with pytest.raises(ParameterError, match=r"200030001 nodes, 200000000 elements and "
                       r"1200180006 DOFs .*element_size=1e-05.*estimated assembly memory "
                       r"3.36e\+03 GB exceeds the limit 1 GB"):
        rectangular_plate_mesh(0.2, 0.1, element_size=1e-5, max_bytes=10**9)
    with pytest.raises(ParameterError, match="exceeds the limit"):
        plate_model(0.2, 0.1, [Ply(steel, 1e-3)], element_size=1e-5)
    assert time.perf_counter() - t0 < 1.0
