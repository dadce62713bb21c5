"""``prima debug``: step through a run, decision by decision.

The run goes on as ``prima run`` would; the debugger sees each trace line as it is
made, and stops at the ones asked for (the next line, or a breakpoint) to read
commands: where the run is, the mediator's working memory (waiting, running,
suspended streams, holds), each application's state and variables. Commands come
from a terminal or any text stream (one per line), so a session can be scripted.
Stopped at a line, the state shown is the state as that decision is made.
"""

from __future__ import annotations

import dataclasses
import math
import shlex
from collections import deque
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TextIO

from prima.escape import terminal
from prima.dsl import Document
from prima.run import Run
from prima.suggest import did_you_mean
from prima.trace import APP_WIDTH, Kind, TraceLine, describe
from prima.tracefile import bounded_lines
from prima.vocab import Value

__all__ = ["Break", "Debugger", "HELP"]

HELP = """\
commands (a prefix will do, or one letter: s c b w m a h q):
  step [N]              run to the next trace line (the N-th), and stop
  continue              run to the next breakpoint (or the end)
  break app NAME        stop at every line of application NAME
  break command NAME    stop where an atomic behavior of Command NAME starts
  break state NAME      stop where an application enters state NAME
  break event NAME      stop where event NAME is posted
  break user [ACTION]   stop where the user acts (say, touch, walk, ...)
  break time SECONDS    stop at the first line at or after that time (once)
  breaks                list the breakpoints
  delete N              remove breakpoint N
  where                 the line the run stopped at
  history [N]           the last N lines (default 10)
  memory                working memory: running, waiting, suspended streams, holds
  apps                  each application's state and variables
  help                  this text
  quit                  stop the run here"""

MAX_COMMAND = 1 << 16
"""The longest command line read, in characters: a longer one (standard input that is
not text, ``< /dev/zero``) is refused, and read in pieces of this size meanwhile."""

_KINDS = ("app", "command", "state", "event", "user", "time")
_ALIASES = {"s": "step", "c": "continue", "b": "break", "w": "where", "m": "memory",
            "a": "apps", "h": "help", "q": "quit"}


@dataclasses.dataclass
class Break:
    """A breakpoint: a line of this kind matching ``value`` stops the run."""

    kind: str
    value: str
    hits: int = 0

    def matches(self, line: TraceLine) -> bool:
        kind = line.kind.value
        if self.kind == "app":
            return line.app == self.value
        if self.kind == "command":
            return kind == "start" and self.value in (line.command or "").split("+")
        if self.kind == "state":
            return kind == "state" and line.text == self.value
        if self.kind == "event":
            return kind == "event" and line.text == self.value
        if self.kind == "user":
            return kind == "user" and self.value in ("", line.action)
        return self.hits == 0 and line.t >= float(self.value)  # time: once

    def __str__(self) -> str:
        return f"{self.kind} {self.value}".rstrip()


class _Quit(BaseException):
    """The user asked to stop the run (a BaseException, like Ctrl-C: no handler of an
    application's failures may take it for one)."""


class Debugger:
    """A run with a prompt: ``start`` runs it to the end, stopping as asked."""

    def __init__(self, scenario: str | Path, inp: TextIO, out: TextIO,
                 **run_options: object) -> None:
        self._in = inp
        self._lines = bounded_lines(inp, MAX_COMMAND)
        """The commands' lines, as they are read (None: one too long)."""
        self._out = out
        self.breaks: list[Break] = []
        self._steps = 0
        """Lines to go before stopping (0: run to a breakpoint)."""
        self._history: deque[TraceLine] = deque(maxlen=200)
        self._at: TraceLine | None = None
        self._documents: list[Document] | None = None
        self._width: int | None = None
        # pose samples at prima run's rate (never a stopping point), so that a line's
        # seq is the one a jsonl trace, prima judge and prima show give it
        self.run = Run(scenario, sink=self._line, **run_options)  # type: ignore[arg-type]
        self._commands: Mapping[str, Callable[[list[str]], bool]] = {
            "step": self._step, "continue": self._continue, "break": self._break,
            "breaks": self._list_breaks, "delete": self._delete, "where": self._where,
            "history": self._show_history, "memory": self._memory, "apps": self._apps,
            "help": self._help, "quit": self._quit,
        }

    # ---------------------------------------------------------------- running
    def start(self) -> None:
        """Ask what to do before the first line, then run, stopping as asked."""
        self._say(f"prima debug: {self.run.scenario.name}; 'help' lists the commands")
        try:
            self._prompt()
            self.run.run()
            self._say(f"the run ended at t={self.run.sim.now():g} s")
        except _Quit:
            self._say(f"stopped at t={self.run.sim.now():g} s")

    def _line(self, line: TraceLine) -> None:
        if line.kind is Kind.POSE:
            return
        self._history.append(line)
        self._at = line
        stop = False
        if self._steps:
            self._steps -= 1
            stop = self._steps == 0
        for i, b in enumerate(self.breaks, 1):
            if b.matches(line):
                b.hits += 1
                self._say(f"breakpoint {i} ({b})")
                stop = True
        if stop:
            self._steps = 0
            self._say(self._describe(line))
            self._prompt()

    def _prompt(self) -> None:
        """Read commands until one lets the run go on."""
        while True:
            self._out.write("(prima) ")
            self._out.flush()
            text = next(self._lines, "")
            if text == "":
                self._say("")
                raise _Quit  # end of input: stop here
            if text is None:  # (read past in pieces, never held whole)
                self._say(f"cannot read that line: it is longer than {MAX_COMMAND:,} "
                          "characters")
                continue
            try:
                words = shlex.split(text, comments=True) if text.strip() else []
            except ValueError as exc:  # an unclosed quote: "don't" said as a word
                self._say(f"cannot read that line: {str(exc).lower()} (quote a name "
                          "with an apostrophe in double quotes)")
                continue
            if not words:
                continue
            self._say_command(words)
            command = self._find(words[0])
            if command is None:
                self._say(f"unknown command {words[0]!r}; 'help' lists the commands")
            elif command(words[1:]):
                return

    def _find(self, word: str) -> Callable[[list[str]], bool] | None:
        """A command by its name, its one-letter alias, or a prefix only it has."""
        name = _ALIASES.get(word, word)
        if name in self._commands:
            return self._commands[name]
        found = [n for n in self._commands if n.startswith(word)]
        return self._commands[found[0]] if len(found) == 1 else None

    def _say(self, text: str) -> None:
        """Write ``text``'s lines; what a document or a trace says, a control character
        say, reaches the terminal as an escape."""
        self._out.write("\n".join(map(terminal, text.split("\n"))) + "\n")

    def _say_command(self, words: list[str]) -> None:
        if not self._in.isatty():  # a scripted session shows what it typed
            self._say(" ".join(words))

    # ---------------------------------------------------------------- commands
    def _step(self, args: list[str]) -> bool:
        try:
            self._steps = max(1, int(args[0])) if args else 1
        except ValueError:
            self._say(f"step takes a number of lines, not {args[0]!r}")
            return False
        return True

    def _continue(self, _args: list[str]) -> bool:
        self._steps = 0
        return True

    def _break(self, args: list[str]) -> bool:
        if not args or args[0] not in _KINDS or (len(args) < 2 and args[0] != "user"):
            self._say("break app|command|state|event NAME, break user [ACTION] or "
                      "break time SECONDS")
            return False
        value = " ".join(args[1:])
        unknown = self._unknown(args[0], value)
        if unknown:
            self._say(unknown)
            return False
        if args[0] == "time":
            try:
                seconds = float(value)
            except ValueError:
                seconds = math.nan
            if not math.isfinite(seconds):  # (no line would ever stop at nan or inf)
                self._say(f"break time takes seconds, not {value!r}")
                return False
        self.breaks.append(Break(args[0], value))
        self._say(f"breakpoint {len(self.breaks)}: {self.breaks[-1]}")
        return False

    def _known(self, kind: str) -> list[str]:
        """The names a breakpoint of ``kind`` can stop at in this run (apps, Commands,
        states; other kinds are not checked)."""
        if kind == "command":
            return [c.name for c in self.run.catalog]
        if self._documents is None:
            self._documents = self.run.documents()
        if kind == "app":
            return list(dict.fromkeys(d.name for d in self._documents))
        if kind == "state":
            return list(dict.fromkeys(s for d in self._documents for s in d.states))
        return []

    def _unknown(self, kind: str, value: str) -> str | None:
        """Why a breakpoint on ``value`` could never stop the run, if it could not."""
        if kind not in ("app", "command", "state"):
            return None
        known = self._known(kind)
        if value in known:
            return None
        what = {"app": "application", "command": "Command", "state": "state"}[kind]
        hint = did_you_mean(value, known) or f" (known: {', '.join(known[:20])})"
        return f"no {what} {value!r} in this run, no breakpoint set{hint}"

    def _list_breaks(self, _args: list[str]) -> bool:
        if not self.breaks:
            self._say("no breakpoints")
        for i, b in enumerate(self.breaks, 1):
            self._say(f"{i}: {b} (hit {b.hits} time{'s' if b.hits != 1 else ''})")
        return False

    def _delete(self, args: list[str]) -> bool:
        number = _count(args[0]) if len(args) == 1 else None
        if number is None or not 1 <= number <= len(self.breaks):
            self._say(f"delete takes a breakpoint's number (1 to {len(self.breaks)})")
            return False
        removed = self.breaks.pop(number - 1)
        self._say(f"deleted breakpoint {args[0]} ({removed})")
        return False

    def _where(self, _args: list[str]) -> bool:
        if self._at is None:
            self._say(f"before the first line (t={self.run.sim.now():g} s)")
        else:
            self._say(self._describe(self._at))
        return False

    def _show_history(self, args: list[str]) -> bool:
        n = _count(args[0]) if args else 10
        if n is None:
            self._say(f"history takes a number of lines, not {args[0]!r}")
            return False
        for line in list(self._history)[-n:] if n else []:  # (history 0: none of them)
            self._say(self._describe(line))
        return False

    def _memory(self, _args: list[str]) -> bool:
        snap = self.run.mediator.snapshot()
        nodes = {n.ab: n for tree in snap.trees for n in tree.nodes}

        def ab(i: int) -> str:
            n = nodes.get(i)
            return f"AB{i}" if n is None else f"AB{i} {n.app} {n.command} on " \
                                               f"{', '.join(n.devices)}"
        self._say(f"working memory at t={snap.t:g} s")
        self._say("  running:   " + ("; ".join(ab(i) for i, _d in snap.running) or "none"))
        waiting = []
        for i in snap.waiting:
            parked = nodes[i].parked_by if i in nodes else None
            waiting.append(ab(i) + (f" (held for {parked})" if parked else ""))
        self._say("  waiting:   " + ("; ".join(waiting) or "none"))
        if snap.suspended:
            for k, tree_id in enumerate(snap.suspended):
                tree = next(t for t in snap.trees if t.id == tree_id)
                live = [f"AB{n.ab} {n.command}" for n in tree.nodes]
                top = " (most recent)" if k == 0 else ""
                self._say(f"  suspended: stream {tree_id} of {tree.app}{top}: "
                          f"{', '.join(live) or 'nothing left'}")
        else:
            self._say("  suspended: none")
        holds = [f"{h.app}'s {h.kind} on {', '.join(h.devices)} until t={h.deadline:g} s"
                 for h in snap.holds]
        self._say("  holds:     " + ("; ".join(holds) or "none"))
        if snap.demoted:
            self._say("  demoted:   " + ", ".join(snap.demoted))
        return False

    def _apps(self, _args: list[str]) -> bool:
        for name, app in self.run.apps.items():
            interpreter = app.interpreter
            self._say(f"{name} ({app.role.value}): state {interpreter.state or '-'}")
            for var, value in sorted(interpreter.variables.items()):
                self._say(f"  {var} = {_shown(value)}")
        if not self.run.apps:
            self._say("no application is loaded yet")
        return False

    def _help(self, _args: list[str]) -> bool:
        self._say(HELP)
        return False

    def _quit(self, _args: list[str]) -> bool:
        raise _Quit

    # ---------------------------------------------------------------- showing
    def _describe(self, line: TraceLine) -> str:
        who = "U" if line.kind is Kind.USER else "R"
        if self._width is None:  # (the text trace's app column: as wide as its longest app)
            self._width = max([APP_WIDTH, *map(len, self._known("app"))])
        return f"{line.seq:5d} {line.t:8.2f}   {who}   {line.app or '':<{self._width}} " \
            f"{describe(line)}"


def _count(text: str) -> int | None:
    """A number typed as ASCII digits (a longer one than 18 digits is as many as 10**18),
    or None: ``str.isdigit`` takes ``²`` too, and ``int`` refuses it, or 5,000 digits."""
    if not (text.isascii() and text.isdigit()):
        return None
    return int(text) if len(text) <= 18 else 10**18


def _shown(value: Value) -> str:
    return repr(value) if isinstance(value, str) else str(value)
