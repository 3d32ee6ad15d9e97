"""AffineModel: substructure matrices from files, K = K0 + sum theta_i K_i, M likewise.

External truth: the directly assembled model of the whole structure (same elements) must
equal the sum of the separately assembled, exported and re-read substructures to
round-off, with each substructure exported on its own DOFs only.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
from affine_plate import assemble, dof_table, plate_mesh

from mvtk.errors import ConfigError, DimensionError, FormatError, ParameterError
from mvtk.fe import (
    AffineModel,
    eigsh_lowest,
)


def _plate_parts():
    """A clamped plate and its left / right halves assembled separately."""
    nodes, halves = plate_mesh()
    return (assemble(nodes, halves), assemble(nodes, {"left": halves["left"]}),
            assemble(nodes, {"right": halves["right"]}, clamped=False))


def _export(tmp_path, model, stem):
    scipy.io.mmwrite(tmp_path / f"{stem}_K.mtx", model.K)
    scipy.io.mmwrite(tmp_path / f"{stem}_M.mtx", model.M)
    with open(tmp_path / f"{stem}_dofs.csv", "w") as f:
        f.write("node,dof\n")
        for n, c in dof_table(model):
            f.write(f"{n},{c}\n")
    return {"K": tmp_path / f"{stem}_K.mtx", "M": tmp_path / f"{stem}_M.mtx",
            "dof_table": tmp_path / f"{stem}_dofs.csv"}


@pytest.fixture(scope="module")
def plate():
    return _plate_parts()


def test_parts_from_files_sum_to_the_whole_model(plate, tmp_path):
    whole, left, right = plate
    assert left.n_dof < whole.n_dof and right.n_dof < whole.n_dof  # own DOFs only
    am = AffineModel.from_files({"left": _export(tmp_path, left, "left"),
                                 "right": _export(tmp_path, right, "right")},
                                dof_table=dof_table(whole))
    m = am.model()
    assert m.n_dof == whole.n_dof
    np.testing.assert_array_equal(m.node_ids[m.dof_node], whole.node_ids[whole.dof_node])
    np.testing.assert_array_equal(m.dof_component, whole.dof_component)
    for a, b in ((m.K, whole.K), (m.M, whole.M)):
        assert abs(a - b).max() <= 1e-14 * abs(b).max()
    # scaling a part scales its matrices: theta = (2, 1) is the whole plus the left part
    m2 = am.model({"left": 2.0})
    ref = whole.K + am.K_parts[0]
    assert abs(m2.K - ref).max() <= 1e-14 * abs(ref).max()
    # union of the part tables in order of appearance when no model table is given
    am2 = AffineModel.from_files({"left": _export(tmp_path, left, "left"),
                                  "right": _export(tmp_path, right, "right")})
    f1 = eigsh_lowest(am2.model().K, am2.model().M, 4).omega2
    f0 = eigsh_lowest(whole.K, whole.M, 4).omega2
    np.testing.assert_allclose(f1, f0, rtol=1e-10)


def test_mat_file_parts_base_and_stiffness_only_parts(plate, tmp_path):
    whole, left, right = plate
    scipy.io.savemat(tmp_path / "left.mat", {"K": left.K, "M": left.M})
    am = AffineModel.from_files(
        {"left": {"K": tmp_path / "left.mat", "M": tmp_path / "left.mat",
                  "dof_table": dof_table(left)},
         "right_stiffness": {"K": right.K, "dof_table": dof_table(right)}},
        base={"M": right.M, "dof_table": dof_table(right)},
        dof_table=dof_table(whole), theta0={"right_stiffness": 1.0},
        nodes=np.column_stack([whole.node_ids, whole.nodes]))
    m = am.model()
    np.testing.assert_array_equal(m.dof_node, whole.dof_node)
    np.testing.assert_array_equal(m.nodes, whole.nodes)
    assert abs(m.K - whole.K).max() <= 1e-14 * abs(whole.K).max()
    assert abs(m.M - whole.M).max() <= 1e-14 * abs(whole.M).max()
    dK, dM = am.matrix_derivatives("theta.right_stiffness")
    assert dM.nnz == 0 and abs(dK).max() > 0
    assert am.description() == {"theta": {"left": 1.0, "right_stiffness": 1.0}}
    assert abs(am(am.description({"left": 0.5})).K - m.K).max() > 0


def test_bad_inputs(plate, tmp_path):
    whole, left, right = plate
    part = _export(tmp_path, left, "left")
    with pytest.raises(ConfigError, match="at least one part"):
        AffineModel.from_files({})
    with pytest.raises(ConfigError, match=r"unknown key\(s\) 'stiffness'; accepted: K, M"):
        AffineModel.from_files({"left": {"stiffness": part["K"]}})
    with pytest.raises(ConfigError, match="at least one of K and M"):
        AffineModel.from_files({"left": {"dof_table": part["dof_table"]}})
    with pytest.raises(ConfigError, match="no dof_table"):
        AffineModel.from_files({"left": {"K": part["K"]}})
    with pytest.raises(ConfigError, match="must be an identifier"):
        AffineModel.from_files({"left skin": part})
    with pytest.raises(DimensionError, match="DOF table of part 'left' has"):
        AffineModel.from_files({"left": {"K": part["K"], "dof_table": dof_table(right)}})
    # a part DOF the model table does not list: node and dof named
    with pytest.raises(FormatError, match=r"part 'right': node \d+ dof \w+ is not in the "
                                          "model's DOF table"):
        AffineModel.from_files({"left": part, "right": _export(tmp_path, right, "right")},
                               dof_table=dof_table(left))
    dup = dof_table(left).copy()
    dup[1] = dup[0]
    with pytest.raises(FormatError, match="appears twice"):
        AffineModel.from_files({"left": {"K": left.K, "dof_table": dup}})
    with pytest.raises(DimensionError, match="not symmetric"):
        bad = left.K.tolil()
        bad[0, 1] += 1e-3 * abs(left.K).max()
        AffineModel.from_files({"left": {"K": bad, "dof_table": dof_table(left)}})
    with pytest.raises(FormatError, match="no variable 'M'"):
        scipy.io.savemat(tmp_path / "k_only.mat", {"K": left.K})
        AffineModel.from_files({"left": tmp_path / "k_only.mat"}, dof_table=dof_table(left))
    with pytest.raises(ConfigError, match=r"theta0: unknown part\(s\) \['skin'\]"):
        AffineModel.from_files({"left": part}, theta0={"skin": 1.0})
    am = AffineModel.from_files({"left": part})
    with pytest.raises(ParameterError, match=r"unknown part\(s\) \['right'\]"):
        am.model({"right": 1.0})
    with pytest.raises(DimensionError, match=r"expected 1 values \(left\), got 2"):
        am.model([1.0, 2.0])
    with pytest.raises(ConfigError, match="unknown key.*theta.skin; accepted: theta.left"):
        am({"theta": {"skin": 1.0}})
    with pytest.raises(ConfigError, match="expected a 'theta' table"):
        am({"materials": {}})
    with pytest.raises(ParameterError, match="no affine parameter 'materials.E'"):
        am.matrix_derivatives("materials.E")
