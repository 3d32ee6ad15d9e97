import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mvtk.damping import RayleighFit, rayleigh_fit, rayleigh_zeta
from mvtk.errors import (
    AccuracyWarning,
    DimensionError,
    IdentifiabilityWarning,
    ParameterError,
)


def test_paper_table3_half_power_pair():
    # paper Table 3: alpha 0.02955, beta 9.77e-6 from zeta 5.84e-4 @ 13.26, 1.32e-3 @ 41.14
    r = rayleigh_fit([13.26, 41.14], [5.84e-4, 1.32e-3])
    assert r.beta == pytest.approx(9.77e-6, rel=2e-3)
    assert r.alpha == pytest.approx(0.02955, rel=5e-3)
    # the paper's zeta1 is printed to 3 digits; 5.8437e-4 (inside its rounding interval
    # 5.835e-4..5.845e-4) gives both printed coefficients to their printed digits
    r2 = rayleigh_fit([13.26, 41.14], [5.8437e-4, 1.32e-3])
    assert round(r2.alpha, 5) == 0.02955
    assert round(r2.beta * 1e6, 2) == 9.77
    np.testing.assert_allclose(r.residual, 0.0, atol=1e-15)


def test_closed_form_and_least_squares_agree_for_two_modes():
    a = rayleigh_fit([10.0, 30.0], [0.01, 0.02])
    b = rayleigh_fit([10.0, 30.0], [0.01, 0.02], "least_squares", weights="inverse_omega")
    assert b.alpha == pytest.approx(a.alpha, rel=1e-10)
    assert b.beta == pytest.approx(a.beta, rel=1e-10)


@settings(max_examples=50, deadline=None)
@given(alpha=st.floats(0.0, 5.0), beta=st.floats(0.0, 1e-3),
       f=st.lists(st.floats(1.0, 500.0), min_size=2, max_size=8, unique=True))
def test_property_exact_rayleigh_recovered(alpha, beta, f):
    f = np.array(sorted(f))
    if np.min(np.diff(f)) < 0.05 * f[0]:
        return
    z = rayleigh_zeta(f, alpha, beta)
    if np.any(z >= 1):
        return
    r = rayleigh_fit(f, z, "least_squares")
    scale_a = max(alpha, 1e-3)
    assert r.alpha == pytest.approx(alpha, abs=1e-6 * scale_a + 1e-9)
    assert r.beta == pytest.approx(beta, abs=1e-6 * max(beta, 1e-7) + 1e-12)
    np.testing.assert_allclose(r.zeta_fit, z, rtol=1e-6, atol=1e-12)


def test_weights_and_nonnegative():
    f = np.array([5.0, 20.0, 60.0, 150.0])
    z = np.array([0.02, 0.005, 0.006, 0.012])
    free = rayleigh_fit(f, z, "least_squares")
    uniform = rayleigh_fit(f, z, "least_squares", weights=[1, 1, 1, 1])
    assert free.alpha == pytest.approx(uniform.alpha)
    nn = rayleigh_fit(f, z, "least_squares", nonnegative=True)
    assert nn.alpha >= 0 and nn.beta >= 0
    # a decreasing damping trend needs beta < 0 without the constraint
    dec = rayleigh_fit([10.0, 40.0], [0.02, 0.001])
    assert dec.beta < 0
    dec_nn = rayleigh_fit([10.0, 40.0], [0.02, 0.001], nonnegative=True)
    assert dec_nn.beta == 0.0 and dec_nn.alpha > 0
    mf = rayleigh_fit(f, z, "least_squares", weights="mass_fraction",
                      mass_fraction=[0.6, 0.2, 0.1, 0.05])
    # the heavy mode 1 dominates the fit
    assert abs(mf.residual[0]) < abs(free.residual[0])


def test_chowdhury_anchor_rule():
    f = np.array([2.0, 6.0, 11.0, 18.0, 30.0])
    mass = np.array([0.62, 0.2, 0.09, 0.05, 0.02])  # cumulative 0.62 0.82 0.91 0.96 0.98
    r = rayleigh_fit(f, 0.05, "chowdhury", mass_fraction=mass)
    assert r.anchors == (0, 2)  # mode 1 and the first to reach 90 %
    two = rayleigh_fit(f, 0.05, modes=(0, 2))
    assert (r.alpha, r.beta) == (two.alpha, two.beta)
    np.testing.assert_allclose(r.zeta_fit[[0, 2]], 0.05)
    assert np.all(r.zeta_fit[1:2] < 0.05)  # modes between anchors are under-damped
    r95 = rayleigh_fit(f, 0.05, "chowdhury", mass_fraction=mass, target_mass=0.95)
    assert r95.anchors == (0, 3)
    with pytest.warns(IdentifiabilityWarning, match="mode 1 alone"):
        rayleigh_fit(f, 0.05, "chowdhury", mass_fraction=[0.95, 0.02, 0.01, 0.01, 0.01])


def test_result_object():
    r = rayleigh_fit([13.26, 41.14], [5.84e-4, 1.32e-3])
    assert isinstance(r, RayleighFit)
    assert r.zeta_at(13.26) == pytest.approx(5.84e-4, rel=1e-9)
    with pytest.warns(AccuracyWarning, match="extrapolated"):
        r.zeta_at(150.0)
    df = r.to_dataframe()
    assert df.attrs["alpha"] == r.alpha and list(df["anchor"]) == [True, True]
    with pytest.raises(AttributeError):
        r.alpha = 1.0


def test_errors():
    with pytest.raises(DimensionError, match="at least 2 modes"):
        rayleigh_fit([10.0], [0.01])
    with pytest.raises(ParameterError, match="not %"):
        rayleigh_fit([10.0, 20.0], [1.0, 2.0])
    with pytest.raises(ParameterError, match="distinct"):
        rayleigh_fit([10.0, 10.0], [0.01, 0.02])
    with pytest.raises(DimensionError, match="zeta needs 3 values"):
        rayleigh_fit([1.0, 2.0, 3.0], [0.01, 0.02])
    with pytest.raises(ParameterError, match="method must be 'two_mode'"):
        rayleigh_fit([10.0, 20.0], [0.01, 0.02], "caughey")
    with pytest.raises(ParameterError, match="needs mass_fraction"):
        rayleigh_fit([10.0, 20.0], [0.01, 0.02], "chowdhury")
    with pytest.raises(ParameterError, match="never reaches"):
        rayleigh_fit([10.0, 20.0], [0.01, 0.02], "chowdhury", mass_fraction=[0.3, 0.2])
    with pytest.raises(ParameterError, match="weights must be"):
        rayleigh_fit([10.0, 20.0], [0.01, 0.02], "least_squares", weights="ones")
    with pytest.raises(ParameterError, match="two distinct indices"):
        rayleigh_fit([10.0, 20.0], [0.01, 0.02], modes=(0, 0))
    with pytest.raises(ParameterError, match="fn_hz must be finite and > 0"):
        rayleigh_fit([-1.0, 20.0], [0.01, 0.02])


def test_results_render_html():
    r = rayleigh_fit([13.26, 41.14], [5.84e-4, 1.32e-3])
    html = r._repr_html_()
    assert "<table" in html and "zeta" in html and "fit" in html
