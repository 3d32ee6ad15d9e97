"""Generate the reference pages of the mvtk docs from the code itself.

On every build this writes ``docs/_generated/``:

- ``api/<package>.md``: one page per public subpackage with an autodoc directive for
  every name in its ``__all__`` (nothing hand-copied: a new public name appears by itself;
  ``tests/test_docs.py`` checks that every name is covered);
- ``cli.md``: the ``--help`` text of ``mvtk`` and of every sub-command, from argparse;
- ``study_schema.md``: the study TOML reference, from the schema the study parser
  validates against (when the study package exposes one);
- ``validation.md``: the validation evidence, from running the registry of validation
  cases (:func:`mvtk.validation.run_validation`, the same cases ``tests/validation``
  asserts): per case its source, reference and current values, error, tolerance and
  verdict. A failing case is a Sphinx warning (an error under ``-W``); a case whose
  measurement file is absent is shown as skipped.
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

#: Public subpackages documented in the API reference, in pipeline order.
API_PACKAGES = ("io", "signal", "damping", "modal", "fe", "updating", "correlation",
                "reduction", "control", "validation", "study", "report", "plot", "scale",
                "testing", "errors")


def _directive(module, name: str) -> str:
    obj = getattr(module, name)
    if inspect.isclass(obj):
        if issubclass(obj, BaseException):
            return f".. autoexception:: {name}\n   :no-members:\n"
        return f".. autoclass:: {name}\n   :members:\n"
    if callable(obj):
        return f".. autofunction:: {name}\n"
    if inspect.ismodule(obj):
        return f".. rubric:: {name}\n\nSubmodule :mod:`{obj.__name__}`.\n"
    return f".. autodata:: {name}\n   :no-value:\n"


def _home_package(obj) -> str | None:
    """``mvtk.<package>`` that defines ``obj`` (None for modules and plain data)."""
    mod = getattr(obj, "__module__", None)
    if inspect.ismodule(obj) or not isinstance(mod, str) or not mod.startswith("mvtk."):
        return None
    parts = mod.split(".")
    if parts[1].startswith("_"):
        return None
    return ".".join(parts[:2])


def api_page(package: str) -> str | None:
    """MyST text of the API page of ``mvtk.<package>`` (None if it does not exist)."""
    modname = f"mvtk.{package}"
    try:
        module = importlib.import_module(modname)
    except ModuleNotFoundError as err:
        if err.name == modname:
            return None
        raise
    names = list(getattr(module, "__all__", []))
    lines = [f"# `{modname}`", "", "```{eval-rst}", f".. automodule:: {modname}",
             "   :no-members:", "", f".. currentmodule:: {modname}", "",
             ".. autosummary::", "   :nosignatures:", ""]
    lines += [f"   {n}" for n in names]
    lines.append("")
    for n in names:
        home = _home_package(getattr(module, n))
        if home is not None and home != modname:
            # a re-export (e.g. mvtk.scale.open_campaign): documented where it lives
            lines.append(f".. rubric:: {n}\n\nRe-exported from :obj:`{home}.{n}`.\n")
        else:
            lines.append(_directive(module, n))
    lines.append("```")
    return "\n".join(lines) + "\n"


def cli_page() -> str:
    """MyST text of the CLI reference from ``mvtk.cli.build_parser``."""
    import argparse

    from mvtk.cli import build_parser

    parser = build_parser()
    parser.prog = "mvtk"
    out = ["# Command line reference", "",
           "Generated from the argparse definitions (`mvtk.cli.build_parser`).", "",
           "```text", parser.format_help().rstrip(), "```", ""]
    for action in parser._actions:  # noqa: SLF001 - argparse exposes no public accessor
        if isinstance(action, argparse._SubParsersAction):  # noqa: SLF001
            for name, sub in action.choices.items():
                out += [f"## `mvtk {name}`", "", "```text", sub.format_help().rstrip(), "```", ""]
    return "\n".join(out)


def _fmt_default(key: dict) -> str:
    if key.get("required"):
        return "**required**"
    value = key.get("default")
    if value is None:
        return "—"
    return f"`{value!r}`" if not isinstance(value, str) else f'`"{value}"`'


def _fmt_range(key: dict) -> str:
    parts = []
    if "minimum" in key:
        parts.append((">" if key.get("exclusive_minimum") else ">=") + f" {key['minimum']:g}")
    if "maximum" in key:
        parts.append(("<" if key.get("exclusive_maximum") else "<=") + f" {key['maximum']:g}")
    if "choices" in key:
        parts.append("one of " + ", ".join(f"`{c}`" for c in key["choices"]))
    if key.get("ascending"):
        parts.append("ascending")
    if "length" in key:
        parts.append(f"{key['length']} values")
    return "; ".join(parts)


def _table_md(title: str, table: dict, level: int, out: list[str]) -> None:
    out += [f"{'#' * level} `{title}`", "", table["doc"], ""]
    for group in table.get("one_of", []):
        out += ["Exactly one of " + ", ".join(f"`{k}`" for k in group) + ".", ""]
    for group in table.get("at_most_one_of", []):
        out += ["At most one of " + ", ".join(f"`{k}`" for k in group) + ".", ""]
    rows = [(name, key) for name, key in table["keys"].items()]
    if rows:
        out += ["| key | type | units | default | allowed | meaning |",
                "| --- | --- | --- | --- | --- | --- |"]
        for name, key in rows:
            doc = " ".join(str(key["doc"]).split()).replace("|", "\\|")
            out.append(f"| `{name}` | {key['type']} | {key['units'] or '—'} | "
                       f"{_fmt_default(key)} | {_fmt_range(key) or '—'} | {doc} |")
        out.append("")
    for name, key in rows:
        if "table" in key:
            sub = f"{title}.{name}" if key["type"] == "table" else f"[{title}.{name}]"
            _table_md(sub, key["table"], min(level + 1, 6), out)


def study_schema_page() -> str | None:
    """MyST text of the study TOML reference, generated from the schema the parser uses.

    Returns None when the study package exposes no declarative schema.
    """
    try:
        schema_mod = importlib.import_module("mvtk.study._schema")
    except ModuleNotFoundError:
        return None
    schema = getattr(schema_mod, "SCHEMA", None)
    if schema is None:
        return None
    out = ["# Study file reference", "",
           "Generated from the schema of `mvtk.study`, the one `mvtk run`, `update`, `reduce` "
           "and `control` validate every study file against: a key that is not listed here "
           "is refused. Paths are relative to the study file; units are SI.", ""]
    for section, table in schema.items():
        _table_md(section, table.to_dict(), 2, out)
    controllers = getattr(schema_mod, "CONTROLLER_SCHEMAS", None)
    if controllers:
        out += ["## Controller types (`[[control.controllers]]`)", ""]
        for name, table in controllers.items():
            _table_md(f"type = \"{name}\"", table.to_dict(), 3, out)
    return "\n".join(out) + "\n"


def _cell(text) -> str:
    return " ".join(str(text).split()).replace("|", "\\|")


def _verdict(status: str) -> str:
    """Verdict of one row (the reason a case did not run is given once, above its table)."""
    if status == "pass":
        return "pass"
    if status == "FAIL":
        return "**FAIL**"
    return "not run" if status.startswith("skipped") else "**error**"


def _case_verdict(rows) -> str:
    statuses = set(rows["status"])
    if statuses == {"pass"}:
        return "pass"
    if "FAIL" in statuses:
        return "**FAIL**"
    return _cell(next(iter(statuses)).split(":")[0])


def _truth_kind(source: str) -> str:
    """Short kind of the external truth, for the summary table."""
    low = source.lower()
    for prefix, kind in (("shared/data", "real file"), ("peer", "peer library"),
                         ("closed form", "closed form"), ("exact", "exact property")):
        if low.startswith(prefix):
            return kind
    return "published benchmark"


def _worst_error(rows) -> str:
    from mvtk.report import format_number

    if rows["value"].isna().all():
        return "—"
    pct = rows["error_pct"].abs()
    if pct.notna().all():
        return f"{format_number(float(pct.max()), 2, floor=1e-10)} %"
    err = rows["error"].abs().max()
    unit = rows["unit"].iloc[0]
    return f"{format_number(float(err), 2)} {unit}".rstrip()


def validation_page(table=None, *, seconds: float | None = None) -> str:
    """MyST text of the validation evidence page.

    Parameters
    ----------
    table : pandas.DataFrame, optional
        The output of :func:`mvtk.validation.run_validation`; default: run the registry now.
    seconds : float, optional
        Wall time of the run, printed on the page.
    """
    import time

    import mvtk
    from mvtk.report import format_number
    from mvtk.validation import run_validation

    if table is None:
        t0 = time.perf_counter()
        table = run_validation()
        seconds = time.perf_counter() - t0
    cases = list(dict.fromkeys(table["case"]))
    status = table.groupby("case", sort=False)["status"].agg(lambda s: _case_verdict(
        table.loc[s.index]))
    n_pass = int((status == "pass").sum())
    n_fail = int((status == "**FAIL**").sum())
    n_skip = len(cases) - n_pass - n_fail
    took = f" in {seconds:.1f} s" if seconds is not None else ""
    out = [
        "# Validation evidence", "",
        "Every number mvtk prints is tested against an external truth: a closed form, a "
        "published benchmark, a peer library on the same data, or a real file from someone "
        "else's instrument (`../shared/data`, see its `PROVENANCE.md`). This page is "
        "**generated when the documentation is built**: it runs the registry of validation "
        "cases (`mvtk.validation.validation_cases()`, the cases `tests/validation` asserts) "
        "with the code it documents, so the values below are the current ones, not copied "
        "from a past run. Run it yourself with `mvtk.validation.run_validation()`.", "",
        f"mvtk {mvtk.__version__}: **{len(cases)} cases, {n_pass} pass, {n_fail} fail, "
        f"{n_skip} not run**{took}. A case is not run when the external measurement corpus "
        "is absent (a fresh clone without `../shared/data`; set `$MVTK_SHARED_DATA`).", "",
        "The whole suite (`make test`) checks much more than this page: patch tests, "
        "convergence rates, hypothesis sweeps, bad-input messages; the registry keeps the "
        "benchmarks that are quick enough to rerun on every documentation build.", "",
        "## Summary", "",
        "| case | area | truth | worst error | tolerance | verdict |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for name in cases:
        rows = table[table["case"] == name]
        first = rows.iloc[0]
        out.append(f"| [`{name}`](#{name.replace('.', '-').replace('_', '-')}) | "
                   f"{first['area']} | {_truth_kind(first['source'])} | {_worst_error(rows)} | "
                   f"{_cell(first['tolerance'])} | {status[name]} |")
    out.append("")
    for area in dict.fromkeys(table["area"]):
        out += [f"## {area}", ""]
        for name in [c for c in cases if table.loc[table["case"] == c, "area"].iloc[0] == area]:
            rows = table[table["case"] == name]
            first = rows.iloc[0]
            out += [f"({name.replace('.', '-').replace('_', '-')})=",
                    f"### `{name}`", "", _cell(first["title"]) + ".", "",
                    f"**Source:** {_cell(first['source'])}.", "",
                    f"**Verdict:** {status[name]}"
                    + (f" ({_cell(first['status'].split(': ', 1)[1])})" if first["status"] not in
                       ("pass", "FAIL") else f" (run time {first['seconds']:.2f} s)") + ".", "",
                    "| quantity | reference | mvtk | error | error % | tolerance | verdict |",
                    "| --- | --- | --- | --- | --- | --- | --- |"]
            for _, r in rows.iterrows():
                unit = f" {r['unit']}" if r["unit"] else ""
                out.append(
                    f"| {_cell(r['quantity'])} | {format_number(r['reference'], 8)}{unit} | "
                    f"{format_number(r['value'], 8)}{unit} | "
                    f"{format_number(r['error'], 2)} | "
                    f"{format_number(r['error_pct'], 2, floor=1e-10)} | "
                    f"{_cell(r['tolerance'])} | {_verdict(r['status'])} |")
            out.append("")
    return "\n".join(out) + "\n"


def _write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.is_file() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def generate(srcdir: Path) -> list[str]:
    """Write the generated pages under ``srcdir/_generated``; return the API packages."""
    gen = Path(srcdir) / "_generated"
    done = []
    for package in API_PACKAGES:
        text = api_page(package)
        if text is not None:
            _write(gen / "api" / f"{package}.md", text)
            done.append(package)
    index = ["# API reference", "", "One page per subpackage, in the order of the pipeline.",
             "", "```{toctree}", ":maxdepth: 1", ""] + [f"{p}" for p in done] + ["```", ""]
    _write(gen / "api" / "index.md", "\n".join(index))
    _write(gen / "cli.md", cli_page())
    schema = study_schema_page()
    _write(gen / "study_schema.md", schema if schema is not None else (
        "# Study file reference\n\nThe study schema is documented in the README.\n"))
    return done


def failing_cases(table) -> list[str]:
    """Cases of a :func:`mvtk.validation.run_validation` table that failed or raised
    (a case not run for want of its measurement file is not a failure)."""
    bad = table["status"].eq("FAIL") | table["status"].str.startswith("error")
    return list(dict.fromkeys(table.loc[bad, "case"]))


def _on_builder_inited(app) -> None:
    import time

    from sphinx.util import logging

    from mvtk.validation import run_validation

    generate(Path(app.srcdir))
    t0 = time.perf_counter()
    table = run_validation()
    page = validation_page(table, seconds=time.perf_counter() - t0)
    _write(Path(app.srcdir) / "_generated" / "validation.md", page)
    log = logging.getLogger(__name__)
    for name in failing_cases(table):  # an error under -W: the docs never show a silent FAIL
        status = table.loc[table["case"] == name, "status"]
        log.warning("validation case %s: %s", name, "; ".join(dict.fromkeys(status)))


def setup(app):
    app.connect("builder-inited", _on_builder_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
