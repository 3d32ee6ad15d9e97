"""Welch auto- and cross-spectral densities on DESIGN.md time histories."""

from __future__ import annotations

import numpy as np
import scipy.fft
import scipy.signal
import xarray as xr

from ..errors import ParameterError
from ._input import as_time_history, channel_coord, sampling_rate, select_channels

__all__ = ["psd", "csd", "welch_segments_params", "accumulate_cross"]

_BLOCK_BYTES = 64 * 2**20  # memory budget of one block of segment spectra


def welch_segments_params(n: int, fs: float, nperseg, noverlap, window) -> tuple[int, int, str]:
    """Validate and default ``nperseg``/``noverlap`` (scipy.signal.welch rules)."""
    if window is None:
        window = "hann"
    if nperseg is None:
        nperseg = min(256, n)
    nperseg = int(nperseg)
    if nperseg < 2 or nperseg > n:
        raise ParameterError(f"nperseg must be in [2, {n}] (record length), got {nperseg}")
    if noverlap is None:
        noverlap = nperseg // 2
    noverlap = int(noverlap)
    if not 0 <= noverlap < nperseg:
        raise ParameterError(f"noverlap must be in [0, nperseg={nperseg}), got {noverlap}")
    return nperseg, noverlap, window


def _window(window, nperseg: int) -> np.ndarray:
    if isinstance(window, (str, tuple)):
        try:
            return scipy.signal.get_window(window, nperseg)
        except ValueError as err:
            raise ParameterError(f"unknown window {window!r} for scipy.signal.get_window") from err
    w = np.asarray(window, dtype=float)
    if w.shape != (nperseg,):
        raise ParameterError(f"window array must have shape ({nperseg},), got {w.shape}")
    return w


def _detrend(seg: np.ndarray, detrend) -> np.ndarray:
    if detrend in (False, None):
        return seg
    if detrend == "constant":
        return seg - seg.mean(axis=-1, keepdims=True)
    if detrend == "linear":
        return scipy.signal.detrend(seg, axis=-1, type="linear")
    raise ParameterError(f"detrend must be 'constant', 'linear' or False, got {detrend!r}")


def _one_sided_factor(nfreq: int, nperseg: int) -> np.ndarray:
    fac = np.full(nfreq, 2.0)
    fac[0] = 1.0
    if nperseg % 2 == 0:
        fac[-1] = 1.0
    return fac


def accumulate_cross(
    y: np.ndarray,
    r: np.ndarray,
    starts: np.ndarray,
    nperseg: int,
    win_y: np.ndarray,
    win_r: np.ndarray,
    detrend,
    nfft: int | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sum over segments of ``Y conj(R)``, ``R conj(R)`` and ``|Y|**2``.

    Segments start at ``starts``; ``win_y``/``win_r`` are the windows applied to the
    response and reference segments (they differ for impact tests). Processed in
    blocks of segments so memory stays bounded; ``nfft`` > ``nperseg`` zero-pads each
    segment. Returns unscaled sums
    ``(Gyr (ny, nr, nf), Grr (nr, nr, nf), Gyy (ny, nf))``.
    """
    ny, nr = y.shape[0], r.shape[0]
    nfft = nperseg if nfft is None else int(nfft)
    nf = nfft // 2 + 1
    gyr = np.zeros((ny, nr, nf), dtype=complex)
    grr = np.zeros((nr, nr, nf), dtype=complex)
    gyy = np.zeros((ny, nf))
    per_seg = (ny + nr) * nf * 16 + (ny + nr) * nfft * 8
    block = max(1, int(_BLOCK_BYTES // max(per_seg, 1)))
    offs = np.arange(nperseg)
    for b0 in range(0, len(starts), block):
        idx = starts[b0:b0 + block, None] + offs  # (nb, nperseg)
        ys = _detrend(y[:, idx], detrend) * win_y  # (ny, nb, nperseg)
        rs = _detrend(r[:, idx], detrend) * win_r
        yf = scipy.fft.rfft(ys, nfft, axis=-1)
        rf = scipy.fft.rfft(rs, nfft, axis=-1)
        gyr += np.einsum("isf,jsf->ijf", yf, rf.conj())
        grr += np.einsum("isf,jsf->ijf", rf, rf.conj())
        gyy += np.sum(yf.real**2 + yf.imag**2, axis=1)
    return gyr, grr, gyy


def _segment_starts(n: int, nperseg: int, noverlap: int) -> np.ndarray:
    step = nperseg - noverlap
    return np.arange(0, n - nperseg + 1, step)


def psd(
    x,
    fs: float | None = None,
    window="hann",
    nperseg="auto",
    noverlap: int | None = None,
    detrend="constant",
    scaling: str = "density",
    average: str = "mean",
) -> xr.DataArray:
    """One-sided power spectral density of every channel by Welch's method.

    Wraps :func:`scipy.signal.welch` (same argument names and defaults, except
    ``nperseg="auto"``: a segment that resolves the narrowest peak) on the
    DESIGN.md time-history conventions. For a free decay or another transient analysed
    for damping, use ``window="boxcar"`` and ``nperseg`` = the record length: the
    default Hann window underestimates the half-power damping of a decay by about a half.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Time history, dims ``("channel", "time")``, or a Dataset with ``"time_history"``.
    fs : float, optional
        Sampling rate in Hz; derived from the ``time`` coordinate and checked if given.
    window, noverlap, detrend, scaling, average
        As in :func:`scipy.signal.welch`.
    nperseg : int, "auto" or None
        Segment length. None: scipy's default (256 samples or the record). ``"auto"``
        (default): chosen from the data as for a random-excitation FRF (the narrowest clear peak
        spans 8 lines at -3 dB with at least 8 averages; see
        :func:`mvtk.signal.auto_segment`), stated in ``attrs["resolution_reason"]``.

    Returns
    -------
    xarray.DataArray
        Dims ``("channel", "frequency")``, frequency in Hz; the ``units`` coordinate is
        ``"(u)^2/Hz"`` for ``scaling="density"`` (``"(u)^2"`` for ``"spectrum"``);
        ``quantity`` is kept; ``attrs`` record the Welch parameters, ``df_hz`` and
        ``spectrum="psd"`` (a power quantity: take its square root before any
        amplitude-based method such as half-power).

    Examples
    --------
    A 50 Hz sine of amplitude 1 m/s^2 sampled at 1024 Hz for 4 s. The PSD peaks at
    50 Hz and its integral is the mean square, A**2 / 2 = 0.5 (m/s^2)^2 (Parseval):

    >>> from mvtk import testing
    >>> t = np.arange(4096) / 1024.0
    >>> x = testing.make_time_history(np.sin(2 * np.pi * 50.0 * t), 1024.0,
    ...                               quantity="acceleration", units="m/s^2")
    >>> p = psd(x, nperseg=1024)
    >>> df = float(p.frequency[1] - p.frequency[0])
    >>> float(p.frequency[p.isel(channel=0).argmax("frequency")]), round(float(p.sum()) * df, 3)
    (50.0, 0.5)
    >>> str(p.units.values[0])
    '(m/s^2)^2/Hz'
    """
    x = as_time_history(x)
    fs = sampling_rate(x, fs)
    n = x.sizes["time"]
    reason = "nperseg given"
    if nperseg == "auto":
        from ._frf import auto_segment

        data = x.values

        def curves(seg):
            win = _window(window, seg)
            _, p = scipy.signal.welch(data, fs=fs, window=win, nperseg=seg,
                                      noverlap=seg // 2, detrend=detrend)
            return np.sqrt(p), None, len(_segment_starts(n, seg, seg // 2))

        nperseg, reason = auto_segment(n, fs, curves)
        noverlap = None
    nperseg, noverlap, window = welch_segments_params(n, fs, nperseg, noverlap, window)
    if scaling not in ("density", "spectrum"):
        raise ParameterError(f"scaling must be 'density' or 'spectrum', got {scaling!r}")
    win = _window(window, nperseg)
    f, pxx = scipy.signal.welch(
        x.values, fs=fs, window=win, nperseg=nperseg, noverlap=noverlap, detrend=detrend,
        scaling=scaling, average=average, axis=-1,
    )
    suffix = "^2/Hz" if scaling == "density" else "^2"
    units = [f"({u}){suffix}" for u in channel_coord(x, "units")]
    coords = {k: v for k, v in x.coords.items() if v.dims == ("channel",)}
    out = xr.DataArray(pxx, dims=("channel", "frequency"), coords={**coords, "frequency": f})
    out = out.assign_coords(units=("channel", units))
    out["frequency"].attrs["units"] = "Hz"
    out.attrs = {
        **x.attrs, "spectrum": "psd", "scaling": scaling, "window": str(window),
        "nperseg": nperseg, "noverlap": noverlap, "fs": fs, "df_hz": fs / nperseg,
        "n_averages": len(_segment_starts(n, nperseg, noverlap)), "average": average,
        "resolution_hz": fs / nperseg, "resolution_reason": reason,
    }
    out.name = "psd"
    return out


def csd(
    x,
    reference=None,
    fs: float | None = None,
    window="hann",
    nperseg: int | None = None,
    noverlap: int | None = None,
    detrend="constant",
    scaling: str = "density",
) -> xr.DataArray:
    """One-sided cross-spectral density matrix by Welch's method.

    ``S[i, j](f) = E[Y_i(f) conj(R_j(f))]`` scaled like :func:`scipy.signal.csd`
    (``S[i, j]`` equals ``scipy.signal.csd(r_j, y_i)``), where ``y`` are the channels
    of ``x`` and ``r`` the ``reference`` channels.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Time history, dims ``("channel", "time")``.
    reference : str, int, list or dict, optional
        Reference channels: names, positions or a coordinate filter such as
        ``{"quantity": "force"}``. Default: every channel (full matrix).

    Returns
    -------
    xarray.DataArray
        Complex, dims ``("response", "reference", "frequency")``, frequency in Hz.

    Examples
    --------
    Channel ``b`` is twice channel ``a``: the cross spectrum S[b, a] is then exactly
    2 x S[a, a] on every line:

    >>> from mvtk import testing
    >>> a = np.random.default_rng(0).standard_normal(4096)
    >>> x = testing.make_time_history(np.vstack([a, 2 * a]), 1024.0, names=["a", "b"],
    ...                               quantity="force", units="N")
    >>> s = csd(x, reference="a", nperseg=256)
    >>> s.dims
    ('response', 'reference', 'frequency')
    >>> ratio = s.sel(response="b", reference="a") / s.sel(response="a", reference="a")
    >>> round(float(np.abs(ratio).max()), 6)
    2.0
    """
    x = as_time_history(x)
    fs = sampling_rate(x, fs)
    n = x.sizes["time"]
    nperseg, noverlap, window = welch_segments_params(n, fs, nperseg, noverlap, window)
    ref = x if reference is None else select_channels(x, reference, name="reference")
    win = _window(window, nperseg)
    starts = _segment_starts(n, nperseg, noverlap)
    gyr, _, _ = accumulate_cross(x.values, ref.values, starts, nperseg, win, win, detrend)
    if scaling == "density":
        scale = 1.0 / (fs * np.sum(win**2))
    elif scaling == "spectrum":
        scale = 1.0 / np.sum(win) ** 2
    else:
        raise ParameterError(f"scaling must be 'density' or 'spectrum', got {scaling!r}")
    gyr *= scale * _one_sided_factor(gyr.shape[-1], nperseg) / len(starts)
    f = scipy.fft.rfftfreq(nperseg, 1 / fs)
    out = xr.DataArray(
        gyr, dims=("response", "reference", "frequency"),
        coords=_pair_coords(x, ref, f),
        attrs={**x.attrs, "spectrum": "csd", "scaling": scaling, "window": str(window),
               "nperseg": nperseg, "noverlap": noverlap, "fs": fs, "df_hz": fs / nperseg,
               "n_averages": len(starts)},
    )
    out.name = "csd"
    return out


def _pair_coords(y: xr.DataArray, r: xr.DataArray, f: np.ndarray) -> dict:
    return {
        "response": [str(c) for c in y["channel"].values],
        "reference": [str(c) for c in r["channel"].values],
        "frequency": ("frequency", f, {"units": "Hz"}),
        "response_quantity": ("response", channel_coord(y, "quantity")),
        "response_units": ("response", channel_coord(y, "units")),
        "reference_quantity": ("reference", channel_coord(r, "quantity")),
        "reference_units": ("reference", channel_coord(r, "units")),
    }
