"""Peak picking of modes on FRFs and spectra."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.signal

from ..errors import DimensionError, FormatError, ParameterError
from ._curves import amplitude_curves

__all__ = ["MAX_PEAKS", "PeakResult", "find_peaks", "noise_jitter_db"]


@dataclass(frozen=True)
class PeakResult:
    """Peaks found on the summed amplitude of one or more curves.

    Attributes
    ----------
    fn_hz : numpy.ndarray
        Peak frequencies in Hz, refined by a parabola through the three lines around
        each maximum of the log amplitude (sub-line resolution).
    index : numpy.ndarray
        Line index of each peak.
    amplitude : numpy.ndarray
        Summed amplitude at the peak line.
    prominence_db : numpy.ndarray
        Prominence of each peak in dB.
    df_hz : float
        Line spacing in Hz.
    noise_db : float
        Estimated noise jitter of the summed curve in dB (see :func:`noise_jitter_db`).

    Examples
    --------
    Returned by :func:`find_peaks`:

    >>> from mvtk import testing
    >>> res = find_peaks(testing.modal_frf(np.arange(0.0, 100.0, 0.125), [20.0, 55.0],
    ...                                    [0.01, 0.02]))
    >>> res.index.tolist(), bool((res.prominence_db > 6).all())
    ([160, 440], True)
    """

    fn_hz: np.ndarray
    index: np.ndarray
    amplitude: np.ndarray
    prominence_db: np.ndarray
    df_hz: float
    noise_db: float = 0.0

    def __len__(self) -> int:
        return int(self.fn_hz.size)

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per peak: ``fn_hz``, ``index``, ``amplitude``, ``prominence_db``."""
        return pd.DataFrame({"fn_hz": self.fn_hz, "index": self.index,
                             "amplitude": self.amplitude, "prominence_db": self.prominence_db})


MAX_PEAKS = 20
"""Default largest number of peaks :func:`find_peaks` returns (the most prominent)."""


def noise_jitter_db(db: np.ndarray, lag: int = 1) -> float:
    """Robust standard deviation (dB) of the line-to-line jitter of a dB curve.

    The second difference (over ``lag`` lines: the zero-padding factor, since padded
    lines are interpolated and not independent) of a smooth curve is small;
    measurement noise makes it ``sqrt(6)`` times the per-line scatter. The median
    absolute deviation keeps real peaks (a few lines) from inflating the estimate.

    Examples
    --------
    A flat curve with 1 dB Gaussian scatter per line:

    >>> db = np.random.default_rng(0).normal(0.0, 1.0, 4000)
    >>> round(noise_jitter_db(db), 1)
    1.0
    """
    lag = max(int(lag), 1)
    if db.size < 2 * lag + 3:
        return 0.0
    d2 = db[2 * lag:] - 2 * db[lag:-lag] + db[:-2 * lag]
    mad = np.median(np.abs(d2 - np.median(d2)))
    return float(1.4826 * mad / np.sqrt(6))


def _local_jitter(db: np.ndarray, lag: int) -> np.ndarray:
    """Noise jitter (dB) per line, estimated in blocks of ~2 % of the band."""
    n = db.size
    width = max(64 * lag, n // 50)
    out = np.empty(n)
    for b0 in range(0, n, width):
        b1 = min(b0 + width, n)
        if n - b1 < width // 2:  # merge a short last block
            b1 = n
        out[b0:b1] = noise_jitter_db(db[b0:b1], lag)
        if b1 == n:
            break
    return out


def _half_width(total: np.ndarray, i: int) -> tuple[int, int]:
    """Lines left and right of peak ``i`` down to the -3 dB level of the amplitude."""
    lvl = total[i] / np.sqrt(2)
    jl = i
    while jl > 0 and total[jl - 1] > lvl and total[jl - 1] <= total[i]:
        jl -= 1
    jr = i
    while jr < total.size - 1 and total[jr + 1] > lvl and total[jr + 1] <= total[i]:
        jr += 1
    return i - jl + 1, jr - i + 1


def find_peaks(
    spectrum,
    f_hz=None,
    *,
    n_peaks: int | None = None,
    fmin: float | None = None,
    fmax: float | None = None,
    prominence_db: float = 6.0,
    power: bool | None = None,
    noise_factor: float = 5.0,
    coherence=None,
    min_coherence: float = 0.5,
    max_peaks: int = MAX_PEAKS,
    dynamic_range_db: float = 60.0,
) -> PeakResult:
    """Pick modal peaks on an FRF or spectrum: modes, not noise.

    All curves (every response/reference pair or channel) are reduced to amplitude
    (``|H|`` or ``sqrt(PSD)``), normalised by their own maximum and summed. A peak of
    the sum (in dB) is kept when

    * its prominence is at least ``prominence_db`` and at least ``noise_factor`` times
      the local noise jitter of the curve (robust line-to-line scatter in dB, see
      :func:`noise_jitter_db`, in blocks of 2 % of the band), so a noisy FRF or a
      noisy part of it does not return its noise;
    * the mean coherence at the peak line is at least ``min_coherence`` (when a
      coherence is available: an FRF Dataset's ``coherence`` variable or the
      ``coherence`` argument);
    * it is at most ``dynamic_range_db`` below the highest peak (a measurement chain's
      usable dynamic range: deeper "peaks" are noise floor);
    * no more prominent peak lies within its -3 dB band (one row per physical peak:
      noise ripples on the flank of a mode are merged into it).

    At most ``max_peaks`` (default :data:`MAX_PEAKS` = 20), or ``n_peaks``, of the most
    prominent peaks are returned, sorted by frequency.

    Parameters
    ----------
    spectrum, f_hz, power
        As in :func:`mvtk.signal.amplitude_curves` (FRF Dataset/DataArray, spectrum
        DataArray with dims ``("channel", "frequency")``, or numpy array with ``f_hz``).
    n_peaks : int, optional
        Keep the most prominent ``n_peaks`` peaks (overrides ``max_peaks``).
    fmin, fmax : float, optional
        Frequency band in Hz searched for peaks. Default ``fmax`` for an impact FRF from
        :func:`mvtk.signal.frf`: the top of its ``excitation_band_hz`` (the force
        spectrum has dropped by 20 dB there; above it the FRF is noise over no input).
        For a swept-sine FRF the band also sets the default ``fmin`` (its bottom).
        Default ``fmin`` when the input states ``resolution_hz`` (FRFs from
        :func:`mvtk.signal.frf`): 5 x that resolution (a mode needs 5 cycles in the
        record; below it drift and offsets make peaks).
    prominence_db : float
        Minimum prominence in dB (default 6 dB).
    noise_factor : float
        Minimum prominence as a multiple of the noise jitter (dB).
    coherence : array_like or xarray, optional
        Coherence on the same lines (n_freq,) or (n_curves, n_freq); default: the
        ``coherence`` variable of an FRF Dataset.
    min_coherence : float
        Peaks where the mean coherence is below this are dropped.
    max_peaks : int
        Documented maximum number of peaks returned.
    dynamic_range_db : float
        Peaks lower than the highest one by more than this are dropped (default 60 dB).

    Returns
    -------
    PeakResult

    Examples
    --------
    The exact receptance of two modes (20 Hz at 1 %, 55 Hz at 2 %) on 0.125 Hz lines:

    >>> from mvtk import testing
    >>> h = testing.modal_frf(np.arange(0.0, 100.0, 0.125), [20.0, 55.0], [0.01, 0.02])
    >>> res = find_peaks(h)
    >>> np.round(res.fn_hz, 1), res.df_hz
    (array([20., 55.]), 0.125)
    """
    curves = amplitude_curves(spectrum, f_hz, power=power)
    if n_peaks is not None and int(n_peaks) < 1:
        raise ParameterError(f"n_peaks must be >= 1, got {n_peaks}")
    if int(max_peaks) < 1:
        raise ParameterError(f"max_peaks must be >= 1, got {max_peaks}")
    if not (np.isfinite(prominence_db) and prominence_db >= 0):
        raise ParameterError(f"prominence_db must be >= 0 dB, got {prominence_db!r}")
    f = curves.f_hz
    amp = curves.amplitude
    band = curves.attrs.get("excitation_band_hz")
    if fmax is None and band is not None and len(band) == 2:
        fmax = float(band[1])
    if fmin is None and curves.attrs.get("resolution_hz"):
        fmin = 5.0 * float(curves.attrs["resolution_hz"])
    if band is not None and len(band) == 2 and float(band[0]) > 0:
        fmin = float(band[0]) if fmin is None else max(fmin, float(band[0]))
    finite = np.isfinite(amp)
    if not finite.any():
        raise FormatError("find_peaks: the spectrum holds no finite value")
    if not finite.all():
        amp = np.where(finite, amp, 0.0)  # e.g. 0/0 at 0 Hz of an H1 FRF: never a peak
    scale = np.max(amp, axis=1, keepdims=True)
    scale[scale == 0] = 1.0
    total = np.sum(amp / scale, axis=0)
    lo = 0 if fmin is None else int(np.searchsorted(f, fmin, side="left"))
    hi = f.size if fmax is None else int(np.searchsorted(f, fmax, side="right"))
    if hi - lo < 3:
        raise ParameterError(
            f"band fmin={fmin!r}..fmax={fmax!r} Hz holds {max(hi - lo, 0)} lines of "
            f"{f[0]:g}..{f[-1]:g} Hz; need >= 3"
        )
    full_db = 20 * np.log10(np.maximum(total, np.finfo(float).tiny))
    db = full_db[lo:hi]
    lag = 1
    if curves.attrs.get("nfft") and curves.attrs.get("nperseg"):
        # zero-padded lines interpolate: the independent scatter (and the 1/record
        # ripple of a noise floor) shows over half the padding factor
        lag = max(int(round(curves.attrs["nfft"] / curves.attrs["nperseg"])) // 2, 1)
    local = _local_jitter(db, lag)
    jitter = float(np.median(local))
    idx, props = scipy.signal.find_peaks(db, prominence=float(prominence_db))
    prom = props["prominences"]
    ok = prom >= noise_factor * local[idx]
    if idx.size:
        ok &= db[idx] >= db[idx].max() - float(dynamic_range_db)
    idx, prom = idx[ok], prom[ok]
    coh = _coherence(spectrum, coherence, f.size)
    if coh is not None and idx.size:
        ok = coh[idx + lo] >= min_coherence
        idx, prom = idx[ok], prom[ok]
    # one row per physical peak: drop peaks inside the -3 dB band of a stronger one
    order = np.argsort(prom)[::-1]
    limit = int(n_peaks) if n_peaks is not None else int(max_peaks)
    kept: list[int] = []
    spans: list[tuple[int, int]] = []
    for j in order:
        if len(kept) >= limit:
            break
        i = idx[j] + lo
        if any(a <= i <= b for a, b in spans):
            continue
        left, right = _half_width(total, i)
        kept.append(int(j))
        spans.append((i - left, i + right))
    kept = sorted(kept)
    idx, prom = idx[kept] + lo, prom[kept]
    fpk = f[idx].astype(float)
    for k, i in enumerate(idx):
        if 0 < i < f.size - 1:
            ym, y0, yp = full_db[i - 1], full_db[i], full_db[i + 1]
            den = ym - 2 * y0 + yp
            if den < 0:
                delta = 0.5 * (ym - yp) / den
                fpk[k] = f[i] + delta * 0.5 * (f[i + 1] - f[i - 1])
    df = float(np.median(np.diff(f)))
    return PeakResult(fpk, idx.astype(int), total[idx], np.asarray(prom, dtype=float), df,
                      jitter)


def _coherence(spectrum, coherence, nf: int):
    """Mean coherence per line from the argument or an FRF Dataset; None if absent."""
    import xarray as xr

    if coherence is None and isinstance(spectrum, xr.Dataset) and "coherence" in spectrum:
        coherence = spectrum["coherence"]
    if coherence is None:
        return None
    c = np.asarray(getattr(coherence, "values", coherence), dtype=float)
    c = c.reshape(-1, c.shape[-1])
    if c.shape[-1] != nf:
        raise DimensionError(
            f"coherence has {c.shape[-1]} frequency lines, the spectrum {nf}")
    return np.nanmean(c, axis=0)
