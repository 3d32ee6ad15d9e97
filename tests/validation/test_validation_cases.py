"""The validation registry (mvtk.validation.validation_cases): every case is asserted here,
and the same registry writes the docs' validation evidence page (docs/_ext/mvtk_docs.py)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mvtk.errors import MissingDependencyError, ParameterError
from mvtk.validation import ValidationCase, run_validation, validation_cases

CASES = validation_cases()
AREAS = ("io", "signal", "damping", "modal", "fe", "updating", "correlation", "reduction",
         "control")


@pytest.mark.parametrize("case", [
    pytest.param(c, id=c.name, marks=[pytest.mark.shared_data] if c.data else [])
    for c in CASES])
def test_case_within_tolerance(case, request):
    data_dir = request.getfixturevalue("shared_data") if case.data else None
    try:
        checks = case.checks(data_dir)
    except MissingDependencyError as err:  # an optional extra (npTDMS) is not installed
        pytest.skip(str(err))
    assert len(checks) == len(case.labels)
    failed = [(c.name, c.value, c.reference, c.describe_tolerance())
              for c in checks if not c.passed]
    assert not failed, failed


def test_registry_is_well_formed():
    names = [c.name for c in CASES]
    assert len(set(names)) == len(names), "case names must be unique"
    assert {c.area for c in CASES} >= set(AREAS), "every pipeline stage has a case"
    for c in CASES:
        assert c.name.startswith(c.area + "."), c.name
        assert c.source and c.title, c.name
        assert all(np.isfinite(c.reference)), c.name


def test_run_validation_table_and_missing_data(tmp_path):
    cheap = [c for c in CASES if c.name in ("damping.rayleigh_table3", "io.lvm_impact_record")]
    df = run_validation(cheap, data_dir=tmp_path)  # an empty corpus: the io case is skipped
    assert list(df["case"].unique()) == [c.name for c in cheap]
    ray = df[df["case"] == "damping.rayleigh_table3"]
    assert ray["passed"].tolist() == [True, True] and set(ray["status"]) == {"pass"}
    lvm = df[df["case"] == "io.lvm_impact_record"]
    assert lvm["passed"].isna().all() and lvm["value"].isna().all()
    status = lvm["status"].iloc[0]
    assert status.startswith("skipped: ") and "lvm/acceleration.lvm not found" in status
    assert str(tmp_path) in status


def _case(compute, reference=(1.0,), **kw):
    return ValidationCase("x.case", "x", "a test case", "nowhere", ("q",) * len(reference),
                          reference, 1e-3, compute, **kw)


def test_a_wrong_value_fails_and_an_exception_is_an_error():
    df = run_validation([_case(lambda: [1.01])])
    assert df["passed"].tolist() == [False] and df["status"].tolist() == ["FAIL"]
    assert df["error_pct"].iloc[0] == pytest.approx(1.0)

    def boom():
        raise RuntimeError("solver diverged")

    df = run_validation([_case(boom)])
    assert df["passed"].isna().all()
    assert df["status"].iloc[0] == "error: RuntimeError: solver diverged"

    def no_extra():
        raise MissingDependencyError("reading TDMS needs npTDMS: pip install 'mvtk[tdms]'")

    df = run_validation([_case(no_extra)])
    assert df["passed"].isna().all()
    assert df["status"].iloc[0] == "skipped: reading TDMS needs npTDMS: pip install 'mvtk[tdms]'"


def test_bad_case_definitions():
    with pytest.raises(ParameterError, match=r"'x.case': 2 labels but 1 reference"):
        ValidationCase("x.case", "x", "t", "s", ("a", "b"), (1.0,), 1e-3, lambda: [1.0])
    with pytest.raises(ParameterError, match=r"'x.case': computed 2 values for 1 labels"):
        _case(lambda: [1.0, 2.0]).checks()
    with pytest.raises(ParameterError, match=r"'x.case': kind must be 'relative', 'absolute', "
                       r"'upper' or 'lower', got 'roughly'"):
        _case(lambda: [1.0], kind="roughly")
    assert isinstance(run_validation([]), pd.DataFrame)
