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
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["EXIT_INTERRUPTED", "EXIT_TERMINATED", "Terminated", "deferred", "note_terminated",
           "sticky", "terminate_as_interrupt"]

EXIT_INTERRUPTED = 128 + signal.SIGINT
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


class _Noted:
    """The signals that came while they were deferred."""

    def __init__(self) -> None:
        self.signals: list[int] = []

    def handle(self, signum: int, _frame: object) -> None:
        self.signals.append(signum)


_depth = [0]


@contextlib.contextmanager
def deferred() -> Iterator[None]:
    """Meanwhile, SIGINT and SIGTERM are noted, not raised; when it ends, the first one
    noted is raised as it would have been (KeyboardInterrupt, or :class:`Terminated`).

    For what a signal must not cut in two: forking a worker process (Python's fork
    hooks swallow an exception raised in them, and the child would inherit a handler
    that raises), stopping the workers, writing a record. In the main thread only
    (elsewhere no handler can be set, and nothing changes); nested, the outermost
    decides."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    if _depth[0]:  # (inside another: that one's handlers note, and it raises)
        _depth[0] += 1
        try:
            yield
        finally:
            _depth[0] -= 1
        return
    noted = _Noted()
    previous = {s: signal.signal(s, noted.handle) for s in (signal.SIGINT, signal.SIGTERM)}
    _depth[0] = 1
    try:
        yield
    finally:
        _depth[0] = 0
        for each, handler in previous.items():
            signal.signal(each, handler)
        if noted.signals:  # (raised in place of what the block raised, if it did)
            first = signal.Signals(noted.signals[0])
            _raise_as(first, previous[first])


@contextlib.contextmanager
def sticky() -> Iterator[Callable[[], None]]:
    """Meanwhile, SIGINT and SIGTERM do what their handlers do, and are noted too; the
    check it gives raises, as its handler would, one that came and was lost.

    Python runs a signal's handler wherever the main thread is. In a weakref's callback
    or a finalizer, which the cycle collector may run at any moment, what the handler
    raises is printed as ignored and dropped: a Ctrl-C that came then would not stop a
    batch, which would run to its end. A loop calls the check where it may stop (after
    each wait): a signal that stopped it as it should has left its block already. (What
    Python would print of one it dropped is not printed: the check says it.) In the
    main thread only (elsewhere no handler can be set: the check does nothing); a signal
    whose handler is not Python's (ignored, or the system's default) is left as it is."""
    if threading.current_thread() is not threading.main_thread():
        yield lambda: None
        return
    previous: dict[signal.Signals, Callable[[int, Any], Any]] = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        handler = signal.getsignal(signum)
        if callable(handler):
            previous[signum] = handler
    noted: list[signal.Signals] = []

    def handle(signum: int, _frame: object) -> None:
        noted.append(signal.Signals(signum))
        _raise_as(signum, previous[signal.Signals(signum)])

    def check() -> None:
        if noted:
            first = noted[0]
            noted.clear()
            _raise_as(first, previous[first])

    said = sys.unraisablehook

    def unraisable(dropped: Any) -> None:
        if not (noted and isinstance(dropped.exc_value, KeyboardInterrupt)):
            said(dropped)  # (a dropped signal is raised at the check: not a word here)

    for signum in previous:
        signal.signal(signum, handle)
    sys.unraisablehook = unraisable
    try:
        yield check
    finally:
        sys.unraisablehook = said
        for signum, kept in previous.items():
            signal.signal(signum, kept)


def _raise_as(signum: int, handler: object) -> None:
    """Do what ``handler`` (the one a signal found deferred) does with ``signum``."""
    if callable(handler):
        handler(signum, None)
    elif handler == signal.SIG_DFL:
        signal.raise_signal(signum)  # (what no handler of Python's catches: the default)
