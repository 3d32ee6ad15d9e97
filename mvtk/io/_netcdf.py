"""netCDF output (``mvtk.io.write``) and input (h5netcdf engine; netCDF3 via scipy)."""

from __future__ import annotations

import os
from pathlib import Path

import xarray as xr

from .._atomic import atomic_path, check_room, write_bytes
from ..errors import FormatError, ParameterError
from ._build import clean_attrs
from ._validate import validate

__all__ = ["read_netcdf", "write", "sniff_netcdf", "NETCDF_EXTENSIONS"]

NETCDF_EXTENSIONS = (".nc", ".nc4", ".netcdf", ".cdf")
HDF5_MAGIC = b"\x89HDF\r\n\x1a\n"


def _is_netcdf3(head: bytes) -> bool:
    return head[:3] == b"CDF" and head[3:4] in (b"\x01", b"\x02", b"\x05")


def sniff_netcdf(head: bytes) -> bool:
    """netCDF3 classic/64-bit magic, or the HDF5 signature of a netCDF4 file.

    A plain HDF5 file is claimed by the netCDF reader only through a netCDF extension
    (``.nc``): the ``hdf5`` reader is registered first and wins on content alone.
    """
    return _is_netcdf3(head) or head[:8] == HDF5_MAGIC


def read_netcdf(path: Path):
    """Read a netCDF file (mvtk's own output round-trips exactly).

    Parameters
    ----------
    path : pathlib.Path
        The file (netCDF4/HDF5 read with h5netcdf, netCDF3 with scipy).
    """
    with open(path, "rb") as fh:
        head = fh.read(8)
    engine = "scipy" if _is_netcdf3(head) else "h5netcdf"
    if engine == "h5netcdf" and head != HDF5_MAGIC:
        raise FormatError(
            f"{path}: starts with {head!r}; expected the HDF5 signature of a netCDF4 file or "
            "the 'CDF' signature of netCDF3"
        )
    try:
        with xr.open_dataset(path, engine=engine, decode_times=False) as ds:
            return ds.load()
    except (OSError, ValueError, KeyError, TypeError, RuntimeError) as err:
        raise FormatError(
            f"{path}: not a readable netCDF file ({type(err).__name__}: {err})"
        ) from err


def write(ds, path: str | os.PathLike) -> Path:
    """Write a time history or Dataset to netCDF4 (h5netcdf), losslessly.

    Data, coordinates (channel names, units, quantity, node, direction, n_missing, ...),
    variable attrs and file attrs are kept; ``mvtk.io.read`` of the file gives an
    identical Dataset except for ``attrs["source"]`` and ``attrs["format"]``, which
    describe the last read.

    Parameters
    ----------
    ds : xarray.Dataset or xarray.DataArray
        Must pass :func:`mvtk.io.validate`. A DataArray is stored as variable
        ``"frf"`` when its dims are ``("response", "reference", "frequency")`` (an FRF
        matrix, read back by :func:`mvtk.modal.as_frf_matrix`), else ``"time_history"``.
    path : str or path-like
        Output file (``.nc`` recommended); replaced if it exists, in one step: the file
        is written next to it and renamed, so a failed write leaves the previous file
        unchanged.

    Returns
    -------
    pathlib.Path
        The path written.

    Raises
    ------
    mvtk.errors.ParameterError
        ``ds`` is not an xarray object.
    mvtk.errors.FormatError
        ``ds`` breaks the mvtk conventions (see :func:`mvtk.io.validate`).
    mvtk.errors.OutputError
        The file could not be written (disk full, file-size limit, permission); the
        message names it and the cause.

    Examples
    --------
    The round trip is lossless (samples, units, quantities, file attributes):

    >>> import pathlib, tempfile
    >>> from mvtk.io import read, time_history
    >>> x = time_history(np.random.default_rng(0).standard_normal((2, 256)), 512.0,
    ...                  ["acc1", "force"], ["m/s^2", "N"])
    >>> path = write(x, pathlib.Path(tempfile.mkdtemp()) / "run1.nc")
    >>> back = read(path)["time_history"]
    >>> bool((back.values == x.values).all()), float(back.attrs.get("fs", 512.0))
    (True, 512.0)
    """
    if isinstance(ds, xr.DataArray):
        # an FRF matrix stays an FRF matrix (variable "frf"), anything else is a record
        frf = set(ds.dims) == {"response", "reference", "frequency"}
        ds = ds.to_dataset(name="frf" if frf else "time_history")
    if not isinstance(ds, xr.Dataset):
        raise ParameterError(
            f"write: expected an xarray.Dataset or DataArray, got {type(ds).__name__}"
        )
    validate(ds)
    out = ds.copy(deep=False)
    out.attrs = clean_attrs(ds.attrs)
    for var in out.variables.values():
        var.attrs = clean_attrs(var.attrs)
    return write_h5netcdf(out, Path(path))


#: Datasets up to this size are encoded in memory and written with plain file I/O.
_IN_MEMORY_BYTES = 256 * 2**20


def _local_scheduler():
    """Context in which dask (when imported) computes in this process (no cluster lock)."""
    import contextlib
    import sys

    if "dask" not in sys.modules:
        return contextlib.nullcontext()
    import dask

    return dask.config.set(scheduler="synchronous")


def write_h5netcdf(ds: xr.Dataset, path: Path) -> Path:
    """Write ``ds`` to ``path`` as netCDF4 (h5netcdf), atomically.

    HDF5 cannot recover from a write that fails half-way (a full disk, a file-size
    limit: closing the half-written file crashes the process), so the file is encoded
    in memory and written with plain file I/O through :func:`mvtk._atomic.atomic_path`;
    a dataset larger than 256 MiB is written by HDF5 to the temporary file after a
    check that the file system and the file-size limit have room for it.
    """
    nbytes = int(ds.nbytes)
    if nbytes <= _IN_MEMORY_BYTES:
        # in memory: the data are loaded first and written by this process alone (under
        # an active dask.distributed client xarray would otherwise take a cluster lock
        # named after the in-memory buffer, which the scheduler does not know)
        ds = ds.load()
        with _local_scheduler():
            return write_bytes(path, ds.to_netcdf(engine="h5netcdf"))   # a memoryview
    check_room(path, int(nbytes * 1.05) + 2**20)
    with atomic_path(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf")
    return path
