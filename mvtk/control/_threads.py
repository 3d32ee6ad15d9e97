"""BLAS thread control around the small dense problems of the controllers.

Riccati solves (QZ), matrix exponentials and the blocked time march work on matrices of a
few hundred rows. On such sizes a second BLAS thread buys nothing and, on a loaded
machine, costs several times the single-thread time (threads waiting for a core).
:func:`small_dense` limits BLAS to one thread (:func:`mvtk._blas.blas_limits`).
"""

from __future__ import annotations

import contextlib
import functools

__all__ = ["small_dense", "one_blas_thread"]

#: Largest matrix order treated as "small" (one BLAS thread).
SMALL_ORDER = 1000


def small_dense(order: int):
    """Context manager: one BLAS thread for a dense problem of ``order`` rows
    (:func:`mvtk._blas.blas_limits`)."""
    if order > SMALL_ORDER:
        return contextlib.nullcontext()
    from .._blas import blas_limits

    return blas_limits()


def one_blas_thread(fn):
    """Decorator: run ``fn(plant, ...)`` under :func:`small_dense` sized by the plant
    (``2 n_coords`` or ``n_states``, plus room for controller states)."""
    @functools.wraps(fn)
    def wrapper(plant, *args, **kwargs):
        n = getattr(plant, "n_coords", None)
        order = 2 * n if n is not None else getattr(plant, "n_states", 0)
        with small_dense(order + 64):
            return fn(plant, *args, **kwargs)

    return wrapper
