"""Pass/fail checks of computed values against references with stated tolerances."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..errors import DimensionError, ParameterError

__all__ = ["Check", "check_table", "frequency_table"]

_KINDS = ("relative", "absolute", "upper", "lower")


@dataclass(frozen=True)
class Check:
    """One verifiable statement: ``value`` agrees with ``reference`` within ``tolerance``.

    Parameters
    ----------
    name : str
        What is checked (shown in the report).
    value : float
        The value mvtk computed, in ``unit``.
    reference : float
        The reference (measurement, closed form, published value), in ``unit``.
    tolerance : float
        Allowed deviation. For ``kind="relative"`` a ratio (0.01 = 1 %) of
        ``|reference|``; for ``"absolute"`` in ``unit``. For ``"upper"`` the check passes
        when ``value <= reference + tolerance`` and for ``"lower"`` when
        ``value >= reference - tolerance`` (``tolerance`` in ``unit``).
    unit : str
        Unit of ``value`` and ``reference`` (free text, e.g. ``"Hz"``).
    kind : {"relative", "absolute", "upper", "lower"}
        How ``tolerance`` is applied.
    source : str
        Where the reference comes from (e.g. ``"paper Table 2"``).
    """

    name: str
    value: float
    reference: float
    tolerance: float
    unit: str = ""
    kind: str = "relative"
    source: str = ""

    def __post_init__(self) -> None:
        if self.kind not in _KINDS:
            raise ParameterError(
                f"Check {self.name!r}: kind must be one of {_KINDS}, got {self.kind!r}"
            )
        tol = float(self.tolerance)
        if not math.isfinite(tol) or tol < 0:
            raise ParameterError(
                f"Check {self.name!r}: tolerance must be a finite number >= 0, got {tol}"
            )
        ref = float(self.reference)
        if not math.isfinite(ref):
            raise ParameterError(f"Check {self.name!r}: reference must be finite, got {ref}")
        if self.kind == "relative" and ref == 0.0:
            raise ParameterError(
                f"Check {self.name!r}: a relative tolerance needs a non-zero reference; "
                "use kind='absolute'"
            )
        object.__setattr__(self, "value", float(self.value))
        object.__setattr__(self, "reference", ref)
        object.__setattr__(self, "tolerance", tol)

    @property
    def error(self) -> float:
        """Signed deviation ``value - reference`` in ``unit``."""
        return self.value - self.reference

    @property
    def relative_error(self) -> float:
        """Signed deviation relative to ``|reference|`` (nan when reference is 0)."""
        if self.reference == 0.0:
            return math.nan
        return self.error / abs(self.reference)

    @property
    def passed(self) -> bool:
        """True when the value is within tolerance. A non-finite value never passes."""
        if not math.isfinite(self.value):
            return False
        if self.kind == "relative":
            return abs(self.relative_error) <= self.tolerance
        if self.kind == "absolute":
            return abs(self.error) <= self.tolerance
        if self.kind == "upper":
            return self.value <= self.reference + self.tolerance
        return self.value >= self.reference - self.tolerance

    def describe_tolerance(self) -> str:
        """Readable tolerance, e.g. ``"±2 %"`` or ``"<= ref + 0.1 Hz"``."""
        if self.kind == "relative":
            return f"±{100 * self.tolerance:g} %"
        if self.kind == "absolute":
            return f"±{self.tolerance:g} {self.unit}".rstrip()
        sign = "+" if self.kind == "upper" else "-"
        op = "<=" if self.kind == "upper" else ">="
        return f"{op} ref {sign} {self.tolerance:g} {self.unit}".rstrip()


def check_table(checks: Iterable[Check]) -> pd.DataFrame:
    """Table of checks with a boolean ``passed`` column (one row per check).

    Columns: ``check, value, reference, unit, error, error_pct, tolerance, source,
    passed``. ``error_pct`` is the relative deviation in percent (nan for a zero
    reference).
    """
    rows = []
    for c in checks:
        if not isinstance(c, Check):
            raise ParameterError(f"check_table expects Check objects, got {type(c).__name__}")
        rows.append(
            {
                "check": c.name,
                "value": c.value,
                "reference": c.reference,
                "unit": c.unit,
                "error": c.error,
                "error_pct": 100.0 * c.relative_error,
                "tolerance": c.describe_tolerance(),
                "source": c.source,
                "passed": c.passed,
            }
        )
    columns = [
        "check", "value", "reference", "unit", "error", "error_pct", "tolerance", "source",
        "passed",
    ]
    return pd.DataFrame(rows, columns=columns)


def frequency_table(
    columns: dict[str, Sequence[float]],
    reference: str,
    *,
    compare: Sequence[str] | None = None,
    index_name: str = "mode",
) -> pd.DataFrame:
    """Side-by-side eigenfrequency table with % errors against one column.

    Parameters
    ----------
    columns : dict of str to sequence of float
        Frequencies in Hz per model/measurement, e.g. ``{"FE": [...], "SE": [...]}``.
        Shorter columns are padded with nan.
    reference : str
        Key of the reference column.
    compare : sequence of str, optional
        Columns to compare with the reference (default: all others). Adds a column
        ``"<name> error %"`` = 100 (x - ref) / ref for each.

    Returns
    -------
    DataFrame indexed 1..n by ``index_name``.
    """
    if reference not in columns:
        raise ParameterError(
            f"reference column {reference!r} not in columns {sorted(columns)}"
        )
    arrays = {k: np.asarray(v, dtype=float).ravel() for k, v in columns.items()}
    n = max((a.size for a in arrays.values()), default=0)
    if n == 0:
        raise DimensionError("frequency_table needs at least one frequency")
    padded = {k: np.pad(a, (0, n - a.size), constant_values=np.nan) for k, a in arrays.items()}
    df = pd.DataFrame(padded, index=pd.RangeIndex(1, n + 1, name=index_name))
    others = [k for k in columns if k != reference] if compare is None else list(compare)
    for k in others:
        if k not in columns:
            raise ParameterError(f"compare column {k!r} not in columns {sorted(columns)}")
        ref = padded[reference]
        with np.errstate(invalid="ignore", divide="ignore"):
            df[f"{k} error %"] = 100.0 * (padded[k] - ref) / ref
    return df
