"""The study's side of the updating weights: which identified std a target takes, and the
report's summary of a model-form verdict (fast: no study run)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from mvtk.study._report import _stage_warnings
from mvtk.study._updating import identified_std
from mvtk.updating import FrequencyTarget


def _study(modal: dict | None):
    return SimpleNamespace(config={"modal": modal} if modal else {},
                           section=lambda name: modal if name == "modal" else None)


def test_identified_std_follows_the_shape_pairing_the_window_and_reliability():
    table = {"mode": [1, 2, 3, 4], "fn_hz": [10.0, 20.0, 30.5, 40.0],
             "fn_std_hz": [0.01, 0.02, 0.03, float("nan")],
             "reliable": [True, True, False, True]}
    targets = [FrequencyTarget(10.1, label="a"),            # mode 1, 1 % away
               FrequencyTarget(25.0, label="b"),            # nothing within 3 %
               FrequencyTarget(30.0, label="c"),            # mode 3: not reliable
               FrequencyTarget(40.0, label="d"),            # mode 4: no std
               FrequencyTarget(19.0, label="e"),            # its shape is test mode 2
               FrequencyTarget(10.0, label="f", std_hz=0.5)]  # stated: kept
    attached = [None, None, None, None, 2, None]
    out, src = identified_std(_study({"pair_within": 0.03}), targets, attached,
                              {"table": table})
    assert [t.std_hz for t in out] == [0.01, None, None, None, 0.02, 0.5]
    assert src == ["test mode 1", "none", "none", "none", "test mode 2", "stated"]
    # without a modal test nothing is attached
    out, src = identified_std(_study(None), targets[:1], [None], None)
    assert out[0].std_hz is None and src == ["none"]


def test_a_model_form_verdict_is_listed_among_the_stage_warnings():
    up = {"parameters": ["k"], "at_bound": [False], "identifiable": True,
          "residual_verdict": ["noise", "model form", "model-form term"],
          "summary": {"residuals": [{"target": "f1"}, {"target": "f2"}, {"target": "f3"}]},
          "targets_hz": [1.0, 2.0, 3.0], "fn_hz": np.array([1.0, 2.0, 3.0])}
    res = SimpleNamespace(results={"updating": up})
    notes = [n for n in _stage_warnings(res) if "model-form term" in n]
    assert notes == ["updating: the residual of f2 is beyond noise and the model-form term "
                     "(model form: the model lacks something no updated value supplies)"]


def test_identifiability_weights_the_log_sensitivities_by_the_target_stds():
    from mvtk.study._stages import identifiability

    S = np.array([[0.5, 0.2], [0.5, 0.21], [0.5, 0.6]])
    prm = [SimpleNamespace(fixed=False), SimpleNamespace(fixed=False)]
    targets = [FrequencyTarget(f) for f in (10.0, 20.0, 30.0)]

    def res(std_hz):
        return SimpleNamespace(sensitivity=S, parameters=prm, at_bound=[False, False],
                               identifiable=True, targets=targets,
                               target_std_hz=np.asarray(std_hz, dtype=float))

    equal = identifiability(res([0.05, 0.1, 0.15]), ["a", "b"], 100.0)  # 0.5 % each
    unweighted = identifiability(res([np.nan] * 3), ["a", "b"], 100.0)
    assert equal["log_condition_number"] == unweighted["log_condition_number"]
    # the only target that separates a from b is 100x less certain: the Fisher matrix
    # S'WS is near-singular and the verdict says so
    weak = identifiability(res([0.05, 0.1, 15.0]), ["a", "b"], 100.0)
    assert weak["log_condition_number"] > 10 * equal["log_condition_number"]
    assert not weak["identifiable_study"] and equal["identifiable_study"]
