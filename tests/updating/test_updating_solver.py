"""Twin experiments, sensitivities, uncertainty and diagnostics of mvtk.updating.update."""

from __future__ import annotations

import json
import tomllib
import warnings

import numpy as np
import pytest
from updating_helpers import NOMINAL, model_fn, strip_model

from mvtk.errors import (
    AccuracyWarning,
    ConfigError,
    DimensionError,
    IdentifiabilityWarning,
    ParameterError,
)
from mvtk.updating import (
    FrequencyTarget,
    Parameter,
    eigen_sensitivity,
    update,
    with_values,
)

E, KR = "materials.steel.E", "boundary.clamp_stiffness"
# rigid clamp, no tip mass: every frequency scales exactly with sqrt(E / rho)
RIGID = {**{k: v for k, v in NOMINAL.items() if k != "boundary"}, "tip_mass": 0.0}


def _truth(n=4, desc=NOMINAL):
    return model_fn(desc, n=max(n, 3))[0][:n]


def _quiet_update(*args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any warning fails the identifiable twin tests
        return update(*args, builder=strip_model, **kwargs)


@pytest.mark.parametrize(
    "path", [E, "materials.steel.rho", KR, "tip_mass", "structure.length",
             "structure.thickness", "structure.width"],
)
def test_sensitivity_matches_finite_differences_of_eigenvalues(path):
    s = eigen_sensitivity(NOMINAL, [path], builder=strip_model, n_modes=6)
    p0 = s.values[0]
    h = 1e-4 * p0
    fp = model_fn(with_values(NOMINAL, {path: p0 + h}), n=6)[0]
    fm = model_fn(with_values(NOMINAL, {path: p0 - h}), n=6)[0]
    fd = (fp - fm) / (2 * h)
    # (torsion modes do not depend on clamp spring or tip mass: exact 0 vs FD noise)
    np.testing.assert_allclose(s.d_fn_hz[:, 0], fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())


def test_forward_matrix_differences_exact_for_linear_parameters_not_geometry():
    fwd = eigen_sensitivity(RIGID, [E, "structure.length"], builder=strip_model, n_modes=4,
                            difference="forward")
    cen = eigen_sensitivity(RIGID, [E, "structure.length"], builder=strip_model, n_modes=4)
    # f ~ sqrt(E) with a rigid clamp: normalised sensitivity exactly 1/2
    np.testing.assert_allclose(fwd.normalised[:, 0], 0.5, rtol=1e-6)
    np.testing.assert_allclose(cen.normalised[:, 0], 0.5, rtol=1e-6)
    # geometry: the forward difference error is amplified (see module notes)
    err = np.abs(fwd.d_fn_hz[:, 1] / cen.d_fn_hz[:, 1] - 1)
    assert 1e-5 < err.max() < 1e-2
    with pytest.raises(ParameterError, match="difference must be 'central' or 'forward'"):
        eigen_sensitivity(RIGID, [E], builder=strip_model, n_modes=2, difference="back")


def test_sensitivity_rejects_a_changing_mesh():
    def remesh(d):
        return strip_model(with_values(d, {"structure.n_elements": 20 + (d["tip_mass"] > 0.002)}))

    with pytest.raises(DimensionError, match="perturbing 'tip_mass' changed the model's free DOFs"):
        eigen_sensitivity(NOMINAL, ["tip_mass"], builder=remesh, n_modes=4)


def test_twin_modulus_and_clamp_stiffness_recovered():
    f = _truth(4)
    start = with_values(NOMINAL, {E: 2.1e11 * 1.2, KR: 6.0 * 0.75})
    params = [Parameter(E, lower=1e11, upper=4e11), Parameter(KR, lower=0.1, upper=100.0)]
    r = _quiet_update(start, params, [FrequencyTarget(x) for x in f])
    np.testing.assert_allclose(r.values, [2.1e11, 6.0], rtol=5e-3)
    assert np.abs(r.residual_table()["error_pct"]).max() < 1e-4
    assert np.abs(r.residual_table()["initial_error_pct"]).max() > 4
    assert r.success and r.identifiable and not r.at_bound.any()
    assert r.description["materials"]["steel"]["E"] == pytest.approx(2.1e11, rel=5e-3)
    assert start["materials"]["steel"]["E"] == 2.1e11 * 1.2  # input untouched
    assert r.initial_description == start
    # with an elastic clamp the bending modes depend on E less than sqrt(E); torsion
    # modes (3rd) exactly as sqrt(E)
    assert r.sensitivity[2, 0] == pytest.approx(0.5, rel=1e-6)
    assert np.all(r.sensitivity[[0, 1, 3], 0] < 0.49)
    # the unpaired modes are the remaining computed ones, in ascending order
    un = r.unpaired_table()
    assert list(un.index) == list(range(5, len(r.model_fn_hz) + 1))
    assert np.all(np.diff(un["fn_hz"]) > 0)
    assert r.timing["n_builds"] >= 1 + 2 * r.n_jacobians


def test_twin_geometry_and_tip_mass_recovered_from_minus_30_percent():
    truth = with_values(NOMINAL, {"structure.length": 0.2, "tip_mass": 0.004})
    f = _truth(4, truth)
    start = with_values(truth, {"structure.length": 0.2 * 0.9, "tip_mass": 0.004 * 0.7})
    params = [Parameter("structure.length", lower=0.1, upper=0.3),
              Parameter("tip_mass", lower=0.0, upper=0.02)]
    r = _quiet_update(start, params, f.tolist())
    np.testing.assert_allclose(r.values, [0.2, 0.004], rtol=5e-3)


def test_modulus_and_density_are_not_identifiable_from_frequencies():
    f = _truth(4, RIGID)
    start = with_values(RIGID, {E: 2.1e11 * 1.2})
    with pytest.warns(IdentifiabilityWarning, match=r"condition number .*materials\.steel\.E.*"
                      r"materials\.steel\.rho"):
        r = update(start, [E, "materials.steel.rho"], f.tolist(), builder=strip_model)
    assert not r.identifiable
    assert r.singular_values[1] / r.singular_values[0] < 1e-5
    assert np.isinf(r.std).all()
    # the frequencies still match: E/rho is what the data fix
    assert np.abs(r.residual_table()["error_pct"]).max() < 1e-3
    assert r.values[0] / r.values[1] == pytest.approx(2.1e11 / 7850, rel=1e-4)
    # fixing rho makes E identifiable again
    r2 = _quiet_update(start, [E, Parameter("materials.steel.rho", fixed=True)], f.tolist())
    assert r2.values[0] == pytest.approx(2.1e11, rel=1e-6) and r2.values[1] == 7850
    assert np.isnan(r2.std[1])


def test_fewer_targets_than_parameters_warns():
    f = _truth(1)
    with pytest.warns(IdentifiabilityWarning, match="1 target frequencies for 2 free parameters"):
        update(NOMINAL, [E, KR], f.tolist(), builder=strip_model)


def test_regularization_pulls_towards_initial_values():
    f = _truth(4, RIGID)
    start = with_values(RIGID, {E: 2.1e11 * 1.2})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IdentifiabilityWarning)
        r0 = update(start, [E, "materials.steel.rho"], f.tolist(), builder=strip_model,
                    regularization=1e-2)
    # minimal-norm move in scaled variables: E down and rho up by about equal relative steps
    dE, drho = r0.values / r0.initial_values - 1
    assert dE < 0 < drho and abs(dE) == pytest.approx(abs(drho), rel=0.3)
    assert np.isfinite(r0.std).all()
    r1 = _quiet_update(start, [E], f.tolist(), regularization=1e3)
    assert abs(r1.values[0] / (2.1e11 * 1.2) - 1) < 0.01  # barely moved


def _noisy_fit(rng, sigma, n_targets=8):
    f = _truth(n_targets)
    noisy = f * (1 + sigma * rng.standard_normal(f.size))
    start = with_values(NOMINAL, {E: 2.1e11 * 1.1, KR: 6.0 * 1.2})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", AccuracyWarning)
        return update(start, [Parameter(E, lower=1e10, upper=1e12),
                              Parameter(KR, lower=0.01, upper=1e3)],
                      noisy.tolist(), builder=strip_model)


def test_noisy_targets_uncertainty_grows_with_noise_and_covers_truth(rng):
    truth = np.array([2.1e11, 6.0])
    small = _noisy_fit(rng, 1e-3)
    large = _noisy_fit(rng, 1e-2)
    assert np.all(large.std > 3 * small.std)
    for r in (small, large):
        assert np.all(np.abs(r.values - truth) < 3 * r.std)
        assert r.cost > 0


@pytest.mark.slow
def test_predicted_std_matches_monte_carlo_scatter(rng):
    sigma = 5e-3
    coarse = with_values(NOMINAL, {"structure.n_elements": 8})
    f = _truth(6, coarse)
    params = [Parameter(E, lower=1e10, upper=1e12), Parameter(KR, lower=0.01, upper=1e3)]
    est = []
    predicted = None
    for _ in range(25):
        noisy = f * (1 + sigma * rng.standard_normal(f.size))
        # E and the clamp spring enter K linearly: forward differences are exact
        r = update(coarse, params, noisy.tolist(), builder=strip_model, frequency_std=sigma,
                   difference="forward", n_modes=6)
        est.append(r.values)
        predicted = r.std
    scatter = np.std(est, axis=0, ddof=1)
    # 25 samples: the sample std is within about +-30 % of the truth at 2 sigma
    np.testing.assert_allclose(scatter, predicted, rtol=0.4)


def test_bound_hit_is_reported():
    f = _truth(4)
    with pytest.warns(AccuracyWarning, match=r"\['materials.steel.E'\] ended on a bound"):
        r = update(NOMINAL, [Parameter(E, lower=2.2e11, upper=3e11, initial=2.5e11)],
                   f.tolist(), builder=strip_model)
    assert r.at_bound[0] and r.values[0] == pytest.approx(2.2e11)
    assert bool(r.parameter_table()["at_bound"].iloc[0])


def test_max_iter_reached_warns_and_flags_failure():
    f = _truth(4)
    start = with_values(NOMINAL, {E: 2.1e11 * 1.3, KR: 6.0 * 0.7})
    with pytest.warns(AccuracyWarning, match=r"stopped after 2 evaluations \(max_iter=2\)"):
        r = update(start, [E, KR], f.tolist(), builder=strip_model, max_iter=2)
    assert not r.success


def test_kind_pairing_and_swap_report_when_modes_cross():
    # widening the strip lowers torsion below the second bending mode
    truth = with_values(NOMINAL, {"structure.width": 0.08})
    f, eig, m = model_fn(truth, n=4)
    from mvtk.updating import classify_modes

    kinds = classify_modes(m, eig.vectors)
    assert kinds[:3] == ["bending", "torsion", "bending"]
    targets = [FrequencyTarget(f[0], kind="bending"), FrequencyTarget(f[1], kind="torsion"),
               FrequencyTarget(f[2], kind="bending")]
    start = with_values(truth, {"structure.width": 0.04})
    r = _quiet_update(start, [Parameter("structure.width", lower=0.01, upper=0.2)], targets)
    assert r.values[0] == pytest.approx(0.08, rel=5e-3)
    assert r.modes_initial.tolist() == [1, 3, 2] and r.modes.tolist() == [1, 2, 3]
    moved = {(s["target"], s["from_mode"], s["to_mode"]) for s in r.swaps}
    assert ("f2", 3, 2) in moved and ("f3", 2, 3) in moved
    assert list(r.residual_table()["kind"]) == ["bending", "torsion", "bending"]


def test_mac_pairing_and_mac_residuals():
    truth = with_values(NOMINAL, {"structure.width": 0.08})
    f, eig, m = model_fn(truth, n=4)
    sensors = [(n, "uz") for n in (3, 6, 9, 12)] + [(n, "rx") for n in (6, 12)]
    rows = [m.dof_index(n, c) for n, c in sensors]
    targets = [FrequencyTarget(f[j], shape=dict(zip(sensors, eig.vectors[rows, j])),
                               label=f"m{j + 1}") for j in range(3)]
    start = with_values(truth, {"structure.width": 0.04, E: 2.4e11})
    params = [Parameter("structure.width", lower=0.01, upper=0.2), Parameter(E, lower=1e11)]
    r = _quiet_update(start, params, targets, mac_weight=0.1)
    np.testing.assert_allclose(r.values, [0.08, 2.1e11], rtol=5e-3)
    assert r.pairing_method == ("mac", "mac", "mac")
    assert r.modes_initial.tolist() == [1, 3, 2]
    assert np.all(r.mac > 0.999)


def test_result_tables_toml_and_json(tmp_path):
    f = _truth(3)
    start = with_values(NOMINAL, {E: 2.3e11})
    r = _quiet_update(start, [Parameter(E, lower=1e11, upper=4e11)], f.tolist())
    assert list(r.to_dataframe().columns[:5]) == [
        "target_hz", "initial_hz", "updated_hz", "initial_error_pct", "error_pct"]
    p = r.to_dataframe("parameters")
    assert p.loc[E, "change_pct"] == pytest.approx(100 * (2.1 / 2.3 - 1), rel=1e-4)
    h = r.to_dataframe("history")
    assert len(h) >= 2 and h["cost"].iloc[-1] < h["cost"].iloc[0]
    assert r.to_dataframe("sensitivity").shape == (3, 1)
    with pytest.raises(ParameterError, match="unknown table 'foo'; expected one of"):
        r.to_dataframe("foo")
    out = r.write_toml(tmp_path / "updated.toml")
    back = tomllib.loads(out.read_text())
    # the written file is a valid starting point (description given as a path)
    again = _quiet_update(out, [Parameter(E, lower=1e11, upper=4e11)], f.tolist())
    assert again.n_evaluations == 1 and again.values[0] == pytest.approx(r.values[0])
    assert back["materials"]["steel"]["E"] == pytest.approx(2.1e11, rel=1e-6)
    assert back["patches"] == NOMINAL["patches"]
    d = json.loads(json.dumps(r.to_dict()))
    assert d["updated_values"][E] == pytest.approx(2.1e11, rel=1e-6)
    assert "<table" in r._repr_html_()


def test_update_bad_inputs():
    f = _truth(2).tolist()
    kw = {"builder": strip_model}
    cases = [
        (([], f), {}, ParameterError, "at least one parameter"),
        (([E, E], f), {}, ParameterError, r"parameters listed twice: \['materials.steel.E'\]"),
        (([Parameter(E, fixed=True)], f), {}, ParameterError, "all parameters are fixed"),
        (([E], []), {}, ParameterError, "at least one target frequency"),
        (([E], ["13"]), {}, ParameterError, "target 1: expected a FrequencyTarget"),
        (([E], f), {"weights": [1.0]}, ParameterError, "expected 2 weights"),
        (([E], f), {"weights": [0.0, 0.0]}, ParameterError, "all target weights are zero"),
        (([E], f), {"n_modes": 1}, ParameterError, "n_modes must be an integer >= 2"),
        (([E], f), {"regularization": -1.0}, ParameterError, "regularization must be"),
        (([E], f), {"max_iter": 0}, ParameterError, "max_iter must be a positive integer"),
        (([E], f), {"frequency_std": 0.0}, ParameterError, "frequency_std must be a positive"),
        (([E], f), {"rel_step": 2.0}, ParameterError, r"rel_step must be in \(0, 1\)"),
        (([E], f), {"difference": "x"}, ParameterError, "difference must be 'central'"),
        ((["materials.alu.E"], f), {}, ConfigError, "no key 'alu' under materials"),
    ]
    for args, extra, exc, match in cases:
        with pytest.raises(exc, match=match):
            update(NOMINAL, *args, **kw, **extra)
    with pytest.raises(ParameterError, match="description must be a mapping"):
        update([1], [E], f, **kw)
    with pytest.raises(ConfigError, match="cannot read structure TOML .*absent.toml"):
        update("absent.toml", [E], f, **kw)
    with pytest.raises(ParameterError, match="must return an mvtk.fe.FEModel, got dict"):
        update(NOMINAL, [E], f, builder=lambda d: d)


def test_log_parameter_recovers_spring_from_a_decade_off_and_stops_on_match():
    f = _truth(4)
    start = with_values(NOMINAL, {KR: 60.0, E: 2.3e11})
    params = [Parameter(E, lower=1e11, upper=4e11),
              Parameter(KR, lower=1e-2, upper=1e4, log=True)]
    r = _quiet_update(start, params, f.tolist())
    np.testing.assert_allclose(r.values, [2.1e11, 6.0], rtol=1e-4)
    assert r.message.startswith("every relative frequency error is below freq_tol = 1e-07")
    assert np.abs(r.residual_table()["error_pct"]).max() <= 1e-5
    # the covariance is mapped back to physical units (d p / d log p = p)
    assert r.covariance.shape == (2, 2)
    with pytest.raises(ParameterError, match="log=True needs a positive value"):
        update(with_values(NOMINAL, {KR: -1.0}), [Parameter(KR, log=True)], f.tolist(),
               builder=strip_model)
    with pytest.raises(ParameterError, match="freq_tol must be a number >= 0"):
        update(NOMINAL, [E], f.tolist(), builder=strip_model, freq_tol=-1)


def test_affine_path_matches_full_rebuilds_with_fewer_builds():
    f = _truth(4)
    start = with_values(NOMINAL, {E: 2.1e11 * 1.2, KR: 6.0 * 0.75})
    params = [Parameter(E, lower=1e11, upper=4e11), Parameter(KR, lower=0.1, upper=100.0)]
    full = _quiet_update(start, params, f.tolist())
    aff = _quiet_update(start, params, f.tolist(), affine=True)
    np.testing.assert_allclose(aff.values, [2.1e11, 6.0], rtol=1e-5)
    np.testing.assert_allclose(aff.values, full.values, rtol=1e-5)
    assert aff.meta["affine_check_rel"] < 1e-7
    assert aff.timing["n_builds"] == 1 + 2 + 1  # base, one per parameter, final check
    assert full.timing["n_builds"] > aff.timing["n_builds"]


def test_affine_path_detects_geometry():
    f = _truth(3)
    start = with_values(NOMINAL, {"structure.length": 0.16})
    with pytest.warns(AccuracyWarning, match="the matrices are not affine in the parameters"):
        r = update(start, [Parameter("structure.length", lower=0.1, upper=0.3)], f.tolist(),
                   builder=strip_model, affine=True)
    assert r.meta["affine_check_rel"] > 1e-4


def test_mesh_change_on_both_sides_falls_back_to_eigenvalue_differences():
    def remeshing(d):
        # 12 elements at "round" tip masses, 13 otherwise: every small step remeshes there
        m = d["tip_mass"]
        n = 12 if abs(m - round(m, 4)) < 1e-12 else 13
        return strip_model(with_values(d, {"structure.n_elements": n}))

    f = _truth(3)
    start = with_values(NOMINAL, {"tip_mass": 0.003})
    r = _quiet_update(start, [Parameter("tip_mass", lower=0.0, upper=0.01)], f.tolist())
    assert r.values[0] == pytest.approx(0.002, rel=1e-6)  # reference: fixed mesh
    r2 = update(start, [Parameter("tip_mass", lower=0.0, upper=0.01)], f.tolist(),
                builder=remeshing)
    assert r2.meta["fd_eigen_parameters"] == ["tip_mass"]
    # 13 instead of 12 elements away from round values: small discretisation offset only
    assert r2.values[0] == pytest.approx(0.002, rel=0.05)
