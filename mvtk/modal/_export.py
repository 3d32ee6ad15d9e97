"""Export of identified modes (UFF 55) and FRF matrices (UFF 58) through pyuff."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .._atomic import atomic_path
from ..errors import FormatError, ParameterError
from ._frf import as_frf_matrix
from ._result import IdentifiedModes

__all__ = ["write_modes_uff", "write_frf_uff"]

_COMP = {"x": 0, "y": 1, "z": 2, "rx": 3, "ry": 4, "rz": 5}
_CODE = {"x": 1, "y": 2, "z": 3, "rx": 4, "ry": 5, "rz": 6}
_FRF_UNITS = {"receptance": (1, "m/N"), "mobility": (11, "m/s/N"),
              "accelerance": (12, "m/s^2/N")}


def _pyuff():
    import pyuff

    return pyuff


def _split_dir(d: str) -> tuple[float, str]:
    d = str(d)
    sign = -1.0 if d.startswith("-") else 1.0
    return sign, d.lstrip("+-")


def write_modes_uff(modes: IdentifiedModes, path, *, shapes: str = "complex") -> Path:
    """Write identified modes as UFF 55 records (one per mode), overwriting ``path``.

    Parameters
    ----------
    modes : IdentifiedModes
    path : str or Path
    shapes : {"complex", "real"}
        ``complex``: analysis type 3 (complex eigenvalue, first order) with the pole
        ``lambda`` (rad/s) and the complex shapes; ``real``: analysis type 2 (normal
        modes) with frequency (Hz), viscous damping ratio and the real shapes.

    Every DOF needs a node label >= 0 and a direction ``+x..-rz``; the values of a DOF
    in a negative direction are written with the opposite sign on the positive axis.

    Raises
    ------
    ParameterError
        A DOF has no node or direction, or ``shapes`` is unknown.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from mvtk import modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> modes = modal.identify(h, 2.0, 110.0, refine=False)
    >>> write_modes_uff(modes, pathlib.Path(tempfile.mkdtemp()) / "modes.uff").name
    'modes.uff'
    """
    if shapes not in ("complex", "real"):
        raise ParameterError(f"shapes must be 'complex' or 'real', got {shapes!r}")
    da = modes.shapes if shapes == "complex" else modes.real_shapes
    nodes = da["node"].values.astype(int)
    dirs = [str(d) for d in da["direction"].values]
    for lab, n, d in zip(da["dof"].values, nodes, dirs):
        if n < 0 or _split_dir(d)[1] not in _COMP:
            raise ParameterError(
                f"write_modes_uff: DOF {lab!s} has node {n} and direction {d!r}; UFF 55 needs "
                "a node label >= 0 and a direction in +x..+rz / -x..-rz"
            )
    unodes = np.array(sorted(set(nodes.tolist())))
    rot = any(_split_dir(d)[1].startswith("r") for d in dirs)
    ncomp = 6 if rot else 3
    pyuff = _pyuff()
    sets = []
    for m in range(modes.n_modes):
        vals = np.zeros((unodes.size, ncomp), complex if shapes == "complex" else float)
        for k, (n, d) in enumerate(zip(nodes, dirs)):
            sign, c = _split_dir(d)
            vals[np.searchsorted(unodes, n), _COMP[c]] += sign * da.values[m, k]
        rec = dict(id1=f"mvtk {modes.method} mode {m + 1}", id2=f"{modes.fn_hz[m]:.6g} Hz",
                   id3=f"zeta {modes.zeta[m]:.6g}", id4=f"normalisation "
                   f"{da.attrs.get('normalisation', '')}", id5="NONE", model_type=1,
                   data_ch=2, spec_data_type=8, load_case=1, mode_n=m + 1,
                   node_nums=unodes.astype(float), type=55)
        if shapes == "complex":
            rec.update(analysis_type=3, eig=complex(modes.pole[m]), modal_a=1.0 + 0j,
                       modal_b=0.0 + 0j)
        else:
            rec.update(analysis_type=2, freq=float(modes.fn_hz[m]), modal_m=1.0,
                       modal_damp_vis=float(modes.zeta[m]), modal_damp_his=0.0)
        for c in range(ncomp):
            rec[f"r{c + 1}"] = vals[:, c]
        sets.append(rec)
    path = Path(path)
    with atomic_path(path) as tmp:
        pyuff.UFF(str(tmp)).write_sets(sets, mode="add")
    return path


def write_frf_uff(frf, path) -> Path:
    """Write an FRF matrix as UFF 58 records (function type 4, one per pair).

    ``frf`` follows the FRF-matrix convention (e.g. ``IdentifiedModes.synthesised``);
    response and reference node/direction go to the record's ``rsp_node``/``rsp_dir``
    and ``ref_node``/``ref_dir``. Frequencies must be uniform.

    Raises
    ------
    FormatError
        The frequency lines are not uniformly spaced.

    Examples
    --------
    Write the exact FRFs of the 2-mass chain and read them back:

    >>> import tempfile, pathlib
    >>> from mvtk import io, modal
    >>> K = np.array([[2e5, -1e5], [-1e5, 1e5]])
    >>> h = modal.exact_frf(np.eye(2), 0.5 * np.eye(2), K, np.arange(0.0, 120.0, 0.25),
    ...                     [0, 1], [0])
    >>> path = write_frf_uff(h, pathlib.Path(tempfile.mkdtemp()) / "frf.uff")
    >>> io.read(path)["frf"].shape
    (2, 1, 480)
    """
    h = as_frf_matrix(frf)
    f = h["frequency"].values
    df = np.diff(f)
    if not np.allclose(df, df[0], rtol=1e-6, atol=0):
        raise FormatError("write_frf_uff: UFF 58 needs uniformly spaced frequency lines")
    ord_type, units = _FRF_UNITS.get(h.attrs.get("frf_type", "other"), (0, ""))
    pyuff = _pyuff()
    sets = []
    for o in range(h.sizes["response"]):
        for i in range(h.sizes["reference"]):
            s_r, c_r = _split_dir(h["direction"].values[o])
            s_f, c_f = _split_dir(h["reference_direction"].values[i])
            sets.append(dict(
                type=58, binary=0, func_type=4, ver_num=0, load_case_id=0,
                id1=f"FRF {h['response'].values[o]!s} / {h['reference'].values[i]!s}",
                id2=str(h.attrs.get("estimator", "")), id3="NONE", id4="NONE", id5="NONE",
                rsp_ent_name="NONE", rsp_node=max(int(h["node"].values[o]), 0),
                rsp_dir=int(s_r * _CODE.get(c_r, 0)),
                ref_ent_name="NONE", ref_node=max(int(h["reference_node"].values[i]), 0),
                ref_dir=int(s_f * _CODE.get(c_f, 0)),
                ord_data_type=6, num_pts=f.size, abscissa_spacing=1,
                abscissa_min=float(f[0]), abscissa_inc=float(df[0]), z_axis_value=0.0,
                abscissa_spec_data_type=18, abscissa_len_unit_exp=0,
                abscissa_force_unit_exp=0, abscissa_temp_unit_exp=0,
                abscissa_axis_units_lab="Hz", ordinate_spec_data_type=ord_type,
                ordinate_len_unit_exp=0, ordinate_force_unit_exp=0,
                ordinate_temp_unit_exp=0, ordinate_axis_units_lab=units or "NONE",
                orddenom_spec_data_type=13, orddenom_len_unit_exp=0,
                orddenom_force_unit_exp=0, orddenom_temp_unit_exp=0,
                orddenom_axis_units_lab="N", z_axis_spec_data_type=0,
                z_axis_len_unit_exp=0, z_axis_force_unit_exp=0, z_axis_temp_unit_exp=0,
                z_axis_axis_units_lab="NONE",
                data=h.values[o, i].astype(complex), x=f.astype(float),
            ))
    path = Path(path)
    with atomic_path(path) as tmp:
        pyuff.UFF(str(tmp)).write_sets(sets, mode="add")
    return path
