"""Structural state-space plants, active vibration controllers, closed-loop simulation."""

from ._statespace import StateSpace

__all__ = ["StateSpace"]
