"""Seeded synthetic vibration signals with known natural frequencies and damping.

Every generator returns data on the DESIGN.md conventions (time histories as
``xarray.DataArray`` with dims ``("channel", "time")``; FRFs with dims
``("response", "reference", "frequency")``) so that estimators can be tested
against exact values. Random numbers come only from an explicit
:class:`numpy.random.Generator`.

The modal model used throughout is a sum of viscously damped modes with unit
modal mass::

    H(omega) = sum_r A_r / (omega_r**2 - omega**2 + 2j zeta_r omega_r omega)

(receptance, m/N for ``A_r`` in 1/kg); mobility and accelerance are ``1j omega H``
and ``-omega**2 H``.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import xarray as xr

from .errors import ParameterError

__all__ = [
    "make_time_history",
    "sdof_free_decay",
    "mdof_free_decay",
    "impulse_response",
    "modal_frf",
    "add_noise",
    "random_excitation_test",
    "impact_test",
]

_KIND_POWER = {"receptance": 0, "mobility": 1, "accelerance": 2}
_KIND_QUANTITY = {
    "receptance": ("displacement", "m"),
    "mobility": ("velocity", "m/s"),
    "accelerance": ("acceleration", "m/s^2"),
}


def _modal_arrays(fn_hz, zeta, modal_constants):
    fn = np.atleast_1d(np.asarray(fn_hz, dtype=float))
    z = np.broadcast_to(np.asarray(zeta, dtype=float), fn.shape).copy()
    a = np.broadcast_to(np.asarray(modal_constants, dtype=float), fn.shape).copy()
    if fn.ndim != 1:
        raise ParameterError(f"fn_hz must be a scalar or 1-D sequence, got shape {fn.shape}")
    if np.any(~np.isfinite(fn)) or np.any(fn <= 0):
        raise ParameterError(f"fn_hz must be finite and > 0 Hz, got {fn.tolist()}")
    if np.any(~np.isfinite(z)) or np.any(z < 0) or np.any(z >= 1):
        raise ParameterError(f"zeta must be in [0, 1) (a ratio, not %), got {z.tolist()}")
    return fn, z, a


def _check_kind(kind: str) -> int:
    if kind not in _KIND_POWER:
        raise ParameterError(
            f"kind must be one of {sorted(_KIND_POWER)}, got {kind!r}"
        )
    return _KIND_POWER[kind]


def _time(fs: float, duration: float) -> np.ndarray:
    if not (np.isfinite(fs) and fs > 0):
        raise ParameterError(f"fs must be a finite sampling rate > 0 Hz, got {fs!r}")
    if not (np.isfinite(duration) and duration > 0):
        raise ParameterError(f"duration must be > 0 s, got {duration!r}")
    n = int(round(duration * fs))
    if n < 2:
        raise ParameterError(f"duration * fs must give at least 2 samples, got {n}")
    return np.arange(n) / fs


def make_time_history(
    data,
    fs: float,
    *,
    quantity: str | Sequence[str] = "displacement",
    units: str | Sequence[str] = "m",
    names: Sequence[str] | None = None,
    node: Sequence[int] | None = None,
    direction: Sequence[str] | None = None,
    attrs: dict | None = None,
) -> xr.DataArray:
    """Wrap an array of samples as a DESIGN.md time history.

    Parameters
    ----------
    data : array_like, shape (n_channel, n_time) or (n_time,)
        Samples in the channel's units.
    fs : float
        Sampling rate in Hz; the time coordinate is ``np.arange(n) / fs`` in s.
    quantity, units : str or sequence of str
        Per-channel physical quantity and unit string.
    names : sequence of str, optional
        Channel names (default ``"ch0"``, ``"ch1"``, ...).
    node, direction : sequence, optional
        Per-channel node number and direction label.
    attrs : dict, optional
        File-level metadata copied to ``attrs``.

    Returns
    -------
    xarray.DataArray
        Dims ``("channel", "time")`` with coords ``quantity``, ``units``, ``node``,
        ``direction`` on ``channel``.
    """
    arr = np.asarray(data)
    if arr.ndim == 1:
        arr = arr[None, :]
    if arr.ndim != 2:
        raise ParameterError(f"data must be 1-D or 2-D (channel, time), got shape {arr.shape}")
    n_ch, n = arr.shape
    if not (np.isfinite(fs) and fs > 0):
        raise ParameterError(f"fs must be a finite sampling rate > 0 Hz, got {fs!r}")

    def per_channel(value, default, label):
        if value is None:
            value = default
        if isinstance(value, str) or np.isscalar(value):
            return [value] * n_ch
        value = list(value)
        if len(value) != n_ch:
            raise ParameterError(
                f"{label} needs {n_ch} entries (one per channel), got {len(value)}"
            )
        return value

    names = per_channel(names, [f"ch{i}" for i in range(n_ch)], "names")
    coords = {
        "channel": names,
        "time": np.arange(n) / fs,
        "quantity": ("channel", per_channel(quantity, "displacement", "quantity")),
        "units": ("channel", per_channel(units, "m", "units")),
        "node": ("channel", per_channel(node, -1, "node")),
        "direction": ("channel", per_channel(direction, "", "direction")),
    }
    out = xr.DataArray(arr, dims=("channel", "time"), coords=coords, attrs=dict(attrs or {}))
    out["time"].attrs["units"] = "s"
    return out


def _modal_decay(t, fn, z, a, phase, power):
    """Sum of damped cosines a_r exp(-s_r t) cos(wd_r t + phase_r), differentiated ``power``
    times (via the complex exponential representation)."""
    w = 2 * np.pi * fn
    sigma = z * w
    wd = w * np.sqrt(1 - z**2)
    lam = -sigma + 1j * wd  # complex pole
    out = np.zeros_like(t)
    for lam_r, a_r, ph in zip(lam, a, phase):
        out += np.real(a_r * np.exp(1j * ph) * lam_r**power * np.exp(lam_r * t))
    return out


def sdof_free_decay(
    fn_hz: float,
    zeta: float,
    fs: float,
    duration: float,
    *,
    amplitude: float = 1.0,
    phase: float = 0.0,
    quantity: str = "displacement",
    units: str = "m",
) -> xr.DataArray:
    """Free decay ``x(t) = A exp(-zeta w t) cos(w_d t + phase)`` of one mode.

    Parameters
    ----------
    fn_hz : float
        Undamped natural frequency in Hz.
    zeta : float
        Viscous damping ratio (0.01 = 1 %).
    fs : float
        Sampling rate in Hz.
    duration : float
        Record length in s.
    amplitude : float
        Initial envelope ``A`` in ``units``.
    phase : float
        Phase in rad.

    Returns
    -------
    xarray.DataArray
        One channel ``"decay"``; ``attrs`` hold the true ``fn_hz`` and ``zeta``.
    """
    return mdof_free_decay([fn_hz], [zeta], fs, duration, amplitudes=[amplitude],
                           phases=[phase], quantity=quantity, units=units)


def mdof_free_decay(
    fn_hz: Sequence[float],
    zeta: Sequence[float] | float,
    fs: float,
    duration: float,
    *,
    amplitudes: Sequence[float] | float = 1.0,
    phases: Sequence[float] | float = 0.0,
    quantity: str = "displacement",
    units: str = "m",
) -> xr.DataArray:
    """Free decay of a sum of damped modes (one channel).

    ``x(t) = sum_r A_r exp(-zeta_r w_r t) cos(w_dr t + phase_r)`` with
    ``w_dr = w_r sqrt(1 - zeta_r**2)``.

    Returns
    -------
    xarray.DataArray
        One channel ``"decay"``; ``attrs["fn_hz"]`` and ``attrs["zeta"]`` list the truth.
    """
    fn, z, a = _modal_arrays(fn_hz, zeta, amplitudes)
    ph = np.broadcast_to(np.asarray(phases, dtype=float), fn.shape)
    t = _time(fs, duration)
    x = _modal_decay(t, fn, z, a, ph, 0)
    return make_time_history(
        x, fs, quantity=quantity, units=units, names=["decay"],
        attrs={"fn_hz": fn.tolist(), "zeta": z.tolist(), "generator": "mdof_free_decay"},
    )


def impulse_response(
    fn_hz: Sequence[float] | float,
    zeta: Sequence[float] | float,
    fs: float,
    duration: float,
    *,
    modal_constants: Sequence[float] | float = 1.0,
    kind: str = "receptance",
) -> np.ndarray:
    """Unit-impulse response of the modal model, sampled at ``np.arange(n) / fs``.

    Parameters
    ----------
    kind : {"receptance", "mobility", "accelerance"}
        Displacement (m per N s), velocity or acceleration response. For
        ``"accelerance"`` the Dirac term ``sum(A_r) delta(t)`` is sampled as
        ``sum(A_r) * fs`` at ``t = 0``; ``h[0]`` holds half the jump at ``t = 0``.

    Returns
    -------
    numpy.ndarray
        ``h(t)``; its Fourier transform ``sum h e^{-i w t} / fs`` approximates the
        continuous FRF of :func:`modal_frf` below the Nyquist frequency.
    """
    power = _check_kind(kind)
    fn, z, a = _modal_arrays(fn_hz, zeta, modal_constants)
    t = _time(fs, duration)
    wd = 2 * np.pi * fn * np.sqrt(1 - z**2)
    # h(t) = A/wd exp(-s t) sin(wd t) = Re[(A / (1j wd)) exp(lam t)]
    h = _modal_decay(t, fn, z, a / wd, np.full(fn.shape, -np.pi / 2), power)
    # h jumps at t = 0: the rectangle rule needs the mean of h(0-) = 0 and h(0+)
    h[0] *= 0.5
    if power == 2:  # accelerance = sum A_r + (regular part): the Dirac term at t = 0
        h[0] += np.sum(a) * fs
    return h


def modal_frf(
    f_hz,
    fn_hz: Sequence[float] | float,
    zeta: Sequence[float] | float,
    *,
    modal_constants: Sequence[float] | float = 1.0,
    kind: str = "receptance",
) -> xr.DataArray:
    """Exact FRF of the modal model on the lines ``f_hz``.

    Returns
    -------
    xarray.DataArray
        Complex, dims ``("response", "reference", "frequency")`` of shape (1, 1, n),
        frequency in Hz, with response/reference quantity and unit coords and
        ``attrs["kind"]``.
    """
    power = _check_kind(kind)
    fn, z, a = _modal_arrays(fn_hz, zeta, modal_constants)
    f = np.asarray(f_hz, dtype=float)
    w = 2 * np.pi * f
    wr = 2 * np.pi * fn
    h = np.zeros(f.shape, dtype=complex)
    for wr_r, z_r, a_r in zip(wr, z, a):
        h += a_r / (wr_r**2 - w**2 + 2j * z_r * wr_r * w)
    h = h * (1j * w) ** power
    quantity, units = _KIND_QUANTITY[kind]
    return xr.DataArray(
        h[None, None, :],
        dims=("response", "reference", "frequency"),
        coords={
            "response": ["response"],
            "reference": ["force"],
            "frequency": f,
            "response_quantity": ("response", [quantity]),
            "response_units": ("response", [units]),
            "reference_quantity": ("reference", ["force"]),
            "reference_units": ("reference", ["N"]),
        },
        attrs={"kind": kind, "fn_hz": fn.tolist(), "zeta": z.tolist(), "units": f"{units}/N"},
    )


def add_noise(
    x: xr.DataArray,
    rng: np.random.Generator,
    *,
    snr_db: float | None = None,
    rms_fraction: float | None = None,
) -> xr.DataArray:
    """Add white Gaussian noise to every channel of a time history.

    Give exactly one of ``snr_db`` (signal RMS / noise RMS in dB, per channel) or
    ``rms_fraction`` (noise RMS as a fraction of the channel's signal RMS: 0.05 is
    5 % RMS noise, i.e. 26 dB).
    """
    if not isinstance(rng, np.random.Generator):
        raise ParameterError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if (snr_db is None) == (rms_fraction is None):
        raise ParameterError("give exactly one of snr_db or rms_fraction")
    frac = 10 ** (-snr_db / 20) if snr_db is not None else float(rms_fraction)
    if not (np.isfinite(frac) and frac >= 0):
        raise ParameterError(f"noise level must be finite and >= 0, got {frac!r}")
    values = np.asarray(x.values, dtype=float)
    rms = np.sqrt(np.mean(values**2, axis=-1, keepdims=True))
    noisy = values + frac * rms * rng.standard_normal(values.shape)
    out = x.copy(data=noisy)
    out.attrs = {**x.attrs, "noise_rms_fraction": frac}
    return out


def random_excitation_test(
    fn_hz: Sequence[float] | float,
    zeta: Sequence[float] | float,
    fs: float,
    duration: float,
    rng: np.random.Generator,
    *,
    modal_constants: Sequence[float] | float = 1.0,
    kind: str = "accelerance",
    force_rms: float = 1.0,
) -> xr.DataArray:
    """Force and response of the modal model under white-noise force.

    The response is computed as the *periodic* steady state (the force is treated as
    one period, response = IFFT(H(f) FFT(force))), so the exact FRF relation holds on
    the record's own frequency lines and the only estimator error is window leakage
    and noise.

    Returns
    -------
    xarray.DataArray
        Channels ``"force"`` (N) and ``"response"`` (units of ``kind``).
    """
    if not isinstance(rng, np.random.Generator):
        raise ParameterError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    t = _time(fs, duration)
    n = t.size
    force = force_rms * rng.standard_normal(n)
    f = np.fft.rfftfreq(n, 1 / fs)
    h = modal_frf(f, fn_hz, zeta, modal_constants=modal_constants, kind=kind).values[0, 0]
    resp = np.fft.irfft(h * np.fft.rfft(force), n)
    quantity, units = _KIND_QUANTITY[kind]
    return make_time_history(
        np.vstack([force, resp]), fs, quantity=["force", quantity], units=["N", units],
        names=["force", "response"],
        attrs={"fn_hz": list(np.atleast_1d(fn_hz)), "zeta": list(np.atleast_1d(zeta)),
               "kind": kind, "generator": "random_excitation_test"},
    )


def impact_test(
    fn_hz: Sequence[float] | float,
    zeta: Sequence[float] | float,
    fs: float,
    record_s: float,
    n_hits: int,
    rng: np.random.Generator,
    *,
    modal_constants: Sequence[float] | float = 1.0,
    kind: str = "accelerance",
    pulse_s: float = 2e-3,
    pretrigger_s: float = 0.05,
) -> xr.DataArray:
    """An impact test at one point: ``n_hits`` half-sine hammer pulses, one per record.

    Each hit starts ``pretrigger_s`` into a record of ``record_s`` seconds; the hit
    amplitudes vary randomly (uniform 0.5..1.5 N peak). The response is the exact
    linear convolution of the sampled force with the sampled impulse response (so it
    keeps ringing into the next record if the damping is too light, as in a real test).

    Returns
    -------
    xarray.DataArray
        Channels ``"force"`` (N) and ``"response"``; ``attrs["hit_times_s"]``.
    """
    if not isinstance(rng, np.random.Generator):
        raise ParameterError(f"rng must be a numpy.random.Generator, got {type(rng).__name__}")
    if int(n_hits) < 1:
        raise ParameterError(f"n_hits must be >= 1, got {n_hits}")
    n_rec = int(round(record_s * fs))
    n = n_rec * int(n_hits)
    t = np.arange(n) / fs
    force = np.zeros(n)
    n_pulse = max(int(round(pulse_s * fs)), 1)
    pulse = np.sin(np.pi * (np.arange(n_pulse) + 0.5) / n_pulse)
    starts = []
    for k in range(int(n_hits)):
        i0 = k * n_rec + int(round(pretrigger_s * fs))
        force[i0:i0 + n_pulse] += rng.uniform(0.5, 1.5) * pulse
        starts.append(i0 / fs)
    h = impulse_response(fn_hz, zeta, fs, n / fs, modal_constants=modal_constants, kind=kind)
    nfft = int(2 ** np.ceil(np.log2(2 * n)))
    resp = np.fft.irfft(np.fft.rfft(force, nfft) * np.fft.rfft(h, nfft), nfft)[:n] / fs
    quantity, units = _KIND_QUANTITY[kind]
    return make_time_history(
        np.vstack([force, resp]), fs, quantity=["force", quantity], units=["N", units],
        names=["force", "response"],
        attrs={"fn_hz": list(np.atleast_1d(fn_hz)), "zeta": list(np.atleast_1d(zeta)),
               "kind": kind, "hit_times_s": starts, "generator": "impact_test",
               "duration_s": float(t[-1] + 1 / fs)},
    )
