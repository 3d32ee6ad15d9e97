"""The study TOML schema: one declarative description of every section and key.

:data:`SCHEMA` is plain data (:class:`Key` and :class:`Table` frozen dataclasses, with a
:meth:`Table.to_dict` for tools that generate documentation). :func:`validate` checks a
parsed TOML against it: unknown keys are refused in every section with the accepted keys
and a close-match suggestion, types and ranges are checked, and defaults are filled in.
Cross-key rules that a per-key schema cannot express (a retained node named in
``[control]`` must exist, broadband modes above the impact ones, ...) live in
:mod:`mvtk.study._config`.

Key types (``Key.type``):

``"str"``, ``"bool"``, ``"int"``, ``"number"`` (int or float), ``"path"`` (a file path
relative to the study file), ``"numbers"`` (list of numbers), ``"strings"`` (list of
strings), ``"xyz"`` (three numbers, m), ``"table"`` (a sub-table with its own
:class:`Table`), ``"tables"`` (an array of tables, ``[[a.b]]``, each an ``item``
:class:`Table`), ``"map"`` (free keys, each value of ``value_type``), ``"any"``.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ..errors import ConfigError

__all__ = ["Key", "Table", "SCHEMA", "CONTROLLER_SCHEMAS", "validate", "REQUIRED",
           "STRUCTURE_TABLES"]


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: Default marking a required key.
REQUIRED = _Required()

#: Top-level keys of a structure description (mvtk.fe.build_model) that a study may hold
#: inline instead of ``[structure] file = ...``.
STRUCTURE_TABLES = ("name", "materials", "structure", "patches", "mesh", "boundary", "points")


@dataclass(frozen=True)
class Key:
    """One key of a study table.

    Attributes
    ----------
    type : str
        See the module docstring.
    doc : str
        What the key means (one sentence or two).
    default : object
        Value used when the key is absent; :data:`REQUIRED` when it must be given, None
        when absence has a meaning of its own (described in ``doc``).
    units : str
        SI units of the value ("" when dimensionless).
    minimum, maximum : float, optional
        Bounds (inclusive unless ``exclusive_minimum``).
    choices : tuple
        Accepted values of a ``str`` key.
    ascending : bool
        ``numbers`` only: values must be strictly increasing (mode order).
    length : int, optional
        Exact length of a list.
    table : Table, optional
        Schema of a ``table`` value or of each item of ``tables``.
    value_type : str
        Type of each value of a ``map``.
    """

    type: str
    doc: str
    default: Any = None
    units: str = ""
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    exclusive_maximum: bool = False
    choices: tuple = ()
    ascending: bool = False
    length: int | None = None
    table: Table | None = None
    value_type: str = "number"
    allow_nan: bool = False
    min_length: int = 0

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def to_dict(self) -> dict:
        """Plain-dict form (for documentation generators)."""
        out: dict[str, Any] = {"type": self.type, "doc": self.doc, "units": self.units,
                               "required": self.required,
                               "default": None if self.required else self.default}
        for name in ("minimum", "maximum", "length"):
            if getattr(self, name) is not None:
                out[name] = getattr(self, name)
        if self.exclusive_minimum:
            out["exclusive_minimum"] = True
        if self.exclusive_maximum:
            out["exclusive_maximum"] = True
        if self.choices:
            out["choices"] = list(self.choices)
        if self.ascending:
            out["ascending"] = True
        if self.type == "map":
            out["value_type"] = self.value_type
        if self.table is not None:
            out["table"] = self.table.to_dict()
        return out


@dataclass(frozen=True)
class Table:
    """A table of the study TOML: its doc and its keys (name -> :class:`Key`).

    ``one_of`` lists groups of keys of which exactly one must be given (e.g.
    ``("targets_hz", "targets")``); ``at_most_one_of`` groups of which at most one.
    """

    doc: str
    keys: dict[str, Key] = field(default_factory=dict)
    one_of: tuple[tuple[str, ...], ...] = ()
    at_most_one_of: tuple[tuple[str, ...], ...] = ()

    def to_dict(self) -> dict:
        return {"doc": self.doc, "keys": {k: v.to_dict() for k, v in self.keys.items()},
                "one_of": [list(g) for g in self.one_of],
                "at_most_one_of": [list(g) for g in self.at_most_one_of]}


def _pos(doc, default=REQUIRED, units="", **kw) -> Key:
    return Key("number", doc, default, units, minimum=0.0, exclusive_minimum=True, **kw)


def _freqs(doc, default=REQUIRED) -> Key:
    return Key("numbers", doc, default, "Hz", minimum=0.0, exclusive_minimum=True,
               ascending=True, min_length=0 if default == [] else 1)


def _read_options() -> Key:
    return Key("map", "Reader options passed to mvtk.io.read for this file, for what the "
               "file does not state, e.g. {units = [\"N\", \"m/s^2\"], quantity = "
               "[\"force\", \"acceleration\"]} or {fs = 2048.0}; any keyword of "
               "mvtk.io.read (see the io guide).", {}, value_type="any")


_IMPACT = Table(
    "An impact (hammer) test: one record per hit, H1 FRF of response over reference.",
    {"file": Key("path", "Measurement file (any format of mvtk.io.read), relative to the "
                 "study file.", REQUIRED),
     "reference": Key("str", "Force channel name.", REQUIRED),
     "response": Key("str", "Response channel name.", REQUIRED),
     "record_s": _pos("Length of one record (one hit); None: chosen from the data "
                      "(the time between hits, zero-padded when the response has decayed), "
                      "as `mvtk damping` does.", None, units="s"),
     "force_window_s": _pos("Force window length after the hit (None: 4 x the measured "
                            "pulse width, as `mvtk damping` does).", None, "s"),
     "kind": Key("str", "Kind of the test: needed for a measurement named other than "
                 "impact/broadband/decay.", "impact", choices=("impact",)),
     "fn_hz": _freqs("Approximate resonances searched in this record (None: damping.fn_hz; "
                     "damping.broadband_fn_hz for 'broadband').", None),
     "read_options": _read_options()},
)

_DECAY = Table(
    "A free-decay record of one channel (envelope fit and logarithmic decrement of mode 1).",
    {"file": Key("path", "Measurement file, relative to the study file.", REQUIRED),
     "channel": Key("str", "Channel name of the decay.", REQUIRED),
     "band_hz": Key("numbers", "Band-pass [f_low, f_high] around mode 1 before the fits "
                    "(None: no filter).", None, "Hz", minimum=0.0, exclusive_minimum=True,
                    ascending=True, length=2),
     "kind": Key("str", "Kind of the test: needed for a measurement named other than "
                 "impact/broadband/decay.", "decay", choices=("decay",)),
     "fn_hz": _pos("Approximate frequency of the decaying mode (None: the first of "
                   "damping.fn_hz).", None, "Hz"),
     "read_options": _read_options()},
)

_MULTI = Table(
    "A further multi-point test of the specimen (kind = \"multi-point\"), beside the one of "
    "[modal]: another roving-hammer or roving-sensor test, a repeat, a test on another "
    "day. It is identified on its own (mvtk.modal.identify, pLSCF + LSFD) in the modal "
    "stage, and each of its modes is compared with the [modal] mode nearest in frequency "
    "(within modal.pair_within): frequency, damping and MAC on the DOFs both tests "
    "measured. [modal] stays the test whose shapes pair the updating targets and are "
    "correlated with the FE model.",
    {"kind": Key("str", "Kind of the test: \"multi-point\".", REQUIRED,
                 choices=("multi-point",)),
     "file": Key("path", "FRF file (as modal.file), relative to the study file. Give either "
                 "'file' or 'sets'.", None),
     "sets": Key("strings", "Time-history files, one measurement set per file (as "
                 "modal.sets), relative to the study file.", None, min_length=1),
     "reference": Key("str", "Force channel of the sets (None: the channels whose quantity "
                      "is force).", None),
     "excitation": Key("str", "Excitation of the sets (auto: detected from the force).",
                       "auto", choices=("auto", "impact", "random", "sweep")),
     "geometry": Key("path", "Test geometry (as modal.geometry; None: that of [modal]).",
                     None),
     "fmin_hz": _pos("Lower end of the identification band (None: modal.fmin_hz).", None,
                     "Hz"),
     "fmax_hz": _pos("Upper end of the identification band (None: modal.fmax_hz).", None,
                     "Hz"),
     "max_order": Key("int", "Highest pLSCF model order (None: mvtk.modal's default).",
                      None, minimum=4),
     "read_options": _read_options()},
    one_of=(("file", "sets"),),
)

_PARAMETER = Table(
    "One updating parameter (mvtk.updating.Parameter).",
    {"path": Key("str", "Dotted path into the structure description, e.g. "
                 "'materials.steel.E'.", REQUIRED),
     "initial": Key("number", "Start value; a field absent from the structure is created "
                    "with it (None: the structure's value).", None),
     "lower": Key("number", "Lower bound (None: unbounded).", None),
     "upper": Key("number", "Upper bound (None: unbounded).", None),
     "fixed": Key("bool", "Keep the parameter at its initial value.", False),
     "scale": Key("number", "Scale of the optimisation variable (None: automatic).", None),
     "label": Key("str", "Label in tables (None: the path).", None),
     "log": Key("bool", "Optimise the logarithm of the parameter.", False)},
)

_TARGET = Table(
    "One updating target (mvtk.updating.FrequencyTarget).",
    {"fn_hz": _pos("Measured natural frequency.", units="Hz"),
     "weight": _pos("Weight of the residual.", 1.0),
     "mode": Key("int", "1-based model mode to pair with (None: automatic pairing).", None,
                 minimum=1),
     "label": Key("str", "Label in tables.", None),
     "shape": Key("numbers", "Measured mode shape at the model's sensor DOFs.", None),
     "kind": Key("str", "Mode kind the pairing must respect (bending, torsion, ...).",
                 None),
     "std_hz": Key("number", "Standard deviation of fn_hz from its identification "
                   "(None: the fn_std_hz of the [modal] mode paired with the target, if "
                   "any).", None, "Hz", minimum=0.0)},
)

_RETAINED = Table(
    "One retained (boundary) item of the super element: exactly one of xyz, node_set, "
    "node.",
    {"name": Key("str", "Label of the item (used by [control]).", None),
     "xyz": Key("xyz", "Point (m); the nearest FE node is retained, refused beyond the "
                "snap tolerance of mvtk.reduction.resolve_retained_config.", None, "m"),
     "node_set": Key("str", "Node set of the model.", None),
     "node": Key("int", "Node index of the model.", None, minimum=0)},
    one_of=(("xyz", "node_set", "node"),),
)

_CTRL_COMMON = {
    "name": Key("str", "Name of the controller in tables (unique, not 'open loop').",
                REQUIRED),
    "type": Key("str", "Control law.", REQUIRED,
                choices=("PPF", "SRF", "LyapunovBangBang", "VelocityFeedback", "LQR")),
    "actuator": Key("str", "Plant input driven (a name of control.actuators; None: the "
                    "first).", None),
    "sensor": Key("str", "Plant output measured, e.g. 'Q:<electrode>' (None: the first "
                  "sensor).", None),
    "u_max": _pos("Actuator limit: the command is clipped to +-u_max (None: no limit).",
                  None, "V"),
    "method": Key("str", "Simulation method (mvtk.control.simulate).", "auto",
                  choices=("auto", "exact", "ode", "sampled")),
    "control_rate_hz": _pos("Sample rate of a sampled (zero-order hold) controller (None: "
                            "continuous).", None, "Hz"),
}
_FILTER = {
    "f_hz": _pos("Filter frequency (tuned on the target mode).", units="Hz"),
    "zeta_f": _pos("Filter damping ratio."),
    "gain": Key("number", "Gain (PPF dimensionless, SRF in s).", REQUIRED, minimum=0.0),
}

#: Schema of each controller type of ``[[control.controllers]]``.
CONTROLLER_SCHEMAS = {
    "PPF": Table("Positive position feedback (Goh & Caughey 1985).",
                 {**_CTRL_COMMON, **_FILTER}),
    "SRF": Table("Strain-rate feedback (a second-order filter on the rate).",
                 {**_CTRL_COMMON, **_FILTER}),
    "VelocityFeedback": Table("Direct velocity feedback u = -g v.",
                              {**_CTRL_COMMON, "gain": Key("number", "Gain (V s/m).",
                                                           REQUIRED, minimum=0.0)}),
    "LQR": Table(
        "Linear-quadratic regulator u = -K x on one or several actuators (full state, "
        "energy weighting x'Qx = twice the mechanical energy).",
        {**{k: v for k, v in _CTRL_COMMON.items() if k not in ("actuator", "sensor")},
         "R": _pos("Weight of the squared command against the energy weighting.",
                   units="J/V^2"),
         "q_scale": _pos("Factor on the energy weighting Q.", 1.0),
         "actuators": Key("strings", "Plant inputs driven (names of control.actuators; "
                          "None: the first).", None, min_length=1)}),
    "LyapunovBangBang": Table(
        "Lyapunov (bang-bang) control u = -u_max sign(B' dq/dt) with a boundary layer.",
        {**_CTRL_COMMON,
         "u_max": _pos("Actuator limit: the command amplitude.", units="V"),
         "boundary_layer": _pos("Boundary layer in units of B' dq/dt.", None),
         "boundary_layer_rel": _pos("Boundary layer relative to the open-loop peak of "
                                    "B' dq/dt.", None)},
        one_of=(("boundary_layer", "boundary_layer_rel"),)),
}

_CHECK_DOC = {
    "identified_fn_rel": ("identified vs target frequencies", 0.005, ""),
    "identified_zeta_rel": ("identified vs reference damping ratios", 0.10, ""),
    "rayleigh_rel": ("half-power Rayleigh alpha, beta vs the references", 0.05, ""),
    "updated_fn_rel": ("updated FE vs target frequencies", 0.005, ""),
    "se_fn_rel": ("SE vs FE, first n_compare modes", 0.05, ""),
    "ppf_settling_s": ("upper bound of the PPF settling time", 1.5, "s"),
    "closed_loop_zeta_min": ("minimum closed-loop damping ratio of mode 1 of every linear "
                             "controller", 0.005, ""),
    "truth_param_rel": ("updated parameters vs the SYNTHETIC truth", 0.05, ""),
    "zeta_consistency_rel": ("damping of one mode from two methods (half-power vs the "
                             "multi-point identification) where both resolve it", 0.30, ""),
    "mpc_min": ("minimum modal phase collinearity of each multi-point mode whose shape "
                "the study uses", 0.9, ""),
    "mpd_max_deg": ("maximum mean phase deviation of each multi-point mode whose shape the "
                    "study uses", 15.0, "deg"),
    "uncertainty_cov_rel": ("Monte-Carlo CoV(f1) vs its first-order estimate", 0.20, ""),
    "mac_min": ("minimum MAC of each multi-point test mode with its paired updated-FE mode",
                0.9, ""),
    "prediction_fn_rel": ("updated-FE frequency of each multi-point test mode that was NOT an "
                          "updating target vs the test (the model-form check)", 0.03, ""),
}

#: The whole study schema: section name -> Table.
SCHEMA: dict[str, Table] = {
    "study": Table("Name and flags of the study.", {
        "name": Key("str", "Title of the report (default: the file name).", None),
        "synthetic": Key("bool", "The measurements are simulated: shown as a banner.", False),
    }),
    "structure": Table(
        "The FE structure: a structure TOML file (mvtk.fe.build_model), or, without "
        "'file', the structure tables (materials, structure, patches, mesh, boundary, "
        "points, name) written inline at the top level of the study file.",
        {"file": Key("path", "Structure TOML, relative to the study file.", None)}),
    "measurements": Table(
        "The measured tests, any number, each a named table: [measurements.impact], "
        "[measurements.broadband] and [measurements.decay] have their kind by name; any "
        "other name, e.g. [measurements.hit_2] or [measurements.decay_tip], says kind = "
        "\"impact\", \"decay\" or \"multi-point\" and takes the keys of that kind. Every "
        "impact test gives "
        "a half-power estimate of the modes it searches (its fn_hz), every decay an "
        "envelope and log-decrement estimate of its mode; the same mode from two tests is "
        "a consistency check of the report.", {
        "impact": Key("table", "Long impact test (fine frequency resolution).", None,
                      table=_IMPACT),
        "broadband": Key("table", "Short broadband impact test for the higher modes "
                         "(listed in damping.broadband_fn_hz).", None, table=_IMPACT),
        "decay": Key("table", "Free decay after release from mode 1.", None, table=_DECAY),
        "<name>": Key("table", "A further multi-point test of any name, kind = "
                      "\"multi-point\" (needs [modal], the test the others are compared "
                      "with).", None, table=_MULTI),
    }),
    "modal": Table(
        "A multi-point FRF test identified by mvtk.modal (pLSCF + LSFD). Its shapes pair the "
        "FE modes by MAC in [updating] and are correlated with the (updated) FE model: "
        "MAC, COMAC, and the prediction of the modes that were not updating targets.",
        {"file": Key("path", "FRF file (UFF 58 FRFs with node/direction fields, or any FRF "
                     "matrix mvtk.io.read returns), relative to the study file. Give "
                     "either 'file' or 'sets'.", None),
         "sets": Key("strings", "Time-history files of a multi-point test, one measurement "
                     "set per file (roving hammer: the hammer moves, the sensor stays; "
                     "roving sensor: the reverse), relative to the study file. Their FRFs "
                     "are estimated (mvtk.modal.frf_matrix: impact, random or sweep "
                     "detected) and merged by node and direction, so every channel needs a "
                     "node and a direction (UFF 58 fields, or CSV '# node:' and "
                     "'# direction:' header lines). With more references than responses "
                     "(roving hammer) the matrix is turned by reciprocity so that the "
                     "shapes are read at the hammer points.", None, min_length=1),
         "reference": Key("str", "Force channel of the sets (None: the channels whose "
                          "quantity is force).", None),
         "excitation": Key("str", "Excitation of the sets (auto: detected from the force).",
                           "auto", choices=("auto", "impact", "random", "sweep")),
         "geometry": Key("path", "Test geometry (UFF 15/2411, CSV or TOML table of node, x, "
                         "y, z in m; None: the UFF 15 records of 'file' or of the first "
                         "set).", None),
         "fmin_hz": _pos("Lower end of the identification band.", units="Hz"),
         "fmax_hz": _pos("Upper end of the identification band.", units="Hz"),
         "max_order": Key("int", "Highest pLSCF model order (None: mvtk.modal's default).",
                          None, minimum=4),
         "mapping": Key("str", "Sensor mapping onto the FE mesh: element shape functions "
                        "or the nearest node.", "shape", choices=("shape", "nearest")),
         "tolerance_m": _pos("Largest distance of a sensor from the FE surface.", 0.005, "m"),
         "pair_updating": Key("bool", "Pair the updating targets with FE modes by MAC "
                              "against the identified shapes.", True),
         "pair_within": _pos("Relative frequency window in which an identified mode is "
                             "attached to an updating target.", 0.03),
         "read_options": _read_options(),
         }, one_of=(("file", "sets"),)),
    "damping": Table("Damping identification (half-power, envelope, Rayleigh fits).", {
        "fn_hz": _freqs("Approximate resonances searched in the impact test, ascending."),
        "broadband_fn_hz": _freqs("Resonances searched in the broadband test, ascending "
                                  "and above fn_hz.", []),
        "half_power_method": Key("str", "Half-power variant (mvtk.damping.half_power; "
                                 "the default is that of `mvtk damping`).",
                                 "fit", choices=("fit", "interpolate")),
        "chowdhury_target_mass": Key("number", "Effective-mass fraction of the upper "
                                     "Chowdhury anchor.", 0.95, minimum=0.0, maximum=1.0,
                                     exclusive_minimum=True),
        "model_damping": Key("str", "Rayleigh pair used in the SE plant.", "half_power",
                             choices=("half_power", "chowdhury")),
    }),
    "fe": Table("The nominal FE model.", {
        "n_modes": Key("int", "Number of modes computed and tabulated.", 6, minimum=1),
    }),
    "updating": Table(
        "Sensitivity-based updating (mvtk.updating.update): give targets_hz or targets.",
        {"targets_hz": _freqs("Measured natural frequencies, ascending. Each is paired "
                              "one-to-one with the nominal FE mode nearest in frequency "
                              "(or by MAC with a multi-point test), not by order; "
                              "[[updating.targets]] with 'mode' fixes the pairing.", None),
         "identifiability_cond_max": _pos(
             "Largest condition number of the log-sensitivities d ln f / d ln p for which "
             "the update is reported identifiable (a 1 % frequency error then moves the "
             "weakest parameter combination by at most about this many %).", 100.0),
         "targets": Key("tables", "Targets as tables (fn_hz, weight, mode, label, shape, "
                        "kind).", None, table=_TARGET, min_length=1),
         "parameters": Key("tables", "Parameters to update ([[updating.parameters]]).",
                           REQUIRED, table=_PARAMETER, min_length=1),
         "max_iter": Key("int", "Maximum solver iterations.", 30, minimum=1),
         "n_modes": Key("int", "Model modes solved per evaluation (None: max(2n, n+4)).",
                        None, minimum=1),
         "regularization": Key("number", "Tikhonov weight towards the initial values.", 0.0,
                               minimum=0.0),
         "mac_weight": Key("number", "Weight of the (1 - MAC) residuals.", 0.0, minimum=0.0),
         "frequency_std": _pos("Relative standard deviation of the measured frequencies "
                               "of targets without an identification std.", None),
         "model_form_std": Key(
             "number", "Relative standard deviation of the model-form term: what no "
             "value of the updated parameters can reproduce (boundaries, joints, sensor "
             "masses). Each target is weighted by 1/sigma^2 with sigma^2 = std_hz^2 + "
             "(model_form_std fn)^2; a residual within 2 sigma of the identification "
             "alone is noise, within 2 sigma with this term is explained by it, beyond "
             "is model form. 0.005: the residual the example smart beam keeps after "
             "updating (0.13-0.51 %), far above identification stds (1e-5..1e-3).",
             0.005, minimum=0.0, maximum=1.0, exclusive_maximum=True),
         "builder": Key("str", "'package.module:function' building an FEModel from the "
                        "description (None: mvtk.fe.build_model).", None)},
        one_of=(("targets_hz", "targets"),)),
    "uncertainty": Table(
        "Monte-Carlo propagation on the updated (else nominal) structure.",
        {"n_samples": Key("int", "Number of samples.", 40, minimum=2),
         "seed": Key("int", "Seed of the numpy random Generator.", 0, minimum=0),
         "n_modes": Key("int", "Modes per sample.", 4, minimum=1),
         "distribution": Key("str", "Input distribution.", "normal",
                             choices=("normal", "lognormal")),
         "scatter": Key("map", "Dotted structure path -> relative standard deviation (CoV) "
                        "in (0, 0.5).", REQUIRED, value_type="number")}),
    "reduction": Table(
        "Craig-Bampton super element (mvtk.reduction.craig_bampton).",
        {"retained": Key("tables", "Retained items ([[reduction.retained]]); plain node "
                         "set names or [x, y, z] points are accepted too.", REQUIRED,
                         table=_RETAINED, min_length=1),
         "n_modes": Key("int", "Fixed-interface modes (0: Guyan; None: 10 unless "
                        "mass_fraction or f_cut_hz is given).", None, minimum=0),
         "mass_fraction": Key("number", "Keep modes up to this effective-mass fraction "
                              "instead of n_modes.", None, minimum=0.0, maximum=1.0,
                              exclusive_minimum=True),
         "f_cut_hz": _pos("Keep modes below this frequency instead of n_modes.", None,
                          "Hz"),
         "direction": Key("str", "Direction of mass_fraction (None: uz).", None,
                          choices=("ux", "uy", "uz", "rx", "ry", "rz")),
         "n_compare": Key("int", "Eigenfrequencies compared FE vs SE.", 4, minimum=1),
         "plant_modes": Key("int", "SE eigenmodes in the control plant (plus the static "
                            "residual of the others).", 12, minimum=1)},
        at_most_one_of=(("n_modes", "mass_fraction", "f_cut_hz"),)),
    "control": Table(
        "Controllers on the SE plant, released from mode 1 (mvtk.control).",
        {"actuator_nodes": Key("strings", "The two retained actuator-edge nodes of the "
                               "pin-force actuator (required unless 'actuators' names "
                               "piezo electrodes).", None, length=2),
         "sensor_node": Key("str", "Retained node of the tip sensor (uz).", REQUIRED),
         "actuators": Key("strings", "Piezo patches or electrodes driven by the controllers "
                          "(mvtk.fe.piezo_coupling on any shell structure); each one's "
                          "voltage is a plant input, the first one is the controllers' "
                          "default.", None, min_length=1),
         "sensors": Key("strings", "Piezo patches or electrodes read by the controllers "
                        "(charge or voltage, see 'sensing'); the first one is the "
                        "controllers' measurement.", None, min_length=1),
         "sensing": Key("str", "How the piezo sensors are read: 'charge' (shorted, a "
                        "charge amplifier) or 'voltage' (open electrodes).", "charge",
                        choices=("charge", "voltage")),
         "release_mode": Key("int", "Plant mode released (and whose damping the table "
                             "reports); 1 = the first.", 1, minimum=1),
         "zeta": Key("number", "Modal damping ratio of the piezo plant when the study has "
                     "no [damping] (the Rayleigh pair of [damping] otherwise).", None,
                     minimum=0.0, exclusive_minimum=True, maximum=1.0),
         "patch": Key("str", "Patch of the structure driving the plant (None: the only "
                      "patch).", None),
         "actuator_limit_v": _pos("Actuator voltage limit checked in the report.", 100.0,
                                  "V"),
         "initial_tip_displacement_m": _pos("Release amplitude at the sensor.", units="m"),
         "t_end_s": Key("number", "Simulated time (more than 1 s: the residual peak after "
                        "1 s is reported).", REQUIRED, "s", minimum=1.0,
                        exclusive_minimum=True),
         "fs_out": _pos("Output sample rate (must resolve 1.2 x the first mode).",
                        units="Hz"),
         "settle_band": Key("number", "Settling band relative to the initial amplitude.",
                            REQUIRED, minimum=0.0, maximum=1.0, exclusive_minimum=True,
                            exclusive_maximum=True),
         "controllers": Key("tables", "Controllers ([[control.controllers]]); the keys "
                            "of each depend on its type (CONTROLLER_SCHEMAS).", [])}),
    "checks": Table("Tolerances of the pass/fail verdicts.", {
        k: _pos(f"Tolerance: {d}.", v, u) for k, (d, v, u) in _CHECK_DOC.items()}),
    "references": Table("Published values shown next to mvtk's.", {
        "source": Key("str", "Citation of the references.", None),
        "experiment_fn_hz": _freqs("Measured frequencies (paper Table 2).", None),
        "fe_fn_hz": Key("numbers", "Published FE frequencies.", None, "Hz"),
        "se_fn_hz": Key("numbers", "Published SE frequencies.", None, "Hz"),
        "fe4_fn_hz": Key("numbers", "Published FE frequencies of the SE comparison.", None,
                         "Hz"),
        "se4_fn_hz": Key("numbers", "Published SE frequencies of the SE comparison.", None,
                         "Hz"),
        "zeta": Key("numbers", "Published damping ratios.", None),
        "half_power_alpha": Key("number", "Published half-power Rayleigh alpha.", None,
                                "1/s"),
        "half_power_beta": Key("number", "Published half-power Rayleigh beta.", None, "s"),
        "chowdhury_alpha": Key("number", "Published Chowdhury alpha.", None, "1/s"),
        "chowdhury_beta": Key("number", "Published Chowdhury beta.", None, "s"),
        "fe_sizes": Key("numbers", "Published FE sizes (nodes, elements, free DOF, DOF).",
                        None, allow_nan=True),
        "se_sizes": Key("numbers", "Published SE sizes.", None, allow_nan=True),
        "ppf_settling_s": _pos("Published PPF settling time.", None, "s"),
        "other_settling_s": _pos("Published settling time of the other controllers.", None,
                                 "s"),
    }),
    "report": Table(
        "The report as a controlled document: its title page and sign-off block, and the "
        "running header of the PDF.", {
            "title": Key("str", "Document title (default: 'Validation report: ' and the "
                         "study name).", None),
            "document_number": Key("str", "Document number (e.g. 'VR-2026-014').", None),
            "revision": Key("str", "Revision (e.g. 'A', '1.2').", None),
            "date": Key("str", "Issue date as written on the title page (default: the "
                        "date of the run).", None),
            "author": Key("str", "Who prepared the report.", None),
            "reviewer": Key("str", "Who checked it.", None),
            "approver": Key("str", "Who approved it.", None),
            "organisation": Key("str", "Organisation issuing the report.", None),
        }),
    "truth": Table(
        "SYNTHETIC data only: the simulated specimen. Dotted structure paths -> values, "
        "and rayleigh_alpha, rayleigh_beta (damping of every simulated mode).",
        {"*": Key("map", "Dotted path -> value.", None, value_type="number")}),
}


# --------------------------------------------------------------------------- validation
def _suggest(key: str, accepted) -> str:
    """`` (did you mean 'x'?)`` for a close match (or a transposition) of ``key``."""
    names = [str(a) for a in accepted]
    close = difflib.get_close_matches(str(key), names, n=1, cutoff=0.75)
    if not close:
        close = [a for a in names if sorted(a.lower()) == sorted(str(key).lower())][:1]
    return f" (did you mean {close[0]!r}?)" if close else ""


def unknown_key_error(key: str, where: str, accepted, source: str = "") -> ConfigError:
    """The ConfigError for an unknown key: names the key, the table, the file, the choices."""
    loc = f"{source}: " if source else ""
    table = f"[{where}]" if where else "the top level"
    return ConfigError(f"{loc}unknown key {key!r} in {table}{_suggest(key, accepted)}; "
                       f"accepted keys: {sorted(map(str, accepted))}")


def _is_number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool)


def _describe(k: Key) -> str:
    what = {"str": "a string", "bool": "true or false", "int": "an integer",
            "number": "a number", "path": "a file path string",
            "numbers": "a list of numbers", "strings": "a list of strings",
            "xyz": "a point [x, y, z] in m", "table": "a table", "tables": "an array of tables",
            "map": "a table", "any": "a value"}[k.type]
    bounds = []
    if k.minimum is not None:
        bounds.append(f"{'>' if k.exclusive_minimum else '>='} {k.minimum:g}")
    if k.maximum is not None:
        bounds.append(f"{'<' if k.exclusive_maximum else '<='} {k.maximum:g}")
    if bounds and k.type in ("int", "number", "numbers"):
        what += (" each" if k.type == "numbers" else "") + " " + " and ".join(bounds)
    if k.choices:
        what = f"one of {list(k.choices)}"
    if k.units and k.type != "xyz":
        what += f" (in {k.units})"
    return what


def _in_range(k: Key, v: float) -> bool:
    if isinstance(v, float) and not math.isfinite(v):
        return k.allow_nan and math.isnan(v)
    if k.minimum is not None and (v <= k.minimum if k.exclusive_minimum else v < k.minimum):
        return False
    return not (k.maximum is not None
                and (v >= k.maximum if k.exclusive_maximum else v > k.maximum))


def _check_value(k: Key, v: Any, where: str, source: str) -> Any:
    loc = f"{source}: " if source else ""
    bad = ConfigError(f"{loc}{where}: expected {_describe(k)}, got {v!r}")
    t = k.type
    if t in ("str", "path"):
        if not isinstance(v, str):
            raise bad
        if k.choices and v not in k.choices:
            raise ConfigError(f"{loc}{where}: expected one of {list(k.choices)}, got {v!r}"
                              f"{_suggest(v, k.choices)}")
        return v
    if t == "bool":
        if not isinstance(v, bool):
            raise bad
        return v
    if t == "int":
        if isinstance(v, bool) or not isinstance(v, int) or not _in_range(k, v):
            raise bad
        return v
    if t == "number":
        if not _is_number(v) or not _in_range(k, v):
            raise bad
        return v
    if t in ("numbers", "xyz"):
        n = 3 if t == "xyz" else k.length
        if (not isinstance(v, list) or (n is not None and len(v) != n)
                or len(v) < k.min_length or not all(_is_number(x) and _in_range(k, x) for x in v)):
            raise bad
        if k.ascending and any(b <= a for a, b in zip(v, v[1:])):
            raise ConfigError(f"{loc}{where}: expected frequencies in ascending (mode) order, "
                              f"got {v!r}; list them from the lowest mode up")
        return v
    if t == "strings":
        if (not isinstance(v, list) or (k.length is not None and len(v) != k.length)
                or not all(isinstance(x, str) for x in v)):
            raise bad
        return v
    if t == "table":
        if not isinstance(v, Mapping):
            raise bad
        return validate_table(v, k.table, where, source)
    if t == "tables":
        if not isinstance(v, list):
            raise bad
        if len(v) < k.min_length:
            raise ConfigError(f"{loc}{where}: expected at least {k.min_length} table(s) "
                              f"([[{where}]]), got {v!r}")
        if k.table is None:  # items validated by the caller (controllers by type)
            for i, item in enumerate(v):
                if not isinstance(item, Mapping):
                    raise ConfigError(f"{loc}{where}[{i}]: expected a table, got {item!r}")
            return [dict(item) for item in v]
        return [validate_table(item, k.table, f"{where}[{i}]", source)
                if isinstance(item, Mapping) else item for i, item in enumerate(v)]
    if t == "map":
        if not isinstance(v, Mapping):
            raise bad
        vk = Key(k.value_type, k.doc)
        return {kk: _check_value(vk, vv, f"{where}.{kk!r}" if "." in str(kk)
                                 else f"{where}.{kk}", source) for kk, vv in v.items()}
    return v


def validate_table(d: Mapping, table: Table, where: str, source: str = "") -> dict:
    """Check ``d`` against ``table``; returns a copy with the defaults filled in.

    Raises
    ------
    ConfigError
        Unknown key (with the accepted keys and a close match), missing required key,
        wrong type or range; the message names the file, the table and the key.
    """
    loc = f"{source}: " if source else ""
    if not isinstance(d, Mapping):
        raise ConfigError(f"{loc}[{where}]: expected a table, got {d!r}")
    if "*" in table.keys:  # a free-form map
        return _check_value(table.keys["*"], d, where, source)
    for key in d:
        if key not in table.keys:
            raise unknown_key_error(key, where, table.keys, source)
    out: dict[str, Any] = {}
    for name, k in table.keys.items():
        if name in d:
            out[name] = _check_value(k, d[name], f"{where}.{name}", source)
        elif k.required:
            raise ConfigError(f"{loc}[{where}]: missing key {name!r} ({k.doc})")
        elif k.default is not None:
            out[name] = k.default if not isinstance(k.default, list) else list(k.default)
    for group in table.one_of:
        given = [g for g in group if g in d]
        if len(given) != 1:
            raise ConfigError(f"{loc}[{where}]: give exactly one of {list(group)}, got "
                              f"{given or 'none'}")
    for group in table.at_most_one_of:
        given = [g for g in group if g in d]
        if len(given) > 1:
            raise ConfigError(f"{loc}[{where}]: give at most one of {list(group)}, got "
                              f"{given}")
    return out


#: Kind of the measurements named by their kind.
_MEASUREMENT_KIND = {"impact": "impact", "broadband": "impact", "decay": "decay"}


def _validate_measurements(d: Any, source: str) -> dict:
    """``[measurements]``: any number of named tests, each of kind impact, decay or
    multi-point (the latter by its ``kind`` key only)."""
    loc = f"{source}: " if source else ""
    if not isinstance(d, Mapping):
        raise ConfigError(f"{loc}[measurements]: expected a table of named tests, got {d!r}")
    out = {}
    for name, m in d.items():
        where = f"measurements.{name}"
        if not isinstance(m, Mapping) and str(name) not in _MEASUREMENT_KIND:
            raise unknown_key_error(name, "measurements", _MEASUREMENT_KIND, source)
        if not isinstance(m, Mapping):
            raise ConfigError(f"{loc}[{where}]: expected a table (file, ... of an impact "
                              f"test or a decay), got {m!r}")
        kind = m.get("kind", _MEASUREMENT_KIND.get(str(name)))
        if "kind" not in m and str(name) not in _MEASUREMENT_KIND:
            err = unknown_key_error(name, "measurements", _MEASUREMENT_KIND, source)
            raise ConfigError(f"{err}; a measurement of another name says its kind "
                              "(kind = \"impact\", \"decay\" or \"multi-point\")")
        if kind not in ("impact", "decay", "multi-point"):
            raise ConfigError(
                f"{loc}[{where}]: expected kind = \"impact\", \"decay\" or \"multi-point\" "
                "(a measurement named other than impact, broadband or decay says its kind), "
                f"got {kind!r}")
        if kind == "multi-point" and str(name) in _MEASUREMENT_KIND:
            raise ConfigError(f"{loc}[{where}]: a multi-point test needs a name of its own "
                              f"(not {name!r}, the name of the {_MEASUREMENT_KIND[name]} test)")
        table = (_MULTI if kind == "multi-point" else
                 SCHEMA["measurements"].keys["decay" if kind == "decay" else "impact"].table)
        out[name] = validate_table(m, table, where, source)
    return out


def validate(cfg: Mapping, source: str = "", inline_structure: bool = False,
             structure_tables=STRUCTURE_TABLES) -> dict:
    """Validate a parsed study TOML against :data:`SCHEMA`.

    Parameters
    ----------
    cfg : mapping
        The parsed TOML.
    source : str
        File name used in messages.
    inline_structure : bool
        The study holds its structure tables inline (no ``[structure] file``): the
        structure-description keys are passed through unvalidated (mvtk.fe validates
        them).

    Returns
    -------
    dict
        The study sections with defaults filled in (the inline structure tables, if any,
        unchanged under their own names).
    """
    out: dict[str, Any] = {}
    accepted = set(SCHEMA) | (set(structure_tables) if inline_structure else set())
    for name in cfg:
        if name not in accepted:
            loc = f"{source}: " if source else ""
            raise ConfigError(f"{loc}unknown sections [{name!r}]{_suggest(name, accepted)}; "
                              f"accepted sections: {sorted(accepted)}")
    for name, value in cfg.items():
        if name == "measurements":
            out[name] = _validate_measurements(value, source)
        elif name in SCHEMA and not (inline_structure and name == "structure"):
            out[name] = validate_table(value, SCHEMA[name], name, source)
        else:
            out[name] = value
    ctrls = out.get("control", {}).get("controllers", [])
    loc = f"{source}: " if source else ""
    for i, c in enumerate(ctrls):
        where = f"control.controllers[{i}]"
        if "type" not in c:
            raise ConfigError(f"{loc}[{where}]: missing key 'type' (one of "
                              f"{list(CONTROLLER_SCHEMAS)})")
        _check_value(_CTRL_COMMON["type"], c["type"], f"{where}.type", source)
        ctrls[i] = validate_table(c, CONTROLLER_SCHEMAS[c["type"]], where, source)
    return out
