"""What the judge finds: one record per fault, each naming whose it is.

Every finding names the application and atomic behavior it is about and where
that application's document asks for it (``doc.pxml:line:col``, from the trace's
request lines), so that an author sees at once whether a fault is theirs: a
late reaction names what the rules let it wait for and what ran on its devices
instead; a split exchange names the utterance that split it.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

__all__ = ["BargeIn", "Blame", "Elsewhere", "Finding", "Ignored", "Leaving", "Reaction",
           "Recovery", "Silence", "Split", "Stuck", "Unfaced", "after"]


@dataclass(frozen=True, init=False)
class Blame:
    """An application's atomic behavior that a finding is about, and why it counts.
    (Its ``__init__`` is written out: compiled, it runs at C speed, where the one
    ``dataclass`` writes runs as Python.)"""

    app: str
    ab: int | None
    command: str
    at: str = ""
    """Where the application's document asks for it (``doc.pxml:line:col``; empty if
    the trace does not say: a trace written before it did)."""
    rule: str = ""
    """The rule under which it went first or ran (``uncut: listening``, ``reaction
    first (4.2)``, ``reply (7.4)``...), or what it did."""
    until: float | None = None
    """When it stopped counting (its end, or the word boundary a cut would reach)."""

    def __init__(self, app: str, ab: int | None, command: str, at: str = "", rule: str = "",
                 until: float | None = None) -> None:
        object.__setattr__(self, "app", app)
        object.__setattr__(self, "ab", ab)
        object.__setattr__(self, "command", command)
        object.__setattr__(self, "at", at)
        object.__setattr__(self, "rule", rule)
        object.__setattr__(self, "until", until)

    def __str__(self) -> str:
        ab = f" AB{self.ab}" if self.ab is not None else ""
        where = f" {self.at}" if self.at else ""
        why = f" [{self.rule}]" if self.rule else ""
        return f"{self.app}{ab} {self.command}{where}{why}"

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


def after(t0: float, t: float | None) -> float | None:
    """Seconds from ``t0`` to ``t`` (None: never), as a reaction's latencies are given."""
    return None if t is None else round(t - t0, 3)


@dataclass(frozen=True)
class Reaction:
    """An application's reaction to a reactive event or to the user's heard answer."""

    event: str
    """The event's name, or ``speech`` for a heard answer."""
    t: float
    seq: int
    """The event line (or the user's say line)."""
    app: str
    request_seq: int
    """The reaction's first request line."""
    commands: tuple[int, ...]
    """Every Command its request lines asked for."""
    trees: tuple[int, ...]
    devices: tuple[str, ...]
    """The devices of its first atomic behavior (with a policy's AB put before it)."""
    user: bool = False
    """The event was the user's own action (a touch, heard speech)."""
    at: str = ""
    """Where its first request is written."""
    residual: float = 0.0
    """How long the rules let its first start wait (s): the running IUs it may not
    cut, replies, reactions that go first (docs/rules.md section 8)."""
    free: float = 0.0
    """How long it was free to start but did not (s)."""
    first_start: float | None = None
    first_start_seq: int | None = None
    first_utterance: float | None = None
    """When its first words said in full began (a cut utterance counts once it is said
    again whole)."""
    first_utterance_seq: int | None = None
    words: bool = False
    """It asked to say something."""
    unheard: bool = False
    """It asked to say something, and none of its words were ever heard whole: cut and
    never said again, or never said long after the event (not: cancelled by its own
    application, or still to come when the trace ended)."""
    words_free: float = 0.0
    """How long its words were free to start, after it had started, but did not (s)."""
    late: bool = False
    why: str = ""
    """Why it is late (empty when it is not)."""
    text: str = ""
    """A heard answer's words."""
    waits: tuple[Blame, ...] = ()
    """What the rules put before it, that it waited for."""
    took: Blame | None = None
    """What ran on its devices while it was free to start (the other application's
    doing, or the mediator's), if anything did."""

    @property
    def latency(self) -> float | None:
        """From the event to the first start (None: it never started)."""
        return after(self.t, self.first_start)

    @property
    def utterance_latency(self) -> float | None:
        """From the event to the first utterance heard whole (None: none was)."""
        return after(self.t, self.first_utterance)

    def to_dict(self) -> dict[str, object]:
        return {
            "event": self.event, "t": self.t, "seq": self.seq, "app": self.app,
            "user": self.user, "at": self.at, "text": self.text,
            "request_seq": self.request_seq, "commands": list(self.commands),
            "trees": list(self.trees), "devices": list(self.devices),
            "residual": self.residual, "free": self.free,
            "first_start": self.first_start, "first_start_seq": self.first_start_seq,
            "latency": self.latency, "first_utterance": self.first_utterance,
            "first_utterance_seq": self.first_utterance_seq,
            "utterance_latency": self.utterance_latency, "words": self.words,
            "words_free": self.words_free, "unheard": self.unheard,
            "late": self.late, "why": self.why,
            "waits": [w.to_dict() for w in self.waits],
            "took": None if self.took is None else self.took.to_dict(),
        }


@dataclass(frozen=True)
class Unfaced:
    """An utterance said while the user was detectable but not faced: at its start, or
    for more than a second in a row while its words ran (docs/rules.md 7.6 (3))."""

    seq: int
    """The utterance's start line."""
    t: float
    app: str
    command: str
    text: str
    off: float
    """Degrees between the robot's heading and the user's bearing (at the start, or the
    most while its words ran)."""
    at: str = ""
    during: float | None = None
    """None: unfaced as its words began; else how long (s) the user was off, in a row,
    while they ran (from the pose line at ``during_seq``)."""
    during_seq: int | None = None
    """The first pose line of that stretch."""
    turned_by: Blame | None = None
    """What drove the wheels as the robot turned away (another application's AB, or the
    utterance's own application's), if anything did."""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Leaving:
    """An utterance during whose words the robot moved away from the user on its own."""

    seq: int
    """The utterance's start line."""
    t: float
    app: str
    text: str
    at_seq: int
    """The first line at which the robot was too far."""
    away: float
    """How much farther from the user the robot was then (m)."""
    at: str = ""
    moved_by: Blame | None = None
    """The atomic behavior that drove the wheels then, if one did."""

    def to_dict(self) -> dict[str, object]:
        out = dataclasses.asdict(self)
        out["moved_by"] = None if self.moved_by is None else self.moved_by.to_dict()
        return out


@dataclass(frozen=True)
class Elsewhere:
    """A suspended stream's first utterance after it resumed, spoken away from where
    the stream was suspended (an explanation resumed far from its panel)."""

    seq: int
    """The utterance's start line."""
    t: float
    app: str
    text: str
    suspend_seq: int
    """The line at which its stream was suspended."""
    away: float
    """How far the robot then was from where it was at the suspension (m)."""
    at: str = ""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Split:
    """Another application's utterance inside an exchange (docs/rules.md 7.4) or an
    explicit stream, or a reply cut."""

    seq: int
    """The intruding utterance's start line (a cut reply: its end line)."""
    t: float
    app: str
    """The application whose exchange was split."""
    by: str
    """The application that spoke (a cut reply: the one whose reaction cut it)."""
    text: str
    kind: str
    """``reply``: between an answer and the end of the words that reply to it (a
    reaction's included, or the reply cut); ``question``: a non-reactive one between
    an answer and the app's next question; ``answer``: a non-reactive one between an
    answer and the app's next atomic behavior, asked for at the answer, when that is no
    words (an answer its app asks nothing for at once ends its exchange); ``stream``: a
    non-reactive one inside an explicit stream."""
    anchor_seq: int
    """The answer's end line, or the stream's open line."""
    at: str = ""
    """Where the intruding utterance is written."""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Silence:
    """No robot output for too long after a user's answer."""

    seq: int
    """The answered Q&A's end line."""
    t: float
    app: str
    gap: float | None
    """Seconds to the next start (None: nothing started before the trace ended)."""
    at: str = ""
    """Where the answered Q&A is written."""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Stuck:
    """An application whose requested Command could not start, or an atomic behavior
    that never ends."""

    app: str
    t: float
    """When it got stuck: the Command's request time plus ``stuck_after``."""
    seq: int
    """The request line of the Command that waited (``ab``: the AB's start line)."""
    command_id: int
    since: float
    """When that Command was requested (``ab``: when the AB started)."""
    kind: str
    """``loop``: behind its own feedback Command iterating on and on; ``search``: its
    search for the user iterated on and on while the user was never detectable;
    ``end``: still waiting when the trace ended; ``ab``: an atomic behavior that
    started and never ended."""
    at: str = ""
    behind: Blame | None = None
    """What it waited for (the loop, or the AB that never ended)."""

    def to_dict(self) -> dict[str, object]:
        out = dataclasses.asdict(self)
        out["behind"] = None if self.behind is None else self.behind.to_dict()
        return out


@dataclass(frozen=True)
class BargeIn:
    """The robot talked on over its user for longer than a word and the slack."""

    seq: int
    """The user's say line."""
    t: float
    text: str
    """What the user said."""
    app: str
    """Whose utterance ran on."""
    command: str
    stopped: float | None
    """When its words stopped (None: they ran to their end)."""
    latency: float
    """Seconds from the user's first word to the robot's stopping."""
    allowed: float
    """The slack plus the word under way (s)."""
    at: str = ""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Ignored:
    """User speech an application took, and did not answer in time."""

    seq: int
    """The user's say line."""
    t: float
    text: str
    app: str
    """The application that took the words."""
    answered: float | None
    """When its first words in reply began (None: never)."""
    allowed: float
    """The slack plus what the rules put first (s)."""
    at: str = ""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Recovery:
    """An utterance cut by words no application took (a false interruption) that did not
    go on within the robot's pause and the slack."""

    seq: int
    """The cut line."""
    t: float
    """When its words stopped."""
    app: str
    command: str
    resumed: float | None
    """When it went on (None: never)."""
    allowed: float
    at: str = ""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


Finding = (Reaction | Unfaced | Leaving | Elsewhere | Split | Silence | Stuck | BargeIn | Ignored
           | Recovery)
"""Anything a measure finds."""
