"""The curved-panel study (data/curved_panel/study.toml): piezo patches on an imported
mesh through the super element into the controllers, from the study file."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from mvtk.errors import ConfigError
from mvtk.study import load_study, run

STUDY = Path(__file__).resolve().parents[2] / "data" / "curved_panel" / "study.toml"


@pytest.mark.slow
def test_curved_panel_study_damps_the_patch_mode(tmp_path):
    res = run(STUDY, tmp_path, use_cache=False, progress=False, parallel=False)
    act = res.results["reduction"]["actuator"]
    assert act["piezo"] and act["name"] == "act" and act["sensors"] == ["sen"]
    # both patches are plant inputs (control.actuators)
    assert act["actuators"] == ["act", "sen"]
    plant = res.arrays["reduction"]
    assert list(plant["input"].values) == ["act", "sen"]
    # the plant's DC gain from the SE equals the full model's (electrodes' static shapes)
    assert act["tip_per_volt_plant_m"] == pytest.approx(act["tip_per_volt_full_m"], rel=1e-6)
    rows = {r["controller"]: r for r in res.results["control"]["metrics"]}
    open_, ppf, srf = rows["open loop"], rows["PPF"], rows["SRF"]
    assert open_["fn_mode1_hz"] == pytest.approx(126.5, abs=0.3)  # the released mode 2
    assert ppf["stable"] and srf["stable"]
    assert ppf["zeta_mode1"] > 2 * open_["zeta_mode1"]
    assert srf["zeta_mode1"] > open_["zeta_mode1"]
    assert ppf["voltage_within_limit"] and ppf["settling_time_s"] < open_["settling_time_s"]
    # PPF from the collocated charge sensor: stable for 0 <= G < 1 (Fanson & Caughey
    # 1990), so the loop gain G = 0.5 may double before instability (measured 2.000)
    assert ppf["critical_gain_factor"] == pytest.approx(1 / 0.5, rel=0.02)
    assert srf["critical_gain_factor"] > 1 and ppf["gain_margin_db"] > 0
    # the LQR on both patches (full state): stable, damps the released mode, within
    # the actuator limit; no single-loop margins for a two-input law
    lqr = rows["LQR (2 patches)"]
    assert lqr["stable"] and lqr["zeta_mode1"] > 2 * open_["zeta_mode1"]
    assert lqr["voltage_within_limit"] and lqr["settling_time_s"] < open_["settling_time_s"]
    assert pd.isna(lqr["gain_margin_db"])
    html = (tmp_path / "index.html").read_text(encoding="utf-8")
    assert "gain margin [dB]" in html and "LQR (2 patches)" in html
    em = pd.read_csv(tmp_path / "tables" / "piezo_emcc.csv")
    assert set(em["electrode"]) == {"act", "sen"} and (em["f_oc_hz"] >= em["f_sc_hz"]).all()


def test_piezo_control_keys_are_checked(tmp_path):
    text = STUDY.read_text().replace('sensors = ["sen"]\n', "")
    text = text.replace('file = "../structures', f'file = "{STUDY.parent.parent}/structures')
    bad = tmp_path / "study.toml"
    bad.write_text(text)
    with pytest.raises(ConfigError, match="control.sensors"):
        load_study(bad)


def test_init_template_of_a_mesh_offers_piezo_patches(tmp_path):
    """The structure TOML `mvtk init` writes around a mesh carries a commented patch
    template; uncommented, it builds electrodes on the mesh."""
    import shutil

    from mvtk.fe import build_model, piezo_coupling
    from mvtk.study._init import mesh_structure_toml

    src = STUDY.parent.parent / "structures" / "curved_panel" / "curved_panel.msh"
    shutil.copy(src, tmp_path / "panel.msh")
    text = mesh_structure_toml(tmp_path / "panel.msh", tmp_path)
    lines = []
    for line in text.splitlines():
        if line.startswith("# ") and any(k in line for k in (
                "[materials.pic151]", "E = 66.667e9", "nu = 0.34", "rho = 7800", "d31 =",
                "eps33 =", "[[patches]]", 'name = "pzt"', "element_set =", "layers = [{",
                'side = "top"')):
            line = line[2:]
        lines.append(line)
    (tmp_path / "structure.toml").write_text("\n".join(lines))
    cp = piezo_coupling(build_model(tmp_path / "structure.toml"))
    assert cp.names == ("pzt",) and cp.C[0] > 0


class _Study:
    def __init__(self, control):
        self._c = control

    def section(self, name):
        return self._c if name == "control" else None


@pytest.mark.parametrize("ctrl, key", [
    ({"name": "P", "type": "PPF", "f_hz": 10.0, "zeta_f": 0.1, "gain": 0.5,
      "sensor": "Q:nope"}, "control.controllers['P'].sensor"),
    ({"name": "P", "type": "PPF", "f_hz": 10.0, "zeta_f": 0.1, "gain": 0.5,
      "actuator": "b"}, "control.controllers['P'].actuator"),
    ({"name": "L", "type": "LQR", "R": 1.0, "actuators": ["a", "b"]},
     "control.controllers['L'].actuators"),
])
def test_controller_inputs_and_outputs_are_checked_against_the_plant(ctrl, key):
    """A controller naming an actuator or sensor the plant does not have: one-line
    error naming the key and the plant's names."""
    import numpy as np

    from mvtk.control import StructuralPlant
    from mvtk.study._stages import _plant_dataset, control

    K, M = np.diag([4e3, 9e4]), np.eye(2)
    plant = StructuralPlant(M, 0.01 * K / 30, K, np.array([[1.0], [0.5]]),
                            np.array([[1.0, 0.2], [1.0, 1.0]]), np.zeros((2, 2)),
                            inputs=["a"], outputs=["Q:sen", "tip"], coords=["m1", "m2"],
                            input_units=["V"], output_units=["C", "m"])
    ds = _plant_dataset(plant, {"moment_per_volt": float("nan"), "output_units": "C|m"})
    cfg = {"initial_tip_displacement_m": 1e-4, "t_end_s": 1.5, "fs_out": 500.0,
           "settle_band": 0.05, "controllers": [ctrl]}
    with pytest.raises(ConfigError) as err:
        control(_Study(cfg), ds, 10.0)
    assert key in str(err.value) and "\n" not in str(err.value)
