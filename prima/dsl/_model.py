"""The validated form of a PXML document, as the interpreter runs it.

Every expression is already compiled (:class:`~prima.dsl.Compiled`);
every reference (states, Commands, grammars, variables, events) is known to
exist. Objects are frozen: one loaded document can back many runs.
"""

from __future__ import annotations

import enum
import re
from collections.abc import Mapping
from dataclasses import dataclass

from prima.dsl._expr import Compiled
from prima.record import Record
from prima.vocab import AppKind, OnInterrupt, RunningOrder


@dataclass(frozen=True, repr=False, eq=False)
class Loc(Record):
    """Where something is written: 1-based line and column."""

    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.line}:{self.col}"


# ---------------------------------------------------------------- Commands

@dataclass(frozen=True, repr=False, eq=False)
class PlaceRef(Record):
    """A place written by name as a Command's argument (``to="hall"``,
    ``TopologicalMove("kidode-room")``), not computed: the map it runs on must have it."""

    name: str
    loc: Loc
    """Where the name is written."""
    command: str
    param: str
    """The Command and its argument (``TopologicalMove``, ``to``)."""


@dataclass(frozen=True, repr=False, eq=False)
class CommandCall(Record):
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


@dataclass(frozen=True, repr=False, eq=False)
class Request(Record):
    """A ``<request>`` or ``<chain>``: Commands sent together, root first."""

    calls: tuple[CommandCall, ...]
    order: RunningOrder
    group: bool
    loc: Loc
    face_user: bool = True
    """``face-user``: its words are for the user (the connect-channel policy may turn
    the robot to them first); false: they are about something else."""
    on_interrupt: OnInterrupt = OnInterrupt.RESTART
    """``interrupt``: what the interrupt policy may do to its atomic behaviors."""


# ---------------------------------------------------------------- actions

@dataclass(frozen=True, repr=False, eq=False)
class Assign(Record):
    """``<assign name expr>``: set a variable."""

    name: str
    expr: Compiled
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class If(Record):
    """``<if>``: the actions of the first branch whose condition holds, else ``otherwise``."""

    branches: tuple[tuple[Compiled, tuple[Action, ...]], ...]
    otherwise: tuple[Action, ...]
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class Goto(Record):
    """``<goto state>``: leave the current state for another."""

    state: str
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class Send(Record):
    """A message to the environment's server (e.g. the EA replying to a host)."""

    to: str
    text: Compiled
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class Raise(Record):
    """Raise a user-defined event (FA only)."""

    event: str
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class StartTimer(Record):
    """``<timer name after>``: (re)start a timer; its event is posted when it fires."""

    name: str
    after: Compiled
    reactive: bool
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class CancelTimer(Record):
    """``<cancel-timer name>``: stop a timer before it fires."""

    name: str
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class Log(Record):
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


@dataclass(frozen=True, repr=False, eq=False)
class Handler(Record):
    """What to do on an event, or on a labelled Command's end or answer."""

    kind: HandlerKind
    key: str
    """The event name, or the label of the Command it listens to."""
    cond: Compiled | None
    reactive: bool | None
    """For ``on``: the author's choice; None means the event's own default."""
    actions: tuple[Action, ...]
    loc: Loc
    match: str | None = None
    """For ``on event="speech"``: the always-on grammar it listens for (None: any
    words the application is given)."""


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


@dataclass(frozen=True, repr=False, eq=False)
class Choice(Record):
    """One answer of a grammar, and the phrases that mean it."""

    value: str
    phrases: tuple[tuple[str, ...], ...]
    """Synonyms, each a tuple of normalised words."""


@dataclass(frozen=True, repr=False, eq=False)
class Pattern(Record):
    """A pattern: words, ``*`` (any words, captured) and ``#`` (a number, captured).

    ``items`` are the normalised words, ``"*"`` and ``"#"``. Matching works on
    the answer's words, in time linear in their number (:func:`match_pattern`).
    """

    source: str
    items: tuple[str, ...]


MAX_PATTERN_ITEMS = 20
"""Most words, ``*`` and ``#`` in one pattern."""

MAX_PATTERN_CAPTURES = 4
"""Most ``*`` and ``#`` in one pattern."""

MAX_PATTERNS = 50
"""Most patterns in one grammar."""

MAX_PHRASE_WORDS = 20
"""Most words in one synonym of a choice."""


@dataclass(frozen=True, repr=False, eq=False)
class Grammar(Record):
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

        The cost is linear in the utterance's words (at most MAX_UTTERANCE
        characters of it are heard) times the grammar's size: one set lookup
        per synonym, and one pass per pattern item.
        """
        heard = words(utterance)
        grams = _Grams(heard)
        for choice in self.choices:
            if any(grams.has(phrase) for phrase in choice.phrases):
                return choice.value
        for pattern in self.patterns:
            captured = match_pattern(pattern.items, heard)
            if captured is not None:
                return " ".join(c for c in captured if c) or " ".join(heard)
        return None


class _Grams:
    """The runs of consecutive words of an utterance, by length, built on first need."""

    def __init__(self, heard: list[str]) -> None:
        self.heard = heard
        self.by_length: dict[int, frozenset[tuple[str, ...]]] = {}

    def has(self, phrase: tuple[str, ...]) -> bool:
        n = len(phrase)
        if n == 0 or n > len(self.heard):
            return False
        runs = self.by_length.get(n)
        if runs is None:
            h = self.heard
            runs = self.by_length[n] = frozenset(tuple(h[i : i + n])
                                                 for i in range(len(h) - n + 1))
        return phrase in runs


def _is_number(word: str) -> bool:
    return word.isascii() and word.isdigit()


def match_pattern(items: tuple[str, ...], heard: list[str]) -> list[str] | None:
    """What ``*`` and ``#`` captured when ``items`` match all of ``heard``, or None.

    A word item matches that word, ``#`` one number, ``*`` any words, as few as
    possible (the first ``*`` takes the fewest words that still let the rest
    match, then the next). ``ends[i]`` holds, for every position, whether the
    items from ``i`` on can match the words from that position to the end: one
    backward pass per item, then one forward pass picks the captures, so the
    cost is linear in the number of words (times the at most 20 items).
    """
    n = len(heard)
    ends: list[list[bool]] = [[False] * (n + 1) for _ in range(len(items) + 1)]
    ends[len(items)][n] = True
    for i in range(len(items) - 1, -1, -1):
        item, after, here = items[i], ends[i + 1], ends[i]
        if item == "*":
            later = False
            for j in range(n, -1, -1):
                later = later or after[j]
                here[j] = later
        else:
            for j in range(n):
                here[j] = after[j + 1] and (_is_number(heard[j]) if item == "#"
                                            else heard[j] == item)
    if not ends[0][0]:
        return None
    captured: list[str] = []
    j = 0
    for i, item in enumerate(items):
        if item == "*":
            k = j
            while not ends[i + 1][k]:
                k += 1
            captured.append(" ".join(heard[j:k]))
            j = k
        else:
            if item == "#":
                captured.append(heard[j])
            j += 1
    return captured


# ---------------------------------------------------------------- structure

@dataclass(frozen=True, repr=False, eq=False)
class State(Record):
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


@dataclass(frozen=True, repr=False, eq=False)
class StreamBlock(Record):
    """An explicit Communication Stream: while the app is in these states, one CS."""

    id: str
    hold: float
    states: tuple[str, ...]
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class AtomicBlock(Record):
    """A begin/end block: while the app is in these states, one atomic behavior."""

    id: str
    watchdog: float
    devices: frozenset[str] | None
    states: tuple[str, ...]
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class Variable(Record):
    """A document variable, with its initial value (null without one)."""

    name: str
    init: Compiled | None
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class EventDecl(Record):
    """A user-defined event (FA only)."""

    name: str
    reactive: bool
    loc: Loc


@dataclass(frozen=True, repr=False, eq=False)
class Document(Record):
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
    places: tuple[PlaceRef, ...] = ()
    """Every place written by name as a Command's argument, in document order (see
    :func:`literal_places`)."""


def literal_places(document: Document) -> tuple[PlaceRef, ...]:
    """The places a document names literally as Command arguments, each with where it is
    written, in document order; places computed with ``{expression}`` are not among them.
    Whoever knows the map the document runs on can check them (``prima validate`` of a
    scenario does)."""
    return document.places
