"""Peak picking of modes on FRFs and spectra."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
import scipy.signal

from ..errors import DimensionError, FormatError, ParameterError
from ._curves import amplitude_curves

__all__ = ["MAX_PEAKS", "EXCITED_DB", "AnalysisBand", "PeakResult", "analysis_band",
           "excited_band", "find_peaks", "noise_jitter_db"]


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
        Frequency band in Hz searched for peaks. Default: the band the excitation covers,
        :func:`excited_band` (a sweep's swept band; with the FRF's per-line force level
        the lines within :data:`EXCITED_DB` of its maximum, 35 dB for a hammer, above it
        the FRF is noise over no input; else a stated ``excitation_band_hz``), from
        5 x the stated ``resolution_hz`` (a mode needs 5 cycles in the record; below it
        drift and offsets make peaks). A stated ``excitation_band_hz`` that starts above
        0 Hz (a sweep) also bounds a given ``fmin``.
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
    if fmin is None or fmax is None:
        lo, hi, _ = _excited_band(spectrum, curves)
        fmin = lo if fmin is None else fmin
        fmax = hi if fmax is None else fmax
    band = curves.attrs.get("excitation_band_hz")
    if band is not None and len(band) == 2 and float(band[0]) > 0:
        fmin = max(fmin, float(band[0]))      # below a sweep's start: no input at all
    coh = _coherence(spectrum, coherence, f.size)
    return _pick(curves, coh, fmin, fmax, n_peaks=n_peaks, prominence_db=prominence_db,
                 noise_factor=noise_factor, min_coherence=min_coherence,
                 max_peaks=max_peaks, dynamic_range_db=dynamic_range_db)


def _total(curves):
    """Sum of the curves each normalised by its maximum, and the same in dB."""
    amp = curves.amplitude
    finite = np.isfinite(amp)
    if not finite.any():
        raise FormatError("find_peaks: the spectrum holds no finite value")
    if not finite.all():
        amp = np.where(finite, amp, 0.0)  # e.g. 0/0 at 0 Hz of an H1 FRF: never a peak
    scale = np.max(amp, axis=1, keepdims=True)
    scale[scale == 0] = 1.0
    total = np.sum(amp / scale, axis=0)
    return total, 20 * np.log10(np.maximum(total, np.finfo(float).tiny))


def _pick(curves, coh, fmin, fmax, *, n_peaks=None, prominence_db=6.0, noise_factor=5.0,
          min_coherence=0.5, max_peaks=MAX_PEAKS, dynamic_range_db=60.0) -> PeakResult:
    """The peak picking of :func:`find_peaks` on ``fmin..fmax`` (Hz, None: open)."""
    f = curves.f_hz
    total, full_db = _total(curves)
    lo = 0 if fmin is None else int(np.searchsorted(f, fmin, side="left"))
    hi = f.size if fmax is None else int(np.searchsorted(f, fmax, side="right"))
    if hi - lo < 3:
        raise ParameterError(
            f"band fmin={fmin!r}..fmax={fmax!r} Hz holds {max(hi - lo, 0)} lines of "
            f"{f[0]:g}..{f[-1]:g} Hz; need >= 3"
        )
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
    if coh is not None and idx.size:
        # before the dynamic range: an incoherent spike (H1 over a dip of the force)
        # must not set the level the modes are measured against
        ok &= coh[idx + lo] >= min_coherence
    idx, prom = idx[ok], prom[ok]
    if idx.size:
        ok = db[idx] >= db[idx].max() - float(dynamic_range_db)
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


EXCITED_DB = {"impact": -35.0, "sweep": -50.0, "random": -50.0}
"""A line is excited when the reference autospectrum there (best reference) is within
this many dB of its maximum, by excitation type (chosen from the real files of
``../shared/data``, see ``docs/guide/modal.md``): a hammer's force rolls off with
frequency and what lies 35 dB down is excited by little more than noise
(acceleration.lvm: the catalogued 8747.5 Hz mode at -31 dB, the noise poles above 10 kHz
at -35..-44 dB); a shaker's force dips at resonances (drop-out: the view_0 sweep has its
catalogued 350 Hz mode at -37 dB) and only falls below -50 dB outside the driven band.
:func:`mvtk.modal.identify` marks a mode below it "weakly excited"."""

MIN_CYCLES = 5
"""A mode needs this many cycles in the record: the default band starts at
``MIN_CYCLES x resolution_hz`` (below it drift and offsets make peaks)."""

RESONANCE_MARGIN = 1.25
"""The default analysis band reaches this factor (about a third octave) below the lowest
and above the highest resonance peak, so that the flanks of the outer modes and the
residual terms are fitted."""


RESONANCE_PROMINENCE_DB = 3.0
"""A resonance peak bounds the default band when it stands 3 dB out of its surroundings
(its half-power points exist; the broad 450..466 Hz hump of the view_0 sweep stands
3.4 dB) and 5 x above the noise jitter."""


def _level(spectrum):
    """Best-reference excitation level per line (dB re its maximum), or None."""
    import xarray as xr

    lev = None
    if isinstance(spectrum, xr.Dataset | xr.DataArray):
        if "reference_level_db" in spectrum.coords:
            lev = spectrum.coords["reference_level_db"]
        elif isinstance(spectrum, xr.Dataset) and "reference_level_db" in spectrum:
            lev = spectrum["reference_level_db"]
    if lev is None or "frequency" not in lev.dims:
        return None
    v = np.asarray(lev.transpose(..., "frequency").values, dtype=float)
    v = v.reshape(-1, v.shape[-1])
    with np.errstate(invalid="ignore"):
        best = np.where(np.isfinite(v), v, -np.inf).max(axis=0)
    return best


def _excited_band(spectrum, curves) -> tuple[float, float, list[str]]:
    """``(fmin, fmax, reasons)``: the band the excitation covers (see :func:`excited_band`)."""
    f = curves.f_hz
    a = curves.attrs
    pos = f[f > 0]
    lo = float(pos[0]) if pos.size else float(f[0])
    hi = float(f[-1])
    why: list[str] = []
    kind = str(a.get("excitation", ""))
    band = a.get("excitation_band_hz")
    band = [float(b) for b in band] if band is not None and len(band) == 2 else None
    level = _level(spectrum)
    if level is not None and level.shape[-1] != f.size:
        level = None
    name = "force" if str(a.get("excitation", "")) else "excitation"
    if kind == "sweep" and band is not None:
        lo, hi = max(lo, band[0]), min(hi, band[1])
        why.append(f"swept band {band[0]:.4g}..{band[1]:.4g} Hz")
    elif level is not None and kind in EXCITED_DB:
        thr = EXCITED_DB[kind]
        ok = (level >= thr) & (f > 0)
        if ok.any():
            lo, hi = max(lo, float(f[ok][0])), float(f[ok][-1])
            why.append(f"{kind} {name} within {-thr:g} dB of its maximum over "
                       f"{f[ok][0]:.4g}..{f[ok][-1]:.4g} Hz")
    elif band is not None:
        lo, hi = max(lo, band[0]), min(hi, band[1])
        why.append(f"excitation band {band[0]:.4g}..{band[1]:.4g} Hz stated by the FRF")
    else:
        why.append("no excitation level or band stated: every line counts as excited")
    res = a.get("resolution_hz")
    if res and MIN_CYCLES * float(res) > lo:
        lo = MIN_CYCLES * float(res)
        why.append(f"from {MIN_CYCLES} x the {float(res):.4g} Hz resolution ({MIN_CYCLES} "
                   "cycles of a mode in the record)")
    return lo, hi, why


def excited_band(spectrum, f_hz=None, *, power: bool | None = None
                 ) -> tuple[float, float, str]:
    """The band (Hz) the excitation of an FRF covers, and why.

    In order: a swept-sine FRF's swept band (``attrs["excitation_band_hz"]`` with
    ``attrs["excitation"] == "sweep"``: below and above it the shaker drove nothing);
    with a per-line excitation level (``reference_level_db``, as :func:`mvtk.signal.frf`
    and :func:`mvtk.modal.frf_matrix` attach it) the lines where the best reference
    lies within :data:`EXCITED_DB` of its maximum (impact 35 dB, random and sweep 50 dB);
    else a stated ``excitation_band_hz``; else the whole axis. The band starts no lower
    than ``MIN_CYCLES x resolution_hz`` (5 cycles of a mode in the record) when the
    FRF states its resolution, and never at 0 Hz.

    Returns
    -------
    fmin_hz, fmax_hz : float
    reason : str

    Examples
    --------
    A sweep from 60 to 500 Hz stated by the FRF: nothing outside it was excited.

    >>> import xarray as xr
    >>> f = np.linspace(0, 2000, 2001)
    >>> h = 1 / (100.0**2 - f**2 + 2j * 0.01 * 100.0 * f)
    >>> da = xr.DataArray(h[None, None], dims=("response", "reference", "frequency"),
    ...                   coords={"frequency": f},
    ...                   attrs={"excitation": "sweep", "excitation_band_hz": [60, 500]})
    >>> lo, hi, why = excited_band(da)
    >>> lo, hi
    (60.0, 500.0)
    """
    curves = amplitude_curves(spectrum, f_hz, power=power)
    lo, hi, why = _excited_band(spectrum, curves)
    return lo, hi, "; ".join(why)


@dataclass(frozen=True)
class AnalysisBand:
    """A default analysis band chosen from the data (:func:`analysis_band`).

    Attributes
    ----------
    fmin_hz, fmax_hz : float
        The band in Hz.
    reason : str
        Why: the excited band, the resonances it holds, the peaks it leaves out or cuts.
    excited_hz : tuple of float
        The band the excitation covers (:func:`excited_band`), Hz.
    peaks_hz : numpy.ndarray
        The resonance peaks (Hz) the band was drawn around.
    left_out_hz : numpy.ndarray
        Spectral peaks (Hz) of the whole axis outside the band.
    cut_hz : numpy.ndarray
        Spectral peaks (Hz) whose -3 dB band an edge of the band cuts.

    Examples
    --------
    Unpacks as ``(fmin_hz, fmax_hz)``:

    >>> b = AnalysisBand(32.0, 100.0, "two resonances", (0.0, 600.0),
    ...                  np.array([40.0, 80.0]), np.array([]), np.array([]))
    >>> fmin, fmax = b
    >>> fmin, fmax, b.peaks_hz.tolist()
    (32.0, 100.0, [40.0, 80.0])
    """

    fmin_hz: float
    fmax_hz: float
    reason: str
    excited_hz: tuple
    peaks_hz: np.ndarray
    left_out_hz: np.ndarray
    cut_hz: np.ndarray

    def __iter__(self):
        return iter((self.fmin_hz, self.fmax_hz))


def _name_peaks(fpk, level, f, limit=6) -> str:
    """``"11928 Hz (force -41 dB), ..."``, the first ``limit`` and how many more."""
    parts = []
    named: list[float] = []
    for x in fpk:
        if len(named) >= limit:
            break
        if any(abs(x - y) <= 0.01 * y for y in named):
            continue            # a cluster of noise peaks: its strongest named once
        named.append(float(x))
        txt = f"{x:.5g} Hz"
        if level is not None:
            k = int(np.argmin(np.abs(f - x)))
            if np.isfinite(level[k]):
                txt += f" (excitation {level[k]:.0f} dB)"
        parts.append(txt)
    more = len(fpk) - len(named)
    return ", ".join(parts) + (f" and {more} more" if more > 0 else "")


def analysis_band(spectrum, f_hz=None, *, power: bool | None = None, coherence=None,
                  min_coherence: float = 0.5, margin: float = RESONANCE_MARGIN
                  ) -> AnalysisBand:
    """Default analysis band of an FRF (or spectrum): where the excitation is strong and
    coherent and the response has resonances.

    1. The excited band (:func:`excited_band`: a sweep's swept band, the lines where
       the force is within :data:`EXCITED_DB` of its maximum, ``MIN_CYCLES x
       resolution_hz`` and up).
    2. The resonance peaks in it, picked as :func:`find_peaks` does (prominence >=
       :data:`RESONANCE_PROMINENCE_DB` = 3 dB and >= 5 x the local noise jitter, mean
       coherence >= ``min_coherence`` where a coherence exists, within 60 dB of the
       highest peak, no limit on their number), and every peak of the whole axis
       (prominence >= 6 dB) whose top lies in the excited band.
    3. The band spans the lowest peak / ``margin`` to the highest peak x ``margin``
       (default :data:`RESONANCE_MARGIN` = 1.25), inside the excited band; without a
       peak, the whole excited band.
    4. An edge that falls inside the -3 dB band of a peak moves out to include it where
       the excited band allows; the peaks that an edge still cuts, and the peaks of the
       whole axis left outside, are named in ``reason``.

    Parameters
    ----------
    spectrum, f_hz, power
        As in :func:`find_peaks`.
    coherence : array_like, optional
        Coherence on the same lines; default the FRF's ``coherence`` (Dataset variable
        or DataArray coordinate, as :func:`mvtk.modal.frf_matrix` attaches it).
    min_coherence : float
        Peaks with a lower mean coherence do not count as resonances.
    margin : float
        Band reach beyond the outer resonance peaks, as a frequency factor (> 1).

    Returns
    -------
    AnalysisBand
        Iterates as ``(fmin_hz, fmax_hz)``.

    Examples
    --------
    Two modes (40 and 80 Hz) on a 0..1000 Hz axis, hammer force stated up to 600 Hz:

    >>> import xarray as xr
    >>> f = np.linspace(0, 1000, 4001)
    >>> h = sum(1 / (fn**2 - f**2 + 2j * 0.01 * fn * f) for fn in (40.0, 80.0))
    >>> da = xr.DataArray(h[None, None], dims=("response", "reference", "frequency"),
    ...                   coords={"frequency": f}, attrs={"excitation_band_hz": [0, 600]})
    >>> b = analysis_band(da)
    >>> round(b.fmin_hz, 1), round(b.fmax_hz, 1)
    (32.0, 100.0)
    """
    import xarray as xr

    if not margin > 1:
        raise ParameterError(f"margin must be > 1, got {margin!r}")
    curves = amplitude_curves(spectrum, f_hz, power=power)
    f = curves.f_hz
    lo, hi, why = _excited_band(spectrum, curves)
    if hi <= lo:
        raise ParameterError(f"analysis_band: the excited band {lo:g}..{hi:g} Hz is empty "
                             f"({'; '.join(why)})")
    if (coherence is None and isinstance(spectrum, xr.DataArray)
            and "coherence" in spectrum.coords
            and "frequency" in spectrum.coords["coherence"].dims):
        coherence = spectrum.coords["coherence"].transpose(..., "frequency")
    coh = _coherence(spectrum, coherence, f.size)
    big = max(f.size, 1)
    inside = _pick(curves, coh, lo, hi, min_coherence=min_coherence, max_peaks=big,
                   prominence_db=RESONANCE_PROMINENCE_DB)
    total, _ = _total(curves)
    level = _level(spectrum)
    if level is not None and level.shape[-1] != f.size:
        level = None
    # every peak of the whole axis (same criteria, as many as there are); one whose
    # top lies in the excited band is a resonance even where the band's edge cuts its
    # flank (its prominence within the band is then too small)
    every = _pick(curves, coh, None, None, min_coherence=min_coherence, max_peaks=big,
                  dynamic_range_db=np.inf)
    res_hz = np.union1d(inside.fn_hz, every.fn_hz[(every.fn_hz >= lo) & (every.fn_hz <= hi)])
    if res_hz.size:
        b0 = max(lo, float(res_hz.min()) / margin)
        b1 = min(hi, float(res_hz.max()) * margin)
        why.append(f"{res_hz.size} resonance peak(s) at {res_hz.min():.5g}.."
                   f"{res_hz.max():.5g} Hz, band x/{margin:g} below and x{margin:g} "
                   "above them")
    else:
        b0, b1 = lo, hi
        why.append("no resonance peak stands out of the noise: the whole excited band")
    cut = []
    for i, fp in zip(every.index, every.fn_hz):
        left, right = _half_width(total, int(i))
        a, b = f[max(int(i) - left, 0)], f[min(int(i) + right, f.size - 1)]
        for edge in (0, 1):
            e = (b0, b1)[edge]
            if a < e < b:
                if edge == 0 and a >= lo:
                    b0 = float(a) - (b - a)
                    b0 = max(b0, lo)
                elif edge == 1 and b <= hi:
                    b1 = min(float(b) + (b - a), hi)
                if (b0, b1)[edge] > a and (b0, b1)[edge] < b:
                    cut.append(float(fp))
    res = curves.attrs.get("resolution_hz")
    floor = MIN_CYCLES * float(res) if res else 0.0
    # peaks below the resolution floor are drift and leakage of the record, not named
    out = every.fn_hz[((every.fn_hz < b0) & (every.fn_hz >= floor)) | (every.fn_hz > b1)]
    out = np.array([x for x in out if x not in cut])
    cut = np.array(sorted(set(cut)))
    if cut.size:
        why.append("the band edge cuts the peak(s) at " + _name_peaks(cut, level, f))
    if out.size:
        # the most strongly excited first (peaks over no input are noise), else the
        # most prominent
        if level is not None:
            key = -level[np.abs(f[None, :] - out[:, None]).argmin(axis=1)]
        else:
            key = -every.prominence_db[np.isin(every.fn_hz, out)]
        why.append("peaks left out: " + _name_peaks(out[np.argsort(key, kind="stable")],
                                                     level, f))
    return AnalysisBand(float(b0), float(b1), "; ".join(why), (float(lo), float(hi)),
                        np.asarray(res_hz, float), out, cut)
