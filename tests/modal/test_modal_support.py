"""The ``support`` quality column: does the FRF need each identified mode?

``support`` is the LSFD misfit within ``fn +- max(5 lines, 2 zeta fn)`` of a fit
without the mode divided by that of the full fit; below 2 (the mode does not even halve
the local misfit) the mode is marked not reliable. Truth here: exact modal models
(``conftest.modal_frf``) with seeded noise, a pole placed where the system has no mode,
and a brute-force refit of :func:`mvtk.modal.lsfd` without each mode.

Values measured when this file was written (threshold 2): true modes of the synthetic
systems >= 15 (single response, noise 20 % of the RMS), the real files' catalogued
peaks >= 4.8 (tests/modal/test_modal_real_data.py), poles fitted to background or
noise <= 1.51.
"""

from __future__ import annotations

import numpy as np

from mvtk import modal
from mvtk.modal._identify import MIN_SUPPORT, modes_from_poles
from mvtk.modal._lsfd import local_misfit
from mvtk.modal._stabilisation import ClusterCriteria, SelectedPoles, StabilityCriteria


def _system(msys, rng, noise):
    f = np.arange(0, 250, 0.1)
    fn = np.array([40.0, 90.0, 150.0])
    z = np.array([0.01, 0.02, 0.01])
    phi = np.array([[1.0, 0.3], [0.5, -0.8], [0.8, 0.6]])
    h = msys.modal_frf(fn, z, phi, f, [0])
    return msys.add_noise(h, noise, rng), fn, z


def test_pole_without_a_mode_is_flagged(msys, rng):
    h, fn, z = _system(msys, rng, 0.05)
    hb = h.sel(frequency=slice(10, 220))
    wn = 2 * np.pi * np.array([40.0, 90.0, 120.0, 150.0])   # no mode at 120 Hz
    zz = np.array([0.01, 0.02, 0.01, 0.01])
    lam = -zz * wn + 1j * wn * np.sqrt(1 - zz**2)
    sel = SelectedPoles(lam, np.ones((4, 1), complex), np.full(4, 20), np.full(4, 20),
                        tuple(np.zeros(0, int) for _ in range(4)))
    diagram = modal.plscf(hb, orders=range(2, 12))
    res = modes_from_poles(hb, diagram, sel, ClusterCriteria(), StabilityCriteria())
    t = res.to_dataframe()
    # (the refinement lets the spurious pole fit some noise: 1.28, still below 2)
    assert t.support[2] < 1.5 and not t.reliable[2], t
    assert "not needed by the data" in t.reason[2]
    real = t.drop(index=2)
    assert (real.support > 50).all() and real.reliable.all(), t


def test_true_modes_in_heavy_noise_are_supported(msys, rng):
    h, fn, z = _system(msys, rng, 0.2)
    res = modal.identify(h.isel(response=[0]), 10, 220)
    assert res.n_modes == 3
    assert np.allclose(res.fn_hz, fn, rtol=2e-3), res.to_dataframe()
    assert (res.support > 3 * MIN_SUPPORT).all() and res.reliable.all(), res.to_dataframe()


def test_local_misfit_equals_brute_force_refit(msys, rng):
    h, fn, z = _system(msys, rng, 0.05)
    hb = h.sel(frequency=slice(10, 220))
    f, H = hb["frequency"].values, hb.values
    wn = 2 * np.pi * fn
    lam = -z * wn + 1j * wn * np.sqrt(1 - z**2)
    wins = [np.abs(f - f0) <= 3.0 for f0 in fn]
    r_with, r_without, energy = local_misfit(H, f, lam, "accelerance", wins)
    full = modal.synthesise(modal.lsfd(H, f, lam, "accelerance"), f)
    for m, k in enumerate(wins):
        drop = modal.synthesise(modal.lsfd(H, f, np.delete(lam, m), "accelerance"), f)
        np.testing.assert_allclose(r_with[m], np.sum(np.abs(H[..., k] - full[..., k]) ** 2),
                                   rtol=1e-8)
        np.testing.assert_allclose(r_without[m],
                                   np.sum(np.abs(H[..., k] - drop[..., k]) ** 2), rtol=1e-8)
        np.testing.assert_allclose(energy[m], np.sum(np.abs(H[..., k]) ** 2), rtol=1e-12)
