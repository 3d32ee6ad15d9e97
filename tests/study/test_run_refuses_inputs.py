"""``mvtk.study.run`` from Python refuses an output folder that would overwrite an input,
as ``mvtk run --out`` does, before any stage runs."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from mvtk.errors import OutputError
from mvtk.study import load_study, run

DATA = Path(__file__).resolve().parents[2] / "data"


def test_run_refuses_an_out_dir_holding_an_input(tmp_path):
    study_dir = tmp_path / "sb"
    shutil.copytree(DATA / "smart_beam", study_dir)
    shutil.copytree(DATA / "structures", tmp_path / "structures")
    study = load_study(study_dir / "study.toml")
    inputs = [Path(p) for p in study.input_files]
    # a measurement file kept in a tables/ folder: writing the report's tables there
    # would replace it
    victim = inputs[-1]
    tables = victim.parent / "tables"
    tables.mkdir(exist_ok=True)
    moved = tables / victim.name
    text = (study_dir / "study.toml").read_text()
    rel = victim.relative_to(study_dir).as_posix()
    assert rel in text, rel
    victim.rename(moved)
    new_rel = moved.relative_to(study_dir).as_posix()
    (study_dir / "study.toml").write_text(text.replace(rel, new_rel))
    before = moved.read_bytes()
    with pytest.raises(OutputError, match="would overwrite the input file") as err:
        run(study_dir / "study.toml", victim.parent, report=False)
    assert moved.name in str(err.value)
    assert moved.read_bytes() == before
    assert not (victim.parent / "cache").exists()      # nothing ran
