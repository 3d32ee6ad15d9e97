"""LabVIEW Measurement (LVM) text files, as written by LabVIEW's "Write To Measurement File".

Layout (NI's LVM specification; every part but the data is optional in practice)::

    LabVIEW Measurement
    Writer_Version  2                       <- file header: key<sep>value lines
    Separator       Tab                     <- Tab, Comma or a single character
    Decimal_Separator   ,                   <- ',' or '.'
    X_Columns       No                      <- No / One / Multi
    Operator  Domen   Date  2018/12/17   Time  10:18:21,109...
    ***End_of_Header***
                                            <- then one or more segments:
    Channels    2
    Samples     50030   50030               <- one value per channel (or one for all)
    Y_Unit_Label    g   Newtons
    X_Dimension Time    Time
    X0          0,0E+0  0,0E+0
    Delta_X     2,0E-5  2,0E-5
    ***End_of_Header***
    X_Value  Acceleration (Trigger)  Force (Trigger)  Comment    <- column names
        -0,007387   0,232147                                       <- data lines

With ``X_Columns No`` the X column is present but empty (or absent); with ``One`` the
first column holds the X values (time in s); with ``Multi`` every channel is preceded by
its own X column. A trailing ``Comment`` column may hold text or nothing.
"""

from __future__ import annotations

import io
import re
import warnings
from datetime import datetime
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from ..errors import DataRepairWarning, FormatError, ParameterError
from ._build import assemble, clean_attrs
from ._model import build_time_history, fs_from_dt, infer_quantity, normalize_units

__all__ = ["read_lvm", "sniff_lvm", "LVM_EXTENSIONS"]

LVM_EXTENSIONS = (".lvm",)
MAGIC = "LabVIEW Measurement"
END = "***End_of_Header***"
_SEPARATORS = {"tab": "\t", "comma": ",", "semicolon": ";", "space": " "}
_SEGMENT_KEYS = {
    "channels",
    "samples",
    "date",
    "time",
    "y_unit_label",
    "x_dimension",
    "x0",
    "delta_x",
    "notes",
    "test_name",
    "test_numbers",
    "test_series",
    "uut_serial_number",
    "uut_part_number",
    "uut_name",
}
_NUM = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def sniff_lvm(head: bytes) -> bool:
    """True when the file starts with the ``LabVIEW Measurement`` identifier."""
    if head.startswith(b"\xef\xbb\xbf"):
        head = head[3:]
    return head.lstrip(b" \t\r\n").startswith(MAGIC.encode())


def _decode(raw: bytes, encoding: str | None, path: Path) -> str:
    if raw.startswith(b"\xef\xbb\xbf"):
        raw = raw[3:]
    if encoding is not None:
        try:
            return raw.decode(encoding)
        except UnicodeDecodeError as err:
            line = raw[: err.start].count(b"\n") + 1
            raise FormatError(
                f"{path}, line {line}: byte {raw[err.start : err.start + 1]!r} is not valid "
                f"{encoding}; expected {encoding} text"
            ) from err
        except LookupError as err:
            raise ParameterError(f"read({path}): unknown encoding {encoding!r}") from err
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        return raw.decode("cp1252", errors="replace")  # LabVIEW writes the Windows code page


def _key(text: str) -> str:
    return re.sub(r"[^0-9a-z_]+", "_", text.strip().lower()).strip("_")


def _number(token: str, decimal: str, what: str, path: Path, line_no: int) -> float:
    t = token.strip()
    other = "." if decimal == "," else ","
    if decimal == ",":
        t = t.replace(",", ".")
    if other in token or not (_NUM.match(t) or t.lower() in ("nan", "inf", "-inf", "+inf")):
        raise FormatError(
            f"{path}, line {line_no}: {what} = {token!r} is not a number; expected a value "
            f"with decimal separator {decimal!r}"
        )
    return float(t)


class _Lines:
    """The lines of a UTF-8 buffer, decoded on demand; vectorised line and field scans."""

    def __init__(self, buf: bytes):
        self.buf = buf
        arr = np.frombuffer(buf, dtype=np.uint8)
        nl = np.flatnonzero(arr == 10)
        ends = np.append(nl, len(buf))
        starts = np.concatenate(([0], nl + 1))
        if len(buf) and buf.endswith(b"\n"):  # no empty line after the last newline
            ends, starts = ends[:-1], starts[:-1]
        self.starts, self.ends = starts, ends
        first = np.full(len(starts), 10, dtype=np.uint8)  # first byte (10 when empty)
        inside = starts < len(arr)
        first[inside] = arr[starts[inside]]
        alpha = ((first >= 65) & (first <= 90)) | ((first >= 97) & (first <= 122))
        self.alpha = np.flatnonzero(alpha)  # lines that may start a segment header
        self._arr = arr

    def __len__(self) -> int:
        return len(self.starts)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        return self.buf[self.starts[i] : self.ends[i]].decode("utf-8")

    def next_alpha(self, i: int) -> np.ndarray:
        """Indices >= i of lines starting with an ASCII letter."""
        return self.alpha[np.searchsorted(self.alpha, i) :]

    def sep_counts(self, first: int, stop: int, sep: str) -> np.ndarray:
        """Number of separators on each line of [first, stop)."""
        if len(sep.encode("utf-8")) != 1:
            return np.fromiter((self[i].count(sep) for i in range(first, stop)), np.int64)
        if stop <= first:
            return np.zeros(0, dtype=np.int64)
        lo, hi = int(self.starts[first]), int(self.ends[stop - 1])
        pos = np.flatnonzero(self._arr[lo:hi] == ord(sep)) + lo
        return np.searchsorted(pos, self.ends[first:stop]) - np.searchsorted(
            pos, self.starts[first:stop]
        )

    def text(self, first: int, stop: int) -> str:
        """Lines [first, stop) joined by newlines."""
        if stop <= first:
            return ""
        return self.buf[self.starts[first] : self.ends[stop - 1]].decode("utf-8")


class _Segment:
    """Header values, column names and the data-line range of one segment."""

    def __init__(self, index: int):
        self.index = index
        self.header: dict[str, tuple[int, list[str]]] = {}  # key -> (line number, values)
        self.names_line: int | None = None
        self.names: list[str] | None = None
        self.first = self.stop = 0  # data lines [first, stop) as 0-based line indices


def _split_header(lines: _Lines, path: Path, sep: str):
    """File header dict and the list of segments with their line ranges."""
    file_header: dict[str, tuple[int, list[str]]] = {}
    n = len(lines)
    i = 0
    while i < n and not lines[i].strip():
        i += 1
    if i == n or not lines[i].strip().startswith(MAGIC):
        raise FormatError(f"{path}, line {i + 1}: expected the '{MAGIC}' identifier line")
    i += 1
    while i < n and not lines[i].startswith(END):
        fields = lines[i].split(sep)
        if fields[0].strip():
            file_header[_key(fields[0])] = (i + 1, [f.strip() for f in fields[1:]])
        i += 1
    if i == n:
        raise FormatError(
            f"{path}: the file header (line 1) has no '{END}' line; expected the header to end "
            "with it before the data"
        )
    i += 1
    segments: list[_Segment] = []
    while True:
        while i < n and not lines[i].strip(sep + " \r"):
            i += 1
        if i == n:
            break
        seg = _Segment(len(segments) + 1)
        head_start = i
        # segment header: key lines up to the next END marker (when the block starts
        # with a known segment key; LVM files may also hold data without segment header)
        if _key(lines[i].split(sep)[0]) in _SEGMENT_KEYS:
            while i < n and not lines[i].startswith(END):
                fields = lines[i].split(sep)
                key = _key(fields[0])
                if key and key not in seg.header:
                    seg.header[key] = (i + 1, [f.strip() for f in fields[1:]])
                i += 1
            if i == n:
                raise FormatError(
                    f"{path}, line {head_start + 1}: segment {seg.index} header has no "
                    f"'{END}' line; expected the segment header to end with it"
                )
            i += 1
        while i < n and not lines[i].strip(sep + " \r"):
            i += 1
        if i < n and lines[i].split(sep)[0].strip().lower() == "x_value":
            seg.names_line = i + 1
            seg.names = [f.strip() for f in lines[i].split(sep)]
            i += 1
        seg.first = i
        i = n
        for k in lines.next_alpha(seg.first):  # data lines start with a number or a separator
            if _key(lines[int(k)].split(sep, 1)[0]) in _SEGMENT_KEYS:
                i = int(k)
                break
        seg.stop = i
        while seg.stop > seg.first and not lines[seg.stop - 1].strip(sep + " \r"):
            seg.stop -= 1
        segments.append(seg)
    if not segments:
        raise FormatError(f"{path}: no data after the file header; expected at least one segment")
    return file_header, segments


def _per_channel(seg: _Segment, key: str, n_ch: int, path: Path) -> tuple[int, list[str]] | None:
    if key not in seg.header:
        return None
    line_no, values = seg.header[key]
    values = [v for v in values if v != ""]
    if len(values) == 1 and n_ch > 1:
        values = values * n_ch  # Multi_Headings No: one value for every channel
    if len(values) != n_ch:
        raise FormatError(
            f"{path}, line {line_no}: {key} has {len(values)} values; expected {n_ch} "
            "(one per channel)"
        )
    return line_no, values


def _layout(seg: _Segment, x_columns: str, n_fields_first: int, path: Path):
    """Column positions: (x positions, y positions, channel names, has comment column)."""
    if seg.names is not None:
        names = list(seg.names)
        comment = bool(names) and names[-1].strip().lower() == "comment"
        if comment:
            names = names[:-1]
        while names and names[-1] == "" and len(names) > 1:
            names = names[:-1]
        xpos = [k for k, nm in enumerate(names) if nm.lower() == "x_value"]
        ypos = [k for k, nm in enumerate(names) if nm.lower() != "x_value"]
        ch_names = [names[k] for k in ypos]
        return xpos, ypos, ch_names, comment
    # no column-name line: positions from X_Columns and the channel count
    n_ch = None
    if "channels" in seg.header:
        line_no, vals = seg.header["channels"]
        vals = [v for v in vals if v]
        if not vals or not vals[0].isdigit() or int(vals[0]) < 1:
            raise FormatError(
                f"{path}, line {line_no}: Channels = {vals[0] if vals else ''!r}; expected a "
                "positive integer"
            )
        n_ch = int(vals[0])
    if x_columns == "multi":
        n_ch = n_ch or n_fields_first // 2
        xpos, ypos = list(range(0, 2 * n_ch, 2)), list(range(1, 2 * n_ch, 2))
    elif x_columns == "one":
        n_ch = n_ch or n_fields_first - 1
        xpos, ypos = [0], list(range(1, n_ch + 1))
    else:
        n_ch = n_ch or n_fields_first
        lead = 1 if n_fields_first in (n_ch + 1, n_ch + 2) and n_fields_first > n_ch else 0
        xpos, ypos = ([0] if lead else []), list(range(lead, lead + n_ch))
    names = ["Untitled"] + [f"Untitled {k}" for k in range(1, len(ypos))]
    return xpos, ypos, names, False


def _parse_block(text: str, sep: str, decimal: str, cols: list[int], n_cols: int):
    """float64 array (len(cols), rows) of the given columns, or None if pandas fails."""
    try:
        df = pd.read_csv(
            io.StringIO(text),
            sep=sep,
            decimal=decimal,
            header=None,
            usecols=cols,
            engine="c",
            skip_blank_lines=False,
            dtype={k: np.float64 for k in cols},
            na_values=[""],
            keep_default_na=False,
        )
    except (ValueError, TypeError, pd.errors.ParserError, pd.errors.EmptyDataError):
        return None
    return df[cols].to_numpy(dtype=np.float64).T


def _diagnose(lines, seg, sep, decimal, cols, names, path):
    """Name the first data line whose value cannot be read."""
    for i in range(seg.first, seg.stop):
        fields = lines[i].split(sep)
        for k, name in zip(cols, names):
            tok = fields[k].strip() if k < len(fields) else ""
            if tok == "":
                continue
            _number(tok, decimal, f"column {k + 1} ({name!r})", path, i + 1)
    raise FormatError(f"{path}: segment {seg.index}: data lines could not be parsed")


def read_lvm(
    path: Path,
    *,
    decimal: str | None = None,
    encoding: str | None = None,
    fs: float | None = None,
    units=None,
    quantity=None,
    allow_truncated: bool = False,
):
    """Read a LabVIEW Measurement (``.lvm``) text file.

    Every segment becomes a time history (``channel``, ``time``); segments that continue
    each other (same channels, units and rate, ``X0`` equal to the end of the previous
    segment) are joined into one record, others become ``time_history_2``, ... .

    Parameters
    ----------
    path : pathlib.Path
        The file.
    decimal : {".", ","}, optional
        Decimal separator; default from the ``Decimal_Separator`` header line ("." when
        absent).
    encoding : str, optional
        Text encoding; UTF-8, else the Windows code page LabVIEW writes (cp1252).
    fs : float, optional
        Sampling rate in Hz for segments without ``Delta_X`` and without X values.
    units, quantity : str or sequence of str, optional
        Per-channel units / quantity overriding ``Y_Unit_Label`` (needed when the file
        has none). Units are kept as written (``g`` stays ``g``, quantity acceleration);
        ``Newtons`` / ``Volts`` are spelled ``N`` / ``V``.
    allow_truncated : bool, default False
        Read a segment holding fewer data lines than its ``Samples`` header states (the
        missing samples are not invented) with a ``DataRepairWarning`` instead of raising.

    Returns
    -------
    xarray.Dataset
        ``time_history`` with ``attrs``: ``fs`` (Hz), ``t0_s`` (``X0`` when non-zero),
        ``segment`` (1-based), the segment's ``date``/``time`` when given; Dataset
        ``attrs`` hold the file header (``operator``, ``date``, ``time``,
        ``start_time`` ISO 8601, ``x_columns``, ``decimal_separator``, ``description``...).

    Raises
    ------
    mvtk.errors.FormatError
        Missing identifier or header end, a data line with missing or extra columns, a
        value that is not a number, a channel count or sample count differing from the
        segment header, channels with different ``Delta_X``; the message names the line.
    """
    if decimal is not None and decimal not in (".", ","):
        raise ParameterError(f"read({path}): decimal={decimal!r}; expected '.' or ','")
    if encoding is None and path.stat().st_size >= _WholeFile.MIN_BYTES:
        # large file: the header from the first bytes, the last segment's data parsed
        # straight from the file; anything unusual is read again the line-by-line way
        head = _head_lines(path)
        if head is not None:
            try:
                with warnings.catch_warnings(record=True) as caught:
                    warnings.simplefilter("always")
                    out = _read(path, head, _WholeFile(path, head), decimal, fs, units,
                                quantity, allow_truncated)
            except (_Retry, FormatError):
                pass  # the line-by-line path gives the answer (or names the line)
            else:
                for w in caught:
                    warnings.warn(w.message, w.category, stacklevel=2)
                return out
    raw = path.read_bytes()
    plain = encoding is None and not raw.startswith(b"\xef\xbb\xbf") and b"\r" not in raw
    if plain:
        try:
            raw.decode("utf-8")  # validity only: lines are decoded on demand
        except UnicodeDecodeError:
            plain = False
    if plain:  # the common case: the file's bytes are the buffer
        lines = _Lines(raw)
    else:
        text = _decode(raw, encoding, path).replace("\r\n", "\n")
        if "\r" in text:  # lone carriage returns end lines too
            text = "\n".join(text.splitlines())
        lines = _Lines(text.encode("utf-8"))
        del text
    del raw
    return _read(path, lines, None, decimal, fs, units, quantity, allow_truncated)


def _read(path, lines, whole, decimal, fs, units, quantity, allow_truncated):
    """The records of the file whose (leading) lines are ``lines``; see read_lvm."""
    sep = "\t"
    for ln in lines[:64]:
        if ln.startswith("Separator") and len(ln) > len("Separator"):
            sep = ln[len("Separator")]
            value = ln[len("Separator") + 1 :].strip(sep + " \r")
            named = _SEPARATORS.get(value.lower())
            if named is not None and named != sep:
                sep = named
            break
    file_header, segments = _split_header(lines, path, sep)
    if whole is not None:
        whole.last = segments[-1].index
    fh = {k: [v for v in vals if v != ""] for k, (_, vals) in file_header.items()}
    dec = decimal or (fh.get("decimal_separator") or ["."])[0]
    if dec not in (".", ","):
        line_no = file_header["decimal_separator"][0]
        raise FormatError(
            f"{path}, line {line_no}: Decimal_Separator {dec!r}; expected '.' or ','"
        )
    x_columns = (fh.get("x_columns") or ["No"])[0].lower()
    if x_columns not in ("no", "one", "multi"):
        raise FormatError(
            f"{path}, line {file_header['x_columns'][0]}: X_Columns {x_columns!r}; expected "
            "No, One or Multi"
        )
    attrs: dict = {}
    for key, vals in fh.items():
        if vals:
            attrs[f"header_{key}" if key in ("fs", "t0_s", "source", "format") else key] = (
                " ".join(vals)
            )
    start = _start_time(fh.get("date"), fh.get("time"))
    if start:
        attrs["start_time"] = start

    records = [
        _read_segment(
            lines, seg, sep, dec, x_columns, fs, units, quantity, allow_truncated, path, whole
        )
        for seg in segments
    ]
    if not records:
        raise FormatError(f"{path}: no data lines; expected at least one sample")
    joined: list[dict] = [records[0]]
    for rec in records[1:]:
        prev = joined[-1]
        t_end = prev["t0"] + prev["data"].shape[1] / prev["fs"]
        if (
            rec["names"] == prev["names"]
            and rec["units"] == prev["units"]
            and rec["quantity"] == prev["quantity"]
            and rec["fs"] == prev["fs"]
            and abs(rec["t0"] - t_end) <= 0.01 / rec["fs"]
        ):
            prev["data"] = np.concatenate([prev["data"], rec["data"]], axis=1)
            prev["n_missing"] = prev["n_missing"] + rec["n_missing"]
            prev["segments"].append(rec["segments"][0])
        else:
            joined.append(rec)
    variables = []
    for rec in joined:
        var_attrs = dict(rec["attrs"])
        var_attrs["segment"] = " ".join(str(s) for s in rec["segments"])
        if rec["t0"] != 0.0:
            var_attrs["t0_s"] = rec["t0"]
        if rec["spectrum"]:
            variables.append(_spectrum(rec, var_attrs))
            continue
        variables.append(
            build_time_history(
                rec["data"],
                rec["fs"],
                rec["names"],
                rec["units"],
                rec["quantity"],
                attrs=clean_attrs(var_attrs),
                n_missing=rec["n_missing"],
            )
        )
    return assemble(variables, clean_attrs(attrs))


def _spectrum(rec: dict, var_attrs: dict) -> xr.DataArray:
    n = rec["data"].shape[1]
    f = rec["t0"] + np.arange(n) / rec["fs"]
    var_attrs.pop("t0_s", None)
    var_attrs["x_dimension"] = rec["x_dimension"]
    da = xr.DataArray(
        rec["data"],
        dims=("channel", "frequency"),
        coords={
            "channel": np.array(rec["names"], dtype=object),
            "frequency": f,
            "units": ("channel", np.array(rec["units"], dtype=object)),
            "quantity": ("channel", np.array(rec["quantity"], dtype=object)),
        },
        name="spectrum",
        attrs=clean_attrs({**var_attrs, "spectrum_type": "linear"}),
    )
    da.frequency.attrs["units"] = "Hz"
    return da


def _start_time(date, time) -> str | None:
    if not date:
        return None
    try:
        day = datetime.strptime(date[0], "%Y/%m/%d")
    except ValueError:
        return None
    if not time:
        return day.date().isoformat()
    m = re.match(r"^(\d{1,2}):(\d{2}):(\d{2})(?:[.,](\d+))?$", time[0])
    if m is None:
        return day.date().isoformat()
    frac = (m.group(4) or "0")[:6].ljust(6, "0")
    try:
        stamp = day.replace(
            hour=int(m.group(1)), minute=int(m.group(2)), second=int(m.group(3)),
            microsecond=int(frac),
        )
    except ValueError:
        return day.date().isoformat()
    return stamp.isoformat()


class _Retry(Exception):
    """The fast path of a large file does not apply: read it line by line."""


#: Bytes read for the header of a large file (its data start within them).
_HEAD_BYTES = 1 << 18


def _head_lines(path: Path):
    """The complete lines of the file's first bytes when they are plain UTF-8 with ``\\n``
    line ends (None otherwise: the line-by-line path decodes and normalises)."""
    with open(path, "rb") as fh:
        head = fh.read(_HEAD_BYTES)
    if head.startswith(b"\xef\xbb\xbf") or b"\r" in head:
        return None
    if len(head) == _HEAD_BYTES:
        head = head[: head.rfind(b"\n") + 1]
    try:
        head.decode("utf-8")
    except UnicodeDecodeError:
        return None
    return _Lines(head) if head else None


class _WholeFile:
    """A large file whose last segment's data run from within its first bytes to its end:
    pandas' C reader parses them straight from the file, in parallel chunks, into one
    array (``_text.read_columns``); the line-by-line path reads files that do not fit this.
    """

    MIN_BYTES = 5 * 2**20

    def __init__(self, path: Path, head: _Lines):
        self.path = path
        self.head = head
        self.last = None  # index of the last segment, set when the header is split

    def parse(self, seg, sep: str, dec: str, n_cols: int, cols: list[int], rows_hint=None):
        """``(columns cols, rows)`` float64 array of the segment's data and the NaN count
        per column, with ``seg.stop`` set; None for a segment inside the first bytes."""
        from ._text import read_columns

        if seg.index != self.last:
            return None
        if seg.first >= len(self.head):
            raise _Retry
        got = read_columns(
            self.path,
            int(self.head.starts[seg.first]),
            n_cols,
            cols,
            # every line is a row (a blank one gives NaN: the line-by-line path names
            # it); quotes are not special in LVM files
            dict(sep=sep, decimal=dec, na_values=[""], keep_default_na=False,
                 skip_blank_lines=False, encoding="utf-8", quoting=3),
            extra="ignore",
            rows_hint=rows_hint,
        )
        if got is None:
            raise _Retry
        arr, n_rows, nans = got
        seg.stop = seg.first + n_rows
        return arr, nans


def _declared_rows(seg) -> int | None:
    """The largest ``Samples`` value of the segment header (None when absent or unreadable;
    the header check names a bad value)."""
    try:
        return max(int(v) for v in seg.header["samples"][1] if v != "")
    except (KeyError, ValueError):
        return None


def _read_segment(
    lines, seg, sep, dec, x_columns, fs, units, quantity, allow_truncated, path, whole
):
    where = f"{path}, segment {seg.index}"
    if seg.first >= seg.stop:
        raise FormatError(
            f"{where} (line {seg.first + 1}): no data lines; expected at least one sample"
        )
    first_fields = lines[seg.first].split(sep)
    xpos, ypos, names, comment = _layout(seg, x_columns, len(first_fields), path)
    n_ch = len(ypos)
    if n_ch == 0:
        raise FormatError(
            f"{path}, line {seg.names_line}: no channel columns; expected X_Value and at least "
            "one channel name"
        )
    if "channels" in seg.header:
        line_no, vals = seg.header["channels"]
        vals = [v for v in vals if v]
        if not vals or not vals[0].isdigit() or int(vals[0]) != n_ch:
            raise FormatError(
                f"{path}, line {line_no}: Channels = {vals[0] if vals else ''!r} but the column "
                f"names (line {seg.names_line}) list {n_ch} channels ({', '.join(names)}); "
                "expected the same count"
            )
    seen: dict[str, int] = {}
    for k, nm in enumerate(names):
        if not nm:
            raise FormatError(
                f"{path}, line {seg.names_line}: channel column {ypos[k] + 1} has an empty "
                "name; expected a channel name"
            )
        if nm in seen:
            raise FormatError(
                f"{path}, line {seg.names_line}: duplicate channel name {nm!r} in columns "
                f"{ypos[seen[nm]] + 1} and {ypos[k] + 1}; expected unique names"
            )
        seen[nm] = k
    n_cols = max(xpos + ypos) + 1
    cols = sorted(xpos + ypos)
    col_names = ["X_Value" if k in xpos else names[ypos.index(k)] for k in cols]
    y_rows = [cols.index(k) for k in ypos]
    # fast path for large files: one pandas pass over the file; accepted only when every
    # line was complete (a short line or a gap gives NaN: the checks below name the line)
    arr = n_missing = None
    if whole is not None:
        got = whole.parse(seg, sep, dec, n_cols, cols, _declared_rows(seg))
        if got is not None:
            arr, nans = got
            n_missing = nans[y_rows]
            if n_missing.any():
                raise _Retry
    if arr is None:
        # every data line has n_cols fields, or one more (Comment text / trailing separator)
        counts = lines.sep_counts(seg.first, seg.stop, sep)
        bad = np.flatnonzero((counts != n_cols - 1) & (counts != n_cols))
        if bad.size:
            i = seg.first + int(bad[0])
            got = int(counts[bad[0]]) + 1
            layout = ", ".join(
                ["X_Value" if k in xpos else names[ypos.index(k)] for k in range(n_cols)]
            )
            raise FormatError(
                f"{path}, line {i + 1}: {got} fields; expected {n_cols} ({layout})"
                + (" plus an optional Comment" if comment else "")
                + f" as in segment {seg.index}"
                + (f" (column names at line {seg.names_line})" if seg.names_line else "")
                + ("; missing columns" if got < n_cols else "; extra columns")
            )
        if (counts == n_cols).any():  # some lines carry a Comment (or a trailing separator)
            block = lines[seg.first : seg.stop]
            block = [ln.rsplit(sep, 1)[0] if c == n_cols else ln for ln, c in zip(block, counts)]
            block_text = "\n".join(block)
        else:
            block_text = lines.text(seg.first, seg.stop)
        arr = _parse_block(block_text, sep, dec, cols, n_cols)
    if arr is None or arr.shape[1] != seg.stop - seg.first:
        _diagnose(lines, seg, sep, dec, cols, col_names, path)
    if y_rows == list(range(y_rows[0], y_rows[0] + n_ch)):
        data = arr[y_rows[0] : y_rows[0] + n_ch]  # a view: no copy of a large block
    else:
        data = arr[y_rows]
    rows = [cols.index(k) for k in xpos]
    if not rows:
        xs = np.empty((0, data.shape[1]))
    elif rows == list(range(rows[0], rows[0] + len(rows))):
        # a view: the copy took 60 ms per channel of a 10-minute 10 kHz record
        xs = arr[rows[0] : rows[0] + len(rows)]
    else:
        xs = arr[rows]
    if n_missing is None:
        n_missing = np.isnan(data).sum(axis=1)
    n = data.shape[1]

    # samples declared
    samples = _per_channel(seg, "samples", n_ch, path)
    if samples is not None:
        line_no, vals = samples
        try:
            declared = [int(v) for v in vals]
        except ValueError as err:
            raise FormatError(
                f"{path}, line {line_no}: Samples {vals}; expected integers"
            ) from err
        top = max(declared)
        if top != n:
            msg = (
                f"{path}, line {line_no}: segment {seg.index} header says {top} samples but "
                f"lines {seg.first + 1}..{seg.stop} hold {n} data lines"
            )
            if n < top and allow_truncated:
                warnings.warn(msg + "; read the samples present", DataRepairWarning, stacklevel=4)
            elif n < top:
                raise FormatError(
                    msg + "; truncated file? pass allow_truncated=True to read what is present"
                )
            else:
                raise FormatError(msg + "; expected the declared count")
        for k, d in enumerate(declared):  # shorter channels: empty cells beyond their end
            if d < n and np.isfinite(data[k, d:]).any():
                raise FormatError(
                    f"{path}, line {line_no}: channel {names[k]!r} declares {d} samples but "
                    f"has values beyond line {seg.first + d}; expected empty cells there"
                )

    # x axis: Delta_X / X0 from the header, else from the X column
    x_dim = "Time"
    dims = _per_channel(seg, "x_dimension", n_ch, path)
    if dims is not None:
        if len(set(dims[1])) > 1:
            raise FormatError(
                f"{path}, line {dims[0]}: channels have X dimensions {dims[1]}; expected one"
            )
        x_dim = dims[1][0]
    spectrum = x_dim.strip().lower() not in ("time", "")
    rate = t0 = None
    dx = _per_channel(seg, "delta_x", n_ch, path)
    if dx is not None:
        line_no, vals = dx
        steps = [_number(v, dec, "Delta_X", path, line_no) for v in vals]
        if any(not np.isfinite(s) or s <= 0 for s in steps):
            raise FormatError(
                f"{path}, line {line_no}: Delta_X {vals}; expected positive sample intervals"
            )
        if max(steps) - min(steps) > 1e-9 * max(steps):
            raise FormatError(
                f"{path}, line {line_no}: channels have different Delta_X {vals}; expected one "
                "sampling interval per segment (read channels of other rates separately)"
            )
        rate = fs_from_dt(steps[0]) if not spectrum else 1.0 / steps[0]
    x0 = _per_channel(seg, "x0", n_ch, path)
    if x0 is not None:
        line_no, vals = x0
        starts = [_number(v, dec, "X0", path, line_no) for v in vals]
        if len(set(starts)) > 1:
            raise FormatError(
                f"{path}, line {line_no}: channels start at different X0 {vals}; expected one "
                "start per segment"
            )
        t0 = starts[0]
    if xs.shape[0] and np.isfinite(xs).any():
        xs_ok = xs[:, np.isfinite(xs).all(axis=0)]
        if not np.isfinite(xs).all():
            i = int(np.flatnonzero(~np.isfinite(xs).all(axis=0))[0])
            raise FormatError(
                f"{path}, line {seg.first + i + 1}: X value missing; expected an X value on "
                f"every line (X_Columns {x_columns})"
            )
        if xs.shape[0] > 1:
            scale = np.abs(xs_ok).max() + 1.0
            diff = np.abs(xs - xs[0]).max(axis=1)
            k = int(np.argmax(diff))
            if diff[k] > 1e-9 * scale:
                i = int(np.argmax(np.abs(xs[k] - xs[0])))
                raise FormatError(
                    f"{path}, line {seg.first + i + 1}: the X columns of the channels differ "
                    f"({xs[0, i]!r} vs {xs[k, i]!r}); expected one time base per segment"
                )
        x = xs[0]
        if n > 1:
            d = np.diff(x)
            step = (x[-1] - x[0]) / (n - 1)
            tol = 0.01 * abs(step) + 8 * np.finfo(float).eps * (np.abs(x).max())
            badx = np.flatnonzero((d <= 0) | (np.abs(d - step) > tol))
            if badx.size:
                i = int(badx[0]) + 1
                raise FormatError(
                    f"{path}, line {seg.first + i + 1}: X value {x[i]!r} after {x[i - 1]!r}; "
                    "expected uniformly increasing X values"
                )
            if rate is None:
                rate = fs_from_dt(step) if not spectrum else 1.0 / step
            elif abs(step * rate - 1.0) > 0.01:
                raise FormatError(
                    f"{path}, segment {seg.index}: X values step by {step!r} but Delta_X is "
                    f"{1.0 / rate!r}; expected the same interval"
                )
        if t0 is None:
            t0 = float(x[0])
    elif xs.shape[0] and x_columns != "no":
        raise FormatError(
            f"{path}, line {seg.first + 1}: X column empty but X_Columns is "
            f"{x_columns.capitalize()}; expected X values"
        )
    if rate is None:
        if fs is None:
            raise FormatError(
                f"{where}: no Delta_X in the segment header and no X values; expected a "
                "sampling interval, or pass fs=<Hz>"
            )
        rate = float(fs)
    elif fs is not None and not np.isclose(float(fs), rate, rtol=1e-6):
        raise FormatError(f"{where}: Delta_X gives {rate} Hz but fs={fs} was passed")

    # units and quantities
    if units is not None:
        u_list = [units] * n_ch if isinstance(units, str) else list(units)
        if len(u_list) != n_ch:
            raise ParameterError(
                f"read({path}): units has {len(u_list)} entries; expected {n_ch} (one per "
                "channel)"
            )
    else:
        labels = _per_channel(seg, "y_unit_label", n_ch, path)
        if labels is None:
            raise FormatError(
                f"{where}: no Y_Unit_Label line; the channels {names} have no units; expected "
                "a Y_Unit_Label header line or units=[...]"
            )
        u_list = labels[1]
    u_list = [normalize_units(str(u)) for u in u_list]
    if quantity is None:
        q_list = [infer_quantity(u) for u in u_list]
    else:
        q_list = [quantity] * n_ch if isinstance(quantity, str) else [str(q) for q in quantity]
        if len(q_list) != n_ch:
            raise ParameterError(
                f"read({path}): quantity has {len(q_list)} entries; expected {n_ch}"
            )
    seg_attrs = {}
    for key in ("date", "time", "notes"):
        got = _per_channel(seg, key, n_ch, path) if key in seg.header else None
        if got is not None and len(set(got[1])) == 1:
            seg_attrs[f"segment_{key}"] = got[1][0]
    return {
        "names": names,
        "units": u_list,
        "quantity": q_list,
        "fs": float(rate),
        "t0": float(t0 or 0.0),
        "data": data,
        "n_missing": n_missing,
        "segments": [seg.index],
        "attrs": seg_attrs,
        "spectrum": spectrum,
        "x_dimension": x_dim,
    }
