"""Closed-loop state space and time simulation.

Linear loops are advanced by the exact zero-order-hold discretisation of the closed loop
(matrix exponential of the augmented matrix ``[[A, B], [0, 0]] dt``, as in
``scipy.signal.cont2discrete(method="zoh")``): exogenous inputs (disturbance, sensor
noise) are held constant between output samples, and the result is exact for such
inputs. Saturated and switching laws run by default as a digital controller
(``method="sampled"``: the command is computed from the state at the control rate, 10 kHz
by default, and held while the plant advances exactly; the in-layer loop of the switching
law is checked for sampled stability), or with :func:`scipy.integrate.solve_ivp` on the
continuous law (``method="LSODA"``, ``"Radau"``, ``"BDF"`` with the analytic Jacobian;
accurate but slow on stiff many-mode plants). The switching law is always smoothed by its
boundary layer; the clip at the actuator limit is applied exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from ..errors import ConvergenceError, DimensionError, ParameterError
from ._controllers import FeedbackLaw, _index, plant_state_space
from ._second_order import SecondOrderSystem
from ._statespace import StateSpace
from ._threads import one_blas_thread

__all__ = ["closed_loop", "simulate", "release_state", "Disturbance", "realize"]

_KINDS = ("impulse", "harmonic", "random", "signal", "step")


def realize(controller, plant, design_plant=None) -> FeedbackLaw | None:
    """``controller.realize(plant, design_plant)``, with a clear error for other objects."""
    if controller is None:
        return None
    if isinstance(controller, FeedbackLaw):
        return controller
    if not hasattr(controller, "realize"):
        raise ParameterError(
            "controller must be a mvtk.control controller (PPF, SRF, VelocityFeedback, LQR, "
            f"LyapunovBangBang) or None, got {type(controller).__name__}"
        )
    return controller.realize(plant, design_plant)


def closed_loop(plant, controller, design_plant=None) -> StateSpace:
    """Linear closed loop of ``plant`` and a linear ``controller`` as a :class:`StateSpace`.

    States: plant states then controller states. Inputs: the plant inputs, acting
    additively (the actuator input becomes an input disturbance at the actuator).
    Outputs: the plant outputs followed by the actuator command ``"u(<actuator>)"``.

    Parameters
    ----------
    plant : SecondOrderSystem or StateSpace
    controller : PPF, SRF, VelocityFeedback or LQR (unsaturated)
    design_plant : optional
        Plant used for the gain normalisation / design (spillover studies).

    Examples
    --------
    The closed loop of a velocity feedback as a state-space model: outputs are the plant
    outputs and the actuator command:

    >>> from mvtk.control import VelocityFeedback, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> cl = closed_loop(plant, VelocityFeedback(gain=1e-3))
    >>> cl.outputs, cl.A.shape
    (('tip', 'u(force)'), (2, 2))
    """
    ss = plant_state_space(plant)
    law = realize(controller, plant, design_plant)
    if law is None or not law.is_linear:
        raise ParameterError(
            "closed_loop needs a linear controller without actuator limit; got "
            f"{'None' if law is None else law.kind}; use simulate() for nonlinear laws"
        )
    n = ss.n_states
    N = law.A.shape[0]
    A = law.closed_loop_matrix()
    acts = list(law.actuator_indices)
    k = len(acts)
    B = np.zeros((N, ss.n_inputs))
    B[:n] = ss.B
    C = np.zeros((ss.n_outputs + k, N))
    C[: ss.n_outputs, :n] = ss.C
    C[: ss.n_outputs] += ss.D[:, acts] @ law.S
    C[ss.n_outputs:] = law.S
    D = np.vstack([ss.D, np.zeros((k, ss.n_inputs))])
    return StateSpace(
        A, B, C, D, inputs=ss.inputs,
        outputs=[*ss.outputs, *(f"u({ss.inputs[a]})" for a in acts)],
        states=[*ss.states, *law.controller_states], input_units=ss.input_units,
        output_units=[*ss.output_units, *(ss.input_units[a] for a in acts)],
        meta={"controller": law.description, **law.meta},
    )


def release_state(
    plant: SecondOrderSystem, mode: int = 1, output: str | None = None, amplitude: float = 1e-3
) -> np.ndarray:
    """Plant state ``[q0; 0]`` at rest in mode shape ``mode`` (1-based) scaled so that
    output ``output`` equals ``amplitude`` (the paper's release from the first eigenmode).

    Examples
    --------
    The state at rest in mode 1 with 1 mm at the output ``tip`` (shape 1 at ``tip``):

    >>> from mvtk.control import modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> release_state(plant, 1, "tip", amplitude=1e-3)
    array([0.001, 0.   ])
    """
    if not isinstance(plant, SecondOrderSystem):
        raise ParameterError(
            f"release_state needs a SecondOrderSystem, got {type(plant).__name__}"
        )
    n = plant.n_coords
    if not 1 <= int(mode) <= n:
        raise ParameterError(f"mode must be in 1..{n} (1-based), got {mode}")
    j = _index(plant.outputs, output, "output")
    try:
        _, vec = scipy.linalg.eigh(plant.K, plant.M, subset_by_index=[mode - 1, mode - 1])
    except np.linalg.LinAlgError as err:
        raise ParameterError(
            "release_state needs a symmetric positive definite mass matrix M (a plant with "
            "massless coordinates: use the modal form of the plant)"
        ) from err
    phi = vec[:, 0]
    y = plant.Cq[j] @ phi
    if abs(y) < 1e-12 * np.max(np.abs(plant.Cq[j])) * np.max(np.abs(phi)):
        raise ParameterError(
            f"output {plant.outputs[j]!r} does not see mode {mode} (a node of the shape); "
            "choose another output to scale the release amplitude"
        )
    return np.concatenate([phi * (amplitude / y), np.zeros(n)])


@dataclass(frozen=True)
class Disturbance:
    """An exogenous force through a plant input or at a generalised coordinate.

    Parameters
    ----------
    kind : {"impulse", "step", "harmonic", "random", "signal"}
        ``impulse``: an impulse of ``amplitude`` (input units x s, e.g. N s) at t = 0,
        applied exactly as an initial velocity ``M^-1 b amplitude``; ``step``: a constant
        ``amplitude`` from t = 0; ``harmonic``: ``amplitude sin(2 pi f_hz t)``; ``random``:
        Gaussian white samples of standard deviation ``amplitude`` at the output rate
        (needs ``rng`` in :func:`simulate`); ``signal``: the given samples at the output
        rate. Between samples the force is held (zero-order hold).
    at : str
        A plant input name or (second-order plants) a coordinate name.
    amplitude : float
    f_hz : float, optional
        Frequency of the harmonic disturbance (Hz).
    signal : array, optional
        Samples for ``kind="signal"``, one per output time.

    Examples
    --------
    An impulse of 0.01 N s through the input ``force``: the peak displacement of the
    mode (unit modal mass) is about ``I / w_d`` = 0.159 mm, a little less with damping:

    >>> from mvtk.control import modal_plant, simulate
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> imp = Disturbance("impulse", at="force", amplitude=0.01)
    >>> sim = simulate(plant, None, t_end=2.0, fs_out=200.0, disturbance=imp)
    >>> round(float(abs(sim.outputs).max()) * 1e3, 3)     # mm
    0.157
    """

    kind: str
    at: str
    amplitude: float = 1.0
    f_hz: float | None = None
    signal: np.ndarray | None = None

    def __post_init__(self) -> None:
        if self.kind not in _KINDS:
            raise ParameterError(f"disturbance kind must be one of {_KINDS}, got {self.kind!r}")
        if self.kind == "harmonic" and not (self.f_hz and self.f_hz > 0):
            raise ParameterError(f"harmonic disturbance needs f_hz > 0, got {self.f_hz}")
        if self.kind == "signal" and self.signal is None:
            raise ParameterError("disturbance kind 'signal' needs the signal samples")

    def column(self, plant, ss: StateSpace) -> np.ndarray:
        """State-derivative column of a unit disturbance."""
        if self.at in ss.inputs:
            return ss.B[:, ss.inputs.index(self.at)].copy()
        if isinstance(plant, SecondOrderSystem) and self.at in plant.coords:
            n = plant.n_coords
            e = np.zeros(n)
            e[plant.coords.index(self.at)] = 1.0
            return np.concatenate([np.zeros(n), np.linalg.solve(plant.M, e)])
        choices = list(ss.inputs) + (list(plant.coords) if isinstance(plant, SecondOrderSystem)
                                     else [])
        raise ParameterError(f"unknown disturbance location {self.at!r}; expected one of {choices}")

    def samples(self, t: np.ndarray, rng) -> np.ndarray:
        """Disturbance samples at times ``t`` (zero for an impulse, applied as a state jump)."""
        if self.kind == "impulse":
            return np.zeros_like(t)
        if self.kind == "step":
            return np.full_like(t, self.amplitude)
        if self.kind == "harmonic":
            return self.amplitude * np.sin(2 * np.pi * self.f_hz * t)
        if self.kind == "random":
            if not isinstance(rng, np.random.Generator):
                raise ParameterError(
                    "a random disturbance needs rng=numpy.random.Generator, got "
                    f"{type(rng).__name__}"
                )
            return self.amplitude * rng.standard_normal(t.size)
        sig = np.asarray(self.signal, dtype=float)
        if sig.shape != t.shape:
            raise DimensionError(
                f"disturbance signal must have one sample per output time ({t.size}), "
                f"got shape {sig.shape}"
            )
        return sig


def _zoh(A: np.ndarray, B: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    n, m = B.shape
    blk = np.zeros((n + m, n + m))
    blk[:n, :n] = A * dt
    blk[:n, n:] = B * dt
    E = scipy.linalg.expm(blk)
    return E[:n, :n], E[:n, n:]


def _march(Phi: np.ndarray, Gam: np.ndarray, x0: np.ndarray, E: np.ndarray | None, n: int,
           block: int = 64):
    """x[k+1] = Phi x[k] + Gam e[k] for k < n - 1 (rows are samples).

    Blocked: with the powers ``Phi^j`` and Markov parameters ``Phi^j Gam`` of one block,
    (1) the forced response of every block from rest is one matrix product (a
    lower-triangular Toeplitz operator times all input blocks), (2) the block start
    states follow from a short recursion with ``Phi^block``, (3) every state is one more
    matrix product of the powers with the start states. Same result as the plain
    recursion (round-off), without a Python loop per sample.
    """
    N = x0.size
    X = np.empty((n, N))
    X[0] = x0
    steps = n - 1
    if steps == 0:
        return X
    if E is not None:  # keep the Toeplitz operator (block^2 N ne values) below ~4e6
        block = min(block, int(np.sqrt(4e6 / (N * max(E.shape[1], 1)))))
    block = max(1, min(block, steps))
    nb = -(-steps // block)
    pows = np.empty((block + 1, N, N))  # Phi^0 .. Phi^block
    pows[0] = np.eye(N)
    for j in range(block):
        pows[j + 1] = Phi @ pows[j]
    P = pows[1:].reshape(block * N, N)  # rows j*N..: Phi^(j+1)
    F = None
    if E is not None:
        ne = E.shape[1]
        markov = pows[:block] @ Gam  # (block, N, ne): Phi^m Gam
        T = np.zeros((block, N, block, ne))  # T[j, :, i] = Phi^(j - i) Gam, i <= j
        for j in range(block):
            T[j, :, : j + 1, :] = markov[j::-1].transpose(1, 0, 2)
        Epad = np.zeros((nb * block, ne))
        Epad[:steps] = E[:steps]
        F = T.reshape(block * N, block * ne) @ Epad.reshape(nb, block * ne).T  # (block N, nb)
    starts = np.empty((N, nb))
    starts[:, 0] = x0
    PhiB = pows[block]
    for b in range(nb - 1):
        nxt = PhiB @ starts[:, b]
        if F is not None:
            nxt = nxt + F[(block - 1) * N:, b]
        starts[:, b + 1] = nxt
    # row b*block + j of Y is the state Phi^(j+1) start_b (+ forced part): the product
    # comes out in sample order, no transposed copy
    Y = starts.T @ P.T
    if F is not None:
        Y += F.T
    X[1:] = Y.reshape(nb * block, N)[:steps]
    return X


def _sampled(law: FeedbackLaw, Bx, Su, E, X0, n_t: int, dt: float, k: int) -> np.ndarray:
    """Digital controller: u computed every ``dt/k`` from the state and held (ZOH)."""
    h = dt / k
    N = X0.size
    Phi, Gam = _zoh(law.A, np.hstack([law.Bu, Bx]), h)
    gu = Gam[:, 0]
    Ge = Gam[:, 1:]
    srow = law.S[0]
    if law.kind == "switching":
        slope = -law.u_max / law.boundary_layer
        rho = np.max(np.abs(np.linalg.eigvals(Phi + slope * np.outer(gu, srow))))
        if rho >= 1.0:
            raise ParameterError(
                f"the boundary layer eps={law.boundary_layer:g} gives an in-layer gain "
                f"u_max/eps={-slope:.3g} too high for the control rate {1 / h:.6g} Hz "
                f"(sampled loop spectral radius {rho:.4f} >= 1); increase boundary_layer "
                "or control_rate_hz, or use method='LSODA'"
            )
    regimes = _regimes(law)
    if E is None and regimes is not None:
        return _sampled_regimes(Phi, gu, srow, regimes, X0, n_t, k)
    u_of = law.u_scalar
    X = np.empty((n_t, N))
    X[0] = X0
    x = X0.copy()
    PhiT = Phi.T
    forced = None if E is None else E @ Ge.T
    su = None if E is None else E @ Su[0]
    for i in range(n_t - 1):
        for _ in range(k):
            s = float(srow @ x) if su is None else float(srow @ x) + su[i]
            x = x @ PhiT + gu * u_of(s)
            if forced is not None:
                x += forced[i]
        X[i + 1] = x
    return X


def _regimes(law: FeedbackLaw):
    """Pieces of a piecewise-affine law ``u = a s + b``: ``((lo, hi), ((a, b), ...))``
    with piece 0 for ``s < lo``, 1 for ``lo <= s <= hi``, 2 for ``s > hi``; None for a
    law that is not piecewise affine (the tanh layer)."""
    if law.kind == "linear":
        return (-np.inf, np.inf), ((0.0, 0.0), (1.0, 0.0), (0.0, 0.0))
    if law.kind == "saturated":
        u = float(law.u_max)
        return (-u, u), ((0.0, -u), (1.0, 0.0), (0.0, u))
    if law.kind == "switching" and law.layer == "sat":
        u, eps = float(law.u_max), float(law.boundary_layer)
        return (-eps, eps), ((0.0, u), (-u / eps, 0.0), (0.0, -u))
    return None


def _sampled_regimes(Phi, gu, srow, regimes, X0, n_t: int, k: int,
                     max_block: int = 2048) -> np.ndarray:
    """:func:`_sampled` without exogenous inputs for a piecewise-affine law.

    While the switching argument ``s = srow x`` stays in one piece ``u = a s + b`` of the
    law, the held-command recursion ``x+ = Phi x + gu u(s)`` is the affine recursion
    ``x+ = A x + c`` (``A = Phi + a gu srow``, ``c = b gu``), whose states after ``j``
    steps are ``A^j x + C_j`` (powers and offsets precomputed once per piece). A block
    of steps is marched at once; the first step whose ``s`` leaves the piece ends the
    block, and the march restarts there in the new piece. The states are those of the
    step-by-step loop up to round-off (a product of powers instead of a chain of
    products), without one Python iteration per control step.
    """
    N = X0.size
    steps = (n_t - 1) * k
    L = max(1, min(max_block, steps))
    (lo, hi), pieces = regimes
    tables = {}

    def table(r):
        if r not in tables:
            a, b = pieces[r]
            A = Phi + a * np.outer(gu, srow)
            c = b * gu
            P = np.empty((L + 1, N, N))
            C = np.empty((L + 1, N))
            P[0] = np.eye(N)
            C[0] = 0.0
            P[1] = A
            C[1] = c
            m = 1
            # doubling: A^(m+i) = A^m A^i and C_(m+i) = A^i C_m + C_i (C_j = sum_{l<j}
            # A^l c) fill 1..2m from 1..m in one batched product, log2(L) products
            while m < L:
                q = min(m, L - m)
                P[m + 1:m + q + 1] = P[m] @ P[1:q + 1]
                C[m + 1:m + q + 1] = P[1:q + 1] @ C[m] + C[1:q + 1]
                m += q
            tables[r] = (P, C, srow @ P, C @ srow)   # s_j = SP[j] x + sC[j]
        return tables[r]

    def piece(sv):
        return np.where(sv < lo, 0, np.where(sv > hi, 2, 1))

    X = np.empty((n_t, N))
    X[0] = X0
    x = np.array(X0, dtype=float)
    g = 0                                   # control steps done
    r = int(piece(float(srow @ x)))
    span = 16                               # steps checked at once (adapts)
    while g < steps:
        P, C, SP, sC = table(r)
        m = min(span, L, steps - g)
        sv = SP[1:m + 1] @ x + sC[1:m + 1]  # s of the states 1..m steps ahead
        left = np.flatnonzero(piece(sv) != r)
        j = int(left[0]) + 1 if left.size else m   # states 1..j are exact
        first = -(-(g + 1) // k) * k             # output samples among g+1..g+j
        out = np.arange(first, g + j + 1, k)
        if out.size:
            X[out // k] = np.einsum("jab,b->ja", P[out - g], x) + C[out - g]
        x = P[j] @ x + C[j]
        g += j
        if left.size:
            r = int(piece(sv[j - 1]))
            span = max(16, 2 * j)
        else:
            span = min(2 * span, L)
    return X


def _default_atol(A, X0, Bx, E, rtol) -> float:
    scale = float(np.max(np.abs(X0))) if X0.size else 0.0
    if E is not None and Bx.size:
        try:
            static = np.linalg.solve(A, Bx @ np.max(np.abs(E), axis=0))
            scale = max(scale, float(np.max(np.abs(static))))
        except np.linalg.LinAlgError:
            pass
    return 1e-3 * rtol * (scale if scale > 0 else 1.0)


def _integrate(law: FeedbackLaw, Bx: np.ndarray, Su: np.ndarray, E, X0, t, method, rtol, atol):
    """solve_ivp on X' = A X + Bu u(S X + Su e) + Bx e with e held between samples."""
    from scipy.integrate import solve_ivp

    A, Bu, S = law.A, law.Bu, law.S
    fs = 1.0 / (t[1] - t[0]) if t.size > 1 else 1.0
    n_t = t.size

    def e_at(tt):
        return E[min(int(tt * fs + 1e-9), n_t - 1)]

    def fun(tt, X):
        s = S @ X
        dX = A @ X
        if E is not None:
            e = e_at(tt)
            s = s + Su @ e
            dX = dX + Bx @ e
        return dX + Bu @ law.u_of(s)

    def jac(tt, X):
        s = S @ X
        if E is not None:
            s = s + Su @ e_at(tt)
        return A + (Bu * law.du_ds(s)) @ S

    opts = {"rtol": rtol, "atol": atol}
    if E is not None:
        opts["max_step"] = 1.0 / fs
    if method in ("LSODA", "Radau", "BDF"):
        opts["jac"] = jac
    sol = solve_ivp(fun, (t[0], t[-1]), X0, method=method, t_eval=t, **opts)
    if not sol.success:
        raise ConvergenceError(f"closed-loop integration ({method}) failed: {sol.message}")
    return sol.y.T


@one_blas_thread
def simulate(
    plant,
    controller=None,
    *,
    t_end: float,
    fs_out: float,
    initial: np.ndarray | Sequence[float] | None = None,
    disturbance: Disturbance | None = None,
    noise_std: float | None = None,
    rng: np.random.Generator | None = None,
    method: str = "auto",
    design_plant=None,
    control_rate_hz: float | None = None,
    rtol: float = 1e-6,
    atol: float | np.ndarray | None = None,
):
    """Simulate the plant with (or without) a controller switched on at t = 0.

    Parameters
    ----------
    plant : SecondOrderSystem or StateSpace
    controller : controller object, optional
        ``None`` is the open loop.
    t_end : float
        Duration (s); samples at ``arange(n) / fs_out``, ``n = round(t_end fs_out) + 1``.
    fs_out : float
        Output sampling rate (Hz); also the hold rate of disturbance and noise samples.
    initial : array, optional
        Initial plant state (length ``n_states``; ``[q0; q0']`` for a second-order plant),
        e.g. from :func:`release_state`. Controller states start at zero.
    disturbance : Disturbance, optional
    noise_std : float, optional
        Standard deviation of white sensor noise added to the controller measurement
        (sensor units), held between samples; needs ``rng``.
    rng : numpy.random.Generator, optional
    method : {"auto", "zoh", "sampled", "LSODA", "Radau", "BDF", "RK45", "DOP853"}
        ``zoh``: exact discretisation (linear loops only). ``sampled``: a digital
        controller, the command computed from the state at ``control_rate_hz`` and held
        between control samples while the plant is advanced exactly (fast; for the
        switching law the in-layer loop is checked for sampled stability). Integrator
        names: :func:`scipy.integrate.solve_ivp` on the continuous law. ``auto``: ``zoh``
        for linear loops, ``sampled`` otherwise (``LSODA`` for a saturated multi-input
        law).
    control_rate_hz : float, optional
        Rate of the ``sampled`` controller, rounded up to an integer multiple of
        ``fs_out``; default ``max(fs_out, 10 kHz)``.
    design_plant : optional
        Plant used for gain normalisation (spillover studies).
    rtol, atol : float
        Tolerances of the integrator (nonlinear laws). ``atol=None``: ``1e-3 rtol`` times
        the largest plant-state magnitude expected (the initial state, or the static
        response to the largest disturbance sample).

    Returns
    -------
    xarray.Dataset
        ``outputs`` (output, time), ``inputs`` (input, time: the command of each
        actuator the law drives, zero for the open loop), ``states`` (state, time),
        ``disturbance`` (time) when given; ``units`` coordinates; attrs ``controller``,
        ``fs_out``, ``method``.

    Examples
    --------
    Release from 1 mm in mode 1, open loop and with velocity feedback. The envelope
    ``exp(-zeta w t)`` falls to 5 % after ``ln(20) / (zeta w)`` = 4.77 s (zeta = 0.01)
    and 1.15 s (zeta = 0.0414):

    >>> from mvtk.control import VelocityFeedback, modal_plant, release_state, settling_time
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> x0 = release_state(plant, 1, "tip", 1e-3)
    >>> sim = simulate(plant, None, t_end=8.0, fs_out=200.0, initial=x0)
    >>> sim.outputs.dims, round(settling_time(sim.outputs.sel(output="tip")), 1)
    (('output', 'time'), 4.8)
    >>> closed = simulate(plant, VelocityFeedback(gain=1e-3), t_end=8.0, fs_out=200.0,
    ...                   initial=x0)
    >>> round(settling_time(closed.outputs.sel(output="tip")), 1)
    1.1
    """
    import xarray as xr

    ss = plant_state_space(plant)
    if not (np.isfinite(t_end) and t_end > 0 and np.isfinite(fs_out) and fs_out > 0):
        raise ParameterError(f"t_end and fs_out must be > 0, got t_end={t_end}, fs_out={fs_out}")
    n_t = int(round(t_end * fs_out)) + 1
    t = np.arange(n_t) / fs_out
    dt = 1.0 / fs_out
    law = realize(controller, plant, design_plant)
    n = ss.n_states
    if law is None:
        A, Bu, S = ss.A, np.zeros((n, 1)), np.zeros((1, n))
        Nz, Sz, N, act = np.zeros((n, 0)), np.zeros((1, 0)), n, None
        cstates: tuple[str, ...] = ()
    else:
        A, Bu, S, Nz, Sz = law.A, law.Bu, law.S, law.Nz, law.Sz
        N, act, cstates = A.shape[0], list(law.actuator_indices), law.controller_states
    X0 = np.zeros(N)
    if initial is not None:
        x0 = np.asarray(initial, dtype=float).ravel()
        if x0.size != n:
            raise DimensionError(
                f"initial state must have {n} plant states ([q0; q0'] for a second-order "
                f"plant), got {x0.size}"
            )
        X0[:n] = x0
    # exogenous inputs e = [w; noise]
    cols, ecols, Sucols = [], [], []
    w = None
    if disturbance is not None:
        if not isinstance(disturbance, Disturbance):
            raise ParameterError(
                f"disturbance must be a Disturbance, got {type(disturbance).__name__}"
            )
        b = np.zeros(N)
        b[:n] = disturbance.column(plant, ss)
        w = disturbance.samples(t, rng)
        if disturbance.kind == "impulse":
            X0 = X0 + b * disturbance.amplitude
        else:
            cols.append(b)
            ecols.append(w)
            Sucols.append(np.zeros(S.shape[0]))
    if noise_std is not None and noise_std > 0:
        if law is None:
            raise ParameterError("sensor noise needs a controller (it enters the measurement)")
        if not isinstance(rng, np.random.Generator):
            raise ParameterError(
                f"noise_std needs rng=numpy.random.Generator, got {type(rng).__name__}"
            )
        nz = Sz.shape[1]
        noise = noise_std * rng.standard_normal((n_t, nz))
        for j in range(nz):
            cols.append(Nz[:, j])
            ecols.append(noise[:, j])
            Sucols.append(Sz[:, j])
    elif noise_std is not None and noise_std < 0:
        raise ParameterError(f"noise_std must be >= 0, got {noise_std}")
    E = np.column_stack(ecols) if ecols else None
    Bx = np.column_stack(cols) if cols else np.zeros((N, 0))
    Su = np.column_stack(Sucols) if Sucols else np.zeros((S.shape[0], 0))

    linear = law is None or law.is_linear
    if method == "auto":
        method = "zoh" if linear else ("sampled" if S.shape[0] == 1 else "LSODA")
    if method == "zoh":
        if not linear:
            raise ParameterError(
                f"method='zoh' is exact only for linear loops; the {law.kind} law needs an "
                "integrator (method='LSODA', 'Radau' or 'BDF')"
            )
        Acl = A + Bu @ S
        Bcl = Bx + Bu @ Su
        Phi, Gam = _zoh(Acl, Bcl if E is not None else np.zeros((N, 1)), dt)
        X = _march(Phi, Gam, X0, E, n_t)
        U = X @ S.T if E is None else X @ S.T + E @ Su.T
    elif method == "sampled":
        if law is None or law.S.shape[0] != 1:
            raise ParameterError("method='sampled' needs a single-actuator controller; "
                                 "a multi-input law runs with 'zoh' (linear) or an "
                                 "integrator ('LSODA', 'Radau', 'BDF')")
        rate = max(fs_out, 1e4) if control_rate_hz is None else float(control_rate_hz)
        if not (np.isfinite(rate) and rate > 0):
            raise ParameterError(f"control_rate_hz must be > 0, got {control_rate_hz}")
        k = max(1, int(np.ceil(rate / fs_out - 1e-9)))
        X = _sampled(law, Bx, Su, E, X0, n_t, dt, k)
        s = X @ law.S.T if E is None else X @ law.S.T + E @ Su.T
        U = law.u_of(s)
    elif method in ("LSODA", "Radau", "BDF", "RK45", "DOP853"):
        if law is None:
            law = FeedbackLaw(A=A, Bu=Bu, Nz=Nz, S=S, Sz=Sz, kind="linear", n_plant=n,
                              actuator=0)
        if atol is None:
            atol = _default_atol(A, X0, Bx, E, rtol)
        X = _integrate(law, Bx, Su, E, X0, t, method, rtol, atol)
        s = X @ law.S.T if E is None else X @ law.S.T + E @ Su.T
        U = law.u_of(s)
    else:
        raise ParameterError(
            "method must be 'auto', 'zoh', 'sampled', 'LSODA', 'Radau', 'BDF', 'RK45' or "
            f"'DOP853', got {method!r}"
        )
    if law is None:
        U = np.zeros((n_t, 1))
    Y = X[:, :n] @ ss.C.T
    if act is not None:
        Y = Y + U @ ss.D[:, act].T
    act_names = [ss.inputs[a] for a in act] if act is not None else [ss.inputs[0]]
    act_units = [ss.input_units[a] for a in act] if act is not None else [ss.input_units[0]]
    data = {
        "outputs": (("output", "time"), Y.T),
        "inputs": (("input", "time"), U.T),
        "states": (("state", "time"), X.T),
    }
    if w is not None:
        data["disturbance"] = (("time",), w)
    ds = xr.Dataset(
        data,
        coords={
            "time": ("time", t, {"units": "s"}),
            "output": list(ss.outputs),
            "output_units": ("output", list(ss.output_units)),
            "input": act_names,
            "input_units": ("input", act_units),
            "state": [*ss.states, *cstates],
        },
        attrs={
            "controller": "open loop" if law is None or act is None else law.description,
            "fs_out": float(fs_out),
            "method": method,
        },
    )
    return ds
