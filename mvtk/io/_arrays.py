"""Shared logic of the array-container readers (MAT, HDF5): pick variables, orient, build."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import FormatError, ParameterError
from ._build import assemble
from ._model import build_time_history, fs_from_dt, infer_quantity, normalize_units
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
    **options,
) -> xr.Dataset:
    """Assemble a Dataset from named arrays of a container file.

    ``get(name)`` returns the array stored under ``name``; ``data`` names one 2-D array
    or a list of 1-D arrays (one per channel); ``time`` names a time vector in s, ``fs``
    / ``dt`` give the rate as a number or as the name of a scalar variable. ``spectra``
    without ``data`` reads a file that holds spectra / FRFs only. ``options`` are the
    FRF options ``response``, ``reference``, ``response_units``, ``reference_units``,
    ``phase_units`` (see :func:`mvtk.io._containers.read_mat`).
    """

    def fetch(name):
        if not isinstance(name, str):
            raise ParameterError(f"read({path}): variable names must be strings, got {name!r}")
        if name not in names_available:
            raise FormatError(
                f"{path}: no variable {name!r}; the file holds: {', '.join(names_available)}"
            )
        return np.asarray(get(name))

    if data is None and spectra:
        return _spectra_only(path, fetch, frequency, spectra, spectrum_units, attrs, options)
    if data is None:
        raise FormatError(
            f"{path}: which variables hold the samples is not stated; expected data='<name>' or "
            f"data=[...] among: {', '.join(names_available)} (with time=, fs= or dt=, units=); "
            "for a file holding spectra or FRFs only: spectra={'frf': '<name>'}, frequency="
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
            f"{path}: no sampling rate; expected time='<name>', fs=<Hz or name> or dt=<s or name> "
            "(on the command line --set time=NAME, --fs HZ or --set dt=S)"
        )
    if units is None:
        raise FormatError(
            f"{path}: the file stores no units for channels {names}; expected units=[...] "
            "(one per channel; on the command line --units U1 U2 ...)"
        )
    var_attrs = {"t0_s": extra.pop("t0_s")} if "t0_s" in extra else None
    variables = [build_time_history(block, rate, names, units, quantity, attrs=var_attrs)]
    if spectra:
        variables += _spectra(path, fetch, frequency, spectra, spectrum_units, variables[0],
                              options)
    return assemble(variables, extra)


#: Two-point functions: stored as (response, reference, frequency) matrices.
TWO_POINT = ("frf", "coherence", "cross_spectrum", "transmissibility")
_FRF_TYPES = {
    ("acceleration", "force"): "accelerance",
    ("velocity", "force"): "mobility",
    ("displacement", "force"): "receptance",
}


def _complex_from(path: Path, fetch, spec, kind: str, phase_units: str) -> tuple[np.ndarray, str]:
    """Values of one spectrum entry: a name, or {magnitude, phase} / {real, imag} names."""
    if isinstance(spec, str):
        arr = fetch(spec)
        return arr, spec
    if isinstance(spec, Mapping):
        keys = set(spec)
        if keys >= {"real", "imag"}:
            re_, im_ = fetch(spec["real"]), fetch(spec["imag"])
            if re_.shape != im_.shape:
                raise FormatError(
                    f"{path}: {kind}: real part {spec['real']!r} has shape {re_.shape}, imaginary "
                    f"part {spec['imag']!r} {im_.shape}; expected equal shapes"
                )
            return re_.astype(np.float64) + 1j * im_.astype(np.float64), str(spec["real"])
        if keys >= {"magnitude", "phase"}:
            mag, ph = fetch(spec["magnitude"]), fetch(spec["phase"])
            if mag.shape != ph.shape:
                raise FormatError(
                    f"{path}: {kind}: magnitude {spec['magnitude']!r} has shape {mag.shape}, "
                    f"phase {spec['phase']!r} {ph.shape}; expected equal shapes"
                )
            unit = str(spec.get("phase_units", phase_units)).lower()
            if unit not in ("deg", "rad"):
                raise ParameterError(
                    f"read({path}): phase_units={unit!r}; expected 'deg' or 'rad'"
                )
            ph = np.deg2rad(ph.astype(np.float64)) if unit == "deg" else ph.astype(np.float64)
            return mag.astype(np.float64) * np.exp(1j * ph), str(spec["magnitude"])
    raise ParameterError(
        f"read({path}): spectra[{kind!r}] = {spec!r}; expected a variable name, a list of "
        "names, {'magnitude': name, 'phase': name} or {'real': name, 'imag': name}"
    )


def _frequency(path: Path, fetch, frequency) -> np.ndarray:
    if frequency is None:
        raise FormatError(f"{path}: spectra given without frequency='<name>' of the axis in Hz")
    if isinstance(frequency, str):
        f = fetch(frequency)
    else:
        f = np.asarray(frequency)
    f = np.asarray(f, dtype=np.float64).reshape(-1)
    return f


def _lines_last(arr: np.ndarray, n_f: int, what: str, path: Path) -> np.ndarray:
    """Array with the frequency axis last: (n_f,), (k, n_f) or (k, m, n_f)."""
    arr = np.asarray(arr)
    arr = arr.reshape([d for d in arr.shape if d != 1] or [1]) if arr.ndim > 1 else arr
    axes = [k for k, d in enumerate(arr.shape) if d == n_f]
    if not axes:
        raise FormatError(
            f"{path}: {what} has shape {arr.shape}; expected {n_f} lines along one axis (the "
            "frequency axis)"
        )
    return np.moveaxis(arr, axes[-1] if axes[-1] == arr.ndim - 1 else axes[0], -1)


def _names(value, n: int, default: list[str], what: str, path: Path) -> list[str]:
    if value is None:
        return default
    names = [value] if isinstance(value, str) else [str(v) for v in value]
    if len(names) != n:
        raise ParameterError(f"read({path}): {what} has {len(names)} names; expected {n}")
    return names


def _split_ratio_units(units: str | None) -> tuple[str | None, str | None]:
    """``"m/s^2/N"`` -> ("m/s^2", "N") when the last part is a known unit."""
    from ._model import UNITS_BY_QUANTITY

    if not units or "/" not in units:
        return None, None
    head, _, tail = units.rpartition("/")
    known = {u for group in UNITS_BY_QUANTITY.values() for u in group}
    tail = normalize_units(tail)
    return (normalize_units(head), tail) if tail in known and head else (None, None)


def _channel_info(name: str, units, th: xr.DataArray | None) -> tuple[str, str]:
    """(units, quantity) of a response/reference channel: time history, option, or unknown."""
    if units is not None:
        u = normalize_units(str(units))
        return u, infer_quantity(u)
    if th is not None and name in [str(c) for c in th.channel.values]:
        sel = th.sel(channel=name)
        return str(sel.units.values), str(sel.quantity.values)
    return "unspecified", "other"


def _per(value, k: int):
    if value is None or isinstance(value, str):
        return value
    return list(value)[k]


def _two_point(path, fetch, f, kind, spec, units, th, options) -> xr.DataArray:
    entries = list(spec) if isinstance(spec, list | tuple) else [spec]
    blocks, labels = [], []
    for entry in entries:
        values, label = _complex_from(path, fetch, entry, kind, options.get("phase_units", "deg"))
        values = _lines_last(values, f.size, f"{kind} variable {label!r}", path)
        if values.ndim == 1:
            values = values[np.newaxis, np.newaxis, :]
        elif values.ndim == 2:
            values = values[:, np.newaxis, :]
        blocks.append(values)
        labels.append(label)
    shapes = {b.shape[1:] for b in blocks}
    if len(shapes) != 1:
        raise FormatError(f"{path}: {kind} variables {labels} have different shapes")
    block = np.concatenate(blocks, axis=0)
    n_resp, n_ref = block.shape[:2]
    default_resp = labels if len(labels) == n_resp else [f"{labels[0]}[{k}]" for k in range(n_resp)]
    resp = _names(options.get("response"), n_resp, default_resp, "response", path)
    ref = _names(
        options.get("reference"),
        n_ref,
        ["reference"] if n_ref == 1 else [f"reference {k + 1}" for k in range(n_ref)],
        "reference",
        path,
    )
    ru, fu = _split_ratio_units(units)
    r_info = [
        _channel_info(n, _per(options.get("response_units"), k) or ru, th)
        for k, n in enumerate(resp)
    ]
    f_info = [
        _channel_info(n, _per(options.get("reference_units"), k) or fu, th)
        for k, n in enumerate(ref)
    ]
    if kind != "coherence" and np.iscomplexobj(block) is False:
        block = block.astype(np.float64)
    if kind == "coherence":
        block = np.real(block).astype(np.float64)
    attrs = {"units": units or "unspecified", "source_variables": " ".join(labels)}
    if kind in ("frf", "transmissibility"):
        types = {_FRF_TYPES.get((r[1], q[1]), "other") for r in r_info for q in f_info}
        attrs["frf_type"] = types.pop() if len(types) == 1 else "other"
        attrs["estimator"] = "measured"
        if units is None and len({r[0] for r in r_info}) == 1 and len({q[0] for q in f_info}) == 1:
            if r_info[0][0] != "unspecified" and f_info[0][0] != "unspecified":
                attrs["units"] = f"{r_info[0][0]}/{f_info[0][0]}"
    da = xr.DataArray(
        block,
        dims=("response", "reference", "frequency"),
        coords={
            "response": np.array(resp, dtype=object),
            "reference": np.array(ref, dtype=object),
            "frequency": f,
            "units": ("response", np.array([r[0] for r in r_info], dtype=object)),
            "quantity": ("response", np.array([r[1] for r in r_info], dtype=object)),
            "reference_units": ("reference", np.array([q[0] for q in f_info], dtype=object)),
            "reference_quantity": ("reference", np.array([q[1] for q in f_info], dtype=object)),
        },
        name=str(kind),
        attrs=attrs,
    )
    da.frequency.attrs["units"] = "Hz"
    return da


def _auto(path, fetch, f, kind, spec, units, th) -> xr.DataArray:
    """(channel, frequency) spectrum; on the time-history channels when it maps onto them."""
    if isinstance(spec, Mapping) and not ({"real", "imag"} <= set(spec) or
                                          {"magnitude", "phase"} <= set(spec)):
        names = [str(k) for k in spec]
        entries = list(spec.values())
    else:
        entries = list(spec) if isinstance(spec, list | tuple) else [spec]
        names = None
    rows, labels = [], []
    for entry in entries:
        values, label = _complex_from(path, fetch, entry, kind, "deg")
        values = _lines_last(values, f.size, f"{kind} variable {label!r}", path)
        rows.append(values.reshape(-1, f.size))
        labels.append(label)
    values = np.concatenate(rows, axis=0)
    th_names = [str(c) for c in th.channel.values] if th is not None else []
    if names is None:
        names = (
            th_names
            if th is not None and len(th_names) == values.shape[0]
            else labels
            if len(labels) == values.shape[0]
            else [f"{labels[0]}[{k}]" for k in range(values.shape[0])]
        )
    coords = {"channel": np.array(names, dtype=object), "frequency": f}
    if th is not None and names == th_names:  # same channel dim as the time history
        for c in th.coords:
            if th[c].dims == ("channel",) and c != "channel":
                coords[str(c)] = ("channel", th[c].values)
    elif th is None or not set(names) & set(th_names):
        coords["units"] = ("channel", np.array(["unspecified"] * len(names), dtype=object))
        coords["quantity"] = ("channel", np.array(["other"] * len(names), dtype=object))
    da = xr.DataArray(
        values,
        dims=("channel", "frequency"),
        coords=coords,
        name=str(kind),
        attrs={"units": units or "unspecified", "source_variables": " ".join(labels)},
    )
    da.frequency.attrs["units"] = "Hz"
    return da


def _spectra(path, fetch, frequency, spectra, spectrum_units, th, options) -> list:
    if not isinstance(spectra, Mapping):
        raise ParameterError(
            f"read({path}): spectra={spectra!r}; expected a dict such as "
            "{'frf': 'Hf_chan_2', 'coherence': 'Hf_coh_chan_2'}"
        )
    f = _frequency(path, fetch, frequency)
    out = []
    first = None  # later two-point functions share the response/reference axes of the first
    order = sorted(spectra, key=lambda k: k != "frf")
    for kind in order:
        spec = spectra[kind]
        units = (spectrum_units or {}).get(kind)
        if kind in TWO_POINT:
            opts = dict(options)
            if first is not None:
                for key, coord in (
                    ("response", "response"),
                    ("reference", "reference"),
                    ("response_units", "units"),
                    ("reference_units", "reference_units"),
                ):
                    if opts.get(key) is None:
                        opts[key] = [str(v) for v in first[coord].values]
            try:
                da = _two_point(path, fetch, f, kind, spec, units, th, opts)
            except ParameterError:
                if first is None:
                    raise
                da = _two_point(path, fetch, f, kind, spec, units, th, options)
            first = da if first is None else first
            out.append(da)
        else:
            out.append(_auto(path, fetch, f, kind, spec, units, th))
    if th is not None:  # "units"/"quantity" are the time-history channel coordinates
        out = [
            da.rename({"units": "response_units", "quantity": "response_quantity"})
            if "response" in da.dims
            else da
            for da in out
        ]
    return out


def _spectra_only(path, fetch, frequency, spectra, spectrum_units, attrs, options):
    return assemble(
        _spectra(path, fetch, frequency, spectra, spectrum_units, None, options), dict(attrs or {})
    )
