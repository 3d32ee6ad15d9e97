"""The study TOML: parsing, validation and path resolution.

Schema (see ``data/smart_beam/study.toml`` for a complete, commented example)::

    [study]            name, synthetic (bool)
    [structure]        file (structure TOML, relative to the study file)
    [measurements.impact]  file, reference, response, record_s, force_window_s
    [measurements.broadband]  same keys as impact: a short broadband impact test for the
                       higher modes (its modes are listed in damping.broadband_fn_hz)
    [measurements.decay]   file, channel, band_hz
    [damping]          fn_hz, broadband_fn_hz, half_power_method, chowdhury_target_mass,
                       model_damping
    [fe]               n_modes
    [updating]         targets_hz, max_iter, [[updating.parameters]] path, initial,
                       lower, upper
    [reduction]        n_modes, n_compare, plant_modes, [[reduction.retained]] name, xyz
    [control]          actuator_nodes, sensor_node, patch, actuator_limit_v,
                       initial_tip_displacement_m, t_end_s, fs_out, settle_band,
                       [[control.controllers]] name, type, ... (gains and u_max in V)
    [uncertainty]      optional Monte-Carlo propagation on the updated structure:
                       n_samples (>= 2), seed (int), n_modes (default 4),
                       distribution ("normal" | "lognormal"), and
                       [uncertainty.scatter] "dotted.path" = relative std (CoV of the
                       input, e.g. "materials.steel.E" = 0.03); the mean of each input
                       is its value in the updated (else nominal) structure
    [checks]           tolerances (ratios or seconds), see :data:`CHECK_KEYS`
    [references]       published values shown next to mvtk's (experiment_fn_hz, fe_fn_hz,
                       se_fn_hz, fe4_fn_hz, zeta, half_power_alpha/beta,
                       chowdhury_alpha/beta, fe_sizes, se_sizes, source)
    [truth]            synthetic data only: parameter values of the simulated specimen,
                       by dotted path (checked against the updated values), and
                       optionally rayleigh_alpha, rayleigh_beta (the damping of every
                       simulated mode; identified higher modes are checked against it)

Every section but ``[study]`` and ``[structure]`` is optional: a missing section skips
its stage (reported as "not configured").
"""

from __future__ import annotations

import copy
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ConfigError

__all__ = ["Study", "load_study", "CHECK_KEYS", "CONTROLLER_TYPES"]

SECTIONS = ("study", "structure", "measurements", "damping", "fe", "updating", "reduction",
            "control", "uncertainty", "checks", "references", "truth")
CHECK_KEYS = {
    "identified_fn_rel": 0.005,
    "identified_zeta_rel": 0.10,
    "rayleigh_rel": 0.05,
    "updated_fn_rel": 0.005,
    "se_fn_rel": 0.05,
    "ppf_settling_s": 1.5,
    "closed_loop_zeta_min": 0.005,
    "truth_param_rel": 0.05,
    "uncertainty_cov_rel": 0.20,
}
UNCERTAINTY_DISTRIBUTIONS = ("normal", "lognormal")
CONTROLLER_TYPES = ("PPF", "SRF", "LyapunovBangBang", "VelocityFeedback")


def _need(d: Mapping, key: str, where: str) -> Any:
    if key not in d:
        raise ConfigError(f"{where}: missing key {key!r}")
    return d[key]


def _number(d: Mapping, key: str, where: str, default: float | None = None,
            positive: bool = True) -> float:
    if key not in d:
        if default is None:
            raise ConfigError(f"{where}: missing key {key!r} (a number)")
        return float(default)
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, int | float):
        raise ConfigError(f"{where}.{key}: expected a number, got {v!r}")
    if positive and not v > 0:
        raise ConfigError(f"{where}.{key}: expected a number > 0, got {v!r}")
    return float(v)


def _file(root: Path, d: Mapping, where: str) -> Path:
    rel = _need(d, "file", where)
    if not isinstance(rel, str):
        raise ConfigError(f"{where}.file: expected a path string, got {rel!r}")
    p = (root / rel).resolve()
    if not p.is_file():
        raise ConfigError(f"{where}.file: {rel!r} not found (looked for {p})")
    return p


@dataclass(frozen=True)
class Study:
    """A parsed and validated study.

    Attributes
    ----------
    path : Path
        The study TOML.
    config : dict
        The parsed TOML (with defaults filled in ``checks``).
    structure_file : Path
    measurement_files : dict of str to Path
        ``"impact"`` / ``"decay"`` when configured.
    """

    path: Path
    config: dict
    structure_file: Path
    measurement_files: dict[str, Path] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return str(self.config["study"].get("name", self.path.stem))

    @property
    def synthetic(self) -> bool:
        return bool(self.config["study"].get("synthetic", False))

    def section(self, name: str) -> dict | None:
        """A deep copy of a section, or None when it is absent."""
        s = self.config.get(name)
        return None if s is None else copy.deepcopy(s)

    @property
    def input_files(self) -> list[Path]:
        return [self.path, self.structure_file, *self.measurement_files.values()]


def load_study(path: str | Path) -> Study:
    """Read and validate a study TOML.

    Raises
    ------
    ConfigError
        Unknown sections, missing keys, wrong types or missing files; the message names
        the dotted key.
    """
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"study file {str(p)!r} not found")
    try:
        cfg = tomllib.loads(p.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"{p}: invalid TOML: {err}") from err
    unknown = sorted(set(cfg) - set(SECTIONS))
    if unknown:
        raise ConfigError(f"{p}: unknown sections {unknown}; expected some of {list(SECTIONS)}")
    root = p.resolve().parent
    if "study" not in cfg or not isinstance(cfg["study"], dict):
        raise ConfigError(f"{p}: missing [study] section")
    structure_file = _file(root, _need(cfg, "structure", str(p)), "structure")

    files: dict[str, Path] = {}
    meas = cfg.get("measurements", {})
    for key in meas:
        if key not in ("impact", "broadband", "decay"):
            raise ConfigError(f"measurements.{key}: unknown test; expected 'impact', "
                              "'broadband' or 'decay'")
        files[key] = _file(root, meas[key], f"measurements.{key}")
    for test in ("impact", "broadband"):
        if test in meas:
            m = meas[test]
            for k in ("reference", "response"):
                if not isinstance(_need(m, k, f"measurements.{test}"), str):
                    raise ConfigError(f"measurements.{test}.{k}: expected a channel name")
            _number(m, "record_s", f"measurements.{test}")
    if "decay" in meas:
        if not isinstance(_need(meas["decay"], "channel", "measurements.decay"), str):
            raise ConfigError("measurements.decay.channel: expected a channel name")
        band = meas["decay"].get("band_hz")
        if band is not None and not (isinstance(band, list) and len(band) == 2
                                     and 0 < band[0] < band[1]):
            raise ConfigError(f"measurements.decay.band_hz: expected [f_low, f_high] in Hz "
                              f"with 0 < f_low < f_high, got {band!r}")

    if "damping" in cfg:
        d = cfg["damping"]
        fn = _need(d, "fn_hz", "damping")
        if not (isinstance(fn, list) and fn and all(isinstance(v, int | float) and v > 0
                                                    for v in fn)):
            raise ConfigError(f"damping.fn_hz: expected a list of frequencies > 0, got {fn!r}")
        bb = d.get("broadband_fn_hz", [])
        if not (isinstance(bb, list) and all(isinstance(v, int | float) and v > 0
                                             for v in bb)):
            raise ConfigError(f"damping.broadband_fn_hz: expected a list of frequencies > 0, "
                              f"got {bb!r}")
        if bb and "broadband" not in meas:
            raise ConfigError("damping.broadband_fn_hz needs a [measurements.broadband] test")
        if bb and min(bb) <= max(fn):
            raise ConfigError(f"damping.broadband_fn_hz: expected modes above those of "
                              f"damping.fn_hz (max {max(fn)} Hz), got {bb!r}")
        tm = _number(d, "chowdhury_target_mass", "damping", default=0.95)
        if tm > 1:
            raise ConfigError(f"damping.chowdhury_target_mass: expected a fraction in (0, 1], "
                              f"got {tm!r}")
        md = d.get("model_damping", "half_power")
        if md not in ("half_power", "chowdhury"):
            raise ConfigError(f"damping.model_damping: expected 'half_power' or 'chowdhury', "
                              f"got {md!r}")

    if "updating" in cfg:
        u = cfg["updating"]
        t = _need(u, "targets_hz", "updating")
        if not (isinstance(t, list) and t and all(isinstance(v, int | float) and v > 0
                                                  for v in t)):
            raise ConfigError(f"updating.targets_hz: expected a list of frequencies > 0, "
                              f"got {t!r}")
        params = _need(u, "parameters", "updating")
        if not isinstance(params, list) or not params:
            raise ConfigError("updating.parameters: expected at least one [[updating.parameters]]")
        for i, par in enumerate(params):
            if not isinstance(_need(par, "path", f"updating.parameters[{i}]"), str):
                raise ConfigError(f"updating.parameters[{i}].path: expected a dotted path")

    if "reduction" in cfg:
        r = cfg["reduction"]
        n = r.get("n_modes", 10)
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise ConfigError(f"reduction.n_modes: expected an integer >= 0, got {n!r}")
        pm = r.get("plant_modes", 12)
        if isinstance(pm, bool) or not isinstance(pm, int) or pm < 1:
            raise ConfigError(f"reduction.plant_modes: expected an integer >= 1, got {pm!r}")
        retained = _need(r, "retained", "reduction")
        names = []
        for i, item in enumerate(retained):
            where = f"reduction.retained[{i}]"
            names.append(str(_need(item, "name", where)))
            xyz = _need(item, "xyz", where)
            if not (isinstance(xyz, list) and len(xyz) == 3):
                raise ConfigError(f"{where}.xyz: expected [x, y, z] in m, got {xyz!r}")
        if len(set(names)) != len(names):
            raise ConfigError(f"reduction.retained: names must be unique, got {names}")

    if "control" in cfg:
        c = cfg["control"]
        if "reduction" not in cfg:
            raise ConfigError("[control] needs a [reduction] section (the plant is the SE)")
        known = {str(it["name"]) for it in cfg["reduction"]["retained"]}
        for key in ("actuator_nodes", "sensor_node"):
            val = _need(c, key, "control")
            vals = val if isinstance(val, list) else [val]
            bad = [v for v in vals if v not in known]
            if bad:
                raise ConfigError(f"control.{key}: {bad} are not retained nodes; expected "
                                  f"names from reduction.retained {sorted(known)}")
        if len(c["actuator_nodes"]) != 2:
            raise ConfigError("control.actuator_nodes: expected the two actuator-edge nodes")
        for key in ("initial_tip_displacement_m", "t_end_s", "fs_out", "settle_band"):
            _number(c, key, "control")
        _number(c, "actuator_limit_v", "control", default=100.0)
        if "patch" in c and not isinstance(c["patch"], str):
            raise ConfigError(f"control.patch: expected a patch name of the structure file, "
                              f"got {c['patch']!r}")
        for i, ctrl in enumerate(c.get("controllers", [])):
            where = f"control.controllers[{i}]"
            _need(ctrl, "name", where)
            kind = _need(ctrl, "type", where)
            if kind not in CONTROLLER_TYPES:
                raise ConfigError(f"{where}.type: expected one of {CONTROLLER_TYPES}, "
                                  f"got {kind!r}")

    if "uncertainty" in cfg:
        _check_uncertainty(cfg["uncertainty"])

    checks = dict(CHECK_KEYS)
    for key in cfg.get("checks", {}):
        if key not in CHECK_KEYS:
            raise ConfigError(f"checks.{key}: unknown tolerance; expected one of "
                              f"{sorted(CHECK_KEYS)}")
        checks[key] = _number(cfg["checks"], key, "checks")
    cfg["checks"] = checks
    return Study(path=p.resolve(), config=cfg, structure_file=structure_file,
                 measurement_files=files)


def _int(d: Mapping, key: str, where: str, default: int, minimum: int) -> int:
    v = d.get(key, default)
    if isinstance(v, bool) or not isinstance(v, int) or v < minimum:
        raise ConfigError(f"{where}.{key}: expected an integer >= {minimum}, got {v!r}")
    return v


def _check_uncertainty(u: Any) -> None:
    """Validate ``[uncertainty]`` (schema in the module docstring)."""
    if not isinstance(u, dict):
        raise ConfigError(f"uncertainty: expected a table, got {u!r}")
    known = {"n_samples", "seed", "n_modes", "distribution", "scatter"}
    unknown = sorted(set(u) - known)
    if unknown:
        raise ConfigError(f"uncertainty: unknown keys {unknown}; expected some of "
                          f"{sorted(known)}")
    _int(u, "n_samples", "uncertainty", 40, 2)
    _int(u, "seed", "uncertainty", 0, 0)
    _int(u, "n_modes", "uncertainty", 4, 1)
    kind = u.get("distribution", "normal")
    if kind not in UNCERTAINTY_DISTRIBUTIONS:
        raise ConfigError(f"uncertainty.distribution: expected one of "
                          f"{UNCERTAINTY_DISTRIBUTIONS}, got {kind!r}")
    sc = _need(u, "scatter", "uncertainty")
    if not isinstance(sc, dict) or not sc:
        raise ConfigError(f"uncertainty.scatter: expected a table of dotted structure paths "
                          f"to relative standard deviations, got {sc!r}")
    for path, rel in sc.items():
        if isinstance(rel, bool) or not isinstance(rel, int | float) or not 0 < rel < 0.5:
            raise ConfigError(f"uncertainty.scatter.{path!r}: expected a relative standard "
                              f"deviation in (0, 0.5), got {rel!r}")
