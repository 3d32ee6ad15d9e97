"""Time-history data model: vocabulary, unit normalisation and the ``time_history`` builder."""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

from ..errors import DimensionError, ParameterError, UnitsError

__all__ = [
    "QUANTITIES",
    "UNITS_BY_QUANTITY",
    "normalize_units",
    "infer_quantity",
    "time_axis",
    "fs_from_dt",
    "time_history",
]

#: Allowed values of the ``quantity`` coordinate. ``"other"`` is for channels whose
#: physical quantity the file does not state and mvtk cannot infer (e.g. a trigger).
QUANTITIES: tuple[str, ...] = (
    "acceleration",
    "velocity",
    "displacement",
    "force",
    "strain",
    "voltage",
    "current",
    "pressure",
    "other",
)

#: Canonical unit strings accepted for each quantity (``"other"`` accepts any non-empty unit).
UNITS_BY_QUANTITY: dict[str, tuple[str, ...]] = {
    "acceleration": ("m/s^2", "mm/s^2", "g"),
    "velocity": ("m/s", "mm/s", "um/s"),
    "displacement": ("m", "mm", "um", "nm"),
    "force": ("N", "kN", "mN"),
    "strain": ("m/m", "um/m", "1"),
    "voltage": ("V", "mV", "uV"),
    "current": ("A", "mA"),
    "pressure": ("Pa", "kPa", "MPa", "mbar", "bar"),
}

_UNIT_ALIASES = {
    "m/s2": "m/s^2",
    "m/s**2": "m/s^2",
    "m/s/s": "m/s^2",
    "m s^-2": "m/s^2",
    "m*s^-2": "m/s^2",
    "ms^-2": "m/s^2",
    "ms-2": "m/s^2",
    "mm/s2": "mm/s^2",
    "mm/s**2": "mm/s^2",
    "µm/s": "um/s",
    "μm/s": "um/s",
    "µm": "um",
    "μm": "um",
    "micron": "um",
    "µm/m": "um/m",
    "μm/m": "um/m",
    "ustrain": "um/m",
    "µstrain": "um/m",
    "microstrain": "um/m",
    "µε": "um/m",
    "strain": "m/m",
    "µv": "uV",
    "μv": "uV",
    "volt": "V",
    "volts": "V",
    "newton": "N",
    "newtons": "N",
    "amp": "A",
    "amps": "A",
    "ampere": "A",
    "amperes": "A",
    "a": "A",
    "ma": "mA",
    "mv": "mV",
    "g0": "g",
    "gn": "g",
    "-": "1",
    "v": "V",
    "n": "N",
    "pa": "Pa",
    "kpa": "kPa",
}

_SUPERSCRIPTS = {"²": "^2", "³": "^3", "¹": "^1", "⁻": "^-"}


def normalize_units(units: str) -> str:
    """Return the canonical spelling of a unit string.

    ``"m/s2"``, ``"m/s²"`` and ``"m/s**2"`` all become ``"m/s^2"``; ``"µm"`` becomes
    ``"um"``. Unknown units are returned stripped but otherwise unchanged.

    Parameters
    ----------
    units : str
        Unit string as written in a file.

    Returns
    -------
    str
        Canonical unit string.

    Examples
    --------
    >>> normalize_units("m/s2"), normalize_units("m/s**2"), normalize_units("µm")
    ('m/s^2', 'm/s^2', 'um')
    """
    if not isinstance(units, str):
        raise UnitsError(f"units must be a string, got {type(units).__name__} {units!r}")
    u = units.strip()
    for sup, rep in _SUPERSCRIPTS.items():
        u = u.replace(sup, rep)
    u = u.replace(" ", "")
    key = u.lower()
    if key in _UNIT_ALIASES:
        return _UNIT_ALIASES[key]
    return u


def infer_quantity(units: str) -> str:
    """Physical quantity implied by a canonical unit string, or ``"other"``.

    Parameters
    ----------
    units : str
        Canonical unit string (see :func:`normalize_units`).

    Returns
    -------
    str
        One of :data:`QUANTITIES`.

    Examples
    --------
    >>> infer_quantity("m/s^2"), infer_quantity("N"), infer_quantity("V")
    ('acceleration', 'force', 'voltage')
    """
    for quantity, allowed in UNITS_BY_QUANTITY.items():
        if units in allowed and units != "1":
            return quantity
    return "other"


def fs_from_dt(dt: float) -> float:
    """Sampling rate in Hz from a sample interval in s, rounded to 10 significant digits.

    The rounding removes the last-bit noise of ``1 / dt`` when ``dt`` was itself written
    as a rounded decimal (``0.0333333333`` -> 30.0 Hz).

    Examples
    --------
    >>> fs_from_dt(1 / 3000), fs_from_dt(0.001)
    (3000.0, 1000.0)
    """
    dt = float(dt)
    if not np.isfinite(dt) or dt <= 0.0:
        raise ParameterError(f"sample interval must be a positive finite number of s, got {dt!r}")
    return float(f"{1.0 / dt:.10g}")


def time_axis(n: int, fs: float) -> np.ndarray:
    """The mvtk time axis: ``np.arange(n) / fs`` in s (never a float ``arange`` with a step).

    Examples
    --------
    >>> time_axis(4, 1024.0)       # s
    array([0.        , 0.00097656, 0.00195312, 0.00292969])
    """
    t = np.arange(int(n), dtype=np.float64)   # exact integers up to 2**53
    t /= float(fs)
    return t


def _per_channel(value, n: int, name: str, default) -> list:
    if value is None:
        return [default] * n
    if isinstance(value, str) or np.isscalar(value):
        return [value] * n
    values = list(value)
    if len(values) != n:
        raise DimensionError(
            f"{name}: expected one entry per channel ({n}), got {len(values)}: "
            f"{[str(v) for v in values]}"
        )
    return values


def time_history(
    data,
    fs: float,
    channels: Sequence[str],
    units: str | Sequence[str],
    quantity: str | Sequence[str] | None = None,
    *,
    node: int | Sequence[int] | None = None,
    direction: str | Sequence[str] | None = None,
    attrs: Mapping | None = None,
    n_missing: Sequence[int] | None = None,
) -> xr.DataArray:
    """Build a valid time-history ``DataArray`` with dims ``("channel", "time")``.

    Parameters
    ----------
    data : array_like, shape (n_channels, n_samples) or (n_samples,)
        Samples in the given units. Integer data are converted to float64; float32 is kept.
    fs : float
        Sampling rate in Hz. The time coordinate is ``np.arange(n_samples) / fs`` in s.
    channels : sequence of str
        Unique channel names.
    units : str or sequence of str
        Unit of each channel (one string applies to all); normalised with
        :func:`normalize_units`.
    quantity : str or sequence of str, optional
        Physical quantity of each channel, from :data:`QUANTITIES`. Inferred from the
        units when omitted.
    node : int or sequence of int, optional
        Measurement node number of each channel (-1 when unknown, the default).
    direction : str or sequence of str, optional
        Measurement direction of each channel (``"x"``, ``"-z"``, ``"rx"``...; ``""``
        when unknown, the default).
    attrs : mapping, optional
        File-level metadata (str, int or float values).
    n_missing : sequence of int, optional
        Number of samples per channel that the source marks as missing (NaN).

    Returns
    -------
    xarray.DataArray
        Validated time history named ``"time_history"`` with ``attrs["fs"]`` in Hz.

    Examples
    --------
    Two channels sampled at 1024 Hz; the quantity follows from the unit:

    >>> x = time_history(np.zeros((2, 1024)), 1024.0, ["acc1", "force"], ["m/s^2", "N"])
    >>> x.dims, list(x.quantity.values), float(x.time[-1])
    (('channel', 'time'), ['acceleration', 'force'], 0.9990234375)
    """
    from ._validate import validate

    return validate(
        build_time_history(
            data,
            fs,
            channels,
            units,
            quantity,
            node=node,
            direction=direction,
            attrs=attrs,
            n_missing=n_missing,
        )
    )


def build_time_history(
    data,
    fs,
    channels,
    units,
    quantity=None,
    *,
    node=None,
    direction=None,
    attrs=None,
    n_missing=None,
) -> xr.DataArray:
    """:func:`time_history` without the final validation (readers validate once in ``read``)."""
    arr = np.asarray(data)
    if arr.ndim == 1:
        arr = arr[np.newaxis, :]
    if arr.ndim != 2:
        raise DimensionError(
            f"time_history data: expected a 1-D or 2-D (channel, time) array, got shape {arr.shape}"
        )
    if np.iscomplexobj(arr):
        raise ParameterError("time_history data: expected real samples, got a complex array")
    if arr.dtype.kind in "iub":
        arr = arr.astype(np.float64)
    elif arr.dtype.kind == "f" and not arr.dtype.isnative:
        arr = arr.astype(arr.dtype.newbyteorder("="))
    elif arr.dtype.kind != "f":
        raise ParameterError(f"time_history data: expected numeric samples, got dtype {arr.dtype}")
    if isinstance(channels, str):
        channels = [channels]
    channels = [str(c) for c in channels]
    n_ch, n = arr.shape
    if len(channels) != n_ch:
        raise DimensionError(
            f"time_history: expected one channel name per row ({n_ch}), got {len(channels)}"
        )
    fs = float(fs)
    if not np.isfinite(fs) or fs <= 0:
        raise ParameterError(f"time_history: fs must be a positive finite rate in Hz, got {fs!r}")
    unit_list = [normalize_units(u) for u in _per_channel(units, n_ch, "units", None)]
    if quantity is None:
        q_list = [infer_quantity(u) for u in unit_list]
    else:
        q_list = [str(q) for q in _per_channel(quantity, n_ch, "quantity", None)]
    node_list = np.asarray(_per_channel(node, n_ch, "node", -1), dtype=np.int64)
    dir_list = [str(d) for d in _per_channel(direction, n_ch, "direction", "")]
    miss = np.asarray(_per_channel(n_missing, n_ch, "n_missing", 0), dtype=np.int64)
    all_attrs = dict(attrs or {})
    all_attrs["fs"] = fs
    da = xr.DataArray(
        arr,
        dims=("channel", "time"),
        coords={
            "channel": np.array(channels, dtype=object),
            "time": time_axis(n, fs),
            "quantity": ("channel", np.array(q_list, dtype=object)),
            "units": ("channel", np.array(unit_list, dtype=object)),
            "node": ("channel", node_list),
            "direction": ("channel", np.array(dir_list, dtype=object)),
            "n_missing": ("channel", miss),
        },
        name="time_history",
        attrs=all_attrs,
    )
    da.time.attrs["units"] = "s"
    return da


_BRACKET_UNITS = re.compile(r"^\s*(?P<name>.*?)\s*[\[(](?P<units>[^\[\]()]*)[\])]\s*$")


def split_name_units(label: str) -> tuple[str, str | None]:
    """Split ``"acc1 [m/s^2]"`` or ``"acc1 (m/s^2)"`` into name and units (None if absent)."""
    m = _BRACKET_UNITS.match(label)
    if m and m.group("name"):
        return m.group("name"), m.group("units").strip()
    return label.strip(), None
