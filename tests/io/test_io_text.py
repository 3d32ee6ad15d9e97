"""CSV / TSV / text exports: layouts that must read, and every bad-input path."""

from __future__ import annotations

import warnings

import numpy as np
import pandas as pd
import pytest
import xarray as xr

import mvtk.io as mio
from mvtk.errors import FormatError, MvtkWarning, ParameterError, UnsupportedFormatError


def _write(tmp_path, name, text, encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return path


GOOD = """# Instrument: DAQ-9
# Operator = J. Doe
Sample rate: 1 kHz
Time [s],acc1 [m/s2],F (N)
0.000,0.1,1
0.001,0.2,2
0.002,0.3,3
0.003,0.4,4
"""


def test_csv_with_metadata_time_and_units(tmp_path):
    ds = mio.read(_write(tmp_path, "a.csv", GOOD))
    th = ds["time_history"]
    assert list(th.channel.values) == ["acc1", "F"]
    assert list(th.units.values) == ["m/s^2", "N"]
    assert list(th.quantity.values) == ["acceleration", "force"]
    assert th.attrs["fs"] == 1000.0
    np.testing.assert_array_equal(th.time.values, np.arange(4) / 1000.0)
    np.testing.assert_array_equal(th.values, [[0.1, 0.2, 0.3, 0.4], [1, 2, 3, 4]])
    assert ds.attrs["instrument"] == "DAQ-9" and ds.attrs["operator"] == "J. Doe"
    assert th.attrs["source"].endswith("a.csv") and ds.attrs["format"] == "text"


def test_values_match_pandas(tmp_path, rng):
    data = rng.standard_normal((500, 3))
    df = pd.DataFrame(data, columns=["a [V]", "b [V]", "c [N]"])
    path = tmp_path / "r.csv"
    df.to_csv(path, index=False, float_format="%.17g")
    with open(path) as fh:
        body = fh.read()
    path.write_text("fs: 2048\n" + body)
    th = mio.read(path)["time_history"]
    np.testing.assert_array_equal(th.values, data.T)
    assert th.attrs["fs"] == 2048.0


def test_tsv_decimal_comma_units_row(tmp_path):
    text = "Zeit\tacc\tF\n[s]\t[g]\t[kN]\n0,0\t1,5\t2\n0,5\t2,5\t3\n1,0\t3,5\t4\n"
    th = mio.read(_write(tmp_path, "b.tsv", text))["time_history"]
    assert list(th.units.values) == ["g", "kN"]
    assert th.attrs["fs"] == 2.0
    np.testing.assert_array_equal(th.values[0], [1.5, 2.5, 3.5])


def test_semicolon_decimal_comma_and_labelled_rows(tmp_path):
    text = "dt;0,5 ms\nnode;3;4\ndirection;z;-y\nunits;m/s^2;N\nacc1;acc2\n1,5;2\n2,5;3\n"
    th = mio.read(_write(tmp_path, "c.csv", text))["time_history"]
    assert th.attrs["fs"] == 2000.0
    assert list(th.node.values) == [3, 4] and list(th.direction.values) == ["z", "-y"]
    np.testing.assert_array_equal(th.values, [[1.5, 2.5], [2.0, 3.0]])


def test_whitespace_delimited_with_ms_time(tmp_path):
    text = "t(ms)  v(mm/s)\n0   1\n2   2\n4   3\n"
    th = mio.read(_write(tmp_path, "d.txt", text))["time_history"]
    assert th.attrs["fs"] == 500.0 and th.units.item() == "mm/s"
    assert th.quantity.item() == "velocity"


def test_utf8_byte_order_mark(tmp_path):
    raw = b"\xef\xbb\xbf" + b"time [s],a [V]\n0,1\n1,2\n"
    th = mio.read(_write(tmp_path, "bom.csv", raw))["time_history"]
    assert list(th.channel.values) == ["a"] and th.attrs["fs"] == 1.0


def test_trailing_delimiter_column_dropped(tmp_path):
    text = "units\tV\tN\t\ntime\ta\tb\t\n0\t1\t2\t\n0.1\t2\t3\t\n0.2\t3\t4\t\n"
    th = mio.read(_write(tmp_path, "t.txt", text))["time_history"]
    assert list(th.channel.values) == ["a", "b"] and list(th.units.values) == ["V", "N"]
    np.testing.assert_array_equal(th.values, [[1, 2, 3], [2, 3, 4]])
    with pytest.raises(FormatError, match=r"t.txt, line 2: column 4 has an empty name"):
        mio.read(_write(tmp_path, "t.txt", text.replace("0.1\t2\t3\t", "0.1\t2\t3\t9")))


def test_options_override_header(tmp_path):
    text = "0.1,1\n0.2,2\n0.3,3\n"
    th = mio.read(_write(tmp_path, "e.csv", text), fs=10.0, channels=["a", "b"], units=["V", "Pa"])[
        "time_history"
    ]
    assert list(th.channel.values) == ["a", "b"] and th.attrs["fs"] == 10.0


def test_time_offset_kept_in_attrs(tmp_path):
    text = "time [s],x [m]\n1.0,0\n1.5,1\n2.0,2\n"
    th = mio.read(_write(tmp_path, "f.csv", text))["time_history"]
    assert th.attrs["t0_s"] == 1.0 and th.time.values[0] == 0.0


def test_marked_missing_values_are_reported(tmp_path):
    text = "time [s],a [V],b [V]\n0,1,NaN\n1,,2\n2,3,4\n"
    with pytest.warns(MvtkWarning, match=r"kept as NaN \('a': 1, 'b': 1\)"):
        th = mio.read(_write(tmp_path, "g.csv", text))["time_history"]
    assert list(th.n_missing.values) == [1, 1]
    assert np.isnan(th.values).sum() == 2
    mio.validate(th)


def test_round_trip_text(tmp_path):
    first = mio.read(_write(tmp_path, "a.csv", GOOD))
    second = mio.read(mio.write(first, tmp_path / "a.nc"))
    for ds in (first, second):
        for obj in [ds, *ds.data_vars.values()]:
            for key in ("source", "format", "original_source", "original_format"):
                obj.attrs.pop(key, None)
    xr.testing.assert_identical(first, second)


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (
            "time [s],a [V],b [V]\n0,1,2\n1,2,3\n2,3\n3,4,5\n",
            r"r.csv, line 4: 2 fields; expected 3 \(time, a, b\) as in the header \(ragged row\)",
        ),
        (
            "time [s],a [V],b [V]\n0,1,2\n1,2,3\n2,3,4,5\n3,4,5\n",
            r"r.csv, line 4: 4 fields; expected 3",
        ),
        (
            "time [s],a [V]\n0,1\n1,2\n2,abc\n3,4\n",
            r"r.csv, line 4, column 2 \('a'\): 'abc' is not a number",
        ),
        (
            "time [s],a [V]\n0,1\n1,2\n0.5,3\n3,4\n",
            r"r.csv, line 4: time 0.5 s is not after the previous 1.0 s; expected strictly",
        ),
        (
            "time [s],a [V]\n0,1\n1,2\n2,3\n4,4\n5,5\n",
            r"r.csv, line 5: time step 2.0 s before time 4.0 s; expected a uniform step",
        ),
        (
            "time [s],a [V],a [V]\n0,1,2\n1,2,3\n",
            r"r.csv, line 1: duplicate channel name 'a' in columns 2 and 3",
        ),
        (
            "time [s],a,b [V]\n0,1,2\n1,2,3\n",
            r"r.csv, line 1: channel 'a' \(column 2\) has no units",
        ),
        (
            "a [V],b [V]\n1,2\n2,3\n",
            r"no time column and no sampling-rate header; expected a column named 'time'",
        ),
        ("1,2\n2,3\n", r"no column-name line before the data at line 1"),
        ("time [s],a [V]\n", r"no numeric data lines found"),
        ("   \n\n", r"holds no data"),
        (
            "Sample rate: fast\ntime [s],a [V]\n0,1\n1,2\n",
            r"line 1: sample_rate = 'fast' is not a number",
        ),
        (
            "fs: 100\ntime [s],a [V]\n0,1\n1,2\n",
            r"the time column gives 1.0 Hz but the header gives 100.0 Hz",
        ),
        ("time [h],a [V]\n0,1\n1,2\n", r"time column 'time' in 'h'; expected s, ms or us"),
        ("time [s],a [V]\n0,1\n", r"one data line only"),
        ("node: 1,2,3\ntime [s],a [V]\n0,1\n1,2\n", r"the node header row has 3 entries"),
    ],
    ids=[
        "short-row",
        "long-row",
        "non-numeric",
        "non-monotonic",
        "non-uniform",
        "duplicate",
        "missing-units",
        "no-rate",
        "no-header",
        "no-data",
        "blank",
        "bad-rate",
        "rate-mismatch",
        "time-unit",
        "one-line",
        "bad-node-row",
    ],
)
def test_bad_csv(tmp_path, text, match):
    with pytest.raises(FormatError, match=match):
        mio.read(_write(tmp_path, "r.csv", text))


def test_non_utf8_header(tmp_path):
    raw = "time [s],acc [m/s²]\n0,1\n1,2\n".encode("latin-1")
    path = _write(tmp_path, "l.csv", raw)
    with pytest.raises(
        FormatError, match=r"l.csv, line 1: byte b'\\xb2' at column 18 is not valid utf-8"
    ):
        mio.read(path)
    th = mio.read(path, encoding="latin-1")["time_history"]
    assert th.units.item() == "m/s^2"


def test_empty_file(tmp_path):
    path = _write(tmp_path, "empty.csv", b"")
    with pytest.raises(FormatError, match=r"empty.csv: the file is empty \(0 bytes\)"):
        mio.read(path)


def test_unknown_format(tmp_path):
    path = _write(tmp_path, "x.bin", bytes(range(256)) * 4)
    with pytest.raises(UnsupportedFormatError, match=r"x.bin: unknown format \(extension '.bin'"):
        mio.read(path)
    with pytest.raises(UnsupportedFormatError, match=r"unknown format 'foo'; expected one of: "):
        mio.read(path, format="foo")


def test_unknown_option(tmp_path):
    path = _write(tmp_path, "a.csv", GOOD)
    with pytest.raises(ParameterError, match=r"option\(s\) sampling not understood by the 'text'"):
        mio.read(path, sampling=3)


def test_bad_time_column_option(tmp_path):
    path = _write(tmp_path, "a.csv", GOOD)
    with pytest.raises(ParameterError, match=r"time_column='zeit' not among the columns"):
        mio.read(path, time_column="zeit")
    with pytest.raises(ParameterError, match=r"time_column=7 out of range"):
        mio.read(path, time_column=7)


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such file"):
        mio.read(tmp_path / "nope.csv")
    with pytest.raises(FormatError, match="is a directory"):
        mio.read(tmp_path)


def test_no_warning_for_clean_file(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mio.read(_write(tmp_path, "a.csv", GOOD))


# ---------------------------------------------------------------- whole-file vs chunked


def _big_csv(tmp_path, rng, trailing=False, nan_at=None):
    n = 70_000  # > 5 MiB: pandas' multi-threaded whole-file parser is eligible
    data = np.round(rng.standard_normal((n, 8)), 6)
    if nan_at is not None:
        data[nan_at, 3] = np.nan
    path = tmp_path / "big.csv"
    block = np.column_stack([np.arange(n) / 1000.0, data])
    head = f"time [s],{','.join(f'a{k} [m/s^2]' for k in range(8))}"
    fmt = ",".join(["%.3f"] + ["%.6f"] * 8) + ("," if trailing else "")
    np.savetxt(path, block, fmt=fmt, header=head, comments="")
    return path, data


@pytest.mark.parametrize("trailing", [False, True])
def test_parallel_and_serial_paths_agree(tmp_path, rng, monkeypatch, trailing):
    import mvtk.io._text as text

    path, data = _big_csv(tmp_path, rng, trailing=trailing)
    assert path.stat().st_size > 5 * 2**20
    calls = []
    real = text.read_columns
    monkeypatch.setattr(text, "read_columns", lambda *a, **k: calls.append(1) or real(*a, **k))
    monkeypatch.setattr(text, "CHUNK_BYTES", 2**20)  # several chunks per thread
    parallel = mio.read(path)["time_history"]
    assert calls, "the parallel path was expected for a file with plain line ends"
    monkeypatch.setattr(text, "read_columns", lambda *a, **k: None)  # the serial path
    serial = mio.read(path)["time_history"]
    np.testing.assert_array_equal(parallel.values, data.T)
    xr.testing.assert_identical(parallel, serial)


def test_parallel_parse_known_values(tmp_path, rng):
    """read_columns against the values written, and its refusal of a non-number."""
    import mvtk.io._text as text

    path, data = _big_csv(tmp_path, rng)
    head = path.read_bytes()[:4096]
    got = text.read_columns(path, head.index(b"\n") + 1, 9, list(range(1, 9)),
                            {"sep": ",", "decimal": "."})
    block, n_rows, nans = got
    assert n_rows == data.shape[0] and not nans.any()
    np.testing.assert_array_equal(block, data.T)
    # a bad value makes the parallel parse give up (the serial path names the line)
    lines = path.read_text().splitlines()
    lines[len(lines) // 2] = lines[len(lines) // 2].replace(",", ",x", 1)
    path.write_text("\n".join(lines) + "\n")
    assert text.read_columns(path, head.index(b"\n") + 1, 9, [1], {"sep": ","}) is None


def test_parallel_parse_with_too_few_rows_estimated(tmp_path, rng, monkeypatch):
    """The workers copy their chunks in place while the row estimate holds; the chunks
    beyond it are copied after the pool into a grown array, in file order."""
    import mvtk.io._text as text

    path, data = _big_csv(tmp_path, rng)
    monkeypatch.setattr(text, "CHUNK_BYTES", 2**20)
    start = path.read_bytes()[:4096].index(b"\n") + 1
    for hint in (1, data.shape[0] // 3, data.shape[0]):
        block, n_rows, nans = text.read_columns(path, start, 9, [8, 1], {"sep": ","},
                                                rows_hint=hint)
        assert n_rows == data.shape[0] and not nans.any()
        np.testing.assert_array_equal(block, data[:, [7, 0]].T)


def test_parallel_parse_with_a_slow_first_chunk(tmp_path, rng, monkeypatch):
    """Chunks parsed before an earlier, slower one wait parked, and are copied in file
    order by the thread that finishes the slow one: the same array as in order."""
    import threading
    import time

    import mvtk.io._text as text

    path, data = _big_csv(tmp_path, rng)
    monkeypatch.setattr(text, "CHUNK_BYTES", 2**20)
    monkeypatch.setattr(text, "MIN_CHUNK_BYTES", 2**18)
    monkeypatch.setattr(text, "parse_workers", lambda: 3)
    real = text._parse_chunk
    first = threading.Event()

    def slow_first(buf, *args):
        if not first.is_set():
            first.set()
            time.sleep(0.3)   # the other threads parse (and park) the next chunks
        return real(buf, *args)

    monkeypatch.setattr(text, "_parse_chunk", slow_first)
    start = path.read_bytes()[:4096].index(b"\n") + 1
    block, n_rows, nans = text.read_columns(path, start, 9, [1, 8], {"sep": ","})
    assert n_rows == data.shape[0] and not nans.any()
    np.testing.assert_array_equal(block, data[:, [0, 7]].T)


def test_parsed_record_in_small_pages_is_the_same_array(tmp_path, rng, monkeypatch):
    """A large parsed record lives in a private anonymous mapping advised against huge
    pages (their compaction cost 0.7-1.0 s per 800 MB on first write): the values are
    the file's, the array writable and its memory freed with it, both when the row
    estimate holds and when the array grows."""
    import gc
    import mmap
    import weakref

    import mvtk.io._text as text

    path, data = _big_csv(tmp_path, rng)
    monkeypatch.setattr(text, "CHUNK_BYTES", 2**20)
    monkeypatch.setattr(text, "SMALL_PAGES_BYTES", 0)
    start = path.read_bytes()[:4096].index(b"\n") + 1
    for hint in (None, 10):
        block, n_rows, _ = text.read_columns(path, start, 9, [1, 8], {"sep": ","},
                                             rows_hint=hint)
        np.testing.assert_array_equal(block, data[:, [0, 7]].T)
        owner = block
        while isinstance(owner, np.ndarray):
            owner = owner.base
        owner = owner.obj if isinstance(owner, memoryview) else owner
        if hasattr(mmap, "MADV_NOHUGEPAGE"):
            assert isinstance(owner, mmap.mmap)
            gone = weakref.ref(owner)
            del owner
            block[0, 0] = 1.5                      # writable
            del block
            gc.collect()
            assert gone() is None                  # unmapped with the array
    if hasattr(mmap, "MADV_NOHUGEPAGE"):
        # an advice the kernel refuses (built without huge pages: EINVAL) is skipped
        monkeypatch.setattr(mmap, "MADV_NOHUGEPAGE", 987654)
        refused = text._fresh_array((3, 4))
        refused[...] = 2.0
        assert refused.sum() == 24.0
    monkeypatch.undo()
    small = text._fresh_array((2, 3))
    assert small.flags.owndata and small.dtype == np.float64     # numpy's own below


def test_validate_exact_axis_and_overflowing_finite_values(rng):
    """The validator's fast paths: the exact ``arange(n) / fs`` axis, and channels whose
    sum of squares overflows although every value is finite (then tested one by one)."""
    import xarray as xr

    import mvtk.io as mio

    big = np.full((2, 50), 1e200)
    da = mio.time_history(big, 1000.0, ["a", "b"], "N", quantity="force")
    mio.validate(da)                              # no NaN, no infinity: accepted
    bad = da.copy(data=big.copy())
    bad.values[0, 7] = -np.inf
    with pytest.raises(FormatError, match=r"infinite value in channel 'a' at sample 7"):
        mio.validate(bad)
    assert isinstance(da, xr.DataArray)
