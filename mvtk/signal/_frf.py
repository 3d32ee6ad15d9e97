"""H1/H2 frequency response functions with coherence, for random and impact tests."""

from __future__ import annotations

import warnings

import numpy as np
import scipy.fft
import xarray as xr

from ..errors import AccuracyWarning, DoubleHitError, FormatError, MvtkError, ParameterError
from ._impact import DOUBLE_HIT_FRACTION, PAD_FACTOR, clipped_channels, second_pulse
from ._input import as_time_history, channel_coord, sampling_rate, select_channels
from ._spectral import (
    _pair_coords,
    _segment_starts,
    _window,
    accumulate_cross,
    welch_segments_params,
)

__all__ = ["frf", "exponential_window_correction", "frf_kind", "is_impulsive", "is_sweep"]

_KINDS = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}


def frf_kind(response_quantity: str, reference_quantity: str = "force") -> str | None:
    """FRF type from the channel quantities: receptance, mobility, accelerance or None.

    Examples
    --------
    >>> frf_kind("acceleration"), frf_kind("velocity"), frf_kind("displacement")
    ('accelerance', 'mobility', 'receptance')
    >>> print(frf_kind("acceleration", reference_quantity="voltage"))
    None
    """
    if reference_quantity != "force":
        return None
    return _KINDS.get(response_quantity)


def exponential_window_correction(fn_hz, zeta, tau_s: float):
    """Remove the damping added by an exponential window ``exp(-t / tau_s)``.

    Multiplying force and response by ``exp(-t/tau)`` multiplies the impulse response
    by it, which moves every pole from ``-sigma + i w_d`` to ``-(sigma + 1/tau) + i w_d``.
    The correction is exact for viscous modes: ``sigma = zeta_m w_m - 1/tau`` with the
    same ``w_d``, then ``w_n = sqrt(sigma**2 + w_d**2)`` and ``zeta = sigma / w_n``.

    Parameters
    ----------
    fn_hz, zeta : array_like
        Natural frequency (Hz) and damping ratio measured on the windowed FRF.
    tau_s : float
        Time constant of the window in s.

    Returns
    -------
    fn_hz, zeta : numpy.ndarray
        Corrected values. A negative corrected zeta means the window dominated the
        decay (the measured damping is all window): it is returned as is, not clipped.

    References
    ----------
    Fladung & Rost, "Application and correction of the exponential window for
    frequency response functions", MSSP 11(1) 1997.

    Examples
    --------
    A 10 Hz mode measured at 2 % through a window with tau = 1 s: the true decay rate is
    ``sigma = 0.02 w_m - 1/tau`` with the same damped frequency:

    >>> fn, zeta = exponential_window_correction([10.0], [0.02], tau_s=1.0)
    >>> np.round(fn, 3), np.round(zeta, 5)
    (array([9.998]), array([0.00409]))
    >>> w = 2 * np.pi * 10.0
    >>> sigma = 0.02 * w - 1.0
    >>> round(float(sigma / np.hypot(sigma, w * np.sqrt(1 - 0.02**2))), 5)
    0.00409
    """
    if not (np.isfinite(tau_s) and tau_s > 0):
        raise ParameterError(f"tau_s must be a finite time constant > 0 s, got {tau_s!r}")
    fn = np.asarray(fn_hz, dtype=float)
    z = np.asarray(zeta, dtype=float)
    w = 2 * np.pi * fn
    sigma = z * w - 1.0 / tau_s
    wd = w * np.sqrt(np.clip(1 - z**2, 0, None))
    wn = np.sqrt(sigma**2 + wd**2)
    return wn / (2 * np.pi), sigma / wn


def _find_hits(force: np.ndarray, level: float, quiet: int, dead: int) -> np.ndarray:
    """Start samples of hits: runs of ``polarity * force >= level``.

    Runs closer than ``quiet`` samples (anti-alias filter ringing of one pulse) or
    within ``dead`` samples of the hit start (the force window) belong to one hit.
    """
    polarity = 1.0 if force[np.argmax(np.abs(force))] >= 0 else -1.0
    above = polarity * force >= level
    edges = np.diff(np.r_[0, above.astype(np.int8), 0])
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1)  # one past the last sample above
    hits: list[int] = []
    last_end = -(10**18)
    for s0, e0 in zip(starts, ends):
        if hits and (s0 - last_end < quiet or s0 - hits[-1] < dead):
            last_end = e0
            continue
        hits.append(int(s0))
        last_end = e0
    return np.asarray(hits, dtype=int)


def _primary_hits(hits: np.ndarray, n: int) -> np.ndarray:
    """Hits that start records: a hit closer to the previous kept hit than a quarter of
    the longest span between hits (or from the last hit to the end of the data) is a
    second pulse (rebound) of that hit, not a hit of its own."""
    if hits.size < 2:
        return hits
    longest = float(np.max(np.diff(np.r_[hits, n])))
    keep = [int(hits[0])]
    for h in hits[1:]:
        if h - keep[-1] >= longest / 4:
            keep.append(int(h))
    return np.asarray(keep, dtype=int)


def _impact_records(force, nperseg, pretrigger, trigger_level, fs, force_window_n,
                    double_hit_fraction=DOUBLE_HIT_FRACTION):
    """Records of an impact test: ``(starts, nperseg, pretrigger, width, doubles, info)``.

    ``starts`` are the clean records; ``doubles`` the records holding a second force
    pulse above ``double_hit_fraction`` x the hit's peak (dicts: ``start``, ``hit_s``,
    ``second`` (sample), ``second_s``, ``ratio``); ``info`` has ``n_hits``,
    ``short_s`` (hits too close to the ends) and ``available`` (the longest record the
    hits allow, samples).
    """
    force = force - np.median(force)  # the trigger works on the signal, not its offset
    peak = np.max(np.abs(force))
    level = trigger_level * peak
    if not level > 0:
        raise FormatError("reference: the force channel is all zeros; no hit to trigger on")
    polarity = 1.0 if force[np.argmax(np.abs(force))] >= 0 else -1.0
    quiet = max(4, int(round(0.005 * fs)))
    n = force.size
    hits = _primary_hits(_find_hits(force, level, quiet, force_window_n or 0), n)
    auto = nperseg is None
    if pretrigger is None:
        # 1 % of the shortest hit-to-hit record, never more than the samples before hit 1
        gap = int(np.min(np.diff(np.r_[hits, n])))
        pretrigger = min(max(gap // 100, 1), int(hits[0]))
    pretrigger = int(pretrigger)
    # the whole record: from pretrigger before a hit to pretrigger before the next
    available = int(np.min(np.diff(np.r_[hits, n + pretrigger])))
    if auto:
        nperseg = available
        if nperseg < 16:
            raise FormatError(f"reference: hits are only {nperseg} samples apart")
    nperseg = int(nperseg)
    starts, doubles, short = [], [], []
    signed = polarity * force
    prev = None
    for h in hits:
        s = h - pretrigger
        if s < 0 or s + nperseg > n:
            short.append(h / fs)
            continue
        if prev is not None and h < prev + nperseg - pretrigger:
            # this hit lies inside the previous hit's record: its own record starts on
            # the previous response, still ringing (refused, never cut)
            doubles.append({"start": int(s), "hit_s": float(prev / fs), "second": int(s),
                            "second_s": float(h / fs), "preceded": True, "ratio": float(
                                signed[h:h + 8].max() / signed[prev:prev + 8].max())})
            prev = int(h)
            continue
        prev = int(h)
        second = second_pulse(signed, int(h), s + nperseg, level, double_hit_fraction)
        if second is not None:
            doubles.append({"start": int(s), "hit_s": float(h / fs), "second": second[0],
                            "second_s": float(second[0] / fs), "ratio": second[1]})
            continue
        starts.append(s)
    if short:
        warnings.warn(
            f"impact FRF: {len(short)} hit(s) too close to the ends of the data (at "
            f"{[round(float(t), 4) for t in short]} s) for a record of {nperseg} samples with "
            f"{pretrigger} pretrigger; not used",
            AccuracyWarning, stacklevel=3,
        )
    if not starts and not doubles:
        raise FormatError(
            f"reference: no complete impact record found ({len(hits)} hit(s) above "
            f"{trigger_level:g} x peak force; nperseg={nperseg}, pretrigger={pretrigger})"
        )
    # pulse width: the run of samples above the trigger level that starts each hit
    above = np.abs(force) >= level
    widths = []
    for s in [*starts, *(d["start"] for d in doubles)]:
        h = s + pretrigger
        e = h
        while e < n and above[e]:
            e += 1
        widths.append(e - h)
    info = {"n_hits": int(hits.size), "short_s": short, "available": available}
    return (np.asarray(starts, dtype=int), nperseg, pretrigger, max(max(widths), 1),
            doubles, info)



def _tau_for_tail(tail: float, nperseg: int, pre: int, fs: float) -> float:
    """Exponential time constant (s) that brings a record's tail ratio to 1 %: reached
    where the tail measurement starts (5 % before the end of the record)."""
    span = nperseg - pre - max(nperseg // 20, 4)
    return span / fs / np.log(tail / 0.01)


def _double_text(d: dict, record_s: float) -> str:
    """One double hit in words (time, ratio, what was done)."""
    if d.get("preceded"):
        return (f"the hit at {d['second_s']:.4g} s lies inside the {record_s:.4g} s record "
                f"of the hit at {d['hit_s']:.4g} s, its record starts on that response: "
                "refused")
    what = (f"cut at {d['second_s']:.4g} s (windowed response {d['cut_tail']:.1%} of its "
            "peak there)" if d["action"] == "cut" else
            f"refused (cutting it there would leave the windowed response at "
            f"{d['cut_tail']:.0%} of its peak)")
    return (f"a second force pulse at {d['second_s']:.4g} s ({d['ratio']:.0%} of the hit at "
            f"{d['hit_s']:.4g} s) inside its record of {record_s:.4g} s, record {what}")


def _double_hits(y, doubles, nperseg: int, pre: int, win_y, policy: str):
    """Decide each double-hit record: cut before its second pulse or refuse it.

    ``"auto"`` cuts when the windowed response has decayed to 1.1 % of its peak where
    the second pulse starts (the truncation then costs no more than the window's own
    end), ``"cut"`` always, ``"refuse"`` never. Sets ``action`` and ``cut_tail`` on
    every dict; returns ``[(record start, samples kept)]`` of the cut records.
    """
    cuts = []
    for d in doubles:
        s, c = d["start"], d["second"] - d["start"]
        seg = y[:, s:s + nperseg] * win_y
        pk = np.max(np.abs(seg[:, pre:]), axis=-1)
        m = max(nperseg // 20, 4)
        lo = max(c - m, pre + 1)
        rms = np.sqrt(np.mean(seg[:, lo:c] ** 2, axis=-1)) if c > lo else pk
        ok = pk > 0
        d["cut_tail"] = float(np.max(rms[ok] / pk[ok])) if ok.any() else 1.0
        cut = policy == "cut" or (policy == "auto" and d["cut_tail"] <= 0.011)
        d["action"] = "cut" if cut and c > pre else "refused"
        if d["action"] == "cut":
            cuts.append((s, c))
    return cuts

def _check_excitation(r: np.ndarray, names) -> None:
    """Refuse a reference channel without excitation (constant or all zeros)."""
    for name, row in zip(names, r):
        if not np.ptp(row) > 0:
            what = "all zeros" if row[0] == 0 else f"{row[0]:g} in every sample"
            raise FormatError(
                f"reference: channel {name!r} is constant ({what}): no excitation, the "
                "FRF is undefined (0/0); check the channel choice"
            )


def _tail_ratio(y: np.ndarray, starts, nperseg: int, pre: int, win: np.ndarray) -> float:
    """Largest RMS of the last 5 % of a (windowed) record over its peak, over records."""
    m = max(nperseg // 20, 4)
    worst = 0.0
    for s in starts:
        seg = y[:, s:s + nperseg] * win
        pk = np.max(np.abs(seg[:, pre:]), axis=-1)
        tail = np.sqrt(np.mean(seg[:, -m:] ** 2, axis=-1))
        ok = pk > 0
        if ok.any():
            worst = max(worst, float(np.max(tail[ok] / pk[ok])))
    return worst


def _pretrigger_offset(x: np.ndarray, starts, pre: int) -> np.ndarray:
    """Mean of the pretrigger samples of every record (offset of each channel)."""
    return np.mean([x[:, s:s + pre].mean(axis=-1) for s in starts], axis=0)


# impact: the FRF is trusted where the force spectrum is within this of its low-f level
_FORCE_DROP_DB = 20.0

# random excitation: search of the segment length
_MIN_AVERAGES = 8       # fewest Welch averages (50 % overlap) the automatic choice accepts
_LINES_TARGET = 8.0     # lines wanted across the narrowest half-power band
_COHERENT = 0.98        # peak coherence above which averaging is not needed


def _auto_nperseg(y, r, fs, window, detrend):
    """Segment length of an H1 FRF under random excitation, chosen from the data.

    See :func:`auto_segment`; the curves are ``|H1|`` of every response against the
    first reference, with their coherence. Returns (nperseg, reason).
    """
    def curves(seg):
        win = _window(window, seg)
        starts = _segment_starts(y.shape[1], seg, seg // 2)
        gyr, grr, gyy = accumulate_cross(y, r[:1], starts, seg, win, win, detrend)
        with np.errstate(divide="ignore", invalid="ignore"):
            h = np.abs(gyr[:, 0, :] / grr[0, 0][None, :])
            coh = np.abs(gyr[:, 0, :]) ** 2 / (gyy * np.real(grr[0, 0])[None, :])
        return h, coh, len(starts)

    return auto_segment(y.shape[1], fs, curves)


def auto_segment(n: int, fs: float, curves) -> tuple[int, str]:
    """Welch segment length (power of two) that resolves the narrowest clear peak.

    Starts at 32 averages (50 % overlap) and doubles the segment while the narrowest
    peak found by :func:`mvtk.signal.find_peaks` on the summed amplitude spans fewer
    than 8 lines between its -3 dB points and at least 8 averages remain. When the
    coherence at the peaks (if ``curves`` gives one) is already above 0.98 with 32
    averages (deterministic excitation such as a sine sweep, or a very clean test),
    averaging buys nothing and the segment may grow to the whole record.

    Parameters
    ----------
    n : int
        Record length in samples.
    fs : float
        Sampling rate in Hz.
    curves : callable
        ``curves(nperseg) -> (amplitude (n_curves, n_freq), coherence or None,
        n_averages)``.

    Returns
    -------
    nperseg : int
    reason : str
        The choice and what limited it, in words.

    Examples
    --------
    A 20 Hz mode at 1 % has a -3 dB band of ``2 zeta f`` = 0.4 Hz; 8 lines across it need
    ``df <= 0.05 Hz``, i.e. at least 20 480 samples at 1024 Hz: the next power of two is
    32 768 (here the exact receptance on the lines of each trial segment, 1024 s of data):

    >>> from mvtk import testing
    >>> fs, n = 1024.0, 2**20
    >>> def curves(nperseg):
    ...     f = np.fft.rfftfreq(nperseg, 1 / fs)
    ...     return np.abs(testing.modal_frf(f, 20.0, 0.01).values[0]), None, 2 * n // nperseg - 1
    >>> nperseg, reason = auto_segment(n, fs, curves)
    >>> nperseg, reason.split(";")[0]
    (32768, '63 average(s) of 32768 samples (df = 0.03125 Hz)')
    """
    from ._peaks import find_peaks

    max_seg = int(2 ** np.floor(np.log2(2 * n / (_MIN_AVERAGES + 1))))
    seg = int(min(max(2 ** np.floor(np.log2(2 * n / 33)), 64), max(max_seg, 16), n))
    reason = ""
    first = True
    coherent = False
    while True:
        h, coh, n_avg = curves(seg)
        h = np.where(np.isfinite(h), h, 0.0)
        f = scipy.fft.rfftfreq(seg, 1 / fs)
        lines = np.inf
        try:
            pk = find_peaks(h[:, 1:], f[1:], max_peaks=8)
        except MvtkError:
            pk = None
        if pk is not None and len(pk):
            amp = np.sum(h / np.maximum(h.max(axis=1, keepdims=True), 1e-300), axis=0)
            for i in pk.index + 1:
                lvl = amp[i] / np.sqrt(2)
                jl = i
                while jl > 0 and amp[jl] > lvl:
                    jl -= 1
                jr = i
                while jr < amp.size - 1 and amp[jr] > lvl:
                    jr += 1
                lines = min(lines, jr - jl - 1)
            if first and coh is not None and n_avg >= 16:
                c = np.nan_to_num(np.mean(coh[:, pk.index + 1], axis=0))
                coherent = bool(np.median(c) > _COHERENT)
        first = False
        limit = n if coherent else max_seg
        reason = (f"{n_avg} average(s) of {seg} samples (df = {fs / seg:.4g} Hz); "
                  f"narrowest peak {lines:g} lines wide at -3 dB")
        if lines >= _LINES_TARGET or 2 * seg > limit:
            break
        seg *= 2
    if coherent:
        reason += f"; coherence at the peaks > {_COHERENT:g}: fewer averages accepted"
    if lines < _LINES_TARGET:
        reason += ("; the record allows no longer segment with enough averages: "
                   "damping of the narrowest peaks is limited by resolution")
    return seg, reason


def frf(
    x,
    reference,
    response=None,
    *,
    estimator: str = "H1",
    excitation: str = "auto",
    fs: float | None = None,
    window=None,
    nperseg: int | None = None,
    noverlap: int | None = None,
    detrend="auto",
    trigger_level: float = 0.1,
    pretrigger: int | None = None,
    force_window_s="auto",
    exponential_tau_s="auto",
    nfft="auto",
    double_hit: str = "auto",
    double_hit_fraction: float = DOUBLE_HIT_FRACTION,
) -> xr.Dataset:
    """Frequency response functions and coherence from reference and response channels.

    With no options the resolution is chosen from the record and the excitation (see
    Notes) and the choice is stated in ``attrs["resolution_reason"]``.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Time history, dims ``("channel", "time")`` (or a Dataset with ``"time_history"``)
        holding both the reference (force) and response channels.
    reference : str, int, list or dict
        Reference channel(s): names, positions or a coord filter ``{"quantity": "force"}``.
        Any quantity may be a reference (force, voltage, current ...).
    response : same kinds, optional
        Response channels; default every channel that is not a reference.
    estimator : {"H1", "H2"}
        ``H1 = G_yr G_rr^-1`` (noise on the response; several references allowed) or
        ``H2 = G_yy / G_ry`` (noise on the reference; one reference only).
    excitation : {"auto", "random", "impact", "sweep"}
        ``"random"``: Welch averaging over overlapping segments (default Hann window).
        ``"impact"``: one record per hit, found by a trigger on the first reference
        channel at ``trigger_level`` x its peak (in the polarity of the largest sample;
        crossings less than max(4 samples, 5 ms) after the force fell below the level,
        e.g. anti-alias ringing, belong to the same hit), starting ``pretrigger``
        samples before the crossing (default 1 % of the record, at most the samples
        before the first hit); a record holding a second force pulse (a double hit) is
        cut before it or refused (see ``double_hit``) with an
        :class:`~mvtk.errors.AccuracyWarning`, and clipped channels are named. Default
        window is rectangular.
        ``"sweep"``: deterministic excitation (sine sweep, chirp, stepped sine): one
        record, the whole time history, rectangular window by default (Hann if a
        shorter ``nperseg`` is given; no averaging
        is needed, and a Hann window over a sweep weights input and response at
        different times: zeta 20-40 % off on a simulated 60-500 Hz sweep, exact with
        the rectangular window).
        ``"auto"``: impact when the first reference is a pulse (see
        :func:`is_impulsive`), sweep when it is a narrow-band signal whose frequency
        moves monotonically through the record (see :func:`is_sweep`), random otherwise.
    fs : float, optional
        Sampling rate in Hz (derived from ``time`` and checked if given).
    window, noverlap
        As in :func:`scipy.signal.csd` (random excitation).
    nperseg : int, optional
        Segment (random) or record (impact) length in samples. Default: chosen from the
        data (see Notes).
    detrend : {"auto", "constant", "linear", False}
        Random: as in :func:`scipy.signal.csd` (``"auto"`` = ``"constant"``). Impact:
        ``"auto"`` subtracts the median of the whole record from each reference (a
        hammer force is zero between pulses) and the mean of the pretrigger samples
        from each response (when there are at least 8 of them).
    force_window_s : float, "auto" or None
        Impact only: keep the force from the record start to ``force_window_s`` after
        the trigger and zero it afterwards (removes noise from the force channel).
        ``"auto"``: 4 x the measured pulse width (at least 8 samples); None: no window.
    exponential_tau_s : float, "auto" or None
        Impact only: multiply force and response records by ``exp(-(t - t_trigger)/tau)``
        after the trigger. The added damping is recorded in ``attrs`` and removed by
        :func:`mvtk.damping.half_power` (see :func:`exponential_window_correction`).
        ``"auto"``: applied only when the response has not decayed to 1 % of its peak
        (RMS of the last 5 % of the record), with the longest ``tau`` that brings the
        tail to 1 %; None: never.
    nfft : int, "auto" or None
        Impact only: FFT length (zero padding of each record). ``"auto"``: when
        ``nperseg`` was chosen automatically and the (windowed) response decays to 1 %
        within the record, the record is zero-padded to :data:`PAD_FACTOR` (8) x its
        length; the lines then interpolate the spectrum of the complete transient (the
        frequency resolution stays ``1 / record``, stated as ``attrs["resolution_hz"]``),
        and every 8th line is one of the record's own (:func:`mvtk.modal.identify` uses
        those for a mode that has not decayed by the record's end).
    double_hit : {"auto", "cut", "refuse"}
        Impact only: what to do with a record that holds a second force pulse above
        ``double_hit_fraction`` x its hit's peak (a rebound of the hammer, or the next
        hit inside the record). ``"cut"``: the record (force and response) ends before
        the second pulse; ``"refuse"``: the record is not averaged; ``"auto"``: cut when
        the (windowed) response has decayed to 1.1 % of its peak where the second pulse
        starts, refused otherwise. Every double hit is named (time, ratio, action) in an
        :class:`~mvtk.errors.AccuracyWarning` and in ``attrs``. A hit closer to the
        previous one than a quarter of the longest hit-to-hit span is a rebound of it and
        starts no record of its own.
    double_hit_fraction : float
        Impact only: threshold of the double-hit detector, a fraction of the hit's peak
        force (default :data:`mvtk.signal.DOUBLE_HIT_FRACTION`).

    Returns
    -------
    xarray.Dataset
        ``frf``: complex, dims ``("response", "reference", "frequency")`` in
        response units per reference unit (``units`` coord); ``coherence``: ordinary
        coherence ``|G_yr|^2 / (G_yy G_rr)`` per pair. ``attrs`` record the estimator,
        excitation, ``n_averages``, ``nperseg``, ``nfft``, ``df_hz`` (line spacing),
        ``resolution_hz`` (``fs / nperseg``), ``resolution_reason``, ``window``,
        ``kind`` / ``frf_type`` (receptance/mobility/accelerance when all responses share
        one quantity and the reference is a force), ``tail_ratio`` (impact),
        ``excitation_band_hz`` (impact: where the force spectrum is within 20 dB of its
        low-frequency level; peak picking stays inside it by default) and
        ``exponential_window_tau_s`` (also ``exp_window_tau_s``) when applied; impact
        also ``n_hits``, ``record_available`` (longest record the hits allow, samples),
        ``double_hit_s`` / ``double_hit_ratio`` / ``double_hit_action`` (one entry per
        double hit: time of the second pulse in s, its peak over the hit's, ``"cut"`` or
        ``"refused"``) and ``clipped`` (channels whose extreme is a flat top of at least
        :data:`mvtk.signal.CLIP_MIN_SAMPLES` samples, the ADC range; ``""`` if none, a
        :class:`~mvtk.errors.AccuracyWarning` names them).
        ``reference_level_db``: autospectrum of each reference per line in dB re its
        largest value above 0 Hz (how strongly each line was excited).

    Raises
    ------
    mvtk.errors.FormatError
        A reference channel is constant (no excitation) or no impact record is complete.
    mvtk.errors.DoubleHitError
        Every impact record holds a double hit and none could be cut.

    Notes
    -----
    Impact tests: the default record is the whole time between hits, a force window
    removes the force channel's noise after the pulse, an exponential window is added
    only if the response would leak, and its damping is removed exactly by
    :func:`mvtk.damping.half_power`. Random tests: the segment length starts at 32
    averages and doubles until the narrowest clear peak spans 8 lines at -3 dB, keeping
    at least 8 averages (50 % overlap); ``resolution_reason`` says what limited it.

    Examples
    --------
    Three hammer hits on a two-mode structure (20 and 55 Hz), simulated:

    >>> from mvtk import testing
    >>> hits = testing.impact_test([20.0, 55.0], [0.01, 0.02], 1024.0, 8.0, 3,
    ...                            np.random.default_rng(0))
    >>> h = frf(hits, reference="force", response="response", excitation="impact")
    >>> sorted(h.data_vars), h.attrs["df_hz"]
    (['coherence', 'frf', 'reference_level_db'], 0.015625)
    """
    if estimator not in ("H1", "H2"):
        raise ParameterError(f"estimator must be 'H1' or 'H2', got {estimator!r}")
    if excitation not in ("auto", "random", "impact", "sweep"):
        raise ParameterError(
            f"excitation must be 'auto', 'random', 'impact' or 'sweep', got {excitation!r}")
    x = as_time_history(x)
    fs = sampling_rate(x, fs)
    ref = select_channels(x, reference, name="reference")
    ref_names = [str(c) for c in ref["channel"].values]
    if response is None:
        keep = [i for i, c in enumerate(x["channel"].values) if str(c) not in ref_names]
        if not keep:
            raise ParameterError("frf: every channel is a reference; no response channel left")
        resp = x.isel(channel=keep)
    else:
        resp = select_channels(x, response, name="response")
    nr = ref.sizes["channel"]
    if estimator == "H2" and nr != 1:
        raise ParameterError(f"estimator 'H2' needs exactly one reference, got {nr}")
    n = x.sizes["time"]
    y = resp.values.astype(float, copy=False)
    r = ref.values.astype(float, copy=False)
    _check_excitation(r, ref_names)
    if excitation == "auto":
        excitation = ("impact" if is_impulsive(r[0]) else
                      "sweep" if is_sweep(r[0], fs) else "random")
    attrs = {"estimator": estimator, "excitation": excitation, "fs": fs}
    auto_seg = nperseg is None

    if excitation in ("random", "sweep"):
        for key, val in (("force_window_s", force_window_s),
                         ("exponential_tau_s", exponential_tau_s), ("nfft", nfft)):
            if val not in ("auto", None):
                raise ParameterError(f"{key}: force_window_s, exponential_tau_s and nfft "
                                     "apply to excitation='impact' only")
        detrend = "constant" if detrend == "auto" else detrend
        if window is None:  # the whole sweep as one record: rectangular, else Hann
            whole = excitation == "sweep" and (auto_seg or int(nperseg) >= n)
            window = "boxcar" if whole else "hann"
        if not auto_seg:
            reason = "nperseg given"
        elif excitation == "sweep":
            nperseg = n
            reason = (f"deterministic (swept) excitation: the whole record, one average "
                      f"({n} samples = {n / fs:.4g} s, df = {fs / n:.4g} Hz)")
        else:
            nperseg, reason = _auto_nperseg(y, r, fs, window, detrend)
        nperseg, noverlap, window = welch_segments_params(n, fs, nperseg, noverlap, window)
        win = _window(window, nperseg)
        starts = _segment_starts(n, nperseg, noverlap)
        gyr, grr, gyy = accumulate_cross(y, r, starts, nperseg, win, win, detrend)
        attrs.update(window=str(window), noverlap=noverlap)
        nfft_used = nperseg
    else:
        if noverlap is not None:
            raise ParameterError("noverlap applies to excitation='random' only")
        window = "boxcar" if window is None else window
        if double_hit not in ("auto", "cut", "refuse"):
            raise ParameterError(
                f"double_hit must be 'auto', 'cut' or 'refuse', got {double_hit!r}")
        raw = np.vstack([r, y])
        starts, nperseg, pre, width, doubles, info = _impact_records(
            r[0], nperseg, pretrigger, trigger_level, fs,
            None if force_window_s in ("auto", None) else
            int(round(_positive(force_window_s, "force_window_s") * fs)),
            double_hit_fraction)
        where = f"{x.attrs['source']}: " if x.attrs.get("source") else ""
        clipped = clipped_channels(raw, ref_names + [str(c) for c in resp["channel"].values],
                                   fs)
        if clipped:
            warnings.warn(
                f"{where}impact FRF: clipped channel(s), a flat top at the ADC range: "
                + "; ".join(f"{c['channel']!r} at {c['value']:g} for {c['n_samples']} "
                            f"samples from {c['time_s']:.4g} s" for c in clipped)
                + " (the FRF near the peak excitation is wrong; repeat with a larger range)",
                AccuracyWarning, stacklevel=2)
        attrs["clipped"] = "; ".join(f"{c['channel']} at {c['value']:g}" for c in clipped)
        fw_n = None
        if force_window_s == "auto":
            fw_n = min(max(4 * width, 8), nperseg - pre)
            force_window_s = fw_n / fs
        elif force_window_s is not None:
            fw_n = int(round(_positive(force_window_s, "force_window_s") * fs))
        every = np.asarray([*starts, *(d["start"] for d in doubles)], dtype=int)
        if detrend == "auto":
            # a hammer force is zero outside its pulses: its offset is the median
            r = r - np.median(r, axis=-1, keepdims=True)
            attrs["offset_removed"] = "force: median of the record"
            if pre >= 8:
                y = y - _pretrigger_offset(y, every, pre)[:, None]
                attrs["offset_removed"] += "; response: pretrigger mean"
            detrend = False
        win = _window(window, nperseg)
        win_y = win.copy()
        win_r = win.copy()
        clean = starts if starts.size else every
        tail = _tail_ratio(y, clean, nperseg, pre, win)
        attrs["tail_ratio"] = tail
        if exponential_tau_s == "auto":
            exponential_tau_s = None
            if tail > 0.01:
                exponential_tau_s = _tau_for_tail(tail, nperseg, pre, fs)
        if exponential_tau_s is not None:
            _positive(exponential_tau_s, "exponential_tau_s")
            k = np.arange(nperseg)
            expo = np.exp(-np.clip(k - pre, 0, None) / (exponential_tau_s * fs))
            win_y *= expo
            win_r *= expo
            attrs["exponential_window_tau_s"] = float(exponential_tau_s)
            attrs["exp_window_tau_s"] = float(exponential_tau_s)
            tail = _tail_ratio(y, clean, nperseg, pre, win_y)
        if fw_n is not None:
            win_r[pre + fw_n:] = 0.0
            attrs["force_window_s"] = float(force_window_s)
        cuts = _double_hits(y, doubles, nperseg, pre, win_y, double_hit)
        if doubles:
            warnings.warn(
                f"{where}impact FRF: double hit: "
                + "; ".join(_double_text(d, nperseg / fs) for d in doubles)
                + f" (threshold {double_hit_fraction:g} x the hit's peak)",
                AccuracyWarning, stacklevel=2)
        attrs["n_hits"] = info["n_hits"]
        attrs["record_available"] = int(info["available"])
        attrs["double_hit_s"] = [float(d["second_s"]) for d in doubles]
        attrs["double_hit_ratio"] = [float(d["ratio"]) for d in doubles]
        attrs["double_hit_action"] = [str(d["action"]) for d in doubles]
        attrs["double_hit_fraction"] = float(double_hit_fraction)
        if not starts.size and not cuts:
            err = DoubleHitError(
                f"{where}every impact record holds a double hit ("
                + ", ".join(f"second pulse at {d['second_s']:.4g} s, {d['ratio']:.0%} of the "
                            f"hit at {d['hit_s']:.4g} s" for d in doubles)
                + f"); no clean record of {nperseg / fs:.4g} s is left: repeat the hit or "
                "pass double_hit='cut' to end the record before the second pulse")
            err.double_hits = [{k: d[k] for k in ("hit_s", "second_s", "ratio")}
                               for d in doubles]
            raise err
        if nfft == "auto":
            nfft_used = nperseg
            if auto_seg and tail <= 0.011:
                nfft_used = PAD_FACTOR * nperseg
        elif nfft is None:
            nfft_used = nperseg
        else:
            nfft_used = int(nfft)
            if nfft_used < nperseg:
                raise ParameterError(f"nfft must be >= nperseg = {nperseg}, got {nfft}")
        reason = ("record length given" if not auto_seg else
                  f"whole record between hits ({nperseg} samples = {nperseg / fs:.4g} s)")
        if nfft_used > nperseg:
            reason += f", zero-padded to {nfft_used} (complete transient)"
        if "exponential_window_tau_s" in attrs:
            reason += f", exponential window tau = {attrs['exponential_window_tau_s']:.4g} s"
        gyr, grr, gyy = accumulate_cross(y, r, starts, nperseg, win_y, win_r, detrend,
                                         nfft=nfft_used)
        for s0, c in cuts:  # records ended before their second pulse
            keep = (np.arange(nperseg) < c).astype(float)
            g = accumulate_cross(y, r, np.asarray([s0]), nperseg, win_y * keep,
                                 win_r * keep, detrend, nfft=nfft_used)
            gyr, grr, gyy = gyr + g[0], grr + g[1], gyy + g[2]
        starts = np.sort(np.r_[starts, [s0 for s0, _ in cuts]]).astype(int)
        attrs.update(window=str(window), pretrigger=int(pre),
                     hit_times_s=[float((s + pre) / fs) for s in starts])

    grr_diag = np.real(np.einsum("jjf->jf", grr))
    with np.errstate(divide="ignore", invalid="ignore"):
        if estimator == "H1":
            if nr == 1:
                h = gyr / grr[0, 0][None, None, :]
            else:
                # H G_rr = G_yr  ->  G_rr^T H^T = G_yr^T, batched over frequency
                a = np.moveaxis(grr, -1, 0).transpose(0, 2, 1)
                b = np.moveaxis(gyr, -1, 0).transpose(0, 2, 1)
                h = np.moveaxis(np.linalg.solve(a, b).transpose(0, 2, 1), 0, -1)
        else:
            h = gyy[:, None, :] / np.conj(gyr)
        coh = np.abs(gyr) ** 2 / (gyy[:, None, :] * grr_diag[None, :, :])
    f = scipy.fft.rfftfreq(nfft_used, 1 / fs)
    if excitation == "impact":
        # usable band of a hammer: force spectrum within 20 dB of its low-frequency level
        g = grr_diag[0]
        ref_level = np.median(g[1:max(int(0.02 * g.size), 3)])
        low = np.flatnonzero(g[1:] < ref_level * 10 ** (-_FORCE_DROP_DB / 10))
        attrs["excitation_band_hz"] = [0.0, float(f[low[0] + 1]) if low.size else float(f[-1])]
    elif excitation == "sweep":
        # the swept band, from the moving frequency of the reference (whole axis if the
        # sweep was forced on a signal that does not sweep)
        band = _sweep_band(r[0], fs)
        attrs["excitation_band_hz"] = list(band) if band else [0.0, float(f[-1])]
    coords = _pair_coords(resp, ref, f)
    ru = channel_coord(resp, "units")
    fu = channel_coord(ref, "units")
    coords["units"] = (("response", "reference"),
                       np.array([[f"{a}/{b}" for b in fu] for a in ru], dtype=object))
    rq = set(channel_coord(resp, "quantity"))
    fq = set(channel_coord(ref, "quantity"))
    kind = frf_kind(rq.pop(), fq.pop()) if len(rq) == 1 and len(fq) == 1 else None
    attrs.update(nperseg=int(nperseg), nfft=int(nfft_used), df_hz=fs / nfft_used,
                 resolution_hz=fs / nperseg, resolution_reason=reason,
                 n_averages=len(starts), kind=kind if kind is not None else "",
                 frf_type=kind if kind is not None else "other")
    # the excitation level per line, dB re its largest value above 0 Hz (weak lines of
    # a hammer, force drop-outs of a shaker): mvtk.modal marks modes the force missed
    with np.errstate(divide="ignore"):
        top = np.max(grr_diag[:, 1:], axis=1, keepdims=True) if f.size > 1 else 1.0
        level = 10 * np.log10(np.maximum(grr_diag, 1e-300) / np.where(top > 0, top, 1.0))
    ds = xr.Dataset(
        {"frf": (("response", "reference", "frequency"), h),
         "coherence": (("response", "reference", "frequency"), np.clip(coh, 0.0, 1.0)),
         "reference_level_db": (("reference", "frequency"), level, {"units": "dB"})},
        coords=coords, attrs=attrs,
    )
    ds["frf"].attrs = dict(attrs)
    return ds


def _positive(value, name: str) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} must be a number of seconds > 0, got {value!r}") from None
    if not (np.isfinite(v) and v > 0):
        raise ParameterError(f"{name} must be > 0 s, got {value!r}")
    return v


def is_impulsive(force: np.ndarray) -> bool:
    """True when ``force`` looks like hammer hits rather than continuous excitation.

    The test behind ``excitation="auto"`` of :func:`frf`: after removing the median
    (offset), the peak exceeds 8 x the robust noise level (1.4826 x median absolute
    deviation) and fewer than 2 % of the samples exceed 20 % of the peak. Gaussian
    random force has a peak of ~4-5 standard deviations; a sine sweep spreads its
    energy over the whole record.

    Examples
    --------
    Three simulated hammer hits versus white-noise force:

    >>> from mvtk import testing
    >>> hits = testing.impact_test(20.0, 0.01, 1024.0, 2.0, 3, np.random.default_rng(0))
    >>> is_impulsive(hits.sel(channel="force").values)
    True
    >>> is_impulsive(np.random.default_rng(1).standard_normal(4096))
    False
    """
    f = np.asarray(force, dtype=float)
    f = f - np.median(f)
    peak = np.max(np.abs(f))
    if not peak > 0:
        return False
    noise = 1.4826 * np.median(np.abs(f))
    busy = np.count_nonzero(np.abs(f) > 0.2 * peak)
    return bool(peak > 8 * noise and busy < 0.02 * f.size)


def is_sweep(force: np.ndarray, fs: float, n_blocks: int = 16) -> bool:
    """True when ``force`` is a deterministic sweep (sine sweep, chirp, stepped sine).

    The test behind ``excitation="auto"`` of :func:`frf`: the record is cut into
    ``n_blocks`` blocks; in each, at least half of the power (offset removed) lies within
    +-5 % (at least +-2 lines) of the block's spectral peak (a narrow-band signal), the
    peak frequency moves monotonically from block to block (at most 10 % of the steps
    go backwards) and spans more than a factor 1.2. Random force spreads its power over
    the whole band; a single sine does not move.

    Parameters
    ----------
    force : numpy.ndarray
        Reference signal, 1-D.
    fs : float
        Sampling rate in Hz.
    n_blocks : int
        Blocks the record is cut into.

    Examples
    --------
    A linear 5-200 Hz chirp over 8 s versus white noise:

    >>> from scipy.signal import chirp
    >>> t = np.arange(8192) / 1024.0
    >>> is_sweep(chirp(t, 5.0, t[-1], 200.0), 1024.0)
    True
    >>> is_sweep(np.random.default_rng(1).standard_normal(8192), 1024.0)
    False
    """
    return _sweep_band(force, fs, n_blocks) is not None


def _sweep_band(force, fs: float, n_blocks: int = 16):
    """Swept band (f_lo, f_hi) in Hz of a sweep, or None (see :func:`is_sweep`).

    The band runs from where the spectrum of the first excited block has dropped by
    20 dB below its peak to where that of the last excited block has.
    """
    x = np.asarray(force, dtype=float)
    m = x.size // n_blocks
    if m < 32:
        return None
    blocks = x[:m * n_blocks].reshape(n_blocks, m)
    blocks = blocks - blocks.mean(axis=1, keepdims=True)
    nfft = max(m, min(8 * m, 2**16))  # zero padding of short blocks: finer peak frequency
    p = np.abs(np.fft.rfft(blocks * np.hanning(m), n=nfft, axis=1)) ** 2
    p[:, 0] = 0.0
    f = np.fft.rfftfreq(nfft, 1 / fs)
    total = p.sum(axis=1)
    live = np.flatnonzero(total > 1e-2 * np.median(total))  # silence before/after: no
    if live.size < n_blocks // 2:
        return None
    k = np.argmax(p, axis=1)
    conc = []
    for i in live:
        w = max(16, int(0.05 * k[i]))
        conc.append(p[i, max(k[i] - w, 1):k[i] + w + 1].sum() / total[i])
    fk = f[k[live]]
    steps = np.diff(fk)
    moving = steps[np.abs(steps) > fs / nfft]
    if moving.size == 0 or not np.median(conc) > 0.5:
        return None
    up = np.count_nonzero(moving > 0)
    backwards = min(up, moving.size - up)
    if backwards > 0.1 * steps.size or not fk.max() > 1.2 * max(fk.min(), fs / m):
        return None
    first, last = (live[0], live[-1]) if up > moving.size - up else (live[-1], live[0])
    drop = 10 ** (-_FORCE_DROP_DB / 10)
    lo = f[np.flatnonzero(p[first] >= drop * p[first].max())[0]]
    hi = f[np.flatnonzero(p[last] >= drop * p[last].max())[-1]]
    return float(lo), float(hi)
