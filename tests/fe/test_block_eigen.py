"""Block shift-invert Lanczos (``eigsh_lowest(..., method="block")``) against dense
``scipy.linalg.eigh`` on small models: repeated eigenvalues (more copies than the block
width too), rigid-body modes, the NAFEMS FV2 double cross, a warm start."""

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

import mvtk.fe as fe
from mvtk.errors import ParameterError
from mvtk.fe import _solvers as S
from mvtk.fe._block_eigen import block_lanczos

HAS_CHOLMOD = S._cholmod_module() is not None
BACKENDS = ["superlu", pytest.param("cholmod", marks=pytest.mark.skipif(
    not HAS_CHOLMOD, reason="sksparse-minimal (mvtk[cholmod]) not installed"))]
STEEL = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)


def _laplacian_2d(n):
    T = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    return (sp.kron(T, sp.eye(n)) + sp.kron(sp.eye(n), T)).tocsc()


def _dense_lowest(K, M, n, sigma=0.0):
    """Lowest n eigenvalues by a dense shift-invert: eigh of L^-1 M L^-T with
    K - sigma M = L L' (a dense eigh(K, M) loses the lowest eigenvalues of shells to the
    token drilling inertia, which makes M ill-conditioned)."""
    L = sla.cholesky((K - sigma * M).toarray(), lower=True)
    X = sla.solve_triangular(L, M.toarray(), lower=True)
    C = sla.solve_triangular(L, X.T, lower=True)
    theta = sla.eigh(0.5 * (C + C.T), eigvals_only=True)[::-1][:n]
    return np.sort(sigma + 1.0 / theta)


def _check_modes(sol, K, M, n):
    V = sol.vectors
    np.testing.assert_allclose(V.T @ (M @ V), np.eye(n), atol=1e-9)
    # eigen-residual relative to the stiffness scale
    R = K @ V - (M @ V) * sol.omega2
    scale = np.abs(K @ V).max(axis=0)
    assert np.all(np.abs(R).max(axis=0) <= 1e-6 * scale)


@pytest.mark.parametrize("backend", BACKENDS)
def test_block_matches_dense_eigh_on_a_plate(backend):
    """Clamped 12 x 8 MITC4 plate with a moderate thickness (M well enough conditioned
    for a dense solve of its lowest modes)."""
    plate = fe.plate_model(0.6, 0.4, [fe.Ply(STEEL, 0.01)], nx=12, ny=8, clamp="x0")
    ref = _dense_lowest(plate.K, plate.M, 8)
    sol = fe.eigsh_lowest(plate.K, plate.M, 8, method="block", backend=backend)
    assert sol.method == "block" and sol.backend == backend
    np.testing.assert_allclose(sol.omega2, ref, rtol=1e-8)
    _check_modes(sol, plate.K, plate.M, 8)
    arp = fe.eigsh_lowest(plate.K, plate.M, 8, method="arpack", backend=backend)
    assert arp.method == "arpack"
    np.testing.assert_allclose(sol.omega2, arp.omega2, rtol=1e-9)


def test_block_repeated_eigenvalues_up_to_and_beyond_the_block_width():
    """Dirichlet Laplacian on a square (double eigenvalues from i <-> j symmetry), and
    five identical decoupled copies of it (every eigenvalue 5-fold, more copies than
    the block width of 3: the Sturm count of K - tau M makes the solver ask again)."""
    n = 12
    K = _laplacian_2d(n)
    M = sp.eye(n * n, format="csc")
    s2 = 4 * np.sin(np.arange(1, n + 1) * np.pi / (2 * (n + 1))) ** 2
    exact = np.sort((s2[:, None] + s2[None, :]).ravel())
    sol = fe.eigsh_lowest(K, M, 6, method="block")
    np.testing.assert_allclose(sol.omega2, exact[:6], rtol=1e-10)
    assert np.isclose(sol.omega2[1], sol.omega2[2], rtol=1e-12)     # (1, 2) and (2, 1)
    K5 = sp.block_diag([K] * 5, format="csc")
    M5 = sp.eye(5 * n * n, format="csc")
    sol5 = fe.eigsh_lowest(K5, M5, 11, method="block")
    np.testing.assert_allclose(sol5.omega2, np.repeat(exact[:3], 5)[:11], rtol=1e-10)
    _check_modes(sol5, K5, M5, 11)


def test_block_nafems_fv2_double_cross_seven_fold_mode():
    """NAFEMS FV2 (pin-ended double cross, in-plane): 17.709 Hz seven times. Against a
    dense solve of the same (beam) model."""
    from test_general import _double_cross  # tests/fe is on sys.path (rootdir-less dir)

    mat = fe.IsotropicMaterial("steel", 200e9, 0.3, 8000.0)
    sec = fe.rectangle_section(mat, 0.125, 0.125)
    nodes, els, ends = _double_cross()
    model = fe.assemble_model(
        nodes, [fe.BeamSet(els, sec, orientation=(0, 0, 1))],
        supports={"ends": "pinned", "all": "symmetry_z"},
        node_sets={"ends": ends, "all": np.arange(len(nodes))})
    ref = _dense_lowest(model.K, model.M, 10)
    sol = fe.eigsh_lowest(model.K, model.M, 10, method="block")
    np.testing.assert_allclose(sol.omega2, ref, rtol=1e-8)
    fn = np.sqrt(sol.omega2) / (2 * np.pi)
    np.testing.assert_allclose(fn[1:8], 17.709, rtol=5e-3)


@pytest.mark.parametrize("backend", BACKENDS)
def test_block_free_free_plate_rigid_body_modes(backend):
    """Free-free plate: K singular, default negative shift; six rigid-body modes at
    round-off and the elastic ones as the dense solve."""
    free = fe.plate_model(0.5, 0.3, [fe.Ply(STEEL, 0.01)], nx=10, ny=6, clamp=None)
    sigma = -0.01 * _dense_lowest(free.K, free.M, 7, sigma=-1e3)[6]
    ref = _dense_lowest(free.K, free.M, 10, sigma=sigma)
    sol = fe.eigsh_lowest(free.K, free.M, 10, method="block", backend=backend)
    assert np.all(np.abs(sol.omega2[:6]) < 1e-6 * sol.omega2[6])
    np.testing.assert_allclose(sol.omega2[6:], ref[6:], rtol=1e-8)
    V = sol.vectors
    np.testing.assert_allclose(V.T @ (free.M @ V), np.eye(10), atol=1e-9)


def test_block_warm_start_and_determinism():
    plate = fe.plate_model(0.6, 0.4, [fe.Ply(STEEL, 0.005)], nx=12, ny=8, clamp="x0")
    near = fe.plate_model(0.6, 0.4, [fe.Ply(STEEL, 0.0051)], nx=12, ny=8, clamp="x0")
    prev = fe.eigsh_lowest(plate.K, plate.M, 8, method="block")
    cold = fe.eigsh_lowest(near.K, near.M, 8, method="block")
    again = fe.eigsh_lowest(near.K, near.M, 8, method="block")
    np.testing.assert_array_equal(cold.omega2, again.omega2)
    assert cold.n_solves == again.n_solves
    warm = fe.eigsh_lowest(near.K, near.M, 8, method="block", v0=prev.vectors)
    np.testing.assert_allclose(warm.omega2, cold.omega2, rtol=1e-9)
    assert warm.n_solves <= cold.n_solves


def test_block_lanczos_invariant_subspace_and_bad_method():
    """A start block spanning an invariant subspace: the iteration goes on with
    pseudo-random directions (as ARPACK does) instead of returning that subspace's
    eigenpairs, which need not be the wanted ones."""
    K = sp.diags(np.arange(1.0, 41.0)).tocsc()
    M = sp.eye(40, format="csc")
    lu = fe.factorize(K)
    for cols, lowest in (([0, 1, 2], [1.0, 2.0, 3.0]), ([1, 2, 3], [1.0, 2.0, 3.0]),
                         ([5, 6, 7], [1.0, 2.0, 3.0])):
        start = np.zeros((40, 3))
        start[cols, [0, 1, 2]] = 1.0       # eigenvectors of OP
        theta, X, steps = block_lanczos(lu.solve, M, 3, start, 1e-10, 40)
        np.testing.assert_allclose(np.sort(1 / theta), lowest, rtol=1e-12)
        np.testing.assert_allclose(X.T @ X, np.eye(3), atol=1e-12)
    # the exact repeated eigenvalue of a diagonal matrix (one copy per start direction)
    K7 = sp.diags([1.0, 2.0, 2.0, 2.0, 5.0, 7.0, 9.0]).tocsc()
    sol = fe.eigsh_lowest(K7, sp.eye(7, format="csc"), 4, method="block")
    np.testing.assert_allclose(sol.omega2, [1, 2, 2, 2], rtol=1e-12)
    with pytest.raises(ParameterError, match="method must be 'auto', 'arpack' or 'block'"):
        fe.eigsh_lowest(K, M, 3, method="lobpcg")


def test_block_free_free_curved_panel_six_rigid_modes_below_a_close_shift():
    """Free-free curved panel with modal_analysis' shift (-1 % of the first elastic
    eigenvalue's estimate): the six rigid-body modes converge so fast that a block of 2
    stopped with four of them (their round-off eigenvalues near 0 did not look repeated
    to a test relative to their size). Clusters are now judged relative to the distance
    from the shift, so the Sturm count finds the two missing and Lanczos runs again."""
    from pathlib import Path

    from mvtk.fe import _modal

    panel = Path(__file__).resolve().parents[2] / "data" / "structures" / "curved_panel"
    desc = fe.load_structure(panel / "curved_panel.toml")
    desc.pop("boundary")
    model = fe.build_model(desc)
    shift = -1e-2 * _modal._smooth_trial_scale(model)
    sol = fe.eigsh_lowest(model.K, model.M, 10, singular_shift=shift)
    assert sol.method == "block"
    elastic0 = sol.omega2[6]
    assert np.all(np.abs(sol.omega2[:6]) < 1e-6 * elastic0)
    assert np.all(sol.omega2[6:] > 0.5 * elastic0)
    ref = fe.eigsh_lowest(model.K, model.M, 10, singular_shift=shift, method="arpack")
    np.testing.assert_allclose(sol.omega2[6:], ref.omega2[6:], rtol=1e-8)
    assert S._clustered(sol.omega2[:6], shift) and not S._clustered(sol.omega2[:6], 0.0)
    assert fe.modal_analysis(model, 10).rigid.sum() == 6


@pytest.mark.parametrize("width", [1, 2, 4, 5])
@pytest.mark.parametrize("trans", [False, True])
def test_block_products_match_numpy(width, trans):
    """The basis products (dgemv per column for narrow blocks, dgemm for wide ones) equal
    numpy's, with and without an accumulated Fortran-ordered output."""
    from mvtk.fe._block_eigen import _gemm

    rng = np.random.default_rng(3)
    A = np.asfortranarray(rng.standard_normal((300, 7)))
    B = rng.standard_normal((300 if trans else 7, width))
    opA = A.T if trans else A
    np.testing.assert_allclose(_gemm(0.5, A, B, trans_a=trans), 0.5 * opA @ B, atol=1e-12)
    c = np.asfortranarray(rng.standard_normal((opA.shape[0], width)))
    expected = c - opA @ B
    out = _gemm(-1.0, A, B, trans_a=trans, beta=1.0, c=c)
    np.testing.assert_allclose(out, expected, atol=1e-12)
    np.testing.assert_allclose(c, expected, atol=1e-12)    # overwritten in place


def test_block_lanczos_refuses_a_non_finite_basis():
    """A solve that returns NaN (a singular shifted matrix factorised with a zero pivot)
    gives a ConvergenceError that says so, not a LAPACK error or NaN eigenvalues."""
    from mvtk.errors import ConvergenceError

    M = sp.identity(40, format="csr")
    start = np.random.default_rng(0).standard_normal((40, 2))
    with pytest.raises(ConvergenceError, match="not finite"):
        block_lanczos(lambda B: np.full(B.shape, np.nan), M, 3, start, 1e-10, 40)
