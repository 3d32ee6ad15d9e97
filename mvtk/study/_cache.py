"""Stage cache: each stage's result stored in ``out_dir/cache`` under a key of what it read.

A stage result is a JSON-serialisable dict plus, optionally, an ``xarray.Dataset`` of
arrays (netCDF). The key of a stage cannot drift from what the stage uses, because it is
*derived from what the stage actually read*:

- a base key: the stage name, the mvtk version, a hash of the source of the subpackages
  it uses (:func:`code_hash`) and the keys of the upstream stages it consumes;
- the study inputs the stage read during its last computation, recorded by a
  :class:`ReadTracker` (stages see the study through :class:`TrackedStudy`, whose config
  sections are read-only views that record every key looked up, every table iterated,
  and the structure description or measurement files used).

On a later run the recorded paths are evaluated against the current study; the entry is
reused only when the base key and every recorded value are unchanged. This is dynamic
dependency tracking: a key the stage did not read cannot invalidate it, and a key it
did read always does, including keys it found absent.

Entries are verified on load: the ``.json`` sidecar holds the SHA-256 of its result and
of the ``.nc`` arrays. A damaged, missing or half-written entry is recomputed with a
:class:`CacheWarning` naming the file. Writes are atomic (temporary file, then
``os.replace``), and :class:`OutputLock` serialises concurrent runs into one folder.
"""

from __future__ import annotations

import contextlib
import copy
import hashlib
import json
import os
import time
import warnings
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .._atomic import atomic_path, write_bytes
from ..errors import MvtkError, MvtkWarning
from ..io._netcdf import write_h5netcdf

__all__ = ["stage_key", "code_hash", "StageCache", "to_jsonable", "ReadTracker",
           "TrackedStudy", "CacheWarning", "OutputLock", "OutputBusyError"]


class CacheWarning(MvtkWarning):
    """A cache entry was damaged or incomplete and is recomputed (the message names it)."""


class OutputBusyError(MvtkError, RuntimeError):
    """Another mvtk run holds the lock of the output folder."""


def to_jsonable(obj: Any) -> Any:
    """Recursively convert numpy scalars/arrays, tuples and paths to JSON types."""
    if isinstance(obj, Mapping):
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


def _canonical(obj: Any) -> str:
    return json.dumps(to_jsonable(obj), sort_keys=True, allow_nan=True)


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
            digest = _source_digest(f)
            if digest is not None:
                h.update(str(f.relative_to(root)).encode())
                h.update(digest)
    return h.hexdigest()[:16]


#: SHA-256 of each source file read by :func:`code_hash`, by path, with the
#: ``(mtime_ns, size, inode)`` it had: every stage key hashes the same files again.
_SOURCE_DIGESTS: dict[Path, tuple[tuple[int, int, int], bytes]] = {}


def _source_digest(path: Path) -> bytes | None:
    """SHA-256 of a source file (None if it is not a file), re-read when it changed."""
    try:
        st = path.stat()
    except OSError:
        return None
    if not path.is_file():
        return None
    stamp = (st.st_mtime_ns, st.st_size, st.st_ino)
    known = _SOURCE_DIGESTS.get(path)
    if known is None or known[0] != stamp:
        known = (stamp, hashlib.sha256(path.read_bytes()).digest())
        _SOURCE_DIGESTS[path] = known
    return known[1]


def stage_key(*parts: Any) -> str:
    """SHA-256 (hex, first 16 characters) of the canonical JSON of ``parts``."""
    return hashlib.sha256(_canonical(list(parts)).encode("utf-8")).hexdigest()[:16]


def _file_sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


# ----------------------------------------------------------------------- array files
#: Datasets up to this size (bytes) whose variables netCDF3 holds exactly are written
#: as netCDF3 (scipy's pure-Python writer: 5-20x less CPU than HDF5 for the study's
#: small datasets, measured 0.08 s against 0.83 s for the 7 arrays of a smart-beam run);
#: larger ones, and complex or 64-bit integer values netCDF3 cannot hold, as netCDF4/HDF5.
NETCDF3_MAX_BYTES = 256 * 2**20
#: Global attributes that restore the dtypes netCDF3 changes (int64 stored as int32,
#: fixed-width unicode read back as Python str objects).
_INT64_ATTR, _UNICODE_ATTR = "_mvtk_int64", "_mvtk_unicode"


def _netcdf3_holds(ds) -> bool:
    """True when every variable of ``ds`` round-trips exactly through netCDF3."""
    if ds.nbytes > NETCDF3_MAX_BYTES or _INT64_ATTR in ds.attrs or _UNICODE_ATTR in ds.attrs:
        return False
    for var in ds.variables.values():
        kind, size = var.dtype.kind, var.dtype.itemsize
        if kind == "i" and size == 8:
            if var.size and (var.values.min() < -2**31 or var.values.max() >= 2**31):
                return False
        elif not (kind in "fU" or (kind == "i" and size <= 4)):
            return False   # complex, unsigned, bool, bytes, objects, datetimes
        if var.encoding.get("dtype") is not None:
            return False
    return True


def _write_arrays(ds, path: Path) -> None:
    """Write ``ds`` to ``path``: netCDF3 when it holds ``ds`` exactly, else netCDF4."""
    if _netcdf3_holds(ds):
        out = ds.copy(deep=False)
        names = {str(k): v.dtype for k, v in ds.variables.items()}
        out.attrs[_INT64_ATTR] = json.dumps([k for k, d in names.items() if d == np.int64])
        out.attrs[_UNICODE_ATTR] = json.dumps([k for k, d in names.items() if d.kind == "U"])
        try:
            out.to_netcdf(path, engine="scipy", format="NETCDF3_64BIT")
            return
        except (ValueError, TypeError, OverflowError):
            with contextlib.suppress(OSError):
                path.unlink()
    write_h5netcdf(ds, path)


def _read_arrays(path: Path):
    """The dataset written by :func:`_write_arrays` (either format), loaded in memory."""
    import xarray as xr

    with open(path, "rb") as fh:
        magic = fh.read(4)
    engine = "scipy" if magic[:3] == b"CDF" else "h5netcdf"
    with xr.open_dataset(path, engine=engine) as f:
        ds = f.load()
    if engine == "scipy":
        restore = {name: np.int64 for name in json.loads(ds.attrs.pop(_INT64_ATTR, "[]"))}
        restore.update({name: str for name in json.loads(ds.attrs.pop(_UNICODE_ATTR, "[]"))})
        for name, dtype in restore.items():
            value = ds[name].astype(dtype)
            if name in ds.coords:
                ds = ds.assign_coords({name: value})
            else:
                ds[name] = value
    return ds


# ------------------------------------------------------------------------ read tracking
_ABSENT = {"absent": True}


class ReadTracker:
    """Records what a stage reads from a study; evaluates recorded reads later.

    A read is ``(kind, path)``: ``kind`` is ``"value"`` (the value at ``path``, or the
    fact that it is a table or absent), ``"full"`` (the whole subtree, for iteration),
    ``"keys"`` (the key names of a table), ``"truth"`` (whether it is non-empty),
    ``"structure"`` (the structure description), ``"measurement_file"`` (the SHA-256 of
    the file of a test, so a moved copy of the same data still matches),
    ``"extra_file"`` (whether a further input such as ``modal_geometry`` is named),
    ``"extra_file_content"`` (its SHA-256, by name like the measurement files) or
    ``"file"`` (the SHA-256 of a file, ``path`` = its resolved name).
    """

    def __init__(self, study) -> None:
        self.study = study
        self.reads: dict[str, Any] = {}

    def _observe(self, kind: str, path: tuple) -> Any:
        if kind == "file":
            p = Path(path[0])
            return _file_sha256(p) if p.is_file() else _ABSENT
        if kind == "measurement_file":  # by content, wherever the study says it is
            p = self.study.measurement_files.get(path[0])
            if p is None or not p.is_file():
                return _ABSENT
            return {"name": p.name, "sha256": _file_sha256(p)}
        if kind == "structure":
            return to_jsonable(self.study.structure)
        if kind == "extra_file":
            return path[0] in getattr(self.study, "extra_files", {})
        if kind == "extra_file_content":  # by content, wherever the study says it is
            p = getattr(self.study, "extra_files", {}).get(path[0])
            if p is None or not p.is_file():
                return _ABSENT
            return {"name": p.name, "sha256": _file_sha256(p)}
        node: Any = self.study.config
        for part in path:
            if isinstance(node, Mapping) and part in node:
                node = node[part]
            else:
                return _ABSENT
        if kind == "truth":
            return bool(node)
        if kind == "keys":
            return sorted(map(str, node)) if isinstance(node, Mapping) else _ABSENT
        if kind == "full" or not isinstance(node, Mapping):
            return {"value": to_jsonable(node)}
        return {"table": True}

    def record(self, kind: str, path: tuple) -> None:
        tag = json.dumps([kind, list(path)])
        if tag not in self.reads:
            self.reads[tag] = self._observe(kind, path)

    def evaluate(self, reads: Mapping[str, Any]) -> dict[str, Any]:
        """The current values of the reads recorded in ``reads`` (same tags)."""
        out = {}
        for tag in reads:
            kind, path = json.loads(tag)
            out[tag] = self._observe(kind, tuple(path))
        return out


class _View(Mapping):
    """A read-only view of a config table that records the keys looked up."""

    def __init__(self, data: Mapping, path: tuple, tracker: ReadTracker) -> None:
        self._data, self._path, self._tracker = data, path, tracker

    def __getitem__(self, key):
        p = (*self._path, key)
        self._tracker.record("value", p)
        v = self._data[key]
        if isinstance(v, Mapping):
            return _View(v, p, self._tracker)
        return copy.deepcopy(v)

    def get(self, key, default=None):
        if key in self:
            return self[key]
        return default

    def __contains__(self, key) -> bool:
        self._tracker.record("value", (*self._path, key))
        return key in self._data

    def __iter__(self) -> Iterator:
        self._tracker.record("full", self._path)
        return iter(self._data)

    def names(self) -> list:
        """The key names of the table, recorded as names only (iterating records the whole
        subtree: a path written otherwise would then change the stage's key)."""
        self._tracker.record("keys", self._path)
        return list(self._data)

    def __len__(self) -> int:
        self._tracker.record("full", self._path)
        return len(self._data)

    def __bool__(self) -> bool:
        self._tracker.record("truth", self._path)
        return bool(self._data)

    def __repr__(self) -> str:
        return f"_View({'.'.join(map(str, self._path))})"


class TrackedStudy:
    """The interface of :class:`~mvtk.study.Study` that stages use, with reads recorded."""

    def __init__(self, study, tracker: ReadTracker) -> None:
        self._study, self._tracker = study, tracker

    @property
    def path(self) -> Path:
        return self._study.path

    @property
    def name(self) -> str:
        return self._study.name

    @property
    def config(self) -> _View:
        return _View(self._study.config, (), self._tracker)

    def section(self, name: str):
        self._tracker.record("value", (name,))
        s = self._study.config.get(name)
        return None if s is None else _View(s, (name,), self._tracker)

    def description(self) -> dict:
        self._tracker.record("structure", ())
        return self._study.description()

    @property
    def structure_file(self) -> Path | None:
        f = self._study.structure_file
        if f is not None:
            self._tracker.record("file", (str(f),))
        return f

    def has_extra_file(self, name: str) -> bool:
        """Whether the study names the further input file ``name`` (the fact is recorded,
        not the path as written, so a study moved with its files keeps its cache)."""
        self._tracker.record("extra_file", (name,))
        return name in self._study.extra_files

    def extra_file(self, name: str) -> Path:
        """A further input file of the study (e.g. ``"modal_file"``), its content recorded."""
        p = self._study.extra_files[name]
        self._tracker.record("extra_file_content", (name,))
        return p

    @property
    def measurement_files(self) -> dict[str, Path]:
        files = self._study.measurement_files
        self._tracker.record("keys", ("measurements",))
        for test in files:
            self._tracker.record("measurement_file", (test,))
        return dict(files)


# ------------------------------------------------------------------------------ cache
def _atomic_write_bytes(path: Path, data: bytes) -> None:
    write_bytes(path, data)


class StageCache:
    """Load or compute stage results in ``directory``.

    Files: ``<stage>.json`` (base key, recorded reads, full key, result and the
    SHA-256 of the result and of the arrays) and ``<stage>.nc`` (arrays). A stage whose
    base key and recorded reads match is loaded after its checksums are verified;
    otherwise it is computed and stored (replacing the previous entry of that stage).

    Attributes
    ----------
    hits, misses : list of str
        Stages loaded / computed.
    keys : dict of str to str
        Full key (base key + reads) of each stage served; downstream stages use it.
    """

    def __init__(self, directory: str | Path, enabled: bool = True) -> None:
        self.directory = Path(directory)
        self.enabled = enabled
        self.hits: list[str] = []
        self.misses: list[str] = []
        self.keys: dict[str, str] = {}

    def _warn(self, path: Path, what: str) -> None:
        warnings.warn(f"cache entry {path} {what}; recomputing the stage (or rerun with "
                      "--no-cache)", CacheWarning, stacklevel=3)

    def _load(self, stage: str, key: str, tracker: ReadTracker | None):
        """The stored (result, dataset, full key) or None; warns on damage."""
        js = self.directory / f"{stage}.json"
        nc = self.directory / f"{stage}.nc"
        if not js.exists():
            if nc.exists():
                self._warn(nc, "has no .json sidecar (an interrupted write)")
            return None
        try:
            stored = json.loads(js.read_bytes().decode("utf-8"))
            result = stored["result"]
            ok = hashlib.sha256(_canonical(result).encode()).hexdigest() == stored[
                "result_sha256"]
            base, full, reads = stored["base"], stored["key"], stored["reads"]
        except (OSError, ValueError, KeyError, TypeError):
            self._warn(js, "is damaged (not a complete cache sidecar)")
            return None
        if not ok:
            self._warn(js, "does not match its checksum")
            return None
        if base != key:
            return None
        current = tracker.evaluate(reads) if tracker is not None else {}
        if stage_key(base, current) != full:
            return None
        ds = None
        if stored.get("arrays_sha256"):
            try:
                digest = _file_sha256(nc)
            except OSError:
                self._warn(nc, "is missing")
                return None
            if digest != stored["arrays_sha256"]:
                self._warn(nc, "does not match the checksum in its .json sidecar")
                return None
            try:
                ds = _read_arrays(nc)
            except Exception:  # noqa: BLE001 - any unreadable file is recomputed
                self._warn(nc, "cannot be read")
                return None
        return result, ds, full

    def peek(self, stage: str, key: str, tracker: ReadTracker | None = None) -> bool:
        """True when :meth:`get` would load ``stage`` from the cache (no warnings here)."""
        if not self.enabled:
            return False
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return self._load(stage, key, tracker) is not None

    def get(self, stage: str, key: str, compute: Callable[[], tuple[dict, Any]],
            tracker: ReadTracker | None = None):
        """Return ``(result_dict, dataset_or_None)`` for ``stage`` with base ``key``.

        ``tracker`` records what ``compute`` reads; its reads become part of the key.
        """
        if self.enabled:
            loaded = self._load(stage, key, tracker)
            if loaded is not None:
                result, ds, full = loaded
                self.hits.append(stage)
                self.keys[stage] = full
                return result, ds
        if tracker is not None:
            tracker.reads.clear()
        result, ds = compute()
        result = to_jsonable(result)
        reads = dict(tracker.reads) if tracker is not None else {}
        full = stage_key(key, reads)
        self.misses.append(stage)
        self.keys[stage] = full
        self._store(stage, key, full, reads, result, ds)
        return result, ds

    def _store(self, stage, base, full, reads, result, ds) -> None:
        self.directory.mkdir(parents=True, exist_ok=True)
        js = self.directory / f"{stage}.json"
        nc = self.directory / f"{stage}.nc"
        arrays_sha = None
        if ds is not None:
            with atomic_path(nc) as tmp:
                _write_arrays(ds, tmp)
                arrays_sha = _file_sha256(tmp)
        elif nc.exists():
            nc.unlink()
        text = json.dumps({"base": base, "key": full, "reads": reads,
                           "arrays_sha256": arrays_sha,
                           "result_sha256": hashlib.sha256(_canonical(result).encode())
                           .hexdigest(),
                           "result": result}, indent=1, allow_nan=True)
        _atomic_write_bytes(js, text.encode("utf-8"))

    def clean_temporaries(self) -> None:
        """Remove temporary files left by an interrupted run (call under the lock)."""
        if self.directory.is_dir():
            for tmp in self.directory.glob(".*.tmp"):
                with contextlib.suppress(OSError):
                    tmp.unlink()


# ------------------------------------------------------------------------------- lock
class OutputLock:
    """Exclusive lock of an output folder (``.mvtk.lock``), so runs into it are serialised.

    Parameters
    ----------
    directory : path
        The output folder (must exist).
    timeout_s : float or None
        Wait at most this long for another run to finish (None: wait as long as it
        takes); ``0``: fail at once.
    on_wait : callable, optional
        Called once with a message when the lock is held by another process.

    Raises
    ------
    OutputBusyError
        The lock was not obtained within ``timeout_s``; the message names the folder
        and the process holding it.
    """

    def __init__(self, directory: str | Path, timeout_s: float | None = None,
                 on_wait: Callable[[str], None] | None = None) -> None:
        self.path = Path(directory) / ".mvtk.lock"
        self.timeout_s = timeout_s
        self.on_wait = on_wait
        self._fh = None

    def _holder(self) -> str:
        try:
            pid = self.path.read_text().strip()
        except OSError:
            pid = ""
        return f"pid {pid}" if pid else "another process"

    def __enter__(self) -> OutputLock:
        try:
            import fcntl
        except ImportError:  # pragma: no cover - Windows: no advisory locks
            return self
        fh = open(self.path, "a+")  # noqa: SIM115 - held for the lifetime of the lock
        t0 = time.monotonic()
        told = False
        while True:
            try:
                fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except OSError:
                waited = time.monotonic() - t0
                if self.timeout_s is not None and waited >= self.timeout_s:
                    holder = self._holder()
                    fh.close()
                    raise OutputBusyError(
                        f"output folder {self.path.parent} is in use by another mvtk run "
                        f"({holder}); wait for it to finish or use another --out"
                    ) from None
                if not told and self.on_wait is not None:
                    self.on_wait(f"output folder {self.path.parent} is in use by another "
                                 f"mvtk run ({self._holder()}); waiting for it to finish")
                    told = True
                time.sleep(0.2)
        fh.seek(0)
        fh.truncate()
        fh.write(str(os.getpid()))
        fh.flush()
        self._fh = fh
        return self

    def fileno(self) -> int | None:
        """File descriptor holding the lock (None when not held or without flock)."""
        return None if self._fh is None else self._fh.fileno()

    def __exit__(self, *exc) -> None:
        if self._fh is not None:
            with contextlib.suppress(OSError):
                self._fh.seek(0)
                self._fh.truncate()
            self._fh.close()  # closing releases the flock
            self._fh = None
