"""Parameters addressed by dotted paths and frequency targets."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from mvtk.errors import ConfigError, DimensionError, ParameterError
from mvtk.updating import (
    FrequencyTarget,
    Parameter,
    get_path,
    set_path,
    targets_from_modal_result,
    with_values,
)

DESC = {
    "materials": {"steel": {"E": 2.1e11, "name": "steel", "flag": True}},
    "patches": [{"x0": 0.005, "x1": 0.055}, {"x0": 0.1}],
    "mesh": {"nx": 10},
}


def test_get_and_set_nested_paths_with_list_index():
    assert get_path(DESC, "materials.steel.E") == 2.1e11
    assert get_path(DESC, "patches.1.x0") == 0.1
    assert get_path(DESC, "mesh.nx") == 10.0
    d = with_values(DESC, {"patches.0.x0": 0.01, "materials.steel.E": 2e11})
    assert d["patches"][0]["x0"] == 0.01 and d["materials"]["steel"]["E"] == 2e11
    # the original is untouched (deep copy)
    assert DESC["patches"][0]["x0"] == 0.005
    set_path(d, "patches.-1.x0", 0.2)
    assert d["patches"][1]["x0"] == 0.2


@pytest.mark.parametrize(
    ("path", "match"),
    [
        ("materials.alu.E", r"no key 'alu' under materials; available keys: \['steel'\]"),
        ("patches.x.x0", "patches is a list, expected an integer index, got 'x'"),
        ("patches.5.x0", r"index 5 out of range for patches \(list of length 2\)"),
        ("materials.steel.name", "expected a number, found str 'steel'"),
        ("materials.steel.flag", "expected a number, found bool"),
        ("materials.steel.E.value", "materials.steel.E is a float value"),
        ("materials..E", "non-empty dotted string"),
    ],
)
def test_bad_paths_raise_config_error_naming_the_path(path, match):
    with pytest.raises(ConfigError, match=match):
        get_path(DESC, path)


def test_parameter_resolve_reads_initial_and_default_scale():
    p = Parameter("materials.steel.E", lower=1e11, upper=3e11)
    assert p.resolve(DESC) == (2.1e11, 2.1e11)
    q = Parameter("patches.0.x0", initial=0.006, scale=0.01, label="patch x0")
    assert q.resolve(DESC) == (0.006, 0.01)
    assert q.name == "patch x0"


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"lower": 3e11, "upper": 1e11}, ParameterError, "lower bound 3e\\+11 must be below"),
        ({"scale": -1.0}, ParameterError, "scale must be a positive finite number"),
        ({"initial": math.nan}, ParameterError, "initial must be a finite number"),
        ({"lower": "a"}, ParameterError, "lower bound must be a number"),
    ],
)
def test_parameter_bad_arguments(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        Parameter("materials.steel.E", **kwargs)


def test_parameter_initial_outside_bounds():
    p = Parameter("materials.steel.E", lower=2.2e11, upper=3e11)
    with pytest.raises(ParameterError, match="initial value 2.1e\\+11 must lie strictly inside"):
        p.resolve(DESC)
    # a fixed parameter may sit anywhere
    assert Parameter("materials.steel.E", lower=2.2e11, fixed=True).resolve(DESC)[0] == 2.1e11


def test_parameter_from_dict_errors():
    assert Parameter.from_dict({"path": "mesh.nx", "lower": 1}).lower == 1
    with pytest.raises(ConfigError, match=r"p\[0\]: unknown keys \['bound'\]"):
        Parameter.from_dict({"path": "a.b", "bound": 1}, "p[0]")
    with pytest.raises(ConfigError, match="missing key 'path'"):
        Parameter.from_dict({"lower": 1})
    with pytest.raises(ConfigError, match="lower bound 2 must be below upper bound 1"):
        Parameter.from_dict({"path": "a", "lower": 2, "upper": 1})


def test_frequency_target_validation_and_shape_forms():
    t = FrequencyTarget(13.26, shape={(3, "uz"): 1.0, (5, "uz"): 0.4})
    assert t.sensors == ((3, "uz"), (5, "uz")) and np.allclose(t.shape_values, [1.0, 0.4])
    t2 = FrequencyTarget(41.14, shape={"nodes": [1, 2], "components": "uz", "values": [1, -1]})
    assert t2.has_shape and t2.sensors[1] == (2, "uz")
    assert not FrequencyTarget(10).has_shape
    with pytest.raises(ParameterError, match="fn_hz must be positive and finite, got -1"):
        FrequencyTarget(-1.0)
    with pytest.raises(ParameterError, match="fn_hz must be a number in Hz, got '13'"):
        FrequencyTarget("13")
    with pytest.raises(ParameterError, match="weight must be a finite number >= 0"):
        FrequencyTarget(10.0, weight=-1)
    with pytest.raises(ParameterError, match="mode must be a 1-based mode number, got 0"):
        FrequencyTarget(10.0, mode=0)
    with pytest.raises(ParameterError, match="unknown DOF component 'uq'"):
        FrequencyTarget(10.0, shape={(1, "uq"): 1.0, (2, "uz"): 1.0})
    with pytest.raises(DimensionError, match="at least 2 sensor values"):
        FrequencyTarget(10.0, shape={(1, "uz"): 1.0})
    with pytest.raises(DimensionError, match="equal lengths, got 2, 2, 3"):
        FrequencyTarget(10.0, shape={"nodes": [1, 2], "components": ["uz", "uz"],
                                     "values": [1, 2, 3]})
    with pytest.raises(ConfigError, match=r"t\[1\]: unknown keys \['freq'\]"):
        FrequencyTarget.from_dict({"freq": 3}, "t[1]")
    with pytest.raises(ConfigError, match="missing key 'fn_hz'"):
        FrequencyTarget.from_dict({"weight": 3})


class _DampingLike:
    def __init__(self, fn):
        self.fn_hz = fn


def test_targets_from_modal_results_of_several_forms():
    a = targets_from_modal_result(_DampingLike(np.array([13.26, 41.14])))
    b = targets_from_modal_result(pd.DataFrame({"fn_hz": [13.26, 41.14], "zeta": [1e-3, 2e-3]}))
    c = targets_from_modal_result([_DampingLike(13.26), _DampingLike(41.14)])
    d = FrequencyTarget.from_modal_result({"fn_hz": [13.26, 41.14]}, weights=[1, 2],
                                          labels=["b1", "t1"])
    for ts in (a, b, c, d):
        assert [t.fn_hz for t in ts] == [13.26, 41.14]
    assert d[1].weight == 2 and d[1].label == "t1"
    sel = targets_from_modal_result(_DampingLike([13.26, 41.14, 80.0]), select=[0, 2])
    assert [t.fn_hz for t in sel] == [13.26, 80.0]


def test_targets_from_modal_result_errors():
    with pytest.raises(ParameterError, match="cannot read natural frequencies from a int"):
        targets_from_modal_result(3)
    with pytest.raises(ParameterError, match=r"no 'fn_hz' key; keys: \['f'\]"):
        targets_from_modal_result({"f": [1.0]})
    with pytest.raises(ParameterError, match="contains no natural frequency"):
        targets_from_modal_result(_DampingLike([]))
    with pytest.raises(ParameterError, match=r"select positions \[4\] out of range for 2"):
        targets_from_modal_result(_DampingLike([1.0, 2.0]), select=[4])
    with pytest.raises(DimensionError, match="expected 2 weights, got 1"):
        targets_from_modal_result(_DampingLike([1.0, 2.0]), weights=[1.0])
    with pytest.raises(ParameterError, match="fn_hz must be positive"):
        targets_from_modal_result(_DampingLike([1.0, np.nan]))
