"""Structure TOML -> build_model, its validation, the smart beam and `mvtk modes`."""

import json
from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ConfigError
from mvtk.fe import build_model, get_by_path, load_structure, modal_analysis, set_by_path

DATA = Path(__file__).resolve().parents[2] / "data" / "structures"


def _strip() -> dict:
    return {
        "materials": {"steel": {"E": 210e9, "nu": 0.3, "rho": 7900.0}},
        "structure": {"type": "plate", "length": 0.2, "width": 0.02,
                      "layers": [{"material": "steel", "thickness": 1e-3}]},
        "mesh": {"nx": 20, "ny": 2},
        "boundary": {"clamp": "x0"},
        "points": [{"name": "tip", "x": 0.2, "y": 0.01}],
    }


def test_smart_beam_nominal_modes():
    model = build_model(DATA / "smart_beam.toml")
    res = modal_analysis(model, 4)
    assert 13.0 < res.fn_hz[0] < 15.0 and res.mode_type[0] == "bending"
    assert 40.0 < res.fn_hz[1] < 45.0 and res.mode_type[1] == "torsion"
    for name in ("x0", "x1", "tip", "sensor", "patch:pzt", "patch:pzt:x0", "patch:pzt:x1",
                 "patch:pzt:y0", "patch:pzt:y1"):
        assert len(model.node_set(name)) >= 1
    assert model.meta["structure"]["structure"]["length"] == 0.18
    # the patch stiffens and adds mass; the section there is unsymmetric (B != 0)
    lam = model.meta["laminates"][1]
    assert abs(lam.B[0, 0]) > 0 and lam.I1 > 0


def test_benchmark_plate_file_matches_leissa():
    model = build_model(DATA / "plate.toml")
    f1 = modal_analysis(model, 1).fn_hz[0]
    E, h, rho, a, nu = 70e9, 3e-3, 2700.0, 0.3, 0.3
    D = E * h**3 / (12 * (1 - nu**2))
    lam1 = 2 * np.pi * f1 * a**2 * np.sqrt(rho * h / D)
    assert lam1 == pytest.approx(3.492, rel=0.01)  # Leissa (1969) Table 4.50


def test_build_is_deterministic_and_perturbable():
    s = _strip()
    m1, m2 = build_model(s), build_model(s)
    assert (m1.K != m2.K).nnz == 0 and (m1.M != m2.M).nnz == 0
    s2 = set_by_path(s, "materials.steel.E", 1.1 * 210e9)
    assert s["materials"]["steel"]["E"] == 210e9  # the original is untouched
    f1 = modal_analysis(m1, 1).fn_hz[0]
    f2 = modal_analysis(build_model(s2), 1).fn_hz[0]
    assert f2 / f1 == pytest.approx(np.sqrt(1.1), rel=1e-6)
    s3 = set_by_path(s, "structure.layers.0.thickness", 2e-3)
    assert get_by_path(s3, "structure.layers.0.thickness") == 2e-3
    f3 = modal_analysis(build_model(s3), 1).fn_hz[0]
    assert f3 / f1 == pytest.approx(2.0, rel=2e-3)
    s4 = dict(s, boundary={"clamp": "x0", "clamp_stiffness": 10.0})
    assert modal_analysis(build_model(s4), 1).fn_hz[0] < f1
    with pytest.raises(ConfigError, match="no entry 'materials.alu.E'"):
        set_by_path(s, "materials.alu.E", 1.0)
    with pytest.raises(ConfigError, match="no entry 'boundary.clamp_stiffness'"):
        set_by_path(s, "boundary.clamp_stiffness", 10.0)
    s5 = set_by_path(s, "boundary.clamp_stiffness", 10.0, create=True)
    assert modal_analysis(build_model(s5), 1).fn_hz[0] == pytest.approx(
        modal_analysis(build_model(s4), 1).fn_hz[0], rel=1e-12)
    with pytest.raises(ConfigError, match=r"boundary: unknown key 'clamp_stifness'; "
                       r"accepted keys: clamp, clamp_stiffness"):
        build_model(set_by_path(s, "boundary.clamp_stifness", 10.0, create=True))


def test_orthotropic_and_piezo_materials_and_element_size():
    s = _strip()
    s["materials"]["cf"] = {"E1": 140e9, "E2": 10e9, "G12": 5e9, "G13": 5e9, "G23": 3.5e9,
                            "nu12": 0.3, "rho": 1600.0}
    s["materials"]["pzt"] = {"E": 66.667e9, "nu": 0.34, "rho": 7800.0, "d31": -210e-12}
    s["structure"]["layers"] = [{"material": "cf", "thickness": 0.5e-3, "angle": 0.0},
                                {"material": "cf", "thickness": 0.5e-3, "angle": 90.0}]
    s["patches"] = [{"name": "a", "x0": 0.0, "x1": 0.05, "y0": 0.0, "y1": 0.02,
                     "layers": [{"material": "pzt", "thickness": 0.25e-3}]}]
    s["mesh"] = {"element_size": 0.01}
    model = build_model(s)
    assert model.meta["laminates"][0].plies[1].angle_deg == 90.0
    assert model.meta["laminates"][1].plies[-1].material.d31 == -210e-12
    assert len(model.meta["x_lines"]) == 21


@pytest.mark.parametrize("path, value, message", [
    ("structure.length", -1.0, r"structure\.length: expected a positive number"),
    ("structure.layers.0.material", "alu", r"structure\.layers\[0\]\.material: 'alu' is not"),
    ("structure.layers.0.thickness", "1mm", r"structure\.layers\[0\]\.thickness: expected a"),
    ("materials.steel.nu", 0.7, r"materials\.steel: .*Poisson ratio"),
    ("materials.steel.E", 0, r"materials\.steel\.E: expected a positive number"),
    ("structure.type", "shell", r"structure\.type: expected 'plate'"),
    ("boundary.clamp", "left", r"boundary\.clamp: expected one of x0"),
    ("mesh.nx", 2.5, r"mesh\.nx: expected a positive integer"),
])
def test_config_errors_name_the_key(path, value, message):
    with pytest.raises(ConfigError, match=message):
        build_model(set_by_path(_strip(), path, value))


def test_config_errors_structure():
    s = _strip()
    s["extra"] = 1
    with pytest.raises(ConfigError, match=r"unknown top-level keys \['extra'\]"):
        build_model(s)
    s = _strip()
    del s["mesh"]
    with pytest.raises(ConfigError, match="mesh: missing"):
        build_model(s)
    s = _strip()
    s["boundary"]["edges"] = {"y0": "glued"}
    with pytest.raises(ConfigError, match="unknown support type 'glued' on edge 'y0'"):
        build_model(s)
    s = _strip()
    s["patches"] = [{"name": "p", "x0": 0.1, "x1": 0.3, "y0": 0.0, "y1": 0.02,
                     "layers": [{"material": "steel", "thickness": 1e-3}]}]
    with pytest.raises(ConfigError, match="patch 'p' extent"):
        build_model(s)


def test_load_structure_errors(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_structure(tmp_path / "none.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[structure\nlength = 1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        build_model(bad)


def test_cli_modes_json_and_table(capsys):
    from mvtk.cli import main

    assert main(["modes", str(DATA / "smart_beam.toml"), "-n", "3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert len(out["fn_hz"]) == 3 and out["n_dof"] > 1000
    assert 13.0 < out["fn_hz"][0] < 15.0
    assert out["mode_type"][:2] == ["bending", "torsion"]
    assert main(["modes", str(DATA / "plate.toml"), "-n", "2"]) == 0
    text = capsys.readouterr().out
    assert "fn_hz" in text and "bending" in text and "DOF" in text


def test_cli_modes_error_exit_code(tmp_path, capsys):
    from mvtk.cli import main

    assert main(["modes", str(tmp_path / "missing.toml")]) == 2
    assert "not found" in capsys.readouterr().err


def test_beam_structure_type_delegates_to_cantilever_beam():
    model = build_model(DATA / "smart_beam_beam.toml")
    assert "beam2" in model.elements
    res = modal_analysis(model, 2)
    assert res.mode_type == ("bending", "torsion")
    # beam and plate models of the same nominal strip agree on the first bending mode
    # within the plate-vs-beam modulus difference (1/(1 - nu^2) = 1.099 in stiffness)
    f_plate = modal_analysis(build_model(DATA / "smart_beam.toml"), 1).fn_hz[0]
    assert 0.95 < f_plate / res.fn_hz[0] < 1.06
    s = load_structure(DATA / "smart_beam_beam.toml")
    s["boundary"]["clamp"] = "y0"
    with pytest.raises(ConfigError, match="boundary.clamp: expected x0, x1 or free"):
        build_model(s)


def test_documented_schema_example_builds():
    import tomllib

    import mvtk.fe._structure as st

    doc = st.__doc__
    block = doc.split("A complete example::")[1].split("A ``type")[0]
    example = tomllib.loads("\n".join(line[4:] for line in block.splitlines()))
    model = build_model(example)
    res = modal_analysis(model, 2)
    assert np.all(res.fn_hz > 0) and not res.rigid.any()
    assert len(model.node_set("patch:pzt:x1")) > 1
    # clamp_stiffness and clamp_translational_stiffness free ry and uz on the clamp
    clamp = model.node_set("x0")
    model.dof_index(clamp[0], "ry")
    model.dof_index(clamp[0], "uz")


def test_mode_labels_without_mirror_symmetric_mesh():
    s = load_structure(DATA / "smart_beam.toml")
    s = set_by_path(set_by_path(s, "patches.0.y0", 0.01), "patches.0.y1", 0.04)
    res = modal_analysis(build_model(s), 2)
    assert res.mode_type == ("bending", "torsion")


def _beam() -> dict:
    s = _strip()
    s["structure"]["type"] = "beam"
    s["mesh"] = {"n_elements": 40}
    s["points"] = [{"name": "tip", "x": 0.2}]
    return s


@pytest.mark.parametrize("path, value, message", [
    ("boundary.edges", {"x1": "free"}, r"boundary.edges: not applicable here \(a beam has "
     r"no edges; use boundary.supports"),
    ("boundary.clamp_stifness", 1.0, r"boundary: unknown key 'clamp_stifness'; accepted keys:"
     r" clamp, clamp_stiffness, clamp_translational_stiffness, springs, supports"),
    ("mesh.ny", 4, r"mesh.ny: not applicable here \(a beam has no elements across"),
    ("mesh.element_size", 0.01, r"mesh: give one of n_elements, nx or element_size, not "
     r"\['n_elements', 'element_size'\]"),
    ("boundary.springs", [{"node_set": "tip", "dof": "uz", "k": 1.0, "per_length": True}],
     r"boundary.springs\[0\].per_length: not applicable here"),
    ("boundary.supports", {"x1": "glued"}, r"boundary.supports.x1: unknown support type "
     r"'glued'; expected one of antisymmetry_x"),
    ("points.0.z", 1.0, r"points\[0\]: unknown key 'z'; accepted keys: name, x, y"),
])
def test_beam_refuses_unknown_and_inapplicable_keys(path, value, message):
    """Issue 16: beam models silently ignored boundary.edges/springs and mesh keys."""
    with pytest.raises(ConfigError, match=message):
        build_model(set_by_path(_beam(), path, value, create=True))


def test_plate_refuses_nx_ny_together_with_element_size():
    s = set_by_path(_strip(), "mesh.element_size", 0.01, create=True)
    with pytest.raises(ConfigError, match=r"mesh: give either nx and ny or element_size, not "
                       r"both \(one of them would be ignored\)"):
        build_model(s)


def test_simply_supported_beam_and_springs_now_expressible():
    s = _beam()
    s["boundary"] = {"clamp": "free",
                     "supports": {"x0": ["ux", "uy", "uz", "rx"], "x1": ["uy", "uz"]}}
    res = modal_analysis(build_model(s), 3)
    E, rho, L, b, h = 210e9, 7900.0, 0.2, 0.02, 1e-3
    ref = np.pi / (2 * L**2) * np.sqrt(E * b * h**3 / 12 / (rho * b * h))
    assert res.fn_hz[0] == pytest.approx(ref, rel=2e-3)
    assert res.mode_type[0] == "bending"
    # element_size now sets the beam mesh; springs act
    s2 = set_by_path(s, "mesh", {"element_size": 0.005})
    assert build_model(s2).meta["structure"]["mesh"] == {"element_size": 0.005}
    assert len(build_model(s2).nodes) == 41
    s3 = set_by_path(s, "boundary.springs", [{"node_set": "mid", "dof": "uz", "k": 1e3}],
                     create=True)
    s3["points"].append({"name": "mid", "x": 0.1})
    assert modal_analysis(build_model(s3), 1).fn_hz[0] > res.fn_hz[0] * 1.01


def test_plate_supports_on_node_sets():
    s = _strip()
    s["boundary"] = {"supports": {"x0": "simply_supported_hard", "x1": "pinned"}}
    res = modal_analysis(build_model(s), 1)
    E, rho, L, h = 210e9, 7900.0, 0.2, 1e-3
    ref = np.pi / (2 * L**2) * np.sqrt(E * h**2 / 12 / rho)  # narrow strip: a beam
    assert res.fn_hz[0] == pytest.approx(ref, rel=0.01)


def test_free_free_beam_reports_six_rigid_modes_sorted_at_zero():
    """Issue 16: -n 6 on a free-free beam gave unsorted fn and rigid modes 'in-plane'."""
    s = load_structure(DATA / "smart_beam_beam.toml")
    s["boundary"]["clamp"] = "free"
    model = build_model(s)
    res = modal_analysis(model, 6)
    assert res.mode_type == ("rigid",) * 6 and np.all(res.fn_hz == 0.0)
    res9 = modal_analysis(model, 9)
    assert res9.mode_type[:6] == ("rigid",) * 6
    assert np.all(np.diff(res9.fn_hz) >= 0) and res9.fn_hz[6] > 10.0


def test_mode_labels_are_deterministic_across_runs_and_mode_counts():
    """Issue 12: a torsion mode was labelled 'torsion' or 'in-plane' at random."""
    model = build_model(DATA / "smart_beam_beam.toml")
    runs = [modal_analysis(model, n).mode_type[:6] for n in (6, 8, 6, 10)]
    assert all(r == runs[0] for r in runs)
    assert runs[0][:2] == ("bending", "torsion")
