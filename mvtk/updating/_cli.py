"""``mvtk update STUDY.toml``: model updating from the ``[updating]`` section of a study.

Study layout read here (the layout of ``data/smart_beam/study.toml`` works as is)::

    [structure]
    file = "../structures/smart_beam.toml"   # structure TOML, relative to the study

    [updating]
    targets_hz = [13.26, 41.14]              # or: targets = [{fn_hz = 13.26, kind = ...}]
    max_iter = 30                            # optional
    # n_modes, regularization, mac_weight, frequency_std: optional solver settings
    # builder = "package.module:function"    # optional, default mvtk.fe.build_model

    [[updating.parameters]]
    path = "materials.steel.E"
    lower = 150e9
    upper = 260e9

    [[updating.parameters]]
    path = "boundary.clamp_stiffness"
    initial = 2000.0     # a field absent from the structure is created with this value
    lower = 20.0
    upper = 1e6
    log = true           # optional: log-scaled variable

Where the structure description comes from, first match wins: ``updating.structure_file``
or a top-level ``structure_file`` (relative to the study); ``[structure] file``;
``updating.structure_key`` (the description is that table of the study); else the study
itself is the description, without its study-level tables (``updating``, ``study``,
``measurements``, ``damping``, ``fe``, ``reduction``, ``control``, ``checks``,
``references``, ``truth``).
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import tomllib
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from ..errors import ConfigError, FormatError

__all__ = ["add_parser", "load_study", "run_update"]

_KEYS = {"structure_file", "structure_key", "builder", "n_modes", "regularization",
         "mac_weight", "max_iter", "frequency_std", "parameters", "targets", "targets_hz"}
#: Tables of a study TOML that are not part of an inline structure description.
STUDY_TABLES = ("updating", "study", "measurements", "damping", "fe", "reduction", "control",
                "checks", "references", "truth")


def _create_missing(description: dict, path: str, value: Any, where: str) -> None:
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


def _read_toml(path: Path, what: str) -> dict:
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ConfigError(f"{what} not found: {path}") from None
    except tomllib.TOMLDecodeError as err:
        raise FormatError(f"{what} {path} is not valid TOML: {err}") from err


def _builder(spec: str):
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


def load_study(path: str | Path) -> dict[str, Any]:
    """Read a study TOML and return the keyword arguments of :func:`mvtk.updating.update`.

    Returns
    -------
    dict
        ``description``, ``parameters``, ``targets`` and the optional solver settings
        (``builder``, ``n_modes``, ``regularization``, ``mac_weight``, ``max_iter``,
        ``frequency_std``), plus ``structure_path`` (or None).

    Raises
    ------
    ConfigError
        Missing ``[updating]`` section, unknown keys, bad parameters or targets.
    """
    from ._parameters import Parameter
    from ._targets import FrequencyTarget

    path = Path(path)
    study = _read_toml(path, "study file")
    up = study.get("updating")
    if not isinstance(up, Mapping):
        raise ConfigError(f"{path}: no [updating] table (found keys {sorted(study)})")
    unknown = set(up) - _KEYS
    if unknown:
        raise ConfigError(
            f"{path}: [updating] has unknown keys {sorted(unknown)}; allowed: {sorted(_KEYS)}"
        )
    sfile = up.get("structure_file", study.get("structure_file"))
    st = study.get("structure")
    if sfile is None and isinstance(st, Mapping) and "file" in st:
        sfile = st["file"]
    structure_path = None
    if sfile is not None:
        structure_path = (path.parent / str(sfile)).resolve()
        description = _read_toml(structure_path, "structure file")
    elif "structure_key" in up:
        key = up["structure_key"]
        if not isinstance(study.get(key), Mapping):
            raise ConfigError(f"{path}: updating.structure_key = {key!r} names no table")
        description = dict(study[key])
    else:
        description = {k: v for k, v in study.items() if k not in STUDY_TABLES}
    params = up.get("parameters")
    if not isinstance(params, list) or not params:
        raise ConfigError(f"{path}: updating.parameters must be a non-empty list of tables")
    for i, p in enumerate(params):
        if isinstance(p, Mapping) and isinstance(p.get("path"), str) and "initial" in p:
            _create_missing(description, p["path"], p["initial"],
                            f"{path}: updating.parameters[{i}]")
    if ("targets" in up) == ("targets_hz" in up):
        raise ConfigError(
            f"{path}: give exactly one of updating.targets (tables) or updating.targets_hz "
            "(frequencies in Hz)"
        )
    if "targets_hz" in up:
        hz = up["targets_hz"]
        if not isinstance(hz, list) or not hz:
            raise ConfigError(f"{path}: updating.targets_hz must be a non-empty list of Hz")
        targets = [{"fn_hz": f, "label": f"f{i + 1}"} for i, f in enumerate(hz)]
    else:
        targets = up["targets"]
        if not isinstance(targets, list) or not targets:
            raise ConfigError(f"{path}: updating.targets must be a non-empty list of tables")
    kwargs: dict[str, Any] = {
        "description": description,
        "parameters": [
            Parameter.from_dict(p, f"{path}: updating.parameters[{i}]")
            for i, p in enumerate(params)
        ],
        "targets": [
            FrequencyTarget.from_dict(t, f"{path}: updating.targets[{i}]")
            for i, t in enumerate(targets)
        ],
        "structure_path": structure_path,
    }
    if "builder" in up:
        kwargs["builder"] = _builder(up["builder"])
    for key in ("n_modes", "regularization", "mac_weight", "max_iter", "frequency_std"):
        if key in up:
            kwargs[key] = up[key]
    return kwargs


def _format_tables(result) -> str:
    import pandas as pd

    with pd.option_context("display.width", 160, "display.max_columns", 20):
        parts = [
            f"converged: {result.success} ({result.message}); evaluations "
            f"{result.n_evaluations}, identifiable: {result.identifiable}",
            "", "Residuals", result.residual_table().to_string(),
            "", "Parameters", result.parameter_table().to_string(),
            "", "Unpaired model modes", result.unpaired_table().to_string(),
        ]
    if result.swaps:
        parts += ["", f"Mode-pairing swaps: {list(result.swaps)}"]
    return "\n".join(parts)


def run_update(args: argparse.Namespace) -> int:
    """Entry point of ``mvtk update``; returns the exit code (0 ok, 1 not converged)."""
    from ._update import update

    kwargs = load_study(args.study)
    kwargs.pop("structure_path")
    if args.max_iter is not None:
        kwargs["max_iter"] = args.max_iter
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = update(**kwargs)
    notes = [f"{w.category.__name__}: {w.message}" for w in caught]
    if args.out is not None:
        result.write_toml(args.out)
    if args.json:
        out = result.to_dict()
        out["warnings"] = notes
        if args.out is not None:
            out["updated_structure"] = str(args.out)
        json.dump(out, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(_format_tables(result))
        for n in notes:
            print(f"warning: {n}", file=sys.stderr)
        if args.out is not None:
            print(f"updated structure written to {args.out}")
    return 0 if result.success else 1


def add_parser(subparsers) -> None:
    """Register ``mvtk update`` on an argparse sub-parser collection."""
    p = subparsers.add_parser(
        "update",
        help="update FE model parameters to measured natural frequencies",
        description="Update the structure of STUDY.toml to the targets of its [updating] "
        "section and print the residual, parameter and unpaired-mode tables.",
    )
    p.add_argument("study", type=Path, help="study TOML with an [updating] table")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--out", type=Path, default=None, help="write the updated structure TOML")
    p.add_argument("--max-iter", type=int, default=None, help="override updating.max_iter")
    p.set_defaults(func=run_update)
