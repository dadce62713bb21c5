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
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["EXIT_INTERRUPTED", "EXIT_TERMINATED", "Terminated", "deferred", "note_terminated",
           "sticky", "stop_if_signalled", "terminate_as_interrupt"]

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


_checks: list[Callable[[], None]] = []
"""The check of the :func:`sticky` block open in this process, if one is."""
os.register_at_fork(after_in_child=_checks.clear)  # (a worker forked in one has none)


def stop_if_signalled() -> None:
    """Raise a Ctrl-C or SIGTERM that came and was lost, if a :func:`sticky` block is
    open (in the main thread: elsewhere, nothing). For what makes one step of work after
    another and may stop between two, whoever runs it: a run, at each line of its trace."""
    if _checks:
        _checks[0]()


@contextlib.contextmanager
def sticky() -> Iterator[Callable[[], None]]:
    """Meanwhile, a Ctrl-C or SIGTERM that Python drops is kept: the check it gives (and
    :func:`stop_if_signalled`) raises it.

    Python runs a signal's handler wherever the main thread is. In a weakref's callback
    or a finalizer, which the cycle collector may run at any moment, what the handler
    raises is printed as ignored and dropped: a Ctrl-C that came then would not stop a
    batch, which would run to its end. A loop calls the check where it may stop (after
    each wait, at each trace line). What Python would print of the dropped signal is not
    printed (the check raises it); anything else a finalizer raises is printed as
    before. The check does nothing in a thread other than the main one (where no
    signal's handler runs). Nested, the inner blocks give the outermost's check."""
    if _checks:
        yield _checks[0]
        return
    dropped: list[BaseException] = []

    def check() -> None:
        if dropped and threading.get_ident() == threading.main_thread().ident:
            lost = dropped[0]
            dropped.clear()
            raise lost.with_traceback(None)

    said = sys.unraisablehook

    def unraisable(what: Any) -> None:
        if isinstance(what.exc_value, KeyboardInterrupt):  # (or Terminated)
            dropped.append(what.exc_value)  # (raised at the check: not a word here)
        else:
            said(what)

    sys.unraisablehook = unraisable
    _checks.append(check)
    try:
        yield check
    finally:
        _checks.clear()
        sys.unraisablehook = said


def _raise_as(signum: int, handler: object) -> None:
    """Do what ``handler`` (the one a signal found deferred) does with ``signum``."""
    if callable(handler):
        handler(signum, None)
    elif handler == signal.SIG_DFL:
        signal.raise_signal(signum)  # (what no handler of Python's catches: the default)
