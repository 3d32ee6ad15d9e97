"""Sparse assembly: node-graph sparsity pattern against a sort of every matrix entry."""

import numpy as np
import pytest
import scipy.sparse as sp

import mvtk.fe as fe
from mvtk.errors import DimensionError, ParameterError
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


def test_dof_kinds_leave_uncoupled_entries_out(grid, rng):
    """With DOF kinds (membrane 0, 1, 5 and bending 2, 3, 4 of a flat shell node) the
    pattern holds only the entries within a kind: the matrix is the entry sum without
    the cross-kind zeros; a nonzero there is refused, not dropped."""
    dofs, fi, n_free = grid
    kinds = np.array([0, 0, 1, 1, 1, 0])
    cross = np.tile(kinds[:, None] != kinds[None, :], (4, 4))
    Ke = rng.standard_normal((len(dofs), 24, 24))
    Ke[:, cross] = 0.0
    p = SparsityPattern(dofs, fi, n_free, kinds)
    K = p.assemble(Ke)
    ref = _reference(Ke, dofs, fi, n_free)
    ref.eliminate_zeros()
    assert K.has_sorted_indices
    np.testing.assert_array_equal(K.indptr, ref.indptr)
    np.testing.assert_array_equal(K.indices, ref.indices)
    assert abs(K - ref).max() <= 1e-13 * abs(ref).max()
    # the lazily computed positions give the same sum (cross-kind entries at nnz)
    data = np.bincount(p.position, weights=Ke.ravel(), minlength=p.nnz + 1)
    assert abs(sp.csr_matrix((data[:p.nnz], p.indices, p.indptr), shape=p.shape)
               - ref).max() <= 1e-13 * abs(ref).max()
    Ke[3, 0, 2] = 1.0                          # ux of node 0 coupled with uz
    with pytest.raises(ParameterError, match="couple DOFs of different kinds"):
        p.assemble(Ke)
    # a generic (entry-sort) pattern keeps every entry whatever the kinds
    assert SparsityPattern(dofs[:, ::-1], fi, n_free, kinds).nnz == \
        SparsityPattern(dofs, fi, n_free).nnz


def test_flat_plate_pattern_splits_membrane_and_bending():
    """A flat plate with a symmetric laminate stores no membrane-bending entries (half
    of K's node blocks, zero by construction); an unsymmetric laminate (B != 0) couples
    them and keeps the full node blocks. Values equal those of the full pattern."""
    from mvtk.fe import _assembly

    steel = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)
    alu = fe.IsotropicMaterial("alu", 70e9, 0.33, 2700.0)
    sym = fe.plate_model(1.0, 0.5, [fe.Ply(steel, 0.01)], nx=6, ny=3, clamp="x0")
    uns = fe.plate_model(1.0, 0.5, [fe.Ply(steel, 0.005), fe.Ply(alu, 0.005)],
                         nx=6, ny=3, clamp="x0")
    assert 2 * sym.K.nnz == uns.K.nnz and sym.M.nnz == sym.K.nnz
    # the same matrices on the full pattern of the mesh
    nodes, el = sym.nodes, sym.elements["mitc4"]
    dofs = (el[:, :, None] * 6 + np.arange(6)).reshape(len(el), 24)
    fi = np.full(len(nodes) * 6, -1)
    fi[sym.dof_node * 6 + sym.dof_component] = np.arange(sym.n_dof)
    xy = nodes[el, :2]
    lam = fe.Laminate([fe.Ply(steel, 0.01)])
    Ku, Mu = _assembly.mitc4_matrices(xy, lam.ABD[None], lam.H[None],
                                      np.array([[lam.I0, lam.I1, lam.I2]]),
                                      _assembly.DRILL_FACTOR)
    full = SparsityPattern(dofs, fi, sym.n_dof)
    for A, U in ((sym.K, Ku), (sym.M, Mu)):
        B = full.assemble(U)
        assert B.nnz == uns.K.nnz
        assert abs(A - B).max() <= 1e-14 * abs(B).max()


def test_model_refuses_a_dof_listed_twice():
    """FEModel's DOF table: each (node, component) once, components 0..5."""
    K = sp.identity(3, format="csr")
    nodes = np.zeros((2, 3))
    fe.FEModel(K=K, M=K, nodes=nodes, dof_node=np.array([0, 0, 1]),
               dof_component=np.array([0, 1, 0]))
    with pytest.raises(DimensionError, match="duplicated DOF"):
        fe.FEModel(K=K, M=K, nodes=nodes, dof_node=np.array([0, 1, 1]),
                   dof_component=np.array([2, 0, 0]))
    with pytest.raises(DimensionError, match="dof_component must be in 0..5"):
        fe.FEModel(K=K, M=K, nodes=nodes, dof_node=np.array([0, 0, 1]),
                   dof_component=np.array([0, 6, 0]))
