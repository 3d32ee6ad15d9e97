"""Covariance-driven stochastic subspace identification (SSI-cov) for output-only data."""

from __future__ import annotations

import numpy as np
import scipy.fft

from ..errors import ParameterError
from ._identify import dof_labels, quality_flags, shapes_array
from ._plscf import _check_orders
from ._quality import mpc, mpd
from ._result import IdentifiedModes
from ._stabilisation import (
    ClusterCriteria,
    StabilisationDiagram,
    StabilityCriteria,
    poles_near,
    poles_to_diagram,
    select_poles,
)

__all__ = ["ssi_cov", "identify_output_only"]


def _correlations(y, yr, nlag):
    """Unbiased output correlations ``R_k = E[y_{t+k} y_ref_t^T]``, k = 0..nlag-1."""
    n = y.shape[1]
    nfft = scipy.fft.next_fast_len(n + nlag)
    Y = scipy.fft.rfft(y, nfft)
    Yr = scipy.fft.rfft(yr, nfft)
    r = scipy.fft.irfft(Y[:, None, :] * np.conj(Yr[None, :, :]), nfft)[..., :nlag]
    return np.moveaxis(r, -1, 0) / (n - np.arange(nlag))[:, None, None]


# largest block Toeplitz matrix (rows) an automatic n_lags may ask for (SVD ~ 2 s)
_MAX_TOEPLITZ_ROWS = 2000
#: default lowest frequency the block rows resolve, as a fraction of the record's lowest
#: spectral peak: an octave below it. With 0.9 (the lowest peak just inside the band)
#: a weak first mode 13 % below a strong second one was cut, and a detected first
#: mode 14 % above the band's start was not identified (too few lags: 1.15 periods).
LOWEST_PEAK_FRACTION = 0.5


def _decimate(y, fs, fmax):
    """``y`` decimated to the lowest rate with ``fmax`` below 0.4 x the new rate."""
    import scipy.signal

    q_total = int(np.floor(0.4 * fs / fmax))
    while q_total > 1:
        q = min(q_total, 10)
        y = scipy.signal.decimate(y, q, axis=1, zero_phase=True)
        fs /= q
        q_total = int(np.floor(0.4 * fs / fmax))
    return y, fs


def _time_history_like(th, y, fs):
    """A time history with the coordinates of ``th`` and samples ``y`` at rate ``fs``."""
    import xarray as xr

    coords = {k: v for k, v in th.coords.items() if "time" not in v.dims}
    coords["time"] = float(th["time"].values[0]) + np.arange(y.shape[1]) / fs
    return xr.DataArray(y, dims=("channel", "time"), coords=coords, attrs=th.attrs,
                        name=th.name)


def _spectral_peaks(y, fs, fmin=None, fmax=None):
    """``(fn_hz, amplitude, line_spacing_hz)`` of the peaks that stand out of the record's
    spectrum: :func:`mvtk.signal.find_peaks` on the summed channel amplitude spectra
    (Welch, segments of 1/8 of the record), lines below 2 line spacings skipped; empty
    when none."""
    import scipy.signal

    from ..errors import MvtkError
    from ..signal import find_peaks

    nper = 2 ** int(np.floor(np.log2(max(y.shape[1] / 8, 16))))
    f, pxx = scipy.signal.welch(y, fs, nperseg=nper, axis=1)
    lo = max(2 * fs / nper, 0.0 if fmin is None else float(fmin))
    try:
        peaks = find_peaks(np.sqrt(pxx), f, power=False, fmin=lo, fmax=fmax)
    except MvtkError:
        return np.zeros(0), np.zeros(0), fs / nper
    return (np.asarray(peaks.fn_hz, dtype=float), np.asarray(peaks.amplitude, dtype=float),
            fs / nper)


def _lowest_peak_hz(y, fs, fmax) -> float:
    """Frequency (Hz) of the lowest peak of :func:`_spectral_peaks` (0 if none)."""
    fn = _spectral_peaks(y, fs, fmax=fmax)[0]
    return float(fn.min()) if fn.size else 0.0


def _warn_unselected_peaks(y, fs, band, fn_sel, kurt_of):
    """AccuracyWarning naming the record's strongest spectral peaks (at least half the
    largest amplitude) that no selected mode explains (none within 1 % or 2 lines)."""
    import warnings

    from ..errors import AccuracyWarning

    strong, df = _near_strong_peaks(y, fs, band)
    if not strong.size:
        return
    fn_sel = np.asarray(fn_sel, dtype=float)
    missed = [fp for fp in strong
              if not np.any(np.abs(fn_sel - fp) <= max(0.01 * fp, 2 * df))]
    if not missed:
        return
    kurt = kurt_of(np.asarray(missed))
    what = "; ".join(
        f"{fp:.4g} Hz" + (f" (band kurtosis {k:.2f}: a harmonic)" if k < 2.0 else
                          f" (band kurtosis {k:.2f})" if np.isfinite(k) else "")
        for fp, k in zip(missed, kurt))
    warnings.warn(
        f"identify_output_only: the record's strongest spectral peak(s) have no selected "
        f"mode: {what}; their poles do not stabilise (a harmonic, closely spaced lines or "
        "a mode SSI-cov could not fit): check them with fn_hz=[...]",
        AccuracyWarning, stacklevel=3,
    )


def _near_strong_peaks(y, fs, band):
    """``(f, df)``: the record's strongest spectral peaks in the band (at least half the
    largest amplitude) and the Welch line spacing."""
    f, amp, df = _spectral_peaks(y, fs, band[0], band[1])
    return (f[amp >= 0.5 * amp.max()] if f.size else f), df


def _line_kurtosis(y, fs, band, fn_sel, band_kurtosis):
    """Per selected mode, the lowest band kurtosis (band ``+-0.5 %``) of the strong
    spectral peaks it explains (within 1 % or 2 lines); NaN when none."""
    strong, df = _near_strong_peaks(y, fs, band)
    out = np.full(np.size(fn_sel), np.nan)
    if not strong.size:
        return out
    k = band_kurtosis(y, fs, strong, np.full(strong.size, 0.0025))
    for m, f in enumerate(np.atleast_1d(fn_sel)):
        near = np.abs(strong - f) <= max(0.01 * f, 2 * df)
        if near.any():
            out[m] = np.nanmin(k[near])
    return out


def _warn_power_below(y, lo, hi, i, fs):
    """ResolutionWarning when the record's largest line or > 25 % of its power lies below
    the resolved band."""
    import warnings

    import scipy.signal

    from ..errors import ResolutionWarning

    if not lo > 0:
        return
    # segments of >= 1/8 of the record and lines <= lo / 4 apart: the power below lo
    # (a segment shorter than a period loses it to the segment's mean) is seen
    nper = min(y.shape[1], 2 ** int(np.ceil(np.log2(max(4 * fs / lo, y.shape[1] / 8)))))
    f, pxx = scipy.signal.welch(y, fs, nperseg=nper, axis=1)
    power = pxx.sum(axis=0)
    total = power[f <= hi].sum()
    below = power[f < lo].sum()
    in_band = f <= hi
    if total > 0 and (below > 0.25 * total or f[in_band][np.argmax(power[in_band])] < lo):
        peak = f[f < lo][int(np.argmax(power[f < lo]))]
        warnings.warn(
            f"ssi_cov: {below / total:.0%} of the record's power up to {hi:g} Hz lies below "
            f"{lo:.4g} Hz, the lowest frequency {i} block rows resolve at {fs:g} Hz "
            f"(largest peak there: {peak:.4g} Hz); to identify it give fmax (the record "
            "is decimated) or fmin (n_lags is raised)",
            ResolutionWarning, stacklevel=3,
        )


def ssi_cov(
    x,
    fmin: float | None = None,
    fmax: float | None = None,
    orders=range(2, 61, 2),
    *,
    reference=None,
    n_lags: int | None = None,
    fs: float | None = None,
    criteria: StabilityCriteria | None = None,
) -> StabilisationDiagram:
    """Poles and shapes of output-only records over a range of model orders (SSI-cov).

    Output correlations ``R_k`` (to the ``reference`` channels) are stacked in the
    block Toeplitz matrix ``T = [R_{i+a-b}]`` (``i = n_lags`` block rows, ``a, b =
    0..i-1``); its SVD ``U S V^T`` gives the observability matrix ``O_n = U_n
    S_n^(1/2)`` of each order ``n`` (one SVD for every order), ``A = O_up^+ O_down``
    and ``C`` = the first block row; ``lambda = fs ln(eig(A))`` and the shapes are
    ``C psi``.

    Parameters
    ----------
    x : xarray.DataArray or Dataset
        Time history ``("channel", "time")`` of the responses (ambient/operational).
    fmin, fmax : float, optional
        Band in Hz for the physical poles (default 0..fs/2). With ``fmax`` below
        ``fs / 8`` the record is first decimated (zero-phase order-8 Chebyshev
        anti-aliasing filters, :func:`scipy.signal.decimate`, in stages of at most 10)
        to the lowest rate keeping ``fmax`` below 0.4 x the new rate. The band's lower
        end is raised to the lowest frequency the block rows resolve,
        ``fs / (2 n_lags)`` (Rainieri & Fabbrocino 2014, ch. 4: ``i >= fs / (2 f_0)``
        for the lowest frequency ``f_0`` of interest). Without ``n_lags``, ``n_lags``
        is raised to resolve ``fmin``, or without ``fmin`` half the record's lowest
        spectral peak (:func:`mvtk.signal.find_peaks`; an octave below it,
        :data:`LOWEST_PEAK_FRACTION`), up to 2000 rows of the Toeplitz matrix. A
        record whose largest spectral line or more than 25 % of whose power lies below
        the resolved band gives a
        :class:`~mvtk.errors.ResolutionWarning` naming its largest peak there.
    orders : iterable of int
        State-space orders (even; each gives ``n/2`` conjugate pairs).
    reference : channel selection, optional
        Reference outputs for the correlations (default every channel).
    n_lags : int, optional
        Block rows ``i``. Default: ``max(ceil((max_order + 1) / n_ref), 20)``, raised
        to ``ceil(fs / (2 f_0))`` with ``f_0`` = ``fmin`` or 0.5 x the lowest spectral
        peak of the record, at most ``2000 / n_channels``.
    fs : float, optional
        Sampling rate in Hz (derived from ``time`` and checked if given).

    Returns
    -------
    StabilisationDiagram
        ``vector`` holds the mode shape of each pole (vector stability = MAC of shapes);
        the indicator behind is the singular values of the output PSD matrix
        (:func:`mvtk.signal.csd`).

    References
    ----------
    Peeters & De Roeck, "Reference-based stochastic subspace identification for
    output-only modal analysis", MSSP 13(6) 1999.
    Rainieri & Fabbrocino, "Operational Modal Analysis of Civil Engineering
    Structures", Springer 2014, ch. 4 (number of block rows).

    Examples
    --------
    Two minutes of the response of two modes (20 Hz at 1 %, 55 Hz at 2 %) to white
    noise, response channel only (no force):

    >>> from mvtk import testing
    >>> x = testing.random_excitation_test([20.0, 55.0], [0.01, 0.02], 256.0, 120.0,
    ...                                    np.random.default_rng(0))
    >>> diagram = ssi_cov(x.sel(channel=["response"]), 5.0, 100.0, orders=range(2, 21, 2))
    >>> sel = select_poles(diagram)
    >>> np.round(np.abs(sel.pole) / (2 * np.pi), 1)
    array([20. , 55.1])
    """
    return _ssi_cov(x, fmin, fmax, orders, reference=reference, n_lags=n_lags, fs=fs,
                    criteria=criteria)[0]


def _ssi_cov(x, fmin, fmax, orders, *, reference=None, n_lags=None, fs=None, criteria=None):
    """:func:`ssi_cov` and the state its uncertainty needs: ``(diagram, state)`` with
    ``state`` the zero-mean (decimated) outputs ``y``, references ``yr``, block rows
    ``i``, rate ``fs`` and the SVD ``U, S, Vt`` of the block Toeplitz matrix."""
    from .. import signal
    from ._quality import cmif

    crit = criteria or StabilityCriteria()
    th = signal.as_time_history(x)
    fs = signal.sampling_rate(th, fs)
    orders = _check_orders(orders)
    y = th.values.astype(float)
    if not np.all(np.isfinite(y)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(y), axis=1))[0])
        raise ParameterError(
            f"ssi_cov: channel {th['channel'].values[bad]!s} holds NaN/inf samples"
        )
    y = y - y.mean(axis=1, keepdims=True)
    fs_in = fs
    if fmax is not None and 0 < float(fmax) < fs / 8:
        y, fs = _decimate(y, fs, float(fmax))
        th = _time_history_like(th, y, fs)
    if reference is None:
        ref_idx = np.arange(y.shape[0])
    else:
        ref = signal._input.select_channels(th, reference, name="reference")
        names = [str(c) for c in th["channel"].values]
        ref_idx = np.array([names.index(str(c)) for c in ref["channel"].values])
    yr = y[ref_idx]
    nl, nr = y.shape[0], yr.shape[0]
    pmax = int(orders.max())
    i = int(n_lags) if n_lags is not None else max(int(np.ceil((pmax + 1) / nr)), 20)
    if n_lags is None:
        # the lowest frequency to resolve: fmin, or an octave below the record's
        # lowest spectral peak (a weaker mode below it that the peak picker missed
        # stays in the band, and the lags span two periods of that peak)
        f0 = float(fmin) if fmin is not None and float(fmin) > 0 else \
            LOWEST_PEAK_FRACTION * _lowest_peak_hz(y, fs, fmax)
        if f0 > 0:
            i = max(i, min(int(np.ceil(fs / (2 * f0))), _MAX_TOEPLITZ_ROWS // nl))
    if i * nr < pmax or i * nl < pmax:
        raise ParameterError(
            f"ssi_cov: n_lags={i} block rows give a Toeplitz matrix of rank <= "
            f"{min(i * nr, i * nl)}; expected at least the highest order {pmax}"
        )
    if 2 * i + 1 >= y.shape[1] // 4:
        raise ParameterError(
            f"ssi_cov: {y.shape[1]} samples"
            + (f" (after decimation from {fs_in:g} to {fs:g} Hz)" if fs != fs_in else "")
            + f" are too few for {i} block rows (need > {4 * (2 * i + 2)}): a longer "
            "record, fewer model orders, or a smaller n_lags"
        )
    lo = 0.0 if fmin is None else float(fmin)
    hi = fs / 2 if fmax is None else float(fmax)
    if not (0 <= lo < hi <= fs / 2):
        raise ParameterError(f"ssi_cov: the band must satisfy 0 <= fmin < fmax <= fs/2 = "
                             f"{fs / 2:g} Hz; got {lo!r}..{hi!r}")
    floor = fs / (2 * i)
    if floor >= hi:
        raise ParameterError(
            f"ssi_cov: {i} block rows at {fs:g} Hz resolve only frequencies above "
            f"{floor:.4g} Hz, above the band's end {hi:g} Hz: raise n_lags to at least "
            f"{int(np.ceil(fs / (2 * max(lo, hi / 10))))} or give fmax (decimation)"
        )
    lo = max(lo, floor)
    # one BLAS thread: the SVD and the per-order solves are 4-100x slower with a
    # second OpenBLAS thread on a loaded 2-core machine (measured: a 1236-row SVD
    # 12 s against 2.7 s)
    from .._blas import blas_limits

    with blas_limits():
        R = _correlations(y, yr, 2 * i + 1)                     # (2i+1, nl, nr)
        a = np.arange(i)
        k = i + a[:, None] - a[None, :]                          # lag index R_{i+a-b}
        T = R[k].transpose(0, 2, 1, 3).reshape(i * nl, i * nr)
        U, S, Vt = np.linalg.svd(T, full_matrices=False)
        per_order = []
        for n in orders:
            O = U[:, :n] * np.sqrt(S[:n])[None, :]
            C = O[:nl]
            A = np.linalg.lstsq(O[:-nl], O[nl:], rcond=None)[0]
            mu, V = np.linalg.eig(A)
            with np.errstate(divide="ignore", invalid="ignore"):
                lam = np.log(mu.astype(complex)) * fs
            good = np.isfinite(lam)
            shp = (C @ V).T[good]
            nrm = np.linalg.norm(shp, axis=1, keepdims=True)
            per_order.append((int(n), lam[good], shp / np.where(nrm > 0, nrm, 1)))
        nper = min(y.shape[1], max(256, 2 ** int(np.ceil(np.log2(fs / max(hi - lo, 1e-9) * 64)))))
        G = signal.csd(th, fs=fs, nperseg=int(min(nper, y.shape[1])))
        f = G["frequency"].values
        band = (f >= lo) & (f <= hi)
        _warn_power_below(y, lo, hi, i, fs)
        ind = cmif(G.values[:, :, band])
        diagram = poles_to_diagram("SSI-cov", per_order, (lo, hi), f[band], ind, crit)
    return diagram, {"y": y, "yr": yr, "i": i, "fs": fs, "U": U, "S": S, "Vt": Vt}


def identify_output_only(
    x,
    fmin: float | None = None,
    fmax: float | None = None,
    *,
    orders=range(2, 61, 2),
    fn_hz=None,
    reference=None,
    n_lags: int | None = None,
    stability: StabilityCriteria | None = None,
    clustering: ClusterCriteria | None = None,
    n_blocks: int | None = None,
) -> IdentifiedModes:
    """Modes of output-only (ambient/operational) records: SSI-cov, selection, shapes.

    Same selection machinery and quality table as :func:`mvtk.modal.identify`; shapes
    are unscaled (``normalisation="unit_max"``: output-only data carry no force) and
    there is no FRF synthesis (``frf``, ``synthesised``, ``correlation`` are None).
    Each mode also gets the kurtosis of its band-passed response
    (:func:`mvtk.modal._harmonics.band_kurtosis`): below 2.0 it is marked not reliable
    as a harmonic (a sinusoid has 1.5, a mode's random response 3). A mode that
    explains one of the record's strongest spectral lines (within 1 % or 2 lines) gets
    that line's band kurtosis (band ``+-0.5 %``) when it is lower: a pole between a
    harmonic and a neighbouring line has a mixed band of its own.

    Uncertainty (``fn_std_hz`` in Hz, ``zeta_std``, ``shape_std`` of the unit-maximum
    complex shapes): first-order propagation of the covariance of the output
    correlations to the poles (Reynders, Pintelon & De Roeck 2008) in the block form of
    Döhler & Mevel (2013). The record is cut into ``n_blocks`` data blocks; the
    scatter of their Toeplitz matrices estimates the covariance of the record's, and
    each block's deviation is carried through the SVD, the least-squares shift
    equation and the eigenvalue problem
    (:func:`mvtk.modal._ssi_uncertainty.ssi_pole_uncertainty`). The linearisation
    holds only where the singular values are well separated at the truncation, so each
    mode is reported from the highest model order among its poles (same mode: within
    the clustering distance, MAC >= ``1 - dmac``) whose gap there is at least
    ``GAP_MARGIN`` (2) standard deviations; its frequency, damping, shape and standard
    deviations then all come from that order. NaN where no order of the mode has such
    a gap or the record holds fewer than 10 blocks; such a mode is marked not reliable,
    reason "no uncertainty: ..." (the data support no standard deviation, so they do not
    support the estimate either).

    Parameters
    ----------
    x, fmin, fmax, orders, reference, n_lags
        As in :func:`ssi_cov`.
    fn_hz : sequence of float, optional
        Select the poles nearest these frequencies (Hz) instead of clustering.
    stability, clustering : StabilityCriteria, ClusterCriteria, optional
        Stability and selection criteria.
    n_blocks : int, optional
        Data blocks for the covariance (default 50, fewer when a block would be
        shorter than 20 x ``n_lags`` samples; no uncertainty below 10). Given, it
        must leave at least 10 blocks of ``8 n_lags`` samples.

    Returns
    -------
    IdentifiedModes

    References
    ----------
    Reynders, Pintelon & De Roeck, "Uncertainty bounds on modal parameters obtained
    from stochastic subspace identification", MSSP 22(4) 948-969, 2008.
    Döhler & Mevel, "Efficient multi-order uncertainty computation for stochastic
    subspace identification", MSSP 40(2) 464-484, 2013.

    Examples
    --------
    The ambient response of two modes (20 Hz at 1 %, 55 Hz at 2 %), 2 min at 256 Hz:

    >>> from mvtk import testing
    >>> x = testing.random_excitation_test([20.0, 55.0], [0.01, 0.02], 256.0, 120.0,
    ...                                    np.random.default_rng(0))
    >>> modes = identify_output_only(x.sel(channel=["response"]), 5.0, 100.0,
    ...                              orders=range(2, 21, 2))
    >>> modes.method, np.round(modes.fn_hz, 1)
    ('SSI-cov', array([20. , 55.1]))
    """
    from .. import signal

    stab = stability or StabilityCriteria()
    clus = clustering or ClusterCriteria()
    th = signal.as_time_history(x)
    diagram, state = _ssi_cov(th, fmin, fmax, orders, reference=reference, n_lags=n_lags,
                              criteria=stab)
    sel = poles_near(diagram, fn_hz) if fn_hz is not None else select_poles(diagram, clus)
    nm = sel.pole.size
    sel, fn_std, zeta_std, psi_std, nb = _uncertainty(state, diagram, sel, n_blocks,
                                                      clus)
    fn = np.abs(sel.pole) / (2 * np.pi)
    zeta = -sel.pole.real / np.where(np.abs(sel.pole) > 0, np.abs(sel.pole), 1)
    psi = sel.vector[:, :th.sizes["channel"]]
    idx = np.argmax(np.abs(psi), axis=1) if nm else np.zeros(0, int)
    cplx = psi * np.exp(-1j * np.angle(psi[np.arange(nm), idx]))[:, None] if nm else psi
    cplx = cplx / np.maximum(np.abs(cplx).max(axis=1, keepdims=True), 1e-300) if nm else cplx
    from ._identify import _rotate_real

    _, real = _rotate_real(cplx)
    real = real / np.maximum(np.abs(real).max(axis=1, keepdims=True), 1e-300) if nm else real
    names = [str(c) for c in th["channel"].values]
    nodes = (th["node"].values if "node" in th.coords else np.full(len(names), -1))
    dirs = (th["direction"].values if "direction" in th.coords else np.full(len(names), ""))
    from ._frf import _direction

    dirs = [_direction(d) for d in dirs]
    labels = dof_labels(nodes, dirs, names)
    shp = shapes_array(cplx, fn, zeta, labels, nodes, dirs, "unit_max", "SSI-cov")
    shp_std = shapes_array(psi_std, fn, zeta, labels, nodes, dirs, "unit_max", "SSI-cov")
    shp_std.name = "shape_std"
    rshp = shapes_array(real, fn, zeta, labels, nodes, dirs, "unit_max", "SSI-cov")
    # one channel: the shape is a single number; MPC and MPD say nothing (NaN)
    mpc_v = mpc(cplx) if len(names) > 1 else np.full(nm, np.nan)
    mpd_v = mpd(cplx) if len(names) > 1 else np.full(nm, np.nan)
    from ._harmonics import HARMONIC_KURTOSIS, band_kurtosis

    fs = signal.sampling_rate(th)
    y = th.values.astype(float)
    kurt = band_kurtosis(y, fs, fn, zeta)
    # a pole between a harmonic and a neighbouring line gets a mixed band; the strong
    # lines it explains (within 1 % or 2 lines) must be random too
    kurt = np.fmin(kurt, _line_kurtosis(y, fs, diagram.band_hz, fn, band_kurtosis))
    if fn_hz is None:
        _warn_unselected_peaks(y, fs, diagram.band_hz, fn,
                               lambda f: band_kurtosis(y, fs, f, np.full(f.size, 0.0025)))
    reliable, reason = quality_flags(fn, zeta, mpc_v, sel.count, clus.min_count,
                                     diagram.band_hz, stab.zeta_max, kurtosis=kurt,
                                     max_harmonic_kurtosis=HARMONIC_KURTOSIS)
    no_std = ~np.isfinite(zeta_std)
    if nm and no_std.any():
        # a mode with no standard deviation is not supported by the data: no order where
        # it is found separates its singular values from the noise (the first-order
        # propagation, hence the uncertainty, does not hold), or the record is too short
        # for the block covariance
        from ._ssi_uncertainty import GAP_MARGIN, MIN_BLOCKS

        why_std = (f"no uncertainty: the record holds {nb} data blocks (< {MIN_BLOCKS}) "
                   "for the covariance of its correlations; a longer record gives one"
                   if nb < MIN_BLOCKS else
                   "no uncertainty: at no model order where this mode is found are its "
                   f"singular values {GAP_MARGIN:g} standard deviations clear of the "
                   "noise's, so the first-order propagation does not hold (a weak or "
                   "noise-like mode; more data or a narrower band)")
        reliable = np.asarray(reliable, bool) & ~no_std
        reason = tuple((why_std if r == "ok" else f"{r}; {why_std}") if n else r
                       for r, n in zip(reason, no_std))
    decay = transient_ratio(y)
    if nm and decay < MIN_STATIONARY_RATIO:
        # a free decay (or another transient): the output correlations are not those of
        # a stationary response, so the damping is biased and the block scatter is not
        # its uncertainty
        why = (f"the record is a transient (RMS of its last quarter {decay:.1%} of its "
               f"first, < {MIN_STATIONARY_RATIO:.0%}): SSI-cov assumes a stationary "
               "response, its damping and standard deviations do not hold; fit the decay "
               "(mvtk damping, envelope)")
        reliable = np.zeros(nm, bool)
        reason = tuple(why if r == "ok" else f"{why}; {r}" for r in reason)
        fn_std = np.full(nm, np.nan)
        zeta_std = np.full(nm, np.nan)
        psi_std = np.full_like(psi_std, np.nan)
        shp_std = shp_std.copy(data=np.full(shp_std.shape, np.nan))
    return IdentifiedModes(
        method="SSI-cov", fn_hz=fn, zeta=zeta, pole=sel.pole, shapes=shp, real_shapes=rshp,
        participation=None, mpc=mpc_v, mpd=mpd_v, stability_count=sel.count,
        reliable=reliable, reason=reason, frf=None, synthesised=None, correlation=None,
        residue=None, lower_residual=None, upper_residual=None, diagram=diagram,
        kurtosis=kurt, fn_std_hz=fn_std, zeta_std=zeta_std, shape_std=shp_std,
    )


MIN_STATIONARY_RATIO = 0.1
"""An output-only record whose last quarter has less than this fraction of the RMS of
its first quarter (median over channels; 20 dB down) is a transient, not a stationary
response: its SSI-cov modes are marked not reliable (:func:`transient_ratio`)."""


def transient_ratio(y) -> float:
    """RMS of the last quarter of a record over the RMS of its first quarter.

    Median over channels of ``rms(y[-n/4:]) / rms(y[:n/4])`` of the mean-removed
    channels: about 1 for a stationary response (ambient, random), ``exp(-zeta w T
    3/4)`` for a free decay of length ``T``. NaN when no channel has signal in its first
    quarter.

    Parameters
    ----------
    y : array_like, shape (n_channels, n_samples)
        The outputs (any unit).

    Returns
    -------
    float

    Examples
    --------
    A 10 Hz free decay at 1 % over 4 s (``exp(-0.01 x 2 pi 10 x 3) = 0.15``) against
    white noise:

    >>> t = np.arange(0, 4, 1e-3)
    >>> decay = np.exp(-0.01 * 2 * np.pi * 10 * t) * np.cos(2 * np.pi * 10 * t)
    >>> round(transient_ratio(decay[None]), 2)
    0.15
    >>> round(transient_ratio(np.random.default_rng(0).standard_normal((2, 4000))), 1)
    1.0
    """
    y = np.atleast_2d(np.asarray(y, dtype=float))
    n = y.shape[-1] // 4
    if n < 1:
        return float("nan")
    y = y - y.mean(axis=-1, keepdims=True)
    first = np.sqrt(np.mean(y[:, :n] ** 2, axis=-1))
    last = np.sqrt(np.mean(y[:, -n:] ** 2, axis=-1))
    ok = first > 0
    return float(np.median(last[ok] / first[ok])) if ok.any() else float("nan")


def _same_mode(diagram, pole, vector, clus):
    """Physical poles of every order that belong to the mode of ``pole``: within the
    clustering distance of :class:`ClusterCriteria` (frequency ``cluster_df``, damping
    ``cluster_dzeta``) and with MAC >= ``1 - dmac`` of their shapes."""
    f0, z0 = abs(pole) / (2 * np.pi), -pole.real / abs(pole)
    near = ((diagram.status != "x")
            & (np.abs(diagram.fn_hz - f0) <= clus.cluster_df * f0)
            & (np.abs(diagram.zeta - z0) <= clus.cluster_dzeta * max(z0, clus.zeta_floor)))
    v = diagram.vector
    num = np.abs(v @ np.conj(vector)) ** 2
    den = np.sum(np.abs(v) ** 2, axis=1) * np.sum(np.abs(vector) ** 2)
    return near & (num >= (1 - diagram.criteria.dmac) * np.where(den > 0, den, np.inf))


def _uncertainty(state, diagram, sel, n_blocks, clus):
    """The selected poles at the orders their uncertainty is computed at, and
    ``(sel, fn_std_hz, zeta_std, shape_std, n_blocks)`` (the data blocks of the
    covariance).

    Each mode's uncertainty comes from the highest model order among its poles
    (:func:`_same_mode`) whose singular-value gap at the
    truncation is at least ``GAP_MARGIN`` standard deviations
    (:func:`~mvtk.modal._ssi_uncertainty.truncation_margin`: above it the first-order
    propagation holds), and that order's pole and shape replace the cluster's
    representative so the table's value and its standard deviation belong to one
    estimate. NaN when no such order exists or the record holds fewer than
    ``MIN_BLOCKS`` data blocks.
    """
    import dataclasses

    from .._blas import blas_limits
    from ._ssi_uncertainty import (
        GAP_MARGIN,
        MIN_BLOCKS,
        block_perturbations,
        default_blocks,
        ssi_pole_uncertainty,
        truncation_margin,
    )

    nm, nl = sel.pole.size, state["y"].shape[0]
    fstd, zstd = np.full(nm, np.nan), np.full(nm, np.nan)
    sstd = np.full((nm, nl), np.nan)
    i = state["i"]
    nb = default_blocks(state["y"].shape[1], i) if n_blocks is None else int(n_blocks)
    if n_blocks is not None and (nb < MIN_BLOCKS or
                                 (state["y"].shape[1] - 2 * i) // nb < 4 * i):
        raise ParameterError(
            f"identify_output_only: n_blocks={n_blocks}: expected at least {MIN_BLOCKS} "
            f"data blocks of at least {8 * i} samples each ({i} block rows); the record "
            f"has {state['y'].shape[1]} samples")
    if nm == 0 or nb < MIN_BLOCKS:
        return sel, fstd, zstd, sstd, nb
    U, S, Vt = state["U"], state["S"], state["Vt"]
    with blas_limits():
        P = block_perturbations(state["y"], state["yr"], i, nb, U, Vt,
                                int(diagram.orders.max()) + 1)
        margin = dict(zip(diagram.orders.tolist(),
                          truncation_margin(U, S, Vt, P, diagram.orders)))
        pick = np.full(nm, -1)
        for m in range(nm):
            cand = np.flatnonzero(_same_mode(diagram, sel.pole[m], sel.vector[m], clus))
            ok = cand[[margin[int(o)] >= GAP_MARGIN for o in diagram.order[cand]]]
            if ok.size:
                top = ok[diagram.order[ok] == diagram.order[ok].max()]
                pick[m] = top[np.argmin(np.abs(diagram.pole[top] - sel.pole[m]))]
        have = pick >= 0
        pole, vector, order = sel.pole.copy(), sel.vector.copy(), sel.order.copy()
        pole[have], vector[have] = diagram.pole[pick[have]], diagram.vector[pick[have]]
        order[have] = diagram.order[pick[have]]
        for o in np.unique(order[have]):
            m = np.flatnonzero(have & (order == o))
            fstd[m], zstd[m], sstd[m] = ssi_pole_uncertainty(U, S, Vt, P, nl, int(o),
                                                             state["fs"], pole[m])
    sel = dataclasses.replace(sel, pole=pole, vector=vector, order=order)
    return sel, fstd, zstd, sstd, nb
