"""Shared logic of the array-container readers (MAT, HDF5): pick variables, orient, build."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import FormatError, ParameterError
from ._build import assemble
from ._model import build_time_history, fs_from_dt
from ._text import check_time_stamps

__all__ = ["build_from_arrays"]


def _scalar(value, what: str, path: Path) -> float:
    arr = np.asarray(value)
    if arr.size != 1 or arr.dtype.kind not in "iuf":
        raise FormatError(f"{path}: {what} holds {arr.shape} {arr.dtype}; expected one number")
    return float(arr.reshape(-1)[0])


def _orient(arr: np.ndarray, n_names: int | None, what: str, path: Path) -> np.ndarray:
    """Return (channel, time) from a 1-D or 2-D array (samples along the longer axis)."""
    arr = np.asarray(arr)
    arr = np.squeeze(arr) if arr.ndim > 2 else arr
    if arr.ndim == 1:
        arr = arr[np.newaxis, :]
    if arr.ndim != 2:
        raise FormatError(f"{path}: {what} has shape {arr.shape}; expected a 1-D or 2-D array")
    if n_names is not None and arr.shape[1] == n_names and arr.shape[0] != n_names:
        return arr.T
    if n_names is not None and arr.shape[0] == n_names:
        return arr
    return arr.T if arr.shape[0] > arr.shape[1] else arr


def build_from_arrays(
    path: Path,
    get: Callable[[str], np.ndarray],
    names_available: list[str],
    *,
    data,
    time=None,
    fs=None,
    dt=None,
    channels=None,
    units=None,
    quantity=None,
    frequency=None,
    spectra: Mapping[str, object] | None = None,
    spectrum_units: Mapping[str, str] | None = None,
    attrs: Mapping | None = None,
) -> xr.Dataset:
    """Assemble a Dataset from named arrays of a container file.

    ``get(name)`` returns the array stored under ``name``; ``data`` names one 2-D array
    or a list of 1-D arrays (one per channel); ``time`` names a time vector in s, ``fs``
    / ``dt`` give the rate as a number or as the name of a scalar variable.
    """

    def fetch(name):
        if not isinstance(name, str):
            raise ParameterError(f"read({path}): variable names must be strings, got {name!r}")
        if name not in names_available:
            raise FormatError(
                f"{path}: no variable {name!r}; the file holds: {', '.join(names_available)}"
            )
        return np.asarray(get(name))

    if data is None:
        raise FormatError(
            f"{path}: which variables hold the samples is not stated; expected data='<name>' or "
            f"data=[...] among: {', '.join(names_available)} (with time=, fs= or dt=, units=)"
        )
    n_names = None if channels is None else len(list(channels))
    if isinstance(data, str):
        block = _orient(fetch(data), n_names, f"variable {data!r}", path)
        default_names = (
            [data] if block.shape[0] == 1 else [f"{data}[{k}]" for k in range(block.shape[0])]
        )
    else:
        cols = [np.asarray(fetch(name)).reshape(-1) for name in data]
        sizes = {c.size for c in cols}
        if len(sizes) != 1:
            raise FormatError(
                f"{path}: data variables {list(data)} have lengths {[c.size for c in cols]}; "
                "expected equal lengths"
            )
        block = np.stack(cols)
        default_names = [str(d) for d in data]
    if block.dtype.kind not in "iuf":
        raise FormatError(f"{path}: data is {block.dtype}; expected real numeric samples")
    names = [str(c) for c in channels] if channels is not None else default_names
    if len(names) != block.shape[0]:
        raise ParameterError(
            f"read({path}): {len(names)} channel names for {block.shape[0]} channels"
        )
    n = block.shape[1]
    extra = dict(attrs or {})
    rate = None
    rtol = 1e-6
    if time is not None:
        t_raw = fetch(time)
        t = t_raw.astype(np.float64).reshape(-1)
        rtol = max(
            1e-6, 4 * t.size * np.finfo(t_raw.dtype if t_raw.dtype.kind == "f" else float).eps
        )
        if t.size != n:
            raise FormatError(
                f"{path}: time variable {time!r} has {t.size} values for {n} samples; "
                "expected one time per sample"
            )
        rate = check_time_stamps(t, path, 0, unit="sample")
        if t[0] != 0:
            extra["t0_s"] = float(t[0])
    given = []
    for key, value in (("fs", fs), ("dt", dt)):
        if value is None:
            continue
        number = (
            _scalar(fetch(value), f"variable {value!r}", path) if isinstance(value, str) else value
        )
        try:
            given.append(float(number) if key == "fs" else fs_from_dt(float(number)))
        except (TypeError, ValueError) as err:
            raise ParameterError(f"read({path}): {key}={value!r} is not a number") from err
    for r in given:
        if not np.isfinite(r) or r <= 0:
            raise FormatError(f"{path}: sampling rate {r} Hz; expected a positive number")
        if rate is not None and not np.isclose(r, rate, rtol=rtol):
            raise FormatError(
                f"{path}: the time vector gives {rate} Hz but fs/dt give {r} Hz; expected the "
                f"same rate (within {rtol:.1e}, the precision of the time vector)"
            )
        rate = r
    if rate is None:
        raise FormatError(
            f"{path}: no sampling rate; expected time='<name>', fs=<Hz or name> or dt=<s or name>"
        )
    if units is None:
        raise FormatError(
            f"{path}: the file stores no units for channels {names}; expected units=[...] "
            "(one per channel)"
        )
    var_attrs = {"t0_s": extra.pop("t0_s")} if "t0_s" in extra else None
    variables = [build_time_history(block, rate, names, units, quantity, attrs=var_attrs)]
    if spectra:
        if frequency is None:
            raise FormatError(f"{path}: spectra given without frequency='<name>' of the axis in Hz")
        f = fetch(frequency).astype(np.float64).reshape(-1)
        for kind, names_k in spectra.items():
            names_k = [names_k] if isinstance(names_k, str) else list(names_k)
            values = np.stack([fetch(nm).reshape(-1) for nm in names_k])
            if values.shape[1] != f.size:
                raise FormatError(
                    f"{path}: spectrum {names_k} has {values.shape[1]} lines; frequency "
                    f"{frequency!r} has {f.size}"
                )
            da = xr.DataArray(
                values,
                dims=("channel", "frequency"),
                coords={"channel": np.array(names_k, dtype=object), "frequency": f},
                name=str(kind),
                attrs={"units": (spectrum_units or {}).get(kind, "unspecified")},
            )
            da.frequency.attrs["units"] = "Hz"
            variables.append(da)
    return assemble(variables, extra)
