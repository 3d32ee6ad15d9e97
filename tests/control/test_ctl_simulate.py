"""Closed-loop simulation against scipy.signal.lsim / python-control, Lyapunov energy,
saturation, disturbances and noise."""

import numpy as np
import pytest
import scipy.signal

from mvtk.control import (
    PPF,
    SRF,
    Disturbance,
    LyapunovBangBang,
    VelocityFeedback,
    cantilever_modal_plant,
    closed_loop,
    release_state,
    simulate,
)
from mvtk.errors import ConvergenceError, DimensionError, ParameterError

F1 = 13.26


@pytest.fixture(scope="module")
def plant():
    return cantilever_modal_plant(3)


def test_dataset_layout(plant):
    ds = simulate(plant, PPF([(F1, 0.3, 0.5)], sensor="tip"), t_end=0.5, fs_out=200.0,
                  initial=release_state(plant, 1, "tip", 1e-3))
    assert ds["outputs"].dims == ("output", "time")
    assert list(ds.output.values) == ["tip", "tip_velocity", "patch_rotation"]
    assert list(ds.output_units.values) == ["m", "m/s", "rad"]
    assert list(ds.input.values) == ["patch"] and ds.input_units.values[0] == "V"
    assert ds["states"].sizes["state"] == 8
    np.testing.assert_array_equal(ds.time.values, np.arange(101) / 200.0)
    assert ds.time.attrs["units"] == "s"
    assert ds.attrs["method"] == "zoh"
    assert ds.outputs.values[0, 0] == pytest.approx(1e-3)


def test_linear_simulation_matches_lsim_with_harmonic_disturbance(plant):
    """Exact ZOH march vs scipy.signal.lsim (zero-order hold) on the closed loop."""
    ctrl = PPF([(F1, 0.4, 0.5)], sensor="tip")
    fs, t_end = 2000.0, 1.0
    dist = Disturbance("harmonic", at="patch", amplitude=10.0, f_hz=20.0)
    x0 = release_state(plant, 1, "tip", 1e-3)
    ds = simulate(plant, ctrl, t_end=t_end, fs_out=fs, initial=x0, disturbance=dist)
    cl = closed_loop(plant, ctrl)
    t = ds.time.values
    U = np.zeros((t.size, cl.n_inputs))
    U[:, 0] = 10.0 * np.sin(2 * np.pi * 20.0 * t)
    X0 = np.concatenate([x0, np.zeros(cl.n_states - x0.size)])
    _, y, _ = scipy.signal.lsim(cl.to_scipy(), U, t, X0=X0, interp=False)
    scale = np.max(np.abs(y), axis=0)
    for k, name in enumerate(cl.outputs[:3]):
        err = np.max(np.abs(ds.outputs.sel(output=name).values - y[:, k]))
        assert err <= 1e-9 * scale[k], name
    # the actuator command (last closed-loop output) is the controller part only
    np.testing.assert_allclose(ds.inputs.values[0], y[:, -1], rtol=0, atol=1e-9 * scale[-1])


def test_linear_simulation_matches_python_control(plant):
    control = pytest.importorskip("control")
    ctrl = SRF([(1.5 * F1, 0.5, 0.002)], sensor="tip")
    x0 = release_state(plant, 1, "tip", 1e-3)
    ds = simulate(plant, ctrl, t_end=1.0, fs_out=1000.0, initial=x0,
                  disturbance=Disturbance("step", at="patch", amplitude=5.0))
    cl = closed_loop(plant, ctrl)
    t = ds.time.values
    U = np.zeros((cl.n_inputs, t.size))
    U[0] = 5.0
    X0 = np.concatenate([x0, np.zeros(cl.n_states - x0.size)])
    resp = control.forced_response(cl.to_control(), T=t, U=U, X0=X0)
    y_ref = np.asarray(resp.outputs)
    for k in range(3):
        scale = np.max(np.abs(y_ref[k]))
        assert np.max(np.abs(ds.outputs.values[k] - y_ref[k])) <= 1e-8 * scale


def test_impulse_is_an_initial_velocity(plant):
    """An impulse I at a coordinate gives q'(0+) = M^-1 e I; free decay afterwards equals
    the response from that initial state."""
    dist = Disturbance("impulse", at="mode1", amplitude=1e-3)
    a = simulate(plant, None, t_end=0.2, fs_out=1000.0, disturbance=dist)
    x0 = np.zeros(6)
    x0[3] = 1e-3
    b = simulate(plant, None, t_end=0.2, fs_out=1000.0, initial=x0)
    np.testing.assert_allclose(a.outputs.values, b.outputs.values, rtol=0, atol=1e-15)
    # mode 1 alone: q(t) = I/w sin(w t) e^{-z w t} (lightly damped)
    w = 2 * np.pi * F1
    t = a.time.values
    q = a.states.sel(state="mode1").values
    z = plant.meta["zeta"][0]
    wd = w * np.sqrt(1 - z**2)
    np.testing.assert_allclose(q, 1e-3 / wd * np.exp(-z * w * t) * np.sin(wd * t), atol=1e-12)


def test_open_loop_decay_rate(plant):
    """Open-loop mode-1 envelope decays with the paper's time constant (about 20.5 s)."""
    ds = simulate(plant, None, t_end=4.0, fs_out=500.0,
                  initial=release_state(plant, 1, "tip", 1e-3))
    y = ds.outputs.sel(output="tip").values
    t = ds.time.values
    pk, _ = scipy.signal.find_peaks(y)
    slope = np.polyfit(t[pk], np.log(y[pk]), 1)[0]
    assert -1 / slope == pytest.approx(20.5, rel=0.01)


def energy(plant, ds):
    n = plant.n_coords
    X = ds.states.values[: 2 * n]
    q, v = X[:n], X[n:]
    return 0.5 * np.einsum("it,ij,jt->t", v, plant.M, v) + 0.5 * np.einsum(
        "it,ij,jt->t", q, plant.K, q)


@pytest.mark.parametrize("layer", ["sat", "tanh"])
def test_lyapunov_velocity_law_decreases_energy_monotonically(plant, layer):
    x0 = release_state(plant, 1, "tip", 1e-3)
    ctrl = LyapunovBangBang(u_max=20.0, boundary_layer=5e-6, layer=layer)
    ds = simulate(plant, ctrl, t_end=2.0, fs_out=1000.0, initial=x0, method="LSODA",
                  rtol=1e-8)
    E = energy(plant, ds)
    assert np.all(np.diff(E) <= 1e-7 * E[0])
    assert E[-1] < 0.01 * E[0]
    u = ds.inputs.values[0]
    assert np.max(np.abs(u)) <= 20.0 * (1 + 1e-12)
    # the command opposes B'q' (power into the structure never positive)
    n = plant.n_coords
    s = plant.B[:, 0] @ ds.states.values[n: 2 * n]
    assert np.all(u * s <= 1e-18)


def test_lyapunov_state_form_decreases_its_lyapunov_function(plant):
    import scipy.linalg

    x0 = release_state(plant, 1, "tip", 1e-3)
    ss = plant.to_state_space()
    Q = scipy.linalg.block_diag(plant.K, plant.M * 0 + np.eye(3) * 1.0)
    ctrl = LyapunovBangBang(u_max=20.0, boundary_layer=1e-6, form="state", Q=Q)
    ds = simulate(plant, ctrl, t_end=1.0, fs_out=1000.0, initial=x0, method="LSODA")
    P = scipy.linalg.solve_continuous_lyapunov(ss.A.T, -Q)
    X = ds.states.values
    V = np.einsum("it,ij,jt->t", X, P, X)
    assert np.all(np.diff(V) <= 1e-7 * V[0])


def test_sampled_and_integrated_lyapunov_agree(plant):
    x0 = release_state(plant, 1, "tip", 1e-3)
    ctrl = LyapunovBangBang(u_max=20.0, boundary_layer=1e-5)
    a = simulate(plant, ctrl, t_end=2.0, fs_out=1000.0, initial=x0, method="LSODA",
                 rtol=1e-8)
    b = simulate(plant, ctrl, t_end=2.0, fs_out=1000.0, initial=x0)  # sampled at 10 kHz
    assert b.attrs["method"] == "sampled"
    ya, yb = a.outputs.values[0], b.outputs.values[0]
    assert np.max(np.abs(ya - yb)) < 0.01 * 1e-3


@pytest.mark.parametrize("method", ["sampled", "LSODA"])
def test_saturation_is_respected_and_active(plant, method):
    x0 = release_state(plant, 1, "tip", 1e-3)
    ctrl = PPF([(F1, 0.3, 0.5)], sensor="tip", u_max=5.0)
    ds = simulate(plant, ctrl, t_end=1.0, fs_out=1000.0, initial=x0, method=method)
    u = ds.inputs.values[0]
    assert np.max(np.abs(u)) <= 5.0 * (1 + 1e-12)
    assert np.mean(np.abs(u) >= 5.0 * (1 - 1e-9)) > 0.05  # clipped for a while
    free = simulate(plant, PPF([(F1, 0.3, 0.5)], sensor="tip"), t_end=1.0, fs_out=1000.0,
                    initial=x0)
    assert np.max(np.abs(free.inputs.values[0])) > 10.0


def test_saturated_loop_equals_linear_loop_when_limit_not_reached(plant):
    x0 = release_state(plant, 1, "tip", 1e-3)
    lin = simulate(plant, PPF([(F1, 0.3, 0.5)], sensor="tip"), t_end=0.5, fs_out=500.0,
                   initial=x0)
    sat = simulate(plant, PPF([(F1, 0.3, 0.5)], sensor="tip", u_max=1e4), t_end=0.5,
                   fs_out=500.0, initial=x0, method="LSODA", rtol=1e-9)
    np.testing.assert_allclose(sat.outputs.values[0], lin.outputs.values[0], rtol=0,
                               atol=1e-9)


def test_sensor_noise_is_reproducible_and_enters_the_command(plant):
    x0 = release_state(plant, 1, "tip", 1e-3)
    ctrl = VelocityFeedback(1e-3, sensor="patch_rotation")
    kw = dict(t_end=0.5, fs_out=1000.0, initial=x0)
    a = simulate(plant, ctrl, noise_std=1e-4, rng=np.random.default_rng(1), **kw)
    b = simulate(plant, ctrl, noise_std=1e-4, rng=np.random.default_rng(1), **kw)
    c = simulate(plant, ctrl, **kw)
    np.testing.assert_array_equal(a.inputs.values, b.inputs.values)
    # the difference in the command at t=0 is the gain times the first noise sample
    g = closed_loop(plant, ctrl).meta["physical_gains"][0]
    n0 = np.random.default_rng(1).standard_normal(1)[0] * 1e-4
    assert a.inputs.values[0, 0] - c.inputs.values[0, 0] == pytest.approx(-g * n0)


def test_random_disturbance_needs_generator_and_is_seeded(plant):
    d = Disturbance("random", at="patch", amplitude=1.0)
    with pytest.raises(ParameterError, match="Generator"):
        simulate(plant, None, t_end=0.1, fs_out=100.0, disturbance=d)
    a = simulate(plant, None, t_end=0.1, fs_out=100.0, disturbance=d,
                 rng=np.random.default_rng(3))
    np.testing.assert_array_equal(a.disturbance.values,
                                  np.random.default_rng(3).standard_normal(11))


def test_bad_simulation_input(plant):
    kw = dict(t_end=0.1, fs_out=100.0)
    with pytest.raises(ParameterError, match="t_end and fs_out"):
        simulate(plant, None, t_end=-1.0, fs_out=100.0)
    with pytest.raises(DimensionError, match="6 plant states"):
        simulate(plant, None, initial=np.zeros(3), **kw)
    with pytest.raises(ParameterError, match="exact only for linear"):
        simulate(plant, LyapunovBangBang(u_max=1.0, boundary_layer=1e-5), method="zoh", **kw)
    with pytest.raises(ParameterError, match="method must be"):
        simulate(plant, None, method="euler", **kw)
    with pytest.raises(ParameterError, match="needs a controller"):
        simulate(plant, None, noise_std=1.0, rng=np.random.default_rng(0), **kw)
    with pytest.raises(ParameterError, match="noise_std needs rng"):
        simulate(plant, PPF([(F1, 0.3, 0.5)]), noise_std=1.0, **kw)
    with pytest.raises(ParameterError, match="unknown disturbance location 'base'"):
        simulate(plant, None, disturbance=Disturbance("step", at="base"), **kw)
    with pytest.raises(ParameterError, match="kind must be one of"):
        Disturbance("sweep", at="patch")
    with pytest.raises(ParameterError, match="f_hz > 0"):
        Disturbance("harmonic", at="patch")
    with pytest.raises(DimensionError, match="one sample per output time"):
        simulate(plant, None, disturbance=Disturbance("signal", at="patch",
                                                       signal=np.zeros(3)), **kw)
    with pytest.raises(ParameterError, match="boundary layer"):
        simulate(plant, LyapunovBangBang(u_max=100.0, boundary_layer=1e-12), **kw)


def test_integrator_failure_is_reported(plant, monkeypatch):
    import types

    import scipy.integrate

    def failing(*args, **kwargs):
        return types.SimpleNamespace(success=False, message="step size too small")

    monkeypatch.setattr(scipy.integrate, "solve_ivp", failing)
    x0 = release_state(plant, 1, "tip", 1e-3)
    with pytest.raises(ConvergenceError, match="integration .LSODA. failed: step size"):
        simulate(plant, PPF([(F1, 0.3, 0.5)], u_max=1.0), t_end=0.1, fs_out=100.0,
                 initial=x0, method="LSODA")


@pytest.mark.parametrize("n", [1, 2, 63, 64, 65, 130])
def test_blocked_march_equals_plain_recursion(n):
    from mvtk.control._simulate import _march

    rng = np.random.default_rng(7)
    Phi = 0.3 * rng.standard_normal((5, 5))
    Gam = rng.standard_normal((5, 2))
    E = rng.standard_normal((n, 2))
    x0 = rng.standard_normal(5)
    ref = np.empty((n, 5))
    ref[0] = x0
    for k in range(n - 1):
        ref[k + 1] = Phi @ ref[k] + Gam @ E[k]
    np.testing.assert_allclose(_march(Phi, Gam, x0, E, n), ref, rtol=1e-12, atol=1e-12)
    free = ref.copy()
    for k in range(n - 1):
        free[k + 1] = Phi @ free[k]
    np.testing.assert_allclose(_march(Phi, Gam, x0, None, n), free, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(("ctrl", "switches"), [
    (PPF([(F1, 0.3, 0.5)], sensor="tip", u_max=5.0), True),   # saturated, clipped a while
    (SRF([(16.0, 0.5, 0.002)], sensor="tip", u_max=2.0), True),
    (LyapunovBangBang(u_max=20.0, boundary_layer=1e-5), True),   # switching, sat layer
    (LyapunovBangBang(u_max=20.0, boundary_layer=2e-3), False),  # inside the layer
    (PPF([(F1, 0.3, 0.5)], sensor="tip"), False),                # linear law
])
def test_piecewise_march_equals_the_step_by_step_loop(plant, ctrl, switches):
    """The sampled controller without exogenous inputs is marched piece by piece of the
    law (blocks of affine steps); a zero-width exogenous input forces the reference
    step-by-step loop on the same discretisation: same states to round-off."""
    from mvtk.control._simulate import _sampled, realize

    law = realize(ctrl, plant, None)
    x0 = np.zeros(law.A.shape[0])
    x0[:2 * plant.n_coords] = release_state(plant, 1, "tip", 1e-3)
    n_t, k = 1001, 10
    N = x0.size
    fast = _sampled(law, np.zeros((N, 0)), np.zeros((1, 0)), None, x0, n_t, 1e-3, k)
    loop = _sampled(law, np.zeros((N, 0)), np.zeros((1, 0)), np.zeros((n_t, 0)), x0, n_t,
                    1e-3, k)
    scale = np.max(np.abs(loop), axis=0)
    assert np.max(np.abs(fast - loop) / np.where(scale > 0, scale, 1.0)) < 1e-9
    u = np.abs(law.u_of(loop @ law.S.T))
    # the switching cases cross pieces of the law, the others stay in one
    lim = np.inf if law.u_max is None else law.u_max * (1 - 1e-9)
    assert (np.any(u >= lim) and np.any(u < lim)) == switches
