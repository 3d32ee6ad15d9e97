import math

import numpy as np
import pytest

from mvtk.errors import DimensionError, ParameterError
from mvtk.validation import Check, check_table, frequency_table


def test_relative_check_against_paper_table2():
    # paper Table 2: FE 13.81 Hz vs experiment 13.26 Hz is a 4.15 % error
    c = Check("f1", 13.81, 13.26, 0.05, "Hz")
    assert c.relative_error == pytest.approx((13.81 - 13.26) / 13.26)
    assert c.passed
    assert not Check("f1", 13.81, 13.26, 0.04, "Hz").passed


def test_absolute_upper_lower_kinds():
    assert Check("a", 1.04, 1.0, 0.05, kind="absolute").passed
    assert not Check("a", 1.06, 1.0, 0.05, kind="absolute").passed
    assert Check("t", 0.9, 1.0, 0.0, "s", kind="upper").passed
    assert not Check("t", 1.1, 1.0, 0.05, "s", kind="upper").passed
    assert Check("z", 0.06, 0.05, 0.0, kind="lower").passed
    assert not Check("z", 0.04, 0.05, 0.005, kind="lower").passed


def test_nan_value_never_passes():
    assert not Check("x", math.nan, 1.0, 10.0).passed


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"kind": "percent"}, "kind must be one of"),
        ({"tolerance": -1.0}, "tolerance must be a finite number >= 0"),
        ({"reference": 0.0}, "relative tolerance needs a non-zero reference"),
        ({"reference": math.inf}, "reference must be finite"),
    ],
)
def test_bad_check_arguments(kwargs, match):
    args = {"name": "c", "value": 1.0, "reference": 1.0, "tolerance": 0.1} | kwargs
    with pytest.raises(ParameterError, match=match):
        Check(**args)


def test_check_table_columns_and_verdicts():
    df = check_table([Check("a", 1.0, 1.0, 0.01), Check("b", 2.0, 1.0, 0.01)])
    assert list(df["passed"]) == [True, False]
    assert df.loc[1, "error_pct"] == pytest.approx(100.0)
    assert df.loc[0, "tolerance"] == "±1 %"
    with pytest.raises(ParameterError, match="expects Check objects, got dict"):
        check_table([{"name": "a"}])


def test_frequency_table_reproduces_paper_table5_errors():
    fe = [13.811, 42.673, 145.49, 150.16]
    se = [14.249, 43.414, 152.54, 154.38]
    df = frequency_table({"FE": fe, "SE": se}, "FE")
    # paper Table 5 "% Error" column: 3.07 (printed; 3.17 computed), 1.71, 4.62 (4.85), 2.73 (2.81)
    np.testing.assert_allclose(df["SE error %"].to_numpy(),
                               100 * (np.array(se) - fe) / np.array(fe))
    assert df["SE error %"].iloc[1] == pytest.approx(1.74, abs=0.01)
    assert list(df.index) == [1, 2, 3, 4]


def test_frequency_table_pads_and_rejects_bad_input():
    df = frequency_table({"test": [13.26, 41.14], "FE": [13.8, 42.7, 82.0]}, "test")
    assert np.isnan(df["test"].iloc[2]) and np.isnan(df["FE error %"].iloc[2])
    with pytest.raises(ParameterError, match="reference column 'x' not in columns"):
        frequency_table({"a": [1.0]}, "x")
    with pytest.raises(ParameterError, match="compare column 'b' not in columns"):
        frequency_table({"a": [1.0]}, "a", compare=["b"])
    with pytest.raises(DimensionError, match="at least one frequency"):
        frequency_table({"a": []}, "a")
