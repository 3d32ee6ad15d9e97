"""``identify``: FRF matrix -> stabilisation diagram -> selected poles -> LSFD -> modes."""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr

from ..signal import EXCITED_DB
from ._frf import as_frf_matrix
from ._lsfd import local_misfit, lsfd_with_misfit, synthesise
from ._plscf import band_frf, plscf
from ._quality import mpc, mpd
from ._refine import pole_std, refine_poles
from ._result import IdentifiedModes
from ._stabilisation import (
    ClusterCriteria,
    SelectedPoles,
    StabilityCriteria,
    poles_near,
    select_poles,
)

__all__ = ["identify", "dof_labels", "shapes_array", "count_peaks", "default_orders",
           "default_band", "excitation_level"]

PEAK_PROMINENCE_DB = 6.0
"""A peak of the smoothed sum-FRF counts when it stands this far above its surroundings."""
SMOOTHING_BINS = 1000
"""The sum-FRF is smoothed over ``n_lines / SMOOTHING_BINS`` lines before counting peaks."""
POLES_PER_PEAK = 8
"""Model order margin: poles per counted peak (2 for the mode, 6 for noise/background;
with 6 the weak 2779.7 Hz mode of camera.lvm, at 3 % of the strongest peak, is stable
in too few orders of its default band)."""
MAX_POLES = 160
"""Cap on ``max_order x n_reference`` for the default orders (runtime)."""
LINES_PER_POLE = 200
"""The default order exceeds the fixed floor only while each pole has this many lines."""


def count_peaks(h) -> tuple[int, np.ndarray]:
    """Peaks of the smoothed sum-FRF in the band: ``(count, frequencies in Hz)``.

    The sum over all FRFs of ``|H|^2`` is taken in dB and smoothed by a moving average
    over ``ceil(n_lines / SMOOTHING_BINS)`` lines (so that a wide, finely resolved band
    is not counted line by line in its noise); a local maximum counts when its
    prominence is at least ``PEAK_PROMINENCE_DB`` (6 dB).
    """
    from scipy.ndimage import uniform_filter1d
    from scipy.signal import find_peaks

    hv = h.values
    p = np.sum(np.abs(np.where(np.isfinite(hv), hv, 0.0)) ** 2, axis=(0, 1))
    pos = p[p > 0]
    if pos.size == 0:
        return 0, np.zeros(0)
    level = 10 * np.log10(np.maximum(p, pos.min()))
    w = max(1, int(np.ceil(p.size / SMOOTHING_BINS)))
    smooth = uniform_filter1d(level, w, mode="nearest")
    idx, _ = find_peaks(smooth, prominence=PEAK_PROMINENCE_DB)
    return int(idx.size), h["frequency"].values[idx]


def default_orders(h) -> range:
    """Default pLSCF model orders ``2..p_max`` of an FRF matrix (band already applied).

    ``p_max = ceil(POLES_PER_PEAK x n_peaks / n_reference)`` with ``n_peaks`` from
    :func:`count_peaks` (every order gives ``n_reference`` poles; a mode takes two),
    at least ``max(20, 64 // n_reference)`` (the former fixed default). Above that
    floor the order is capped by runtime (``MAX_POLES = 160`` poles per order) and by
    the data: at most one pole per ``LINES_PER_POLE = 200`` lines of the band. A short
    band (few lines per mode) cannot tell a ripple from a mode, and a higher order fits
    its noise (the view_0 swept-sine H1, 851 lines in 65..490 Hz: order 84 instead of
    64 drops two catalogued peaks below ``support`` 2), while a long, finely resolved
    wide band (the LVM hammer tests, 262 145 lines in 0..25 kHz, 14..38 counted peaks)
    needs orders 96..160 for its weaker modes.
    """
    ni = h.sizes["reference"]
    floor = max(20, 64 // ni)
    n, _ = count_peaks(h)
    p = int(np.ceil(POLES_PER_PEAK * n / ni))
    cap = max(floor, min(MAX_POLES, h.sizes["frequency"] // LINES_PER_POLE) // ni)
    return range(2, min(max(floor, p), cap) + 1)


def dof_labels(nodes, directions, names) -> list[str]:
    """``"<node><direction>"`` labels (response names where the node is unknown)."""
    labels = [f"{int(n)}{d}" if int(n) >= 0 else str(nm)
              for n, d, nm in zip(nodes, directions, names)]
    if len(set(labels)) != len(labels):
        labels = [str(nm) for nm in names]
    return labels


def shapes_array(values, fn_hz, zeta, labels, nodes, directions, normalisation, source):
    """A ``("mode", "dof")`` DataArray on the conventions."""
    return xr.DataArray(
        values, dims=("mode", "dof"),
        coords={"mode": np.arange(1, len(fn_hz) + 1), "fn_hz": ("mode", np.asarray(fn_hz)),
                "zeta": ("mode", np.asarray(zeta)), "dof": labels,
                "node": ("dof", np.asarray(nodes, dtype=np.int64)),
                "direction": ("dof", np.asarray(directions, dtype=str))},
        attrs={"normalisation": normalisation, "source": source}, name="shape",
    )


def _rotate_real(psi):
    """Rotate each complex shape onto its best-fit line; return (rotated complex, real)."""
    out = np.empty_like(psi)
    for k, row in enumerate(psi):
        u = np.column_stack([row.real, row.imag])
        _, _, vt = np.linalg.svd(u, full_matrices=False)
        theta = np.arctan2(vt[0, 1], vt[0, 0])
        out[k] = row * np.exp(-1j * theta)
        i = np.argmax(np.abs(out[k].real))
        if out[k].real[i] < 0:
            out[k] = -out[k]
    return out, out.real.copy()


def _driving_points(h):
    """``[(response index, reference index), ...]`` of every driving point of the matrix.

    A response is the driving point of a reference when its node and direction (sign
    ignored) match the reference's, or, without nodes, when their names match.
    """
    out = []
    rnode, rdir = h["reference_node"].values, h["reference_direction"].values
    rname, node = h["reference"].values, h["node"].values
    odir, oname = h["direction"].values, h["response"].values
    for i in range(rnode.size):
        rn, rd = int(rnode[i]), str(rdir[i])
        for o in range(node.size):
            same = (rn >= 0 and int(node[o]) == rn
                    and str(odir[o]).lstrip("+") == rd.lstrip("+") and rd)
            if same or str(oname[o]) == str(rname[i]):
                out.append((o, i))
                break
    return out


def rank_one_shapes(residue, pole, driving_points):
    """Shapes and participations of every mode from the residues of all references.

    Each mode's residue matrix ``A_m`` (``n_response x n_reference``) is replaced by its
    best rank-one approximation ``psi_m L_m^T`` (first singular pair: the least-squares
    estimate over all references, so a mode small at one driving point is carried by
    the others). With driving points ``(o_k, i_k)`` the shape is scaled to unit modal A
    (``A_m = phi_m phi_m^T`` on the driving-point rows): reciprocity ``phi_{o_k} =
    phi_{ref, i_k}`` gives ``c^2 psi_{o_k} = L_{i_k}`` for ``phi = c psi`` and ``c^2`` is
    their least-squares solution over all driving points (weighted by
    ``|psi_{o_k}|^2``, so no single small driving-point value decides the scale).

    Parameters
    ----------
    residue : numpy.ndarray, shape (n_modes, n_response, n_reference)
        Receptance residues (m/N/s for ``A / (i w - lambda)``).
    pole : numpy.ndarray of complex, (n_modes,)
        Poles in rad/s.
    driving_points : list of (int, int)
        ``(response index, reference index)`` pairs; empty: no mass scaling.

    Returns
    -------
    shapes : numpy.ndarray of complex, (n_modes, n_response)
        Unit-modal-A shapes (``A_oi = phi_o phi_i``) when driving points exist, else
        the singular vector scaled to largest component 1.
    participation : numpy.ndarray of complex, (n_modes, n_reference)
        Unit-norm participation ``L_m`` of the references, ``A_m ~ psi_m L_m^T``.
    scaled : bool
        Whether the shapes are scaled from driving points.
    """
    nm, no, ni = residue.shape
    psi = np.zeros((nm, no), complex)
    part = np.zeros((nm, ni), complex)
    for m in range(nm):
        u, s, vh = np.linalg.svd(residue[m], full_matrices=False)
        psi[m] = u[:, 0] * s[0]
        part[m] = vh[0]                      # A_m ~ psi_m part_m^T
    if not driving_points or nm == 0:
        return psi, part, False
    o = np.array([d[0] for d in driving_points])
    i = np.array([d[1] for d in driving_points])
    num = np.sum(np.conj(psi[:, o]) * part[:, i], axis=1)
    den = np.sum(np.abs(psi[:, o]) ** 2, axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.sqrt(np.where(den > 0, num / np.where(den > 0, den, 1.0), np.nan))
    return psi * c[:, None], part, True


MIN_SUPPORT = 2.0
"""A mode must at least halve the LSFD misfit within ``fn +- max(5 lines, 2 zeta fn)``."""

WEAK_EXCITATION_DB = EXCITED_DB
"""A mode is weakly excited when the reference autospectrum at its frequency (best
reference) is this far below its maximum in the band, by excitation type: the limit of
the excited band, :data:`mvtk.signal.EXCITED_DB` (impact -35 dB, sweep and random
-50 dB; see ``docs/guide/modal.md``)."""


MAX_WINDOW_FRACTION = 0.9
"""A mode is not reliable when the exponential window's damping ``1 / (tau wn)`` exceeds
this fraction of its identified (windowed) damping: removing it multiplies any relative
error of the windowed pole by ``1 / (1 - fraction)`` (10 at 0.9)."""

MAX_ZETA_REL_STD = 0.5
"""A mode is not reliable when the standard deviation of its damping exceeds this
fraction of the damping: its 95 % interval ``zeta (1 +- 2 x 0.5)`` then reaches zero, so
the data do not determine the damping (a weak, broad pole the fit could as well drop or
move: camera.lvm's default-band poles near 10 kHz have 55-70 %, its catalogued modes
below 1 %)."""

MAX_LACK_OF_FIT = 10.0
"""With the default orders, a reliable mode whose :func:`lack_of_fit` (LSFD residual
energy per line near the mode over its median in the band) exceeds this makes
:func:`identify` try higher orders (:func:`raise_orders`). A 3 x 4 roving-hammer test of
the stiffened curved panel (zeta 0.6 %, 0.1 % noise): at the default orders 2..64 the
weak mode at 364.97 Hz (4.7 % of the strongest modal constant, 0.8 half-power bandwidths
from 368.60 Hz) was not found, its neighbours had zeta +7.2 % with standard deviations
4-6 x smaller than the error and ratios 125 and 642; at 2..128 every mode is within
0.1 % and the ratios are 0.5-0.9. Measured real and noisy FRFs give 1-3000 at their
peaks (nonlinearity, drift: the ratio alone does not mark a mode)."""

MIN_RELATIVE_RESIDUAL = 1e-3
""":func:`lack_of_fit` counts the residual floor as at least this fraction of ``|H|``
near the mode (rms): what an FRF estimate or a file's stored digits are good to."""

MIN_MPC_FITTED = 0.9
"""A reliable mode whose :func:`lack_of_fit` stays above :data:`MAX_LACK_OF_FIT` (after
:func:`raise_orders`) and whose shape is complex, MPC below this, is not reliable
("unresolved"): one pole stands for two close modes the record cannot tell apart (a
curved panel's pair 445.60 / 447.75 Hz, 2.15 Hz apart in 2.2 Hz lines, came out as one
mode at 446.75 Hz, zeta +20 %, MPC 0.86, ratio 41) or for a distortion (the smart-beam
scan's 13.26 Hz mode, whose FRFs carry an exponential window the file does not state:
zeta 8.6 x the truth, MPC 0.81, ratio 129). Either indicator alone marks nothing: real
peaks leave large ratios with a real shape (a single-response test has no MPC), and
noise lowers the MPC of well-fitted modes."""

NEIGHBOUR_BANDWIDTHS = 3.0
"""How far from a mode that lacks fit (in its half-power bandwidths ``2 zeta fn``) a pole
of the higher orders counts as its missing neighbour (:func:`raise_orders`)."""

MAX_TRUNCATION = 0.01
"""On zero-padded (interpolated) lines of an impact record, windowed or not, a mode whose
decay ``exp(-sigma T)`` (windowed: ``sigma_w``) is still above this fraction of its
amplitude at the end of the record ``T`` is not reliable: its truncation adds
``exp(-i w T) / (i w - lambda)``, a ripple of period ``1 / T``, that no modal model holds
(on the record's own lines ``k / T`` it only scales the residue). An unwindowed record is
padded only when the whole response has decayed to 1 %, but a weak slow mode may not
have: a 20-point roving test of a plate, 2 s records, gave mode 1 (29 Hz, zeta 0.8 %,
5.6 % left) zeta +8.7 % with a standard deviation 14 x smaller than the error. When the
padding is a whole multiple of the record (:func:`own_lines`), :func:`identify` repeats
the fit on the own lines instead (there +0.02 %); the rule marks what is left."""


def excitation_level(h, fn_hz) -> np.ndarray:
    """Level of the excitation at each frequency in dB re its maximum in the band.

    From the ``reference_level_db`` coordinate ``("reference", "frequency")`` that
    :func:`frf_matrix` attaches (reference autospectrum per line; ``("response",
    "frequency")`` after :func:`reciprocal`, where the hammer points are the responses):
    for each excitation point the level at the line nearest ``fn`` minus its largest
    value in the band (lines above 0 Hz), the best point taken. NaN when the FRF matrix
    carries no excitation level (FRFs read from UFF 58 or other files without the force).
    """
    fn_hz = np.asarray(fn_hz, dtype=float)
    out = np.full(fn_hz.size, np.nan)
    lev = h.coords.get("reference_level_db")
    if lev is None or fn_hz.size == 0:
        return out
    f = h["frequency"].values
    L = np.asarray(lev.transpose(..., "frequency").values, dtype=float)
    L = L.reshape(-1, L.shape[-1])
    top = np.max(np.where(np.isfinite(L) & (f > 0)[None, :], L, -np.inf), axis=1)
    ok = np.isfinite(top)
    if not ok.any():
        return out
    rel = L[ok] - top[ok, None]
    k = np.abs(f[None, :] - fn_hz[:, None]).argmin(axis=1)
    vals = rel[:, k]                                   # (reference, mode)
    with np.errstate(invalid="ignore"):
        best = np.where(np.isfinite(vals), vals, -np.inf).max(axis=0)
    out[np.isfinite(best)] = best[np.isfinite(best)]
    return out


def quality_flags(fn, zeta, mpc_v, count, need, band, zeta_max, edge=0.01, df_hz=None,
                  contribution=None, min_contribution=0.1, local=None, min_local=0.8,
                  support=None, min_support=MIN_SUPPORT, half_hz=None,
                  excitation_db=None, min_excitation_db=None, excitation_name="force",
                  kurtosis=None, max_harmonic_kurtosis=None, zeta_fit=None,
                  clean_support=None, flagged="", zeta_window=None,
                  max_window_fraction=MAX_WINDOW_FRACTION, truncation=None,
                  max_truncation=MAX_TRUNCATION, zeta_std=None,
                  max_zeta_rel_std=MAX_ZETA_REL_STD):
    """``reliable`` and ``reason`` per mode from the stated criteria.

    ``zeta_fit``: damping of the fitted FRFs (before an exponential window's damping
    was removed) for the resolution check; default ``zeta``. ``clean_support``: the
    support on the FRFs of sets without a quality verdict (``flagged`` says which
    are not), below ``min_support`` the mode is the flagged sets' alone.
    ``zeta_window``: the window's damping ``1 / (tau wn)``, above
    ``max_window_fraction`` of ``zeta_fit`` the mode is not reliable.
    ``truncation``: the mode's amplitude left at the end of a zero-padded record,
    above ``max_truncation`` not reliable (see :data:`MAX_TRUNCATION`).
    ``zeta_std``: standard deviation of ``zeta``; above ``max_zeta_rel_std`` of it the
    damping is not determined by the data (:data:`MAX_ZETA_REL_STD`)."""
    reliable, reason = [], []
    nan = np.full(len(fn), np.nan)
    kurtosis = nan if kurtosis is None else kurtosis
    contribution = nan if contribution is None else contribution
    local = nan if local is None else local
    support = nan if support is None else support
    half_hz = nan if half_hz is None else half_hz
    excitation_db = nan if excitation_db is None else excitation_db
    zeta_fit = zeta if zeta_fit is None else zeta_fit
    clean_support = nan if clean_support is None else clean_support
    zeta_window = nan if zeta_window is None else zeta_window
    truncation = nan if truncation is None else truncation
    zeta_std = nan if zeta_std is None else zeta_std
    for f, z, m, c, q, loc, sup, hw, ex, ku, zf, cs, zw, tr, zs in zip(
            fn, zeta, mpc_v, count, contribution, local, support, half_hz, excitation_db,
            kurtosis, zeta_fit, clean_support, zeta_window, truncation, zeta_std):
        why = []
        if np.isfinite(zs) and z > 0 and zs > max_zeta_rel_std * z:
            why.append(f"damping not determined by the data: zeta_std is {zs / z:.0%} of "
                       f"zeta (> {max_zeta_rel_std:.0%})")
        if np.isfinite(zw) and zf > 0 and zw > max_window_fraction * zf:
            why.append(f"window damping is {zw / zf:.0%} of the identified damping "
                       f"(> {max_window_fraction:.0%}): removing it multiplies any error "
                       f"of the windowed pole by {zf / max(zf - zw, 1e-300):.3g}")
        if np.isfinite(tr) and tr > max_truncation:
            why.append(f"zero-padded lines of a record that ends with this mode at "
                       f"{tr:.1%} of its amplitude (> {max_truncation:.0%}): the truncation "
                       "ripple biases its damping (use the record's own lines, nfft = "
                       "nperseg)")
        if (np.isfinite(cs) and cs < min_support and not (np.isfinite(sup)
                                                           and sup < min_support)):
            why.append(f"needed only by FRFs of flagged sets: LSFD misfit within "
                       f"+-{hw:.3g} Hz without/with the mode {cs:.2f} on the clean FRFs "
                       f"(< {min_support:g}; {flagged})")
        if max_harmonic_kurtosis is not None and np.isfinite(ku) and ku < max_harmonic_kurtosis:
            why.append(f"harmonic: kurtosis of the band-passed response {ku:.2f} "
                       f"(< {max_harmonic_kurtosis:g}; a sinusoid gives 1.5, a mode's random "
                       "response 3)")
        if (min_excitation_db is not None and np.isfinite(ex)
                and ex < min_excitation_db):
            why.append(f"weakly excited: {excitation_name} {ex:.0f} dB re its maximum in "
                       f"the band (< {min_excitation_db:g} dB)")
        if np.isfinite(sup) and sup < min_support:
            why.append(f"not needed by the data: LSFD misfit within +-{hw:.3g} Hz without/"
                       f"with the mode {sup:.2f} (< {min_support:g})")
        if np.isfinite(loc) and loc < min_local:
            why.append(f"measured vs synthesised FRF correlation {loc:.2f} < {min_local:g} "
                       "around the mode (noise fitted?)")
        if np.isfinite(q) and q < min_contribution:
            why.append(f"weak: the mode makes {q:.0%} of |H| at its frequency "
                       f"(< {min_contribution:.0%})")
        if df_hz is not None and 0 < zf and 2 * zf * f < df_hz:
            why.append(f"half-power bandwidth {2 * zf * f:.3g} Hz < line spacing "
                       f"{df_hz:.3g} Hz: damping not resolved")
        if c < need:
            why.append(f"stable in {c} model orders (< {need:g})")
        if not (0 < z <= zeta_max):
            why.append(f"damping {z:.3g} outside (0, {zeta_max:g}]")
        if f < band[0] * (1 + edge) or f > band[1] * (1 - edge):
            why.append(f"within {edge:.0%} of the band edge {band[0]:g}..{band[1]:g} Hz")
        if np.isfinite(m) and m < 0.5:
            why.append(f"shape not collinear (MPC {m:.2f} < 0.5)")
        reliable.append(not why)
        reason.append("; ".join(why) if why else "ok")
    return np.array(reliable, bool), tuple(reason)


def identify(
    frf,
    fmin: float | None = None,
    fmax: float | None = None,
    *,
    orders=None,
    fn_hz=None,
    stability: StabilityCriteria | None = None,
    clustering: ClusterCriteria | None = None,
    residuals: bool = True,
    refine: bool | None = None,
) -> IdentifiedModes:
    """Identify modes from an FRF matrix: pLSCF poles, automatic selection, maximum-
    likelihood refinement, LSFD shapes, uncertainty of every modal parameter.

    Parameters
    ----------
    frf : xarray.DataArray or Dataset
        FRF matrix ``("response", "reference", "frequency")`` (conventions page), e.g.
        from :func:`frf_matrix` or :func:`mvtk.io.read` on UFF 58 records.
    fmin, fmax : float, optional
        Analysis band in Hz. Default (each bound not given): from the data,
        :func:`default_band` / :func:`mvtk.signal.analysis_band`: the lines the
        excitation covers (a sweep's swept band; the force within
        :data:`mvtk.signal.EXCITED_DB` of its maximum, 35 dB for a hammer; from 5 x the
        resolution) trimmed to the resonance peaks there / x 1.25; the band and why are
        ``result.band_hz`` and ``result.band_reason`` (peaks it leaves out or cuts named).
    orders : iterable of int, optional
        pLSCF model orders. Default :func:`default_orders`, chosen from the data:
        ``2..p_max`` with ``p_max = ceil(8 n_peaks / n_reference)`` (``n_peaks``: peaks
        of the smoothed sum-FRF in the band, :func:`count_peaks`; every order gives
        ``n_reference`` poles), at least ``max(20, 64 // n_reference)``, at most 160
        poles per order and one pole per 200 lines of the band. Where the fit at these
        orders leaves model error next to a reliable mode (a weak mode without a peak
        of its own missing beside it), higher orders are tried and only the poles
        beside such modes taken (:func:`raise_orders`; ``band_reason`` says so). The
        orders used are ``result.diagram.orders``.
    fn_hz : sequence of float, optional
        Select the poles nearest these frequencies (see :func:`poles_near`) instead of
        the automatic clustering.
    stability, clustering : optional
        Tolerances of the diagram (:class:`StabilityCriteria`) and of the automatic
        selection (:class:`ClusterCriteria`).
    residuals : bool
        Fit lower and upper residuals in LSFD (default True).
    refine : bool, optional
        Refine the selected poles by weighted nonlinear least squares on the FRFs
        (maximum likelihood for Gaussian noise; :func:`mvtk.modal._refine.refine_poles`).
        Default: True with the automatic selection, False with ``fn_hz`` (the poles the
        user picked may leave out a mode next to them, and a refinement without it
        would move the pole). ``False``: the selected pLSCF poles as they are; their
        standard deviations come from the same first-order covariance at those poles.

    Returns
    -------
    IdentifiedModes
        Table with quality (``reliable``/``reason``: stable in too few orders, damping
        outside ``(0, zeta_max]``, a pole within 1 % of a band edge, MPC < 0.5, a weak
        mode whose own FRF is < 10 % of the measured ``|H|`` at its frequency, a
        measured vs synthesised correlation < 0.8 within ``fn +- max(5 lines, 2 zeta
        fn)`` (poles fitted to noise), a
        half-power bandwidth ``2 zeta fn`` narrower than the line spacing, a mode the
        force hardly excited: ``excitation_db``, the reference autospectrum at ``fn`` re
        its maximum in the band, below ``WEAK_EXCITATION_DB`` of the excitation type,
        -35 dB impact, -50 dB sweep/random; NaN without a ``reference_level_db``
        coordinate, e.g. UFF 58 FRFs), a mode only the FRFs of flagged sets need
        (``support`` < 2 on the FRFs whose ``pair_quality`` is empty: a clipped force,
        a cut double hit), an exponential window's damping above ``MAX_WINDOW_FRACTION``
        (90 %) of the identified one, a mode still above ``MAX_TRUNCATION`` (1 %) of
        its amplitude at the end of a zero-padded record whose own lines are not among
        the given ones: with a whole number of padded lines per record line the
        identification is repeated on the record's own lines (:func:`own_lines`), in the
        same band, and ``band_reason`` says so), complex
        and real shapes at the response DOFs from the residues of all references
        (mass-normalised when driving points exist), synthesised FRFs and their
        correlation with the measured ones; ``fn_std_hz``, ``zeta_std`` and
        ``shape_std``: first-order standard deviations from the FRF noise (the fit
        residual of each FRF; on zero-padded lines, ``attrs["nfft"] > attrs["nperseg"]``,
        the variances are multiplied by ``nfft / nperseg``: the lines interpolate
        ``nperseg / 2`` independent ones). When the FRFs carry
        ``attrs["exponential_window_tau_s"]`` (or ``exp_window_tau_s``) the damping the
        window added, ``1 / (tau w_n)``, is removed from every pole
        (:func:`mvtk.signal.exponential_window_correction`) and stated in the
        ``zeta_window`` column and ``window_tau_s``.

    Raises
    ------
    ParameterError
        Bad band or orders, or no pole near a requested frequency.

    Examples
    --------
    The exact receptance of a 2-mass chain (modes at 31.105 and 81.434 Hz):

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0, 120, 0.25),
    ...                     [0, 1], [0], frf_type="receptance")
    >>> np.round(identify(h, 2, 110).fn_hz, 3)
    array([31.105, 81.434])
    """
    stab = stability or StabilityCriteria()
    clus = clustering or ClusterCriteria()
    fmin, fmax, band_reason = default_band(frf, fmin, fmax)
    if refine is None:
        refine = fn_hz is None
    opts = dict(fn_hz=fn_hz, stab=stab, clus=clus, residuals=residuals, refine=bool(refine))
    h = band_frf(frf, fmin, fmax)
    res = _identify_band(h, orders, **opts)
    res = dataclasses.replace(res, band_hz=tuple(float(b) for b in res.diagram.band_hz))
    left = truncation(res)
    own = own_lines(as_frf_matrix(frf)) if np.any(left > MAX_TRUNCATION) else None
    if own is None:
        res, raised = _raised(h, res, orders, **opts)
        return _mark_unresolved(dataclasses.replace(res, band_reason=band_reason + raised))
    # a mode still above 1 % at the end of the zero-padded record: on the record's own
    # lines its truncated decay is exactly a pole (only the residue is scaled), so the
    # identification is repeated there, in the same band
    k = int(np.argmax(left))
    lo, hi = res.band_hz
    h_own = band_frf(own, lo, hi)
    again = _identify_band(h_own, None if orders is None else res.diagram.orders, **opts)
    again, raised = _raised(h_own, again, orders, **opts)
    _, pad = record_lines(res.frf)
    note = (f"; identified on the record's own lines (every {pad:.0f}th of the "
            f"zero-padded ones, 1 / T = {own.attrs['resolution_hz']:.4g} Hz): the mode at "
            f"{res.fn_hz[k]:.4g} Hz ends the record at {left[k]:.1%} of its amplitude "
            f"(> {MAX_TRUNCATION:.0%}), whose truncation ripple on interpolated lines "
            "biases the damping")
    return _mark_unresolved(dataclasses.replace(
        again, band_hz=tuple(float(b) for b in again.diagram.band_hz),
        band_reason=band_reason + raised + note))


def _mark_unresolved(res):
    """Mark the modes that both lack fit and have a complex shape (see
    :data:`MIN_MPC_FITTED`): two close modes in one pole, or a distortion."""
    lack = lack_of_fit(res)
    mpc_v = np.asarray(res.mpc, dtype=float)
    hit = (np.asarray(res.reliable, bool) & (lack > MAX_LACK_OF_FIT)
           & np.isfinite(mpc_v) & (mpc_v < MIN_MPC_FITTED))
    if not hit.any():
        return res
    reason = list(res.reason)
    for m in np.flatnonzero(hit):
        reason[m] = (f"unresolved: the fit leaves {lack[m]:.0f} x the band's median residual "
                     f"around the mode (> {MAX_LACK_OF_FIT:g}) and the shape is complex (MPC "
                     f"{mpc_v[m]:.2f} < {MIN_MPC_FITTED:g}): two close modes in one pole, or "
                     "a distortion no modal model holds (leakage, a window left in); its "
                     "damping and shape are not determined")
    return dataclasses.replace(res, reliable=np.asarray(res.reliable, bool) & ~hit,
                               reason=tuple(reason))


def _identify_band(h, orders, *, fn_hz, stab, clus, residuals, refine):
    """Diagram, selection and modes of FRFs already cut to the band."""
    diagram = plscf(h, orders=default_orders(h) if orders is None else orders,
                    criteria=stab)
    sel = poles_near(diagram, fn_hz) if fn_hz is not None else select_poles(diagram, clus)
    return modes_from_poles(h, diagram, sel, clus, stab, residuals=residuals, refine=refine)


def _raised(h, res, orders, *, fn_hz, stab, clus, residuals, refine):
    """:func:`raise_orders` with the default orders and the automatic selection (the
    orders from the peak count can stop below a weak mode that makes no peak of its own
    beside a strong one; its missing contribution then biases the neighbours, with
    standard deviations from a residual that is model error); ``(result, note)``."""
    if orders is not None or fn_hz is not None:
        return res, ""
    return raise_orders(h, res, stab, clus, residuals=residuals, refine=refine)


def lack_of_fit(res) -> np.ndarray:
    """How far the modal model falls short of the FRFs around each mode.

    Per FRF, the mean ``|H - H_synthesised|^2`` over the mode's window ``fn +- max(5
    lines, 2 zeta fn)`` over the median of ``|H - H_synthesised|^2`` over the band; the
    median over the FRFs. About 1 when the residual near the mode is what it is
    elsewhere (noise, the residual terms' error); a mode missing next to it (a weak one
    that makes no peak of its own) leaves tens to hundreds, and so do distortions no
    modal model holds (nonlinearity, drift). The band's median counts as at least
    ``MIN_RELATIVE_RESIDUAL`` (0.1 %) of the mean ``|H|`` in the window: exact FRFs,
    fitted to round-off, have nothing left to find. Non-finite lines take no part.

    Parameters
    ----------
    res : IdentifiedModes
        A pLSCF+LSFD result (``frf`` and ``synthesised`` present).

    Returns
    -------
    numpy.ndarray
        One ratio per mode (dimensionless); NaN without FRFs.

    Examples
    --------
    The exact FRFs of a 2-mass chain are fitted to round-off: nothing is left near
    either mode that is not left elsewhere.

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0, 120, 0.25),
    ...                     [0, 1], [0], frf_type="receptance")
    >>> bool(np.all(lack_of_fit(identify(h, 2, 110)) < MAX_LACK_OF_FIT))
    True
    """
    nm = np.size(res.fn_hz)
    if res.frf is None or res.synthesised is None or nm == 0:
        return np.full(nm, np.nan)
    f = res.frf["frequency"].values
    r = res.frf.values - res.synthesised.values
    ok = np.all(np.isfinite(r), axis=(0, 1))
    e = np.abs(r[..., ok]) ** 2
    level = np.abs(res.frf.values[..., ok]) ** 2
    floor = np.median(e, axis=-1) if e.shape[-1] else np.zeros(e.shape[:2])
    out = np.full(nm, np.nan)
    windows, _ = _windows(f[ok], np.asarray(res.fn_hz), np.asarray(res.zeta))
    for m, w in enumerate(windows):
        if not w.any():
            continue
        # what an FRF estimate or a stored file is good to: 0.1 % of |H| near the mode
        den = np.maximum(floor, MIN_RELATIVE_RESIDUAL**2 * level[..., w].mean(axis=-1))
        use = den > 0
        if use.any():
            out[m] = float(np.median(e[..., w].mean(axis=-1)[use] / den[use]))
    return out


def raise_orders(h, res, stab, clus, *, residuals=True, refine=True):
    """Look at higher pLSCF orders for a weak mode missing beside a reliable one.

    A reliable mode whose :func:`lack_of_fit` exceeds :data:`MAX_LACK_OF_FIT` may have
    a neighbour the default orders did not reach (it makes no peak of its own). The
    diagram is computed again up to twice the highest order (at most ``MAX_POLES``
    poles per order). Of its selected poles only those are taken that match a mode of
    the lower orders (within one half-power bandwidth ``2 zeta fn``) or lie within
    :data:`NEIGHBOUR_BANDWIDTHS` half-power bandwidths of a mode that lacked fit: a
    higher order also finds poles elsewhere that fit noise or distortion (on
    acceleration.lvm, three "modes" where the response spectrum has no peak). The
    higher orders are kept when they add such a neighbour, at least two resolution lines
    ``1 / T`` from every mode (closer, two poles fit one peak's distortion: case1.mat's
    212.09 Hz got a "mode" 0.26 Hz away, within its 0.31 Hz lines), keep every reliable
    mode reliable and bring a mode that lacked fit below the limit; then the step
    repeats.

    Parameters
    ----------
    h : xarray.DataArray
        FRF matrix cut to the band.
    res : IdentifiedModes
        The result at the default orders.
    stab, clus : StabilityCriteria, ClusterCriteria
    residuals, refine : bool
        As for :func:`identify`.

    Returns
    -------
    (IdentifiedModes, str)
        The result kept and a note for ``band_reason`` (empty when nothing changed).
    """
    first, lack0 = res, lack_of_fit(res)
    record_s, _ = record_lines(h)
    f_h = h["frequency"].values
    resolution = 1.0 / record_s if record_s else float(np.median(np.diff(f_h)))
    cap = max(MAX_POLES // max(int(h.sizes["reference"]), 1), 2)
    top, lack = int(res.diagram.orders.max()), lack0
    short = res.reliable & (lack > MAX_LACK_OF_FIT)
    while short.any() and top < cap:
        top = min(2 * top, cap)
        diagram = plscf(h, orders=range(2, top + 1), criteria=stab)
        sel = select_poles(diagram, clus)
        f_sel = np.abs(sel.pole) / (2 * np.pi)
        known = np.zeros(f_sel.size, bool)
        for f, z in zip(res.fn_hz, res.zeta):
            k = int(np.argmin(np.abs(f_sel - f))) if f_sel.size else -1
            if k >= 0 and abs(f_sel[k] - f) <= 2 * abs(z) * f:
                known[k] = True
        near = np.zeros(f_sel.size, bool)
        for f, z in zip(res.fn_hz[short], res.zeta[short]):
            near |= np.abs(f_sel - f) <= NEIGHBOUR_BANDWIDTHS * 2 * abs(z) * f
        # two poles closer than two resolution lines 1 / T are one peak's distortion,
        # not two modes the record can tell apart
        apart = np.array([np.all(np.abs(res.fn_hz - f) >= 2 * resolution) for f in f_sel],
                         bool)
        added = near & ~known & apart
        if not added.any():
            continue
        keep = np.flatnonzero(known | added)
        sub = SelectedPoles(sel.pole[keep], sel.vector[keep], sel.order[keep],
                            sel.count[keep], tuple(sel.members[i] for i in keep))
        trial = modes_from_poles(h, diagram, sub, clus, stab, residuals=residuals,
                                 refine=refine)
        lack_t = lack_of_fit(trial)
        mended = [lack_t[int(np.argmin(np.abs(trial.fn_hz - f)))] <= MAX_LACK_OF_FIT
                  for f in res.fn_hz[short]]
        if not (_keeps_reliable(res, trial) and any(mended)):
            break
        res, lack = trial, lack_t
        short = res.reliable & (lack > MAX_LACK_OF_FIT)
    if res is first:
        return res, ""
    bad = first.reliable & (lack0 > MAX_LACK_OF_FIT)
    kept = {int(np.argmin(np.abs(res.fn_hz - f))) for f in first.fn_hz}
    new = ", ".join(f"{f:.5g}" for k, f in enumerate(res.fn_hz) if k not in kept)
    where = ", ".join(f"{f:.5g} Hz ({v:.0f} x)" for f, v in zip(first.fn_hz[bad], lack0[bad]))
    return res, (f"; model orders raised from 2..{int(first.diagram.orders.max())} to "
                 f"2..{int(res.diagram.orders.max())} for a mode missing beside "
                 f"reliable ones: the lower orders left around {where} a residual above "
                 f"{MAX_LACK_OF_FIT:g} x its median in the band, and the higher orders add "
                 f"{new} Hz there (their other new poles are not taken)")


def _keeps_reliable(old, new) -> bool:
    """Whether every reliable mode of ``old`` has a reliable one in ``new`` within one
    half-power bandwidth ``2 zeta fn``."""
    f_new = np.asarray(new.fn_hz)[np.asarray(new.reliable, bool)]
    rel = np.asarray(old.reliable, bool)
    return all(np.any(np.abs(f_new - f) <= max(2 * abs(z) * f, 1e-9 * f))
               for f, z in zip(np.asarray(old.fn_hz)[rel], np.asarray(old.zeta)[rel]))


def own_lines(frf):
    """The FRFs at the record's own lines ``k / T`` when they are zero-padded with a whole
    number of lines per record line (every ``nfft / nperseg``-th line, counted from
    0 Hz); None when they are not padded or the padding is not a whole multiple.

    On these lines the padded spectrum equals the record's own DFT: a mode that has not
    decayed by the end of the record ``T`` is there exactly a pole whose residue is
    scaled by ``1 - exp(lambda T)``, while the interpolated lines between them carry
    the truncation's ripple (:data:`MAX_TRUNCATION`).

    Parameters
    ----------
    frf : xarray.DataArray or Dataset
        FRFs with a ``frequency`` dimension and ``attrs`` ``resolution_hz`` (``1 /
        T``) or ``nperseg`` and ``nfft``, as :func:`mvtk.signal.frf` states them.

    Returns
    -------
    xarray.DataArray or Dataset or None
        The same object at the own lines, ``attrs`` ``df_hz`` and ``nfft`` updated.

    Examples
    --------
    A 1 s impact record zero-padded 8 x: lines every 0.125 Hz, own lines every 1 Hz:

    >>> import xarray as xr
    >>> f = np.arange(0, 50, 0.125)
    >>> h = xr.DataArray(np.ones((1, 1, f.size), complex), dims=("response", "reference",
    ...                  "frequency"), coords={"frequency": f},
    ...                  attrs={"nperseg": 1000, "nfft": 8000, "resolution_hz": 1.0})
    >>> own = own_lines(h)
    >>> own["frequency"].values[:4], own.attrs["nfft"]
    (array([0., 1., 2., 3.]), 1000)
    """
    h = frf
    if "frequency" not in h.dims or h.sizes["frequency"] < 2:
        return None
    record_s, pad = record_lines(h)
    step = int(round(pad))
    if record_s is None or step < 2 or abs(pad - step) > 1e-6 * pad:
        return None
    f = h["frequency"].values
    df = float(np.median(np.diff(f)))
    j = np.rint(f / df).astype(np.int64)
    if np.max(np.abs(f / df - j)) > 1e-6:
        return None
    keep = np.flatnonzero(j % step == 0)
    if keep.size < 8:
        return None
    out = h.isel(frequency=keep)
    out.attrs = dict(h.attrs, df_hz=df * step, resolution_hz=df * step)
    if "nperseg" in out.attrs:
        out.attrs["nfft"] = out.attrs["nperseg"]
    return out


def truncation(res) -> np.ndarray:
    """Amplitude of each identified mode left at the end of a zero-padded record,
    ``exp(-sigma T)`` with the fitted (windowed) decay rate ``sigma`` (NaN where the
    FRFs are not padded or do not state their record; see :data:`MAX_TRUNCATION`)."""
    if res.frf is None or not res.n_modes:
        return np.full(res.n_modes, np.nan)
    sigma = -np.real(res.pole)
    if res.window_tau_s is not None:
        sigma = sigma + 1.0 / res.window_tau_s
    return _left_at_end(sigma, res.frf)


def _left_at_end(sigma, h) -> np.ndarray:
    """``exp(-sigma T)`` of decay rates ``sigma`` (1/s) at the end ``T`` of the record
    behind the zero-padded FRFs ``h``; NaN when they are not padded or do not say."""
    record_s, pad = record_lines(h)
    if record_s is None or pad < 1.5:
        return np.full(np.shape(sigma), np.nan)
    return np.exp(-np.clip(sigma, 0, None) * record_s)


def default_band(frf, fmin=None, fmax=None) -> tuple[float | None, float | None, str]:
    """The analysis band of :func:`identify`: ``(fmin, fmax, reason)`` in Hz.

    Bounds the user gave are kept ("given"); a missing one comes from
    :func:`mvtk.signal.analysis_band` (the band where the excitation is strong and the
    response has resonances, with the peaks it leaves out or cuts named in the reason).

    Examples
    --------
    The 2-mass chain's FRFs (31.1 and 81.4 Hz) on 0..400 Hz: the band is drawn around
    its two resonances; a bound the user gives is kept.

    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 400.0, 0.25),
    ...                     [0, 1], [0])
    >>> fmin, fmax, why = default_band(h)
    >>> fmin < 31.1 and 81.4 < fmax < 400.0
    True
    >>> default_band(h, 5.0, 150.0)
    (5.0, 150.0, 'given')
    """
    from mvtk.signal import analysis_band

    if fmin is not None and fmax is not None:
        return fmin, fmax, "given"
    m = as_frf_matrix(frf)
    src = dict(frf.attrs)
    if isinstance(frf, xr.Dataset) and "frf" in frf.data_vars:
        src.update(frf["frf"].attrs)
    if src.get("excitation_band_hz") is not None:     # a list: as_frf_matrix drops it
        m.attrs["excitation_band_hz"] = list(src["excitation_band_hz"])
    b = analysis_band(m)
    parts = []
    if fmin is None:
        fmin = b.fmin_hz
    else:
        parts.append(f"fmin {fmin:g} Hz given")
    if fmax is None:
        fmax = b.fmax_hz
    else:
        parts.append(f"fmax {fmax:g} Hz given")
    if fmin >= fmax:
        from mvtk.errors import ParameterError

        raise ParameterError(f"the band {fmin:g}..{fmax:g} Hz is empty: the default "
                             f"band from the data is {b.fmin_hz:g}..{b.fmax_hz:g} Hz "
                             f"({b.reason}); give both fmin and fmax")
    return fmin, fmax, "; ".join(parts + [f"from the data: {b.reason}"])


def _contribution(fit, h):
    """``||H_m(f_n)|| / ||H_measured(f_n)||`` (Frobenius over all FRFs) of each mode."""
    f = h["frequency"].values
    out = np.empty(fit.pole.size)
    for m, (lam, A) in enumerate(zip(fit.pole, fit.residue)):
        k = int(np.argmin(np.abs(f - abs(lam) / (2 * np.pi))))
        iw = 2j * np.pi * f[k]
        hm = (A / (iw - lam) + np.conj(A) / (iw - np.conj(lam))) * iw**fit.power
        den = np.linalg.norm(h.values[:, :, k])
        out[m] = np.linalg.norm(hm) / den if den > 0 else np.nan
    return out


def _windows(f, fn, zeta):
    """Lines within ``fn +- max(5 lines, 2 zeta fn)`` of each mode (bool per line)."""
    df = float(np.median(np.diff(f)))
    half = np.maximum(5 * df, 2 * np.abs(zeta) * fn)
    return [(f >= f0 - h) & (f <= f0 + h) for f0, h in zip(fn, half)], half


def _local_correlation(Hm, Hs, windows):
    """Measured vs synthesised correlation over each mode's window."""
    out = np.empty(len(windows))
    for m, k in enumerate(windows):
        a, b = Hm[..., k], Hs[..., k]
        den = np.sum(np.abs(a) ** 2) * np.sum(np.abs(b) ** 2)
        out[m] = np.abs(np.sum(a * np.conj(b))) ** 2 / den if den > 0 else np.nan
    return out


def window_tau(h) -> float | None:
    """Time constant (s) of the exponential window the FRFs were computed with, or None."""
    for key in ("exponential_window_tau_s", "exp_window_tau_s"):
        v = h.attrs.get(key)
        if v is not None and np.isfinite(float(v)) and float(v) > 0:
            return float(v)
    return None


def record_lines(h) -> tuple[float | None, float]:
    """Record length (s) behind the FRFs and how many lines per record line they hold.

    From ``attrs["resolution_hz"]`` (``1 / record``) and the line spacing of the FRFs
    as they are (lines kept one per resolution after zero padding count as independent),
    else from ``attrs["nperseg"]`` and ``attrs["nfft"]`` (samples; :func:`mvtk.signal.frf`
    and :func:`frf_matrix` state them) with the line spacing: ``(nperseg / fs,
    nfft / nperseg)``; ``(None, 1.0)`` when the FRFs do not say. A factor above 1 means
    zero-padded, interpolated lines: neighbouring lines are not independent.
    """
    n, nfft = h.attrs.get("nperseg"), h.attrs.get("nfft")
    f = h["frequency"].values
    if f.size < 2:
        return None, 1.0
    res, df = h.attrs.get("resolution_hz"), float(np.median(np.diff(f)))
    if isinstance(res, (int, float)) and res > 0 and df > 0:
        return 1.0 / float(res), max(float(res) / df, 1.0)
    if n is None or nfft is None:
        return None, 1.0
    n, nfft = int(n), int(nfft)
    if n <= 0 or nfft < n:
        return None, 1.0
    fs = float(np.median(np.diff(f))) * nfft
    return n / fs, nfft / n


def record_window(h) -> tuple[np.ndarray, float] | None:
    """Time window ``(w per sample, fs)`` of the records behind impact FRFs, for the
    line correlation of their noise (``refine_poles(record_window=...)``), or None when
    the lines are independent (an unwindowed, unpadded record), the FRFs do not say
    (``attrs`` ``nperseg``, ``nfft``, ``window``, ``exponential_window_tau_s``,
    ``pretrigger``) or they are not of an impact test (averaged random or swept
    excitation decorrelates the lines: the force spectrum varies from record to
    record)."""
    from scipy.signal import get_window

    a = h.attrs
    if a.get("excitation") != "impact":
        return None
    try:
        n, nfft = int(a["nperseg"]), int(a["nfft"])
        tau = a.get("exponential_window_tau_s", a.get("exp_window_tau_s"))
        tau = None if tau is None else float(tau)
        name = a.get("window", "boxcar")
        w = get_window("boxcar" if name in (None, "None") else name, n, fftbins=True)
        df = float(a.get("df_hz") or np.median(np.diff(h["frequency"].values)))
        pre = int(a.get("pretrigger", 0) or 0)
    except (KeyError, TypeError, ValueError):
        return None
    if n <= 0 or nfft < n or not (df > 0):
        return None
    fs = df * nfft
    if tau is not None and tau > 0:
        w = w * np.exp(-np.clip(np.arange(n) - pre, 0, None) / (tau * fs))
    elif nfft == n and np.all(w == w[0]):
        return None
    return w, fs


def modes_from_poles(h, diagram, sel: SelectedPoles, clus, stab, *, residuals=True,
                     refine=True):
    """Refinement, LSFD on the selected poles and everything the result table needs."""
    from mvtk.signal import exponential_window_correction

    f = h["frequency"].values
    kind = h.attrs.get("frf_type", "other")
    Hv = h.values
    finite = np.all(np.isfinite(Hv), axis=(0, 1))
    Hf = Hv if finite.all() else np.where(np.isfinite(Hv), Hv, 0.0)
    pole = sel.pole
    nm = pole.size
    cov = np.full((nm, 2, 2), np.nan)
    refined = np.zeros(nm, bool)
    noise = None
    if nm:
        # impact records: the window (exponential, zero-padding) correlates the noise
        # of neighbouring lines, which the poles' covariance then accounts for
        window = record_window(h)
        ref = refine_poles(Hf[:, :, finite], f[finite], pole, kind, residuals=residuals,
                           max_nfev=50 if refine else 0, record_window=window)
        if refine:
            pole, refined = ref.pole.copy(), ref.refined.copy()
        cov, noise = ref.covariance, ref.noise_std
    # zero-padded lines interpolate the record's nperseg / 2 independent ones: the fit
    # counts each piece of information ``pad`` times (variances ``pad`` times too small),
    # unless the line correlation of the record's window was used
    _, pad = record_lines(h)
    if not nm or window is None:
        cov = cov * pad
    fn = np.abs(pole) / (2 * np.pi)
    zeta = -pole.real / np.where(np.abs(pole) > 0, np.abs(pole), 1)
    windows, half = _windows(f, fn, zeta)
    fit, (r_with, r_without, _), coef_var = lsfd_with_misfit(
        Hf, f, pole, kind, [w & finite for w in windows], residuals=residuals,
        coef_variance=True, record_window=window if nm else None)
    # support: misfit without / with the mode within its window
    with np.errstate(divide="ignore", invalid="ignore"):
        support = np.where(r_with > 0, r_without / np.where(r_with > 0, r_with, 1.0), np.inf)
    clean_support, flagged = _clean_support(h, Hf, f, pole, kind,
                                            [w & finite for w in windows], residuals)
    no = h.sizes["response"]
    phi, part, scaled = rank_one_shapes(fit.residue, pole, _driving_points(h))
    if scaled:
        cplx = phi
        # phi sqrt(2 i w_d): the real mass-normalised shape of a proportionally damped mode
        rot, real = _rotate_real(phi * np.sqrt(2j * pole.imag)[:, None])
        norm = "mass"
    else:
        amp = np.abs(phi).max(axis=1, keepdims=True) if nm else np.ones((0, 1))
        idx = np.argmax(np.abs(phi), axis=1) if nm else np.zeros(0, int)
        ph = np.exp(-1j * np.angle(phi[np.arange(nm), idx]))[:, None] if nm else 1
        cplx = phi * ph / np.where(amp > 0, amp, 1)
        rot, real = _rotate_real(cplx)
        real = real / np.maximum(np.abs(real).max(axis=1, keepdims=True), 1e-300)
        norm = "unit_max"
    psi_std = _shape_std(coef_var, part, noise, no) * np.sqrt(
        pad if not nm or window is None else 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        gain = np.linalg.norm(cplx, axis=1) / np.linalg.norm(phi, axis=1) if nm else 1.0
    # the window's damping leaves every pole: sigma_true = sigma_id - 1 / tau
    fn_fit, zeta_fit = fn, zeta
    tau = window_tau(h)
    zeta_window = np.full(nm, np.nan)
    if tau is not None and nm:
        fn, zeta = exponential_window_correction(fn_fit, zeta_fit, tau)
        zeta_window = zeta_fit - zeta
    # what is left of each (windowed or not) mode at the end of its record: the policy
    # pads only when the whole response has decayed, which a weak slow mode of an
    # accelerance need not have
    left = _left_at_end(-pole.real, h)
    fn_std, zeta_std = pole_std(2 * np.pi * fn * (-zeta + 1j * np.sqrt(
        np.clip(1 - zeta**2, 0, None))), cov) if nm else (np.zeros(0), np.zeros(0))
    labels = dof_labels(h["node"].values, h["direction"].values, h["response"].values)
    shp_std = shapes_array(psi_std * np.atleast_1d(gain)[:, None] if nm else psi_std, fn,
                           zeta, labels, h["node"].values, h["direction"].values,
                           "mass" if scaled else "unit_max", "pLSCF+LSFD")
    shp_std.name = "shape_std"
    shp = shapes_array(cplx, fn, zeta, labels, h["node"].values, h["direction"].values,
                       norm, "pLSCF+LSFD")
    rshp = shapes_array(real, fn, zeta, labels, h["node"].values, h["direction"].values,
                        norm, "pLSCF+LSFD")
    syn_v = synthesise(fit, f)
    syn = h.copy(data=syn_v)
    syn.name = "frf_synthesised"
    # lines where either FRF is not finite (the residual terms of a band that starts at
    # 0 Hz are infinite there) take no part in the correlation
    bad = ~(np.isfinite(h.values) & np.isfinite(syn_v))
    Hm, Sv = h.values, syn_v
    if bad.any():
        Hm, Sv = np.where(bad, 0.0, Hm), np.where(bad, 0.0, Sv)
    num = np.abs(np.sum(Hm * np.conj(Sv), axis=(1, 2))) ** 2
    den = np.sum(np.abs(Hm) ** 2, axis=(1, 2)) * np.sum(np.abs(Sv) ** 2, axis=(1, 2))
    corr = xr.DataArray(np.where(den > 0, num / np.where(den > 0, den, 1), 0.0),
                        dims=("response",), coords={"response": h["response"].values},
                        name="correlation")
    tot_num = np.abs(np.sum(Hm * np.conj(Sv))) ** 2
    tot_den = np.sum(np.abs(Hm) ** 2) * np.sum(np.abs(Sv) ** 2)
    corr.attrs["overall"] = float(tot_num / tot_den) if tot_den > 0 else 0.0
    # one response: the shape is one number; MPC and MPD say nothing (NaN)
    mpc_v = mpc(cplx) if no > 1 else np.full(nm, np.nan)
    mpd_v = mpd(cplx) if no > 1 else np.full(nm, np.nan)
    need = clus.min_count
    df = float(np.median(np.diff(f)))
    contrib = _contribution(fit, h)
    local = _local_correlation(h.values, syn_v, windows)
    exc_db = excitation_level(h, fn)
    kind = str(h.attrs.get("excitation", ""))
    rq = {str(q) for q in h["reference_quantity"].values}
    # an impact record's DFT holds each mode exactly as a pole (a complete transient, or
    # a truncated one on the record's own lines, as :func:`identify` makes sure), so the
    # line spacing does not limit its damping; zeta_std says how well the data fix it
    # (the spacing does limit Welch spectra of random or swept excitation: leakage)
    transient = kind == "impact"
    reliable, reason = quality_flags(fn, zeta, mpc_v, sel.count, need, diagram.band_hz,
                                     stab.zeta_max, df_hz=None if transient else df,
                                     zeta_fit=zeta_fit,
                                     contribution=contrib,
                                     local=local, support=support, half_hz=half,
                                     excitation_db=exc_db,
                                     min_excitation_db=WEAK_EXCITATION_DB.get(kind),
                                     excitation_name="force" if rq == {"force"}
                                     else "excitation",
                                     clean_support=clean_support, flagged=flagged,
                                     zeta_window=zeta_window, truncation=left,
                                     zeta_std=zeta_std)
    return IdentifiedModes(
        method="pLSCF+LSFD", fn_hz=fn, zeta=zeta,
        pole=2 * np.pi * fn * (-zeta + 1j * np.sqrt(np.clip(1 - zeta**2, 0, None))),
        shapes=shp,
        real_shapes=rshp, participation=part, mpc=mpc_v, mpd=mpd_v,
        stability_count=sel.count, reliable=reliable, reason=reason, frf=h,
        synthesised=syn, correlation=corr, residue=fit.residue,
        lower_residual=fit.lower, upper_residual=fit.upper, diagram=diagram,
        support=support, excitation_db=exc_db, fn_std_hz=fn_std, zeta_std=zeta_std,
        shape_std=shp_std, refined=refined, zeta_window=zeta_window, window_tau_s=tau,
    )


def _clean_support(h, H, f, pole, kind, windows, residuals):
    """``support`` on the FRFs whose measurement sets passed the quality checks.

    The ``pair_quality`` coordinate (:func:`frf_matrix`) names, per pair, the verdicts of
    the sets behind it that are not ``"ok"`` (a clipped force, a cut double hit). A pole
    that only such FRFs need (the spectrum of a clipped force has its zeros elsewhere
    than the true one's: ``H F_true / F_clipped`` gets a pole at a zero of
    ``F_clipped``) is fitted to the fault, not to the structure. LSFD fits every FRF
    with its own residues on the shared basis, so the misfit of the clean FRFs alone is
    that of a fit to them alone. Returns ``(support, text)``: NaN and ``""`` when no
    pair is flagged or every pair is.
    """
    nm = pole.size
    out = np.full(nm, np.nan)
    pq = h.coords.get("pair_quality")
    if pq is None or nm == 0:
        return out, ""
    verdict = np.asarray(pq.transpose("response", "reference").values).astype(str)
    bad = verdict != ""
    if not bad.any() or bad.all():
        return out, ""
    clean = H[~bad][:, None, :]
    r_with, r_without, _ = local_misfit(clean, f, pole, kind, windows, residuals=residuals)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = np.where(r_with > 0, r_without / np.where(r_with > 0, r_with, 1.0), np.inf)
    names = sorted({v for v in verdict[bad]})
    return out, (f"{int(bad.sum())} of {bad.size} FRFs from flagged sets: "
                 + "; ".join(names))


def _shape_std(coef_var, part, noise, no):
    """First-order std of the rank-one shapes ``psi = A conj(L)`` at fixed poles.

    The LSFD residues of FRF ``(o, i)`` have variances ``s_oi^2 / 2 diag (B^T B)^-1``
    (``coef_var``: real basis ``B`` of :func:`lsfd`; ``s_oi`` the FRF's complex noise
    std); with the unit participation ``L``, ``var(psi_o) = sum_i |L_i|^2 var(A_oi)``.
    Units of the residues.
    """
    nm, ni = part.shape
    if nm == 0 or noise is None:
        return np.full((nm, no), np.nan)
    vres = coef_var[0:2 * nm:2] + coef_var[1:2 * nm:2]    # var(Re) + var(Im), unit noise
    var_a = (np.asarray(noise) ** 2 / 2)[None] * vres[:, None, None]   # (nm, no, ni)
    return np.sqrt(np.einsum("mi,moi->mo", np.abs(part) ** 2, var_a))
