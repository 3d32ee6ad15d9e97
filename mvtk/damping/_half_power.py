"""Half-power bandwidth damping on FRF magnitude or sqrt(PSD)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ..errors import (
    AccuracyWarning,
    FormatError,
    ModeOverlapWarning,
    ParameterError,
    ResolutionWarning,
)
from ..signal._curves import amplitude_curves
from ..signal._frf import exponential_window_correction
from ..signal._peaks import MAX_PEAKS, RESONANCE_PROMINENCE_DB, _coherence, find_peaks
from ._common import NoEstimateError

__all__ = ["HalfPowerResult", "half_power", "half_power_zeta"]

# g(u) * u**p is an exact quadratic in u = omega**2 for one viscous mode, g = 1/|H|**2
_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}


@dataclass(frozen=True)
class HalfPowerResult:
    """Per curve and mode: natural frequency, damping ratio and how trustworthy they are.

    Attributes
    ----------
    curve : tuple of str
        Curve label (``"response/reference"`` or channel name).
    mode : numpy.ndarray
        Mode number (0-based, in order of the target frequencies).
    fn_hz, zeta : numpy.ndarray
        Natural frequency (Hz) and damping ratio (exponential window removed when
        applied); NaN where the half-power points were not found.
    f1_hz, f2_hz : numpy.ndarray
        Interpolated half-power frequencies (Hz), where ``|H| = |H|max / sqrt(2)``.
    peak_hz, peak_amplitude : numpy.ndarray
        Interpolated peak frequency (Hz) and amplitude (curve units).
    n_lines : numpy.ndarray
        ``(f2 - f1) / df``: frequency lines across the half-power band.
    record_needed_s : numpy.ndarray
        Record length that gives ``min_lines`` lines across the band
        (``min_lines / (f2 - f1)``, rectangular window). A lower bound when the band
        itself was overestimated by a short record.
    scatter : numpy.ndarray
        RMS relative deviation of ``|H|`` from the single-mode curve fitted to the lines
        above ``fit_level`` x peak (NaN with fewer than 6 such lines): measures noise,
        neighbouring modes and a wrong ``kind``/``power`` choice.
    quality : tuple of str
        ``"ok"``, ``"coarse"`` (fewer than ``min_lines`` lines), ``"overlap"`` (a
        neighbouring mode within ``overlap_factor`` bandwidths), ``"noisy"`` (scatter
        above ``max_scatter`` or coherence at the peak below ``min_coherence``; the name
        covers every deviation from one mode), ``"window"`` (the exponential window
        made more than 75 % of the measured damping), ``"background"`` (complex FRFs:
        one mode plus a complex constant fitted around the peak gives a damping more
        than :data:`MAX_BACKGROUND_CHANGE` (5 %) away, the other modes' contribution
        shifting the -3 dB points; the fitted value is in ``reason``), ``"weak"`` (a
        peak only 3..6 dB
        above its surroundings, listed so that no resonance is dropped silently, never
        reliable) or ``"failed"``.
    kind : tuple of str
        Exact single-mode relation used: receptance, mobility or accelerance.
    df_hz : float
        Line spacing in Hz.
    reliable : numpy.ndarray of bool
        True only for quality ``"ok"``: the data support the estimate.
    reason : tuple of str
        Why a row is not reliable (empty when it is), in words.
    coherence : numpy.ndarray
        Mean coherence at the peak line (NaN when the input carries none).

    Examples
    --------
    Returned by :func:`half_power`; ``to_dataframe`` gives one row per curve and mode:

    >>> from mvtk import testing
    >>> h = testing.modal_frf(np.arange(0.0, 100.0, 0.05), 20.0, 0.01)  # 20 Hz, 1 %
    >>> res = half_power(h, fn_hz=[20.0])
    >>> res.to_dataframe()[["fn_hz", "zeta"]].round(3).values.tolist()
    [[20.0, 0.01]]
    """

    curve: tuple[str, ...]
    mode: np.ndarray
    fn_hz: np.ndarray
    zeta: np.ndarray
    f1_hz: np.ndarray
    f2_hz: np.ndarray
    peak_hz: np.ndarray
    peak_amplitude: np.ndarray
    n_lines: np.ndarray
    record_needed_s: np.ndarray
    scatter: np.ndarray
    quality: tuple[str, ...]
    kind: tuple[str, ...]
    df_hz: float
    reliable: np.ndarray
    reason: tuple[str, ...]
    coherence: np.ndarray

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption=type(self).__name__, passed_column=None)

    def to_dataframe(self) -> pd.DataFrame:
        """One row per (curve, mode)."""
        return pd.DataFrame({
            "curve": list(self.curve), "mode": self.mode, "fn_hz": self.fn_hz,
            "zeta": self.zeta, "f1_hz": self.f1_hz, "f2_hz": self.f2_hz,
            "peak_hz": self.peak_hz, "peak_amplitude": self.peak_amplitude,
            "n_lines": self.n_lines, "record_needed_s": self.record_needed_s,
            "scatter": self.scatter,
            "quality": list(self.quality), "kind": list(self.kind),
            "coherence": self.coherence, "reliable": self.reliable,
            "reason": list(self.reason),
        })


def half_power_zeta(f1_hz, f2_hz, kind: str = "mobility"):
    """Exact single-mode damping ratio and natural frequency from half-power points.

    Parameters
    ----------
    f1_hz, f2_hz : array_like
        Lower and upper frequencies (Hz) where ``|H| = |H|max / sqrt(2)``.
    kind : {"mobility", "receptance", "accelerance"}
        For mobility (velocity/force) ``w1 w2 = wn**2`` and ``w2 - w1 = 2 zeta wn``
        exactly. For receptance and accelerance
        ``zeta = sqrt((1 - (1 + D**2)**-0.5) / 2)``, ``D = (w2**2 - w1**2)/(w2**2 + w1**2)``
        with ``wn**2 = (w1**2 + w2**2) / (2 (1 - 2 zeta**2))`` (receptance) or
        ``wn**2 = 2 (1 - 2 zeta**2) / (w1**-2 + w2**-2)`` (accelerance).

    Returns
    -------
    fn_hz, zeta : numpy.ndarray

    Examples
    --------
    For mobility the half-power points of a 20 Hz mode at 2 % are exactly
    ``w1,2 = wn (sqrt(1 + zeta**2) -+ zeta)``:

    >>> z, fn = 0.02, 20.0
    >>> f1, f2 = fn * (np.sqrt(1 + z**2) - z), fn * (np.sqrt(1 + z**2) + z)
    >>> fn_hz, zeta = half_power_zeta(f1, f2, kind="mobility")
    >>> round(float(fn_hz), 6), round(float(zeta), 6)
    (20.0, 0.02)
    """
    if kind not in _POWER:
        raise ParameterError(f"kind must be one of {sorted(_POWER)}, got {kind!r}")
    f1 = np.asarray(f1_hz, dtype=float)
    f2 = np.asarray(f2_hz, dtype=float)
    if kind == "mobility":
        fn = np.sqrt(f1 * f2)
        return fn, (f2 - f1) / (2 * fn)
    d = (f2**2 - f1**2) / (f2**2 + f1**2)
    zeta = np.sqrt((1 - 1 / np.sqrt(1 + d**2)) / 2)
    if kind == "receptance":
        fn2 = (f1**2 + f2**2) / (2 * (1 - 2 * zeta**2))
    else:
        fn2 = 2 * (1 - 2 * zeta**2) / (f1**-2.0 + f2**-2.0)
    return np.sqrt(fn2), zeta


def _quad(u, y):
    """Coefficients (c0, c1, c2) of the quadratic through (or least squares to) points."""
    us = u.mean()
    ss = u.std() or 1.0
    x = (u - us) / ss
    c2, c1, c0 = np.polyfit(x, y, 2)
    # back to the unscaled variable: y = c2 ((u-us)/ss)^2 + c1 (u-us)/ss + c0
    a2 = c2 / ss**2
    a1 = c1 / ss - 2 * c2 * us / ss**2
    a0 = c0 - c1 * us / ss + c2 * us**2 / ss**2
    return a0, a1, a2


def _min_of(c, p):
    """Minimum of g(u) = P(u) / u**p, P = c0 + c1 u + c2 u^2; returns (u*, g*) or None."""
    c0, c1, c2 = c
    if p == 0:
        if c2 <= 0:
            return None
        u = -c1 / (2 * c2)
    elif p == 1:
        if c2 <= 0 or c0 <= 0:
            return None
        u = np.sqrt(c0 / c2)
    else:
        if c0 <= 0:
            return None
        v = -c1 / (2 * c0)
        if v <= 0:
            return None
        u = 1 / v
    if not u > 0:
        return None
    g = (c0 + c1 * u + c2 * u**2) / u**p
    return (u, g) if g > 0 else None


def _crossing(c, p, level, lo, hi):
    """Root u in [lo, hi] of P(u) - level * u**p = 0 (quadratic in u)."""
    c0, c1, c2 = c
    coef = [c2, c1, c0]
    coef[2 - p] -= level
    roots = np.roots(coef)
    roots = roots[np.isreal(roots)].real
    if roots.size == 0:
        return None
    tol = 1e-9 * (hi if np.isfinite(hi) else lo)
    inside = np.sort(roots[(roots >= lo - tol) & (roots <= hi + tol)])
    if inside.size:
        return float(inside[-1] if np.isinf(hi) else inside[0])
    return None


def _one_mode(f, a, k0, p, search, method, fit_level):
    """Half-power analysis of one peak. Returns dict with f1, f2, peak or a failure."""
    n = f.size
    lo, hi = max(k0 - search, 1), min(k0 + search + 1, n - 1)
    if not np.isfinite(a[lo - 1:hi + 1]).all():
        return None, "nonfinite"
    k = lo + int(np.argmax(a[lo:hi]))
    if k <= 0 or k >= n - 1 or not a[k] > 0 or not (a[k] > a[k - 1] and a[k] >= a[k + 1]):
        return None, "no_peak"
    u = (2 * np.pi * f) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        y = u**p / a**2  # = P(u) for a single mode
    jl, jr = k, k
    while jl > 0 and fit_level * a[k] <= a[jl - 1] <= a[k]:
        jl -= 1
    while jr < n - 1 and fit_level * a[k] <= a[jr + 1] <= a[k]:
        jr += 1
    idx = np.arange(jl, jr + 1) if jr - jl + 1 >= 3 else np.arange(k - 1, k + 2)
    idx = idx[(u[idx] > 0) & np.isfinite(y[idx]) & (y[idx] > 0)]
    scatter = np.nan
    cfit = None
    if idx.size >= 3:
        w = 1.0 / y[idx]
        us, ss = u[idx].mean(), u[idx].std() or 1.0
        x = (u[idx] - us) / ss
        c2, c1, c0 = _wfit(x, y[idx], w)
        cfit = (c0 - c1 * us / ss + c2 * us**2 / ss**2, c1 / ss - 2 * c2 * us / ss**2,
                c2 / ss**2)
        if idx.size >= 6:
            # relative amplitude scatter about the single-mode curve (1/|H|^2 -> / 2)
            rel = (c2 * x**2 + c1 * x + c0) / y[idx] - 1.0
            scatter = float(np.sqrt(np.sum(rel**2) / (idx.size - 3)) / 2)
    if method == "fit":
        cpk = cfit
    else:
        cpk = _quad(u[k - 1:k + 2], y[k - 1:k + 2])
    m = _min_of(cpk, p)
    if m is None:
        gpk, upk = y[k] / u[k] ** p, u[k]
    else:
        upk, gpk = m
        # an interpolated peak cannot be below the top line (a least-squares fit can:
        # the top line of a noisy curve is biased high, so "fit" keeps its own peak)
        if method == "interpolate" and gpk > y[k] / u[k] ** p:
            gpk, upk = y[k] / u[k] ** p, u[k]
    peak = 1 / np.sqrt(gpk)
    level = peak / np.sqrt(2)
    out = {"k": k, "peak": peak, "upk": upk, "scatter": scatter}
    if method == "fit":
        left = _crossing(cpk, p, 2 * gpk, 0.0, upk)
        right = _crossing(cpk, p, 2 * gpk, upk, np.inf)
        if left is None or right is None or left <= 0:
            return out, "failed"
        out["left"] = np.sqrt(left) / (2 * np.pi)
        out["right"] = np.sqrt(right) / (2 * np.pi)
        return out, "ok"
    for side, step in (("left", -1), ("right", 1)):
        j = k
        low = a[k]
        while 0 <= j + step < n and a[j + step] > level:
            low = min(low, a[j + step])
            # rising again (beyond noise) before the -3 dB point: a neighbouring mode
            if a[j + step] > a[k] or a[j + step] > 1.25 * low:
                return out, "overlap"
            j += step
        if not 0 <= j + step < n:
            return out, "failed"
        jo = j + step  # first line below the level
        u_lo, u_hi = sorted((u[j], u[jo]))
        tri = np.array(sorted({j - step, j, jo} if 0 <= j - step < n else {j, jo, jo + step}))
        tri = tri[(tri >= 0) & (tri < n)]
        c = _quad(u[tri], y[tri]) if tri.size == 3 else None
        root = _crossing(c, p, 2 * gpk, u_lo, u_hi) if c is not None else None
        if root is None:  # fall back to linear interpolation of 1/|H|^2
            g1, g2 = 1 / a[j] ** 2, 1 / a[jo] ** 2
            t = (2 * gpk - g1) / (g2 - g1)
            root = u[j] + t * (u[jo] - u[j])
        out[side] = np.sqrt(root) / (2 * np.pi)
    return out, "ok"


#: Largest relative difference between the half-power damping and that of one mode plus a
#: complex constant fitted to the complex FRF around the peak before the row is marked
#: ``"background"`` (not reliable): the other modes' contribution shifts the -3 dB points
#: without a neighbouring peak (the overlap check) or scatter about the single-mode curve
#: (the noisy check) to show it.
MAX_BACKGROUND_CHANGE = 0.05


def _background_fit(f, h, fn, zeta, p, span=2.0):
    """``(zeta, background / peak)`` of one mode plus a complex constant fitted to the
    complex FRF ``h`` within ``span`` half-power bandwidths of ``fn`` (Hz).

    The mode is ``(i w)**p / (wn**2 - w**2 + 2 i zeta wn w)`` (``p`` 0, 1, 2 for
    receptance, mobility, accelerance) times a complex constant; constant and residue
    are linear, ``(wn, zeta)`` found by least squares (variable projection) from the
    half-power values. None with fewer than 8 lines in the span or a failed fit.
    """
    from scipy.optimize import least_squares

    sel = np.abs(f - fn) <= span * 2 * zeta * fn
    if sel.sum() < 8 or not np.all(np.isfinite(h[sel])):
        return None
    ws, hs = 2 * np.pi * f[sel], h[sel]
    scale = float(np.abs(hs).max())
    if not scale > 0:
        return None

    def fit(theta):
        wn, z = theta
        b = (1j * ws) ** p / (wn**2 - ws**2 + 2j * z * wn * ws)
        basis = np.column_stack([b, np.ones_like(b)])
        coef, *_ = np.linalg.lstsq(basis, hs, rcond=None)
        return coef, hs - basis @ coef

    def residual(theta):
        r = fit(theta)[1] / scale
        return np.r_[r.real, r.imag]

    wn0 = 2 * np.pi * fn
    try:
        sol = least_squares(residual, [wn0, zeta], x_scale=[zeta * wn0, zeta],
                            bounds=([wn0 * (1 - 4 * zeta), 1e-7],
                                    [wn0 * (1 + 4 * zeta), 0.5]))
    except (ValueError, np.linalg.LinAlgError):
        return None
    if not sol.success:
        return None
    wn, z = sol.x
    coef, _ = fit(sol.x)
    peak = abs(coef[0] * (1j * wn) ** p / (2j * z * wn * wn))
    return float(z), float(abs(coef[1]) / peak) if peak > 0 else np.inf


def _wfit(x, y, w):
    """Least squares of y ~ c2 x^2 + c1 x + c0 minimising sum (w (fit - y))^2."""
    A = np.vstack([x**2, x, np.ones_like(x)]).T * w[:, None]
    if not (np.isfinite(A).all() and np.isfinite(y * w).all()):
        raise FormatError("half_power: non-finite values in the lines fitted at the peak")
    coef, *_ = np.linalg.lstsq(A, y * w, rcond=None)
    return coef


def half_power(
    spectrum,
    f_hz=None,
    *,
    fn_hz=None,
    n_modes: int | None = None,
    fmin: float | None = None,
    fmax: float | None = None,
    kind: str = "auto",
    power: bool | None = None,
    method: str = "fit",
    fit_level: float = 0.3,
    min_lines: float = 5.0,
    overlap_factor: float = 5.0,
    max_scatter: float = 0.05,
    exponential_tau_s="auto",
    min_coherence: float = 0.5,
    max_modes: int = MAX_PEAKS,
) -> HalfPowerResult:
    """Half-power (-3 dB) bandwidth damping of each mode on each curve.

    Works on amplitude: ``|H|`` of an FRF or ``sqrt(PSD)`` of a power spectrum (the
    square root is taken automatically for :func:`mvtk.signal.psd` output or
    ``power=True``), never on the PSD at ``1/sqrt(2)``.

    Parameters
    ----------
    spectrum : xarray.Dataset, xarray.DataArray or array_like
        FRF Dataset/DataArray from :func:`mvtk.signal.frf`, spectrum DataArray with dims
        ``("channel", "frequency")``, or a numpy array (n_freq,) / (n_curves, n_freq) with
        ``f_hz``.
    f_hz : array_like, optional
        Frequency lines (Hz) for numpy input.
    fn_hz : array_like, optional
        Approximate mode frequencies (Hz); the peak is searched within +-2 % (at least
        +-3 lines) of each. Default: :func:`mvtk.signal.find_peaks` on all curves.
    n_modes, fmin, fmax
        Passed to :func:`~mvtk.signal.find_peaks` when ``fn_hz`` is not given.
    kind : {"auto", "receptance", "mobility", "accelerance"}
        Which exact single-mode relation to use (see :func:`half_power_zeta`); ``"auto"``
        reads the FRF ``kind`` or the response ``quantity`` (mobility if unknown).
    method : {"fit", "interpolate"}
        ``"fit"`` (default; measured best on real and synthetic data, see
        ``docs/damping.md`` and ``benchmarks/bench_damping.py``): the quadratic below
        fitted by least squares (relative error) to every line above ``fit_level`` x
        peak, so one noisy line does not move the -3 dB points. ``"interpolate"``: the
        peak and each -3 dB crossing are interpolated by the quadratic through three
        neighbouring lines of ``u**p / |H|**2`` with
        ``u = omega**2`` (``p`` = 0, 1, 2 for receptance, mobility, accelerance), which is
        exactly quadratic for a single viscous mode, so noise-free single-mode data are
        recovered exactly at any line spacing, but noise on the three lines at the
        peak goes straight into zeta.
    min_lines : float
        Fewer lines than this across the band gives quality ``"coarse"`` and a
        :class:`~mvtk.errors.ResolutionWarning` that states the record length needed.
    overlap_factor : float
        A neighbouring peak closer than ``overlap_factor`` x (f2 - f1) gives quality
        ``"overlap"`` and a :class:`~mvtk.errors.ModeOverlapWarning` (the neighbour
        biases the bandwidth, usually upwards).
    min_coherence : float
        Coherence at the peak below this (when the FRF carries a coherence) gives
        quality ``"noisy"``; also used by the peak picking.
    max_modes : int
        Most peaks picked when ``fn_hz`` is not given (default
        :data:`mvtk.signal.MAX_PEAKS` = 20, the most prominent kept).
    max_scatter : float
        Relative scatter of ``|H|`` about the fitted single-mode curve above which the
        quality is ``"noisy"`` and an :class:`~mvtk.errors.AccuracyWarning` is issued.
        The default 5 % is calibrated on simulated H1 measurements: 12 averages with
        5 % response noise scatter 1.6-3.5 % (zeta error < 7 %, no flag); 2 averages or
        30 % noise scatter 4-18 % with zeta errors of 10-80 %.
    exponential_tau_s : float, "auto" or None
        Exponential-window time constant to remove (see
        :func:`mvtk.signal.exponential_window_correction`); ``"auto"`` reads
        ``attrs["exponential_window_tau_s"]`` of an FRF from :func:`mvtk.signal.frf`.

    Returns
    -------
    HalfPowerResult

    Notes
    -----
    On the spectrum of a free decay (or any transient) use a rectangular window over the
    whole record (``psd(x, window="boxcar", nperseg=n)``): a Hann window multiplies the
    decay by a hump that narrows the peak and underestimates zeta by about a half
    (0.52 x for the paper's mode 1 on a 600 s record), and no line count reveals it.
    With a transient record the estimate is only as good as the spectral resolution:
    leakage widens the peak of a lightly damped mode (a 10 s record of a 13 Hz mode
    with zeta = 5.8e-4 overestimates zeta 8-10 times). Use
    :func:`mvtk.damping.envelope_fit` or :func:`mvtk.damping.log_decrement` on free
    decays when the warning fires.

    References
    ----------
    Papagiannopoulos & Hatzigeorgiou, Soil Dyn. Earthq. Eng. 31 (2011) 1075-1079 (exact
    half-power relations); Josefsson, Ahlin & Broman, Shock Vib. 19 (2012) (leakage bias).

    Examples
    --------
    The FRF of a simulated impact test (modes at 20 and 55 Hz, zeta 1 % and 2 %):

    >>> from mvtk import signal, testing
    >>> hits = testing.impact_test([20.0, 55.0], [0.01, 0.02], 1024.0, 8.0, 3,
    ...                            np.random.default_rng(0))
    >>> h = signal.frf(hits, reference="force", response="response", excitation="impact")
    >>> res = half_power(h, fn_hz=[20.0, 55.0])
    >>> np.round(res.fn_hz, 1), np.round(res.zeta, 3)
    (array([20. , 55.2]), array([0.01 , 0.021]))
    """
    if method not in ("interpolate", "fit"):
        raise ParameterError(f"method must be 'interpolate' or 'fit', got {method!r}")
    if not (np.isfinite(min_lines) and min_lines > 0):
        raise ParameterError(f"min_lines must be > 0, got {min_lines!r}")
    if not 0 < fit_level < 1 / np.sqrt(2):
        raise ParameterError(f"fit_level must be in (0, 0.707), got {fit_level!r}")
    curves = amplitude_curves(spectrum, f_hz, power=power, kind=kind)
    f = curves.f_hz
    df = float(np.median(np.diff(f)))
    finite = np.isfinite(curves.amplitude)
    flat = [lab for lab, a, ok in zip(curves.labels, curves.amplitude, finite)
            if ok.any() and not np.ptp(a[ok]) > 0]
    if flat:
        raise FormatError(
            f"half_power: curve(s) {flat} are flat (the same amplitude on every line): "
            "no resonance peak to measure"
        )
    coh = _coherence(spectrum, None, f.size)
    weak: dict[float, float] = {}
    if fn_hz is None:
        peaks = find_peaks(spectrum, f_hz, n_peaks=n_modes, fmin=fmin, fmax=fmax,
                           power=power, coherence=coh, max_peaks=max_modes)
        targets = peaks.fn_hz
        if n_modes is None and targets.size < max_modes:
            # resonances standing 3..6 dB out of their surroundings (a weak mode on the
            # flank of a strong one: acceleration.lvm's 2779.7 Hz, 5 dB) get a row
            # marked not reliable instead of none
            low = find_peaks(spectrum, f_hz, fmin=fmin, fmax=fmax, power=power,
                             coherence=coh, max_peaks=max_modes,
                             prominence_db=RESONANCE_PROMINENCE_DB)
            spans = [(f[i] - 3 * df, f[i] + 3 * df) for i in peaks.index]
            cand = [(p, x) for x, p in zip(low.fn_hz, low.prominence_db)
                    if not any(a <= x <= b for a, b in spans) and x not in targets]
            for p, x in sorted(cand, reverse=True)[:max_modes - targets.size]:
                weak[float(x)] = float(p)
            targets = np.sort(np.r_[targets, list(weak)])
        if targets.size == 0:
            raise NoEstimateError(
                "half_power: no peak stands out of the noise (prominence >= max(6 dB, 5 x "
                f"the {peaks.noise_db:.2g} dB line-to-line jitter)"
                + (", coherence >= 0.5" if coh is not None else "")
                + "); give fn_hz, a band (fmin/fmax) or better data")
    else:
        targets = np.atleast_1d(np.asarray(fn_hz, dtype=float))
        if np.any(~np.isfinite(targets)) or np.any(targets <= f[0]) or np.any(targets >= f[-1]):
            raise ParameterError(
                f"fn_hz must lie inside the spectrum {f[0]:g}..{f[-1]:g} Hz, got "
                f"{targets.tolist()}"
            )
    if exponential_tau_s == "auto":
        tau = curves.attrs.get("exponential_window_tau_s", curves.attrs.get("exp_window_tau_s"))
    else:
        tau = exponential_tau_s
    rows = {k: [] for k in ("curve", "mode", "fn", "zeta", "f1", "f2", "pk", "amp", "nl",
                            "need", "scatter", "quality", "kind", "reason", "coh")}
    cplx = curves.complex_values
    for i_curve, (label, a, ck) in enumerate(zip(curves.labels, curves.amplitude,
                                                 curves.kinds)):
        p = _POWER[ck]
        seen: set[int] = set()
        n_rows = 0
        for m, ft in enumerate(targets):
            k0 = int(np.argmin(np.abs(f - ft)))
            search = max(3, int(np.ceil(0.02 * ft / df)))
            res, quality = _one_mode(f, a, k0, p, search, method, fit_level)
            if fn_hz is None and res and res["k"] in seen:
                continue  # two picked peaks climb to one maximum: one row per peak
            if res:
                seen.add(res["k"])
            if quality == "nonfinite":
                bad = f[max(k0 - search - 1, 0):k0 + search + 2]
                raise FormatError(
                    f"half_power: curve {label!r} holds NaN/inf near {ft:.6g} Hz (lines "
                    f"{bad[0]:g}..{bad[-1]:g} Hz); remove or fill them, or move fn_hz"
                )
            f1 = res.get("left", np.nan) if res else np.nan
            f2 = res.get("right", np.nan) if res else np.nan
            reason = ""
            coh_pk = float(coh[res["k"]]) if coh is not None and res else np.nan
            fn = z = nl = band = np.nan
            if quality == "ok":
                fn, z = half_power_zeta(f1, f2, ck)
                fn, z = float(fn), float(z)
                z_meas = z
                if tau is not None:
                    fn, z = (float(v) for v in exponential_window_correction(fn, z, tau))
                band = f2 - f1
                nl = band / df
                # weak-peak rows (3..6 dB out of their surroundings) do not make a
                # neighbour overlapped: so small a resonance hardly moves another
                # mode's -3 dB points
                others = np.array([t for i, t in enumerate(targets)
                                   if i != m and float(t) not in weak])
                near = others[np.argmin(np.abs(others - fn))] if others.size else np.nan
                if others.size and abs(near - fn) < overlap_factor * band:
                    quality = "overlap"
                    reason = (f"a neighbouring peak at {near:.5g} Hz lies within "
                              f"{overlap_factor:g} half-power bandwidths")
                elif nl < min_lines * (1 - 1e-6):
                    quality = "coarse"
                    reason = (f"{nl:.2g} frequency lines across the half-power band (< "
                              f"{min_lines:g}): resolution-limited, needs a record of "
                              f">= {min_lines / band:.3g} s")
                elif tau is not None and not z > 0.25 * z_meas:
                    quality = "window"
                    reason = (f"the exponential window (tau = {tau:.3g} s) is "
                              f"{(z_meas - z) / z_meas:.0%} of the measured damping")
                elif coh_pk < min_coherence:
                    quality = "noisy"
                    reason = f"coherence {coh_pk:.2f} at the peak (< {min_coherence:g})"
                elif res["scatter"] > max_scatter:
                    quality = "noisy"
                    reason = (f"|H| scatters {res['scatter']:.1%} RMS about the single-mode "
                              f"curve near the peak (> {max_scatter:.0%})")
                elif cplx is not None:
                    bg = _background_fit(f, cplx[i_curve], float(fn), z_meas, p)
                    if bg is not None and abs(z_meas / bg[0] - 1) > MAX_BACKGROUND_CHANGE:
                        quality = "background"
                        reason = (f"the other modes' background ({bg[1]:.1%} of the "
                                  f"peak) shifts the -3 dB points: one mode plus a "
                                  f"constant fitted to the complex FRF gives zeta "
                                  f"{bg[0]:.4g}, {z_meas / bg[0] - 1:+.1%} from the "
                                  f"half-power {z_meas:.4g} "
                                  f"(> {MAX_BACKGROUND_CHANGE:.0%})")
            elif quality == "no_peak":
                quality = "failed"
                reason = f"no peak within +-{search} lines of {ft:.5g} Hz"
            elif quality == "overlap":
                reason = (f"the amplitude rises again before the -3 dB point of the peak "
                          f"near {ft:.5g} Hz: neighbouring mode")
            else:
                reason = (f"the -3 dB points were not found on both sides of the peak "
                          f"near {ft:.5g} Hz")
            if fn_hz is None and float(ft) in weak:
                why = (f"weak peak at {ft:.5g} Hz: {weak[float(ft)]:.1f} dB above its "
                       "surroundings "
                       "(< 6 dB: a neighbouring mode's flank or the background shifts the "
                       "-3 dB points)")
                reason = why + ("; " + reason if reason else "")
                if quality == "ok":
                    quality = "weak"
            pk_hz = np.sqrt(res["upk"]) / (2 * np.pi) if res else np.nan
            rows["curve"].append(label)
            rows["mode"].append(m if fn_hz is not None else n_rows)
            n_rows += 1
            rows["fn"].append(fn)
            rows["zeta"].append(z)
            rows["f1"].append(f1)
            rows["f2"].append(f2)
            rows["pk"].append(pk_hz)
            rows["amp"].append(res["peak"] if res else np.nan)
            rows["nl"].append(nl)
            rows["need"].append(min_lines / band if band > 0 else np.nan)
            rows["scatter"].append(res["scatter"] if res else np.nan)
            rows["quality"].append(quality)
            rows["kind"].append(ck)
            rows["reason"].append(reason)
            rows["coh"].append(coh_pk)
    result = HalfPowerResult(
        tuple(rows["curve"]), np.asarray(rows["mode"], dtype=int), np.asarray(rows["fn"]),
        np.asarray(rows["zeta"]), np.asarray(rows["f1"]), np.asarray(rows["f2"]),
        np.asarray(rows["pk"]), np.asarray(rows["amp"]), np.asarray(rows["nl"]),
        np.asarray(rows["need"]), np.asarray(rows["scatter"]), tuple(rows["quality"]),
        tuple(rows["kind"]), df, np.asarray([q == "ok" for q in rows["quality"]], dtype=bool),
        tuple(rows["reason"]), np.asarray(rows["coh"], dtype=float),
    )
    _warn(result, min_lines, df, max_scatter)
    return result


def _warn(r: HalfPowerResult, min_lines: float, df: float, max_scatter: float) -> None:
    coarse = [i for i, q in enumerate(r.quality) if q == "coarse"]
    if coarse:
        parts = [
            f"{r.curve[i]} mode {r.mode[i]} at {r.fn_hz[i]:.4g} Hz: {r.n_lines[i]:.2g} lines "
            f"(needs a record of at least {r.record_needed_s[i]:.3g} s)"
            for i in coarse[:6]
        ]
        warnings.warn(
            f"half_power: fewer than {min_lines:g} frequency lines (df = {df:.4g} Hz, record "
            f"{1 / df:.4g} s) across the half-power band of {len(coarse)} mode(s); the damping "
            "is unreliable (overestimated by leakage on short transient records): "
            + "; ".join(parts)
            + ". Use a longer record or envelope_fit/log_decrement on the free decay.",
            ResolutionWarning, stacklevel=3,
        )
    noisy = [i for i, q in enumerate(r.quality) if q == "noisy"]
    if noisy:
        parts = [f"{r.curve[i]} mode {r.mode[i]} at {r.fn_hz[i]:.4g} Hz: {r.scatter[i]:.1%}"
                 for i in noisy[:6]]
        warnings.warn(
            f"half_power: |H| deviates by more than {max_scatter:.0%} RMS from a single-mode "
            "curve near the peak of " + "; ".join(parts) + ". Noise (a spike at the peak "
            "narrows the band), a neighbouring mode or the wrong FRF kind / power quantity "
            "bias the -3 dB points. Use more averages, a time-domain "
            "estimator, or check kind/power.",
            AccuracyWarning, stacklevel=3,
        )
    shifted = [i for i, q in enumerate(r.quality) if q == "background"]
    if shifted:
        parts = [f"{r.curve[i]} mode {r.mode[i]} at {r.fn_hz[i]:.4g} Hz" for i in shifted[:6]]
        warnings.warn(
            "half_power: the other modes' background shifts the -3 dB points of "
            + "; ".join(parts) + f" (one mode plus a constant fitted to the complex FRF "
            f"differs by more than {MAX_BACKGROUND_CHANGE:.0%}; values in the reason "
            "column). Use a multi-mode fit (mvtk modal) for these modes.",
            AccuracyWarning, stacklevel=3,
        )
    overlap = [i for i, q in enumerate(r.quality) if q == "overlap"]
    if overlap:
        parts = [f"{r.curve[i]} mode {r.mode[i]} near {r.peak_hz[i]:.4g} Hz" for i in overlap[:6]]
        warnings.warn(
            f"half_power: a neighbouring mode overlaps the half-power band of {len(overlap)} "
            "mode(s) (single-mode estimate biased, usually upwards, or -3 dB point not "
            "reached before the next peak): " + "; ".join(parts),
            ModeOverlapWarning, stacklevel=3,
        )
