"""Reduced-basis path of parameter studies: equal to the full solves within its bound."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import mvtk.fe
from mvtk.errors import ParameterError
from mvtk.scale import monte_carlo, parameter_study
from mvtk.scale._reduced import Decomposition, _NotReducible, clear_cache
from mvtk.updating import with_values

#: a clamped steel strip with a bonded aluminium patch (unsymmetric laminate there):
#: K is linear in E, M in rho, both cubic in the base thickness
STRIP = {
    "name": "patched steel strip",
    "materials": {"steel": {"E": 200e9, "nu": 0.3, "rho": 7850.0},
                  "al": {"E": 70e9, "nu": 0.33, "rho": 2700.0}},
    "structure": {"type": "plate", "length": 0.3, "width": 0.03,
                  "layers": [{"material": "steel", "thickness": 1e-3}]},
    "patches": [{"name": "p", "x0": 0.02, "x1": 0.08, "y0": 0.0, "y1": 0.03,
                 "layers": [{"material": "al", "thickness": 0.5e-3}]}],
    "mesh": {"nx": 30, "ny": 3},
    "boundary": {"clamp": "x0"},
}
PATHS = ["materials.steel.E", "materials.steel.rho", "structure.layers.0.thickness"]


def _full(desc, row, n_modes):
    model = mvtk.fe.build_model(with_values(desc, dict(zip(PATHS, row))))
    return mvtk.fe.modal_analysis(model, n_modes).fn_hz


def _samples(rng, n, rel=(0.03, 0.01, 0.02)):
    p0 = np.array([200e9, 7850.0, 1e-3])
    return p0 * (1 + rng.standard_normal((n, 3)) * np.array(rel))


def test_reduced_samples_equal_full_solves_within_their_bound():
    clear_cache()
    values = _samples(np.random.default_rng(4), 20)
    ds = parameter_study(STRIP, dict(zip(PATHS, values.T)), n_modes=4)
    assert ds.attrs["method"] == "reduced" and ds.attrs["reduced_note"] == ""
    paths = ds["path"].values
    assert set(paths) <= {"reduced", "reduced+correction", "full"}
    assert np.sum(paths != "full") >= 15          # most samples take the reduced path
    bound = ds["error_bound"].values
    for i, row in enumerate(values):
        full = _full(STRIP, row, 4)
        err = np.max(np.abs(ds["fn_hz"].values[i] / full - 1))
        if paths[i] == "full":
            assert np.isnan(bound[i])
            assert err < 1e-10
        else:
            assert bound[i] <= 1e-8
            # the bound is on the eigenvalues of the interpolated matrices; those equal
            # a real build's to round-off, which moves f1 of this thin strip (L/h =
            # 300) by ~1e-9 (SuperLU vs CHOLMOD on one build: up to 7e-10)
            assert err <= bound[i] + 5e-9, (i, err, bound[i])
    # the exact method solves every sample in full and says so
    ex = parameter_study(STRIP, dict(zip(PATHS, values[:3].T)), n_modes=4, method="exact")
    assert list(ex["path"].values) == ["full"] * 3 and ex.attrs["method"] == "exact"
    np.testing.assert_allclose(ex["fn_hz"].values, ds["fn_hz"].values[:3], rtol=1e-8)


def test_a_sample_far_from_the_centre_falls_back_to_the_full_solve():
    """A sample with E at 0.4 x the centre (frequencies at 0.63 x, beyond the factor
    1.6 the bound's K >= K0/2 assumption allows) is built and solved in full."""
    clear_cache()
    values = _samples(np.random.default_rng(7), 16)
    values[5, 0] = 0.4 * 200e9
    ds = parameter_study(STRIP, dict(zip(PATHS, values.T)), n_modes=3, method="reduced")
    assert ds["path"].values[5] == "full"
    # two full solves of slightly different matrices (the study's K without its
    # round-off entries): equal to the factorisation's round-off on the strip's mode 1
    # (1.9e-10 with SuperLU and the block Lanczos)
    np.testing.assert_allclose(ds["fn_hz"].values[5], _full(STRIP, values[5], 3),
                               rtol=1e-9)
    assert ds.attrs["n_full"] >= 1
    # a tolerance no sample meets sends every sample to a correction or a full solve
    tight = parameter_study(STRIP, dict(zip(PATHS, values.T)), n_modes=3,
                            method="reduced", tol=1e-300)
    assert set(tight["path"].values) == {"full"}


def test_monte_carlo_records_path_and_bound_and_reuses_the_basis():
    clear_cache()
    dists = {"materials.steel.E": ("normal", (200e9, 6e9)),
             "structure.layers.0.thickness": ("normal", (1e-3, 2e-5))}
    mc = monte_carlo(STRIP, dists, 20, np.random.default_rng(2), n_modes=3)
    assert mc.samples.attrs["method"] == "reduced"
    assert np.isfinite(mc.samples["error_bound"].values[
        mc.samples["path"].values != "full"]).all()
    # a smaller study inside the box of the first (first-order differences) reuses it
    table = mc.parameters_dataframe().iloc[:3]
    small = parameter_study(STRIP, table, n_modes=3)
    assert small.attrs["method"] == "reduced"
    np.testing.assert_allclose(small["fn_hz"].values, mc.fn_hz[:3], rtol=1e-12)


def test_the_interpolation_check_rejects_a_non_polynomial_parameter():
    """Patch position moves element edges: K is not a low polynomial in it (and the
    mesh may change), so the reduced path is refused with the reason."""
    clear_cache()
    desc = copy.deepcopy(STRIP)
    x0 = np.linspace(0.015, 0.025, 16)
    ds = parameter_study(desc, {"patches.0.x0": x0}, n_modes=2, method="reduced")
    assert ds.attrs["method"] == "reduced" and ds.attrs["reduced_note"]
    assert set(ds["path"].values) == {"full"}


def test_decomposition_is_exact_for_affine_and_cubic_parameters():
    def build(p):
        return mvtk.fe.build_model(with_values(STRIP, dict(zip(PATHS, p))))

    p0 = np.array([200e9, 7850.0, 1e-3])
    w = p0 * np.array([0.1, 0.05, 0.06])
    dec = Decomposition.from_builds(build, p0, w)
    assert dec.depends["K"].tolist() == [True, False, True]
    assert dec.depends["M"].tolist() == [False, True, True]
    assert dec.check_rel < 1e-12
    p = p0 * np.array([1.07, 0.97, 0.95])
    K, M = dec.matrices(p)
    ref = build(p)
    np.testing.assert_allclose(abs(K - ref.K).max(), 0, atol=1e-12 * abs(ref.K).max())
    np.testing.assert_allclose(abs(M - ref.M).max(), 0, atol=1e-12 * abs(ref.M).max())
    with pytest.raises(_NotReducible):
        Decomposition.from_builds(lambda p: mvtk.fe.build_model(mvtk.fe.set_by_path(
            with_values(STRIP, {"materials.steel.E": p[0]}), "mesh.nx",
            30 if p[0] <= 200e9 else 31)), p0[:1], w[:1])


def test_bad_method_and_tol():
    with pytest.raises(ParameterError, match="method must be one of"):
        parameter_study(STRIP, {"materials.steel.E": [1e11]}, method="fast")
    with pytest.raises(ParameterError, match="tol must be"):
        parameter_study(STRIP, {"materials.steel.E": [1e11]}, tol=0)
