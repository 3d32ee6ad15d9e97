"""Controller comparison in the shape of the paper's section 4.3, and the ``[control]``
section of a study."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError, ParameterError
from ._controllers import LQR, PPF, SRF, LyapunovBangBang, VelocityFeedback
from ._metrics import added_damping, peak_reduction_db, settling_time, voltage_stats
from ._second_order import SecondOrderSystem
from ._simulate import Disturbance, release_state, simulate
from ._stability import stability_summary

__all__ = ["Scenario", "ComparisonResult", "compare_controllers", "run_control_section",
           "controller_from_dict", "switching_peak"]


@dataclass(frozen=True)
class Scenario:
    """The simulation case shared by all controllers of a comparison.

    Default: the paper's scenario, the plant released at rest from its first eigenmode
    shape with ``amplitude`` at ``output``, controller on at t = 0.

    Parameters
    ----------
    output : str
        Plant output used for the release amplitude, settling time and spectra.
    t_end, fs_out : float
        Duration (s) and output rate (Hz).
    release_mode : int or None
        1-based mode of the initial shape; ``None``: start at rest.
    amplitude : float
        Release amplitude at ``output`` (output units, e.g. m).
    disturbance : Disturbance, optional
    noise_std : float, optional
        Sensor noise (needs ``seed``).
    seed : int, optional
        Seed of the ``numpy.random.Generator`` used for random disturbance and noise.
    band : float
        Settling band as a fraction of the initial amplitude.
    method : str
        Simulation method for nonlinear laws (see :func:`simulate`).

    Examples
    --------
    Release from 1 mm at ``tip``, 4 s at 200 Hz (see :func:`compare_controllers`):

    >>> sc = Scenario(output="tip", t_end=4.0, fs_out=200.0, amplitude=1e-3)
    >>> sc.release_mode, sc.amplitude
    (1, 0.001)
    """

    output: str
    t_end: float = 5.0
    fs_out: float = 1000.0
    release_mode: int | None = 1
    amplitude: float = 1e-3
    disturbance: Disturbance | None = None
    noise_std: float | None = None
    seed: int | None = None
    band: float = 0.05
    method: str = "auto"


@dataclass(frozen=True)
class ComparisonResult:
    """Metrics per controller (rows) plus the simulated histories.

    Columns: ``settling_time_s`` (inf: not settled within the record), ``fn1_hz`` and
    ``zeta1`` (closed-loop mode 1 from the eigenvalues; NaN for nonlinear laws; for an
    unstable or marginal loop those of the worst pole, see
    :func:`~mvtk.control.added_damping`), ``added_damping1`` (NaN unless stable),
    ``peak_reduction_db`` (FFT peak at mode 1 vs the open loop), ``peak_voltage``,
    ``rms_voltage`` (actuator units), then the stability columns of
    :func:`~mvtk.control.stability_summary`: ``stable``, ``verdict``, ``max_real_pole``,
    ``min_closed_loop_zeta``, ``gain_margin_db``, ``phase_margin_deg``,
    ``critical_gain_factor``, ``critical_gain``, ``stability_source``,
    ``stability_reason``. The open-loop row carries the plant's own verdict (no margins).

    Examples
    --------
    Returned by :func:`compare_controllers`; ``to_dataframe`` gives one row per
    controller:

    >>> from mvtk.control import Scenario, VelocityFeedback, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> res = compare_controllers(plant, {"VF": VelocityFeedback(gain=1e-3)},
    ...                           Scenario(output="tip", t_end=4.0, fs_out=200.0))
    >>> res.to_dataframe().index.tolist(), sorted(res.simulations)
    (['open loop', 'VF'], ['VF', 'open loop'])
    """

    rows: tuple[dict, ...]
    simulations: Mapping = field(default_factory=dict)
    scenario: Scenario | None = None

    def to_dataframe(self):
        import pandas as pd

        return pd.DataFrame(list(self.rows)).set_index("controller")

    def _repr_html_(self) -> str:
        from .._table import html_table

        return html_table(self.to_dataframe(), caption="Controller comparison",
                          passed_column=None)

    def to_dict(self) -> dict:
        """JSON-friendly rows (inf/NaN as None)."""
        def clean(v):
            if isinstance(v, float) and not math.isfinite(v):
                return None
            if isinstance(v, np.bool_):
                return bool(v)
            return v

        return {"rows": [{k: clean(v) for k, v in r.items()} for r in self.rows]}


def compare_controllers(
    plant, controllers: Mapping, scenario: Scenario, methods: Mapping | None = None
) -> ComparisonResult:
    """Simulate the open loop and each controller on the same scenario and tabulate.

    Parameters
    ----------
    plant : SecondOrderSystem
    controllers : mapping name -> controller
    scenario : Scenario
    methods : mapping name -> str, optional
        Simulation method per controller (default ``scenario.method``).

    Examples
    --------
    Open loop versus velocity feedback on a 1 mm release (damping 0.01 and
    0.01 + G w / 2 = 0.0414):

    >>> from mvtk.control import Scenario, VelocityFeedback, modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> res = compare_controllers(plant, {"velocity": VelocityFeedback(gain=1e-3)},
    ...                           Scenario(output="tip", t_end=4.0, fs_out=200.0))
    >>> [(r["controller"], round(r["zeta1"], 4)) for r in res.rows]
    [('open loop', 0.01), ('velocity', 0.0414)]
    """
    methods = dict(methods or {})
    if not isinstance(scenario, Scenario):
        raise ParameterError(f"scenario must be a Scenario, got {type(scenario).__name__}")
    if not isinstance(plant, SecondOrderSystem):
        raise ParameterError(
            f"compare_controllers needs a SecondOrderSystem plant, got {type(plant).__name__}"
        )
    if scenario.output not in plant.outputs:
        raise ParameterError(
            f"scenario output {scenario.output!r} is not a plant output {list(plant.outputs)}"
        )
    x0 = None
    if scenario.release_mode is not None:
        x0 = release_state(plant, scenario.release_mode, scenario.output, scenario.amplitude)

    def run(ctrl, method):
        rng = np.random.default_rng(scenario.seed) if scenario.seed is not None else None
        return simulate(plant, ctrl, t_end=scenario.t_end, fs_out=scenario.fs_out, initial=x0,
                        disturbance=scenario.disturbance, noise_std=scenario.noise_std,
                        rng=rng, method=method)

    sims = {"open loop": run(None, "auto")}
    for name, ctrl in controllers.items():
        sims[str(name)] = run(ctrl, methods.get(name, scenario.method))
    y_open = sims["open loop"].outputs.sel(output=scenario.output).values
    ref = scenario.amplitude if scenario.release_mode is not None else None
    ref = ref if ref else float(np.max(np.abs(y_open)))
    from ._metrics import closed_loop_modes

    open_modes = closed_loop_modes(plant)
    nan = float("nan")
    forced = scenario.noise_std is not None or (
        scenario.disturbance is not None and scenario.disturbance.kind != "impulse")
    osc = open_modes.eigenvalues.imag > 0
    f1, z1 = float(open_modes.fn_hz[osc][0]), float(open_modes.zeta[osc][0])
    rows = []
    for name, ds in sims.items():
        y = ds.outputs.sel(output=scenario.output).values
        t = ds.time.values
        row = {"controller": name,
               "settling_time_s": settling_time(y, t, band=scenario.band, reference=ref)}
        ctrl = controllers.get(name) if name != "open loop" else None
        if ctrl is None:
            row.update(fn1_hz=f1, zeta1=z1, added_damping1=0.0)
        elif getattr(ctrl, "u_max", None) is None and not isinstance(ctrl, LyapunovBangBang):
            ad = added_damping(plant, ctrl, 1)
            row.update(fn1_hz=ad["fn_hz_closed"], zeta1=ad["zeta_closed"],
                       added_damping1=ad["added"])
        else:
            row.update(fn1_hz=float("nan"), zeta1=float("nan"), added_damping1=float("nan"))
        row["peak_reduction_db"] = float(peak_reduction_db(y_open, y, scenario.fs_out, [f1])[0])
        v = voltage_stats(ds.inputs.values[0])
        row.update(peak_voltage=v["peak"], rms_voltage=v["rms"])
        if ctrl is None:
            ov = open_modes.verdict
            row.update(stable=ov.stable, verdict=ov.verdict, max_real_pole=ov.max_real_pole,
                       min_closed_loop_zeta=ov.min_zeta, gain_margin_db=nan,
                       phase_margin_deg=nan, critical_gain_factor=nan, critical_gain=nan,
                       stability_source="eigenvalues", stability_reason=ov.reason)
        else:
            row.update(stability_summary(plant, ctrl, ds, forced=forced))
        rows.append(row)
    return ComparisonResult(rows=tuple(rows), simulations=sims, scenario=scenario)


_CONTROLLERS = {"ppf": PPF, "srf": SRF, "velocityfeedback": VelocityFeedback,
                "velocity": VelocityFeedback, "lqr": LQR, "lyapunovbangbang": LyapunovBangBang,
                "lyapunov": LyapunovBangBang}


def controller_from_dict(spec: Mapping, switching_peak: float | None = None):
    """Build a controller from a study TOML table.

    ``type`` is one of PPF, SRF, VelocityFeedback, LQR, LyapunovBangBang (case
    insensitive). Filter controllers take ``targets = [[f_hz, zeta_f, gain], ...]`` or a
    single ``f_hz``, ``zeta_f``, ``gain``. ``LyapunovBangBang`` takes ``boundary_layer``
    or ``boundary_layer_rel`` (times ``switching_peak``, the largest ``|B'q'|`` of the
    open loop). ``name`` and ``method`` (the simulation method, read by
    :func:`run_control_section`) are ignored here. Other keys go to the controller.

    Examples
    --------
    >>> controller_from_dict({"type": "PPF", "f_hz": 10.0, "zeta_f": 0.1, "gain": 0.5}).targets
    ((10.0, 0.1, 0.5),)
    """
    if not isinstance(spec, Mapping) or "type" not in spec:
        raise ConfigError(
            f"a controller table needs a 'type' in {sorted(_CONTROLLERS)}, got {spec!r}"
        )
    kind = str(spec["type"]).lower()
    if kind not in _CONTROLLERS:
        raise ConfigError(
            f"unknown controller type {spec['type']!r}; expected one of "
            "PPF, SRF, VelocityFeedback, LQR, LyapunovBangBang"
        )
    args = {k: v for k, v in spec.items() if k not in ("type", "name", "method")}
    cls = _CONTROLLERS[kind]
    if cls in (PPF, SRF):
        if "targets" in args:
            args["targets"] = tuple(tuple(t) for t in args["targets"])
        else:
            try:
                args["targets"] = ((args.pop("f_hz"), args.pop("zeta_f"), args.pop("gain")),)
            except KeyError as err:
                raise ConfigError(
                    f"controller {spec.get('name', kind)!r}: expected 'targets' or f_hz, "
                    f"zeta_f and gain; missing {err}"
                ) from err
    if cls is LyapunovBangBang and "boundary_layer_rel" in args:
        rel = float(args.pop("boundary_layer_rel"))
        if switching_peak is None:
            raise ConfigError("boundary_layer_rel needs the open-loop switching peak")
        args["boundary_layer"] = rel * switching_peak
    try:
        return cls(**args)
    except TypeError as err:
        raise ConfigError(f"controller {spec.get('name', kind)!r}: {err}") from err


#: Keys of the study's [control] section that belong to the plant (read by the study).
_PLANT_KEYS = {"actuator_nodes", "sensor_node"}
_SECTION_KEYS = {"output", "initial_tip_displacement_m", "amplitude", "t_end_s", "t_end",
                 "fs_out", "settle_band", "band", "release_mode", "method", "disturbance",
                 "noise_std", "seed", "controllers"}


def run_control_section(plant, section: Mapping) -> ComparisonResult:
    """Run the ``[control]`` section of a study on ``plant`` (the SE plant).

    Keys (the study schema of :mod:`mvtk.study`; SI units, Hz)::

        [control]
        sensor_node = "tip"                 # or output = "tip": the plant output
        initial_tip_displacement_m = 2e-3   # release amplitude (or amplitude)
        t_end_s = 6.0                       # (or t_end)
        fs_out = 500.0
        settle_band = 0.05                  # (or band)
        release_mode = 1                    # optional, 0: start at rest
        method = "auto"                     # optional, see simulate()
        disturbance = {kind = "harmonic", at = "...", amplitude = 1.0, f_hz = 13.26}
        noise_std = 1e-6                    # optional, with seed
        seed = 1
        [[control.controllers]]
        name = "PPF"
        type = "PPF"
        f_hz = 13.26
        zeta_f = 0.3
        gain = 0.5
        method = "auto"                     # optional per controller, see simulate()

    ``controllers`` may also be a table of tables keyed by name.

    Examples
    --------
    The ``[control]`` table of a study as a mapping; velocity feedback adds
    ``G w / 2`` = 0.0314 to the 1 % of the mode:

    >>> from mvtk.control import modal_plant
    >>> plant = modal_plant([10.0], 0.01, B=np.array([[1.0]]), Cq=np.array([[1.0]]),
    ...                     inputs=["force"], outputs=["tip"])     # one mode: 10 Hz, 1 %
    >>> res = run_control_section(plant, {
    ...     "sensor_node": "tip", "initial_tip_displacement_m": 1e-3, "t_end_s": 4.0,
    ...     "fs_out": 200.0,
    ...     "controllers": [{"name": "VF", "type": "VelocityFeedback", "gain": 1e-3}]})
    >>> [(r["controller"], round(r["zeta1"], 4)) for r in res.rows]
    [('open loop', 0.01), ('VF', 0.0414)]
    """
    if not isinstance(section, Mapping):
        raise ConfigError(f"[control] must be a table, got {type(section).__name__}")
    unknown = sorted(set(section) - _SECTION_KEYS - _PLANT_KEYS)
    if unknown:
        raise ConfigError(
            f"[control]: unknown keys {unknown}; expected some of "
            f"{sorted(_SECTION_KEYS | _PLANT_KEYS)}"
        )
    ctrls = section.get("controllers")
    if isinstance(ctrls, Mapping):
        ctrls = [{"name": k, **dict(v)} for k, v in ctrls.items()]
    if not isinstance(ctrls, list) or not ctrls:
        raise ConfigError("[control] needs at least one [[control.controllers]] table")
    output = section.get("output", section.get("sensor_node"))
    if output is None:
        raise ConfigError(
            f"[control] needs 'sensor_node' or 'output' (one of {list(plant.outputs)})"
        )
    dist = section.get("disturbance")
    if dist is not None:
        try:
            dist = Disturbance(**dict(dist))
        except TypeError as err:
            raise ConfigError(f"[control.disturbance]: {err}") from err
    mode = section.get("release_mode", 1)
    amplitude = section.get("initial_tip_displacement_m", section.get("amplitude", 1e-3))
    scenario = Scenario(
        output=str(output), t_end=float(section.get("t_end_s", section.get("t_end", 5.0))),
        fs_out=float(section.get("fs_out", 1000.0)),
        release_mode=int(mode) if mode else None, amplitude=float(amplitude),
        disturbance=dist, noise_std=section.get("noise_std"), seed=section.get("seed"),
        band=float(section.get("settle_band", section.get("band", 0.05))),
        method=str(section.get("method", "auto")),
    )
    peak = None
    if any("boundary_layer_rel" in c for c in ctrls):
        peak = switching_peak(plant, scenario)
    controllers, methods = {}, {}
    for i, spec in enumerate(ctrls):
        name = str(spec.get("name", f"controller{i + 1}"))
        if name in controllers or name == "open loop":
            raise ConfigError(
                f"controller names must be unique and not 'open loop', got {name!r}"
            )
        controllers[name] = controller_from_dict(spec, peak)
        if "method" in spec:
            methods[name] = str(spec["method"])
    return compare_controllers(plant, controllers, scenario, methods)


def switching_peak(plant: SecondOrderSystem, scenario: Scenario, actuator: int = 0) -> float:
    """Largest ``|B' q'|`` of the open-loop scenario (scale for a Lyapunov boundary layer)."""
    x0 = None
    if scenario.release_mode is not None:
        x0 = release_state(plant, scenario.release_mode, scenario.output, scenario.amplitude)
    rng = np.random.default_rng(scenario.seed) if scenario.seed is not None else None
    ds = simulate(plant, None, t_end=scenario.t_end, fs_out=scenario.fs_out, initial=x0,
                  disturbance=scenario.disturbance, rng=rng)
    n = plant.n_coords
    return float(np.max(np.abs(plant.B[:, actuator] @ ds["states"].values[n:, :])))
