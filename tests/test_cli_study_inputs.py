"""The example study given to the file commands: modes runs its structure, damping and
modal refuse it in one line naming the study's measurement files and `mvtk run`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

STUDY = Path(__file__).resolve().parents[1] / "data" / "smart_beam" / "study.toml"


def _mvtk(*args):
    return subprocess.run([sys.executable, "-m", "mvtk", *args], capture_output=True,
                          text=True, timeout=300)


def test_modes_of_a_study_is_its_structure():
    r = _mvtk("modes", str(STUDY), "--json")
    s = _mvtk("modes", str(STUDY.parents[1] / "structures" / "smart_beam.toml"), "--json")
    assert r.returncode == 0 and r.stdout == s.stdout


def test_damping_and_modal_refuse_a_study_in_one_line():
    for cmd in ("damping", "modal"):
        r = _mvtk(cmd, str(STUDY))
        assert r.returncode == 2
        err = r.stderr.strip().splitlines()
        assert len(err) == 1 and "is a study, not a measurement file" in err[0]
        assert "SYNTHETIC_smart_beam_impact.csv" in err[0] and "mvtk run" in err[0]


def test_correlate_a_study_prints_its_correlation_stage():
    import json

    r = _mvtk("correlate", str(STUDY), "--json")
    assert r.returncode == 0, r.stderr
    doc = json.loads(r.stdout)
    assert doc["n_sensors"] == 13 and doc["mapping"] == "shape"
    pairs = doc["pairs"]
    assert len(pairs["test_mode"]) == 6 and all(pairs["paired"])
    # the report's model-form check: every identified mode pairs with MAC > 0.95
    assert min(pairs["mac"]) > 0.95
    assert max(abs(x) for x in pairs["df_pct"]) < 3.0
    text = _mvtk("correlate", str(STUDY))
    assert text.returncode == 0 and "13 sensor DOFs mapped (shape) onto the updated FE" \
        in text.stdout


def test_correlate_without_a_structure_says_what_is_missing():
    structure = STUDY.parents[1] / "structures" / "smart_beam.toml"
    for arg, expect in ((structure, "no [modal] section"),
                        (STUDY.parent / "SYNTHETIC_smart_beam_impact.csv",
                         "needs a STRUCTURE TOML")):
        r = _mvtk("correlate", str(arg))
        assert r.returncode == 2, r.stderr
        err = r.stderr.strip().splitlines()
        assert len(err) == 1 and expect in err[0], err
