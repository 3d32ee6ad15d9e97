"""Shared pieces of the damping estimators."""

from __future__ import annotations

from ..errors import ParameterError

__all__ = ["NoEstimateError"]


class NoEstimateError(ParameterError):
    """The data support no estimate at all (no peak above the noise, no decaying channel).

    A :class:`~mvtk.errors.ParameterError` (so ``except ValueError`` still works); the
    ``mvtk damping`` command reports it as "no reliable estimate" with exit code 1.
    """
