"""Provenance of a report: versions, input file hashes, parameters, date."""

from __future__ import annotations

import datetime as _dt
import hashlib
import platform
import sys
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from ..errors import ParameterError

__all__ = ["Provenance", "file_sha256", "collect_provenance"]


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
        mvtk, python, numpy, scipy, pandas, xarray, matplotlib versions and the platform.
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


def collect_provenance(
    inputs: Iterable[str | Path] = (),
    parameters: Mapping[str, Any] | None = None,
    *,
    now: _dt.datetime | None = None,
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
    """
    rows = []
    for p in inputs:
        path = Path(p)
        rows.append({"path": str(path), "bytes": path.stat().st_size if path.is_file() else -1,
                     "sha256": file_sha256(path)})
    import mvtk

    versions = {
        "mvtk": mvtk.__version__,
        "python": sys.version.split()[0],
        "platform": platform.platform(),
    }
    for mod in ("numpy", "scipy", "pandas", "xarray", "matplotlib"):
        versions[mod] = _version(mod)
    stamp = (now or _dt.datetime.now(_dt.UTC)).astimezone(_dt.UTC)
    return Provenance(
        created_utc=stamp.isoformat(timespec="seconds"),
        versions=versions,
        inputs=pd.DataFrame(rows, columns=["path", "bytes", "sha256"]),
        parameters=dict(parameters or {}),
    )
