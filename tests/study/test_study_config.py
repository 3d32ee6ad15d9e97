import shutil
from pathlib import Path

import numpy as np
import pytest
from study_text import with_absolute_paths

from mvtk.errors import ConfigError
from mvtk.study import load_study
from mvtk.study._cache import StageCache, stage_key

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"


def test_smart_beam_study_loads_and_resolves_files():
    s = load_study(STUDY)
    assert s.synthetic and "SYNTHETIC" in s.name
    assert s.structure_file.name == "smart_beam.toml" and s.structure_file.is_file()
    assert set(s.measurement_files) == {"impact", "broadband", "decay"}
    assert s.config["checks"]["se_fn_rel"] == 0.05
    assert [r["name"] for r in s.config["reduction"]["retained"]] == [
        "clamp", "actuator_x0", "actuator_x1", "sensor", "tip"]
    assert s.config["reduction"]["n_modes"] == 10
    assert s.config["updating"]["targets_hz"] == [13.26, 41.14, 78.69, 137.78]


def _variant(tmp_path, old: str, new: str) -> Path:
    """A copy of the smart-beam study with one text replacement, paths made absolute."""
    text = STUDY.read_text()
    assert old in text, old
    text = with_absolute_paths(text.replace(old, new))
    p = tmp_path / "study.toml"
    p.write_text(text)
    return p


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("[study]\n", "[studdy]\nname='x'\n[study]\n", r"unknown sections \['studdy'\]"),
        ('file = "SYNTHETIC_smart_beam_decay.csv"', 'file = "nope.csv"',
         "measurements.decay.file: 'nope.csv' not found"),
        ('model_damping = "half_power"', 'model_damping = "guess"',
         r"damping.model_damping: expected one of \['half_power', 'chowdhury'\]"),
        ("targets_hz = [13.26, 41.14, 78.69, 137.78]", "targets_hz = []",
         "updating.targets_hz: expected a list of numbers each > 0"),
        ('sensor_node = "tip"', 'sensor_node = "toe"',
         r"control.sensor_node: \['toe'\] are not retained nodes"),
        ('type = "SRF"', 'type = "PID"', r"control.controllers\[1\].type: expected one of"),
        ("se_fn_rel = 0.05", "se_fn_rel = 0.05\nsloppiness = 1.0",
         r"unknown key 'sloppiness' in \[checks\]"),
        ("se_fn_rel = 0.05", "se_fn_rel = -1.0", r"checks.se_fn_rel: expected a number > 0"),
        ("xyz = [0.180, 0.0665, 0.0]", "xyz = [0.180, 0.0665]",
         r"reduction.retained\[4\].xyz: expected a point \[x, y, z\]"),
        ("band_hz = [11.0, 15.5]", "band_hz = [15.5, 11.0]",
         "measurements.decay.band_hz: expected"),
        ("broadband_fn_hz = [78.7, 137.8, 224.5]", "broadband_fn_hz = [30.0, 139.0]",
         r"damping.broadband_fn_hz: expected modes above those of damping.fn_hz \(max 41.14"),
        ("broadband_fn_hz = [78.7, 137.8, 224.5]", "broadband_fn_hz = [78.6, -1.0]",
         "damping.broadband_fn_hz: expected a list of numbers each > 0"),
        ("[measurements.broadband]", "[measurements.broadbandx]",
         r"unknown key 'broadbandx' in \[measurements\] \(did you mean 'broadband'\?\)"),
        ('response = "tip_accel"\nrecord_s = 8.0', 'response = "tip_accel"\nrecord_s = -8.0',
         r"measurements.broadband.record_s: expected a number > 0"),
        ("chowdhury_target_mass = 0.95", "chowdhury_target_mass = 1.5",
         r"damping.chowdhury_target_mass: expected a number each > 0 and <= 1|"
         r"damping.chowdhury_target_mass: expected a number > 0 and <= 1"),
        ("plant_modes = 12", "plant_modes = 0",
         "reduction.plant_modes: expected an integer >= 1, got 0"),
        ("actuator_limit_v = 100.0", "actuator_limit_v = -100.0",
         r"control.actuator_limit_v: expected a number > 0"),
        ('patch = "pzt"', "patch = 3", "control.patch: expected a string, got 3"),
        ("n_samples = 40 ", "n_samples = 1 ",
         "uncertainty.n_samples: expected an integer >= 2, got 1"),
        ("seed = 1\n", "seed = 1.5\n", "uncertainty.seed: expected an integer >= 0, got 1.5"),
        ('distribution = "normal"', 'distribution = "weibull"',
         r"uncertainty.distribution: expected one of \['normal', 'lognormal'\], got 'weibull'"),
        ('"materials.steel.E" = 0.03', '"materials.steel.E" = 3.0',
         r"uncertainty.scatter.'materials.steel.E': expected a relative standard deviation "
         r"in \(0, 0.5\), got 3.0"),
        ("[uncertainty.scatter]", "[uncertainty.scater]",
         r"unknown key 'scater' in \[uncertainty\] \(did you mean 'scatter'\?\)"),
        ("[uncertainty.scatter]     # relative standard deviation of each input (its CoV)\n"
         "\"materials.steel.E\" = 0.03                 # typical spread of a rolled steel sheet\n"
         "\"materials.steel.rho\" = 0.01\n"
         "\"structure.layers.0.thickness\" = 0.02      # 0.5 mm +- 10 um (sheet tolerance)",
         "scatter = {}",
         "uncertainty.scatter: expected a table of dotted structure paths"),
    ],
)
def test_bad_study_files(tmp_path, old, new, match):
    with pytest.raises(ConfigError, match=match):
        load_study(_variant(tmp_path, old, new))


def test_missing_study_and_invalid_toml(tmp_path):
    with pytest.raises(ConfigError, match="not found"):
        load_study(tmp_path / "absent.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[study\nname=1")
    with pytest.raises(ConfigError, match="invalid TOML"):
        load_study(bad)
    shutil.copy(STUDY, tmp_path / "nostudy.toml")
    p = tmp_path / "nostudy.toml"
    p.write_text(p.read_text().replace("[study]\n", "[studyx]\n"))
    with pytest.raises(ConfigError, match="unknown sections"):
        load_study(p)


def test_stage_key_is_order_independent_for_dicts_and_sensitive_to_values():
    a = stage_key("s", {"gain": 0.1, "f": 13.26})
    assert a == stage_key("s", {"f": 13.26, "gain": 0.1})
    assert a != stage_key("s", {"f": 13.26, "gain": 0.2})


def test_stage_cache_hits_only_with_same_key(tmp_path):
    import numpy as np
    import xarray as xr

    calls = []

    def compute():
        calls.append(1)
        return {"x": np.float64(1.5), "v": np.arange(3)}, xr.Dataset({"y": ("t", [1.0, 2.0])})

    cache = StageCache(tmp_path)
    r1, d1 = cache.get("stage", "k1", compute)
    r2, d2 = cache.get("stage", "k1", compute)
    assert calls == [1] and r1 == r2 == {"x": 1.5, "v": [0, 1, 2]}
    assert d2["y"].values.tolist() == [1.0, 2.0]
    cache.get("stage", "k2", compute)
    assert len(calls) == 2 and cache.hits == ["stage"] and cache.misses == ["stage", "stage"]
    off = StageCache(tmp_path, enabled=False)
    off.get("stage", "k2", compute)
    assert len(calls) == 3


def test_code_hash_follows_the_source():
    from mvtk.study import _cache

    a = _cache.code_hash("study/_stages.py")
    assert a == _cache.code_hash("study/_stages.py")
    assert a != _cache.code_hash("study/_config.py")
    assert _cache.code_hash("fe") != _cache.code_hash("fe", "study/_stages.py")


def test_source_digest_is_reread_when_the_file_changes(tmp_path):
    """code_hash keeps each file's digest while its (mtime, size, inode) is unchanged."""
    import hashlib
    import os

    from mvtk.study import _cache

    f = tmp_path / "stage.py"
    f.write_text("x = 1\n")
    assert _cache._source_digest(f) == hashlib.sha256(b"x = 1\n").digest()
    st = f.stat()
    f.write_text("x = 2\n")                      # same size: the mtime tells
    os.utime(f, ns=(st.st_atime_ns, st.st_mtime_ns + 10**9))
    assert _cache._source_digest(f) == hashlib.sha256(b"x = 2\n").digest()
    assert _cache._source_digest(tmp_path / "missing.py") is None
    assert _cache._source_digest(tmp_path) is None


def test_broadband_modes_need_the_broadband_test(tmp_path):
    p = _variant(tmp_path, "[measurements.broadband]", "[measurements.broadband]")
    text = p.read_text()
    start = text.index("[measurements.broadband]")
    end = text.index("[measurements.decay]")
    p.write_text(text[:start] + text[end:])
    with pytest.raises(ConfigError, match=r"damping.broadband_fn_hz needs a "
                                          r"\[measurements.broadband\] test"):
        load_study(p)


def test_patch_actuator_is_the_papers_eq7_for_the_smart_beam_stack():
    """Moment per volt of the study's patch vs the paper's eq. 7, evaluated here by hand."""
    from mvtk.fe import load_structure
    from mvtk.study._stages import patch_actuator

    desc = load_structure(ROOT / "data" / "structures" / "smart_beam.toml")
    act = patch_actuator(desc)
    # eq. 7: beam (steel 0.5 mm), adhesive (epoxy 36 um), piezo (PIC 151 0.25 mm)
    Ep, Ea, Eb = 66.667e9, 3.546e9, 210e9
    tp, ta, tb, d31, b = 0.25e-3, 0.036e-3, 0.5e-3, -210e-12, 0.030
    eq7 = ((Ep * Ea * (tp * ta + ta**2) + Ep * Eb * (tb**2 + tp * tb + 2 * ta * tb))
           / (Ep * tp + Ea * ta + Eb * tb) * d31 * b / 2)
    assert act["moment_per_volt"] == pytest.approx(eq7, rel=1e-9)
    assert act["paper_eq7_moment_per_volt"] == pytest.approx(eq7, rel=1e-9)
    assert act["width_m"] == pytest.approx(b) and act["piezo_thickness_m"] == tp
    assert act["moment_per_volt"] == pytest.approx(-1.4888e-4, rel=1e-4)


@pytest.mark.parametrize(("change", "match"), [
    ("name", r"control.patch: no patch 'nope' in the structure; expected one of \['pzt'\]"),
    ("two", "control.patch: the structure has 2 patches; name the actuator patch"),
    ("no_piezo", r"patch 'pzt': expected one piezo layer \(with d31\) in the stack, found 0"),
])
def test_patch_actuator_bad_input(change, match):
    import copy

    from mvtk.fe import load_structure
    from mvtk.study._stages import patch_actuator

    desc = load_structure(ROOT / "data" / "structures" / "smart_beam.toml")
    name = None
    if change == "name":
        name = "nope"
    elif change == "two":
        desc["patches"].append(copy.deepcopy(desc["patches"][0]) | {"name": "pzt2"})
    else:
        del desc["materials"]["pic151"]["d31"]
    with pytest.raises(ConfigError, match=match):
        patch_actuator(desc, name)


def _plain_plate() -> dict:
    """The smart-beam steel plate without the patch, rigidly clamped, coarse mesh."""
    from mvtk.fe import load_structure

    desc = load_structure(ROOT / "data" / "structures" / "smart_beam.toml")
    desc.pop("patches", None)
    desc["mesh"]["element_size"] = 0.02
    return desc


def test_uncertainty_sensitivities_of_a_homogeneous_plate_are_the_scaling_laws():
    """f of a thin homogeneous plate scales as t sqrt(E / rho): S = 1/2, -1/2, about 1."""
    from mvtk.study._stages import _first_order_cov

    scatter = {"materials.steel.E": 0.03, "materials.steel.rho": 0.01,
               "structure.layers.0.thickness": 0.02}
    sens, cov = _first_order_cov(_plain_plate(), scatter, 3)
    assert sens[0] == pytest.approx(0.5, abs=1e-6)     # K linear in E
    assert sens[1] == pytest.approx(-0.5, abs=1e-6)    # M linear in rho
    assert sens[2] == pytest.approx(1.0, abs=5e-3)     # Kirchhoff limit (t/L = 0.003)
    assert cov == pytest.approx(np.hypot(np.hypot(0.015, 0.005), 0.02), rel=5e-3)


@pytest.mark.parametrize(("path", "match"), [
    ("materials.steel.Young", "no entry 'materials.steel.Young' in the structure"),
    ("materials.steel", r"uncertainty.scatter.'materials.steel': the structure value at "
                        "this path is not a number"),
])
def test_uncertainty_stage_rejects_bad_paths(tmp_path, path, match):
    from mvtk.study._stages import uncertainty

    p = _variant(tmp_path, '"materials.steel.E" = 0.03', f'"{path}" = 0.03')
    with pytest.raises(ConfigError, match=match):
        uncertainty(load_study(p), _plain_plate())
