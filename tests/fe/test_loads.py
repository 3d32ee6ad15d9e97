"""Static loads (gravity, pressure, point loads) and reactions on general models.

External truths:
- clamped square plate under uniform pressure: w_max = 0.00126 q a^4 / D (nu = 0.3;
  Timoshenko & Woinowsky-Krieger, "Theory of Plates and Shells", 2nd ed. 1959, table 35);
- cantilever tip force and tip moment: Euler-Bernoulli / Timoshenko closed forms;
- equilibrium: reactions balance the applied load, self weight = total mass x g.
"""

from __future__ import annotations

import numpy as np
import pytest

from mvtk.errors import ParameterError
from mvtk.fe import (
    BeamSet,
    IsotropicMaterial,
    Laminate,
    Ply,
    PointMass,
    ShellSet,
    assemble_model,
    gravity_load,
    gravity_nodal,
    nodal_load,
    pressure_nodal,
    rectangle_section,
    rectangular_plate_mesh,
    static_solution,
    static_solve,
)

STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)


def test_clamped_square_plate_uniform_pressure_timoshenko():
    a, h, q = 1.0, 0.01, 1e3
    m = rectangular_plate_mesh(a, a, nx=24, ny=24)
    edges = np.unique(np.concatenate([m.node_sets[k] for k in ("x0", "x1", "y0", "y1")]))
    model = assemble_model(m.nodes, [ShellSet(m.elements, Laminate((Ply(STEEL, h),)))],
                           supports={"edge": "clamped"}, node_sets={"edge": edges})
    sol = static_solution(model, pressure_nodal(model, -q))
    D = STEEL.E * h**3 / (12 * (1 - 0.3**2))
    w_max = -sol.displacement[:, 2].min()
    assert w_max == pytest.approx(0.00126 * q * a**4 / D, rel=1e-2)
    # the series value to more digits, 0.00126532 (Taylor & Govindjee, Commun. Numer.
    # Meth. Engng 20 (2004) 757-765)
    assert w_max == pytest.approx(0.00126532 * q * a**4 / D, rel=2e-3)
    # the reactions carry the whole load q a^2 (upwards)
    np.testing.assert_allclose(sol.total_reaction, [0.0, 0.0, q * a**2], atol=1e-6 * q)


def test_self_weight_is_total_mass_times_g_and_cantilever_tip_loads():
    L, b, t, n = 1.0, 0.03, 0.01, 20
    nodes = np.column_stack([np.linspace(0, L, n + 1), np.zeros((n + 1, 2))])
    els = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    sec = rectangle_section(STEEL, b, t)
    model = assemble_model(nodes, [BeamSet(els, sec, orientation=(0, 1, 0)),
                                   PointMass(n, 0.5, (1e-4, 1e-4, 1e-4), (0.0, 0.0, 0.1))],
                           supports={"root": "clamped"}, node_sets={"root": [0]})
    g = np.array([0.0, 0.0, -9.81])
    fn = gravity_nodal(model, g)
    mass = STEEL.rho * b * t * L + 0.5
    np.testing.assert_allclose(fn[:, :3].sum(axis=0), mass * g, rtol=1e-12)
    sol = static_solution(model, fn)
    np.testing.assert_allclose(sol.total_reaction, -mass * g, rtol=1e-10)
    # the offset mass's weight gives no moment about the x axis here; tip deflection of
    # a uniform load + a tip force (Euler-Bernoulli + shear)
    EI = STEEL.E * b * t**3 / 12
    w = -sol.displacement[n, 2]
    q, P = STEEL.rho * b * t * 9.81, 0.5 * 9.81
    kGA = sec.kGAz
    ref = q * L**4 / (8 * EI) + P * L**3 / (3 * EI) + q * L**2 / (2 * kGA) + P * L / kGA
    assert w == pytest.approx(ref, rel=1e-6)
    assert np.allclose(gravity_load(model, g), nodal_load(model, fn))
    # tip moment: rotation M L / EI
    f = np.zeros((n + 1, 6))
    f[n, 4] = 2.0
    u = static_solve(model, nodal_load(model, f))
    assert u[model.dof_index(n, "ry")] == pytest.approx(2.0 * L / EI, rel=1e-9)


def test_bad_load_input():
    m = rectangular_plate_mesh(1.0, 1.0, nx=2, ny=2)
    model = assemble_model(m.nodes, [ShellSet(m.elements, Laminate((Ply(STEEL, 0.01),)),
                                              name="skin")],
                           supports={"x0": "clamped"}, node_sets=m.node_sets)
    with pytest.raises(ParameterError, match="no shell set 'wing'"):
        pressure_nodal(model, 1.0, "wing")
    with pytest.raises(ParameterError, match="acceleration must be 3"):
        gravity_nodal(model, (0, 9.81))


def _roof(n: int):
    """Quarter of the Scordelis-Lo roof (MacNeal & Harder, Finite Elements in Analysis
    and Design 1 (1985) 3-20): R = 25, L = 50, 40 deg, t = 0.25, E = 4.32e8, nu = 0,
    self weight 90 per unit area; rigid diaphragm ends (uy = uz = 0); n x n MITC4."""
    R, L, t = 25.0, 50.0, 0.25
    mat = IsotropicMaterial("roof", 4.32e8, 0.0, 360.0)  # rho t g = 90 with g = 1
    X, P = np.meshgrid(np.linspace(0, L / 2, n + 1), np.radians(np.linspace(0, 40, n + 1)),
                       indexing="ij")
    nodes = np.column_stack([X.ravel(), R * np.sin(P).ravel(), R * np.cos(P).ravel()])
    idx = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    quads = np.column_stack([idx[:-1, :-1].ravel(), idx[1:, :-1].ravel(),
                             idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()])
    sets = {"end": idx[0], "mid": idx[-1], "crown": idx[:, 0]}
    model = assemble_model(nodes, [ShellSet(quads, Laminate((Ply(mat, t),)))],
                           supports={"end": ["uy", "uz"], "mid": "symmetry_x",
                                     "crown": "symmetry_y"}, node_sets=sets)
    sol = static_solution(model, gravity_nodal(model, (0.0, 0.0, -1.0)))
    return -sol.displacement[idx[-1, -1], 2], sol


def test_scordelis_lo_roof_self_weight_macneal_harder():
    """Vertical deflection at the middle of the free edge: 0.3024 (MacNeal-Harder);
    the MITC4 mesh converges to it from below (16 x 16: -0.9 %, 32 x 32: -0.3 %)."""
    w16, _ = _roof(16)
    w32, sol = _roof(32)
    assert w16 == pytest.approx(0.3024, rel=1e-2)
    assert w32 == pytest.approx(0.3024, rel=4e-3)
    assert w16 < w32 < 0.3024
    weight = 90.0 * 25.0 * 25.0 * np.radians(40.0)  # quarter roof
    np.testing.assert_allclose(sol.total_reaction, [0.0, 0.0, weight], rtol=1e-4,
                               atol=1e-6 * weight)
