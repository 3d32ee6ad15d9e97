"""Small modal plants for controller design, tests and benchmarks.

:func:`modal_plant` builds a :class:`SecondOrderSystem` in mass-normalised modal
coordinates; :func:`cantilever_modal_plant` fills it with the closed-form
Euler-Bernoulli cantilever modes, a pin-force piezo patch (equal and opposite moments at
the patch ends) as actuator and the tip displacement as sensor.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import DimensionError, ParameterError
from ._second_order import SecondOrderSystem

__all__ = ["modal_plant", "cantilever_modal_plant", "cantilever_beta_l"]

#: Roots of 1 + cos(bL) cosh(bL) = 0 for the first four cantilever modes.
_BETA_L = (1.8751040687119611, 4.6940911329741746, 7.8547574382376126, 10.995540734875467)


def cantilever_beta_l(n_modes: int) -> np.ndarray:
    """Eigenvalues ``beta_n L`` of the clamped-free Euler-Bernoulli beam.

    Roots of ``cos b + 1 / cosh b = 0`` (i.e. ``1 + cos b cosh b = 0``): tabulated for
    n <= 4, Newton-refined from ``(2n - 1) pi / 2`` beyond.
    """
    if n_modes < 1:
        raise ParameterError(f"n_modes must be >= 1, got {n_modes}")
    out = []
    for i in range(n_modes):
        if i < 4:
            out.append(_BETA_L[i])
            continue
        b = (2 * i + 1) * np.pi / 2
        for _ in range(3):
            b -= (np.cos(b) + 1 / np.cosh(b)) / (-np.sin(b) - np.tanh(b) / np.cosh(b))
        out.append(b)
    return np.array(out)


def modal_plant(
    fn_hz: Sequence[float],
    zeta: Sequence[float] | float,
    B: np.ndarray,
    Cq: np.ndarray,
    Cv: np.ndarray | None = None,
    *,
    inputs: Sequence[str] | None = None,
    outputs: Sequence[str] | None = None,
    input_units: Sequence[str] | None = None,
    output_units: Sequence[str] | None = None,
) -> SecondOrderSystem:
    """Second-order plant in mass-normalised modal coordinates.

    ``q_i'' + 2 zeta_i omega_i q_i' + omega_i^2 q_i = (B u)_i``, ``y = Cq q + Cv q'``.

    Parameters
    ----------
    fn_hz : sequence of float
        Natural frequencies (Hz), all > 0.
    zeta : float or sequence of float
        Modal damping ratios (one value for all modes allowed).
    B : ndarray, shape (n_modes, n_inputs)
        Modal input matrix (modal force per unit input).
    Cq, Cv : ndarray, shape (n_outputs, n_modes)
        Output matrices on modal displacement and velocity (``Cv`` zeros if omitted).

    Examples
    --------
    One mass-normalised mode at 10 Hz with 1 % damping, force in, displacement out:

    >>> from mvtk.control import closed_loop_modes
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> plant.inputs, plant.outputs
    (('force',), ('tip',))
    >>> m = closed_loop_modes(plant)
    >>> m.fn_hz, np.round(m.zeta, 6)
    (array([10.]), array([0.01]))
    """
    fn = np.atleast_1d(np.asarray(fn_hz, dtype=float))
    n = fn.size
    if n == 0 or np.any(fn <= 0) or not np.all(np.isfinite(fn)):
        raise ParameterError(f"fn_hz must be finite and > 0, got {fn}")
    z = np.broadcast_to(np.asarray(zeta, dtype=float), (n,)) if np.ndim(zeta) == 0 else (
        np.asarray(zeta, dtype=float)
    )
    if z.shape != (n,):
        raise DimensionError(f"zeta must be a scalar or have {n} values, got shape {z.shape}")
    if np.any(z < 0):
        raise ParameterError(f"zeta must be >= 0, got {z}")
    w = 2 * np.pi * fn
    B = np.asarray(B, dtype=float).reshape(n, -1)
    Cq = np.atleast_2d(np.asarray(Cq, dtype=float))
    if Cq.shape[1] != n:
        raise DimensionError(f"Cq must have {n} columns (one per mode), got shape {Cq.shape}")
    Cv = np.zeros_like(Cq) if Cv is None else np.atleast_2d(np.asarray(Cv, dtype=float))
    return SecondOrderSystem(
        M=np.eye(n), C=np.diag(2 * z * w), K=np.diag(w**2), B=B, Cq=Cq, Cv=Cv,
        inputs=inputs, outputs=outputs, coords=[f"mode{i + 1}" for i in range(n)],
        input_units=input_units, output_units=output_units,
        meta={"fn_hz": fn.tolist(), "zeta": z.tolist(), "form": "modal"},
    )


def _cantilever_shape(beta_l: float, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape phi and slope dphi/d(beta x) at s = beta x, overflow-free.

    phi = cosh s - cos s - sigma (sinh s - sin s), normalised so that the integral of
    phi^2 over the length equals the length.
    """
    b = beta_l
    e = np.exp(-b)
    den = 1 - e * e + 2 * e * np.sin(b)
    # 1 - sigma = (sin b - cos b - e^-b) / (sinh b + sin b), without cancellation
    num = np.sin(b) - np.cos(b) - e
    sig = 1.0 - 2 * e * num / den
    grow = np.exp(s - b) * num / den  # e^s (1 - sigma) / 2
    decay = 0.5 * (1 + sig) * np.exp(-s)
    phi = grow + decay - np.cos(s) + sig * np.sin(s)
    dphi = grow - decay + np.sin(s) + sig * np.cos(s)
    return phi, dphi


def cantilever_modal_plant(
    n_modes: int = 3,
    *,
    length: float = 0.18,
    mass_per_length: float = 0.158,
    f1_hz: float = 13.26,
    alpha: float = 0.02955,
    beta: float = 9.77e-6,
    patch: tuple[float, float] = (0.005, 0.055),
    moment_per_volt: float = -1.984e-4,
    sensor_x: float | None = None,
) -> SecondOrderSystem:
    """Modal plant of a uniform Euler-Bernoulli cantilever with a piezo patch.

    Input ``"patch"`` (V): the patch acts as equal and opposite bending moments
    ``moment_per_volt * V`` at its ends ``patch = (x1, x2)`` (pin-force model, Crawley &
    de Luis 1987), so the modal force is ``moment_per_volt * (phi'(x2) - phi'(x1))``.
    Outputs ``"tip"`` (m, transverse displacement at ``sensor_x``, default the tip),
    ``"tip_velocity"`` (m/s) and ``"patch_rotation"`` (rad, slope difference between the
    patch ends, proportional to the patch strain: the collocated sensor, ``B = moment_per_volt
    Cq[patch_rotation]'``). Rayleigh damping ``zeta_i = alpha/(2 w_i) + beta w_i/2``.

    Parameters
    ----------
    n_modes : int
        Number of bending modes kept.
    length : float
        Free length L (m).
    mass_per_length : float
        Mass per unit length (kg/m); with ``f1_hz`` it fixes the bending stiffness
        ``EI = mu L^4 w1^2 / (beta_1 L)^4``.
    f1_hz : float
        First natural frequency (Hz); default the paper's measured 13.26 Hz.
    alpha, beta : float
        Rayleigh coefficients (1/s, s); defaults are the paper's half-power pair (Table 3).
    patch : (float, float)
        Patch end coordinates from the clamp (m).
    moment_per_volt : float
        Bending moment per volt (N m/V); default -4.96e-3 N m/(V m) (PHYSICS.md section 1)
        times a 40 mm patch width.
    sensor_x : float, optional
        Sensor position (m), default ``length``.

    Notes
    -----
    Modes are mass-normalised analytically (the integral of phi^2 over L equals L for the
    classical cantilever shape). Mode n has ``w_n = w_1 (beta_n L / beta_1 L)^2``.

    Examples
    --------
    Euler-Bernoulli cantilever modes: ``f_k / f_1 = (lambda_k / lambda_1)**2`` = 6.267,
    17.547 for f1 = 13.26 Hz:

    >>> from mvtk.control import closed_loop_modes
    >>> plant = cantilever_modal_plant(3)
    >>> np.round(closed_loop_modes(plant).fn_hz, 1), plant.inputs
    (array([ 13.3,  83.1, 232.7]), ('patch',))
    """
    L = float(length)
    if L <= 0 or mass_per_length <= 0 or f1_hz <= 0:
        raise ParameterError(
            f"length, mass_per_length and f1_hz must be > 0, got {length}, "
            f"{mass_per_length}, {f1_hz}"
        )
    x1, x2 = (float(v) for v in patch)
    xs = L if sensor_x is None else float(sensor_x)
    if not (0 <= x1 < x2 <= L) or not (0 <= xs <= L):
        raise ParameterError(
            f"expected 0 <= patch[0] < patch[1] <= length={L} and 0 <= sensor_x <= length, "
            f"got patch={patch}, sensor_x={sensor_x}"
        )
    bl = cantilever_beta_l(n_modes)
    w = 2 * np.pi * f1_hz * (bl / bl[0]) ** 2
    zeta = alpha / (2 * w) + beta * w / 2
    scale = 1.0 / np.sqrt(mass_per_length * L)
    B = np.zeros((n_modes, 1))
    Cq = np.zeros((3, n_modes))
    Cv = np.zeros((3, n_modes))
    for i, b in enumerate(bl):
        beta_n = b / L
        _, d1 = _cantilever_shape(b, np.array(beta_n * x1))
        _, d2 = _cantilever_shape(b, np.array(beta_n * x2))
        phi_s, _ = _cantilever_shape(b, np.array(beta_n * xs))
        B[i, 0] = moment_per_volt * scale * beta_n * (d2 - d1)
        Cq[2, i] = scale * beta_n * (d2 - d1)
        Cq[0, i] = scale * phi_s
        Cv[1, i] = scale * phi_s
    plant = modal_plant(
        w / (2 * np.pi), zeta, B, Cq, Cv, inputs=["patch"],
        outputs=["tip", "tip_velocity", "patch_rotation"], input_units=["V"],
        output_units=["m", "m/s", "rad"],
    )
    meta = dict(plant.meta)
    meta.update(source="cantilever_modal_plant", length=L, patch=(x1, x2), alpha=alpha,
                beta=beta, EI=mass_per_length * L**4 * (2 * np.pi * f1_hz) ** 2 / bl[0] ** 4)
    object.__setattr__(plant, "meta", meta)
    return plant
