"""Every bad-input path of mvtk.correlation raises an mvtk error naming the problem."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import xarray as xr
from correlation_helpers import plate_setup

from mvtk import correlation as co
from mvtk.errors import DimensionError, FormatError, ParameterError
from mvtk.fe import FEModel


@pytest.fixture(scope="module")
def setup():
    return plate_setup(4)


def test_metric_errors(setup):
    model, modal, geo, mp, fe = setup
    with pytest.raises(DimensionError, match=r"expected dims \('mode', 'dof'\), got \('a', 'b'\)"):
        co.mac(xr.DataArray(np.ones((2, 2)), dims=("a", "b")), fe)
    with pytest.raises(DimensionError, match="MSF pairs modes by position: got 4 and 2"):
        co.msf(fe, fe.isel(mode=[0, 1]))
    with pytest.raises(DimensionError, match="pair the modes first: got 4 and 2"):
        co.comac(fe, fe.isel(mode=[0, 1]))
    with pytest.raises(ParameterError, match="variant must be 'signed' or 'lieven_ewins'"):
        co.comac(fe, fe, variant="x")
    with pytest.raises(ParameterError, match="identically zero"):
        co.comac(fe * 0, fe)
    with pytest.raises(DimensionError, match="observation matrix has 3 columns"):
        co.serep_tam(modal.shapes, np.ones((2, 3)))
    with pytest.raises(ParameterError, match="zero or negative TAM mass"):
        co.cross_orthogonality(fe, None, -np.eye(fe.sizes["dof"]))
    H = co.synthesize_frf(fe, [10.0, 20.0], references=["1+z"], zeta=0.01)
    with pytest.raises(DimensionError, match=r"measured FRF: expected a DataArray with dims"):
        co.frac(H.isel(reference=0), H)
    with pytest.raises(DimensionError, match="FRF matrices differ in shape"):
        co.csac(H, H.isel(frequency=[0]))
    with pytest.raises(DimensionError, match="different response labels"):
        co.csf(H, H.assign_coords(response=[f"x{i}" for i in range(H.sizes["response"])]))
    with pytest.raises(ParameterError, match=r"reference DOFs \['99\+z'\] are not among"):
        co.synthesize_frf(fe, [1.0], references=["99+z"], zeta=0.01)
    with pytest.raises(ParameterError, match="frf_type must be receptance, mobility"):
        co.synthesize_frf(fe, [1.0], references=["1+z"], zeta=0.01, frf_type="inertance")
    with pytest.raises(ParameterError, match="need an 'fn_hz' coordinate"):
        co.synthesize_frf(fe.drop_vars("fn_hz"), [1.0], references=["1+z"], zeta=0.01)
    with pytest.raises(ParameterError, match="freq_weight must be >= 0"):
        co.pair_modes(fe, fe, freq_weight=-1)


def test_tam_needs_supported_structure():
    n = 4
    K = sp.csr_matrix(np.array([[1.0, -1, 0, 0], [-1, 2, -1, 0], [0, -1, 2, -1],
                                [0, 0, -1, 1]]))  # free-free chain: singular
    model = FEModel(nodes=np.column_stack([np.arange(n), np.zeros(n), np.zeros(n)]),
                    M=sp.identity(n, format="csr"), K=K, dof_node=np.arange(n),
                    dof_component=np.full(n, 2))
    with pytest.raises(ParameterError, match="non-singular K"):
        co.guyan_tam(model, np.eye(n)[:2])


def test_mapping_and_adapter_errors(setup):
    model, modal, geo, mp, fe = setup
    with pytest.raises(ParameterError, match="geometry must be a TestGeometry, got dict"):
        co.map_sensors({}, model)
    with pytest.raises(ParameterError, match="model must be an FEModel, got str"):
        co.map_sensors(geo, "model")
    with pytest.raises(ParameterError, match="tol must be a finite distance"):
        co.map_sensors(geo, model, tol=-1.0)
    with pytest.raises(DimensionError, match=f"expected FE vectors with {model.n_dof} rows"):
        mp.observe(np.ones((3, 2)))
    with pytest.raises(DimensionError, match=r"expected dims \('mode', 'dof'\)"):
        mp.project(xr.DataArray(np.ones((2, 3)), dims=("dof", "mode")))
    with pytest.raises(ParameterError, match="expected an mvtk.fe.ModalResult"):
        mp.project(object())
    with pytest.raises(DimensionError, match="modal shapes have 3 rows"):
        co.fe_shapes(model, type("E", (), {"vectors": np.ones((3, 1)),
                                           "omega2": np.ones(1)})())
    with pytest.raises(ParameterError, match="unknown element kind 'hex8'"):
        co.shape_functions("hex8", 0, 0)


def test_beam_model_maps_by_nearest_node():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "updating"))
    from updating_helpers import NOMINAL, strip_model

    m = strip_model(NOMINAL)  # beam2 elements only: no surface to interpolate on
    geo = co.TestGeometry([1, 2], [[0.09, 0.0, 0.0], [0.18, 0.0, 0.0]],
                          sensors=(co.Sensor(1, "+z"), co.Sensor(2, "+z")))
    mp = co.map_sensors(geo, m, method="shape")
    assert mp.report["method"].eq("nearest").all()
    assert mp.report["fe_node"].tolist() == [7, 13]
    assert np.isnan(mp.report["surface_distance_m"]).all()


def test_expansion_and_pretest_errors(setup):
    model, modal, geo, mp, fe = setup
    with pytest.raises(ParameterError, match="mapping must be a DofMapping"):
        co.expand_serep(fe, model, modal, np.eye(3))
    with pytest.raises(ParameterError, match="smoothing must be a finite number >= 0"):
        co.expand_lsq(fe, model, modal, mp, smoothing=-1.0)
    with pytest.raises(ParameterError, match=r"candidate nodes \[99999\] are not FE node"):
        co.candidate_geometry(model, nodes=[99999])
    cand = co.candidate_geometry(model, nodes=[100, 101])
    with pytest.raises(ParameterError, match="candidates must be a TestGeometry"):
        co.effective_independence(model, modal, "grid", 4)
    with pytest.raises(ParameterError, match="must be a positive integer, got 0"):
        co.kinetic_energy_placement(model, modal, cand, 0)
    with pytest.raises(ParameterError, match="linearly dependent on the candidate DOFs"):
        mid = co.fe_node_ids(model)[np.isclose(model.nodes[:, 1], 0.1)
                                    & (model.nodes[:, 0] > 0)]
        # the torsion mode (2) vanishes on the mid-line of the symmetric plate
        co.effective_independence(model, modal, co.candidate_geometry(model, nodes=mid), 3,
                                  modes=[1, 2])


def test_triaxial_efi_removes_whole_nodes(setup):
    model, modal, *_ = setup
    cand = co.candidate_geometry(model, directions=("+x", "+y", "+z"), node_set="x1")
    pl = co.effective_independence(model, modal, cand, 9, modes=[1, 2, 3], triaxial=True)
    nodes = [int(d.split("+")[0]) for d in pl.dof]
    assert len(pl.dof) == 9 and all(nodes.count(n) == 3 for n in set(nodes))


def test_geometry_uff_errors(tmp_path):
    pyuff = pytest.importorskip("pyuff")
    p = tmp_path / "cycle.uff"
    u = pyuff.UFF(str(p))
    u.write_sets(pyuff.prepare_18(cs_num=[1, 2], cs_type=[1, 0], ref_cs_num=[2, 1],
                                  cs_name=["a", "b"], ref_o=np.zeros((2, 3)),
                                  x_point=np.array([[1.0, 0, 0]] * 2),
                                  xz_point=np.array([[1.0, 0, 1]] * 2)), "add")
    u.write_sets(pyuff.prepare_15(node_nums=[1], def_cs=[0], disp_cs=[1], color=[1],
                                  x=[0.0], y=[0.0], z=[0.0]), "add")
    with pytest.raises(FormatError, match=r"cycle.uff: coordinate systems \[1, 2\] refer to "
                                          "each other in a cycle"):
        co.read_test_geometry(p)
    q = tmp_path / "undef.uff"
    u = pyuff.UFF(str(q))
    u.write_sets(pyuff.prepare_15(node_nums=[1], def_cs=[3], disp_cs=[0], color=[1],
                                  x=[0.0], y=[0.0], z=[0.0]), "add")
    with pytest.raises(FormatError, match=r"coordinate system 3 is used but not defined"):
        co.read_test_geometry(q)
