"""The ``[updating]`` section of a study as the inputs of :func:`mvtk.updating.update`."""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any

from ..errors import ConfigError

__all__ = ["create_missing", "import_builder", "identified_std", "update_arguments",
           "updating_inputs"]


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


def identified_std(study, targets: list, attached: list, modal_result) -> tuple[list, list]:
    """Targets with the ``fn_std_hz`` of their identified mode as ``std_hz``.

    The identified mode of a target is the test mode whose shape it carries
    (``attached``), else the reliable identified mode nearest in frequency within
    ``modal.pair_within`` (the rule of the shape pairing). A target that states its own
    ``std_hz`` keeps it. Returns the targets and, per target, where its standard
    deviation came from (``"stated"``, ``"test mode k"`` or ``"none"``).
    """
    import dataclasses

    import numpy as np

    tab = (modal_result or {}).get("table") or {}
    fn = np.asarray(tab.get("fn_hz", []), dtype=float)
    std = np.asarray(tab.get("fn_std_hz", [np.nan] * fn.size), dtype=float)
    ok = np.asarray(tab.get("reliable", [True] * fn.size), dtype=bool)
    modes = list(tab.get("mode", range(1, fn.size + 1)))
    modal_cfg = study.section("modal")
    within = float(modal_cfg["pair_within"]) if modal_cfg is not None else 0.0
    out, source = [], []
    for t, k in zip(targets, attached):
        if t.std_hz is not None:
            out.append(t)
            source.append("stated")
            continue
        j = modes.index(k) if k is not None and k in modes else None
        if j is None and fn.size:
            near = int(np.argmin(np.abs(fn - t.fn_hz)))
            if abs(fn[near] / t.fn_hz - 1) <= within and ok[near]:
                j = near
        if j is None or not np.isfinite(std[j]):
            out.append(t)
            source.append("none")
            continue
        out.append(dataclasses.replace(t, std_hz=float(std[j])))
        source.append(f"test mode {modes[j]}")
    return out, source


def updating_inputs(study, modal_arrays=None, modal_result=None) -> dict[str, Any]:
    """The inputs of :func:`mvtk.updating.update` from a study's ``[updating]`` section.

    The one reading of ``[updating]`` (the study's updating stage and
    :func:`update_arguments` use it): parameters (a field absent from the structure is
    created with ``initial``), targets (``targets_hz`` labelled f1, f2, ... or
    ``targets`` tables), with a ``[modal]`` test and ``modal.pair_updating`` the
    identified shapes attached (MAC pairing; shapes that are not normal modes dropped),
    the identification standard deviations attached (:func:`identified_std`), and every
    target without a shape or a ``mode`` paired with its nominal FE mode by frequency
    (:func:`mvtk.study._stages.pair_targets`).

    Returns
    -------
    dict
        ``description``, ``parameters``, ``targets``, ``kwargs`` (the solver settings of
        ``update``: ``max_iter``, ``model_form_std`` and those given, ``builder`` or
        ``affine``), ``attached`` (test mode of each target's shape or None),
        ``pairing_table``, ``shapes_not_used`` and ``std_source``.
    """
    from ..updating import FrequencyTarget, Parameter
    from ._stages import _affine_parameters, _normal_mode_shapes, pair_targets

    cfg = study.section("updating")
    desc = study.description()
    params = []
    for i, p in enumerate(cfg["parameters"]):
        where = f"updating.parameters[{i}]"
        if p.get("initial") is not None:
            # a field absent from the nominal description (e.g. an elastic clamp) starts
            # at the configured value
            create_missing(desc, p["path"], p["initial"], where)
        params.append(Parameter.from_dict({k: v for k, v in p.items() if v is not None},
                                          where))
    if cfg.get("targets_hz") is not None:
        targets = [FrequencyTarget(float(f), label=f"f{i + 1}")
                   for i, f in enumerate(cfg["targets_hz"])]
    else:
        targets = [FrequencyTarget.from_dict(dict(t), f"updating.targets[{i}]")
                   for i, t in enumerate(cfg["targets"])]
    attached: list = [None] * len(targets)
    modal_cfg = study.section("modal")
    builder = import_builder(cfg["builder"]) if cfg.get("builder") is not None else None
    if builder is None:
        from ..fe import build_model as builder_or_default
    else:
        builder_or_default = builder
    nominal_model = None
    dropped: list[str] = []
    if modal_arrays is not None and modal_cfg is not None and modal_cfg["pair_updating"]:
        from ._ema import shape_targets

        nominal_model = builder_or_default(desc)
        targets, attached = shape_targets(study, targets, modal_arrays, nominal_model)
        targets, attached, dropped = _normal_mode_shapes(study, targets, attached,
                                                         modal_result)
    targets, std_source = identified_std(study, targets, attached, modal_result)
    targets, pairing_table = pair_targets(desc, targets, builder_or_default, nominal_model)
    kwargs = {k: cfg[k] for k in ("n_modes", "regularization", "mac_weight", "frequency_std")
              if cfg.get(k) is not None}
    kwargs["max_iter"] = int(cfg.get("max_iter", 30))
    kwargs["model_form_std"] = float(cfg["model_form_std"])
    if builder is not None:
        kwargs["builder"] = builder
    else:
        kwargs["affine"] = _affine_parameters(desc, [p.path for p in params])
    return {"description": desc, "parameters": params, "targets": targets,
            "kwargs": kwargs, "attached": attached, "pairing_table": pairing_table,
            "shapes_not_used": dropped, "std_source": std_source}


def update_arguments(path: str | Path) -> dict[str, Any]:
    """Read a study TOML and return the keyword arguments of :func:`mvtk.updating.update`.

    The study is parsed by :func:`mvtk.study.load_study` (the one study schema) and its
    ``[updating]`` section by :func:`updating_inputs`, as the study's updating stage
    does (without a ``[modal]`` test's shapes: targets paired with the nominal FE modes
    by frequency).

    Returns
    -------
    dict
        ``description``, ``parameters``, ``targets`` and the solver settings
        (``max_iter``, ``model_form_std``, ``builder`` or ``affine``, and ``n_modes``,
        ``regularization``, ``mac_weight``, ``frequency_std`` when given), plus
        ``structure_path`` (or None for an inline structure).

    Raises
    ------
    ConfigError
        Missing ``[updating]`` section, unknown keys, bad parameters or targets.
    """
    from ._config import load_study as load

    study = load(path)
    if study.config.get("updating") is None:
        raise ConfigError(f"{path}: no [updating] section (found sections "
                          f"{sorted(study.config)})")
    inputs = updating_inputs(study)
    return {"description": inputs["description"], "parameters": inputs["parameters"],
            "targets": inputs["targets"], **inputs["kwargs"],
            "structure_path": study.structure_file}
