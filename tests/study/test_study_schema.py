"""The one study schema: unknown keys refused everywhere, types, encodings, introspection."""

from __future__ import annotations

import codecs
import json
import re
from pathlib import Path

import pytest
from study_text import with_absolute_paths

from mvtk.errors import ConfigError
from mvtk.study import CONTROLLER_SCHEMAS, SCHEMA, load_study

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"


def _absolute_copy(tmp_path: Path, text: str | None = None, encoding: str = "utf-8",
                   bom: bytes = b"") -> Path:
    """The smart-beam study with absolute paths, written in ``encoding``."""
    text = STUDY.read_text(encoding="utf-8") if text is None else text
    text = with_absolute_paths(text)
    p = tmp_path / "study.toml"
    p.write_bytes(bom + text.encode(encoding))
    return p


def _insert_after(text: str, header: str, line: str) -> str:
    assert header in text, header
    return text.replace(header, header + "\n" + line, 1)


# every table header of the smart-beam study -> an inserted unknown key
_TABLES = [
    ("[study]", "study"), ("[structure]", "structure"),
    ("[measurements.impact]", "measurements.impact"),
    ("[measurements.decay]", "measurements.decay"),
    ("[damping]", "damping"), ("[fe]", "fe"), ("[updating]", "updating"),
    ("[[updating.parameters]]", "updating.parameters[0]"),
    ("[uncertainty]", "uncertainty"), ("[reduction]", "reduction"),
    ("[[reduction.retained]]", "reduction.retained[0]"), ("[control]", "control"),
    ("[[control.controllers]]", "control.controllers[0]"), ("[checks]", "checks"),
    ("[references]", "references"),
]


@pytest.mark.parametrize(("header", "where"), _TABLES, ids=[w for _, w in _TABLES])
def test_unknown_key_refused_in_every_table(tmp_path, header, where):
    text = _insert_after(STUDY.read_text(encoding="utf-8"), header, "bogus_key = 1")
    p = _absolute_copy(tmp_path, text)
    with pytest.raises(ConfigError) as info:
        load_study(p)
    msg = str(info.value)
    assert str(p) in msg and "'bogus_key'" in msg and f"[{where}]" in msg
    assert "accepted keys:" in msg


def test_fe_n_mode_typo_names_key_section_file_and_suggestion(tmp_path):
    """Issue 16: `[fe] n_mode = 12` was silently ignored (6 modes computed)."""
    text = STUDY.read_text(encoding="utf-8").replace("n_modes = 6", "n_mode = 12")
    p = _absolute_copy(tmp_path, text)
    with pytest.raises(ConfigError, match=r"unknown key 'n_mode' in \[fe\] \(did you mean "
                                          r"'n_modes'\?\); accepted keys: \['n_modes'\]"):
        load_study(p)


def test_controller_key_typo_refused_before_any_stage(tmp_path):
    """Issue 16: a controller key typo surfaced as `KeyError: 'zeta_f'` after the FE work."""
    text = STUDY.read_text(encoding="utf-8").replace("zeta_f = 0.3", "zeta_ff = 0.3")
    with pytest.raises(ConfigError, match=r"unknown key 'zeta_ff' in "
                                          r"\[control.controllers\[0\]\] \(did you mean "
                                          r"'zeta_f'\?\)"):
        load_study(_absolute_copy(tmp_path, text))
    text = STUDY.read_text(encoding="utf-8").replace("zeta_f = 0.3\n", "")
    with pytest.raises(ConfigError, match=r"\[control.controllers\[0\]\]: missing key "
                                          "'zeta_f'"):
        load_study(_absolute_copy(tmp_path, text))


@pytest.mark.parametrize(("old", "new", "match"), [
    ("t_end_s = 6.0", "t_end_s = 0.5", r"control.t_end_s: expected a number > 1"),
    ("fs_out = 500.0", "fs_out = -5.0", r"control.fs_out: expected a number > 0"),
    ("targets_hz = [13.26, 41.14, 78.69, 137.78]", "targets_hz = [41.14, 13.26]",
     r"updating.targets_hz: expected frequencies in ascending \(mode\) order"),
    ("fn_hz = [13.26, 41.14]", "fn_hz = [41.14, 13.26]",
     r"damping.fn_hz: expected frequencies in ascending"),
    ("n_modes = 6", 'n_modes = "six"', r"fe.n_modes: expected an integer >= 1, got 'six'"),
    ("synthetic = true", 'synthetic = "yes"', r"study.synthetic: expected true or false"),
    ("boundary_layer_rel = 0.2", "boundary_layer_rel = 0.2\nboundary_layer = 1.0",
     r"give exactly one of \['boundary_layer', 'boundary_layer_rel'\]"),
    ('type = "SRF"', 'type = "SFR"', r"expected one of \[.*\], got 'SFR' \(did you mean "
                                     r"'SRF'\?\)"),
    ('name = "tip"\nxyz', 'name = "sensor"\nxyz',
     r"reduction.retained: names must be unique"),
    ('name = "SRF"', 'name = "PPF"', "control.controllers: names must be unique"),
    ("se_fn_rel = 0.05", "se_fn_rel = nan", r"checks.se_fn_rel: expected a number > 0"),
])
def test_types_ranges_and_cross_rules(tmp_path, old, new, match):
    text = STUDY.read_text(encoding="utf-8")
    assert old in text
    with pytest.raises(ConfigError, match=match):
        load_study(_absolute_copy(tmp_path, text.replace(old, new, 1)))


@pytest.mark.parametrize(("encoding", "bom"), [
    ("utf-8", codecs.BOM_UTF8), ("utf-16-le", codecs.BOM_UTF16_LE),
    ("utf-16-be", codecs.BOM_UTF16_BE)])
def test_study_read_with_a_byte_order_mark(tmp_path, encoding, bom):
    """Issue 16: a UTF-16 study file gave a raw traceback."""
    s = load_study(_absolute_copy(tmp_path, encoding=encoding, bom=bom))
    assert s.config["updating"]["targets_hz"] == [13.26, 41.14, 78.69, 137.78]


def test_latin1_study_refused_naming_byte_offset_and_line(tmp_path):
    text = STUDY.read_text(encoding="utf-8").replace("# Validation study", "# Étude", 1)
    p = _absolute_copy(tmp_path, text, encoding="latin-1")
    with pytest.raises(ConfigError, match=r"not UTF-8 text: byte 0xc9 at offset 2 \(line 1, "
                                          r"column 3\); save the file as UTF-8"):
        load_study(p)


def test_latin1_structure_file_refused_naming_the_file(tmp_path):
    beam = (ROOT / "data" / "structures" / "smart_beam.toml").read_text(encoding="utf-8")
    (tmp_path / "beam.toml").write_bytes(("# Acier é\n" + beam).encode("latin-1"))
    text = STUDY.read_text(encoding="utf-8").replace('"../structures/smart_beam.toml"',
                                                     f'"{(tmp_path / "beam.toml").as_posix()}"')
    p = _absolute_copy(tmp_path, text)
    with pytest.raises(ConfigError, match=re.escape(str(tmp_path / "beam.toml"))
                       + r": not UTF-8 text: byte 0xe9 at offset 8 \(line 1, column 9\)"):
        load_study(p)


def test_inline_structure_study(tmp_path):
    beam = (ROOT / "data" / "structures" / "smart_beam.toml").read_text(encoding="utf-8")
    p = tmp_path / "inline.toml"
    p.write_text(beam + '\n[fe]\nn_modes = 3\n', encoding="utf-8")
    s = load_study(p)
    assert s.structure_file is None and s.structure["structure"]["layers"]
    assert s.config["fe"] == {"n_modes": 3} and s.name == "inline"


def test_schema_is_plain_introspectable_data():
    d = {name: t.to_dict() for name, t in SCHEMA.items()}
    json.dumps(d)  # plain data
    assert d["fe"]["keys"]["n_modes"] == {
        "type": "int", "doc": "Number of modes computed and tabulated.", "units": "",
        "required": False, "default": 6, "minimum": 1}
    for name, table in {**SCHEMA, **CONTROLLER_SCHEMAS}.items():
        assert table.doc, name
        for key, k in table.keys.items():
            assert k.doc.endswith("."), (name, key)
            if key.endswith("_hz") and k.type in ("number", "numbers"):
                assert k.units == "Hz", (name, key)
    assert d["updating"]["one_of"] == [["targets_hz", "targets"]]
    assert set(CONTROLLER_SCHEMAS) == {"PPF", "SRF", "LyapunovBangBang", "VelocityFeedback",
                                       "LQR"}
