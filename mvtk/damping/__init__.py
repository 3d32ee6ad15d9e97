"""Damping identification: half-power bandwidth, free-decay fits, Rayleigh alpha/beta."""

from ._decay import DecayResult, damping_vs_amplitude, envelope_fit, log_decrement
from ._estimate import DampingEstimate, estimate
from ._half_power import HalfPowerResult, half_power, half_power_zeta
from ._rayleigh import RayleighFit, rayleigh_fit, rayleigh_zeta

__all__ = [
    "DampingEstimate",
    "DecayResult",
    "HalfPowerResult",
    "damping_vs_amplitude",
    "RayleighFit",
    "envelope_fit",
    "estimate",
    "half_power",
    "half_power_zeta",
    "log_decrement",
    "rayleigh_fit",
    "rayleigh_zeta",
]
