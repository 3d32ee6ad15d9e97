"""Exact synthetic systems (known poles, residues, shapes) for the modal tests."""

from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def modal_data() -> Path:
    """``../shared/data`` (or ``$MVTK_SHARED_DATA``); skips when the corpus is absent."""
    for p in (ROOT.parent / "shared" / "data", Path(os.environ.get("MVTK_SHARED_DATA", "-"))):
        if p.is_dir():
            return p
    pytest.skip(f"external measurement corpus not found at {ROOT.parent / 'shared' / 'data'}"
                " (or $MVTK_SHARED_DATA)")


def chain(n, m=1.0, k=1e5, alpha=0.5, beta=1e-5, dashpot=0.0):
    """Fixed-free spring-mass chain; Rayleigh damping plus an optional grounded dashpot
    on the last mass (non-proportional damping -> complex modes)."""
    M = np.eye(n) * m
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] += 2 * k if i < n - 1 else k
        if i > 0:
            K[i, i - 1] = K[i - 1, i] = -k
    C = alpha * M + beta * K
    C[-1, -1] += dashpot
    return M, C, K


def modal_frf(fn_hz, zeta, phi, f, refs, frf_type="accelerance"):
    """FRF matrix of a modal model with real mass-normalised shapes ``phi`` (n_modes x n_dof):
    ``H = sum phi phi^T / (w_n^2 - w^2 + 2 i zeta w_n w)`` times ``(i w)^k``; responses at
    every DOF (node k+1, +z), references at DOFs ``refs``."""
    from mvtk.modal import FRF_TYPES, as_frf_matrix

    w = 2 * np.pi * np.asarray(f)
    wn = 2 * np.pi * np.asarray(fn_hz)
    den = wn[:, None] ** 2 - w[None, :] ** 2 + 2j * np.asarray(zeta)[:, None] * wn[:, None] * w
    H = np.einsum("mo,mi,mf->oif", phi, phi[:, refs], 1 / den) * (1j * w) ** FRF_TYPES[frf_type]
    n = phi.shape[1]
    q = {"receptance": "displacement", "mobility": "velocity", "accelerance": "acceleration"}
    return as_frf_matrix(xr.DataArray(
        H, dims=("response", "reference", "frequency"),
        coords={"response": [f"{k + 1}+z" for k in range(n)],
                "reference": [f"{k + 1}+z" for k in refs], "frequency": f,
                "node": ("response", np.arange(1, n + 1)), "direction": ("response", ["+z"] * n),
                "quantity": ("response", [q[frf_type]] * n),
                "reference_node": ("reference", np.asarray(refs) + 1),
                "reference_direction": ("reference", ["+z"] * len(refs)),
                "reference_quantity": ("reference", ["force"] * len(refs))},
        attrs={"frf_type": frf_type}))


def add_noise(h, level, rng):
    """Additive complex Gaussian noise, std = ``level`` x RMS magnitude of each FRF."""
    rms = np.sqrt(np.mean(np.abs(h.values) ** 2, axis=-1, keepdims=True))
    noise = (rng.standard_normal(h.shape) + 1j * rng.standard_normal(h.shape)) / np.sqrt(2)
    return h.copy(data=h.values + level * rms * noise)


def match(found_fn, true_fn):
    """Index of the found mode nearest each true frequency."""
    found_fn = np.asarray(found_fn)
    return np.array([int(np.argmin(np.abs(found_fn - f))) for f in true_fn])


def ambient(fs, n=2**16, noise=0.05, seed=3):
    """Displacements of the 5-DOF :func:`chain` under white-noise forces on every DOF
    (FFT filtering of one long record by the exact receptance) plus ``noise`` x RMS
    sensor noise: ``(time history, fn_hz, zeta, complex shapes)``."""
    from mvtk import io, modal

    M, C, K = chain(5)
    rng = np.random.default_rng(seed)
    f = np.fft.rfftfreq(n, 1 / fs)
    H = modal.exact_frf(M, C, K, f, range(5), range(5)).values
    F = np.fft.rfft(rng.standard_normal((5, n)), axis=1)
    y = np.fft.irfft(np.einsum("oif,if->of", H, F), n, axis=1)
    y += noise * y.std(axis=1, keepdims=True) * rng.standard_normal(y.shape)
    th = io.time_history(y, fs, [f"a{k}" for k in range(1, 6)], "m", "displacement",
                         node=[1, 2, 3, 4, 5], direction="z")
    lam, psi = modal.exact_modes(M, C, K)
    return th, np.abs(lam) / 2 / np.pi, -lam.real / np.abs(lam), psi


@pytest.fixture(scope="session")
def msys():
    return SimpleNamespace(chain=chain, modal_frf=modal_frf, add_noise=add_noise, match=match,
                           ambient=ambient)
