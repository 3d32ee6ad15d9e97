"""BLAS threads held to one around mvtk's dense and sparse kernels.

On a 2-core machine that also runs other work, OpenBLAS's second thread waits for a
core more than it computes: measured, the small dense kernels of sparse triangular
solves became 2-3x slower, a 1236-row SVD of SSI-cov took 12 s instead of 2.7 s, and
Riccati solves of a few hundred states several times their single-thread time.
:func:`blas_limits` limits BLAS to :data:`BLAS_THREADS` with :mod:`threadpoolctl`
(re-entrant; the library scan, ~30 ms, is made once per process).

:func:`load_system_blas` gives CHOLMOD an optimised BLAS: the PyPI wheel of
``sksparse-minimal`` bundles the reference BLAS, whose dense kernels are most of a
supernodal factorisation. Loaded with global symbols before the wheel's extension, a
system OpenBLAS (Debian's ``libopenblas0``) takes over CHOLMOD's BLAS and LAPACK calls:
measured on a 195 480-DOF plate, the factorisation went from 3.1-4.0 s to 1.3-1.7 s.
"""

from __future__ import annotations

__all__ = ["BLAS_THREADS", "blas_limits", "load_system_blas"]

#: BLAS threads inside :func:`blas_limits` (None: leave the libraries' own setting).
BLAS_THREADS: int | None = 1

_CONTROLLER = None
_DEPTH = 0
#: The outcome of :func:`load_system_blas` (None until it has run).
_SYSTEM_BLAS: tuple[str | None, str] | None = None


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


def load_system_blas() -> tuple[str | None, str]:
    """Load the system's OpenBLAS with global symbols, once per process (Linux only).

    Must run before ``sksparse_minimal`` is imported: CPython opens extension modules
    with ``RTLD_NOW``, so CHOLMOD's ``dgemm_``, ``dsyrk_``, ``dtrsm_``, ``dpotrf_``, ...
    are bound at import, to the first definition in the global scope. The environment
    variable ``MVTK_CHOLMOD_BLAS`` chooses: ``"auto"`` (default: OpenBLAS when the
    dynamic loader finds ``libopenblas``), ``"bundled"`` (the wheel's reference BLAS),
    or the path of a library with the Fortran BLAS/LAPACK names.

    Returns
    -------
    path : str or None
        The library loaded, None when none was (CHOLMOD keeps its bundled BLAS).
    description : str
        What CHOLMOD's BLAS is, for timings and report provenance, e.g.
        ``"OpenBLAS 0.3.21 (libopenblasp-r0.3.21.so)"``.

    Examples
    --------
    >>> path, description = load_system_blas()
    >>> path is None or "BLAS" in description
    True
    """
    global _SYSTEM_BLAS, _CONTROLLER
    if _SYSTEM_BLAS is not None:
        return _SYSTEM_BLAS
    import ctypes
    import ctypes.util
    import os
    import sys

    bundled = "the reference BLAS bundled in the sksparse-minimal wheel"
    choice = os.environ.get("MVTK_CHOLMOD_BLAS", "auto")
    if choice == "bundled" or not sys.platform.startswith("linux"):
        _SYSTEM_BLAS = (None, bundled)
        return _SYSTEM_BLAS
    if "sksparse_minimal" in sys.modules:
        _SYSTEM_BLAS = (None, bundled + " (sksparse_minimal was imported before mvtk "
                        "could load an optimised BLAS)")
        return _SYSTEM_BLAS
    path = ctypes.util.find_library("openblas") if choice == "auto" else choice
    if path is None:
        _SYSTEM_BLAS = (None, bundled + " (no system OpenBLAS found: Debian's "
                        "libopenblas0 makes the factorisation 2-3x faster)")
        return _SYSTEM_BLAS
    try:
        lib = ctypes.CDLL(path, mode=ctypes.RTLD_GLOBAL)
        lib.dgemm_  # noqa: B018  (has the Fortran BLAS names)
    except (OSError, AttributeError) as err:
        if choice != "auto":
            from .errors import ParameterError

            raise ParameterError(
                f"environment variable MVTK_CHOLMOD_BLAS={choice!r}: not a BLAS library "
                f"with the Fortran names (dgemm_): {err}") from err
        _SYSTEM_BLAS = (None, bundled + f" ({path} could not be loaded: {err})")
        return _SYSTEM_BLAS
    _CONTROLLER = None   # the next blas_limits() scans the libraries again, this one too
    name = os.path.basename(path)
    path = _mapped_path("/" + name.split(".so")[0]) or path
    try:
        lib.openblas_get_config.restype = ctypes.c_char_p
        config = lib.openblas_get_config().decode(errors="replace").split()
        name = " ".join(config[:2])
    except AttributeError:
        pass
    _SYSTEM_BLAS = (path, f"{name} ({os.path.basename(path)})")
    return _SYSTEM_BLAS


def _mapped_path(stem: str) -> str | None:
    """The file of a loaded library whose path contains ``stem`` (``/proc/self/maps``:
    the soname's target, e.g. ``.../libopenblasp-r0.3.21.so``), or None."""
    try:
        with open("/proc/self/maps") as maps:
            for line in maps:
                fields = line.split(maxsplit=5)
                if len(fields) == 6 and stem in fields[5]:
                    return fields[5].strip()
    except OSError:
        return None
    return None
