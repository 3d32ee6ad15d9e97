"""Checks and coercions shared by the spectral estimators."""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..errors import DimensionError, FormatError, ParameterError

__all__ = ["as_time_history", "sampling_rate", "select_channels", "channel_coord"]


def as_time_history(x, *, name: str = "x") -> xr.DataArray:
    """Return ``x`` as a DataArray with dims ``("channel", "time")``.

    Accepts a DataArray with dims ``("channel", "time")`` (any order) or ``("time",)``,
    or an ``xarray.Dataset`` holding a ``"time_history"`` variable (the output of
    ``mvtk.io.read``).

    Examples
    --------
    A single channel with dims ``("time",)`` becomes one row of ``("channel", "time")``:

    >>> from mvtk import testing
    >>> x = testing.sdof_free_decay(12.0, 0.01, 256.0, 2.0).isel(channel=0)
    >>> as_time_history(x).dims
    ('channel', 'time')
    """
    if isinstance(x, xr.Dataset):
        if "time_history" not in x.data_vars:
            raise FormatError(
                f"{name}: expected a Dataset with a 'time_history' variable (from mvtk.io.read), "
                f"found variables {sorted(map(str, x.data_vars))}"
            )
        x = x["time_history"]
    if not isinstance(x, xr.DataArray):
        raise ParameterError(
            f"{name}: expected an xarray.DataArray with dims ('channel', 'time') or a Dataset "
            f"with 'time_history', got {type(x).__name__}"
        )
    if x.dims == ("time",):
        x = x.expand_dims(channel=[str(x.name) if x.name is not None else "ch0"])
    if set(x.dims) != {"channel", "time"}:
        raise DimensionError(
            f"{name}: expected dims ('channel', 'time'), found {tuple(map(str, x.dims))}"
        )
    x = x.transpose("channel", "time")
    if "time" not in x.coords:
        raise FormatError(f"{name}: the 'time' coordinate (s) is missing; fs is derived from it")
    if not np.issubdtype(x.dtype, np.number) or np.iscomplexobj(x.values[:, :0]):
        raise FormatError(f"{name}: expected real numeric samples, found dtype {x.dtype}")
    # a sum propagates NaN/inf: one cheap pass; the exact per-sample check only on failure
    if not np.isfinite(np.sum(x.values, axis=-1)).all():
        finite = np.isfinite(x.values).all(axis=-1)
    else:
        finite = np.ones(x.sizes["channel"], dtype=bool)
    if not finite.all():
        bad = [str(c) for c, ok in zip(x["channel"].values, finite) if not ok]
        counts = [int(np.count_nonzero(~np.isfinite(x.values[i])))
                  for i in np.flatnonzero(~finite)]
        raise FormatError(
            f"{name}: channel(s) {bad} hold {counts} missing or non-finite samples (NaN/inf); "
            "spectra and decay fits need complete records: cut or fill them first"
        )
    return x


def sampling_rate(x: xr.DataArray, fs: float | None = None, *, name: str = "x") -> float:
    """Sampling rate in Hz derived from the ``time`` coordinate (uniform sampling required).

    If ``fs`` is also given it must agree with the coordinate to 1e-6 relative.

    Examples
    --------
    >>> from mvtk import testing
    >>> x = testing.sdof_free_decay(12.0, 0.01, 256.0, 2.0)
    >>> sampling_rate(x)
    256.0
    """
    t = np.asarray(x["time"].values, dtype=float)
    if t.size < 2:
        raise DimensionError(f"{name}: need at least 2 time samples, found {t.size}")
    dt = np.diff(t)
    span = t[-1] - t[0]
    if not span > 0:
        raise FormatError(f"{name}: time coordinate must increase, runs {t[0]} .. {t[-1]} s")
    fs_t = (t.size - 1) / span
    dev = np.max(np.abs(dt * fs_t - 1.0))
    if dev > 1e-6 * max(1.0, t.size * 1e-3):
        i = int(np.argmax(np.abs(dt * fs_t - 1.0)))
        raise FormatError(
            f"{name}: time coordinate is not uniformly sampled: step {dt[i]!r} s at sample {i} "
            f"vs mean step {1 / fs_t!r} s"
        )
    if fs is not None:
        if not (np.isfinite(fs) and fs > 0):
            raise ParameterError(f"fs must be a finite sampling rate > 0 Hz, got {fs!r}")
        if abs(fs - fs_t) > 1e-6 * fs_t:
            raise ParameterError(
                f"{name}: fs={fs!r} Hz disagrees with the time coordinate ({fs_t!r} Hz)"
            )
        return float(fs)
    return float(fs_t)


def channel_coord(x: xr.DataArray, coord: str, default: str = "") -> list[str]:
    """Per-channel coordinate values as strings (``default`` where the coord is absent)."""
    if coord in x.coords and x[coord].dims == ("channel",):
        return [str(v) for v in x[coord].values]
    return [default] * x.sizes["channel"]


def select_channels(x: xr.DataArray, sel, *, name: str) -> xr.DataArray:
    """Channels picked by name, list of names, integer positions, or a quantity filter.

    ``sel`` may be a channel name, a list of names/positions, or a dict such as
    ``{"quantity": "force"}`` matched against channel coordinates.
    """
    channels = [str(c) for c in x["channel"].values]
    if isinstance(sel, dict):
        mask = np.ones(len(channels), dtype=bool)
        for key, value in sel.items():
            mask &= np.array([v == str(value) for v in channel_coord(x, key, default="\0")])
        if not mask.any():
            raise ParameterError(
                f"{name}: no channel matches {sel}; channels {channels} have "
                + ", ".join(f"{k}={channel_coord(x, k)}" for k in sel)
            )
        return x.isel(channel=np.flatnonzero(mask))
    items = [sel] if isinstance(sel, (str, int, np.integer)) else list(sel)
    idx = []
    for item in items:
        if isinstance(item, (int, np.integer)):
            if not -len(channels) <= item < len(channels):
                raise ParameterError(
                    f"{name}: channel position {item} out of range for {len(channels)} channels"
                )
            idx.append(int(item) % len(channels))
        elif str(item) in channels:
            idx.append(channels.index(str(item)))
        else:
            raise ParameterError(f"{name}: channel {item!r} not found; valid: {channels}")
    if not idx:
        raise ParameterError(f"{name}: empty channel selection")
    return x.isel(channel=idx)
