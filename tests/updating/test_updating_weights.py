"""Statistical weights of updating targets: identification variance + model-form term.

The truth is a fresh closed-form case (a 3-mass spring chain, not a model the rest of the
suite uses): its frequencies scale as ``sqrt(k)`` when every spring scales with ``k``, so
the weighted least-squares estimate of ``ln k`` from targets of relative standard
deviation ``s_i`` has the standard deviation ``2 / sqrt(sum 1 / s_i^2)`` exactly
(linear regression of ``ln f_i = c_i + ln(k) / 2``). The predicted parameter standard
deviation is checked against that and against the scatter of noisy repetitions; a mass
the model lacks must get the "model form" verdict.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.sparse as sp

from mvtk.errors import ParameterError
from mvtk.fe import FEModel
from mvtk.updating import FrequencyTarget, Parameter, targets_from_modal_result, update

MASSES = (1.0, 1.5, 0.8)  # kg


def chain(d) -> FEModel:
    """Fixed-free chain: ground -k1- m1 -k2- m2 -k3- m3 (uz), extra mass on m2."""
    k = [d["k1"] * d.get("k", 1.0), d["k2"] * d.get("k", 1.0), d["k3"] * d.get("k", 1.0)]
    K = np.array([[k[0] + k[1], -k[1], 0.0], [-k[1], k[1] + k[2], -k[2]],
                  [0.0, -k[2], k[2]]])
    M = np.diag([MASSES[0], MASSES[1] + d.get("extra_mass", 0.0), MASSES[2]])
    return FEModel(nodes=np.column_stack([np.arange(3.0), np.zeros(3), np.zeros(3)]),
                   M=sp.csr_matrix(M), K=sp.csr_matrix(K), dof_node=np.arange(3),
                   dof_component=np.full(3, 2), name="chain")


TRUTH = {"k1": 4.0e4, "k2": 2.5e4, "k3": 1.5e4, "k": 1.0}


def chain_fn(d) -> np.ndarray:
    m = chain(d)
    w2 = np.linalg.eigvalsh(np.linalg.solve(np.sqrt(m.M.toarray()),
                                            np.linalg.solve(np.sqrt(m.M.toarray()),
                                                            m.K.toarray()).T))
    return np.sqrt(np.sort(w2)) / (2 * np.pi)


def _fit(f, std_rel, params, model_form_std=0.0, start=None):
    targets = [FrequencyTarget(float(fi), std_hz=float(s * fi), mode=i + 1,
                               label=f"f{i + 1}")
               for i, (fi, s) in enumerate(zip(f, std_rel))]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return update(start or {**TRUTH, "k": 1.3}, params, targets, builder=chain,
                      model_form_std=model_form_std, n_modes=3, affine=True)


def test_one_parameter_std_is_the_closed_form_and_the_monte_carlo_scatter():
    rng = np.random.default_rng(27)
    f0 = chain_fn(TRUTH)
    s = np.array([0.002, 0.005, 0.01])  # relative identification std of f1, f2, f3
    params = [Parameter("k", lower=0.1, upper=10.0)]
    exact = 2.0 / np.sqrt(np.sum(1 / s**2))  # std of ln k, closed form
    est, pred, verdicts = [], [], []
    for _ in range(120):  # sample std within about +-6.5 % (1 sigma) of the truth
        r = _fit(f0 * (1 + s * rng.standard_normal(3)), s, params)
        est.append(r.values[0])
        pred.append(r.std[0] / r.values[0])
        verdicts += list(r.verdicts)
    assert np.median(pred) == pytest.approx(exact, rel=0.02)
    scatter = np.std(np.log(est), ddof=1)
    assert scatter == pytest.approx(exact, rel=0.25)
    # noise only: the 2-sigma residual limits hold about 95 % of the residuals
    assert set(verdicts) <= {"noise", "model form"}
    assert 0.91 <= verdicts.count("noise") / len(verdicts) <= 0.99


@pytest.mark.slow
def test_two_parameters_std_matches_monte_carlo_and_weights_follow_the_variances():
    rng = np.random.default_rng(7)
    f0 = chain_fn(TRUTH)
    s = np.array([0.001, 0.004, 0.004])
    params = [Parameter("k1", lower=1e3, upper=1e6), Parameter("k2", lower=1e3, upper=1e6)]
    est, pred = [], []
    for _ in range(100):  # sample std within about +-7 % (1 sigma) of the truth
        r = _fit(f0 * (1 + s * rng.standard_normal(3)), s, params,
                 start={**TRUTH, "k1": 3.0e4, "k2": 3.0e4})
        est.append(r.values)
        pred.append(r.std)
    scatter = np.std(est, axis=0, ddof=1)
    np.testing.assert_allclose(np.median(pred, axis=0), scatter, rtol=0.25)
    assert r.meta["weighting"] == "statistical"
    assert "a priori" in r.meta["covariance_scaling"]
    # unit-variance rows: the covariance is (J' W J)^-1, its diagonal the std^2
    np.testing.assert_allclose(np.sqrt(np.diag(r.covariance)), r.std, rtol=1e-12)


def test_missing_mass_is_model_form_and_the_model_form_term_explains_small_errors():
    f_true = chain_fn({**TRUTH, "extra_mass": 0.3})  # the model has no extra mass
    s = np.full(3, 1e-4)
    r = _fit(f_true, s, [Parameter("k", lower=0.1, upper=10.0)], model_form_std=0.002)
    tab = r.residual_table()
    # f1 and f3 move against each other (the lumped mass shifts the mode ratios): far
    # beyond noise + 0.2 % model form; f2 lies between them, near the fitted k
    assert list(tab["verdict"]) == ["model form", "model-form term", "model form"]
    assert np.all(np.abs(tab["residual_hz"]) > tab["noise_limit_hz"])
    assert r.meta["variance_factor"] > 10  # the stated sigmas are too small
    # a small extra mass within the stated model-form term: explained by it
    f_small = chain_fn({**TRUTH, "extra_mass": 0.004})
    r2 = _fit(f_small, s, [Parameter("k", lower=0.1, upper=10.0)], model_form_std=0.005)
    assert "model form" not in r2.verdicts
    assert "model-form term" in r2.verdicts
    tab2 = r2.residual_table()
    assert np.all(tab2["std_hz"] > tab2["id_std_hz"])
    np.testing.assert_allclose(tab2["std_hz"], np.hypot(tab2["id_std_hz"],
                                                        0.005 * tab2["target_hz"]))


def test_as_many_parameters_as_targets_has_no_redundancy():
    f0 = chain_fn(TRUTH)[:2]
    targets = [FrequencyTarget(float(f), std_hz=0.01, mode=i + 1) for i, f in enumerate(f0)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = update({**TRUTH, "k1": 3e4, "k2": 3e4}, [Parameter("k1", lower=1e3, upper=1e6),
                   Parameter("k2", lower=1e3, upper=1e6)], targets, builder=chain,
                   n_modes=3, model_form_std=0.0)
    assert r.verdicts == ("no redundancy", "no redundancy")
    assert np.all(np.isfinite(r.std)) and r.meta["std_note"] is None


def test_without_std_the_weights_are_unchanged_and_no_verdict():
    f0 = chain_fn(TRUTH)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = update({**TRUTH, "k": 1.3}, ["k"], f0.tolist(), builder=chain, n_modes=3)
    assert r.meta["weighting"] == "weights" and r.verdicts == ("no std",) * 3
    assert r.values[0] == pytest.approx(1.0, rel=1e-8)


def test_targets_from_modal_result_carry_fn_std_and_bad_std_is_refused():
    import pandas as pd

    t = targets_from_modal_result(pd.DataFrame({"fn_hz": [10.0, 20.0],
                                                "fn_std_hz": [0.01, np.nan]}))
    assert [x.std_hz for x in t] == [0.01, None]
    assert targets_from_modal_result({"fn_hz": [5.0]})[0].std_hz is None
    import xarray as xr

    from mvtk.updating import targets_from_shapes

    shapes = xr.DataArray(np.eye(3)[:2] + 0.1, dims=("mode", "dof"),
                          coords={"mode": [1, 2], "fn_hz": ("mode", [10.0, 20.0])})
    q = pd.DataFrame({"mode": [1, 2], "fn_std_hz": [0.02, np.nan]})
    t = targets_from_shapes(shapes, np.eye(3), quality=q)
    assert [x.std_hz for x in t] == [0.02, None]
    with pytest.raises(ParameterError, match="std_hz must be a finite number >= 0"):
        FrequencyTarget(10.0, std_hz=-1.0)
    with pytest.raises(ParameterError, match=r"\['f1'\] have a zero standard deviation"):
        update(TRUTH, ["k"], [FrequencyTarget(10.0, std_hz=0.0, label="f1")],
               builder=chain, n_modes=3, model_form_std=0.0)
    with pytest.raises(ParameterError, match="model_form_std must be"):
        update(TRUTH, ["k"], [10.0], builder=chain, n_modes=3, model_form_std=-0.1)
