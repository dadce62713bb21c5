"""``python -m prima`` and the ``prima`` command: :func:`prima.cli.main`, with Ctrl-C and SIGTERM
one line and an exit status at any moment of the process, not only while a command runs.

It imports nothing heavy before it takes the signals: one that comes while the
command's modules load (before :func:`prima.cli.main` handles it itself) ends the
process with ``prima: interrupted`` and 130 (143 for SIGTERM); one that comes once
the command is done, while Python shuts down (its worker pools joined, its files
closed), ends it at once with the command's own status, instead of a traceback from
whatever Python was doing then. A command that a signal ended ends the process as soon
as it returns, without Python's shutdown. Tests call :func:`prima.cli.main` itself.
"""

from __future__ import annotations

import contextlib
import gc
import os
import signal
import sys

from prima.signals import EXIT_INTERRUPTED, EXIT_TERMINATED, Terminated

__all__ = ["main"]


def _terminated(_signum: int, _frame: object) -> None:
    raise Terminated


def main() -> int:
    """Run the command the process' arguments name; its exit status."""
    # What Python made as it started lives as long as the process: the collections
    # PRIMA's imports set off leave it unvisited (2% of a cold ``prima validate``).
    gc.freeze()
    try:
        # (as Ctrl-C: the command's own sets it too. Inside the try: a SIGTERM that comes
        # as it is set is handled at once, while setting it still returns)
        signal.signal(signal.SIGTERM, _terminated)
        from prima.cli import main as command

        status = command()
    except KeyboardInterrupt as exc:
        print("prima: interrupted", file=sys.stderr)
        status = EXIT_TERMINATED if isinstance(exc, Terminated) else EXIT_INTERRUPTED
    _done(status)
    return status


def _done(status: int) -> None:
    """From now on a signal ends the process at once, with ``status``: the command said
    what it had to (flushed here). A command a signal ended ends the process now."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError):  # (a closed pipe or stream)
            stream.flush()
    if status in (EXIT_INTERRUPTED, EXIT_TERMINATED):
        _leave_now(status)

    def leave(_signum: int, _frame: object) -> None:
        os._exit(status)

    signal.signal(signal.SIGINT, leave)
    signal.signal(signal.SIGTERM, leave)
    # Python's own shutdown may race a worker pool's wakeup pipe (concurrent.futures'
    # exit handler writes to it as its manager thread closes it: "Exception ignored
    # in: <module 'threading'> ... Bad file descriptor"): not the command's words.
    sys.unraisablehook = _unsaid


def _leave_now(status: int) -> None:
    """End the process a signal stopped the command of, its worker processes first.

    The command closed its files and said so. Python's shutdown would join the threads
    it leaves: a worker pool's manager thread may wait there for ever, on a result that
    a worker the signal ended was writing (the pipe never ends: this process holds its
    other end too; a sweep said "interrupted" and hung). A worker still busy (one forked
    as the signal came, which it did not see) is ended here, as Python's shutdown would
    have waited for it, not left running with the process' standard error."""
    if "multiprocessing" in sys.modules:  # (no worker pool without it)
        import multiprocessing

        children = multiprocessing.active_children()
        for child in children:
            with contextlib.suppress(OSError):
                child.kill()
        for child in children:
            child.join()
    os._exit(status)


def _unsaid(_unraisable: object) -> None:
    """What Python reports, once the command is done, of an error it ignores."""


if __name__ == "__main__":
    sys.exit(main())
