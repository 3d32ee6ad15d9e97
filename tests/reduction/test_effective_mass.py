"""Effective modal mass against the Euler-Bernoulli cantilever closed form."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from mvtk.errors import ParameterError
from mvtk.reduction import EffectiveMassTable, craig_bampton, effective_mass
from mvtk.reduction._examples import eb_beam_xz

BETA_L = np.array([1.875104069, 4.694091133, 7.854757438, 10.99554073])


def cantilever_fractions() -> np.ndarray:
    """(int phi)^2 / (L int phi^2) of the exact cantilever shapes (L = 1)."""
    out = []
    for bl in BETA_L:
        s = (np.cosh(bl) + np.cos(bl)) / (np.sinh(bl) + np.sin(bl))

        def phi(x, bl=bl, s=s):
            return np.cosh(bl * x) - np.cos(bl * x) - s * (np.sinh(bl * x) - np.sin(bl * x))

        a = quad(phi, 0, 1, epsabs=1e-13)[0]
        b = quad(lambda x, phi=phi: phi(x) ** 2, 0, 1, epsabs=1e-13)[0]
        out.append(a * a / b)
    return np.array(out)


def test_closed_form_reference_values():
    # the classical table: 61.3 %, 18.8 %, 6.5 %, 3.3 % of the beam mass
    np.testing.assert_allclose(cantilever_fractions(), [0.6131, 0.1883, 0.0647, 0.0331],
                               atol=6e-5)


def test_fixed_base_fractions_match_closed_form():
    model = eb_beam_xz(n_el=60)
    table = effective_mass(model, "uz", n_modes=6)
    assert table.kind == "fixed_base"
    # relative to the whole beam mass (the clamped node's consistent mass is not free)
    frac = table.effective_mass_kg[:4] / model.meta["mass_kg"]
    np.testing.assert_allclose(frac, cantilever_fractions(), rtol=2e-3)
    assert table.total_mass_kg < model.meta["mass_kg"]
    np.testing.assert_allclose(table.cumulative, np.cumsum(table.fraction))


def test_given_modes_give_the_table_of_a_fresh_solve():
    """modes= (a modal_analysis or eigsh_lowest result of the model) replaces the solve:
    the same table, and the closed form still holds; wrong shapes are refused."""
    from mvtk.errors import DimensionError
    from mvtk.fe import eigsh_lowest, modal_analysis

    model = eb_beam_xz(n_el=60)
    ref = effective_mass(model, "uz", n_modes=6)
    for modes in (modal_analysis(model, 6), eigsh_lowest(model.K, model.M, 6)):
        got = effective_mass(model, "uz", modes=modes)
        np.testing.assert_allclose(got.fn_hz, ref.fn_hz, rtol=1e-12)
        np.testing.assert_allclose(got.effective_mass_kg, ref.effective_mass_kg, rtol=1e-9)
        frac = got.effective_mass_kg[:4] / model.meta["mass_kg"]
        np.testing.assert_allclose(frac, cantilever_fractions(), rtol=2e-3)
    other = eb_beam_xz(n_el=30)
    with pytest.raises(DimensionError, match="shapes of this model"):
        effective_mass(model, "uz", modes=modal_analysis(other, 6))
    with pytest.raises(ParameterError, match="modes= applies"):
        effective_mass(model, "uz", base=["clamp"], modes=ref)


def test_all_modes_sum_to_total_mass():
    model = eb_beam_xz(n_el=20)
    table = effective_mass(model, "uz", n_modes=model.n_dof)
    assert table.cumulative[-1] == pytest.approx(1.0, abs=1e-10)
    assert table.n_for_fraction(0.95) == int(np.argmax(table.cumulative >= 0.95)) + 1


def test_fixed_interface_of_free_beam_with_base_boundary():
    """Free-free beam, boundary = node 0: the interior modes are the cantilever's and the
    base translation constraint mode is rigid (Psi r_l = r_f); the total is the whole
    beam mass and the fractions converge to the closed form."""
    model = eb_beam_xz(n_el=60, clamped=False)
    se = craig_bampton(model, ["clamp"], 8)
    r_l = np.array([1.0, 0.0])  # (uz, ry) of node 0
    rigid = se.T[:, :2] @ r_l
    expected = (model.dof_component == 2).astype(float)
    np.testing.assert_allclose(rigid, expected, atol=1e-8)  # round-off of K_ff^-1 K_fl
    table = effective_mass(se, "uz")
    assert table.kind == "fixed_interface"
    assert table.total_mass_kg == pytest.approx(model.meta["mass_kg"], rel=1e-12)
    np.testing.assert_allclose(table.fraction[:4], cantilever_fractions(), rtol=2e-3)
    # coupling form: L = M_r[eta, l] r_l
    np.testing.assert_allclose(table.participation, se.M[2:, :2] @ r_l, rtol=1e-9)
    df = table.to_dataframe()
    assert list(df.columns) == ["mode", "fn_hz", "participation", "effective_mass_kg",
                                "fraction", "cumulative"]
    assert table.n_below(se.interior_fn_hz[2]) == 3
    same = effective_mass(model, "uz", n_modes=8, base="clamp")
    np.testing.assert_allclose(same.effective_mass_kg, table.effective_mass_kg)
    with pytest.raises(ParameterError, match="base= applies to an FEModel"):
        effective_mass(se, base="clamp")


def test_bad_inputs():
    model = eb_beam_xz(n_el=10)
    with pytest.raises(ParameterError, match="direction must be a translation"):
        effective_mass(model, "ry")
    with pytest.raises(ParameterError, match="no mass moves with a translation in ux"):
        effective_mass(model, "ux")
    with pytest.raises(ParameterError, match="n_modes must be in 1..20"):
        effective_mass(model, n_modes=0)
    with pytest.raises(ParameterError, match="expected an FEModel or a SuperElement"):
        effective_mass(np.eye(3))
    table = effective_mass(model, n_modes=2)
    assert isinstance(table, EffectiveMassTable)
    with pytest.raises(ParameterError, match="does not reach 0.99; compute more modes"):
        table.n_for_fraction(0.99)
    with pytest.raises(ParameterError, match=r"target fraction must be in \(0, 1\]"):
        table.n_for_fraction(0.0)
