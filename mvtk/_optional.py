"""Optional dependency checks: dask and dask.distributed are imported only when used."""

from __future__ import annotations

from .errors import MissingDependencyError

__all__ = ["require_dask", "require_distributed"]

_PIP = 'pip install "mvtk[scale]"  (or: pip install "dask[array,distributed]")'


def require_dask(feature: str):
    """Return the ``dask`` module, or raise MissingDependencyError naming ``feature``."""
    try:
        import dask
        import dask.array  # noqa: F401
    except ImportError as err:
        raise MissingDependencyError(
            f"{feature} needs dask, which is not installed; install it with: {_PIP}"
        ) from err
    return dask


def require_distributed(feature: str):
    """Return the ``dask.distributed`` module, or raise MissingDependencyError."""
    require_dask(feature)
    try:
        import dask.distributed as distributed
    except ImportError as err:
        raise MissingDependencyError(
            f"{feature} needs dask.distributed, which is not installed; install it with: {_PIP}"
        ) from err
    return distributed
