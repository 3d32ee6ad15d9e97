"""Structural state-space plants, active vibration controllers, closed-loop simulation."""

from ._second_order import SecondOrderSystem
from ._statespace import StateSpace

__all__ = ["SecondOrderSystem", "StateSpace"]
