"""What every command shares: exit statuses, colour as asked, how problems and usage
errors are worded, and a command's entry in the table (:class:`Command`)."""

from __future__ import annotations

import argparse
import contextlib
import importlib
import signal
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from typing import TextIO, TypeAlias

from prima.errors import Problem, Severity
from prima.escape import terminal
from prima.record import Record
from prima.signals import Terminated, note_terminated
from prima.suggest import SuggestingParser
from prima.term import BOLD, RED, WHEN, YELLOW, Paint, wants_colour

Commands: TypeAlias = "argparse._SubParsersAction[SuggestingParser]"
"""Where a command adds its parser (``prima``'s subcommands)."""


@dataclass(frozen=True, repr=False, eq=False)
class Command(Record):
    """One ``prima`` command: its name, what adds its arguments, and what it does (given
    the parsed arguments, standard output and error; it returns the exit status)."""

    name: str
    add: Callable[[Commands], None]
    execute: Callable[[argparse.Namespace, TextIO, TextIO], int]


EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_PIPE = 0, 1, 2, 130, 141
"""141: as a shell reports a process its closed pipe stopped (128 + SIGPIPE)."""


_colour = "auto"
"""``--color`` as this command line gives it (``main`` sets it first)."""


def set_colour(when: str) -> None:
    """``--color`` as the command line gives it (:func:`~prima.cli.main` sets it first)."""
    global _colour
    _colour = when


def _colour_asked(given: Sequence[str]) -> str:
    """``--color WHEN`` as the words of a command line give it, before they are parsed
    (an error parsing them is coloured as asked)."""
    when = "auto"
    for i, word in enumerate(given):
        if word == "--":
            break
        value = word.partition("=")[2] if word.startswith("--color=") else \
            given[i + 1] if word == "--color" and i + 1 < len(given) else None
        when = value if value in WHEN else when
    return when


def _paint(stream: TextIO) -> Paint:
    """Colour for what goes to ``stream`` (:func:`prima.term.wants_colour`)."""
    return Paint(wants_colour(stream, _colour))


def _error(command: str, stream: TextIO) -> str:
    """``prima COMMAND: error:``, coloured for a terminal."""
    return f"prima {command}: {_paint(stream)('error', RED, BOLD)}:"


def _report(problems: Iterable[Problem], to: TextIO) -> None:
    """One line per problem, its file's name and message escaped (they may hold control
    characters); under a fault inside an expression, its line and a caret. On a
    terminal, ``file:line:col:`` in bold, ``error`` in red, ``warning`` in yellow."""
    paint = _paint(to)
    for problem in problems:
        where = f"{terminal(problem.file)}:{problem.line}:{problem.col}:"
        severity = problem.severity.value
        if paint.on:
            print(paint(where, BOLD), paint(severity, RED if problem.severity is Severity.ERROR
                                             else YELLOW, BOLD) + ":",
                  terminal(problem.message), file=to)
        else:
            print(f"{where} {severity}: {terminal(problem.message)}", file=to)
        caret = _caret(problem)
        if caret:
            print(caret, file=to)


def _caret(problem: Problem) -> str:
    """``problem``'s source line and a caret under its column (:meth:`Problem.caret`),
    the line escaped as every row is (tabs kept, so the caret still lines up)."""
    if not problem.source:
        return ""
    line = problem.source.rstrip("\r\n")
    shown = "\t".join(terminal(part) for part in line.split("\t"))
    pad = "".join(c if c == "\t" else " " * len(terminal(c))
                  for c in line[: max(problem.col - 1, 0)])
    return f"    {shown}\n    {pad}^"


def _usage(command: str, message: str, err: TextIO) -> int:
    # (escaped: a file's name, an option's value in it may hold an escape sequence)
    print(f"{_error(command, err)} {terminal(message)}", file=err)
    return EXIT_USAGE


def _missing_extra(module: str, library: str, extra: str) -> str | None:
    """Why a viewer cannot run here: the optional extra it needs is not installed
    (checked before anything runs, like a usage error)."""
    try:
        importlib.import_module(module)
    except ImportError:
        return (f"{library} is not installed; install the {extra} extra: pip install "
                f"'prima[{extra}]' (in a checkout of PRIMA: pip install -e '.[{extra}]')")
    return None


class _Deferred:
    """A Ctrl-C noted, to be raised at the next safe point (``check``)."""

    def __init__(self) -> None:
        self.asked = False
        self.terminated = False

    def handle(self, signum: int, _frame: object) -> None:
        if signum == signal.SIGTERM:
            self.terminated = True
            note_terminated()
        if self.asked:  # a second Ctrl-C: at once
            self.check()
        self.asked = True

    def check(self) -> None:
        if self.asked:
            raise Terminated if self.terminated else KeyboardInterrupt


@contextlib.contextmanager
def _between_lines() -> Iterator[_Deferred]:
    """While writing a file that a torn write would spoil (a chrome trace), Ctrl-C and
    SIGTERM are raised only between two trace lines (a second one at once)."""
    deferred = _Deferred()
    if threading.current_thread() is not threading.main_thread():
        yield deferred  # signals go to the main thread only
        return
    previous = signal.signal(signal.SIGINT, deferred.handle)
    terminate = signal.signal(signal.SIGTERM, deferred.handle)
    try:
        yield deferred
    finally:
        signal.signal(signal.SIGINT, previous)
        signal.signal(signal.SIGTERM, terminate)


class _BarLine:
    """Standard error while a progress bar is drawn on it: whether the bar's line is
    still open. Leaving the block (``with``), however it is left, ends that line, so
    nothing printed next, on standard output or error, shares it with the bar."""

    def __init__(self, err: TextIO) -> None:
        self.err = err
        self.open = False

    def write(self, text: str) -> None:
        if text:
            self.err.write(text)
            self.err.flush()
            self.open = not text.endswith("\n")

    def end(self) -> None:
        if self.open:
            self.open = False
            self.err.write("\n")
            self.err.flush()

    def __enter__(self) -> _BarLine:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.end()


def _colour_argument(parser: argparse.ArgumentParser, default: str = argparse.SUPPRESS) -> None:
    """``--color``, before the command or after it (there, only when given)."""
    parser.add_argument("--color", choices=WHEN, default=default,
                        help="colour the output: auto (default: on a terminal, unless "
                             "NO_COLOR is set; FORCE_COLOR forces it), always or never")
