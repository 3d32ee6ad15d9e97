"""Peak picking of modes on FRFs and spectra."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.signal

from ..errors import ParameterError
from ._curves import amplitude_curves

__all__ = ["PeakResult", "find_peaks"]


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
    """

    fn_hz: np.ndarray
    index: np.ndarray
    amplitude: np.ndarray
    prominence_db: np.ndarray
    df_hz: float

    def __len__(self) -> int:
        return int(self.fn_hz.size)

    def _repr_html_(self) -> str:
        return self.to_dataframe()._repr_html_()

    def to_dataframe(self) -> pd.DataFrame:
        """One row per peak: ``fn_hz``, ``index``, ``amplitude``, ``prominence_db``."""
        return pd.DataFrame({"fn_hz": self.fn_hz, "index": self.index,
                             "amplitude": self.amplitude, "prominence_db": self.prominence_db})


def find_peaks(
    spectrum,
    f_hz=None,
    *,
    n_peaks: int | None = None,
    fmin: float | None = None,
    fmax: float | None = None,
    prominence_db: float = 6.0,
    power: bool | None = None,
) -> PeakResult:
    """Pick modal peaks on an FRF or spectrum.

    All curves (every response/reference pair or channel) are reduced to amplitude
    (``|H|`` or ``sqrt(PSD)``), normalised by their own maximum and summed; peaks of the
    sum in dB with at least ``prominence_db`` prominence are returned, the
    ``n_peaks`` most prominent ones sorted by frequency.

    Parameters
    ----------
    spectrum, f_hz, power
        As in :func:`mvtk.signal.amplitude_curves` (FRF Dataset/DataArray, spectrum
        DataArray with dims ``("channel", "frequency")``, or numpy array with ``f_hz``).
    n_peaks : int, optional
        Keep the most prominent ``n_peaks`` peaks.
    fmin, fmax : float, optional
        Frequency band in Hz searched for peaks.
    prominence_db : float
        Minimum prominence in dB (default 6 dB).

    Returns
    -------
    PeakResult
    """
    curves = amplitude_curves(spectrum, f_hz, power=power)
    if n_peaks is not None and int(n_peaks) < 1:
        raise ParameterError(f"n_peaks must be >= 1, got {n_peaks}")
    if not (np.isfinite(prominence_db) and prominence_db >= 0):
        raise ParameterError(f"prominence_db must be >= 0 dB, got {prominence_db!r}")
    f = curves.f_hz
    amp = curves.amplitude
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
    db = 20 * np.log10(np.maximum(total[lo:hi], np.finfo(float).tiny))
    idx, props = scipy.signal.find_peaks(db, prominence=prominence_db)
    prom = props["prominences"]
    if n_peaks is not None and idx.size > n_peaks:
        keep = np.sort(np.argsort(prom)[::-1][: int(n_peaks)])
        idx, prom = idx[keep], prom[keep]
    idx = idx + lo
    fpk = f[idx].astype(float)
    full_db = 20 * np.log10(np.maximum(total, np.finfo(float).tiny))
    for k, i in enumerate(idx):
        if 0 < i < f.size - 1:
            ym, y0, yp = full_db[i - 1], full_db[i], full_db[i + 1]
            den = ym - 2 * y0 + yp
            if den < 0:
                delta = 0.5 * (ym - yp) / den
                fpk[k] = f[i] + delta * 0.5 * (f[i + 1] - f[i - 1])
    df = float(np.median(np.diff(f)))
    return PeakResult(fpk, idx.astype(int), total[idx], np.asarray(prom, dtype=float), df)
