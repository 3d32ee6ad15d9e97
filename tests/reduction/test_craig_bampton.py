"""Craig-Bampton / Guyan reduction against closed forms and the full FE model."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla

from mvtk.errors import AccuracyWarning, DimensionError, ParameterError
from mvtk.fe import IsotropicMaterial, Ply, eigsh_lowest
from mvtk.fe._beam import cantilever_beam
from mvtk.reduction import SuperElement, craig_bampton, effective_mass, guyan
from mvtk.reduction import _craig_bampton as cb_module
from mvtk.reduction._examples import eb_beam_xz

STEEL = IsotropicMaterial("steel", E=210e9, nu=0.3, rho=7900.0)
# Euler-Bernoulli cantilever roots beta_n L (Blevins, Formulas for Natural Frequency
# and Mode Shape, table 8-1)
BETA_L = np.array([1.875104069, 4.694091133, 7.854757438, 10.99554073])


def fe_hz(model, n):
    sol = eigsh_lowest(model.K, model.M, n)
    return np.sqrt(sol.omega2) / (2 * np.pi)


def se_hz(se, n=None):
    w2 = sla.eigh(se.K, se.M, eigvals_only=True)
    w2 = w2 if n is None else w2[:n]
    return np.sqrt(np.clip(w2, 0, None)) / (2 * np.pi)


@pytest.fixture(scope="module")
def beam():
    return eb_beam_xz(n_el=40)


@pytest.fixture(scope="module")
def beam3d():
    """6-DOF Timoshenko cantilever (mvtk.fe) with named points."""
    return cantilever_beam(
        0.18, 0.02, [Ply(STEEL, 0.5e-3)], n_elements=24,
        points={"a": 0.005, "b": 0.055, "sensor": 0.12},
    )


def test_helper_beam_matches_euler_bernoulli_closed_form(beam):
    EI, rA, L = beam.meta["EI"], beam.meta["rhoA"], beam.meta["length"]
    exact = BETA_L**2 / (2 * np.pi * L**2) * np.sqrt(EI / rA)
    f = fe_hz(beam, 4)
    np.testing.assert_allclose(f, exact, rtol=1e-5)
    assert np.all(f >= exact)  # consistent mass: Rayleigh-Ritz upper bound


def test_all_interior_modes_reproduce_fe_eigenvalues(beam):
    se = craig_bampton(beam, ["tip", "mid"], n_modes=beam.n_dof - 4)
    assert se.n_dof == beam.n_dof
    full = sla.eigh(beam.K.toarray(), beam.M.toarray(), eigvals_only=True)
    red = sla.eigh(se.K, se.M, eigvals_only=True)
    # round-off of a dense eigen solve: absolute error ~ eps * largest eigenvalue
    np.testing.assert_allclose(red, full, rtol=1e-7, atol=1e-13 * full.max())


def test_all_interior_modes_3d_beam(beam3d):
    se = craig_bampton(beam3d, ["a", "b", "tip"], n_modes=beam3d.n_dof - 18)
    full = sla.eigh(beam3d.K.toarray(), beam3d.M.toarray(), eigvals_only=True)
    red = sla.eigh(se.K, se.M, eigvals_only=True)
    np.testing.assert_allclose(red, full, rtol=1e-7, atol=1e-13 * full.max())


@pytest.mark.parametrize("n_modes", [0, 1, 3, 6, 12])
def test_truncated_frequencies_are_upper_bounds(beam, n_modes):
    se = craig_bampton(beam, ["tip", "mid"], n_modes)
    n = min(se.n_dof, 8)
    fe, red = fe_hz(beam, n), se_hz(se, n)
    assert np.all(red >= fe * (1 - 1e-10))


def test_error_falls_as_n_modes_grows(beam3d):
    fe = fe_hz(beam3d, 4)
    errs = []
    for n_modes in (2, 5, 10, 20):
        se = craig_bampton(beam3d, ["a", "b", "sensor", "tip"], n_modes)
        errs.append(np.max(se_hz(se, 4) / fe - 1))
    assert all(e2 < e1 for e1, e2 in zip(errs, errs[1:]))
    assert errs[0] > 1e-3 and errs[-1] < 1e-4


def test_reduced_matrix_structure(beam):
    se = craig_bampton(beam, ["tip", "mid"], 5)
    nb = se.n_boundary
    kscale = np.abs(se.K).max()
    assert np.abs(se.K[:nb, nb:]).max() < 1e-9 * kscale
    np.testing.assert_allclose(se.M[nb:, nb:], np.eye(5), atol=1e-10)
    nu2 = (2 * np.pi * se.interior_fn_hz) ** 2
    np.testing.assert_allclose(np.diag(se.K[nb:, nb:]), nu2, rtol=1e-10)
    assert se.labels == ("n20:uz", "n20:ry", "n40:uz", "n40:ry",
                         "eta0", "eta1", "eta2", "eta3", "eta4")
    np.testing.assert_array_equal(se.boundary_nodes, [20, 40])


def test_fixed_interface_modes_of_clamped_free_segments(beam):
    """Retaining both DOFs of the tip of a cantilever: the fixed-interface modes are
    those of a clamped-clamped beam (Blevins table 8-1)."""
    se = craig_bampton(beam, ["tip"], 3)
    EI, rA, L = beam.meta["EI"], beam.meta["rhoA"], beam.meta["length"]
    cc = np.array([4.730040745, 7.853204624, 10.99560784])
    exact = cc**2 / (2 * np.pi * L**2) * np.sqrt(EI / rA)
    np.testing.assert_allclose(se.interior_fn_hz, exact, rtol=1e-5)


def test_guyan_tip_flexibility_closed_form(beam):
    """Guyan of a cantilever onto its tip (uz, ry): K_r^-1 is the tip flexibility."""
    se = guyan(beam, "tip")
    EI, L = beam.meta["EI"], beam.meta["length"]
    # ry = -dw/dx, so the uz-ry coupling changes sign
    flex = np.array([[L**3 / (3 * EI), -(L**2) / (2 * EI)],
                     [-(L**2) / (2 * EI), L / EI]])
    np.testing.assert_allclose(np.linalg.inv(se.K), flex, rtol=1e-9)
    assert se.n_modes == 0 and se.meta["method"] == "guyan"
    same = craig_bampton(beam, "tip", 0)
    np.testing.assert_allclose(same.M, se.M)


def test_rayleigh_damping_commutes_with_projection(beam):
    se = craig_bampton(beam, ["tip", "mid"], 6)
    a, b = 0.02955, 9.77e-6
    full = (a * beam.M + b * beam.K).toarray()
    proj = se.T.T @ full @ se.T
    np.testing.assert_allclose(se.damping(a, b), proj, rtol=1e-9, atol=1e-12 * np.abs(proj).max())


def test_modal_damping_diagonalised_by_se_modes(beam):
    se = craig_bampton(beam, ["tip"], 4)
    C = se.damping(modal_damping=0.02)
    w2, phi = sla.eigh(se.K, se.M)
    cm = phi.T @ C @ phi
    np.testing.assert_allclose(np.diag(cm), 2 * 0.02 * np.sqrt(w2), rtol=1e-8)
    assert np.abs(cm - np.diag(np.diag(cm))).max() < 1e-8 * np.abs(cm).max()


def test_damping_bad_input(beam):
    se = craig_bampton(beam, ["tip"], 2)
    with pytest.raises(ParameterError, match="either Rayleigh"):
        se.damping(0.1, 0.0, modal_damping=0.01)
    with pytest.raises(ParameterError, match=">= 0"):
        se.damping(-1.0)
    with pytest.raises(DimensionError, match="one per mode"):
        se.damping(modal_damping=[0.01, 0.02])
    with pytest.raises(ParameterError, match="ratios must be >= 0"):
        se.damping(modal_damping=-0.01)


def test_expand_and_dataframe(beam):
    se = craig_bampton(beam, ["tip", "mid"], 3)
    q = np.zeros(se.n_dof)
    q[2] = 1.0  # unit tip deflection
    x = se.expand(q)
    assert x.shape == (beam.n_dof,)
    assert x[beam.dof_index(40, "uz")] == pytest.approx(1.0)
    assert se.expand(np.eye(se.n_dof)).shape == (beam.n_dof, se.n_dof)
    with pytest.raises(DimensionError, match="expected 7 reduced coordinates"):
        se.expand(np.zeros(5))
    df = se.to_dataframe()
    assert list(df["kind"]).count("boundary") == 4
    np.testing.assert_allclose(df["fn_hz"].to_numpy()[4:], se.interior_fn_hz)
    assert isinstance(se, SuperElement)
    with pytest.raises(dataclasses.FrozenInstanceError):
        se.M = None


def test_one_factorisation_and_eigsh_path(monkeypatch):
    """Large interior: one factorisation of K_ff serves Psi and the eigen solve."""
    model = eb_beam_xz(n_el=310)  # 616 interior DOFs: above the dense limit (600)
    calls = []
    real = cb_module.factorize

    def counting(A):
        calls.append(A.shape)
        return real(A)

    monkeypatch.setattr(cb_module, "factorize", counting)
    se = craig_bampton(model, ["mid", "tip"], 6)
    assert len(calls) == 1
    assert calls[0] == (model.n_dof - 4, model.n_dof - 4)
    # the sparse shift-invert path gives the dense answer
    f = np.setdiff1d(np.arange(model.n_dof), se.boundary_dofs)
    kff = model.K[f][:, f].toarray()
    mff = model.M[f][:, f].toarray()
    w2 = sla.eigh(kff, mff, eigvals_only=True, subset_by_index=[0, 5])
    nu2 = (2 * np.pi * se.interior_fn_hz) ** 2
    # the dense solver itself is only good to ~1e-7 here (condition of a 400-element
    # beam); the shift-invert residuals are much smaller
    np.testing.assert_allclose(nu2, w2, rtol=1e-6)
    phi = se.T[f, se.n_boundary:]
    resid = np.linalg.norm(kff @ phi - mff @ phi * nu2, axis=0)
    assert np.all(resid < 1e-6 * np.linalg.norm(kff @ phi, axis=0))
    np.testing.assert_allclose(phi.T @ mff @ phi, np.eye(6), atol=1e-9)


def test_mass_fraction_choice_matches_table(beam):
    se = craig_bampton(beam, ["mid"], mass_fraction=0.95)
    big = craig_bampton(beam, ["mid"], 30)
    table = effective_mass(big)
    assert se.n_modes == table.n_for_fraction(0.95)
    assert se.meta["mass_fraction"] == 0.95
    fewer = craig_bampton(beam, ["mid"], mass_fraction=0.5)
    assert fewer.n_modes == table.n_for_fraction(0.5) < se.n_modes


def test_mass_fraction_batches_beyond_first_ten():
    model = eb_beam_xz(n_el=400)  # sparse path with growing batches
    se = craig_bampton(model, ["tip"], mass_fraction=0.97)
    table = effective_mass(craig_bampton(model, ["tip"], 60))
    assert se.n_modes > 10
    assert se.n_modes == table.n_for_fraction(0.97)


def test_frequency_cutoff(beam):
    se = craig_bampton(beam, ["tip"], f_cut_hz=1000.0)
    big = craig_bampton(beam, ["tip"], 20)
    assert np.all(se.interior_fn_hz <= 1000.0)
    assert big.interior_fn_hz[se.n_modes] > 1000.0
    assert se.n_modes == int(np.sum(big.interior_fn_hz <= 1000.0))


def test_criterion_not_reached_warns(beam):
    with pytest.warns(AccuracyWarning, match="not reached with 3 fixed-interface modes"):
        se = craig_bampton(beam, ["tip"], 3, mass_fraction=0.999)
    assert se.n_modes == 3


def test_retained_by_points_dofs_and_free_free():
    model = eb_beam_xz(n_el=10, clamped=False)
    se = craig_bampton(model, [[0.0, 0.0, 0.001]], 3)  # nearest node 0
    np.testing.assert_array_equal(se.boundary_nodes, [0])
    se2 = craig_bampton(model, retained_dofs=[0, 1], n_modes=3)
    np.testing.assert_allclose(se2.K, se.K)
    # clamped model: the clamp node has no free DOF but counts as a retained node
    clamped = eb_beam_xz(n_el=10)
    se3 = craig_bampton(clamped, ["clamp", "tip"], 2)
    assert se3.n_boundary == 2 and se3.n_nodes == 2


def test_smart_beam_shape_40_dof():
    """Free-free 6-DOF beam, 5 retained nodes x 6 DOF + 10 modes = 40 DOF (paper)."""
    model = cantilever_beam(0.18, 0.02, [Ply(STEEL, 0.5e-3)], 24, clamp=None,
                            points={"a": 0.005, "b": 0.055, "sensor": 0.12})
    se = craig_bampton(model, ["x0", "a", "b", "sensor", "tip"], 10)
    assert (se.n_boundary, se.n_modes, se.n_dof, se.n_nodes) == (30, 10, 40, 5)


def test_bad_inputs(beam):
    with pytest.raises(ParameterError, match="no node set 'nope'"):
        craig_bampton(beam, ["nope"])
    with pytest.raises(ParameterError, match="retained node 99 does not exist"):
        craig_bampton(beam, [99])
    with pytest.raises(ParameterError, match="is not understood"):
        craig_bampton(beam, [1.5])
    with pytest.raises(ParameterError, match="retained_dofs must be in 0..79"):
        craig_bampton(beam, retained_dofs=[80])
    with pytest.raises(ParameterError, match="integer free-DOF indices"):
        craig_bampton(beam, retained_dofs=[1.0])
    with pytest.raises(ParameterError, match="no boundary given"):
        craig_bampton(beam)
    with pytest.raises(ParameterError, match=r"n_modes must be in 0..78"):
        craig_bampton(beam, "tip", 79)
    with pytest.raises(ParameterError, match=r"n_modes must be in 0..78"):
        craig_bampton(beam, "tip", -1)
    with pytest.raises(ParameterError, match="at most one of"):
        craig_bampton(beam, "tip", mass_fraction=0.9, f_cut_hz=100.0)
    with pytest.raises(ParameterError, match=r"mass_fraction must be in \(0, 1\]"):
        craig_bampton(beam, "tip", mass_fraction=1.5)
    with pytest.raises(ParameterError, match="f_cut_hz must be > 0"):
        craig_bampton(beam, "tip", f_cut_hz=0.0)
    with pytest.raises(ParameterError, match="direction must be a translation"):
        craig_bampton(beam, "tip", mass_fraction=0.9, direction="ry")
    with pytest.raises(ParameterError, match="would be empty"):
        craig_bampton(beam, "clamp", 0)


def test_under_restrained_interior_is_reported():
    model = eb_beam_xz(n_el=10, clamped=False)
    with pytest.raises(ParameterError, match="K_ff .* is singular"):
        craig_bampton(model, retained_dofs=[0], n_modes=2)  # uz of node 0 only


def test_solve_columns_matches_dense(beam, rng):
    import scipy.sparse as sp

    from mvtk.fe import factorize
    from mvtk.reduction._craig_bampton import solve_columns

    lu = factorize(beam.K)
    B = rng.standard_normal((beam.n_dof, 3))
    ref = np.linalg.solve(beam.K.toarray(), B)
    np.testing.assert_allclose(solve_columns(lu, B), ref, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(solve_columns(lu, sp.csc_matrix(B)), ref, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(solve_columns(lu, B[:, 0]), ref[:, 0], rtol=1e-7, atol=1e-12)


HAS_CHOLMOD = __import__("mvtk.fe._solvers", fromlist=["x"])._cholmod_module() is not None
BACKENDS = ["superlu", pytest.param("cholmod", marks=pytest.mark.skipif(
    not HAS_CHOLMOD, reason="sksparse-minimal (mvtk[cholmod]) not installed"))]


@pytest.fixture(scope="module")
def long_beam():
    """400-element cantilever: 798 interior DOFs with the tip retained (sparse path)."""
    return eb_beam_xz(n_el=400)


def _interior(model, retained):
    import scipy.sparse as sp

    se = craig_bampton(model, retained, 0)
    f = np.setdiff1d(np.arange(model.n_dof), se.boundary_dofs)
    return (sp.csc_matrix(model.K[f][:, f]), sp.csr_matrix(model.M[f][:, f]), f)


@pytest.mark.parametrize("backend", BACKENDS)
def test_sparse_fixed_interface_modes_closed_form_and_dense(long_beam, backend, monkeypatch):
    """Interior above the dense limit: block Lanczos of mvtk.fe on the K_ff factorisation
    (no second factorisation) gives the clamped-clamped beam (Blevins table 8-1) and
    the dense generalised eigenpairs to round-off."""
    from mvtk.fe import _solvers, factorize

    kff, mff, _ = _interior(long_beam, ["tip"])
    assert kff.shape[0] > cb_module._DENSE_LIMIT
    lu = factorize(kff, backend=backend)

    def no_factorize(*args, **kwargs):
        raise AssertionError("the fixed-interface eigen solve factorised again")

    monkeypatch.setattr(_solvers, "factorize", no_factorize)
    nu2, phi = cb_module.fixed_interface_modes(kff, mff, lu, 4)
    monkeypatch.undo()
    EI, rA, L = (long_beam.meta[k] for k in ("EI", "rhoA", "length"))
    cc = np.array([4.730040745, 7.853204624, 10.99560784, 14.13716549])
    exact = cc**2 / (2 * np.pi * L**2) * np.sqrt(EI / rA)
    np.testing.assert_allclose(np.sqrt(nu2) / (2 * np.pi), exact, rtol=1e-6)
    # dense reference from the inverse pencil M v = mu K v (factorises K; eigh(K, M)
    # loses 7e-6 relative on this pencil). cond(K_ff) is 8e11: the round-off floor of
    # the eigenvalues is ~1e-8 relative (ARPACK's, the dense ones, the block Lanczos
    # ones with either backend spread 1.3e-9-1.2e-8), hence rtol 3e-8
    n = kff.shape[0]
    mu, v = sla.eigh(mff.toarray(), kff.toarray(), subset_by_index=[n - 4, n - 1])
    w2, v = 1.0 / mu[::-1], v[:, ::-1]
    v = v / np.sqrt(np.einsum("ij,ij->j", v, mff @ v))
    np.testing.assert_allclose(nu2, w2, rtol=3e-8)
    np.testing.assert_allclose(phi.T @ (mff @ phi), np.eye(4), atol=1e-12)
    # (signs aligned: the largest entries of these symmetric and antisymmetric modes
    # come in +- pairs, so the largest-entry-positive rule is decided by round-off)
    v = v * np.sign(np.einsum("ij,ij->j", v, mff @ phi))
    np.testing.assert_allclose(phi, v, atol=1e-6 * np.abs(v).max())
    # a raw scipy SuperLU factorisation (the former documented type) still works
    import scipy.sparse.linalg as spla

    nu2_raw, _ = cb_module.fixed_interface_modes(kff, mff, spla.splu(kff), 4)
    np.testing.assert_allclose(nu2_raw, w2, rtol=3e-8)


def test_eigsh_lowest_with_given_factorization(long_beam):
    """``factorization=`` reuses it: same eigenpairs as factorising, none made, and
    only the solve's own right-hand sides counted."""
    from mvtk.fe import factorize

    kff, mff, _ = _interior(long_beam, ["tip"])
    ref = eigsh_lowest(kff, mff, 5)
    lu = factorize(kff)
    lu.solve(np.ones(kff.shape[0]))
    sol = eigsh_lowest(kff, mff, 5, factorization=lu)
    assert sol.n_factorizations == 0 and sol.n_solves == lu.n_solves - 1 > 0
    np.testing.assert_allclose(sol.omega2, ref.omega2, rtol=3e-8)
    np.testing.assert_allclose(np.abs(sol.vectors.T @ (mff @ ref.vectors)), np.eye(5),
                               atol=1e-8)


@pytest.mark.parametrize("backend", BACKENDS)
def test_solve_columns_blocks_match_dense(beam, rng, backend):
    """Multi-right-hand-side solves in chunks (dense and sparse B) vs a dense solve."""
    import scipy.sparse as sp

    from mvtk.fe import factorize

    lu = factorize(beam.K, backend=backend)
    B = rng.standard_normal((beam.n_dof, 7))
    B[:, 3] = 0.0
    K = beam.K.toarray()
    ref = np.linalg.solve(K, B)
    # two direct solvers agree to about cond(K) * eps, not better (the beam's K has
    # cond ~ 1e7: the dense reference itself carries that error)
    rtol = 10 * np.linalg.cond(K) * np.finfo(float).eps
    first = None
    for chunk in (1, 3, 64):
        for b in (B, sp.csc_matrix(B), sp.csr_matrix(B)):
            x = cb_module.solve_columns(lu, b, chunk=chunk)
            assert x.shape == B.shape and x.flags.f_contiguous
            # backward error of a stable direct solve: round-off of K's size
            resid = np.linalg.norm(K @ x - B, axis=0)
            scale = np.linalg.norm(K, 2) * np.linalg.norm(x, axis=0) + np.linalg.norm(B, axis=0)
            assert np.all(resid <= 1e-13 * scale)
            np.testing.assert_allclose(x, ref, rtol=rtol, atol=rtol * np.abs(ref).max())
            # chunking and the storage of B never change the numbers
            first = x if first is None else first
            np.testing.assert_allclose(x, first, rtol=1e-12, atol=0)
