import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from mvtk.errors import DimensionError, FormatError, MvtkError, ParameterError
from mvtk.fe import FEModel, eigsh_lowest


def test_import_does_not_pull_heavy_modules():
    code = (
        "import sys, mvtk; bad=[m for m in ('matplotlib','pyuff','dask') if m in sys.modules];"
        "print(','.join(bad))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == ""


def test_errors_subclass_builtins():
    assert issubclass(FormatError, ValueError) and issubclass(FormatError, MvtkError)


def _chain(n=500, k=1e4, m=1.0):
    K = sp.diags([2 * k * np.ones(n), -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1])
    K = K.tolil()
    K[n - 1, n - 1] = k
    M = sp.identity(n) * m
    nodes = np.zeros((n, 3))
    nodes[:, 0] = np.arange(n)
    return FEModel(nodes, M, K.tocsr(), np.arange(n), np.zeros(n, dtype=int))


def test_chain_eigenvalues_closed_form():
    # fixed-free spring-mass chain: omega_j = 2 sqrt(k/m) sin((2j-1) pi / (2(2n+1)))
    n, k = 500, 1e4
    model = _chain(n, k)
    sol = eigsh_lowest(model.K, model.M, 5)
    j = np.arange(1, 6)
    exact = 2 * np.sqrt(k) * np.sin((2 * j - 1) * np.pi / (2 * (2 * n + 1)))
    np.testing.assert_allclose(np.sqrt(sol.omega2), exact, rtol=1e-9)
    np.testing.assert_allclose(sol.vectors.T @ model.M @ sol.vectors, np.eye(5), atol=1e-10)


def test_femodel_lookup_and_errors():
    model = _chain(10)
    assert model.dof_index(3, "ux") == 3
    with pytest.raises(ParameterError, match="constrained"):
        model.dof_index(3, "uz")
    with pytest.raises(DimensionError):
        FEModel(np.zeros((2, 3)), sp.eye(2), sp.eye(3), [0, 1], [0, 0])
    assert model.expand(np.ones(10)).shape == (10, 6)


def test_free_free_chain_finds_rigid_body_mode():
    n, k = 600, 1e4
    K = sp.diags([2 * k * np.ones(n), -k * np.ones(n - 1), -k * np.ones(n - 1)], [0, 1, -1])
    K = K.tolil()
    K[0, 0] = K[n - 1, n - 1] = k  # free-free: one rigid-body mode
    sol = eigsh_lowest(K.tocsr(), sp.identity(n), 4)
    j = np.arange(0, 4)
    exact = 2 * np.sqrt(k) * np.sin(j * np.pi / (2 * n))  # free-free chain
    assert abs(sol.omega2[0]) < 1e-8 * exact[1] ** 2
    np.testing.assert_allclose(np.sqrt(np.abs(sol.omega2[1:])), exact[1:], rtol=1e-8)


def test_statespace_static_gain_and_roundtrip():
    from mvtk.control import StateSpace

    g = StateSpace(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((2, 0)), [[2.0], [3.0]])
    assert (g.n_states, g.n_inputs, g.n_outputs) == (0, 1, 2)
    np.testing.assert_allclose(g.dc_gain(), [[2.0], [3.0]])
    np.testing.assert_allclose(g.frequency_response([1.0])[:, :, 0], [[2.0], [3.0]])
    sdof = StateSpace([[0, 1], [-100.0, -0.2]], [[0], [1]], [[1, 0]], inputs=["f"])
    np.testing.assert_allclose(sdof.dc_gain(), [[0.01]])
    back = StateSpace.from_scipy(sdof.to_scipy())
    np.testing.assert_allclose(back.A, sdof.A)
    with pytest.raises(DimensionError, match="C must have 2 columns"):
        StateSpace(sdof.A, sdof.B, [[1, 0, 0]])
