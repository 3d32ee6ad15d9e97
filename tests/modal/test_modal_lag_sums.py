"""The pLSCF lag sums, computed block by block over the lines, equal the direct sums."""

from __future__ import annotations

import numpy as np

import mvtk.modal._plscf as P


def test_blocked_lag_sums_equal_the_direct_formula(monkeypatch, rng):
    nf, order = 1000, 40
    f = np.linspace(3.0, 500.0, nf)
    phase = 2 * np.pi * f / (2 * f[-1])
    a = rng.standard_normal((nf, 5)) + 1j * rng.standard_normal((nf, 5))
    k = np.arange(-order, order + 1)
    direct = np.exp(1j * np.outer(k, phase)) @ a
    monkeypatch.setattr(P, "_LAG_BLOCK", 97)  # several blocks and a ragged last one
    np.testing.assert_allclose(P._lag_sums(phase, order, a), direct, rtol=0,
                               atol=1e-11 * np.abs(direct).max())
