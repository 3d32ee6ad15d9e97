"""Updating parameters: numeric fields of a nested structure description.

A structure description is the nested ``dict`` read from a structure TOML (tables are
dicts, arrays are lists). A :class:`Parameter` addresses one numeric field by a dotted
path such as ``"materials.steel.E"`` or ``"patches.0.x0"`` (integer parts index lists).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ..errors import ConfigError, ParameterError
from ..fe._structure import walk_path

__all__ = ["Parameter", "get_path", "set_path", "with_values"]


def _split(path: str) -> list[str]:
    if not isinstance(path, str) or not path or any(p == "" for p in path.split(".")):
        raise ConfigError(
            f"parameter path must be a non-empty dotted string such as 'materials.steel.E', "
            f"got {path!r}"
        )
    return path.split(".")


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def get_path(description: Mapping[str, Any], path: str) -> float:
    """Numeric value of the field ``path`` of a nested description.

    Parameters
    ----------
    description : mapping
        Nested dicts/lists (e.g. a parsed structure TOML).
    path : str
        Dotted path; integer parts index lists (``"patches.0.x0"``).

    Returns
    -------
    float

    Raises
    ------
    ConfigError
        If the path does not exist or the field is not a (non-boolean) number.

    Examples
    --------
    >>> get_path({"patches": [{"x0": 0.05}]}, "patches.0.x0")
    0.05
    """
    try:
        node = walk_path(description, _split(path))
    except ConfigError as err:
        raise ConfigError(f"parameter path {path!r}: {err}") from None
    if not _is_number(node):
        raise ConfigError(
            f"parameter path {path!r}: expected a number, found {type(node).__name__} "
            f"{node!r}"
        )
    return float(node)


def set_path(description: Any, path: str, value: float) -> None:
    """Set the numeric field ``path`` of ``description`` in place (see :func:`get_path`).

    Examples
    --------
    >>> d = {"materials": {"steel": {"E": 2.1e11}}}
    >>> set_path(d, "materials.steel.E", 2.0e11)
    >>> d
    {'materials': {'steel': {'E': 200000000000.0}}}
    """
    get_path(description, path)  # validates path and type
    parts = _split(path)
    node = walk_path(description, parts[:-1])
    last = parts[-1]
    if isinstance(node, Mapping):
        node[last] = float(value)
    else:
        node[int(last)] = float(value)


def with_values(description: Mapping[str, Any], values: Mapping[str, float]) -> dict:
    """Deep copy of ``description`` with the fields ``values`` (path -> value) replaced.

    Examples
    --------
    The original description is left unchanged:

    >>> d = {"materials": {"steel": {"E": 2.1e11}}}
    >>> with_values(d, {"materials.steel.E": 2.0e11})
    {'materials': {'steel': {'E': 200000000000.0}}}
    >>> d
    {'materials': {'steel': {'E': 210000000000.0}}}
    """
    out = copy.deepcopy(description)
    for path, value in values.items():
        set_path(out, path, value)
    return out


@dataclass(frozen=True)
class Parameter:
    """One numeric field of the structure description to be updated.

    Parameters
    ----------
    path : str
        Dotted path of the field (``"materials.steel.E"``, ``"patches.0.x0"``).
    initial : float, optional
        Starting value in the field's SI unit. Default: the value in the description.
    lower, upper : float, optional
        Bounds in the field's unit (default unbounded). The initial value must lie
        strictly inside them.
    fixed : bool
        Keep the field at ``initial`` (it still appears in the tables).
    scale : float, optional
        Reference magnitude; the solver works on ``value / scale`` so that 2e11 Pa and
        5e-4 m are equally conditioned. Default: ``abs(initial)`` (1 if it is zero).
    label : str, optional
        Name in tables (default: ``path``).
    log : bool
        Work on ``log(value / scale)`` instead (for positive quantities that may move
        by orders of magnitude, e.g. a clamp spring stiffness).

    Examples
    --------
    Young's modulus of the material ``steel``, bounded to 100..300 GPa:

    >>> p = Parameter("materials.steel.E", lower=1e11, upper=3e11)
    >>> p.path, p.lower, p.fixed
    ('materials.steel.E', 100000000000.0, False)
    """

    path: str
    initial: float | None = None
    lower: float = -math.inf
    upper: float = math.inf
    fixed: bool = False
    scale: float | None = None
    label: str | None = None
    log: bool = False

    def __post_init__(self) -> None:
        _split(self.path)
        for name in ("lower", "upper"):
            v = getattr(self, name)
            if v is None:
                object.__setattr__(self, name, -math.inf if name == "lower" else math.inf)
            elif not _is_number(v) or math.isnan(v):
                raise ParameterError(
                    f"parameter {self.path!r}: {name} bound must be a number, got {v!r}"
                )
        if not self.lower < self.upper:
            raise ParameterError(
                f"parameter {self.path!r}: lower bound {self.lower:g} must be below "
                f"upper bound {self.upper:g}"
            )
        if self.initial is not None and not (
            _is_number(self.initial) and math.isfinite(self.initial)
        ):
            raise ParameterError(
                f"parameter {self.path!r}: initial must be a finite number, "
                f"got {self.initial!r}"
            )
        if self.scale is not None and not (
            _is_number(self.scale) and math.isfinite(self.scale) and self.scale > 0
        ):
            raise ParameterError(
                f"parameter {self.path!r}: scale must be a positive finite number, "
                f"got {self.scale!r}"
            )

    @property
    def name(self) -> str:
        """Label used in tables."""
        return self.label or self.path

    def resolve(self, description: Mapping[str, Any]) -> tuple[float, float]:
        """Initial value and scale of this parameter for ``description``.

        Raises
        ------
        ConfigError
            Path missing or not numeric.
        ParameterError
            Initial value not strictly inside the bounds (for a free parameter).
        """
        current = get_path(description, self.path)
        x0 = current if self.initial is None else float(self.initial)
        if self.log and (x0 <= 0 or self.upper <= 0):
            raise ParameterError(
                f"parameter {self.path!r}: log=True needs a positive value and upper bound, "
                f"got initial {x0:g}, upper {self.upper:g}"
            )
        if not self.fixed and not self.lower < x0 < self.upper:
            raise ParameterError(
                f"parameter {self.path!r}: initial value {x0:g} must lie strictly inside "
                f"the bounds ({self.lower:g}, {self.upper:g})"
            )
        scale = self.scale if self.scale is not None else (abs(x0) or 1.0)
        return x0, float(scale)

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], where: str = "parameter") -> Parameter:
        """Build from a TOML table ``{path=..., lower=..., upper=..., ...}``."""
        if not isinstance(d, Mapping):
            raise ConfigError(f"{where}: expected a table with a 'path' key, got {d!r}")
        allowed = {"path", "initial", "lower", "upper", "fixed", "scale", "label", "log"}
        unknown = set(d) - allowed
        if unknown:
            raise ConfigError(
                f"{where}: unknown keys {sorted(unknown)}; allowed: {sorted(allowed)}"
            )
        if "path" not in d:
            raise ConfigError(f"{where}: missing key 'path'")
        try:
            return cls(**dict(d))
        except ParameterError as err:
            raise ConfigError(f"{where}: {err}") from err
