"""Generate the reference pages of the mvtk docs from the code itself.

On every build this writes ``docs/_generated/``:

- ``api/<package>.md``: one page per public subpackage with an autodoc directive for
  every name in its ``__all__`` (nothing hand-copied: a new public name appears by itself;
  ``tests/test_docs.py`` checks that every name is covered);
- ``cli.md``: the ``--help`` text of ``mvtk`` and of every sub-command, from argparse;
- ``study_schema.md``: the study TOML reference, from the schema the study parser
  validates against (when the study package exposes one).
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


def _on_builder_inited(app) -> None:
    generate(Path(app.srcdir))


def setup(app):
    app.connect("builder-inited", _on_builder_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
