"""The ``[updating]`` section of a study as the inputs of :func:`mvtk.updating.update`."""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from ..errors import ConfigError

__all__ = ["create_missing", "import_builder", "update_arguments"]


def create_missing(description: dict, path: str, value: Any, where: str) -> None:
    """Create the field ``path`` (dict keys only) with ``value`` if it does not exist."""
    node = description
    parts = path.split(".")
    for part in parts[:-1]:
        if isinstance(node, list):
            try:
                node = node[int(part)]
            except (ValueError, IndexError):
                return  # let Parameter.resolve report the bad path
            continue
        if not isinstance(node, dict):
            return
        node = node.setdefault(part, {})
    if isinstance(node, dict) and parts[-1] not in node:
        if not isinstance(value, int | float) or isinstance(value, bool):
            raise ConfigError(f"{where}.initial: expected a number, got {value!r}")
        node[parts[-1]] = float(value)


def import_builder(spec: str):
    if not isinstance(spec, str) or spec.count(":") != 1:
        raise ConfigError(
            f"updating.builder: expected 'package.module:function', got {spec!r}"
        )
    mod, func = spec.split(":")
    try:
        fn = getattr(importlib.import_module(mod), func)
    except (ImportError, AttributeError) as err:
        raise ConfigError(f"updating.builder: cannot import {spec!r}: {err}") from err
    if not callable(fn):
        raise ConfigError(f"updating.builder: {spec!r} is not callable")
    return fn


def update_arguments(path: str | Path) -> dict[str, Any]:
    """Read a study TOML and return the keyword arguments of :func:`mvtk.updating.update`.

    The study is parsed by :func:`mvtk.study.load_study` (the one study schema).

    Returns
    -------
    dict
        ``description``, ``parameters``, ``targets`` and the solver settings given
        (``builder``, ``n_modes``, ``regularization``, ``mac_weight``, ``max_iter``,
        ``frequency_std``), plus ``structure_path`` (or None for an inline structure).

    Raises
    ------
    ConfigError
        Missing ``[updating]`` section, unknown keys, bad parameters or targets.
    """
    from ..updating._parameters import Parameter
    from ..updating._targets import FrequencyTarget
    from ._config import load_study as load

    study = load(path)
    up = study.config.get("updating")
    if up is None:
        raise ConfigError(f"{path}: no [updating] section (found sections "
                          f"{sorted(study.config)})")
    description = study.description()
    for i, p in enumerate(up["parameters"]):
        if p.get("initial") is not None:
            create_missing(description, p["path"], p["initial"],
                            f"{path}: updating.parameters[{i}]")
    if up.get("targets_hz") is not None:
        targets = [FrequencyTarget(float(f), label=f"f{i + 1}")
                   for i, f in enumerate(up["targets_hz"])]
    else:
        targets = [FrequencyTarget.from_dict(dict(t), f"{path}: updating.targets[{i}]")
                   for i, t in enumerate(up["targets"])]
    kwargs: dict[str, Any] = {
        "description": description,
        "parameters": [
            Parameter.from_dict({k: v for k, v in p.items() if v is not None},
                                f"{path}: updating.parameters[{i}]")
            for i, p in enumerate(up["parameters"])
        ],
        "targets": targets,
        "structure_path": study.structure_file,
    }
    if up.get("builder") is not None:
        kwargs["builder"] = import_builder(up["builder"])
    for key in ("n_modes", "regularization", "mac_weight", "max_iter", "frequency_std"):
        if up.get(key) is not None:
            kwargs[key] = up[key]
    return kwargs
