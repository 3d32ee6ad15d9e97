"""Stability verdicts, loop margins and critical gains (issue 16 item 2).

External truths: the single-mode Routh-Hurwitz limits of PHYSICS.md section 4 (PPF
``G < 1``, SRF ``2 zf (wf^2 - w^2) / (w^2 wf)``), Kalman's LQR margins (phase margin of
at least 60 deg, infinite upward gain margin; Anderson & Moore, Optimal Control, 1990,
section 5.4), python-control's ``stability_margins`` on the same loops, the bisection
of ``critical_gain`` on the closed-loop eigenvalues, and the characteristic equation
``1 - K(s) G(s) = 0`` of a plant with feedthrough.
"""

import math

import numpy as np
import pytest
import xarray as xr

from mvtk.control import (
    LQR,
    PPF,
    SRF,
    LyapunovBangBang,
    Scenario,
    StructuralPlant,
    VelocityFeedback,
    added_damping,
    cantilever_modal_plant,
    closed_loop,
    closed_loop_stability,
    compare_controllers,
    critical_gain,
    loop_margins,
    modal_plant,
    release_state,
    simulate,
    spillover_check,
    srf_gain_limit,
    stability_summary,
    stability_verdict,
    trajectory_stability,
)
from mvtk.control._compare import switching_peak
from mvtk.control._simulate import realize
from mvtk.errors import ParameterError

F1 = 13.26


@pytest.fixture(scope="module")
def plant3():
    return cantilever_modal_plant(3)


# ------------------------------------------------------------ issue 16 symptom
def test_unstable_ppf_is_never_reported_as_added_damping(plant3):
    """Issue 16: PPF gain 5 (above the limit 1) gave 'added damping 0.085' while the loop
    has a real pole at +79.4 1/s."""
    ad = added_damping(plant3, PPF([(F1, 0.3, 5.0)], sensor="tip"))
    assert ad["verdict"] == "unstable" and ad["stable"] is False
    assert math.isnan(ad["added"])
    assert ad["max_real_pole"] == pytest.approx(79.4, abs=0.05)
    # zeta_closed is the worst pole's (real, unstable: -1): a zeta >= zeta_min check fails
    assert ad["zeta_closed"] == pytest.approx(-1.0)
    assert ad["zeta_closed"] < 0.005
    assert "+79.4" in ad["reason"] and "real pole" in ad["reason"]
    ok = added_damping(plant3, PPF([(F1, 0.3, 0.5)], sensor="tip"))
    assert ok["verdict"] == "stable" and ok["added"] > 0.05


def test_comparison_table_fails_the_unstable_gain(plant3):
    sc = Scenario(output="tip", t_end=1.0, fs_out=500.0)
    res = compare_controllers(plant3, {"PPF 0.5": PPF([(F1, 0.3, 0.5)], sensor="tip"),
                                       "PPF 5": PPF([(F1, 0.3, 5.0)], sensor="tip")}, sc)
    df = res.to_dataframe()
    assert list(df["stable"]) == [True, True, False]
    bad = df.loc["PPF 5"]
    assert bad["verdict"] == "unstable" and math.isnan(bad["added_damping1"])
    assert bad["zeta1"] < 0 and bad["max_real_pole"] > 79
    # critical gain: the PPF limit G = 1 (constant term w^2 wf^2 (1 - G))
    assert bad["critical_gain"] == pytest.approx(1.0, rel=1e-9)
    assert df.loc["PPF 0.5", "critical_gain"] == pytest.approx(1.0, rel=1e-9)
    assert df.loc["PPF 0.5", "gain_margin_db"] == pytest.approx(20 * np.log10(2), rel=1e-9)
    rows = res.to_dict()["rows"]
    assert rows[2]["stable"] is False and rows[2]["added_damping1"] is None
    import json

    back = json.loads(json.dumps(res.to_dict()))  # the CLI's --json path
    assert back["rows"][2]["verdict"] == "unstable"
    assert back["rows"][2]["stability_reason"].startswith("unstable: real pole at +79.4")


# ------------------------------------------------------------------- verdicts
def test_verdict_classification_of_known_poles():
    assert stability_verdict([-1 + 10j, -1 - 10j, -5]).verdict == "stable"
    v = stability_verdict([1e-9 + 10j, 1e-9 - 10j, -5])  # |Re| < 1e-6 |lambda|
    assert v.verdict == "marginal" and v.offending.size == 1
    assert v.offending[0] == pytest.approx(1e-9 + 10j)
    v = stability_verdict([0.5 + 10j, 0.5 - 10j, -2.0, 3.0])
    assert v.verdict == "unstable" and v.max_real_pole == 3.0
    np.testing.assert_allclose(v.offending, [3.0, 0.5 + 10j])  # worst first, one per pair
    assert v.min_zeta == pytest.approx(-1.0)
    t = v.offending_table()
    assert list(t.columns) == ["real", "imag", "fn_hz", "zeta"]
    assert t["fn_hz"].iloc[1] == pytest.approx(abs(0.5 + 10j) / (2 * np.pi))
    d = v.to_dict()
    assert d["verdict"] == "unstable" and d["stable"] is False and len(d["offending"]) == 2
    # the marginal tolerance is a damping ratio: zeta 1e-5 is stable, 1e-7 is marginal
    assert stability_verdict([-1e-5 * 10 + 10j]).verdict == "stable"
    assert stability_verdict([-1e-7 * 10 + 10j]).verdict == "marginal"
    assert stability_verdict([-1e-7 * 10 + 10j], zeta_tol=1e-8).verdict == "stable"
    # an integrator (pole at the origin, round-off) is marginal
    assert stability_verdict([1e-13, -100.0 + 2000j]).verdict == "marginal"


@pytest.mark.parametrize("bad, match", [([], "at least one"), ([np.nan], "not finite")])
def test_verdict_bad_input(bad, match):
    with pytest.raises(ParameterError, match=match):
        stability_verdict(bad)


def test_verdict_bad_tolerance():
    with pytest.raises(ParameterError, match="zeta_tol must be in"):
        stability_verdict([-1.0], zeta_tol=2.0)


def test_undamped_open_loop_is_marginal_and_modal_properties_agree(plant3):
    p0 = modal_plant([F1, 80.0], 0.0, [[1.0], [1.0]], [[1.0, 1.0]])
    from mvtk.control import closed_loop_modes

    assert closed_loop_modes(p0).verdict.verdict == "marginal"
    assert not closed_loop_modes(p0).stable
    assert closed_loop_modes(plant3).stable


# -------------------------------------------------------------------- margins
LAWS = {
    "PPF": lambda: PPF([(F1, 0.5, 0.1)], sensor="tip"),
    "PPF unstable": lambda: PPF([(F1, 0.3, 5.0)], sensor="tip"),
    "SRF": lambda: SRF([(1.3 * F1, 0.5, 0.16 * srf_gain_limit(F1, 1.3 * F1, 0.5))],
                       sensor="tip"),
    "velocity collocated": lambda: VelocityFeedback(1e-3, sensor="patch_rotation"),
    "velocity non-collocated": lambda: VelocityFeedback(1e-3, sensor="tip"),
    "LQR": lambda: LQR(R=1e-3),
    # filter with the damping of the mode it is tuned on: a nearly defective loop matrix
    # (eigenvector condition ~1e10), evaluated on its complex Schur form
    "PPF defective": lambda: PPF([(F1, cantilever_modal_plant(3).meta["zeta"][0], 0.5)],
                                 sensor="tip"),
}


@pytest.mark.parametrize("name", list(LAWS))
def test_margins_match_python_control(plant3, name):
    control = pytest.importorskip("control")
    ctrl = LAWS[name]()
    A, b, c = realize(ctrl, plant3).loop()
    gm, pm, _, wpc, wgc, _ = control.stability_margins(control.ss(A, b, c, 0))
    m = loop_margins(plant3, ctrl)
    assert m.gain_margin == pytest.approx(gm, rel=1e-7)
    assert m.phase_margin_deg == pytest.approx(pm, rel=1e-7, abs=1e-7)
    if math.isfinite(gm):
        assert m.w_pc == pytest.approx(wpc, rel=1e-7, abs=1e-9)
    assert m.w_gc == pytest.approx(wgc, rel=1e-7)
    # all crossovers python-control finds below 1e4 rad/s are found too (except those
    # where |L| vanishes, e.g. SRF at w = 0: gain margin 1/0)
    gms_all, pms_all, _, wpc_all, wgc_all, _ = control.stability_margins(
        control.ss(A, b, c, 0), returnall=True)
    wpc_all, gms_all = np.asarray(wpc_all), np.asarray(gms_all)
    for w in wpc_all[(wpc_all < 1e4) & (gms_all < 1e10)]:
        assert np.min(np.abs(m.phase_crossovers - w)) <= 1e-6 * max(w, 1.0)
    for w in np.asarray(wgc_all):
        assert np.min(np.abs(m.gain_crossovers - w)) <= 1e-6 * w


def test_loop_closes_to_the_closed_loop_matrix(plant3):
    for make in LAWS.values():
        law = realize(make(), plant3)
        A, b, c = law.loop()
        np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(A - b @ c)),
                                   np.sort_complex(np.linalg.eigvals(law.closed_loop_matrix())),
                                   rtol=1e-9)


@pytest.mark.parametrize("kind", ["PPF", "SRF"])
def test_loop_of_a_feedthrough_plant_is_minus_k_times_g(kind):
    """Static-correction plant (D != 0 on the sensor): L(jw) = -K(jw) G(jw) with
    G = C (jwI - A)^-1 B + D, and the loop closes to the closed-loop poles."""
    base = cantilever_modal_plant(1)
    D = np.array([[-3e-6], [0.0], [0.0]])
    p = StructuralPlant(base.M, base.C, base.K, base.B, base.Cq, base.Cv,
                        inputs=base.inputs, outputs=base.outputs, D=D)
    ff, zf = 1.4 * F1, 0.4
    wf = 2 * np.pi * ff
    ctrl = (PPF if kind == "PPF" else SRF)([(ff, zf, 0.05 if kind == "SRF" else 5e-3)],
                                          sensor="tip")
    law = realize(ctrl, p)
    g = law.meta["physical_gains"][0]
    ss = p.to_state_space()
    A, b, c = law.loop()
    for w in (3.0, 80.0, 2 * np.pi * ff, 900.0):
        s = 1j * w
        G = (ss.C[0] @ np.linalg.solve(s * np.eye(2) - ss.A, ss.B[:, 0])) + D[0, 0]
        K = g * wf**2 / (s**2 + 2 * zf * wf * s + wf**2) * (1 if kind == "PPF" else -s)
        L = (c @ np.linalg.solve(s * np.eye(A.shape[0]) - A, b))[0, 0]
        assert L == pytest.approx(-K * G, rel=1e-9)
    np.testing.assert_allclose(np.sort_complex(np.linalg.eigvals(A - b @ c)),
                               np.sort_complex(closed_loop(p, ctrl).poles()), rtol=1e-9)


@pytest.mark.parametrize("ff, zf", [(F1, 0.3), (1.5 * F1, 0.1), (0.7 * F1, 0.6)])
def test_ppf_critical_gain_is_one_on_a_single_mode(ff, zf):
    p = modal_plant([F1], 0.01, [[0.37]], [[2.5]], inputs=["u"], outputs=["y"])
    for g in (0.2, 0.8):
        m = loop_margins(p, PPF([(ff, zf, g)]))
        assert m.critical_gain_factor * g == pytest.approx(1.0, rel=1e-9)
        assert m.gain_margin_db == pytest.approx(-20 * np.log10(g), rel=1e-9)
        assert m.w_pc == 0.0  # L(0) = -G: the phase crossover is the static one


@pytest.mark.parametrize("ratio, zf", [(1.3, 0.5), (2.0, 0.2)])
def test_srf_critical_gain_matches_routh_hurwitz(ratio, zf):
    """Undamped mode (open loop marginal): the stable interval starts at 0 and ends at the
    closed-form SRF limit."""
    p = modal_plant([F1], 0.0, [[1.0]], [[1.0]], inputs=["u"], outputs=["y"])
    g = 0.3 * srf_gain_limit(F1, ratio * F1, zf)
    s = stability_summary(p, SRF([(ratio * F1, zf, g)]))
    assert s["stable"]
    assert s["critical_gain"] == pytest.approx(srf_gain_limit(F1, ratio * F1, zf), rel=1e-7)


def test_critical_gain_factor_matches_eigenvalue_bisection(plant3):
    """Multi-mode loops: the critical gain from the phase crossovers equals the bisection
    on the largest real part of the closed-loop eigenvalues."""
    srf = SRF([(1.3 * F1, 0.5, 0.001)], sensor="tip")
    m = loop_margins(plant3, srf)
    assert m.critical_gain_factor * 0.001 == pytest.approx(
        critical_gain(plant3, srf, g_max=1.0, rtol=1e-10), rel=1e-6)
    vel = VelocityFeedback(1e-5, sensor="tip")  # non-collocated: destabilises mode 2
    m = loop_margins(plant3, vel)
    assert m.critical_gain_factor * 1e-5 == pytest.approx(
        critical_gain(plant3, vel, g_max=1.0, rtol=1e-10), rel=1e-6)


def test_unstable_loop_critical_factor_points_to_the_stable_gains(plant3):
    m = loop_margins(plant3, PPF([(F1, 0.3, 5.0)], sensor="tip"))
    assert m.critical_gain_factor == pytest.approx(0.2, rel=1e-9)
    assert math.isnan(m.lower_gain_factor)
    below = PPF([(F1, 0.3, 5.0 * 0.2 * 0.999)], sensor="tip")
    assert closed_loop_stability(plant3, below).verdict == "stable"


def test_lqr_has_kalman_margins():
    """LQR (single input): |1 + L(jw)| >= 1, hence phase margin >= 60 deg and no gain
    increase destabilises the loop."""
    p = cantilever_modal_plant(4)
    for R in (1e-9, 1e-6, 1e-3):
        m = loop_margins(p, LQR(R=R))
        assert m.phase_margin_deg >= 60.0 - 1e-6
        assert math.isinf(m.critical_gain_factor) and math.isinf(m.gain_margin)
        A, b, c = realize(LQR(R=R), p).loop()
        w = np.logspace(0, 5, 400)
        ret = [abs(1 + (c @ np.linalg.solve(1j * x * np.eye(A.shape[0]) - A, b))[0, 0])
               for x in w]
        assert min(ret) >= 1 - 1e-6


def test_lqr_gain_of_an_80_state_plant_matches_python_control():
    """The speed path (one BLAS thread around solve_continuous_are) keeps the result."""
    control = pytest.importorskip("control")
    import scipy.linalg

    p = cantilever_modal_plant(40)
    ss = p.to_state_space()
    K = LQR(R=1e-9).gain_matrix(p)
    K_ref, _, _ = control.lqr(ss.A, ss.B, scipy.linalg.block_diag(p.K, p.M), 1e-9)
    np.testing.assert_allclose(K, K_ref, rtol=1e-8, atol=1e-8 * np.max(np.abs(K_ref)))
    assert closed_loop_stability(p, LQR(R=1e-9)).stable


# ----------------------------------------------------------------- trajectories
def test_saturated_unstable_ppf_is_unstable_by_its_linearisation(plant3):
    ctrl = PPF([(F1, 0.3, 5.0)], sensor="tip", u_max=2.0)
    x0 = release_state(plant3, 1, "tip", 1e-3)
    ds = simulate(plant3, ctrl, t_end=2.0, fs_out=1000.0, initial=x0)
    v = trajectory_stability(plant3, ds, ctrl)
    assert v.verdict == "unstable" and v.source == "linearisation+trajectory"
    assert v.max_real_pole == pytest.approx(79.4, abs=0.05)
    ok = PPF([(F1, 0.3, 0.5)], sensor="tip", u_max=2.0)
    ds = simulate(plant3, ok, t_end=2.0, fs_out=1000.0, initial=x0)
    assert trajectory_stability(plant3, ds, ok).verdict == "stable"


def test_lyapunov_law_energy_does_not_increase(plant3):
    sc = Scenario(output="tip", t_end=3.0, fs_out=1000.0)
    ctrl = LyapunovBangBang(u_max=0.5, boundary_layer=0.05 * switching_peak(plant3, sc))
    x0 = release_state(plant3, 1, "tip", 1e-3)
    ds = simulate(plant3, ctrl, t_end=3.0, fs_out=1000.0, initial=x0)
    v = trajectory_stability(plant3, ds, ctrl)
    assert v.verdict == "stable"
    assert v.trajectory["energy_rise"] < 1e-9  # V' = -q'Cq' + q'B u <= 0
    assert v.trajectory["energy_ratio"] < 0.5
    s = stability_summary(plant3, ctrl, ds)
    assert s["stable"] and s["stability_source"] == "linearisation+trajectory"
    assert math.isinf(s["gain_margin_db"])  # collocated in-layer velocity feedback


def _fake(plant, q_scale, t_end=2.0, n=200):
    """A Dataset like simulate()'s with plant states q = scale(t) * phi1, q' = 0."""
    t = np.linspace(0, t_end, n)
    x0 = release_state(plant, 1, "tip", 1e-3)
    X = np.outer(x0, q_scale(t))
    return xr.Dataset({"states": (("state", "time"), X)}, coords={"time": t})


@pytest.mark.parametrize("scale, verdict", [
    (lambda t: np.exp(-t), "stable"),
    (lambda t: np.exp(0.2 * t), "unstable"),
    (lambda t: np.ones_like(t), "marginal"),
    (lambda t: np.where(t < 1.9, np.exp(t), np.nan), "unstable"),
])
def test_trajectory_verdicts_on_known_energies(plant3, scale, verdict):
    v = trajectory_stability(plant3, _fake(plant3, scale))
    assert v.verdict == verdict and v.source == "trajectory"
    if verdict != "stable":
        assert v.reason.startswith(verdict)


def test_forced_trajectory_judges_divergence_only(plant3):
    grow = _fake(plant3, lambda t: 1 + t)  # a build-up under forcing is not instability
    assert trajectory_stability(plant3, grow, forced=True).verdict == "stable"
    assert trajectory_stability(plant3, grow).verdict == "unstable"
    blow = _fake(plant3, lambda t: np.exp(10 * t))
    assert trajectory_stability(plant3, blow, forced=True).verdict == "unstable"


def test_trajectory_bad_input(plant3):
    with pytest.raises(ParameterError, match="Dataset of mvtk.control.simulate"):
        trajectory_stability(plant3, np.zeros((6, 10)))
    with pytest.raises(ParameterError, match="at least 8 samples"):
        trajectory_stability(plant3, _fake(plant3, np.exp, n=4))
    with pytest.raises(ParameterError, match="decay_min"):
        trajectory_stability(plant3, _fake(plant3, np.exp), decay_min=0.0)


def test_open_loop_has_no_stability_summary(plant3):
    with pytest.raises(ParameterError, match="needs a controller"):
        closed_loop_stability(plant3, None)


# ------------------------------------------------------------------- spillover
def test_spillover_names_the_residual_mode():
    """Non-collocated velocity feedback (tip velocity -> patch) designed on mode 1 only
    destabilises mode 2 (83.1 Hz) of the 3-mode plant: the residual mode is named."""
    design, full = cantilever_modal_plant(1), cantilever_modal_plant(3)
    res = spillover_check(VelocityFeedback(1e-3, sensor="tip"), design, full)
    assert res.verdict_design.verdict == "stable"
    assert res.verdict == "unstable" and res.verdict_evaluation.reason.startswith("unstable")
    t = res.offending_table()
    assert len(t) == 1
    row = t.iloc[0]
    assert row["continues"] == "plant mode 2" and bool(row["residual"])
    assert row["open_fn_hz"] == pytest.approx(full.meta["fn_hz"][1], rel=1e-3)
    assert row["real"] > 0
    d = res.to_dict()
    assert d["verdict_evaluation"]["verdict"] == "unstable"
    assert d["offending"][0]["continues"] == "plant mode 2"
    ok = spillover_check(PPF([(F1, 0.3, 0.5)], sensor="tip"), design, full)
    assert ok.verdict == "stable" and ok.offending == ()


def test_spillover_on_a_retained_mode_is_not_residual():
    """The destabilised mode exists in the design plant: it is not a residual mode."""
    p = cantilever_modal_plant(3)
    res = spillover_check(VelocityFeedback(1e-3, sensor="tip"), p, p)
    assert res.verdict == "unstable"
    assert not res.offending[0]["residual"]


def test_forced_comparison_judges_saturated_law_by_boundedness(plant3):
    """A harmonic disturbance at mode 1 keeps energy in the plant: the saturated PPF is
    judged on divergence only (and on its unsaturated eigenvalues)."""
    from mvtk.control import Disturbance

    sc = Scenario(output="tip", t_end=1.0, fs_out=500.0, release_mode=None,
                  disturbance=Disturbance("harmonic", "patch", 5.0, f_hz=F1))
    res = compare_controllers(plant3, {"PPF sat": PPF([(F1, 0.3, 0.5)], sensor="tip",
                                                      u_max=1.0)}, sc)
    row = res.to_dataframe().loc["PPF sat"]
    assert row["verdict"] == "stable" and row["stability_source"] == "linearisation+trajectory"


def test_trajectory_of_a_state_space_plant_uses_the_state_norm(plant3):
    ss = plant3.to_state_space()
    ds = _fake(plant3, lambda t: np.exp(-t))
    assert trajectory_stability(ss, ds).verdict == "stable"
    ds = _fake(plant3, lambda t: np.exp(t))
    assert trajectory_stability(ss, ds).verdict == "unstable"
