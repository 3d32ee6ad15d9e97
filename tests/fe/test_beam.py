"""Timoshenko layered beam: closed forms for stiffness, statics and vibration."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from mvtk.errors import DimensionError, ParameterError
from mvtk.fe import IsotropicMaterial, OrthotropicMaterial, Ply, eigsh_lowest, factorize
from mvtk.fe._beam import (
    SHEAR_CORRECTION,
    BeamPatch,
    beam_element_matrices,
    beam_section,
    cantilever_beam,
    ply_axial_modulus,
    timoshenko_element_matrices,
)

STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7900.0)
EPOXY = IsotropicMaterial("epoxy", 3.546e9, 0.35, 1180.0)
PZT = IsotropicMaterial("PIC151", 66.667e9, 0.34, 7800.0)

# Euler-Bernoulli clamped-free roots of cos(bL) cosh(bL) = -1 (Blevins, Formulas for
# Natural Frequency and Mode Shape, table 8-1)
EB_ROOTS = np.array([1.87510406871, 4.69409113297, 7.85475743823, 10.9955407349])


def _plane_fraction(model, sol, components):
    """Share of each mode's kinetic energy (phi' M phi = 1) in the given DOF components."""
    mv = model.M @ sol.vectors
    sel = np.isin(model.dof_component, components)
    return np.einsum("ij,ij->j", sol.vectors[sel], mv[sel])


def freqs_hz(model, n):
    sol = eigsh_lowest(model.K, model.M, n)
    return np.sqrt(np.abs(sol.omega2)) / (2 * np.pi), sol


# ---------------------------------------------------------------- element matrices
def test_element_stiffness_equals_classical_exact_timoshenko_matrix():
    EI, kGA, L = 3.0, 40.0, 0.6
    K, _ = timoshenko_element_matrices(L, 1.0, 1.0, EI, EI, kGA, kGA, 1.0, 0.0, 0.0)
    phi = 12 * EI / (kGA * L**2)
    kc = EI / ((1 + phi) * L**3) * np.array([
        [12, 6 * L, -12, 6 * L],
        [6 * L, (4 + phi) * L**2, -6 * L, (2 - phi) * L**2],
        [-12, -6 * L, 12, -6 * L],
        [6 * L, (2 - phi) * L**2, -6 * L, (4 + phi) * L**2],
    ])
    ixy = [1, 5, 7, 11]
    np.testing.assert_allclose(K[0][np.ix_(ixy, ixy)], kc, rtol=1e-12, atol=1e-12)
    s = np.array([1, -1, 1, -1])  # ry = -dw/dx
    ixz = [2, 4, 8, 10]
    np.testing.assert_allclose(K[0][np.ix_(ixz, ixz)], kc * s[:, None] * s, rtol=1e-12,
                               atol=1e-12)


def test_element_mass_euler_bernoulli_limit_is_classical_consistent_mass():
    # kGA -> infinity, no rotary inertia: the cubic Hermite consistent mass (Przemieniecki)
    L, m = 0.5, 3.0
    _, M = timoshenko_element_matrices(L, 1.0, 1.0, 1.0, 1.0, 1e14, 1e14, m, 0.0, 0.0)
    mc = m * L / 420 * np.array([
        [156, 22 * L, 54, -13 * L],
        [22 * L, 4 * L**2, 13 * L, -3 * L**2],
        [54, 13 * L, 156, -22 * L],
        [-13 * L, -3 * L**2, -22 * L, 4 * L**2],
    ])
    ixy = [1, 5, 7, 11]
    np.testing.assert_allclose(M[0][np.ix_(ixy, ixy)], mc, rtol=1e-9, atol=1e-12)
    # total translational mass in every direction equals m L
    for c in range(3):
        u = np.zeros(12)
        u[[c, c + 6]] = 1.0
        assert u @ M[0] @ u == pytest.approx(m * L, rel=1e-12)


def test_rigid_body_motions_of_a_skew_element_are_strain_free():
    rng = np.random.default_rng(1)
    xa, xb = rng.normal(size=3), rng.normal(size=3)
    sec = beam_section([Ply(STEEL, 0.01)], 0.03)
    K, _ = beam_element_matrices(xa[None], xb[None], [sec], y_ref=(0.3, 1.0, 0.2))
    nodes = np.array([xa, xb])
    modes = []
    for c in range(3):
        u = np.zeros((2, 6))
        u[:, c] = 1.0
        modes.append(u.ravel())
    for c in range(3):  # small rotation about global axis c: u = w x r, theta = w
        w = np.zeros(3)
        w[c] = 1.0
        u = np.zeros((2, 6))
        u[:, :3] = np.cross(w, nodes)
        u[:, 3:] = w
        modes.append(u.ravel())
    r = np.array(modes).T
    assert np.abs(K[0] @ r).max() < 1e-9 * np.abs(K[0]).max()
    assert np.linalg.matrix_rank(K[0], tol=1e-9 * np.abs(K[0]).max()) == 6


# ---------------------------------------------------------------- sections
def test_homogeneous_section_matches_textbook_formulas():
    b, t = 0.03, 0.002
    s = beam_section([Ply(STEEL, t)], b)
    G = STEEL.G
    assert s.EA == pytest.approx(210e9 * b * t)
    assert s.neutral_axis == pytest.approx(t / 2)
    assert s.EIy == pytest.approx(210e9 * b * t**3 / 12)
    assert s.EIz == pytest.approx(210e9 * t * b**3 / 12)
    assert s.kGAz == pytest.approx(5 / 6 * G * b * t)
    assert s.rhoA == pytest.approx(7900 * b * t)
    assert s.rhoIy == pytest.approx(7900 * b * t**3 / 12)
    # thin-strip torsion: b t^3/3 (1 - 0.630 t/b) (Roark, table 10.7 case 4), within 0.1 %
    assert s.GJ == pytest.approx(G * b * t**3 / 3 * (1 - 0.630 * t / b), rel=1e-3)


def test_square_section_torsion_constant_is_0_1406_a4():
    # Timoshenko & Goodier: J = 0.1406 a^4 for a square of side a
    a = 0.01
    s = beam_section([Ply(STEEL, a)], a)
    assert s.GJ / STEEL.G == pytest.approx(0.1406 * a**4, rel=2e-4)


def test_layered_section_equals_split_homogeneous_section():
    b = 0.02
    one = beam_section([Ply(STEEL, 0.001)], b)
    two = beam_section([Ply(STEEL, 0.0004), Ply(STEEL, 0.0006)], b)
    for key, v in one.as_dict().items():
        assert getattr(two, key) == pytest.approx(v, rel=1e-12, abs=1e-18), key


def test_unsymmetric_section_neutral_axis_and_parallel_axis_stiffness():
    b = 0.04
    lay = [Ply(STEEL, 0.5e-3), Ply(EPOXY, 0.036e-3), Ply(PZT, 0.25e-3)]
    s = beam_section(lay, b)
    # PHYSICS.md section 1: neutral axis 0.3065 mm above the steel bottom
    assert s.neutral_axis * 1e3 == pytest.approx(0.3065, abs=5e-5)
    # EI by the parallel-axis theorem, layer by layer
    z0 = np.array([0.0, 0.5e-3, 0.536e-3])
    t = np.array([0.5e-3, 0.036e-3, 0.25e-3])
    E = np.array([210e9, 3.546e9, 66.667e9])
    zc = z0 + t / 2
    ei = np.sum(E * (b * t**3 / 12 + b * t * (zc - s.neutral_axis) ** 2))
    assert s.EIy == pytest.approx(ei, rel=1e-12)
    assert s.mass_offset != 0.0


def test_orthotropic_ply_axial_modulus_rotates_like_compliance():
    cfrp = OrthotropicMaterial("cfrp", 140e9, 10e9, 5e9, 5e9, 3.5e9, 0.3, 1600)
    assert ply_axial_modulus(Ply(cfrp, 1e-3, 0.0)) == pytest.approx(140e9)
    assert ply_axial_modulus(Ply(cfrp, 1e-3, 90.0)) == pytest.approx(10e9)
    # 45 deg: 1/Ex = (1/E1 + 1/E2 + 1/G12 - 2 nu12/E1) / 4
    ex45 = 1 / ((1 / 140e9 + 1 / 10e9 + 1 / 5e9 - 2 * 0.3 / 140e9) / 4)
    assert ply_axial_modulus(Ply(cfrp, 1e-3, 45.0)) == pytest.approx(ex45)


# ---------------------------------------------------------------- statics
@pytest.mark.parametrize("n_el", [1, 3, 10])
def test_static_tip_deflection_bending_plus_shear_is_nodally_exact(n_el):
    L, b, h, P = 0.3, 0.05, 0.06, 1000.0  # stubby: shear part is large
    model = cantilever_beam(L, b, [Ply(STEEL, h)], n_el)
    f = np.zeros(model.n_dof)
    tip = model.node_set("tip")[0]
    f[model.dof_index(tip, "uz")] = P
    u = factorize(model.K).solve(f)
    s = model.meta["sections"][0]
    expected = P * L**3 / (3 * s["EIy"]) + P * L / s["kGAz"]
    assert u[model.dof_index(tip, "uz")] == pytest.approx(expected, rel=1e-10)
    # rotation: ry = -dw/dx = -P L^2 / (2 EI)
    assert u[model.dof_index(tip, "ry")] == pytest.approx(-P * L**2 / (2 * s["EIy"]), rel=1e-10)
    # in-plane load
    f[:] = 0
    f[model.dof_index(tip, "uy")] = P
    u = factorize(model.K).solve(f)
    expected = P * L**3 / (3 * s["EIz"]) + P * L / s["kGAy"]
    assert u[model.dof_index(tip, "uy")] == pytest.approx(expected, rel=1e-10)


def test_static_axial_and_torsion_tip_response():
    L, b, h = 0.5, 0.04, 0.002
    model = cantilever_beam(L, b, [Ply(STEEL, h)], 7)
    s = model.meta["sections"][0]
    tip = model.node_set("tip")[0]
    f = np.zeros(model.n_dof)
    f[model.dof_index(tip, "ux")] = 500.0
    f[model.dof_index(tip, "rx")] = 0.2
    u = factorize(model.K).solve(f)
    assert u[model.dof_index(tip, "ux")] == pytest.approx(500.0 * L / s["EA"], rel=1e-12)
    assert u[model.dof_index(tip, "rx")] == pytest.approx(0.2 * L / s["GJ"], rel=1e-12)


def test_clamp_rotational_spring_adds_rigid_rotation_deflection():
    L, b, h, P, kr = 0.2, 0.02, 0.001, 1.0, 50.0
    model = cantilever_beam(L, b, [Ply(STEEL, h)], 8, clamp_stiffness={"ry": kr})
    s = model.meta["sections"][0]
    tip = model.node_set("tip")[0]
    f = np.zeros(model.n_dof)
    f[model.dof_index(tip, "uz")] = P
    u = factorize(model.K).solve(f)
    expected = P * L**3 / (3 * s["EIy"]) + P * L / s["kGAz"] + P * L * L / kr
    assert u[model.dof_index(tip, "uz")] == pytest.approx(expected, rel=1e-10)
    # the spring DOF is free, the others of the clamp node are not
    clamp = model.node_set("clamp")[0]
    assert model.dof_index(clamp, "ry") >= 0
    with pytest.raises(ParameterError, match="constrained"):
        model.dof_index(clamp, "uz")


def test_clamp_float_stiffness_is_ry_spring_and_translational_spring_adds_p_over_k():
    L, b, h, P, kr, kt = 0.2, 0.02, 0.001, 1.0, 50.0, 2e4
    model = cantilever_beam(L, b, [Ply(STEEL, h)], 8, clamp_stiffness=kr,
                            clamp_translational_stiffness=kt)
    s = model.meta["sections"][0]
    assert model.meta["clamp_stiffness"] == {"ry": kr, "uz": kt}
    tip = model.node_set("tip")[0]
    f = np.zeros(model.n_dof)
    f[model.dof_index(tip, "uz")] = P
    u = factorize(model.K).solve(f)
    expected = P * L**3 / (3 * s["EIy"]) + P * L / s["kGAz"] + P * L * L / kr + P / kt
    assert u[model.dof_index(tip, "uz")] == pytest.approx(expected, rel=1e-10)
    clamp = model.node_set("clamp")[0]
    for comp in ("ux", "uy", "rx", "rz"):
        with pytest.raises(ParameterError, match="constrained"):
            model.dof_index(clamp, comp)


# ---------------------------------------------------------------- vibration
def test_slender_cantilever_matches_euler_bernoulli():
    L, b, h = 0.2, 0.02, 0.5e-3
    model = cantilever_beam(L, b, [Ply(STEEL, h)], 40)
    f, _ = freqs_hz(model, 6)
    s = model.meta["sections"][0]
    f_eb = EB_ROOTS**2 / L**2 * np.sqrt(s["EIy"] / s["rhoA"]) / (2 * np.pi)
    # pick the out-of-plane bending modes: lowest, 2nd and 3rd bending are modes 0, 1, 2
    bending = f[[0, 1, 2]]
    np.testing.assert_allclose(bending, f_eb[:3], rtol=2e-4)


def _timoshenko_cantilever_frequencies(L, EI, kGA, rhoA, rhoI, n, f_max):
    """Clamped-free Timoshenko beam frequencies by exact transfer matrices.

    ODE (Timoshenko 1921): rhoA w'' _tt = kGA (w'' - psi'), rhoI psi_tt = EI psi'' +
    kGA (w' - psi). For harmonic motion the state y = [w, psi, w', psi'] obeys
    y' = A(omega) y with constant A, so y(L) = expm(A L) y(0) exactly. Clamp: w = psi = 0;
    free end: EI psi' = 0 and kGA (w' - psi) = 0. Roots of the 2x2 determinant.
    """
    from scipy.linalg import expm
    from scipy.optimize import brentq

    def det(f):
        w2 = (2 * np.pi * f) ** 2
        A = np.array([
            [0, 0, 1, 0],
            [0, 0, 0, 1],
            [-rhoA * w2 / kGA, 0, 0, 1],
            [0, kGA / EI - rhoI * w2 / EI, -kGA / EI, 0],
        ])
        Y = expm(A * L)[:, 2:]  # solutions starting with w' = 1 or psi' = 1
        B = np.array([Y[3], Y[2] - Y[1]])
        return np.linalg.det(B)

    grid = np.linspace(f_max * 1e-3, f_max, 400)  # roots are > 2 kHz apart here
    d = np.array([det(x) for x in grid])
    roots = [brentq(det, grid[i], grid[i + 1], xtol=1e-12)
             for i in np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:]))]
    return np.array(roots[:n])


def test_stubby_cantilever_matches_timoshenko_frequency_equation():
    # L/h = 5: shear and rotary inertia lower f1 by several percent vs Euler-Bernoulli
    L, b, h = 0.25, 0.03, 0.05
    model = cantilever_beam(L, b, [Ply(STEEL, h)], 60)
    s = model.meta["sections"][0]
    f_ref = _timoshenko_cantilever_frequencies(
        L, s["EIy"], s["kGAz"], s["rhoA"], s["rhoIy"], 3, 12000.0)
    assert len(f_ref) == 3
    f_eb = EB_ROOTS[:3] ** 2 / L**2 * np.sqrt(s["EIy"] / s["rhoA"]) / (2 * np.pi)
    assert f_ref[0] < 0.97 * f_eb[0]  # the test case really is shear-dominated
    sol = eigsh_lowest(model.K, model.M, 20)
    f = np.sqrt(sol.omega2) / (2 * np.pi)
    f_bend = f[_plane_fraction(model, sol, (2, 4)) > 0.9][:3]
    np.testing.assert_allclose(f_bend, f_ref, rtol=3e-4)  # 60 elements: 1e-6, 4e-5, 2e-4


def test_frequency_convergence_rate_is_fourth_order():
    # self-convergence against a 128-element solution of the same Timoshenko model (an
    # Euler-Bernoulli reference would stop the rate at the small shear effect)
    L, b, h = 0.2, 0.02, 0.5e-3
    ref, _ = freqs_hz(cantilever_beam(L, b, [Ply(STEEL, h)], 128), 3)
    errs = []
    for n in (4, 8, 16):
        f, _ = freqs_hz(cantilever_beam(L, b, [Ply(STEEL, h)], n), 3)
        errs.append(np.abs(f[1:3] - ref[1:3]) / ref[1:3])
    errs = np.array(errs)
    rates = np.log2(errs[:-1] / errs[1:])
    assert np.all(rates > 3.5), rates  # measured 3.66-3.94
    s = cantilever_beam(L, b, [Ply(STEEL, h)], 4).meta["sections"][0]
    f_eb = EB_ROOTS[1] ** 2 / L**2 * np.sqrt(s["EIy"] / s["rhoA"]) / (2 * np.pi)
    assert ref[1] == pytest.approx(f_eb, rel=1e-4)


def test_torsion_frequencies_of_a_strip():
    # Saint-Venant torsion of a clamped-free shaft: f_n = (2n - 1)/(4L) sqrt(GJ / rho Ip)
    # (torsion of the beam model is uncoupled; linear interpolation converges as h^2)
    L, b, h = 0.3, 0.03, 0.002
    model = cantilever_beam(L, b, [Ply(STEEL, h)], 60)
    s = model.meta["sections"][0]
    sol = eigsh_lowest(model.K, model.M, 24)
    f = np.sqrt(sol.omega2) / (2 * np.pi)
    tors = _plane_fraction(model, sol, (3,)) > 0.99
    ref = np.array([1, 3]) / (4 * L) * np.sqrt(s["GJ"] / (s["rhoIy"] + s["rhoIz"]))
    np.testing.assert_allclose(f[tors][:2], ref, rtol=1e-3)


def test_free_free_beam_has_six_rigid_body_modes_and_correct_first_elastic():
    L, b, h = 0.4, 0.03, 0.002
    model = cantilever_beam(L, b, [Ply(STEEL, h)], 30, clamp=None)
    assert "clamp" not in model.node_sets
    assert model.n_dof == 6 * model.n_nodes
    sol = eigsh_lowest(model.K, model.M, 8)
    s = model.meta["sections"][0]
    wscale = (4.730040745**2 / L**2) ** 2 * s["EIy"] / s["rhoA"]  # free-free root 4.7300
    assert np.all(np.abs(sol.omega2[:6]) < 1e-6 * wscale)
    assert np.sqrt(sol.omega2[6] / wscale) == pytest.approx(1.0, rel=2e-4)


def test_orthotropic_beam_uses_rotated_modulus_in_bending():
    cfrp = OrthotropicMaterial("cfrp", 140e9, 10e9, 5e9, 5e9, 3.5e9, 0.3, 1600)
    L, b, h = 0.3, 0.02, 1e-3
    m0 = cantilever_beam(L, b, [Ply(cfrp, h, 0.0)], 20)
    m90 = cantilever_beam(L, b, [Ply(cfrp, h, 90.0)], 20)
    f0, _ = freqs_hz(m0, 1)
    f90, _ = freqs_hz(m90, 1)
    assert f0[0] / f90[0] == pytest.approx(np.sqrt(14.0), rel=1e-3)


# ---------------------------------------------------------------- builder
def test_patches_points_and_node_sets():
    patch = BeamPatch("pzt", 0.01, 0.06, (Ply(EPOXY, 0.036e-3), Ply(PZT, 0.25e-3)))
    model = cantilever_beam(0.2, 0.04, [Ply(STEEL, 0.5e-3)], 20, patches=[patch],
                            points={"sensor": 0.123})
    x = model.nodes[:, 0]
    assert x[model.node_set("patch:pzt:x0")[0]] == pytest.approx(0.01)
    assert x[model.node_set("patch:pzt:x1")[0]] == pytest.approx(0.06)
    assert x[model.node_set("sensor")[0]] == pytest.approx(0.123)
    on_patch = x[model.node_set("patch:pzt")]
    assert on_patch.min() == pytest.approx(0.01) and on_patch.max() == pytest.approx(0.06)
    assert np.all(np.diff(on_patch) > 0)
    assert x[model.node_set("clamp")[0]] == 0.0
    assert x[model.node_set("tip")[0]] == pytest.approx(0.2)
    assert len(model.meta["sections"]) == 2
    secs = model.meta["element_section"]
    xm = 0.5 * (x[model.elements["beam2"][:, 0]] + x[model.elements["beam2"][:, 1]])
    inside = (xm > 0.01) & (xm < 0.06)
    assert np.all(secs[inside] == secs[inside][0]) and np.all(secs[~inside] != secs[inside][0])
    assert model.meta["sections"][secs[inside][0]]["EIy"] > model.meta["sections"][0]["EIy"]
    # a dict patch is accepted and gives the same model
    same = cantilever_beam(0.2, 0.04, [Ply(STEEL, 0.5e-3)], 20, points={"sensor": 0.123},
                           patches=[{"name": "pzt", "x0": 0.01, "x1": 0.06,
                                     "layers": (Ply(EPOXY, 0.036e-3), Ply(PZT, 0.25e-3))}])
    assert abs(same.K - model.K).max() == 0


def test_clamp_at_x1_mirrors_clamp_at_x0():
    lay = [Ply(STEEL, 0.5e-3)]
    a = cantilever_beam(0.2, 0.02, lay, 10, clamp="x0")
    b = cantilever_beam(0.2, 0.02, lay, 10, clamp="x1")
    fa, _ = freqs_hz(a, 4)
    fb, _ = freqs_hz(b, 4)
    np.testing.assert_allclose(fa, fb, rtol=1e-7)
    assert b.node_set("tip")[0] == 0


def test_bottom_patch_equals_top_patch_of_a_symmetric_layer():
    lay = [Ply(STEEL, 0.5e-3)]
    top = cantilever_beam(0.2, 0.02, lay, 10, patches=[BeamPatch("p", 0.0, 0.1,
                                                                 (Ply(PZT, 2e-4),), "top")])
    bot = cantilever_beam(0.2, 0.02, lay, 10, patches=[BeamPatch("p", 0.0, 0.1,
                                                                 (Ply(PZT, 2e-4),), "bottom")])
    assert abs(top.K - bot.K).max() <= 1e-9 * abs(top.K).max()


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"length": -1.0}, "length must be a positive"),
        ({"width": 0.0}, "width must be a positive"),
        ({"length": "long"}, "length must be a positive"),
        ({"n_elements": "ten"}, "n_elements must be an integer"),
        ({"n_elements": True}, "n_elements must be an integer"),
        ({"n_elements": 0}, "n_elements must be an integer"),
        ({"n_elements": 2.5}, "n_elements must be an integer"),
        ({"clamp": "middle"}, "clamp must be"),
        ({"layers": []}, "layer stack is empty"),
        ({"layers": [STEEL]}, "must be a mvtk.fe.Ply"),
        ({"points": {"s": 0.5}}, "point 's' at x = 0.5 m is outside"),
        ({"clamp_stiffness": {"rq": 1.0}}, "unknown component 'rq'"),
        ({"clamp_stiffness": -3.0}, "clamp stiffness of 'ry' must be a positive stiffness"),
        ({"clamp_stiffness": {"ry": "stiff"}}, "of 'ry' must be a positive stiffness"),
        ({"clamp_translational_stiffness": 0.0}, "of 'uz' must be a positive stiffness"),
        ({"points": {"tip": 0.1}}, "clashes with the built-in node set 'tip'"),
        ({"points": {"s": (0.1, 0.0, 0.0, 1.0)}}, "expected x or \\(x, y\\[, z\\]\\)"),
        ({"shear_correction": 0.0}, "shear_correction must be in"),
        ({"clamp": None, "clamp_stiffness": 1.0}, "clamp is None"),
        ({"patches": [BeamPatch("p", 0.1, 0.3, (Ply(PZT, 1e-4),))]}, "outside the beam"),
        ({"patches": [BeamPatch("p", 0.0, 0.1, (Ply(PZT, 1e-4),)),
                      BeamPatch("p", 0.1, 0.2, (Ply(PZT, 1e-4),))]}, "duplicate patch names"),
        ({"patches": [{"name": "p", "x_start": 0.0}]}, "expected keys name, x0, x1"),
        ({"patches": ["p"]}, "patches must be BeamPatch"),
    ],
)
def test_cantilever_beam_bad_input(kwargs, match):
    args = {"length": 0.2, "width": 0.02, "layers": [Ply(STEEL, 1e-3)], "n_elements": 4}
    args.update(kwargs)
    with pytest.raises(ParameterError, match=match):
        cantilever_beam(**args)


def test_bad_patch_and_section_input():
    with pytest.raises(ParameterError, match="expected x0 < x1"):
        BeamPatch("p", 0.2, 0.1, (Ply(PZT, 1e-4),))
    with pytest.raises(ParameterError, match="expected x0 < x1"):
        BeamPatch("p", "start", 0.1, (Ply(PZT, 1e-4),))
    with pytest.raises(ParameterError, match="expected x or"):
        cantilever_beam(0.2, 0.02, [Ply(STEEL, 1e-3)], 4, points={"s": "middle"})
    with pytest.raises(ParameterError, match="side must be 'top' or 'bottom'"):
        BeamPatch("p", 0.0, 0.1, (Ply(PZT, 1e-4),), side="left")
    with pytest.raises(ParameterError, match="width must be a positive"):
        beam_section([Ply(STEEL, 1e-3)], -0.01)
    with pytest.raises(ParameterError, match="EIy must be positive"):
        timoshenko_element_matrices(1.0, 1.0, 1.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0)
    with pytest.raises(ParameterError, match="rhoA must be >= 0"):
        timoshenko_element_matrices(1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, -1.0, 0.0, 0.0)
    sec = beam_section([Ply(STEEL, 1e-3)], 0.01)
    with pytest.raises(DimensionError, match="zero length"):
        beam_element_matrices([[0, 0, 0]], [[0, 0, 0]], [sec])
    with pytest.raises(ParameterError, match="parallel to the element axis"):
        beam_element_matrices([[0, 0, 0]], [[0, 1, 0]], [sec])
    with pytest.raises(DimensionError, match="expected 1 sections"):
        beam_element_matrices([[0, 0, 0]], [[1, 0, 0]], [sec, sec])
    with pytest.raises(DimensionError, match="shape \\(n_el, 3\\)"):
        beam_element_matrices([[0, 0]], [[1, 0]], [sec])


def test_shear_correction_is_reissner_value():
    assert SHEAR_CORRECTION == pytest.approx(5 / 6)


def test_dense_mass_matrix_is_positive_definite_and_total_mass_right():
    model = cantilever_beam(0.2, 0.02, [Ply(STEEL, 1e-3)], 6, clamp=None)
    M = model.M.toarray()
    assert np.all(sla.eigvalsh(M) > 0)
    u = np.zeros(model.n_dof)
    u[model.dof_component == 2] = 1.0
    assert u @ M @ u == pytest.approx(7900 * 0.2 * 0.02 * 1e-3, rel=1e-12)


def test_layer_widths_section():
    b, bp = 0.04, 0.01
    lay = [Ply(STEEL, 1e-3), Ply(STEEL, 1e-3)]
    same = beam_section(lay, b, layer_widths=[b, b])
    ref = beam_section(lay, b)
    for key, v in ref.as_dict().items():
        assert getattr(same, key) == pytest.approx(v, rel=1e-12), key
    s = beam_section(lay, b, layer_widths=[b, bp])
    assert s.EA == pytest.approx(210e9 * 1e-3 * (b + bp))
    zn = (b * 0.5e-3 + bp * 1.5e-3) / (b + bp)
    assert s.neutral_axis == pytest.approx(zn)
    ei = 210e9 * (b * (1e-9 / 12 + 1e-3 * (0.5e-3 - zn) ** 2)
                  + bp * (1e-9 / 12 + 1e-3 * (1.5e-3 - zn) ** 2))
    assert s.EIy == pytest.approx(ei)
    assert s.EIz == pytest.approx(210e9 * 1e-3 * (b**3 + bp**3) / 12)
    assert s.rhoA == pytest.approx(7900 * 1e-3 * (b + bp))
    assert ref.GJ > s.GJ > beam_section(lay[:1], b).GJ
    with pytest.raises(DimensionError, match="expected 2 layer widths"):
        beam_section(lay, b, layer_widths=[b])
    with pytest.raises(ParameterError, match="layer widths must be positive"):
        beam_section(lay, b, layer_widths=[b, -1.0])
    with pytest.raises(ParameterError, match="patch 'p': width must be a positive"):
        BeamPatch("p", 0.0, 0.1, (Ply(STEEL, 1e-4),), width=0.0)


def test_skew_cantilever_assembled_from_global_matrices_has_same_frequencies():
    # the same cantilever along an arbitrary direction, section width along a chosen y
    L, b, h, n = 0.3, 0.02, 0.004, 12
    ref = cantilever_beam(L, b, [Ply(STEEL, h)], n)
    f_ref, _ = freqs_hz(ref, 8)
    ex = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
    y_ref = np.cross([0.3, -0.2, 1.0], ex)
    xyz = np.linspace(0, L, n + 1)[:, None] * ex
    sec = beam_section([Ply(STEEL, h)], b)
    ke, me = beam_element_matrices(xyz[:-1], xyz[1:], [sec] * n, y_ref=y_ref)
    nd = 6 * (n + 1)
    K = np.zeros((nd, nd))
    M = np.zeros((nd, nd))
    for e in range(n):
        K[6 * e:6 * e + 12, 6 * e:6 * e + 12] += ke[e]
        M[6 * e:6 * e + 12, 6 * e:6 * e + 12] += me[e]
    w2 = sla.eigh(K[6:, 6:], M[6:, 6:], eigvals_only=True)[:8]
    np.testing.assert_allclose(np.sqrt(w2) / (2 * np.pi), f_ref, rtol=1e-9)
