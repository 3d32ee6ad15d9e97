"""Shared fixtures of the robustness suite: a clean run of the fast smart-beam study."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fast_study import write_fast_study  # noqa: E402


@pytest.fixture(scope="session")
def clean_run(tmp_path_factory):
    """``(study_path, out_dir, StudyResult)`` of a clean run of the fast study."""
    from mvtk.study import run

    base = tmp_path_factory.mktemp("clean")
    study = write_fast_study(base / "in")
    res = run(study, base / "out", progress=False)
    assert not res.failed and not res.unavailable, (res.failed, res.unavailable)
    return study, base / "out", res
