"""``mvtk init``: a first study from the user's own files (issue 18, item 3)."""

from __future__ import annotations

from pathlib import Path

import pytest

from mvtk.cli import main
from mvtk.errors import ConfigError
from mvtk.study import load_study
from mvtk.study._init import init_study

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data" / "smart_beam"
STRUCTURE = ROOT / "data" / "structures" / "smart_beam.toml"


def test_init_recognises_the_tests_and_writes_a_valid_study(tmp_path, capsys):
    files = [DATA / "SYNTHETIC_smart_beam_impact.csv", DATA / "SYNTHETIC_smart_beam_decay.csv",
             DATA / "SYNTHETIC_smart_beam_scan.uff"]
    assert main(["init", str(tmp_path / "mine"), "--structure", str(STRUCTURE),
                 "--measurements", *map(str, files)]) == 0
    out = capsys.readouterr().out
    assert "impact" in out and "decay" in out and "modal" in out and "next: mvtk run" in out
    study = load_study(tmp_path / "mine" / "study.toml")
    cfg = study.config
    m = cfg["measurements"]
    assert (m["impact"]["reference"], m["impact"]["response"]) == ("force", "tip_accel")
    assert m["impact"]["record_s"] == pytest.approx(128.0, rel=0.01)  # 3 hits 128 s apart
    assert m["decay"]["channel"] == "tip_disp"
    # the resonances the default estimator finds are the specimen's first two modes
    assert cfg["damping"]["fn_hz"] == pytest.approx([13.26, 41.14], rel=1e-3)
    assert cfg["updating"]["targets_hz"] == cfg["damping"]["fn_hz"]
    assert cfg["modal"]["fmax_hz"] <= 400.0
    assert study.structure_file == STRUCTURE.resolve()


def test_init_without_structure_writes_a_placeholder_that_builds(tmp_path):
    res = init_study(tmp_path / "s", measurements=[DATA / "SYNTHETIC_smart_beam_decay.csv"])
    from mvtk.fe import build_model, load_structure

    model = build_model(load_structure(res.structure))
    assert model.n_dof > 100
    text = res.study.read_text(encoding="utf-8")
    assert "EDIT: a placeholder plate" in text and "[measurements.decay]" in text


def test_init_refuses_to_overwrite_and_names_missing_files(tmp_path):
    init_study(tmp_path / "s")
    with pytest.raises(ConfigError, match="exists; use --force"):
        init_study(tmp_path / "s")
    init_study(tmp_path / "s", overwrite=True)
    with pytest.raises(ConfigError, match="measurement file '.*nope.csv' not found"):
        init_study(tmp_path / "t", measurements=[tmp_path / "nope.csv"])
    assert main(["init", str(tmp_path / "s")]) == 2


def test_init_lists_files_it_cannot_use(tmp_path):
    p = tmp_path / "random.csv"
    p.write_text("time [s],acc [m/s^2]\n" + "".join(f"{i / 100},{(-1) ** i * 0.1}\n"
                                                    for i in range(300)), encoding="utf-8")
    res = init_study(tmp_path / "s", measurements=[p])
    (t,) = res.tests
    assert t["kind"] == "decay"  # one response channel and no force: a decay to fit
    bad = tmp_path / "bad.csv"
    bad.write_text("not,a\nmeasurement\n", encoding="utf-8")
    res = init_study(tmp_path / "u", measurements=[bad])
    assert res.tests[0]["kind"] == "skipped" and "not readable" in res.tests[0]["why"]


@pytest.mark.slow
def test_mvtk_run_accepts_what_init_wrote(tmp_path):
    files = [DATA / "SYNTHETIC_smart_beam_impact.csv", DATA / "SYNTHETIC_smart_beam_decay.csv"]
    res = init_study(tmp_path / "mine", structure=STRUCTURE, measurements=files)
    from mvtk.study import run

    out = run(res.study, tmp_path / "mine" / "report", progress=False)
    assert not out.failed, out.failed
    assert out.report_path is not None and out.report_path.is_file()
