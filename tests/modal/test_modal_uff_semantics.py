"""UFF 58 semantics: one file per reference merges by reference node/direction; the
numerator/denominator data types and units decide the FRF type; an FRF matrix
round-trips through mvtk.io.write/read. Truth: exact FRFs of a 4-DOF chain
(mvtk.modal.exact_frf, state-space modes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import pyuff

from mvtk import io, modal
from mvtk.cli.modal import load_frf
from mvtk.errors import DataRepairWarning


def _chain(n=4, m=1.0, k=1e5):
    M = np.eye(n) * m
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] = 2 * k if i < n - 1 else k
        if i:
            K[i, i - 1] = K[i - 1, i] = -k
    return M, 0.5 * M + 1e-5 * K, K


def _uff_set(h, o, i, f, num_type, num_units, den_type, den_units):
    return dict(type=58, binary=0, func_type=4, ver_num=0, load_case_id=0, id1="FRF",
                id2="NONE", id3="NONE", id4="NONE", id5="NONE", rsp_ent_name="NONE",
                rsp_node=o + 1, rsp_dir=3, ref_ent_name="NONE", ref_node=i + 1, ref_dir=3,
                ord_data_type=6, num_pts=f.size, abscissa_spacing=1,
                abscissa_min=float(f[0]), abscissa_inc=float(f[1] - f[0]), z_axis_value=0.0,
                abscissa_spec_data_type=18, abscissa_len_unit_exp=0,
                abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0,
                abscissa_axis_units_lab="Hz", ordinate_spec_data_type=num_type,
                ordinate_len_unit_exp=0, ordinate_force_unit_exp=0, ordinate_temp_unit_exp=0,
                ordinate_axis_units_lab=num_units, orddenom_spec_data_type=den_type,
                orddenom_len_unit_exp=0, orddenom_force_unit_exp=0, orddenom_temp_unit_exp=0,
                orddenom_axis_units_lab=den_units, z_axis_spec_data_type=0,
                z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
                z_axis_axis_units_lab="NONE", data=h[o, i].astype(complex), x=f)


def _write(path, h, refs, f, **kw):
    sets = [_uff_set(h, o, i, f, **kw) for i in refs for o in range(h.shape[0])]
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path


@pytest.fixture()
def chain_frf():
    M, C, K = _chain()
    f = np.arange(1, 801) * 0.1
    h = modal.exact_frf(M, C, K, f, [0, 1, 2, 3], [0, 1, 3], frf_type="accelerance")
    return h, f


def test_three_per_reference_files_equal_one_file(tmp_path, chain_frf):
    h, f = chain_frf
    kw = dict(num_type=12, num_units="m/s^2", den_type=13, den_units="N")
    one = _write(tmp_path / "all.uff", h.values, [0, 1, 2], f, **kw)
    # the references' nodes are 1, 2, 4: one file each
    per = [_write(tmp_path / f"ref{k}.uff", h.values[:, [k]], [0], f, **kw) for k in range(3)]
    for k, p in enumerate(per):  # ref node of file k is the k-th reference's node
        sets = pyuff.UFF(str(p)).read_sets()
        sets = sets if isinstance(sets, list) else [sets]
        for s in sets:
            s["ref_node"] = int(h["reference_node"].values[k])
        p.unlink()
        pyuff.UFF(str(p)).write_sets(sets, mode="add")
    a = load_frf([one])
    b = load_frf(per)
    assert a.attrs["frf_type"] == b.attrs["frf_type"] == "accelerance"
    assert b["reference_node"].values.tolist() == [1, 2, 4]
    assert a["reference_node"].values.tolist() == [1, 2, 3]  # written as in the file
    np.testing.assert_allclose(b.values, h.values, rtol=1e-6)  # UFF ASCII: 7 digits
    ra = modal.identify(a, 1.0, 80.0)
    rb = modal.identify(b, 1.0, 80.0)
    np.testing.assert_allclose(ra.fn_hz, rb.fn_hz, rtol=1e-6)
    np.testing.assert_allclose(ra.zeta, rb.zeta, rtol=1e-4)


@pytest.mark.parametrize("num_type, num_units, den_type, den_units, kind", [
    (12, "m/s^2", 13, "N", "accelerance"),   # data types say it
    (0, "g", 0, "N", "accelerance"),         # only the unit labels say it
    (11, "m/s", 13, "N", "mobility"),
    (8, "m", 9, "N", "receptance"),
])
def test_uff58_types_and_units_decide_the_frf_type(tmp_path, chain_frf, num_type, num_units,
                                                    den_type, den_units, kind):
    h, f = chain_frf
    p = _write(tmp_path / "x.uff", h.values[:2], [0], f, num_type=num_type,
               num_units=num_units, den_type=den_type, den_units=den_units)
    m = modal.as_frf_matrix(io.read(p))
    assert m.attrs["frf_type"] == kind
    assert m["reference_node"].values.tolist() == [1]


def test_frf_matrix_round_trips_through_io_write(tmp_path, chain_frf):
    h, _ = chain_frf
    io.write(h, tmp_path / "h.nc")
    ds = io.read(tmp_path / "h.nc")
    assert "frf" in ds.data_vars and "time_history" not in ds.data_vars
    back = modal.as_frf_matrix(ds)
    assert back.attrs["frf_type"] == "accelerance"
    np.testing.assert_array_equal(back.values, h.values)
    assert back["reference_node"].values.tolist() == [1, 2, 4]


def test_real_uff58_with_a_latin1_unit_label_is_accelerance():
    # pyuff's test file labels its FRF "(1/N)*(m/s" + byte 0xB2 + ")": m/s^2 per N in
    # Latin-1; data types 1 (general) over 0 (unknown) say nothing
    shared = Path(__file__).resolve().parents[3] / "shared" / "data" / "uff"
    p = shared / "non_ascii_header.uff"
    if not p.is_file():
        pytest.skip(f"external measurement corpus not found at {shared}")
    with pytest.warns(DataRepairWarning, match="not valid UTF-8"):
        ds = io.read(p)
    assert modal.as_frf_matrix(ds).attrs["frf_type"] == "accelerance"
