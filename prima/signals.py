"""SIGTERM handled as Ctrl-C is: what CI cancellation, ``timeout`` and ``kill`` send.

A command stopped by SIGTERM ends as one stopped by Ctrl-C does: the trace or
page written so far stays written and whole (its buffered tail flushed), a
sweep keeps its finished runs, and the exit status says which signal it was
(143 = 128 + SIGTERM, where Ctrl-C gives 130). :class:`Terminated` is a
:class:`KeyboardInterrupt`, so every place that keeps its work on Ctrl-C keeps
it on SIGTERM too.
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Iterator

__all__ = ["EXIT_TERMINATED", "Terminated", "note_terminated", "terminate_as_interrupt"]

EXIT_TERMINATED = 128 + signal.SIGTERM


class Terminated(KeyboardInterrupt):
    """SIGTERM arrived."""


class _Received:
    def __init__(self) -> None:
        self.terminated = False

    def handle(self, _signum: int, _frame: object) -> None:
        self.terminated = True
        raise Terminated


_received = _Received()


def note_terminated() -> None:
    """SIGTERM came, and a handler of its own (one that defers it) took it."""
    _received.terminated = True


@contextlib.contextmanager
def terminate_as_interrupt() -> Iterator[_Received]:
    """Meanwhile, SIGTERM raises :class:`Terminated` (in the main thread; elsewhere,
    where no signal handler can be set, nothing changes). ``terminated`` says
    whether it came."""
    received = _received
    received.terminated = False
    if threading.current_thread() is not threading.main_thread():
        yield received
        return
    previous = signal.signal(signal.SIGTERM, received.handle)
    try:
        yield received
    finally:
        signal.signal(signal.SIGTERM, previous)
