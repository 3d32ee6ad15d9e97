"""Family "bad study TOMLs": generated from the schema and the smart-beam study.

- an unknown key in every table of the study (sections, sub-tables, array items);
- a value of the wrong type for every key the study sets;
- bad encodings and damaged files.

Every case must end in one ConfigError naming the file and the dotted key (or the byte),
never another exception.
"""

from __future__ import annotations

import copy
import tomllib
from pathlib import Path

import pytest
import tomli_w

from mvtk.errors import ConfigError
from mvtk.study import CONTROLLER_SCHEMAS, SCHEMA, load_study

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "data" / "smart_beam" / "study.toml"


def _base() -> dict:
    d = tomllib.loads(STUDY.read_text(encoding="utf-8"))
    d["structure"]["file"] = str(ROOT / "data" / "structures" / "smart_beam.toml")
    for m in d["measurements"].values():
        m["file"] = str(STUDY.parent / m["file"])
    for key in ("file", "geometry"):
        if key in d.get("modal", {}):
            d["modal"][key] = str(STUDY.parent / d["modal"][key])
    d["references"] = {k: v for k, v in d["references"].items()
                       if not (isinstance(v, list) and any(x != x for x in v))}  # NaN
    return d


def _tables(d: dict, path: tuple = ()):
    """Every table of the parsed study: (path, table) with list items as ints."""
    for k, v in d.items():
        if isinstance(v, dict):
            yield (*path, k), v
            if k not in ("scatter",) and (*path, k) != ("truth",):
                yield from _tables(v, (*path, k))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            for i, item in enumerate(v):
                yield (*path, k, i), item


def _where(path: tuple) -> str:
    out = ""
    for p in path:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


def _get(d, path):
    for p in path:
        d = d[p]
    return d


def _key_schema(path: tuple, key: str, d: dict):
    """The schema Key of ``key`` in the table at ``path`` (None for free maps)."""
    section = SCHEMA[path[0]]
    if len(path) == 1:
        return section.keys.get(key)
    if path[0] == "control" and path[1] == "controllers":
        return CONTROLLER_SCHEMAS[_get(d, path)["type"]].keys.get(key)
    sub = section.keys[path[1]].table
    return None if sub is None else sub.keys.get(key)


_BASE = _base()
_TABLE_PATHS = [p for p, _ in _tables(_BASE) if p[0] in SCHEMA and p[-1] != "scatter"
                and p[0] != "truth"]
_LEAVES = [(p, k) for p in _TABLE_PATHS for k, v in _get(_BASE, p).items()
           if not isinstance(v, dict) and _key_schema(p, k, _BASE) is not None
           and not (isinstance(v, list) and v and isinstance(v[0], dict))]
_WRONG = {"str": 3, "path": 3, "bool": "yes", "int": 2.5, "number": "1.0",
          "numbers": "1, 2", "strings": "a", "xyz": [0.0, 0.0], "tables": 1}


def _write(tmp_path: Path, d: dict) -> Path:
    p = tmp_path / "study.toml"
    p.write_text(tomli_w.dumps(d), encoding="utf-8")
    return p


def test_the_base_study_loads(tmp_path):
    load_study(_write(tmp_path, _BASE))
    assert len(_TABLE_PATHS) >= 20 and len(_LEAVES) >= 60


@pytest.mark.parametrize("path", _TABLE_PATHS, ids=[_where(p) for p in _TABLE_PATHS])
def test_unknown_key_in_every_table(tmp_path, path):
    d = copy.deepcopy(_BASE)
    _get(d, path)["unknown_key_x"] = 1
    p = _write(tmp_path, d)
    with pytest.raises(ConfigError) as info:
        load_study(p)
    msg = str(info.value)
    assert msg.startswith(str(p)) and f"unknown key 'unknown_key_x' in [{_where(path)}]" in msg


@pytest.mark.parametrize(("path", "key"), _LEAVES,
                         ids=[f"{_where(p)}.{k}" for p, k in _LEAVES])
def test_wrong_type_for_every_key(tmp_path, path, key):
    d = copy.deepcopy(_BASE)
    k = _key_schema(path, key, d)
    _get(d, path)[key] = _WRONG[k.type]
    p = _write(tmp_path, d)
    with pytest.raises(ConfigError) as info:
        load_study(p)
    assert f"{_where(path)}.{key}: expected" in str(info.value)


_ENCODED = {
    "latin-1 comment": "# réglage\n".encode("latin-1"),
    "utf-16 without BOM": "[study]\n".encode("utf-16-le"),
    "binary": bytes(range(256)),
    "empty": b"",
    "truncated": STUDY.read_bytes()[:700],
}


@pytest.mark.parametrize("case", list(_ENCODED))
def test_bad_encodings_and_damaged_files(tmp_path, case):
    p = tmp_path / "study.toml"
    p.write_bytes(_ENCODED[case])
    with pytest.raises(ConfigError) as info:
        load_study(p)
    assert str(p) in str(info.value)
