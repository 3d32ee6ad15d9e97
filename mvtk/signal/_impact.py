"""Impact-test checks: double hits, clipped channels, one window policy per test, and the
per-set quality table of an FRF matrix built from hammer (or any) measurement sets."""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from ..errors import FormatError

__all__ = ["DOUBLE_HIT_FRACTION", "CLIP_MIN_SAMPLES", "COHERENCE_MIN", "clipped_channels",
           "second_pulse", "SetQuality", "set_quality", "ImpactPolicy", "impact_policy",
           "quality_row", "peak_force", "set_excitation", "PAD_FACTOR"]

#: A second force pulse whose peak exceeds this fraction of the hit's peak, inside the
#: hit's record, makes the record a double hit.
DOUBLE_HIT_FRACTION = 0.05
#: Zero padding of a complete impact transient: the FFT length is this many times the
#: record, a whole number, so that every ``PAD_FACTOR``-th line is one of the record's
#: own lines ``k / T`` (where a mode that has not decayed is still exactly a pole).
PAD_FACTOR = 8
#: Consecutive samples at a channel's extreme value that make a flat (clipped) top.
CLIP_MIN_SAMPLES = 3
# samples within this fraction of the extreme count as "at" it (values written as
# text with 6-9 significant digits round a saturated ADC code to the same number)
_CLIP_RTOL = 1e-6


def clipped_channels(values: np.ndarray, names, fs: float,
                     min_samples: int = CLIP_MIN_SAMPLES) -> list[dict]:
    """Channels whose largest positive or negative excursion is a flat top.

    An analogue-to-digital converter driven beyond its range returns its end code for
    every sample of the overload: the channel's extreme value then repeats over
    consecutive samples. A sampled smooth peak (a hammer pulse, a decaying response)
    reaches its extreme in one sample.

    Parameters
    ----------
    values : numpy.ndarray
        Samples, ``(channel, time)``, offsets not removed (the ADC range is absolute).
    names : sequence of str
        Channel names.
    fs : float
        Sampling rate in Hz (for the time of the flat top).
    min_samples : int
        Shortest run of samples at the extreme (within 1e-6 of it, relative) that is a
        flat top.

    Returns
    -------
    list of dict
        One per clipped channel: ``channel``, ``value`` (the clipped level, channel
        units), ``n_samples`` (longest run at it), ``time_s`` (start of that run).

    Examples
    --------
    Channel ``acc1`` sits at 5.0 for four samples (an overloaded ADC); ``acc2`` is smooth:

    >>> v = np.vstack([[0, 0, 1, 2, 5, 5, 5, 5, 2, 0], np.sin(np.arange(10.0))])
    >>> clipped_channels(v, ["acc1", "acc2"], fs=1000.0)
    [{'channel': 'acc1', 'value': 5.0, 'n_samples': 4, 'time_s': 0.004}]
    """
    out = []
    x = np.asarray(values, dtype=float)
    for name, row in zip(names, x):
        finite = row[np.isfinite(row)]
        if finite.size < min_samples or not np.ptp(finite) > 0:
            continue
        best = None
        base = float(np.median(finite))
        reach = max(finite.max() - base, base - finite.min())
        for level in (finite.max(), finite.min()):
            if abs(level - base) < 0.5 * reach:
                continue  # the quiet side of a pulse (a force at rest), not an overload
            tol = _CLIP_RTOL * max(abs(level), np.ptp(finite))
            at = np.abs(row - level) <= tol
            edges = np.diff(np.r_[0, at.astype(np.int8), 0])
            starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
            if not starts.size:
                continue
            k = int(np.argmax(ends - starts))
            run = int(ends[k] - starts[k])
            if run >= min_samples and (best is None or run > best["n_samples"]):
                best = {"channel": str(name), "value": float(level), "n_samples": run,
                        "time_s": float(starts[k] / fs)}
        if best is not None:
            out.append(best)
    return out


def second_pulse(force: np.ndarray, hit: int, end: int, level: float,
                 fraction: float = DOUBLE_HIT_FRACTION):
    """First sample of a second force pulse after the pulse that starts at ``hit``.

    ``force`` is offset-free and in the polarity of the hits (positive pulses). The hit's
    pulse runs from ``hit`` while ``force >= level``; a second pulse is a sample in
    ``[pulse end + pulse width, end)`` at or above ``fraction`` x the hit's peak (the
    force must have left the pulse for one pulse width: the samples just after a pulse
    are its own tail) that rises from a force near zero: a lobe preceded by a negative
    excursion of more than half its height is anti-alias filter ringing, not a hit.

    Returns
    -------
    (int, float) or None
        Sample of the second pulse's start (where it first reaches ``fraction`` x the
        peak, walked back to where it rose from the floor) and its peak over the hit's
        peak; None when the record holds one pulse.
    """
    n = force.size
    e = hit
    while e < n and force[e] >= level:
        e += 1
    if e <= hit:
        return None
    peak = float(np.max(force[hit:e]))
    width = e - hit
    s0 = e + max(width, 2)
    end = min(end, n)
    if s0 >= end or not peak > 0:
        return None
    seg = force[s0:end]
    above = s0 + np.flatnonzero(seg >= fraction * peak)
    # anti-alias filter ringing after a short pulse alternates in sign, its negative
    # lobes as large as the positive ones; a rebound rises from a force near zero
    for k in above:
        top = float(np.max(force[k:min(k + width + 2, n)]))
        if np.min(force[e:k]) > -0.5 * top:
            break
    else:
        return None
    k = int(k)
    # where the second pulse rose from the floor (below half the threshold)
    j = k
    while j > s0 and force[j - 1] >= 0.5 * fraction * peak:
        j -= 1
    nxt = k
    while nxt < end and force[nxt] >= fraction * peak:
        nxt += 1
    return j, float(np.max(force[k:max(nxt, k + 1)]) / peak)


# --- the per-set quality table -------------------------------------------------------

_COLUMNS = ("set", "source", "excitation", "references", "responses", "n_hits",
            "n_averages", "peak_force", "excitation_band_hz", "coherence", "double_hit_s",
            "double_hit_ratio", "double_hit_action", "clipped", "usable", "verdict")


@dataclass(frozen=True)
class SetQuality:
    """Quality of each measurement set behind an FRF matrix (one row per set).

    Built by :func:`mvtk.modal.frf_matrix`; stored with the FRF matrix in
    ``attrs["set_quality"]`` (JSON text, so it survives :func:`mvtk.io.write` and
    :func:`mvtk.io.read`) and returned by :func:`set_quality`.

    Attributes
    ----------
    rows : tuple of dict
        Per set: ``set`` (1-based position in the list of sets), ``source`` (the file
        the set was read from, ``""`` if unknown), ``excitation`` (impact, random,
        sweep), ``references``/``responses`` (``node+direction`` or channel names,
        comma separated), ``n_hits`` (force pulses found, impact), ``n_averages``
        (records or segments averaged), ``peak_force`` (largest reference excursion,
        reference units), ``excitation_band_hz`` (upper end of the band where the force
        spectrum is within 20 dB of its low-frequency level, impact/sweep; NaN
        otherwise), ``coherence`` (mean ordinary coherence of the set's pairs inside
        that band; NaN with a single average, where coherence is 1 by construction),
        ``double_hit_s`` (time in the file of the first second pulse, s; NaN if none),
        ``double_hit_ratio`` (its peak over the hit's), ``double_hit_action`` (``""``,
        ``"cut"``: the record was ended before the second pulse, or ``"refused"``),
        ``clipped`` (channels with a flat top at the ADC range and their level,
        ``""`` if none), ``usable`` (False: the set is not in the FRF matrix) and
        ``verdict`` (``"ok"`` or what is wrong, in words).

    Examples
    --------
    Returned by :func:`set_quality`; ``to_dataframe`` gives one row per set:

    >>> from mvtk import testing
    >>> from mvtk.modal import frf_matrix
    >>> hits = testing.impact_test(20.0, 0.01, 256.0, 4.0, 3, np.random.default_rng(0))
    >>> q = set_quality(frf_matrix([hits], "force"))
    >>> len(q.rows), q.rows[0]["excitation"]
    (1, 'impact')
    """

    rows: tuple

    def to_dataframe(self):
        """The table as a :class:`pandas.DataFrame` indexed by ``set``."""
        import pandas as pd

        df = pd.DataFrame(list(self.rows), columns=list(_COLUMNS))
        return df.set_index("set")

    def to_json(self) -> str:
        """JSON text of the rows (NaN written as null)."""
        def clean(v):
            if isinstance(v, float) and not np.isfinite(v):
                return None
            if isinstance(v, (np.floating, np.integer, np.bool_)):
                return clean(v.item())
            return v
        return json.dumps([{k: clean(r.get(k)) for k in _COLUMNS} for r in self.rows])

    @classmethod
    def from_json(cls, text: str) -> SetQuality:
        """Rows from :meth:`to_json` text (null read back as NaN)."""
        rows = []
        for r in json.loads(text):
            rows.append({k: (np.nan if r.get(k) is None and k not in ("source", "verdict")
                             else r.get(k)) for k in _COLUMNS})
        return cls(rows=tuple(rows))

    @property
    def flagged(self):
        """Rows whose verdict is not ``"ok"``."""
        return tuple(r for r in self.rows if r["verdict"] != "ok")

    def _repr_html_(self) -> str:  # pragma: no cover - notebook display
        return self.to_dataframe()._repr_html_()


def set_quality(frf) -> SetQuality:
    """The per-set quality table of an FRF matrix made by :func:`mvtk.modal.frf_matrix`.

    Parameters
    ----------
    frf : xarray.DataArray or xarray.Dataset
        FRF matrix (or a Dataset holding one as ``frf``) with ``attrs["set_quality"]``.

    Returns
    -------
    SetQuality

    Raises
    ------
    mvtk.errors.FormatError
        The object carries no set-quality table (FRFs read from an FRF file, or made
        by another tool).

    Examples
    --------
    Three hits of a simulated impact test: one set, all hits found, usable:

    >>> from mvtk import testing
    >>> from mvtk.modal import frf_matrix
    >>> hits = testing.impact_test([20.0, 55.0], [0.01, 0.02], 256.0, 4.0, 3,
    ...                            np.random.default_rng(0))
    >>> table = set_quality(frf_matrix([hits], "force")).to_dataframe()
    >>> table[["excitation", "n_hits", "usable"]].values.tolist()
    [['impact', 3, True]]
    """
    attrs = dict(getattr(frf, "attrs", {}))
    if "frf" in getattr(frf, "data_vars", {}):
        attrs = {**attrs, **frf["frf"].attrs}
    text = attrs.get("set_quality")
    if not isinstance(text, str) or not text:
        raise FormatError(
            "set_quality: the FRF matrix carries no attrs['set_quality'] (made by "
            "mvtk.modal.frf_matrix from measurement sets); FRFs read from an FRF file "
            "have no per-set record")
    return SetQuality.from_json(text)


# --- one window policy per impact test ------------------------------------------------

@dataclass(frozen=True)
class ImpactPolicy:
    """Record, pretrigger, exponential window and FFT length shared by every set of an
    impact test (see :func:`impact_policy`).

    Examples
    --------
    Returned by :func:`impact_policy`; ``reason`` states the choices in words:

    >>> from mvtk import testing
    >>> hits = testing.impact_test(20.0, 0.01, 256.0, 4.0, 3, np.random.default_rng(0))
    >>> pol = impact_policy([hits], "force")
    >>> pol.nperseg, pol.reason.startswith("one policy")
    (1021, True)
    """

    nperseg: int
    pretrigger: int
    exponential_tau_s: float | None
    nfft: int
    slowest_set: int
    tail_ratio: float
    reason: str

    def frf_options(self) -> dict:
        """Keyword arguments of :func:`mvtk.signal.frf` that apply the policy."""
        return {"nperseg": self.nperseg, "pretrigger": self.pretrigger,
                "exponential_tau_s": self.exponential_tau_s, "nfft": self.nfft}


def impact_policy(sets, reference, response=None, *, trigger_level: float = 0.1,
                  double_hit_fraction: float = DOUBLE_HIT_FRACTION, names=None,
                  nperseg: int | None = None, pretrigger: int | None = None,
                  exponential_tau_s="auto", nfft="auto") -> ImpactPolicy:
    """One record length and one exponential window for all sets of an impact test.

    Each set alone would take the whole time between its hits as record and its own
    window time constant; poles identified from FRFs windowed differently carry
    different added damping, which no single correction removes. Here:

    - record: the shortest whole record (pretrigger before a hit to pretrigger before
      the next hit, or to the end of the data) over the sets, leaving out sets whose
      record is shorter than half the median (a double hit or a late hit: their
      records are then cut or refused by :func:`mvtk.signal.frf`, not the test's);
    - pretrigger: the smallest automatic pretrigger of the sets that set the record
      (1 % of the record); a set with a longer one gives up the difference;
    - exponential window: none when every set's response decays to 1 % of its peak
      within the record (RMS of its last 5 %); otherwise the time constant that brings
      the slowest decay (largest tail) to 1 %, applied to every set. A set whose tail is
      within 3 x its pretrigger RMS has decayed into its noise floor and does not
      count (a window cannot make noise decay);
    - FFT length: the record itself when a window is applied; :data:`PAD_FACTOR` (8) x
      the record (the lines interpolate the spectrum, every 8th is one of the record's
      own) only when every response has decayed to 1 % unwindowed. An exponential
      window brings the *whole* response to 1 % of its peak, but a slow mode of small
      amplitude (the first bending mode of an accelerance) still ends the record at
      several per cent of its own amplitude: on the record's own lines ``k / T`` the
      truncated exponential is exactly a pole (``exp(-i w T) = 1``, only its residue
      is scaled), on interpolated lines it adds a ripple ``exp(-i w T) / (i w -
      lambda)`` of period ``1 / T``, about one windowed bandwidth, that no modal model
      holds: the damping of such a mode comes out biased (+17 % pLSCF, +34 % refined
      on a 0.3 s roving-hammer test) and removing the window's damping multiplies that
      bias. The same holds unwindowed; :func:`mvtk.modal.identify` then repeats the
      fit on the own lines of the padded FRFs.

    Parameters
    ----------
    sets : sequence of time histories
        ``("channel", "time")`` DataArrays or Datasets with ``time_history``.
    reference, response
        Channel selection as in :func:`mvtk.signal.frf`.
    trigger_level, double_hit_fraction : float
        As in :func:`mvtk.signal.frf`.
    names : sequence of str, optional
        Names of the sets for the reason text (file names); default ``set k``.
    nperseg, pretrigger, exponential_tau_s, nfft
        As in :func:`mvtk.signal.frf`; a value given is kept for every set (None for
        ``exponential_tau_s``: no window), ``None``/``"auto"`` is chosen as above.

    Returns
    -------
    ImpactPolicy
        ``nperseg``, ``pretrigger`` (samples), ``exponential_tau_s`` (s, or None),
        ``nfft``, ``slowest_set`` (1-based), ``tail_ratio`` (its unwindowed tail) and
        ``reason`` (the choice in words); :meth:`ImpactPolicy.frf_options` gives the
        keywords of :func:`mvtk.signal.frf`.

    Raises
    ------
    mvtk.errors.FormatError
        A set has no force pulse, or the sets have different sampling rates.

    Examples
    --------
    Three hits 8 s apart on a lightly damped structure (20 and 55 Hz): the response has
    decayed within each record, so no exponential window is needed:

    >>> from mvtk import testing
    >>> hits = testing.impact_test([20.0, 55.0], [0.01, 0.02], 1024.0, 8.0, 3,
    ...                            np.random.default_rng(0))
    >>> pol = impact_policy([hits], "force")
    >>> pol.nperseg, pol.nfft, pol.exponential_tau_s
    (8192, 65536, None)
    """
    import warnings

    from ._frf import _impact_records, _pretrigger_offset, _tail_ratio, _tau_for_tail
    from ._input import as_time_history, sampling_rate, select_channels
    from ._spectral import _window

    data = []
    fs0 = None
    names = list(names) if names is not None else [f"set {k + 1}" for k in range(len(sets))]
    for k, x in enumerate(sets):
        th = as_time_history(x)
        fs = sampling_rate(th)
        if fs0 is None:
            fs0 = fs
        elif abs(fs - fs0) > 1e-6 * fs0:
            raise FormatError(f"{names[k]}: sampled at {fs:g} Hz; expected the {fs0:g} Hz of "
                              f"{names[0]} (one record length for the whole test)")
        ref = select_channels(th, reference, name="reference")
        refn = {str(c) for c in ref["channel"].values}
        if response is None:
            keep = [i for i, c in enumerate(th["channel"].values) if str(c) not in refn]
            resp = th.isel(channel=keep)
        else:
            resp = select_channels(th, response, name="response")
        r = np.asarray(ref.values, dtype=float)
        y = np.asarray(resp.values, dtype=float)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            _, _, pre, _, _, info = _impact_records(r[0], None, None, trigger_level, fs,
                                                    None, double_hit_fraction)
        data.append((r, y, pre, info["available"]))
    avail = np.array([d[3] for d in data], dtype=float)
    own_pre = np.array([d[2] for d in data], dtype=float)
    typical = avail >= 0.5 * np.median(avail)
    given = nperseg is not None
    # the pretrigger and the record come from the same sets (a double-hit set left out
    # of the record must not shorten the pretrigger either), and a set whose own
    # pretrigger is longer loses the difference from its record
    pre = int(pretrigger) if pretrigger is not None else int(np.min(own_pre[typical]))
    nperseg = (int(nperseg) if given else
               int(np.min(avail[typical] - np.clip(own_pre[typical] - pre, 0, None))))
    win = _window("boxcar", nperseg)
    tails, floor = [], []
    for r, y, _, _ in data:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            try:
                starts, _, _, _, doubles, _ = _impact_records(
                    r[0], nperseg, pre, trigger_level, fs0, None, double_hit_fraction)
            except FormatError:
                tails.append(0.0)  # no complete record: frf says so for this set
                continue
        if not starts.size:
            tails.append(0.0)  # double hits only: refused or cut by frf, not the measure
            continue
        use = starts
        yy = y - _pretrigger_offset(y, use, pre)[:, None] if pre >= 8 else y
        tail = _tail_ratio(yy, use, nperseg, pre, win)
        if pre >= 8 and tail <= 3 * _noise_ratio(yy, use, nperseg, pre):
            floor.append(len(tails))
            tail = 0.0  # the record ends in the sensor's noise: the decay is complete
        tails.append(tail)
    tails = np.asarray(tails)
    slow = int(np.argmax(tails))
    if exponential_tau_s == "auto":
        tau = (_tau_for_tail(float(tails[slow]), nperseg, pre, fs0) if tails[slow] > 0.01
               else None)
    else:
        tau = None if exponential_tau_s is None else float(exponential_tau_s)
    nfft = (PAD_FACTOR * nperseg if nfft in ("auto", None) and
            tau is None and tails[slow] <= 0.011 else
            nperseg if nfft in ("auto", None) else int(nfft))
    if given:
        what = "given"
    else:
        what = "the shortest whole record between hits" + (
            f", {int(np.sum(~typical))} set(s) with a shorter one "
            "left to their double-hit check" if not typical.all() else "")
    reason = (f"one policy for the {len(data)} sets: record {nperseg} samples = "
              f"{nperseg / fs0:.4g} s ({what}), pretrigger {pre}"
              + (f", zero-padded to {nfft}" if nfft > nperseg else "") + "; ")
    if floor:
        reason += (f"{len(floor)} set(s) end in their noise floor (tail within 3 x the "
                   "pretrigger RMS: decay complete); ")
    if exponential_tau_s != "auto":
        reason += ("exponential window as given: " + ("none" if tau is None else
                                                      f"tau = {tau:.4g} s on every set"))
    elif tau is None:
        reason += ("no exponential window: every response decays to 1 % within the record "
                   f"(largest tail {tails[slow]:.2%}, {names[slow]})")
    else:
        reason += (f"exponential window tau = {tau:.4g} s on every set, from the slowest "
                   f"decay ({names[slow]}: tail {tails[slow]:.1%} of its peak at the end of "
                   f"the record, brought to 1 %); it adds 1/(tau omega_n) to every damping "
                   "ratio (mvtk.signal.exponential_window_correction removes it)")
    return ImpactPolicy(nperseg=nperseg, pretrigger=pre, exponential_tau_s=tau, nfft=nfft,
                        slowest_set=slow + 1, tail_ratio=float(tails[slow]), reason=reason)


def _noise_ratio(y: np.ndarray, starts, nperseg: int, pre: int) -> float:
    """Largest pretrigger RMS over the record's peak (the noise floor), over records."""
    worst = 0.0
    for s in starts:
        seg = y[:, s:s + nperseg]
        pk = np.max(np.abs(seg[:, pre:]), axis=-1)
        noise = np.sqrt(np.mean(seg[:, :pre] ** 2, axis=-1))
        ok = pk > 0
        if ok.any():
            worst = max(worst, float(np.max(noise[ok] / pk[ok])))
    return worst


# --- rows of the set-quality table ---------------------------------------------------

#: Mean coherence in the excited band below which a set with several averages is flagged.
COHERENCE_MIN = 0.8


def quality_row(index: int, source: str, peak: float, ds, references, responses) -> dict:
    """The :class:`SetQuality` row of one measurement set and its FRF Dataset.

    ``peak`` is the set's peak force (:func:`peak_force`), ``ds`` what
    :func:`mvtk.signal.frf` returned for it, or the exception that refused the set.
    """
    row = {k: np.nan for k in _COLUMNS}
    row.update(set=int(index), source=str(source), peak_force=float(peak),
               references=", ".join(references),
               responses=", ".join(responses), double_hit_action="", clipped="")
    if isinstance(ds, Exception):
        doubles = list(getattr(ds, "double_hits", ()))
        row.update(excitation="impact", usable=False, n_averages=0,
                   double_hit_action="refused")
        if doubles:
            row.update(double_hit_s=float(doubles[0]["second_s"]),
                       double_hit_ratio=float(doubles[0]["ratio"]),
                       verdict="refused: double hit at " + ", ".join(
                           f"{d['second_s']:.4g} s ({d['ratio']:.0%} of the hit)"
                           for d in doubles) + ", no clean record")
        else:
            row["verdict"] = f"refused: {ds}"
        return row
    a = ds.attrs
    row["excitation"] = str(a.get("excitation", ""))
    row["n_averages"] = int(a.get("n_averages", 1))
    row["n_hits"] = int(a["n_hits"]) if "n_hits" in a else np.nan
    band = a.get("excitation_band_hz")
    f = ds["frequency"].values
    if band is not None:
        row["excitation_band_hz"] = float(band[1])
        inband = (f > 0) & (f >= band[0]) & (f <= band[1])
    else:
        inband = f > 0
    if row["n_averages"] > 1:
        row["coherence"] = float(np.nanmean(ds["coherence"].values[..., inband]))
    verdicts = []
    times = list(a.get("double_hit_s", []))
    if times:
        row["double_hit_s"] = float(times[0])
        row["double_hit_ratio"] = float(a["double_hit_ratio"][0])
        acts = list(a.get("double_hit_action", []))
        row["double_hit_action"] = "cut" if "cut" in acts else "refused"
        verdicts.append("double hit at " + ", ".join(f"{t:.4g} s" for t in times) + " ("
                        + ", ".join(f"record {act}" for act in acts) + ")")
    if a.get("clipped"):
        row["clipped"] = str(a["clipped"])
        verdicts.append(f"clipped: {a['clipped']}")
    if np.isfinite(row["coherence"]) and row["coherence"] < COHERENCE_MIN:
        verdicts.append(f"mean coherence {row['coherence']:.2f} < {COHERENCE_MIN:g}")
    row["usable"] = True
    row["verdict"] = "; ".join(verdicts) if verdicts else "ok"
    return row


def peak_force(values: np.ndarray) -> float:
    """Largest excursion of a reference channel from its median (its rest level)."""
    v = np.asarray(values, dtype=float)
    return float(np.max(np.abs(v - np.median(v))))


def set_excitation(x, reference) -> str:
    """Excitation of one measurement set as ``excitation="auto"`` of
    :func:`mvtk.signal.frf` finds it: ``"impact"``, ``"sweep"`` or ``"random"``.

    Examples
    --------
    >>> from mvtk import testing
    >>> hits = testing.impact_test(20.0, 0.01, 1024.0, 2.0, 3, np.random.default_rng(0))
    >>> set_excitation(hits, "force")
    'impact'
    """
    from ._frf import is_impulsive, is_sweep
    from ._input import as_time_history, sampling_rate, select_channels

    th = as_time_history(x)
    r = np.asarray(select_channels(th, reference, name="reference").values[0], dtype=float)
    return ("impact" if is_impulsive(r) else
            "sweep" if is_sweep(r, sampling_rate(th)) else "random")
