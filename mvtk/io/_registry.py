"""Reader registry, format detection and the ``read`` entry point."""

from __future__ import annotations

import inspect
import os
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from importlib.metadata import entry_points
from pathlib import Path

import xarray as xr

from .._atomic import special_file
from ..errors import FormatError, MvtkError, MvtkWarning, ParameterError, UnsupportedFormatError
from ._build import clean_attrs
from ._validate import validate

__all__ = ["register_reader", "list_formats", "detect_format", "read", "ENTRY_POINT_GROUP"]

ENTRY_POINT_GROUP = "mvtk.io"


@dataclass(frozen=True)
class _Reader:
    name: str
    func: Callable[..., xr.Dataset]
    extensions: tuple[str, ...]
    sniff: Callable[[bytes], bool] | None


_REGISTRY: dict[str, _Reader] = {}
_ENTRY_POINTS_LOADED = False


def register_reader(
    name: str,
    func: Callable[..., xr.Dataset],
    *,
    extensions: Sequence[str] = (),
    sniff: Callable[[bytes], bool] | None = None,
    overwrite: bool = False,
) -> None:
    """Register a reader for a file format.

    Third-party packages can also advertise a reader through the entry point group
    ``mvtk.io``: the entry point name is the format name and the object it points to is
    the reader function; optional attributes ``extensions`` (sequence of suffixes such
    as ``".xyz"``) and ``sniff`` (a function of the first 4096 bytes returning True when
    the content is of this format) on that function are used for detection.

    Parameters
    ----------
    name : str
        Format name, used as ``mvtk.io.read(path, format=name)``.
    func : callable
        ``func(path: pathlib.Path, **options) -> xarray.Dataset``. The Dataset must pass
        :func:`mvtk.io.validate`; ``read`` adds ``attrs["source"]`` and ``attrs["format"]``.
    extensions : sequence of str, optional
        File suffixes (with the dot, case-insensitive) that select this reader.
    sniff : callable, optional
        ``sniff(head: bytes) -> bool`` on the first 4096 bytes of the file.
    overwrite : bool, default False
        Replace an existing reader of the same name instead of raising.

    Raises
    ------
    mvtk.errors.ParameterError
        The name is taken (and ``overwrite`` is False) or ``func`` is not callable.
    """
    if not isinstance(name, str) or not name:
        raise ParameterError(f"register_reader: expected a non-empty format name, got {name!r}")
    if not callable(func):
        raise ParameterError(f"register_reader: reader for {name!r} is not callable: {func!r}")
    if name in _REGISTRY and not overwrite:
        raise ParameterError(
            f"register_reader: format {name!r} is already registered; pass overwrite=True"
        )
    exts = tuple(e.lower() if e.startswith(".") else "." + e.lower() for e in extensions)
    _REGISTRY[name] = _Reader(name, func, exts, sniff)


def _load_entry_points() -> None:
    global _ENTRY_POINTS_LOADED
    if _ENTRY_POINTS_LOADED:
        return
    _ENTRY_POINTS_LOADED = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        if ep.name in _REGISTRY:
            continue
        try:
            func = ep.load()
        except Exception as err:  # a broken plugin must not break mvtk
            warnings.warn(
                f"mvtk.io: entry point {ep.name!r} ({ep.value}) could not be loaded: {err}",
                MvtkWarning,
                stacklevel=3,
            )
            continue
        register_reader(
            ep.name,
            func,
            extensions=tuple(getattr(func, "extensions", ())),
            sniff=getattr(func, "sniff", None),
        )


def list_formats() -> list[str]:
    """Names of all registered formats (built-in and from entry points).

    Examples
    --------
    >>> {"uff", "tdms", "mat", "netcdf"} <= set(list_formats())
    True
    """
    _load_entry_points()
    return sorted(_REGISTRY)


def detect_format(path: str | os.PathLike) -> str:
    """Name of the reader for ``path``, from its content (magic bytes) and extension.

    Raises
    ------
    mvtk.errors.FormatError
        The file is empty.
    mvtk.errors.UnsupportedFormatError
        No registered reader recognises the file.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from mvtk.io import time_history, write
    >>> x = time_history(np.zeros((1, 64)), 1024.0, ["acc1"], "m/s^2")
    >>> detect_format(write(x, pathlib.Path(tempfile.mkdtemp()) / "run1.nc"))
    'netcdf'
    """
    _load_entry_points()
    path = Path(path)
    with open(path, "rb") as fh:
        head = fh.read(4096)
    if not head:
        raise FormatError(f"{path}: the file is empty (0 bytes); expected a measurement file")
    ext = path.suffix.lower()
    by_ext = [r for r in _REGISTRY.values() if ext in r.extensions]
    for reader in by_ext:
        if reader.name != "text" and reader.sniff is not None and reader.sniff(head):
            return reader.name
    for reader in _REGISTRY.values():
        if reader.sniff is not None and reader not in by_ext and reader.name != "text":
            if reader.sniff(head):
                return reader.name
    if by_ext:
        return by_ext[0].name
    text = _REGISTRY.get("text")
    if text is not None and text.sniff is not None and text.sniff(head):
        return "text"
    raise UnsupportedFormatError(
        f"{path}: unknown format (extension {ext or 'none'!r}, first bytes {head[:16]!r}); "
        f"expected one of: {', '.join(sorted(_REGISTRY))}; pass format=... to force a reader "
        "or register one with mvtk.io.register_reader"
    )


def _check_options(reader: _Reader, options: dict, path: Path) -> None:
    sig = inspect.signature(reader.func)
    params = sig.parameters
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values()):
        return
    names = [
        n for n, p in list(params.items())[1:] if p.kind is not inspect.Parameter.VAR_POSITIONAL
    ]
    unknown = sorted(set(options) - set(names))
    if unknown:
        raise ParameterError(
            f"read({path}): option(s) {', '.join(unknown)} not understood by the "
            f"{reader.name!r} reader; valid options: {', '.join(names) or 'none'}"
        )


def _fixed_width_strings(ds: xr.Dataset) -> xr.Dataset:
    """Object arrays of str become numpy str arrays (what a netCDF round trip gives back)."""
    changes = {}
    for name, var in ds.variables.items():
        if var.dtype == object and all(isinstance(v, str) for v in var.values.ravel()):
            changes[name] = var.astype(str)
    return (
        ds.assign_coords({k: v for k, v in changes.items() if k in ds.coords}).assign(
            {k: v for k, v in changes.items() if k not in ds.coords}
        )
        if changes
        else ds
    )


def _provenance(attrs, path: Path, format: str) -> dict:
    """``source``/``format`` of this read; a file that records an earlier read (mvtk's
    own netCDF output) keeps it as ``original_source``/``original_format``."""
    out = {"source": str(path), "format": format}
    before = attrs.get("source")
    if before is not None and str(before) != str(path) and "original_source" not in attrs:
        out["original_source"] = str(before)
        if attrs.get("format") is not None:
            out["original_format"] = str(attrs["format"])
    return out


def read(path: str | os.PathLike, format: str | None = None, **options) -> xr.Dataset:
    """Read a measurement file into a validated ``xarray.Dataset``.

    Parameters
    ----------
    path : str or path-like
        The file.
    format : str, optional
        Force a reader (see :func:`list_formats`); detected from content and extension
        when omitted.
    **options
        Reader-specific options (see the reader docstrings in the module documentation
        of :mod:`mvtk.io`).

    Returns
    -------
    xarray.Dataset
        See the layout in the :mod:`mvtk.io` module docstring. ``attrs["source"]`` is the
        path and ``attrs["format"]`` the reader name.

    Raises
    ------
    FileNotFoundError
        The path does not exist.
    mvtk.errors.FormatError
        The content is malformed (the message names file, line or record and channel).
    mvtk.errors.UnsupportedFormatError
        No reader recognises the file or ``format`` is unknown.
    mvtk.errors.ParameterError
        An option is not understood by the chosen reader.

    Examples
    --------
    Write a two-channel record (an accelerometer in m/s^2 and a force in N, 1024 Hz) to
    netCDF and read it back; any supported format reads the same way:

    >>> import pathlib, tempfile
    >>> from mvtk.io import time_history, write
    >>> x = time_history(np.zeros((2, 1024)), 1024.0, ["acc1", "force"], ["m/s^2", "N"])
    >>> path = write(x, pathlib.Path(tempfile.mkdtemp()) / "run1.nc")
    >>> ds = read(path)
    >>> ds.attrs["format"], ds["time_history"].shape, [str(q) for q in ds["quantity"].values]
    ('netcdf', (2, 1024), ['acceleration', 'force'])
    """
    _load_entry_points()
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"read: no such file: {path}")
    if path.is_dir():
        raise FormatError(f"read: {path} is a directory; expected a measurement file")
    kind = special_file(path)
    if kind is not None:
        raise FormatError(f"read: {path} is {kind}; expected a regular measurement file")
    if format is None:
        format = detect_format(path)
    elif format not in _REGISTRY:
        raise UnsupportedFormatError(
            f"read({path}): unknown format {format!r}; expected one of: "
            + ", ".join(sorted(_REGISTRY))
        )
    reader = _REGISTRY[format]
    _check_options(reader, options, path)
    if path.stat().st_size == 0:
        raise FormatError(f"{path}: the file is empty (0 bytes); expected a {format} file")
    try:
        ds = reader.func(path, **options)
    except (MvtkError, MemoryError):
        raise
    except Exception as err:
        raise FormatError(
            f"{path}: could not be read as {format}: {type(err).__name__}: {err}"
        ) from err
    if not isinstance(ds, xr.Dataset):
        raise FormatError(
            f"{path}: reader {format!r} returned {type(ds).__name__}; expected an xarray.Dataset"
        )
    ds = _fixed_width_strings(ds)
    ds.attrs = clean_attrs({**ds.attrs, **_provenance(ds.attrs, path, format)})
    for name, var in ds.data_vars.items():
        if str(name).startswith("time_history"):
            var.attrs = clean_attrs(
                {**ds.attrs, **var.attrs, **_provenance(var.attrs, path, format)}
            )
    validate(ds)
    return ds
