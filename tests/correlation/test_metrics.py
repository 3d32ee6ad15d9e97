"""MAC family, TAMs, FRF criteria; COMAC finds a bad sensor; peer comparison."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from correlation_helpers import plate_setup as _setup
from correlation_helpers import sdynpy_module

from mvtk import correlation as co
from mvtk.errors import DimensionError, ParameterError


def test_mac_properties_and_scale_invariance():
    *_, fe = _setup()
    m = co.mac(fe, fe)
    np.testing.assert_allclose(np.diag(m), 1.0)
    np.testing.assert_allclose(m, m.T)
    scaled = fe * xr.DataArray([2.0, -3, 1j, 1, -1, 5], dims="mode")
    np.testing.assert_allclose(co.mac(scaled, fe).values, m.values, atol=1e-12)
    np.testing.assert_allclose(co.msf(3.0 * fe, fe).values, 3.0)
    # the second set is reordered onto the first set's DOF labels
    np.testing.assert_allclose(co.mac(fe, fe.isel(dof=slice(None, None, -1))).values, m.values)
    with pytest.raises(DimensionError, match="different DOFs: 1 of the first set missing"):
        co.mac(fe, fe.isel(dof=slice(1, None)))


def test_comac_flags_misoriented_and_misplaced_sensor(rng):
    model, modal, geo, mp, fe = _setup()
    # the "test": same rig but sensor 7 is mounted along x instead of z (mis-oriented) and
    # sensor 14 sits 5 cm away from where the geometry says; 0.5 % noise everywhere
    sens = list(geo.sensors)
    sens[6] = co.Sensor(7, "+x")
    xyz = geo.xyz.copy()
    xyz[13] += [-0.04, 0.03, 0]
    real = co.TestGeometry(geo.node, xyz, sensors=tuple(sens))
    test = co.map_sensors(real, model).project(modal).isel(mode=slice(0, 6))
    amp = np.abs(test.values).max(axis=1, keepdims=True)
    test = test.copy(data=test.values + 0.005 * amp * rng.normal(size=test.shape))
    test = test.assign_coords(dof=fe["dof"].values)  # labelled as the intended DOFs
    c = co.comac(test, fe)
    worst = c.sortby(c).dof.values[:2].tolist()
    assert set(worst) == {"7+z", "14+z"}
    others = c.drop_sel(dof=["7+z", "14+z"])
    # the mis-oriented sensor reads in-plane motion (about zero in bending) plus noise:
    # its COMAC is the correlation of that noise with the FE shapes, which depends on the
    # eigensolver's arbitrary sign of each mode (0.2-0.55 seen): well below the others
    assert float(others.min()) > 0.95 and float(c.sel(dof="7+z")) < 0.7
    assert float(c.sel(dof="14+z")) < 0.8
    e = co.ecomac(test, fe)
    assert set(e.sortby(e).dof.values[-2:].tolist()) == {"7+z", "14+z"}


def test_sign_error_is_seen_by_ecomac_not_comac():
    *_, fe = _setup()
    flipped = fe.copy(data=fe.values.copy())
    flipped[:, 6] *= -1  # sensor 7 mounted upside down
    c = co.comac(flipped, fe)
    # a constant factor (gain or sign) on one DOF is invisible to COMAC in any form
    np.testing.assert_allclose(c.values, 1.0, atol=1e-12)
    e = co.ecomac(flipped, fe)
    assert e.sortby(e).dof.values[-1] == "7+z" and float(e.sel(dof="7+z")) > 0.05


def test_serep_tam_orthogonality_and_guyan_tam():
    model, modal, geo, mp, fe = _setup()
    Phi = modal.shapes[:, :6]
    tam = co.serep_tam(Phi, mp)
    xo = co.cross_orthogonality(fe, None, tam)
    np.testing.assert_allclose(xo.values, np.eye(6), atol=1e-10)
    np.testing.assert_allclose(tam, co.serep_tam(Phi, mp, mass=model.M), atol=1e-8 * abs(tam).max())
    # Guyan TAM with C selecting FE DOFs equals the classic partitioned condensation
    from mvtk.correlation import map_sensors

    near = map_sensors(geo, model, method="nearest")
    a = near.matrix.indices
    K, M = model.K.toarray(), model.M.toarray()
    o = np.setdiff1d(np.arange(model.n_dof), a)
    T = np.zeros((model.n_dof, a.size))
    T[a] = np.eye(a.size)
    T[o] = -np.linalg.solve(K[np.ix_(o, o)], K[np.ix_(o, a)])
    np.testing.assert_allclose(co.guyan_tam(model, near), T.T @ M @ T, rtol=1e-8,
                               atol=1e-10 * np.abs(T.T @ M @ T).max())
    xg = co.cross_orthogonality(near.project(modal).isel(mode=slice(0, 3)), None,
                                co.guyan_tam(model, near))
    assert np.all(np.abs(np.diag(xg)) > 0.99)
    with pytest.raises(DimensionError, match="TAM must be 20 x 20"):
        co.cross_orthogonality(fe, None, np.eye(3))


def _frf(fe, zeta=0.01):
    f = np.linspace(5, 400, 800)
    return co.synthesize_frf(fe, f, references=["1+z", "20+z"], zeta=zeta)


def test_frf_criteria():
    *_, fe = _setup()
    H = _frf(fe)
    assert H.dims == ("response", "reference", "frequency")
    assert H["reference_node"].values.tolist() == [1, 20]
    np.testing.assert_allclose(co.frac(H, H).values, 1.0)
    np.testing.assert_allclose(co.csac(2 * H, H).values, 1.0)
    np.testing.assert_allclose(co.csf(2 * H, H).values, 0.8)  # 2*2 / (4 + 1)
    shifted = _frf(fe.assign_coords(fn_hz=fe["fn_hz"] * 1.05))
    fr = co.frac(H, shifted)
    assert fr.dims == ("response", "reference") and float(fr.max()) < 0.9
    with pytest.raises(DimensionError, match="different frequency lines"):
        co.frac(H, H.assign_coords(frequency=H.frequency * 2))
    with pytest.raises(ParameterError, match="zeta is NaN"):
        co.synthesize_frf(fe, [1.0, 2.0], references=["1+z"])


def test_synthesised_frf_equals_direct_solution():
    """All modes of a small model: modal sum == (K - w^2 M)^-1 (undamped receptance)."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "updating"))
    from scipy.linalg import eigh
    from updating_helpers import NOMINAL, strip_model

    m = strip_model(NOMINAL)
    K, M = m.K.toarray(), m.M.toarray()
    w2, V = eigh(K, M)

    class Eig:
        vectors, omega2 = V, w2

    S = co.fe_shapes(m, Eig)
    f = np.array([3.0, 17.0, 55.0])
    H = co.synthesize_frf(S, f, references=[S.dof.values[-3]], zeta=0.0)
    j = m.n_dof - 3
    for k, fk in enumerate(f):
        x = np.linalg.solve(K - (2 * np.pi * fk) ** 2 * M, np.eye(m.n_dof)[:, j])
        np.testing.assert_allclose(H.values[:, 0, k].real, x, rtol=1e-7, atol=1e-8 * abs(x).max())


def test_agrees_with_sdypy_and_sdynpy():
    *_, fe = _setup()
    rng = np.random.default_rng(3)
    test = fe.copy(data=fe.values + 0.05 * np.abs(fe.values).max() * rng.normal(size=fe.shape))
    ours = co.mac(test, fe).values
    ema = pytest.importorskip("sdypy.EMA.tools", reason="sdypy-EMA (test extra) not installed")
    np.testing.assert_allclose(ema.MAC(test.values.T, fe.values.T), ours, rtol=1e-12)
    sdc = sdynpy_module("signal_processing/sdynpy_correlation.py")
    np.testing.assert_allclose(sdc.mac(test.values.T, fe.values.T), ours, rtol=1e-12)
    H = _frf(fe)
    Hx = H + 0.02 * float(np.abs(H).max()) * rng.normal(size=H.shape)
    np.testing.assert_allclose(sdc.frac(Hx.values, H.values).real, co.frac(Hx, H).values,
                               rtol=1e-12)
    # SDynPy's msf scales the first set onto the second: msf(shapes, ref) = ref^H s / ref^H ref
    np.testing.assert_allclose(sdc.msf(fe.values.T, test.values.T).real,
                               co.msf(fe, test).values, rtol=1e-12)


@pytest.mark.parametrize("scale", [1e-160, 1.0, 1e160])
def test_every_mac_is_one_implementation_and_scale_free(scale):
    """mvtk.modal, mvtk.correlation, mvtk.updating and mvtk.reduction share one MAC; a
    shape of magnitude 1e-160 (its squares underflow) gives the same MAC as at 1."""
    import mvtk.correlation as corr
    import mvtk.modal as modal
    from mvtk.reduction._verify import mac as mac_reduction
    from mvtk.updating import mac as mac_updating

    rng = np.random.default_rng(3)
    a, b = rng.standard_normal((6, 2)), rng.standard_normal((6, 3))
    ref = (a.T @ b) ** 2 / np.outer((a * a).sum(0), (b * b).sum(0))   # closed form
    for got in (mac_updating(scale * a, b), mac_reduction(scale * a, b),
                modal.mac((scale * a).T, b.T), corr.mac((scale * a).T, b.T).values):
        np.testing.assert_allclose(got, ref, rtol=1e-12)
    np.testing.assert_allclose(np.diag(mac_updating(scale * a, scale * a)), 1.0, rtol=1e-12)
