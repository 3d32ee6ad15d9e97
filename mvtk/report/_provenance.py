"""Provenance of a report: versions, input file hashes, parameters, date."""

from __future__ import annotations

import datetime as _dt
import hashlib
import os
import platform
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from ..errors import ParameterError

__all__ = ["Provenance", "file_sha256", "collect_provenance", "relative_path", "command_line"]


def file_sha256(path: str | Path, chunk_size: int = 1 << 20) -> str:
    """SHA-256 hex digest of the file at ``path``.

    Raises
    ------
    ParameterError
        If ``path`` is not an existing file.
    """
    p = Path(path)
    if not p.is_file():
        raise ParameterError(f"cannot hash {str(p)!r}: not an existing file")
    h = hashlib.sha256()
    with p.open("rb") as fh:
        for block in iter(lambda: fh.read(chunk_size), b""):
            h.update(block)
    return h.hexdigest()


def _version(module: str) -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(module)
    except PackageNotFoundError:
        return "not installed"


@dataclass(frozen=True)
class Provenance:
    """Where a report's numbers come from.

    Attributes
    ----------
    created_utc : str
        ISO 8601 UTC time stamp of the run.
    versions : dict of str to str
        mvtk, python, numpy, scipy, pandas, xarray, matplotlib versions, the platform
        and the sparse solver of the FE stages (:func:`mvtk.fe.sparse_backend`).
    inputs : DataFrame
        One row per input file: ``path, bytes, sha256``.
    parameters : dict
        The parameters the run used (e.g. the parsed study TOML).
    """

    created_utc: str
    versions: Mapping[str, str]
    inputs: pd.DataFrame
    parameters: Mapping[str, Any] = field(default_factory=dict)

    def to_dataframe(self) -> pd.DataFrame:
        """Versions and date as a two-column table (``item, value``)."""
        rows = [("created (UTC)", self.created_utc)] + list(self.versions.items())
        return pd.DataFrame(rows, columns=["item", "value"])


def relative_path(path: str | Path, base: str | Path | None) -> str:
    """``path`` as written in a report: relative to ``base`` (POSIX separators), never
    an absolute path of the machine that ran it (outside ``base``: ``.../name``).

    Examples
    --------
    >>> relative_path("/data/lab/study/impact.csv", "/data/lab/study")
    'impact.csv'
    >>> relative_path("/data/lab/structures/plate.toml", "/data/lab/study")
    '../structures/plate.toml'
    >>> relative_path("/tmp/out", "/data/lab/study")
    '.../out'
    """
    p = Path(path)
    if not p.is_absolute():
        return p.as_posix()
    if base is not None:
        b = Path(base).resolve()
        rel = Path(os.path.relpath(p.resolve(), b))
        # at most two levels up stays readable and says where the file is; further up
        # would spell out the machine's folders
        if rel.parts[:3] != ("..", "..", "..") and not rel.is_absolute():
            return rel.as_posix()
    return f".../{p.name}"


def _git_commit(path: Path) -> str:
    """Commit of the git checkout holding ``path`` (``+ local changes`` when the tracked
    files differ from it); "not a git checkout" otherwise."""
    import subprocess

    try:
        head = subprocess.run(["git", "-C", str(path), "rev-parse", "HEAD"],
                              capture_output=True, text=True, timeout=10, check=False)
        if head.returncode != 0:
            return "not a git checkout"
        dirty = subprocess.run(["git", "-C", str(path), "status", "--porcelain", "-uno"],
                               capture_output=True, text=True, timeout=20, check=False)
    except (OSError, subprocess.SubprocessError):
        return "not a git checkout"
    commit = head.stdout.strip()
    return commit + (" + local changes" if dirty.stdout.strip() else "")


def command_line(argv: Iterable[str] | None = None, base: str | Path | None = None) -> str:
    """The command that made the report (``sys.argv`` by default), its absolute paths
    written relative to ``base`` (:func:`relative_path`)."""
    import shlex

    args = list(sys.argv if argv is None else argv)
    if not args:
        return "–"
    first = Path(args[0])
    if first.name == "mvtk" or (first.name == "__main__.py" and first.parent.name == "mvtk"):
        args[0] = "mvtk"
    elif argv is None:
        # mvtk called from another program (a script, a notebook, a test runner): its
        # command line is not the one that made the report, only its name is recorded
        prog = first.parent.name if first.name == "__main__.py" else first.name
        return f"mvtk called from Python ({prog or 'interactive'})"
    return " ".join(shlex.quote(relative_path(a, base) if a.startswith("/") else a)
                    for a in args)


def collect_provenance(
    inputs: Iterable[str | Path] = (),
    parameters: Mapping[str, Any] | None = None,
    *,
    now: _dt.datetime | None = None,
    base: str | Path | None = None,
    command: Iterable[str] | None = None,
) -> Provenance:
    """Collect versions, input-file SHA-256 hashes, parameters and the UTC date.

    Parameters
    ----------
    inputs : iterable of path
        Files the results depend on; each must exist.
    parameters : mapping, optional
        Parameters to record (must be JSON-serialisable for the HTML report).
    now : datetime, optional
        Time stamp to record (default: the current UTC time).
    base : path, optional
        Folder the input paths and the command line are written relative to (e.g. the
        study file's folder); no absolute path of the machine appears in the record.
    command : list of str, optional
        The command line (default ``sys.argv``).
    """
    rows = []
    for p in inputs:
        path = Path(p)
        rows.append({"path": relative_path(path, base),
                     "bytes": path.stat().st_size if path.is_file() else -1,
                     "sha256": file_sha256(path)})
    import mvtk

    versions = {
        "mvtk": mvtk.__version__,
        "mvtk git commit": _git_commit(Path(mvtk.__file__).resolve().parent),
        "command line": command_line(command, base),
        "python": sys.version.split()[0],
        "platform": platform.platform(),
    }
    for mod in ("numpy", "scipy", "pandas", "xarray", "matplotlib"):
        versions[mod] = _version(mod)
    from ..fe import sparse_backend

    # the factorisation (and, for CHOLMOD, its BLAS) behind every FE figure and timing
    versions["sparse solver (FE)"] = sparse_backend(detail=True)
    stamp = (now or _dt.datetime.now(_dt.UTC)).astimezone(_dt.UTC)
    return Provenance(
        created_utc=stamp.isoformat(timespec="seconds"),
        versions=versions,
        inputs=pd.DataFrame(rows, columns=["path", "bytes", "sha256"]),
        parameters=dict(parameters or {}),
    )
