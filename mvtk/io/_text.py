"""CSV / TSV / whitespace text exports of DAQ systems.

Layout understood (all parts but the data optional)::

    # Instrument: XYZ DAQ            <- metadata lines ``key: value``, ``key = value``
    Sample rate: 10 kHz              <- or ``key<delimiter>value``; '#', '%', '//' prefixes ok
    Time [s], acc1 [m/s^2], F (N)    <- column names, units in [] or ()
    s, m/s^2, N                      <- or a separate units row
    0.0000, 0.12, 3.4                <- numeric data, delimiter , ; tab or blanks,
    ...                                 decimal point or decimal comma

A time column (named time, t, zeit, timestamp; units s, ms or us) or a sampling-rate
header (``sample rate``, ``sampling rate``, ``fs`` in Hz/kHz, or ``dt`` / ``sample
interval`` in s/ms) gives the time axis. Metadata rows ``units:``, ``quantity:``,
``node:`` and ``direction:`` with one value per channel are understood too.

A file of one column of complex numbers written as ``(re+imj)`` (no header) is read as
a spectrum when ``df_hz`` is given.
"""

from __future__ import annotations

import io
import mmap
import os
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd

from ..errors import FormatError, MvtkWarning, ParameterError
from ._build import assemble, clean_attrs
from ._model import build_time_history, fs_from_dt, normalize_units, split_name_units

__all__ = ["read_text", "sniff_text", "check_time_stamps", "TEXT_EXTENSIONS"]

TEXT_EXTENSIONS = (".csv", ".tsv", ".txt", ".dat", ".asc", ".prn")
_HEAD_BYTES = 1 << 18
_NA_TOKENS = [  # pandas' default missing-value markers
    "",
    "#N/A",
    "#N/A N/A",
    "#NA",
    "-1.#IND",
    "-1.#QNAN",
    "-NaN",
    "-nan",
    "1.#IND",
    "1.#QNAN",
    "<NA>",
    "N/A",
    "NA",
    "NULL",
    "NaN",
    "None",
    "n/a",
    "nan",
    "null",
]
_NA_SET = frozenset(_NA_TOKENS)
_TIME_NAMES = {"time", "t", "zeit", "timestamp", "time_s", "tiempo", "temps", "x_time"}
_TIME_SCALE = {"s": 1.0, "sec": 1.0, "seconds": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6}
_FS_KEYS = {
    "fs",
    "sample_rate",
    "sampling_rate",
    "samplerate",
    "sampling_frequency",
    "sample_frequency",
    "sample_rate_hz",
    "sampling_rate_hz",
    "scan_rate",
    "rate",
}
_DT_KEYS = {"dt", "sample_interval", "sampling_interval", "delta_t", "time_step", "increment"}
_CHANNEL_KEYS = {
    "units": "units",
    "unit": "units",
    "quantity": "quantity",
    "quantities": "quantity",
    "node": "node",
    "nodes": "node",
    "direction": "direction",
    "directions": "direction",
}
_LAYOUT_LINES = 400  # header + first data lines examined for the layout
_DELIMS = (",", ";", "\t", None)  # None = runs of blanks
_NUM = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")


def sniff_text(head: bytes) -> bool:
    """True when the first bytes look like a text export (no NUL, mostly printable)."""
    if b"\x00" in head:
        return False
    sample = head[:4096]
    printable = sum(32 <= b < 127 or b in (9, 10, 13) for b in sample)
    return printable >= 0.95 * len(sample)


def _split(line: str, delim: str | None) -> list[str]:
    if delim is None:
        return line.split()
    return [f.strip() for f in line.split(delim)]


def _is_number(token: str, decimal: str) -> bool:
    if decimal == ",":
        token = token.replace(",", ".")
    return bool(_NUM.match(token)) or token.lower() in ("nan", "inf", "-inf", "+inf")


def _numeric_fields(line: str, delim: str | None, decimal: str) -> int:
    """Field count when every field is a number or a missing-value token, else 0."""
    fields = _split(line, delim)
    if not fields or all(f in _NA_SET for f in fields):
        return 0
    for f in fields:
        if f not in _NA_SET and not _is_number(f, decimal):
            return 0
    return len(fields)


def _find_layout(lines: list[str]) -> tuple[int, str | None, str, int] | None:
    """(first data line, delimiter, decimal, n fields) of the best-fitting layout.

    The data start at the first numeric line followed by another numeric line (or by
    nothing); the field count is the most common one among the next six data lines.
    """
    best = None
    non_empty = [i for i, ln in enumerate(lines) if ln.strip()][:_LAYOUT_LINES]
    for delim in _DELIMS:
        for decimal in (".", ","):
            if decimal == "," and delim == ",":
                continue
            counts = {}
            for pos, i in enumerate(non_empty):
                k = counts.setdefault(i, _numeric_fields(lines[i], delim, decimal))
                if k == 0:
                    continue
                nxt = non_empty[pos + 1] if pos + 1 < len(non_empty) else None
                if nxt is not None and _numeric_fields(lines[nxt], delim, decimal) == 0:
                    continue
                window = [
                    _numeric_fields(lines[j], delim, decimal) for j in non_empty[pos : pos + 6]
                ]
                window = [w for w in window if w]
                n_fields = max(set(window), key=lambda w: (window.count(w), w))
                cand = (i, -n_fields, delim, decimal)
                if best is None or cand[:2] < best[:2]:
                    best = cand
                break
    if best is None:
        return None
    return best[0], best[2], best[3], -best[1]


def _metadata(line: str, delim: str | None) -> tuple[str, str] | None:
    text = line.strip().lstrip("#%/").strip()
    if not text:
        return None
    m = re.match(r"^([^:=]+?)\s*[:=]\s*(.*)$", text)
    if m is None and delim is not None and delim in text:
        key, _, value = text.partition(delim)
        m_key, m_val = key.strip(), value.strip()
    elif m is not None:
        m_key, m_val = m.group(1), m.group(2)
    else:
        return None
    key = re.sub(r"[^0-9a-zA-Z_]+", "_", m_key.strip().lower()).strip("_")
    return (key, m_val.strip()) if key else None


def _parse_rate(value: str, key: str, path: Path, line_no: int) -> float:
    m = re.match(r"^\s*([+-]?[\d.,eE+-]+)\s*([a-zA-Zµ/]*)\s*$", value)
    if m is None:
        raise FormatError(
            f"{path}, line {line_no}: {key} = {value!r} is not a number; expected e.g. "
            "'10000', '10 kHz' or '1e-4 s'"
        )
    try:
        number = float(m.group(1).replace(",", "."))
    except ValueError as err:
        raise FormatError(f"{path}, line {line_no}: {key} = {value!r} is not a number") from err
    unit = m.group(2).lower()
    if key in _DT_KEYS:
        scale = {"": 1.0, "s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6}.get(unit)
        if scale is None or number <= 0:
            raise FormatError(
                f"{path}, line {line_no}: sample interval {value!r}; expected a positive number "
                "in s, ms or us"
            )
        return fs_from_dt(number * scale)
    scale = {"": 1.0, "hz": 1.0, "khz": 1e3, "s/s": 1.0, "sps": 1.0, "mhz": 1e6}.get(unit)
    if scale is None or number <= 0:
        raise FormatError(
            f"{path}, line {line_no}: sampling rate {value!r}; expected a positive number in "
            "Hz or kHz"
        )
    return number * scale


def _decode_head(raw: bytes, encoding: str, path: Path) -> list[str]:
    if raw.startswith(b"\xef\xbb\xbf"):  # UTF-8 byte-order mark (Excel exports)
        raw = raw[3:]
    lines = raw.splitlines()
    out = []
    for i, b in enumerate(lines):
        try:
            out.append(b.decode(encoding))
        except UnicodeDecodeError as err:
            bad = b[err.start : err.start + 1]
            raise FormatError(
                f"{path}, line {i + 1}: byte {bad!r} at column {err.start + 1} is not valid "
                f"{encoding}; expected {encoding} text (pass encoding='latin-1' or the "
                "encoding the file was written with)"
            ) from err
    return out


def _read_complex_column(path: Path, lines: list[str], df_hz, channels, units) -> list:
    import xarray as xr

    if df_hz is None:
        raise FormatError(
            f"{path}: one column of complex values and no frequency column; expected "
            "df_hz=<line spacing in Hz> (and optionally f0_hz) to place the lines"
        )
    values = []
    for i, line in enumerate(lines):
        s = line.strip()
        if not s:
            continue
        try:
            values.append(complex(s.replace(" ", "")))
        except ValueError as err:
            raise FormatError(
                f"{path}, line {i + 1}: {s!r} is not a complex number; expected '(re+imj)'"
            ) from err
    name = channels[0] if channels else path.stem
    f = np.arange(len(values)) * float(df_hz)
    da = xr.DataArray(
        np.asarray(values, dtype=np.complex128)[np.newaxis, :],
        dims=("channel", "frequency"),
        coords={"channel": np.array([name], dtype=object), "frequency": f},
        name="spectrum",
        attrs={"units": units if isinstance(units, str) else "unspecified"},
    )
    da.frequency.attrs["units"] = "Hz"
    return [da]


def _diagnose(path: Path, start: int, delim, decimal: str, names: list[str], trailing: bool):
    """Slow scan that names the first bad line; returns per-column counts of NA tokens."""
    n_fields = len(names)
    na_counts = np.zeros(n_fields, dtype=np.int64)
    with open(path, "rb") as fh:
        for line_no, raw in enumerate(fh, start=1):
            if line_no <= start:
                continue
            line = raw.decode("latin-1").rstrip("\r\n")
            if not line.strip():
                continue
            fields = _split(line, delim)
            if trailing and len(fields) == n_fields + 1 and fields[-1] == "":
                fields = fields[:-1]
            if len(fields) != n_fields:
                raise FormatError(
                    f"{path}, line {line_no}: {len(fields)} fields; expected {n_fields} "
                    f"({', '.join(names)}) as in the header (ragged row)"
                )
            for k, token in enumerate(fields):
                if token in _NA_SET:
                    na_counts[k] += 1
                elif not _is_number(token, decimal):
                    raise FormatError(
                        f"{path}, line {line_no}, column {k + 1} ({names[k]!r}): {token!r} is "
                        "not a number; expected a numeric value or a missing-value marker "
                        "(empty, NaN, NA)"
                    )
    return na_counts


def check_time_stamps(t: np.ndarray, path: Path, first_line: int, unit: str = "line") -> float:
    """Sampling rate in Hz from strictly increasing, uniform (1 %) time stamps in s.

    Errors name ``f"{path}, {unit} {first_line + i}"`` for the first bad stamp ``i``.
    """
    n = t.size
    if n < 2:
        raise FormatError(f"{path}: one data line only; expected at least two time stamps")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise FormatError(
            f"{path}, {unit} {first_line + i}: time stamp missing; expected a finite time in s"
        )
    d = np.diff(t)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0]) + 1
        raise FormatError(
            f"{path}, {unit} {first_line + i}: time {t[i].item()!r} s is not after the previous "
            f"{t[i - 1].item()!r} s; expected strictly increasing time stamps"
        )
    dt = np.median(d)
    bad = np.flatnonzero(np.abs(d - dt) > 0.01 * dt)
    if bad.size:
        i = int(bad[0]) + 1
        raise FormatError(
            f"{path}, {unit} {first_line + i}: time step {d[i - 1].item()!r} s before time "
            f"{t[i].item()!r} s; "
            f"expected a uniform step of {dt.item()!r} s (within 1 %); non-uniform sampling"
        )
    return fs_from_dt((t[-1] - t[0]) / (n - 1))


def _per_channel_option(value, n: int, name: str):
    if value is None:
        return None
    if isinstance(value, str) or np.isscalar(value):
        return [value] * n
    value = list(value)
    if len(value) != n:
        raise ParameterError(
            f"read: {name} has {len(value)} entries; expected {n} (one per channel)"
        )
    return value


def read_text(
    path: Path,
    *,
    delimiter: str | None = None,
    decimal: str | None = None,
    encoding: str = "utf-8",
    fs: float | None = None,
    time_column: str | int | bool | None = None,
    channels=None,
    units=None,
    quantity=None,
    df_hz: float | None = None,
):
    """Read a CSV / TSV / text DAQ export.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    delimiter : str, optional
        Field delimiter (``","``, ``";"``, ``"\\t"`` or ``" "`` for blanks); detected.
    decimal : str, optional
        ``"."`` or ``","``; detected.
    encoding : str, default "utf-8"
        Encoding of the header lines.
    fs : float, optional
        Sampling rate in Hz when the file has neither a time column nor a rate header.
    time_column : str, int or bool, optional
        Name or 0-based index of the time column; False when there is none. Detected
        from the column names when omitted.
    channels : sequence of str, optional
        Channel names (overrides the header; needed when there is no header).
    units, quantity : str or sequence of str, optional
        Per-channel units / quantity overriding the header.
    df_hz : float, optional
        Line spacing in Hz for a headerless column of complex values.
    """
    with open(path, "rb") as fh:
        raw = fh.read(_HEAD_BYTES)
    if not raw.strip():
        raise FormatError(f"{path}: the file holds no data (only blanks); expected a text export")
    if len(raw) == _HEAD_BYTES:
        raw = raw[: raw.rfind(b"\n") + 1] or raw
    lines = _decode_head(raw, encoding, path)
    if delimiter == " ":
        delimiter = None
    layout = _find_layout(lines)
    if layout is None:
        first = next((ln.strip() for ln in lines if ln.strip()), "")
        if first.startswith("(") and first.endswith("j)"):
            with open(path, encoding=encoding) as fh:
                all_lines = fh.read().splitlines()
            return assemble(_read_complex_column(path, all_lines, df_hz, channels, units))
        raise FormatError(
            f"{path}: no numeric data lines found in the first {len(lines)} lines; expected "
            "rows of numbers separated by ',', ';', tab or blanks"
        )
    start, det_delim, det_decimal, n_fields = layout
    delim = det_delim if delimiter is None else delimiter
    dec = det_decimal if decimal is None else decimal
    if delimiter is not None or decimal is not None:
        n_fields = _numeric_fields(lines[start], delim, dec) or n_fields
    data_head = [ln.rstrip("\r\n ") for ln in lines[start : start + 20] if ln.strip()]
    trailing = delim is not None and n_fields > 1 and all(ln.endswith(delim) for ln in data_head)
    if trailing:  # every line ends with the delimiter: an empty last column, dropped
        n_fields -= 1

    def fields_of(line: str) -> list[str]:
        out = _split(line, delim)
        if trailing and len(out) > 1 and out[-1] == "":
            out = out[:-1]
        return out

    # header: metadata lines, column names, units row
    header = [(i, ln) for i, ln in enumerate(lines[:start]) if ln.strip()]
    names_line = units_line = None
    table = [h for h in header if (_metadata(h[1], delim) or ("",))[0] not in _CHANNEL_KEYS]
    if table and len(fields_of(table[-1][1])) == n_fields:
        last = fields_of(table[-1][1])
        prev = fields_of(table[-2][1]) if len(table) > 1 else None
        if prev is not None and len(prev) == n_fields and _looks_like_units(last):
            names_line, units_line = table[-2], table[-1]
        else:
            names_line = table[-1]
    meta_lines = [h for h in header if h not in (names_line, units_line)]
    attrs: dict = {}
    header_fs = None
    per_channel: dict[str, list[str]] = {}
    for i, ln in meta_lines:
        kv = _metadata(ln, delim)
        if kv is None:
            attrs.setdefault("comment", "")
            attrs["comment"] = (attrs["comment"] + "\n" + ln.strip()).strip()
            continue
        key, value = kv
        if key in _FS_KEYS or key in _DT_KEYS:
            rate = _parse_rate(value, key, path, i + 1)
            if header_fs is not None and not np.isclose(rate, header_fs, rtol=1e-9):
                raise FormatError(
                    f"{path}, line {i + 1}: {key} gives {rate} Hz but an earlier header line "
                    f"gives {header_fs} Hz; expected one sampling rate"
                )
            header_fs = rate
        if key in _CHANNEL_KEYS:
            per_channel[_CHANNEL_KEYS[key]] = fields_of(value)
        attrs[f"header_{key}" if key in ("fs", "t0_s", "source", "format") else key] = value

    if names_line is not None:
        raw_names = fields_of(names_line[1])
        header_line_no = names_line[0] + 1
    elif channels is not None:
        raw_names = None
        header_line_no = None
    else:
        raise FormatError(
            f"{path}: no column-name line before the data at line {start + 1}; expected a "
            f"header with {n_fields} names (e.g. 'time [s], acc1 [m/s^2]') or channels=[...]"
        )
    names, col_units = [], []
    if raw_names is not None:
        for label in raw_names:
            name, unit = split_name_units(label)
            names.append(name)
            col_units.append(unit)
    if units_line is not None:
        row = [u.strip().strip("[]()") for u in fields_of(units_line[1])]
        col_units = [u or c for u, c in zip(row, col_units)]

    # time column
    tcol = None
    if time_column is None:
        for k, name in enumerate(names):
            if name.strip().lower() in _TIME_NAMES:
                tcol = k
                break
    elif time_column is False:
        tcol = None
    elif isinstance(time_column, int) and not isinstance(time_column, bool):
        if not 0 <= time_column < n_fields:
            raise ParameterError(
                f"read({path}): time_column={time_column} out of range; the file has "
                f"{n_fields} columns"
            )
        tcol = time_column
    else:
        if time_column not in names:
            raise ParameterError(
                f"read({path}): time_column={time_column!r} not among the columns {names}"
            )
        tcol = names.index(time_column)
    ch_cols = [k for k in range(n_fields) if k != tcol]
    n_ch = len(ch_cols)
    if channels is not None:
        ch_names = [str(c) for c in _per_channel_option(channels, n_ch, "channels")]
        if raw_names is None:
            names = ["time"] * (tcol is not None) + ch_names
            col_units = [None] * n_fields
    else:
        ch_names = [names[k] for k in ch_cols]
    where = f", line {header_line_no}" if header_line_no else ""
    seen: dict[str, int] = {}
    for k, name in zip(ch_cols, ch_names):
        if not name:
            raise FormatError(f"{path}{where}: column {k + 1} has an empty name; expected a name")
        if name in seen:
            raise FormatError(
                f"{path}{where}: duplicate channel name {name!r} in columns {seen[name] + 1} and "
                f"{k + 1}; expected unique channel names"
            )
        seen[name] = k
    opt_units = _per_channel_option(units, n_ch, "units")
    meta_units = per_channel.get("units")
    ch_units = []
    for j, k in enumerate(ch_cols):
        u = opt_units[j] if opt_units is not None else col_units[k] if col_units else None
        if u is None and meta_units is not None:
            u = (
                meta_units[k]
                if len(meta_units) == n_fields
                else (meta_units[j] if len(meta_units) == n_ch else None)
            )
        if u is None or not str(u).strip():
            raise FormatError(
                f"{path}{where}: channel {ch_names[j]!r} (column {k + 1}) has no units; "
                "expected 'name [unit]' in the header, a units row, or units=[...] (--units "
                "on the command line, read_options in a study)"
            )
        ch_units.append(normalize_units(str(u)))
    ch_quantity = _per_channel_option(quantity, n_ch, "quantity")
    if ch_quantity is None and "quantity" in per_channel:
        ch_quantity = _pick(per_channel["quantity"], ch_cols, n_fields, path, "quantity")
    node = per_channel.get("node")
    if node is not None:
        node = _pick(node, ch_cols, n_fields, path, "node")
        try:
            node = [int(x) for x in node]
        except ValueError as err:
            raise FormatError(f"{path}: node row {node}; expected integer node numbers") from err
    direction = per_channel.get("direction")
    if direction is not None:
        direction = _pick(direction, ch_cols, n_fields, path, "direction")

    # numeric block: pandas C parser, chunk by chunk into one preallocated array
    all_names = names if names else [f"column {k + 1}" for k in range(n_fields)]
    block, n_rows, has_nan = _read_block(path, lines, start, delim, dec, n_fields, trailing,
                                         _line_offset(raw, start))
    if block is None:
        _diagnose(path, start, delim, dec, all_names, trailing)
        raise FormatError(
            f"{path}: data block could not be parsed; expected {n_fields} numeric columns"
        )
    if n_rows == 0:
        raise FormatError(f"{path}: no data lines after the header at line {start}")
    arr = block[:, :n_rows]
    n_missing = np.zeros(n_fields, dtype=np.int64)
    if has_nan:
        n_missing = _diagnose(path, start, delim, dec, all_names, trailing)
    t_first_line = start + 1
    if tcol is not None:
        tname, tunit = names[tcol], (col_units[tcol] if col_units else None) or "s"
        scale = _TIME_SCALE.get(tunit.strip().lower())
        if scale is None:
            raise FormatError(
                f"{path}{where}: time column {tname!r} in {tunit!r}; expected s, ms or us"
            )
        t = arr[tcol] * scale
        rate = check_time_stamps(t, path, t_first_line)
        if header_fs is not None and not np.isclose(rate, header_fs, rtol=1e-6):
            raise FormatError(
                f"{path}: the time column gives {rate} Hz but the header gives {header_fs} Hz; "
                "expected the same sampling rate"
            )
        if fs is not None and not np.isclose(rate, fs, rtol=1e-6):
            raise FormatError(f"{path}: the time column gives {rate} Hz but fs={fs} was passed")
        if t[0] != 0.0:
            attrs["t0_s"] = float(t[0])
    else:
        rate = fs if fs is not None else header_fs
        if rate is None:
            raise FormatError(
                f"{path}: no time column and no sampling-rate header; expected a column named "
                "'time' or a header line 'sample rate: <Hz>' (or 'dt: <s>'), or pass fs="
            )
    if ch_cols == list(range(ch_cols[0], ch_cols[0] + n_ch)):
        data = arr[ch_cols[0] : ch_cols[0] + n_ch]
    else:
        data = arr[ch_cols]
    missing = n_missing[ch_cols]
    if missing.any():
        listed = ", ".join(f"{ch_names[j]!r}: {int(m)}" for j, m in enumerate(missing) if m)
        warnings.warn(
            f"{path}: samples marked missing in the file are kept as NaN ({listed}); see "
            "the 'n_missing' coordinate",
            MvtkWarning,
            stacklevel=3,
        )
    da = build_time_history(
        data,
        rate,
        ch_names,
        ch_units,
        ch_quantity,
        node=node,
        direction=direction,
        attrs={"t0_s": attrs.pop("t0_s")} if "t0_s" in attrs else None,
        n_missing=missing,
    )
    return assemble([da], clean_attrs(attrs))


def _read_block(path, lines, start, delim, dec, n_fields, trailing=False, offset=None):
    """Parse the data lines into a (column, row) float64 array.

    Returns ``(block, n_rows, has_nan)``; ``block`` is None when a chunk does not parse
    as ``n_fields`` numeric columns. With ``offset`` (the byte offset of line ``start``,
    known when the head's line ends are plain) the text is parsed in parallel chunks
    (:func:`read_columns`); otherwise, or when that fails, pandas reads it chunk by chunk
    into one array allocated from an estimate of the row count (pages never written are
    never committed). Either way the peak memory stays near one copy of the data.
    """
    options = dict(
        sep=r"\s+" if delim is None else delim,
        decimal=dec,
        encoding="utf-8",
        encoding_errors="replace",
        skip_blank_lines=True,
    )
    if offset is not None:
        got = read_columns(path, offset, n_fields, list(range(n_fields)), options,
                           extra="empty" if trailing else "error")
        if got is not None:
            block, n_rows, nans = got
            return block, n_rows, bool(nans.any())
    head_bytes = sum(len(ln) + 1 for ln in lines[:start])
    sample = [len(ln) + 1 for ln in lines[start:] if ln.strip()]
    avg = max(sum(sample) / max(len(sample), 1), 2.0)
    remaining = max(os.path.getsize(path) - head_bytes, 0)
    cap = int(remaining / avg * 1.05) + 64
    options.update(header=None, skiprows=start, engine="c",
                   usecols=list(range(n_fields)) if trailing else None)
    block = _fresh_array((n_fields, cap))
    chunk_rows = 250_000
    n_rows, has_nan = 0, False
    try:
        reader = pd.read_csv(path, chunksize=chunk_rows, **options)
        with reader:
            for chunk in reader:
                if chunk.shape[1] != n_fields:
                    return None, 0, False
                m = chunk.shape[0]
                if n_rows + m > cap:
                    cap = int((n_rows + m) * 1.25) + 64
                    grown = _fresh_array((n_fields, cap))
                    grown[:, :n_rows] = block[:, :n_rows]
                    block = grown
                for j in range(n_fields):
                    column = chunk.iloc[:, j].to_numpy(dtype=np.float64)
                    block[j, n_rows : n_rows + m] = column
                    has_nan = has_nan or bool(np.isnan(column).any())
                n_rows += m
    except (ValueError, TypeError, pd.errors.ParserError):
        return None, 0, False
    except pd.errors.EmptyDataError:
        return block, 0, False
    return block, n_rows, has_nan


def _line_offset(raw: bytes, start: int) -> int | None:
    """Byte offset of line ``start`` (0-based) in the head ``raw``, when its lines end
    with ``\\n`` or ``\\r\\n`` only (as ``bytes.splitlines`` and pandas count them);
    None otherwise."""
    if raw.count(b"\r") != raw.count(b"\r\n"):
        return None
    pos = 0
    for _ in range(start):
        pos = raw.find(b"\n", pos) + 1
        if pos == 0:
            return None
    return pos


def _pick(values: list[str], ch_cols: list[int], n_fields: int, path: Path, what: str):
    if len(values) == n_fields:
        return [values[k] for k in ch_cols]
    if len(values) == len(ch_cols):
        return values
    raise FormatError(
        f"{path}: the {what} header row has {len(values)} entries; expected {len(ch_cols)} "
        f"(one per channel) or {n_fields} (one per column)"
    )


def _looks_like_units(fields: list[str]) -> bool:
    """True when every non-empty field of a header row reads as a unit."""
    from ._model import UNITS_BY_QUANTITY

    known = {u for group in UNITS_BY_QUANTITY.values() for u in group} | set(_TIME_SCALE)
    ok = 0
    for f in fields:
        f = f.strip().strip("[]()")
        if not f:
            continue
        if normalize_units(f) not in known and "/" not in f and "^" not in f:
            return False
        ok += 1
    return ok > 0


#: Largest number of bytes of text per chunk of the parallel column parser (see
#: read_columns); smaller files are split into four chunks per thread.
CHUNK_BYTES = 16 * 2**20
#: Smallest chunk (below it pandas' per-call cost would show).
MIN_CHUNK_BYTES = 2**20


def parse_workers() -> int:
    """Threads for parsing text: pandas' ``mode.max_threads`` when set, else the CPUs this
    process may use (at most 6, pandas' own default ceiling)."""
    try:
        option = pd.get_option("mode.max_threads")
    except (KeyError, pd.errors.OptionError):
        option = None
    if option:
        return max(int(option), 1)
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        n = os.cpu_count() or 1
    return max(1, min(n, 6))


def _chunk_offsets(fd: int, start: int, size: int, chunk: int) -> list[int]:
    """Byte offsets in [start, size] splitting the text at line ends, about ``chunk`` apart."""
    offsets = [start]
    pos = start + chunk
    while pos < size:
        tail = os.pread(fd, 1 << 16, pos)
        nl = tail.find(b"\n")
        while nl < 0 and tail:  # a very long line: keep looking
            pos += len(tail)
            tail = os.pread(fd, 1 << 16, pos)
            nl = tail.find(b"\n")
        if nl < 0:
            break
        pos += nl + 1
        if pos >= size:
            break
        offsets.append(pos)
        pos += chunk
    offsets.append(size)
    return offsets


def read_columns(
    path: Path,
    start: int,
    n_fields: int,
    keep: list[int],
    options: dict,
    *,
    extra: str = "error",
    rows_hint: int | None = None,
):
    """Parse the numeric text from byte ``start`` to the end of ``path`` in parallel.

    The data are split at line ends into chunks of about ``CHUNK_BYTES``; each chunk is
    parsed by pandas' C reader (which releases the GIL) on a pool of ``parse_workers()``
    threads, and the columns ``keep`` are copied, in file order, into one preallocated
    ``(len(keep), rows)`` float64 array. At most one chunk per thread and one more are in
    flight, so the peak memory is the result plus a few chunks (about one copy of the
    data), where a whole-file parse holds the chunks' frames, their concatenation and its
    copy (3.3x the data measured for ``pandas.read_csv`` on a 16-channel LVM file).

    Parameters
    ----------
    path : pathlib.Path
        The text file (UTF-8 or ASCII bytes from ``start`` on).
    start : int
        Byte offset of the first data line.
    n_fields : int
        Fields per data line.
    keep : list of int
        Field indices returned, in this order.
    options : dict
        ``pandas.read_csv`` options (``sep``, ``decimal``, ``na_values``...); ``header``
        and ``engine`` are set here.
    extra : {"error", "ignore", "empty"}
        What a chunk with one field more than ``n_fields`` means: refused, a comment
        column (ignored) or a trailing delimiter (that column must be empty).
    rows_hint : int, optional
        Expected row count (sizes the result; it grows when exceeded).

    Returns
    -------
    tuple or None
        ``(block, n_rows, nan_counts)``: the ``(len(keep), n_rows)`` array, the row count
        and the number of NaN per kept column; None when a chunk does not parse as
        ``n_fields`` numeric fields per line (the caller's line-by-line path then names
        the line).
    """
    import threading
    from concurrent.futures import ThreadPoolExecutor

    size = os.path.getsize(path)
    # (pandas' low_memory default parses a chunk in cache-sized pieces: 25-30 % less CPU
    # than low_memory=False on 16 MiB chunks, measured)
    opts = {**options, "header": None, "engine": "c"}
    keep = list(keep)
    with open(path, "rb") as fh:
        fd = fh.fileno()
        n_workers = parse_workers()
        # at least 4 chunks per thread, at most CHUNK_BYTES each, and a multiple of the
        # threads so that the last round does not leave threads idle
        rounds = max(4, -(-(size - start) // (n_workers * CHUNK_BYTES)))
        chunk = max(MIN_CHUNK_BYTES, -(-(size - start) // (rounds * n_workers)))
        offsets = _chunk_offsets(fd, start, size, chunk)
        if rows_hint is None:
            sample = os.pread(fd, min(1 << 16, size - start), start)
            per_line = max(len(sample) / max(sample.count(b"\n"), 1), 2.0)
            rows_hint = int((size - start) / per_line * 1.05) + 64
        rows_hint = max(int(rows_hint), 1)
        n_chunks = len(offsets) - 1
        block = _fresh_array((len(keep), rows_hint))
        # a parsed chunk is copied into ``block`` as soon as the rows of every chunk
        # before it are known, by the thread that makes them known: a worker never
        # waits for a slower one (its chunk is parked until then); a chunk beyond the
        # estimated rows is kept and copied after the pool, into a grown array
        state = threading.Lock()
        rows = [-1] * n_chunks           # rows of each parsed chunk
        first = [0] * (n_chunks + 1)     # row offset of each chunk, known for k < known
        known = [0]
        parked: dict[int, list] = {}
        overflow: dict[int, list] = {}

        def parse(k: int):
            lo, hi = offsets[k], offsets[k + 1]
            buf = os.pread(fd, hi - lo, lo)
            got = _parse_chunk(buf, opts, n_fields, keep, extra)
            del buf
            if got is None:
                return None
            columns, nans = got
            with state:
                rows[k] = len(columns[0]) if keep else 0
                parked[k] = columns
                ready = []
                while known[0] < n_chunks and rows[known[0]] >= 0:
                    j = known[0]
                    first[j + 1] = first[j] + rows[j]
                    ready.append((j, parked.pop(j)))
                    known[0] += 1
            for j, cols in ready:
                a, b = first[j], first[j + 1]
                if b > block.shape[1]:
                    overflow[j] = cols
                else:
                    for i, column in enumerate(cols):
                        block[i, a:b] = column
            return nans

        nan_counts = np.zeros(len(keep), dtype=np.int64)
        with ThreadPoolExecutor(max_workers=n_workers) as pool:
            pending = []
            submitted = 0
            while submitted < n_chunks and len(pending) < n_workers + 1:
                pending.append(pool.submit(parse, submitted))
                submitted += 1
            while pending:
                nans = pending.pop(0).result()
                if nans is None:
                    for f in pending:
                        f.cancel()
                    return None
                nan_counts += nans
                if submitted < n_chunks:
                    pending.append(pool.submit(parse, submitted))
                    submitted += 1
    n_rows = first[n_chunks]
    if overflow:
        grown = _fresh_array((len(keep), n_rows))
        grown[:, :block.shape[1]] = block[:, :min(block.shape[1], n_rows)]
        for k, columns in overflow.items():
            for j, column in enumerate(columns):
                grown[j, first[k]:first[k + 1]] = column
        block = grown
    return block[:, :n_rows], n_rows, nan_counts


#: Smallest result (bytes) that :func:`_fresh_array` maps in small pages.
SMALL_PAGES_BYTES = 64 * 2**20


def _fresh_array(shape: tuple[int, int]) -> np.ndarray:
    """An uninitialised float64 array for a parsed record, in the kernel's small pages.

    numpy asks Linux for transparent huge pages on large arrays; where the kernel then
    compacts memory on the first write (``defrag`` = ``madvise``, common), writing a
    fresh 800 MB array cost 0.7-1.0 s of system time against 0.25 s in 4 KiB pages
    (measured on this project's 2-core machine; a 16-channel, 10-minute, 10 kHz LVM
    file read 2.9-3.1 s against 2.5-2.85 s). The array is a private anonymous mapping
    advised ``MADV_NOHUGEPAGE`` (pages still committed only when written, and returned
    when the array is freed); elsewhere, or for small arrays, ``numpy.empty``.
    """
    nbytes = 8 * int(np.prod(shape))
    advise = getattr(mmap, "MADV_NOHUGEPAGE", None)
    if nbytes < SMALL_PAGES_BYTES or advise is None or os.name != "posix":
        return np.empty(shape, dtype=np.float64)
    mapped = mmap.mmap(-1, nbytes, flags=mmap.MAP_PRIVATE | mmap.MAP_ANONYMOUS)
    try:
        mapped.madvise(advise)
    except OSError:        # a kernel built without transparent huge pages: no advice needed
        pass
    return np.frombuffer(mapped, dtype=np.float64).reshape(shape)


def _parse_chunk(buf: bytes, opts: dict, n_fields: int, keep: list[int], extra: str):
    """``(columns, nan_counts)`` of one chunk of numeric text (the fields ``keep`` as
    float64 arrays); None when it does not parse as ``n_fields`` numeric fields per line
    (see :func:`read_columns` for ``extra``)."""
    try:
        df = pd.read_csv(io.BytesIO(buf), **opts)
    except pd.errors.EmptyDataError:
        return [np.empty(0)] * len(keep), np.zeros(len(keep), dtype=np.int64)
    except (ValueError, TypeError, pd.errors.ParserError):
        return None
    m = df.shape[1]
    if m == n_fields + 1 and extra == "empty":
        if not df.iloc[:, -1].isna().all():
            return None
    elif m != n_fields and not (m == n_fields + 1 and extra == "ignore"):
        return None
    if any(dt.kind not in "fiu" for dt in df.dtypes.iloc[:n_fields]):
        return None  # text in a numeric column
    columns = [df.iloc[:, k].to_numpy(dtype=np.float64, copy=False) for k in keep]
    return columns, np.array([np.count_nonzero(np.isnan(c)) for c in columns], dtype=np.int64)
