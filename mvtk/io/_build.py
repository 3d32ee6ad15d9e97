"""Assemble reader output into one Dataset, renaming dims that would collide."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr

__all__ = ["assemble", "clean_attrs"]


def _along(obj, dim: str) -> dict[str, np.ndarray]:
    return {str(c): np.asarray(obj[c].values) for c in obj.coords if obj[c].dims == (dim,)}


def _same(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> bool:
    if a.keys() != b.keys():
        return False
    return all(a[k].shape == b[k].shape and np.array_equal(a[k], b[k]) for k in a)


def _suffix(name: str, k: int) -> str:
    return name if k == 1 else f"{name}_{k}"


def assemble(variables: Sequence[xr.DataArray], attrs: Mapping | None = None) -> xr.Dataset:
    """Put named DataArrays into one Dataset.

    A dim whose name is already used with other coordinate values (another channel list,
    another time or frequency grid) is renamed ``dim_2``, ``dim_3``..., together with
    every coordinate along it (``units`` -> ``units_2``). Variable names that repeat get
    the same kind of suffix (``time_history``, ``time_history_2``).
    """
    ds = xr.Dataset(attrs=dict(attrs or {}))
    for var in variables:
        renames: dict[str, str] = {}
        for dim in var.dims:
            own = _along(var, dim)
            k = 1
            while True:
                cand = _suffix(dim, k)
                if cand not in ds.dims:
                    break
                mapped = {_suffix(c, k): v for c, v in own.items()}
                if ds.sizes[cand] == var.sizes[dim] and _same(_along(ds, cand), mapped):
                    break
                k += 1
            if k > 1:
                renames[dim] = _suffix(dim, k)
                renames.update({c: _suffix(c, k) for c in own if c != dim})
        if renames:
            var = var.rename(renames)
        base = str(var.name)
        k = 1
        while _suffix(base, k) in ds.data_vars:
            k += 1
        ds[_suffix(base, k)] = var
    return ds


def clean_attrs(attrs: Mapping) -> dict:
    """Keep attrs that netCDF stores losslessly: str, int, float (others become str)."""
    out = {}
    for key, value in attrs.items():
        if value is None:
            continue
        if isinstance(value, bool | np.bool_):
            out[str(key)] = int(value)
        elif isinstance(value, int | np.integer):
            out[str(key)] = int(value)
        elif isinstance(value, float | np.floating):
            out[str(key)] = float(value)
        elif isinstance(value, bytes):
            out[str(key)] = value.decode("utf-8", errors="replace")
        else:
            out[str(key)] = str(value)
    return out
