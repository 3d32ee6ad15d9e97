# ruff: noqa: UP031  (UFF records are fixed-width Fortran formats; %-formats mirror the spec)
"""UFF 58/58b, MAT v5/v7.3, HDF5, netCDF, TDMS and WAV written here with peer libraries."""

from __future__ import annotations

import struct

import h5py
import numpy as np
import pytest
import scipy.io
import scipy.io.wavfile
import xarray as xr

import mvtk.io as mio
from mvtk.errors import (
    DataRepairWarning,
    FormatError,
    MissingDependencyError,
    MvtkWarning,
    ParameterError,
)

# ---------------------------------------------------------------- UFF


def _uff58_header(name, n, dt, units="m/s2", func=1, node=5, direction=3, ord_type=2, binary=None):
    """The 11 header lines (after '-1' and the dataset number line) of a UFF 58 record."""
    lines = [name, "NONE", "01-Jan-26 00:00:00", "NONE", "NONE"]
    lines.append(
        "%5i%10i%5i%10i %10s%10i%4i %10s%10i%4i"
        % (func, 0, 0, 0, name[:10], node, direction, "NONE", 0, 0)
    )
    lines.append("%10i%10i%10i%13.5e%13.5e%13.5e" % (ord_type, n, 1, 0.0, dt, 0.0))
    x_type = 17 if func == 1 else 18
    lines.append(
        "%10i%5i%5i%5i %-20s %-20s" % (x_type, 0, 0, 0, "Time", "s" if func == 1 else "Hz")
    )
    lines.append("%10i%5i%5i%5i %-20s %-20s" % (12, 0, 0, 0, "Acceleration", units))
    lines.append("%10i%5i%5i%5i %-20s %-20s" % (0, 0, 0, 0, "NONE", "NONE"))
    lines.append("%10i%5i%5i%5i %-20s %-20s" % (0, 0, 0, 0, "NONE", "NONE"))
    return lines


def uff58_ascii(values, dt, **kw):
    lines = ["    -1", "    58", *_uff58_header(n=len(values), dt=dt, ord_type=4, **kw)]
    for k in range(0, len(values), 4):
        lines.append("".join("%20.11e" % v for v in values[k : k + 4]))
    lines.append("    -1")
    return ("\n".join(lines) + "\n").encode()


def uff58_binary(values, dt, *, double=True, big_endian=False, **kw):
    fmt = (">" if big_endian else "<") + ("d" if double else "f") * len(values)
    payload = struct.pack(fmt, *values)
    head = _uff58_header(n=len(values), dt=dt, ord_type=4 if double else 2, **kw)
    desc = "    58b%6i%6i%12i%12i%6i%6i%12i%12i" % (
        2 if big_endian else 1,
        2,
        11,
        len(payload),
        0,
        0,
        0,
        0,
    )
    text = "\n".join(["    -1", desc, *head]) + "\n"
    return text.encode() + payload + b"\n    -1\n"


@pytest.mark.parametrize("kind", ["ascii", "bin-f64-le", "bin-f64-be", "bin-f32-le", "bin-f32-be"])
def test_uff58_variants(tmp_path, rng, kind):
    values = rng.standard_normal(37)
    if kind == "ascii":
        raw = uff58_ascii(values, 1e-3, name="acc A")
    else:
        raw = uff58_binary(
            values, 1e-3, name="acc A", double="f64" in kind, big_endian=kind.endswith("be")
        )
    path = tmp_path / "r.uff"
    path.write_bytes(raw)
    th = mio.read(path)["time_history"]
    expected = values if "f32" not in kind else values.astype(np.float32).astype(np.float64)
    np.testing.assert_allclose(th.values[0], expected, rtol=1e-10 if kind == "ascii" else 0)
    assert th.attrs["fs"] == 1000.0 and th.units.item() == "m/s^2"
    assert th.node.item() == 5 and th.direction.item() == "z"


def test_uff58_two_grids_and_duplicate_names(tmp_path, rng):
    a, b, c = rng.standard_normal(8), rng.standard_normal(8), rng.standard_normal(16)
    raw = (
        uff58_ascii(a, 1e-3, name="acc")
        + uff58_ascii(b, 1e-3, name="acc")
        + uff58_ascii(c, 5e-4, name="force", units="N")
    )
    path = tmp_path / "m.uff"
    path.write_bytes(raw)
    with pytest.warns(DataRepairWarning, match=r"channel names \['acc'\] occur in several records"):
        ds = mio.read(path)
    assert list(ds["time_history"].channel.values) == ["acc #1", "acc #2"]
    assert ds["time_history_2"].dims == ("channel_2", "time_2")
    assert ds["time_history_2"].attrs["fs"] == 2000.0
    assert list(ds["units_2"].values) == ["N"]


def test_uff58_frf_grid(tmp_path, rng):
    recs = b""
    h = rng.standard_normal((2, 5)) + 1j * rng.standard_normal((2, 5))
    for k in range(2):
        lines = ["    -1", "    58"]
        head = _uff58_header(name=f"H{k}", n=5, dt=0.5, func=4, node=k + 1, ord_type=6)
        head[5] = "%5i%10i%5i%10i %10s%10i%4i %10s%10i%4i" % (
            4,
            0,
            0,
            0,
            "NONE",
            k + 1,
            3,
            "NONE",
            9,
            -3,
        )
        lines += head
        inter = np.column_stack([h[k].real, h[k].imag]).ravel()
        for j in range(0, inter.size, 4):
            lines.append("".join("%20.11e" % v for v in inter[j : j + 4]))
        lines.append("    -1")
        recs += ("\n".join(lines) + "\n").encode()
    path = tmp_path / "frf.uff"
    path.write_bytes(recs)
    frf = mio.read(path)["frf"]
    assert frf.dims == ("response", "reference", "frequency")
    assert list(frf.response.values) == ["1:z", "2:z"] and list(frf.reference.values) == ["9:-z"]
    np.testing.assert_allclose(frf.values[:, 0, :], h, rtol=1e-10)
    np.testing.assert_allclose(frf.frequency.values, np.arange(5) * 0.5)


def test_uff_truncated_binary_and_unterminated(tmp_path, rng):
    raw = uff58_binary(rng.standard_normal(40), 1e-3, name="a")
    cut = raw[: len(raw) - 100] + b"\n    -1\n"
    path = tmp_path / "cut.uff"
    path.write_bytes(cut)
    with pytest.raises(
        FormatError, match=r"record 1: header declares 40 points but the record holds"
    ):
        mio.read(path)
    path.write_bytes(uff58_ascii(rng.standard_normal(8), 1e-3, name="a") + b"    -1\n    58\nabc\n")
    with pytest.raises(FormatError, match=r"record 2: data after the last complete dataset"):
        mio.read(path)


def test_uff_missing_units_and_unsupported_function(tmp_path, rng):
    path = tmp_path / "u.uff"
    path.write_bytes(uff58_ascii(rng.standard_normal(8), 1e-3, name="a", units="NONE"))
    with pytest.raises(FormatError, match=r"u.uff, record 1: no ordinate units"):
        mio.read(path)
    path.write_bytes(uff58_ascii(rng.standard_normal(8), 1e-3, name="a", func=7))
    with pytest.raises(FormatError, match=r"record 1: UFF 58 function type 7; expected one of"):
        mio.read(path)


# ---------------------------------------------------------------- MAT, HDF5


def test_mat_v5_matrix_and_columns(tmp_path, rng):
    x = rng.standard_normal((100, 2))
    path = tmp_path / "a.mat"
    scipy.io.savemat(path, {"y": x, "fs": 512.0, "t": np.arange(100) / 512.0})
    th = mio.read(path, data="y", fs="fs", units=["m/s^2", "N"])["time_history"]
    np.testing.assert_array_equal(th.values, x.T)
    assert list(th.channel.values) == ["y[0]", "y[1]"] and th.attrs["fs"] == 512.0
    th = mio.read(path, data="y", time="t", channels=["a", "f"], units="V")["time_history"]
    assert list(th.channel.values) == ["a", "f"] and th.attrs["fs"] == 512.0
    with pytest.raises(FormatError, match=r"a.mat: no variable 'z'; the file holds: "):
        mio.read(path, data="z", fs=1.0, units="V")
    with pytest.raises(FormatError, match=r"no sampling rate; expected time="):
        mio.read(path, data="y", units="V")


def _write_mat73(path, arrays):
    with h5py.File(path, "w", userblock_size=512) as fh:
        for k, v in arrays.items():
            fh[k] = np.asarray(v).T
    header = (
        b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Sun Nov 22 2026 HDF5 schema 1.00 ."
    )
    with open(path, "r+b") as fh:
        fh.write(header.ljust(116) + b"\x00" * 8 + b"\x00\x02IM")


def test_mat_v73(tmp_path, rng):
    x = rng.standard_normal((3, 64))
    path = tmp_path / "b.mat"
    _write_mat73(path, {"data": x, "dt": np.array([[1e-3]])})
    assert mio.detect_format(path) == "mat"
    th = mio.read(path, data="data", dt="dt", units="V")["time_history"]
    np.testing.assert_array_equal(th.values, x)
    assert th.attrs["fs"] == 1000.0


def test_hdf5_generic_with_paths(tmp_path, rng):
    x = rng.standard_normal((50, 2))
    path = tmp_path / "c.h5"
    with h5py.File(path, "w") as fh:
        fh["meas/samples"] = x
        fh["meas/rate"] = 200
        fh["meas/samples"].attrs["units"] = ["g", "N"]
    th = mio.read(path, data="meas/samples", fs="meas/rate", channels=["a", "f"])["time_history"]
    assert list(th.units.values) == ["g", "N"]
    np.testing.assert_array_equal(th.values, x.T)
    with pytest.raises(FormatError, match=r"c.h5: cannot tell which dataset holds the samples"):
        mio.read(path)


def test_netcdf_dataarray_write_and_bad_write(tmp_path, rng):
    da = mio.time_history(rng.standard_normal((2, 10)), 100.0, ["a", "b"], ["m/s^2", "N"])
    path = mio.write(da, tmp_path / "x.nc")
    assert mio.detect_format(path) == "netcdf"  # issue 14: own output is netCDF, not hdf5
    back = mio.read(path)["time_history"]
    np.testing.assert_array_equal(back.values, da.values)
    assert back.attrs["format"] == "netcdf"
    assert "original_source" not in back.attrs  # a DataArray from memory had no source
    h5 = tmp_path / "same.h5"  # the same netCDF4 bytes under an HDF5 name: the hdf5 reader
    h5.write_bytes(path.read_bytes())
    assert mio.detect_format(h5) == "hdf5"
    np.testing.assert_array_equal(mio.read(h5)["time_history"].values, da.values)
    with pytest.raises(ParameterError, match="expected an xarray.Dataset or DataArray, got list"):
        mio.write([1, 2], tmp_path / "y.nc")
    bad = da.copy()
    bad["units"] = ("channel", ["", "N"])
    with pytest.raises(FormatError, match="channel 'a' has no units"):
        mio.write(bad, tmp_path / "z.nc")


def test_netcdf_corrupted(tmp_path, rng):
    da = mio.time_history(rng.standard_normal((2, 10)), 100.0, ["a", "b"], "V")
    path = mio.write(da, tmp_path / "x.nc")
    raw = path.read_bytes()
    path.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(FormatError, match=r"x.nc"):
        mio.read(path)


# ---------------------------------------------------------------- TDMS, WAV


def test_tdms_written_with_nptdms(tmp_path, rng):
    nptdms = pytest.importorskip("nptdms")
    x = rng.standard_normal((2, 300)).astype(np.float32)
    path = tmp_path / "d.tdms"
    with nptdms.TdmsWriter(path) as writer:
        chans = [
            nptdms.ChannelObject(
                "g", f"c{k}", x[k], properties={"wf_increment": 0.01, "unit_string": "V"}
            )
            for k in range(2)
        ]
        writer.write_segment(chans)
    th = mio.read(path)["time_history"]
    assert list(th.channel.values) == ["g/c0", "g/c1"] and th.attrs["fs"] == 100.0
    np.testing.assert_array_equal(th.values, x)
    raw = path.read_bytes()
    path.write_bytes(raw[:-200])
    with pytest.raises(FormatError, match=r"d.tdms: npTDMS reports a damaged file: Last segment"):
        mio.read(path)


def test_tdms_missing_dependency(tmp_path, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def fake_import(name, *args, **kwargs):
        if name == "nptdms":
            raise ImportError("No module named 'nptdms'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake_import)
    path = tmp_path / "e.tdms"
    path.write_bytes(b"TDSm" + bytes(40))
    with pytest.raises(MissingDependencyError, match=r"pip install 'mvtk\[tdms\]'"):
        mio.read(path)


def test_wav_calibration(tmp_path, rng):
    counts = rng.integers(-30000, 30000, size=(400, 2), dtype=np.int16)
    path = tmp_path / "f.wav"
    scipy.io.wavfile.write(path, 8000, counts)
    raw = mio.read(path)["time_history"]
    assert list(raw.units.values) == ["counts", "counts"]
    assert list(raw.quantity.values) == ["other", "other"]
    cal = mio.read(path, calibration=[1e-3, 2e-3], units="Pa")["time_history"]
    np.testing.assert_allclose(cal.values, counts.T * np.array([[1e-3], [2e-3]]))
    assert cal.attrs["fs"] == 8000.0 and list(cal.quantity.values) == ["pressure"] * 2
    with pytest.raises(ParameterError, match="calibration given without units="):
        mio.read(path, calibration=1.0)
    with pytest.raises(ParameterError, match=r"calibration \[1.0, 2.0, 3.0\]; expected one"):
        mio.read(path, calibration=[1.0, 2.0, 3.0], units="Pa")
    path.write_bytes(path.read_bytes()[:30])
    with pytest.raises(FormatError, match=r"f.wav"):
        mio.read(path)


# ---------------------------------------------------------------- registry


def test_register_reader_and_entry_point_style_attributes(tmp_path, monkeypatch):
    from mvtk.io import _registry

    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))

    def read_xyz(path, *, gain=1.0):
        values = np.frombuffer(path.read_bytes()[4:], dtype="<f8") * gain
        return xr.Dataset({"time_history": mio.time_history(values, 10.0, ["x"], "V")})

    mio.register_reader("xyz", read_xyz, extensions=[".xyz"], sniff=lambda h: h[:4] == b"XYZ0")
    path = tmp_path / "a.dat"
    path.write_bytes(b"XYZ0" + np.arange(4.0).tobytes())
    assert mio.detect_format(path) == "xyz"
    ds = mio.read(path, gain=2.0)
    np.testing.assert_array_equal(ds["time_history"].values[0], [0, 2, 4, 6])
    assert "xyz" in mio.list_formats()
    with pytest.raises(ParameterError, match="format 'xyz' is already registered"):
        mio.register_reader("xyz", read_xyz)
    with pytest.raises(ParameterError, match="reader for 'abc' is not callable"):
        mio.register_reader("abc", 3)


def test_entry_point_plugin_loaded(monkeypatch):
    from mvtk.io import _registry

    def plugin(path):  # pragma: no cover - only registered
        raise AssertionError

    plugin.extensions = (".plg",)

    class FakeEP:
        name, value = "plg", "pkg:plugin"

        def load(self):
            return plugin

    class BrokenEP:
        name, value = "broken", "pkg:missing"

        def load(self):
            raise ImportError("no module pkg")

    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    monkeypatch.setattr(_registry, "_ENTRY_POINTS_LOADED", False)
    monkeypatch.setattr(_registry, "entry_points", lambda group: [FakeEP(), BrokenEP()])
    with pytest.warns(
        MvtkWarning, match=r"entry point 'broken' \(pkg:missing\) could not be loaded"
    ):
        names = mio.list_formats()
    assert "plg" in names and "broken" not in names
    assert _registry._REGISTRY["plg"].extensions == (".plg",)


def test_reader_returning_bad_object(tmp_path, monkeypatch):
    from mvtk.io import _registry

    monkeypatch.setattr(_registry, "_REGISTRY", dict(_registry._REGISTRY))
    mio.register_reader("bad", lambda path: [1, 2, 3])
    path = tmp_path / "a.bad"
    path.write_bytes(b"x")
    with pytest.raises(
        FormatError, match=r"reader 'bad' returned list; expected an xarray.Dataset"
    ):
        mio.read(path, format="bad")


# ---------------------------------------------------------------- CLI


def test_cli_read_subcommand(tmp_path, capsys):
    import argparse

    from mvtk.cli.read import add_parser

    parser = argparse.ArgumentParser(prog="mvtk")
    add_parser(parser.add_subparsers(dest="command"))
    src = tmp_path / "a.csv"
    src.write_text("time [s],a [V],b [N]\n0,1,2\n0.5,2,3\n1,3,4\n")
    out = tmp_path / "a.nc"
    args = parser.parse_args(
        ["read", str(src), "--set", 'quantity=["other", "force"]', "-o", str(out)]
    )
    assert args.func(args) == 0
    text = capsys.readouterr().out
    assert "time_history (channel=2, time=3) float64  fs=2 Hz" in text
    assert "a: other [V]" in text and out.exists()
    args = parser.parse_args(["read", str(tmp_path / "missing.csv")])
    assert args.func(args) == 2
    assert "no such file" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        parser.parse_args(["read", str(src), "--set", "novalue"])
