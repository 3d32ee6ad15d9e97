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
        Band in Hz for the physical poles (default 0..fs/2).
    orders : iterable of int
        State-space orders (even; each gives ``n/2`` conjugate pairs).
    reference : channel selection, optional
        Reference outputs for the correlations (default every channel).
    n_lags : int, optional
        Block rows ``i`` (default ``max(ceil((max_order + 1) / n_ref), 20)``).
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
    """
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
    if i * nr < pmax or i * nl < pmax:
        raise ParameterError(
            f"ssi_cov: n_lags={i} block rows give a Toeplitz matrix of rank <= "
            f"{min(i * nr, i * nl)}; expected at least the highest order {pmax}"
        )
    if 2 * i + 1 >= y.shape[1] // 4:
        raise ParameterError(f"ssi_cov: {y.shape[1]} samples are too few for {i} block rows")
    R = _correlations(y, yr, 2 * i + 1)                     # (2i+1, nl, nr)
    a = np.arange(i)
    k = i + a[:, None] - a[None, :]                          # lag index R_{i+a-b}
    T = R[k].transpose(0, 2, 1, 3).reshape(i * nl, i * nr)
    U, S, _ = np.linalg.svd(T, full_matrices=False)
    lo = 0.0 if fmin is None else float(fmin)
    hi = fs / 2 if fmax is None else float(fmax)
    if not (0 <= lo < hi <= fs / 2):
        raise ParameterError(f"ssi_cov: the band must satisfy 0 <= fmin < fmax <= fs/2 = "
                             f"{fs / 2:g} Hz; got {lo!r}..{hi!r}")
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
    ind = cmif(G.values[:, :, band])
    return poles_to_diagram("SSI-cov", per_order, (lo, hi), f[band], ind, crit)


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
) -> IdentifiedModes:
    """Modes of output-only (ambient/operational) records: SSI-cov, selection, shapes.

    Same selection machinery and quality table as :func:`mvtk.modal.identify`; shapes
    are unscaled (``normalisation="unit_max"``: output-only data carry no force) and
    there is no FRF synthesis (``frf``, ``synthesised``, ``correlation`` are None).
    Parameters as in :func:`ssi_cov`; ``fn_hz`` selects the poles nearest those
    frequencies instead of clustering.
    """
    from .. import signal

    stab = stability or StabilityCriteria()
    clus = clustering or ClusterCriteria()
    th = signal.as_time_history(x)
    diagram = ssi_cov(th, fmin, fmax, orders, reference=reference, n_lags=n_lags,
                      criteria=stab)
    sel = poles_near(diagram, fn_hz) if fn_hz is not None else select_poles(diagram, clus)
    nm = sel.pole.size
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
    rshp = shapes_array(real, fn, zeta, labels, nodes, dirs, "unit_max", "SSI-cov")
    mpc_v = mpc(cplx) if len(names) > 1 else np.ones(nm)
    mpd_v = mpd(cplx) if len(names) > 1 else np.zeros(nm)
    reliable, reason = quality_flags(fn, zeta, mpc_v, sel.count, clus.min_count,
                                     diagram.band_hz, stab.zeta_max)
    return IdentifiedModes(
        method="SSI-cov", fn_hz=fn, zeta=zeta, pole=sel.pole, shapes=shp, real_shapes=rshp,
        participation=None, mpc=mpc_v, mpd=mpd_v, stability_count=sel.count,
        reliable=reliable, reason=reason, frf=None, synthesised=None, correlation=None,
        residue=None, lower_residual=None, upper_residual=None, diagram=diagram,
    )
