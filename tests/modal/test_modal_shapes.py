"""Shapes from all references: the rank-one estimate of the LSFD residues.

Truth: the modal superposition of a simply supported rectangular plate (closed-form
shapes ``sin(m pi x / a) sin(n pi y / b)``, frequencies ``~ (m/a)^2 + (n/b)^2``)
sampled on an 8 x 5 grid, three references of which two lie on the nodal line
``y = b/2``: the modes ``(1,2)``, ``(2,2)`` and ``(3,2)`` vanish at every driving point
but one. A shape taken from the first driving point's residue column is 0/0 there.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from mvtk import modal

MN = [(1, 1), (2, 1), (1, 2), (3, 1), (2, 2), (3, 2)]
ZETA = np.array([0.01, 0.012, 0.008, 0.01, 0.015, 0.01])
REFS = [2, 22, 8]          # grid points (0, 2), (4, 2) on y = b/2 and (1, 3)


def plate(nx=8, ny=5, a=1.0, b=0.62):
    x = (np.arange(nx) + 0.5) / nx
    y = (np.arange(ny) + 0.5) / ny
    X, Y = (g.ravel() for g in np.meshgrid(x, y, indexing="ij"))
    phi = np.array([np.sin(m * np.pi * X) * np.sin(n * np.pi * Y) for m, n in MN])
    phi /= np.sqrt(np.sum(phi**2, axis=1, keepdims=True))       # unit modal mass
    fn = np.array([40 * ((m / a) ** 2 + (n / b) ** 2) for m, n in MN])
    return fn, phi


@pytest.fixture(scope="module")
def plate_frf(msys):
    fn, phi = plate()
    f = np.arange(0, 1000.0001, 0.5)
    return fn, phi, msys.modal_frf(fn, ZETA, phi, f, REFS)


@pytest.mark.parametrize("noise, floor", [(0.0, 0.999), (0.05, 0.98)])
def test_shapes_use_every_reference(plate_frf, msys, noise, floor):
    fn, phi, h = plate_frf
    # the set-up is what it claims: three modes vanish at two of the three driving points
    at_refs = np.abs(phi[:, REFS]) / np.abs(phi).max(axis=1, keepdims=True)
    assert np.sum((at_refs < 1e-6).sum(axis=1) == 2) == 3
    if noise:
        h = msys.add_noise(h, noise, np.random.default_rng(11))
    res = modal.identify(h)                   # defaults: band and orders from the data
    k = msys.match(res.fn_hz, fn)
    assert res.n_modes >= 6
    np.testing.assert_allclose(res.fn_hz[k], fn, rtol=1e-4)
    # zeta within 10 % with defaults (3 references x 40 responses, 5 % noise: found 0.5 %)
    np.testing.assert_allclose(res.zeta[k], ZETA, rtol=0.10 if noise else 1e-4)
    for shapes in (res.shapes.values, res.real_shapes.values):
        m = np.array([modal.mac(np.vstack([shapes[kk], phi[j]]))[0, 1]
                      for j, kk in enumerate(k)])
        assert m.min() > floor, m
    assert res.reliable[k].all(), res.to_dataframe()
    if noise == 0:
        # unit modal A from all driving points: phi_mass / sqrt(2 i w_d), amplitude and sign
        wd = res.pole[k].imag
        want = phi / np.sqrt(2j * wd)[:, None]
        np.testing.assert_allclose(np.abs(res.shapes.values[k]), np.abs(want), atol=1e-5 *
                                   np.abs(want).max())
        np.testing.assert_allclose(np.abs(res.real_shapes.values[k]), np.abs(phi),
                                   atol=1e-5)


def test_rank_one_scaling_of_complex_residues(rng):
    """Non-proportional (complex) shapes: ``A = phi phi^T`` rebuilt from the residues
    with the scale from all driving points, whatever the SVD's phase."""
    from mvtk.modal._identify import rank_one_shapes

    phi = rng.standard_normal((3, 7)) + 1j * rng.standard_normal((3, 7))
    refs = [1, 4]
    A = phi[:, :, None] * phi[:, None, refs]
    shp, part, scaled = rank_one_shapes(A, np.array([-1 + 10j] * 3), [(1, 0), (4, 1)])
    assert scaled
    for m in range(3):
        s = shp[m] / phi[m]
        np.testing.assert_allclose(s, s[0] * np.ones(7), rtol=1e-12)
        assert abs(abs(s[0]) - 1) < 1e-12 and abs(s[0] ** 2 - 1) < 1e-12   # +-phi
    # participation: A ~ psi L^T with the unit-norm L of the references
    psi = modal_rank_one(A)
    for m in range(3):
        np.testing.assert_allclose(np.outer(psi[m], part[m]), A[m], atol=1e-12)


def modal_rank_one(A):
    u, s, _ = np.linalg.svd(A)
    return u[:, :, 0] * s[:, :1]


def test_json_and_uff55_carry_the_multi_reference_shapes(plate_frf, tmp_path):
    import mvtk.io

    fn, phi, h = plate_frf
    res = modal.identify(h, 20, 950)
    tab = res.shape_table()
    assert {"mode", "dof", "node", "direction", "real", "imag"} <= set(tab.columns)
    assert len(tab) == res.n_modes * h.sizes["response"]
    rec = json.loads(tab.to_json(orient="records", double_precision=15))
    z = np.array([[r["real"] + 1j * r["imag"] for r in rec if r["mode"] == m + 1]
                  for m in range(res.n_modes)])
    np.testing.assert_allclose(z, res.shapes.values, atol=1e-14)
    back = mvtk.io.read(modal.write_modes_uff(res, tmp_path / "modes.uff"))
    k = np.argsort(back["node"].values) if "node" in back.coords else slice(None)
    got = back["mode_shape"].values[:, :, 2][:, k]
    np.testing.assert_allclose(got, res.shapes.values, rtol=1e-4,
                               atol=1e-6 * np.abs(res.shapes.values).max())
