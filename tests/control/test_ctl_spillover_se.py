"""A controller designed on a Craig-Bampton super element, evaluated on the full FE model
(the spillover check of issue 7, on the reduction engineer's plants)."""

import numpy as np
import pytest

from mvtk.control import PPF, added_damping, release_state, simulate, spillover_check
from mvtk.control._plant import structural_plant
from mvtk.reduction import craig_bampton
from mvtk.reduction._examples import eb_beam_xz

ALPHA, BETA = 0.02955, 9.77e-6


@pytest.fixture(scope="module")
def plants():
    beam = eb_beam_xz(n_el=40)
    se = craig_bampton(beam, ["mid", "tip"], 2)
    inputs, outputs = {"moment": (20, "ry")}, {"tip": (40, "uz")}
    design = structural_plant(se, inputs, outputs, alpha=ALPHA, beta=BETA, form="modal")
    full = structural_plant(beam, inputs, outputs, alpha=ALPHA, beta=BETA, form="modal",
                            n_modes=12)
    return design, full


def test_ppf_designed_on_se_is_stable_on_full_model(plants):
    design, full = plants
    f1 = design.meta["fn_hz"][0]
    ctrl = PPF([(f1, 0.4, 0.3)], sensor="tip")
    res = spillover_check(ctrl, design, full)
    assert res.stable_design and res.stable_evaluation
    assert res.verdict == "stable" and res.offending == ()
    # mode-1 closed-loop damping on the SE and on the full model agree: the SE keeps
    # mode 1 and the static flexibility (static correction) exact enough
    z_se = added_damping(design, ctrl, 1, design_plant=design)["zeta_closed"]
    z_fe = added_damping(full, ctrl, 1, design_plant=design)["zeta_closed"]
    assert z_fe == pytest.approx(z_se, rel=0.03)
    assert z_se > 0.05


def test_se_and_full_model_closed_loop_responses_agree(plants):
    design, full = plants
    f1 = design.meta["fn_hz"][0]
    ctrl = PPF([(f1, 0.4, 0.3)], sensor="tip")
    kw = dict(t_end=1.0, fs_out=500.0)
    y_se = simulate(design, ctrl, initial=release_state(design, 1, "tip", 1e-3),
                    design_plant=design, **kw).outputs.values[0]
    y_fe = simulate(full, ctrl, initial=release_state(full, 1, "tip", 1e-3),
                    design_plant=design, **kw).outputs.values[0]
    assert np.max(np.abs(y_se - y_fe)) < 0.03 * 1e-3
