"""H1/H2 frequency response functions with coherence, for random and impact tests."""

from __future__ import annotations

import warnings

import numpy as np
import scipy.fft
import xarray as xr

from ..errors import AccuracyWarning, FormatError, ParameterError
from ._input import as_time_history, channel_coord, sampling_rate, select_channels
from ._spectral import (
    _pair_coords,
    _segment_starts,
    _window,
    accumulate_cross,
    welch_segments_params,
)

__all__ = ["frf", "exponential_window_correction", "frf_kind"]

_KINDS = {"displacement": "receptance", "velocity": "mobility", "acceleration": "accelerance"}


def frf_kind(response_quantity: str, reference_quantity: str = "force") -> str | None:
    """FRF type from the channel quantities: receptance, mobility, accelerance or None."""
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


def _impact_records(force, nperseg, pretrigger, trigger_level, fs, force_window_n):
    level = trigger_level * np.max(np.abs(force))
    if not level > 0:
        raise FormatError("reference: the force channel is all zeros; no hit to trigger on")
    quiet = max(4, int(round(0.005 * fs)))
    hits = _find_hits(force, level, quiet, force_window_n or 0)
    n = force.size
    if nperseg is None:
        gaps = np.diff(np.r_[hits, n])
        nperseg = int(np.min(gaps))
        if nperseg < 16:
            raise FormatError(f"reference: hits are only {nperseg} samples apart")
    nperseg = int(nperseg)
    if pretrigger is None:
        pretrigger = max(nperseg // 100, 1)
    starts, double, short = [], [], []
    for k, h in enumerate(hits):
        s = h - pretrigger
        if s < 0 or s + nperseg > n:
            short.append(h / fs)
            continue
        nxt = hits[k + 1] if k + 1 < len(hits) else n
        if nxt < s + nperseg:  # another hit inside this record
            double.append(h / fs)
            continue
        starts.append(s)
    if double or short:
        warnings.warn(
            f"impact FRF: rejected {len(double)} record(s) with a second hit inside the record "
            f"(hits at {[round(t, 4) for t in double]} s) and {len(short)} hit(s) too close "
            f"to the ends of the data (at {[round(t, 4) for t in short]} s); "
            f"nperseg={nperseg}, pretrigger={pretrigger} samples",
            AccuracyWarning, stacklevel=3,
        )
    if not starts:
        raise FormatError(
            f"reference: no complete impact record found ({len(hits)} hit(s) above "
            f"{trigger_level:g} x peak force; nperseg={nperseg}, pretrigger={pretrigger})"
        )
    return np.asarray(starts, dtype=int), nperseg, pretrigger


def frf(
    x,
    reference,
    response=None,
    *,
    estimator: str = "H1",
    excitation: str = "random",
    fs: float | None = None,
    window=None,
    nperseg: int | None = None,
    noverlap: int | None = None,
    detrend="constant",
    trigger_level: float = 0.1,
    pretrigger: int | None = None,
    force_window_s: float | None = None,
    exponential_tau_s: float | None = None,
) -> xr.Dataset:
    """Frequency response functions and coherence from reference and response channels.

    Parameters
    ----------
    x : xarray.DataArray or xarray.Dataset
        Time history, dims ``("channel", "time")`` (or a Dataset with ``"time_history"``)
        holding both the reference (force) and response channels.
    reference : str, int, list or dict
        Reference channel(s): names, positions or a coord filter ``{"quantity": "force"}``.
    response : same kinds, optional
        Response channels; default every channel that is not a reference.
    estimator : {"H1", "H2"}
        ``H1 = G_yr G_rr^-1`` (noise on the response; several references allowed) or
        ``H2 = G_yy / G_ry`` (noise on the reference; one reference only).
    excitation : {"random", "impact"}
        ``"random"``: Welch averaging over overlapping segments (default Hann window).
        ``"impact"``: one record of ``nperseg`` samples per hit, found by a trigger on
        the first reference channel at ``trigger_level`` x its peak (in the polarity of
        the largest sample; crossings less than max(4 samples, 5 ms) after the force
        fell below the level, e.g. anti-alias ringing, belong to the same hit), starting
        ``pretrigger`` samples before the crossing (default 1 % of the record); records
        with a second hit are rejected with an :class:`~mvtk.errors.AccuracyWarning`.
        Default window is rectangular and ``detrend=False``.
    fs : float, optional
        Sampling rate in Hz (derived from ``time`` and checked if given).
    window, nperseg, noverlap, detrend
        As in :func:`scipy.signal.csd` (random excitation).
    force_window_s : float, optional
        Impact only: keep the force from the record start to ``force_window_s`` after
        the trigger and zero it afterwards (removes noise from the force channel).
    exponential_tau_s : float, optional
        Impact only: multiply force and response records by ``exp(-(t - t_trigger)/tau)``
        after the trigger. The added damping is recorded in ``attrs`` and removed by
        :func:`mvtk.damping.half_power` (see :func:`exponential_window_correction`).

    Returns
    -------
    xarray.Dataset
        ``frf``: complex, dims ``("response", "reference", "frequency")`` in
        response units per reference unit (``units`` coord); ``coherence``: ordinary
        coherence ``|G_yr|^2 / (G_yy G_rr)`` per pair. ``attrs`` record the estimator,
        excitation, ``n_averages``, ``nperseg``, ``df_hz``, ``window``, ``kind``
        (receptance/mobility/accelerance when all responses share one quantity) and
        ``exponential_window_tau_s`` when applied.
    """
    if estimator not in ("H1", "H2"):
        raise ParameterError(f"estimator must be 'H1' or 'H2', got {estimator!r}")
    if excitation not in ("random", "impact"):
        raise ParameterError(f"excitation must be 'random' or 'impact', got {excitation!r}")
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
    attrs = {"estimator": estimator, "excitation": excitation, "fs": fs}

    if excitation == "random":
        if force_window_s is not None or exponential_tau_s is not None:
            raise ParameterError(
                "force_window_s and exponential_tau_s apply to excitation='impact' only"
            )
        nperseg, noverlap, window = welch_segments_params(n, fs, nperseg, noverlap, window)
        win = _window(window, nperseg)
        starts = _segment_starts(n, nperseg, noverlap)
        gyr, grr, gyy = accumulate_cross(y, r, starts, nperseg, win, win, detrend)
        attrs.update(window=str(window), noverlap=noverlap)
    else:
        if noverlap is not None:
            raise ParameterError("noverlap applies to excitation='random' only")
        window = "boxcar" if window is None else window
        detrend = False if detrend == "constant" else detrend
        fw_n = None
        if force_window_s is not None:
            if not (np.isfinite(force_window_s) and force_window_s > 0):
                raise ParameterError(f"force_window_s must be > 0 s, got {force_window_s!r}")
            fw_n = int(round(force_window_s * fs))
        starts, nperseg, pre = _impact_records(r[0], nperseg, pretrigger, trigger_level, fs,
                                               fw_n)
        win = _window(window, nperseg)
        win_y = win.copy()
        win_r = win.copy()
        if exponential_tau_s is not None:
            if not (np.isfinite(exponential_tau_s) and exponential_tau_s > 0):
                raise ParameterError(
                    f"exponential_tau_s must be > 0 s, got {exponential_tau_s!r}"
                )
            k = np.arange(nperseg)
            expo = np.exp(-np.clip(k - pre, 0, None) / (exponential_tau_s * fs))
            win_y *= expo
            win_r *= expo
            attrs["exponential_window_tau_s"] = float(exponential_tau_s)
        if fw_n is not None:
            win_r[pre + fw_n:] = 0.0
            attrs["force_window_s"] = float(force_window_s)
        gyr, grr, gyy = accumulate_cross(y, r, starts, nperseg, win_y, win_r, detrend)
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
    f = scipy.fft.rfftfreq(nperseg, 1 / fs)
    coords = _pair_coords(resp, ref, f)
    ru = channel_coord(resp, "units")
    fu = channel_coord(ref, "units")
    coords["units"] = (("response", "reference"),
                       np.array([[f"{a}/{b}" for b in fu] for a in ru], dtype=object))
    rq = set(channel_coord(resp, "quantity"))
    fq = set(channel_coord(ref, "quantity"))
    kind = frf_kind(rq.pop(), fq.pop()) if len(rq) == 1 and len(fq) == 1 else None
    attrs.update(nperseg=int(nperseg), df_hz=fs / nperseg, n_averages=len(starts),
                 kind=kind if kind is not None else "")
    ds = xr.Dataset(
        {"frf": (("response", "reference", "frequency"), h),
         "coherence": (("response", "reference", "frequency"), np.clip(coh, 0.0, 1.0))},
        coords=coords, attrs=attrs,
    )
    ds["frf"].attrs = dict(attrs)
    return ds
