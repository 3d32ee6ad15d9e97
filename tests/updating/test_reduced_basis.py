"""Reduced-basis (Rayleigh-Ritz) inner loop of affine updates (``update(reduced_basis=)``).

External truths: the full-model update (``reduced_basis=False``, every evaluation a
sparse eigen solve) on the same data; a twin experiment whose targets come from the same
mesh at known parameter values (the optimum is those values); an independent eigen
solve of the final description; the Rayleigh-Ritz bound (Ritz values are upper bounds
of the eigenvalues, exact when the basis holds the eigenvectors) against dense LAPACK.

Model: the smart beam of ``data/structures/smart_beam.toml`` on a 15 mm mesh (935 DOFs),
updated in the steel modulus and an elastic clamp stiffness, as the smart-beam study.
"""

from __future__ import annotations

import copy
import json
import tomllib
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

from mvtk.errors import ParameterError
from mvtk.fe import build_model, eigsh_lowest
from mvtk.updating import Parameter, update, with_values
from mvtk.updating._reduced import RitzBasis, static_derivatives

ROOT = Path(__file__).resolve().parents[2]
E, KR = "materials.steel.E", "boundary.clamp_stiffness"
TARGETS = [13.26, 41.14, 78.69, 137.78]   # the smart-beam study's targets (Hz)
PARAMS = [Parameter(E, lower=150e9, upper=260e9), Parameter(KR, lower=20.0, upper=1e6)]


@pytest.fixture(scope="module")
def beam():
    d = tomllib.loads((ROOT / "data/structures/smart_beam.toml").read_text())
    d["mesh"]["element_size"] = 0.015
    d["boundary"]["clamp_stiffness"] = 2000.0
    return d


def _update(desc, params, targets, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return update(desc, params, targets, affine=True, **kw)


def _fn(desc, n):
    m = build_model(desc)
    return np.sqrt(eigsh_lowest(m.K, m.M, n).omega2) / (2 * np.pi)


def test_reduced_path_reaches_the_full_path_optimum(beam):
    # four measured frequencies, two parameters: a least-squares optimum with a model-form
    # residual of 0.2-0.8 %, as in the study
    full = _update(beam, PARAMS, TARGETS, reduced_basis=False)
    red = _update(beam, PARAMS, TARGETS)          # default: on, since it applies
    assert full.meta["reduced_basis"] == {"used": False}
    rb = red.meta["reduced_basis"]
    assert rb["used"] and rb["rounds"] >= 1 and rb["fallback"] is None
    # both paths stop on the same least-squares optimum: equal costs, and end points
    # apart by a negligible fraction of the parameters' standard deviations (E and the
    # clamp stiffness are correlated, so the cost is flat along one direction: the
    # trust-region steps stop anywhere in a 1e-4-sigma neighbourhood, measured 1.3e-4
    # sigma with scipy 1.17, 1e-6 sigma with 1.16)
    assert red.cost == pytest.approx(full.cost, rel=1e-7)
    assert np.all(np.abs(red.values - full.values) <= 1e-3 * full.std)
    np.testing.assert_allclose(red.fn_hz, full.fn_hz, rtol=1e-5)
    # evaluated at those two points (2.8e-5 apart in the clamp stiffness)
    np.testing.assert_allclose(red.sensitivity, full.sensitivity, rtol=1e-4)
    np.testing.assert_allclose(red.std, full.std, rtol=1e-4)
    # one full eigen solve at the start and one per round, against one per evaluation
    assert red.timing["n_eigen"] == 1 + rb["rounds"] == 1 + rb["n_full_eigen"]
    assert full.timing["n_eigen"] > 2 * red.timing["n_eigen"]
    assert rb["mismatch"] < 1e-8
    # the reported frequencies are the full model's at the final values (independent
    # solve of the returned description), not Ritz values. 1e-8: the affine K and a
    # fresh build round differently, and mode 1 of a shell is ill-conditioned in
    # floating point (|phi|'|K||phi| / phi'K phi ~ 1e8 on the smart beam: its membrane
    # and drilling stiffness dwarf the bending energy), measured 1.3e-9
    np.testing.assert_allclose(red.model_fn_hz, _fn(red.description, red.model_fn_hz.size),
                               rtol=1e-8)
    models = red.to_dataframe("history")["model"]
    assert set(models) == {"full", "reduced"} and models.iloc[0] == "full"
    summary = json.loads(json.dumps(red.to_dict()))["reduced_basis"]
    assert summary["n_full_eigen"] == rb["n_full_eigen"] and summary["used"] is True


def test_reduced_optimum_is_stationary_for_the_full_model(beam):
    # independent of mvtk's Jacobian: central differences of full eigen solves around the
    # end point give the gradient of the cost; the Gauss-Newton step it implies is tiny
    red = _update(beam, PARAMS, TARGETS)
    ft = np.array(TARGETS)
    vals = red.values
    # h = 3e-3: truncation (h^2/6 relative on J) and eigen round-off (~1e-10 / h) each
    # move the Gauss-Newton step by ~1e-7 here (with h = 1e-4 the round-off alone moves
    # the weakly sensitive clamp by ~1e-6)
    h = 3e-3
    J = np.zeros((4, 2))
    for k, path in enumerate((E, KR)):
        up = with_values(red.description, {path: vals[k] * (1 + h)})
        dn = with_values(red.description, {path: vals[k] * (1 - h)})
        J[:, k] = (_fn(up, 4) - _fn(dn, 4)) / ft / (2 * h)   # d(f/ft) / d ln p
    r = (_fn(red.description, 4) - ft) / ft
    step = np.linalg.lstsq(J, -r, rcond=None)[0]             # relative parameter change
    assert np.all(np.abs(step) < 1e-6), step


def test_large_move_enriches_the_basis_and_finds_the_truth(beam):
    # twin experiment: the targets are the model's own frequencies at E = 190 GPa and a
    # clamp of 60 N m/rad/m; start 26 % and three decades away. The first reduced fit
    # (modes and their static derivatives at the start) lands where the full model
    # differs by >1e-5, so the full modes there must join the basis
    truth = copy.deepcopy(beam)
    truth["materials"]["steel"]["E"], truth["boundary"]["clamp_stiffness"] = 1.9e11, 60.0
    f = _fn(truth, 4)
    start = copy.deepcopy(beam)
    start["materials"]["steel"]["E"], start["boundary"]["clamp_stiffness"] = 2.4e11, 5e4
    params = [Parameter(E, lower=1e11, upper=4e11),
              Parameter(KR, lower=1.0, upper=1e6, log=True)]
    red = _update(start, params, f.tolist(), freq_tol=0.0)
    full = _update(start, params, f.tolist(), freq_tol=0.0, reduced_basis=False)
    rb = red.meta["reduced_basis"]
    assert rb["rounds"] >= 2
    first = rb["round_details"][0]
    assert first["mismatch"] > 1e-5
    assert rb["basis_size"] > first["basis_size"]
    np.testing.assert_allclose(red.values, [1.9e11, 60.0], rtol=1e-7)
    np.testing.assert_allclose(red.values, full.values, rtol=1e-7)
    # the affine matrices and a fresh build round differently (see above): 1.3e-9
    np.testing.assert_allclose(red.fn_hz, f, rtol=1e-8)


def test_ritz_values_bound_the_eigenvalues_and_are_exact_on_the_modes(beam):
    # Rayleigh-Ritz against dense LAPACK on the full matrices (a 25 mm mesh, 400 DOFs)
    coarse = with_values(beam, {"mesh.element_size": 0.025})
    m0 = build_model(coarse)
    m1 = build_model(with_values(coarse, {KR: 3000.0}))
    dK = (m1.K - m0.K) / 1000.0
    dM = m1.M - m0.M
    n = 6
    eig0 = eigsh_lowest(m0.K, m0.M, n)
    basis = RitzBasis(m0.K, m0.M, [dK], [dM])
    assert basis.extend(eig0.vectors) == n
    assert basis.extend(eig0.vectors) == 0          # already in the span: nothing added
    np.testing.assert_allclose(basis.M0r, np.eye(n), atol=1e-12)
    w, _ = basis.eig(np.array([0.0]), n)
    # the solver's eigenvalues vs the Rayleigh quotients of its vectors: equal up to the
    # factorisation's round-off on this clamped strip's ill-conditioned mode 1 (2.3e-10
    # measured with CHOLMOD, below 1e-10 with SuperLU)
    np.testing.assert_allclose(w, eig0.omega2, rtol=1e-9)
    # at another clamp value: upper bounds, closer with the static derivatives added
    for kr in (200.0, 20000.0):
        # LAPACK on M x = mu K x, mu = 1 / omega^2 (K is well conditioned, M is not:
        # the token drilling inertia of the shell; eigh(K, M) would lose the lowest)
        K = (m0.K + (kr - 2000.0) * dK).toarray()
        nd = K.shape[0]
        mu = sla.eigh(m0.M.toarray(), K, eigvals_only=True,
                      subset_by_index=[nd - n, nd - 1])
        dense = 1.0 / mu[::-1]
        modes_only, _ = basis.eig(np.array([kr - 2000.0]), n)
        assert np.all(modes_only >= dense * (1 - 1e-10))
        enriched = RitzBasis(m0.K, m0.M, [dK], [dM])
        enriched.extend(eig0.vectors)
        enriched.extend(static_derivatives(m0.K, m0.M, eig0.omega2, eig0.vectors, [dK], [dM]))
        w2, _ = enriched.eig(np.array([kr - 2000.0]), n)
        assert np.all(w2 >= dense * (1 - 1e-10))
        assert np.all(w2 - dense <= modes_only - dense + 1e-9 * dense)
        assert np.max(w2 / dense - 1) < 0.1 * np.max(modes_only / dense - 1)


def test_reduced_basis_option_checks(beam):
    with pytest.raises(ParameterError, match="reduced_basis must be None, True or False"):
        update(beam, PARAMS, TARGETS, affine=True, reduced_basis="yes")
    with pytest.raises(ParameterError, match="reduced_basis=True needs affine=True"):
        update(beam, PARAMS, TARGETS, reduced_basis=True)
    with pytest.raises(ParameterError, match="no mode-shape residuals"):
        update(beam, PARAMS, TARGETS, affine=True, mac_weight=1.0, reduced_basis=True)


def test_start_at_the_optimum_costs_no_further_eigen_solve(beam):
    # twin targets at the start values: the full model's Gauss-Newton step there is ~0
    f = _fn(beam, 4)
    red = _update(beam, PARAMS, f.tolist(), freq_tol=0.0)
    rb = red.meta["reduced_basis"]
    assert rb["rounds"] == 0 and rb["n_full_eigen"] == 0 and red.timing["n_eigen"] == 1
    assert red.message == "the initial values are stationary for the full model"
    np.testing.assert_allclose(red.values, [2.1e11, 2000.0], rtol=1e-8)
