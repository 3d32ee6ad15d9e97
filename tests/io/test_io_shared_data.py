"""The external corpus in ../shared/data: values checked in PROVENANCE.md, and round trips."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import xarray as xr

import mvtk.io as mio
from mvtk.errors import DataRepairWarning, FormatError

pytestmark = pytest.mark.shared_data

MAT_OPTS = dict(
    data=["Time_chan_1", "Time_chan_2"],
    time="Time_domain",
    fs="Time_Sample_Rate",
    units=["N", "m/s^2"],
    frequency="Freq_domain",
    spectra={"frf": "Hf_chan_2", "coherence": "Hf_coh_chan_2"},
)


def _read(path, **options):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DataRepairWarning)
        return mio.read(path, **options)


def test_uff_mpstd_four_channels(shared_data):
    ds = mio.read(shared_data / "uff" / "MPSTD_Set001_2024_10_08_10_27_07.uff")
    th = ds["time_history"]
    assert th.shape == (4, 222400)
    assert th.attrs["fs"] == 3200.0
    np.testing.assert_allclose(np.diff(th.time.values[:3]), 3.125e-4, rtol=1e-12)
    sums = th.sum("time").values
    np.testing.assert_allclose(
        sums,
        [16068.767305360794, -70573.08901242912, -16626.510861555733, 28644.6128317588],
        rtol=1e-12,
    )
    assert list(th.node.values) == [1, 2, 3, 1]
    assert list(th.direction.values) == ["z"] * 4
    assert set(th.units.values) == {"m/s^2"} and set(th.quantity.values) == {"acceleration"}
    assert list(th.record.values) == [1, 2, 3, 4]


@pytest.mark.parametrize(
    ("name", "total", "n", "dt", "units"),
    [
        ("Sample_UFF58_ascii.uff", 5.715039728042096, 79292, 1.52588e-5, "Pa"),
        ("Sample_UFF58b_bin.uff", 5.715040058740556, 79292, 1.52588e-5, "Pa"),
        ("binary8byte.uff", 6.313748425276373, 250, 0.01, "g"),
        ("time-history-not-all-columns-filled.uff", -47.70822999999999, 13, 5e-5, "m/s^2"),
    ],
)
def test_uff_single_time_records(shared_data, name, total, n, dt, units):
    th = mio.read(shared_data / "uff" / name)["time_history"]
    assert th.shape == (1, n)
    assert float(th.sum()) == pytest.approx(total, rel=1e-12)
    assert th.attrs["fs"] == pytest.approx(1 / dt, rel=1e-9)
    assert th.units.item() == units


def test_uff_psd_record_with_non_utf8_units(shared_data):
    path = shared_data / "uff" / "sample_dataset58_psd.uff"
    with pytest.warns(DataRepairWarning, match=r"record 1: units .* not valid UTF-8"):
        ds = mio.read(path)
    psd = ds["psd"]
    assert psd.dims == ("channel", "frequency") and psd.shape == (1, 3201)
    assert float(psd.sum()) == pytest.approx(0.31306925539025443, rel=1e-12)
    np.testing.assert_array_equal(psd.frequency.values, np.arange(3201.0))


def test_uff_truncated_record_refused_then_read_on_request(shared_data):
    path = shared_data / "uff" / "dataset_milestone_in_header.uff"
    with pytest.raises(
        FormatError, match=r"record 1: header declares 2508876 points but the record holds 42"
    ):
        mio.read(path)
    with pytest.warns(DataRepairWarning, match="read the 42 points present"):
        ds = mio.read(path, allow_truncated=True)
    th = ds["time_history"]
    assert th.shape == (1, 42)
    assert th.attrs["t0_s"] == pytest.approx(1.11858e-05)
    assert th.quantity.item() == "pressure"


def test_uff_complex_frf_non_ascii_header(shared_data):
    ds = _read(shared_data / "uff" / "non_ascii_header.uff")
    frf = ds["frf"]
    assert frf.dims == ("response", "reference", "frequency") and frf.shape == (1, 1, 6)
    assert np.iscomplexobj(frf.values)
    np.testing.assert_allclose(frf.frequency.values, np.arange(6) * 0.195313)


def test_uff55_modes(shared_data):
    ds = mio.read(shared_data / "uff" / "uff55_translation.uff")
    np.testing.assert_allclose(ds["mode_shape"].fn_hz.values, [10.0, 12.0, 13.0])
    assert ds["mode_shape"].shape == (3, 4, 3)
    ds = mio.read(shared_data / "uff" / "uff55_translation_rotation.uff")
    ms = ds["mode_shape"]
    assert ms.shape == (1, 43, 6) and ms.fn_hz.item() == pytest.approx(97.013)
    assert list(ms.component.values) == ["ux", "uy", "uz", "rx", "ry", "rz"]
    ds = mio.read(shared_data / "uff" / "uff55_sample_test_record10.uff")
    ms = ds["mode_shape"]
    assert ms.eigenvalue.item() == pytest.approx(-0.1111111 + 41.11111j)
    assert ms.fn_hz.item() == pytest.approx(abs(-0.1111111 + 41.11111j) / (2 * np.pi))
    assert ms.damping_ratio.item() == pytest.approx(0.1111111 / abs(-0.1111111 + 41.11111j))


@pytest.mark.parametrize("k", [1, 2, 3])
def test_meas_point_text_frfs(shared_data, k):
    path = shared_data / "uff" / f"meas_point_{k}.txt"
    with pytest.raises(FormatError, match="pass|expected df_hz"):
        mio.read(path)
    spec = mio.read(path, df_hz=1.0)["spectrum"]
    assert spec.shape == (1, 1001) and spec.frequency.values[-1] == 1000.0
    mag = np.abs(spec.values[0])
    # first free-free bending peak near 52 Hz (PROVENANCE.md)
    assert 45 <= int(np.argmax(mag[20:100])) + 20 <= 60


def test_mat_case_files(shared_data):
    ds = mio.read(shared_data / "mat" / "case1.mat", **MAT_OPTS)
    th = ds["time_history"]
    assert th.shape == (2, 4096) and th.attrs["fs"] == 1280.0
    frf = ds["frf"]
    assert frf.dims == ("response", "reference", "frequency")  # docs/conventions.md
    assert frf.shape == (1, 1, 1601)
    assert ds["coherence"].dims == frf.dims  # shares the FRF axes (no response_2)
    np.testing.assert_allclose(np.diff(frf.frequency.values[:3]), 0.3125)
    f = frf.frequency.values
    band = (f > 150) & (f < 250)
    assert f[band][np.argmax(np.abs(frf.values[0, 0, band]))] == pytest.approx(212.2, abs=1.0)
    ds2 = mio.read(shared_data / "mat" / "case2.mat", **MAT_OPTS)
    f2 = ds2["frf"].frequency.values
    band = (f2 > 150) & (f2 < 250)
    peak = f2[band][np.argmax(np.abs(ds2["frf"].values[0, 0, band]))]
    assert peak == pytest.approx(192.5, abs=1.0)


def test_mat_case_frf_only_and_channels_named(shared_data):
    """Issue 14: FRF without time histories; spectra on 'channel', never 'channel_2'."""
    path = shared_data / "mat" / "case1.mat"
    ds = mio.read(
        path,
        frequency="Freq_domain",
        spectra={"frf": "Hf_chan_2", "coherence": "Hf_coh_chan_2"},
        spectrum_units={"frf": "m/s^2/N"},
    )
    frf = ds["frf"]
    assert frf.shape == (1, 1, 1601) and "time_history" not in ds
    assert frf.attrs["frf_type"] == "accelerance"
    assert list(frf.units.values) == ["m/s^2"] and list(frf.reference_units.values) == ["N"]
    assert frf.frequency.values[1] == 0.3125 and frf.frequency.size == 1601
    both = mio.read(
        path,
        **MAT_OPTS | {"spectra": {"frf": "Hf_chan_2", "psd": ["PSD_chan_1", "PSD_chan_2"]}},
        response="Time_chan_2",
        reference="Time_chan_1",
    )
    assert both["psd"].dims == ("channel", "frequency")
    assert not any(str(d).endswith("_2") for d in both.dims)
    assert list(both["frf"].response_quantity.values) == ["acceleration"]
    assert list(both["frf"].reference_quantity.values) == ["force"]
    assert both["frf"].attrs["frf_type"] == "accelerance"


def test_mat_without_data_option_names_variables(shared_data):
    with pytest.raises(FormatError, match=r"case1.mat: which variables .* Time_chan_1"):
        mio.read(shared_data / "mat" / "case1.mat")
    with pytest.raises(FormatError, match="stores no units"):
        mio.read(shared_data / "mat" / "case1.mat", data="Time_chan_1", fs=1280.0)


def test_mat_frf_data1(shared_data):
    th = mio.read(shared_data / "mat" / "frf_data1.mat", data="x", dt="dt", units="m")[
        "time_history"
    ]
    assert th.shape == (1, 1024) and th.attrs["fs"] == 10.0
    assert th.time.values[1] == 0.1


def test_hdf5_view0(shared_data):
    path = shared_data / "hdf5" / "view_0.hdf5"
    with pytest.raises(
        FormatError, match=r"stores no units for channels \['force', 'acc', 'trigger'\]"
    ):
        mio.read(path)
    th = mio.read(path, units=["N", "m/s^2", "V"])["time_history"]
    assert list(th.channel.values) == ["force", "acc", "trigger"]
    assert th.shape == (3, 51200) and th.attrs["fs"] == 25600.0
    assert list(th.quantity.values) == ["force", "acceleration", "voltage"]
    assert th.time.values[-1] == pytest.approx(2.0 - 1 / 25600)


def test_tdms_good_file(shared_data):
    pytest.importorskip("nptdms")
    th = mio.read(shared_data / "tdms" / "good_tdms_1.tdms")["time_history"]
    assert th.shape == (8, 18000) and th.dtype == np.float32
    assert th.attrs["fs"] == 30.0
    assert float(th.values.astype(np.float64).sum()) == pytest.approx(-15.5978486, rel=1e-7)
    assert set(th.units.values) == {"g"}
    assert th.attrs["start_time"].startswith("2020-04-09T22:00:00")


def test_tdms_faulty_file_refused(shared_data):
    pytest.importorskip("nptdms")
    with pytest.raises(FormatError, match=r"faulty_tdms_01.tdms: not a readable TDMS file"):
        mio.read(shared_data / "tdms" / "faulty_tdms_01.tdms")


ROUND_TRIP = [
    ("uff/MPSTD_Set001_2024_10_08_10_27_07.uff", {}),
    ("uff/Sample_UFF58_ascii.uff", {}),
    ("uff/binary8byte.uff", {}),
    ("uff/sample_dataset58_psd.uff", {}),
    ("uff/non_ascii_header.uff", {}),
    ("uff/uff55_translation.uff", {}),
    ("uff/uff55_sample_test_record10.uff", {}),
    ("uff/dataset_milestone_in_header.uff", {"allow_truncated": True}),
    ("uff/meas_point_1.txt", {"df_hz": 1.0}),
    ("mat/case1.mat", MAT_OPTS),
    ("hdf5/view_0.hdf5", {"units": ["N", "m/s^2", "V"]}),
    ("tdms/good_tdms_1.tdms", {}),
]


_PROVENANCE = ("source", "format", "original_source", "original_format")


def _without_provenance(ds: xr.Dataset) -> xr.Dataset:
    out = ds.copy()
    for obj in [out, *out.data_vars.values()]:
        obj.attrs = {k: v for k, v in obj.attrs.items() if k not in _PROVENANCE}
    return out


@pytest.mark.parametrize(("rel", "options"), ROUND_TRIP, ids=[r for r, _ in ROUND_TRIP])
def test_round_trip_netcdf_identical(shared_data, tmp_path, rel, options):
    first = _read(shared_data / rel, **options)
    out = mio.write(first, tmp_path / "copy.nc")
    second = mio.read(out)
    assert second.attrs["format"] == "netcdf"  # issue 14: not "hdf5"
    assert second.attrs["original_source"] == str(shared_data / rel)
    xr.testing.assert_identical(_without_provenance(first), _without_provenance(second))
    for name in first.variables:
        assert first[name].dtype == second[name].dtype, name


def test_mat_frf_feeds_half_power(shared_data):
    """Issue 14 symptom: half_power rejected the MAT reader's output (dim 'channel_2')."""
    import mvtk.damping as md

    ds = mio.read(shared_data / "mat" / "case1.mat", **MAT_OPTS)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = md.half_power(ds["frf"], fn_hz=[212.1])
    assert res.fn_hz[0] == pytest.approx(212.09, abs=0.3)  # source project's fit: 212.0925
