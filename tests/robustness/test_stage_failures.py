"""Family "stage inputs": input changes after a run (the cache must follow them) and inputs
that make a stage fail (a clear message, never a raw numpy error); stability verdicts;
the JSON output of run and control against their JSON Schemas."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from robust_helpers import assert_same_numbers, copy_run

from mvtk.cli import main
from mvtk.study import run, study_checks

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]


def _validate(doc: dict, command: str) -> None:
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((ROOT / "schemas" / f"{command}.schema.json").read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    jsonschema.validate(doc, schema, cls=jsonschema.Draft202012Validator)


def test_changed_patch_reruns_the_reduction(clean_run, tmp_path):
    """Issue 16: changing control.patch to a patch that does not exist and rerunning into
    the same --out exited 0 with identical tables."""
    study, out = copy_run(clean_run, tmp_path, {'patch = "pzt"': 'patch = "nope"'})
    res = run(study, out, progress=False, report=False)
    assert "reduction" in res.failed and "reduction" not in res.cache_hits
    assert "control.patch: no patch 'nope' in the structure" in res.failed["reduction"]
    assert "control" in res.unavailable
    assert {"ingest", "modal", "fe", "updating", "correlation", "damping",
            "uncertainty"} <= set(res.cache_hits)


def test_controller_gain_change_reruns_only_control(clean_run, tmp_path):
    study, out = copy_run(clean_run, tmp_path, {"gain = 0.1 ": "gain = 0.05 "})
    res = run(study, out, progress=False, report=False)
    assert set(res.cache_hits) == {"ingest", "modal", "fe", "updating", "correlation",
                                   "uncertainty", "damping", "reduction"}


def test_fs_out_too_low_is_a_clear_stage_failure(clean_run, tmp_path, capsys):
    """Issue 16: `fs_out = 5` failed as `ValueError: zero-size array`."""
    study, out = copy_run(clean_run, tmp_path, {"fs_out = 200.0": "fs_out = 5.0"})
    assert main(["run", str(study), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert re.search(r"mvtk run: stage control FAILED: control\.fs_out = 5 Hz cannot resolve "
                     r"the first mode \(13\.\d+ Hz\) in the spectra: expected fs_out > 2\.4 "
                     r"x 13\.\d+", err), err
    assert "zero-size" not in err and "Traceback" not in err
    html = (out / "index.html").read_text(encoding="utf-8")
    assert "control.fs_out = 5 Hz" in html  # the report names the failure too


def test_unstable_ppf_fails_the_study_and_mvtk_control(clean_run, tmp_path, capsys):
    """Issue 16: a PPF gain of 5.0 passed the closed-loop zeta check (the loop has a pole
    in the right half plane); `mvtk control` printed no stability information."""
    study, out = copy_run(clean_run, tmp_path, {"gain = 0.1 ": "gain = 5.0 "})
    res = run(study, out, progress=False, report=False)
    rows = {r["controller"]: r for r in res.results["control"]["metrics"]}
    assert rows["PPF"]["stable"] is False and rows["PPF"]["max_real_pole_1_per_s"] > 1.0
    assert rows["SRF"]["stable"] and rows["open loop"]["stable"]
    failed = [c.name for c in study_checks(res) if not c.passed]
    assert "PPF closed loop stable (largest real part of the poles)" in failed
    assert "PPF closed-loop zeta of mode 1 (loop UNSTABLE: least-damped pole)" in failed
    assert main(["control", str(study), "--cache", str(out), "--json"]) == 1
    doc = json.loads(capsys.readouterr().out)
    _validate(doc, "control")
    assert doc["unstable"] == ["PPF"]
    assert main(["control", str(study), "--cache", str(out)]) == 1
    text = capsys.readouterr()
    assert "stable" in text.out and "closed loop 'PPF' is UNSTABLE" in text.err


def test_run_and_control_json_conform_to_their_schemas(clean_run, tmp_path, capsys):
    study, out = copy_run(clean_run, tmp_path)
    assert main(["run", str(study), "--out", str(out), "--json", "--quiet"]) == 0
    doc = json.loads(capsys.readouterr().out)
    _validate(doc, "run")
    assert doc["passed"] and len(doc["cached_stages"]) == 9
    assert all(c["passed"] for c in doc["checks"])
    assert main(["control", str(study), "--cache", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    _validate(doc, "control")
    assert [r["controller"] for r in doc["rows"]] == ["open loop", "PPF", "SRF", "Lyapunov"]
    assert all(r["stable"] for r in doc["rows"]) and doc["unstable"] == []
    assert main(["reduce", str(study), "--cache", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    _validate(doc, "reduce")
    assert doc["updated_model"] and [r["name"] for r in doc["retained"]][-1] == "tip"
    assert main(["update", str(study), "--cache", str(out), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    _validate(doc, "update")
    assert doc["cached"] is True


def test_views_agree_with_the_run(clean_run, tmp_path, capsys):
    """The commands are views of one pipeline: the same numbers as `mvtk run`."""
    study, out = copy_run(clean_run, tmp_path)
    res = run(study, out, progress=False, report=False)
    assert_same_numbers(clean_run[2].results, res.results, rtol=0.0)
