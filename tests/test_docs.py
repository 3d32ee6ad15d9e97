"""The documentation generators and the site checker (the site itself: ``make docs``)."""

from __future__ import annotations

import importlib
import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "docs" / "_ext"))
sys.path.insert(0, str(ROOT / "docs"))

import mvtk_docs  # noqa: E402


def test_every_public_name_has_an_api_entry():
    for package in mvtk_docs.API_PACKAGES:
        modname = f"mvtk.{package}"
        if importlib.util.find_spec(modname) is None:
            continue
        page = mvtk_docs.api_page(package)
        module = importlib.import_module(modname)
        for name in module.__all__:
            assert f":: {name}\n" in page or f"rubric:: {name}\n" in page, (modname, name)


def test_reexports_point_to_their_home():
    page = mvtk_docs.api_page("scale")
    assert "Re-exported from :obj:`mvtk.io.open_campaign`" in page


def test_cli_reference_lists_every_command():
    from mvtk.cli import build_parser

    text = mvtk_docs.cli_page()
    sub = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    for name in sub.choices:
        assert f"## `mvtk {name}`" in text


def _site(tmp_path: Path, body: str) -> Path:
    (tmp_path / "index.html").write_text(
        f'<html><body><h1 id="top">x</h1>{body}</body></html>', encoding="utf-8")
    (tmp_path / "other.html").write_text('<p id="here">y</p>', encoding="utf-8")
    return tmp_path


def test_site_checker_finds_broken_internal_links(tmp_path):
    check_site = importlib.import_module("check_site")
    good = _site(tmp_path, '<a href="other.html#here">ok</a><a href="#top">t</a>'
                           '<a href="https://example.org/x">ext</a>')
    problems, external = check_site.check_links(good)
    assert problems == [] and external == ["https://example.org/x"]
    bad = _site(tmp_path, '<a href="missing.html">m</a><a href="other.html#nope">n</a>')
    problems, _ = check_site.check_links(bad)
    assert len(problems) == 2
    assert "missing.html" in problems[0] and "no anchor #nope" in problems[1]


def test_site_checker_refuses_an_unbuilt_site(tmp_path, capsys):
    check_site = importlib.import_module("check_site")
    assert check_site.main([str(tmp_path)]) == 2
    assert "build the docs first" in capsys.readouterr().err


@pytest.mark.skipif(importlib.util.find_spec("sphinx") is None, reason="sphinx not installed")
def test_conf_lists_the_generator_extension():
    text = (ROOT / "docs" / "conf.py").read_text(encoding="utf-8")
    assert '"mvtk_docs"' in text and 'nb_execution_raise_on_error = True' in text


def test_study_reference_is_generated_from_the_schema(monkeypatch):
    """Changing a default in the study schema changes the generated reference page."""
    import dataclasses

    schema_mod = pytest.importorskip("mvtk.study._schema")
    page = mvtk_docs.study_schema_page()
    for section, table in schema_mod.SCHEMA.items():
        assert f"`{section}`" in page
        for key in table.keys:
            assert f"| `{key}` |" in page
    # a changed default shows up in the page: nothing is hand-copied
    section, table = next((s, t) for s, t in schema_mod.SCHEMA.items()
                          if any(not k.required and isinstance(k.default, bool)
                                 for k in t.keys.values()))
    name, key = next((n, k) for n, k in table.keys.items()
                     if not k.required and isinstance(k.default, bool))
    changed = dict(schema_mod.SCHEMA)
    changed[section] = dataclasses.replace(
        table, keys={**table.keys, name: dataclasses.replace(key, default="SENTINEL-42")})
    monkeypatch.setattr(schema_mod, "SCHEMA", changed)
    assert '`"SENTINEL-42"`' in mvtk_docs.study_schema_page()
    assert '`"SENTINEL-42"`' not in page


def _fast_registry(fail: str | None = None):
    """The registry with each case's computation replaced by its reference values (or
    twice them for ``fail``): the page logic without the seconds of the real run."""
    import dataclasses

    from mvtk.validation import validation_cases

    def const(values):
        return lambda *_: values

    return [dataclasses.replace(c, compute=const(
        [2 * r if c.name == fail else r for r in c.reference])) for c in validation_cases()]


def test_validation_page_lists_every_registry_case(tmp_path):
    from mvtk.validation import run_validation, validation_cases

    cases = _fast_registry()
    table = run_validation(cases, data_dir=tmp_path)  # empty corpus: file cases not run
    page = mvtk_docs.validation_page(table, seconds=1.0)
    for case in validation_cases():
        assert f"### `{case.name}`" in page, case.name
        assert f"[`{case.name}`](#" in page, case.name  # in the summary table
        assert " ".join(case.source.split()) in page, case.name  # in its section
    n_data = sum(bool(c.data) for c in cases)
    assert f"{len(cases)} cases, {len(cases) - n_data} pass, 0 fail, {n_data} not run" in page
    assert "**FAIL**" not in page
    assert mvtk_docs.failing_cases(table) == []  # not run is not a failure


def test_validation_page_shows_a_failing_case():
    from mvtk.validation import run_validation

    cases = [c for c in _fast_registry(fail="fe.nafems_fv2") if not c.data]
    page = mvtk_docs.validation_page(run_validation(cases))
    line = next(x for x in page.splitlines() if x.startswith("| [`fe.nafems_fv2`]"))
    assert line.endswith("| **FAIL** |") and "| 100 % |" in line
    assert "1 fail" in page
    table = run_validation(cases)
    assert mvtk_docs.failing_cases(table) == ["fe.nafems_fv2"]


def test_site_checker_counts_the_pictures(tmp_path):
    check_site = importlib.import_module("check_site")
    site = tmp_path / "site"
    (site / "gallery").mkdir(parents=True)
    (site / "guide").mkdir()
    for page in check_site.REQUIRED_PAGES:
        (site / page).write_text("<html></html>", encoding="utf-8")
    img = '<img src="_images/a.png">'
    (site / "index.html").write_text("<p>no pictures</p>", encoding="utf-8")
    (site / "gallery" / "a.html").write_text("<p>text only</p>", encoding="utf-8")
    (site / "gallery" / "b.html").write_text("<p>data file NOT FOUND - skipping</p>",
                                             encoding="utf-8")
    problems = check_site.check_pictures(site)
    assert any("index.html: 0 pictures" in p for p in problems)
    assert any("gallery/a.html: no figure" in p for p in problems)
    assert not any("b.html" in p for p in problems)   # no data here: nothing to draw
    (site / "index.html").write_text(img * 2, encoding="utf-8")
    (site / "gallery" / "a.html").write_text(img * 6, encoding="utf-8")
    assert check_site.check_pictures(site) == []
    (site / "help.html").unlink()
    assert check_site.check_pictures(site) == ["help.html: page missing"]
