"""Spectra, FRFs and peak picking on the DESIGN.md xarray conventions.

``psd``/``csd`` wrap Welch's method (argument names of scipy.signal), ``frf`` gives H1/H2
FRFs with coherence for random and impact excitation, ``find_peaks`` picks modes.
"""

from ._curves import AmplitudeCurves, amplitude_curves
from ._frf import exponential_window_correction, frf, frf_kind
from ._input import as_time_history, sampling_rate
from ._peaks import PeakResult, find_peaks
from ._spectral import csd, psd

__all__ = [
    "AmplitudeCurves",
    "PeakResult",
    "amplitude_curves",
    "as_time_history",
    "csd",
    "exponential_window_correction",
    "find_peaks",
    "frf",
    "frf_kind",
    "psd",
    "sampling_rate",
]
