"""Spectra, FRFs and peak picking on the DESIGN.md xarray conventions.

``psd``/``csd`` wrap Welch's method (argument names of scipy.signal), ``frf`` gives H1/H2
FRFs with coherence for random and impact excitation, ``find_peaks`` picks modes.
"""

from ._curves import AmplitudeCurves, amplitude_curves
from ._frf import auto_segment, exponential_window_correction, frf, frf_kind, is_impulsive, is_sweep
from ._impact import (
    CLIP_MIN_SAMPLES,
    COHERENCE_MIN,
    DOUBLE_HIT_FRACTION,
    PAD_FACTOR,
    ImpactPolicy,
    SetQuality,
    clipped_channels,
    impact_policy,
    set_excitation,
    set_quality,
)
from ._input import as_time_history, sampling_rate
from ._peaks import (
    EXCITED_DB,
    MAX_PEAKS,
    AnalysisBand,
    PeakResult,
    analysis_band,
    excited_band,
    find_peaks,
    noise_jitter_db,
)
from ._spectral import csd, psd

__all__ = [
    "CLIP_MIN_SAMPLES",
    "COHERENCE_MIN",
    "DOUBLE_HIT_FRACTION",
    "PAD_FACTOR",
    "ImpactPolicy",
    "SetQuality",
    "clipped_channels",
    "impact_policy",
    "set_excitation",
    "set_quality",
    "MAX_PEAKS",
    "AmplitudeCurves",
    "PeakResult",
    "amplitude_curves",
    "auto_segment",
    "as_time_history",
    "csd",
    "exponential_window_correction",
    "find_peaks",
    "analysis_band",
    "excited_band",
    "AnalysisBand",
    "EXCITED_DB",
    "frf",
    "frf_kind",
    "is_impulsive",
    "is_sweep",
    "noise_jitter_db",
    "psd",
    "sampling_rate",
]
