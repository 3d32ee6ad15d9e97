"""``mvtk reduce`` on small study/structure TOMLs, and the [reduction] config."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from mvtk.errors import ConfigError

pytest.importorskip("mvtk.fe._structure")
from mvtk.cli import main  # noqa: E402
from mvtk.cli.reduce import load_reduction_input  # noqa: E402
from mvtk.fe import build_model  # noqa: E402
from mvtk.reduction._config import super_element_from_config  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SMART_BEAM = ROOT / "data" / "structures" / "smart_beam.toml"

REDUCTION = """
[reduction]
n_modes = 10
n_compare = 4

[[reduction.retained]]
name = "clamp"
xyz = [0.0, 0.0665, 0.0]

[[reduction.retained]]
name = "actuator_x0"
xyz = [0.005, 0.0665, 0.0]

[[reduction.retained]]
name = "actuator_x1"
xyz = [0.055, 0.0665, 0.0]

[[reduction.retained]]
name = "sensor"
xyz = [0.120, 0.0665, 0.0]

[[reduction.retained]]
name = "tip"
node_set = "tip"
"""


def coarse_structure_text() -> str:
    text = SMART_BEAM.read_text()
    assert "element_size = 0.005" in text
    return text.replace("element_size = 0.005", "element_size = 0.015")


@pytest.fixture(scope="module")
def study_file(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("study")
    (d / "beam.toml").write_text(coarse_structure_text())
    study = d / "study.toml"
    study.write_text('[study]\nname = "t"\n\n[structure]\nfile = "beam.toml"\n' + REDUCTION)
    return study


def test_reduce_json_paper_shape(study_file, capsys):
    assert main(["reduce", str(study_file), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    jsonschema = pytest.importorskip("jsonschema")
    schema = json.loads((ROOT / "schemas" / "reduce.schema.json").read_text())
    jsonschema.validate(out, schema, cls=jsonschema.Draft202012Validator)
    assert out["schema_version"] == "mvtk.reduce/1" and not out["updated_model"]
    sizes = {row["quantity"]: row for row in out["sizes"]}
    # 5 retained nodes (the clamp node has no free DOF), 10 modes: the paper's 40 DOF
    assert sizes["Number of nodes"]["se"] == 5
    assert sizes["DOF (6 per node)"]["se"] == 40
    assert sizes["DOF (free)"]["se"] == 34
    assert sizes["Number of elements"]["se"] == 1
    assert [r["name"] for r in out["retained"]] == ["clamp", "actuator_x0", "actuator_x1",
                                                     "sensor", "tip"]
    assert out["retained"][0]["free_dofs"] == 0
    modes = out["modes"]
    assert len(modes) == 4
    assert all(r["error_pct"] >= -1e-7 for r in modes)  # Rayleigh-Ritz upper bound
    assert all(r["mac"] > 0.99 for r in modes)
    assert out["static_max_rel_error"] < 1e-7


def test_reduce_text_and_inline_structure(tmp_path, capsys):
    path = tmp_path / "inline.toml"
    path.write_text(coarse_structure_text() + REDUCTION)
    assert main(["reduce", str(path), "-n", "2"]) == 0
    out = capsys.readouterr().out
    assert "Number of nodes" in out and "error_pct" in out and "static check" in out
    assert "24 boundary DOF + 10 fixed-interface modes" in out


def test_config_mass_fraction_and_plain_names():
    model = build_model(tomllib.loads(coarse_structure_text()))
    se, pts = super_element_from_config(
        model, {"retained": ["tip", [0.12, 0.0665, 0.0]], "mass_fraction": 0.9}
    )
    assert se.meta["mass_fraction"] == 0.9 and se.n_modes >= 1
    assert pts[0].name == "tip" and pts[1].name.startswith("n")
    assert np.all(np.diff(se.interior_fn_hz) >= 0)


@pytest.mark.parametrize(
    ("cfg", "message"),
    [
        ({"n_modes": 3}, "missing key 'retained'"),
        ({"retained": []}, "expected a non-empty list"),
        ({"retained": ["tip"], "bogus": 1}, r"unknown keys \['bogus'\]"),
        ({"retained": ["nope"]}, r"reduction.retained\[0\]: no node set 'nope'"),
        ({"retained": [{"name": "a"}]}, "exactly one of 'xyz', 'node_set', 'node'"),
        ({"retained": [[0.0, 1.0]]}, r"expected a point \[x, y, z\] in m"),
        ({"retained": [{"name": "a", "node": 10**6}]}, "node 1000000 does not exist"),
        ({"retained": [{"name": "a", "node": "3"}]}, "expected an integer node index"),
        ({"retained": ["tip"], "n_modes": "ten"}, "reduction.n_modes: expected a number"),
        ({"retained": ["tip"], "n_modes": 10**6}, r"reduction: n_modes must be in 0\.\."),
    ],
)
def test_config_errors(cfg, message):
    model = build_model(tomllib.loads(coarse_structure_text()))
    with pytest.raises(ConfigError, match=message):
        super_element_from_config(model, cfg)


def test_cli_file_errors(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text("[reduction\n")
    (tmp_path / "beam.toml").write_text(coarse_structure_text())
    no_red = tmp_path / "nored.toml"
    no_red.write_text('[structure]\nfile = "beam.toml"\n')
    missing_struct = tmp_path / "ms.toml"
    missing_struct.write_text('[structure]\nfile = "x.toml"\n' + REDUCTION)
    no_struct = tmp_path / "ns.toml"
    no_struct.write_text(REDUCTION)
    cases = [
        (tmp_path / "missing.toml", "not found"),
        (bad, "invalid TOML"),
        (no_red, r"no \[reduction\] section"),
        (missing_struct, "structure.file: 'x.toml' not found"),
        (no_struct, r"missing \[structure\] section"),
        (tmp_path, "is a directory, expected a TOML file"),
    ]
    for path, message in cases:
        with pytest.raises(ConfigError, match=message):
            load_reduction_input(path)
        # through the command: MvtkError -> exit code 2 and one line on stderr
        assert main(["reduce", str(path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("mvtk reduce: error:") and err.count("\n") == 1, err
