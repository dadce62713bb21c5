"""``prima ARGV`` in a child process that sends itself a signal (Ctrl-C's SIGINT, or
SIGTERM) once its trace has passed a time of the run: the signal lands at a point of the
run, not of the wall clock. (A signal the test sent after a while would land wherever a
loaded machine had got to, or before the run had begun; and a trace written to a file
cannot be watched as it grows: it is written to a temporary file, in chunks.)"""

from __future__ import annotations

import signal
import subprocess
import sys

_CHILD = """
import os, signal, sys
import prima.run
from prima.cli import main

made, which, after = prima.run.Run, getattr(signal, sys.argv[1]), float(sys.argv[2])

def run(*args, sink, **kwargs):
    sent = []
    def watched(line):
        sink(line)
        if line.t > after and not sent:
            sent.append(line.t)
            os.kill(os.getpid(), which)
    return made(*args, sink=watched, **kwargs)

prima.run.Run = run
sys.exit(main(sys.argv[3:]))
"""

HANG = 600.0
"""Seconds the child may take at most: a bound against a hang, not a speed."""


def signalled_run(which: str, after: float, *argv: str) -> subprocess.CompletedProcess[str]:
    """``prima ARGV`` (a ``prima run``), sent the signal named ``which`` (``"SIGINT"``,
    ``"SIGTERM"``) by itself once its trace passes ``after`` simulated seconds; its exit
    status and what it said."""
    return subprocess.run(
        [sys.executable, "-c", _CHILD, which, str(after), *argv], capture_output=True,
        text=True, check=False, timeout=HANG,
        # Ctrl-C's default action in the child even when this process ignores SIGINT (as
        # a background job of a non-interactive shell does, and its children inherit)
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
