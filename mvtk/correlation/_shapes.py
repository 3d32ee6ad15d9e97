"""Measured mode shapes from a file, as values along the sensors of a test geometry.

Experimental modal analysis software (and ``mvtk modal --uff-modes``) writes identified
shapes as UFF 55 records: per node, the translations ``ux uy uz`` (and possibly the
rotations) in the node's displacement coordinate system. Correlation works on the
sensor DOFs of a test geometry (``"101+z"``, a skewed ``"s1"``...). Each sensor's value is
the projection of its node's vector onto the sensing axis: ``u . v`` with ``v`` the
sensor's unit vector in the node's coordinate system (:meth:`Sensor.local_vector`), so a
``-z`` sensor reads ``-uz`` and a skewed one its component.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import xarray as xr

from ..errors import DimensionError, FormatError, ParameterError

__all__ = ["shapes_at_sensors", "read_test_shapes"]

_TRANSLATIONS = ("ux", "uy", "uz")
_ROTATIONS = ("rx", "ry", "rz")


def shapes_at_sensors(mode_shape: xr.DataArray, geometry, *, source: str = "") -> xr.DataArray:
    """Node-vector mode shapes -> values along the sensors of ``geometry``.

    Parameters
    ----------
    mode_shape : xarray.DataArray, dims ("mode", "node", "component")
        As :func:`mvtk.io.read` returns UFF 55 records: components ``ux uy uz`` (and
        optionally ``rx ry rz``) in each node's displacement coordinate system;
        coordinates ``fn_hz`` (Hz) and ``damping_ratio`` per mode are carried over.
        Real or complex.
    geometry : TestGeometry
        The sensors (node, direction or skewed vector) to read the shapes along.
    source : str
        Name of the file the shapes came from, for messages.

    Returns
    -------
    xarray.DataArray, dims ("mode", "dof")
        ``dof`` = :meth:`TestGeometry.dof_labels`; ``fn_hz`` (and ``damping_ratio``)
        per mode when the input has them.

    Raises
    ------
    DimensionError
        Wrong dims, or a sensor's node or component is not in the shapes.

    Examples
    --------
    One measured mode as node vectors (UFF 55 layout: mode, node, component), read
    along three +z sensors:

    >>> import xarray as xr
    >>> from mvtk.correlation import read_test_geometry
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> shape = xr.DataArray([[[0, 0, 0.2], [0, 0, 0.6], [0, 0, 1.0]]],
    ...                      dims=("mode", "node", "component"),
    ...                      coords={"mode": [1], "node": [1, 2, 3],
    ...                              "component": ["ux", "uy", "uz"], "fn_hz": ("mode", [18.6])})
    >>> s = shapes_at_sensors(shape, geo)
    >>> s.dims, s.values.tolist()
    (('mode', 'dof'), [[0.2, 0.6, 1.0]])
    """
    where = f"{source}: " if source else ""
    if not isinstance(mode_shape, xr.DataArray) or set(mode_shape.dims) != {
            "mode", "node", "component"}:
        dims = getattr(mode_shape, "dims", type(mode_shape).__name__)
        raise DimensionError(f"{where}mode shapes: expected dims ('mode', 'node', "
                             f"'component'), got {dims}")
    ms = mode_shape.transpose("mode", "node", "component")
    comps = [str(c) for c in ms["component"].values]
    nodes = {int(n): i for i, n in enumerate(ms["node"].values)}
    values = ms.values
    out = np.zeros((values.shape[0], len(geometry.sensors)), dtype=values.dtype)
    for j, s in enumerate(geometry.sensors):
        if s.node not in nodes:
            raise DimensionError(
                f"{where}sensor {s.label}: node {s.node} has no mode-shape values; the "
                f"shapes hold nodes {sorted(nodes)[:12]}{' ...' if len(nodes) > 12 else ''}")
        want = _ROTATIONS if s.rotation else _TRANSLATIONS
        missing = [c for c in want if c not in comps]
        if missing:
            raise DimensionError(
                f"{where}sensor {s.label}: the shapes have components {comps}; expected "
                f"{list(want)}")
        idx = [comps.index(c) for c in want]
        out[:, j] = values[:, nodes[s.node], idx] @ s.local_vector()
    coords = {"mode": ms["mode"].values, "dof": list(geometry.dof_labels)}
    for name in ("fn_hz", "damping_ratio"):
        if name in ms.coords:
            coords[name] = ("mode", np.asarray(ms[name].values, dtype=float))
    return xr.DataArray(out, dims=("mode", "dof"), coords=coords, name="test_shapes",
                        attrs={"source": source} if source else {})


def read_test_shapes(path: str | Path, geometry) -> xr.DataArray:
    """Measured shapes from a file, along the sensors of ``geometry``.

    Parameters
    ----------
    path : path
        A file :func:`mvtk.io.read` reads into a ``mode_shape`` variable (UFF 55 normal
        or complex modes, e.g. written by ``mvtk modal --uff-modes``; a netCDF written by
        :func:`mvtk.io.write`), or a netCDF holding one DataArray with dims
        ``("mode", "dof")`` whose ``dof`` labels are the geometry's sensor labels.
    geometry : TestGeometry

    Returns
    -------
    xarray.DataArray, dims ("mode", "dof")

    Raises
    ------
    FormatError
        The file holds neither form.

    Examples
    --------
    Shapes saved as a ``("mode", "dof")`` DataArray in netCDF, with sensor labels as ``dof``:

    >>> import pathlib, tempfile
    >>> import xarray as xr
    >>> from mvtk.correlation import read_test_geometry
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "shapes.nc"
    >>> xr.DataArray([[0.2, 0.6, 1.0]], dims=("mode", "dof"), name="shapes",
    ...              coords={"mode": [1], "dof": ["1+z", "2+z", "3+z"],
    ...                      "fn_hz": ("mode", [18.6])}).to_netcdf(path)
    >>> s = read_test_shapes(path, geo)
    >>> s.values.tolist(), s["fn_hz"].values.tolist()
    ([[0.2, 0.6, 1.0]], [18.6])
    """
    import mvtk.io

    path = Path(path)
    if not path.is_file():
        raise ParameterError(f"{path}: shapes file not found")
    if path.suffix.lower() in (".nc", ".nc4", ".netcdf"):
        try:
            da = xr.open_dataarray(path).load()
        except ValueError:
            da = None  # several variables: an mvtk.io netCDF, read below
        except OSError as err:
            raise FormatError(f"{path}: cannot read a shapes DataArray ({err})") from err
        if da is not None:
            if set(da.dims) == {"mode", "dof"}:
                return _finite(da.transpose("mode", "dof"), path)
            if set(da.dims) == {"mode", "node", "component"}:
                return _finite(shapes_at_sensors(da, geometry, source=str(path)), path)
            raise FormatError(f"{path}: a DataArray with dims {da.dims}; expected ('mode', "
                              "'dof') or ('mode', 'node', 'component')")
    ds = mvtk.io.read(path)
    if "mode_shape" not in ds:
        raise FormatError(f"{path}: no mode shapes (variables {list(ds.data_vars)}); expected "
                          "UFF 55 records or a ('mode', 'dof') netCDF DataArray")
    return _finite(shapes_at_sensors(ds["mode_shape"], geometry, source=str(path)), path)


def _finite(da: xr.DataArray, path: Path) -> xr.DataArray:
    """``da``, or FormatError naming the first mode and DOF whose value is not finite."""
    bad = ~np.isfinite(np.asarray(da.values))
    if bad.any():
        m, k = (int(v[0]) for v in np.nonzero(bad))
        n = int(bad.any(axis=1).sum())
        value = np.asarray(da.values)[m, k].item()
        raise FormatError(f"{path}: shape value of mode {da['mode'].values[m]!s} at DOF "
                          f"{da['dof'].values[k]!s} is {value!r} ({int(bad.sum())} "
                          f"non-finite value(s) in {n} mode(s)); a MAC needs every value")
    return da
