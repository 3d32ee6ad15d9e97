"""Harmonic (periodic) components among output-only modes: the kurtosis test.

Operational records of machines (rotors, pumps, wind turbines) carry harmonics of the
running speed. SSI-cov finds them as lightly damped stable poles, and nothing in the
stabilisation tells them from structural modes. Their amplitude statistics do: the
response of a mode to broadband random excitation, band-passed around the mode, is a
narrow-band Gaussian process (kurtosis 3), while a sinusoid has kurtosis 1.5 (a
probability density peaked at +-A). A harmonic carrying 75 % of the band's power (with
Gaussian noise for the rest) gives 2.16. Brincker, Andersen & Moller, "An indicator for
separation of structural and harmonic modes in output-only modal testing", IMAC 18
(2000) use the same statistics.
"""

from __future__ import annotations

import numpy as np

__all__ = ["HARMONIC_KURTOSIS", "band_kurtosis"]

#: Below this kurtosis of the band-passed response a "mode" is taken as a harmonic
#: (sinusoid 1.5; 75 % harmonic power in Gaussian noise 2.16; random response 3).
HARMONIC_KURTOSIS = 2.0


def band_kurtosis(y: np.ndarray, fs: float, fn_hz, zeta) -> np.ndarray:
    """Kurtosis of the response band-passed around each mode, on its strongest channel.

    Parameters
    ----------
    y : numpy.ndarray, shape (n_channel, n_time)
        Records (mean removed inside), sampled at ``fs``.
    fs : float
        Sampling rate in Hz.
    fn_hz, zeta : array_like
        Frequencies (Hz) and damping ratios of the modes.

    Returns
    -------
    numpy.ndarray
        Kurtosis (``E[x^4] / E[x^2]^2``; 3 for a Gaussian, 1.5 for a sinusoid) of the
        channel with the most power in ``fn (1 +- b)``, ``b = 2 zeta`` clipped to
        0.5..5 % (a 4th-order zero-phase Butterworth band-pass; 5 % of the record
        dropped at both ends for the filter's transient). NaN where the band does not
        fit below ``fs / 2`` or the record is shorter than 50 periods of the mode.
    """
    import scipy.signal

    y = np.asarray(y, dtype=float)
    y = y - y.mean(axis=1, keepdims=True)
    n = y.shape[1]
    out = np.full(len(np.atleast_1d(fn_hz)), np.nan)
    for k, (f, z) in enumerate(zip(np.atleast_1d(fn_hz), np.atleast_1d(zeta))):
        b = float(np.clip(2 * z, 0.005, 0.05)) if np.isfinite(z) else 0.05
        lo, hi = f * (1 - b), f * (1 + b)
        if not (0 < lo and hi < fs / 2) or n < 50 * fs / f:
            continue
        sos = scipy.signal.butter(4, [lo, hi], btype="band", fs=fs, output="sos")
        x = scipy.signal.sosfiltfilt(sos, y, axis=1)[:, n // 20: n - n // 20]
        p2 = np.mean(x**2, axis=1)
        j = int(np.argmax(p2))
        if p2[j] > 0:
            out[k] = float(np.mean(x[j] ** 4) / p2[j] ** 2)
    return out
