"""mvtk: structural dynamics model validation.

From measured vibration data to a validated reduced model and a verified active
vibration controller:

``mvtk.io``  -> ``mvtk.signal`` -> ``mvtk.damping`` and ``mvtk.modal``;
``mvtk.fe``  -> ``mvtk.correlation`` / ``mvtk.updating`` -> ``mvtk.reduction`` ->
``mvtk.control``;
``mvtk.validation``, ``mvtk.report`` and ``mvtk.study`` wire it together;
``mvtk.scale`` runs the same calls on dask (campaigns, parameter studies).

Subpackages are imported lazily (``mvtk.fe`` is loaded on first access), and
``import mvtk`` never imports matplotlib, pyuff or dask.
"""

from __future__ import annotations

import importlib
from importlib.metadata import PackageNotFoundError, version

from . import errors

try:
    __version__ = version("mvtk")
except PackageNotFoundError:  # pragma: no cover - running from a source tree
    __version__ = "0.0.0+unknown"

_SUBPACKAGES = (
    "io",
    "signal",
    "damping",
    "modal",
    "fe",
    "updating",
    "correlation",
    "reduction",
    "control",
    "validation",
    "plot",
    "report",
    "study",
    "scale",
    "testing",
)

__all__ = ["__version__", "errors", *_SUBPACKAGES]


def __getattr__(name: str):
    if name in _SUBPACKAGES:
        return importlib.import_module(f"mvtk.{name}")
    raise AttributeError(f"module 'mvtk' has no attribute {name!r}")
