"""BLAS threads held to one around mvtk's dense and sparse kernels.

On a 2-core machine that also runs other work, OpenBLAS's second thread waits for a
core more than it computes: measured, the small dense kernels of sparse triangular
solves became 2-3x slower, a 1236-row SVD of SSI-cov took 12 s instead of 2.7 s, and
Riccati solves of a few hundred states several times their single-thread time.
:func:`blas_limits` limits BLAS to :data:`BLAS_THREADS` with :mod:`threadpoolctl`
(re-entrant; the library scan, ~30 ms, is made once per process).
"""

from __future__ import annotations

__all__ = ["BLAS_THREADS", "blas_limits"]

#: BLAS threads inside :func:`blas_limits` (None: leave the libraries' own setting).
BLAS_THREADS: int | None = 1

_CONTROLLER = None
_DEPTH = 0


class _BlasLimits:
    def __enter__(self):
        global _CONTROLLER, _DEPTH
        self._limit = None
        if BLAS_THREADS is not None and _DEPTH == 0:
            from threadpoolctl import ThreadpoolController

            if _CONTROLLER is None:
                _CONTROLLER = ThreadpoolController()
            self._limit = _CONTROLLER.limit(limits=BLAS_THREADS, user_api="blas")
        _DEPTH += 1
        return self

    def __exit__(self, *exc):
        global _DEPTH
        _DEPTH -= 1
        if self._limit is not None:
            self._limit.restore_original_limits()
        return False


def blas_limits() -> _BlasLimits:
    """Context manager: BLAS limited to :data:`BLAS_THREADS` threads inside it
    (nested uses keep the outermost limit)."""
    return _BlasLimits()
