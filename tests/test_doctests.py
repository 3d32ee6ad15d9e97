"""Every Examples section of the package runs as written (doctest).

The examples in the docstrings are what the API reference shows; this runs them all
(``# doctest: +SKIP`` marks the few that need files or a browser).
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import mvtk

MODULES = sorted(m.name for m in pkgutil.walk_packages(mvtk.__path__, "mvtk.")
                 if not m.name.endswith("__main__"))


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples_run(name):
    module = importlib.import_module(name)
    finder = doctest.DocTestFinder(exclude_empty=True)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    for test in finder.find(module, name, extraglobs={"np": __import__("numpy")}):
        if test.lineno is None or test.filename is None:
            continue
        # only the examples written in this module (not those of re-exported objects)
        if not test.filename.endswith(name.replace(".", "/") + ".py") and not \
                test.filename.endswith(name.replace(".", "/") + "/__init__.py"):
            continue
        runner.run(test)
    res = runner.summarize(verbose=False)
    assert res.failed == 0, f"{res.failed} of {res.attempted} examples of {name} failed"


#: the entry point of each stage package carries a runnable example (the API reference
#: shows it; the test above runs it)
ENTRY_POINTS = ("mvtk.signal.frf", "mvtk.damping.half_power", "mvtk.damping.log_decrement",
                "mvtk.damping.rayleigh_fit", "mvtk.fe.plate_model", "mvtk.modal.identify",
                "mvtk.correlation.mac", "mvtk.reduction.craig_bampton",
                "mvtk.report.classify_checks", "mvtk.plot.mode_animation_html")


@pytest.mark.parametrize("path", ENTRY_POINTS)
def test_stage_entry_points_have_examples(path):
    module, name = path.rsplit(".", 1)
    doc = getattr(importlib.import_module(module), name).__doc__ or ""
    assert "Examples\n    --------" in doc and ">>> " in doc, path
