"""A first study from the user's own files: init -> run with no hand edit, paired right.

The own structure: a cantilever aluminium plate (300 x 200 x 2 mm, clamped at x = 0,
not the smart beam). The specimen differs from it (E = 74.2 GPa instead of 70 GPa); its
hammer test is simulated from the specimen's own FE modes at the tip centre (driving
point), where the torsion modes have a nodal line: the sensor misses FE modes 2 and 4,
as a real accelerometer on a nodal line does. Pairing the measured peaks with the FE
modes by order would compare 123 Hz with the 63 Hz torsion mode; the truth is known
(the specimen's E and its mode numbers), so the pairing, the updated E and the verdicts
are checked against it.
"""

from __future__ import annotations

import copy
import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
E_TRUE = 74.2e9
PLATE = {"name": "aluminium plate", "materials": {"al": {"E": 70e9, "nu": 0.33, "rho": 2700}},
         "structure": {"type": "plate", "length": 0.3, "width": 0.2,
                       "layers": [{"material": "al", "thickness": 2e-3}]},
         "mesh": {"element_size": 0.025}, "boundary": {"clamp": "x0"}}


def _write_structure(path: Path, desc: dict) -> None:
    import tomli_w

    path.write_text(tomli_w.dumps(desc), encoding="utf-8")


ZETA = 0.01   # every mode of the specimen


def _specimen_hammer_test(path: Path, sensor=(0.3, 0.1), seed=7) -> tuple[np.ndarray, tuple]:
    """Three hits at the tip centre of the specimen, the accelerometer at ``sensor``
    (x, y in m); accelerance, zeta 1 %, 0.1 % noise."""
    from mvtk.fe import DOF_NAMES, build_model, modal_analysis
    from mvtk.testing import impact_test

    truth = copy.deepcopy(PLATE)
    truth["materials"]["al"]["E"] = E_TRUE
    model = build_model(truth)
    modes = modal_analysis(model, 8)
    uz = model.expand(modes.shapes)[:, DOF_NAMES.index("uz"), :]

    def at(x, y):
        return uz[int(np.argmin(np.linalg.norm(model.nodes - [x, y, 0.0], axis=1)))]

    phi = at(0.3, 0.1) * at(*sensor)
    seen = (modes.fn_hz < 400) & (np.abs(phi) > 1e-9 * np.abs(phi).max())
    th = impact_test(modes.fn_hz[seen], ZETA, 2048.0, 8.0, 3, np.random.default_rng(seed),
                     modal_constants=phi[seen])
    x = th.values.copy()
    x[1] += 1e-3 * x[1].std() * np.random.default_rng(seed + 1).standard_normal(x.shape[1])
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# hammer test at the tip centre of the plate\n"
                 "# quantity: force, acceleration\n"
                 "time [s],hammer [N],accel [m/s^2]\n")
        np.savetxt(fh, np.column_stack([th["time"].values, x[0], x[1]]), fmt="%.10g",
                   delimiter=",")
    return modes.fn_hz[seen], tuple(int(k) + 1 for k in np.flatnonzero(seen))


def _specimen_decay(path: Path, fn_hz: float, amplitude: float, seed: int) -> None:
    """A free decay of mode 1 (zeta 1 %), 8 s at 2048 Hz, 0.5 % noise."""
    from mvtk.testing import sdof_free_decay

    d = sdof_free_decay(fn_hz, ZETA, 2048.0, 8.0, amplitude=amplitude,
                        quantity="acceleration", units="m/s^2")
    x = d.values[0] + 5e-3 * amplitude * np.random.default_rng(seed).standard_normal(
        d.sizes["time"])
    with open(path, "w", encoding="utf-8") as fh:
        fh.write("# free decay after a release, mode 1\n# quantity: acceleration\n"
                 "time [s],tip [m/s^2]\n")
        np.savetxt(fh, np.column_stack([d["time"].values, x]), fmt="%.10g", delimiter=",")


def test_pair_by_frequency_skips_a_missed_mode():
    from mvtk.updating import FrequencyTarget, pair_by_frequency, pair_modes

    model = [19.0, 63.2, 119.5, 216.5, 299.3]
    assert list(pair_by_frequency([19.5, 123.1, 308.1], model)) == [0, 2, 4]
    # by order the second target would take the 63 Hz mode
    t = [FrequencyTarget(f) for f in (19.5, 123.1, 308.1)]
    assert list(pair_modes(t, np.array(model)).modes) == [0, 1, 2]
    assert list(pair_modes(t, np.array(model), rest="frequency").modes) == [0, 2, 4]
    # mode types are respected; a target beyond max_rel stays unpaired
    kinds = ["bending", "torsion", "bending", "torsion", "bending"]
    got = pair_by_frequency([70.0, 200.0], model, target_kinds=["bending", None],
                            model_kinds=kinds)
    assert list(got) == [2, 3]          # 70 Hz bending: 119.5, not the 63.2 Hz torsion
    assert list(pair_by_frequency([1000.0], model, max_rel=0.1)) == [-1]


def test_init_name_is_written_through_the_toml_writer(tmp_path):
    from mvtk.study._init import init_study

    name = 'a"b = 1\nsynthetic = true'
    res = init_study(tmp_path / "s", name=name)
    cfg = tomllib.loads(res.study.read_text(encoding="utf-8"))
    assert cfg["study"] == {"name": name}
    from mvtk.cli import main

    assert main(["init", str(tmp_path / "t"), "--name", 'a"b = 1']) == 0
    cfg = tomllib.loads((tmp_path / "t" / "study.toml").read_text(encoding="utf-8"))
    assert cfg["study"] == {"name": 'a"b = 1'}


def test_run_refuses_the_placeholder_structure(tmp_path):
    from mvtk.study import run
    from mvtk.study._init import PLACEHOLDER_MARK, init_study

    res = init_study(tmp_path / "s")
    with pytest.raises(ConfigError, match="placeholder structure"):
        run(res.study, tmp_path / "out")
    s = res.structure.read_text(encoding="utf-8")
    res.structure.write_text("\n".join(x for x in s.splitlines() if PLACEHOLDER_MARK not in x),
                             encoding="utf-8")
    from mvtk.study._init import placeholder_structure

    assert not placeholder_structure(res.structure)


def test_e_and_thickness_from_frequencies_is_not_identifiable():
    """f ~ t sqrt(E / rho) for a plate: only E^0.5 t is determined by frequencies."""
    import warnings

    from mvtk.fe import build_model, modal_analysis
    from mvtk.study._stages import identifiability
    from mvtk.updating import FrequencyTarget, Parameter, update

    plate = copy.deepcopy(PLATE)
    plate["mesh"] = {"element_size": 0.05}
    truth = copy.deepcopy(plate)
    truth["materials"]["al"]["E"] = E_TRUE
    f = modal_analysis(build_model(truth), 5).fn_hz
    targets = [FrequencyTarget(float(x)) for x in f]
    e = Parameter("materials.al.E", lower=35e9, upper=140e9)
    t = Parameter("structure.layers.0.thickness", lower=1e-3, upper=4e-3)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        both = update(plate, [e, t], targets)
        one = update(plate, [e], targets)
    v = identifiability(both, [e.path, t.path], 100.0)
    assert v["identifiable_study"] is False
    assert "condition number" in v["not_identifiable_why"]
    # the combination the frequencies determine: E^0.5 * t (exponents normalised)
    assert v["identifiable_combination"] == ("materials.al.E^0.50 * "
                                             "structure.layers.0.thickness^1.00")
    w = identifiability(one, [e.path], 100.0)
    assert w["identifiable_study"] is True and w["not_identifiable_why"] == ""
    assert one.values[0] == pytest.approx(E_TRUE, rel=1e-4)


def test_first_study_from_init_to_run_without_edits(tmp_path, capsys):
    """init -> run: targets paired with the right FE modes, E within 0.5 % of the truth,
    two hammer records and two decays in one study, and the study's damping table equal
    to `mvtk damping` on the same file."""
    from mvtk.cli import main
    from mvtk.study import run
    from mvtk.study._init import init_study

    structure = tmp_path / "plate.toml"
    _write_structure(structure, PLATE)
    test = tmp_path / "hammer.csv"
    f_true, seen_modes = _specimen_hammer_test(test)
    assert seen_modes == (1, 3, 5, 6)           # the sensor misses torsion modes 2 and 4
    # a second record of the same specimen, the sensor at a corner (sees the torsion
    # modes), and two free decays of mode 1
    _specimen_hammer_test(tmp_path / "hammer_corner.csv", sensor=(0.3, 0.0), seed=11)
    _specimen_decay(tmp_path / "decay_a.csv", f_true[0], 5.0, 21)
    _specimen_decay(tmp_path / "decay_b.csv", f_true[0], 2.0, 22)
    files = [test, tmp_path / "hammer_corner.csv", tmp_path / "decay_a.csv",
             tmp_path / "decay_b.csv"]
    res = init_study(tmp_path / "study", structure=structure, measurements=files)
    assert [t["kind"] for t in res.tests] == ["impact", "impact", "decay", "decay"]
    cfg = tomllib.loads(res.study.read_text(encoding="utf-8"))
    assert set(cfg["measurements"]) == {"impact", "impact_2", "decay", "decay_2"}
    targets = cfg["updating"]["targets"]
    # the reliable peaks (modes 5 and 6, 58 Hz apart, may overlap) with their true mode
    truth = [seen_modes[int(np.argmin(np.abs(f_true - t["fn_hz"])))] for t in targets]
    assert len(targets) >= 3 and truth[:3] == [1, 3, 5]
    assert [t["mode"] for t in targets] == truth
    assert "targets_hz" not in cfg["updating"]
    assert "record_s" not in cfg["measurements"]["impact"]
    assert len(cfg["damping"]["fn_hz"]) == len(targets)

    out = run(res.study, tmp_path / "report", progress=False, parallel=False)
    assert not out.failed, out.failed
    up = out.results["updating"]
    assert list(up["modes"]) == truth
    assert up["values"][0] == pytest.approx(E_TRUE, rel=5e-3)
    assert up["identifiable_study"] is True
    # Table 2's nominal column: the nominal FE frequency of each target's paired mode
    import pandas as pd

    from mvtk.fe import build_model, modal_analysis

    f_nom = modal_analysis(build_model(PLATE), 8).fn_hz
    t2 = pd.read_csv(tmp_path / "report" / "tables" / "table2_frequencies.csv")
    assert list(t2["FE nominal"]) == pytest.approx([f_nom[m - 1] for m in truth], rel=1e-6)
    d = out.results["damping"]
    hp = d["half_power"]
    assert set(hp["test"]) == {"impact", "impact_2"}
    assert np.allclose(hp["zeta"], ZETA, rtol=0.1)
    assert set(d["decays"]) == {"decay", "decay_2"}
    for dec in d["decays"].values():
        assert dec["envelope"]["zeta"][0] == pytest.approx(ZETA, rel=0.05)
    from mvtk.study._report import study_checks

    checks = {c.name: c for c in study_checks(out)}
    assert all(c.passed for c in checks.values()), [c.name for c in checks.values()
                                                    if not c.passed]
    assert checks["updated parameters identifiable from the targets"].passed
    n = len(targets)
    assert all(f"updated FE f{i}" in checks for i in range(1, n + 1))
    assert all(f"identified f{i} (half-power peak)" in checks for i in range(1, n + 1))
    repeats = [k for k in checks if k.startswith("zeta at")]
    assert any("test impact_2 vs test impact" in k for k in repeats)
    assert sum("decay" in k for k in repeats) == 2

    # one estimator: `mvtk damping` with the settings the study states gives its table
    for name, file in (("impact", test), ("impact_2", tmp_path / "hammer_corner.csv")):
        opts = d["half_power_settings"][name]["command_options"].split()
        capsys.readouterr()
        assert main(["damping", str(file), *opts, "--json"]) in (0, 1)
        rows = json.loads(capsys.readouterr().out)
        mine = [i for i, t in enumerate(hp["test"]) if t == name]
        for key in ("fn_hz", "zeta", "f1_hz", "f2_hz"):
            assert [r[key] for r in rows] == pytest.approx([hp[key][i] for i in mine],
                                                           rel=1e-9, abs=0)
    # and the defaults are the same: without options the command finds the same modes
    capsys.readouterr()
    main(["damping", str(test), "--json"])
    rows = [r for r in json.loads(capsys.readouterr().out) if r["reliable"]]
    first = [i for i, t in enumerate(hp["test"]) if t == "impact"]
    assert [r["zeta"] for r in rows] == pytest.approx([hp["zeta"][i] for i in first],
                                                      rel=1e-9, abs=0)


def test_init_hints_at_a_coarse_mesh(tmp_path):
    """A 3 x 2 element plate: the refined mesh moves the paired modes by more than the
    target tolerance, and init says so with the refined frequencies (checked by an
    independent solve of the 0.05 m mesh); the 0.025 m mesh of the chain above needs
    no hint for mode 1."""
    from mvtk.fe import build_model, modal_analysis
    from mvtk.study._init import init_study

    test = tmp_path / "hammer.csv"
    _specimen_hammer_test(test)
    coarse = copy.deepcopy(PLATE)
    coarse["mesh"] = {"element_size": 0.1}
    _write_structure(tmp_path / "coarse.toml", coarse)
    res = init_study(tmp_path / "s", structure=tmp_path / "coarse.toml", measurements=[test])
    assert res.mesh_hint and res.mesh_hint[0].startswith("MESH:")
    assert "MESH:" in res.study.read_text(encoding="utf-8")
    fine = copy.deepcopy(coarse)
    fine["mesh"] = {"element_size": 0.05}
    f_fine = modal_analysis(build_model(fine), 8).fn_hz
    for r in res.pairing:
        assert r["fe_fn_refined_hz"] == pytest.approx(f_fine[r["fe_mode"] - 1], rel=1e-9)
    assert any(abs(r["refined_change_pct"]) > 0.5 for r in res.pairing)


def _fake_run(updating: dict, hp: dict):
    from types import SimpleNamespace

    from mvtk.study._config import CHECK_KEYS

    study = SimpleNamespace(config={"checks": dict(CHECK_KEYS), "updating": updating})
    return SimpleNamespace(study=study, results={"damping": {
        "half_power": hp, "fn_guess_hz": [100.0, 300.0]}}, arrays={})


def test_identification_checks_do_not_depend_on_the_target_form():
    """targets_hz and [[updating.targets]] give the same checks; a NaN damping fails the
    verdict; modes are checked against the target of the same mode, not by position."""
    from mvtk.study._report import study_checks

    hp = {"fn_hz": [100.2, 299.0], "zeta": [0.01, float("nan")], "reliable": [True, False],
          "reason": ["", "half-power points not found"], "quality": ["ok", "failed"],
          "test": ["impact", "impact"]}
    # a target list that lacks the 100 Hz mode: 299 Hz is checked against 300 Hz
    forms = ({"targets_hz": [300.0]}, {"targets": [{"fn_hz": 300.0, "mode": 3}]})
    names = []
    for up in forms:
        checks = study_checks(_fake_run(up, hp))
        names.append(sorted((c.name, c.passed) for c in checks))
        by = {c.name: c for c in checks}
        assert by["identified f2 (half-power peak)"].reference == 300.0
        assert "identified f1 (half-power peak)" not in by
        bad = [c for c in checks if c.name.startswith("damping of mode 2")]
        assert len(bad) == 1 and not bad[0].passed and "NaN" in bad[0].name
    assert names[0] == names[1]


def _roving_hammer_sets(folder: Path) -> tuple[list[Path], np.ndarray, np.ndarray]:
    """A roving-hammer test of the specimen: 12 hammer points (4 x 3 grid), the
    accelerometer fixed at the corner (0.3, 0) (node 2); one hit per file, zeta 1 %.
    Node 1 is the tip centre, on the nodal line of the torsion modes. Returns the files,
    the specimen's frequencies below 400 Hz and its mode types."""
    from mvtk.fe import DOF_NAMES, build_model, modal_analysis
    from mvtk.testing import impact_test

    truth = copy.deepcopy(PLATE)
    truth["materials"]["al"]["E"] = E_TRUE
    model = build_model(truth)
    modes = modal_analysis(model, 8)
    keep = modes.fn_hz < 400
    uz = model.expand(modes.shapes)[:, DOF_NAMES.index("uz"), :]

    def at(x, y):
        return uz[int(np.argmin(np.linalg.norm(model.nodes - [x, y, 0.0], axis=1)))][keep]

    points = [(0.3, 0.1), (0.3, 0.0)] + [(x, y) for x in (0.075, 0.15, 0.225, 0.3)
                                         for y in (0.0, 0.1, 0.2)
                                         if (x, y) not in ((0.3, 0.1), (0.3, 0.0))]
    (folder / "geometry.csv").write_text("node,x,y,z\n" + "".join(
        f"{k + 1},{x},{y},0\n" for k, (x, y) in enumerate(points)), encoding="utf-8")
    sensor = at(0.3, 0.0)
    files = []
    for k, (x, y) in enumerate(points):
        c = at(x, y) * sensor
        th = impact_test(modes.fn_hz[keep], ZETA, 2048.0, 6.0, 1, np.random.default_rng(k),
                         modal_constants=np.where(np.abs(c) > 1e-9 * np.abs(c).max(), c, 0))
        v = th.values.copy()
        noise = np.random.default_rng(100 + k).standard_normal(v.shape)
        # noise on both channels: a noiseless sampled half-sine has an exact zero at the
        # Nyquist line, where mvtk.modal.frf_matrix refuses the H1 ratio
        v += 1e-3 * v.std(axis=1, keepdims=True) * noise
        p = folder / f"hit_{k + 1:02d}.csv"
        with open(p, "w", encoding="utf-8") as fh:
            fh.write(f"# roving hammer at node {k + 1}, accelerometer at node 2\n"
                     f"# node: {k + 1}, 2\n# direction: +z, +z\n"
                     "# quantity: force, acceleration\ntime [s],hammer [N],accel [m/s^2]\n")
            np.savetxt(fh, np.column_stack([th["time"].values, v[0], v[1]]), fmt="%.10g",
                       delimiter=",")
        files.append(p)
    return files, modes.fn_hz[keep], np.asarray(modes.mode_type)[keep]


@pytest.mark.slow
def test_roving_hammer_and_decay_from_init_to_run(tmp_path):
    """The acceptance chain: own plate, a specimen that differs (E), a simulated
    roving-hammer test and a decay; init then run with no edit: the targets (from the
    hammer point on the torsion nodal line) paired with the right FE modes by MAC,
    E within 0.5 % of the truth, every check passes."""
    from mvtk.study import run
    from mvtk.study._init import init_study

    structure = tmp_path / "plate.toml"
    _write_structure(structure, PLATE)
    sets, f_true, kinds = _roving_hammer_sets(tmp_path)
    _specimen_decay(tmp_path / "decay.csv", f_true[0], 5.0, 31)
    res = init_study(tmp_path / "study", structure=structure,
                     measurements=[*sets, tmp_path / "decay.csv"],
                     geometry=tmp_path / "geometry.csv")
    cfg = tomllib.loads(res.study.read_text(encoding="utf-8"))
    assert len(cfg["modal"]["sets"]) == 12 and "decay" in cfg["measurements"]
    lo, hi = cfg["modal"]["fmin_hz"], cfg["modal"]["fmax_hz"]
    assert lo < f_true[0] and hi > max(t["fn_hz"] for t in cfg["updating"]["targets"])
    out = run(res.study, tmp_path / "report", progress=False, parallel=False)
    assert not out.failed, out.failed
    up = out.results["updating"]
    want = [int(np.argmin(np.abs(f_true - f))) + 1 for f in up["targets_hz"]]
    assert all(kinds[m - 1] == "bending" for m in want)   # the torsion modes are missed
    assert list(up["modes"]) == want
    assert up["values"][0] == pytest.approx(E_TRUE, rel=5e-3)
    from mvtk.study._report import study_checks

    failed = [c.name for c in study_checks(out) if not c.passed]
    assert not failed, failed
