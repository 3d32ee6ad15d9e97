"""Universal File Format datasets 58 / 58b (functions) and 55 (mode shapes), via pyuff."""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from .._interrupt import deferred_interrupt
from ..errors import (
    DataRepairWarning,
    FormatError,
    MissingDependencyError,
    MvtkWarning,
    UnsupportedFormatError,
)
from ._build import assemble
from ._model import build_time_history, fs_from_dt, infer_quantity, normalize_units

__all__ = ["read_uff", "sniff_uff", "UFF_EXTENSIONS", "FUNCTION_TYPES"]

UFF_EXTENSIONS = (".uff", ".unv", ".uf", ".58")

#: UFF 58 function types read by mvtk -> variable name in the Dataset.
FUNCTION_TYPES = {
    1: "time_history",
    2: "auto_spectrum",
    3: "cross_spectrum",
    4: "frf",
    5: "transmissibility",
    6: "coherence",
    9: "psd",
    12: "spectrum",
}
_TWO_POINT = {"cross_spectrum", "frf", "transmissibility"}
_DIRS = {1: "x", 2: "y", 3: "z", 4: "rx", 5: "ry", 6: "rz"}
_NONE = {"", "NONE", "none"}


def sniff_uff(head: bytes) -> bool:
    """True when the file starts with a UFF delimiter line ``-1`` followed by a dataset number."""
    lines = [ln.strip() for ln in head.splitlines()[:3]]
    lines = [ln for ln in lines if ln]
    return len(lines) >= 2 and lines[0] == b"-1" and lines[1][:6].strip().isdigit()


def _direction(code: int) -> str:
    code = int(code)
    if code == 0:
        return ""
    label = _DIRS.get(abs(code), str(abs(code)))
    return ("-" if code < 0 else "") + label


def _text(value) -> str:
    return str(value).strip() if value is not None else ""


def _label(rec: dict, which: str, index: int) -> str:
    node, code = int(rec.get(f"{which}_node", 0)), int(rec.get(f"{which}_dir", 0))
    if node > 0 or code != 0:
        return f"{node}:{_direction(code)}" if code else str(node)
    ent = _text(rec.get(f"{which}_ent_name"))
    if ent not in _NONE:
        return ent
    ident = _text(rec.get("id1"))
    return ident if ident not in _NONE else f"record {index}"


def _check_units_text(units: str, path: Path, index: int) -> str:
    if "\ufffd" in units:
        warnings.warn(
            f"{path}, record {index}: units {units!r} contain a byte that is not valid UTF-8 "
            "(shown as U+FFFD); the label is kept as read, check it",
            DataRepairWarning,
            stacklevel=5,
        )
    return units


def _check_points(rec: dict, path: Path, index: int, allow_truncated: bool) -> np.ndarray:
    data = np.asarray(rec.get("data", []))
    declared = int(rec.get("num_pts", data.size))
    if data.size == 0:
        raise FormatError(f"{path}, record {index}: no data values; expected {declared} points")
    if data.size != declared:
        msg = (
            f"{path}, record {index}: header declares {declared} points but the record "
            f"holds {data.size} (truncated or corrupted record)"
        )
        if not allow_truncated or data.size > declared:
            raise FormatError(msg + "; pass allow_truncated=True to read the points present")
        warnings.warn(
            msg + f"; read the {data.size} points present", DataRepairWarning, stacklevel=4
        )
    if not np.all(np.isfinite(data)):
        i = int(np.flatnonzero(~np.isfinite(data))[0])
        raise FormatError(
            f"{path}, record {index}: value {i} is {data[i].item()!r}; expected finite values"
        )
    return data


def _abscissa(rec: dict, n: int, path: Path, index: int) -> np.ndarray:
    if int(rec.get("abscissa_spacing", 1)) == 1:
        return float(rec.get("abscissa_min", 0.0)) + np.arange(n) * float(rec["abscissa_inc"])
    x = np.asarray(rec.get("x", []), dtype=np.float64)
    if x.size != n:
        raise FormatError(
            f"{path}, record {index}: {x.size} abscissa values for {n} ordinates; expected equal"
        )
    return x


def _time_record(rec, data, path, index):
    if np.iscomplexobj(data):
        raise FormatError(
            f"{path}, record {index}: time response with complex ordinates; expected real values"
        )
    n = data.size
    inc = float(rec.get("abscissa_inc", 0.0))
    if int(rec.get("abscissa_spacing", 1)) != 1:
        x = _abscissa(rec, n, path, index)
        d = np.diff(x)
        if n < 2 or np.any(d <= 0) or np.any(np.abs(d - d.mean()) > 0.01 * d.mean()):
            raise FormatError(
                f"{path}, record {index}: uneven time abscissa; expected uniform sampling"
            )
        inc = float((x[-1] - x[0]) / (n - 1))
    if not np.isfinite(inc) or inc <= 0:
        raise FormatError(
            f"{path}, record {index}: abscissa increment {inc!r} s; expected a positive time step"
        )
    units = _check_units_text(_text(rec.get("ordinate_axis_units_lab")), path, index)
    if units in _NONE:
        raise FormatError(
            f"{path}, record {index}: no ordinate units; expected a unit label in the record header"
        )
    units = normalize_units(units)
    quantity = infer_quantity(units)
    name = _text(rec.get("id1"))
    if name in _NONE:
        name = _text(rec.get("rsp_ent_name"))
    if name in _NONE:
        name = _label(rec, "rsp", index)
    return {
        "name": name,
        "data": data,
        "fs": fs_from_dt(inc),
        "t0": float(rec.get("abscissa_min", 0.0)),
        "units": units,
        "quantity": quantity,
        "node": int(rec.get("rsp_node", -1)),
        "direction": _direction(rec.get("rsp_dir", 0)),
        "record": index,
    }


def _unique_names(items: list[dict], path: Path) -> list[str]:
    names = [it["name"] for it in items]
    dup = {n for n in names if names.count(n) > 1}
    if not dup:
        return names
    out = [f"{it['name']} #{it['record']}" if it["name"] in dup else it["name"] for it in items]
    warnings.warn(
        f"{path}: channel names {sorted(dup)} occur in several records; renamed with the record "
        "number ('name #record')",
        DataRepairWarning,
        stacklevel=5,
    )
    return out


def _time_variables(items: list[dict], path: Path) -> list[xr.DataArray]:
    groups: dict[tuple, list[dict]] = {}
    for it in items:
        groups.setdefault((it["fs"], it["data"].size, it["t0"]), []).append(it)
    out = []
    for (fs, _, t0), members in groups.items():
        names = _unique_names(members, path)
        dtype = np.result_type(*[m["data"].dtype for m in members])
        data = np.empty((len(members), members[0]["data"].size), dtype=dtype)
        for k, m in enumerate(members):
            data[k] = m["data"]
        attrs = {"t0_s": t0} if t0 != 0.0 else {}
        da = build_time_history(
            data,
            fs,
            names,
            [m["units"] for m in members],
            [m["quantity"] for m in members],
            node=[m["node"] for m in members],
            direction=[m["direction"] for m in members],
            attrs=attrs,
        )
        out.append(da.assign_coords(record=("channel", [m["record"] for m in members])))
    return out


def _spectral_variables(items: list[dict], path: Path) -> list[xr.DataArray]:
    groups: dict[tuple, list[dict]] = {}
    for it in items:
        groups.setdefault((it["kind"], it["f"].tobytes()), []).append(it)
    out = []
    for (kind, _), members in groups.items():
        f = members[0]["f"]
        values = np.stack([m["data"] for m in members])
        if np.iscomplexobj(values) and kind in ("psd", "auto_spectrum", "coherence"):
            if np.all(values.imag == 0):
                values = values.real.copy()
        units = sorted({m["units"] for m in members})
        attrs = {"units": units[0] if len(units) == 1 else ", ".join(units), "uff_function": kind}
        kinds = {m.get("frf_type", "") for m in members}
        if kind == "frf" and len(kinds) == 1 and "" not in kinds:
            attrs["frf_type"] = kinds.pop()  # from the record's data types and units
        rsp = [m["rsp"] for m in members]
        ref = [m["ref"] for m in members]
        pairs = list(zip(rsp, ref))
        u_rsp, u_ref = list(dict.fromkeys(rsp)), list(dict.fromkeys(ref))
        if kind in _TWO_POINT and len(set(pairs)) == len(pairs) == len(u_rsp) * len(u_ref):
            grid = np.empty((len(u_rsp), len(u_ref), f.size), dtype=values.dtype)
            for k, (a, b) in enumerate(pairs):
                grid[u_rsp.index(a), u_ref.index(b)] = values[k]
            da = xr.DataArray(
                grid,
                dims=("response", "reference", "frequency"),
                coords={
                    "response": np.array(u_rsp, dtype=object),
                    "reference": np.array(u_ref, dtype=object),
                    "frequency": f,
                },
                name=kind,
                attrs=attrs,
            )
        else:
            names = _unique_names(
                [
                    {"name": a if kind not in _TWO_POINT else f"{a}/{b}", "record": m["record"]}
                    for (a, b), m in zip(pairs, members)
                ],
                path,
            )
            coords = {"channel": np.array(names, dtype=object), "frequency": f}
            if kind in _TWO_POINT:
                coords["response"] = ("channel", np.array(rsp, dtype=object))
                coords["reference"] = ("channel", np.array(ref, dtype=object))
            da = xr.DataArray(
                values, dims=("channel", "frequency"), coords=coords, name=kind, attrs=attrs
            )
        da.frequency.attrs["units"] = "Hz"
        out.append(da)
    return out


def _spectral_record(rec, data, path, index, kind):
    f = _abscissa(rec, data.size, path, index)
    x_units = _text(rec.get("abscissa_axis_units_lab")).lower()
    x_type = int(rec.get("abscissa_spec_data_type", 0))
    if x_type not in (0, 18) or (x_units not in ("hz", "") and x_type != 18):
        raise UnsupportedFormatError(
            f"{path}, record {index}: {kind} over abscissa type {x_type} ({x_units!r}); expected "
            "frequency in Hz"
        )
    if f.size > 1 and np.any(np.diff(f) <= 0):
        raise FormatError(
            f"{path}, record {index}: frequencies do not increase strictly; expected an "
            "increasing abscissa in Hz"
        )
    units = _check_units_text(_text(rec.get("ordinate_axis_units_lab")), path, index)
    den = _check_units_text(_text(rec.get("orddenom_axis_units_lab")), path, index)
    frf_type = ""
    if kind == "frf":
        frf_type = _frf_type(int(rec.get("ordinate_spec_data_type", 0) or 0),
                             int(rec.get("orddenom_spec_data_type", 0) or 0), units, den)
        if den not in _NONE and units not in _NONE and "/" not in units:
            units = f"{units}/{den}"  # numerator over denominator: the FRF's own unit
    return {
        "kind": kind,
        "f": f,
        "data": data,
        "units": units,
        "frf_type": frf_type,
        "rsp": _label(rec, "rsp", index),
        "ref": _label(rec, "ref", index),
        "record": index,
    }


#: UFF 58 record 8/9 specific data types of FRF numerators, and the FRF they make
#: over a force (type 9 reaction force or 13 excitation force).
_FRF_OF_SPEC = {8: "receptance", 11: "mobility", 12: "accelerance"}
_FRF_OF_QUANTITY = {"displacement": "receptance", "velocity": "mobility",
                    "acceleration": "accelerance"}


_PER_UNIT = re.compile(r"^\(1/([^)]+)\)\*\(([^)]+)\)$")


def _frf_type(num_type: int, den_type: int, num_units: str, den_units: str) -> str:
    """FRF type of a UFF 58 FRF record: from the numerator/denominator data types, else
    from the numerator/denominator unit labels (``m/s^2`` over ``N``; a numerator label
    ``(1/N)*(m/s2)`` states both); ``""`` when neither tells. A ``m/s`` followed by a
    byte that is not UTF-8 (a Latin-1 superscript two, written by some tools) is read as
    ``m/s^2`` for this decision only (the label is kept as read)."""
    num_units = num_units.replace("m/s\ufffd", "m/s^2")
    m = _PER_UNIT.match(num_units.replace(" ", ""))
    if m is not None and den_units in _NONE:
        den_units, num_units = m.group(1), m.group(2)
    den_quantity = infer_quantity(normalize_units(den_units)) if den_units not in _NONE else ""
    den_is_force = den_type in (9, 13) or den_quantity == "force"
    if not den_is_force and den_type not in (0, 1) and den_units not in _NONE:
        return "other"
    if num_type in _FRF_OF_SPEC and (den_is_force or den_type in (0, 1)):
        return _FRF_OF_SPEC[num_type]
    if den_is_force and num_units not in _NONE:
        return _FRF_OF_QUANTITY.get(infer_quantity(normalize_units(num_units)), "")
    return ""


def _mode_variable(records: list[tuple[int, dict]], path: Path) -> xr.DataArray:
    first_idx, first = records[0]
    nodes = np.asarray(first["node_nums"], dtype=np.int64)
    n_comp = int(first.get("n_data_per_node", 3))
    if n_comp not in (3, 6):
        raise FormatError(f"{path}, record {first_idx}: {n_comp} values per node; expected 3 or 6")
    comps = ("ux", "uy", "uz", "rx", "ry", "rz")[:n_comp]
    shapes, fn, zeta, number, eig = [], [], [], [], []
    for index, rec in records:
        rec_nodes = np.asarray(rec.get("node_nums", []), dtype=np.int64)
        if not np.array_equal(rec_nodes, nodes) or int(rec.get("n_data_per_node", 3)) != n_comp:
            raise FormatError(
                f"{path}, record {index}: mode shape on other nodes/components than record "
                f"{first_idx}; expected all modes on the same {nodes.size} nodes x {n_comp}"
            )
        try:
            shape = np.stack([np.asarray(rec[f"r{k + 1}"]) for k in range(n_comp)], axis=1)
        except KeyError as err:
            raise FormatError(f"{path}, record {index}: missing component {err}") from err
        analysis = int(rec.get("analysis_type", 2))
        if analysis == 2:
            f = float(rec.get("freq", np.nan))
            z = float(rec.get("modal_damp_vis", 0.0))
            lam = complex(-z * 2 * np.pi * f, 2 * np.pi * f * np.sqrt(max(1 - z * z, 0.0)))
        elif analysis == 3:
            lam = complex(rec.get("eig", np.nan))
            f = abs(lam) / (2 * np.pi)
            z = -lam.real / abs(lam) if abs(lam) > 0 else np.nan
        else:
            raise UnsupportedFormatError(
                f"{path}, record {index}: UFF 55 analysis type {analysis}; expected 2 (normal "
                "mode) or 3 (complex eigenvalue)"
            )
        if not (np.isfinite(f) and np.all(np.isfinite(shape))):
            raise FormatError(f"{path}, record {index}: non-finite frequency or mode shape values")
        shapes.append(shape)
        fn.append(f)
        zeta.append(z)
        eig.append(lam)
        number.append(int(rec.get("mode_n", len(number) + 1)))
    values = np.stack(shapes)
    return xr.DataArray(
        values,
        dims=("mode", "node", "component"),
        coords={
            "mode": np.arange(1, len(records) + 1),
            "node": nodes,
            "component": np.array(comps, dtype=object),
            "fn_hz": ("mode", np.asarray(fn)),
            "damping_ratio": ("mode", np.asarray(zeta)),
            "eigenvalue": ("mode", np.asarray(eig, dtype=np.complex128)),
            "mode_number": ("mode", np.asarray(number, dtype=np.int64)),
            "record": ("mode", np.asarray([i for i, _ in records], dtype=np.int64)),
        },
        name="mode_shape",
        attrs={"units": "unscaled"},
    )


def _check_unterminated(uff, path: Path, n_sets: int) -> None:
    """Refuse trailing content after the last complete '-1 ... -1' dataset (a cut file)."""
    blocks = getattr(uff, "_block_ind", None)
    if blocks is None or len(blocks) == 0:
        return
    end = int(blocks[-1][1]) + 1
    with open(path, "rb") as fh:
        fh.seek(end)
        tail = fh.read()
    rest = tail[6:] if tail.startswith(b"    -1") else tail
    if rest.strip():
        raise FormatError(
            f"{path}, record {n_sets + 1}: data after the last complete dataset without a closing "
            "'-1' delimiter (truncated file); expected every dataset to end with '    -1'"
        )


def read_uff(path: Path, *, allow_truncated: bool = False):
    """Read UFF 58 / 58b function records and UFF 55 mode shapes.

    Parameters
    ----------
    path : pathlib.Path
        The file.
    allow_truncated : bool, default False
        Read a record that holds fewer points than its header declares (with a
        ``DataRepairWarning``) instead of raising ``FormatError``.
    """
    try:
        import pyuff
    except ImportError as err:  # pragma: no cover - pyuff is a base dependency
        raise MissingDependencyError("reading UFF needs pyuff: pip install pyuff") from err
    try:
        with deferred_interrupt():
            uff = pyuff.UFF(str(path))
            types = [int(t) for t in uff.get_set_types()]
    except Exception as err:
        raise FormatError(
            f"{path}: not a readable UFF file ({type(err).__name__}: {err}); expected "
            "'-1'-delimited datasets"
        ) from err
    if not types:
        raise FormatError(f"{path}: no UFF datasets found; expected at least one dataset 58 or 55")
    _check_unterminated(uff, path, len(types))
    times, spectra, modes = [], [], []
    for i, set_type in enumerate(types):
        index = i + 1
        if set_type == 0:
            raise FormatError(
                f"{path}, record {index}: dataset number unreadable; expected a line with the "
                "dataset number after the '-1' delimiter"
            )
        if set_type not in (55, 58):
            warnings.warn(
                f"{path}, record {index}: dataset type {set_type} is not measurement data "
                "(mvtk reads 58 and 55); skipped",
                MvtkWarning,
                stacklevel=3,
            )
            continue
        try:
            with deferred_interrupt():
                rec = uff.read_sets(i)
        except Exception as err:
            raise FormatError(
                f"{path}, record {index} (dataset {set_type}): could not be parsed "
                f"({type(err).__name__}: {err})"
            ) from err
        if set_type == 55:
            modes.append((index, rec))
            continue
        func = int(rec.get("func_type", 0))
        kind = FUNCTION_TYPES.get(func)
        if kind is None:
            raise UnsupportedFormatError(
                f"{path}, record {index}: UFF 58 function type {func}; expected one of "
                + ", ".join(f"{k} ({v})" for k, v in FUNCTION_TYPES.items())
            )
        data = _check_points(rec, path, index, allow_truncated)
        if kind == "time_history":
            times.append(_time_record(rec, data, path, index))
        else:
            spectra.append(_spectral_record(rec, data, path, index, kind))
    variables = _time_variables(times, path) + _spectral_variables(spectra, path)
    if modes:
        variables.append(_mode_variable(modes, path))
    if not variables:
        raise FormatError(f"{path}: no dataset 58 or 55 in the file; nothing to read")
    return assemble(variables)
