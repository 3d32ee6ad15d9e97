"""The package floors of docs/architecture.md: the import-linter contract holds, covers
every package, fails on an upward import, and the package graph has no cycle."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
grimp = pytest.importorskip("grimp", reason="import-linter (test extra) not installed")
LINT = shutil.which("lint-imports", path=str(Path(sys.executable).parent))


def _contract() -> dict:
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    (contract,) = cfg["tool"]["importlinter"]["contracts"]
    return contract


def _layer_modules() -> list[list[str]]:
    out = []
    for layer in _contract()["layers"]:
        out.append([m.strip() for m in layer.replace(":", "|").split("|")])
    return out


def _top_level_modules() -> set[str]:
    names = set()
    for p in (ROOT / "mvtk").iterdir():
        if p.is_dir() and (p / "__init__.py").exists():
            names.add(f"mvtk.{p.name}")
        elif p.suffix == ".py" and p.stem not in ("__init__", "__main__"):
            names.add(f"mvtk.{p.stem}")
    return names


def _lint(root: Path) -> subprocess.CompletedProcess:
    env = {"PYTHONPATH": str(root), "PATH": str(Path(sys.executable).parent)}
    return subprocess.run([LINT, "--no-cache", "--config", str(root / "pyproject.toml")],
                          cwd=root, capture_output=True, text=True, env=env, timeout=120)


def test_every_package_is_on_a_floor():
    listed = {m for layer in _layer_modules() for m in layer}
    missing = _top_level_modules() - listed
    assert not missing, f"packages on no floor of [tool.importlinter]: {sorted(missing)}"
    assert not listed - _top_level_modules(), "a floor names a module that does not exist"


@pytest.mark.skipif(LINT is None, reason="lint-imports (import-linter) not installed")
def test_contract_kept_and_broken_by_an_upward_import(tmp_path):
    shutil.copytree(ROOT / "mvtk", tmp_path / "mvtk",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path / "pyproject.toml")
    ok = _lint(tmp_path)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    assert "1 kept, 0 broken" in ok.stdout
    # a stage package reaching up to the study (the old `_cli.py` pattern) breaks it
    modal = tmp_path / "mvtk" / "fe" / "_modal.py"
    modal.write_text(modal.read_text(encoding="utf-8")
                     + "\n\ndef _upward():\n    from ..study import load_study\n\n"
                       "    return load_study\n", encoding="utf-8")
    bad = _lint(tmp_path)
    assert bad.returncode != 0
    assert "BROKEN" in bad.stdout and "mvtk.fe._modal -> mvtk.study" in bad.stdout


def test_package_graph_is_acyclic():
    graph = grimp.build_graph("mvtk")
    packages = sorted(_top_level_modules())

    def owner(module: str) -> str | None:
        return next((p for p in packages if module == p or module.startswith(p + ".")), None)

    edges: dict[str, set[str]] = {p: set() for p in packages}
    for module in graph.modules:
        src = owner(module)
        if src is None:
            continue
        for imported in graph.find_modules_directly_imported_by(module):
            dst = owner(imported)
            if dst is not None and dst != src:
                edges[src].add(dst)
    # Kahn's algorithm: every package is removed only when nothing it imports is left
    remaining = {p: set(d) for p, d in edges.items()}
    while remaining:
        free = [p for p, d in remaining.items() if not d & remaining.keys()]
        assert free, f"import cycle among {sorted(remaining)}"
        for p in free:
            del remaining[p]
