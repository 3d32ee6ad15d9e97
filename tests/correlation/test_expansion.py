"""SEREP and GCV-regularised expansion of measured shapes to all FE DOFs."""

from __future__ import annotations

import numpy as np
import pytest
from correlation_helpers import plate_setup

from mvtk import correlation as co
from mvtk.errors import DimensionError


def test_serep_returns_fe_shapes_to_round_off():
    model, modal, geo, mp, fe = plate_setup(6)
    ex = co.expand_serep(fe, model, modal, mp, modes=range(1, 7))
    full = co.fe_shapes(model, modal).isel(mode=slice(0, 6))
    assert ex.shapes["dof"].values.tolist() == full["dof"].values.tolist()
    err = np.abs(ex.shapes.values - full.values).max() / np.abs(full.values).max()
    assert err < 1e-12
    assert ex.residual.max() < 1e-12
    np.testing.assert_allclose(ex.coefficients, np.eye(6), atol=1e-10)


def test_gcv_expansion_smooths_noise_and_reports_residual(rng):
    model, modal, geo, mp, fe = plate_setup(4)
    amp = np.abs(fe.values).max(axis=1, keepdims=True)
    noisy = fe.copy(data=fe.values + 0.03 * amp * rng.normal(size=fe.shape))
    truth = co.fe_shapes(model, modal).isel(mode=slice(0, 4)).values
    ex = co.expand_lsq(noisy, model, modal, mp)  # 10 basis modes, 20 sensors
    assert ex.smoothing > 0 and ex.gcv.shape[1] == 2
    assert np.all(ex.residual > 0.005) and np.all(ex.residual < 0.1)
    raw = co.expand_serep(noisy, model, modal, mp)  # unregularised fit in the same basis
    err_reg = np.linalg.norm(ex.shapes.values - truth, axis=1)
    err_raw = np.linalg.norm(raw.shapes.values - truth, axis=1)
    assert np.all(err_reg <= err_raw * 1.0001)
    fixed = co.expand_lsq(fe, model, modal, mp, modes=range(1, 5), smoothing=0.0)
    np.testing.assert_allclose(fixed.shapes.values, truth, atol=1e-10 * np.abs(truth).max())
    assert fixed.to_dataframe().shape[0] == 4


def test_expansion_bad_input():
    model, modal, geo, mp, fe = plate_setup(2)
    with pytest.raises(DimensionError, match=r"test DOFs \['x'\] are not in the sensor mapping"):
        co.expand_serep(fe.assign_coords(dof=["x"] + list(fe.dof.values[1:])), model, modal, mp)
