"""Time-domain damping of free decays: logarithmic decrement and envelope fit."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.signal

from ..errors import AccuracyWarning, DimensionError, ParameterError, ResolutionWarning
from ..signal._input import as_time_history, sampling_rate, select_channels
from ._common import NoEstimateError

__all__ = ["DecayResult", "log_decrement", "envelope_fit", "damping_vs_amplitude"]


@dataclass(frozen=True)
class DecayResult:
    """Natural frequency and damping of one mode per channel from a free decay.

    Attributes
    ----------
    channel : tuple of str
        Channel names.
    fn_hz, zeta : numpy.ndarray
        Undamped natural frequency (Hz) and damping ratio (NaN where the channel failed).
    fn_std_hz, zeta_std : numpy.ndarray
        One-sigma standard errors from the regression (residuals treated as
        independent, so an optimistic bound when they are correlated).
    fd_hz : numpy.ndarray
        Damped natural frequency (Hz).
    t_start_s, t_end_s : numpy.ndarray
        Time span used for the fit (s, on the record's own time axis).
    n_points : numpy.ndarray
        Number of peaks (log decrement) or samples (envelope) in the fit.
    method : str
        ``"log_decrement"``, ``"envelope_hilbert"`` or ``"envelope_peaks"``.
    band_hz : tuple of float or None
        Band-pass filter edges (Hz) applied before the fit (the first channel's when
        chosen per channel).
    zeta_early, zeta_late : numpy.ndarray
        Damping ratio fitted on the first and second half of the fit span (high and
        low amplitude): a difference beyond their errors is amplitude-dependent
        damping (see :func:`damping_vs_amplitude` for the full curve).
    reliable : numpy.ndarray of bool
        True when the fit is a clear exponential decay (see ``reason``).
    reason : tuple of str
        Why a channel is unreliable or failed (empty when reliable).

    Examples
    --------
    Returned by :func:`log_decrement` and :func:`envelope_fit`; ``to_dataframe`` gives
    one row per channel:

    >>> from mvtk import testing
    >>> res = log_decrement(testing.sdof_free_decay(12.0, 0.01, 256.0, 10.0), 12.0)
    >>> res.channel, bool(res.reliable[0])
    (('decay',), True)
    >>> res.to_dataframe()[["channel", "fn_hz", "zeta"]].round(4).values.tolist()
    [['decay', 12.0, 0.01]]
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
    zeta_early: np.ndarray | None = None
    zeta_late: np.ndarray | None = None
    reliable: np.ndarray | None = None
    reason: tuple[str, ...] = ()

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per channel."""
        n = len(self.channel)
        nan = np.full(n, np.nan)
        return pd.DataFrame({
            "channel": list(self.channel), "fn_hz": self.fn_hz, "zeta": self.zeta,
            "fn_std_hz": self.fn_std_hz, "zeta_std": self.zeta_std, "fd_hz": self.fd_hz,
            "t_start_s": self.t_start_s, "t_end_s": self.t_end_s, "n_points": self.n_points,
            "method": self.method,
            "zeta_early": nan if self.zeta_early is None else self.zeta_early,
            "zeta_late": nan if self.zeta_late is None else self.zeta_late,
            "reliable": np.ones(n, bool) if self.reliable is None else self.reliable,
            "reason": list(self.reason) if self.reason else [""] * n,
        })


# a fit is a clear decay when zeta is known to this relative standard error ...
_MAX_REL_SE = 0.1
# ... and the envelope falls by at least this factor across the fitted span
_MIN_DROP = 2.0
# ... over at least this many damped periods (fewer: the fit sees a dip, not a decay)
_MIN_CYCLES = 3.0
# ... with zeta of the high- and low-amplitude halves within this factor of each other
# (a single exponential; beyond it: beating of two modes, a noise floor, amplitude-
# dependent damping, or no decay at all)
_MAX_EARLY_LATE = 2.0
# ... with the straight line explaining at least this share of the (weighted) variation
# of ln(amplitude): clean decays from 40 down to 10 dB SNR and the real LVM hammer decays
# give 0.93-0.9999, two beating modes of amplitudes 1 : 0.8 give 0.45-0.53
_MIN_R2 = 0.8
# ... and the envelope never comes back above this fraction of the fit's first value
# after the fit (a free decay does not grow again: a second impact, continuous
# excitation or ambient noise does)
_MAX_REBOUND = 0.5


def _prepare(x, channel, fn_hz, band_hz, order, detrend, t_start_s, t_end_s):
    x = as_time_history(x)
    if channel is not None:
        x = select_channels(x, channel, name="channel")
    fs = sampling_rate(x)
    t = np.asarray(x["time"].values, dtype=float)
    lo = 0 if t_start_s is None else int(np.searchsorted(t, float(t_start_s), side="left"))
    hi = t.size if t_end_s is None else int(np.searchsorted(t, float(t_end_s), side="right"))
    if t_start_s is not None or t_end_s is not None:
        if hi - lo < 16:
            raise ParameterError(
                f"time window t_start_s={t_start_s!r}..t_end_s={t_end_s!r} s holds "
                f"{max(hi - lo, 0)} samples of the record {t[0]:g}..{t[-1]:g} s; need >= 16"
            )
    data = np.asarray(x.values[:, lo:hi], dtype=float)
    t0 = float(t[lo]) if t.size else 0.0
    if data.shape[1] < 16:
        raise DimensionError(f"free decay needs at least 16 samples, got {data.shape[1]}")
    if detrend not in ("linear", "constant", False, None):
        raise ParameterError(f"detrend must be 'linear', 'constant' or False, got {detrend!r}")
    if detrend:
        data = np.vstack([sig - _centre_line(sig, fs, detrend) for sig in data])
    if fn_hz is not None and not (np.isfinite(fn_hz) and 0 < fn_hz < fs / 2):
        raise ParameterError(f"fn_hz must be in (0, fs/2 = {fs / 2:g}) Hz, got {fn_hz!r}")
    if band_hz is None and fn_hz is not None:
        band_hz = (0.5 * fn_hz, min(1.5 * fn_hz, 0.49 * fs))
    if band_hz is not None:
        lo_b, hi_b = (float(v) for v in band_hz)
        if not 0 < lo_b < hi_b < fs / 2:
            raise ParameterError(
                f"band_hz must satisfy 0 < low < high < fs/2 = {fs / 2:g} Hz, got {band_hz!r}"
            )
        data = _bandpass(data, fs, (lo_b, hi_b), order)
        band_hz = (lo_b, hi_b)
    names = tuple(str(c) for c in x["channel"].values)
    return data, fs, names, band_hz, t0


def _centre_line(sig, fs, kind):
    """Offset (and drift) of an oscillation: a line through the midpoints of its swings.

    Consecutive maxima and minima are found; the midpoint of each max-min pair lies
    on the signal's centre whatever the decay (the alternating decay bias cancels), so
    a constant or straight line fitted to the midpoints removes a sensor offset and a
    drift without the bias a plain mean or least-squares detrend of a decaying record
    has. Falls back to the plain mean/line with fewer than 4 swings.
    """
    t = np.arange(sig.size) / fs
    guess = _fn_guess(sig, fs)
    tm = np.empty(0)
    if guess > 0:
        dist = max(int(0.6 * fs / guess), 1)
        ip, _ = scipy.signal.find_peaks(sig, distance=dist)
        iv, _ = scipy.signal.find_peaks(-sig, distance=dist)
        ext = np.sort(np.r_[ip, iv])
        if ext.size >= 5:
            tm = 0.5 * (t[ext[1:]] + t[ext[:-1]])
            xm = 0.5 * (sig[ext[1:]] + sig[ext[:-1]])
    if tm.size < 4:
        tm, xm = t, sig
    if kind == "constant":
        return np.full_like(sig, np.mean(xm))
    b, a = np.polyfit(tm, xm, 1)
    return a + b * t


def _bandpass(data, fs, band, order):
    sos = scipy.signal.butter(order, list(band), btype="bandpass", fs=fs, output="sos")
    return scipy.signal.sosfiltfilt(sos, data, axis=-1)


def _auto_band(sig, fs, order):
    """Frequency guess and, for a multi-mode or noisy record, a band around it (0.5..1.5 x).

    Returns ``(guess_hz, band or None, filtered signal)``. The band
    is applied only when more than 5 % of the energy lies outside it.
    """
    guess = _fn_guess(sig, fs)
    if not guess > 0:
        return guess, None, sig
    band = (0.5 * guess, min(1.5 * guess, 0.45 * fs))
    spec = np.abs(np.fft.rfft(sig)) ** 2
    f = np.fft.rfftfreq(sig.size, 1 / fs)
    inside = spec[(f >= band[0]) & (f <= band[1])].sum()
    if inside >= 0.95 * spec.sum() or not band[0] < band[1]:
        return guess, None, sig
    return guess, band, _bandpass(sig[None, :], fs, band, order)[0]


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
    """Dominant frequency (Hz) of a record (mean removed; lines below 2 / record skipped)."""
    sig = sig - np.mean(sig)
    nfft = int(2 ** np.ceil(np.log2(sig.size * 4)))
    spec = np.abs(np.fft.rfft(sig * np.hanning(sig.size), nfft))
    f = np.fft.rfftfreq(nfft, 1 / fs)
    spec[f < 2.0 * fs / sig.size] = 0
    return float(f[int(np.argmax(spec))])


def _r2(y, res, w):
    """Weighted coefficient of determination of a straight-line fit with residuals ``res``."""
    ym = np.sum(w * y) / np.sum(w)
    ss = np.sum(w * (y - ym) ** 2)
    return float(1.0 - np.sum(w * res**2) / ss) if ss > 0 else np.nan


class _ChannelFailure(Exception):
    """One channel could not be fitted; the message says why."""


def _verdict(sigma, zeta, zse, span_s, *, cycles=np.inf, early=np.nan, late=np.nan,
             rebound=None, r2=np.nan):
    """Reliability of a decay fit: (reliable, reason).

    ``cycles``: damped periods spanned by the fit; ``early``/``late``: zeta of the
    high- and low-amplitude halves; ``rebound``: ``(ratio, t_s)``, the largest envelope
    after the fit relative to its first value and when; ``r2``: weighted coefficient of
    determination of the straight line through ln(amplitude). Every failed criterion is
    named in the reason (joined by "; ").
    """
    if not sigma > 0:
        return False, f"the envelope does not decay (sigma = {sigma:.3g} 1/s): not a free decay"
    why = []
    drop = np.exp(sigma * span_s)
    if drop < _MIN_DROP:
        why.append(f"the envelope falls only {drop:.2f} x over the fitted "
                   f"{span_s:.3g} s (< {_MIN_DROP:g} x): noise or a forced response?")
    if rebound is not None and rebound[0] > _MAX_REBOUND:
        why.append(f"envelope rises again ({rebound[0]:.2f} x the fit's start at "
                   f"{rebound[1]:.3g} s): not one free decay")
    if cycles < _MIN_CYCLES:
        why.append(f"only {cycles:.2g} periods fitted (< {_MIN_CYCLES:g})")
    if np.isfinite(early) and np.isfinite(late):
        lo, hi = min(early, late), max(early, late)
        if not lo > 0 or hi > _MAX_EARLY_LATE * lo:
            why.append(f"zeta early {early:.3g} vs late {late:.3g} (> {_MAX_EARLY_LATE:g} x): "
                       "not one exponential")
    if r2 < _MIN_R2:
        why.append(f"the exponential explains {max(r2, 0.0):.0%} of ln(amplitude) "
                   f"(R^2 < {_MIN_R2:g}): beating or no decay")
    if not zse <= _MAX_REL_SE * zeta:
        why.append(f"zeta uncertain: standard error {zse / zeta:.0%} of the value "
                   f"(> {_MAX_REL_SE:.0%})")
    return not why, "; ".join(why)


def _run(names, data, fs, fn_hz, band, order, fit_one, t0, estimator):
    """Loop over channels: a failing channel gives a NaN row with its reason."""
    rows = []
    bands = []
    for name, sig in zip(names, data):
        b = band
        if fn_hz is None and band is None:
            guess, b, sig = _auto_band(sig, fs, order)
        else:
            guess = fn_hz or _fn_guess(sig, fs)
        bands.append(b)
        try:
            if not guess > 0:
                raise _ChannelFailure("no dominant frequency (flat or constant record)")
            r = fit_one(name, sig, guess, b)
        except _ChannelFailure as err:
            rows.append(dict(fn=np.nan, z=np.nan, fn_se=np.nan, zse=np.nan, fd=np.nan,
                             t0=np.nan, t1=np.nan, n=0, ze=np.nan, zl=np.nan, ok=False,
                             why=f"failed: {err}"))
            continue
        r["t0"] += t0
        r["t1"] += t0
        rows.append(r)
    if not any(np.isfinite(r["fn"]) for r in rows):
        raise NoEstimateError(
            f"{estimator}: no channel could be fitted: "
            + "; ".join(f"{n!r}: {r['why']}" for n, r in zip(names, rows))
        )
    bad = [(n, r["why"]) for n, r in zip(names, rows) if not r["ok"]]
    if bad:
        warnings.warn(
            f"{estimator}: unreliable or failed on {len(bad)} channel(s): "
            + "; ".join(f"{n!r}: {w}" for n, w in bad[:6]),
            AccuracyWarning, stacklevel=3,
        )
    col = {k: np.asarray([r[k] for r in rows], dtype=float)
           for k in ("fn", "z", "fn_se", "zse", "fd", "t0", "t1", "ze", "zl")}
    return DecayResult(
        tuple(names), col["fn"], col["z"], col["fn_se"], col["zse"], col["fd"], col["t0"],
        col["t1"], np.asarray([r["n"] for r in rows], dtype=int), estimator,
        next((b for b in bands if b is not None), None), col["ze"], col["zl"],
        np.asarray([r["ok"] for r in rows], dtype=bool), tuple(r["why"] for r in rows),
    )


def _halves(t, y, w, fit):
    """zeta on the first and second half of the points (high / low amplitude)."""
    h = t.size // 2
    out = []
    for sl in (slice(0, h), slice(h, None)):
        try:
            out.append(fit(t[sl], y[sl], w[sl]))
        except (np.linalg.LinAlgError, ValueError, ZeroDivisionError):
            out.append(np.nan)
    return out


def log_decrement(
    x,
    fn_hz: float | None = None,
    *,
    channel=None,
    band_hz: tuple[float, float] | None = None,
    threshold: float = 0.05,
    skip_cycles: int = 1,
    order: int = 2,
    detrend="linear",
    t_start_s: float | None = None,
    t_end_s: float | None = None,
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
        ``band_hz`` (default 0.5..1.5 fn) with a zero-phase Butterworth filter. Without
        it the dominant frequency of each channel is found from its spectrum (offset
        and drift removed first) and, when more than 5 % of the energy lies outside
        0.5..1.5 x that frequency (other modes, noise), the channel is band-passed there.
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
    detrend : {"linear", "constant", False}
        Removed from each channel first: the offset and linear drift of the
        oscillation's centre line (default; a line through the midpoints of successive
        maxima and minima, unbiased by the decay), the offset only, or nothing. A
        sensor offset otherwise biases peak amplitudes and the frequency guess.
    t_start_s, t_end_s : float, optional
        Time window (s, on the record's time axis) to analyse.

    Returns
    -------
    DecayResult
        One row per channel. A channel that cannot be fitted gets NaN and its reason
        (the others are still fitted); a fit that is not one clear exponential decay
        is marked ``reliable=False`` with every failed criterion in ``reason``: no
        decay; less than a factor 2 of amplitude drop; the envelope growing back above
        half the fit's first value after the fit (a second impact, continuous or
        ambient excitation); fewer than 3 periods fitted; zeta of the high- and
        low-amplitude halves (``zeta_early``, ``zeta_late``) more than 2x apart; a
        straight line explaining less than 80 % of ln(amplitude) (R^2 < 0.8, beating
        modes); a zeta standard error above 10 %.

    Raises
    ------
    mvtk.errors.ParameterError
        When no channel at all can be fitted (the message gives each reason).

    Examples
    --------
    >>> from mvtk import testing
    >>> x = testing.sdof_free_decay(12.0, 0.005, 256.0, 10.0)   # 12 Hz, zeta 0.5 %
    >>> res = log_decrement(x, 12.0)
    >>> np.round(res.zeta, 5)
    array([0.005])
    """
    if not 0 < threshold < 1:
        raise ParameterError(f"threshold must be in (0, 1), got {threshold!r}")
    data, fs, names, band, t0 = _prepare(x, channel, fn_hz, band_hz, order, detrend,
                                         t_start_s, t_end_s)

    def fit_one(name, sig, guess, b):
        if fs / guess < 8:
            warnings.warn(
                f"log_decrement: channel {name!r} has only {fs / guess:.2g} samples per period "
                f"of the {guess:.4g} Hz mode; interpolated peak amplitudes are biased (up to "
                "about 1 % in zeta at 5 samples per period): use >= 8 samples per period or "
                "envelope_fit",
                ResolutionWarning, stacklevel=4,
            )
        t, amp = _peaks(sig, fs, guess)
        settle = _settle_s(b)
        keep = np.flatnonzero((amp > 0) & (t >= settle) & (t <= sig.size / fs - settle))
        t, amp = t[keep], amp[keep]
        if amp.size:
            i0 = int(np.argmax(amp))
            t, amp = t[i0 + int(skip_cycles):], amp[i0 + int(skip_cycles):]
        rebound = None
        if amp.size:
            below = np.flatnonzero(amp < threshold * amp[0])
            if below.size:
                after = int(np.argmax(amp[below[0]:])) + below[0]
                rebound = (amp[after] / amp[0], t[after] + t0)
                t, amp = t[: below[0]], amp[: below[0]]
        if amp.size < 3:
            raise _ChannelFailure(
                f"{amp.size} usable peaks above {threshold:g} x the first; need >= 3 "
                "(longer record, lower threshold or check fn_hz/band_hz)"
            )
        k = np.arange(amp.size, dtype=float)

        def zeta_of(kk, tt, aa):
            st, sst, _, _ = _linfit(kk, tt)
            sa, ssa, _, res = _linfit(kk, np.log(aa), aa**2)
            sigma = -sa / st
            sigma_se = np.hypot(ssa / st, sa * sst / st**2)
            wd, wd_se = 2 * np.pi / st, 2 * np.pi * sst / st**2
            return _zeta_from(sigma, sigma_se, wd, wd_se), sigma, wd, _r2(np.log(aa), res,
                                                                         aa**2)

        (fn, z, fn_se, zse), sigma, wd, r2 = zeta_of(k, t, amp)
        ze, zl = _halves(k, t, amp, lambda kk, tt, aa: zeta_of(kk, tt, aa)[0][1]) \
            if amp.size >= 6 else (np.nan, np.nan)
        ok, why = _verdict(sigma, z, zse, t[-1] - t[0], cycles=amp.size - 1.0, early=ze,
                           late=zl, rebound=rebound, r2=r2)
        return dict(fn=fn, z=z, fn_se=fn_se, zse=zse, fd=wd / (2 * np.pi), t0=t[0],
                    t1=t[-1], n=amp.size, ze=ze, zl=zl, ok=ok, why=why)

    return _run(names, data, fs, fn_hz, band, order, fit_one, t0, "log_decrement")


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
    detrend="linear",
    t_start_s: float | None = None,
    t_end_s: float | None = None,
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
    x, fn_hz, channel, band_hz, threshold, order, detrend, t_start_s, t_end_s
        As in :func:`log_decrement`.
    method : {"hilbert", "peaks"}
    trim : float
        Fraction of the record dropped at both ends (Hilbert method). With a band-pass
        filter at least ``3 / (high - low)`` s is dropped at both ends (the filter's
        own transient).

    Returns
    -------
    DecayResult
        As in :func:`log_decrement` (failed channels as NaN rows with a reason,
        unclear decays marked ``reliable=False``).

    References
    ----------
    Feldman, "Hilbert transform in vibration analysis", MSSP 25 (2011) 735-802.

    Examples
    --------
    A simulated free decay at 12 Hz with 1 % damping, sampled at 256 Hz for 10 s:

    >>> from mvtk import testing
    >>> x = testing.sdof_free_decay(12.0, 0.01, 256.0, 10.0)
    >>> res = envelope_fit(x, 12.0)
    >>> np.round(res.fn_hz, 2), np.round(res.zeta, 4), res.method
    (array([12.]), array([0.01]), 'envelope_hilbert')
    """
    if method not in ("hilbert", "peaks"):
        raise ParameterError(f"method must be 'hilbert' or 'peaks', got {method!r}")
    if not 0 < threshold < 1:
        raise ParameterError(f"threshold must be in (0, 1), got {threshold!r}")
    if not 0 <= trim < 0.5:
        raise ParameterError(f"trim must be in [0, 0.5), got {trim!r}")
    data, fs, names, band, t0 = _prepare(x, channel, fn_hz, band_hz, order, detrend,
                                         t_start_s, t_end_s)

    def fit_one(name, sig, guess, b):
        rebound = None
        if not np.any(np.asarray(sig) != np.asarray(sig).flat[0]):
            raise _ChannelFailure("the record is constant (no decay to fit)")
        t, env, phase = _envelope(sig, fs, guess, b, method, trim)
        if env.size and not np.max(env) > 0:
            raise _ChannelFailure("the envelope is zero throughout (no decay to fit)")
        if env.size < 8:
            raise _ChannelFailure(
                f"{env.size} envelope points above {threshold:g} x the initial envelope; "
                "need >= 8"
            )
        if env.size:
            start = int(np.argmax(env[: max(1, env.size // 4)]))
            t, env = t[start:], env[start:]
            if phase is not None:
                phase = phase[start:]
            below = np.flatnonzero(env < threshold * env[0])
            stop = below[0] if below.size else env.size
            if stop < env.size:
                after = int(np.argmax(env[stop:])) + stop
                rebound = (env[after] / env[0], t[after] + t0)
            t, env = t[:stop], env[:stop]
            if phase is not None:
                phase = phase[:stop]
        if env.size < 8:
            raise _ChannelFailure(
                f"{env.size} envelope points above {threshold:g} x the initial envelope; "
                "need >= 8"
            )
        r = _fit_envelope(t, env, phase)
        cycles = (t[-1] - t[0]) * r["wd"] / (2 * np.pi)
        if env.size >= 16:
            h = env.size // 2
            ze = _fit_envelope(t[:h], env[:h], None if phase is None else phase[:h])["z"]
            zl = _fit_envelope(t[h:], env[h:], None if phase is None else phase[h:])["z"]
        else:
            ze = zl = np.nan
        ok, why = _verdict(r["sigma"], r["z"], r["zse"], t[-1] - t[0], cycles=cycles,
                           early=ze, late=zl, rebound=rebound, r2=r["r2"])
        return dict(fn=r["fn"], z=r["z"], fn_se=r["fn_se"], zse=r["zse"],
                    fd=r["wd"] / (2 * np.pi), t0=t[0], t1=t[-1], n=env.size, ze=ze, zl=zl,
                    ok=ok, why=why)

    return _run(names, data, fs, fn_hz, band, order, fit_one, t0, f"envelope_{method}")


def _envelope(sig, fs, guess, band, method, trim):
    """(t, envelope, unwrapped phase or None) of a decay, filter/Hilbert ends dropped."""
    n = sig.size
    if method == "hilbert":
        z = scipy.signal.hilbert(sig)
        env = np.abs(z)
        phase = np.unwrap(np.angle(z))
        t = np.arange(n) / fs
        settle = int(np.ceil(_settle_s(band) * fs))
        i0, i1 = max(int(trim * n), settle), n - max(int(trim * n), settle)
        return t[i0:i1], env[i0:i1], phase[i0:i1]
    tp, ap = _peaks(sig, fs, guess)
    tn, an = _peaks(-sig, fs, guess)
    t = np.r_[tp, tn]
    env = np.r_[ap, an]
    order_t = np.argsort(t)
    t, env = t[order_t], env[order_t]
    settle = _settle_s(band)
    keep = (env > 0) & (t >= settle) & (t <= n / fs - settle)
    return t[keep], env[keep], None


def _fit_envelope(t, env, phase):
    if not np.all(env > 0):
        raise _ChannelFailure("the envelope reaches zero inside the fitted range")
    slope, se, _, res = _linfit(t, np.log(env), env**2)
    sigma, sigma_se = -slope, se
    if phase is not None:
        wd, wd_se, _, _ = _linfit(t, phase, env**2)
    else:
        # alternate +/- peaks are half a damped period apart
        k = np.arange(env.size, dtype=float)
        half, half_se, _, _ = _linfit(k, t)
        wd, wd_se = np.pi / half, np.pi * half_se / half**2
    fn, z, fn_se, zse = _zeta_from(sigma, sigma_se, wd, wd_se)
    return dict(fn=fn, z=z, fn_se=fn_se, zse=zse, sigma=sigma, wd=wd,
                r2=_r2(np.log(env), res, env**2))


def damping_vs_amplitude(
    x,
    fn_hz: float | None = None,
    *,
    channel=None,
    band_hz: tuple[float, float] | None = None,
    n_windows: int = 4,
    threshold: float = 0.05,
    trim: float = 0.05,
    order: int = 2,
    detrend="linear",
    t_start_s: float | None = None,
    t_end_s: float | None = None,
) -> pd.DataFrame:
    """Damping ratio against vibration amplitude along a free decay.

    The Hilbert envelope (as in :func:`envelope_fit`) from its maximum down to
    ``threshold`` x that value is cut into ``n_windows`` windows of equal amplitude
    ratio (each covers the same drop in dB) and ``zeta`` is fitted in each. Constant
    zeta within its errors is viscous damping; zeta growing with amplitude (friction
    in joints, air damping) shows as a trend.

    Parameters
    ----------
    x, fn_hz, channel, band_hz, threshold, trim, order, detrend, t_start_s, t_end_s
        As in :func:`envelope_fit`.
    n_windows : int
        Number of amplitude windows (>= 1).

    Returns
    -------
    pandas.DataFrame
        One row per (channel, window): ``channel``, ``window``, ``t_start_s``,
        ``t_end_s``, ``amplitude`` (geometric mean of the envelope in the window, in
        channel units), ``fn_hz``, ``zeta``, ``zeta_std``, ``n_points``, ``reliable``,
        ``reason``.

    Examples
    --------
    Viscous damping (the simulated decay, 12 Hz at 1 %) gives the same zeta in every
    amplitude window:

    >>> from mvtk import testing
    >>> x = testing.sdof_free_decay(12.0, 0.01, 256.0, 10.0)
    >>> table = damping_vs_amplitude(x, 12.0, n_windows=3)
    >>> table["zeta"].round(4).tolist()
    [0.01, 0.01, 0.01]
    """
    if int(n_windows) < 1:
        raise ParameterError(f"n_windows must be >= 1, got {n_windows}")
    if not 0 < threshold < 1:
        raise ParameterError(f"threshold must be in (0, 1), got {threshold!r}")
    data, fs, names, band, t0 = _prepare(x, channel, fn_hz, band_hz, order, detrend,
                                         t_start_s, t_end_s)
    rows = []
    for name, sig in zip(names, data):
        b = band
        if fn_hz is None and band is None:
            guess, b, sig = _auto_band(sig, fs, order)
        else:
            guess = fn_hz or _fn_guess(sig, fs)
        t, env, phase = _envelope(sig, fs, guess, b, "hilbert", trim)
        if env.size < 8:
            continue
        start = int(np.argmax(env[: max(1, env.size // 4)]))
        t, env, phase = t[start:], env[start:], phase[start:]
        edges = env[0] * threshold ** (np.arange(int(n_windows) + 1) / int(n_windows))
        for w in range(int(n_windows)):
            sel = (env <= edges[w]) & (env > edges[w + 1])
            # keep the first contiguous run (noise can cross the band edges later)
            idx = np.flatnonzero(sel)
            row = dict(channel=name, window=w, t_start_s=np.nan, t_end_s=np.nan,
                       amplitude=np.nan, fn_hz=np.nan, zeta=np.nan, zeta_std=np.nan,
                       n_points=int(idx.size), reliable=False, reason="")
            if idx.size < 8:
                row["reason"] = f"{idx.size} envelope samples in this amplitude window"
                rows.append(row)
                continue
            idx = idx[: int(np.argmax(np.diff(np.r_[idx, idx[-1] + 2]) > 1)) + 1]
            if idx.size < 8:
                row["reason"] = "the envelope crosses this window only briefly"
                rows.append(row)
                continue
            r = _fit_envelope(t[idx], env[idx], phase[idx])
            ok, why = _verdict(r["sigma"], r["z"], r["zse"], t[idx[-1]] - t[idx[0]])
            if not ok and "falls only" in why:  # each window covers a fixed drop by design
                ok, why = bool(r["zse"] <= _MAX_REL_SE * r["z"]), "" if \
                    r["zse"] <= _MAX_REL_SE * r["z"] else why
            row.update(t_start_s=t[idx[0]] + t0, t_end_s=t[idx[-1]] + t0,
                       amplitude=float(np.exp(np.mean(np.log(env[idx])))), fn_hz=r["fn"],
                       zeta=r["z"], zeta_std=r["zse"], reliable=ok, reason=why)
            rows.append(row)
    if not rows:
        raise ParameterError("damping_vs_amplitude: no channel has an envelope to fit")
    return pd.DataFrame(rows)
