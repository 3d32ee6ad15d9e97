"""Closed-loop metrics: settling time, modal damping, peak reduction, voltage, stability.

References
----------
Goh & Caughey, Int. J. Control 41 (1985) (PPF); Fanson & Caughey, AIAA J 28 (1990);
Newman, Smart Mater. Struct. 1 (1992) (SRF). Stability limits: Routh-Hurwitz on the
single-mode loops of PHYSICS.md section 4.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..errors import DimensionError, ParameterError
from ._controllers import plant_state_space
from ._simulate import closed_loop, realize
from ._stability import ZETA_TOL, StabilityVerdict, stability_verdict

__all__ = [
    "settling_time",
    "ModalProperties",
    "modal_properties",
    "closed_loop_modes",
    "added_damping",
    "peak_reduction_db",
    "voltage_stats",
    "ppf_gain_limit",
    "srf_gain_limit",
    "critical_gain",
    "SpilloverResult",
    "spillover_check",
]


def settling_time(y, t=None, *, band: float = 0.05, reference: float | None = None) -> float:
    """Time after which ``|y|`` stays within ``band * reference`` (s).

    Parameters
    ----------
    y : array or xarray.DataArray, shape (n,)
        Output history (e.g. tip displacement); a DataArray supplies its ``time`` coord.
    t : array, shape (n,), optional
        Times (s), required when ``y`` is a plain array.
    band : float
        Half-width of the band as a fraction of ``reference`` (0.05 = 5 %).
    reference : float, optional
        Initial amplitude; default ``max |y|``.

    Returns
    -------
    float
        Time of the first sample after the last excursion outside the band (the
        envelope crossing, resolved to the sample; conservative by at most half a period
        compared with a smooth envelope), 0.0 if ``y`` never leaves the band, ``inf`` if
        it is still outside the band at the end of the record.

    Examples
    --------
    A decay ``exp(-t)``: ``|y|`` stays within 5 % after ``ln(20)`` = 3.0 s:

    >>> t = np.linspace(0.0, 10.0, 10001)
    >>> round(settling_time(np.exp(-t), t), 2)
    3.0
    """
    if t is None:
        if not hasattr(y, "coords") or "time" not in y.coords:
            raise ParameterError("settling_time needs t when y is not a DataArray with time")
        t = y["time"].values
    y = np.asarray(y, dtype=float).ravel()
    t = np.asarray(t, dtype=float).ravel()
    if y.shape != t.shape or y.size < 2:
        raise DimensionError(f"y and t must be 1-D of equal length >= 2, got {y.shape}, {t.shape}")
    if not (0 < band < 1):
        raise ParameterError(f"band must be a fraction in (0, 1), got {band}")
    ref = float(np.max(np.abs(y))) if reference is None else float(reference)
    if not ref > 0:
        raise ParameterError(f"reference amplitude must be > 0, got {ref}")
    outside = np.nonzero(np.abs(y) > band * ref)[0]
    if outside.size == 0:
        return 0.0
    last = outside[-1]
    if last == y.size - 1:
        return float("inf")
    return float(t[last + 1])


@dataclass(frozen=True)
class ModalProperties:
    """Natural frequencies (Hz) and damping ratios from eigenvalues (rad/s).

    One entry per oscillatory pair (positive imaginary part) and per real eigenvalue,
    sorted by frequency.

    Examples
    --------
    Returned by :func:`modal_properties` and :func:`closed_loop_modes`:

    >>> m = modal_properties([-1.0 + 10.0j, -1.0 - 10.0j])
    >>> np.round(m.fn_hz, 4), np.round(m.zeta, 4)      # |lambda| / 2 pi, -Re / |lambda|
    (array([1.5995]), array([0.0995]))
    """

    fn_hz: np.ndarray
    zeta: np.ndarray
    eigenvalues: np.ndarray
    meta: dict = field(default_factory=dict)

    @property
    def stable(self) -> bool:
        """True when the verdict is ``"stable"`` (marginal poles are not stable)."""
        return self.verdict.stable

    @property
    def verdict(self) -> StabilityVerdict:
        """:func:`~mvtk.control.stability_verdict` of the eigenvalues."""
        return stability_verdict(self.eigenvalues)

    def to_dataframe(self):
        import pandas as pd

        return pd.DataFrame({"fn_hz": self.fn_hz, "zeta": self.zeta,
                             "real": self.eigenvalues.real, "imag": self.eigenvalues.imag})


def modal_properties(eigenvalues) -> ModalProperties:
    """:class:`ModalProperties` of eigenvalues ``lambda``: ``fn = |lambda| / 2 pi``,
    ``zeta = -Re(lambda) / |lambda|``; conjugate pairs counted once.

    Examples
    --------
    >>> w = 2 * np.pi * 10.0
    >>> m = modal_properties([-0.01 * w + 1j * w * np.sqrt(1 - 0.01**2)])
    >>> m.fn_hz, np.round(m.zeta, 6)
    (array([10.]), array([0.01]))
    """
    lam = np.asarray(eigenvalues, dtype=complex).ravel()
    tol = 1e-9 * max(float(np.max(np.abs(lam))) if lam.size else 0.0, 1.0)
    keep = lam[(lam.imag > tol) | (np.abs(lam.imag) <= tol)]
    keep = np.where(np.abs(keep.imag) <= tol, keep.real + 0j, keep)
    mag = np.abs(keep)
    order = np.argsort(mag, kind="stable")
    keep, mag = keep[order], mag[order]
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(mag > 0, -keep.real / np.where(mag > 0, mag, 1.0), np.nan)
    return ModalProperties(fn_hz=mag / (2 * np.pi), zeta=zeta, eigenvalues=keep)


def closed_loop_modes(plant, controller=None, design_plant=None) -> ModalProperties:
    """Modal properties of the closed loop (open loop for ``controller=None``).

    Examples
    --------
    >>> from mvtk.control import VelocityFeedback, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> np.round(closed_loop_modes(plant, VelocityFeedback(gain=1e-3)).zeta, 4)   # 0.01 + G w / 2
    array([0.0414])
    """
    if controller is None:
        return modal_properties(np.linalg.eigvals(plant_state_space(plant).A))
    return modal_properties(closed_loop(plant, controller, design_plant).poles())


def _match(open_poles: np.ndarray, closed_poles: np.ndarray) -> np.ndarray:
    """Index into closed_poles for each open pole (min total distance assignment)."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(open_poles[:, None] - closed_poles[None, :])
    rows, cols = linear_sum_assignment(cost)
    out = np.empty(open_poles.size, dtype=int)
    out[rows] = cols
    return out


def _origins(law) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Closed-loop poles, and for each the uncoupled open-loop pole it continues and
    where that pole comes from (``"plant mode k"`` or ``"controller"``).

    The pairing is the assignment of least total distance in the complex plane between
    the poles of the uncoupled plant and controller and the closed-loop poles.
    """
    n = law.n_plant
    lam_p = np.linalg.eigvals(law.A[:n, :n])
    lam_c = np.linalg.eigvals(law.A[n:, n:]) if law.A.shape[0] > n else np.zeros(0, complex)
    plant_modes = modal_properties(lam_p)
    labels_p = []
    for lam in lam_p:
        k = int(np.argmin(np.abs(plant_modes.eigenvalues - (lam.real + 1j * abs(lam.imag)))))
        labels_p.append(f"plant mode {k + 1}")
    lam_open = np.concatenate([lam_p, lam_c])
    labels = labels_p + ["controller"] * lam_c.size
    lam_closed = np.linalg.eigvals(law.linearized_matrix())
    idx = _match(lam_closed, lam_open)  # open pole for each closed pole
    return lam_closed, lam_open[idx], [labels[i] for i in idx]


def added_damping(plant, controller, mode: int = 1, design_plant=None,
                  *, zeta_tol: float = ZETA_TOL) -> dict:
    """Damping of plant mode ``mode`` (1-based) without and with the controller.

    The closed-loop poles are paired with the open-loop poles of the uncoupled plant and
    controller (assignment of least total distance in the complex plane), so that the
    pole that continues the structural mode is followed even when a PPF filter tuned on
    it splits the pair.

    An unstable or marginal loop adds no damping: the verdict of the closed-loop
    eigenvalues (:func:`~mvtk.control.stability_verdict`) comes first, and when it is not
    ``"stable"`` ``added`` is NaN and ``zeta_closed`` / ``fn_hz_closed`` are those of the
    worst closed-loop pole (``zeta_closed <= 0`` up to the marginal tolerance, e.g. -1
    for a real unstable pole), so that a check ``zeta_closed >= zeta_min`` fails.

    Returns
    -------
    dict
        ``fn_hz_open``, ``zeta_open``, ``fn_hz_closed``, ``zeta_closed``, ``added``, and
        the verdict: ``stable`` (bool), ``verdict`` (``"stable"``, ``"marginal"`` or
        ``"unstable"``), ``max_real_pole`` (1/s), ``min_closed_loop_zeta``, ``reason``
        (one line naming the offending pole; empty when stable).

    Examples
    --------
    Velocity feedback adds ``G w / 2`` = 0.0314 to the 1 % of the mode:

    >>> from mvtk.control import VelocityFeedback, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> d = added_damping(plant, VelocityFeedback(gain=1e-3))
    >>> d["verdict"], round(d["zeta_open"], 4), round(d["added"], 4)
    ('stable', 0.01, 0.0314)
    """
    law = realize(controller, plant, design_plant)
    if law is None or not law.is_linear:
        raise ParameterError("added_damping needs a linear controller (eigenvalues)")
    n = law.n_plant
    open_modes = modal_properties(np.linalg.eigvals(law.A[:n, :n]))
    osc = np.nonzero(open_modes.eigenvalues.imag > 0)[0]
    if not 1 <= mode <= osc.size:
        raise ParameterError(f"mode must be in 1..{osc.size} (oscillatory plant modes), got {mode}")
    A_unc = law.A.copy()
    A_unc[n:, :n] = 0.0
    lam_open = np.linalg.eigvals(A_unc)
    lam_closed = np.linalg.eigvals(law.closed_loop_matrix())
    verdict = stability_verdict(lam_closed, zeta_tol=zeta_tol)
    zo = float(open_modes.zeta[osc[mode - 1]])
    out = {"fn_hz_open": float(open_modes.fn_hz[osc[mode - 1]]), "zeta_open": zo,
           "stable": verdict.stable, "verdict": verdict.verdict,
           "max_real_pole": verdict.max_real_pole,
           "min_closed_loop_zeta": verdict.min_zeta, "reason": verdict.reason}
    if not verdict.stable:
        worst = verdict.offending[0]
        out.update(fn_hz_closed=float(abs(worst) / (2 * np.pi)),
                   zeta_closed=float(-worst.real / abs(worst)) if abs(worst) > 0 else 0.0,
                   added=float("nan"))
        return out
    up_o = lam_open[lam_open.imag >= 0]
    up_c = lam_closed[lam_closed.imag >= 0]
    if up_o.size != up_c.size:  # a real pair split or merged; compare on the full sets
        up_o, up_c = lam_open, lam_closed
    target = open_modes.eigenvalues[osc[mode - 1]]
    i_open = int(np.argmin(np.abs(up_o - target)))
    lam = up_c[_match(up_o, up_c)[i_open]]
    fc, zc = abs(lam) / (2 * np.pi), -lam.real / abs(lam)
    out.update(fn_hz_closed=float(fc), zeta_closed=float(zc), added=float(zc - zo))
    return out


def _amplitude_spectrum(y: np.ndarray, fs: float) -> tuple[np.ndarray, np.ndarray]:
    spec = np.abs(np.fft.rfft(y)) * 2.0 / y.size
    return np.fft.rfftfreq(y.size, 1.0 / fs), spec


def peak_reduction_db(
    y_open, y_closed, fs: float, f_hz, *, rel_band: float = 0.1
) -> np.ndarray:
    """FFT peak reduction ``20 log10(peak_open / peak_closed)`` (dB) near each ``f_hz``.

    Peaks are the maxima of the amplitude spectra (rectangular window, the whole record,
    as the paper's FFT plots) within ``f (1 +- rel_band)``. Positive = reduction.

    Examples
    --------
    Halving the response halves its FFT peak: ``20 log10(2)`` = 6.02 dB:

    >>> t = np.arange(2000) / 200.0
    >>> y = np.exp(-0.5 * t) * np.sin(2 * np.pi * 10.0 * t)
    >>> np.round(peak_reduction_db(y, y / 2, 200.0, [10.0]), 2)
    array([6.02])
    """
    y_open = np.asarray(y_open, dtype=float).ravel()
    y_closed = np.asarray(y_closed, dtype=float).ravel()
    if y_open.shape != y_closed.shape:
        raise DimensionError(
            f"open and closed-loop records must have equal length, got {y_open.size} "
            f"and {y_closed.size}"
        )
    if not fs > 0:
        raise ParameterError(f"fs must be > 0, got {fs}")
    f, a_open = _amplitude_spectrum(y_open, fs)
    _, a_closed = _amplitude_spectrum(y_closed, fs)
    out = []
    for fk in np.atleast_1d(np.asarray(f_hz, dtype=float)):
        sel = (f >= fk * (1 - rel_band)) & (f <= fk * (1 + rel_band))
        if not np.any(sel):
            raise ParameterError(
                f"no spectral line within {rel_band:.0%} of {fk} Hz (resolution "
                f"{f[1]:.4g} Hz, Nyquist {fs / 2:g} Hz)"
            )
        po, pc = a_open[sel].max(), a_closed[sel].max()
        out.append(20 * np.log10(po / pc) if pc > 0 else np.inf)
    return np.array(out)


def voltage_stats(u) -> dict:
    """Peak ``max |u|`` and RMS of an actuator command history (input units).

    Examples
    --------
    A sine of 100 V amplitude over whole periods: RMS ``100 / sqrt(2)``:

    >>> u = 100.0 * np.sin(2 * np.pi * np.arange(1000) / 100)
    >>> s = voltage_stats(u)
    >>> round(s["peak"], 3), round(s["rms"], 3)
    (100.0, 70.711)
    """
    u = np.asarray(u, dtype=float).ravel()
    if u.size == 0:
        raise DimensionError("empty actuator history")
    return {"peak": float(np.max(np.abs(u))), "rms": float(np.sqrt(np.mean(u**2)))}


def ppf_gain_limit() -> float:
    """Upper PPF gain of the single-mode form: stable iff ``0 <= G < 1`` (any wf, zf).

    The closed-loop characteristic polynomial has constant term ``w^2 wf^2 (1 - G)``.

    Examples
    --------
    >>> ppf_gain_limit()
    1.0
    """
    return 1.0


def srf_gain_limit(f_hz: float, f_filter_hz: float, zeta_filter: float) -> float:
    """Upper SRF gain for an undamped mode: ``2 zf (wf^2 - w^2) / (w^2 wf)`` (s).

    Routh-Hurwitz on ``(s^2 + w^2)(s^2 + 2 zf wf s + wf^2) + G w^2 wf^2 s``; the filter
    must be tuned above the mode (``wf > w``), otherwise no positive gain is stable.

    Examples
    --------
    Mode at 10 Hz, filter at 15 Hz with zf = 0.3:
    ``2 zf (wf**2 - w**2) / (w**2 wf)`` in s:

    >>> round(srf_gain_limit(10.0, 15.0, 0.3), 6)
    0.007958
    """
    if not (f_hz > 0 and f_filter_hz > 0 and zeta_filter > 0):
        raise ParameterError(
            f"expected f_hz > 0, f_filter_hz > 0, zeta_filter > 0, got {f_hz}, "
            f"{f_filter_hz}, {zeta_filter}"
        )
    w, wf = 2 * np.pi * f_hz, 2 * np.pi * f_filter_hz
    if wf <= w:
        raise ParameterError(
            f"SRF filter at {f_filter_hz} Hz is not above the mode at {f_hz} Hz: no positive "
            "gain is stable for an undamped mode"
        )
    return 2 * zeta_filter * (wf**2 - w**2) / (w**2 * wf)


def _with_gain(controller, g: float):
    if hasattr(controller, "targets"):
        if len(controller.targets) != 1:
            raise ParameterError("critical_gain scales a single-filter controller")
        f, z, _ = controller.targets[0]
        return replace(controller, targets=((f, z, g),))
    if hasattr(controller, "gain"):
        return replace(controller, gain=g)
    raise ParameterError(f"critical_gain cannot scale a {type(controller).__name__}")


def critical_gain(
    plant, controller, *, g_max: float, rtol: float = 1e-6, design_plant=None
) -> float:
    """Smallest gain in ``(0, g_max]`` at which the closed loop loses stability.

    Bisection on the largest real part of the closed-loop eigenvalues (the gain of a
    single-filter PPF/SRF or a VelocityFeedback is varied). Returns ``inf`` if the loop
    is stable at ``g_max``; raises if it is unstable at ``g_max * 1e-9``.

    Examples
    --------
    The single-mode PPF loses stability at G = 1 (constant term ``w**2 wf**2 (1 - G)``):

    >>> from mvtk.control import PPF, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> round(critical_gain(plant, PPF([(10.0, 0.1, 0.5)]), g_max=5.0), 4)
    1.0
    """
    def unstable(g):
        cl = closed_loop(plant, _with_gain(controller, g), design_plant)
        return bool(np.max(np.linalg.eigvals(cl.A).real) >= 0)

    if not g_max > 0:
        raise ParameterError(f"g_max must be > 0, got {g_max}")
    lo, hi = g_max * 1e-9, g_max
    if unstable(lo):
        raise ParameterError(f"closed loop already unstable at gain {lo:g}")
    if not unstable(hi):
        return float("inf")
    while hi - lo > rtol * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if unstable(mid) else (mid, hi)
    return 0.5 * (lo + hi)


@dataclass(frozen=True)
class SpilloverResult:
    """Closed-loop modes of a controller on its design plant and on a larger plant.

    Attributes
    ----------
    design, evaluation : ModalProperties
        Closed-loop modes on the design (reduced) plant and on the evaluation plant.
    verdict_design, verdict_evaluation : StabilityVerdict
        Stability verdicts of both loops.
    offending : list of dict
        One row per offending (unstable or marginal) closed-loop pole of the evaluation
        loop: ``real``, ``imag`` (1/s, rad/s), ``fn_hz``, ``zeta``, ``continues`` (the
        uncoupled open-loop pole it continues: ``"plant mode k"`` or ``"controller"``),
        ``open_fn_hz`` and ``residual`` (True when that plant mode has no counterpart
        within 1 % in frequency among the design plant's modes: spillover onto a
        residual mode).

    Examples
    --------
    Returned by :func:`spillover_check`:

    >>> from mvtk.control import VelocityFeedback, modal_plant
    >>> design = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                      inputs=["force"], outputs=["tip"])
    >>> full = modal_plant([10.0, 60.0], 0.01, B=np.array([[1.0], [1.0]]),
    ...                    Cq=np.array([[1.0, 1.0]]), inputs=["force"], outputs=["tip"])
    >>> res = spillover_check(VelocityFeedback(gain=1e-3), design, full)
    >>> res.design.fn_hz.size, res.evaluation.fn_hz.size, res.verdict_evaluation.verdict
    (1, 2, 'stable')
    """

    design: ModalProperties
    evaluation: ModalProperties
    stable_design: bool
    stable_evaluation: bool
    max_real_evaluation: float
    verdict_design: StabilityVerdict | None = None
    verdict_evaluation: StabilityVerdict | None = None
    offending: tuple = ()

    @property
    def verdict(self) -> str:
        """Verdict of the evaluation loop (the one that matters)."""
        return self.verdict_evaluation.verdict

    def to_dataframe(self):
        import pandas as pd

        d = self.design.to_dataframe().assign(plant="design")
        e = self.evaluation.to_dataframe().assign(plant="evaluation")
        return pd.concat([d, e], ignore_index=True)

    def offending_table(self):
        """The offending poles of the evaluation loop as a DataFrame."""
        import pandas as pd

        return pd.DataFrame(list(self.offending),
                            columns=["real", "imag", "fn_hz", "zeta", "continues",
                                     "open_fn_hz", "residual"])

    def to_dict(self) -> dict:
        """JSON-friendly summary."""
        return {"verdict_design": self.verdict_design.to_dict(),
                "verdict_evaluation": self.verdict_evaluation.to_dict(),
                "offending": [dict(r) for r in self.offending]}


def spillover_check(controller, design_plant, evaluation_plant, *,
                    zeta_tol: float = ZETA_TOL) -> SpilloverResult:
    """Evaluate a controller designed (normalised) on ``design_plant`` on a larger plant.

    The gains are fixed on the design plant (``design_plant=`` of :func:`closed_loop`);
    the same sensor and actuator names must exist on both plants. The result carries the
    stability verdict of both loops and, for an unstable or marginal evaluation loop,
    the offending poles with the plant mode each continues and whether that mode is a
    residual mode (absent from the design plant: spillover).

    Examples
    --------
    Collocated velocity feedback designed on one mode stays stable on a plant with a
    second (residual) mode at 60 Hz:

    >>> from mvtk.control import VelocityFeedback, modal_plant
    >>> design = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                      inputs=["force"], outputs=["tip"])
    >>> full = modal_plant([10.0, 60.0], 0.01, B=np.array([[1.0], [1.0]]),
    ...                    Cq=np.array([[1.0, 1.0]]), inputs=["force"], outputs=["tip"])
    >>> res = spillover_check(VelocityFeedback(gain=1e-3), design, full)
    >>> res.stable_design, res.stable_evaluation
    (True, True)
    """
    d = closed_loop_modes(design_plant, controller, design_plant)
    e = closed_loop_modes(evaluation_plant, controller, design_plant)
    vd = stability_verdict(d.eigenvalues, zeta_tol=zeta_tol)
    ve = stability_verdict(e.eigenvalues, zeta_tol=zeta_tol)
    rows = []
    if not ve.stable:
        design_fn = closed_loop_modes(design_plant).fn_hz
        law = realize(controller, evaluation_plant, design_plant)
        lam_c, lam_o, labels = _origins(law)
        for p in ve.offending:
            i = int(np.argmin(np.abs(lam_c - p)))
            o = lam_o[i]
            fo = abs(o) / (2 * np.pi)
            residual = labels[i].startswith("plant") and not np.any(
                np.abs(design_fn - fo) <= 0.01 * fo)
            rows.append({"real": float(p.real), "imag": float(p.imag),
                         "fn_hz": float(abs(p) / (2 * np.pi)),
                         "zeta": float(-p.real / abs(p)) if abs(p) > 0 else float("nan"),
                         "continues": labels[i], "open_fn_hz": float(fo),
                         "residual": bool(residual)})
    return SpilloverResult(
        design=d, evaluation=e, stable_design=vd.stable, stable_evaluation=ve.stable,
        max_real_evaluation=float(np.max(e.eigenvalues.real)), verdict_design=vd,
        verdict_evaluation=ve, offending=tuple(rows),
    )
