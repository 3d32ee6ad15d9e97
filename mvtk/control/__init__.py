"""Structural state-space plants, active vibration controllers, closed-loop simulation.

Plants are :class:`SecondOrderSystem` (``M q'' + C q' + K q = B u``, ``y = Cq q + Cv q'``;
from a super element with :func:`structural_plant`, or :func:`modal_plant` /
:func:`cantilever_modal_plant` for tests). Controllers are small frozen objects connected
to a plant output (sensor) and input (actuator) by name:

- :class:`PPF` and :class:`SRF` (one or several second-order filters
  ``(f_hz, zeta_f, gain)``; gains normalised by the plant's static gain from actuator to
  sensor so that ``gain`` is the dimensionless G of the single-mode forms of PHYSICS.md
  section 4), :class:`VelocityFeedback`, :class:`LQR` (full state, one or several actuators),
- :class:`LyapunovBangBang` (``u = -u_max sat(B'q'/eps)`` or ``-u_max sat(B'Px/eps)``).

Any of them may have an actuator limit ``u_max``. :func:`closed_loop` gives the linear
closed loop as a :class:`StateSpace`; :func:`simulate` returns an xarray Dataset
(``outputs``, ``inputs``, ``states``). Metrics: :func:`settling_time`,
:func:`added_damping`, :func:`closed_loop_modes`, :func:`peak_reduction_db`,
:func:`voltage_stats`, :func:`critical_gain`, :func:`ppf_gain_limit`,
:func:`srf_gain_limit`, :func:`spillover_check`; :func:`compare_controllers` tabulates
them in the shape of the paper's section 4.3. Stability comes first: every loop gets a
verdict (:func:`closed_loop_stability`, :func:`trajectory_stability` for the nonlinear
laws, :func:`stability_summary`), with gain and phase margins and the critical gain
(:func:`loop_margins`); an unstable or marginal loop is never reported as added damping
(docs/control_stability.md).

Example
-------
>>> import mvtk.control as mc
>>> plant = mc.cantilever_modal_plant(3)          # paper's f1 and Rayleigh damping
>>> x0 = mc.release_state(plant, 1, "tip", 1e-3)  # released from mode 1, 1 mm at the tip
>>> ds = mc.simulate(plant, mc.PPF([(13.26, 0.5, 0.1)], sensor="tip"),
...                  t_end=2.0, fs_out=1000.0, initial=x0)
>>> round(mc.settling_time(ds.outputs.sel(output="tip"), band=0.02), 1)
0.8
"""

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
from ._piezo import piezo_plant
from ._plant import StructuralPlant, dof_load, dof_output, structural_plant
from ._second_order import SecondOrderSystem
from ._simulate import Disturbance, closed_loop, release_state, simulate
from ._stability import (
    VERDICTS,
    LoopMargins,
    StabilityVerdict,
    closed_loop_stability,
    loop_margins,
    stability_summary,
    stability_verdict,
    trajectory_stability,
)
from ._statespace import StateSpace

__all__ = [
    "SecondOrderSystem",
    "StateSpace",
    "StructuralPlant",
    "structural_plant",
    "piezo_plant",
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
    "VERDICTS",
    "StabilityVerdict",
    "stability_verdict",
    "closed_loop_stability",
    "trajectory_stability",
    "LoopMargins",
    "loop_margins",
    "stability_summary",
    "Scenario",
    "ComparisonResult",
    "compare_controllers",
    "controller_from_dict",
    "run_control_section",
]
