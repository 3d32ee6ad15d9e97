"""K without its round-off entries: what is dropped, what is kept, stable pattern."""

import numpy as np
import scipy.sparse as sp

from mvtk.fe import build_model, eigsh_lowest
from mvtk.updating import with_values
from mvtk.updating._roundoff import without_roundoff

PLATE = {
    "materials": {"steel": {"E": 210e9, "nu": 0.3, "rho": 7900.0},
                  "pzt": {"E": 66.7e9, "nu": 0.34, "rho": 7800.0, "d31": -2.1e-10}},
    "structure": {"type": "plate", "length": 0.18, "width": 0.13,
                  "layers": [{"material": "steel", "thickness": 5e-4}]},
    "patches": [{"name": "p", "x0": 0.01, "x1": 0.06, "y0": 0.05, "y1": 0.08,
                 "layers": [{"material": "pzt", "thickness": 2.5e-4}]}],
    "mesh": {"nx": 18, "ny": 13},
    "boundary": {"clamp": "x0", "clamp_stiffness": 500.0},
}


def _ratios(K):
    K = sp.csr_matrix(K)
    d = np.abs(K.diagonal())
    rows = np.repeat(np.arange(K.shape[0]), np.diff(K.indptr))
    return np.abs(K.data) / np.sqrt(d[rows] * d[K.indices])


def test_only_roundoff_entries_are_dropped_and_the_pattern_is_the_same_for_new_values():
    K1 = build_model(PLATE).K
    r = _ratios(K1)
    # the stored entries are exact zeros, round-off (< 1e-14) or physical (> 1e-7)
    assert not np.any((r > 1e-14) & (r < 1e-7))
    P1 = without_roundoff(K1)
    assert P1.nnz == np.count_nonzero(r > 1e-13)
    np.testing.assert_array_equal(P1.diagonal(), K1.diagonal())
    assert abs(P1 - K1).max() <= 1e-13 * abs(K1).max()
    # new values (modulus, thickness, clamp): the same pruned pattern
    desc = with_values(PLATE, {"materials.steel.E": 190e9,
                               "structure.layers.0.thickness": 5.2e-4,
                               "boundary.clamp_stiffness": 800.0})
    P2 = without_roundoff(build_model(desc).K)
    np.testing.assert_array_equal(P2.indptr, P1.indptr)
    np.testing.assert_array_equal(P2.indices, P1.indices)


def test_eigenvalues_move_by_round_off_only():
    m = build_model(PLATE)
    a = eigsh_lowest(m.K, m.M, 6).omega2
    b = eigsh_lowest(without_roundoff(m.K), m.M, 6).omega2
    np.testing.assert_allclose(b, a, rtol=1e-9)


def test_small_physical_couplings_and_the_diagonal_are_kept():
    """A coupling of 1e-10 of the diagonal is physics (kept); 1e-16 is round-off
    (dropped); a zero diagonal entry stays (a massless, stiffness-free DOF)."""
    rows = [0, 0, 0, 1, 1, 2, 2, 3]
    cols = [0, 1, 2, 0, 1, 0, 2, 3]
    vals = [1.0, 1e-10, 1e-16, 1e-10, 1.0, 1e-16, 1.0, 0.0]   # K[3, 3]: a stored zero
    K = sp.csr_matrix((vals, (rows, cols)), shape=(4, 4))
    assert K.nnz == 8
    P = without_roundoff(K)
    expected = K.toarray()
    expected[0, 2] = expected[2, 0] = 0.0
    np.testing.assert_array_equal(P.toarray(), expected)
    assert P.nnz == 6 and P.has_sorted_indices   # the zero diagonal entry stays stored
