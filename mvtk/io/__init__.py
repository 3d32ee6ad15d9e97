"""Ingest of measured vibration data: readers, the time-history data model, validation.

Entry points
------------
``read(path, format=None, **options) -> xarray.Dataset``
    Detects the format from content (magic bytes) and extension, or uses ``format``.
``write(ds, path)``
    netCDF4 (h5netcdf); ``read`` gives the same Dataset back.
``validate(obj, *, source=None)``
    Checks the conventions below; every reader's output passes it.
``time_history(data, fs, channels, units, quantity=None, *, node, direction, attrs)``
    Builds a valid time-history DataArray from numpy (used for synthetic signals).
``register_reader(name, func, *, extensions, sniff)``
    Adds a format; third-party packages can use the entry point group ``mvtk.io``
    (entry point name = format name, object = reader function, optional attributes
    ``extensions`` and ``sniff`` on it).

Dataset layout
--------------
``time_history`` : float (channel, time)
    The primary time histories: all channels that share one sampling grid. ``time`` is
    ``np.arange(n) / fs`` in s; ``attrs["fs"]`` is the rate in Hz; a non-zero start time
    of the record is in ``attrs["t0_s"]``. Coordinates on ``channel``: ``quantity`` (one
    of :data:`QUANTITIES`), ``units`` (canonical spelling, see :func:`normalize_units`),
    ``node`` (int, -1 unknown), ``direction`` (``"x"``, ``"-z"``, ``"rx"``..., ``""``
    unknown), ``n_missing`` (samples the file marks missing, kept as NaN); UFF adds
    ``record`` (1-based record number).
``time_history_2``, ``time_history_3``, ... : float (channel_2, time_2), ...
    Further sampling grids (never resampled); their coordinates carry the same suffix
    (``units_2``, ``quantity_2``...).
``psd``, ``auto_spectrum``, ``coherence``, ``spectrum`` : (channel, frequency)
    Spectra from UFF 58 (function types 9, 2, 6, 12), MAT or text files; ``frequency``
    in Hz; ``attrs["units"]`` is the ordinate unit as written in the file.
``frf``, ``cross_spectrum``, ``transmissibility`` : complex (response, reference, frequency)
    Two-point functions (UFF 58 types 4, 3, 5) when the records form a complete
    response x reference grid; otherwise (channel, frequency) with ``response`` and
    ``reference`` coordinates on ``channel``. A UFF 58 FRF's ``attrs["units"]`` is
    numerator over denominator (``m/s^2/N``) and ``attrs["frf_type"]`` (receptance,
    mobility, accelerance; ``other`` over a non-force denominator) comes from the
    records' numerator/denominator data types (8, 11, 12 over 9 or 13) or, when those
    are general/unknown, from their unit labels. An FRF matrix written by :func:`write`
    is read back as ``frf``.
``mode_shape`` : (mode, node, component)
    UFF 55 mode shapes; coordinates ``fn_hz``, ``damping_ratio``, ``eigenvalue``
    (complex, rad/s), ``mode_number`` on ``mode``; ``component`` from ``ux uy uz rx ry rz``.

When a dim name would be reused with other coordinate values (a second channel list,
another frequency grid) it gets a suffix ``_2``, ``_3``... together with its coordinates.
``attrs`` of the Dataset hold file-level metadata (str, int or float): ``source`` (the
path read), ``format`` (the reader), and what the file states (header lines, instrument,
start time...).

Formats and their options
-------------------------
``text`` (.csv .tsv .txt .dat .asc)
    ``delimiter``, ``decimal``, ``encoding``, ``fs``, ``time_column``, ``channels``,
    ``units``, ``quantity``, ``df_hz`` -- see :func:`mvtk.io._text.read_text`.
``uff`` (.uff .unv)
    ``allow_truncated`` -- datasets 58 / 58b (ASCII, binary float32/float64, both byte
    orders) and 55, via pyuff.
``mat`` (.mat v5/v7 and v7.3)
    ``data``, ``time``, ``fs``, ``dt``, ``channels``, ``units``, ``quantity``,
    ``frequency``, ``spectra``, ``spectrum_units``.
``hdf5`` (.h5 .hdf5)
    ``data``, ``time``, ``fs``, ``dt``, ``channels``, ``units``, ``quantity``; netCDF4
    files go to the netCDF reader.
``netcdf`` (.nc)
    no options. mvtk's own output reads back with ``attrs["format"] == "netcdf"``; the
    file that was read originally is kept as ``attrs["original_source"]`` (and its reader
    as ``attrs["original_format"]``).
``tdms`` (.tdms, optional extra ``mvtk[tdms]``)
    ``units``, ``fs``, ``allow_truncated``.
``lvm`` (.lvm, LabVIEW Measurement text files)
    ``decimal``, ``encoding``, ``fs``, ``units``, ``quantity``, ``allow_truncated`` --
    file and segment headers, decimal comma or point, any separator, several segments,
    ``X_Columns`` No / One / Multi (:func:`mvtk.io._lvm.read_lvm`).
``wav`` (.wav)
    ``calibration``, ``units``, ``quantity``, ``channels``.

Command line
------------
``mvtk read PATH [--format F] [--set key=value ...] [-o out.nc]`` prints the layout of
a file and optionally converts it to netCDF (:mod:`mvtk.cli.read`).

Errors
------
Malformed content raises :class:`mvtk.errors.FormatError` naming the file and the line,
record or channel and what was expected; unknown formats raise
:class:`mvtk.errors.UnsupportedFormatError`; data that were usable after a repair come
with a :class:`mvtk.errors.DataRepairWarning` saying what was repaired. A truncated
UFF record or TDMS segment is refused unless ``allow_truncated=True`` is passed.
"""

from __future__ import annotations

from ._campaign import open_campaign
from ._containers import (
    read_hdf5,
    read_mat,
    read_tdms,
    read_wav,
    sniff_hdf5,
    sniff_mat,
    sniff_tdms,
    sniff_wav,
)
from ._lvm import LVM_EXTENSIONS, read_lvm, sniff_lvm
from ._model import (
    QUANTITIES,
    UNITS_BY_QUANTITY,
    fs_from_dt,
    infer_quantity,
    normalize_units,
    time_axis,
    time_history,
)
from ._netcdf import NETCDF_EXTENSIONS, read_netcdf, sniff_netcdf, write
from ._registry import ENTRY_POINT_GROUP, detect_format, list_formats, read, register_reader
from ._text import TEXT_EXTENSIONS, read_text, sniff_text
from ._uff import UFF_EXTENSIONS, read_uff, sniff_uff
from ._validate import validate

__all__ = [
    "read",
    "open_campaign",
    "write",
    "validate",
    "time_history",
    "time_axis",
    "register_reader",
    "list_formats",
    "detect_format",
    "normalize_units",
    "infer_quantity",
    "fs_from_dt",
    "QUANTITIES",
    "UNITS_BY_QUANTITY",
    "ENTRY_POINT_GROUP",
]

register_reader("uff", read_uff, extensions=UFF_EXTENSIONS, sniff=sniff_uff)
register_reader("mat", read_mat, extensions=(".mat",), sniff=sniff_mat)
register_reader("hdf5", read_hdf5, extensions=(".h5", ".hdf5", ".hdf", ".he5"), sniff=sniff_hdf5)
register_reader("netcdf", read_netcdf, extensions=NETCDF_EXTENSIONS, sniff=sniff_netcdf)
register_reader("tdms", read_tdms, extensions=(".tdms",), sniff=sniff_tdms)
register_reader("lvm", read_lvm, extensions=LVM_EXTENSIONS, sniff=sniff_lvm)
register_reader("wav", read_wav, extensions=(".wav",), sniff=sniff_wav)
register_reader("text", read_text, extensions=TEXT_EXTENSIONS, sniff=sniff_text)
