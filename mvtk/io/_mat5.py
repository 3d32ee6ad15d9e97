"""Structural check of MAT v5 files before scipy.io.loadmat sees them.

scipy's compiled MAT v5 reader can crash the interpreter (segmentation fault) on a file
whose element sizes disagree with its array dimensions. This walk checks every data
element tag against its parent and the array dimensions, so a damaged file becomes a
FormatError naming the byte offset instead of a crash.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

from ..errors import FormatError

__all__ = ["check_mat5"]

_SIZES = {1: 1, 2: 1, 3: 2, 4: 2, 5: 4, 6: 4, 7: 4, 9: 8, 12: 8, 13: 8, 16: 1, 17: 2, 18: 4}
_MATRIX, _COMPRESSED = 14, 15
_NUMERIC_CLASSES = set(range(6, 16))
_CELL, _STRUCT, _OBJECT, _SPARSE = 1, 2, 3, 5


class _Walker:
    def __init__(self, path: Path, endian: str):
        self.path = path
        self.e = endian

    def fail(self, offset: int, what: str):
        raise FormatError(
            f"{self.path}, byte {offset}: {what}; the MAT v5 file is truncated or corrupted"
        )

    def tag(self, buf: bytes, pos: int, end: int, base: int) -> tuple[int, int, int, int]:
        """(mdtype, nbytes, data start, next element) of the element at ``pos``."""
        if pos + 8 > end:
            self.fail(base + pos, f"element tag needs 8 bytes, {end - pos} left")
        first, second = struct.unpack(self.e + "II", buf[pos : pos + 8])
        if first >> 16:
            mdtype, nbytes = first & 0xFFFF, first >> 16
            if nbytes > 4:
                self.fail(base + pos, f"small data element claims {nbytes} bytes (max 4)")
            return mdtype, nbytes, pos + 4, pos + 8
        mdtype, nbytes = first, second
        nxt = pos + 8 + nbytes
        if mdtype != _COMPRESSED:
            nxt += (-nbytes) % 8
        if pos + 8 + nbytes > end:
            self.fail(base + pos, f"element of {nbytes} bytes runs past its container")
        return mdtype, nbytes, pos + 8, min(nxt, end)

    def numeric(self, buf, pos, end, base, count: int | None, what: str) -> int:
        mdtype, nbytes, start, nxt = self.tag(buf, pos, end, base)
        size = _SIZES.get(mdtype)
        if size is None:
            self.fail(base + pos, f"{what}: data type {mdtype} is not a numeric MAT type")
        if nbytes % size:
            self.fail(base + pos, f"{what}: {nbytes} bytes is not a whole number of items")
        if count is not None and nbytes // size != count:
            self.fail(base + pos, f"{what}: {nbytes // size} values, dimensions need {count}")
        return nxt

    def matrix(self, buf: bytes, pos: int, end: int, base: int) -> None:
        """Check the body (after the tag) of a miMATRIX element spanning buf[pos:end]."""
        if pos == end:
            return  # empty matrix
        mdtype, nbytes, start, nxt = self.tag(buf, pos, end, base)
        if mdtype != 6 or nbytes != 8:
            self.fail(base + pos, "array flags: expected 8 bytes of uint32")
        cls = buf[start + (0 if self.e == "<" else 3)]
        pos = nxt
        mdtype, nbytes, start, nxt = self.tag(buf, pos, end, base)
        if mdtype != 5 or nbytes % 4 or nbytes == 0:
            self.fail(base + pos, "dimensions: expected int32 values")
        dims = struct.unpack(self.e + f"{nbytes // 4}i", buf[start : start + nbytes])
        if any(d < 0 for d in dims):
            self.fail(base + pos, f"negative dimension in {dims}")
        count = 1
        for d in dims:
            count *= d
        pos = self.numeric(buf, nxt, end, base, None, "array name")
        if cls in _NUMERIC_CLASSES:
            pos = self.numeric(buf, pos, end, base, count, "real part")
            if pos < end:
                self.numeric(buf, pos, end, base, count, "imaginary part")
        elif cls == _CELL:
            for _ in range(count):
                pos = self.element(buf, pos, end, base)
        elif cls == _STRUCT:
            mdtype, nbytes, start, pos = self.tag(buf, pos, end, base)
            if nbytes != 4:
                self.fail(base + pos, "struct field-name length: expected one int32")
            name_len = struct.unpack(self.e + "i", buf[start : start + 4])[0]
            mdtype, nbytes, start, pos = self.tag(buf, pos, end, base)
            n_fields = nbytes // name_len if name_len > 0 else 0
            for _ in range(count * n_fields):
                pos = self.element(buf, pos, end, base)
        else:  # char, sparse and object arrays: element boundaries only
            while pos < end:
                pos = self.numeric(buf, pos, end, base, None, "array data")

    def element(self, buf: bytes, pos: int, end: int, base: int) -> int:
        mdtype, nbytes, start, nxt = self.tag(buf, pos, end, base)
        if mdtype == _MATRIX:
            self.matrix(buf, start, start + nbytes, base)
        elif mdtype == _COMPRESSED:
            try:
                inner = zlib.decompress(buf[start : start + nbytes])
            except zlib.error as err:
                self.fail(base + pos, f"compressed element does not inflate ({err})")
            self.element(inner, 0, len(inner), base + start)
        elif mdtype not in _SIZES:
            self.fail(base + pos, f"unknown data type {mdtype}")
        return nxt


def check_mat5(path: Path, raw: bytes) -> None:
    """Raise FormatError when the element structure of a MAT v5 file is inconsistent."""
    if len(raw) < 128:
        raise FormatError(f"{path}: {len(raw)} bytes; a MAT v5 file has a 128-byte header")
    marker = raw[126:128]
    if marker not in (b"IM", b"MI"):
        raise FormatError(
            f"{path}, byte 126: endian indicator {marker!r}; expected 'IM' or 'MI' (MAT v5)"
        )
    walker = _Walker(path, "<" if marker == b"IM" else ">")
    pos = 128
    while pos < len(raw):
        if not raw[pos:].strip(b"\x00"):
            break
        pos = walker.element(raw, pos, len(raw), 0)
