"""Naturalness, measured: what a user would notice, computed from a trace alone.

The thesis judged naturalness by showing videos to people; :func:`judge`
measures the same things on every jsonl trace (MISSION.md section 8):

- **reactions**: from a reactive event (or the user's heard answer) to the
  reacting application's first atomic behavior and first utterance, against
  what was running on its devices then (the residual);
- **talking unfaced**: an utterance started while the user is detectable and
  more than 30 degrees off the robot's heading;
- **leaving while talking**: the robot moving more than 0.3 m away from the
  user while an utterance runs;
- **split exchanges**: another application's utterance between a Q&A's answer
  and the reply to it, or inside an explicit stream;
- **silences**: more than 2 s without any robot output after a user's answer;
- **stuck**: an application whose waiting Commands cannot start, or that
  searches for a user it never sees.

Every definition is in ``docs/judging.md``. One pass over the trace, plus work
proportional to the reactions and Commands it holds: the cost is linear in
the trace's length. A trace is :class:`~prima.trace.TraceLine` objects or the
dicts of its jsonl form (:func:`load_trace` reads a file); both are judged
alike (a TraceLine is judged as the jsonl line it writes).
"""

from __future__ import annotations

import collections
import dataclasses
import heapq
import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from prima.errors import TraceError
from prima.tracefile import Row, load_trace, read_trace
from prima.tracefile import rows as _rows
from prima.catalog import BODY_DEVICE, STANDARD_COMMANDS
from prima.vocab import FACE_TOLERANCE, RESTORE_DISTANCE

__all__ = ["Elsewhere", "Leaving", "Reaction", "Report", "Silence", "Split", "Stuck", "Thresholds",
           "Unfaced", "find_scenarios", "format_summary", "format_table", "judge", "judge_file",
           "load_trace"]

_EPS = 1e-6

UNMEASURED_EVENTS = frozenset({"place-reached"})
"""Reactive events whose reactions are not measured: the robot's own motion
arriving, which nobody waits on the robot for (MISSION.md section 8 lists touch,
heard speech, messages, the user found or lost)."""

TALK_DEVICES = ("speaker", "speech-recognition")
"""Where an utterance runs: what a reaction's first utterance waits for."""

SEARCH_DEVICE = "human-detection"
"""A feedback Command on this device looks for the user: iterating on and on
while the user is never detectable (``search_after``), its application is stuck
(kind ``search``)."""
"""Times in a trace are rounded to the millisecond: comparisons allow this much."""

_ANSWERED = re.compile(r"(?:^|, )status=answered(?:,|$)")



# ---------------------------------------------------------------------------- thresholds

@dataclass(frozen=True)
class Thresholds:
    """How much of each fault a run may show, and the measures' parameters.

    The defaults are MISSION.md's targets: no late reaction, no utterance
    unfaced, no leaving while talking, no split exchange, no silence, nothing
    stuck.
    """

    max_late: int = 0
    """Late reactions allowed."""
    max_unfaced: int = 0
    """Utterances started facing away from a detectable user allowed."""
    max_leaving: int = 0
    """Utterances during which the robot moved away from the user allowed."""
    max_elsewhere: int = 0
    """Streams resumed away from where they were suspended allowed."""
    max_splits: int = 0
    """Split exchanges allowed."""
    max_silences: int = 0
    """Silences after an answer allowed."""
    max_stuck: int = 0
    """Stuck applications allowed."""
    reaction_slack: float = 0.2
    """A reaction's first start may come this long (s) after the residual."""
    utterance_slack: float = 1.0
    """Its first utterance may come this much (s) later still."""
    react_within: float | None = None
    """If set, a fixed bound (s) for the first start instead of residual + slack
    (what the interrupt policy promises: 0.2 s)."""
    face_tolerance: float = FACE_TOLERANCE
    """Degrees between the robot's heading and the user's bearing still counted as facing."""
    leave_distance: float = 0.3
    """Metres the robot may move away from the user during an utterance."""
    resume_distance: float = RESTORE_DISTANCE
    """Metres from where a stream was suspended at which its first utterance after it
    resumes still counts as spoken in the same place."""
    silence: float = 2.0
    """Seconds without robot output after an answer that count as a silence."""
    stuck_after: float = 60.0
    """Seconds a Command may wait before its application counts as stuck."""
    search_after: float = 90.0
    """Seconds a search may go on without a sight of the user before its application
    counts as stuck: one full turn of the thesis' Turn-and-Search (ten-second looks,
    60 degrees at a time) takes about 67 s, so a bounded search that gives up after
    one turn is not stuck."""

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"{f.name} must be a number, not {value!r}")
            if not math.isfinite(value) or value < 0:
                raise ValueError(f"{f.name} must be a number from 0 up, not {value!r}")
            if f.name.startswith("max_") and int(value) != value:
                raise ValueError(f"{f.name} must be a whole number, not {value!r}")

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


# ---------------------------------------------------------------------------- findings

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
    """The devices of its first request, then those of a policy's AB put before that
    request's Command (the connect-channel turn: the reaction's first AB then)."""
    residual: float
    """How long the ABs running on those devices at ``t`` (any application's: a
    started AB is never cut) still ran: the running IU's residual."""
    talk_residual: float = 0.0
    """The same on the talk devices (speaker, speech recognition), and at least until
    a policy's AB put before its words ended: what its first utterance had to wait
    for."""
    first_start: float | None = None
    first_start_seq: int | None = None
    first_utterance: float | None = None
    first_utterance_seq: int | None = None
    late: bool = False
    why: str = ""
    """Why it is late (empty when it is not)."""
    text: str = ""
    """A heard answer's words."""

    @property
    def latency(self) -> float | None:
        """From the event to the first start (None: it never started)."""
        return None if self.first_start is None else round(self.first_start - self.t, 3)

    @property
    def utterance_latency(self) -> float | None:
        """From the event to the first utterance (None: it said nothing)."""
        return None if self.first_utterance is None else round(self.first_utterance - self.t, 3)

    def to_dict(self) -> dict[str, object]:
        return {
            "event": self.event, "t": self.t, "seq": self.seq, "app": self.app,
            "text": self.text, "request_seq": self.request_seq,
            "commands": list(self.commands), "trees": list(self.trees),
            "devices": list(self.devices), "residual": self.residual,
            "talk_residual": self.talk_residual,
            "first_start": self.first_start, "first_start_seq": self.first_start_seq,
            "latency": self.latency, "first_utterance": self.first_utterance,
            "first_utterance_seq": self.first_utterance_seq,
            "utterance_latency": self.utterance_latency, "late": self.late, "why": self.why,
        }


@dataclass(frozen=True)
class Unfaced:
    """An utterance started while the user was detectable but not faced."""

    seq: int
    t: float
    app: str
    command: str
    text: str
    off: float
    """Degrees between the robot's heading and the user's bearing."""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Leaving:
    """An utterance during which the robot moved away from the user."""

    seq: int
    """The utterance's start line."""
    t: float
    app: str
    text: str
    at_seq: int
    """The first line at which the robot was too far."""
    away: float
    """How much farther from the user the robot was then (m)."""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


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

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Split:
    """Another application's utterance inside an exchange."""

    seq: int
    """The intruding utterance's start line."""
    t: float
    app: str
    """The application whose exchange was split."""
    by: str
    """The application that spoke."""
    text: str
    kind: str
    """``answer``: between an answer and the reply to it; ``stream``: inside an explicit stream."""
    anchor_seq: int
    """The answer's end line, or the stream's open line."""

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

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Stuck:
    """An application whose requested Command could not start."""

    app: str
    t: float
    """When it got stuck: the Command's request time plus ``stuck_after``."""
    seq: int
    """The request line of the Command that waited."""
    command_id: int
    since: float
    """When that Command was requested."""
    kind: str
    """``loop``: behind its own feedback Command iterating on and on; ``search``:
    its search for the user iterated on and on while the user was never
    detectable (``command_id``: the search; ``since``: when it last saw the user
    or the search began); ``end``: still waiting when the trace ended."""

    def to_dict(self) -> dict[str, object]:
        return dataclasses.asdict(self)


# ---------------------------------------------------------------------------- the report

_COUNTS = (("late", "late reactions", "max_late"),
           ("unfaced", "talking unfaced", "max_unfaced"),
           ("leaving", "leaving while talking", "max_leaving"),
           ("elsewhere", "resumed elsewhere", "max_elsewhere"),
           ("splits", "split exchanges", "max_splits"),
           ("silences", "silences", "max_silences"),
           ("stuck", "stuck", "max_stuck"))
"""Each count: its key, its name, its threshold's field."""


@dataclass(frozen=True)
class Report:
    """What :func:`judge` found in one trace."""

    name: str
    end: float
    """The trace's last time (s)."""
    lines: int
    thresholds: Thresholds
    reactions: tuple[Reaction, ...] = ()
    unfaced: tuple[Unfaced, ...] = ()
    leaving: tuple[Leaving, ...] = ()
    elsewhere: tuple[Elsewhere, ...] = ()
    splits: tuple[Split, ...] = ()
    silences: tuple[Silence, ...] = ()
    stuck: tuple[Stuck, ...] = ()

    @property
    def late(self) -> tuple[Reaction, ...]:
        """The late reactions."""
        return tuple(r for r in self.reactions if r.late)

    def counts(self) -> dict[str, int]:
        """Every count, by key (``late``, ``unfaced``, ``leaving``, ``splits``, ...)."""
        return {key: len(getattr(self, key)) for key, _, _ in _COUNTS}

    def seqs(self, key: str) -> list[int]:
        """The trace lines (seq) of one count's findings."""
        items: Sequence[Any] = getattr(self, key)
        return [item.seq for item in items]

    def breaches(self) -> list[str]:
        """Each threshold exceeded, readably (empty: the run passes)."""
        out = []
        for key, name, limit_name in _COUNTS:
            n, limit = len(getattr(self, key)), getattr(self.thresholds, limit_name)
            if n > limit:
                seqs = ", ".join(map(str, self.seqs(key)[:8]))
                more = ", ..." if n > 8 else ""
                out.append(f"{name}: {n} > {limit} (seq {seqs}{more})")
        return out

    def exceeded(self) -> list[str]:
        """Each threshold exceeded, briefly (``late reactions 2 > 0``)."""
        return [b.split(" (seq")[0].replace(":", "") for b in self.breaches()]

    @property
    def ok(self) -> bool:
        """No threshold exceeded."""
        return not self.breaches()

    def worst_lateness(self) -> float:
        """How far (s) the latest reaction went past what it was allowed (0: none late;
        infinite: one never started)."""
        worst = 0.0
        for r in self.reactions:
            worst = max(worst, _lateness(r, self.thresholds))
        return worst

    def worst_latency(self) -> float:
        """The longest time (s) from an event to its reaction's first start (infinite:
        one never started; 0 without reactions)."""
        return max((math.inf if r.latency is None else r.latency for r in self.reactions),
                   default=0.0)

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name, "end": self.end, "lines": self.lines,
            "thresholds": self.thresholds.to_dict(),
            "counts": {"reactions": len(self.reactions), **self.counts()},
            "reactions": [r.to_dict() for r in self.reactions],
            "late": self.seqs("late"),
            "unfaced": [u.to_dict() for u in self.unfaced],
            "leaving": [x.to_dict() for x in self.leaving],
            "elsewhere": [x.to_dict() for x in self.elsewhere],
            "splits": [s.to_dict() for s in self.splits],
            "silences": [s.to_dict() for s in self.silences],
            "stuck": [s.to_dict() for s in self.stuck],
            "breaches": self.breaches(),
            "ok": self.ok,
        }


def _bounds(r: Reaction, th: Thresholds) -> tuple[float, float]:
    """How long a reaction may take to its first start, and to its first utterance."""
    if th.react_within is not None:
        return th.react_within, th.react_within + th.utterance_slack
    start = r.residual + th.reaction_slack
    return start, max(start, r.talk_residual + th.reaction_slack) + th.utterance_slack


def _lateness(r: Reaction, th: Thresholds) -> float:
    if r.latency is None:
        return math.inf
    start, utter = _bounds(r, th)
    late = r.latency - start
    if r.utterance_latency is not None:
        late = max(late, r.utterance_latency - utter)
    return max(0.0, round(late, 3))


# ---------------------------------------------------------------------------- reading a trace

# Reading a trace file is :mod:`prima.tracefile`'s (one reader for every reader).


# ---------------------------------------------------------------------------- helpers

def _command_ids(row: Row) -> tuple[int, ...]:
    ids = row.get("command_ids")
    if ids:
        return tuple(ids)
    cid = (row.get("detail") or {}).get("command_id")
    return (cid,) if isinstance(cid, int) else ()


def _answered(row: Row) -> bool:
    result = (row.get("detail") or {}).get("result")
    return (row.get("command") == "QA" and isinstance(result, str)
            and _ANSWERED.search(result) is not None)


def _xy(pose: Mapping[str, float]) -> tuple[float, float]:
    return float(pose["x"]), float(pose["y"])


def _off_heading(robot: Mapping[str, float], user: Mapping[str, float]) -> float | None:
    """Degrees between the robot's heading and its bearing to the user (None: same spot)."""
    dx, dy = user["x"] - robot["x"], user["y"] - robot["y"]
    if math.hypot(dx, dy) < 1e-9:
        return None
    bearing = math.degrees(math.atan2(dy, dx))
    return abs((bearing - robot["heading"] + 180.0) % 360.0 - 180.0)


_AIMING = frozenset(c.name for c in STANDARD_COMMANDS if c.aims)


_TRAVELS = frozenset(c.name for c in STANDARD_COMMANDS if c.travels)


def _travels(row: Row) -> bool:
    """A start of the app's own that takes the robot somewhere (a move, following the
    user): where its stream then speaks is where it chose to go. The restore-state
    policy's return is not one: it takes the robot back."""
    return row.get("reason") != "restore-state" and \
        any(c in _TRAVELS for c in str(row.get("command") or "").split("+"))


def _about_something_else(row: Row, before: str | None) -> bool:
    """An utterance that is not for the user's face: its AB turns or points the robot
    itself (FaceHumanAndSpeak, a Speak grouped with a PointByHand), or the AB before
    it in its stream aimed the robot at something on purpose (a Turn, a PointByHand):
    the words are about that."""
    if BODY_DEVICE in (row.get("devices") or ()) \
            or not _AIMING.isdisjoint(str(row.get("command")).split("+")):
        return True
    return before is not None and not _AIMING.isdisjoint(before.split("+"))


def _is_utterance(row: Row) -> bool:
    return bool(row.get("text"))


# ---------------------------------------------------------------------------- the measures

@dataclass
class _Reaction:
    event: str
    t: float
    seq: int
    app: str
    text: str
    request_seq: int = -1
    commands: list[int] = field(default_factory=list)
    trees: list[int] = field(default_factory=list)
    devices: tuple[str, ...] = ()
    """Its first request's, then a policy AB's put before that request's Command."""
    residual: float = 0.0
    """So far: when the ABs running on ``devices`` at ``t`` ended."""
    talk_residual: float = 0.0
    """So far: when the ABs running on the talk devices at ``t`` ended."""

    blocking: int = 0
    """ABs in its residual still running (it cannot have started yet)."""

    def grow(self, talk: bool, residual: float) -> None:
        self.blocking -= 1
        if talk:
            self.talk_residual = max(self.talk_residual, residual)
        else:
            self.residual = max(self.residual, residual)
    first_start: Row | None = None
    first_utterance: Row | None = None


@dataclass
class _Window:
    """Where the lines of a reaction may appear: after its cause, at the same instant."""

    event: str
    t: float
    seq: int
    app: str | None = None
    """A heard answer's reacting app (None: an event's, any app reacting)."""
    text: str = ""
    reactions: dict[str, _Reaction] = field(default_factory=dict)


@dataclass
class _Command:
    id: int
    app: str
    t: float
    seq: int
    pred: int | None
    """The Command ahead of it in its stream, if known."""
    done: bool = False


@dataclass
class _Running:
    """A Command's ABs (feedback iterations) as they run."""

    running: set[int] = field(default_factory=set)
    streak: float = 0.0
    """When its current run of back-to-back ABs began."""
    last_end: float = -1.0
    iterated: bool = False
    """An iteration (not the first AB) started in the current streak."""


class _Judge:
    """One pass over a trace; ``finish`` returns the report."""

    def __init__(self, thresholds: Thresholds, name: str) -> None:
        self.th = thresholds
        self.name = name
        self.t = 0.0
        self.lines = 0
        # reactions
        self.window: _Window | None = None
        self.heard: tuple[float, int, str] | None = None
        self.reactions: list[_Reaction] = []
        self.pending: dict[str, collections.deque[_Reaction]] = {}
        """Each app's latest reactions that have not started yet (a few: older ones
        are late anyway)."""
        self.instant: list[_Reaction] = []
        self.awaiting: dict[int, list[_Reaction]] = {}
        """Command id -> reactions waiting for it to start."""
        self.reaction_commands: dict[str, set[int]] = {}
        # ABs
        self.ab_command: dict[int, int] = {}
        self.on_device: dict[str, dict[int, str]] = {}
        """Device -> the ABs running on it, and their apps."""
        self.watched: dict[int, list[tuple[_Reaction, bool]]] = {}
        """AB -> the reactions whose residual its end sets."""
        # findings
        self.unfaced: list[Unfaced] = []
        self.talking: dict[int, tuple[Row, tuple[float, float]]] = {}
        self.last_command: dict[int, str] = {}
        """Tree -> the Command (``A+B`` for a group) of its latest AB started."""
        self.leaving: list[Leaving] = []
        self.robot: tuple[float, float] | None = None
        """Where the robot was at the latest posed line."""
        self.suspended_at: dict[int, tuple[int, tuple[float, float]]] = {}
        """Tree -> its suspension line and where the robot was then."""
        self.resumed: dict[int, tuple[int, tuple[float, float]]] = {}
        """Tree -> the same, once it resumed and until its first utterance."""
        self.elsewhere: list[Elsewhere] = []
        self.last_start: Row | None = None
        """The latest start line (a resume line follows its AB's start line)."""
        self.answers: dict[str, tuple[Row, Row | None]] = {}
        """App -> its answered Q&A's end line, and the first other app's utterance since."""
        self.streams: dict[str, Row] = {}
        self.splits: list[Split] = []
        self.silent: list[Row] = []
        self.silences: list[Silence] = []
        # stuck
        self.commands: dict[int, _Command] = {}
        self.waiting: dict[str, dict[int, _Command]] = {}
        self.behind: dict[int, list[int]] = {}
        """Command id -> the waiting Commands that follow it."""
        self.runs: dict[int, _Running] = {}
        self.checks: list[tuple[float, int, int]] = []
        self.stuck: dict[str, Stuck] = {}
        self.last_seen = 0.0
        """The latest time a posed line showed the user detectable."""

    # -------------------------------------------------------------- the pass

    def feed(self, row: Row) -> None:
        t = float(row["t"])
        if t > self.t + _EPS:
            self._close_instant()
            self._check_stuck(before=t)
            self.t = t
        self.lines += 1
        kind = row["kind"]
        ab, cid = row.get("ab"), (row.get("detail") or {}).get("command_id")
        if isinstance(ab, int) and isinstance(cid, int):
            self.ab_command.setdefault(ab, cid)
        if row.get("robot") is not None:
            self.robot = _xy(row["robot"])
        if row.get("robot") is not None and row.get("user") is not None:
            if row["user"].get("detectable") is True:
                self.last_seen = t
            self._posed(row)
        handler = _HANDLERS.get(kind)
        if handler is not None:
            handler(self, row)

    def _close_instant(self) -> None:
        """The instant is over: what ran on each reaction's devices is now known."""
        for r in self.instant:
            own = set(r.commands)
            for talk, devices in ((False, r.devices), (True, TALK_DEVICES)):
                running = {ab for d in devices for ab in self.on_device.get(d, {})
                           if self.ab_command.get(ab) not in own}
                for ab in running:
                    self.watched.setdefault(ab, []).append((r, talk))
                    r.blocking += 1
        self.instant = []
        self.window = None
        self.heard = None

    # -------------------------------------------------------------- kinds

    def _event(self, row: Row) -> None:
        name = str(row.get("text") or "")
        if name in UNMEASURED_EVENTS:
            self.window = None
            return
        self.window = _Window(name, float(row["t"]), int(row["seq"]))

    def _user(self, row: Row) -> None:
        self.window = None
        heard = (row.get("detail") or {}).get("heard")
        if row.get("action") == "say" and heard:
            self.heard = (float(row["t"]), int(row["seq"]), str(row.get("text") or ""))

    def _request(self, row: Row) -> None:
        app = str(row.get("app") or "")
        self._track_request(row, app)
        precedes = (row.get("detail") or {}).get("precedes")
        if isinstance(precedes, int):
            self._policy_request(row, precedes)
            return
        w = self.window
        if w is None:
            return
        if w.app is None and row.get("reactive") is not True:
            return
        if w.app is not None and (app != w.app or row.get("reason") != "end-event"):
            return
        r = w.reactions.get(app)
        if r is None:
            r = _Reaction(w.event, w.t, w.seq, app, w.text, int(row["seq"]),
                          devices=tuple(row.get("devices") or ()))
            w.reactions[app] = r
            self.reactions.append(r)
            self.pending.setdefault(app, collections.deque(maxlen=16)).append(r)
            self.instant.append(r)
        tree = row.get("tree")
        if isinstance(tree, int) and tree not in r.trees:
            r.trees.append(tree)
        for cid in _command_ids(row):
            r.commands.append(cid)
            self.awaiting.setdefault(cid, []).append(r)
            self.reaction_commands.setdefault(app, set()).add(cid)

    def _policy_request(self, row: Row, precedes: int) -> None:
        """A policy's AB put before a Command (a turn to the user before an utterance):
        the reactions waiting for that Command start with it, and their words may
        wait for it as for a talk residual (not once they have spoken: what comes
        after the first utterance cannot excuse it). Put before the Command whose
        devices a reaction's residual looks at, it is that reaction's first AB: its
        devices count in the residual too (:meth:`_goes_first`)."""
        ab = row.get("ab")
        devices = tuple(row.get("devices") or ())
        for waiting in list(self.awaiting.get(precedes, ())):
            for cid in _command_ids(row):
                self.awaiting.setdefault(cid, []).append(waiting)
                waiting.commands.append(cid)
            if waiting.first_start is None and waiting.commands[0] == precedes:
                self._goes_first(waiting, devices, float(row["t"]))
            if isinstance(ab, int) and waiting.first_utterance is None:
                self.watched.setdefault(ab, []).append((waiting, True))
                waiting.blocking += 1

    def _goes_first(self, r: _Reaction, devices: tuple[str, ...], t: float) -> None:
        """A policy's AB goes before ``r``'s first requested Command: what ran on its
        devices too is what ``r``'s first start waited for. Requested in ``r``'s own
        instant, the instant's close counts what ran there at ``r.t``; requested later
        (the utterance became ready only then), what runs there now counts, while ``r``
        is not yet late (a reaction already late is not excused by what came after its
        bound)."""
        new = tuple(d for d in devices if d not in r.devices)
        if not new:
            return
        r.devices += new
        if any(x is r for x in self.instant):
            return
        if r.blocking <= 0 and t > r.t + r.residual + self.th.reaction_slack + _EPS:
            return
        own = set(r.commands)
        for ab in {ab for d in new for ab in self.on_device.get(d, {})
                   if self.ab_command.get(ab) not in own}:
            self.watched.setdefault(ab, []).append((r, False))
            r.blocking += 1

    def _start(self, row: Row) -> None:
        app = str(row.get("app") or "")
        ab = row.get("ab")
        ids = _command_ids(row)
        if isinstance(ab, int):
            for d in row.get("devices") or ():
                self.on_device.setdefault(d, {})[ab] = app
        self._reacted(row, ids)
        self._silence_ends(row)
        self._split_start(row, app)
        self._unfaced(row, app)
        self._elsewhere(row, app)
        self.last_start = row
        if _is_utterance(row) and isinstance(ab, int) and row.get("robot") is not None:
            self.talking[ab] = (row, _xy(row["robot"]))
        self._command_started(row, ids)

    def _end(self, row: Row) -> None:
        ab = row.get("ab")
        if isinstance(ab, int):
            t = float(row["t"])
            for d in row.get("devices") or ():
                self.on_device.get(d, {}).pop(ab, None)
            for r, talk in self.watched.pop(ab, ()):
                r.grow(talk, t - r.t)
            self.talking.pop(ab, None)
            cid = self.ab_command.get(ab)
            run = self.runs.get(cid) if cid is not None else None
            if run is not None:
                run.running.discard(ab)
                run.last_end = t
        if _answered(row):
            app = str(row.get("app") or "")
            self.answers[app] = (row, None)
            self.silent.append(row)
            if self.heard is not None:
                t, seq, text = self.heard
                self.window = _Window("speech", t, seq, app=app, text=text)
                self.heard = None

    def _cancel(self, row: Row) -> None:
        for cid in _command_ids(row):
            self._done(cid)

    def _unload(self, row: Row) -> None:
        app = str(row.get("app") or "")
        for command in list(self.waiting.pop(app, {}).values()):
            command.done = True
        self.answers.pop(app, None)
        self.streams.pop(app, None)

    def _stream(self, row: Row) -> None:
        app = str(row.get("app") or "")
        if row.get("text") == "open":
            self.streams[app] = row
        elif row.get("text") == "close":
            self.streams.pop(app, None)

    # -------------------------------------------------------------- reactions

    def _reacted(self, row: Row, ids: tuple[int, ...]) -> None:
        """A start of some reactions' Command: their first start, maybe their first
        utterance. Another app's reaction to the same or an earlier cause that has not
        started yet waits for this first AB too, where they share devices (of two
        reactions, the latest wins, rule 4.2): it is part of that reaction's
        residual."""
        utterance = _is_utterance(row)
        ab = row.get("ab")
        for cid in ids:
            for r in self.awaiting.pop(cid, ()):
                if r.first_start is None:
                    r.first_start = row
                    if isinstance(ab, int):
                        self._others_wait(r, ab, frozenset(row.get("devices") or ()),
                                          float(row["t"]))
                if utterance and r.first_utterance is None:
                    r.first_utterance = row

    def _others_wait(self, first: _Reaction, ab: int, devices: frozenset[str],
                     t: float) -> None:
        """Only while ``r`` still waited for its residual, or was within its slack: a
        reaction already late is not excused by what started after its bound."""
        for app, pending in self.pending.items():
            if app == first.app:
                continue
            for r in pending:
                if r.first_utterance is not None or r.seq > first.seq:
                    continue
                bound = r.t + max(r.residual, r.talk_residual) + self.th.reaction_slack
                if r.blocking <= 0 and t > bound + _EPS:
                    continue
                # not started yet: its residual; started but not yet spoken: its talk
                wants = ((False, r.devices), (True, TALK_DEVICES)) if r.first_start is None \
                    else ((True, TALK_DEVICES),)
                for talk, wanted in wants:
                    if not devices.isdisjoint(wanted):
                        self.watched.setdefault(ab, []).append((r, talk))
                        r.blocking += 1

    def _reaction(self, r: _Reaction) -> Reaction:
        residual = round(r.residual, 3)
        start, utter = r.first_start, r.first_utterance
        found = Reaction(
            r.event, r.t, r.seq, r.app, r.request_seq, tuple(r.commands), tuple(r.trees),
            r.devices, residual, round(r.talk_residual, 3),
            first_start=None if start is None else float(start["t"]),
            first_start_seq=None if start is None else int(start["seq"]),
            first_utterance=None if utter is None else float(utter["t"]),
            first_utterance_seq=None if utter is None else int(utter["seq"]), text=r.text)
        why = _why_late(found, self.th)
        return dataclasses.replace(found, late=bool(why), why=why)

    # -------------------------------------------------------------- poses

    def _unfaced(self, row: Row, app: str) -> None:
        tree = row.get("tree")
        before = self.last_command.get(tree) if isinstance(tree, int) else None
        if isinstance(tree, int):
            self.last_command[tree] = str(row.get("command"))
        if not _is_utterance(row) or _about_something_else(row, before):
            return
        robot, user = row.get("robot"), row.get("user")
        if robot is None or user is None or user.get("detectable") is not True:
            return
        off = _off_heading(robot, user)
        if off is not None and off > self.th.face_tolerance + _EPS:
            self.unfaced.append(Unfaced(int(row["seq"]), float(row["t"]), app,
                                        str(row.get("command")), str(row.get("text")),
                                        round(off, 1)))

    def _suspend(self, row: Row) -> None:
        tree = row.get("tree")
        if isinstance(tree, int) and self.robot is not None:
            self.suspended_at[tree] = (int(row["seq"]), self.robot)

    def _resume(self, row: Row) -> None:
        tree = row.get("tree")
        if isinstance(tree, int) and tree in self.suspended_at:
            self.resumed[tree] = self.suspended_at.pop(tree)
            start = self.last_start
            if start is not None and start.get("ab") == row.get("ab"):
                self._elsewhere(start, str(row.get("app") or ""))  # it resumed speaking

    def _elsewhere(self, row: Row, app: str) -> None:
        tree = row.get("tree")
        if not isinstance(tree, int) or tree not in self.resumed:
            return
        if _travels(row):
            del self.resumed[tree]  # it resumed going somewhere: not the same place
            return
        if not _is_utterance(row):
            return
        seq, was = self.resumed.pop(tree)
        robot = row.get("robot")
        away = math.dist(_xy(robot), was) if robot is not None else 0.0
        if away > self.th.resume_distance + _EPS:
            self.elsewhere.append(Elsewhere(int(row["seq"]), float(row["t"]), app,
                                            str(row.get("text")), seq, round(away, 3)))

    def _posed(self, row: Row) -> None:
        if not self.talking:
            return
        robot, user = _xy(row["robot"]), _xy(row["user"])
        now = math.dist(robot, user)
        for ab, (start, was) in list(self.talking.items()):
            away = now - math.dist(was, user)
            if away > self.th.leave_distance + _EPS:
                self.leaving.append(Leaving(int(start["seq"]), float(start["t"]),
                                            str(start.get("app")), str(start.get("text")),
                                            int(row["seq"]), round(away, 3)))
                del self.talking[ab]  # counted once

    # -------------------------------------------------------------- exchanges

    def _split_start(self, row: Row, app: str) -> None:
        end, by = self.answers.pop(app, (None, None))
        if end is not None and by is not None:
            self.splits.append(Split(int(by["seq"]), float(by["t"]), app, str(by.get("app")),
                                     str(by.get("text")), "answer", int(end["seq"])))
        if not _is_utterance(row):
            return
        for other, (answer, since) in self.answers.items():
            if other != app and since is None:
                self.answers[other] = (answer, row)
        if any(other != app for other in self.streams) and not self._reacting(row, app):
            for other, opened in self.streams.items():
                if other != app:
                    self.splits.append(Split(int(row["seq"]), float(row["t"]), other, app,
                                             str(row.get("text")), "stream", int(opened["seq"])))

    def _reacting(self, row: Row, app: str) -> bool:
        """Whether a start is part of one of its application's reactions."""
        mine = self.reaction_commands.get(app, set())
        return any(cid in mine for cid in _command_ids(row))

    def _silence_ends(self, row: Row) -> None:
        t = float(row["t"])
        for end in self.silent:
            gap = round(t - float(end["t"]), 3)
            if gap > self.th.silence + _EPS:
                self.silences.append(Silence(int(end["seq"]), float(end["t"]),
                                             str(end.get("app")), gap))
        self.silent = []

    # -------------------------------------------------------------- stuck

    def _track_request(self, row: Row, app: str) -> None:
        ids = _command_ids(row)
        before = row.get("before")
        pred = self.ab_command.get(before) if isinstance(before, int) else None
        t = float(row["t"])
        for cid in ids:
            command = _Command(cid, app, t, int(row["seq"]), pred)
            self.commands[cid] = command
            self.waiting.setdefault(app, {})[cid] = command
            if pred is not None:
                self.behind.setdefault(pred, []).append(cid)
            heapq.heappush(self.checks, (t + self.th.stuck_after, int(row["seq"]), cid))
            pred = cid

    def _done(self, cid: int) -> None:
        command = self.commands.get(cid)
        if command is not None and not command.done:
            command.done = True
            self.waiting.get(command.app, {}).pop(cid, None)

    def _command_started(self, row: Row, ids: tuple[int, ...]) -> None:
        t = float(row["t"])
        iteration = (row.get("detail") or {}).get("iteration")
        for cid in ids:
            self._done(cid)
            run = self.runs.setdefault(cid, _Running())
            if not run.running and abs(run.last_end - t) > _EPS:
                run.streak, run.iterated = t, False  # a new run of back-to-back ABs
                for waiter in self.behind.get(cid, ()):
                    command = self.commands[waiter]
                    if not command.done:
                        due = max(command.t, t) + self.th.stuck_after
                        heapq.heappush(self.checks, (due, command.seq, waiter))
            if iteration:
                run.iterated = True
                if SEARCH_DEVICE in (row.get("devices") or ()):
                    self._searching(row, cid, run)
            ab = row.get("ab")
            if isinstance(ab, int):
                run.running.add(ab)

    def _searching(self, row: Row, cid: int, run: _Running) -> None:
        """A search iterates: has it gone on without a sight of the user too long?"""
        app = str(row.get("app") or "")
        since = max(run.streak, self.last_seen)
        t = float(row["t"])
        if app not in self.stuck and t - since > self.th.search_after + _EPS:
            self.stuck[app] = Stuck(app, round(since + self.th.search_after, 3),
                                    int(row["seq"]), cid, round(since, 3), "search")

    def _check_stuck(self, before: float) -> None:
        """Every Command due for a check before ``before``: is its app stuck behind a loop?"""
        while self.checks and self.checks[0][0] < before - _EPS:
            due, _, cid = heapq.heappop(self.checks)
            command = self.commands[cid]
            if command.done or command.app in self.stuck or command.pred is None:
                continue
            run = self.runs.get(command.pred)
            if run is None or not run.running or not run.iterated:
                continue  # not behind a loop now: a new run of it schedules a new check
            since = max(command.t, run.streak) + self.th.stuck_after
            if since > due + _EPS:
                heapq.heappush(self.checks, (since, command.seq, cid))
                continue
            self.stuck[command.app] = Stuck(command.app, round(since, 3), command.seq, cid,
                                            command.t, "loop")

    # -------------------------------------------------------------- the end

    def finish(self) -> Report:
        end = self.t
        self._close_instant()
        self._check_stuck(before=end)
        for reactions in self.watched.values():  # ABs still running: to the end
            for r, talk in reactions:
                r.grow(talk, end - r.t)
        for app, waiting in self.waiting.items():
            late = [c for c in waiting.values()
                    if not c.done and end - c.t > self.th.stuck_after + _EPS]
            if late and app not in self.stuck:
                first = min(late, key=lambda c: c.seq)
                self.stuck[app] = Stuck(app, round(first.t + self.th.stuck_after, 3), first.seq,
                                        first.id, first.t, "end")
        for row in self.silent:
            if end - float(row["t"]) > self.th.silence + _EPS:
                self.silences.append(Silence(int(row["seq"]), float(row["t"]),
                                             str(row.get("app")), None))
        splits = {s.seq: s for s in sorted(self.splits, key=lambda s: s.kind != "answer")}
        return Report(
            self.name, end, self.lines, self.th,
            reactions=tuple(self._reaction(r) for r in self.reactions),
            unfaced=tuple(self.unfaced), leaving=tuple(self.leaving),
            elsewhere=tuple(self.elsewhere),
            splits=tuple(sorted(splits.values(), key=lambda s: s.seq)),
            silences=tuple(sorted(self.silences, key=lambda s: s.seq)),
            stuck=tuple(sorted(self.stuck.values(), key=lambda s: (s.t, s.seq))))


_HANDLERS = {
    "event": _Judge._event,
    "user": _Judge._user,
    "request": _Judge._request,
    "start": _Judge._start,
    "end": _Judge._end,
    "cancel": _Judge._cancel,
    "unload": _Judge._unload,
    "stream": _Judge._stream,
    "suspend": _Judge._suspend,
    "resume": _Judge._resume,
}


def _why_late(r: Reaction, th: Thresholds) -> str:
    if r.latency is None:
        return "never started"
    start, utter = _bounds(r, th)
    if r.latency > start + _EPS:
        return f"started after {r.latency:g} s (allowed {start:g} s)"
    if r.utterance_latency is not None and r.utterance_latency > utter + _EPS:
        return f"spoke after {r.utterance_latency:g} s (allowed {utter:g} s)"
    return ""


def judge(trace: Iterable[object], *, thresholds: Thresholds = Thresholds(),
          name: str = "") -> Report:
    """Measure a trace's naturalness: TraceLine objects or jsonl dicts, in trace order."""
    judging = _Judge(thresholds, name)
    for row in _rows(trace):
        judging.feed(row)
    return judging.finish()


# ---------------------------------------------------------------------------- the table

def _num(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def _short(text: str, width: int) -> str:
    text = " ".join(text.split())
    return text if len(text) <= width else text[: width - 3] + "..."


def _reaction_rows(report: Report) -> list[str]:
    width = max([len(r.app) for r in report.reactions] + [3])
    rows = [f"  {'time':>7}  {'event':<22} {'app':<{width}} {'start':>6} {'utter':>6} "
            f"{'resid':>6} {'talk':>6}  late"]
    for r in report.reactions:
        cause = f'speech "{_short(r.text, 13)}"' if r.event == "speech" else r.event
        late = f"LATE: {r.why}" if r.late else ""
        rows.append(f"  {r.t:7.2f}  {_short(cause, 22):<22} {r.app:<{width}} "
                    f"{_num(r.latency):>6} {_num(r.utterance_latency):>6} {r.residual:6.2f} "
                    f"{r.talk_residual:6.2f}  "
                    f"{late}".rstrip())
    return rows


def _finding(key: str, item: Any) -> str:
    if key == "unfaced":
        return (f"seq {item.seq} t={item.t:g} {item.app} {item.command} "
                f'"{_short(item.text, 30)}": {item.off:g} deg off')
    if key == "leaving":
        return (f"seq {item.seq} t={item.t:g} {item.app} \"{_short(item.text, 30)}\": "
                f"{item.away:g} m farther at seq {item.at_seq}")
    if key == "elsewhere":
        return (f"seq {item.seq} t={item.t:g} {item.app} \"{_short(item.text, 30)}\": "
                f"{item.away:g} m from where its stream was suspended (seq {item.suspend_seq})")
    if key == "splits":
        where = (f"between {item.app}'s answer (seq {item.anchor_seq}) and its reply"
                 if item.kind == "answer" else
                 f"inside {item.app}'s stream (opened seq {item.anchor_seq})")
        return f'seq {item.seq} t={item.t:g} {item.by} "{_short(item.text, 30)}" {where}'
    if key == "silences":
        gap = "until the end" if item.gap is None else f"{item.gap:g} s"
        return f"seq {item.seq} t={item.t:g} after {item.app}'s answer: silent {gap}"
    if key == "stuck":
        why = ("behind its own feedback loop" if item.kind == "loop"
               else "still waiting at the end")
        return (f"seq {item.seq} t={item.t:g} {item.app}: Command {item.command_id} "
                f"requested at {item.since:g} s, {why}")
    return f"seq {item.seq} t={item.t:g} {item.app} {item.event}: {item.why}"


def _block(report: Report) -> list[str]:
    rows = [f"{report.name}  ({report.end:g} s, {report.lines} lines, "
            f"{len(report.reactions)} reactions)"]
    rows += _reaction_rows(report)
    limits = report.thresholds
    for key, name, limit_name in _COUNTS:
        items: Sequence[Any] = getattr(report, key)
        limit = getattr(limits, limit_name)
        mark = "  > max " + str(limit) if len(items) > limit else ""
        rows.append(f"  {name:<22} {len(items)}{mark}")
        rows += [f"      {_finding(key, item)}" for item in items[:10]]
        if len(items) > 10:
            rows.append(f"      ... and {len(items) - 10} more")
    return rows


def format_summary(report: Report, width: int = 0) -> str:
    """One line: the run's counts and whether it passes (``width``: pad the name to it)."""
    counts = "  ".join(f"{key} {n:<2}" for key, n in report.counts().items())
    verdict = "ok" if report.ok else "FAIL: " + ", ".join(report.exceeded())
    return f"{report.name:<{width}}  reactions {len(report.reactions):<3} {counts}  {verdict}"


def format_table(reports: Iterable[Report]) -> str:
    """A block per run (its reactions, then its counts), then a summary line per run."""
    reports = list(reports)
    rows: list[str] = []
    for report in reports:
        rows += _block(report) + [""]
    width = max((len(r.name) for r in reports), default=0)
    rows += [format_summary(r, width) for r in reports]
    return "\n".join(rows) + "\n"


# ---------------------------------------------------------------------------- files

def judge_file(path: str | Path, *, thresholds: Thresholds = Thresholds(),
               name: str | None = None) -> Report:
    """Judge a jsonl trace file, or run a scenario file in-process (writing nothing) and
    judge its trace. Raises :class:`~prima.errors.LocatedError` for a bad file."""
    path = Path(path)
    name = str(path) if name is None else name
    if path.suffix == ".jsonl":  # streamed: a long trace is never held whole
        return judge(read_trace(path), thresholds=thresholds, name=name)
    from prima.run import Run  # only now: the whole stack comes with it

    return judge(Run(path).run(), thresholds=thresholds, name=name)


def find_scenarios(folder: str | Path) -> list[Path]:
    """The scenario files in a folder and its subfolders (maps and profiles left out;
    a file that is not even XML is kept, so that judging it reports its problem)."""
    from lxml import etree

    from prima.errors import LocatedError
    from prima.sim import SCENARIO_NS
    from prima.xmlio import parse_xml, read_source

    found = []
    for path in sorted(Path(folder).rglob("*.xml")):
        try:
            doc = parse_xml(read_source(path, TraceError), str(path), TraceError)
        except LocatedError:
            found.append(path)
            continue
        if etree.QName(doc.root).namespace == SCENARIO_NS:
            found.append(path)
    return found
