"""Active vibration controllers as small frozen objects.

Every controller has ``realize(plant, design_plant=None) -> FeedbackLaw``: the law in
the common form used by :func:`closed_loop` and :func:`simulate`,

    X = [x; xc],  X' = A X + Bu u + Bw w,  u = f(S X + Sz n),

with ``x`` the plant state, ``xc`` the controller state, ``n`` sensor noise on the
measurement and ``f`` the identity (linear), a clip at the actuator limit (saturation) or
the Lyapunov switching function.

Gain normalisation (``normalise="static"``, the default): a controller gain ``G`` is
divided by the static gain ``k_s`` of the plant from the actuator to the sensor output
(``dc_gain`` of the design plant). On a single-mode plant ``y = c xi``,
``xi'' + 2 z w xi' + w^2 xi = b u``, ``k_s = c b / w^2`` and the loop becomes exactly the
dimensionless SDOF form of PHYSICS.md section 4 (``G w^2 eta`` on the right-hand side).
On a collocated multi-mode plant the full static gain makes ``0 <= G < 1`` the exact PPF
stability range (``K - B Gamma B'`` positive definite). ``normalise="none"`` takes the
gain in actuator units per sensor unit.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from ..errors import DimensionError, ParameterError
from ._second_order import SecondOrderSystem
from ._statespace import StateSpace
from ._threads import small_dense

__all__ = [
    "PPF",
    "SRF",
    "VelocityFeedback",
    "LQR",
    "LyapunovBangBang",
    "FeedbackLaw",
    "plant_state_space",
]

_NORMALISE = ("static", "none")


def plant_state_space(plant: SecondOrderSystem | StateSpace) -> StateSpace:
    """The plant as a :class:`StateSpace` (``x = [q; q']`` for a second-order plant)."""
    if isinstance(plant, SecondOrderSystem):
        return plant.to_state_space()
    if isinstance(plant, StateSpace):
        return plant
    raise ParameterError(
        f"plant must be a SecondOrderSystem or a StateSpace, got {type(plant).__name__}"
    )


def _index(names: Sequence[str], name: str | None, what: str) -> int:
    names = tuple(names)
    if name is None:
        if not names:
            raise DimensionError(f"the plant has no {what}s")
        return 0
    if name not in names:
        raise ParameterError(f"unknown {what} {name!r}; the plant has {list(names)}")
    return names.index(name)


@dataclass(frozen=True, eq=False)
class FeedbackLaw:
    """A controller connected to a plant (see module docstring for the form).

    Attributes
    ----------
    A, Bu, Bw_noise : ndarray
        Open-loop augmented dynamics (plant and controller, controller driven by the
        measurement), actuator input matrix, and noise-to-state matrix ``Nz``.
    S, Sz : ndarray
        ``u = f(S X + Sz n)``; rows per actuator, ``Sz`` columns per measurement.
    kind : str
        ``"linear"``, ``"saturated"`` or ``"switching"``.
    n_plant : int
        Number of plant states (the first ones in X).
    u_max : float or None
        Actuator limit (input units).
    boundary_layer : float
        Width of the switching boundary layer (``"switching"`` only).
    layer : str
        ``"sat"`` or ``"tanh"`` smoothing of the switch.
    actuator : int
        Index of the actuated plant input (the first one of ``actuators``).
    actuators : tuple of int
        Indices of all actuated plant inputs of a multi-input law (``Bu`` and ``S``
        have one column / row per entry); empty for a single-input law.
    states, units : tuple of str
        Names of the controller states.

    Examples
    --------
    A controller connected to a plant (``realize``): here velocity feedback on one 10 Hz
    mode; the closed-loop damping is ``0.01 + G w / 2`` = 0.0414:

    >>> from mvtk.control import VelocityFeedback, modal_plant, modal_properties
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])
    >>> law = VelocityFeedback(gain=1e-3).realize(plant)
    >>> law.kind, law.is_linear
    ('linear', True)
    >>> np.round(modal_properties(np.linalg.eigvals(law.closed_loop_matrix())).zeta, 4)
    array([0.0414])
    """

    A: np.ndarray
    Bu: np.ndarray
    Nz: np.ndarray
    S: np.ndarray
    Sz: np.ndarray
    kind: str
    n_plant: int
    actuator: int
    controller_states: tuple[str, ...] = ()
    u_max: float | None = None
    boundary_layer: float = 0.0
    layer: str = "sat"
    description: str = ""
    meta: dict = field(default_factory=dict)
    A_loop: np.ndarray | None = None
    B_loop: np.ndarray | None = None
    actuators: tuple[int, ...] = ()

    @property
    def is_linear(self) -> bool:
        return self.kind == "linear"

    @property
    def actuator_indices(self) -> tuple[int, ...]:
        """Plant inputs the law drives, in the order of the rows of ``S``."""
        return tuple(self.actuators) if self.actuators else (int(self.actuator),)

    def slope(self) -> float:
        """``du/ds`` at ``s = 0``: 1 for linear and saturated laws, ``-u_max/eps`` for the
        switching law (its in-layer gain)."""
        return float(self.du_ds(np.zeros(1))[0])

    def linearized_matrix(self) -> np.ndarray:
        """``A + Bu (du/ds)(0) S``: the closed loop linearised at the origin.

        Equals :meth:`closed_loop_matrix` for a linear law; for a saturated law it is the
        unsaturated loop, for the switching law the in-layer (boundary-layer) loop. Its
        eigenvalues decide the local stability of the origin.
        """
        return self.A + self.slope() * (self.Bu @ self.S)

    def loop(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Loop transfer broken at the actuator input, ``L(s) = c (sI - A)^-1 b``.

        Returns ``(A, b, c)`` in the negative-feedback convention: the closed loop is
        ``A - b c`` (same eigenvalues as :meth:`linearized_matrix`), the characteristic
        equation ``1 + L(s) = 0``. The plant's own feedthrough into the measurement (a
        static correction) belongs to ``L``; the law is linearised at the origin.
        """
        A = self.A if self.A_loop is None else self.A_loop
        b = self.Bu if self.B_loop is None else self.B_loop
        return A, b, -self.slope() * self.S

    def u_of(self, s: np.ndarray) -> np.ndarray:
        """Actuator command for the switching argument(s) ``s`` (any shape)."""
        if self.kind == "linear":
            return s
        if self.kind == "saturated":
            return np.clip(s, -self.u_max, self.u_max)
        z = s / self.boundary_layer
        sw = np.tanh(z) if self.layer == "tanh" else np.clip(z, -1.0, 1.0)
        return -self.u_max * sw

    def u_scalar(self, s: float) -> float:
        """:meth:`u_of` for one actuator and a Python float (fast path)."""
        if self.kind == "linear":
            return s
        if self.kind == "saturated":
            return min(max(s, -self.u_max), self.u_max)
        z = s / self.boundary_layer
        if self.layer == "tanh":
            return -self.u_max * math.tanh(z)
        return -self.u_max * min(max(z, -1.0), 1.0)

    def du_ds(self, s: np.ndarray) -> np.ndarray:
        """Derivative of :meth:`u_of` (for the integrator Jacobian)."""
        if self.kind == "linear":
            return np.ones_like(s)
        if self.kind == "saturated":
            return (np.abs(s) < self.u_max).astype(float)
        z = s / self.boundary_layer
        if self.layer == "tanh":
            return -self.u_max / self.boundary_layer / np.cosh(np.clip(z, -350, 350)) ** 2
        return -self.u_max / self.boundary_layer * (np.abs(z) < 1.0)

    def closed_loop_matrix(self) -> np.ndarray:
        """``A + Bu S`` (the linear closed loop; unsaturated)."""
        if self.kind == "switching":
            raise ParameterError("a switching (Lyapunov) law has no linear closed loop")
        return self.A + self.Bu @ self.S


def _check_u_max(u_max: float | None) -> None:
    if u_max is not None and not (np.isfinite(u_max) and u_max > 0):
        raise ParameterError(f"u_max must be a finite positive actuator limit, got {u_max}")


def _measurement(ss: StateSpace, sensor: str | None, rate: bool, act: int) -> tuple:
    """Rows ``(Cz, Dz, Dzdot)`` of the measurement ``z = Cz x + Dz u + Dzdot u'``: the
    output ``sensor`` (``Dz = D``) or its time derivative (``Cz = C A``, ``Dz = C B``,
    ``Dzdot = D``, the feedthrough of a static correction)."""
    j = _index(ss.outputs, sensor, "output")
    c = ss.C[j]
    d = ss.D[j, act]
    if not rate:
        return c[None, :], np.array([[d]]), np.zeros((1, 1))
    cb = c @ ss.B[:, act]
    return (c @ ss.A)[None, :], np.array([[cb]]), np.array([[d]])


def _static_gain(ss: StateSpace, act: int, sensor: str | None) -> float:
    j = _index(ss.outputs, sensor, "output")
    try:
        k = float(-(ss.C[j] @ np.linalg.solve(ss.A, ss.B[:, act])) + ss.D[j, act])
    except np.linalg.LinAlgError as err:
        raise ParameterError(
            "cannot normalise the gain by the static gain: the plant A matrix is singular "
            "(rigid-body modes?); use normalise='none'"
        ) from err
    if not np.isfinite(k) or k == 0.0:
        raise ParameterError(
            f"static gain from input {ss.inputs[act]!r} to output {ss.outputs[j]!r} is {k}; "
            "cannot normalise the controller gain, use normalise='none'"
        )
    return k


@dataclass(frozen=True)
class _Ctrl:
    """Controller ``xc' = Ac xc + Bc z``, ``u = Cc xc + Dc z`` (may have no state)."""

    Ac: np.ndarray
    Bc: np.ndarray
    Cc: np.ndarray
    Dc: np.ndarray
    states: tuple[str, ...] = ()


def _linear_law(
    ss: StateSpace, act: int, meas: tuple[np.ndarray, np.ndarray], ctrl: _Ctrl,
    u_max: float | None, description: str, meta: dict,
) -> FeedbackLaw:
    """Connect the controller ``ctrl`` (input: measurement z, output: u) to the plant."""
    Cz, Dz, Dzdot = meas
    n, nc = ss.n_states, ctrl.Ac.shape[0]
    direct = np.any(Dz != 0) or np.any(Dzdot != 0)
    if direct and np.any(ctrl.Dc != 0):
        raise ParameterError(
            "algebraic loop: the measured signal depends directly on the actuator (plant "
            "feedthrough D != 0, e.g. a static correction, or a velocity output) and the "
            "controller has a direct term; use a filter controller (PPF, SRF) or a sensor "
            "without feedthrough"
        )
    if np.any(Dzdot != 0) and np.any(ctrl.Cc @ ctrl.Bc != 0):
        raise ParameterError("the controller output must not depend on its input rate")
    A = np.zeros((n + nc, n + nc))
    A[:n, :n] = ss.A
    A[n:, :n] = ctrl.Bc @ Cz
    A[n:, n:] = ctrl.Ac
    Bu = np.vstack([ss.B[:, [act]], np.zeros((nc, 1))])
    S = np.hstack([ctrl.Dc @ Cz, ctrl.Cc])
    # loop broken at the actuator input v (plant input and measurement feedthrough):
    # X' = A0 X + [b; Bc Dz] v + [0; Bc Dzdot] v', u = S X; with X~ = X - [0; Bc Dzdot] v
    # (S [0; Bc Dzdot] = Cc Bc Dzdot = 0) the loop is (A0, [b; Bc Dz] + A0 [0; Bc Dzdot], S)
    A_loop = A.copy()
    E = np.vstack([np.zeros((n, 1)), ctrl.Bc @ Dzdot])
    B_loop = np.vstack([ss.B[:, [act]], ctrl.Bc @ Dz]) + A_loop @ E
    if direct:  # z = Cz x + Dz u + Dzdot u', u = Cc xc, u' = Cc Ac xc (Dc = 0, Cc Bc = 0)
        A[n:, :] += ctrl.Bc @ Dz @ S
        A[n:, n:] += ctrl.Bc @ Dzdot @ ctrl.Cc @ ctrl.Ac
    Nz = np.vstack([np.zeros((n, Cz.shape[0])), ctrl.Bc])
    return FeedbackLaw(
        A=A, Bu=Bu, Nz=Nz, S=S, Sz=ctrl.Dc.copy(),
        kind="linear" if u_max is None else "saturated", n_plant=n, actuator=act,
        controller_states=tuple(ctrl.states), u_max=u_max, description=description, meta=meta,
        A_loop=A_loop, B_loop=B_loop,
    )


def _targets(targets, name: str) -> tuple[tuple[float, float, float], ...]:
    try:
        out = tuple((float(f), float(z), float(g)) for f, z, g in targets)
    except (TypeError, ValueError) as err:
        raise ParameterError(
            f"{name} targets must be a sequence of (f_hz, zeta_f, gain) triples, got {targets!r}"
        ) from err
    if not out:
        raise ParameterError(f"{name} needs at least one (f_hz, zeta_f, gain) filter")
    for f, z, g in out:
        if not (f > 0 and np.isfinite(f)) or not (z > 0 and np.isfinite(z)) or not np.isfinite(g):
            raise ParameterError(
                f"{name} filter (f_hz={f}, zeta_f={z}, gain={g}): expected f_hz > 0, "
                "zeta_f > 0 and a finite gain"
            )
    return out


def _filter_bank(targets, gains: Sequence[float], sign: float, prefix: str) -> _Ctrl:
    """Second-order filters ``eta'' + 2 zf wf eta' + wf^2 eta = wf^2 z``, ``u = sign sum g eta``."""
    k = len(targets)
    A = np.zeros((2 * k, 2 * k))
    B = np.zeros((2 * k, 1))
    C = np.zeros((1, 2 * k))
    states = []
    for i, ((f, z, _), g) in enumerate(zip(targets, gains)):
        wf = 2 * np.pi * f
        A[2 * i, 2 * i + 1] = 1.0
        A[2 * i + 1, 2 * i] = -wf**2
        A[2 * i + 1, 2 * i + 1] = -2 * z * wf
        B[2 * i + 1, 0] = wf**2
        C[0, 2 * i] = sign * g
        states += [f"{prefix}{i + 1}.eta", f"{prefix}{i + 1}.deta"]
    return _Ctrl(A, B, C, np.zeros((1, 1)), tuple(states))


@dataclass(frozen=True)
class _FilterController:
    targets: Sequence[tuple[float, float, float]]
    sensor: str | None = None
    actuator: str | None = None
    normalise: str = "static"
    u_max: float | None = None

    _rate = False
    _sign = 1.0
    _name = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "targets", _targets(self.targets, self._name))
        if self.normalise not in _NORMALISE:
            raise ParameterError(
                f"normalise must be one of {_NORMALISE}, got {self.normalise!r}"
            )
        _check_u_max(self.u_max)

    def _bank(self, ss: StateSpace, design_plant) -> tuple[int, _Ctrl, dict]:
        act = _index(ss.inputs, self.actuator, "input")
        k_s = 1.0
        if self.normalise == "static":
            dss = plant_state_space(design_plant) if design_plant is not None else ss
            k_s = _static_gain(dss, _index(dss.inputs, ss.inputs[act], "input"),
                               ss.outputs[_index(ss.outputs, self.sensor, "output")])
        gains = [g / k_s for _, _, g in self.targets]
        ctrl = _filter_bank(self.targets, gains, self._sign, self._name)
        meta = {"controller": self._name, "static_gain": k_s, "physical_gains": gains}
        return act, ctrl, meta

    def realize(
        self, plant: SecondOrderSystem | StateSpace, design_plant=None
    ) -> FeedbackLaw:
        """Connect to ``plant``; gains normalised on ``design_plant`` (default ``plant``)."""
        ss = plant_state_space(plant)
        act, ctrl, meta = self._bank(ss, design_plant)
        meas = _measurement(ss, self.sensor, self._rate, act)
        return _linear_law(ss, act, meas, ctrl, self.u_max, repr(self), meta)

    def state_space(self, plant, design_plant=None) -> StateSpace:
        """The controller alone: input the measured signal (the sensor output, or its rate
        ``"d(<sensor>)/dt"`` for SRF), output the actuator command (physical gains)."""
        ss = plant_state_space(plant)
        act, ctrl, meta = self._bank(ss, design_plant)
        j = _index(ss.outputs, self.sensor, "output")
        name, unit = ss.outputs[j], ss.output_units[j]
        if self._rate:
            name, unit = f"d({name})/dt", f"{unit}/s" if unit else ""
        return StateSpace(ctrl.Ac, ctrl.Bc, ctrl.Cc, ctrl.Dc, inputs=[name],
                          outputs=[ss.inputs[act]], states=list(ctrl.states),
                          input_units=[unit], output_units=[ss.input_units[act]], meta=meta)


@dataclass(frozen=True)
class PPF(_FilterController):
    """Positive position feedback (Goh & Caughey 1985; Fanson & Caughey 1990).

    Each filter ``(f_hz, zeta_f, G)``: ``eta'' + 2 zf wf eta' + wf^2 eta = wf^2 y`` on the
    sensor output ``y``; the actuator command is ``u = sum_i (G_i / k_s) eta_i``. In the
    single-mode form ``xi'' + 2 z w xi' + w^2 xi = G w^2 eta`` the loop is stable iff
    ``0 <= G < 1`` (any wf, zf). With ``wf = w`` and small ``G`` the added damping is
    ``G / (4 zf)`` (the paper's eq. 15: ``G w / (2 zf)`` added to ``2 z w``).

    Parameters
    ----------
    targets : sequence of (f_hz, zeta_f, gain)
        Filter frequency (Hz), filter damping ratio and dimensionless gain per filter.
    sensor, actuator : str, optional
        Plant output fed to the filters and plant input driven (default the first ones).
    normalise : {"static", "none"}
        Gain normalisation (module docstring).
    u_max : float, optional
        Actuator limit (input units, e.g. V): the command is clipped to +-u_max.

    Examples
    --------
    A PPF filter tuned on the mode (10 Hz, filter damping 0.1, gain 0.5); the single-mode
    loop is stable for ``0 <= G < 1``:

    >>> from mvtk.control import closed_loop_stability, critical_gain, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> ppf = PPF([(10.0, 0.1, 0.5)])
    >>> closed_loop_stability(plant, ppf).verdict
    'stable'
    >>> round(critical_gain(plant, PPF([(10.0, 0.1, 0.5)]), g_max=5.0), 4)
    1.0
    """

    _sign = 1.0
    _name = "PPF"


@dataclass(frozen=True)
class SRF(_FilterController):
    """Strain-rate feedback (Newman 1992), standard form of PHYSICS.md section 4.

    ``eta'' + 2 zf wf eta' + wf^2 eta = wf^2 y'`` on the rate of the sensor output and
    ``u = -sum_i (G_i / k_s) eta_i``; single mode:
    ``xi'' + 2 z w xi' + w^2 xi = -G w^2 eta``. With ``z = 0`` stable for
    ``0 < G < 2 zf (wf^2 - w^2) / (w^2 wf)`` (units of s): the filter must be tuned
    above the mode (see :func:`srf_gain_limit`). The paper's eqs. 16-17 are garbled.

    ``sensor`` must be a displacement-type output (``Cv = 0``); its rate is formed from
    the plant states (an ideal rate sensor). Parameters as :class:`PPF`.

    Examples
    --------
    An SRF filter tuned above the mode (15 Hz, 0.3); for the undamped mode the gain limit
    is ``2 zf (wf**2 - w**2) / (w**2 wf)`` = 7.96 ms (:func:`~mvtk.control.srf_gain_limit`):

    >>> from mvtk.control import closed_loop_stability, modal_plant, srf_gain_limit
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> round(srf_gain_limit(10.0, 15.0, 0.3) * 1e3, 2)      # ms
    7.96
    >>> closed_loop_stability(plant, SRF([(15.0, 0.3, 4e-3)])).verdict
    'stable'
    """

    _rate = True
    _sign = -1.0
    _name = "SRF"


@dataclass(frozen=True)
class VelocityFeedback:
    """Direct velocity feedback ``u = -(G / k_s) y'`` on the rate of the sensor output.

    Single mode with ``normalise="static"``: ``xi'' + (2 z w + G w^2) xi' + w^2 xi = 0``,
    so the added damping ratio is ``G w / 2`` (``G`` in s). Unconditionally stable when
    collocated.

    Examples
    --------
    On a single mode the added damping ratio is ``G w / 2``: with G = 1 ms at 10 Hz,
    0.01 + 0.0314 = 0.0414:

    >>> from mvtk.control import closed_loop_modes, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> np.round(closed_loop_modes(plant, VelocityFeedback(gain=1e-3)).zeta, 4)
    array([0.0414])
    """

    gain: float
    sensor: str | None = None
    actuator: str | None = None
    normalise: str = "static"
    u_max: float | None = None

    def __post_init__(self) -> None:
        if not np.isfinite(self.gain):
            raise ParameterError(f"VelocityFeedback gain must be finite, got {self.gain}")
        if self.normalise not in _NORMALISE:
            raise ParameterError(
                f"normalise must be one of {_NORMALISE}, got {self.normalise!r}"
            )
        _check_u_max(self.u_max)

    def realize(self, plant, design_plant=None) -> FeedbackLaw:
        """Connect to ``plant``; gain normalised on ``design_plant`` (default ``plant``)."""
        ss = plant_state_space(plant)
        act = _index(ss.inputs, self.actuator, "input")
        meas = _measurement(ss, self.sensor, True, act)
        k_s = 1.0
        if self.normalise == "static":
            dss = plant_state_space(design_plant) if design_plant is not None else ss
            k_s = _static_gain(dss, _index(dss.inputs, ss.inputs[act], "input"),
                               ss.outputs[_index(ss.outputs, self.sensor, "output")])
        g = self.gain / k_s
        ctrl = _Ctrl(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), np.array([[-g]]))
        meta = {"controller": "VelocityFeedback", "static_gain": k_s, "physical_gains": [g]}
        return _linear_law(ss, act, meas, ctrl, self.u_max, repr(self), meta)


@dataclass(frozen=True)
class LQR:
    """Linear-quadratic regulator, full-state feedback ``u = -K x`` (ideal baseline).

    Minimises the integral of ``x'Qx + u'Ru``. ``Q=None`` on a second-order plant uses the
    energy weighting ``blkdiag(K, M)`` (``x'Qx`` = twice the mechanical energy) times
    ``q_scale``. Needs the full plant state (no observer).

    ``actuator`` may name several plant inputs (e.g. the voltages of several piezo
    patches): :meth:`gain_matrix` then solves the multi-input Riccati equation with
    ``R`` times the identity and :meth:`closed_loop_poles` gives the poles of
    ``A - B K``; :meth:`realize` connects all of them (one command per actuator, each
    clipped to ``u_max``), so :func:`~mvtk.control.simulate` and
    :func:`~mvtk.control.closed_loop` run the multi-input loop.

    Examples
    --------
    Full-state LQR with the energy weighting (unit R) on one mode:

    >>> from mvtk.control import closed_loop_modes, closed_loop_stability, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> lqr = LQR(R=1.0)
    >>> closed_loop_stability(plant, lqr).verdict, np.round(closed_loop_modes(plant, lqr).zeta, 4)
    ('stable', array([0.0151]))
    """

    R: float = 1.0
    Q: np.ndarray | None = None
    q_scale: float = 1.0
    actuator: str | Sequence[str] | None = None
    u_max: float | None = None

    def _inputs(self, ss: StateSpace) -> list[int]:
        if self.actuator is None or isinstance(self.actuator, str):
            return [_index(ss.inputs, self.actuator, "input")]
        acts = [_index(ss.inputs, a, "input") for a in self.actuator]
        if not acts or len(set(acts)) != len(acts):
            raise ParameterError(f"LQR actuators must be distinct plant inputs, got "
                                 f"{list(self.actuator)!r}")
        return acts

    def closed_loop_poles(self, plant) -> np.ndarray:
        """Poles (rad/s) of ``A - B K`` with every actuator of :meth:`gain_matrix`."""
        ss = plant_state_space(plant)
        b = ss.B[:, self._inputs(ss)]
        return np.linalg.eigvals(ss.A - b @ self.gain_matrix(plant))

    def __post_init__(self) -> None:
        if not (np.isfinite(self.R) and self.R > 0):
            raise ParameterError(f"LQR R must be a positive scalar, got {self.R}")
        if not (np.isfinite(self.q_scale) and self.q_scale > 0):
            raise ParameterError(f"LQR q_scale must be > 0, got {self.q_scale}")
        _check_u_max(self.u_max)

    def gain_matrix(self, plant) -> np.ndarray:
        """State-feedback gain K (n_actuators, n_states) from the continuous Riccati
        equation."""
        ss = plant_state_space(plant)
        acts = self._inputs(ss)
        n = ss.n_states
        if self.Q is None:
            if not isinstance(plant, SecondOrderSystem):
                raise ParameterError("LQR with Q=None needs a SecondOrderSystem (energy weight)")
            Q = scipy.linalg.block_diag(plant.K, plant.M) * self.q_scale
        else:
            Q = np.asarray(self.Q, dtype=float) * self.q_scale
            if Q.shape != (n, n):
                raise DimensionError(f"LQR Q must have shape ({n}, {n}), got {Q.shape}")
        b = ss.B[:, acts]
        with small_dense(2 * n + len(acts)):  # the QZ of the pencil: one BLAS thread
            P = scipy.linalg.solve_continuous_are(ss.A, b, Q, self.R * np.eye(len(acts)))
        return (b.T @ P) / self.R

    def realize(self, plant, design_plant=None) -> FeedbackLaw:
        """Connect to ``plant`` (gain computed on ``design_plant`` if given, same states)."""
        ss = plant_state_space(plant)
        acts = self._inputs(ss)
        if design_plant is not None:
            dss = plant_state_space(design_plant)
            if [dss.inputs[i] for i in self._inputs(dss)] != [ss.inputs[i] for i in acts]:
                raise ParameterError("LQR: the design plant must have the actuators "
                                     f"{[ss.inputs[i] for i in acts]} of the plant")
        Kg = self.gain_matrix(design_plant if design_plant is not None else plant)
        if Kg.shape[1] != ss.n_states:
            raise DimensionError(
                f"LQR designed on {Kg.shape[1]} states cannot drive a plant with "
                f"{ss.n_states} states"
            )
        n = ss.n_states
        meta = {"controller": "LQR", "gain": Kg}
        if len(acts) == 1:
            ctrl = _Ctrl(np.zeros((0, 0)), np.zeros((0, n)), np.zeros((1, 0)), -Kg)
            meas = (np.eye(n), np.zeros((n, 1)), np.zeros((n, 1)))
            return _linear_law(ss, acts[0], meas, ctrl, self.u_max, repr(self), meta)
        # full-state feedback on every actuator: u = -K x (the state is the measurement)
        Bu = ss.B[:, acts]
        return FeedbackLaw(
            A=ss.A.copy(), Bu=Bu, Nz=np.zeros((n, n)), S=-Kg, Sz=-Kg.copy(),
            kind="linear" if self.u_max is None else "saturated", n_plant=n,
            actuator=acts[0], u_max=self.u_max, description=repr(self), meta=meta,
            A_loop=ss.A.copy(), B_loop=Bu, actuators=tuple(acts))


@dataclass(frozen=True)
class LyapunovBangBang:
    """Lyapunov-based switching law with a boundary layer and an actuator limit.

    ``form="velocity"`` (energy ``V = q'Mq'/2 + q'Kq/2``, ``V' = -q'Cq' + q'^T B u``):
    ``u = -u_max sat(B' q' / eps)``, constant-amplitude velocity feedback; needs a
    :class:`SecondOrderSystem`. ``form="state"``: ``V = x'Px`` with ``A'P + PA = -Q``
    (``Q`` default identity) and ``u = -u_max sat(B'P x / eps)``. ``layer="tanh"``
    replaces ``sat`` by ``tanh``. Both make ``V`` non-increasing (with Rayleigh damping,
    strictly decreasing). The exact law of Ghareeb & Schmidt 2012 was not available; the
    velocity form (velocity as the fed-back signal) is the one that reproduces the
    paper's observation that SRF and Lyapunov behave alike, and it is the one mvtk reports.

    Parameters
    ----------
    u_max : float
        Actuator amplitude (input units, e.g. V).
    boundary_layer : float
        ``eps`` > 0 in units of the switching signal (``B'q'``: generalised force per
        input unit times velocity). ``eps -> 0`` is the hard switch, which chatters and is
        refused.

    Examples
    --------
    Switching velocity feedback limited to 1 N: the command saturates at ``u_max``:

    >>> from mvtk.control import modal_plant, release_state, simulate
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> law = LyapunovBangBang(u_max=1.0, boundary_layer=1e-3)
    >>> sim = simulate(plant, law, t_end=0.5, fs_out=200.0,
    ...                initial=release_state(plant, 1, "tip", 1e-3))
    >>> round(float(abs(sim.inputs).max()), 6)
    1.0
    """

    u_max: float
    boundary_layer: float
    form: str = "velocity"
    Q: np.ndarray | None = None
    actuator: str | None = None
    layer: str = "sat"

    def __post_init__(self) -> None:
        _check_u_max(self.u_max)
        if self.u_max is None:
            raise ParameterError("LyapunovBangBang needs u_max (actuator amplitude), got None")
        if not (np.isfinite(self.boundary_layer) and self.boundary_layer > 0):
            raise ParameterError(
                f"boundary_layer must be > 0 (the hard switch eps=0 chatters), got "
                f"{self.boundary_layer}"
            )
        if self.form not in ("velocity", "state"):
            raise ParameterError(f"form must be 'velocity' or 'state', got {self.form!r}")
        if self.layer not in ("sat", "tanh"):
            raise ParameterError(f"layer must be 'sat' or 'tanh', got {self.layer!r}")

    def realize(self, plant, design_plant=None) -> FeedbackLaw:
        """Connect to ``plant`` (``design_plant`` is ignored: the law uses plant B, P)."""
        ss = plant_state_space(plant)
        act = _index(ss.inputs, self.actuator, "input")
        n = ss.n_states
        if self.form == "velocity":
            if not isinstance(plant, SecondOrderSystem):
                raise ParameterError(
                    "LyapunovBangBang(form='velocity') needs a SecondOrderSystem plant "
                    f"(B' q'), got {type(plant).__name__}"
                )
            nq = plant.n_coords
            S = np.hstack([np.zeros(nq), plant.B[:, act]])[None, :]
        else:
            Q = np.eye(n) if self.Q is None else np.asarray(self.Q, dtype=float)
            if Q.shape != (n, n):
                raise DimensionError(f"Lyapunov Q must have shape ({n}, {n}), got {Q.shape}")
            if np.max(np.linalg.eigvals(ss.A).real) >= 0:
                raise ParameterError(
                    "form='state' needs an asymptotically stable open-loop A (A'P + PA = -Q)"
                )
            P = scipy.linalg.solve_continuous_lyapunov(ss.A.T, -Q)
            S = ss.B[:, [act]].T @ P
        return FeedbackLaw(
            A=ss.A.copy(), Bu=ss.B[:, [act]].copy(), Nz=np.zeros((n, 1)), S=S,
            Sz=np.ones((1, 1)), kind="switching", n_plant=n, actuator=act,
            u_max=float(self.u_max), boundary_layer=float(self.boundary_layer),
            layer=self.layer, description=repr(self),
            meta={"controller": "Lyapunov", "form": self.form},
        )
