"""Modal test plants: closed-form cantilever against beam theory."""

import numpy as np
import pytest

from mvtk.control import cantilever_modal_plant, modal_plant, release_state
from mvtk.control._modal import cantilever_beta_l
from mvtk.errors import DimensionError, ParameterError


def test_cantilever_frequencies_follow_beta_l_squared():
    p = cantilever_modal_plant(4)
    fn = np.array(p.meta["fn_hz"])
    # classical ratios f_n / f_1 = (beta_n L / beta_1 L)^2: 6.2669, 17.547, 34.386
    np.testing.assert_allclose(fn / fn[0], [1.0, 6.26689, 17.5475, 34.3861], rtol=1e-5)
    assert fn[0] == pytest.approx(13.26)


def test_cantilever_rayleigh_damping_matches_paper_time_constant():
    p = cantilever_modal_plant(3)
    z1 = p.meta["zeta"][0]
    w1 = 2 * np.pi * 13.26
    # PHYSICS.md section 2: zeta1 = 5.84e-4, open-loop decay time constant 20.5 s
    assert z1 == pytest.approx(5.84e-4, rel=2e-3)
    assert 1 / (z1 * w1) == pytest.approx(20.5, rel=5e-3)


def test_static_tip_deflection_converges_to_beam_theory():
    """Sum of modal contributions -> Euler-Bernoulli static deflection under the patch
    moments: w(L) = M/EI (x2 - x1) (L - (x1 + x2)/2)."""
    p = cantilever_modal_plant(40)
    ss = p.to_state_space()
    k = ss.dc_gain()[0, 0]
    L, (x1, x2), EI = p.meta["length"], p.meta["patch"], p.meta["EI"]
    exact = -1.984e-4 / EI * (x2 - x1) * (L - 0.5 * (x1 + x2))
    assert k == pytest.approx(exact, rel=2e-3)


def test_collocated_output_matches_input_matrix():
    p = cantilever_modal_plant(5)
    np.testing.assert_allclose(p.B[:, 0], -1.984e-4 * p.Cq[2], rtol=1e-12)


def test_mode_shapes_are_overflow_free_for_high_modes():
    p = cantilever_modal_plant(25)
    # the tip of the mass-normalised shape is +-2 / sqrt(mu L) for every mode
    tip = np.abs(p.Cq[0]) * np.sqrt(0.158 * 0.18)
    np.testing.assert_allclose(tip, 2.0, rtol=1e-9)
    assert np.all(np.isfinite(p.B))


def test_beta_l_roots():
    b = cantilever_beta_l(6)
    np.testing.assert_allclose(1 + np.cos(b[:4]) * np.cosh(b[:4]), 0, atol=1e-9)
    np.testing.assert_allclose(np.cos(b) + 1 / np.cosh(b), 0, atol=1e-14)
    assert b[5] == pytest.approx(11 * np.pi / 2, rel=1e-6)


def test_release_state_scales_output():
    p = cantilever_modal_plant(3)
    x0 = release_state(p, 1, "tip", 2e-3)
    assert p.Cq[0] @ x0[:3] == pytest.approx(2e-3)
    assert np.all(x0[3:] == 0)
    assert np.count_nonzero(x0[:3]) == 1


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"n_modes": 0}, "n_modes"),
        ({"length": -1.0}, "must be > 0"),
        ({"patch": (0.1, 0.05)}, "patch"),
        ({"sensor_x": 0.5}, "sensor_x"),
    ],
)
def test_cantilever_bad_input(kwargs, match):
    with pytest.raises(ParameterError, match=match):
        cantilever_modal_plant(**kwargs)


def test_modal_plant_bad_input():
    with pytest.raises(ParameterError, match="fn_hz"):
        modal_plant([0.0], 0.01, [[1.0]], [[1.0]])
    with pytest.raises(DimensionError, match="zeta"):
        modal_plant([1.0, 2.0], [0.01, 0.02, 0.03], [[1.0], [1.0]], [[1.0, 1.0]])
    with pytest.raises(ParameterError, match="zeta must be >= 0"):
        modal_plant([1.0], -0.01, [[1.0]], [[1.0]])
    with pytest.raises(DimensionError, match="Cq must have 2 columns"):
        modal_plant([1.0, 2.0], 0.01, [[1.0], [1.0]], [[1.0]])


def test_release_state_bad_input():
    p = cantilever_modal_plant(3)
    with pytest.raises(ParameterError, match="mode must be in 1..3"):
        release_state(p, 4, "tip")
    with pytest.raises(ParameterError, match="unknown output 'nope'"):
        release_state(p, 1, "nope")
    with pytest.raises(ParameterError, match="SecondOrderSystem"):
        release_state(p.to_state_space(), 1, "tip")


def test_release_state_needs_positive_definite_mass():
    from mvtk.control import SecondOrderSystem

    p = SecondOrderSystem(np.diag([1.0, 0.0]), np.zeros((2, 2)), np.eye(2), [[1.0], [0.0]],
                          [[1.0, 0.0]], [[0.0, 0.0]])
    with pytest.raises(ParameterError, match="positive definite mass"):
        release_state(p, 1, None)
