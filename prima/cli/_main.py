"""``prima``'s parser and its entry: :func:`main`. Each command is one module of this
package (its arguments, and a call into the library), one name in :data:`NAMES`."""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import stat
import sys
from collections.abc import Callable, Sequence
from typing import TextIO

from prima import __version__, compiled
from prima.cli._common import (
    EXIT_ERRORS,
    EXIT_INTERRUPTED,
    EXIT_PIPE,
    Command,
    _colour_argument,
    _colour_asked,
    _error,
    _paint,
    _report,
    _usage,
    set_colour,
)
from prima.errors import LocatedError, PrimaError
from prima.escape import terminal
from prima.signals import EXIT_TERMINATED, sticky, terminate_as_interrupt
from prima.suggest import SuggestingParser, unrecognized
from prima.term import BOLD, RED

__all__ = ["NAMES", "build_parser", "command", "main"]

# Each command imports what it needs when it runs (``prima --help`` imports no lxml,
# lark or pymunk; ``prima validate`` of documents no simulator), and the parser imports
# only the module of the command the line names: a cold start pays for its own command.

NAMES: tuple[str, ...] = ("validate", "run", "debug", "test", "judge", "sweep", "check",
                          "show", "plot", "live", "lsp", "completion")
"""Every ``prima`` command, in the order ``prima --help`` lists them: the command ``NAME``
is the module ``prima/cli/_NAME.py`` and its ``COMMAND``."""


def command(name: str) -> Command:
    """The command ``name`` of :data:`NAMES` (its module imported now)."""
    found: Command = importlib.import_module(f"prima.cli._{name}").COMMAND
    return found


def _named(given: Sequence[str]) -> str | None:
    """The command a command line names (its first word that is no option, past
    ``--color``'s value), if it is one of :data:`NAMES`; else None."""
    words = iter(given)
    for word in words:
        if word == "--color":
            next(words, None)
        elif not word.startswith("-"):
            return word if word in NAMES else None
    return None


def build_parser(given: Sequence[str] | None = None) -> SuggestingParser:
    """``prima``'s parser; for the command line ``given``, only the command it names (the
    others' modules are not imported), and none at all for ``prima --version``. Every
    command when ``given`` is None, or for ``prima --help``, a mistyped command,
    completion."""
    parser = SuggestingParser(
        prog="prima",
        description="PRIMA: mediate two robot applications sharing one personal robot.",
    )
    build = " (compiled)" if compiled() else ""
    parser.add_argument("--version", action="version", version=f"prima {__version__}{build}")
    _colour_argument(parser, "auto")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    named = None if given is None else _named(given)
    version = given is not None and named is None and "--version" in given \
        and not {"-h", "--help"} & set(given)
    for name in NAMES:
        if (named is None and not version) or name == named:
            command(name).add(commands)
    return parser


def main(argv: Sequence[str] | None = None, out: TextIO | None = None,
         err: TextIO | None = None) -> int:
    out = out or sys.stdout
    err = err or sys.stderr
    given = list(sys.argv[1:] if argv is None else argv)
    completing = "_ARGCOMPLETE" in os.environ
    parser = build_parser(None if completing else given)
    if completing:  # the shell asks what may come next (prima completion)
        try:
            from prima.completion import autocomplete
        except ImportError:  # (no argcomplete: the shell completes file names instead)
            return EXIT_ERRORS
        autocomplete(parser)
    set_colour(_colour_asked(given))
    error = _paint(sys.stderr)("error", RED, BOLD)
    for each in (parser, *_subparsers(parser)):
        each.given = given  # (for a did-you-mean in a "required" error)
        each.error_word = error
        each.escape = terminal
    try:
        args, extra = parser.parse_known_args(argv)
        if extra:  # as parse_args would say, with the option a misspelt one may be
            _subparser(parser, args.command).error(unrecognized(extra, _subparser(
                parser, args.command)))
    except SystemExit as exc:
        return int(exc.code or 0)
    set_colour(args.color)
    problem = _locate_inputs(args)
    if problem:
        return _usage(args.command, problem, err)
    execute: Callable[[argparse.Namespace, TextIO, TextIO], int] = command(args.command).execute
    # (sticky: a Ctrl-C a finalizer dropped stops the command at its next step, such as a
    # run's next trace line, rather than nowhere)
    with terminate_as_interrupt() as signals, sticky():
        status = _main(execute, args, out, err)
    return EXIT_TERMINATED if signals.terminated and status == EXIT_INTERRUPTED else status


_INPUTS = {"scenario": None, "input": None, "paths": None, "inputs": None, "map": "map",
           "eas": "ea", "fa": "fa", "ea": "ea", "robot": "robot"}
"""The options and arguments that name files to read, each with what a bare name there
names (:data:`prima.shipped.NAMED`: ``--fa fa2-follow``), or None."""

_FOLDERS_TOO = ("paths",)
"""The arguments that may name a folder as well as a file (``prima validate``, ``prima
test`` and ``prima judge`` search it)."""


def _locate_inputs(args: argparse.Namespace) -> str | None:
    """Each file to read as :func:`prima.shipped.locate` finds it: one the current folder
    lacks may be shipped with PRIMA (``scenarios/thesis/sample-03.xml`` from an install,
    as from a checkout). Not for ``prima test --update``, which writes beside them: PRIMA's
    own golden traces are not rewritten from outside a checkout. What is wrong with a name
    no file can have (too long to look up), or with what a name found is (a folder where
    a file is expected, a named pipe), as a usage error, or None."""
    for name in _INPUTS:
        value = getattr(args, name, None)
        for text in value if isinstance(value, list) else [value]:
            problem = _unnameable(text) if isinstance(text, str) else None
            if problem:
                return problem
    if not getattr(args, "update", False):
        from prima.shipped import locate

        for name, kind in _INPUTS.items():
            value = getattr(args, name, None)
            if isinstance(value, str):
                setattr(args, name, locate(value, kind))
            elif isinstance(value, list):
                setattr(args, name, [locate(v, kind) if isinstance(v, str) else v
                                     for v in value])
    if args.command == "validate":  # (it reports such a file at file:1:1, and goes on)
        return None
    for name in _INPUTS:
        value = getattr(args, name, None)
        for text in value if isinstance(value, list) else [value]:
            problem = _not_a_file(text, name in _FOLDERS_TOO) if isinstance(text, str) else None
            if problem:
                return problem
    return None


def _not_a_file(text: str, folder: bool) -> str | None:
    """Why what ``text`` names cannot be read as a file: it is a folder (unless ``folder``
    may be one), a named pipe, a device or a socket; or None, for a regular file or for
    nothing at all (the command says there is no such file). It is looked at, never
    opened: reading a named pipe would wait for a writer for ever."""
    try:
        mode = os.stat(text).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISREG(mode) or (folder and stat.S_ISDIR(mode)):
        return None
    if stat.S_ISDIR(mode):
        return f"{text}: is a folder, not a file"
    kind = "a named pipe" if stat.S_ISFIFO(mode) else "a socket" if stat.S_ISSOCK(mode) \
        else "a device" if stat.S_ISCHR(mode) or stat.S_ISBLK(mode) else None
    return f"{text}: is {kind}, not a regular file" if kind else f"{text}: is not a regular file"


def _unnameable(text: str) -> str | None:
    """Why the system cannot look ``text`` up at all (a name longer than a file's or a
    path's may be), or None."""
    try:
        os.stat(text)
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            return f"{terminal(text[:40])}...: {os.strerror(exc.errno).lower()}"
    except ValueError:  # (a NUL in it: the commands say there is no such file)
        pass
    return None


def _main(command: Callable[[argparse.Namespace, TextIO, TextIO], int],
          args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    try:
        return command(args, out, err)
    except LocatedError as exc:
        _report(exc.problems, err)
        return EXIT_ERRORS
    except PrimaError as exc:  # a user's error is a message, never a traceback
        print(f"{_error(args.command, err)} {exc}", file=err)
        return EXIT_ERRORS
    except BrokenPipeError:  # e.g. `prima validate apps/ | head`: the reader had enough
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the flush at exit
        return EXIT_PIPE
    except OSError as exc:  # the file system refused (a name too long...): a message too
        from prima.output import shown

        reason = exc.strerror or str(exc)
        named = f"{shown(os.fsdecode(exc.filename))}: " if exc.filename is not None else ""
        print(f"{_error(args.command, err)} {named}{reason[:1].lower() + reason[1:]}",
              file=err)
        return EXIT_ERRORS
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: what was written so far stays written
        print(f"prima {args.command}: interrupted", file=err)
        return EXIT_INTERRUPTED


def _subparsers(parser: argparse.ArgumentParser) -> list[SuggestingParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return [p for p in action.choices.values() if isinstance(p, SuggestingParser)]


def _subparser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    chosen: argparse.ArgumentParser = action.choices[command]
    return chosen
