"""Controllers on single-mode plants: the analytic PPF/SRF results of PHYSICS.md section 4
and the paper's eq. 15; connection details (normalisation, feedthrough, spillover)."""

import numpy as np
import pytest
import scipy.signal

from mvtk.control import (
    LQR,
    PPF,
    SRF,
    LyapunovBangBang,
    StructuralPlant,
    VelocityFeedback,
    added_damping,
    cantilever_modal_plant,
    closed_loop,
    critical_gain,
    modal_plant,
    ppf_gain_limit,
    release_state,
    simulate,
    spillover_check,
    srf_gain_limit,
)
from mvtk.errors import DimensionError, ParameterError

F1 = 13.26
W1 = 2 * np.pi * F1


def sdof(zeta=5.84e-4, b=0.37, c=2.5):
    """Single mode with arbitrary (non-unit) input/output gains: the normalisation must
    recover the dimensionless SDOF form."""
    return modal_plant([F1], zeta, [[b]], [[c]], inputs=["u"], outputs=["y"])


def test_ppf_sdof_closed_loop_is_the_textbook_matrix():
    G, zf, ff = 0.3, 0.4, 1.2 * F1
    cl = closed_loop(sdof(zeta=0.01), PPF([(ff, zf, G)]))
    wf = 2 * np.pi * ff
    # states [xi, xi', eta_y, eta_y'] with eta_y the filter on y = c xi
    c = 2.5
    A = np.array([
        [0, 1, 0, 0],
        [-W1**2, -2 * 0.01 * W1, G * W1**2 / c, 0],
        [0, 0, 0, 1],
        [wf**2 * c, 0, -wf**2, -2 * zf * wf],
    ])
    np.testing.assert_allclose(cl.A, A, rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("G", [0.001, 0.002, 0.005])
def test_ppf_active_damping_matches_paper_eq15(G):
    """Paper eq. 15: with wf = w, 2 z w -> 2 z w + G w / (2 zf), i.e. added zeta G/(4 zf);
    first order in G, valid while G << 4 zf^2 (at G = 0.01, zf = 0.3 it is 3 % off)."""
    zf = 0.3
    ad = added_damping(sdof(), PPF([(F1, zf, G)]), 1)
    assert ad["added"] == pytest.approx(G / (4 * zf), rel=0.02)
    assert ad["zeta_open"] == pytest.approx(5.84e-4, rel=1e-9)


def test_ppf_simulated_decay_matches_eq15():
    """Log-decrement of the simulated closed-loop response (released from the mode shape)
    against the eq. 15 prediction."""
    G, zf = 0.005, 0.3
    p = sdof()
    ds = simulate(p, PPF([(F1, zf, G)]), t_end=12.0, fs_out=2000.0,
                  initial=release_state(p, 1, "y", 1e-3))
    y = ds.outputs.sel(output="y").values
    t = ds.time.values
    pk, _ = scipy.signal.find_peaks(y)
    keep = t[pk] > 0.5  # after the filter transient (filter pole decays in ~0.04 s)
    slope = np.polyfit(t[pk][keep], np.log(y[pk][keep]), 1)[0]
    zeta_sim = -slope / W1
    assert zeta_sim == pytest.approx(5.84e-4 + G / (4 * zf), rel=0.02)


@pytest.mark.parametrize("ratio, zf", [(1.0, 0.3), (0.7, 0.1), (1.5, 0.5)])
def test_ppf_stability_boundary_at_unit_gain(ratio, zf):
    g = critical_gain(sdof(), PPF([(ratio * F1, zf, 0.1)]), g_max=2.0)
    assert g == pytest.approx(ppf_gain_limit(), rel=1e-4)


def test_ppf_collocated_multimode_boundary_with_static_normalisation():
    """Collocated (patch rotation sensor) 3-mode plant: K - B Gamma B' > 0 <=> G < 1 when G
    is normalised by the full static gain."""
    p = cantilever_modal_plant(3)
    g = critical_gain(p, PPF([(F1, 0.3, 0.1)], sensor="patch_rotation"), g_max=3.0)
    assert g == pytest.approx(1.0, rel=1e-4)


@pytest.mark.parametrize("ratio, zf", [(1.2, 0.3), (1.5, 0.5), (2.0, 0.2)])
def test_srf_stability_boundary_matches_routh_bound(ratio, zf):
    bound = srf_gain_limit(F1, ratio * F1, zf)
    g = critical_gain(sdof(zeta=0.0), SRF([(ratio * F1, zf, bound / 10)]), g_max=3 * bound)
    assert g == pytest.approx(bound, rel=0.01)


def test_srf_adds_damping_below_the_bound():
    bound = srf_gain_limit(F1, 1.5 * F1, 0.5)
    ad = added_damping(sdof(), SRF([(1.5 * F1, 0.5, 0.3 * bound)]), 1)
    assert ad["added"] > 0.01


def test_velocity_feedback_added_damping_closed_form():
    """Normalised gain G (s): xi'' + (2 z w + G w^2) xi' + w^2 xi = 0."""
    G = 1e-3
    ad = added_damping(sdof(zeta=0.0), VelocityFeedback(G), 1)
    assert ad["zeta_closed"] == pytest.approx(G * W1 / 2, rel=1e-9)


def test_normalise_none_uses_physical_gain():
    p = sdof(zeta=0.0)
    g_phys = 2e-3 * W1**2 / (0.37 * 2.5)
    a = closed_loop(p, VelocityFeedback(2e-3)).A
    b = closed_loop(p, VelocityFeedback(g_phys, normalise="none")).A
    np.testing.assert_allclose(a, b, rtol=1e-12)


def test_lqr_gain_matches_python_control():
    control = pytest.importorskip("control")
    p = cantilever_modal_plant(3)
    ss = p.to_state_space()
    Q = np.diag(np.arange(1.0, 7.0))
    K = LQR(R=1e-6, Q=Q).gain_matrix(p)
    K_ref, _, _ = control.lqr(ss.A, ss.B[:, :1], Q, 1e-6)
    np.testing.assert_allclose(K, K_ref, rtol=1e-8)
    assert np.all(closed_loop(p, LQR(R=1e-6, Q=Q)).poles().real < 0)


def test_multi_filter_ppf_damps_two_modes():
    p = cantilever_modal_plant(3)
    f2 = p.meta["fn_hz"][1]
    ctrl = PPF([(F1, 0.3, 0.2), (f2, 0.3, 0.2)], sensor="patch_rotation")
    a1 = added_damping(p, ctrl, 1)
    a2 = added_damping(p, ctrl, 2)
    assert a1["added"] > 0.1 and a2["added"] > 0.01
    single = added_damping(p, PPF([(F1, 0.3, 0.2)], sensor="patch_rotation"), 2)
    assert a2["added"] > 5 * single["added"]


def loop_residual(plant, ctrl_tf, poles):
    """|1 - K(p) G(p)| at closed-loop poles p, with u = K(s) y (positive feedback)."""
    ss = plant.to_state_space()
    out = []
    for s in poles:
        G = (ss.C[0] @ np.linalg.solve(s * np.eye(ss.n_states) - ss.A, ss.B[:, 0])
             + ss.D[0, 0])
        out.append(abs(1 - ctrl_tf(s) * G))
    return np.array(out)


@pytest.mark.parametrize("kind", ["PPF", "SRF"])
def test_feedthrough_plant_closed_loop_poles_solve_characteristic_equation(kind):
    """A static-correction plant (D != 0 on the sensor): the closed-loop poles must be the
    roots of 1 - K(s) G(s) with G(s) = C (sI - A)^-1 B + D."""
    base = cantilever_modal_plant(1)
    D = np.array([[-3e-6], [0.0], [0.0]])  # residual flexibility on the tip output
    p = StructuralPlant(base.M, base.C, base.K, base.B, base.Cq, base.Cv,
                        inputs=base.inputs, outputs=base.outputs, D=D)
    ff, zf = 1.4 * F1, 0.4
    wf = 2 * np.pi * ff
    ctrl = (PPF if kind == "PPF" else SRF)([(ff, zf, 0.05 if kind == "SRF" else 0.5 * 1e-2)],
                                          sensor="tip")
    cl = closed_loop(p, ctrl)
    g = cl.meta["physical_gains"][0]
    if kind == "PPF":
        def K(s):
            return g * wf**2 / (s**2 + 2 * zf * wf * s + wf**2)
    else:
        def K(s):
            return -g * wf**2 * s / (s**2 + 2 * zf * wf * s + wf**2)
    res = loop_residual(p, K, cl.poles())
    assert np.max(res) < 1e-8
    assert cl.D[0, 0] == pytest.approx(-3e-6)  # the plant's own input keeps its feedthrough


def test_spillover_of_non_collocated_velocity_feedback():
    """Velocity feedback from the tip to the patch: stable on the 1-mode design plant,
    destabilises mode 2 of the 3-mode plant (opposite sign of b_i c_i)."""
    design = cantilever_modal_plant(1)
    full = cantilever_modal_plant(3)
    res = spillover_check(VelocityFeedback(1e-3, sensor="tip"), design, full)
    assert res.stable_design and not res.stable_evaluation
    assert res.max_real_evaluation > 0
    df = res.to_dataframe()
    assert set(df["plant"]) == {"design", "evaluation"}
    # PPF on the same non-collocated pair rolls off and stays stable
    ok = spillover_check(PPF([(F1, 0.3, 0.5)], sensor="tip"), design, full)
    assert ok.stable_design and ok.stable_evaluation


# ------------------------------------------------------------------ bad input
@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: PPF([]), "at least one"),
        (lambda: PPF([(13.0, 0.3)]), "triples"),
        (lambda: PPF([(-1.0, 0.3, 0.5)]), "f_hz > 0"),
        (lambda: SRF([(13.0, 0.0, 0.5)]), "zeta_f > 0"),
        (lambda: PPF([(13.0, 0.3, 0.5)], normalise="modal"), "normalise must be one of"),
        (lambda: PPF([(13.0, 0.3, 0.5)], u_max=0.0), "u_max"),
        (lambda: VelocityFeedback(np.nan), "finite"),
        (lambda: LQR(R=0.0), "R must be"),
        (lambda: LyapunovBangBang(u_max=10.0, boundary_layer=0.0), "hard switch"),
        (lambda: LyapunovBangBang(u_max=10.0, boundary_layer=1.0, form="x"), "form"),
        (lambda: LyapunovBangBang(u_max=10.0, boundary_layer=1.0, layer="x"), "layer"),
        (lambda: LyapunovBangBang(u_max=None, boundary_layer=1.0), "u_max"),
    ],
)
def test_controller_bad_parameters(make, match):
    with pytest.raises(ParameterError, match=match):
        make()


def test_connection_errors():
    p = cantilever_modal_plant(3)
    with pytest.raises(ParameterError, match="unknown output 'strain'"):
        closed_loop(p, PPF([(F1, 0.3, 0.5)], sensor="strain"))
    with pytest.raises(ParameterError, match="unknown input 'shaker'"):
        closed_loop(p, PPF([(F1, 0.3, 0.5)], actuator="shaker"))
    with pytest.raises(ParameterError, match="algebraic loop"):
        closed_loop(p, VelocityFeedback(1e-3, sensor="tip_velocity", normalise="none"))
    with pytest.raises(ParameterError, match="nonlinear"):
        closed_loop(p, LyapunovBangBang(u_max=1.0, boundary_layer=1.0))
    with pytest.raises(ParameterError, match="without actuator limit"):
        closed_loop(p, PPF([(F1, 0.3, 0.5)], u_max=5.0))
    with pytest.raises(ParameterError, match="SecondOrderSystem"):
        LyapunovBangBang(u_max=1.0, boundary_layer=1.0).realize(p.to_state_space())
    with pytest.raises(DimensionError, match="Q must have shape"):
        LQR(Q=np.eye(2)).realize(p)
    with pytest.raises(ParameterError, match="static gain"):
        closed_loop(p, PPF([(F1, 0.3, 0.5)], sensor="tip_velocity"))
    with pytest.raises(ParameterError, match="must be a mvtk.control controller"):
        closed_loop(p, "PPF")
    with pytest.raises(ParameterError, match="SecondOrderSystem or a StateSpace"):
        closed_loop(np.eye(2), PPF([(F1, 0.3, 0.5)]))


def test_srf_bound_needs_filter_above_mode():
    with pytest.raises(ParameterError, match="not above the mode"):
        srf_gain_limit(F1, F1, 0.3)
    with pytest.raises(ParameterError, match="expected f_hz > 0"):
        srf_gain_limit(-1.0, F1, 0.3)


def test_critical_gain_errors():
    with pytest.raises(ParameterError, match="g_max"):
        critical_gain(sdof(), PPF([(F1, 0.3, 0.1)]), g_max=0.0)
    with pytest.raises(ParameterError, match="single-filter"):
        critical_gain(sdof(), PPF([(F1, 0.3, 0.1), (2 * F1, 0.3, 0.1)]), g_max=1.0)
    assert critical_gain(sdof(), VelocityFeedback(1e-3), g_max=1.0) == float("inf")


def test_filter_controller_state_space_is_the_filter_transfer_function():
    p = cantilever_modal_plant(3)
    ff, zf, G = 1.3 * F1, 0.5, 2e-3
    srf = SRF([(ff, zf, G)], sensor="tip").state_space(p)
    assert srf.inputs == ("d(tip)/dt",) and srf.outputs == ("patch",)
    assert srf.input_units == ("m/s",) and srf.output_units == ("V",)
    g = srf.meta["physical_gains"][0]
    wf = 2 * np.pi * ff
    f = np.array([5.0, 13.26, 40.0])
    s = 2j * np.pi * f
    expected = -g * wf**2 / (s**2 + 2 * zf * wf * s + wf**2)
    np.testing.assert_allclose(srf.frequency_response(f)[0, 0], expected, rtol=1e-12)
    ppf = PPF([(F1, 0.3, 0.5)], sensor="tip").state_space(p)
    assert ppf.dc_gain()[0, 0] == pytest.approx(0.5 / p.to_state_space().dc_gain()[0, 0])


def test_closed_loop_poles_match_python_control_feedback():
    """Our interconnection vs python-control's feedback() of the plant (actuator -> sensor)
    and the controller's own state space (positive feedback)."""
    control = pytest.importorskip("control")
    p = cantilever_modal_plant(3)
    ss = p.to_state_space()
    ctrl = PPF([(F1, 0.4, 0.3), (60.0, 0.3, 0.1)], sensor="tip")
    P = control.ss(ss.A, ss.B[:, [0]], ss.C[[0]], ss.D[[0]][:, [0]])
    K = ctrl.state_space(p).to_control()
    ref = np.sort_complex(control.feedback(P, K, sign=1).poles())
    ours = np.sort_complex(closed_loop(p, ctrl).poles())
    np.testing.assert_allclose(ours, ref, rtol=1e-9)
