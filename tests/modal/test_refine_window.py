"""Pole uncertainty of windowed (impact) FRFs: the window correlates the noise of
neighbouring lines, which the refinement's covariance accounts for
(``refine_poles(record_window=...)``), checked against closed forms and Monte Carlo."""

import numpy as np
import pytest

from mvtk.errors import ParameterError
from mvtk.modal._line_noise import line_correlation
from mvtk.modal._refine import refine_poles

FS, N, TAU = 1000.0, 1000, 0.25             # 1 s records, exponential window tau 0.25 s


def _exponential(n=N, fs=FS, tau=TAU):
    return np.exp(-np.arange(n) / (fs * tau))


def test_line_correlation_closed_forms():
    # unwindowed record on its own lines: independent (orthogonal DFT bins)
    f = np.arange(40, 60) * FS / N
    assert np.allclose(line_correlation(f, np.ones(N), FS), np.eye(f.size), atol=1e-12)
    # exponential window: sum_n a^n exp(-2 pi i d n / N) = (1 - a^N) / (1 - a e^(-2 pi i d/N))
    a = np.exp(-2 / (FS * TAU))
    C = line_correlation(f, _exponential(), FS)
    d = np.arange(f.size)
    exact = (1 - a**N) / (1 - a * np.exp(-2j * np.pi * d / N)) / ((1 - a**N) / (1 - a))
    assert np.allclose(C[:, 0], exact, rtol=1e-10, atol=1e-12)
    assert np.allclose(C, C.conj().T) and np.allclose(np.diag(C), 1)
    # zero-padding by 4 (boxcar): the Dirichlet kernel, 1 at multiples of the record's
    # resolution and |sin(pi d / 4)| / (N sin(pi d / 4N)) between
    fp = np.arange(8) * FS / (4 * N)
    Cp = line_correlation(fp, np.ones(N), FS)
    dp = np.arange(1, 8)
    assert np.allclose(np.abs(Cp[1:, 0]),
                       np.abs(np.sin(np.pi * dp / 4) / (N * np.sin(np.pi * dp / (4 * N)))),
                       atol=1e-12)
    # lines not on one grid: the direct sum
    g = np.array([50.0, 51.3, 53.1])
    t = np.arange(N) / FS
    direct = (np.exp(-2j * np.pi * (g[:, None, None] - g[None, :, None]) * t)
              @ _exponential() ** 2) / np.sum(_exponential() ** 2)
    assert np.allclose(line_correlation(g, _exponential(), FS), direct, atol=1e-12)


def test_line_correlation_refuses_bad_window():
    with pytest.raises(ParameterError, match="record window"):
        line_correlation([1.0, 2.0], np.zeros(10), FS)
    with pytest.raises(ParameterError, match="sampling rate"):
        line_correlation([1.0, 2.0], np.ones(10), 0.0)


def _monte_carlo(record_window, reps=300, seed=7):
    """Scatter of the refined (fn, zeta) over their reported std: one mode (50 Hz,
    zeta 1 % plus the window's 1 / (tau w_n)), noise = DFT of windowed white noise."""
    rng = np.random.default_rng(seed)
    wn = 2 * np.pi * 50.0
    zeta = 0.01 + 1 / (TAU * wn)
    lam = -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)
    k = np.arange(N // 2)
    f = k * FS / N
    iw = 2j * np.pi * f
    H = (1 / (iw - lam) + 1 / (iw - np.conj(lam))) * 1e-2
    w = _exponential()
    noise_level = 0.02 * np.abs(H).max()
    fn, z, fs_, zs = [], [], [], []
    for _ in range(reps):
        n = np.fft.fft(w * rng.standard_normal(N))[: N // 2] / np.sqrt(np.sum(w**2))
        ref = refine_poles((H + noise_level * n)[None, None], f, np.array([lam]),
                           "receptance", record_window=record_window)
        assert ref.refined[0]
        p = ref.pole[0]
        fn.append(abs(p) / (2 * np.pi))
        z.append(-p.real / abs(p))
        s_f, s_z = _std(ref)
        fs_.append(s_f)
        zs.append(s_z)
    return np.std(fn) / np.median(fs_), np.std(z) / np.median(zs)


def _std(ref):
    from mvtk.modal._refine import pole_std

    s_f, s_z = pole_std(ref.pole, ref.covariance)
    return s_f[0], s_z[0]


def test_windowed_noise_pole_std_calibrated():
    # with the window's correlation: scatter / reported std within 20 % of 1 (300
    # repetitions: the ratio itself scatters ~4 %)
    r_fn, r_zeta = _monte_carlo((_exponential(), FS))
    assert 0.8 < r_fn < 1.2 and 0.8 < r_zeta < 1.2, (r_fn, r_zeta)
    # treating the lines as independent under-reports (the defect this guards against)
    r_fn0, r_zeta0 = _monte_carlo(None)
    assert r_zeta0 > 1.2 and r_fn0 > 1.2, (r_fn0, r_zeta0)


def test_windowed_noise_residue_variance_calibrated():
    """LSFD at the true pole on the same windowed noise: the residue's scatter over the
    coefficient std of :func:`lsfd_with_misfit` (``record_window``) is ~1; with
    independent lines it is ~2x under-reported."""
    from mvtk.modal._lsfd import lsfd_with_misfit

    rng = np.random.default_rng(11)
    wn = 2 * np.pi * 50.0
    zeta = 0.01 + 1 / (TAU * wn)
    lam = -zeta * wn + 1j * wn * np.sqrt(1 - zeta**2)
    k = np.arange(1, N // 2)
    f = k * FS / N
    iw = 2j * np.pi * f
    H = (1 / (iw - lam) + 1 / (iw - np.conj(lam))) * 1e-2
    w = _exponential()
    level = 0.02 * np.abs(H).max()
    win = [np.abs(f - 50) < 10]
    res = []
    for _ in range(300):
        n = np.fft.fft(w * rng.standard_normal(N))[k] / np.sqrt(np.sum(w**2))
        fit, _ = lsfd_with_misfit((H + level * n)[None, None], f, np.array([lam]),
                                  "receptance", win)
        res.append(fit.residue[0, 0, 0])
    res = np.array(res)
    scatter = np.sqrt(np.var(res.real) + np.var(res.imag))
    sigma2 = level**2 / 2                      # variance of the real and imaginary parts
    ratios = []
    for window in ((w, FS), None):
        _, _, d = lsfd_with_misfit(H[None, None], f, np.array([lam]), "receptance", win,
                                   coef_variance=True, record_window=window)
        ratios.append(scatter / np.sqrt((d[0] + d[1]) * sigma2))
    assert 0.85 < ratios[0] < 1.15, ratios
    assert ratios[1] > 1.5, ratios
