"""Many measurement files opened lazily as one dask-backed Dataset (:func:`open_campaign`)."""

from __future__ import annotations

import glob as _glob
import os
import warnings
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._optional import require_dask
from ..errors import DataRepairWarning, FormatError, MvtkError, ParameterError

__all__ = ["open_campaign", "DEFAULT_TIME_CHUNK"]

DEFAULT_TIME_CHUNK = 2**18
"""Default chunk length along ``time`` (samples): 2 MiB per float64 channel."""

_CHANNEL_COORDS = ("quantity", "units", "node", "direction")
_HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"


@dataclass
class _FileMeta:
    """What the metadata pass learns about one file (no samples are read)."""

    path: str
    format: str
    channels: tuple[str, ...]
    channel_coords: dict
    fs: float
    n: int
    dtype: np.dtype
    t0_s: float | None
    start_time: str
    attrs: dict = field(default_factory=dict)
    data: object = None  # dask array (channel, time), set after the pass
    handle: object = None  # the lazily opened xarray.Dataset (closed if the file is dropped)


def _expand(paths_or_glob) -> list[str]:
    if isinstance(paths_or_glob, (str, os.PathLike)):
        text = os.fspath(paths_or_glob)
        if Path(text).is_dir():
            paths = sorted(str(p) for p in Path(text).iterdir() if p.is_file())
        elif any(c in text for c in "*?["):
            paths = sorted(_glob.glob(text))
        else:
            paths = [text]
        if not paths:
            raise FileNotFoundError(f"open_campaign: no file matches {text!r}")
        return paths
    try:
        paths = [os.fspath(p) for p in paths_or_glob]
    except TypeError as err:
        raise ParameterError(
            "open_campaign: expected a glob pattern, a directory or a list of paths, got "
            f"{type(paths_or_glob).__name__}"
        ) from err
    if not paths:
        raise ParameterError("open_campaign: the list of paths is empty")
    return paths


def _time_chunk(chunks) -> int:
    if chunks is None:
        return DEFAULT_TIME_CHUNK
    if isinstance(chunks, dict):
        chunks = chunks.get("time", DEFAULT_TIME_CHUNK)
    if isinstance(chunks, (int, np.integer)) and not isinstance(chunks, bool) and chunks > 0:
        return int(chunks)
    raise ParameterError(
        f"open_campaign: chunks must be a positive number of time samples or "
        f"{{'time': n}}, got {chunks!r}"
    )


def _meta_from_dataarray(path: str, fmt: str, da, attrs: dict) -> _FileMeta:
    """Metadata of a ``("channel", "time")`` time history (lazy or in memory)."""
    from ..signal import sampling_rate

    if set(da.dims) != {"channel", "time"}:
        raise FormatError(f"time_history has dims {tuple(da.dims)}; expected ('channel', 'time')")
    da = da.transpose("channel", "time")
    fs = sampling_rate(da, name="time_history")
    coords = {}
    for name in _CHANNEL_COORDS:
        if name in da.coords and da[name].dims == ("channel",):
            coords[name] = tuple(np.asarray(da[name].values).tolist())
    merged = {**attrs, **da.attrs}
    t0 = merged.get("t0_s")
    t0 = float(t0) if t0 is not None else None
    t_first = float(da["time"].values[0])
    if t0 is None and t_first != 0.0:
        t0 = t_first
    start = merged.get("start_time", "")
    return _FileMeta(
        path=path, format=fmt, channels=tuple(str(c) for c in da["channel"].values),
        channel_coords=coords, fs=fs, n=int(da.sizes["time"]), dtype=np.dtype(da.dtype),
        t0_s=t0, start_time=str(start), attrs=merged,
    )


def _lazy_netcdf(path: str, time_chunk: int):
    """Open an mvtk netCDF4 file without reading samples; None if it is not one."""
    import xarray as xr

    with open(path, "rb") as fh:
        head = fh.read(8)
    if head != _HDF5_MAGIC:
        return None
    try:
        ds = xr.open_dataset(path, engine="h5netcdf", decode_times=False,
                             chunks={"time": time_chunk, "channel": -1})
    except (OSError, ValueError, KeyError, TypeError, RuntimeError):
        return None
    if "time_history" not in ds.data_vars:
        ds.close()
        return None
    return ds


def _read_meta(path: str, fmt: str | None, options: dict):
    """Metadata of one file via a full mvtk.io.read (for formats without a lazy path).

    Returns ``(meta, None)`` or ``(None, reason)``; the samples are dropped.
    """
    from ..io import read

    try:
        ds = read(path, format=fmt, **options)
        if "time_history" not in ds.data_vars:
            return None, (f"no 'time_history' variable (found {sorted(map(str, ds.data_vars))}); "
                          "a campaign stacks time histories")
        meta = _meta_from_dataarray(path, ds.attrs.get("format", fmt or ""),
                                    ds["time_history"], dict(ds.attrs))
        return meta, None
    except FileNotFoundError:
        return None, "no such file"
    except (MvtkError, OSError) as err:
        return None, f"{type(err).__name__}: {err}"


def _read_values(path: str, fmt: str | None, options: dict, channels: tuple, n: int):
    """Samples of one file (channel, time), checked against the metadata pass."""
    from ..io import read

    da = read(path, format=fmt, **options)["time_history"].transpose("channel", "time")
    found = tuple(str(c) for c in da["channel"].values)
    if found != channels or da.sizes["time"] != n:
        raise FormatError(
            f"{path}: changed since open_campaign checked it: expected channels {list(channels)} "
            f"x {n} samples, found {list(found)} x {da.sizes['time']}"
        )
    return np.asarray(da.values)


def _open_one(path: str, fmt: str | None, options: dict, time_chunk: int):
    """Try the lazy (metadata-only) path; return ``(meta, reason)`` or None to defer."""
    if not Path(path).is_file():
        return None, "no such file" if not Path(path).exists() else "not a regular file"
    if Path(path).stat().st_size == 0:
        return None, "the file is empty (0 bytes)"
    if options or fmt not in (None, "netcdf", "hdf5"):
        return None
    ds = _lazy_netcdf(path, time_chunk)
    if ds is None:
        return None
    try:
        meta = _meta_from_dataarray(path, "netcdf", ds["time_history"], dict(ds.attrs))
    except MvtkError as err:
        ds.close()
        return None, f"{type(err).__name__}: {err}"
    meta.data = ds["time_history"].transpose("channel", "time").data
    meta.handle = ds
    return meta, None


def _signature(m: _FileMeta, concat: str) -> tuple:
    sig = (m.channels, round(m.fs, 6), tuple(sorted(m.channel_coords.get("units", ()))))
    return sig + ((m.n,) if concat == "record" else ())


def _mismatch(m: _FileMeta, ref: _FileMeta, concat: str) -> str | None:
    if m.channels != ref.channels:
        return f"channels {list(m.channels)} differ from the campaign's {list(ref.channels)}"
    if abs(m.fs - ref.fs) > 1e-6 * ref.fs:
        return f"sampling rate {m.fs!r} Hz differs from the campaign's {ref.fs!r} Hz"
    if m.channel_coords.get("units") != ref.channel_coords.get("units"):
        return (f"channel units {list(m.channel_coords.get('units', ()))} differ from the "
                f"campaign's {list(ref.channel_coords.get('units', ()))}")
    if concat == "record" and m.n != ref.n:
        return (f"{m.n} samples per channel differ from the campaign's {ref.n} "
                "(records must have equal length; use concat='time' for contiguous files)")
    return None


def open_campaign(
    paths_or_glob,
    *,
    format: str | None = None,
    concat: str = "record",
    on_error: str = "raise",
    chunks=None,
    **read_options,
):
    """Open many measurement files as one lazy, dask-backed ``xarray.Dataset``.

    Every file is checked before any sample is read: mvtk netCDF4 files (the output of
    :func:`mvtk.io.write`) are opened lazily and only their header and ``time``
    coordinate are read; other formats are read once by :func:`mvtk.io.read` inside
    ``dask.delayed`` tasks (run on the active dask scheduler, e.g. a
    ``dask.distributed.Client``) that return only the metadata, and read again lazily
    when the samples are needed. All bad files are reported together.

    Parameters
    ----------
    paths_or_glob : str, path-like or sequence of paths
        A glob pattern (``"day1/*.nc"``), a directory (all its files), one path, or a
        list of paths. Globs and directories are sorted by name.
    format : str, optional
        Force the reader (see :func:`mvtk.io.list_formats`); detected per file otherwise.
    concat : {"record", "time"}
        ``"record"``: equal-length files are stacked along a new ``record`` dim
        (dims ``("record", "channel", "time")``). ``"time"``: files are joined end to end
        (dims ``("channel", "time")``); they must be contiguous (each file's ``t0_s``
        equal to the previous start plus its duration, within half a sample); files
        without ``t0_s`` are joined in the given order.
    on_error : {"raise", "skip"}
        ``"raise"``: one :class:`~mvtk.errors.FormatError` lists every bad file and its
        reason. ``"skip"``: bad files are left out, a
        :class:`~mvtk.errors.DataRepairWarning` lists them, and
        ``ds.attrs["skipped_files"]`` / ``ds.attrs["skipped_reasons"]`` record them.
    chunks : int or {"time": int}, optional
        Chunk length along ``time`` in samples (default :data:`DEFAULT_TIME_CHUNK`).
        Each chunk holds all channels of one record. Files read through ``mvtk.io.read``
        are loaded whole by one task before rechunking, so each must fit in a worker.
    **read_options
        Passed to :func:`mvtk.io.read` (forces the read path for every file).

    Returns
    -------
    xarray.Dataset
        ``time_history`` (dask-backed, float) with the DESIGN.md channel coordinates of
        the files; ``time = arange(n) / fs`` in s. With ``concat="record"`` the
        ``record`` coordinates ``source``, ``format``, ``t0_s`` (s, NaN if unknown) and
        ``start_time`` (str, ``""`` if unknown) describe each file; with
        ``concat="time"`` the variables ``file_source``, ``file_start_sample`` and
        ``file_t0_s`` (dim ``file``) do. ``attrs``: ``fs`` (Hz), ``concat``,
        ``n_files``, ``t0_s`` (time concat), ``skipped_files``, ``skipped_reasons``.

    Raises
    ------
    FileNotFoundError
        A glob pattern or path matches nothing.
    mvtk.errors.FormatError
        With ``on_error="raise"``: at least one file is unreadable, has no time history,
        or differs from the campaign majority (channels, units, sampling rate, length);
        with ``concat="time"``: the files are not contiguous. With ``"skip"``: no file
        is usable.
    mvtk.errors.ParameterError
        Invalid ``concat``, ``on_error`` or ``chunks``.
    mvtk.errors.MissingDependencyError
        dask is not installed.

    Examples
    --------
    Two runs of the same test, opened lazily along a new ``record`` dimension:

    >>> import pathlib, tempfile
    >>> from mvtk.io import time_history, write
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> for run in ("run1", "run2"):
    ...     _ = write(time_history(np.zeros((2, 1024)), 1024.0, ["acc1", "force"],
    ...                            ["m/s^2", "N"]), folder / f"{run}.nc")
    >>> campaign = open_campaign(str(folder / "*.nc"))
    >>> dict(campaign.sizes)
    {'channel': 2, 'time': 1024, 'record': 2}
    """
    dask = require_dask("open_campaign")
    import dask.array as dsa
    import xarray as xr

    if concat not in ("record", "time"):
        raise ParameterError(f"open_campaign: concat must be 'record' or 'time', got {concat!r}")
    if on_error not in ("raise", "skip"):
        raise ParameterError(f"open_campaign: on_error must be 'raise' or 'skip', got {on_error!r}")
    time_chunk = _time_chunk(chunks)
    paths = _expand(paths_or_glob)
    metas: dict[str, _FileMeta] = {}
    bad: dict[str, str] = {}
    deferred: list[str] = []
    for p in paths:
        got = _open_one(p, format, read_options, time_chunk)
        if got is None:
            deferred.append(p)
        elif got[0] is None:
            bad[p] = got[1]
        else:
            metas[p] = got[0]
    if deferred:
        tasks = [dask.delayed(_read_meta, pure=True)(p, format, read_options) for p in deferred]
        for p, (meta, reason) in zip(deferred, dask.compute(*tasks)):
            if meta is None:
                bad[p] = reason
                continue
            values = dask.delayed(_read_values, pure=True)(
                p, meta.format, read_options, meta.channels, meta.n)
            meta.data = dsa.from_delayed(values, shape=(len(meta.channels), meta.n),
                                         dtype=meta.dtype)
            metas[p] = meta
    if metas:
        counts = Counter(_signature(m, concat) for m in metas.values())
        ref_sig = counts.most_common(1)[0][0]
        ref = next(m for m in metas.values() if _signature(m, concat) == ref_sig)
        for p, m in list(metas.items()):
            reason = _mismatch(m, ref, concat)
            if reason is not None:
                bad[p] = reason
                if m.handle is not None:
                    m.handle.close()
                del metas[p]
    good = [p for p in paths if p in metas]
    bad_list = [(p, bad[p]) for p in paths if p in bad]
    if bad_list and (on_error == "raise" or not good):
        for m in metas.values():
            if m.handle is not None:
                m.handle.close()
        lines = "\n".join(f"  {p}: {r}" for p, r in bad_list)
        what = "no usable file" if not good else f"{len(bad_list)} of {len(paths)} files are bad"
        raise FormatError(
            f"open_campaign: {what} (expected readable time histories with the same channels, "
            f"units and sampling rate{', and length' if concat == 'record' else ''}):\n{lines}"
            + ("\npass on_error='skip' to leave them out" if good else "")
        )
    if bad_list:
        warnings.warn(
            f"open_campaign: skipped {len(bad_list)} of {len(paths)} files:\n"
            + "\n".join(f"  {p}: {r}" for p, r in bad_list),
            DataRepairWarning, stacklevel=2,
        )
    ms = [metas[p] for p in good]
    ref = ms[0]
    chan_coords = {"channel": list(ref.channels)}
    for name, values in ref.channel_coords.items():
        chan_coords[name] = ("channel", list(values))
    attrs = {
        "fs": ref.fs, "concat": concat, "n_files": len(ms),
        "format": ",".join(sorted({m.format for m in ms})),
        "skipped_files": [p for p, _ in bad_list],
        "skipped_reasons": [r for _, r in bad_list],
    }
    arrays = [m.data.rechunk((-1, time_chunk)) for m in ms]
    if concat == "record":
        data = dsa.stack(arrays, axis=0)
        t0 = np.array([np.nan if m.t0_s is None else m.t0_s for m in ms])
        coords = {
            **chan_coords, "time": ("time", np.arange(ref.n) / ref.fs, {"units": "s"}),
            "record": np.arange(len(ms)),
            "source": ("record", [m.path for m in ms]),
            "record_format": ("record", [m.format for m in ms]),
            "t0_s": ("record", t0, {"units": "s"}),
            "start_time": ("record", [m.start_time for m in ms]),
        }
        th = xr.DataArray(data, dims=("record", "channel", "time"), coords=coords,
                          attrs={"fs": ref.fs}, name="time_history")
        return xr.Dataset({"time_history": th}, attrs=attrs)
    ms = _order_contiguous(ms)
    starts = np.concatenate([[0], np.cumsum([m.n for m in ms])[:-1]])
    data = dsa.concatenate([m.data.rechunk((-1, time_chunk)) for m in ms], axis=1)
    data = data.rechunk((-1, time_chunk))
    n_total = int(sum(m.n for m in ms))
    t0 = ms[0].t0_s if ms[0].t0_s is not None else 0.0
    th = xr.DataArray(
        data, dims=("channel", "time"),
        coords={**chan_coords, "time": ("time", np.arange(n_total) / ref.fs, {"units": "s"})},
        attrs={"fs": ref.fs, "t0_s": t0}, name="time_history",
    )
    files = {
        "file_source": ("file", [m.path for m in ms]),
        "file_start_sample": ("file", starts.astype(np.int64)),
        "file_t0_s": ("file", np.array([np.nan if m.t0_s is None else m.t0_s for m in ms])),
    }
    return xr.Dataset({"time_history": th, **files}, attrs={**attrs, "t0_s": t0})


def _order_contiguous(ms: list[_FileMeta]) -> list[_FileMeta]:
    """Files in time order; FormatError listing every gap or overlap."""
    known = [m.t0_s is not None for m in ms]
    if not any(known):
        return ms
    if not all(known):
        missing = [m.path for m in ms if m.t0_s is None]
        raise FormatError(
            "open_campaign(concat='time'): some files state a start time (t0_s) and others "
            f"do not, so they cannot be ordered: no t0_s in {missing}"
        )
    ms = sorted(ms, key=lambda m: m.t0_s)
    problems = []
    for a, b in zip(ms[:-1], ms[1:]):
        expected = a.t0_s + a.n / a.fs
        if abs(b.t0_s - expected) > 0.5 / a.fs:
            problems.append(
                f"  {b.path}: starts at t0_s={b.t0_s!r} s, expected {expected!r} s "
                f"(end of {a.path}); gap {b.t0_s - expected:+.6g} s"
            )
    if problems:
        raise FormatError(
            "open_campaign(concat='time'): files are not contiguous in time (use "
            "concat='record' to stack them instead):\n" + "\n".join(problems)
        )
    return ms
