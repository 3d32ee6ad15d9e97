"""Hypothesis fuzzing: mutated valid files give validated data or an MvtkError, never a hang."""

from __future__ import annotations

import atexit
import shutil
import signal
import struct
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest
import scipy.io
import scipy.io.wavfile
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import mvtk.io as mio
from mvtk.errors import MvtkError

_DIR = Path(tempfile.mkdtemp(prefix="mvtk-io-fuzz-"))
atexit.register(shutil.rmtree, _DIR, ignore_errors=True)


def _uff_ascii() -> bytes:
    vals = np.sin(np.arange(10) / 3.0)
    lines = [
        "    -1",
        "    58",
        "acc",
        "NONE",
        "NONE",
        "NONE",
        "NONE",
        "    1         0    0         0 acc                1   3 NONE               0   0",
        "         4        10         1  0.00000E+00  1.00000E-03  0.00000E+00",
        "        17    0    0    0 Time                 s                   ",
        "        12    0    0    0 Acceleration         m/s2                ",
        "         0    0    0    0 NONE                 NONE                ",
        "         0    0    0    0 NONE                 NONE                ",
    ]
    for k in range(0, 10, 4):
        lines.append("".join(f"{v:20.11e}" for v in vals[k : k + 4]))
    lines.append("    -1")
    return ("\n".join(lines) + "\n").encode()


def _uff_binary() -> bytes:
    head = _uff_ascii().split(b"\n")[:13]
    payload = struct.pack("<10d", *np.cos(np.arange(10.0)))
    head[1] = b"    58b     1     2          11          80     0     0           0           0"
    return b"\n".join(head) + b"\n" + payload + b"\n    -1\n"


def _csv() -> bytes:
    rows = "\n".join(f"{k * 0.001:.3f},{np.sin(k):.6f},{np.cos(k):.6f}" for k in range(12))
    return ("# instrument: sim\ntime [s],a [m/s^2],f [N]\n" + rows + "\n").encode()


def _files() -> dict[str, tuple[bytes, str, dict]]:
    mat = _DIR / "base.mat"
    scipy.io.savemat(mat, {"y": np.arange(20.0).reshape(10, 2), "fs": 100.0})
    wav = _DIR / "base.wav"
    scipy.io.wavfile.write(wav, 1000, (np.arange(40) * 100).astype(np.int16))
    nc = _DIR / "base.nc"
    mio.write(mio.time_history(np.ones((2, 8)), 10.0, ["a", "b"], ["V", "N"]), nc)
    return {
        "csv": (_csv(), ".csv", {}),
        "uff": (_uff_ascii(), ".uff", {}),
        "uffb": (_uff_binary(), ".uff", {}),
        "mat": (mat.read_bytes(), ".mat", {"data": "y", "fs": "fs", "units": "V"}),
        "wav": (wav.read_bytes(), ".wav", {}),
        "netcdf": (nc.read_bytes(), ".nc", {}),
    }


BASE = _files()


@st.composite
def mutations(draw, size: int):
    kind = draw(st.sampled_from(["flip", "truncate", "insert", "delete", "overwrite"]))
    pos = draw(st.integers(0, max(size - 1, 0)))
    if kind == "flip":
        return kind, pos, draw(st.integers(1, 255))
    if kind == "truncate":
        return kind, pos, 0
    if kind == "insert":
        return kind, pos, draw(st.binary(min_size=1, max_size=8))
    if kind == "delete":
        return kind, pos, draw(st.integers(1, 16))
    return kind, pos, draw(st.sampled_from([b"-1", b"nan", b",", b";", b"\n", b"e99", b"x"]))


def _mutate(raw: bytes, mutation) -> bytes:
    kind, pos, arg = mutation
    if kind == "flip":
        return raw[:pos] + bytes([raw[pos] ^ arg]) + raw[pos + 1 :]
    if kind == "truncate":
        return raw[:pos]
    if kind == "insert":
        return raw[:pos] + arg + raw[pos:]
    if kind == "delete":
        return raw[:pos] + raw[pos + arg :]
    return raw[:pos] + arg + raw[pos + len(arg) :]


class _Hang(Exception):
    pass


def _alarm(signum, frame):
    raise _Hang("reader did not return within 10 s")


@pytest.mark.parametrize("fmt", sorted(BASE))
def test_mutated_files_read_or_raise_mvtk_error(fmt):
    raw, ext, options = BASE[fmt]

    @settings(
        max_examples=60,
        deadline=None,
        derandomize=True,
        suppress_health_check=[HealthCheck.too_slow],
    )
    @given(mutation=mutations(len(raw)))
    def check(mutation):
        path = _DIR / f"fuzz_{fmt}{ext}"
        path.write_bytes(_mutate(raw, mutation))
        old = signal.signal(signal.SIGALRM, _alarm)
        signal.alarm(10)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                ds = mio.read(path, **options)
        except MvtkError:
            return
        finally:
            signal.alarm(0)
            signal.signal(signal.SIGALRM, old)
        mio.validate(ds)
        assert ds.attrs["source"] == str(path)

    check()
