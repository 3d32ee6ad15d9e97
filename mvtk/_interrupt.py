"""Keep Ctrl-C a Ctrl-C through third-party code that swallows it.

pyuff wraps every failure of a record read, ``KeyboardInterrupt`` included (bare
``except:``), into a generic ``Exception("Error when reading data-set(s).")``; an
interrupted run would then be reported as a corrupt file. :func:`deferred_interrupt`
holds SIGINT back for the duration of such a call and raises ``KeyboardInterrupt``
right after it.
"""

from __future__ import annotations

import contextlib
import signal
import threading

__all__ = ["deferred_interrupt"]


@contextlib.contextmanager
def deferred_interrupt():
    """Defer SIGINT until the block ends, then raise ``KeyboardInterrupt``.

    A no-op outside the main thread or when SIGINT has a handler other than Python's
    default (the caller then owns the signal).
    """
    if (threading.current_thread() is not threading.main_thread()
            or signal.getsignal(signal.SIGINT) is not signal.default_int_handler):
        yield
        return
    received = []
    signal.signal(signal.SIGINT, lambda signum, frame: received.append(signum))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        if received:
            raise KeyboardInterrupt
