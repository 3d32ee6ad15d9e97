"""Helpers of the robustness suite (a uniquely named module: several test folders have a
``conftest.py``, so ``from conftest import ...`` would be ambiguous)."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
from fast_study import write_fast_study

__all__ = ["copy_run", "numbers", "assert_same_numbers", "read_tables", "write_fast_study"]


def copy_run(clean_run, dest: Path, replace: dict[str, str] | None = None) -> tuple[Path, Path]:
    """A copy of the clean run's study (with text replacements) and output folder."""
    study, out, _ = clean_run
    new_study = write_fast_study(dest / "in", replace)
    new_out = dest / "out"
    shutil.copytree(out, new_out)
    return new_study, new_out


def numbers(obj, prefix=""):
    """Flatten the numeric leaves of a stage result: {dotted path: float}."""
    out = {}
    if isinstance(obj, dict):
        for k, v in obj.items():
            if k in ("timing", "warnings", "half_power_warnings", "decay_warnings",
                     "scheduler", "n_evaluations", "message", "summary"):
                continue
            out.update(numbers(v, f"{prefix}.{k}" if prefix else str(k)))
    elif isinstance(obj, list | tuple):
        for i, v in enumerate(obj):
            out.update(numbers(v, f"{prefix}[{i}]"))
    elif isinstance(obj, bool):
        out[prefix] = float(obj)
    elif isinstance(obj, int | float):
        out[prefix] = float(obj)
    return out


def assert_same_numbers(a: dict, b: dict, rtol: float = 1e-4) -> None:
    """Every numeric leaf of every stage result agrees to ``rtol``.

    A recomputed stage is not bit-identical: ARPACK's random start vector makes an eigen
    solution differ at about 1e-9 relative, which the finite-difference sensitivities of
    the updating stage amplify (its condition number moves by about 1e-5 relative); the
    report shows 4 significant digits. Values near zero (relative pairing errors of
    7e-6, a static check error of 6e-9) move by up to a few 1e-8: ``atol`` = 1e-7.
    """
    assert set(a) == set(b), (sorted(a), sorted(b))
    for stage in a:
        na, nb = numbers(a[stage]), numbers(b[stage])
        assert set(na) == set(nb), stage
        for k in na:
            x, y = na[k], nb[k]
            if math.isnan(x) and math.isnan(y):
                continue
            assert np.isclose(x, y, rtol=rtol, atol=1e-7), (stage, k, x, y)


def read_tables(out: Path) -> dict[str, str]:
    return {p.name: p.read_text() for p in sorted((out / "tables").glob("*.csv"))}
