"""``mvtk run STUDY.toml --out DIR``: run a validation study and write its report.

Also the helpers every study command shares: :func:`run_view` (run the stages a
command needs through the one cached pipeline), :func:`json_document` (the versioned
JSON output, schemas in ``schemas/``) and the output-path checks done before any work.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ConfigError, MvtkError

__all__ = ["add_parser", "run_view", "json_document", "json_clean", "check_output_file",
           "add_cache_argument", "StageError", "SCHEMA_VERSIONS"]

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


def add_cache_argument(p: argparse.ArgumentParser) -> None:
    p.add_argument("--cache", default=None, metavar="DIR",
                   help="output folder whose stage cache is used and updated (e.g. the "
                   "--out of `mvtk run`; default: a temporary folder)")


def _waiting(message: str) -> None:
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
    from .study import load_study, run
    from .study._run import check_output_dir

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
                  on_wait=_waiting)
    for s in stages:
        if s in res.failed:
            raise StageError(f"stage {s} failed: {res.failed[s]}")
        if s not in res.results:
            why = res.unavailable.get(s, "did not run")
            # the upstream stage that failed is the useful message
            up = "; ".join(f"stage {k} failed: {v}" for k, v in res.failed.items())
            raise StageError(f"stage {s} not available: {why}" + (f" ({up})" if up else ""))
    return res


def _run(args: argparse.Namespace) -> int:
    from .study import run, study_checks

    t0 = time.perf_counter()
    res = run(args.study, args.out, use_cache=not args.no_cache,
              progress=None if not args.quiet else False, on_wait=_waiting)
    dt = time.perf_counter() - t0
    checks = study_checks(res) if res.results else []
    failed_checks = [c for c in checks if not c.passed]
    if args.json:
        from .validation import check_table

        stages = res.to_dataframe().to_dict(orient="records")
        table = check_table(checks).to_dict(orient="records") if checks else []
        sys.stdout.write(json_document("run", args.study, {
            "report": str(res.report_path) if res.report_path else None,
            "time_s": dt, "cached_stages": list(res.cache_hits),
            "stages": stages, "checks": table,
            "passed": res.ok and not failed_checks}) + "\n")
    for stage, reason in res.unavailable.items():
        print(f"mvtk run: stage {stage} not available: {reason}", file=sys.stderr)
    for stage, reason in res.failed.items():
        print(f"mvtk run: stage {stage} FAILED: {reason}", file=sys.stderr)
    for c in failed_checks:
        print(f"mvtk run: check FAILED: {c.name}: {c.value:.6g} vs {c.reference:.6g} "
              f"{c.unit}".rstrip(), file=sys.stderr)
    if res.report_path is not None and not args.json:
        print(f"report: {res.report_path} ({dt:.1f} s; cached stages: "
              f"{', '.join(res.cache_hits) or 'none'})")
    if args.pdf and res.report_path is not None:
        from .report import to_pdf

        pdf = to_pdf(res.report_path)
        if not args.json:
            print(f"pdf: {pdf}")
    if res.failed:
        return 2
    return 1 if failed_checks else 0


def add_parser(subparsers) -> None:
    """Register ``mvtk run``."""
    p = subparsers.add_parser(
        "run", help="run a validation study (TOML) and write the HTML report",
        description="Run every stage of a study (cached in OUT/cache) and write the HTML "
        "report. Exit status: 0 all checks passed, 1 a check failed, 2 an error (bad "
        "input, a failed stage), 130 interrupted.",
    )
    p.add_argument("study", help="study TOML file, e.g. data/smart_beam/study.toml")
    p.add_argument("--out", required=True, help="output folder (index.html, tables/, cache/)")
    p.add_argument("--no-cache", action="store_true", help="recompute every stage")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--json", action="store_true",
                   help="print the stage and check tables as JSON (schemas/run.schema.json)")
    p.add_argument("--pdf", action="store_true",
                   help="also print the report to DIR/report.pdf with headless Chromium "
                   "(Debian package chromium)")
    p.set_defaults(func=_run)
