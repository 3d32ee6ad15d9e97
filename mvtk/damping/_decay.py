"""Time-domain damping of free decays: logarithmic decrement and envelope fit."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.signal

from ..errors import AccuracyWarning, DimensionError, ParameterError, ResolutionWarning
from ..signal._input import as_time_history, sampling_rate, select_channels

__all__ = ["DecayResult", "log_decrement", "envelope_fit"]


@dataclass(frozen=True)
class DecayResult:
    """Natural frequency and damping of one mode per channel from a free decay.

    Attributes
    ----------
    channel : tuple of str
        Channel names.
    fn_hz, zeta : numpy.ndarray
        Undamped natural frequency (Hz) and damping ratio.
    fn_std_hz, zeta_std : numpy.ndarray
        One-sigma standard errors from the regression (residuals treated as
        independent, so an optimistic bound when they are correlated).
    fd_hz : numpy.ndarray
        Damped natural frequency (Hz).
    t_start_s, t_end_s : numpy.ndarray
        Time span used for the fit (s).
    n_points : numpy.ndarray
        Number of peaks (log decrement) or samples (envelope) in the fit.
    method : str
        ``"log_decrement"``, ``"envelope_hilbert"`` or ``"envelope_peaks"``.
    band_hz : tuple of float or None
        Band-pass filter edges (Hz) applied before the fit.
    """

    channel: tuple[str, ...]
    fn_hz: np.ndarray
    zeta: np.ndarray
    fn_std_hz: np.ndarray
    zeta_std: np.ndarray
    fd_hz: np.ndarray
    t_start_s: np.ndarray
    t_end_s: np.ndarray
    n_points: np.ndarray
    method: str
    band_hz: tuple[float, float] | None

    def _repr_html_(self) -> str:
        return self.to_dataframe()._repr_html_()

    def to_dataframe(self) -> pd.DataFrame:
        """One row per channel."""
        return pd.DataFrame({
            "channel": list(self.channel), "fn_hz": self.fn_hz, "zeta": self.zeta,
            "fn_std_hz": self.fn_std_hz, "zeta_std": self.zeta_std, "fd_hz": self.fd_hz,
            "t_start_s": self.t_start_s, "t_end_s": self.t_end_s, "n_points": self.n_points,
            "method": self.method,
        })


def _prepare(x, channel, fn_hz, band_hz, order):
    x = as_time_history(x)
    if channel is not None:
        x = select_channels(x, channel, name="channel")
    fs = sampling_rate(x)
    data = np.asarray(x.values, dtype=float)
    if data.shape[1] < 16:
        raise DimensionError(f"free decay needs at least 16 samples, got {data.shape[1]}")
    if fn_hz is not None and not (np.isfinite(fn_hz) and 0 < fn_hz < fs / 2):
        raise ParameterError(f"fn_hz must be in (0, fs/2 = {fs / 2:g}) Hz, got {fn_hz!r}")
    if band_hz is None and fn_hz is not None:
        band_hz = (0.5 * fn_hz, min(1.5 * fn_hz, 0.49 * fs))
    if band_hz is not None:
        lo, hi = (float(v) for v in band_hz)
        if not 0 < lo < hi < fs / 2:
            raise ParameterError(
                f"band_hz must satisfy 0 < low < high < fs/2 = {fs / 2:g} Hz, got {band_hz!r}"
            )
        sos = scipy.signal.butter(order, [lo, hi], btype="bandpass", fs=fs, output="sos")
        data = scipy.signal.sosfiltfilt(sos, data, axis=-1)
        band_hz = (lo, hi)
    names = tuple(str(c) for c in x["channel"].values)
    return data, fs, names, band_hz


def _settle_s(band) -> float:
    """Time (s) for the band-pass filter's own transient to die out: 3 / bandwidth."""
    return 0.0 if band is None else 3.0 / (band[1] - band[0])


def _zeta_from(sigma, sigma_se, wd, wd_se):
    wn = np.hypot(sigma, wd)
    zeta = sigma / wn
    # d zeta/d sigma = wd^2 / wn^3, d zeta/d wd = -sigma wd / wn^3
    zse = np.hypot(wd**2 / wn**3 * sigma_se, sigma * wd / wn**3 * wd_se)
    wn_se = np.hypot(sigma / wn * sigma_se, wd / wn * wd_se)
    return wn / (2 * np.pi), zeta, wn_se / (2 * np.pi), zse


def _linfit(t, y, w=None):
    """Weighted straight line y = a + b t; returns b, se(b), a, residuals."""
    w = np.ones_like(t) if w is None else w
    A = np.vstack([np.ones_like(t), t]).T
    sw = np.sqrt(w)
    coef, *_ = np.linalg.lstsq(A * sw[:, None], y * sw, rcond=None)
    res = y - A @ coef
    dof = max(t.size - 2, 1)
    s2 = np.sum(w * res**2) / dof
    cov = s2 * np.linalg.inv((A * w[:, None]).T @ A)
    return coef[1], np.sqrt(cov[1, 1]), coef[0], res


def _peaks(sig, fs, fn_guess):
    dist = max(int(0.6 * fs / fn_guess), 1) if fn_guess else 1
    idx, _ = scipy.signal.find_peaks(sig, distance=dist)
    idx = idx[(idx > 0) & (idx < sig.size - 1)]
    ym, y0, yp = sig[idx - 1], sig[idx], sig[idx + 1]
    den = ym - 2 * y0 + yp
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(den < 0, 0.5 * (ym - yp) / den, 0.0)
    t = (idx + delta) / fs
    amp = y0 - 0.25 * (ym - yp) * delta
    return t, amp


def _fn_guess(sig, fs):
    nfft = int(2 ** np.ceil(np.log2(sig.size * 4)))
    spec = np.abs(np.fft.rfft(sig * np.hanning(sig.size), nfft))
    spec[0] = 0
    return np.fft.rfftfreq(nfft, 1 / fs)[int(np.argmax(spec))]


def log_decrement(
    x,
    fn_hz: float | None = None,
    *,
    channel=None,
    band_hz: tuple[float, float] | None = None,
    threshold: float = 0.05,
    skip_cycles: int = 1,
    order: int = 2,
) -> DecayResult:
    """Logarithmic decrement of a free decay, one mode per channel.

    Positive peaks are located (parabolic interpolation of time and amplitude), the
    decrement ``delta = ln(x_k / x_{k+1})`` is the slope of ``ln x_k`` against the
    peak number obtained by least squares (weighted by ``x_k**2``, since additive noise
    gives ``ln x_k`` a variance ~ ``1/x_k**2``) over all peaks above ``threshold`` x the
    largest (the classic two-peak formula ``ln(x_0/x_n)/n`` is its two-point case),
    and ``zeta = delta / sqrt(4 pi^2 + delta^2)``. The damped period is the slope of
    the peak times.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Free decay, dims ``("channel", "time")`` (or a Dataset with ``"time_history"``).
    fn_hz : float, optional
        Approximate frequency (Hz) of the mode; with it the signal is band-passed to
        ``band_hz`` (default 0.5..1.5 fn) with a zero-phase Butterworth filter.
    channel : str, int or list, optional
        Channels to analyse (default all).
    band_hz : (float, float), optional
        Band-pass edges in Hz (isolate one mode of a multi-mode decay).
    threshold : float
        Peaks below this fraction of the largest peak are ignored (noise floor).
    skip_cycles : int
        Peaks discarded after the largest one (impact transients). With a band-pass
        filter, peaks within ``3 / (high - low)`` s of either end are also dropped
        (the zero-phase filter's own transient).
    order : int
        Order of the Butterworth band-pass (applied forwards and backwards).

    Returns
    -------
    DecayResult
    """
    if not 0 < threshold < 1:
        raise ParameterError(f"threshold must be in (0, 1), got {threshold!r}")
    data, fs, names, band = _prepare(x, channel, fn_hz, band_hz, order)
    out = []
    for name, sig in zip(names, data):
        guess = fn_hz or _fn_guess(sig, fs)
        if fs / guess < 8:
            warnings.warn(
                f"log_decrement: channel {name!r} has only {fs / guess:.2g} samples per period "
                f"of the {guess:.4g} Hz mode; interpolated peak amplitudes are biased (up to "
                "about 1 % in zeta at 5 samples per period): use >= 8 samples per period or "
                "envelope_fit",
                ResolutionWarning, stacklevel=2,
            )
        t, amp = _peaks(sig, fs, guess)
        settle = _settle_s(band)
        keep = np.flatnonzero((amp > 0) & (t >= settle) & (t <= sig.size / fs - settle))
        t, amp = t[keep], amp[keep]
        if amp.size:
            i0 = int(np.argmax(amp))
            t, amp = t[i0 + int(skip_cycles):], amp[i0 + int(skip_cycles):]
        if amp.size:
            below = np.flatnonzero(amp < threshold * amp[0])
            if below.size:
                t, amp = t[: below[0]], amp[: below[0]]
        if amp.size < 3:
            raise ParameterError(
                f"log_decrement: channel {name!r} has {amp.size} usable peaks above "
                f"{threshold:g} x the first; need >= 3 (longer record, lower threshold or "
                "check fn_hz/band_hz)"
            )
        k = np.arange(amp.size, dtype=float)
        slope_t, se_t, _, _ = _linfit(k, t)  # damped period
        slope_a, se_a, _, _ = _linfit(k, np.log(amp), amp**2)
        delta, delta_se = -slope_a, se_a
        td, td_se = slope_t, se_t
        sigma, sigma_se = delta / td, np.hypot(delta_se / td, delta * td_se / td**2)
        wd, wd_se = 2 * np.pi / td, 2 * np.pi * td_se / td**2
        fn, z, fn_se, zse = _zeta_from(sigma, sigma_se, wd, wd_se)
        out.append((fn, z, fn_se, zse, wd / (2 * np.pi), t[0], t[-1], amp.size))
    return _result(names, out, "log_decrement", band)


def envelope_fit(
    x,
    fn_hz: float | None = None,
    *,
    channel=None,
    band_hz: tuple[float, float] | None = None,
    method: str = "hilbert",
    threshold: float = 0.05,
    trim: float = 0.05,
    order: int = 2,
) -> DecayResult:
    """Exponential fit of the envelope of a (band-passed) free decay.

    The envelope ``A(t)`` is the magnitude of the analytic signal (``method="hilbert"``)
    or the interpolated positive and negative peaks of ``|x|`` (``"peaks"``).
    ``ln A(t) = ln A0 - sigma t`` is fitted by least squares weighted by ``A**2``
    (the variance of ``ln A`` from additive noise is ``~ 1/A**2``) over the part above
    ``threshold`` x the initial envelope, after dropping ``trim`` of the record at
    each end (Hilbert and filter end effects). The damped frequency ``w_d`` is the
    slope of the unwrapped phase (Hilbert) or of the zero-crossing/peak times;
    ``w_n = sqrt(sigma**2 + w_d**2)``, ``zeta = sigma / w_n``.

    Parameters
    ----------
    x, fn_hz, channel, band_hz, threshold, order
        As in :func:`log_decrement`.
    method : {"hilbert", "peaks"}
    trim : float
        Fraction of the record dropped at both ends (Hilbert method). With a band-pass
        filter at least ``3 / (high - low)`` s is dropped at both ends (the filter's
        own transient).

    Returns
    -------
    DecayResult

    References
    ----------
    Feldman, "Hilbert transform in vibration analysis", MSSP 25 (2011) 735-802.
    """
    if method not in ("hilbert", "peaks"):
        raise ParameterError(f"method must be 'hilbert' or 'peaks', got {method!r}")
    if not 0 < threshold < 1:
        raise ParameterError(f"threshold must be in (0, 1), got {threshold!r}")
    if not 0 <= trim < 0.5:
        raise ParameterError(f"trim must be in [0, 0.5), got {trim!r}")
    data, fs, names, band = _prepare(x, channel, fn_hz, band_hz, order)
    out = []
    for name, sig in zip(names, data):
        n = sig.size
        if method == "hilbert":
            z = scipy.signal.hilbert(sig)
            env = np.abs(z)
            phase = np.unwrap(np.angle(z))
            t = np.arange(n) / fs
            settle = int(np.ceil(_settle_s(band) * fs))
            i0, i1 = max(int(trim * n), settle), n - max(int(trim * n), settle)
            t, env, phase = t[i0:i1], env[i0:i1], phase[i0:i1]
        else:
            guess = fn_hz or _fn_guess(sig, fs)
            tp, ap = _peaks(sig, fs, guess)
            tn, an = _peaks(-sig, fs, guess)
            t = np.r_[tp, tn]
            env = np.r_[ap, an]
            order_t = np.argsort(t)
            t, env = t[order_t], env[order_t]
            settle = _settle_s(band)
            keep = (env > 0) & (t >= settle) & (t <= n / fs - settle)
            t, env = t[keep], env[keep]
            phase = None
        if env.size:
            start = int(np.argmax(env[: max(1, env.size // 4)]))
            t, env = t[start:], env[start:]
            if phase is not None:
                phase = phase[start:]
            below = np.flatnonzero(env < threshold * env[0])
            stop = below[0] if below.size else env.size
            t, env = t[:stop], env[:stop]
            if phase is not None:
                phase = phase[:stop]
        if env.size < 8:
            raise ParameterError(
                f"envelope_fit: channel {name!r} has {env.size} envelope points above "
                f"{threshold:g} x the initial envelope; need >= 8"
            )
        slope, se, _, _ = _linfit(t, np.log(env), env**2)
        sigma, sigma_se = -slope, se
        if phase is not None:
            wd, wd_se, _, _ = _linfit(t, phase, env**2)
        else:
            # alternate +/- peaks are half a damped period apart
            k = np.arange(env.size, dtype=float)
            half, half_se, _, _ = _linfit(k, t)
            wd, wd_se = np.pi / half, np.pi * half_se / half**2
        if sigma <= 0:
            warnings.warn(
                f"envelope_fit: channel {name!r} envelope does not decay (sigma = {sigma:.3g} "
                "1/s); the record is not a free decay of a damped mode",
                AccuracyWarning, stacklevel=2,
            )
        cycles = (t[-1] - t[0]) * wd / (2 * np.pi)
        if cycles < 3:
            warnings.warn(
                f"envelope_fit: channel {name!r} fit spans only {cycles:.2g} cycles",
                ResolutionWarning, stacklevel=2,
            )
        fn, zz, fn_se, zse = _zeta_from(sigma, sigma_se, wd, wd_se)
        out.append((fn, zz, fn_se, zse, wd / (2 * np.pi), t[0], t[-1], env.size))
    return _result(names, out, f"envelope_{method}", band)


def _result(names, rows, method, band):
    cols = list(zip(*rows))
    arr = [np.asarray(c, dtype=float) for c in cols]
    return DecayResult(tuple(names), arr[0], arr[1], arr[2], arr[3], arr[4], arr[5], arr[6],
                       arr[7].astype(int), method, band)
