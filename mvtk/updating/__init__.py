"""FE model updating against measured natural frequencies (and mode shapes).

Parameters are numeric fields of a structure description addressed by dotted paths;
targets are measured frequencies, optionally with mode shapes at sensors (on FE DOFs
or observed through an :mod:`mvtk.correlation` sensor mapping, see
:func:`targets_from_shapes`); :func:`update` runs a bounded, sensitivity-based
least-squares fit and returns an :class:`UpdateResult` with the updated description and
diagnostics (residuals, parameter changes and uncertainty, sensitivities,
identifiability, unpaired modes). Targets with a standard deviation (``std_hz``, e.g. the
identified ``fn_std_hz``) are weighted by ``1 / sigma^2`` with a stated model-form term,
and each residual gets a verdict: noise, explained by the model-form term, or model form.
"""

from ._pairing import Pairing, classify_modes, mac, pair_by_frequency, pair_modes, target_mac
from ._parameters import Parameter, get_path, set_path, with_values
from ._sensitivity import Sensitivity, eigen_sensitivity
from ._targets import FrequencyTarget, targets_from_modal_result, targets_from_shapes
from ._update import DEFAULT_MODEL_FORM_STD, HistoryEntry, UpdateResult, update

__all__ = [
    "Parameter",
    "get_path",
    "set_path",
    "with_values",
    "FrequencyTarget",
    "targets_from_modal_result",
    "targets_from_shapes",
    "mac",
    "classify_modes",
    "pair_modes",
    "pair_by_frequency",
    "target_mac",
    "Pairing",
    "eigen_sensitivity",
    "Sensitivity",
    "update",
    "UpdateResult",
    "HistoryEntry",
    "DEFAULT_MODEL_FORM_STD",
]
