"""SIGINT inside code that swallows KeyboardInterrupt (pyuff's bare except) stays an interrupt."""

import os
import signal

import pytest

from mvtk._interrupt import deferred_interrupt


def _swallowing_reader():
    """What pyuff does: any failure, Ctrl-C included, becomes a generic Exception."""
    try:
        os.kill(os.getpid(), signal.SIGINT)
        return "read"
    except BaseException:  # noqa: BLE001 - imitating the peer
        raise Exception("Error when reading data-set(s).") from None


def test_sigint_during_a_swallowing_call_is_raised_after_it():
    done = []
    with pytest.raises(KeyboardInterrupt):
        with deferred_interrupt():
            done.append(_swallowing_reader())
    assert done == ["read"]   # the call finished, then the interrupt came
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler


def test_no_signal_no_effect():
    with deferred_interrupt():
        x = 1
    assert x == 1
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
