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

__all__ = ["ColumnFormat", "format_number", "infer_format", "format_table", "dict_table",
           "COLUMN_REGISTRY", "PARAMETER_UNITS", "parameter_unit"]

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
    notation: str = "auto"
    zero_below: float | None = None
    fixed_min: float = 1e-3

    def __post_init__(self):
        if self.notation not in ("auto", "fixed", "sci"):
            raise ParameterError(f"ColumnFormat notation must be 'auto', 'fixed' or 'sci', "
                                 f"got {self.notation!r}")
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
        if (self.zero_below is not None and isinstance(value, float | np.floating)
                and abs(float(value)) < self.zero_below):
            return "0"
        return format_number(value, digits=self.digits, floor=self.floor,
                             notation=self.notation, fixed_min=self.fixed_min)

    def for_column(self, values: list) -> ColumnFormat:
        """This format fitted to one column: one notation for all its numbers
        (scientific for every row when any row needs it) and, for a quantity with a
        unit, values below 1e-9 of the column's largest shown as round-off ``0``
        (a 1.4e-17 m distance next to millimetres)."""
        nums = np.array([float(v) for v in values
                         if isinstance(v, float | np.floating) and math.isfinite(v)
                         and not isinstance(v, bool | np.bool_)], dtype=float)
        if not len(nums) or self.kind in ("integer", "text"):
            return self
        a = np.abs(nums)
        zero = self.zero_below
        if zero is None and self.unit and self.floor is None and a.max() > 0:
            zero = 1e-9 * float(a.max())
            if self.unit == "m":   # coordinates' round-off (1e-17 m) is no distance
                zero = max(zero, 1e-12)
        shown = a[(a > 0) & (a >= (self.floor or 0.0)) & (a >= (zero or 0.0))]
        notation = self.notation
        # one quantity per column (a unit, or a kind such as a damping ratio): one
        # notation; a column of mixed quantities (a check's value) keeps each its own
        homogeneous = bool(self.unit) or self.kind in ("percent", "ratio", "damping",
                                                      "frequency", "duration")
        if notation == "auto" and len(shown) and homogeneous:
            r = np.array([abs(float(f"{x:.{self.digits - 1}e}")) for x in shown])
            if ((r >= 1e-3) & (r < 1e5)).all() or (
                    self.kind == "percent" and (r < 1e5).all()):
                notation = "fixed"
            else:
                notation = "sci"
        elif notation == "auto" and len(shown) and (shown < 1e-3).any():
            # a column of mixed quantities: its small numbers (damping ratios next to
            # frequencies) share one notation, 5.839e-4 next to 1.321e-3
            return replace(self, zero_below=zero, fixed_min=1e-2)
        return replace(self, notation=notation, zero_below=zero)


def _floor_text(floor: float) -> str:
    return f"< {floor:.0e}".replace("e-0", "e-").replace("e+0", "e+")


def format_number(value: Any, digits: int = 4, floor: float | None = None,
                  notation: str = "auto", fixed_min: float = 1e-3) -> str:
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
    >>> format_number(0.001321, digits=4, notation="sci")
    '1.321e-3'
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
        return (f"{format_number(c.real, digits, floor, notation, fixed_min)} {sign} "
                f"{format_number(abs(c.imag), digits, floor, notation, fixed_min)}j")
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
    if notation == "fixed" or (notation == "auto" and fixed_min <= a < 1e5):
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


#: Column labels and units of the fields the stages write, by field name: the one
#: place where a field name becomes a header (``max_real_pole_1_per_s`` ->
#: ``max real pole [1/s]``). Entries: (label, unit, kind, digits, floor); a kind of
#: ``None`` keeps the kind inferred from the name.
COLUMN_REGISTRY: dict[str, tuple[str, str, str | None, int | None, float | None]] = {
    # identified modes (mvtk.modal, the study's [modal])
    "mpc": ("MPC", "", "ratio", 4, None),
    "mpd": ("MPD", "deg", "number", 3, None),
    "stability_count": ("stable orders", "", None, None, None),
    "excitation_db": ("excitation", "dB", "number", 3, None),
    "fn_std_hz": ("std of fn", "Hz", "frequency", 2, None),
    "zeta_std": ("std of zeta", "", "damping", 2, None),
    "support": ("support", "", "number", 3, None),
    # test-FE correlation
    "test_mode": ("test mode", "", None, None, None),
    "fe_mode": ("FE mode", "", None, None, None),
    "fn_test_hz": ("fn test", "Hz", "frequency", 5, None),
    "fn_fe_hz": ("fn FE", "Hz", "frequency", 5, None),
    "df_pct": ("Δf", "%", "percent", 3, 1e-6),
    "mac": ("MAC", "", "ratio", 4, 1e-6),
    "second_mac": ("second-highest MAC", "", "ratio", 4, 1e-6),
    "comac": ("COMAC", "", "ratio", 4, 1e-6),
    "ecomac": ("eCOMAC", "", "ratio", 4, 1e-6),
    "fe_node": ("FE node", "", None, None, None),
    "direction_source": ("direction source", "", None, None, None),
    "node_distance_m": ("node distance", "m", "number", 3, None),
    "surface_distance_m": ("surface distance", "m", "number", 3, None),
    # uncertainty
    "cov": ("CoV", "", "ratio", 3, None),
    "cov_first_order": ("CoV first-order", "", "ratio", 3, None),
    "cov_first_order_same_samples": ("CoV first-order (same samples)", "", "ratio", 3, None),
    "rel_std": ("rel. std", "", "ratio", 3, None),
    "n_samples": ("samples", "", None, None, None),
    # super element
    "fe": ("FE", "Hz", "frequency", 5, None),
    "se": ("SE", "Hz", "frequency", 5, None),
    "fe_hz": ("FE", "Hz", "frequency", 5, None),
    "se_hz": ("SE", "Hz", "frequency", 5, None),
    "error_pct_of_se": ("error of SE", "%", "percent", 3, 1e-6),
    "se_match": ("SE mode matched", "", None, None, None),
    "mac_match": ("MAC of the match", "", "ratio", 4, 1e-6),
    # controllers
    "settling_time_s": ("settling time", "s", "duration", 3, None),
    "zeta_mode1": ("zeta of mode 1", "", "damping", 3, None),
    "fn_mode1_hz": ("fn of mode 1", "Hz", "frequency", 5, None),
    "max_real_pole_1_per_s": ("max real pole", "1/s", "number", 4, None),
    "critical_pole_imag_rad_s": ("critical pole imag", "rad/s", "number", 4, None),
    "zeta_min": ("min zeta", "", "damping", 3, None),
    "stability_basis": ("stability basis", "", "text", None, None),
    "peak_tip_m_after_1s": ("peak tip after 1 s", "m", "number", 3, None),
    "peak_voltage_V": ("peak voltage", "V", "number", 4, None),
    "peak_moment_Nm": ("peak moment", "N m", "number", 3, None),
    "voltage_within_limit": ("voltage within limit", "", None, None, None),
    "spectrum_peak_m": ("spectrum peak", "m", "number", 3, None),
    "peak_reduction_db": ("peak reduction", "dB", "number", 3, None),
    # checks
    "error_pct": ("error", "%", "percent", 3, 1e-6),
    "deviation_pct": ("deviation", "%", "percent", 3, 1e-6),
    "margin_pct": ("margin", "%", "percent", 3, None),
    "tolerance_used_pct": ("share of tolerance used", "%", "percent", 3, None),
}

#: Units of the structure parameters an updating or a scatter names, by the last key
#: of their dotted path (``materials.steel.E`` -> Pa).
PARAMETER_UNITS: dict[str, str] = {
    "E": "Pa", "E1": "Pa", "E2": "Pa", "E3": "Pa", "G": "Pa", "G12": "Pa", "G13": "Pa",
    "G23": "Pa", "rho": "kg/m^3", "nu": "-", "nu12": "-", "nu13": "-", "nu23": "-",
    "thickness": "m", "length": "m", "width": "m", "height": "m", "radius": "m",
    "mass": "kg", "clamp_stiffness": "N m/rad per m", "k": "N/m", "d31": "m/V",
    "eps33": "F/m", "rayleigh_alpha": "1/s", "rayleigh_beta": "s",
}


def parameter_unit(path: str) -> str:
    """SI unit of a structure parameter from its dotted path (``""`` when unknown).

    Examples
    --------
    >>> parameter_unit("materials.steel.E"), parameter_unit("structure.layers.0.thickness")
    ('Pa', 'm')
    """
    return PARAMETER_UNITS.get(str(path).rsplit(".", 1)[-1], "")


_TOKEN = re.compile(r"[a-z0-9]+|%")
_BRACKET = re.compile(r"\[[^\]]*\]")
#: unit suffixes (last token of the name) -> unit shown in the header
_UNIT_SUFFIX = {"hz": "Hz", "s": "s", "pct": "%", "percent": "%", "v": "V", "nm": "N m",
                "m": "m", "db": "dB", "n": "N", "rad": "rad", "deg": "deg"}


#: unit suffixes of more than one word: ``_1_per_s`` (1/s), ``_rad_s`` (rad/s) ...
_COMPOUND_UNITS = (
    (re.compile(r"_1_per_s$"), "1/s"), (re.compile(r"_per_s$"), "1/s"),
    (re.compile(r"_rad_s$"), "rad/s"), (re.compile(r"_Nm$"), "N m"),
    (re.compile(r"_V$"), "V"),
)


def _readable(name: str) -> str:
    """A field name as header text: ``stability_count`` -> ``stability count``."""
    return re.sub(r"(?<=[A-Za-z0-9])_(?=[A-Za-z0-9(])", " ", name)


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
    reg = COLUMN_REGISTRY.get(text)
    if reg is not None:
        label, unit, kind, digits, floor = reg
        if values is not None and (pd.api.types.is_bool_dtype(values)
                                   or pd.api.types.is_integer_dtype(values)):
            return ColumnFormat("integer", unit=unit, label=label)
        base = infer_format(label, None) if kind is None else ColumnFormat(kind)
        return ColumnFormat(kind or base.kind, digits or base.digits, unit, floor, label)
    if values is not None:
        if pd.api.types.is_bool_dtype(values) or pd.api.types.is_integer_dtype(values):
            return ColumnFormat("integer", label=_readable(text))
        if not (pd.api.types.is_float_dtype(values) or pd.api.types.is_complex_dtype(values)
                or values.dtype == object):
            return ColumnFormat("text", label=_readable(text))
    tok = _tokens(text)
    has_unit = bool(_BRACKET.search(text))
    words = set(tok)
    last = tok[-1] if tok else ""
    suffix_unit = "" if has_unit or len(tok) < 2 else _UNIT_SUFFIX.get(last, "")
    label = _strip_suffix(text, last) if suffix_unit else text
    if not has_unit and not suffix_unit and "hz" in tok[1:]:  # fn_hz (half-power)
        suffix_unit, label = "Hz", _strip_suffix(text, "hz")

    for pattern, unit in _COMPOUND_UNITS:
        if not has_unit and (m := pattern.search(text)):
            suffix_unit, label = unit, text[:m.start()]
            break
    label = _readable(label)

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
        if isinstance(fmt, ColumnFormat):
            fmt = fmt.for_column(series.tolist())
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
