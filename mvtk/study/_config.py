"""The study TOML: parsing, validation and path resolution.

Every key is described (type, default, units, doc) by :data:`mvtk.study.SCHEMA`
(:mod:`mvtk.study._schema`), against which :func:`load_study` validates the file; this
module adds the cross-key rules and resolves the files. Overview (see
``data/smart_beam/study.toml`` for a complete, commented example)::

    [study]            name, synthetic (bool)
    [structure]        file (structure TOML, relative to the study file)
    [measurements.impact]  file, reference, response, record_s, force_window_s, fn_hz
    [measurements.broadband]  same keys as impact: a short broadband impact test for the
                       higher modes (its modes are listed in damping.broadband_fn_hz)
    [measurements.decay]   file, channel, band_hz, fn_hz
    [measurements.<any name>]  kind = "impact" | "decay" | "multi-point" and the keys of
                       that kind: any number of hammer records, decays and further
                       multi-point tests (compared with [modal]), each with its own options
    [damping]          fn_hz, broadband_fn_hz, half_power_method, chowdhury_target_mass,
                       model_damping
    [fe]               n_modes
    [updating]         targets_hz, max_iter, [[updating.parameters]] path, initial,
                       lower, upper
    [reduction]        n_modes, n_compare, plant_modes, [[reduction.retained]] name, xyz
    [control]          actuator_nodes | actuators + sensors (+ sensing, zeta),
                       sensor_node, patch, actuator_limit_v,
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
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..errors import ConfigError
from ._schema import CONTROLLER_SCHEMAS, SCHEMA, STRUCTURE_TABLES, validate
from ._text import read_toml

__all__ = ["Study", "load_study", "CHECK_KEYS", "CONTROLLER_TYPES"]

SECTIONS = tuple(SCHEMA)
CHECK_KEYS = {k: v.default for k, v in SCHEMA["checks"].keys.items()}
UNCERTAINTY_DISTRIBUTIONS = SCHEMA["uncertainty"].keys["distribution"].choices
CONTROLLER_TYPES = tuple(CONTROLLER_SCHEMAS)


def multipoint_file(test: str, what: str) -> str:
    """Key in :attr:`Study.extra_files` of a file of the multi-point measurement ``test``
    (``what``: ``"file"``, ``"set_<k>"`` (1-based) or ``"geometry"``)."""
    return f"multipoint[{test}].{what}"


def _file(root: Path, rel: str, where: str, key: str = "file") -> Path:
    p = (root / rel).resolve()
    if not p.is_file():
        what = "is a directory" if p.is_dir() else "not found"
        raise ConfigError(f"{where}.{key}: {rel!r} {what} (looked for {p})")
    return p


@dataclass(frozen=True)
class Study:
    """A parsed and validated study.

    Attributes
    ----------
    path : Path
        The study TOML.
    config : dict
        The validated sections (defaults filled in, see :data:`mvtk.study.SCHEMA`).
    structure_file : Path or None
        The structure TOML (None when the structure is written inline in the study).
    measurement_files : dict of str to Path
        The file of each impact and decay test, by name (``"impact"``, ``"decay"``, ...).
        The files of a multi-point test are in ``extra_files`` (``modal_file``,
        ``modal_set_<k>``, ``modal_geometry`` of ``[modal]``; :func:`multipoint_file`
        names those of a multi-point measurement).
    structure : dict
        The structure description (parsed structure TOML or the inline tables).
    """

    path: Path
    config: dict
    structure_file: Path | None
    measurement_files: dict[str, Path] = field(default_factory=dict)
    structure: dict = field(default_factory=dict)
    extra_files: dict[str, Path] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return str(self.config["study"].get("name") or self.path.stem)

    @property
    def synthetic(self) -> bool:
        return bool(self.config["study"].get("synthetic", False))

    def section(self, name: str) -> dict | None:
        """A deep copy of a section, or None when it is absent."""
        s = self.config.get(name)
        return None if s is None else copy.deepcopy(s)

    def description(self) -> dict:
        """A deep copy of the structure description."""
        return copy.deepcopy(self.structure)

    @property
    def input_files(self) -> list[Path]:
        """Every file the study reads: the study, the structure, the mesh files the
        structure names (``file`` keys), the measurements and the modal files."""
        files = [self.path]
        if self.structure_file is not None:
            files.append(self.structure_file)
        files += _named_files(self.structure, self.structure_file or self.path)
        return files + list(self.measurement_files.values()) + list(self.extra_files.values())


def _named_files(desc: Any, base: Path) -> list[Path]:
    """Existing files named by a ``file`` key anywhere in a structure description."""
    out: list[Path] = []
    if isinstance(desc, Mapping):
        for key, val in desc.items():
            if key == "file" and isinstance(val, str):
                p = Path(val) if Path(val).is_absolute() else base.parent / val
                if p.is_file():
                    out.append(p)
            else:
                out += _named_files(val, base)
    elif isinstance(desc, list | tuple):
        for val in desc:
            out += _named_files(val, base)
    return out


def load_study(path: str | Path) -> Study:
    """Read and validate a study TOML against :data:`mvtk.study.SCHEMA`.

    Text is read as UTF-8, UTF-8 with a BOM or UTF-16 with a BOM. The structure is
    either ``[structure] file = "..."`` or the structure tables written inline (a
    ``[structure]`` table without ``file`` then holds the geometry, as in a structure
    TOML).

    Raises
    ------
    ConfigError
        Unknown sections or keys (with the accepted keys and a close match), missing
        keys, wrong types or missing files; the message names the file and dotted key.
    """
    p = Path(path)
    if p.is_dir():
        raise ConfigError(f"study file {str(p)!r} is a directory, expected a TOML file")
    if not p.exists():
        raise ConfigError(f"study file {str(p)!r} not found")
    raw = read_toml(p, "study file")
    src = str(p)
    st = raw.get("structure")
    inline = isinstance(st, Mapping) and "file" not in st
    if "structure" not in raw:
        raise ConfigError(f"{p}: missing [structure] section (file = \"structure.toml\" "
                          "or the structure tables inline)")
    tables = STRUCTURE_TABLES
    up = raw.get("updating")
    if inline and isinstance(up, Mapping) and up.get("builder") is not None:
        # a custom builder reads a description of its own: every non-study table
        tables = tuple(k for k in raw if k not in SCHEMA or k == "structure")
    cfg = validate(raw, src, inline_structure=inline, structure_tables=tables)
    cfg.setdefault("study", {})
    root = p.resolve().parent
    if inline:
        structure_file = None
        structure = {k: copy.deepcopy(raw[k]) for k in tables if k in raw}
        cfg = {k: v for k, v in cfg.items() if k not in tables}
    else:
        structure_file = _file(root, cfg["structure"]["file"], "structure")
        from ..fe._structure import resolve_mesh_file

        structure = resolve_mesh_file(read_toml(structure_file, "structure file"),
                                      structure_file.parent)

    files: dict[str, Path] = {}
    meas = cfg.get("measurements", {})
    extra: dict[str, Path] = {}
    for key, m in meas.items():
        if m.get("kind") != "multi-point":
            files[key] = _file(root, m["file"], f"measurements.{key}")
            continue
        # a further multi-point test: its files are inputs of the modal stage
        where = f"measurements.{key}"
        if "modal" not in cfg:
            raise ConfigError(f"{where}: a multi-point measurement needs a [modal] section "
                              "(the multi-point test whose shapes pair the updating targets; "
                              "the others are compared with it)")
        if m.get("file") is not None:
            extra[multipoint_file(key, "file")] = _file(root, m["file"], where)
        else:
            for k, name in enumerate(m["sets"]):
                extra[multipoint_file(key, f"set_{k + 1}")] = _file(root, name, where,
                                                                    f"sets[{k}]")
        if m.get("geometry") is not None:
            extra[multipoint_file(key, "geometry")] = _file(root, m["geometry"],
                                                            f"{where}.geometry")
        lo = m["fmin_hz"] if m.get("fmin_hz") is not None else cfg["modal"]["fmin_hz"]
        hi = m["fmax_hz"] if m.get("fmax_hz") is not None else cfg["modal"]["fmax_hz"]
        if hi <= lo:
            raise ConfigError(f"{where}: expected fmin_hz < fmax_hz, got {lo} and {hi} Hz")

    if "modal" in cfg:
        mo = cfg["modal"]
        if mo.get("file") is not None:
            extra["modal_file"] = _file(root, mo["file"], "modal")
        else:
            for k, name in enumerate(mo["sets"]):
                extra[f"modal_set_{k + 1}"] = _file(root, name, "modal", f"sets[{k}]")
        if mo.get("geometry") is not None:
            extra["modal_geometry"] = _file(root, mo["geometry"], "modal.geometry")
        if mo["fmax_hz"] <= mo["fmin_hz"]:
            raise ConfigError(f"modal: expected fmin_hz < fmax_hz, got {mo['fmin_hz']} and "
                              f"{mo['fmax_hz']} Hz")

    if "damping" in cfg:
        d = cfg["damping"]
        fn, bb = d["fn_hz"], d["broadband_fn_hz"]
        if bb and "broadband" not in meas:
            raise ConfigError("damping.broadband_fn_hz needs a [measurements.broadband] test")
        if bb and min(bb) <= max(fn):
            raise ConfigError(f"damping.broadband_fn_hz: expected modes above those of "
                              f"damping.fn_hz (max {max(fn)} Hz), got {bb!r}")

    if "reduction" in cfg:
        names = [str(it["name"]) for it in cfg["reduction"]["retained"]
                 if isinstance(it, Mapping) and it.get("name") is not None]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ConfigError(f"reduction.retained: names must be unique, got {names} "
                              f"({dup} repeated)")

    if "control" in cfg:
        c = cfg["control"]
        if "reduction" not in cfg:
            raise ConfigError("[control] needs a [reduction] section (the plant is the SE)")
        known = {str(it["name"]) for it in cfg["reduction"]["retained"]
                 if isinstance(it, Mapping) and it.get("name") is not None}
        if c.get("actuators") is None and c.get("actuator_nodes") is None:
            raise ConfigError("control.actuator_nodes: required (the two retained "
                              "actuator-edge nodes), or name piezo patches in "
                              "control.actuators")
        if c.get("actuators") is not None and c.get("sensors") is None:
            raise ConfigError("control.sensors: required with control.actuators (the "
                              "piezo patches or electrodes the controllers read)")
        for key in ("actuator_nodes", "sensor_node"):
            if c.get(key) is None:
                continue
            val = c[key]
            vals = val if isinstance(val, list) else [val]
            bad = [v for v in vals if v not in known]
            if bad:
                raise ConfigError(f"control.{key}: {bad} are not retained nodes; expected "
                                  f"names from reduction.retained {sorted(known)}")
        names = [str(ct["name"]) for ct in c["controllers"]]
        if len(set(names)) != len(names) or "open loop" in names:
            raise ConfigError(f"control.controllers: names must be unique and not "
                              f"'open loop', got {names}")

    if "uncertainty" in cfg:
        _check_uncertainty(cfg["uncertainty"])

    cfg["checks"] = {**CHECK_KEYS, **cfg.get("checks", {})}
    return Study(path=p.resolve(), config=cfg, structure_file=structure_file,
                 measurement_files=files, structure=structure, extra_files=extra)


def _check_uncertainty(u: dict) -> None:
    """Rules of ``[uncertainty]`` beyond the per-key schema."""
    sc = u["scatter"]
    if not sc:
        raise ConfigError(f"uncertainty.scatter: expected a table of dotted structure paths "
                          f"to relative standard deviations, got {sc!r}")
    for path, rel in sc.items():
        if not 0 < rel < 0.5:
            raise ConfigError(f"uncertainty.scatter.{path!r}: expected a relative standard "
                              f"deviation in (0, 0.5), got {rel!r}")
