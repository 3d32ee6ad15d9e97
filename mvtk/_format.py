"""Numbers formatted by quantity for report tables and notebook reprs.

A column's *kind* is inferred from its name (``fn_hz`` is a frequency in Hz, ``error_pct``
a relative error in percent, ``time_s`` a duration, ``zeta`` a damping ratio,
``mass_fraction`` / ``mac`` a ratio in [0, 1] ...). Each kind has a number of significant
digits, a unit shown in the header (``fn [Hz]``) and, for errors, ratios and percentages,
a round-off floor: a value whose magnitude is below it is shown as ``"< 1e-06"`` instead
of ``7.8e-21``. Scientific notation is used only outside ``1e-3 <= |x| < 1e5``.
The integer part is never rounded (``209630005213`` is ``2.096e11``, ``388.4`` with
2 digits is ``388``).

Every rule can be overridden per table: ``formats={"column": ColumnFormat(...)}``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
import pandas as pd

from .errors import ParameterError

__all__ = ["ColumnFormat", "format_number", "infer_format", "format_table", "dict_table"]

_KINDS = ("number", "frequency", "percent", "duration", "ratio", "error", "damping",
          "integer", "text")


@dataclass(frozen=True)
class ColumnFormat:
    """How the values of one table column are written.

    Parameters
    ----------
    kind : str
        One of ``number, frequency, percent, duration, ratio, error, damping, integer,
        text`` (informative; the other fields decide the output).
    digits : int
        Significant digits (>= 1).
    unit : str
        Unit shown in the header as ``name [unit]`` (``""``: no unit).
    floor : float or None
        Values with ``0 < |x| < floor`` are written ``"< floor"`` (round-off noise);
        ``None`` writes every value.
    label : str or None
        Header text without the unit (default: the column name with a recognised unit
        suffix such as ``_hz`` removed).
    """

    kind: str = "number"
    digits: int = 4
    unit: str = ""
    floor: float | None = None
    label: str | None = None

    def __post_init__(self):
        if self.kind not in _KINDS:
            raise ParameterError(f"ColumnFormat kind must be one of {', '.join(_KINDS)}, "
                                 f"got {self.kind!r}")
        if not isinstance(self.digits, int | np.integer) or self.digits < 1:
            raise ParameterError(f"ColumnFormat digits must be an integer >= 1, got "
                                 f"{self.digits!r}")
        if self.floor is not None and not (self.floor > 0 and math.isfinite(self.floor)):
            raise ParameterError(f"ColumnFormat floor must be a positive finite number or "
                                 f"None, got {self.floor!r}")

    def header(self, name: str) -> str:
        """Header text: ``label [unit]``."""
        label = self.label if self.label is not None else name
        return f"{label} [{self.unit}]" if self.unit else label

    def __call__(self, value: Any) -> str:
        return format_number(value, digits=self.digits, floor=self.floor)


def _floor_text(floor: float) -> str:
    return f"< {floor:.0e}".replace("e-0", "e-").replace("e+0", "e+")


def format_number(value: Any, digits: int = 4, floor: float | None = None) -> str:
    """One value as text with ``digits`` significant digits.

    ``nan``/``None`` -> ``"–"``, booleans -> ``yes``/``no``, integers unchanged, strings
    unchanged. Floats use fixed notation for ``1e-3 <= |x| < 1e5`` and scientific
    notation outside (``"2.5e-7"``), trailing zeros dropped (``128.0`` -> ``"128"``,
    ``13.2600`` -> ``"13.26"``); with ``floor``, ``0 < |x| < floor`` -> ``"< 1e-6"``
    and exact zero -> ``"0"``.

    Examples
    --------
    >>> format_number(7.47905)
    '7.479'
    >>> format_number(0.9999999992, digits=4)
    '1.000'
    >>> format_number(7.82821e-21, floor=1e-6)
    '< 1e-6'
    >>> format_number(0.625521, digits=2)
    '0.63'
    """
    if value is None:
        return "–"
    if isinstance(value, bool | np.bool_):
        return "yes" if value else "no"
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, complex | np.complexfloating):
        c = complex(value)
        sign = "-" if c.imag < 0 else "+"
        return (f"{format_number(c.real, digits, floor)} {sign} "
                f"{format_number(abs(c.imag), digits, floor)}j")
    if not isinstance(value, float | np.floating):
        if isinstance(value, pd.Timestamp | pd.Timedelta):
            return str(value)
        try:
            if pd.isna(value):
                return "–"
        except (TypeError, ValueError):
            pass
        return str(value)
    v = float(value)
    if math.isnan(v):
        return "–"
    if math.isinf(v):
        return "∞" if v > 0 else "-∞"
    if v == 0.0:
        return "0"
    a = abs(v)
    if floor is not None and a < floor:
        return _floor_text(floor)
    # round to `digits` significant digits first, so a carry (9.9996 -> 10.00) is seen
    r = float(f"{v:.{digits - 1}e}")
    a = abs(r)
    if 1e-3 <= a < 1e5:
        exp10 = math.floor(math.log10(a))
        decimals = max(digits - 1 - exp10, 0)
        text = f"{v:.{decimals}f}"
        return "0" if text in ("-0", "") else _strip_exact(text, v)
    mant, exp = f"{v:.{digits - 1}e}".split("e")
    mant = _strip_exact(mant, v / 10.0 ** int(exp))
    return f"{mant}e{int(exp)}"


def _strip_exact(text: str, v: float) -> str:
    """Drop trailing zeros only when the shorter text is the exact value (``128.0`` ->
    ``"128"``, ``13.26`` -> ``"13.26"``); a rounded value keeps them (``0.99999999`` with
    4 digits stays ``"1.000"``), so the precision shown is the precision computed."""
    if "." not in text:
        return text
    short = text.rstrip("0").rstrip(".")
    return short if float(short) == v or math.isclose(float(short), v, rel_tol=1e-15) \
        else text


_TOKEN = re.compile(r"[a-z0-9]+|%")
_BRACKET = re.compile(r"\[[^\]]*\]")
#: unit suffixes (last token of the name) -> unit shown in the header
_UNIT_SUFFIX = {"hz": "Hz", "s": "s", "pct": "%", "percent": "%", "v": "V", "nm": "N m",
                "m": "m", "db": "dB", "n": "N", "rad": "rad", "deg": "deg"}


def _tokens(name: str) -> list[str]:
    return _TOKEN.findall(_BRACKET.sub(" ", name.lower()))


def _strip_suffix(name: str, token: str) -> str:
    """``fn_hz (half-power)`` -> ``fn (half-power)`` for token ``hz``."""
    out = re.sub(rf"[_ ]{re.escape(token)}(?=$|[^A-Za-z0-9])", "", name, count=1,
                 flags=re.IGNORECASE)
    return out.strip() or name


def infer_format(name: Any, values: pd.Series | None = None) -> ColumnFormat:
    """The :class:`ColumnFormat` a column gets from its name (and dtype).

    Rules, on the words of the name (split at ``_``, spaces, brackets; first match wins):

    ======================================  =========  ======  ====  =====
    name contains                           kind       digits  unit  floor
    ======================================  =========  ======  ====  =====
    ``pct``, ``percent``, ``%``             percent    3       %     1e-6
    ``rel`` and ``error``/``residual``      error      3             1e-6
    ``error``, ``residual``, ``deviation``  error      3
    ``zeta``, ``damping``                   damping    4
    ``mac``, ``fraction``, ``coherence``    ratio      4             1e-6
    ``hz``, ``fn``, ``frequency``           frequency  5       Hz
    ends in ``s``; ``time``, ``duration``   duration   2       s
    anything else                           number     4
    ======================================  =========  ======  ====  =====

    A unit written in the name (``alpha [1/s]``) is kept and suppresses the unit
    rules; a unit suffix (``_hz``, ``_s``, ``_pct``, ``_v``, ``_m``, ``_db``, ``_nm``)
    moves into the header (``fn_hz`` -> ``fn [Hz]``). Boolean and integer columns are
    written as they are. An absolute error has no floor: its unit may differ per row.

    Examples
    --------
    >>> infer_format("fn_hz").header("fn_hz")
    'fn [Hz]'
    >>> infer_format("error_pct")(2.5e-07)
    '< 1e-6'
    >>> infer_format("time_s")(0.625521)
    '0.63'
    """
    text = str(name)
    if values is not None:
        if pd.api.types.is_bool_dtype(values) or pd.api.types.is_integer_dtype(values):
            return ColumnFormat("integer", label=text)
        if not (pd.api.types.is_float_dtype(values) or pd.api.types.is_complex_dtype(values)
                or values.dtype == object):
            return ColumnFormat("text", label=text)
    tok = _tokens(text)
    has_unit = bool(_BRACKET.search(text))
    words = set(tok)
    last = tok[-1] if tok else ""
    suffix_unit = "" if has_unit or len(tok) < 2 else _UNIT_SUFFIX.get(last, "")
    label = _strip_suffix(text, last) if suffix_unit else text
    if not has_unit and not suffix_unit and "hz" in tok[1:]:  # fn_hz (half-power)
        suffix_unit, label = "Hz", _strip_suffix(text, "hz")

    def fmt(kind, digits, unit="", floor=None):
        if has_unit or "%" in text:
            unit = ""
        return ColumnFormat(kind, digits, unit or suffix_unit, floor, label)

    errorish = words & {"error", "err", "residual", "deviation", "discrepancy"}
    if words & {"pct", "percent"} or "%" in text:
        return fmt("percent", 3, "%", 1e-6)
    if errorish and words & {"rel", "relative"}:
        return fmt("error", 3, "", 1e-6)
    if errorish:
        return fmt("error", 3)
    if words & {"zeta", "damping"}:
        return fmt("damping", 4)
    if words & {"mac", "fraction", "coherence"}:
        return fmt("ratio", 4, "", 1e-6)
    if not has_unit and (words & {"hz", "fn", "frequency", "freq"}):
        return fmt("frequency", 5, "Hz")
    if not has_unit and (last in {"s", "sec", "seconds"}
                         or words & {"time", "duration", "elapsed"}):
        return fmt("duration", 2, "s")
    return fmt("number", 4)


FormatSpec = ColumnFormat | Callable[[Any], str] | int


def _resolve(name: Any, values: pd.Series, override: FormatSpec | None) -> ColumnFormat | Callable:
    if override is None:
        return infer_format(name, values)
    if isinstance(override, ColumnFormat):
        return override if override.label is not None else replace(override, label=str(name))
    if isinstance(override, int) and not isinstance(override, bool):
        return replace(infer_format(name, values), digits=override)
    if callable(override):
        return override
    raise ParameterError(
        f"format of column {name!r} must be a ColumnFormat, a number of significant digits "
        f"or a callable value -> str, got {type(override).__name__}")


def format_table(
    df: pd.DataFrame,
    formats: Mapping[Any, FormatSpec] | None = None,
) -> tuple[list[str], list[list[str]]]:
    """Headers and cell texts of ``df`` formatted column by column.

    Parameters
    ----------
    df : DataFrame
    formats : mapping of column name to ColumnFormat, int or callable, optional
        Per-table overrides: a :class:`ColumnFormat`, a number of significant digits
        (the inferred kind is kept), or a function value -> str. Names not in ``df``
        raise :class:`~mvtk.errors.ParameterError`.

    Returns
    -------
    headers : list of str
        One per column (units in brackets), index excluded.
    cells : list of list of str
        ``cells[i][j]`` is row ``i``, column ``j``.
    """
    if df.columns.has_duplicates:
        dup = sorted({str(c) for c in df.columns[df.columns.duplicated()]})
        raise ParameterError(f"table has duplicate column names {dup}; give each column a "
                             "unique name")
    formats = dict(formats or {})
    unknown = [k for k in formats if k not in df.columns]
    if unknown:
        raise ParameterError(f"formats name columns not in the table: {unknown}; "
                             f"columns are {[str(c) for c in df.columns]}")
    headers, columns = [], []
    for col in df.columns:
        series = df[col]
        fmt = _resolve(col, series, formats.get(col))
        headers.append(fmt.header(str(col)) if isinstance(fmt, ColumnFormat) else str(col))
        columns.append([fmt(v) if isinstance(fmt, ColumnFormat) else str(fmt(v))
                        for v in series.tolist()])
    cells = [list(row) for row in zip(*columns)] if columns else [[] for _ in range(len(df))]
    return headers, cells


def _flatten(prefix: str, value: Any, rows: list[tuple[str, str]]) -> None:
    if isinstance(value, Mapping):
        if not value:
            rows.append((prefix, "{}"))
        for k in sorted(value, key=str):
            _flatten(f"{prefix}.{k}" if prefix else str(k), value[k], rows)
    elif isinstance(value, list | tuple) and any(isinstance(v, Mapping | list | tuple)
                                                 for v in value):
        for i, v in enumerate(value):
            _flatten(f"{prefix}[{i}]", v, rows)
    elif isinstance(value, list | tuple | np.ndarray):
        rows.append((prefix, ", ".join(format_number(v, digits=6) for v in value)
                     if len(value) else "[]"))
    else:
        rows.append((prefix, format_number(value, digits=6)))


def dict_table(params: Mapping[str, Any], *, key: str = "parameter",
               value: str = "value") -> pd.DataFrame:
    """A nested mapping (e.g. a parsed TOML/JSON) as a two-column key/value table.

    Nested keys are joined with ``.`` (``damping.band_hz``), lists of mappings are
    indexed (``channels[0].name``), lists of scalars are joined with ``", "`` and
    numbers get 6 significant digits.

    Parameters
    ----------
    params : mapping
    key, value : str
        Column names.

    Raises
    ------
    ParameterError
        If ``params`` is not a mapping.
    """
    if not isinstance(params, Mapping):
        raise ParameterError(f"dict_table expects a mapping (e.g. a parsed TOML/JSON "
                             f"object), got {type(params).__name__}")
    rows: list[tuple[str, str]] = []
    _flatten("", params, rows)
    return pd.DataFrame(rows, columns=[key, value])
