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
    # the record is chosen from the data when the study runs, as `mvtk damping` does
    assert m["impact"].get("record_s") is None
    assert m["decay"]["channel"] == "tip_disp"
    # the resonances the default estimator finds are the specimen's first two modes
    assert cfg["damping"]["fn_hz"] == pytest.approx([13.26, 41.14], rel=1e-3)
    # targets as tables; with a multi-point test their FE modes are paired by MAC at run
    assert [t["fn_hz"] for t in cfg["updating"]["targets"]] == cfg["damping"]["fn_hz"]
    assert all(t.get("mode") is None for t in cfg["updating"]["targets"])
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


# ------------------------------------------------------------ imported meshes (issue 18)
PANEL = ROOT / "data" / "structures" / "curved_panel"
IMPACT = [DATA / "SYNTHETIC_smart_beam_impact.csv"]


def test_init_around_a_bare_mesh_lists_the_physical_groups(tmp_path, capsys):
    assert main(["init", str(tmp_path / "m"), "--structure", str(PANEL / "curved_panel.msh")]
                ) == 0
    out = capsys.readouterr().out
    assert f"wrote {tmp_path / 'm' / 'structure.toml'} around " in out
    assert "then check it with `mvtk modes" in out
    from types import SimpleNamespace

    res = SimpleNamespace(structure=tmp_path / "m" / "structure.toml",
                          study=tmp_path / "m" / "study.toml")
    text = res.structure.read_text(encoding="utf-8")
    # the surface group gets a shell section, the line groups are commented candidates
    assert 'sections = { skin = "skin" }' in text
    assert '#   stiffener = "stiffener_beam"   (20 line2)' in text
    assert '#   ends = "ends_beam"   (32 line2)' in text
    assert "# [sections.stiffener_beam]" in text and "[sections.skin]" in text
    assert "FREE-FREE" in text and "node\n# sets of the mesh): ends, skin, stiffener." in text
    assert '# supports = { ends = "clamped" }' in text
    assert "357 nodes, 320 quad4, 52 line2" in text
    from mvtk.fe import load_structure

    desc = load_structure(res.structure)
    assert desc["mesh"]["sections"] == {"skin": "skin"}
    study = load_study(res.study)
    assert study.structure_file == res.structure.resolve()
    assert "EDIT: written around your mesh" in res.study.read_text(encoding="utf-8")


def test_init_mesh_errors_name_the_file_and_what_was_found(tmp_path):
    meshio = pytest.importorskip("meshio")
    import numpy as np

    lines = tmp_path / "rods.vtu"
    meshio.Mesh(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]),
                [("line", np.array([[0, 1], [1, 2]]))],
                cell_data={"ref": [np.array([7, 7])]}).write(lines)
    with pytest.raises(ConfigError, match=r"rods.vtu' has no element set \(physical group\) of "
                       r"only triangle/quad cells .* sets found: ref:7 \(line2\)"):
        init_study(tmp_path / "a", structure=lines)
    junk = tmp_path / "part.msh"
    junk.write_text("this is not a mesh\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"--structure '.*part.msh' is neither a structure "
                       "TOML nor a readable mesh"):
        init_study(tmp_path / "b", structure=junk)
    # the written structure.toml is refused like any other file to overwrite
    init_study(tmp_path / "c", structure=PANEL / "curved_panel.msh")
    (tmp_path / "c" / "study.toml").unlink()
    with pytest.raises(ConfigError, match="structure.toml' exists; use --force"):
        init_study(tmp_path / "c", structure=PANEL / "curved_panel.msh")


def test_init_around_a_nastran_deck_references_it(tmp_path):
    from mvtk.study._init import mesh_structure_toml

    deck = tmp_path / "wing.bdf"
    deck.write_text("BEGIN BULK\nENDDATA\n", encoding="utf-8")
    text = mesh_structure_toml(deck, tmp_path / "s")
    assert 'type = "mesh"' in text and 'file = "../wing.bdf"' in text
    assert "sections" not in text.split("[mesh]")[1]  # the deck carries its properties


def _run_ok(study_path, out):
    from mvtk.study import run

    res = run(study_path, out, progress=False)
    assert not res.failed, res.failed
    assert res.report_path is not None and res.report_path.is_file()
    return res


@pytest.mark.slow
def test_mvtk_run_accepts_init_on_the_imported_panel(tmp_path):
    """The curved panel (Gmsh mesh referenced by its structure TOML) with a free decay:
    init writes a study that runs (FE modes of the imported mesh, decay damping)."""
    res = init_study(tmp_path / "p", structure=PANEL / "curved_panel.toml",
                     measurements=[DATA / "SYNTHETIC_smart_beam_decay.csv"])
    assert res.structure == PANEL / "curved_panel.toml"  # referenced, not rewritten
    out = _run_ok(res.study, tmp_path / "p" / "report")
    assert "fe" in out.results


@pytest.mark.slow
def test_mvtk_run_accepts_init_on_a_bare_mesh_once_supported(tmp_path):
    """`mvtk init --structure part.msh` with a hammer test: choosing a support among the
    listed candidates (the EDIT a user makes) gives a study that runs, updating included.
    The measurements are the smart beam's, not the panel's, so the report's frequency
    checks fail (as they should); no stage fails."""
    assert main(["init", str(tmp_path / "m"), "--structure", str(PANEL / "curved_panel.msh"),
                 "--measurements", *map(str, IMPACT)]) == 0
    s = tmp_path / "m" / "structure.toml"
    text = s.read_text(encoding="utf-8")
    s.write_text(text.replace('# supports = { ends = "clamped" }',
                              'supports = { ends = "clamped" }'), encoding="utf-8")
    study = (tmp_path / "m" / "study.toml").read_text(encoding="utf-8")
    assert 'path = "materials.steel.E"' in study and "lower = 1.05e+11" in study
    out = _run_ok(tmp_path / "m" / "study.toml", tmp_path / "m" / "report")
    assert "updating" in out.results


def test_init_mesh_lists_sets_mixing_surface_and_line_cells(tmp_path, monkeypatch):
    import numpy as np

    import mvtk.fe
    from mvtk.fe import ImportedMesh
    from mvtk.study._init import mesh_structure_toml

    mesh = ImportedMesh(
        np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [2, 0, 0.0]]),
        {"quad4": np.array([[0, 1, 2, 3]]), "line2": np.array([[1, 4]])},
        {"plate": {"quad4": np.array([0])},
         "both": {"quad4": np.array([0]), "line2": np.array([0])}},
        {"plate": np.arange(4), "both": np.arange(5)})
    monkeypatch.setattr(mvtk.fe, "read_mesh", lambda path: mesh)
    text = mesh_structure_toml(tmp_path / "part.inp", tmp_path)
    assert 'sections = { plate = "plate" }' in text
    assert ("# sets mixing surface and line cells (split them in the mesher to use them): "
            "both (1 quad4, 1 line2)") in text


def _strip_units(src: Path, dst: Path) -> Path:
    """A copy of a CSV export whose header names carry no '[unit]' (as many DAQs write)."""
    import re

    lines = src.read_text(encoding="utf-8").splitlines()
    dst.write_text("\n".join(re.sub(r" \[[^\]]*\]", "", ln) if ln[:1].isalpha() else ln
                             for ln in lines) + "\n", encoding="utf-8")
    return dst


def test_init_and_run_with_reader_options_for_a_file_without_units(tmp_path, capsys):
    src = _strip_units(DATA / "SYNTHETIC_smart_beam_decay.csv", tmp_path / "decay.csv")
    # without units the file is listed as unreadable, naming the flag
    assert main(["init", str(tmp_path / "a"), "--measurements", str(src)]) == 0
    out = capsys.readouterr().out
    assert "skipped: not readable" in out and "has no units" in out and "--units" in out
    # with them it is a decay test, and the study carries the option to its run
    assert main(["init", str(tmp_path / "b"), "--measurements", str(src), "--units", "m",
                 "m/s^2"]) == 0
    assert "decay.csv: decay" in capsys.readouterr().out
    study = load_study(tmp_path / "b" / "study.toml")
    assert study.config["measurements"]["decay"]["read_options"] == {"units": ["m", "m/s^2"]}
    from mvtk.study import run

    s_file = tmp_path / "b" / "structure.toml"   # the documented edit: drop the mark line
    s_file.write_text("\n".join(x for x in s_file.read_text(encoding="utf-8").splitlines()
                                if "PLACEHOLDER structure" not in x), encoding="utf-8")
    res = run(study.path, tmp_path / "b" / "out", stages=["ingest"], progress=False,
              report=False)
    assert not res.failed, res.failed
    ch = res.results["ingest"]["channels"]
    assert [(c["channel"], c["units"]) for c in ch] == [("tip_disp", "m")]


def test_study_read_options_are_validated(tmp_path):
    _strip_units(DATA / "SYNTHETIC_smart_beam_decay.csv", tmp_path / "decay.csv")
    (tmp_path / "study.toml").write_text(
        f'[structure]\nfile = "{STRUCTURE.as_posix()}"\n[measurements.decay]\n'
        f'file = "decay.csv"\nchannel = "tip_disp"\nread_options = "m"\n', encoding="utf-8")
    with pytest.raises(ConfigError, match=r"measurements\.decay\.read_options: expected a "
                       r"table"):
        load_study(tmp_path / "study.toml")


def test_init_reader_options_go_to_the_files_that_take_them(tmp_path, capsys):
    # a decay CSV without units (needs --units m m/s^2) and the impact UFF, which states
    # its own units and refuses two for its three channels: each file read as it needs
    src = _strip_units(DATA / "SYNTHETIC_smart_beam_decay.csv", tmp_path / "decay.csv")
    impact = DATA / "SYNTHETIC_smart_beam_impact.uff"
    assert main(["init", str(tmp_path / "s"), "--structure", str(STRUCTURE),
                 "--measurements", str(impact), str(src), "--units", "m", "m/s^2"]) == 0
    out = capsys.readouterr().out
    assert "decay.csv: decay" in out
    assert "impact.uff: impact (read without the reader options" in out
    study = load_study(tmp_path / "s" / "study.toml")
    meas = study.config["measurements"]
    assert meas["decay"]["read_options"] == {"units": ["m", "m/s^2"]}
    assert not meas["impact"].get("read_options")
    text = (tmp_path / "s" / "study.toml").read_text()
    assert text.count("read_options =") == 1
    # a file that reads neither way is still listed with the first error
    res = init_study(tmp_path / "t", structure=STRUCTURE, measurements=[src],
                     read_options={"units": ["m"]})
    assert res.tests[0]["kind"] == "skipped" and "units" in res.tests[0]["why"]


def test_a_second_multipoint_file_is_a_multipoint_measurement(tmp_path):
    """Two FRF files of one multi-point test (the scan and a copy of it): the first is
    [modal], the second a multi-point measurement identified on its own; the same data
    give the same modes, each paired with itself (df 0, MAC 1)."""
    import shutil

    import numpy as np

    from mvtk.study import run, study_checks

    (tmp_path / "day2").mkdir()
    scan = DATA / "SYNTHETIC_smart_beam_scan.uff"
    copy = tmp_path / "day2" / scan.name
    shutil.copy(scan, copy)
    res = init_study(tmp_path / "s", structure=STRUCTURE, measurements=[scan, copy],
                     geometry=DATA / "SYNTHETIC_smart_beam_scan_geometry.csv")
    cfg = load_study(res.study).config
    mp = cfg["measurements"]["multipoint_2"]
    assert mp["kind"] == "multi-point" and mp["file"].endswith("day2/" + scan.name)
    out = run(res.study, tmp_path / "out", stages=["modal"], progress=False, report=False)
    assert not out.failed, out.failed
    mod = out.results["modal"]
    t = mod["tests"]["multipoint_2"]
    assert t["table"]["fn_hz"] == mod["table"]["fn_hz"]
    c = t["comparison"]
    n = len(mod["table"]["fn_hz"])
    assert c["paired_mode"] == list(range(1, n + 1)) and np.allclose(c["df_pct"], 0.0)
    assert np.allclose(c["mac"], 1.0, atol=1e-12)
    checks = [k for k in study_checks(out) if "multi-point test multipoint_2" in k.name]
    assert checks and all(k.passed for k in checks)
