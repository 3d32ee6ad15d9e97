"""The manifest of a run's output folder: what the run wrote, with SHA-256 hashes.

``mvtk run`` writes ``OUT/manifest.json`` last, after the page, the tables and the stage
cache: every file it claims with its size and SHA-256. :func:`verify_manifest` (used by
``mvtk report``) recomputes them, so a page cut short by a full disk, a table edited by
hand or a cache file replaced is found before a verdict is printed.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

from .._atomic import TEMP_SUFFIX, write_text
from ..errors import FormatError

__all__ = ["MANIFEST", "write_manifest", "verify_manifest"]

#: File name of the manifest in the output folder.
MANIFEST = "manifest.json"
_SCHEMA = "mvtk.manifest/1"


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _claimed(out: Path, page: Path) -> list[Path]:
    files = [page]
    for sub, pattern in (("tables", "*.csv"), ("cache", "*.json"), ("cache", "*.nc")):
        folder = out / sub
        if folder.is_dir():
            files += sorted(p for p in folder.glob(pattern)
                            if p.is_file() and not p.name.startswith(".")
                            and not p.name.endswith(TEMP_SUFFIX))
    return files


def write_manifest(out_dir: str | Path, page: str | Path) -> Path:
    """Write ``out_dir/manifest.json``: size and SHA-256 of the page, tables and cache.

    Parameters
    ----------
    out_dir : path
        The run's output folder.
    page : path
        The report page just written (``out_dir/index.html``).

    Returns
    -------
    Path
        The manifest file (written atomically).
    """
    out = Path(out_dir)
    files = {}
    for p in _claimed(out, Path(page)):
        files[p.relative_to(out).as_posix()] = {"bytes": p.stat().st_size,
                                                "sha256": _sha256(p)}
    doc = {"schema": _SCHEMA, "files": files}
    return write_text(out / MANIFEST, json.dumps(doc, indent=1, sort_keys=True) + "\n")


def verify_manifest(out_dir: str | Path) -> int:
    """Check every file ``out_dir/manifest.json`` claims; return how many were checked.

    Raises
    ------
    FormatError
        The manifest is unreadable, or a claimed file is missing, of another size or
        another SHA-256; the message names the file and what differs.
    FileNotFoundError
        There is no manifest.
    """
    out = Path(out_dir)
    path = out / MANIFEST
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        files = doc["files"]
        if doc.get("schema") != _SCHEMA or not isinstance(files, dict):
            raise KeyError("schema")
    except FileNotFoundError:
        raise
    except (OSError, ValueError, KeyError, TypeError) as err:
        raise FormatError(f"{path}: not a readable mvtk manifest ({type(err).__name__}: "
                          f"{err}); rerun `mvtk run` to rewrite the folder") from None
    for rel, want in sorted(files.items()):
        p = out / rel
        if not p.is_file():
            raise FormatError(f"{p}: listed in {path} but missing; the folder is not the "
                              "one the run wrote (rerun `mvtk run`)")
        size = p.stat().st_size
        if size != want.get("bytes"):
            raise FormatError(f"{p}: {size} bytes, the run wrote {want.get('bytes')} "
                              f"(manifest {path}): cut short or changed since; rerun "
                              "`mvtk run`")
        if _sha256(p) != want.get("sha256"):
            raise FormatError(f"{p}: content differs from what the run wrote (SHA-256 "
                              f"mismatch with {path}): changed since; rerun `mvtk run`")
    return len(files)
