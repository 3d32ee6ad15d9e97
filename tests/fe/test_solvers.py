"""Sparse factorisation, ordering, eigen solver and memory estimate."""

import numpy as np
import pytest
import scipy.sparse as sp

import mvtk.fe as fe
from mvtk.errors import DimensionError, MissingDependencyError, ParameterError
from mvtk.fe import _solvers as S

HAS_CHOLMOD = S._cholmod_module() is not None


@pytest.fixture(scope="module")
def plate():
    """CFFF steel plate, 16 x 16 MITC4 (1 632 DOF)."""
    steel = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    return fe.plate_model(1.0, 1.0, [fe.Ply(steel, 0.005)], nx=16, ny=16, clamp="x0")


def _laplacian_2d(n):
    T = sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1])
    return (sp.kron(T, sp.eye(n)) + sp.kron(sp.eye(n), T)).tocsc()


def test_metis_ordering_is_a_permutation_keeping_node_dofs_together(plate):
    p = S.fill_reducing_ordering(plate.K, "metis")
    assert np.array_equal(np.sort(p), np.arange(plate.n_dof))
    # DOFs of one supervariable stay consecutive and in order: on this flat plate the
    # membrane (ux, uy, rz) and the bending (uz, rx, ry) DOFs of a node, which its K does
    # not couple (nor store)
    group = 2 * plate.dof_node + np.isin(plate.dof_component, (2, 3, 4))
    g = group[p]
    starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
    assert len(starts) == len(np.unique(group))
    assert np.all(np.diff(p)[g[1:] == g[:-1]] > 0)
    assert S.fill_reducing_ordering(plate.K, "mmd") is None
    assert S.fill_reducing_ordering(plate.K) is p          # cached per pattern


def test_metis_fill_not_worse_than_superlu_mmd():
    """The fill the issue measures, nnz(L) + nnz(U), against SuperLU's own MMD ordering.
    On this 40 x 40 plate (9 840 DOF) they are within 1 %; nested dissection pays off
    on larger meshes (90 x 90: 8.8 M against 10.3 M, printed by benchmarks/bench_fe.py)."""
    steel = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    big = fe.plate_model(1.0, 1.0, [fe.Ply(steel, 0.005)], nx=40, ny=40, clamp="x0")
    metis = fe.factorize(big.K, backend="superlu", ordering="metis")
    mmd = fe.factorize(big.K, backend="superlu", ordering="mmd")
    assert metis.nnz_factor < 1.03 * mmd.nnz_factor


@pytest.mark.parametrize("backend", ["superlu", pytest.param("cholmod", marks=pytest.mark.skipif(
    not HAS_CHOLMOD, reason="sksparse-minimal (mvtk[cholmod]) not installed"))])
def test_factorize_solves(plate, backend, rng):
    lu = fe.factorize(plate.K, backend=backend)
    assert lu.backend == backend
    b = rng.standard_normal((plate.n_dof, 2))
    x = lu.solve(b)
    np.testing.assert_allclose(plate.K @ x, b, rtol=0, atol=1e-8 * np.abs(b).max())
    np.testing.assert_allclose(lu.solve(b[:, 0]), x[:, 0], rtol=0,
                               atol=1e-9 * np.abs(x).max())
    assert lu.n_solves == 3
    # a transposed (Fortran-ordered) right-hand side, as K^-1 C' builds it
    np.testing.assert_allclose(lu.solve(np.asfortranarray(b)), x, rtol=0,
                               atol=1e-9 * np.abs(x).max())
    with pytest.raises(DimensionError, match=r"right-hand side must have shape \(1632,\)"):
        lu.solve(np.ones(5))


def test_factorize_singular_and_bad_input():
    A = _laplacian_2d(10).tolil()
    A[0, :] = 0
    A[:, 0] = 0
    with pytest.raises(ParameterError, match="singular"):
        fe.factorize(A.tocsc())
    with pytest.raises(DimensionError, match="must be square"):
        fe.factorize(sp.eye(3, 4))
    with pytest.raises(ParameterError, match="backend must be one of"):
        fe.factorize(sp.eye(3), backend="mumps")
    with pytest.raises(ParameterError, match="ordering must be"):
        S.fill_reducing_ordering(sp.eye(3), "amd")


def test_cholmod_backend_missing(monkeypatch):
    monkeypatch.setattr(S, "_cholmod_module", lambda: None)
    monkeypatch.delenv("MVTK_SPARSE_BACKEND", raising=False)   # "auto" below
    with pytest.raises(MissingDependencyError, match=r'pip install "mvtk\[cholmod\]"'):
        fe.factorize(sp.eye(3, format="csc"), backend="cholmod")
    assert fe.factorize(_laplacian_2d(9)).backend == "superlu"   # auto falls back


def test_eigsh_closed_form_laplacian():
    """Dirichlet 2-D Laplacian: lambda = 4 sin^2(i pi / 2(n+1)) + 4 sin^2(j pi / 2(n+1))."""
    n = 30
    K = _laplacian_2d(n)
    s2 = 4 * np.sin(np.arange(1, n + 1) * np.pi / (2 * (n + 1))) ** 2
    ref = np.sort((s2[:, None] + s2[None, :]).ravel())[:8]
    sol = fe.eigsh_lowest(K, sp.eye(n * n, format="csr"), 8)
    np.testing.assert_allclose(sol.omega2, ref, rtol=1e-12)


def test_eigsh_matches_scipy_and_backends_agree(plate):
    """Lowest modes against scipy's own shift-invert (its splu, tol=0). A dense
    eigh is no reference here: the token drilling inertia makes M ill-conditioned."""
    import scipy.sparse.linalg as spla

    ref = np.sort(spla.eigsh(plate.K.tocsc(), k=6, M=plate.M.tocsc(), sigma=0.0,
                             which="LM", tol=0)[0])
    backends = ["superlu"] + (["cholmod"] if HAS_CHOLMOD else [])
    sols = [fe.eigsh_lowest(plate.K, plate.M, 6, backend=b) for b in backends]
    for sol in sols:
        np.testing.assert_allclose(sol.omega2, ref, rtol=1e-8)
        assert sol.n_factorizations == 1          # K's own factorisation is reused
        assert 0 < sol.n_solves <= 40
        V = sol.vectors
        np.testing.assert_allclose(V.T @ (plate.M @ V), np.eye(6), atol=1e-9)
    for sol in sols[1:]:
        np.testing.assert_allclose(sol.omega2, sols[0].omega2, rtol=1e-9)


def test_eigsh_is_deterministic(plate):
    a = fe.eigsh_lowest(plate.K, plate.M, 5)
    b = fe.eigsh_lowest(plate.K, plate.M, 5)
    assert a.n_solves == b.n_solves
    np.testing.assert_array_equal(a.omega2, b.omega2)


def test_warm_start_gives_same_modes_with_fewer_or_equal_solves(plate):
    steel = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    near = fe.plate_model(1.0, 1.0, [fe.Ply(steel, 0.0051)], nx=16, ny=16, clamp="x0")
    prev = fe.eigsh_lowest(plate.K, plate.M, 8)
    cold = fe.eigsh_lowest(near.K, near.M, 8)
    warm = fe.eigsh_lowest(near.K, near.M, 8, v0=prev.vectors)
    np.testing.assert_allclose(warm.omega2, cold.omega2, rtol=1e-8)
    assert warm.n_solves <= cold.n_solves
    # a warm start missing modes (only the first 3 of 8) still finds all 8
    part = fe.eigsh_lowest(near.K, near.M, 8, v0=prev.vectors[:, :3])
    np.testing.assert_allclose(part.omega2, cold.omega2, rtol=1e-8)


def test_eigsh_bad_input(plate):
    with pytest.raises(DimensionError, match=r"v0 must have shape \(1632,\) or \(1632, k\)"):
        fe.eigsh_lowest(plate.K, plate.M, 3, v0=np.ones(7))
    with pytest.raises(ParameterError, match="v0 contains non-finite"):
        fe.eigsh_lowest(plate.K, plate.M, 3, v0=np.full(plate.n_dof, np.nan))
    with pytest.raises(ParameterError, match=r"tol must be in \[0, 1\)"):
        fe.eigsh_lowest(plate.K, plate.M, 3, tol=2.0)


def test_free_free_plate_finds_rigid_modes():
    steel = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    free = fe.plate_model(1.0, 0.6, [fe.Ply(steel, 0.005)], nx=10, ny=6, clamp=None)
    import scipy.sparse.linalg as spla

    res = fe.modal_analysis(free, 8)
    assert res.rigid.sum() == 6
    sigma = -0.01 * res.omega2[6]
    ref = np.sort(spla.eigsh(free.K.tocsc(), k=8, M=free.M.tocsc(), sigma=sigma,
                             which="LM", tol=0)[0])[6:]
    np.testing.assert_allclose(res.omega2[6:], ref, rtol=1e-8)


def test_memory_estimate_predicts_superlu_storage(plate):
    """The estimate from the matrix is exact for the storage SuperLU allocates (same
    METIS ordering, same dropped zeros of uncoupled membrane and bending DOFs); from the
    node graph alone (no assembly) it cannot know which DOF kinds are uncoupled and is
    the exact estimate of the fully coupled pattern, an upper bound."""
    est = fe.estimate_eigen_memory(plate.K, 10)
    lu = fe.factorize(plate.K, backend="superlu")
    assert est.nnz_factor == lu.nnz_storage
    assert est.nnz_matrix == S._drop_uncoupled(sp.csc_matrix(plate.K)).nnz
    assert est.n_dof == plate.n_dof
    el = plate.elements["mitc4"]
    r = np.repeat(el, 4, axis=1).ravel()
    c = np.tile(el, (1, 4)).ravel()
    G = sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(plate.n_nodes,) * 2)
    nfree = np.bincount(plate.dof_node, minlength=plate.n_nodes)
    est2 = fe.estimate_eigen_memory(G, 10, dofs_per_vertex=nfree)
    # the fully coupled pattern: every 6 x 6 node-pair block (K itself stores only
    # the membrane and bending entries of a flat plate)
    free = plate.dof_node * 6 + plate.dof_component
    full = sp.kron(G, np.ones((6, 6))).tocsr()[free][:, free].tocsc()
    assert full.nnz == 2 * plate.K.nnz
    est_full = fe.estimate_eigen_memory(full, 10)
    assert est2.nnz_factor == est_full.nnz_factor and est2.total == est_full.total
    assert est2.nnz_factor > 1.5 * est.nnz_factor       # flat plate: about 2x
    assert est.total > est.solve > S.FACTOR_BYTES_PER_NNZ * est.nnz_factor
    assert list(est.to_dataframe()["part"]) == ["matrices", "solve", "total"]
    with pytest.raises(ParameterError, match="n_modes must be a positive integer"):
        fe.estimate_eigen_memory(plate.K, 0)
    with pytest.raises(DimensionError, match=r"dofs_per_vertex must be a scalar or have shape"):
        fe.estimate_eigen_memory(G, 10, dofs_per_vertex=np.ones(3))


def test_sturm_count_of_missed_repeated_eigenvalues(plate):
    """The inertia of K - tau M (negative SuperLU pivots in its symmetric ordering) counts
    the eigenvalues below tau exactly: checked against a dense solve of the plate, and
    the count of copies Lanczos would have missed."""
    import scipy.linalg as sla

    small = fe.plate_model(0.3, 0.2, [fe.Ply(fe.IsotropicMaterial("s", 210e9, 0.3, 7850.0),
                                              1e-3)], nx=6, ny=4, clamp="x0")
    w = sla.eigh(small.K.toarray(), small.M.toarray(), eigvals_only=True)
    for j in (3, 10, 40):
        tau = 0.5 * (w[j] + w[j + 1])
        lu = fe.factorize((small.K - tau * small.M).tocsc(), backend="superlu")
        assert np.count_nonzero(lu.U.diagonal() < 0) == j + 1
    # a repeated eigenvalue with one copy "missed": K = diag(1, 2, 2, 2, 5), M = I
    K = sp.diags([1.0, 2.0, 2.0, 2.0, 5.0, 7.0, 9.0]).tocsc()
    M = sp.eye(7, format="csc")
    assert S._missed_copies(K, M, np.array([1.0, 2.0, 2.0, 5.0])) == 1
    assert S._missed_copies(K, M, np.array([1.0, 2.0, 2.0, 2.0, 5.0])) == 0
    # copies of the highest eigenvalue beyond the n requested are not missing
    assert S._missed_copies(K, M, np.array([1.0, 2.0, 2.0])) == 0
    assert S._missed_copies(K, M, np.array([1.0, 2.0])) is None  # no cluster: not checked
    # eigsh_lowest returns all three copies
    np.testing.assert_allclose(fe.eigsh_lowest(K, M, 4).omega2, [1, 2, 2, 2], rtol=1e-12)


def test_uncoupled_zeros_are_dropped_by_kind_not_by_value(plate):
    """A flat plate's K stores the zero membrane-bending coupling: factorize drops it
    (and only zeros), halving SuperLU's storage; zeros inside a coupled kind (couplings
    that vanish by the symmetry of the regular mesh) are kept, so the pattern is the
    mesh's; a shell whose fields couple keeps every entry."""
    # K on the fully coupled pattern (every 6 x 6 node-pair block, as an assembly that
    # does not leave the membrane-bending entries out stores it)
    el = plate.elements["mitc4"]
    G = sp.csr_matrix((np.ones(16 * len(el)), (np.repeat(el, 4, axis=1).ravel(),
                                               np.tile(el, (1, 4)).ravel())),
                      shape=(plate.n_nodes,) * 2)
    free = plate.dof_node * 6 + plate.dof_component
    pat = sp.kron(G, np.ones((6, 6))).tocsr()[free][:, free].tocoo()
    K = sp.csc_matrix((plate.K.toarray()[pat.row, pat.col], (pat.row, pat.col)),
                      shape=plate.K.shape)
    K.sort_indices()
    assert K.nnz == 2 * plate.K.nnz and abs(K - plate.K).max() == 0.0
    K0 = S._drop_uncoupled(K)
    assert abs(K0 - K).max() == 0.0                       # only zeros dropped
    assert K0.nnz < 0.55 * K.nnz
    # exactly the entries plate_model's assembly stores (it leaves the others out)
    np.testing.assert_array_equal(K0.indptr, plate.K.indptr)
    np.testing.assert_array_equal(K0.indices, plate.K.indices)
    assert np.count_nonzero(K0.data == 0) > 0             # symmetric-mesh zeros kept
    c = plate.dof_component
    membrane, bending = np.isin(c, (0, 1, 5)), np.isin(c, (2, 3, 4))
    assert K0[membrane][:, bending].nnz == 0
    # the kinds are found from the nonzeros: a membrane-bending coupling keeps them all
    Kc = K.tolil()
    i, j = np.flatnonzero(membrane)[10], np.flatnonzero(bending)[10]
    Kc[i, j] = Kc[j, i] = 1.0
    Kc = Kc.tocsc()
    Kc.sort_indices()
    assert S._drop_uncoupled(Kc).nnz == Kc.nnz
    full = fe.factorize(K, backend="superlu", ordering="metis")
    assert full.nnz_storage < 0.6 * S._superlu(K, S.fill_reducing_ordering(K))[1].nnz
    b = np.random.default_rng(3).standard_normal(plate.n_dof)
    np.testing.assert_allclose(K @ full.solve(b), b, atol=1e-8 * np.abs(b).max())


def test_sparse_backend_names_what_factorize_uses(monkeypatch):
    """sparse_backend() (for timings and report provenance) against the backend that
    factorize actually picks for a positive definite matrix, with and without CHOLMOD
    and with the environment override."""
    A = sp.diags([4.0] * 200) + sp.diags([-1.0] * 199, 1) + sp.diags([-1.0] * 199, -1)
    A = A.tocsc()
    monkeypatch.delenv("MVTK_SPARSE_BACKEND", raising=False)
    assert fe.sparse_backend() == fe.factorize(A).backend
    assert fe.sparse_backend(detail=True).startswith(fe.sparse_backend() + " (")
    monkeypatch.setattr(S, "_cholmod_module", lambda: None)
    assert fe.sparse_backend() == fe.factorize(A).backend == "superlu"
    assert "scipy" in fe.sparse_backend(detail=True)
    monkeypatch.setenv("MVTK_SPARSE_BACKEND", "superlu")
    assert fe.sparse_backend() == "superlu"
    monkeypatch.setenv("MVTK_SPARSE_BACKEND", "bogus")
    with pytest.raises(ParameterError, match="MVTK_SPARSE_BACKEND"):
        fe.sparse_backend()
