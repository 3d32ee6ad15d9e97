"""MATLAB (v5 via scipy.io, v7.3 via h5py), generic HDF5, TDMS (npTDMS) and WAV readers."""

from __future__ import annotations

import logging
import warnings
from pathlib import Path

import numpy as np

from ..errors import (
    DataRepairWarning,
    FormatError,
    MissingDependencyError,
    MvtkError,
    ParameterError,
)
from ._arrays import build_from_arrays
from ._build import assemble, clean_attrs
from ._mat5 import check_mat5
from ._model import build_time_history, fs_from_dt, normalize_units
from ._netcdf import HDF5_MAGIC, read_netcdf

__all__ = [
    "read_mat",
    "read_hdf5",
    "read_tdms",
    "read_wav",
    "sniff_mat",
    "sniff_hdf5",
    "sniff_tdms",
    "sniff_wav",
]


def sniff_mat(head: bytes) -> bool:
    """MATLAB v5/v7 text header, or the v7.3 header in front of an HDF5 body."""
    return head[:10] == b"MATLAB 5.0" or head[:10] == b"MATLAB 7.3"


def sniff_hdf5(head: bytes) -> bool:
    """HDF5 signature at offset 0."""
    return head[:8] == HDF5_MAGIC


def sniff_tdms(head: bytes) -> bool:
    """TDMS lead-in tag ``TDSm``."""
    return head[:4] == b"TDSm"


def sniff_wav(head: bytes) -> bool:
    """RIFF/WAVE header."""
    return head[:4] in (b"RIFF", b"RIFX") and head[8:12] == b"WAVE"


def read_mat(
    path: Path,
    *,
    data=None,
    time=None,
    fs=None,
    dt=None,
    channels=None,
    units=None,
    quantity=None,
    frequency=None,
    spectra=None,
    spectrum_units=None,
    response=None,
    reference=None,
    response_units=None,
    reference_units=None,
    phase_units="deg",
):
    """Read a MATLAB file (v5/v7 with scipy.io, v7.3 with h5py).

    Variables inside structs are named by their path, ``"Fe.Out.Acc"``. Spectra and FRFs
    can be read without time histories (``spectra`` and ``frequency`` only). FRFs,
    coherence, cross spectra and transmissibilities become ``(response, reference,
    frequency)`` matrices (``docs/conventions.md``); auto spectra ``(channel,
    frequency)``, on the time-history channels when there is one spectrum per channel.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    data : str or list of str
        One 2-D variable (samples along the longer axis) or one 1-D variable per channel.
    time : str, optional
        Variable holding the time vector in s.
    fs, dt : float or str, optional
        Sampling rate in Hz / sample interval in s, or the name of a scalar variable.
    channels : list of str, optional
        Channel names (default: the variable names).
    units, quantity : str or list of str
        Units (required: MAT files carry none) and quantities per channel.
    frequency : str, optional
        Variable holding the frequency axis (Hz) of ``spectra``.
    spectra : dict, optional
        ``{kind: entry}`` with kinds ``frf``, ``coherence``, ``cross_spectrum``,
        ``transmissibility`` (two-point) or any other name (auto spectra: ``psd``,
        ``auto_spectrum``...). An entry is a variable name (complex or real values; a 2-D
        array is responses x lines, a 3-D array responses x references x lines), a list
        of names (one per response or channel), ``{"magnitude": name, "phase": name}``
        or ``{"real": name, "imag": name}``; for auto spectra also ``{channel: name}``.
    spectrum_units : dict, optional
        ``{kind: unit string}``, e.g. ``{"frf": "m/s^2/N"}`` (the response and reference
        units are taken from it when not given otherwise).
    response, reference : str or list of str, optional
        Names of the FRF response and reference channels; a name that is a time-history
        channel gives its units and quantity.
    response_units, reference_units : str or list of str, optional
        Units of the FRF response / reference channels, e.g. ``reference_units="A"`` for
        a current reference (quantity ``current``) or ``"V"``.
    phase_units : {"deg", "rad"}, default "deg"
        Unit of a phase variable given as ``{"magnitude": ..., "phase": ...}``.
    """
    with open(path, "rb") as fh:
        head = fh.read(128)
    header = head[:116].decode("latin-1").rstrip("\x00 ")
    opts = dict(
        data=data,
        time=time,
        fs=fs,
        dt=dt,
        channels=channels,
        units=units,
        quantity=quantity,
        frequency=frequency,
        spectra=spectra,
        spectrum_units=spectrum_units,
        attrs={"mat_header": header},
        response=response,
        reference=reference,
        response_units=response_units,
        reference_units=reference_units,
        phase_units=phase_units,
    )
    if head[:10] == b"MATLAB 7.3":
        import h5py

        try:
            fh5 = h5py.File(path, "r")
        except OSError as err:
            raise FormatError(f"{path}: MAT v7.3 file is not readable HDF5 ({err})") from err
        with fh5:
            names = _h5_leaves(fh5)
            return build_from_arrays(path, lambda k: _h5_value(fh5, k), names, **opts)
    import scipy.io

    check_mat5(path, path.read_bytes())
    try:
        content = scipy.io.loadmat(path, squeeze_me=False)
    except Exception as err:  # scipy raises many kinds on damaged files
        raise FormatError(
            f"{path}: not a readable MAT v5 file ({type(err).__name__}: {err})"
        ) from err
    leaves: dict[str, np.ndarray] = {}
    for key, value in content.items():
        if not key.startswith("__"):
            _mat_leaves(key, value, leaves, 0)
    return build_from_arrays(path, leaves.__getitem__, list(leaves), **opts)


def _mat_leaves(name: str, value, out: dict, depth: int) -> None:
    """Flatten MATLAB structs (scipy.io record arrays) into ``"a.b.c"`` leaf arrays."""
    arr = np.asarray(value)
    if arr.dtype.names and depth < 8:
        if arr.size != 1:
            out[name] = arr  # struct array: kept whole (not a numeric leaf)
            return
        rec = arr.reshape(-1)[0]
        for field in arr.dtype.names:
            _mat_leaves(f"{name}.{field}", rec[field], out, depth + 1)
        return
    if arr.dtype == object and arr.size == 1 and depth < 8:
        _mat_leaves(name, arr.reshape(-1)[0], out, depth + 1)
        return
    out[name] = arr


def _h5_leaves(fh5) -> list[str]:
    """Dataset paths of a MAT v7.3 file with struct fields joined by dots."""
    import h5py

    names: list[str] = []

    def visit(key, obj):
        if isinstance(obj, h5py.Dataset) and not key.startswith("#"):
            names.append(key.replace("/", "."))

    fh5.visititems(visit)
    return names


def _h5_value(fh5, name: str) -> np.ndarray:
    arr = np.asarray(fh5[name.replace(".", "/")][()])
    if arr.dtype.names and set(arr.dtype.names) == {"real", "imag"}:  # MATLAB complex
        arr = arr["real"] + 1j * arr["imag"]
    return arr.T


def _is_netcdf4(h5file) -> bool:
    if "_NCProperties" in h5file.attrs:
        return True
    return any(
        getattr(obj, "attrs", {}).get("CLASS") == b"DIMENSION_SCALE" for obj in h5file.values()
    )


def read_hdf5(
    path: Path,
    *,
    data=None,
    time=None,
    fs=None,
    dt=None,
    channels=None,
    units=None,
    quantity=None,
):
    """Read an HDF5 file: netCDF4 files go to the netCDF reader, others by dataset paths.

    Without options, a group holding a 2-D ``data`` dataset with ``time`` and/or
    ``sample_rate`` and ``channel_names`` datasets (the layout of e.g. ``view_0.hdf5``)
    is found automatically.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    data : str, optional
        Path of the 2-D sample dataset (samples along the longer axis).
    time : str, optional
        Path of the time vector in s.
    fs, dt : float or str, optional
        Sampling rate in Hz / interval in s, or path of a scalar dataset.
    channels : str or list of str, optional
        Path of a dataset of channel names, or the names.
    units, quantity : str or list of str
        Units (required unless the file has a ``units`` dataset or attribute) and
        quantities per channel.
    """
    import h5py

    try:
        fh5 = h5py.File(path, "r")
    except OSError as err:
        raise FormatError(f"{path}: not a readable HDF5 file ({err})") from err
    try:
        with fh5:
            ds = _read_hdf5_open(path, fh5, data, time, fs, dt, channels, units, quantity)
    except MvtkError:
        raise
    except (KeyError, RuntimeError, OSError, ValueError, TypeError) as err:
        raise FormatError(f"{path}: damaged HDF5 file ({type(err).__name__}: {err})") from err
    return read_netcdf(path) if ds is None else ds


def _read_hdf5_open(path, fh5, data, time, fs, dt, channels, units, quantity):
    import h5py

    if data is None and _is_netcdf4(fh5):
        return None
    paths: list[str] = []
    fh5.visititems(lambda name, obj: paths.append(name) if isinstance(obj, h5py.Dataset) else None)

    def get(name):
        return fh5[name][()]

    if data is None:
        cands = [p for p in paths if p.split("/")[-1] == "data" and fh5[p].ndim == 2]
        if len(cands) != 1:
            raise FormatError(
                f"{path}: cannot tell which dataset holds the samples; expected "
                f"data='<path>' among: {', '.join(paths)}"
            )
        data = cands[0]
    group = data.rsplit("/", 1)[0] + "/" if "/" in data else ""
    if time is None and fs is None and dt is None:
        for cand in ("time", "t"):
            if group + cand in paths:
                time = group + cand
                break
        for cand in ("sample_rate", "sampling_rate", "fs"):
            if group + cand in paths:
                fs = group + cand
                break
    if channels is None and group + "channel_names" in paths:
        channels = group + "channel_names"
    if isinstance(channels, str):
        raw = np.asarray(get(channels)).reshape(-1)
        channels = [c.decode("utf-8") if isinstance(c, bytes) else str(c) for c in raw]
    if units is None:
        for cand in ("units", "channel_units"):
            if group + cand in paths:
                raw = np.asarray(get(group + cand)).reshape(-1)
                units = [u.decode("utf-8") if isinstance(u, bytes) else str(u) for u in raw]
                break
        else:
            attr = fh5[data].attrs.get("units")
            if attr is not None:
                units = [
                    u.decode() if isinstance(u, bytes) else str(u)
                    for u in np.asarray(attr).reshape(-1)
                ]
    return build_from_arrays(
        path,
        get,
        paths,
        data=data,
        time=time,
        fs=fs,
        dt=dt,
        channels=channels,
        units=units,
        quantity=quantity,
        attrs={"hdf5_data": data},
    )


class _Collect(logging.Handler):
    """Collects warnings that npTDMS logs (it logs, rather than raises, on truncation)."""

    def __init__(self):
        super().__init__(level=logging.WARNING)
        self.messages: list[str] = []

    def emit(self, record):
        self.messages.append(record.getMessage())


def read_tdms(path: Path, *, units=None, fs=None, allow_truncated=False):
    """Read a National Instruments TDMS file (needs the optional npTDMS: ``mvtk[tdms]``).

    Every channel with waveform properties (``wf_increment``) becomes a time-history
    channel named ``group/channel``; channels sharing rate, length and start offset are
    stacked. Units come from ``unit_string``.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    units : str or list of str, optional
        Units for channels whose ``unit_string`` is empty.
    fs : float, optional
        Sampling rate in Hz for channels without ``wf_increment``.
    allow_truncated : bool, default False
        Read a file that npTDMS reports as damaged (short last segment) with a
        ``DataRepairWarning`` instead of raising ``FormatError``.
    """
    try:
        from nptdms import TdmsFile
    except ImportError as err:
        raise MissingDependencyError(
            "reading TDMS needs the optional dependency npTDMS (LGPL): "
            "pip install 'mvtk[tdms]'  (or: pip install npTDMS)"
        ) from err
    handler = _Collect()
    logger = logging.getLogger("nptdms")
    logger.addHandler(handler)
    try:
        tdms = TdmsFile.read(path)
    except Exception as err:  # npTDMS raises ValueError, KeyError, struct errors...
        raise FormatError(
            f"{path}: not a readable TDMS file ({type(err).__name__}: {err}); expected "
            "segments starting with the 'TDSm' lead-in"
        ) from err
    finally:
        logger.removeHandler(handler)
    if handler.messages:
        msg = f"{path}: npTDMS reports a damaged file: {'; '.join(handler.messages)}"
        if not allow_truncated:
            raise FormatError(msg + "; pass allow_truncated=True to read what is present")
        warnings.warn(msg + "; read the samples present", DataRepairWarning, stacklevel=3)
    items = []
    for group in tdms.groups():
        for ch in group.channels():
            props = ch.properties
            name = f"{group.name}/{ch.name}"
            values = np.asarray(ch[:])
            if values.dtype.kind not in "iuf":
                raise FormatError(
                    f"{path}, channel {name!r}: {values.dtype} data; expected numeric samples"
                )
            inc = props.get("wf_increment")
            if inc is not None:
                rate = fs_from_dt(float(inc))
            elif fs is not None:
                rate = float(fs)
            else:
                raise FormatError(
                    f"{path}, channel {name!r}: no wf_increment property; expected waveform "
                    "channels or fs=<Hz>"
                )
            unit = str(props.get("unit_string", "")).strip()
            if not unit:
                if units is None:
                    raise FormatError(
                        f"{path}, channel {name!r}: no unit_string property; expected units "
                        "in the file or units=..."
                    )
                unit = units if isinstance(units, str) else list(units)[len(items)]
            declared = props.get("wf_samples")
            if declared is not None and int(declared) != values.size:
                warnings.warn(
                    f"{path}, channel {name!r}: wf_samples says {int(declared)} but "
                    f"{values.size} samples are stored; all stored samples were read",
                    DataRepairWarning,
                    stacklevel=3,
                )
            start = props.get("wf_start_time")
            items.append(
                {
                    "name": name,
                    "data": values,
                    "fs": rate,
                    "t0": float(props.get("wf_start_offset", 0.0)),
                    "units": normalize_units(unit),
                    "start": "" if start is None else str(start),
                }
            )
    if not items:
        raise FormatError(f"{path}: no channels in the TDMS file; expected waveform channels")
    groups: dict[tuple, list[dict]] = {}
    for it in items:
        groups.setdefault((it["fs"], it["data"].size, it["t0"], it["start"]), []).append(it)
    variables = []
    for (rate, _, t0, start), members in groups.items():
        attrs = {"t0_s": t0} if t0 else {}
        if start:
            attrs["start_time"] = start
        block = np.stack([m["data"] for m in members])
        variables.append(
            build_time_history(
                block,
                rate,
                [m["name"] for m in members],
                [m["units"] for m in members],
                attrs=attrs,
            )
        )
    return assemble(variables, clean_attrs(dict(tdms.properties)))


def read_wav(path: Path, *, calibration=None, units=None, quantity=None, channels=None):
    """Read a WAV file; ``calibration`` converts raw samples to physical units.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    calibration : float or list of float, optional
        Physical units per raw sample unit (per count for integer PCM, per unit of full
        scale for float WAV), one value or one per channel. Without it the raw values are
        returned with units ``"counts"`` (integer PCM) or ``"FS"`` (float) and quantity
        ``"other"``.
    units, quantity : str or list of str, optional
        Units (required with ``calibration``) and quantity per channel.
    channels : list of str, optional
        Channel names (default ``ch1``, ``ch2``, ...).
    """
    import scipy.io.wavfile

    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            rate, samples = scipy.io.wavfile.read(path, mmap=False)
    except Exception as err:  # scipy raises struct.error, ZeroDivisionError... on damage
        raise FormatError(f"{path}: not a readable WAV file ({type(err).__name__}: {err})") from err
    for w in caught:
        raise FormatError(f"{path}: damaged WAV file: {w.message}")
    samples = np.asarray(samples)
    block = samples[np.newaxis, :] if samples.ndim == 1 else samples.T
    if block.shape[1] == 0:
        raise FormatError(f"{path}: WAV file holds no samples; expected at least one frame")
    raw_units = "FS" if block.dtype.kind == "f" else "counts"
    names = [f"ch{k + 1}" for k in range(block.shape[0])] if channels is None else list(channels)
    if len(names) != block.shape[0]:
        raise ParameterError(
            f"read({path}): {len(names)} channel names for {block.shape[0]} channels"
        )
    if calibration is None:
        if units is not None:
            raise ParameterError(
                f"read({path}): units={units!r} given without calibration=; raw WAV values "
                f"are in {raw_units}"
            )
        return assemble(
            [
                build_time_history(
                    block.astype(np.float64),
                    rate,
                    names,
                    raw_units,
                    "other",
                    attrs={"wav_dtype": str(samples.dtype)},
                )
            ]
        )
    if units is None:
        raise ParameterError(
            f"read({path}): calibration given without units=; expected the physical unit"
        )
    cal = np.asarray(calibration, dtype=np.float64).reshape(-1, 1)
    if cal.shape[0] not in (1, block.shape[0]) or not np.all(np.isfinite(cal)) or np.any(cal == 0):
        raise ParameterError(
            f"read({path}): calibration {calibration!r}; expected one non-zero finite factor or "
            f"{block.shape[0]} (one per channel)"
        )
    data = block.astype(np.float64) * cal
    attrs = {
        "wav_dtype": str(samples.dtype),
        "calibration": " ".join(repr(float(c)) for c in cal.ravel()),
    }
    return assemble([build_time_history(data, rate, names, units, quantity, attrs=attrs)])
