"""Beam shear factors (Cowper's default, set per section on imported meshes) and full
inertia tensors of point masses in a frame.

External truths: Cowper, "The shear coefficient in Timoshenko's beam theory", J. Appl.
Mech. 33 (1966) 335-340, table 1: rectangle k = 10 (1 + nu) / (12 + 11 nu); cantilever
tip deflection with shear, P L^3 / (3 E I) + P L / (k G A) (Timoshenko & Gere); the
rotation of a second-order tensor, J_global = R' J_local R.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mvtk.errors import ConfigError, ParameterError
from mvtk.fe import (
    IsotropicMaterial,
    PointMass,
    build_model,
    load_vector,
    rectangle_section,
    static_solve,
)

meshio = pytest.importorskip("meshio")
STEEL = IsotropicMaterial("steel", 210e9, 0.3, 7850.0)


def test_rectangle_default_shear_factor_is_cowpers():
    sec = rectangle_section(STEEL, 0.02, 0.05)
    k = 10 * 1.3 / (12 + 11 * 0.3)
    assert k == pytest.approx(0.8497, abs=1e-4)  # Cowper 1966, nu = 0.3
    assert sec.kGAz == pytest.approx(k * STEEL.G * 0.02 * 0.05, rel=1e-14)
    assert sec.kGAy == pytest.approx(sec.kGAz, rel=1e-14)
    assert rectangle_section(STEEL, 0.02, 0.05, 5 / 6).kGAz == pytest.approx(
        5 / 6 * STEEL.G * 1e-3)
    with pytest.raises(ParameterError, match="shear_correction"):
        rectangle_section(STEEL, 0.02, 0.05, -1.0)


def _beam_desc(tmp_path, section):
    n, L = 10, 0.5
    nodes = np.column_stack([np.linspace(0, L, n + 1), np.zeros((n + 1, 2))])
    els = np.column_stack([np.arange(n), np.arange(1, n + 1)])
    meshio.Mesh(nodes, [("line", els)], cell_sets={"BEAM": [np.arange(n)]},
                point_sets={"ROOT": [0], "TIP": [n]}).write(tmp_path / "b.inp")
    return {"materials": {"st": {"E": 210e9, "nu": 0.3, "rho": 7850.0}},
            "structure": {"type": "mesh"},
            "mesh": {"file": str(tmp_path / "b.inp"), "sections": {"BEAM": "s"}},
            "sections": {"s": section},
            "boundary": {"supports": {"ROOT": "clamped"}},
            "coordinate_systems": {"tilt": {"type": "rectangular", "z_axis": [0, 1, 0],
                                            "x_axis": [0, 0, 1]}},
            "loads": [{"type": "force", "node_set": "TIP", "force": [0, 0, -1e4]}]}


@pytest.mark.parametrize("k", [None, 0.4])
def test_shear_factor_on_an_imported_beam_mesh(tmp_path, k):
    """A deep cantilever (L/h = 5) read from an Abaqus mesh: tip deflection with shear."""
    b, h, L, P = 0.05, 0.1, 0.5, 1e4
    sec = {"shape": "rectangle", "material": "st", "width": b, "height": h,
           "orientation": [0, 1, 0]}
    if k is not None:
        sec["shear_factor"] = k
    model = build_model(_beam_desc(tmp_path, sec))
    u = static_solve(model, load_vector(model))
    kk = 10 * 1.3 / 15.3 if k is None else k
    EI, kGA = 210e9 * b * h**3 / 12, kk * STEEL.G * b * h
    w = -u[model.dof_index(10, "uz")]
    assert w == pytest.approx(P * L**3 / (3 * EI) + P * L / kGA, rel=1e-9)


def test_point_mass_inertia_tensor_in_a_frame(tmp_path):
    R = Rotation.from_euler("zyx", [30, -20, 65], degrees=True).as_matrix().T
    J = np.array([[2.0, 0.3, -0.1], [0.3, 1.0, 0.2], [-0.1, 0.2, 3.0]])
    m = PointMass(0, 5.0, J, frame=R).matrix()
    np.testing.assert_allclose(m[3:, 3:], R.T @ J @ R, atol=1e-14)
    # invariants of the tensor are kept
    np.testing.assert_allclose(np.linalg.eigvalsh(m[3:, 3:]), np.linalg.eigvalsh(J))
    with pytest.raises(ParameterError, match="frame must be an orthonormal"):
        PointMass(0, 1.0, J, frame=2 * np.eye(3)).matrix()
    # the structure file: a full tensor given in a coordinate system (axes z -> y, x -> z)
    desc = _beam_desc(tmp_path, {"shape": "rectangle", "material": "st", "width": 0.05,
                                 "height": 0.1})
    desc["points"] = [{"name": "tip", "x": 0.5, "y": 0.0, "z": 0.0}]
    desc["masses"] = [{"point": "tip", "mass": 5.0, "inertia": J.tolist(),
                       "system": "tilt"}]
    model = build_model(desc)
    (pm,) = [x for x in model.meta["members"] if isinstance(x, PointMass)]
    Rt = np.array([[0, 0, 1.0], [1.0, 0, 0], [0, 1.0, 0]])  # rows: x, y, z of "tilt"
    np.testing.assert_allclose(pm.matrix()[3:, 3:], Rt.T @ J @ Rt, atol=1e-14)
    desc["masses"][0]["inertia"] = [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    with pytest.raises(ConfigError, match=r"masses\[0\]: .*positive semi-definite"):
        build_model(desc)
