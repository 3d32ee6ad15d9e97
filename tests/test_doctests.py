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


#: the stage packages whose public API (``__all__``) carries Examples sections
STAGE_PACKAGES = ("mvtk.signal", "mvtk.damping", "mvtk.modal", "mvtk.fe", "mvtk.correlation",
                  "mvtk.updating", "mvtk.reduction", "mvtk.control", "mvtk.io", "mvtk.plot")


def _has_example(obj) -> bool:
    doc = obj.__doc__ or ""
    return "Examples\n" in doc and ">>> " in doc


def _public_callables(package: str) -> list[str]:
    """Public functions and classes of ``package`` (constants in ``__all__`` excluded)."""
    mod = importlib.import_module(package)
    return [f"{package}.{n}" for n in mod.__all__ if callable(getattr(mod, n))]


#: public functions and classes still without an Examples section, by package. A new
#: public name must come with an example; an entry leaves this list when its example lands.
#: ``register_reader`` changes the process-wide reader registry, which a doctest would leave
#: changed for every later test (its use is described in the mvtk.io module documentation).
NO_EXAMPLE_YET = {
    "mvtk.io": (
        "register_reader",
    ),
}


def _without_example() -> set[str]:
    missing = set()
    for package in STAGE_PACKAGES:
        mod = importlib.import_module(package)
        for path in _public_callables(package):
            if not _has_example(getattr(mod, path.rsplit(".", 1)[1])):
                missing.add(path)
    return missing


def test_public_api_has_examples():
    """Every public function/class of a stage package has an Examples section, except
    those listed in NO_EXAMPLE_YET."""
    allowed = {f"{p}.{n}" for p, names in NO_EXAMPLE_YET.items() for n in names}
    new = sorted(_without_example() - allowed)
    assert not new, f"public names without an Examples section: {new}"


def test_no_example_list_is_current():
    """NO_EXAMPLE_YET names only existing public names that still lack an example."""
    allowed = {f"{p}.{n}" for p, names in NO_EXAMPLE_YET.items() for n in names}
    public = {path for p in STAGE_PACKAGES for path in _public_callables(p)}
    stale = sorted(allowed - (_without_example() & public))
    assert not stale, f"remove from NO_EXAMPLE_YET (they have an example or are gone): {stale}"
