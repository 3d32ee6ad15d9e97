"""Piezo actuator: paper eqs. 1-7, pin-force edge moments, static bimorph/unimorph."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.integrate import quad

from mvtk.errors import DimensionError, ParameterError
from mvtk.fe import FEModel, IsotropicMaterial, PiezoMaterial, Ply, factorize
from mvtk.fe._beam import BeamPatch, cantilever_beam
from mvtk.fe._piezo import (
    PiezoPatch,
    edge_moment_load,
    neutral_axis,
    paper_eq7_moment_per_volt,
    piezo_moment_per_volt,
)

# Paper Table 1 and the PIC 151 datasheet (PHYSICS.md section 1)
STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7900.0)
EPOXY = IsotropicMaterial("epoxy", 3.546e9, 0.35, 1180.0)
PIC151 = PiezoMaterial("PIC151", 66.667e9, 0.34, 7800.0, d31=-210e-12)
T_B, T_A, T_P = 0.5e-3, 0.036e-3, 0.25e-3
PAPER = (Ply(STEEL, T_B), Ply(EPOXY, T_A), Ply(PIC151, T_P))


def eq6(E_p, E_a, E_b, t_p, t_a, t_b):
    """Paper eq. 6 as printed."""
    num = (E_p * t_p**2 + 2 * E_p * t_p * t_a + 2 * E_p * t_p * t_b + E_a * t_a**2
           + 2 * E_a * t_a * t_b + E_b * t_b**2)
    return num / (2 * E_p * t_p + 2 * E_a * t_a + 2 * E_b * t_b)


# ---------------------------------------------------------------- voltage to moment
def test_paper_layup_numbers_of_physics_notes():
    assert neutral_axis(PAPER) * 1e3 == pytest.approx(0.3065, abs=5e-5)
    m = piezo_moment_per_volt(PAPER, 2)  # N m / (V m)
    assert m == pytest.approx(-4.96e-3, abs=5e-6)
    assert piezo_moment_per_volt(PAPER, 2, width=0.04) == pytest.approx(0.04 * m, rel=1e-14)
    assert piezo_moment_per_volt(PAPER, -1) == m


def test_neutral_axis_equals_printed_eq6():
    d = eq6(66.667e9, 3.546e9, 210e9, T_P, T_A, T_B)
    assert neutral_axis(PAPER) == pytest.approx(d, rel=1e-13)


def test_direct_integration_of_eq3_by_quadrature():
    # eq. 2 stress times b z, integrated numerically over the piezo layer about D of eq. 6
    D = eq6(66.667e9, 3.546e9, 210e9, T_P, T_A, T_B)
    sigma_per_volt = 66.667e9 * -210e-12 / T_P
    ref, _ = quad(lambda z: sigma_per_volt * 1.0 * z, T_A + T_B - D, T_P + T_A + T_B - D,
                  epsabs=0, epsrel=1e-13)
    assert piezo_moment_per_volt(PAPER, 2) == pytest.approx(ref, rel=1e-12)


def test_printed_eq7_equals_direct_integration_no_typo():
    kw = dict(E_p=66.667e9, E_a=3.546e9, E_b=210e9, t_p=T_P, t_a=T_A, t_b=T_B, d31=-210e-12)
    assert paper_eq7_moment_per_volt(**kw) == pytest.approx(piezo_moment_per_volt(PAPER, 2),
                                                            rel=1e-13)
    # and for arbitrary three-layer stacks
    rng = np.random.default_rng(7)
    for _ in range(20):
        E = rng.uniform(1e9, 300e9, 3)
        t = rng.uniform(1e-5, 2e-3, 3)
        d31 = rng.uniform(-300e-12, -50e-12)
        lay = (Ply(IsotropicMaterial("b", E[0], 0.3, 1.0), t[0]),
               Ply(IsotropicMaterial("a", E[1], 0.3, 1.0), t[1]),
               Ply(PiezoMaterial("p", E[2], 0.3, 1.0, d31), t[2]))
        eq7 = paper_eq7_moment_per_volt(E_p=E[2], E_a=E[1], E_b=E[0], t_p=t[2], t_a=t[1],
                                        t_b=t[0], d31=d31, width=0.03)
        assert eq7 == pytest.approx(piezo_moment_per_volt(lay, 2, width=0.03), rel=1e-12)


def test_moment_sign_flips_for_a_patch_below_the_neutral_axis():
    below = (Ply(PIC151, T_P), Ply(EPOXY, T_A), Ply(STEEL, T_B))
    assert piezo_moment_per_volt(below, 0) == pytest.approx(-piezo_moment_per_volt(PAPER, 2))


def test_symmetric_bimorph_moment_closed_form():
    # two identical piezo layers, NA at the interface: M/V per layer = E d31 b t / 2
    t, b = 0.2e-3, 0.01
    lay = (Ply(PIC151, t), Ply(PIC151, t))
    assert neutral_axis(lay) == pytest.approx(t)
    assert piezo_moment_per_volt(lay, 1, b) == pytest.approx(66.667e9 * -210e-12 * b * t / 2)


# ---------------------------------------------------------------- edge moment load
def test_edge_load_on_beam_is_equal_and_opposite_moment_pair():
    model = cantilever_beam(0.2, 0.04, [Ply(STEEL, T_B)], 10,
                            patches=[BeamPatch("p", 0.05, 0.1, PAPER[1:])])
    f = edge_moment_load(model, "patch:p:x0", "patch:p:x1", 2.0)
    a = model.node_set("patch:p:x0")[0]
    b = model.node_set("patch:p:x1")[0]
    assert f[model.dof_index(a, "ry")] == pytest.approx(-2.0 * 0.04)
    assert f[model.dof_index(b, "ry")] == pytest.approx(2.0 * 0.04)
    assert np.count_nonzero(f) == 2
    g = edge_moment_load(model, [a], [b], 2.0, component="rz", width=0.5)
    assert g[model.dof_index(b, "rz")] == pytest.approx(1.0)


def _grid_model(ys):
    """A bare FEModel with two edge lines x = 0 and x = 1 at the given y (no physics)."""
    ys = np.asarray(ys, float)
    nodes = np.concatenate([np.column_stack([np.zeros_like(ys), ys, np.zeros_like(ys)]),
                            np.column_stack([np.ones_like(ys), ys, np.zeros_like(ys)])])
    n = len(nodes) * 6
    return FEModel(nodes=nodes, M=sp.identity(n), K=sp.identity(n),
                   dof_node=np.arange(n) // 6, dof_component=np.arange(n) % 6)


def test_edge_load_tributary_lengths_are_trapezoidal():
    ys = [0.3, 0.0, 0.1, 0.6]  # unsorted, unequal spacing along the edge
    model = _grid_model(ys)
    f = edge_moment_load(model, [0, 1, 2, 3], [4, 5, 6, 7], 10.0, component="ry")
    ry = np.array([model.dof_index(i, "ry") for i in range(8)])
    # sorted y 0, 0.1, 0.3, 0.6 -> weights 0.05, 0.15, 0.25, 0.15
    expect = np.array([0.25, 0.05, 0.15, 0.15])
    np.testing.assert_allclose(f[ry[:4]], -10.0 * expect, rtol=1e-12)
    np.testing.assert_allclose(f[ry[4:]], 10.0 * expect, rtol=1e-12)
    assert f[ry[4:]].sum() == pytest.approx(10.0 * 0.6)  # line moment times edge length


def test_edge_load_on_a_clamped_edge_is_dropped():
    model = cantilever_beam(0.2, 0.02, [Ply(STEEL, T_B)], 4)
    f = edge_moment_load(model, "clamp", "tip", 1.0)
    assert np.count_nonzero(f) == 1
    assert f[model.dof_index(model.node_set("tip")[0], "ry")] == pytest.approx(0.02)


# ---------------------------------------------------------------- statics through the beam
def _tip(model, u):
    tip = model.node_set("tip")[0]
    return u[model.dof_index(tip, "uz")], u[model.dof_index(tip, "ry")]


def _ei(layers, b):
    """Parallel-axis EI of the stack about eq. 6's neutral axis, by hand."""
    z0 = np.cumsum([0.0] + [p.thickness for p in layers[:-1]])
    t = np.array([p.thickness for p in layers])
    E = np.array([p.material.E for p in layers])
    d = neutral_axis(layers)
    return float(np.sum(E * (b * t**3 / 12 + b * t * (z0 + t / 2 - d) ** 2)))


def test_unimorph_full_length_uniform_moment_closed_form():
    # patch over the whole beam: uniform moment M, tip w = -M L^2/(2EI), ry = M L / EI
    L, b, V = 0.2, 0.04, 100.0
    model = cantilever_beam(L, b, [Ply(STEEL, T_B)], 12,
                            patches=[BeamPatch("pzt", 0.0, L, PAPER[1:])])
    patch = PiezoPatch.on_beam(model, "pzt", PAPER, piezo_index=2)
    assert patch.width == b
    M = piezo_moment_per_volt(PAPER, 2, b) * V
    u = factorize(model.K).solve(patch.load_vector(model, voltage=V))
    w, ry = _tip(model, u)
    ei = _ei(PAPER, b)
    assert w == pytest.approx(-M * L**2 / (2 * ei), rel=1e-10)
    assert ry == pytest.approx(M * L / ei, rel=1e-10)
    assert w > 0  # d31 < 0, V > 0, patch on top: the tip moves toward the patch (+z)


def test_partial_patch_tip_deflection_closed_form():
    # curvature -M/EI only on [a, c]: tip w = -M/EI ((c-a)^2/2 + (c-a)(L-c))
    L, b, a, c, V = 0.25, 0.03, 0.02, 0.09, -50.0
    model = cantilever_beam(L, b, [Ply(STEEL, T_B)], 25,
                            patches=[BeamPatch("pzt", a, c, PAPER[1:])])
    patch = PiezoPatch.on_beam(model, "pzt", PAPER, piezo_index=2)
    u = factorize(model.K).solve(patch.load_vector(model, V))
    w, ry = _tip(model, u)
    M = patch.moment_per_volt * V
    ei = _ei(PAPER, b)
    assert w == pytest.approx(-M / ei * ((c - a) ** 2 / 2 + (c - a) * (L - c)), rel=1e-10)
    assert ry == pytest.approx(M * (c - a) / ei, rel=1e-10)


def test_series_bimorph_tip_deflection_smits_formula():
    # Smits, Dalke & Cooney (1991): series bimorph of total thickness h, free tip
    # deflection delta = 3/2 d31 V L^2 / h^2 (each layer sees V/2 across h/2, opposite
    # strains). Computed through the beam model with both layers' moment pairs.
    L, b, t, V = 0.03, 0.005, 0.25e-3, 10.0
    lay = (Ply(PIC151, t), Ply(PIC151, t))
    model = cantilever_beam(L, b, lay, 8)
    top = PiezoPatch("top", lay, 1, ("clamp", "tip"), b)
    bottom = PiezoPatch("bottom", lay, 0, ("clamp", "tip"), b)
    f = top.load_vector(model, V / 2) + bottom.load_vector(model, -V / 2)
    w, _ = _tip(model, factorize(model.K).solve(f))
    h = 2 * t
    assert abs(w) == pytest.approx(1.5 * 210e-12 * V * L**2 / h**2, rel=1e-10)
    assert w > 0  # top layer contracts (d31 V/2 < 0), bottom extends: bends toward +z


# ---------------------------------------------------------------- bad input
def test_piezo_bad_input():
    with pytest.raises(ParameterError, match="expected a PiezoMaterial"):
        piezo_moment_per_volt(PAPER, 0)
    with pytest.raises(ParameterError, match="piezo_index must be an integer in 0..2"):
        piezo_moment_per_volt(PAPER, 3)
    with pytest.raises(ParameterError, match="piezo_index must be an integer"):
        piezo_moment_per_volt(PAPER, 1.5)
    with pytest.raises(ParameterError, match="width must be positive"):
        piezo_moment_per_volt(PAPER, 2, width=0.0)
    with pytest.raises(ParameterError, match="layer stack is empty"):
        neutral_axis([])
    with pytest.raises(ParameterError, match="t_a must be positive"):
        paper_eq7_moment_per_volt(E_p=1.0, E_a=1.0, E_b=1.0, t_p=1.0, t_a=-1.0, t_b=1.0,
                                  d31=-1e-10)
    with pytest.raises(DimensionError, match="edges must be a pair"):
        PiezoPatch("p", PAPER, 2, ("a",), 0.01)
    with pytest.raises(ParameterError, match="expected a PiezoMaterial"):
        PiezoPatch("p", PAPER, 1, ("a", "b"), 0.01)


def test_edge_load_bad_input():
    model = cantilever_beam(0.2, 0.02, [Ply(STEEL, T_B)], 4, points={"s": 0.1})
    with pytest.raises(ParameterError, match="component must be one of 'rx', 'ry', 'rz'"):
        edge_moment_load(model, "s", "tip", 1.0, component="uz")
    with pytest.raises(ParameterError, match="no node set 'nope'"):
        edge_moment_load(model, "nope", "tip", 1.0)
    with pytest.raises(ParameterError, match="share node"):
        edge_moment_load(model, "tip", [4], 1.0)
    with pytest.raises(ParameterError, match="integer node indices"):
        edge_moment_load(model, [0.5], "tip", 1.0)
    with pytest.raises(ParameterError, match="outside 0..4"):
        edge_moment_load(model, [9], "tip", 1.0)
    with pytest.raises(ParameterError, match="has no nodes"):
        edge_moment_load(model, [], "tip", 1.0)
    with pytest.raises(ParameterError, match="must be finite"):
        edge_moment_load(model, "s", "tip", np.nan)
    with pytest.raises(ParameterError, match="width must be positive"):
        edge_moment_load(model, "s", "tip", 1.0, width=-1.0)
    bare = _grid_model([0.0])
    with pytest.raises(ParameterError, match="single node needs its width"):
        edge_moment_load(bare, [0], [1], 1.0)
    keep = np.flatnonzero(np.arange(12) % 6 != 4)  # two nodes without their ry DOF
    no_ry = FEModel(nodes=np.eye(2, 3), M=sp.identity(10), K=sp.identity(10),
                    dof_node=keep // 6, dof_component=keep % 6, meta={"width": 0.1})
    with pytest.raises(ParameterError, match="every ry DOF of both edges is constrained"):
        edge_moment_load(no_ry, [0], [1], 1.0)
    with pytest.raises(ParameterError, match="no node set 'patch:nope:x0'"):
        PiezoPatch.on_beam(model, "nope", PAPER, 2)


# ---------------------------------------------------------------- narrow patches
def test_neutral_axis_and_moment_with_unequal_layer_widths():
    widths = (0.04, 0.03, 0.03)  # steel 40 mm wide, epoxy and PZT 30 mm
    E = np.array([210e9, 3.546e9, 66.667e9])
    t = np.array([T_B, T_A, T_P])
    zc = np.array([T_B / 2, T_B + T_A / 2, T_B + T_A + T_P / 2])
    d = np.sum(E * np.array(widths) * t * zc) / np.sum(E * np.array(widths) * t)
    assert neutral_axis(PAPER, widths) == pytest.approx(d, rel=1e-13)
    m = piezo_moment_per_volt(PAPER, 2, widths=widths)
    assert m == pytest.approx(66.667e9 * -210e-12 * 0.03 * (zc[2] - d), rel=1e-12)
    # equal widths: the same as the width argument
    assert piezo_moment_per_volt(PAPER, 2, widths=(0.03,) * 3) == pytest.approx(
        piezo_moment_per_volt(PAPER, 2, width=0.03), rel=1e-14)
    with pytest.raises(ParameterError, match="either width or widths"):
        piezo_moment_per_volt(PAPER, 2, width=0.03, widths=widths)
    with pytest.raises(DimensionError, match="expected 3 layer widths"):
        neutral_axis(PAPER, (0.1, 0.1))
    with pytest.raises(ParameterError, match="layer widths must be positive"):
        neutral_axis(PAPER, (0.1, 0.0, 0.1))


def test_narrow_full_length_patch_unimorph_through_beam_model():
    L, b, bp, V = 0.2, 0.04, 0.025, 150.0
    model = cantilever_beam(L, b, [Ply(STEEL, T_B)], 10,
                            patches=[BeamPatch("pzt", 0.0, L, PAPER[1:], width=bp)])
    patch = PiezoPatch.on_beam(model, "pzt")  # stack, index and widths from the model
    assert patch.piezo_index == 2 and patch.width == bp
    assert patch.layer_widths == (b, bp, bp)
    widths = np.array([b, bp, bp])
    d = neutral_axis(PAPER, widths)
    z0 = np.array([0.0, T_B, T_B + T_A])
    t = np.array([T_B, T_A, T_P])
    E = np.array([210e9, 3.546e9, 66.667e9])
    ei = np.sum(E * widths * (t**3 / 12 + t * (z0 + t / 2 - d) ** 2))
    M = 66.667e9 * -210e-12 * bp * (T_B + T_A + T_P / 2 - d) * V
    u = factorize(model.K).solve(patch.load_vector(model, V))
    w, ry = _tip(model, u)
    assert w == pytest.approx(-M * L**2 / (2 * ei), rel=1e-10)
    assert ry == pytest.approx(M * L / ei, rel=1e-10)


def test_on_beam_errors():
    steel_patch = BeamPatch("s", 0.1, 0.15, (Ply(STEEL, 1e-4),))
    pzt = BeamPatch("p", 0.02, 0.08, PAPER[1:])
    over = BeamPatch("q", 0.05, 0.09, (Ply(STEEL, 1e-4),))
    model = cantilever_beam(0.2, 0.02, [Ply(STEEL, T_B)], 10,
                            patches=[steel_patch, pzt, over])
    with pytest.raises(ParameterError, match="expected exactly one PiezoMaterial layer"):
        PiezoPatch.on_beam(model, "s")
    with pytest.raises(ParameterError, match="overlaps other patches"):
        PiezoPatch.on_beam(model, "p")
    # explicit layers bypass the look-up
    ok = PiezoPatch.on_beam(model, "p", layers=PAPER)
    assert ok.piezo_index == 2 and ok.width == 0.02
    with pytest.raises(ParameterError, match="differs from the piezo layer width"):
        PiezoPatch("p", PAPER, 2, ("patch:p:x0", "patch:p:x1"), 0.02,
                   layer_widths=(0.02, 0.01, 0.01))
