"""Acceptance chain on a generated plate with a piezo patch: init -> run, no edit.

The own structure: a cantilever aluminium plate (240 x 120 x 1.5 mm, clamped at x = 0)
with a PIC 151 patch (50 x 40 mm, 0.25 mm on 50 um epoxy) bonded at its root, given as
``[[patches]]`` of the generated plate (the patch's plies stiffen and load the root;
short-circuited electrodes). The specimen differs from the model: E of the aluminium is
67 GPa instead of 70 GPa (-4.3 %); the patch is the same, so the frequencies do not
scale by one factor and the update is a genuine nonlinear fit. The specimen's 12-point
roving-hammer test (the accelerometer at the free corner) and a decay of its mode 1 are
simulated from its own FE modes at the mesh nodes (tests/roving_hammer.py). The truth is
known: the specimen's E and its mode numbers.
"""

from __future__ import annotations

import copy
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
import roving_hammer as RH  # noqa: E402

E_TRUE = 67e9
ZETA = 0.01
PLATE = {
    "name": "cantilever plate with a PZT patch",
    "materials": {
        "al": {"E": 70e9, "nu": 0.33, "rho": 2700},
        "epoxy": {"E": 3.5e9, "nu": 0.35, "rho": 1180},
        "pic151": {"E": 66.667e9, "nu": 0.34, "rho": 7800, "d31": -210e-12,
                   "eps33": 2.125e-8},
    },
    "structure": {"type": "plate", "length": 0.24, "width": 0.12,
                  "layers": [{"material": "al", "thickness": 1.5e-3}]},
    "patches": [{"name": "pzt", "x0": 0.01, "x1": 0.06, "y0": 0.04, "y1": 0.08,
                 "layers": [{"material": "epoxy", "thickness": 50e-6},
                            {"material": "pic151", "thickness": 0.25e-3}]}],
    "mesh": {"element_size": 0.01},
    "boundary": {"clamp": "x0"},
}


def _write(path: Path, desc: dict) -> Path:
    import tomli_w

    path.write_text(tomli_w.dumps(desc), encoding="utf-8")
    return path


def _specimen_tests(folder: Path, sensor_xy=(0.24, 0.0), seed=60):
    """12 hammer points (4 x 3 grid, hit 1 on the free corner (0.24, 0), where the
    accelerometer is unless ``sensor_xy`` says otherwise) and a decay of mode 1; returns
    the files, the specimen's frequencies, mode types and shapes (uz at the hammer
    points)."""
    from mvtk.fe import DOF_NAMES, build_model, modal_analysis

    truth = copy.deepcopy(PLATE)
    truth["materials"]["al"]["E"] = E_TRUE
    model = build_model(truth)
    modes = modal_analysis(model, 10)

    def node(x, y):
        return int(np.argmin(np.linalg.norm(model.nodes - [x, y, 0.0], axis=1)))

    points = [node(0.24, 0.0)] + [node(x, y) for x in (0.06, 0.12, 0.18, 0.24)
                                  for y in (0.0, 0.06, 0.12) if (x, y) != (0.24, 0.0)]
    files = RH.write_fe_test(folder, model, modes, points, node(*sensor_xy), zeta=ZETA,
                             fs=1024.0, record_s=8.0, f_max_hz=450.0, seed=seed)
    decay = RH.write_decay(folder / "decay.csv", modes.fn_hz[0], zeta=ZETA, fs=1024.0,
                           record_s=6.0, seed=seed + 1)
    uz = model.expand(modes.shapes)[:, DOF_NAMES.index("uz"), :]
    return (files + [decay], np.asarray(modes.fn_hz), np.asarray(modes.mode_type),
            uz[points])


@pytest.mark.slow
def test_pzt_plate_roving_hammer_from_init_to_run(tmp_path, capsys):
    """`mvtk init` then `mvtk run`, no edit: the targets paired with the specimen's
    modes (the torsion mode between them included), E of the aluminium within 0.5 %,
    exit status 0 with every check passed."""
    from mvtk.cli import main
    from mvtk.fe import build_model, modal_analysis
    from mvtk.study import run, study_checks
    from mvtk.updating import FrequencyTarget, pair_modes

    files, f_true, kinds, shapes_true = _specimen_tests(tmp_path)
    structure = _write(tmp_path / "plate.toml", PLATE)
    f_nom = modal_analysis(build_model(PLATE), 8).fn_hz
    assert main(["init", str(tmp_path / "study"), "--structure", str(structure),
                 "--measurements", *map(str, files),
                 "--geometry", str(tmp_path / "geometry.csv")]) == 0
    said = capsys.readouterr().out
    assert said.count("roving set") == 11 and "decay.csv: decay" in said
    study = tmp_path / "study" / "study.toml"
    cfg = tomllib.loads(study.read_text(encoding="utf-8"))
    assert len(cfg["modal"]["sets"]) == 12 and "decay" in cfg["measurements"]
    assert cfg["updating"]["parameters"][0]["path"] == "materials.al.E"
    targets = [t["fn_hz"] for t in cfg["updating"]["targets"]]
    truth = [int(np.argmin(np.abs(f_true - f))) + 1 for f in targets]
    assert len(targets) >= 3 and truth != list(range(1, len(truth) + 1))  # a mode skipped
    assert all(abs(f_true[m - 1] / f - 1) < 2e-3 for f, m in zip(targets, truth))
    by_order = pair_modes([FrequencyTarget(f) for f in targets], np.asarray(f_nom)).modes
    assert [int(m) + 1 for m in by_order] != truth        # order pairing would be wrong
    assert len(cfg["damping"]["fn_hz"]) >= 2

    out = tmp_path / "report"
    assert main(["run", str(study), "--out", str(out), "--quiet"]) == 0, \
        capsys.readouterr().err
    res = run(study, out, progress=False)              # the cached results
    up = res.results["updating"]
    assert list(up["modes"]) == truth
    assert up["values"][0] == pytest.approx(E_TRUE, rel=5e-3)
    assert up["identifiable_study"] is True
    mo = res.results["modal"]["table"]
    shp = res.arrays["modal"]["shapes"]
    for k, f in enumerate(mo["fn_hz"]):
        m = int(np.argmin(np.abs(f_true - f)))
        assert mo["reliable"][k] and f == pytest.approx(f_true[m], rel=1e-3)
        a, b = shp.values[k], shapes_true[:, m]
        assert abs(a @ b) ** 2 / ((a @ a) * (b @ b)) > 0.99, (k, f)
    assert {str(kinds[m - 1]) for m in truth} == {"bending", "torsion"}
    d = res.results["damping"]
    assert np.allclose(d["half_power"]["zeta"], ZETA, rtol=0.1)
    assert d["decays"]["decay"]["envelope"]["zeta"][0] == pytest.approx(ZETA, rel=0.05)
    checks = {c.name: c for c in study_checks(res)}
    assert all(c.passed for c in checks.values())
    assert all(f"updated FE f{i}" in checks for i in range(1, len(targets) + 1))


@pytest.mark.slow
def test_two_roving_tests_of_one_specimen_in_one_study(tmp_path):
    """Two roving-hammer tests of the specimen (two folders; the accelerometer on one
    free corner, then on the other): init makes the first [modal] and the second a
    multi-point measurement; the modal stage identifies each, the second's modes are
    the specimen's (frequency 0.1 %, MAC > 0.99 with its FE shapes) and are paired with
    the same modes of the first; the report shows both."""
    from mvtk.study import run, study_checks
    from mvtk.study._init import init_study

    (tmp_path / "day1").mkdir()
    (tmp_path / "day2").mkdir()
    a, f_true, _, shapes_true = _specimen_tests(tmp_path / "day1")
    b, *_ = _specimen_tests(tmp_path / "day2", sensor_xy=(0.24, 0.12), seed=70)
    structure = _write(tmp_path / "plate.toml", PLATE)
    res = init_study(tmp_path / "study", structure=structure, measurements=a[:-1] + b[:-1],
                     geometry=tmp_path / "day1" / "geometry.csv")
    cfg = tomllib.loads(res.study.read_text(encoding="utf-8"))
    assert [Path(p).parent.name for p in cfg["modal"]["sets"]] == ["day1"] * 12
    mp = cfg["measurements"]["roving_2"]
    assert mp["kind"] == "multi-point" and len(mp["sets"]) == 12
    assert all(Path(p).parent.name == "day2" for p in mp["sets"])
    assert set(cfg["measurements"]) == {"impact", "roving_2"}
    out = run(res.study, tmp_path / "report", stages=["modal"], progress=False)
    assert not out.failed, out.failed
    mod = out.results["modal"]
    t2 = mod["tests"]["roving_2"]
    assert t2["n_responses"] == 12 and "reciprocity" in t2["note"]
    tab, cmp_ = t2["table"], t2["comparison"]
    assert len(tab["fn_hz"]) >= 4 and all(tab["reliable"])
    truth = [int(np.argmin(np.abs(f_true - f))) for f in tab["fn_hz"]]
    assert tab["fn_hz"] == pytest.approx(f_true[truth], rel=1e-3)
    # the same modes in the first test, by frequency and by shape
    first = np.asarray(mod["table"]["fn_hz"])
    assert [int(np.argmin(np.abs(first - f_true[m]))) + 1 for m in truth] == \
        cmp_["paired_mode"]
    assert min(cmp_["mac"]) > 0.99 and set(cmp_["n_common_dofs"]) == {12}
    import mvtk.modal

    own = np.diag(mvtk.modal.mac(shapes_true[:, truth].T, np.asarray(
        [out.arrays["modal"]["shapes"].values[i - 1] for i in cmp_["paired_mode"]])))
    assert own.min() > 0.99       # the first test's paired shapes are the specimen's
    checks = [c for c in study_checks(out) if "multi-point test roving_2" in c.name]
    assert len(checks) == 3 * len(tab["fn_hz"]) and all(c.passed for c in checks)
    from mvtk.study._report import build_report  # the report of the modal stage alone

    html = build_report(out, {}).read_text(encoding="utf-8")
    assert "Multi-point test roving_2" in html
    for name in ("modal_modes_roving_2", "modal_compare_roving_2"):
        assert (tmp_path / "report" / "tables" / f"{name}.csv").is_file()
