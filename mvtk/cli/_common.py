"""Helpers every command module shares: reader options, output-path checks, the JSON
document of a command and :func:`run_view` (the stages a command needs, through the one
cached study pipeline)."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ConfigError, MvtkError

__all__ = ["run_view", "json_document", "json_clean", "check_output_file", "refuse_inputs",
           "study_inputs", "refuse_study_as_data",
           "add_cache_argument", "StageError", "SCHEMA_VERSIONS", "parse_option",
           "add_reader_options", "reader_options"]

#: Version of the JSON output of each command (``schemas/<command>.schema.json``).
SCHEMA_VERSIONS = {"run": "mvtk.run/1", "update": "mvtk.update/1", "reduce": "mvtk.reduce/1",
                   "control": "mvtk.control/1"}


class StageError(MvtkError, RuntimeError):
    """A pipeline stage a command needs failed or could not run."""


def json_clean(obj: Any) -> Any:
    """JSON-safe copy: numpy scalars/arrays to Python, NaN and +-inf to None."""
    if isinstance(obj, dict):
        return {str(k): json_clean(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_clean(obj.tolist())
    if isinstance(obj, np.generic):
        return json_clean(obj.item())
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, Path):
        return str(obj)
    return obj


def json_document(command: str, study: str | Path, body: dict) -> str:
    """The ``--json`` text of ``command``: ``schema_version``, ``study`` and ``body``."""
    doc = {"schema_version": SCHEMA_VERSIONS[command], "study": str(study), **body}
    return json.dumps(json_clean(doc), indent=2, allow_nan=False)


def check_output_file(path: str | Path, option: str) -> Path:
    """Prove that ``path`` can be written (folder exists and is writable), before work.

    Raises
    ------
    ConfigError
        Naming the option, the path and what is wrong.
    """
    p = Path(path)
    if p.is_dir():
        raise ConfigError(f"{option} {str(p)!r} is a folder, expected a file name")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        what = "is not a folder" if parent.exists() else "does not exist"
        raise ConfigError(f"{option} {str(p)!r}: the folder {str(parent)!r} {what}")
    try:
        fd, probe = tempfile.mkstemp(prefix=".mvtk-write-test-", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as err:
        raise ConfigError(f"{option} {str(p)!r}: cannot write in {str(parent)!r} "
                          f"({err.strerror or err})") from None
    return p


def refuse_inputs(outputs, inputs) -> None:
    """Refuse every output path that is one of the input files (before any work).

    Parameters
    ----------
    outputs : iterable of (str, path)
        ``(option, path)`` of each output file (``path`` None: not requested).
    inputs : iterable of path
        Every file the command reads.

    Raises
    ------
    OutputError
        Naming the option, the output and the input it would replace (symlinks and hard
        links followed); no option lifts this.
    """
    from .._atomic import refuse_input, same_file

    inputs = [p for p in inputs if p is not None]
    given = [(opt, p) for opt, p in outputs if p is not None]
    for opt, p in given:
        refuse_input(p, inputs, opt)
    for i, (opt_a, a) in enumerate(given):
        for opt_b, b in given[i + 1:]:
            if same_file(a, b):
                from ..errors import OutputError

                raise OutputError(f"{opt_a} and {opt_b} name one file {str(a)!r}: give "
                                  "each output its own path")


def study_inputs(study_path) -> list[Path]:
    """Every file a study reads (:attr:`mvtk.study.Study.input_files`)."""
    from ..study import load_study

    return list(load_study(study_path).input_files)


def refuse_study_as_data(paths, command: str) -> None:
    """A study TOML given where a measurement file is expected: a one-line error naming
    the study's measurement files and ``mvtk run``, instead of a reader's "no numeric
    data" (the study's own stages run those files with the study's settings)."""
    from ..errors import ConfigError

    for path in paths:
        p = Path(path)
        if p.suffix.lower() != ".toml" or not p.is_file():
            continue
        from ..study._text import read_toml

        try:
            cfg = read_toml(p, "study file")
        except Exception:  # not a readable TOML: the reader's own error says why
            continue
        if "study" not in cfg:
            continue
        data = [str(f) for f in study_inputs(p) if f.suffix.lower() != ".toml"]
        raise ConfigError(
            f"{p} is a study, not a measurement file: `mvtk {command}` reads a "
            f"measurement file, e.g. one the study uses ({', '.join(data[:4]) or 'none'})"
            f"; `mvtk run {p} --out DIR` runs every stage of the study")


def add_cache_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--cache", default=None, metavar="DIR",
                   help="output folder whose stage cache is used and updated (e.g. the "
                   "--out of `mvtk run`; default: a temporary folder)")


def waiting(message: str) -> None:
    print(f"mvtk: {message}", file=sys.stderr)


def run_view(study_path, stages, cache_dir=None, overrides: dict | None = None):
    """Run the pipeline stages a command needs (with their cache) and return the result.

    Parameters
    ----------
    study_path : path
        Study TOML (the one schema of :mod:`mvtk.study`).
    stages : sequence of str
        The stages whose results the command prints.
    cache_dir : path, optional
        Output folder holding the cache; default a temporary folder.
    overrides : dict, optional
        ``{(section, key): value}`` set in the study before running (command options
        such as ``--max-iter``); they enter the stage keys like any other read.

    Raises
    ------
    StageError
        A requested stage failed or could not run; the message says why.
    """
    from ..study import load_study, run
    from ..study._run import check_output_dir

    study = load_study(study_path)
    if overrides:
        cfg = {k: (dict(v) if isinstance(v, dict) else v) for k, v in study.config.items()}
        for (section, key), value in overrides.items():
            cfg.setdefault(section, {})[key] = value
        study = dataclasses.replace(study, config=cfg)
    with contextlib.ExitStack() as stack:
        if cache_dir is None:
            cache_dir = stack.enter_context(tempfile.TemporaryDirectory(prefix="mvtk-"))
        else:
            check_output_dir(cache_dir)
        res = run(study, cache_dir, report=False, progress=False, stages=stages,
                  on_wait=waiting)
    for s in stages:
        if s in res.failed:
            raise StageError(f"stage {s} failed: {res.failed[s]}")
        if s not in res.results:
            why = res.unavailable.get(s, "did not run")
            # the upstream stage that failed is the useful message
            up = "; ".join(f"stage {k} failed: {v}" for k, v in res.failed.items())
            raise StageError(f"stage {s} not available: {why}" + (f" ({up})" if up else ""))
    return res


def parse_option(text: str) -> tuple[str, object]:
    """``"key=value"`` -> (key, value); the value is JSON when it parses, else a string."""
    key, sep, value = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected key=value, got {text!r}")
    try:
        return key, json.loads(value)
    except json.JSONDecodeError:
        return key, value


def add_reader_options(parser: argparse.ArgumentParser) -> None:
    """Add the reader options group shared by ``mvtk read``, ``damping`` and ``modal``.

    Every option of :func:`mvtk.io.read` is reachable as ``--set KEY=VALUE``; the common
    ones (the ones a reader's error message asks for when a file does not state them)
    have their own flags: ``--units``, ``--quantity``, ``--fs`` and ``--variable``
    (the reader option ``data=``).
    """
    rd = parser.add_argument_group("reader options (mvtk.io.read)")
    rd.add_argument("--format", default=None, help="force a reader (default: detect)")
    rd.add_argument("--set", action="append", type=parse_option, metavar="KEY=VALUE",
                    help="reader option, value as JSON or text (repeatable), e.g. "
                    "--set units='[\"N\", \"m/s^2\"]'")
    rd.add_argument("--variable", nargs="+", default=None, metavar="NAME",
                    help="variable(s) of the file holding the data (reader option data=)")
    rd.add_argument("--units", nargs="+", default=None, metavar="UNIT",
                    help="units per channel, for files that store none (reader option "
                    "units=), e.g. --units N m/s^2 V")
    rd.add_argument("--quantity", nargs="+", default=None, metavar="Q",
                    help="quantity per channel, e.g. force acceleration (reader option "
                    "quantity=)")
    rd.add_argument("--fs", type=float, default=None, metavar="HZ",
                    help="sampling rate in Hz, for files that store none (reader option fs=)")


def reader_options(args: argparse.Namespace) -> dict:
    """The keyword arguments of :func:`mvtk.io.read` given by :func:`add_reader_options`.

    The named flags win over the same key given with ``--set``; ``format`` is included
    when given.
    """
    opts = dict(args.set or [])
    for key, val in (("units", args.units), ("quantity", args.quantity), ("fs", args.fs)):
        if val is not None:
            opts[key] = val
    if args.variable is not None:
        opts["data"] = args.variable[0] if len(args.variable) == 1 else args.variable
    if args.format is not None:
        opts["format"] = args.format
    return opts




def spare_dask_probe() -> None:
    """Keep xarray from importing dask in a command that never makes a dask array.

    When dask is installed (the ``scale`` extra), xarray imports ``dask.array`` on the
    first DataArray it builds, to test whether the data is a dask array: 1.2-1.3 s of a
    2-s ``mvtk read``. ``read``, ``damping`` and ``modal`` hold every array in memory, so
    they record in xarray's duck-array table that dask arrays are not in use in this
    process. A no-op when dask is already imported or when xarray's table is not where
    this xarray version keeps it (the command is then only slower).
    """
    if "dask" in sys.modules:
        return
    try:
        from xarray.namedarray import pycompat

        entry = object.__new__(pycompat.DuckArrayModule)
        entry.module, entry.version, entry.type, entry.available = (
            None, pycompat.Version("0.0.0"), (), False)
        pycompat._cached_duck_array_modules.setdefault("dask", entry)
    except (ImportError, AttributeError, TypeError):  # another xarray layout
        return
