"""Stability verdicts, loop margins and critical gains of the closed loops.

Every controller gets one verdict, ``"stable"``, ``"marginal"`` or ``"unstable"``, with
the offending poles:

- linear laws (PPF, SRF, VelocityFeedback, LQR): the eigenvalues of the closed loop;
- saturated laws: the eigenvalues of the unsaturated loop (the law near the origin),
  and, when a simulation is given, the energy along the simulated trajectory;
- the Lyapunov switching law: the eigenvalues of the in-layer loop (slope
  ``-u_max / eps``) and the energy along the simulated trajectory.

A pole ``lambda`` is *unstable* if ``Re lambda > tol``, *marginal* if
``|Re lambda| <= tol`` and stable otherwise, with ``tol = max(zeta_tol |lambda|, atol)``,
``zeta_tol = 1e-6`` (a damping ratio below one in a million counts as zero) and
``atol = 1e-9 max |lambda|`` (round-off of a pole at the origin). The loop verdict is the
worst pole's.

Margins are those of the loop transfer function broken at the actuator input,
``L(s) = c (sI - A)^-1 b`` (negative feedback, characteristic equation ``1 + L = 0``).
For a law driving one actuator ``L`` is SISO, also for full-state LQR; a multi-input
LQR has no single loop and :func:`loop_margins` refuses it. Definitions
(those of :func:`control.stability_margins`): phase crossovers are the frequencies
``w >= 0`` where ``L(jw)`` is real and negative, each with the gain margin
``1 / |L(jw)|``; the reported gain margin is the one closest to 1 (0 dB). Gain
crossovers are where ``|L(jw)| = 1``, each with the phase margin
``angle(L) mod 360 - 180`` deg; the reported one has the smallest magnitude. The
*critical gain factor* ``k_c`` multiplies the whole loop (all controller gains): the
closed loop of ``k L`` can only change stability where ``k = 1 / |L(jw_pc)|``; the
intervals between these gains are tested with eigenvalues, and ``k_c`` is the upper end
of the stable interval containing ``k = 1`` (stable loop) or of the nearest stable
interval below it (unstable loop; NaN if none).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ParameterError
from ._controllers import FeedbackLaw
from ._threads import one_blas_thread

__all__ = [
    "VERDICTS",
    "StabilityVerdict",
    "stability_verdict",
    "LoopMargins",
    "loop_margins",
    "closed_loop_stability",
    "trajectory_stability",
    "worst_verdict",
    "stability_summary",
    "SUMMARY_COLUMNS",
]

#: Verdict vocabulary, best to worst.
VERDICTS = ("stable", "marginal", "unstable")

ZETA_TOL = 1e-6
ATOL_REL = 1e-9


def worst_verdict(*verdicts: str) -> str:
    """The worst of the given verdicts (``"unstable"`` > ``"marginal"`` > ``"stable"``)."""
    return VERDICTS[max(VERDICTS.index(v) for v in verdicts)]


def _pole_rows(poles: np.ndarray) -> list[dict]:
    rows = []
    for lam in poles:
        mag = abs(lam)
        rows.append({"real": float(lam.real), "imag": float(lam.imag),
                     "fn_hz": float(mag / (2 * np.pi)),
                     "zeta": float(-lam.real / mag) if mag > 0 else float("nan")})
    return rows


@dataclass(frozen=True)
class StabilityVerdict:
    """Stability of a closed loop with the poles (and trajectory figures) behind it.

    Attributes
    ----------
    verdict : str
        ``"stable"``, ``"marginal"`` or ``"unstable"``.
    eigenvalues : ndarray of complex
        Poles of the (linearised) closed loop (rad/s); empty for a trajectory-only check.
    offending : ndarray of complex
        The unstable and marginal poles, one per conjugate pair (upper half plane).
    max_real_pole : float
        Largest real part of the poles (1/s); NaN without eigenvalues.
    min_zeta : float
        Smallest damping ratio ``-Re/|lambda|`` of the poles (-1 for a real unstable pole).
    source : str
        What decided: ``"eigenvalues"``, ``"linearisation"`` (saturated or switching law
        near the origin), ``"trajectory"`` or ``"linearisation+trajectory"``.
    reason : str
        One line naming the offending pole or the trajectory figure.
    trajectory : dict
        Energy figures of the simulated trajectory (see :func:`trajectory_stability`).

    Examples
    --------
    Returned by :func:`stability_verdict` and the stability checks:

    >>> v = stability_verdict([0.1 + 10j, 0.1 - 10j, -1.0 + 20j, -1.0 - 20j])
    >>> v.verdict, v.offending.tolist(), v.max_real_pole
    ('unstable', [(0.1+10j)], 0.1)
    """

    verdict: str
    eigenvalues: np.ndarray
    offending: np.ndarray
    max_real_pole: float
    min_zeta: float
    source: str = "eigenvalues"
    reason: str = ""
    zeta_tol: float = ZETA_TOL
    trajectory: dict = field(default_factory=dict)

    @property
    def stable(self) -> bool:
        return self.verdict == "stable"

    def offending_table(self):
        """The offending poles as a DataFrame (``real``, ``imag`` in 1/s and rad/s,
        ``fn_hz``, ``zeta``)."""
        import pandas as pd

        return pd.DataFrame(_pole_rows(self.offending), columns=["real", "imag", "fn_hz",
                                                                 "zeta"])

    def to_dict(self) -> dict:
        """JSON-friendly summary (non-finite numbers as None)."""
        def clean(v):
            return None if isinstance(v, float) and not math.isfinite(v) else v

        return {"verdict": self.verdict, "stable": self.stable, "source": self.source,
                "reason": self.reason, "max_real_pole": clean(self.max_real_pole),
                "min_zeta": clean(self.min_zeta),
                "offending": [{k: clean(v) for k, v in r.items()}
                              for r in _pole_rows(self.offending)],
                "trajectory": {k: clean(v) if isinstance(v, float) else v
                               for k, v in self.trajectory.items()}}


def _tolerance(lam: np.ndarray, zeta_tol: float) -> np.ndarray:
    scale = float(np.max(np.abs(lam))) if lam.size else 0.0
    return np.maximum(zeta_tol * np.abs(lam), ATOL_REL * scale)


def stability_verdict(eigenvalues, *, zeta_tol: float = ZETA_TOL,
                      source: str = "eigenvalues") -> StabilityVerdict:
    """Classify closed-loop poles (rad/s) as stable, marginal or unstable.

    Parameters
    ----------
    eigenvalues : array of complex
        Closed-loop poles (rad/s).
    zeta_tol : float
        Marginal tolerance as a damping ratio: ``|Re lambda| <= zeta_tol |lambda|`` (or
        ``<= 1e-9 max |lambda|`` near the origin) is marginal.
    source : str
        Stored in the verdict (what the poles are).

    Examples
    --------
    >>> stability_verdict([-1 + 10j, -1 - 10j]).verdict
    'stable'
    >>> stability_verdict([0.1 + 10j]).verdict, stability_verdict([10j]).verdict
    ('unstable', 'marginal')
    """
    if not (np.isfinite(zeta_tol) and 0 <= zeta_tol < 1):
        raise ParameterError(f"zeta_tol must be in [0, 1), got {zeta_tol}")
    lam = np.asarray(eigenvalues, dtype=complex).ravel()
    if lam.size == 0:
        raise ParameterError("stability_verdict needs at least one eigenvalue")
    if not np.all(np.isfinite(lam)):
        raise ParameterError("closed-loop eigenvalues are not finite (NaN or inf in A)")
    tol = _tolerance(lam, zeta_tol)
    unstable = lam.real > tol
    marginal = np.abs(lam.real) <= tol
    bad = (unstable | marginal) & (lam.imag >= -tol)  # one per conjugate pair
    offending = lam[bad]
    offending = offending[np.argsort(-offending.real, kind="stable")]
    verdict = "unstable" if unstable.any() else "marginal" if marginal.any() else "stable"
    mag = np.abs(lam)
    with np.errstate(invalid="ignore", divide="ignore"):
        zeta = np.where(mag > 0, -lam.real / np.where(mag > 0, mag, 1.0), 0.0)
    reason = ""
    if offending.size:
        p = offending[0]
        p_tol = max(zeta_tol * abs(p), ATOL_REL * float(np.max(np.abs(lam))))
        what = "real pole" if abs(p.imag) <= p_tol else "pole pair"
        reason = (f"{verdict}: {what} at {p.real:+.4g}{p.imag:+.4g}j 1/s "
                  f"({abs(p) / (2 * np.pi):.4g} Hz, zeta {-p.real / abs(p) if abs(p) else 0:.3g})"
                  + (f" and {offending.size - 1} more" if offending.size > 1 else ""))
    return StabilityVerdict(
        verdict=verdict, eigenvalues=lam, offending=offending,
        max_real_pole=float(np.max(lam.real)), min_zeta=float(np.min(zeta)),
        source=source, reason=reason, zeta_tol=zeta_tol,
    )


def _law(controller, plant, design_plant) -> FeedbackLaw:
    from ._simulate import realize

    law = realize(controller, plant, design_plant)
    if law is None:
        raise ParameterError("a stability check needs a controller, got None (open loop)")
    return law


@one_blas_thread
def closed_loop_stability(plant, controller, design_plant=None, *,
                          zeta_tol: float = ZETA_TOL) -> StabilityVerdict:
    """Verdict from the closed-loop eigenvalues of ``controller`` on ``plant``.

    For a saturated or switching law the loop is linearised at the origin
    (:meth:`FeedbackLaw.linearized_matrix`): this decides local stability only; use
    :func:`trajectory_stability` (or :func:`mvtk.control.compare_controllers`) for the
    behaviour along a trajectory.

    Examples
    --------
    >>> from mvtk.control import PPF, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> closed_loop_stability(plant, PPF([(10.0, 0.1, 0.5)])).verdict
    'stable'
    >>> closed_loop_stability(plant, PPF([(10.0, 0.1, 1.5)])).verdict     # G > 1
    'unstable'
    """
    law = _law(controller, plant, design_plant)
    source = "eigenvalues" if law.is_linear else "linearisation"
    return stability_verdict(np.linalg.eigvals(law.linearized_matrix()), zeta_tol=zeta_tol,
                             source=source)


# ------------------------------------------------------------------------- margins
@dataclass(frozen=True)
class LoopMargins:
    """Classical margins of the loop ``L(jw)`` broken at the actuator input.

    Attributes
    ----------
    gain_margin : float
        ``1 / |L(jw_pc)|`` at the phase crossover closest to 0 dB (inf: none).
    gain_margin_db : float
        ``20 log10(gain_margin)``.
    phase_margin_deg : float
        Phase margin (deg) at the gain crossover with the smallest absolute margin (inf: none).
    w_pc, w_gc : float
        Frequencies (rad/s) of the reported phase and gain crossovers (NaN: none).
    critical_gain_factor : float
        Loop-gain multiplier at the edge of the stable gain interval (see module
        docstring): > 1 for a stable loop (inf if no gain destabilises it), < 1 for an
        unstable loop that a lower gain stabilises, NaN if none does.
    lower_gain_factor : float
        Lower end of the stable interval containing ``k = 1`` (0: any lower gain is
        stable; NaN for an unstable loop).
    phase_crossovers, gain_crossovers : ndarray
        All crossover frequencies (rad/s); ``all_gain_margins``, ``all_phase_margins_deg``
        the margins there.

    Examples
    --------
    Returned by :func:`loop_margins`:

    >>> from mvtk.control import VelocityFeedback, loop_margins, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> m = loop_margins(plant, VelocityFeedback(gain=1e-3))
    >>> m.gain_margin_db, m.critical_gain_factor
    (inf, inf)
    """

    gain_margin: float
    gain_margin_db: float
    phase_margin_deg: float
    w_pc: float
    w_gc: float
    critical_gain_factor: float
    lower_gain_factor: float
    phase_crossovers: np.ndarray
    gain_crossovers: np.ndarray
    all_gain_margins: np.ndarray
    all_phase_margins_deg: np.ndarray

    def to_dict(self) -> dict:
        def clean(v):
            return None if not math.isfinite(v) else float(v)

        return {"gain_margin_db": clean(self.gain_margin_db),
                "phase_margin_deg": clean(self.phase_margin_deg),
                "w_pc_rad_s": clean(self.w_pc), "w_gc_rad_s": clean(self.w_gc),
                "critical_gain_factor": clean(self.critical_gain_factor),
                "lower_gain_factor": clean(self.lower_gain_factor)}


class _Residues:
    """``L(s) = c (sI - A)^-1 b`` on many frequencies.

    Pole-residue form when the eigenvectors are well conditioned (O(n) per frequency);
    otherwise (nearly defective A, e.g. a PPF filter with the damping of the mode it is
    tuned on) back substitution on the complex Schur form, vectorised over frequencies
    (O(n^2) per frequency). Crossovers are verified by direct solves (:meth:`exact`).
    """

    def __init__(self, A, b, c):
        import scipy.linalg

        self.A, self.b, self.c = A, b[:, 0], c[0]
        lam, V = np.linalg.eig(A)
        self.lam = lam
        self.ok = np.linalg.cond(V) < 1e10
        if self.ok:
            self.res = (self.c @ V) * np.linalg.solve(V, self.b)
        else:
            T, Z = scipy.linalg.schur(A.astype(complex), output="complex")
            self.T, self.g, self.h = T, Z.conj().T @ self.b, self.c @ Z

    def __call__(self, w: np.ndarray) -> np.ndarray:
        w = np.atleast_1d(np.asarray(w, dtype=float))
        out = np.empty(w.size, dtype=complex)
        for i in range(0, w.size, 4096):  # bounded memory
            s = 1j * w[i:i + 4096]
            if self.ok:
                out[i:i + 4096] = (self.res[None, :] / (s[:, None] - self.lam[None, :])).sum(1)
            else:
                out[i:i + 4096] = self._schur(s)
        return out

    def _schur(self, s: np.ndarray) -> np.ndarray:
        T, n = self.T, self.T.shape[0]
        y = np.zeros((s.size, n), dtype=complex)
        for k in range(n - 1, -1, -1):  # (sI - T) y = g, T upper triangular
            y[:, k] = (self.g[k] + y[:, k + 1:] @ T[k, k + 1:]) / (s - T[k, k])
        return y @ self.h

    def exact(self, w: np.ndarray) -> np.ndarray:
        """Direct solves (no diagonalisation)."""
        n = self.A.shape[0]
        eye = np.eye(n)
        return np.array([self.c @ np.linalg.solve(1j * wk * eye - self.A, self.b)
                         for wk in np.atleast_1d(w)])


def _grid(lam: np.ndarray) -> np.ndarray:
    mag = np.abs(lam)
    nz = mag[mag > 0]
    lo = 1e-3 * (nz.min() if nz.size else 1.0)
    hi = 1e3 * (nz.max() if nz.size else 1.0)
    parts = [np.logspace(np.log10(lo), np.log10(hi), int(100 * np.log10(hi / lo)) + 2)]
    offs = np.concatenate([-np.logspace(-4, 0, 25)[::-1], [0.0], np.logspace(-4, 0, 25)])
    for p in lam[lam.imag > 0]:
        wd, sig = p.imag, max(abs(p.real), 1e-12 * abs(p))
        parts.append(wd + sig * np.linspace(-20, 20, 81))
        parts.append(wd * (1 + 0.3 * offs))
    w = np.concatenate(parts)
    return np.unique(w[w > 0])


def _refine(f, w: np.ndarray, v: np.ndarray) -> np.ndarray:
    from scipy.optimize import brentq

    idx = np.nonzero(np.signbit(v[:-1]) != np.signbit(v[1:]))[0]
    out = []
    for i in idx:
        if v[i] == 0.0:
            out.append(w[i])
            continue
        try:
            out.append(brentq(f, w[i], w[i + 1], xtol=1e-14 * w[i + 1], rtol=1e-13))
        except ValueError:
            continue
    return np.array(out)


def _margins_from_loop(A, b, c, stable_at) -> LoopMargins:
    L = _Residues(A, b, c)
    w = _grid(L.lam)
    Lw = L(w)
    # phase crossovers: Im L = 0 with Re L < 0 (sign changes of Im L, refined)
    wpc = _refine(lambda x: L(np.array([x]))[0].imag, w, Lw.imag)
    Lpc = L.exact(wpc) if wpc.size else np.zeros(0, complex)
    keep = (Lpc.real < 0) & (np.abs(Lpc.imag) <= 1e-3 * np.abs(Lpc))  # not a pole jump
    wpc, Lpc = wpc[keep], Lpc[keep]
    L0 = None
    try:
        L0 = float((-c @ np.linalg.solve(A, b))[0, 0])
    except np.linalg.LinAlgError:
        pass
    if L0 is not None and np.isfinite(L0) and L0 < 0:
        wpc, Lpc = np.concatenate([[0.0], wpc]), np.concatenate([[L0 + 0j], Lpc])
    with np.errstate(divide="ignore"):
        gms = 1.0 / np.abs(Lpc)
    # gain crossovers: |L| = 1
    wgc = _refine(lambda x: np.log(abs(L(np.array([x]))[0])), w, np.log(np.abs(Lw)))
    Lgc = L.exact(wgc) if wgc.size else np.zeros(0, complex)
    keep = np.abs(np.abs(Lgc) - 1.0) <= 1e-3
    wgc, Lgc = wgc[keep], Lgc[keep]
    pms = np.remainder(np.angle(Lgc, deg=True), 360.0) - 180.0
    gm, wp = float("inf"), float("nan")
    finite = np.isfinite(gms) & (gms > 0)
    if finite.any():
        i = np.argmin(np.abs(np.log(np.where(finite, gms, 1e300))))
        gm, wp = float(gms[i]), float(wpc[i])
    pm, wg = float("inf"), float("nan")
    if pms.size:
        i = int(np.argmin(np.abs(pms)))
        pm, wg = float(pms[i]), float(wgc[i])
    # critical gain factor from the stability-change gains, intervals tested by eigenvalues
    ks = np.unique(gms[finite])
    k_up, k_lo = _stable_interval(ks, stable_at(1.0), stable_at)
    with np.errstate(divide="ignore"):
        gm_db = 20 * np.log10(gm) if gm > 0 else -np.inf
    return LoopMargins(
        gain_margin=gm, gain_margin_db=float(gm_db), phase_margin_deg=pm, w_pc=wp,
        w_gc=wg, critical_gain_factor=k_up, lower_gain_factor=k_lo,
        phase_crossovers=wpc, gain_crossovers=wgc, all_gain_margins=gms,
        all_phase_margins_deg=pms,
    )


def _stable_interval(ks: np.ndarray, nominal_stable: bool, stable_at) -> tuple[float, float]:
    above = ks[ks > 1.0]
    below = ks[ks < 1.0][::-1]  # descending
    if nominal_stable:
        lo = float(below[0]) if below.size else 0.0
        # a tangent crossing does not destabilise: step up until the loop is unstable
        edges = list(above) + [np.inf]
        for j, k in enumerate(edges[:-1]):
            nxt = edges[j + 1]
            probe = k * 1.001 if not np.isfinite(nxt) else math.sqrt(k * nxt)
            if not stable_at(probe):
                return float(k), lo
        return float("inf"), lo
    # unstable: nearest stable interval below k = 1
    edges = list(below) + [0.0]
    for j, k in enumerate(edges[:-1]):
        nxt = edges[j + 1]
        probe = 0.5 * k if nxt == 0.0 else math.sqrt(k * nxt)
        if stable_at(probe):
            return float(k), float("nan")
    return float("nan"), float("nan")


@one_blas_thread
def loop_margins(plant, controller, design_plant=None, *,
                 zeta_tol: float = ZETA_TOL) -> LoopMargins:
    """Gain and phase margins and the critical gain factor of a controller's loop.

    The loop is broken at the actuator input (:meth:`FeedbackLaw.loop`); saturated and
    switching laws are linearised at the origin. See the module docstring for the
    definitions (those of :func:`control.stability_margins`).

    Returns
    -------
    LoopMargins

    Examples
    --------
    Collocated velocity feedback never loses stability (infinite gain margin):

    >>> from mvtk.control import VelocityFeedback, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> m = loop_margins(plant, VelocityFeedback(gain=1e-3))
    >>> m.gain_margin, round(m.phase_margin_deg, 1)
    (inf, 108.6)
    """
    law = _law(controller, plant, design_plant)
    if len(law.actuator_indices) > 1:
        raise ParameterError(
            f"loop_margins: the law drives {len(law.actuator_indices)} inputs; gain and "
            "phase margins are those of a loop broken at one input (use "
            "closed_loop_stability for the multi-input loop)")
    A, b, c = law.loop()

    def stable_at(k: float) -> bool:
        lam = np.linalg.eigvals(A - k * (b @ c))
        return stability_verdict(lam, zeta_tol=zeta_tol).stable

    return _margins_from_loop(A, b, c, stable_at)


# ---------------------------------------------------------------------- trajectory
def _energy(plant, states: np.ndarray) -> np.ndarray:
    """Mechanical energy ``q'Mq'/2 + q'Kq/2`` per sample (``|x|^2 / 2`` for a
    state-space plant); ``states`` has shape (n_states_total, n_t)."""
    from ._second_order import SecondOrderSystem

    if isinstance(plant, SecondOrderSystem):
        n = plant.n_coords
        q, v = states[:n], states[n:2 * n]
        return 0.5 * (np.einsum("it,ij,jt->t", v, plant.M, v)
                      + np.einsum("it,ij,jt->t", q, plant.K, q))
    n = plant.n_states
    return 0.5 * np.sum(states[:n] ** 2, axis=0)


@one_blas_thread
def trajectory_stability(plant, simulation, controller=None, design_plant=None, *,
                         decay_min: float = 0.01, growth_max: float = 1e-3,
                         zeta_tol: float = ZETA_TOL, forced: bool = False,
                         ) -> StabilityVerdict:
    """Verdict along a simulated trajectory (nonlinear laws), in the same vocabulary.

    The plant's mechanical energy ``E(t)`` (``q'Mq'/2 + q'Kq/2``) is computed from the
    simulated states. With ``E1`` / ``E4`` the largest energy in the first / last
    quarter of the record:

    - any non-finite state, or ``E4 > (1 + growth_max) E1``: ``"unstable"`` (energy
      grows along the trajectory);
    - ``E4 > (1 - decay_min) E1`` or ``E4 > (1 - decay_min) E3`` (``E3``: third
      quarter): ``"marginal"`` (no decay: a limit cycle or a deflection held by the
      saturated actuator);
    - otherwise, or when ``E4`` is below ``1e-12`` of the largest energy (decayed to
      round-off), ``"stable"`` (bounded decay).

    With ``forced=True`` (a persistent disturbance: energy need not decay) only
    divergence counts: non-finite states or ``E4 > 1e3 E1`` are ``"unstable"``.
    When ``controller`` is given the verdict is combined (worst of both) with the
    eigenvalues of the loop linearised at the origin (:func:`closed_loop_stability`),
    which decide the local stability the trajectory cannot show.

    The figures ``energy_ratio`` (``E4 / E1``), ``energy_ratio_end`` (``E4 / E3``),
    ``energy_rise`` (largest rise of ``E``
    above its running minimum, relative to ``E(0)``: 0 for a non-increasing energy, as
    the Lyapunov law guarantees in continuous time) and ``t_nonfinite_s`` are in
    ``verdict.trajectory``.

    Parameters
    ----------
    plant : SecondOrderSystem or StateSpace
    simulation : xarray.Dataset
        Output of :func:`mvtk.control.simulate` (``states`` with a ``time`` coord).
    controller : controller, optional
    decay_min, growth_max : float
        Relative thresholds above.
    forced : bool
        The record is driven by a persistent disturbance.

    Examples
    --------
    The energy of a released mode under velocity feedback decays along the simulation:

    >>> from mvtk.control import VelocityFeedback, modal_plant, release_state, simulate
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> vf = VelocityFeedback(gain=1e-3)
    >>> sim = simulate(plant, vf, t_end=4.0, fs_out=200.0,
    ...                initial=release_state(plant, 1, "tip", 1e-3))
    >>> trajectory_stability(plant, sim, vf).verdict
    'stable'
    """
    if not (0 < decay_min < 1 and growth_max >= 0):
        raise ParameterError(
            f"expected 0 < decay_min < 1 and growth_max >= 0, got {decay_min}, {growth_max}"
        )
    try:
        X = np.asarray(simulation["states"].values, dtype=float)
        t = np.asarray(simulation["time"].values, dtype=float)
    except (KeyError, TypeError, AttributeError, IndexError, ValueError) as err:
        raise ParameterError(
            "trajectory_stability needs the Dataset of mvtk.control.simulate (variable "
            f"'states', coord 'time'), got {type(simulation).__name__}"
        ) from err
    if X.ndim != 2 or X.shape[1] != t.size or t.size < 8:
        raise ParameterError(
            f"states must be (state, time) with at least 8 samples, got shape {X.shape}"
        )
    finite = np.all(np.isfinite(X), axis=0)
    info: dict = {"energy_ratio": float("nan"), "energy_rise": float("nan"),
                  "t_nonfinite_s": float("nan")}
    if not finite.all():
        i = int(np.argmin(finite))
        info["t_nonfinite_s"] = float(t[i])
        verdict, reason = "unstable", f"unstable: the state is not finite from t = {t[i]:.4g} s"
    else:
        with np.errstate(over="ignore", invalid="ignore"):
            E = _energy(plant, X)
        q = max(t.size // 4, 1)
        E1, E3, E4 = (float(np.max(E[:q])), float(np.max(E[-2 * q:-q])),
                      float(np.max(E[-q:])))
        ratio = E4 / E1 if E1 > 0 else (0.0 if E4 == 0 else float("inf"))
        ratio_end = E4 / E3 if E3 > 0 else (0.0 if E4 == 0 else float("inf"))
        run_min = np.minimum.accumulate(E)
        rise = float(np.max(E - run_min) / E[0]) if E[0] > 0 else float("nan")
        info.update(energy_ratio=float(ratio), energy_ratio_end=float(ratio_end),
                    energy_rise=rise)
        decayed = E4 <= 1e-12 * float(np.max(E))  # at round-off: nothing left to judge
        if not np.isfinite(ratio) or (forced and ratio > 1e3):
            verdict = "unstable"
        elif forced or decayed:
            verdict = "stable"
        elif ratio > 1 + growth_max:
            verdict = "unstable"
        elif ratio > 1 - decay_min or ratio_end > 1 - decay_min:
            verdict = "marginal"
        else:
            verdict = "stable"
        reason = "" if verdict == "stable" else (
            f"{verdict}: the largest energy of the last quarter of the record is "
            f"{ratio:.4g} times that of the first and {ratio_end:.4g} times that of the "
            "third" + (" (energy grows)" if verdict == "unstable" else " (no decay)"))
    traj = StabilityVerdict(
        verdict=verdict, eigenvalues=np.zeros(0, complex), offending=np.zeros(0, complex),
        max_real_pole=float("nan"), min_zeta=float("nan"), source="trajectory",
        reason=reason, zeta_tol=zeta_tol, trajectory=info,
    )
    if controller is None:
        return traj
    lin = closed_loop_stability(plant, controller, design_plant, zeta_tol=zeta_tol)
    combined = worst_verdict(lin.verdict, traj.verdict)
    reasons = [r for r in (lin.reason, traj.reason) if r]
    return StabilityVerdict(
        verdict=combined, eigenvalues=lin.eigenvalues, offending=lin.offending,
        max_real_pole=lin.max_real_pole, min_zeta=lin.min_zeta,
        source=f"{lin.source}+trajectory", reason="; ".join(reasons), zeta_tol=zeta_tol,
        trajectory=info,
    )


def _scalar_gain(controller) -> float:
    """The controller's own scalar gain (PPF/SRF with one filter, VelocityFeedback)."""
    targets = getattr(controller, "targets", None)
    if targets is not None:
        return float(targets[0][2]) if len(targets) == 1 else float("nan")
    g = getattr(controller, "gain", None)
    return float(g) if isinstance(g, int | float) else float("nan")


#: Columns of :func:`stability_summary` (and of the comparison table).
SUMMARY_COLUMNS = ("stable", "verdict", "max_real_pole", "min_closed_loop_zeta",
                   "gain_margin_db", "phase_margin_deg", "critical_gain_factor",
                   "critical_gain", "stability_source", "stability_reason")


@one_blas_thread
def stability_summary(plant, controller, simulation=None, design_plant=None, *,
                      forced: bool = False, zeta_tol: float = ZETA_TOL) -> dict:
    """One row of stability figures for a controller (the columns of the comparison).

    Parameters
    ----------
    plant : SecondOrderSystem or StateSpace
    controller : controller object
    simulation : xarray.Dataset, optional
        Its simulation (:func:`mvtk.control.simulate`); used for the saturated and
        switching laws (energy along the trajectory, :func:`trajectory_stability`).
        Linear laws are decided by their eigenvalues.
    forced : bool
        The simulation is driven by a persistent disturbance or noise.

    Returns
    -------
    dict
        ``stable`` (bool), ``verdict``, ``max_real_pole`` (1/s), ``min_closed_loop_zeta``,
        ``gain_margin_db``, ``phase_margin_deg``, ``critical_gain_factor`` (multiplier on
        the loop, see :func:`loop_margins`), ``critical_gain`` (the same in the
        controller's gain units for single-gain controllers, else NaN),
        ``stability_source`` and ``stability_reason``. Margins of saturated and
        switching laws are those of the loop linearised at the origin.

    Examples
    --------
    >>> from mvtk.control import VelocityFeedback, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> row = stability_summary(plant, VelocityFeedback(gain=1e-3))
    >>> row["verdict"], round(row["min_closed_loop_zeta"], 4)
    ('stable', 0.0414)
    """
    law = _law(controller, plant, design_plant)
    if law.is_linear or simulation is None:
        v = closed_loop_stability(plant, law, zeta_tol=zeta_tol)
    else:
        v = trajectory_stability(plant, simulation, law, forced=forced, zeta_tol=zeta_tol)
    m = loop_margins(plant, law, zeta_tol=zeta_tol)
    return {"stable": v.stable, "verdict": v.verdict, "max_real_pole": v.max_real_pole,
            "min_closed_loop_zeta": v.min_zeta, "gain_margin_db": m.gain_margin_db,
            "phase_margin_deg": m.phase_margin_deg,
            "critical_gain_factor": m.critical_gain_factor,
            "critical_gain": m.critical_gain_factor * _scalar_gain(controller),
            "stability_source": v.source, "stability_reason": v.reason}
