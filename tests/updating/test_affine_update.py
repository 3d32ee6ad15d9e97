"""Updating a third-party model given as substructure matrices (mvtk.fe.AffineModel).

Twin experiment: a clamped plate split into two element sets whose stiffness matrices
were assembled and exported separately (each on its own DOFs, through Matrix Market
files and DOF tables); the "measured" frequencies come from the same matrices with
known factors theta, which the update must recover. External truth for the
sensitivities: central finite differences of the eigenvalues.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
import scipy.linalg as sl
from affine_plate import assemble, dof_table, plate_mesh

from mvtk.fe import (
    AffineModel,
    eigsh_lowest,
)
from mvtk.updating import Parameter, eigen_sensitivity, update

THETA_TRUE = {"left": 1.25, "right": 0.8}
@pytest.fixture(scope="module")
def affine(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("affine")
    nodes, halves = plate_mesh()
    whole = assemble(nodes, halves)
    parts = {}
    for k, q in halves.items():
        m = assemble(nodes, {k: q}, clamped=k == "left")
        scipy.io.mmwrite(tmp / f"{k}_K.mtx", m.K)
        np.savetxt(tmp / f"{k}_dofs.csv", dof_table(m), fmt="%d", delimiter=",",
                   header="node,dof", comments="")
        parts[k] = {"K": tmp / f"{k}_K.mtx", "dof_table": tmp / f"{k}_dofs.csv"}
    scipy.io.mmwrite(tmp / "M.mtx", whole.M)
    np.savetxt(tmp / "dofs.csv", dof_table(whole), fmt="%d", delimiter=",")
    return AffineModel.from_files(parts, base={"M": tmp / "M.mtx"},
                                  dof_table=tmp / "dofs.csv")


def test_twin_experiment_recovers_the_substructure_factors(affine):
    true = affine.model(THETA_TRUE)
    fn = np.sqrt(eigsh_lowest(true.K, true.M, 6).omega2) / (2 * np.pi)
    params = [Parameter(f"theta.{k}", lower=0.2, upper=5.0) for k in affine.names]
    with np.errstate(all="ignore"):
        res = update(affine.description(), params, list(fn), builder=affine, affine=True,
                     n_modes=10)
    got = [res.description["theta"][k] for k in affine.names]
    np.testing.assert_allclose(got, [THETA_TRUE[k] for k in affine.names], rtol=1e-6)
    assert res.identifiable
    # the exact derivatives make the affine model the model: the real build agrees
    assert res.meta["affine_check_rel"] < 1e-9  # eigen-solver round-off


def _dense_w2(model, n):
    # dense LAPACK on M x = mu K x (K is well conditioned, M is not: token drilling
    # inertia), mu = 1 / omega^2: eigenvalues to round-off, which ARPACK's would not be
    m = model.n_dof
    mu = sl.eigh(model.M.toarray(), model.K.toarray(), eigvals_only=True,
                 subset_by_index=[m - n, m - 1])
    return 1.0 / mu[::-1]


def test_sensitivities_against_finite_differences_of_eigenvalues(affine):
    n = 5
    sens = eigen_sensitivity(affine.description(), [f"theta.{k}" for k in affine.names],
                             builder=affine, n_modes=n)
    h = 1e-3  # truncation ~1e-6, round-off of the dense eigenvalues ~1e-7 (relative)
    for col, k in enumerate(affine.names):
        up = affine.model({k: 1.0 + h})
        dn = affine.model({k: 1.0 - h})
        fd = (_dense_w2(up, n) - _dense_w2(dn, n)) / (2 * h)
        np.testing.assert_allclose(sens.d_omega2[:, col], fd, rtol=1e-5)
    # and the analytic form phi' K_i phi of mass-normalised modes
    m0 = affine.model()
    eig = eigsh_lowest(m0.K, m0.M, n)
    for col, k in enumerate(affine.names):
        dK, _ = affine.matrix_derivatives(f"theta.{k}")
        exact = np.einsum("ij,ij->j", eig.vectors, dK @ eig.vectors)
        # as accurate as eigsh's eigenvectors (a partial quadratic form is linear in them)
        np.testing.assert_allclose(sens.d_omega2[:, col], exact, rtol=2e-6)
    # the two halves share the stiffness: at theta = 1, sum_i theta_i dw2/dtheta_i = w2
    np.testing.assert_allclose(sens.d_omega2.sum(axis=1), eig.omega2, rtol=1e-6)
