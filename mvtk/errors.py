"""Exceptions and warnings of mvtk.

Every exception derives from :class:`MvtkError` *and* from the builtin category it
belongs to, so ``except ValueError`` keeps working for callers that do not know mvtk.
Messages say what was wrong, what was expected, what was found and where (file,
line or record, channel).

Warnings derive from :class:`MvtkWarning`; they are issued with
``warnings.warn(msg, SomeWarning, stacklevel=2)``.
"""

from __future__ import annotations

__all__ = [
    "MvtkError",
    "FormatError",
    "UnsupportedFormatError",
    "DoubleHitError",
    "DimensionError",
    "UnitsError",
    "ConfigError",
    "ParameterError",
    "ConvergenceError",
    "MissingDependencyError",
    "OutputError",
    "MvtkWarning",
    "DataRepairWarning",
    "ResolutionWarning",
    "ModeOverlapWarning",
    "IdentifiabilityWarning",
    "AccuracyWarning",
    "ModelWarning",
]


class MvtkError(Exception):
    """Base class of every error raised by mvtk."""


class FormatError(MvtkError, ValueError):
    """A file (or in-memory object) does not have the expected content or layout."""


class DoubleHitError(FormatError):
    """Every impact record of a measurement holds a second force pulse (a double hit)."""


class UnsupportedFormatError(FormatError):
    """The format of a file is unknown or not supported by any registered reader."""


class DimensionError(MvtkError, ValueError):
    """An array has the wrong shape, dimension names or sizes."""


class UnitsError(MvtkError, ValueError):
    """A physical unit is missing, unknown or inconsistent."""


class ConfigError(MvtkError, ValueError):
    """A study or structure description (TOML) is invalid."""


class ParameterError(MvtkError, ValueError):
    """A function argument is out of its valid range or of the wrong kind."""


class ConvergenceError(MvtkError, RuntimeError):
    """An iterative solver or fit did not converge."""


class MissingDependencyError(MvtkError, ImportError):
    """An optional dependency needed for this feature is not installed."""


class OutputError(MvtkError, OSError):
    """An output file could not be written, or would replace an input file.

    The message names the file and the cause (disk full, file-size limit, permission,
    the output being one of the inputs); the previous file is unchanged.
    """


class MvtkWarning(UserWarning):
    """Base class of every warning issued by mvtk."""


class DataRepairWarning(MvtkWarning):
    """Input was usable only after a repair; the message says exactly what was changed."""


class ResolutionWarning(MvtkWarning):
    """Too few frequency lines or samples for a reliable estimate."""


class ModeOverlapWarning(MvtkWarning):
    """Neighbouring modes overlap and bias a single-mode estimate."""


class IdentifiabilityWarning(MvtkWarning):
    """Parameters cannot be separated by the available targets."""


class AccuracyWarning(MvtkWarning):
    """A result is outside the range where the method is known to be accurate."""


class ModelWarning(MvtkWarning):
    """A structural model looks implausible (units, mesh density, cracks); the message
    names the entity and the likely cause."""
