"""Stage cache: each stage's result stored in ``out_dir/cache`` under a hash of its inputs.

A stage result is a JSON-serialisable dict plus, optionally, an ``xarray.Dataset`` of
arrays (netCDF). The key is the SHA-256 of the canonical JSON of everything the stage
depends on (its config section, the keys of the upstream stages, input-file hashes and
the mvtk version and a hash of the source code of the subpackages it uses), so changing a
controller gain reruns only the control stage.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["stage_key", "code_hash", "StageCache", "to_jsonable"]


def to_jsonable(obj: Any) -> Any:
    """Recursively convert numpy scalars/arrays, tuples and paths to JSON types."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.bool_):
        return bool(obj)
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.floating):
        return float(obj)
    if isinstance(obj, Path):
        return str(obj)
    return obj


def code_hash(*subpackages: str) -> str:
    """SHA-256 (first 16 hex) of the source of mvtk subpackages or modules.

    ``subpackages`` are paths relative to the ``mvtk`` folder: ``"fe"`` (every ``.py``
    below it) or ``"study/_stages.py"`` (one file).

    Part of every stage key, so that editing the code of a stage (in a development
    install) invalidates its cached results, not only a version bump.
    """
    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256()
    for sub in sorted(subpackages):
        base = root / sub
        if base.is_dir():
            files = sorted(base.rglob("*.py"))
        else:
            files = [base if sub.endswith(".py") else root / f"{sub}.py"]
        for f in files:
            if f.is_file():
                h.update(str(f.relative_to(root)).encode())
                h.update(f.read_bytes())
    return h.hexdigest()[:16]


def stage_key(*parts: Any) -> str:
    """SHA-256 (hex, first 16 characters) of the canonical JSON of ``parts``."""
    text = json.dumps(to_jsonable(list(parts)), sort_keys=True, allow_nan=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


class StageCache:
    """Load or compute stage results in ``directory``.

    Files: ``<stage>.json`` (``{"key": ..., "result": ...}``) and ``<stage>.nc`` (arrays).
    A stage whose key matches is loaded; otherwise computed and stored (replacing the
    previous entry of that stage).
    """

    def __init__(self, directory: str | Path, enabled: bool = True) -> None:
        self.directory = Path(directory)
        self.enabled = enabled
        self.hits: list[str] = []
        self.misses: list[str] = []

    def get(self, stage: str, key: str, compute: Callable[[], tuple[dict, Any]]):
        """Return ``(result_dict, dataset_or_None)`` for ``stage`` with ``key``."""
        import xarray as xr

        js = self.directory / f"{stage}.json"
        nc = self.directory / f"{stage}.nc"
        if self.enabled and js.is_file():
            try:
                stored = json.loads(js.read_text(encoding="utf-8"))
            except json.JSONDecodeError:
                stored = {}
            if stored.get("key") == key:
                ds = None
                if stored.get("has_arrays"):
                    with xr.open_dataset(nc, engine="h5netcdf") as f:
                        ds = f.load()
                self.hits.append(stage)
                return stored["result"], ds
        result, ds = compute()
        self.misses.append(stage)
        self.directory.mkdir(parents=True, exist_ok=True)
        if ds is not None:
            ds.to_netcdf(nc, engine="h5netcdf")
        elif nc.exists():
            nc.unlink()
        js.write_text(json.dumps({"key": key, "has_arrays": ds is not None,
                                  "result": to_jsonable(result)}, indent=1,
                                 allow_nan=True), encoding="utf-8")
        return to_jsonable(result), ds
