"""modal_analysis' shift and rigid-mode check: free structures get the negative shift
without factorising the singular K, supported ones skip the trial-field scale."""

from __future__ import annotations

import numpy as np
import pytest

import mvtk.fe as fe
from mvtk.fe import _modal

STEEL = fe.IsotropicMaterial("steel", 210e9, 0.3, 7850.0)


def _plate(**kw):
    return fe.plate_model(0.6, 0.36, [fe.Ply(STEEL, 0.002)], nx=12, ny=8, **kw)


def test_unsupported_tells_free_from_supported():
    assert _modal._unsupported(_plate())
    assert not _modal._unsupported(_plate(clamp="x0"))
    assert not _modal._unsupported(_plate(clamp="y1"))


def test_free_plate_same_modes_as_the_factorised_singular_path():
    model = _plate()
    res = fe.modal_analysis(model, 10)
    assert res.rigid.sum() == 6
    # the path that factorises K, finds it singular and then takes the same shift
    q = _modal._smooth_trial_scale(model)
    ref = fe.eigsh_lowest(model.K, model.M, 10, singular_shift=-1e-2 * q)
    assert ref.n_factorizations >= 2
    np.testing.assert_allclose(res.omega2[6:], ref.omega2[6:], rtol=1e-12)
    assert np.all(res.fn_hz[6:] > 0)


@pytest.mark.parametrize("clamp", ["x0", "x1", "y0", "y1"])
def test_supported_plate_skips_the_full_trial_scale(monkeypatch, clamp):
    model = _plate(clamp=clamp)
    calls = []
    full = _modal._smooth_trial_scale

    def spy(m, pairs=None, origins=(0, 1, 2)):
        calls.append(pairs)
        return full(m, pairs, origins)

    monkeypatch.setattr(_modal, "_smooth_trial_scale", spy)
    res = fe.modal_analysis(model, 6)
    assert not res.rigid.any()
    assert calls and all(p is not None for p in calls)
    # the bound from four fields is an upper bound of the scale over all twelve
    assert _modal._trial_scale_bound(model) >= full(model)
