"""LabVIEW Measurement (LVM) reader: the two real impact records and synthetic variants."""

from __future__ import annotations

import atexit
import shutil
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mvtk.io as mio
from mvtk.errors import DataRepairWarning, FormatError, MvtkError, ParameterError

# Checked values: ../shared/data/PROVENANCE.md, section "lvm/" (numpy on the parsed text).
RECORDS = {
    "acceleration.lvm": dict(
        sums=(-544.9039429631198, 14592.541468000001),
        peak_force=195.605522,
        peak_index=36,
        max_acc=35.457661,
        max_acc_index=80,
        time="10:18:21,109129399999515521",
    ),
    "camera.lvm": dict(
        sums=(-215.53455562967986, 24138.30709852329),
        peak_force=422.370802,
        peak_index=35,
        max_acc=54.791435,
        max_acc_index=None,
        time="12:48:23,5013039999998275277",
    ),
}


@pytest.mark.shared_data
@pytest.mark.parametrize("name", sorted(RECORDS))
def test_real_impact_records(shared_data, name):
    ref = RECORDS[name]
    path = shared_data / "lvm" / name
    assert mio.detect_format(path) == "lvm"
    ds = mio.read(path)
    th = ds["time_history"]
    assert ds.attrs["format"] == "lvm"
    assert th.shape == (2, 50030)
    assert th.attrs["fs"] == 50000.0
    assert list(th.channel.values) == ["Acceleration (Trigger)", "Force (Trigger)"]
    assert list(th.units.values) == ["g", "N"]  # "Newtons" spelled N; g kept as g
    assert list(th.quantity.values) == ["acceleration", "force"]
    np.testing.assert_allclose(th.sum("time").values, ref["sums"], rtol=1e-13)
    force = th.sel(channel="Force (Trigger)").values
    acc = th.sel(channel="Acceleration (Trigger)").values
    assert force.max() == pytest.approx(ref["peak_force"], rel=1e-12)
    assert int(np.argmax(force)) == ref["peak_index"]
    assert np.abs(acc).max() == pytest.approx(ref["max_acc"], rel=1e-12)
    if ref["max_acc_index"] is not None:
        assert int(np.argmax(np.abs(acc))) == ref["max_acc_index"]
    assert ds.attrs["operator"] == "Domen"
    assert ds.attrs["date"] == "2018/12/17"
    assert ds.attrs["time"] == ref["time"]
    assert ds.attrs["start_time"].startswith("2018-12-17T" + ref["time"][:8])
    assert ds.attrs["decimal_separator"] == ","
    assert th.attrs["segment"] == "1" and "t0_s" not in th.attrs


@pytest.mark.shared_data
def test_real_record_netcdf_round_trip(shared_data, tmp_path):
    src = shared_data / "lvm" / "acceleration.lvm"
    first = mio.read(src)
    second = mio.read(mio.write(first, tmp_path / "acc.nc"))
    assert second.attrs["format"] == "netcdf"
    assert second.attrs["source"] == str(tmp_path / "acc.nc")
    assert second.attrs["original_source"] == str(src)
    assert second.attrs["original_format"] == "lvm"
    drop = ("source", "format", "original_source", "original_format")
    for a, b in [(first, second), *zip(first.data_vars.values(), second.data_vars.values())]:
        a.attrs = {k: v for k, v in a.attrs.items() if k not in drop}
        b.attrs = {k: v for k, v in b.attrs.items() if k not in drop}
    xr.testing.assert_identical(first, second)


# --------------------------------------------------------------------------- synthetic

FILE_HEADER = """LabVIEW Measurement{s}
Writer_Version{s}2
Reader_Version{s}2
Separator{s}{sepname}
Decimal_Separator{s}{dec}
Multi_Headings{s}Yes
X_Columns{s}{xcols}
Time_Pref{s}Relative
Operator{s}tester
Date{s}2024/05/06
Time{s}07:08:09{dec}5
***End_of_Header***{s}
"""


def _fmt(v: float, dec: str) -> str:
    return f"{v:.9g}".replace(".", dec)


def _lvm(
    tmp_path: Path,
    data: np.ndarray,
    *,
    dt: float = 1e-3,
    x0: float = 0.0,
    xcols: str = "No",
    dec: str = ".",
    sep: str = "\t",
    units=("m/s^2", "N"),
    names=("acc", "force"),
    segments: int = 1,
    comment: str = "",
    name: str = "f.lvm",
) -> Path:
    sepname = {"\t": "Tab", ",": "Comma"}.get(sep, sep)
    s = sep
    text = FILE_HEADER.format(s=s, sepname=sepname, dec=dec, xcols=xcols) + s + "\n"
    n_ch = data.shape[0]
    parts = np.array_split(np.arange(data.shape[1]), segments)
    for idx in parts:
        seg_x0 = x0 + idx[0] * dt
        text += s.join(["Channels", str(n_ch)]) + s + "\n"
        text += s.join(["Samples"] + [str(idx.size)] * n_ch) + s + "\n"
        text += s.join(["Y_Unit_Label", *units]) + s + "\n"
        text += s.join(["X_Dimension"] + ["Time"] * n_ch) + s + "\n"
        text += s.join(["X0"] + [_fmt(seg_x0, dec)] * n_ch) + s + "\n"
        text += s.join(["Delta_X"] + [_fmt(dt, dec)] * n_ch) + s + "\n"
        text += "***End_of_Header***" + s + "\n"
        if xcols == "Multi":
            heads = [h for nm in names for h in ("X_Value", nm)]
        else:
            heads = ["X_Value", *names]
        text += s.join([*heads, "Comment"]) + "\n"
        for k in idx:
            t = _fmt(x0 + k * dt, dec)
            ys = [_fmt(v, dec) for v in data[:, k]]
            if xcols == "Multi":
                fields = [f for y in ys for f in (t, y)]
            elif xcols == "One":
                fields = [t, *ys]
            else:
                fields = ["", *ys]
            if comment and k == idx[0]:
                fields.append(comment)
            text += s.join(fields) + "\n"
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


@pytest.fixture
def signal(rng):
    return np.round(rng.normal(size=(2, 40)), 6)


@pytest.mark.parametrize(
    ("xcols", "dec", "sep"),
    [("No", ",", "\t"), ("One", ".", "\t"), ("Multi", ".", "\t"), ("One", ".", ",")],
)
def test_synthetic_variants(tmp_path, signal, xcols, dec, sep):
    path = _lvm(tmp_path, signal, xcols=xcols, dec=dec, sep=sep, comment="first hit")
    ds = mio.read(path)
    th = ds["time_history"]
    np.testing.assert_array_equal(th.values, signal)
    assert th.attrs["fs"] == 1000.0
    assert list(th.channel.values) == ["acc", "force"]
    assert list(th.quantity.values) == ["acceleration", "force"]
    assert ds.attrs["x_columns"] == xcols
    assert ds.attrs["start_time"] == "2024-05-06T07:08:09.500000"


def test_extension_or_content_selects_lvm(tmp_path, signal):
    path = _lvm(tmp_path, signal, name="export.txt")  # LVM content in a .txt file
    assert mio.detect_format(path) == "lvm"
    assert mio.read(path, format="lvm")["time_history"].shape == (2, 40)


def test_contiguous_segments_are_joined(tmp_path, signal):
    ds = mio.read(_lvm(tmp_path, signal, segments=3, xcols="One"))
    th = ds["time_history"]
    np.testing.assert_array_equal(th.values, signal)
    assert th.attrs["segment"] == "1 2 3"
    assert "time_history_2" not in ds


def test_separate_segments_stay_separate(tmp_path, signal):
    path = _lvm(tmp_path, signal, segments=2)
    text = path.read_text().replace("X0\t0.02\t0.02", "X0\t5\t5")  # second segment later
    path.write_text(text)
    ds = mio.read(path)
    np.testing.assert_array_equal(ds["time_history"].values, signal[:, :20])
    np.testing.assert_array_equal(ds["time_history_2"].values, signal[:, 20:])
    assert ds["time_history_2"].attrs["t0_s"] == 5.0
    assert ds["time_history_2"].attrs["segment"] == "2"


def test_nonzero_x0_and_x_values(tmp_path, signal):
    th = mio.read(_lvm(tmp_path, signal, xcols="One", x0=2.5))["time_history"]
    assert th.attrs["t0_s"] == 2.5
    assert th.time.values[0] == 0.0


def test_missing_column_names_line(tmp_path, signal):
    path = _lvm(tmp_path, signal)
    lines = path.read_text().splitlines()
    bad = lines.index(next(ln for ln in lines if ln.startswith("X_Value"))) + 1 + 5
    lines[bad] = lines[bad].rsplit("\t", 1)[0]  # one value missing
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match=rf"f\.lvm, line {bad + 1}: 2 fields; expected 3 "
                       r"\(X_Value, acc, force\).*missing columns"):
        mio.read(path)


def test_extra_column_refused(tmp_path, signal):
    path = _lvm(tmp_path, signal)
    lines = path.read_text().splitlines()
    bad = lines.index(next(ln for ln in lines if ln.startswith("X_Value"))) + 1 + 3
    lines[bad] += "\t1.0\t2.0"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match=rf"line {bad + 1}: 5 fields; expected 3.*extra"):
        mio.read(path)


def test_non_numeric_value_named(tmp_path, signal):
    path = _lvm(tmp_path, signal, dec=",")
    lines = path.read_text().splitlines()
    bad = lines.index(next(ln for ln in lines if ln.startswith("X_Value"))) + 1 + 7
    lines[bad] = "\t1.5\t2,0"  # decimal point in a decimal-comma file
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match=rf"line {bad + 1}: column 2 \('acc'\) = '1.5' is not"):
        mio.read(path)


def test_truncated_segment(tmp_path, signal):
    path = _lvm(tmp_path, signal)
    path.write_text("\n".join(path.read_text().splitlines()[:-5]) + "\n")
    with pytest.raises(FormatError, match=r"line \d+: segment 1 header says 40 samples but .* "
                       r"35 data lines; truncated"):
        mio.read(path)
    with pytest.warns(DataRepairWarning, match="read the samples present"):
        th = mio.read(path, allow_truncated=True)["time_history"]
    assert th.shape == (2, 35)


def test_channel_count_and_header_errors(tmp_path, signal):
    path = _lvm(tmp_path, signal)
    path.write_text(path.read_text().replace("Channels\t2", "Channels\t3"))
    with pytest.raises(FormatError, match=r"line 14: Channels = '3' but the column names "
                       r"\(line 21\) list 2 channels \(acc, force\)"):
        mio.read(path)
    path = _lvm(tmp_path, signal)
    path.write_text(path.read_text().replace("Delta_X\t0.001\t0.001", "Delta_X\t0.001\t0.002"))
    with pytest.raises(FormatError, match="line 19: channels have different Delta_X"):
        mio.read(path)
    path = _lvm(tmp_path, signal)
    path.write_text(path.read_text().replace("***End_of_Header***", "***End***"))
    with pytest.raises(FormatError, match=r"file header \(line 1\) has no '\*\*\*End_of_Header"):
        mio.read(path)
    with pytest.raises(ParameterError, match="decimal=';'"):
        mio.read(_lvm(tmp_path, signal), decimal=";")


def test_units_option_and_missing_units(tmp_path, signal):
    path = _lvm(tmp_path, signal)
    path.write_text(path.read_text().replace("Y_Unit_Label\tm/s^2\tN\t\n", ""))
    with pytest.raises(FormatError, match=r"no Y_Unit_Label line; the channels \['acc', 'force'\]"):
        mio.read(path)
    th = mio.read(path, units=["A", "V"])["time_history"]
    assert list(th.quantity.values) == ["current", "voltage"]


# --------------------------------------------------------------------------- fuzzing

_DIR = Path(tempfile.mkdtemp(prefix="mvtk-lvm-fuzz-"))
atexit.register(shutil.rmtree, _DIR, ignore_errors=True)
_SEED = _lvm(_DIR, np.round(np.sin(np.arange(24.0)).reshape(2, 12), 5), dec=",",
             name="seed.lvm").read_bytes()


@settings(max_examples=120, deadline=None, suppress_health_check=list(HealthCheck))
@given(
    pos=st.integers(0, len(_SEED) - 1),
    cut=st.integers(0, 40),
    insert=st.binary(max_size=6)
    | st.sampled_from([b"\t", b",", b".", b"\n", b"E", b"-", b"***End_of_Header***"]),
)
def test_mutated_lvm_gives_data_or_mvtk_error(pos, cut, insert):
    path = _DIR / "mutant.lvm"
    path.write_bytes(_SEED[:pos] + insert + _SEED[pos + cut :])
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            ds = mio.read(path)
    except MvtkError:
        return
    mio.validate(ds)


def test_frequency_x_dimension_gives_a_spectrum(tmp_path, signal):
    path = _lvm(tmp_path, np.abs(signal), dt=0.5)
    path.write_text(path.read_text().replace("X_Dimension\tTime\tTime", "X_Dimension\tHz\tHz"))
    ds = mio.read(path)
    spec = ds["spectrum"]
    assert spec.dims == ("channel", "frequency") and "time_history" not in ds
    np.testing.assert_allclose(spec.frequency.values[:3], [0.0, 0.5, 1.0])
    np.testing.assert_array_equal(spec.values, np.abs(signal))


@pytest.mark.parametrize("xcols", ["No", "One"])
def test_file_and_memory_parse_paths_agree(tmp_path, signal, monkeypatch, xcols):
    import mvtk.io._lvm as lvm

    path = _lvm(tmp_path, signal, xcols=xcols, dec=",", segments=2)
    memory = mio.read(path)
    calls = []
    real = lvm._WholeFile.parse
    monkeypatch.setattr(lvm._WholeFile, "MIN_BYTES", 0)
    monkeypatch.setattr(lvm._WholeFile, "parse", lambda *a: calls.append(1) or real(*a))
    from_file = mio.read(path)
    assert calls  # the last segment runs to the end of the file
    xr.testing.assert_identical(memory, from_file)
    lines = path.read_text().splitlines()
    lines[-3] = "\tNA\t1,0"  # not a number in an LVM file: the line is named on both paths
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match=rf"line {len(lines) - 2}: column 2 \('acc'\) = 'NA'"):
        mio.read(path)
    lines[-3] = lines[-4].rsplit("\t", 1)[0]  # a short line near the end of the file
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(FormatError, match=rf"line {len(lines) - 2}: 2 fields; expected 3"):
        mio.read(path)


@pytest.mark.parametrize("segments", [1, 3])
def test_parallel_chunks_give_the_written_values(tmp_path, rng, monkeypatch, segments):
    """Large-file path (header from the first bytes, data in parallel chunks) on a fresh
    file split into many chunks: the values written, and the same Dataset as the
    line-by-line path; a file it cannot take (a later segment beyond the first bytes, a
    Comment on a later line) is read again line by line to the same result."""
    import mvtk.io._lvm as lvm
    import mvtk.io._text as text

    data = np.round(rng.normal(size=(3, 1500)), 6)
    path = _lvm(tmp_path, data, dec=",", names=("a", "b", "c"), units=("g", "g", "N"),
                segments=segments, xcols="One")
    slow = mio.read(path)
    used, reads = [], []
    real = text.read_columns
    monkeypatch.setattr(text, "read_columns", lambda *a, **k: used.append(1) or real(*a, **k))
    real_read = lvm._read
    monkeypatch.setattr(lvm, "_read", lambda *a: reads.append(1) or real_read(*a))
    monkeypatch.setattr(lvm._WholeFile, "MIN_BYTES", 0)
    monkeypatch.setattr(lvm, "_HEAD_BYTES", 2048)
    monkeypatch.setattr(text, "MIN_CHUNK_BYTES", 1000)
    monkeypatch.setattr(text, "CHUNK_BYTES", 1000)
    fast = mio.read(path)
    assert used and len(reads) == (1 if segments == 1 else 2)  # 2: read again
    np.testing.assert_array_equal(fast["time_history"].values, data)
    xr.testing.assert_identical(slow, fast)
    lines = path.read_text().splitlines()
    lines[-100] += "\tlate comment"
    path.write_text("\n".join(lines) + "\n")
    reads.clear()
    xr.testing.assert_identical(mio.read(path), slow)
    assert len(reads) == 2
