"""Updating a free-free model: its rigid-body modes are solved and set aside, never paired.

A bare mesh that `mvtk init` wraps has no supports until the user adds one; updating it
gave NaN sensitivities (0 Hz rigid modes paired with targets) and scipy's
"array must not contain infs or NaNs".
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mvtk.fe import build_model, load_structure, modal_analysis
from mvtk.updating import Parameter, update
from mvtk.updating._parameters import with_values

PANEL = (Path(__file__).resolve().parents[2] / "data" / "structures" / "curved_panel"
         / "curved_panel.toml")


def _free_panel():
    desc = load_structure(PANEL)
    desc.pop("boundary")
    return desc


def test_free_free_twin_recovers_the_modulus_from_elastic_modes():
    truth = _free_panel()
    res = modal_analysis(build_model(truth), n_modes=10)
    assert res.rigid.sum() == 6   # the truth really is free-free
    targets = res.fn_hz[~res.rigid][:3]
    start = with_values(truth, {"materials.al.E": 70e9 * 1.2})
    r = update(start, [Parameter("materials.al.E", lower=35e9, upper=140e9)],
               targets.tolist(), n_modes=6)
    assert r.values[0] == pytest.approx(70e9, rel=1e-5)
    assert np.abs(r.residual_table()["error_pct"]).max() < 1e-4
    # frequencies of a free-free shell scale exactly as sqrt(E)
    np.testing.assert_allclose(r.sensitivity[:, 0], 0.5, rtol=1e-6)
    assert np.all(np.asarray(r.model_fn_hz) > 1.0)  # no rigid mode among the model's modes


def test_fewer_requested_modes_than_rigid_ones_still_gives_elastic_modes():
    """n_modes = 2 on a model with 6 rigid-body modes: the first solve returns only rigid
    modes; they are counted and the solve repeated until two elastic modes are found."""
    truth = _free_panel()
    res = modal_analysis(build_model(truth), n_modes=8)
    r = update(truth, [Parameter("materials.al.E", lower=35e9, upper=140e9)],
               res.fn_hz[6:8].tolist(), n_modes=2)
    np.testing.assert_allclose(r.model_fn_hz, res.fn_hz[6:8], rtol=1e-8)
    assert r.values[0] == pytest.approx(70e9, rel=1e-6)
