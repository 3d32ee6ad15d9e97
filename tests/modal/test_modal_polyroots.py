"""pLSCF denominator roots by Ehrlich-Aberth against LAPACK's companion eigenvalues.

The iteration (``mvtk.modal._polyroots``) replaces the dense eigenvalues of the block
companion matrices of high model orders; its roots must be LAPACK's (``dgeev`` on the
companion matrix) to rounding, and a stabilisation diagram must not change.
"""

from __future__ import annotations

import numpy as np
import pytest

from mvtk import modal
from mvtk.modal import _polyroots as pr


def _match(a, b):
    """Largest relative distance from each root of ``a`` to its partner in ``b``."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(a[:, None] - b[None, :])
    i, j = linear_sum_assignment(cost)
    return float(np.max(cost[i, j] / np.maximum(np.abs(a[i]), 1e-3)))


def test_scalar_polynomial_known_roots(rng):
    # 42 known roots: 20 damped conjugate pairs spread round the upper half circle and two
    # real ones (more roots near the unit circle and the monomial coefficients no longer
    # determine them: 30 pairs lose 4e-4 in the companion eigenvalues as well)
    n = 20
    ang = (np.arange(n) + 0.5) / n * np.pi + rng.uniform(-0.2, 0.2, n) / n
    pairs = rng.uniform(0.9, 0.99, n) * np.exp(1j * ang)
    roots = np.concatenate([pairs, np.conj(pairs), [0.5, -0.5]])
    c = np.real(np.poly(roots))                        # monic, highest power first
    coef = c[::-1][:-1].reshape(-1, 1, 1)              # z^0 .. z^(p-1)
    z = pr.aberth_roots(coef, roots * (1 + 1e-3 * rng.standard_normal(roots.size)))
    assert z is not None
    assert _match(roots, z) < 1e-7
    assert _match(pr.companion_roots(coef), z) < 1e-10
    assert np.sum(z.imag == 0) == 2


@pytest.mark.parametrize("ni", [1, 2, 3, 4])
def test_matrix_polynomial_roots_equal_companion_eigenvalues(rng, ni):
    p = max(100 // ni, 30)
    coefs = [0.3 * rng.standard_normal((q, ni, ni)) for q in range(p - 3, p + 1)]
    got = pr.roots_by_order(coefs)
    for coef, z in zip(coefs, got):
        ref = pr.companion_roots(coef)
        assert z.size == ref.size == coef.shape[0] * ni
        assert _match(ref, z) < 1e-10
        # real roots come back real (LAPACK's convention), so one of each pair has Im > 0
        assert np.sum(z.imag > 0) == np.sum(ref.imag > 0)


def test_stabilisation_diagram_unchanged(msys, rng, monkeypatch):
    # 12 responses x 3 references with 2 % noise, orders up to 40: 120 poles at the top,
    # the Aberth path in use from order 30
    fn = np.array([31.0, 58.0, 97.0, 140.0, 171.0, 230.0])
    phi = rng.standard_normal((fn.size, 12))
    h = msys.modal_frf(fn, np.full(fn.size, 0.01), phi, np.linspace(5, 260, 1200), [0, 5, 9])
    h = msys.add_noise(h, 0.02, rng)
    d1 = modal.plscf(h, orders=range(1, 41))
    monkeypatch.setattr(pr, "ABERTH_MIN_SIZE", 10**9)      # companion eigenvalues only
    d0 = modal.plscf(h, orders=range(1, 41))
    assert d1.pole.size == d0.pole.size
    np.testing.assert_allclose(d1.pole, d0.pole, rtol=1e-10)
    assert np.array_equal(d1.status, d0.status)


def test_failed_iteration_falls_back_to_companion(rng, monkeypatch):
    coefs = [0.3 * rng.standard_normal((q, 2, 2)) for q in (50, 51)]
    monkeypatch.setattr(pr, "ABERTH_MAX_SWEEPS", 1)
    got = pr.roots_by_order(coefs)
    for coef, z in zip(coefs, got):
        assert _match(pr.companion_roots(coef), z) < 1e-12
