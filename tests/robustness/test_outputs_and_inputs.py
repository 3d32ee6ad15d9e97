"""Nothing lost: no command writes onto one of its inputs (symlinks and hard links
followed; ``--force`` is no escape), and ``mvtk report`` checks the run's manifest
before it prints a verdict."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from mvtk.cli import main

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "data" / "smart_beam"


def _refused(capsys, argv, *inputs):
    before = {p: Path(p).read_bytes() for p in inputs}
    assert main([str(a) for a in argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    assert "refusing to overwrite an input" in err or "would overwrite the input" in err, err
    for p, data in before.items():
        assert Path(p).read_bytes() == data, f"{p} changed"
    return err


@pytest.mark.parametrize("how", ["same", "symlink", "hardlink"])
def test_read_refuses_output_onto_its_input(tmp_path, capsys, how):
    src = tmp_path / "impact.csv"
    shutil.copy(DATA / "SYNTHETIC_smart_beam_impact.csv", src)
    out = {"same": src, "symlink": tmp_path / "link.nc", "hardlink": tmp_path / "hard.nc"}[how]
    if how == "symlink":
        out.symlink_to(src)
    elif how == "hardlink":
        os.link(src, out)
    err = _refused(capsys, ["read", src, "-o", out], src)
    assert f"--output '{out}' is the input file '{src}'" in err


@pytest.mark.parametrize("option", ["--uff-modes", "--uff-frf"])
def test_modal_refuses_uff_export_onto_the_measured_file(tmp_path, capsys, option):
    src = tmp_path / "scan.uff"
    shutil.copy(DATA / "SYNTHETIC_smart_beam_scan.uff", src)
    os.link(src, tmp_path / "other.uff")
    _refused(capsys, ["modal", src, option, src], src)
    _refused(capsys, ["modal", src, option, tmp_path / "other.uff"], src)


def test_modal_refuses_two_exports_onto_one_file(tmp_path, capsys):
    src = DATA / "SYNTHETIC_smart_beam_scan.uff"
    assert main(["modal", str(src), "--uff-modes", str(tmp_path / "a.uff"),
                 "--uff-frf", str(tmp_path / "a.uff")]) == 2
    assert "--uff-modes and --uff-frf name one file" in capsys.readouterr().err


def test_update_refuses_out_onto_the_study_or_its_structure(clean_run, tmp_path, capsys):
    study = clean_run[0]
    structure = study.parent / "beam.toml"
    _refused(capsys, ["update", study, "--out", study], study)
    _refused(capsys, ["update", study, "--out", structure], structure)
    (tmp_path / "s.toml").symlink_to(structure)
    _refused(capsys, ["update", study, "--out", tmp_path / "s.toml"], structure)


def test_run_refuses_an_out_folder_whose_outputs_are_inputs(clean_run, tmp_path, capsys):
    study = clean_run[0]
    out = tmp_path / "out"
    out.mkdir()
    os.link(study.parent / "beam.toml", out / "index.html")   # a hard link to an input
    err = _refused(capsys, ["run", study, "--out", out, "--quiet"], study.parent / "beam.toml")
    assert "beam.toml" in err and not (out / "cache").exists()


def test_init_refuses_to_overwrite_an_input_even_with_force(tmp_path, capsys):
    folder = tmp_path / "study"
    folder.mkdir()
    meas = folder / "study.toml"     # a measurement file that has the output's name
    shutil.copy(DATA / "SYNTHETIC_smart_beam_impact.csv", meas)
    _refused(capsys, ["init", folder, "--measurements", meas, "--force"], meas)
    # the geometry given as the file init writes
    _refused(capsys, ["init", folder, "--geometry", meas, "--force"], meas)


def _copy_out(clean_run, dest: Path) -> Path:
    out = dest / "out"
    shutil.copytree(clean_run[1], out)
    return out


def test_report_verifies_the_manifest(clean_run, tmp_path, capsys):
    out = _copy_out(clean_run, tmp_path)
    assert (out / "manifest.json").is_file()
    assert main(["report", str(out)]) == 0
    text = capsys.readouterr().out
    assert "integrity: " in text and "match" in text and "verdict: PASS" in text


def test_report_refuses_a_half_cut_page(clean_run, tmp_path, capsys):
    out = _copy_out(clean_run, tmp_path)
    page = out / "index.html"
    data = page.read_bytes()
    page.write_bytes(data[: len(data) // 2])
    assert main(["report", str(out)]) == 2
    cap = capsys.readouterr()
    assert "verdict" not in cap.out
    assert f"{page}: {len(data) // 2} bytes, the run wrote {len(data)}" in cap.err
    # without the manifest the cut page is still refused (it does not end the document)
    (out / "manifest.json").unlink()
    assert main(["report", str(out)]) == 2
    assert "the page is cut short" in capsys.readouterr().err


def test_report_refuses_a_changed_table_or_cache_file(clean_run, tmp_path, capsys):
    out = _copy_out(clean_run, tmp_path)
    table = sorted((out / "tables").glob("*.csv"))[0]
    table.write_text(table.read_text().replace("1", "2", 1))
    assert main(["report", str(out)]) == 2
    assert f"{table}: " in capsys.readouterr().err
    out2 = _copy_out(clean_run, tmp_path / "b")
    victim = sorted((out2 / "cache").glob("*.json"))[0]
    victim.unlink()
    assert main(["report", str(out2)]) == 2
    assert "missing" in capsys.readouterr().err


def test_report_pdf_refuses_output_onto_the_page(clean_run, tmp_path, capsys):
    out = _copy_out(clean_run, tmp_path)
    _refused(capsys, ["report", out, "--pdf", "--output", out / "index.html"],
             out / "index.html")
