"""Nastran OUTPUT4 (OP4) matrix files, ASCII and binary, dense and sparse.

An OP4 file holds one or more matrices, each a header followed by column records and a
terminating record whose column number exceeds the column count:

- header: ``NCOL NROW FORM TYPE NAME [FORMAT]``; ``NROW < 0`` marks the "BIGMAT"
  sparse layout; ``TYPE`` 1/2/3/4 = real single / real double / complex single /
  complex double; ``FORM`` 1 square, 2 rectangular, 3 diagonal, 4 lower triangular,
  5 upper triangular, 6 symmetric (stored in full), 8 identity, 9 pseudo-identity;
- column record: ``ICOL IROW NW``; ``IROW > 0``: dense, consecutive values from row
  IROW; ``IROW = 0``: sparse, a sequence of *strings*, each with a header (one word
  ``IS = IROW + 65536 L`` or, in BIGMAT, two words ``L IROW``) and ``L - 1`` data
  words (a double-precision number takes two words, a complex one two numbers).

ASCII files print one record per line group (integers as I8, numbers in the E format of
the header); binary files are Fortran unformatted sequential records (4-byte length
markers, 32-bit integers, either byte order).

Format reference: MSC Nastran Quick Reference Guide, DMAP module OUTPUT4 (description
of the formatted and unformatted output); the layout above was checked on the OP4 files
of pyNastran's test suite (``tests/fe/data/op4``).
"""

from __future__ import annotations

import re
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ..errors import FormatError

__all__ = ["Op4Matrix", "read_op4"]

FORMS = {1: "square", 2: "rectangular", 3: "diagonal", 4: "lower triangular",
         5: "upper triangular", 6: "symmetric", 8: "identity", 9: "pseudo-identity"}
_NUMBER = re.compile(r"[+-]?(?:\d+\.\d*|\.\d+)(?:[EeDd][+-]?\d+)?")
_NUMBER_LINE = re.compile(r"^[\s\d.EeDd+-]*\.[\s\d.EeDd+-]*$")


@dataclass(frozen=True, eq=False)
class Op4Matrix:
    """One matrix of an OP4 file.

    Attributes
    ----------
    name : str
        Matrix name from the header (e.g. ``"KGG"``).
    form : int
        Nastran matrix form (6 = symmetric, ...; see :data:`FORMS`).
    matrix : scipy.sparse.csc_matrix
        The values (float or complex), shape ``(nrow, ncol)``.

    Examples
    --------
    Returned by :func:`read_op4`; ``"file.op4:KAA"`` picks it in :func:`mvtk.fe.read_matrices`.
    The 2-mass chain of :func:`read_op4`'s example, unit masses, DOFs along z; closed form
    ``f1 = sqrt(k (3 - sqrt(5)) / 2) / (2 pi)`` = 31.105 Hz:

    >>> import pathlib, tempfile
    >>> from mvtk.fe import modal_analysis, read_matrices
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "kaa.op4"
    >>> _ = path.write_text(
    ...     "       2       2       6       2KAA      1P,3E23.16\\n"
    ...     "       1       1       2\\n 2.0000000000000000E+05-1.0000000000000000E+05\\n"
    ...     "       2       1       2\\n-1.0000000000000000E+05 1.0000000000000000E+05\\n"
    ...     "       3       1       1\\n 1.0000000000000000E+00\\n")
    >>> model = read_matrices(f"{path}:KAA", np.eye(2), np.array([[1, 3], [2, 3]]))
    >>> np.round(modal_analysis(model, 1).fn_hz, 3)
    array([31.105])
    """

    name: str
    form: int
    matrix: sp.csc_matrix

    @property
    def form_name(self) -> str:
        """The form in words (``"symmetric"``), or ``"form <n>"`` when not standard."""
        return FORMS.get(self.form, f"form {self.form}")

    def toarray(self) -> np.ndarray:
        """Dense copy of :attr:`matrix`."""
        return self.matrix.toarray()


def _words_per_number(typ: int) -> int:
    return 2 if typ in (2, 4) else 1


def _assemble(name, form, typ, nrow, ncol, rows, cols, vals) -> Op4Matrix:
    complex_ = typ in (3, 4)
    v = np.concatenate(vals) if vals else np.zeros(0)
    r = np.concatenate(rows) if rows else np.zeros(0, dtype=np.int64)
    c = np.concatenate(cols) if cols else np.zeros(0, dtype=np.int64)
    if complex_:
        v = v[0::2] + 1j * v[1::2]
    A = sp.csc_matrix((v, (r, c)), shape=(nrow, ncol),
                      dtype=complex if complex_ else float)
    return Op4Matrix(name=name, form=form, matrix=A)


def _place(where, name, nrow, irow, icol, values, typ, rows, cols, vals) -> None:
    """Store consecutive values from row irow (1-based) of column icol."""
    per = 2 if typ in (3, 4) else 1
    if len(values) % per:
        raise FormatError(f"{where}: matrix {name!r} column {icol}: a complex value lacks "
                          "its imaginary part")
    n = len(values) // per
    if irow < 1 or irow - 1 + n > nrow:
        raise FormatError(f"{where}: matrix {name!r} column {icol}: rows {irow}..{irow + n - 1}"
                          f" outside 1..{nrow}")
    rows.append(np.arange(irow - 1, irow - 1 + n))
    cols.append(np.full(n, icol - 1))
    vals.append(np.asarray(values, dtype=float))


def _header_fields(line: str, where: str):
    try:
        ncol, nrow, form, typ = (int(line[i:i + 8]) for i in range(0, 32, 8))
    except ValueError:
        raise FormatError(f"{where}: expected a matrix header 'NCOL NROW FORM TYPE NAME' "
                          f"(4 I8 and A8), got {line.strip()[:60]!r}") from None
    name = line[32:40].strip()
    return ncol, nrow, form, typ, name


def _check_header(where, name, ncol, nrow, typ) -> None:
    if typ not in (1, 2, 3, 4):
        raise FormatError(f"{where}: matrix {name!r}: type {typ} is not 1..4 (real/complex, "
                          "single/double)")
    if ncol < 0:
        raise FormatError(f"{where}: matrix {name!r}: negative column count {ncol}")


def _ints(line: str, n: int, where: str, what: str) -> list[int]:
    try:
        out = [int(t) for t in line.split()]
    except ValueError:
        out = []
    if len(out) != n:
        raise FormatError(f"{where}: expected {what} ({n} integers), got {line.strip()[:60]!r}")
    return out


def _read_ascii(path: Path, text: str) -> dict[str, Op4Matrix]:
    lines = text.splitlines()
    out: dict[str, Op4Matrix] = {}
    i = 0

    def numbers_until(count: int | None, start: int, name: str) -> tuple[list[float], int]:
        """Numbers from line ``start`` on: exactly ``count``, or up to a non-number line."""
        vals: list[float] = []
        j = start
        while j < len(lines) and (count is None or len(vals) < count):
            line = lines[j]
            if not _NUMBER_LINE.match(line):
                break
            vals.extend(float(t.replace("D", "E").replace("d", "e"))
                        for t in _NUMBER.findall(line))
            j += 1
        if count is not None and len(vals) != count:
            raise FormatError(f"{path.name} line {j + 1}: matrix {name!r}: expected {count} "
                              f"numbers, found {len(vals)}")
        return vals, j

    while i < len(lines):
        if not lines[i].strip():
            i += 1
            continue
        where = f"{path.name} line {i + 1}"
        ncol, nrow, form, typ, name = _header_fields(lines[i], where)
        _check_header(where, name, ncol, nrow, typ)
        bigmat, nrow = nrow < 0, abs(nrow)
        wpn = _words_per_number(typ)
        rows: list = []
        cols: list = []
        vals: list = []
        i += 1
        while True:
            if i >= len(lines):
                raise FormatError(f"{path.name}: matrix {name!r} ends without its "
                                  f"terminating record (column {ncol + 1})")
            where = f"{path.name} line {i + 1}"
            icol, irow, nw = _ints(lines[i], 3, where, f"a column record of matrix {name!r}")
            i += 1
            if icol > ncol:  # terminating record and its value(s)
                _, i = numbers_until(None, i, name)
                break
            if icol < 1:
                raise FormatError(f"{where}: matrix {name!r}: column {icol} outside 1..{ncol}")
            if irow > 0:  # dense: NW counts numbers (some writers: words)
                values, i = numbers_until(None, i, name)
                if len(values) not in (nw, nw // wpn):
                    raise FormatError(f"{where}: matrix {name!r} column {icol}: NW = {nw} "
                                      f"but {len(values)} numbers follow")
                _place(where, name, nrow, irow, icol, values, typ, rows, cols, vals)
                continue
            used = 0
            while used < nw:  # sparse strings
                where = f"{path.name} line {i + 1}"
                if i >= len(lines):
                    raise FormatError(f"{path.name}: matrix {name!r} column {icol}: file "
                                      "ends inside a sparse column")
                if bigmat:
                    L, srow = _ints(lines[i], 2, where, "a BIGMAT string header 'L IROW'")
                    used += 2
                else:
                    (code,) = _ints(lines[i], 1, where, "a string header IROW + 65536 L")
                    L, srow = divmod(code, 65536)
                    used += 1
                i += 1
                n_words = L - 1
                if n_words < 0 or n_words % wpn:
                    raise FormatError(f"{where}: matrix {name!r} column {icol}: string of "
                                      f"{n_words} words does not hold whole numbers")
                values, i = numbers_until(n_words // wpn, i, name)
                _place(where, name, nrow, srow, icol, values, typ, rows, cols, vals)
                used += n_words
            if used != nw:
                raise FormatError(f"{where}: matrix {name!r} column {icol}: strings hold "
                                  f"{used} words, the column record says {nw}")
        out[name] = _assemble(name, form, typ, nrow, ncol, rows, cols, vals)
    if not out:
        raise FormatError(f"{path.name}: no matrix found")
    return out


def _records(path: Path, data: bytes):
    """Fortran unformatted records (byte order from the first marker: 24-byte header)."""
    if len(data) < 4:
        raise FormatError(f"{path.name}: too short for an OP4 file")
    for bo in ("<", ">"):
        if struct.unpack(bo + "i", data[:4])[0] == 24:
            break
    else:
        raise FormatError(f"{path.name}: not a 32-bit binary OP4 file (the first record is "
                          "not the 24-byte matrix header) and not ASCII")
    pos, k = 0, 0
    while pos < len(data):
        k += 1
        if pos + 4 > len(data):
            raise FormatError(f"{path.name} record {k}: truncated length marker")
        (n,) = struct.unpack(bo + "i", data[pos:pos + 4])
        end = pos + 4 + n
        if n < 0 or end + 4 > len(data) or data[end:end + 4] != data[pos:pos + 4]:
            raise FormatError(f"{path.name} record {k}: broken record markers (file truncated "
                              "or not Fortran unformatted)")
        yield k, bo, data[pos + 4:end]
        pos = end + 4


def _read_binary(path: Path, data: bytes) -> dict[str, Op4Matrix]:
    out: dict[str, Op4Matrix] = {}
    recs = _records(path, data)
    for k, bo, rec in recs:
        where = f"{path.name} record {k}"
        if len(rec) != 24:
            raise FormatError(f"{where}: expected a 24-byte matrix header, got {len(rec)} "
                              "bytes")
        ncol, nrow, form, typ = struct.unpack(bo + "4i", rec[:16])
        name = rec[16:24].decode("ascii", errors="replace").strip()
        _check_header(where, name, ncol, nrow, typ)
        bigmat, nrow = nrow < 0, abs(nrow)
        wpn = _words_per_number(typ)
        ftype = np.dtype(bo + ("f8" if wpn == 2 else "f4"))
        rows: list = []
        cols: list = []
        vals: list = []
        for k2, _, col in recs:
            where = f"{path.name} record {k2}"
            if len(col) < 12:
                raise FormatError(f"{where}: matrix {name!r}: column record shorter than "
                                  "ICOL IROW NW")
            icol, irow, _nw = struct.unpack(bo + "3i", col[:12])
            body = col[12:]
            if icol > ncol:
                break
            if icol < 1:
                raise FormatError(f"{where}: matrix {name!r}: column {icol} outside 1..{ncol}")
            if irow > 0:
                if len(body) % ftype.itemsize:
                    raise FormatError(f"{where}: matrix {name!r} column {icol}: "
                                      f"{len(body)} bytes are not whole numbers")
                _place(where, name, nrow, irow, icol, np.frombuffer(body, ftype), typ,
                       rows, cols, vals)
                continue
            p = 0
            while p < len(body):
                if bigmat:
                    L, srow = struct.unpack(bo + "2i", body[p:p + 8])
                    p += 8
                else:
                    L, srow = divmod(struct.unpack(bo + "i", body[p:p + 4])[0], 65536)
                    p += 4
                nbytes = 4 * (L - 1)
                if L < 1 or p + nbytes > len(body) or nbytes % ftype.itemsize:
                    raise FormatError(f"{where}: matrix {name!r} column {icol}: bad sparse "
                                      f"string (L = {L}) at byte {p}")
                _place(where, name, nrow, srow, icol, np.frombuffer(body[p:p + nbytes], ftype),
                       typ, rows, cols, vals)
                p += nbytes
        else:
            raise FormatError(f"{path.name}: matrix {name!r} ends without its terminating "
                              f"record (column {ncol + 1})")
        out[name] = _assemble(name, form, typ, nrow, ncol, rows, cols, vals)
    if not out:
        raise FormatError(f"{path.name}: no matrix found")
    return out


def read_op4(path: str | Path) -> dict[str, Op4Matrix]:
    """Read every matrix of a Nastran OUTPUT4 file (ASCII or binary).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    dict of str to Op4Matrix
        By matrix name, in file order. Symmetric matrices (form 6) are stored in full
        by OUTPUT4 and returned as stored.

    Raises
    ------
    FormatError
        Missing file, or content that is not OP4; the message names the file, the line
        (ASCII) or record (binary) and the matrix.

    Examples
    --------
    A 2 x 2 stiffness matrix (the 2-mass chain, N/m) written by hand as an ASCII OUTPUT4
    file (header, one record per column, the end record):

    >>> import pathlib, tempfile
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "kaa.op4"
    >>> _ = path.write_text(
    ...     "       2       2       6       2KAA      1P,3E23.16\\n"
    ...     "       1       1       2\\n 2.0000000000000000E+05-1.0000000000000000E+05\\n"
    ...     "       2       1       2\\n-1.0000000000000000E+05 1.0000000000000000E+05\\n"
    ...     "       3       1       1\\n 1.0000000000000000E+00\\n")
    >>> mats = read_op4(path)
    >>> list(mats), mats["KAA"].form, mats["KAA"].matrix.toarray() / 1e5
    (['KAA'], 6, array([[ 2., -1.],
           [-1.,  1.]]))
    """
    path = Path(path)
    if not path.is_file():
        raise FormatError(f"OP4 file {str(path)!r} not found")
    data = path.read_bytes()
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        return _read_binary(path, data)
    if "\x00" in text[:64]:
        return _read_binary(path, data)
    return _read_ascii(path, text)
