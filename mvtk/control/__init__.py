"""Structural state-space plants, active vibration controllers, closed-loop simulation."""

from ._compare import (
    ComparisonResult,
    Scenario,
    compare_controllers,
    controller_from_dict,
    run_control_section,
)
from ._controllers import LQR, PPF, SRF, FeedbackLaw, LyapunovBangBang, VelocityFeedback
from ._metrics import (
    ModalProperties,
    SpilloverResult,
    added_damping,
    closed_loop_modes,
    critical_gain,
    modal_properties,
    peak_reduction_db,
    ppf_gain_limit,
    settling_time,
    spillover_check,
    srf_gain_limit,
    voltage_stats,
)
from ._modal import cantilever_modal_plant, modal_plant
from ._plant import StructuralPlant, dof_load, dof_output, structural_plant
from ._second_order import SecondOrderSystem
from ._simulate import Disturbance, closed_loop, release_state, simulate
from ._statespace import StateSpace

__all__ = [
    "SecondOrderSystem",
    "StateSpace",
    "StructuralPlant",
    "structural_plant",
    "dof_load",
    "dof_output",
    "modal_plant",
    "cantilever_modal_plant",
    "PPF",
    "SRF",
    "VelocityFeedback",
    "LQR",
    "LyapunovBangBang",
    "FeedbackLaw",
    "closed_loop",
    "simulate",
    "release_state",
    "Disturbance",
    "settling_time",
    "ModalProperties",
    "modal_properties",
    "closed_loop_modes",
    "added_damping",
    "peak_reduction_db",
    "voltage_stats",
    "ppf_gain_limit",
    "srf_gain_limit",
    "critical_gain",
    "SpilloverResult",
    "spillover_check",
    "Scenario",
    "ComparisonResult",
    "compare_controllers",
    "controller_from_dict",
    "run_control_section",
]
