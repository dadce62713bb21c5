"""The validated form of a PXML document, as the interpreter runs it.

Every expression is already compiled (:class:`~prima.dsl.Compiled`);
every reference (states, Commands, grammars, variables, events) is known to
exist. Objects are frozen: one loaded document can back many runs.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Mapping
from dataclasses import dataclass, field

from prima.dsl._expr import Compiled
from prima.vocab import AppKind, RunningOrder


@dataclass(frozen=True)
class Loc:
    """Where something is written: 1-based line and column."""

    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.line}:{self.col}"


# ---------------------------------------------------------------- Commands

@dataclass(frozen=True)
class CommandCall:
    """One Command as written in a request, arguments compiled."""

    command: str
    args: Mapping[str, Compiled]
    extra: Mapping[str, Compiled]
    label: str | None
    loc: Loc
    grammar: str | None = None
    """Q&A only: the id of the answer grammar."""
    into: str | None = None
    """Q&A only: the variable that receives the answer."""


@dataclass(frozen=True)
class Request:
    """A ``<request>`` or ``<chain>``: Commands sent together, root first."""

    calls: tuple[CommandCall, ...]
    order: RunningOrder
    group: bool
    loc: Loc


# ---------------------------------------------------------------- actions

@dataclass(frozen=True)
class Assign:
    """``<assign name expr>``: set a variable."""

    name: str
    expr: Compiled
    loc: Loc


@dataclass(frozen=True)
class If:
    """``<if>``: the actions of the first branch whose condition holds, else ``otherwise``."""

    branches: tuple[tuple[Compiled, tuple[Action, ...]], ...]
    otherwise: tuple[Action, ...]
    loc: Loc


@dataclass(frozen=True)
class Goto:
    """``<goto state>``: leave the current state for another."""

    state: str
    loc: Loc


@dataclass(frozen=True)
class Send:
    """A message to the environment's server (e.g. the EA replying to a host)."""

    to: str
    text: Compiled
    loc: Loc


@dataclass(frozen=True)
class Raise:
    """Raise a user-defined event (FA only)."""

    event: str
    loc: Loc


@dataclass(frozen=True)
class StartTimer:
    """``<timer name after>``: (re)start a timer; its event is posted when it fires."""

    name: str
    after: Compiled
    reactive: bool
    loc: Loc


@dataclass(frozen=True)
class CancelTimer:
    """``<cancel-timer name>``: stop a timer before it fires."""

    name: str
    loc: Loc


@dataclass(frozen=True)
class Log:
    """``<log text>``: a note in the trace."""

    text: Compiled
    loc: Loc


Action = Request | Assign | If | Goto | Send | Raise | StartTimer | CancelTimer | Log
"""What a state's entry or a handler does, in order."""


# ---------------------------------------------------------------- handlers

class HandlerKind(str, enum.Enum):
    """What a handler reacts to."""

    EVENT = "on"
    """A predefined, robot-specific, user-defined or timer event."""
    END = "on-end"
    """The end event of a labelled Command."""
    ANSWER = "on-answer"
    """A labelled Q&A heard an answer its grammar matches."""
    NOINPUT = "on-noinput"
    """A labelled Q&A timed out without hearing anything."""
    NOMATCH = "on-nomatch"
    """A labelled Q&A heard something its grammar does not match."""


@dataclass(frozen=True)
class Handler:
    """What to do on an event, or on a labelled Command's end or answer."""

    kind: HandlerKind
    key: str
    """The event name, or the label of the Command it listens to."""
    cond: Compiled | None
    reactive: bool | None
    """For ``on``: the author's choice; None means the event's own default."""
    actions: tuple[Action, ...]
    loc: Loc


# ---------------------------------------------------------------- grammars

_WORD = re.compile(r"[a-z0-9']+|[0-9]+(?:\.[0-9]+)?")
MAX_UTTERANCE = 500


def words(text: str) -> list[str]:
    """Normalised words of an utterance: lower case, punctuation dropped.

    A possessive ``'s`` and apostrophes are dropped too (``Kidode's`` reads as
    ``kidode``, ``I'll`` as ``ill``): recognisers are not reliable about them,
    and synonyms are normalised the same way.
    """
    raw = _WORD.findall(text[:MAX_UTTERANCE].lower().replace("\u2019", "'"))
    out = []
    for word in raw:
        if word.endswith("'s"):
            word = word[:-2]
        word = word.replace("'", "")
        if word:
            out.append(word)
    return out


@dataclass(frozen=True)
class Choice:
    """One answer of a grammar, and the phrases that mean it."""

    value: str
    phrases: tuple[tuple[str, ...], ...]
    """Synonyms, each a tuple of normalised words."""


@dataclass(frozen=True)
class Pattern:
    """A pattern: words, ``*`` (any words, captured) and ``#`` (a number, captured)."""

    source: str
    regex: re.Pattern[str] = field(compare=False)


@dataclass(frozen=True)
class Grammar:
    """An answer grammar: choices with synonyms, and/or patterns."""

    id: str
    choices: tuple[Choice, ...]
    patterns: tuple[Pattern, ...]
    loc: Loc

    def match(self, utterance: str) -> str | None:
        """The answer value for ``utterance``, or None (a no-match).

        A choice matches when one of its synonyms appears in the utterance
        as whole words; the first matching choice wins. A pattern matches the
        whole utterance; its value is what ``*`` and ``#`` captured (or the
        utterance's words if it captures nothing).
        """
        heard = words(utterance)
        for choice in self.choices:
            for phrase in choice.phrases:
                if _contains(heard, phrase):
                    return choice.value
        joined = " ".join(heard)
        for pattern in self.patterns:
            m = pattern.regex.fullmatch(joined)
            if m:
                captured = [g.strip() for g in m.groups() if g and g.strip()]
                return " ".join(captured) if captured else joined
        return None


def _contains(heard: list[str], phrase: tuple[str, ...]) -> bool:
    n = len(phrase)
    return n > 0 and any(tuple(heard[i : i + n]) == phrase for i in range(len(heard) - n + 1))


# ---------------------------------------------------------------- structure

@dataclass(frozen=True)
class State:
    """A state: actions on entry, and handlers active while the application is in it."""

    id: str
    initial: bool
    entry: tuple[Action, ...]
    handlers: tuple[Handler, ...]
    loc: Loc
    stream: str | None = None
    """The id of the explicit stream block this state belongs to, if any."""
    block: str | None = None
    """The id of the begin/end block this state belongs to, if any."""


@dataclass(frozen=True)
class StreamBlock:
    """An explicit Communication Stream: while the app is in these states, one CS."""

    id: str
    hold: float
    states: tuple[str, ...]
    loc: Loc


@dataclass(frozen=True)
class AtomicBlock:
    """A begin/end block: while the app is in these states, one atomic behavior."""

    id: str
    watchdog: float
    devices: frozenset[str] | None
    states: tuple[str, ...]
    loc: Loc


@dataclass(frozen=True)
class Variable:
    """A document variable, with its initial value (null without one)."""

    name: str
    init: Compiled | None
    loc: Loc


@dataclass(frozen=True)
class EventDecl:
    """A user-defined event (FA only)."""

    name: str
    reactive: bool
    loc: Loc


@dataclass(frozen=True)
class Document:
    """A validated PXML application."""

    path: str
    kind: AppKind
    name: str
    description: str
    variables: Mapping[str, Variable]
    grammars: Mapping[str, Grammar]
    events: Mapping[str, EventDecl]
    handlers: tuple[Handler, ...]
    """Document-scope handlers (active in every state)."""
    states: Mapping[str, State]
    initial: str
    streams: Mapping[str, StreamBlock]
    blocks: Mapping[str, AtomicBlock]
    commands: Mapping[str, CommandCall]
    """Every labelled Command, by label."""
    timers: frozenset[str]
