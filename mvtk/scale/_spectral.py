"""Chunked Welch spectra and per-channel estimators on dask-backed time histories."""

from __future__ import annotations

import numpy as np
import scipy.fft
import scipy.signal

from .._optional import require_dask
from ..errors import DimensionError, FormatError, ParameterError

__all__ = ["psd", "csd", "frf", "map_channels"]


def _as_lazy_history(x):
    """DataArray with time last: dims (..., "channel", "time")."""
    import xarray as xr

    if isinstance(x, xr.Dataset):
        if "time_history" not in x.data_vars:
            raise FormatError(
                "expected a Dataset with a 'time_history' variable (from mvtk.io.read or "
                f"open_campaign), found variables {sorted(map(str, x.data_vars))}"
            )
        x = x["time_history"]
    if not isinstance(x, xr.DataArray):
        raise ParameterError(
            "expected an xarray.DataArray with dims (..., 'channel', 'time') or a Dataset with "
            f"'time_history', got {type(x).__name__}"
        )
    if "time" not in x.dims or "channel" not in x.dims:
        raise DimensionError(
            f"expected dims (..., 'channel', 'time'), found {tuple(map(str, x.dims))}"
        )
    if "time" not in x.coords:
        raise FormatError("the 'time' coordinate (s) is missing; fs is derived from it")
    others = [d for d in x.dims if d not in ("channel", "time")]
    return x.transpose(*others, "channel", "time")


def _fs(x, fs):
    from ..signal import sampling_rate

    return sampling_rate(x.isel({d: 0 for d in x.dims if d not in ("channel", "time")}), fs)


def _segment_sums(block: np.ndarray, n_starts: int, step: int, nperseg: int,
                  win: np.ndarray, detrend) -> np.ndarray:
    """Sum over the segments starting at 0, step, ... (n_starts of them) of |rfft|^2."""
    nf = nperseg // 2 + 1
    out = np.zeros(block.shape[:-1] + (nf,))
    if n_starts <= 0:
        return out
    offs = np.arange(nperseg)
    per_seg = max(1, int(np.prod(block.shape[:-1]))) * nperseg * 24
    sub = max(1, (32 * 2**20) // per_seg)
    for s0 in range(0, n_starts, sub):
        idx = (np.arange(s0, min(s0 + sub, n_starts)) * step)[:, None] + offs
        seg = block[..., idx]  # (..., nseg, nperseg)
        if detrend == "constant":
            seg = seg - seg.mean(axis=-1, keepdims=True)
        elif detrend == "linear":
            seg = scipy.signal.detrend(seg, axis=-1, type="linear")
        spec = scipy.fft.rfft(seg * win, axis=-1)
        out += np.sum(spec.real**2 + spec.imag**2, axis=-2)
    return out


def _cross_sums(block: np.ndarray, n_starts: int, step: int, nperseg: int, win: np.ndarray,
                detrend, iy: np.ndarray, ir: np.ndarray) -> np.ndarray:
    """Sum over segments of ``Y_i conj(R_j)``: shape (..., len(iy), len(ir), nf)."""
    nf = nperseg // 2 + 1
    lead = block.shape[:-2]
    out = np.zeros(lead + (len(iy), len(ir), nf), dtype=complex)
    if n_starts <= 0:
        return out
    offs = np.arange(nperseg)
    per_seg = max(1, int(np.prod(block.shape[:-1]))) * nperseg * 24
    sub = max(1, (32 * 2**20) // per_seg)
    for s0 in range(0, n_starts, sub):
        idx = (np.arange(s0, min(s0 + sub, n_starts)) * step)[:, None] + offs
        seg = block[..., idx]  # (..., channel, nseg, nperseg)
        if detrend == "constant":
            seg = seg - seg.mean(axis=-1, keepdims=True)
        elif detrend == "linear":
            seg = scipy.signal.detrend(seg, axis=-1, type="linear")
        spec = scipy.fft.rfft(seg * win, axis=-1)
        out += np.einsum("...isf,...jsf->...ijf", spec[..., iy, :, :], spec[..., ir, :, :].conj())
    return out


def _blocks(data, n: int, nperseg: int, step: int, n_seg: int, lead_chunks):
    """(piece, n_starts) per block: pieces hold the segments starting in each block."""
    chunk0 = data.chunks[-1][0]
    block = max(int(np.ceil(max(chunk0, nperseg) / step)), 1) * step
    data = data.rechunk(lead_chunks + (block,))
    for b0 in range(0, n_seg * step, block):
        first = b0 // step
        k = min(block // step, n_seg - first)
        stop = min(b0 + (k - 1) * step + nperseg, n)
        yield data[..., b0:stop].rechunk(lead_chunks + (-1,)), k


def csd(
    x,
    reference=None,
    fs: float | None = None,
    window="hann",
    nperseg: int | None = None,
    noverlap: int | None = None,
    detrend="constant",
    scaling: str = "density",
    *,
    compute: bool = True,
):
    """Welch cross-spectral density matrix of a dask-backed time history, chunk by chunk.

    Same numbers (to round-off), dims and coordinates as :func:`mvtk.signal.csd`
    (``S[i, j] = E[Y_i conj(R_j)]``, one-sided), computed block by block like
    :func:`psd`; a leading ``record`` dim is kept.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Dims ``(..., "channel", "time")``.
    reference : str, int, list or dict, optional
        Reference channels (names, positions or a coordinate filter such as
        ``{"quantity": "force"}``); default every channel.
    fs, window, nperseg, noverlap, detrend, scaling
        As in :func:`mvtk.signal.csd`.
    compute : bool
        Return computed values (default) or a lazy DataArray.

    Returns
    -------
    xarray.DataArray
        Complex, dims ``(..., "response", "reference", "frequency")``, frequency in Hz.
    """
    require_dask("mvtk.scale.csd")
    import dask.array as dsa
    import xarray as xr

    from ..signal._input import select_channels
    from ..signal._spectral import (
        _one_sided_factor,
        _pair_coords,
        _window,
        welch_segments_params,
    )

    x = _as_lazy_history(x)
    fs = _fs(x, fs)
    n = x.sizes["time"]
    nperseg, noverlap, window = welch_segments_params(n, fs, nperseg, noverlap, window)
    if scaling not in ("density", "spectrum"):
        raise ParameterError(f"scaling must be 'density' or 'spectrum', got {scaling!r}")
    if detrend not in ("constant", "linear", False, None):
        raise ParameterError(f"detrend must be 'constant', 'linear' or False, got {detrend!r}")
    names = [str(c) for c in x["channel"].values]
    ref = x if reference is None else select_channels(x, reference, name="reference")
    ir = np.array([names.index(str(c)) for c in ref["channel"].values])
    iy = np.arange(len(names))
    win = _window(window, nperseg)
    step = nperseg - noverlap
    n_seg = (n - nperseg) // step + 1
    nf = nperseg // 2 + 1
    data = x.data if isinstance(x.data, dsa.Array) else dsa.from_array(x.values)
    lead_chunks = data.chunks[:-2] + ((len(names),),)
    data = data.rechunk(lead_chunks + (data.chunks[-1],))
    parts = [
        dsa.map_blocks(_cross_sums, piece, k, step, nperseg, win, detrend, iy, ir,
                       dtype=complex, new_axis=[data.ndim],
                       chunks=data.chunks[:-2] + ((len(iy),), (len(ir),), (nf,)))
        for piece, k in _blocks(data, n, nperseg, step, n_seg, lead_chunks)
    ]
    total = dsa.stack(parts, axis=0).sum(axis=0)
    if scaling == "density":
        scale = 1.0 / (fs * np.sum(win**2))
    else:
        scale = 1.0 / np.sum(win) ** 2
    sxy = total * (scale * _one_sided_factor(nf, nperseg) / n_seg)
    f = scipy.fft.rfftfreq(nperseg, 1 / fs)
    lead_dims = tuple(x.dims[:-2])
    y0 = x.isel({d: 0 for d in lead_dims})
    coords = _pair_coords(y0, y0.isel(channel=ir), f)
    for name, c in x.coords.items():
        if c.dims and set(c.dims) <= set(lead_dims):
            coords[name] = c
    out = xr.DataArray(
        sxy, dims=lead_dims + ("response", "reference", "frequency"), coords=coords,
        attrs={**{k: v for k, v in x.attrs.items() if k != "t0_s"}, "spectrum": "csd",
               "scaling": scaling, "window": str(window), "nperseg": nperseg,
               "noverlap": noverlap, "fs": fs, "df_hz": fs / nperseg, "n_averages": n_seg},
    )
    out.name = "csd"
    return out.compute() if compute else out


def _h_and_coherence(gyr, grr, gyy, estimator):
    """H1 (``G_yr G_rr^-1``) or H2 (``G_yy / conj(G_yr)``) and ordinary coherence."""
    nr = grr.shape[0]
    grr_diag = np.real(np.einsum("jjf->jf", grr))
    with np.errstate(divide="ignore", invalid="ignore"):
        if estimator == "H2":
            h = gyy[:, None, :] / np.conj(gyr)
        elif nr == 1:
            h = gyr / grr[0, 0][None, None, :]
        else:
            a = np.moveaxis(grr, -1, 0).transpose(0, 2, 1)
            b = np.moveaxis(gyr, -1, 0).transpose(0, 2, 1)
            h = np.moveaxis(np.linalg.solve(a, b).transpose(0, 2, 1), 0, -1)
        coh = np.abs(gyr) ** 2 / (gyy[:, None, :] * grr_diag[None, :, :])
    return h, np.clip(coh, 0.0, 1.0)


def frf(
    x,
    reference,
    response=None,
    *,
    estimator: str = "H1",
    fs: float | None = None,
    window=None,
    nperseg: int | None = None,
    noverlap: int | None = None,
    detrend="constant",
):
    """H1/H2 FRFs and coherence of a dask-backed record under random excitation.

    The chunked counterpart of :func:`mvtk.signal.frf` with ``excitation="random"``:
    one pass over the data accumulates the Welch cross-spectral sums of all channels
    block by block (as :func:`csd`), then the FRFs are formed exactly as the in-memory
    function does, giving the same Dataset to round-off. A leading ``record`` dim is
    kept (one FRF per record). Impact testing (hit detection on the whole force record)
    is not chunked: run :func:`mvtk.signal.frf` per record.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Dims ``(..., "channel", "time")``, dask-backed or not.
    reference, response, estimator, fs, window, nperseg, noverlap, detrend
        As in :func:`mvtk.signal.frf` (default window Hann).

    Returns
    -------
    xarray.Dataset
        ``frf`` and ``coherence``, dims ``(..., "response", "reference", "frequency")``,
        with the coordinates and attrs of :func:`mvtk.signal.frf`.
    """
    require_dask("mvtk.scale.frf")
    import dask
    import xarray as xr

    from ..signal import frf_kind
    from ..signal._input import channel_coord, select_channels
    from ..signal._spectral import _pair_coords, welch_segments_params

    if estimator not in ("H1", "H2"):
        raise ParameterError(f"estimator must be 'H1' or 'H2', got {estimator!r}")
    if detrend not in ("constant", "linear", False, None):
        raise ParameterError(f"detrend must be 'constant', 'linear' or False, got {detrend!r}")
    x = _as_lazy_history(x)
    fs = _fs(x, fs)
    ref = select_channels(x, reference, name="reference")
    ref_names = [str(c) for c in ref["channel"].values]
    names = [str(c) for c in x["channel"].values]
    if response is None:
        keep = [i for i, c in enumerate(names) if c not in ref_names]
        if not keep:
            raise ParameterError("frf: every channel is a reference; no response channel left")
        resp = x.isel(channel=keep)
    else:
        resp = select_channels(x, response, name="response")
    nr = len(ref_names)
    if estimator == "H2" and nr != 1:
        raise ParameterError(f"estimator 'H2' needs exactly one reference, got {nr}")
    n = x.sizes["time"]
    nperseg, noverlap, window = welch_segments_params(n, fs, nperseg, noverlap, window)
    iy = np.array([names.index(str(c)) for c in resp["channel"].values])
    ir = np.array([names.index(c) for c in ref_names])
    # the full cross-spectral matrix in one pass gives gyr, grr and gyy
    full = csd(x, None, fs=fs, window=window, nperseg=nperseg, noverlap=noverlap,
               detrend=detrend, compute=False)
    (g,) = dask.compute(full.data)
    lead_dims = tuple(x.dims[:-2])
    lead_shape = g.shape[:-3]
    h = np.empty(lead_shape + (len(iy), nr, g.shape[-1]), dtype=complex)
    coh = np.empty(h.shape)
    for idx in np.ndindex(*lead_shape):
        gi = g[idx]
        gyr = gi[np.ix_(iy, ir)]
        grr = gi[np.ix_(ir, ir)]
        gyy = np.real(np.einsum("iif->if", gi))[iy]
        h[idx], coh[idx] = _h_and_coherence(gyr, grr, gyy, estimator)
    f = full["frequency"].values
    y0 = resp.isel({d: 0 for d in lead_dims})
    r0 = ref.isel({d: 0 for d in lead_dims})
    coords = _pair_coords(y0, r0, f)
    ru = channel_coord(y0, "units")
    fu = channel_coord(r0, "units")
    coords["units"] = (("response", "reference"),
                       np.array([[f"{a}/{b}" for b in fu] for a in ru], dtype=object))
    for name, c in x.coords.items():
        if c.dims and set(c.dims) <= set(lead_dims):
            coords[name] = c
    rq = set(channel_coord(y0, "quantity"))
    fq = set(channel_coord(r0, "quantity"))
    kind = frf_kind(rq.pop(), fq.pop()) if len(rq) == 1 and len(fq) == 1 else None
    attrs = {"estimator": estimator, "excitation": "random", "fs": fs,
             "window": str(window), "noverlap": noverlap, "nperseg": int(nperseg),
             "nfft": int(nperseg), "df_hz": fs / nperseg, "resolution_hz": fs / nperseg,
             "resolution_reason": "nperseg given", "n_averages": int(full.attrs["n_averages"]),
             "kind": kind if kind is not None else "",
             "frf_type": kind if kind is not None else "other"}
    dims = lead_dims + ("response", "reference", "frequency")
    ds = xr.Dataset({"frf": (dims, h), "coherence": (dims, coh)}, coords=coords, attrs=attrs)
    ds["frf"].attrs = dict(attrs)
    return ds


def psd(
    x,
    fs: float | None = None,
    window="hann",
    nperseg: int | None = None,
    noverlap: int | None = None,
    detrend="constant",
    scaling: str = "density",
    *,
    combine_records: bool = False,
    compute: bool = True,
):
    """Welch PSD of a dask-backed (or in-memory) time history, chunk by chunk.

    Gives the numbers of :func:`mvtk.signal.psd` (hence :func:`scipy.signal.welch`
    with ``average="mean"``) to floating-point round-off, without loading the record:
    the record is cut into blocks whose length is a multiple of the segment step
    ``nperseg - noverlap`` (and at least ``nperseg``); each task sums ``|FFT|^2`` of
    the segments that *start* in its block, reading the first ``noverlap`` samples of
    the next block for the segments that straddle the boundary; the block sums are
    added and scaled exactly like scipy's mean. Memory per task: about one block plus
    its segment spectra.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Dims ``(..., "channel", "time")`` (e.g. ``("record", "channel", "time")`` from
        :func:`open_campaign`), dask-backed or not, or a Dataset with ``time_history``.
    fs : float, optional
        Sampling rate in Hz, derived from ``time`` and checked if given.
    window, nperseg, noverlap, detrend, scaling
        As in :func:`mvtk.signal.psd` (window a name, tuple or array; detrend
        ``"constant"``, ``"linear"`` or ``False``).
    combine_records : bool
        With a ``record`` dim: average the segments of all records into one spectrum
        per channel (equal-length records, so the plain mean of record spectra).
    compute : bool
        Return computed values (default) or a lazy dask-backed DataArray.

    Returns
    -------
    xarray.DataArray
        Dims ``(..., "channel", "frequency")``, frequency in Hz, ``units`` coordinate
        ``"(u)^2/Hz"`` (``"(u)^2"`` for ``scaling="spectrum"``), the attrs of
        :func:`mvtk.signal.psd` (``nperseg``, ``noverlap``, ``df_hz``, ``n_averages``...).

    Notes
    -----
    Non-finite samples are not searched for (that would need a pass over the data):
    they make the spectrum of their channel NaN rather than silently wrong.
    """
    require_dask("mvtk.scale.psd")
    import dask.array as dsa
    import xarray as xr

    from ..signal._input import channel_coord
    from ..signal._spectral import _one_sided_factor, _window, welch_segments_params

    x = _as_lazy_history(x)
    fs = _fs(x, fs)
    n = x.sizes["time"]
    nperseg, noverlap, window = welch_segments_params(n, fs, nperseg, noverlap, window)
    if scaling not in ("density", "spectrum"):
        raise ParameterError(f"scaling must be 'density' or 'spectrum', got {scaling!r}")
    if detrend not in ("constant", "linear", False, None):
        raise ParameterError(f"detrend must be 'constant', 'linear' or False, got {detrend!r}")
    if combine_records and "record" not in x.dims:
        raise DimensionError(
            f"combine_records=True needs a 'record' dim, found {tuple(map(str, x.dims))}"
        )
    win = _window(window, nperseg)
    step = nperseg - noverlap
    n_seg = (n - nperseg) // step + 1
    data = x.data if isinstance(x.data, dsa.Array) else dsa.from_array(x.values)
    nf = nperseg // 2 + 1
    parts = [
        dsa.map_blocks(_segment_sums, piece, k, step, nperseg, win, detrend,
                       dtype=float, chunks=piece.chunks[:-1] + ((nf,),))
        for piece, k in _blocks(data, n, nperseg, step, n_seg, data.chunks[:-1])
    ]
    total = dsa.stack(parts, axis=0).sum(axis=0)
    if scaling == "density":
        scale = 1.0 / (fs * np.sum(win**2))
    else:
        scale = 1.0 / np.sum(win) ** 2
    pxx = total * (scale * _one_sided_factor(nf, nperseg) / n_seg)
    dims = tuple(x.dims[:-1]) + ("frequency",)
    n_avg = n_seg
    if combine_records:
        pxx = pxx.mean(axis=dims.index("record"))
        dims = tuple(d for d in dims if d != "record")
        n_avg = n_seg * x.sizes["record"]
    f = scipy.fft.rfftfreq(nperseg, 1 / fs)
    suffix = "^2/Hz" if scaling == "density" else "^2"
    units = [f"({u}){suffix}" for u in channel_coord(x, "units")]
    coords = {k: v for k, v in x.coords.items()
              if "time" not in v.dims and set(v.dims) <= set(dims)}
    out = xr.DataArray(pxx, dims=dims, coords={**coords, "frequency": f})
    out = out.assign_coords(units=("channel", units))
    out["frequency"].attrs["units"] = "Hz"
    out.attrs = {
        **{k: v for k, v in x.attrs.items() if k != "t0_s"}, "spectrum": "psd",
        "scaling": scaling, "window": str(window), "nperseg": nperseg, "noverlap": noverlap,
        "fs": fs, "df_hz": fs / nperseg, "n_averages": n_avg, "average": "mean",
    }
    out.name = "psd"
    return out.compute() if compute else out


def map_channels(
    func,
    x,
    *,
    output_dims: tuple[str, ...] = (),
    output_sizes: dict | None = None,
    output_dtype=float,
    kwargs: dict | None = None,
):
    """Apply a per-channel estimator to every channel (and record) in parallel.

    A thin :func:`xarray.apply_ufunc` wrapper with ``dask="parallelized"``: ``func``
    receives one channel's samples as a 1-D numpy array (the whole ``time`` axis; it
    is rechunked into one chunk per channel, so one channel must fit in a worker) and
    returns a scalar or an array of shape ``output_sizes``.

    Parameters
    ----------
    func : callable
        ``func(samples_1d, **kwargs) -> float or ndarray``. Must be picklable (a module
        level function) to run on a distributed cluster.
    x : xarray.DataArray or xarray.Dataset
        Dims ``(..., "channel", "time")``, dask-backed or in memory.
    output_dims : tuple of str
        Names of the dims of ``func``'s result (``()`` for a scalar).
    output_sizes : dict, optional
        Sizes of new ``output_dims`` (required by dask for dims not in ``x``).
    output_dtype : dtype
        dtype of the result.
    kwargs : dict, optional
        Keyword arguments of ``func`` (e.g. ``{"fs": 1024.0}``).

    Returns
    -------
    xarray.DataArray
        Dims ``(..., "channel", *output_dims)``, lazy when ``x`` is dask-backed (call
        ``.compute()``).
    """
    require_dask("mvtk.scale.map_channels")
    import xarray as xr

    if not callable(func):
        raise ParameterError(f"map_channels: func must be callable, got {type(func).__name__}")
    x = _as_lazy_history(x)
    if x.chunks is not None:
        x = x.chunk({"time": -1})
    output_dims = tuple(output_dims)
    missing = [d for d in output_dims if d not in x.dims and d not in (output_sizes or {})]
    if missing:
        raise ParameterError(
            f"map_channels: output_sizes must give the length of new output dims {missing}"
        )
    return xr.apply_ufunc(
        func, x, input_core_dims=[["time"]], output_core_dims=[list(output_dims)],
        vectorize=True, dask="parallelized", output_dtypes=[output_dtype],
        dask_gufunc_kwargs={"output_sizes": dict(output_sizes or {})},
        kwargs=dict(kwargs or {}), keep_attrs=False,
    )
