"""Runs one red-team case in a forked child, under a CPU-time and a memory limit.

A case writes its input (a document, scenario, map, profile, a named pipe...)
into a folder, then the child runs ``prima validate`` on it exactly as the
command line does, optionally followed by more work on an accepted input
(matching an answer, say). The child's verdict carries the CPU time it took (so a
loaded machine does not fail a case: a quadratic cost still would). A hang fails
the case instead of the test run, and neither is told by the wall clock, which a
loaded machine stretches: a child that spins (a backtracking regex in C) is ended by
its CPU time, four times its limit and a second (``RLIMIT_CPU``); one that waits
without spinning (a blocked FIFO) is killed by the parent after :data:`HANG` seconds
of waiting, a bound no case comes near. The child's address space is capped with
``RLIMIT_AS``, so an entity bomb or a quadratic blow-up fails with a MemoryError
instead of taking the machine down.
"""

from __future__ import annotations

import io
import math
import multiprocessing
import os
import resource
import signal
import sys
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass
from multiprocessing.connection import Connection
from pathlib import Path

from prima.cli import main

HANG = 600.0
"""Seconds the parent waits for a child's verdict at most: the bound on a child that
waits without using its CPU time (a busy one ends by ``RLIMIT_CPU`` first)."""

Make = Callable[[Path], Path]
"""Writes a case's input into a folder and returns the path to validate."""


@dataclass(frozen=True)
class Rejected:
    """Validation fails; its first error is at ``at`` in ``file`` and says ``fragment``.

    ``at`` is a (line, col), or a piece of the file's text whose first character
    is where the error points (``offset`` characters later).
    """

    fragment: str
    at: str | tuple[int, int] = (1, 1)
    file: str | None = None
    """The file the error is in, relative to the case's folder (default: the input)."""
    offset: int = 0


@dataclass(frozen=True)
class Accepted:
    """Validation passes (warnings allowed)."""


@dataclass(frozen=True)
class Exits:
    """Another command (``Case.command``) ends with ``code`` and says ``fragment`` (on
    standard output or error), and nothing it says matches ``absent`` (a regular
    expression: raw control characters, say)."""

    code: int
    fragment: str = ""
    absent: str = ""


Verdict = Rejected | Accepted | Exits


@dataclass(frozen=True)
class Case:
    """One hostile input and what must become of it."""

    id: str
    attack: str
    """What it attacks."""
    make: Make
    expect: Verdict
    argv: tuple[str, ...] = ()
    """More ``prima validate`` options (``--robot``...); ``{dir}`` is the case's folder."""
    seconds: float = 2.0
    """CPU seconds the case may take."""
    megabytes: int = 512
    then: Callable[[Path], object] | None = None
    """More work on an accepted input, inside the same limits."""
    command: tuple[str, ...] = ()
    """Another command than ``prima validate``, whole (``{path}``: the input, ``{dir}``:
    its folder, ``{port}``: what the file ``port`` there says), with an :class:`Exits`
    verdict."""
    stdin: str | bytes = ""
    """What ``prima debug`` reads as typed (text), or the bytes ``prima lsp`` reads from
    its client (bytes; what it answers is dropped)."""
    file_limit: int | None = None
    """The most bytes the child may write into one file (``RLIMIT_FSIZE``): a write past
    it fails as on a full disk (``EFBIG``), half-way through an output."""
    env: tuple[tuple[str, str], ...] = ()
    """Environment variables the command runs with (in the child only)."""


@dataclass(frozen=True)
class Outcome:
    code: int
    out: str
    err: str
    seconds: float
    crash: str = ""


def _vm_bytes() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmSize:"):
            return int(line.split()[1]) * 1024
    return 0


def _child(case: Case, path: Path, conn: Connection) -> None:
    try:
        cap = _vm_bytes() + case.megabytes * 1024 * 1024
        resource.setrlimit(resource.RLIMIT_AS, (cap, cap))
        cpu = cpu_bound(case)
        resource.setrlimit(resource.RLIMIT_CPU, (cpu, cpu + 1))  # SIGXCPU, then SIGKILL
        if case.file_limit is not None:
            signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # (the write fails instead)
            hard = resource.getrlimit(resource.RLIMIT_FSIZE)[1]  # (``then`` may lift it)
            resource.setrlimit(resource.RLIMIT_FSIZE, (case.file_limit, hard))
        argv = [a.replace("{dir}", str(path.parent)) for a in case.argv]
        out, err = io.StringIO(), io.StringIO()
        start = time.process_time()
        if case.command:
            import prima.cli._debug

            if isinstance(case.stdin, bytes):  # a language client's bytes
                sys.stdin = io.TextIOWrapper(io.BytesIO(case.stdin))
                sys.stdout = io.TextIOWrapper(io.BytesIO())
            else:
                typed = case.stdin
                prima.cli._debug._stdin = lambda: io.StringIO(typed)
            os.environ.update(dict(case.env))
            port = path.parent / "port"  # (a port the case's input listens on)
            command = [a.replace("{path}", str(path)).replace("{dir}", str(path.parent))
                       .replace("{port}", port.read_text() if port.exists() else "")
                       for a in case.command]
            code = main(command, out=out, err=err)
        else:
            code = main(["validate", *argv, str(path)], out=out, err=err)
        if case.then is not None and (code == 0 or case.command):
            case.then(path)
        conn.send(Outcome(code, out.getvalue(), err.getvalue(), time.process_time() - start))
    except BaseException:  # noqa: BLE001 - everything is a failure of the case, reported
        conn.send(Outcome(-1, "", "", 0.0, traceback.format_exc()))
    finally:
        conn.close()
        os._exit(0)


def cpu_bound(case: Case) -> int:
    """The CPU seconds after which a case's child is ended (a hang that spins)."""
    return math.ceil(case.seconds * 4 + 1)


def run_case(case: Case, folder: Path, hang: float = HANG) -> tuple[Path, Outcome]:
    """Make the case's input in ``folder`` and validate it in a child: the input and what
    became of it. A child that spins past :func:`cpu_bound` ends, one that waits ``hang``
    seconds is killed, and either is an AssertionError."""
    path = case.make(folder)
    receive, send = multiprocessing.Pipe(duplex=False)
    child = multiprocessing.get_context("fork").Process(target=_child, args=(case, path, send))
    child.start()
    send.close()
    if not receive.poll(hang):
        child.kill()
        child.join()
        raise AssertionError(f"{case.id}: no verdict after waiting {hang:g} s (a hang)")
    try:
        outcome: Outcome = receive.recv()
    except EOFError:  # (ended without a verdict: over its CPU time)
        child.join()
        raise AssertionError(f"{case.id}: no verdict within {cpu_bound(case)} s of CPU time "
                             f"(a hang; the child ended with {child.exitcode})") from None
    child.join()
    return path, outcome


def position(text: str, at: str | tuple[int, int], offset: int = 0) -> tuple[int, int]:
    """The line and column ``at`` designates in ``text``."""
    if isinstance(at, tuple):
        return at
    index = text.index(at) + offset
    line = text.count("\n", 0, index) + 1
    return line, index - (text.rfind("\n", 0, index) + 1) + 1
