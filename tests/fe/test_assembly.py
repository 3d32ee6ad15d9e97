"""Sparse assembly: node-graph sparsity pattern against a sort of every matrix entry."""

import numpy as np
import pytest
import scipy.sparse as sp

import mvtk.fe as fe
from mvtk.errors import DimensionError
from mvtk.fe._assembly import SparsityPattern, sparsity_pattern


def _grid(n):
    el = np.array([[i * (n + 1) + j, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1,
                    i * (n + 1) + j + 1] for i in range(n) for j in range(n)])
    nn = (n + 1) ** 2
    dofs = (el[:, :, None] * 6 + np.arange(6)).reshape(len(el), 24)
    fixed = np.zeros(nn * 6, bool)
    fixed[: 6 * (n + 1)] = True                          # clamped edge
    fixed[np.arange(nn) * 6 + 5] = np.arange(nn) % 7 == 0  # scattered single DOFs
    free = np.flatnonzero(~fixed)
    fi = np.full(nn * 6, -1)
    fi[free] = np.arange(len(free))
    return dofs, fi, len(free)


def _reference(Ke, dofs, fi, n_free):
    """COO sum of every kept entry (scipy sums duplicates)."""
    f = fi[dofs]
    n = dofs.shape[1]
    rows = np.broadcast_to(f[:, :, None], Ke.shape).ravel()
    cols = np.broadcast_to(f[:, None, :], Ke.shape).ravel()
    keep = (rows >= 0) & (cols >= 0)
    del n
    return sp.coo_matrix((Ke.ravel()[keep], (rows[keep], cols[keep])),
                         shape=(n_free, n_free)).tocsr()


@pytest.fixture
def grid():
    return _grid(7)


def test_node_graph_pattern_matches_entry_sort(grid, rng):
    dofs, fi, n_free = grid
    Ke = rng.standard_normal((len(dofs), 24, 24))
    node = SparsityPattern(dofs, fi, n_free)
    K = node.assemble(Ke)
    ref = _reference(Ke, dofs, fi, n_free)
    assert K.has_sorted_indices
    assert K.nnz == ref.nnz            # no duplicates, no extra entries
    assert abs(K - ref).max() <= 1e-13 * abs(ref).max()
    # the generic path (entry sort) on shuffled element DOFs gives the same matrix
    perm = rng.permutation(24)
    generic = SparsityPattern(dofs[:, perm], fi, n_free)
    K2 = generic.assemble(Ke[:, perm][:, :, perm])
    np.testing.assert_array_equal(K2.indptr, K.indptr)
    np.testing.assert_array_equal(K2.indices, K.indices)
    assert abs(K2 - K).max() <= 1e-13 * abs(ref).max()


def test_pattern_is_cached_and_reused(grid, rng):
    dofs, fi, n_free = grid
    p1 = sparsity_pattern(dofs, fi, n_free)
    p2 = sparsity_pattern(dofs.copy(), fi.copy(), n_free)
    assert p1 is p2
    fi2 = fi.copy()
    fi2[fi2 == n_free - 1] = -1        # one more constrained DOF: a new pattern
    assert sparsity_pattern(dofs, fi2, n_free - 1) is not p1


def test_plate_rebuild_reuses_pattern_and_matches(monkeypatch):
    from mvtk.fe import _assembly

    monkeypatch.setattr(_assembly, "_PATTERN_CACHE", type(_assembly._PATTERN_CACHE)())
    steel = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    a = fe.plate_model(1.0, 0.5, [fe.Ply(steel, 0.01)], nx=8, ny=4, clamp="x0")
    b = fe.plate_model(1.0, 0.5, [fe.Ply(steel, 0.02)], nx=8, ny=4, clamp="x0")
    assert len(_assembly._PATTERN_CACHE) == 1   # one pattern served both builds
    np.testing.assert_array_equal(a.K.indices, b.K.indices)
    # the reused pattern gives exactly what a fresh one gives
    _assembly._PATTERN_CACHE.clear()
    c = fe.plate_model(1.0, 0.5, [fe.Ply(steel, 0.02)], nx=8, ny=4, clamp="x0")
    np.testing.assert_array_equal(b.K.toarray(), c.K.toarray())
    np.testing.assert_array_equal(b.M.toarray(), c.M.toarray())


def test_bad_element_matrices_shape(grid):
    dofs, fi, n_free = grid
    p = sparsity_pattern(dofs, fi, n_free)
    with pytest.raises(DimensionError, match=r"element matrices must have shape \(49, 24, 24\)"):
        p.assemble(np.zeros((49, 12, 12)))


def test_bad_dofs(grid):
    dofs, fi, n_free = grid
    with pytest.raises(DimensionError, match="element DOF indices must be in 0.."):
        SparsityPattern(dofs + len(fi), fi, n_free)
    with pytest.raises(DimensionError, match=r"dofs must have shape \(n_el, n\)"):
        SparsityPattern(dofs.ravel(), fi, n_free)


def test_distinct_matrices_and_lazy_position_match_the_entry_sum(grid, rng):
    """Distinct element matrices with each element's index (``rep``) give the matrices of
    the summed copies, for K and M at once; the node-graph pattern's lazily computed
    ``position`` sums the same matrix with ``np.bincount`` (as mvtk.fe._general does)."""
    dofs, fi, n_free = grid
    Ku = rng.standard_normal((3, 24, 24))
    Mu = rng.standard_normal((3, 24, 24))
    rep = rng.integers(0, 3, size=len(dofs))
    p = SparsityPattern(dofs, fi, n_free)
    K, M = p.assemble_many([Ku, Mu], rep)
    for A, U in ((K, Ku), (M, Mu)):
        ref = _reference(U[rep], dofs, fi, n_free)
        assert A.nnz == ref.nnz
        assert abs(A - ref).max() <= 1e-13 * abs(ref).max()
        data = np.bincount(p.position, weights=U[rep].ravel(), minlength=p.nnz + 1)
        B = sp.csr_matrix((data[:p.nnz], p.indices, p.indptr), shape=p.shape)
        assert abs(B - ref).max() <= 1e-13 * abs(ref).max()
    # the positions of the node-graph pattern are those of the entry sort
    generic = SparsityPattern(dofs[:, ::-1], fi, n_free)
    pos_node = p.position.reshape(len(dofs), 24, 24)[:, ::-1, ::-1].ravel()
    np.testing.assert_array_equal(pos_node, generic.position)
    with pytest.raises(DimensionError, match=r"rep must have shape \(49,\)"):
        p.assemble(Ku, rep[:-1])
    with pytest.raises(DimensionError, match=r"rep must index 0..2"):
        p.assemble(Ku, rep + 3)
