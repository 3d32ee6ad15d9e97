import shutil
from pathlib import Path

import pytest

from mvtk.errors import ConfigError
from mvtk.study import load_study
from mvtk.study._cache import StageCache, stage_key

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"


def test_smart_beam_study_loads_and_resolves_files():
    s = load_study(STUDY)
    assert s.synthetic and "SYNTHETIC" in s.name
    assert s.structure_file.name == "smart_beam.toml" and s.structure_file.is_file()
    assert set(s.measurement_files) == {"impact", "decay"}
    assert s.config["checks"]["se_fn_rel"] == 0.05
    assert [r["name"] for r in s.config["reduction"]["retained"]] == [
        "clamp", "actuator_x0", "actuator_x1", "sensor", "tip"]
    assert s.config["reduction"]["n_modes"] == 10
    assert s.config["updating"]["targets_hz"] == [13.26, 41.14]


def _variant(tmp_path, old: str, new: str) -> Path:
    """A copy of the smart-beam study with one text replacement, paths made absolute."""
    text = STUDY.read_text()
    assert old in text, old
    text = text.replace(old, new)
    base = STUDY.parent
    text = text.replace('"../structures/smart_beam.toml"',
                        f'"{(base.parent / "structures" / "smart_beam.toml").as_posix()}"')
    for name in ("SYNTHETIC_smart_beam_impact.csv", "SYNTHETIC_smart_beam_decay.csv"):
        text = text.replace(f'"{name}"', f'"{(base / name).as_posix()}"')
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
         "damping.model_damping: expected 'half_power' or 'chowdhury'"),
        ("targets_hz = [13.26, 41.14]", "targets_hz = []",
         "updating.targets_hz: expected a list of frequencies > 0"),
        ('sensor_node = "tip"', 'sensor_node = "toe"',
         r"control.sensor_node: \['toe'\] are not retained nodes"),
        ('type = "SRF"', 'type = "PID"', r"control.controllers\[1\].type: expected one of"),
        ("se_fn_rel = 0.05", "se_fn_rel = 0.05\nsloppiness = 1.0",
         "checks.sloppiness: unknown tolerance"),
        ("se_fn_rel = 0.05", "se_fn_rel = -1.0", r"checks.se_fn_rel: expected a number > 0"),
        ("xyz = [0.180, 0.0665, 0.0]", "xyz = [0.180, 0.0665]",
         r"reduction.retained\[4\].xyz: expected \[x, y, z\]"),
        ("band_hz = [11.0, 15.5]", "band_hz = [15.5, 11.0]",
         "measurements.decay.band_hz: expected"),
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
