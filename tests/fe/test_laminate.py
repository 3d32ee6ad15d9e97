"""Laminate ABD, shear and inertia terms against closed forms (Reddy 2004, ch. 3)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtk.errors import ParameterError
from mvtk.fe import IsotropicMaterial, Laminate, OrthotropicMaterial, Ply

STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
CFRP = OrthotropicMaterial("cfrp", E1=140e9, E2=10e9, G12=5e9, G13=5e9, G23=3.5e9,
                           nu12=0.3, rho=1600.0)


def test_homogeneous_plate_closed_forms():
    h = 2e-3
    lam = Laminate((Ply(STEEL, h),))
    E, nu = 210e9, 0.3
    assert lam.A[0, 0] == pytest.approx(E * h / (1 - nu**2), rel=1e-12)
    assert lam.A[0, 1] == pytest.approx(nu * E * h / (1 - nu**2), rel=1e-12)
    assert lam.A[2, 2] == pytest.approx(E / (2 * (1 + nu)) * h, rel=1e-12)
    assert lam.D[0, 0] == pytest.approx(E * h**3 / (12 * (1 - nu**2)), rel=1e-12)
    np.testing.assert_allclose(lam.B, 0.0, atol=1e-9)
    G = E / (2 * (1 + nu))
    np.testing.assert_allclose(lam.H, np.diag([5 / 6 * G * h] * 2), rtol=1e-12)
    assert lam.I0 == pytest.approx(7850 * h)
    assert lam.I1 == pytest.approx(0.0, abs=1e-18)
    assert lam.I2 == pytest.approx(7850 * h**3 / 12)


def test_split_plies_equal_single_ply():
    one = Laminate((Ply(STEEL, 1e-3),))
    four = Laminate(tuple(Ply(STEEL, 0.25e-3) for _ in range(4)))
    np.testing.assert_allclose(four.ABD, one.ABD, rtol=1e-12, atol=1e-6)


def test_offset_reference_surface_parallel_axis():
    h = 1e-3
    mid = Laminate((Ply(STEEL, h),))
    bottom = Laminate((Ply(STEEL, h),), z_bottom=0.0)
    d = h / 2  # mid-plane sits at z = h/2 above the reference surface
    np.testing.assert_allclose(bottom.A, mid.A, rtol=1e-12)
    np.testing.assert_allclose(bottom.B, mid.A * d, rtol=1e-12)
    np.testing.assert_allclose(bottom.D, mid.D + mid.A * d**2, rtol=1e-12)
    assert bottom.I1 == pytest.approx(mid.I0 * d)
    assert bottom.I2 == pytest.approx(mid.I2 + mid.I0 * d**2)


def test_unsymmetric_stack_couples_and_matches_two_layer_formula():
    soft = IsotropicMaterial("epoxy", 3.5e9, 0.35, 1180.0)
    t1, t2 = 0.5e-3, 0.25e-3
    lam = Laminate((Ply(STEEL, t1), Ply(soft, t2)))
    h = t1 + t2
    z = np.array([-h / 2, -h / 2 + t1, h / 2])
    Q1 = STEEL.plane_stress_q()
    Q2 = soft.plane_stress_q()
    B = 0.5 * (Q1 * (z[1] ** 2 - z[0] ** 2) + Q2 * (z[2] ** 2 - z[1] ** 2))
    np.testing.assert_allclose(lam.B, B, rtol=1e-12)
    assert abs(lam.B[0, 0]) > 1e-3 * lam.A[0, 0] * h  # genuinely coupled


def test_cross_ply_and_angle_ply_transformations():
    lam0 = Laminate((Ply(CFRP, 1e-3, 0.0),))
    lam90 = Laminate((Ply(CFRP, 1e-3, 90.0),))
    assert lam90.A[0, 0] == pytest.approx(lam0.A[1, 1], rel=1e-12)
    assert lam90.A[1, 1] == pytest.approx(lam0.A[0, 0], rel=1e-12)
    assert lam90.H[0, 0] == pytest.approx(lam0.H[1, 1], rel=1e-12)
    # [0/90/90/0] is symmetric: B = 0, D16 = 0
    cp = Laminate(tuple(Ply(CFRP, 0.25e-3, a) for a in (0, 90, 90, 0)))
    np.testing.assert_allclose(cp.B, 0.0, atol=1e-6 * cp.A[0, 0] * 1e-3)
    # a single 45 degree ply: Qbar16 = (Q11 - Q12 - 2 Q66)/4 - (Q22 - Q12 - 2 Q66)/4
    Q = CFRP.plane_stress_q()
    lam45 = Laminate((Ply(CFRP, 1e-3, 45.0),))
    q16 = (Q[0, 0] - Q[0, 1] - 2 * Q[2, 2]) / 4 - (Q[1, 1] - Q[0, 1] - 2 * Q[2, 2]) / 4
    assert lam45.A[0, 2] / 1e-3 == pytest.approx(q16, rel=1e-12)


def test_bad_inputs():
    with pytest.raises(ParameterError, match="at least one ply"):
        Laminate(())
    with pytest.raises(ParameterError, match="must be a Ply"):
        Laminate((STEEL,))
    with pytest.raises(ParameterError, match="shear_correction"):
        Laminate((Ply(STEEL, 1e-3),), shear_correction=0.0)


def _random_plies(draw_angles, draw_t):
    return [Ply(CFRP, t, a) for a, t in zip(draw_angles, draw_t)]


_angles = st.lists(st.sampled_from([0.0, 30.0, 45.0, -45.0, 90.0, 15.0]), min_size=1,
                   max_size=4)


@settings(max_examples=40, deadline=None)
@given(_angles, st.floats(1e-4, 2e-3))
def test_property_symmetric_stacks_uncoupled_and_abd_positive(angles, t):
    sym = Laminate(tuple(_random_plies(angles + angles[::-1], [t] * (2 * len(angles)))))
    scale = np.abs(sym.A).max() * sym.thickness
    np.testing.assert_allclose(sym.B, 0.0, atol=1e-12 * scale)
    # any stack: ABD positive definite (strain energy > 0), H positive definite
    lam = Laminate(tuple(_random_plies(angles, [t] * len(angles))), z_bottom=-t / 3)
    S = np.diag(1 / np.sqrt(np.diag(lam.ABD)))
    assert np.linalg.eigvalsh(S @ lam.ABD @ S).min() > 0
    assert np.linalg.eigvalsh(lam.H).min() > 0
    # rotating every ply by 180 degrees changes nothing
    rot = Laminate(tuple(Ply(CFRP, t, a + 180.0) for a in angles), z_bottom=-t / 3)
    np.testing.assert_allclose(rot.ABD, lam.ABD, rtol=1e-10, atol=1e-9 * np.abs(lam.ABD).max())
