"""Noise correlation between the FRF lines of a windowed record.

White noise multiplied by the record's window ``w`` (an impact test's exponential
window, zero-padding of ``len(w)`` samples to a longer FFT) has correlated lines,
``C_kl = sum_t w_t^2 exp(-2 pi i (f_k - f_l) t) / sum_t w_t^2``. Least-squares fits on
such lines (the pole refinement, LSFD) need ``X^T S X`` for their covariances, with
``S`` the real form of ``C`` acting on ``[real parts; imaginary parts]`` of the lines:
:func:`correlated_gram`.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError

__all__ = ["line_correlation", "correlate_lines", "correlated_gram"]


def line_correlation(f_hz, window, fs: float) -> np.ndarray:
    """Correlation of white noise between FRF lines of a windowed record.

    ``C_kl = sum_t w_t^2 exp(-2 pi i (f_k - f_l) t) / sum_t w_t^2`` with ``t = n / fs``
    over the window's samples: the identity for an unwindowed record on its own
    lines, correlated neighbours for an exponential (impact) window or zero-padding.

    Parameters
    ----------
    f_hz : numpy.ndarray
        Frequency lines (Hz).
    window : numpy.ndarray
        Window value per sample of the record (ones for none).
    fs : float
        Sampling rate (Hz).

    Returns
    -------
    numpy.ndarray, shape (len(f_hz), len(f_hz)), complex
        Hermitian, ones on the diagonal.

    Examples
    --------
    The lines of an unwindowed record are independent; an exponential window with
    tau = T / 3 correlates neighbours (``|C| = 1 / |1 + i pi tau / T|`` for a long
    record):

    >>> f = np.arange(3) * 10.0                    # lines of a 0.1 s record
    >>> np.round(np.abs(line_correlation(f, np.ones(1000), 1e4)[0]), 6)
    array([1., 0., 0.])
    >>> w = np.exp(-np.arange(1000) / 1e4 / (0.1 / 3))
    >>> np.round(np.abs(line_correlation(f, w, 1e4)[0, 1]), 2)
    np.float64(0.69)
    """
    f = np.asarray(f_hz, dtype=float)
    w2, fs = _window_power(window, fs)
    diff = f[:, None] - f[None, :]
    # depends on f_k - f_l only: evaluated once per distinct difference
    uniq, inverse = np.unique(np.round(diff * (w2.size / fs), 9), return_inverse=True)
    return _correlation_at(uniq * (fs / w2.size), w2, fs)[inverse.reshape(diff.shape)]


def _window_power(window, fs):
    w2 = np.asarray(window, dtype=float) ** 2
    if w2.ndim != 1 or w2.size == 0 or not np.all(np.isfinite(w2)) or w2.sum() <= 0:
        raise ParameterError("record window: a non-empty 1-D array of finite values, "
                             "not all zero")
    if not (np.isfinite(fs) and fs > 0):
        raise ParameterError(f"record window: sampling rate must be > 0 Hz, got {fs!r}")
    return w2, float(fs)


def _correlation_at(d_hz, w2, fs):
    """``sum_t w2_t exp(-2 pi i d t) / sum w2`` for each frequency offset ``d_hz``."""
    d_hz = np.asarray(d_hz, dtype=float)
    step = np.min(np.abs(d_hz[d_hz != 0])) if np.any(d_hz != 0) else 0.0
    period = fs / step if step else 0.0
    k = d_hz / step if step else np.zeros_like(d_hz)
    if step and abs(period - round(period)) < 1e-6 * period and np.allclose(
            k, np.round(k), atol=1e-6):
        # offsets on a grid of fs / M: one FFT of the window power folded on M points
        M = int(round(period))
        folded = np.zeros(M)
        np.add.at(folded, np.arange(w2.size) % M, w2)
        G = np.fft.fft(folded)
        return G[np.round(k).astype(np.int64) % M] / w2.sum()
    t = np.arange(w2.size) / fs
    g = np.empty(d_hz.size, complex)
    for lo in range(0, d_hz.size, 256):                    # bounded memory
        g[lo:lo + 256] = np.exp(-2j * np.pi * d_hz[lo:lo + 256, None] * t[None, :]) @ w2
    return g / w2.sum()


def correlate_lines(Xc, f_lines, record_window) -> np.ndarray:
    """``C Xc`` for complex columns ``Xc`` (shape ``(L, p)``) on lines ``f_lines`` whose
    noise has the line correlation ``C`` of ``record_window = (w, fs)``. Equally spaced
    lines: ``C`` is Toeplitz and applied by FFT, never formed."""
    w2, fs = _window_power(*record_window)
    f_lines = np.asarray(f_lines, dtype=float)
    L = f_lines.size
    if Xc.ndim != 2 or Xc.shape[0] != L:
        raise ParameterError(f"correlate_lines: {L} rows expected, got {Xc.shape}")
    d = np.diff(f_lines)
    if L > 1 and np.allclose(d, d[0], rtol=1e-6):
        from scipy.linalg import matmul_toeplitz

        g = _correlation_at(np.arange(L) * d[0], w2, fs)
        return matmul_toeplitz((g, g.conj()), Xc)
    return line_correlation(f_lines, np.sqrt(w2), fs) @ Xc


def correlated_gram(X, f_lines, record_window) -> np.ndarray:
    """``X^T S X`` for the real ``[Re; Im]`` rows ``X`` (shape ``(2 L, p)``) of lines
    ``f_lines`` whose (proper complex) noise has the line correlation ``C`` of
    ``record_window``: ``Re(Xc^H C Xc)`` with ``Xc = X[:L] + i X[L:]``."""
    X = np.asarray(X, dtype=float)
    L = np.size(f_lines)
    if X.ndim != 2 or X.shape[0] != 2 * L:
        raise ParameterError(f"correlated_gram: X must have 2 x {L} rows, got {X.shape}")
    Xc = X[:L] + 1j * X[L:]
    return np.real(Xc.conj().T @ correlate_lines(Xc, f_lines, record_window))
