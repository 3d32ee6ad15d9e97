"""Keep Ctrl-C a Ctrl-C through code that swallows it.

Two ways an interrupt gets lost in a long run:

* third-party code catches everything: pyuff wraps every failure of a record read,
  ``KeyboardInterrupt`` included (bare ``except:``), into a generic
  ``Exception("Error when reading data-set(s).")``, so an interrupted run would be
  reported as a corrupt file. :func:`deferred_interrupt` holds SIGINT back for the
  duration of such a call and delivers it right after.
* Python itself drops an exception raised inside a weakref callback or ``__del__``
  ("Exception ignored in ..."): a SIGINT that lands there vanishes and the run goes on.
  :func:`interrupt_latch` remembers every SIGINT, and :func:`check_interrupt` raises
  ``KeyboardInterrupt`` again at the next safe point (between pipeline stages, at the end
  of a command) if one was received. Inside the latch such a dropped interrupt is not
  printed either (``sys.unraisablehook``): the user sees "interrupted", not a
  traceback.
"""

from __future__ import annotations

import contextlib
import signal
import sys
import threading

__all__ = ["check_interrupt", "deferred_interrupt", "forget_unhandled_interrupt",
           "interrupt_latch"]

_received = threading.Event()


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


@contextlib.contextmanager
def interrupt_latch():
    """SIGINT raises ``KeyboardInterrupt`` as usual and is also remembered for
    :func:`check_interrupt`. A no-op outside the main thread."""
    if not _main_thread():
        yield
        return

    def handler(signum, frame):
        _received.set()
        raise KeyboardInterrupt

    previous_hook = sys.unraisablehook

    def quiet_interrupt(unraisable):
        # the interrupt Python cannot raise there is remembered, not printed as an
        # "Exception ignored in ... Traceback" block: check_interrupt raises it
        if isinstance(unraisable.exc_value, KeyboardInterrupt):
            _received.set()
            return
        previous_hook(unraisable)

    previous = signal.signal(signal.SIGINT, handler)
    sys.unraisablehook = quiet_interrupt
    _received.clear()
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        sys.unraisablehook = previous_hook
        _received.clear()


def check_interrupt() -> None:
    """Raise ``KeyboardInterrupt`` if a SIGINT was received inside :func:`interrupt_latch`
    (whether or not the code that was running let it through)."""
    if _received.is_set():
        raise KeyboardInterrupt


@contextlib.contextmanager
def deferred_interrupt():
    """Defer SIGINT until the block ends, then deliver it (``KeyboardInterrupt``).

    A no-op outside the main thread or when SIGINT is not handled by Python (ignored,
    or the default C action).
    """
    previous = signal.getsignal(signal.SIGINT) if _main_thread() else None
    if not callable(previous):
        yield
        return
    received = []
    signal.signal(signal.SIGINT, lambda signum, frame: received.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
        if received:
            previous(signal.SIGINT, None)
            raise KeyboardInterrupt  # the previous handler did not raise


def forget_unhandled_interrupt() -> None:
    """Let a process whose ``KeyboardInterrupt`` was handled exit with its own status.

    CPython (3.8-3.13) ends ``python -m ...`` by re-raising SIGINT on itself (status -2,
    not the 130 the command returned) when a ``KeyboardInterrupt`` once escaped code
    run from a *string*, even if a caller caught it afterwards: ``exec``/``eval`` of
    source text set an interpreter flag (``unhandled_keyboard_interrupt``) that only
    the next evaluation of a string clears. Such code runs all the time during lazy
    imports (dataclasses and namedtuples build their methods with ``exec``), so a
    Ctrl-C that landed there ended ``mvtk run`` by a signal after it had printed
    "interrupted" (about 1 run in 8 at some delays). Evaluating a trivial string
    clears the flag.
    """
    eval("None")  # noqa: S307 - a constant; the evaluation itself is the point
