"""Updating targets: measured natural frequencies with optional mode shapes."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ConfigError, DimensionError, ParameterError
from ..fe._model import DOF_NAMES

__all__ = ["FrequencyTarget", "targets_from_modal_result", "targets_from_shapes"]


def _normalise_shape(shape: Any, where: str) -> tuple[tuple[tuple[int, str], ...], np.ndarray]:
    """Sensors ((node, component), ...) and values from the accepted shape forms."""
    if isinstance(shape, Mapping) and {"nodes", "components", "values"} <= set(shape):
        nodes = list(shape["nodes"])
        comps = shape["components"]
        if isinstance(comps, str):
            comps = [comps] * len(nodes)
        comps = list(comps)
        values = list(shape["values"])
        if not len(nodes) == len(comps) == len(values):
            raise DimensionError(
                f"{where}: shape nodes, components and values must have equal lengths, "
                f"got {len(nodes)}, {len(comps)}, {len(values)}"
            )
        items = list(zip(zip(nodes, comps), values))
    elif isinstance(shape, Mapping):
        items = list(shape.items())
    else:
        raise ParameterError(
            f"{where}: shape must be a mapping {{(node, component): value}} or "
            f"{{'nodes': [...], 'components': [...], 'values': [...]}}, got "
            f"{type(shape).__name__}"
        )
    if len(items) < 2:
        raise DimensionError(f"{where}: a mode shape needs at least 2 sensor values")
    sensors = []
    for key, _ in items:
        try:
            node, comp = key
            node = int(node)
        except (TypeError, ValueError):
            raise ParameterError(
                f"{where}: shape key must be (node, component), got {key!r}"
            ) from None
        if comp not in DOF_NAMES:
            raise ParameterError(
                f"{where}: unknown DOF component {comp!r}; expected one of {DOF_NAMES}"
            )
        sensors.append((node, str(comp)))
    values = np.asarray([v for _, v in items], dtype=float)
    if not np.all(np.isfinite(values)) or not np.any(values):
        raise ParameterError(f"{where}: shape values must be finite and not all zero")
    return tuple(sensors), values


def _observed_shape(shape: Mapping, where: str):
    """``{"values": [...], "observation": C}``: the shape is ``C @ phi`` of the model."""
    import scipy.sparse as sp

    unknown = set(shape) - {"values", "observation", "labels"}
    if unknown or "values" not in shape:
        raise ParameterError(
            f"{where}: an observed shape needs keys 'values' and 'observation' (optional "
            f"'labels'), got {sorted(shape)}"
        )
    values = np.asarray(shape["values"], dtype=float).ravel()
    C = shape["observation"]
    C = getattr(C, "matrix", C)
    C = sp.csr_matrix(C) if sp.issparse(C) else sp.csr_matrix(np.asarray(C, dtype=float))
    if C.shape[0] != values.size:
        raise DimensionError(
            f"{where}: observation has {C.shape[0]} rows for {values.size} shape values"
        )
    if values.size < 2:
        raise DimensionError(f"{where}: a mode shape needs at least 2 sensor values")
    if not np.all(np.isfinite(values)) or not np.any(values):
        raise ParameterError(f"{where}: shape values must be finite and not all zero")
    labels = tuple(str(v) for v in shape.get("labels", range(values.size)))
    return labels, values, C


@dataclass(frozen=True, eq=False)
class FrequencyTarget:
    """A measured natural frequency the model must reach.

    Parameters
    ----------
    fn_hz : float
        Measured natural frequency in Hz.
    weight : float
        Weight of the relative residual ``(f_model - fn_hz) / fn_hz`` (default 1).
    mode : int, optional
        Force pairing with this model mode (1-based, ascending frequency).
    label : str, optional
        Name in tables (default ``"f{i}"``).
    shape : mapping, optional
        Measured mode shape at sensor DOFs, either ``{(node, "uz"): value, ...}`` or
        ``{"nodes": [...], "components": [...] or "uz", "values": [...]}``. Real
        (normal-mode) values; node numbers are model node indices. Used for MAC pairing
        and the optional 1 - MAC residuals. Or ``{"values": [...], "observation": C}``
        with ``C`` an observation matrix (n_sensors, n_dof) or a
        :class:`mvtk.correlation.DofMapping` (sensors anywhere on the mesh, skewed
        directions): the model's shape at the sensors is ``C @ phi`` (see
        :func:`targets_from_shapes`).
    kind : str, optional
        Mode type (``"bending"``, ``"torsion"``, ...) checked when pairing by order.
    std_hz : float, optional
        Standard deviation of ``fn_hz`` from its identification, Hz (e.g. the
        ``fn_std_hz`` of :class:`mvtk.modal.IdentifiedModes`). :func:`update` weights
        the target by ``1 / sigma^2`` with ``sigma^2 = std_hz^2 + (model_form_std
        fn_hz)^2`` and tells noise from model form in its residual verdicts.

    Attributes
    ----------
    sensors : tuple of (int, str)
        Sensor DOFs of ``shape`` (empty without a shape).
    shape_values : ndarray or None
        Shape values in the order of ``sensors``.

    Examples
    --------
    A measured 116 Hz mode with its shape at three nodes (uz), and one without a shape:

    >>> t1 = FrequencyTarget(116.0, shape={"nodes": [7, 14, 20], "components": "uz",
    ...                                    "values": [-0.5, -0.3, 0.9]})
    >>> t2 = FrequencyTarget(18.6, weight=2.0, label="first bending")
    >>> t1.fn_hz, t2.label
    (116.0, 'first bending')
    """

    fn_hz: float
    weight: float = 1.0
    mode: int | None = None
    label: str | None = None
    shape: Any = None
    kind: str | None = None
    std_hz: float | None = None

    def __post_init__(self) -> None:
        where = f"target {self.label or self.fn_hz!r}"
        f = self.fn_hz
        if isinstance(f, bool) or not isinstance(f, int | float | np.floating | np.integer):
            raise ParameterError(f"{where}: fn_hz must be a number in Hz, got {f!r}")
        if not (math.isfinite(f) and f > 0):
            raise ParameterError(f"{where}: fn_hz must be positive and finite, got {f!r}")
        object.__setattr__(self, "fn_hz", float(f))
        w = self.weight
        if isinstance(w, bool) or not isinstance(w, int | float) or not (
            math.isfinite(w) and w >= 0
        ):
            raise ParameterError(f"{where}: weight must be a finite number >= 0, got {w!r}")
        object.__setattr__(self, "weight", float(w))
        sd = self.std_hz
        if sd is not None:
            if isinstance(sd, bool) or not isinstance(
                    sd, int | float | np.floating | np.integer) or not (
                    math.isfinite(sd) and sd >= 0):
                raise ParameterError(
                    f"{where}: std_hz must be a finite number >= 0 in Hz, got {sd!r}")
            object.__setattr__(self, "std_hz", float(sd))
        if self.mode is not None:
            if isinstance(self.mode, bool) or int(self.mode) != self.mode or self.mode < 1:
                raise ParameterError(
                    f"{where}: mode must be a 1-based mode number, got {self.mode!r}"
                )
            object.__setattr__(self, "mode", int(self.mode))
        observation = None
        if isinstance(self.shape, Mapping) and "observation" in self.shape:
            sensors, values, observation = _observed_shape(self.shape, where)
        elif self.shape is not None:
            sensors, values = _normalise_shape(self.shape, where)
        else:
            sensors, values = (), None
        object.__setattr__(self, "sensors", sensors)
        object.__setattr__(self, "shape_values", values)
        object.__setattr__(self, "observation", observation)

    @property
    def has_shape(self) -> bool:
        """True when a measured shape is attached."""
        return self.shape_values is not None

    @classmethod
    def from_dict(cls, d: Mapping[str, Any], where: str = "target") -> FrequencyTarget:
        """Build from a TOML table ``{fn_hz=..., weight=..., mode=..., std_hz=..., ...}``."""
        if not isinstance(d, Mapping):
            raise ConfigError(f"{where}: expected a table with an 'fn_hz' key, got {d!r}")
        allowed = {"fn_hz", "weight", "mode", "label", "shape", "kind", "std_hz"}
        unknown = set(d) - allowed
        if unknown:
            raise ConfigError(
                f"{where}: unknown keys {sorted(unknown)}; allowed: {sorted(allowed)}"
            )
        if "fn_hz" not in d:
            raise ConfigError(f"{where}: missing key 'fn_hz'")
        try:
            return cls(**dict(d))
        except (ParameterError, DimensionError) as err:
            raise ConfigError(f"{where}: {err}") from err

    @classmethod
    def from_modal_result(cls, result: Any, **kwargs: Any) -> list[FrequencyTarget]:
        """Targets from a modal/damping result; see :func:`targets_from_modal_result`."""
        return targets_from_modal_result(result, **kwargs)


def _fn_values(result: Any, name: str = "fn_hz") -> np.ndarray:
    """The ``name`` values (``fn_hz``, or ``fn_std_hz``: None where absent) of a result."""
    optional = name != "fn_hz"
    if hasattr(result, "columns") and name in getattr(result, "columns", ()):
        return np.asarray(result[name], dtype=float).ravel()
    if hasattr(result, "columns") and optional and "fn_hz" in result.columns:
        return None
    if isinstance(result, Mapping):
        if name not in result:
            if optional:
                return None
            raise ParameterError(
                f"modal result mapping has no 'fn_hz' key; keys: {sorted(map(str, result))}"
            )
        return np.asarray(result[name], dtype=float).ravel()
    if hasattr(result, "fn_hz"):
        v = getattr(result, name, None)
        return None if v is None else np.asarray(v, dtype=float).ravel()
    if isinstance(result, Sequence) and not isinstance(result, str):
        if not result:
            return np.array([])
        parts = [_fn_values(r, name) for r in result]
        if optional:
            parts = [np.full(_fn_values(r).size, np.nan) if v is None else v
                     for r, v in zip(result, parts)]
        return np.concatenate(parts)
    if hasattr(result, "to_dataframe"):
        return _fn_values(result.to_dataframe(), name)
    raise ParameterError(
        f"cannot read natural frequencies from a {type(result).__name__}: expected an "
        "object with an 'fn_hz' attribute, a table with an 'fn_hz' column, or a list of them"
    )


def targets_from_modal_result(
    result: Any,
    *,
    select: Sequence[int] | None = None,
    weights: Sequence[float] | None = None,
    labels: Sequence[str] | None = None,
) -> list[FrequencyTarget]:
    """Frequency targets from an identified modal/damping result.

    Parameters
    ----------
    result : object
        Anything carrying natural frequencies in Hz: an object with an ``fn_hz``
        attribute (scalar or array; e.g. a ``mvtk.damping`` result), a
        ``pandas.DataFrame`` with an ``fn_hz`` column, a mapping with key ``"fn_hz"``,
        an object with ``to_dataframe()``, or a list of any of these (one per mode).
        Where it also carries ``fn_std_hz`` (:class:`mvtk.modal.IdentifiedModes`, its
        table), each target gets that standard deviation as ``std_hz`` (none where NaN).
    select : sequence of int, optional
        0-based positions of the frequencies to keep (default all).
    weights, labels : sequence, optional
        Per selected target.

    Returns
    -------
    list of FrequencyTarget

    Examples
    --------
    >>> targets = targets_from_modal_result({"fn_hz": [18.6, 116.0]})
    >>> [t.fn_hz for t in targets]
    [18.6, 116.0]
    """
    fn = _fn_values(result)
    if fn.size == 0:
        raise ParameterError("modal result contains no natural frequency (fn_hz is empty)")
    std = _fn_values(result, "fn_std_hz")
    if std is None or std.size != fn.size:
        std = np.full(fn.size, np.nan)
    if select is not None:
        idx = list(select)
        bad = [i for i in idx if not -fn.size <= i < fn.size]
        if bad:
            raise ParameterError(
                f"select positions {bad} out of range for {fn.size} identified frequencies"
            )
        fn, std = fn[idx], std[idx]
    for name, seq in (("weights", weights), ("labels", labels)):
        if seq is not None and len(seq) != fn.size:
            raise DimensionError(f"expected {fn.size} {name}, got {len(seq)}")
    return [
        FrequencyTarget(
            float(f),
            weight=1.0 if weights is None else float(weights[i]),
            label=None if labels is None else labels[i],
            std_hz=float(std[i]) if np.isfinite(std[i]) else None,
        )
        for i, f in enumerate(fn)
    ]


def targets_from_shapes(
    shapes: Any,
    observation: Any,
    *,
    quality: Any = None,
    min_mpc: float = 0.0,
    labels: Sequence[str] | None = None,
) -> list[FrequencyTarget]:
    """Frequency + shape targets from identified modes on test DOFs.

    Parameters
    ----------
    shapes : xarray.DataArray ("mode", "dof")
        Identified shapes with an ``fn_hz`` coordinate (complex shapes are rotated to
        their most real phase and their real part is used).
    observation : mvtk.correlation.DofMapping or matrix
        Sensor mapping onto the model being updated (its ``dof`` labels select and order
        the test DOFs); or a matrix (n_dof_test, n_fe_dof) in the order of ``shapes``.
    quality : pandas.DataFrame, optional
        Per-mode identification quality (the ``mvtk.modal`` table), indexed by mode or
        with a ``mode`` column; ``mpc`` (0..1) and ``reliable`` (bool) are used: the
        weight of a target is its ``mpc`` (1 when absent or NaN), 0 when not
        ``reliable`` or when ``mpc < min_mpc``; ``fn_std_hz`` (when present and finite)
        becomes the target's ``std_hz``.
    min_mpc : float
    labels : sequence of str, optional

    Returns
    -------
    list of FrequencyTarget

    Examples
    --------
    Targets with shapes from the (here: FE) shapes at three sensors of a cantilever:

    >>> from mvtk.correlation import correlate, read_test_geometry
    >>> from mvtk.fe import IsotropicMaterial, Ply, cantilever_beam, modal_analysis
    >>> beam = cantilever_beam(0.3, 0.02, [Ply(IsotropicMaterial("steel", 2.1e11, 0.3,
    ...                                                          7850.0), 2e-3)])
    >>> geo = read_test_geometry({"nodes": [{"node": i, "x": 0.1 * i, "y": 0.0, "z": 0.0}
    ...                                     for i in (1, 2, 3)],
    ...                           "sensors": [{"node": i, "direction": "+z"} for i in (1, 2, 3)]})
    >>> c = correlate(geo, beam, modal_analysis(beam, 2))
    >>> targets = targets_from_shapes(c.fe, c.mapping)
    >>> [round(t.fn_hz, 1) for t in targets]
    [18.6, 116.3]
    """
    import xarray as xr

    if not isinstance(shapes, xr.DataArray) or set(shapes.dims) != {"mode", "dof"}:
        raise DimensionError(
            f"shapes must be a DataArray with dims ('mode', 'dof'), got "
            f"{getattr(shapes, 'dims', type(shapes).__name__)}"
        )
    shapes = shapes.transpose("mode", "dof")
    if "fn_hz" not in shapes.coords:
        raise ParameterError("shapes need an 'fn_hz' coordinate on 'mode'")
    dofs = getattr(observation, "dof", None)
    C = getattr(observation, "matrix", observation)
    if dofs is not None:
        have = {str(v) for v in shapes["dof"].values}
        missing = [d for d in dofs if d not in have]
        if missing:
            raise DimensionError(f"mapped DOFs {missing[:6]} are not in the identified shapes")
        shapes = shapes.sel(dof=list(dofs))
    vals = shapes.values
    if np.iscomplexobj(vals):
        vals = np.array([np.real(v * np.exp(-0.5j * np.angle(np.sum(v * v)))) for v in vals])
    modes = shapes["mode"].values
    w = np.ones(len(modes))
    std = np.full(len(modes), np.nan)
    if quality is not None:
        q = quality.set_index("mode") if "mode" in getattr(quality, "columns", ()) else quality
        for k, m in enumerate(modes):
            if m not in q.index:
                raise ParameterError(f"quality table has no row for mode {m}")
            row = q.loc[m]
            # NaN MPC (a one-DOF shape: no evidence either way) keeps the weight 1
            if "mpc" in q.columns and np.isfinite(float(row["mpc"])):
                w[k] = float(row["mpc"]) if float(row["mpc"]) >= min_mpc else 0.0
            if "reliable" in q.columns and not bool(row["reliable"]):
                w[k] = 0.0
            if "fn_std_hz" in q.columns:
                std[k] = float(row["fn_std_hz"])
    if labels is not None and len(labels) != len(modes):
        raise DimensionError(f"expected {len(modes)} labels, got {len(labels)}")
    dof_labels = [str(d) for d in shapes["dof"].values]
    return [
        FrequencyTarget(
            float(shapes["fn_hz"].values[k]), weight=float(w[k]),
            label=labels[k] if labels is not None else f"mode {modes[k]}",
            shape={"values": vals[k], "observation": C, "labels": dof_labels},
            std_hz=float(std[k]) if np.isfinite(std[k]) else None,
        )
        for k in range(len(modes))
    ]
