"""What every measure reads of a trace, kept in one pass: the atomic behaviors with
their times and devices, which application and tree each belongs to and where its
document asks for it, the reactions, the exchanges, holds, blocks and precedence.

The measures (:mod:`._measures`) each see every line too, after the context has
taken it in; what needs the whole run (a reaction's allowed wait) is worked out at
the end (:mod:`._reactions`) from what is kept here, which is linear in the number
of atomic behaviors, not of lines (poses are not kept).
"""

from __future__ import annotations

import bisect
import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any, Final

from prima.catalog import STANDARD_COMMANDS
from prima.judge._reading import Row
from prima.judge._thresholds import Thresholds

__all__ = ["EPS", "FOLLOW_COMMANDS", "TALK_DEVICES", "TRAVEL_COMMANDS", "UNMEASURED_EVENTS", "Ab",
           "Context", "Exchange", "Hold", "ReactionState", "covered", "span_at", "spans_meeting",
           "xy"]

EPS: Final = 1e-6
"""Times in a trace are rounded to the millisecond: comparisons allow this much."""

UNMEASURED_EVENTS = frozenset({"place-reached"})
"""Reactive events whose reactions are not measured: the robot's own motion
arriving, which nobody waits on the robot for (docs/rules.md section 8 lists touch,
heard speech, messages, the user found or lost)."""

TALK_DEVICES = frozenset({"speaker", "speech-recognition"})
"""Where an utterance runs."""

_ANSWERED = re.compile(r"(?:^|, )status=answered(?:,|$)")

_ANSWERS = " answers the user"
"""How a hold or a suspension for a reaction to the user's own action ends its text."""

LOW_COMMANDS: Final = frozenset(c.name for c in STANDARD_COMMANDS if c.breaks_cc)
"""Commands that break the Communication Channel (LOW priority)."""

FOLLOW_COMMANDS = frozenset(c.name for c in STANDARD_COMMANDS if c.follows_user)
"""Commands that move the robot after its user (Tracking Human)."""

TRAVEL_COMMANDS = frozenset(c.name for c in STANDARD_COMMANDS if c.travels)
"""Commands that take the robot somewhere (a move, following the user)."""


def xy(pose: dict[str, Any]) -> tuple[float, float]:
    return float(pose["x"]), float(pose["y"])


def command_ids(row: Row) -> tuple[int, ...]:
    ids = row.get("command_ids")
    if ids:
        return tuple(ids)
    detail: dict[str, Any] = row.get("detail") or {}  # (typed: the compiled build's dict)
    cid = detail.get("command_id")
    return (cid,) if isinstance(cid, int) else ()


def answered(row: Row) -> bool:
    """An end line of a Q&A (its Commands' last) that its user answered."""
    command = str(row.get("command") or "")
    if not (command == "QA" or command.endswith("+QA")):  # (most end lines: no more)
        return False
    detail: dict[str, Any] = row.get("detail") or {}
    result = detail.get("result")
    return isinstance(result, str) and _ANSWERED.search(result) is not None


@dataclass(init=False)
class Ab:
    """One atomic behavior as the trace shows it. (Its ``__init__`` is written out: the
    compiled build compiles it, where the one ``dataclass`` writes runs as Python, once
    for each start line.)"""

    id: int
    app: str
    tree: int
    command: str
    """Its Commands' names, ``A+B`` for a group."""
    ids: tuple[int, ...]
    devices: frozenset[str]
    start: float
    seq: int
    """Its start line."""
    reason: str
    """Why it started (the start line's reason)."""
    text: str = ""
    cuttable: bool = False
    """The interrupt policy may cut it (its Commands are interruptible on this robot and
    its request allows it: the start line says so)."""
    iteration: int = 0
    words: tuple[float, float] | None = None
    """When its words began and ended (from its start line when they begin with it,
    from its end line otherwise: as said, up to a cut)."""
    planned: tuple[float, float] | None = None
    """When its start line said its words would begin and end (None: it did not)."""
    end: float | None = None
    end_seq: int | None = None
    end_reason: str = ""
    blended_over: bool = False
    """Another AB started blended over it (the blend policy: never cut)."""
    dropped: bool = False
    """It was cut and its request said to drop it: it is not said again."""
    place: int = 0
    """Where it is among its tree's ABs (``Context.tree_abs``)."""

    def __init__(self, id: int, app: str, tree: int, command: str, ids: tuple[int, ...],
                 devices: frozenset[str], start: float, seq: int, reason: str,
                 text: str = "", cuttable: bool = False, iteration: int = 0,
                 words: tuple[float, float] | None = None,
                 planned: tuple[float, float] | None = None, end: float | None = None,
                 end_seq: int | None = None, end_reason: str = "", blended_over: bool = False,
                 dropped: bool = False, place: int = 0) -> None:
        self.id = id
        self.app = app
        self.tree = tree
        self.command = command
        self.ids = ids
        self.devices = devices
        self.start = start
        self.seq = seq
        self.reason = reason
        self.text = text
        self.cuttable = cuttable
        self.iteration = iteration
        self.words = words
        self.planned = planned
        self.end = end
        self.end_seq = end_seq
        self.end_reason = end_reason
        self.blended_over = blended_over
        self.dropped = dropped
        self.place = place

    @property
    def low(self) -> bool:
        """It breaks the Communication Channel (LOW priority: a group is as low as its
        lowest Command)."""
        return any(c in LOW_COMMANDS for c in self.command.split("+"))

    @property
    def listens(self) -> bool:
        return "QA" in self.command.split("+")

    def until(self, end: float) -> float:
        return self.end if self.end is not None else end


@dataclass(init=False)
class ReactionState:
    """A reaction as the pass collects it (the finding is made at the end). (Its
    ``__init__`` is written out, as :class:`Ab`'s is.)"""

    event: str
    t: float
    seq: int
    app: str
    user: bool
    text: str
    order: int
    """Its first request line's seq: the later, the more recent (rule 4.2)."""
    commands: list[int] = field(default_factory=list)
    trees: list[int] = field(default_factory=list)
    devices: frozenset[str] = frozenset()
    """Its first request's devices (its first AB's)."""
    at: str = ""
    words: bool = False
    """A request line of it says words (its root's)."""
    answer: bool = False
    """A reaction to a heard answer (its Q&A's tree goes on: no reaction of its own)."""
    before: int | None = None
    """The AB its first request follows (its application's own, still to end), if any."""

    def __init__(self, event: str, t: float, seq: int, app: str, user: bool, text: str,
                 order: int, commands: list[int] | None = None,
                 trees: list[int] | None = None, devices: frozenset[str] = frozenset(),
                 at: str = "", words: bool = False, answer: bool = False,
                 before: int | None = None) -> None:
        self.event, self.t, self.seq, self.app, self.user = event, t, seq, app, user
        self.text, self.order = text, order
        self.commands = [] if commands is None else commands
        self.trees = [] if trees is None else trees
        self.devices, self.at, self.words, self.answer = devices, at, words, answer
        self.before = before


@dataclass
class Exchange:
    """A Q&A the user answered, and how its application replied (docs/rules.md 7.4)."""

    app: str
    tree: int
    t: float
    seq: int
    """The answered Q&A's end line."""
    at: str
    kind: str = "none"
    """``words`` (the first AB its answer handler asked for says something and asks
    nothing), ``question`` (a Q&A), ``other`` (something else), ``none`` (nothing at
    once)."""
    reply: tuple[int, ...] = ()
    """The reply's Commands (its first request's)."""
    reply_ab: int | None = None
    """The reply's words' AB, once it started."""
    done: float | None = None
    """When the reply's words ended (or the question started: the exchange is over)."""


@dataclass
class Hold:
    """A ``hold`` line: another app's hold, block, talk or reaction keeps an AB."""

    t: float
    seq: int
    ab: int
    app: str
    reason: str
    holder: str
    """The application that keeps it (its name, from the line's text)."""
    before: int | None
    """A reservation's: the AB it keeps the devices for."""


@dataclass
class _Window:
    """Where the lines of a reaction may appear: after its cause, at the same instant."""

    event: str
    t: float
    seq: int
    user: bool
    app: str | None = None
    """A heard answer's reacting app (None: an event's, any app reacting)."""
    text: str = ""
    reactions: dict[str, ReactionState] = field(default_factory=dict)


class _Shape:
    """What a start line gives its AB, but its number, time, line and iteration
    (:meth:`Context._shape`): the line it was made of (but for those, its detail apart,
    and its poses) and what it says, the AB's lists in :attr:`Context.on_device` and
    :attr:`Context.tree_abs`, and whether its Commands follow the user, travel, listen."""

    __slots__ = ("app", "command", "detail", "devices", "ids", "lists", "moves", "reason",
                 "row", "siblings", "text", "tree", "words")

    def __init__(self, row: dict[str, Any], detail: dict[str, Any], app: str, tree: int,
                 command: str, ids: tuple[int, ...], devices: frozenset[str], reason: str,
                 text: str, words: tuple[float, float] | None,
                 moves: tuple[bool, bool, bool], lists: list[list[Ab]],
                 siblings: list[Ab]) -> None:
        self.row = row
        self.detail = detail
        self.app = app
        self.tree = tree
        self.command = command
        self.ids = ids
        self.devices = devices
        self.reason = reason
        self.text = text
        self.words = words
        self.moves = moves
        self.lists = lists
        self.siblings = siblings


_OWN: Final[dict[str, Any]] = {"t": None, "seq": None, "ab": None, "detail": None,
                               "robot": None, "user": None}
"""What a start line says of its own AB, apart (a copy of a line updated by this is the
same for the lines of a loop's iterations; its detail, but its iteration, too)."""

_SHAPES_KEPT: Final = 1024
"""How many Commands' start lines a context keeps (:meth:`Context._shape`)."""


Feed = Callable[[Row, "Context"], None]
"""What a line is fed to: a finder's ``feed``, or its ``feeder``'s for the line's kind."""

Route = tuple[Callable[["Context", Row], None] | None, list[Feed]]
"""What a kind of line goes to: the context's handling of it (None: none), then what the
measures feed it to, in order (:meth:`Context.feed_all`)."""


def _no_feeders(_kind: str) -> list[Feed]:
    return []


class Context:
    """What every measure reads, kept as the lines go by (:meth:`feed`). Of the line being
    fed: :attr:`now`, its time; for a start or end line, :attr:`ab`, the AB it starts or
    ends (None: it names none, or none that started), and :attr:`follows` and
    :attr:`travels`, whether its Commands follow the user or take the robot somewhere, and
    :attr:`listens`, whether one is a Q&A (worked out once for all the measures; a feedback
    loop's lines name the same Commands again and again)."""

    def __init__(self, thresholds: Thresholds) -> None:
        self.th = thresholds
        self.t = 0.0
        self.lines = 0
        self.last: Row | None = None
        """The line before the one being fed."""
        self.now = 0.0
        self.ab: Ab | None = None
        self.follows = self.travels = self.listens = False
        self._moves: dict[str, tuple[bool, bool, bool]] = {}  # (command -> follows, ...)
        self._routes: dict[str, Route] = {}
        """What each kind of line goes to (:meth:`feed_all`'s, :meth:`reroute`)."""
        self._robot: dict[str, Any] | None = None
        self.last_seen = 0.0
        """Until when the user was known detectable: now while the latest line with poses
        shows them so; else the time of the line with poses that first showed them not
        (a line's poses hold until the next line that has some)."""
        self._seeing = False
        """The latest line with poses showed the user detectable."""
        # atomic behaviors
        self.abs: dict[int, Ab] = {}
        self.running: dict[int, Ab] = {}
        self.on_device: dict[str, list[Ab]] = {}
        """Device -> its ABs, in start order (what a reaction's wait is judged on)."""
        self._shapes: dict[object, _Shape] = {}
        """Command -> what the latest start line of an AB of it gives its AB
        (:meth:`_shape`): a loop's start lines are the same but for their AB, time, line,
        iteration and poses, and start theirs from it."""
        self.cmd_ab: dict[int, int] = {}
        """Command -> its latest AB."""
        self.cmd_at: dict[int, str] = {}
        """Command -> where its request is written."""
        self.cmd_app: dict[int, str] = {}
        self.restarted: dict[int, int] = {}
        """A cut AB -> the AB that starts it again (its restart, or its going on)."""
        self.precedes: dict[int, int] = {}
        """A policy's Command (a turn, a return) -> the Command it was put before."""
        self.cancelled: dict[int, float] = {}
        """Command -> when it was cancelled."""
        self.cancelled_ab: dict[int, tuple[float, int | None]] = {}
        """AB (one never started, too) -> when it was cancelled, and its tree."""
        self.requested_at: dict[int, tuple[float, int]] = {}
        """AB -> when (and at which line) it was requested: the root of a request, a
        policy's AB, a restart."""
        self.requested: dict[int, tuple[str, str, str]] = {}
        """AB -> its application, its Command and where it is asked for, from its request
        (an AB that never started is known by this alone)."""
        self.elsewhere: set[int] = set()
        """Commands whose request said their words are about something else."""
        self.waiting_devices: dict[int, frozenset[str]] = {}
        """Command -> the devices of the AB it waits as, from a ``hold`` or ``suspend``
        line that names that AB before it starts (a request line gives only its first
        AB's devices: a chain's later Command is known by these lines alone)."""
        self.tree_app: dict[int, str] = {}
        self.tree_reactions: dict[int, list[ReactionState]] = {}
        """Tree -> the reactions that took it over, in order (the latest ranks)."""
        self.tree_taken: dict[int, float] = {}
        """Tree -> when a reaction first took it over."""
        self.tree_abs: dict[int, list[Ab]] = {}
        # reactions
        self.reactions: list[ReactionState] = []
        self._window: _Window | None = None
        self._heard: tuple[float, int, str] | None = None
        self.reaction_cmds: dict[int, ReactionState] = {}
        """Command -> the reaction that asked for it."""
        self._exchanges_and_holds()

    def _exchanges_and_holds(self) -> None:
        """What :meth:`__init__` keeps of exchanges, holds, precedence and blocks."""
        self.exchanges: list[Exchange] = []
        self.open_exchange: dict[str, Exchange] = {}
        """App -> its exchange whose reply is not yet known or not yet over."""
        self.replied: dict[int, list[Exchange]] = {}
        """An AB -> the exchanges whose reply's words it says (``reply_ab``)."""
        self.holds: list[Hold] = []
        self.demoted: dict[str, list[list[float]]] = {}
        """App -> when it had lost its precedence: [from, until] (until: inf if it had
        not regained it), in time order and apart (:func:`span_at`)."""
        self.demoted_seq: dict[str, list[int]] = {}
        """App -> the seq of the line that said it lost its precedence, for each span:
        what started before it in that instant started with its precedence."""
        self.blocks: dict[str, list[list[float]]] = {}
        """App -> when its begin/end block was open: [from, until], in time order and
        apart (:func:`span_at`)."""
        self.interrupts: dict[int, str] = {}
        """AB -> the application whose reaction had it cut."""
        self.user_cuts: dict[int, bool] = {}
        """AB -> cut because the user spoke over it: whether an application took the
        words (False: none did, a false interruption: it goes on after a pause)."""

    @property
    def robot(self) -> tuple[float, float] | None:
        """Where the latest line with poses put the robot (worked out when asked: few
        lines ask)."""
        return xy(self._robot) if self._robot is not None else None

    # ---------------------------------------------------------------- the pass
    def feed(self, row: Row) -> None:
        """One line, taken in (a line alone: :meth:`feed_all` feeds the measures too)."""
        self.feed_all((row,), {}, _no_feeders)

    def feed_all(self, rows: Iterable[Row], routes: dict[str, Route],
                 feeders: Callable[[str], list[Feed]]) -> None:
        """Lines of the trace, in order: each taken in, then fed to what ``routes`` has
        for its kind (``feeders(kind)``: what to feed that kind, asked the first time),
        and :attr:`last` set. The judge's one loop (:meth:`Judging.feed_all
        <prima.judge.Judging.feed_all>`): what every line needs is done here, not in a
        call of its own, and its kind is asked once for the context and the measures."""
        self._routes = routes
        for row in rows:
            t = float(row["t"])
            self.now = t
            if t > self.t + EPS:
                self._window = None
                self._heard = None
                self.t = t
            self.lines += 1
            if self._seeing:
                self.last_seen = t
            robot = row.get("robot")
            if robot is not None:
                self._robot = robot
                user: dict[str, Any] | None = row.get("user")
                self._seeing = user is not None and user.get("detectable") is True
                if self._seeing:
                    self.last_seen = t
            kind = row["kind"]
            route = routes.get(kind)
            if route is None:
                route = routes[kind] = (_HANDLERS.get(kind), feeders(kind))
            handler, those = route
            if handler is not None:
                handler(self, row)
            for feed in those:
                feed(row, self)
            self.last = row

    def reroute(self) -> None:
        """What the kinds of line are fed to is asked again, from the next line on: a
        finder whose ``feeder`` for a kind depends on its state (one that has nothing to
        do with the lines of that kind until some other line comes) says so when that
        state changes."""
        self._routes.clear()

    def _moved(self, command: str) -> tuple[bool, bool, bool]:
        """:attr:`follows`, :attr:`travels` and :attr:`listens` for a start or end line's
        Commands (worked out the first time they are seen), set and returned."""
        moves = self._moves.get(command)
        if moves is None:
            names = command.split("+")
            moves = self._moves[command] = (not FOLLOW_COMMANDS.isdisjoint(names),
                                            not TRAVEL_COMMANDS.isdisjoint(names),
                                            "QA" in names)
        self.follows, self.travels, self.listens = moves
        return moves

    def _event(self, row: Row) -> None:
        name = str(row.get("text") or "")
        if name in UNMEASURED_EVENTS:
            self._window = None
            return
        last = self.last
        # (the event a touch posts, or the words heard: not a perception that comes in
        # the instant the user said something the robot did not hear)
        user = (last is not None and last.get("kind") == "user"
                and abs(float(last["t"]) - float(row["t"])) <= EPS
                and (last.get("action") == "touch"
                     or (last.get("action") == "say" and name == "speech"
                         and (last.get("detail") or {}).get("heard") is True)))
        words = (row.get("detail") or {}).get("words") if name == "speech" else None
        self._window = _Window(name, float(row["t"]), int(row["seq"]), user,
                               text=str(words or ""))

    def _user(self, row: Row) -> None:
        self._window = None
        heard = (row.get("detail") or {}).get("heard")
        if row.get("action") == "say" and heard:
            self._heard = (float(row["t"]), int(row["seq"]), str(row.get("text") or ""))

    def _request(self, row: Row) -> None:
        app = str(row.get("app") or "")
        detail: dict[str, Any] = row.get("detail") or {}
        ids = command_ids(row)
        ab = row.get("ab")
        at = str(detail.get("at") or "")
        if isinstance(ab, int):
            self.requested_at[ab] = (float(row["t"]), int(row["seq"]))
            self.requested[ab] = (app, str(row.get("command") or ""), at)
        tree = row.get("tree")
        if isinstance(tree, int):
            self.tree_app.setdefault(tree, app)
        for cid in ids:
            self.cmd_app[cid] = app
            if at:
                self.cmd_at[cid] = at
        if detail.get("face_user") is False:
            self.elsewhere.update(ids)  # (its words are about something else)
        precedes = detail.get("precedes")
        if isinstance(precedes, int):
            for cid in ids:
                self.precedes[cid] = precedes
                mine = self.reaction_cmds.get(precedes)
                if mine is not None:
                    self.reaction_cmds[cid] = mine
            return
        if row.get("reason") == "restart":
            cut, again = row.get("before"), row.get("ab")
            if isinstance(cut, int) and isinstance(again, int):
                self.restarted[cut] = again
            return
        self._exchange_request(row, app, ids)
        self._reaction_request(row, app, ids, at)

    def _reaction_request(self, row: Row, app: str, ids: tuple[int, ...], at: str) -> None:
        w = self._window
        if w is None:
            self._unmeasured(row, app)
            return
        if w.app is not None and (app != w.app or row.get("reason") != "end-event"):
            return
        r = w.reactions.get(app)
        if r is None:
            if w.app is None and row.get("reactive") is not True:
                self._unmeasured(row, app)
                return
            before = row.get("before")
            r = ReactionState(w.event, w.t, w.seq, app, w.user, w.text, int(row["seq"]),
                              devices=frozenset(row.get("devices") or ()), at=at,
                              answer=w.app is not None,
                              before=before if isinstance(before, int) else None)
            w.reactions[app] = r
            self.reactions.append(r)
        if row.get("text"):
            r.words = True
        tree = row.get("tree")
        if isinstance(tree, int) and tree not in r.trees:  # (a tree it had not taken yet)
            r.trees.append(tree)
            if not r.answer:  # (a reply continues its Q&A's tree: no reaction of its own)
                self._taken(tree, r)
        for cid in ids:
            r.commands.append(cid)
            self.reaction_cmds[cid] = r

    def _unmeasured(self, row: Row, app: str) -> None:
        """A reactive request outside a measured event's instant (an application's own
        reactive event or timer, a place reached): its tree ranks as a reaction all
        the same (rule 4.2), though its latency is not measured."""
        tree = row.get("tree")
        if row.get("reactive") is not True or not isinstance(tree, int) \
                or row.get("reason") == "end-event":
            return
        r = ReactionState("", float(row["t"]), int(row["seq"]), app, False, "",
                          int(row["seq"]), trees=[tree])
        self._taken(tree, r)

    def _taken(self, tree: int, r: ReactionState) -> None:
        self.tree_reactions.setdefault(tree, []).append(r)
        self.tree_taken[tree] = min(r.t, self.tree_taken.get(tree, r.t))

    def _exchange_request(self, row: Row, app: str, ids: tuple[int, ...]) -> None:
        ex = self.open_exchange.get(app)
        if ex is None or ex.kind != "none" or ex.t < self.t - EPS:
            return
        if row.get("reason") != "end-event":
            return
        command = str(row.get("command") or "")
        if "QA" in command.split("+"):
            ex.kind = "question"
        elif row.get("text") and not TALK_DEVICES.isdisjoint(row.get("devices") or ()):
            ex.kind = "words"  # (its first AB speaks: a request line's devices are its)
        else:
            ex.kind = "other"  # (a reply that aims or points first, then speaks, too)
        ex.reply = ids

    def _start(self, row: Row) -> None:
        ab_id = row.get("ab")
        if not isinstance(ab_id, int):
            self.ab = None
            self._moved(str(row.get("command") or ""))
            return
        detail: dict[str, Any] = row.get("detail") or {}
        key = detail.get("command_id")
        shape = self._shapes.get(key)
        if shape is None or {**row, **_OWN} != shape.row \
                or {**detail, "iteration": None} != shape.detail:
            shape = self._shape(row, detail, key)  # (else: a loop's next iteration, say)
        ab = Ab(ab_id, shape.app, shape.tree, shape.command, shape.ids, shape.devices,
                float(row["t"]), int(row["seq"]), shape.reason, text=shape.text,
                cuttable=detail.get("cuttable") is True,
                iteration=int(detail.get("iteration") or 0), words=shape.words,
                planned=shape.words)
        self.ab = ab
        self.follows, self.travels, self.listens = shape.moves
        if shape.reason == "blend":
            for d in ab.devices:
                for other in self.running.values():
                    if d in other.devices:
                        other.blended_over = True
        self.abs[ab_id] = ab
        self.running[ab_id] = ab
        for on in shape.lists:
            on.append(ab)
        siblings = shape.siblings
        ab.place = len(siblings)
        siblings.append(ab)
        for cid in ab.ids:
            self.cmd_ab[cid] = ab_id
        self._reply_started(ab)

    def _shape(self, row: Row, detail: dict[str, Any], key: object) -> _Shape:
        """What a start line gives its AB but its number, time, line and iteration, kept
        under its Command for the next start line that is the same but for these."""
        tree = row.get("tree")
        tree = tree if isinstance(tree, int) else -1
        command = str(row.get("command") or "")
        devices = frozenset(row.get("devices") or ())
        ws, we = detail.get("words_start"), detail.get("words_end")
        shape = _Shape({**row, **_OWN}, {**detail, "iteration": None},
                       str(row.get("app") or ""), tree, command, command_ids(row), devices,
                       str(row.get("reason") or ""), str(row.get("text") or ""),
                       (float(ws), float(we)) if isinstance(ws, (int, float))
                       and isinstance(we, (int, float)) else None,
                       self._moved(command),
                       [self.on_device.setdefault(d, []) for d in devices],
                       self.tree_abs.setdefault(tree, []))
        if len(self._shapes) >= _SHAPES_KEPT:
            self._shapes.clear()
        self._shapes[key] = shape
        return shape

    def _reply_started(self, ab: Ab) -> None:
        ex = self.open_exchange.get(ab.app)
        if ex is None or not ex.reply:
            return
        if ex.kind == "words" and ex.reply_ab is None and ex.reply[0] in ab.ids and not ab.text:
            ex.kind = "other"  # (its first AB, on the speaker, says nothing: a sound)
        if ex.kind == "words" and ab.text and not set(ab.ids).isdisjoint(ex.reply):
            if ex.reply_ab is not None:  # (words said again: a cut reply started anew)
                self.replied[ex.reply_ab] = [e for e in self.replied[ex.reply_ab] if e is not ex]
            ex.reply_ab = ab.id
            self.replied.setdefault(ab.id, []).append(ex)
        elif ex.kind == "question" and not set(ab.ids).isdisjoint(ex.reply):
            ex.done = ab.start
            del self.open_exchange[ab.app]

    def _end(self, row: Row) -> None:
        ab_id = row.get("ab")
        ab = self.ab = self.abs.get(ab_id) if isinstance(ab_id, int) else None
        command = str(row.get("command") or "")
        moves = self._moved(command)
        if ab is not None:
            self.running.pop(ab.id, None)
            ab.end = float(row["t"])
            ab.end_seq = int(row["seq"])
            ab.end_reason = str(row.get("reason") or "")
            detail: dict[str, Any] = row.get("detail") or {}
            ab.dropped = detail.get("interrupt") == "dropped"
            ws, we = detail.get("words_start"), detail.get("words_end")
            if isinstance(ws, (int, float)) and isinstance(we, (int, float)):
                ab.words = (float(ws), float(we))
            ex = self.open_exchange.get(ab.app)
            if ex is not None and ex.reply_ab == ab.id:
                ex.done = ab.end
                del self.open_exchange[ab.app]
        if moves[2] and answered(row):  # (a Q&A's: the others are not answered)
            app = str(row.get("app") or "")
            tree = row.get("tree")
            cid = command_ids(row)
            ex = Exchange(app, tree if isinstance(tree, int) else -1, float(row["t"]),
                          int(row["seq"]), self.cmd_at.get(cid[0], "") if cid else "")
            self.exchanges.append(ex)
            self.open_exchange[app] = ex
            if self._heard is not None:
                t, seq, text = self._heard
                self._window = _Window("speech", t, seq, True, app=app, text=text)
                self._heard = None

    def _cancel(self, row: Row) -> None:
        ids = command_ids(row)
        for cid in ids:
            self.cancelled.setdefault(cid, float(row["t"]))
        ab, tree = row.get("ab"), row.get("tree")
        if isinstance(ab, int):
            self.cancelled_ab.setdefault(ab, (float(row["t"]),
                                              tree if isinstance(tree, int) else None))
        for app, ex in list(self.open_exchange.items()):
            if not set(ex.reply).isdisjoint(ids):  # its reply will never be said
                ex.done = float(row["t"])
                del self.open_exchange[app]

    def _waits_as(self, row: Row) -> None:
        """A line names a waiting AB with its devices: note them for its Commands."""
        devices = row.get("devices")
        if devices:
            for cid in command_ids(row):
                self.waiting_devices.setdefault(cid, frozenset(devices))

    def _hold(self, row: Row) -> None:
        ab = row.get("ab")
        if not isinstance(ab, int):
            return
        self._waits_as(row)
        text = str(row.get("text") or "")
        holder = ""
        for marker in ("kept for ", "for "):
            if marker in text:
                holder = text.split(marker, 1)[1].split("'s")[0].split()[0]
                break
        if not holder and text.endswith(" is talking"):
            holder = text[:-len(" is talking")]
        if text.endswith(_ANSWERS):  # (docs/rules.md 7.6 (1): "[while] X answers the user")
            holder = text[:-len(_ANSWERS)].removeprefix("while ")
        before = row.get("before")
        self.holds.append(Hold(float(row["t"]), int(row["seq"]), ab,
                               str(row.get("app") or ""), str(row.get("reason") or ""),
                               holder, before if isinstance(before, int) else None))

    def _suspend(self, row: Row) -> None:
        """A stream suspended while a reaction answers the user (7.6 (1)) is held as a
        hold line says (its other suspensions are what its ABs lost, seen on devices)."""
        if row.get("reason") == "answering":
            self._hold(row)
        elif isinstance(row.get("ab"), int):
            self._waits_as(row)

    def _budget(self, row: Row) -> None:
        app = str(row.get("app") or "")
        text = str(row.get("text") or "")
        spans = self.demoted.setdefault(app, [])
        if "loses its precedence" in text:
            if spans and spans[-1][1] == _OPEN:
                return  # (a forged trace's second loss: it had not regained it)
            spans.append([float(row["t"]), _OPEN])
            self.demoted_seq.setdefault(app, []).append(int(row["seq"]))
        elif "regains" in text and spans:
            spans[-1][1] = float(row["t"])

    def _block(self, row: Row) -> None:
        app = str(row.get("app") or "")
        spans = self.blocks.setdefault(app, [])
        if row.get("text") == "open":
            if spans and spans[-1][1] == _OPEN:
                return  # (a forged trace's second open: one close ends the block)
            spans.append([float(row["t"]), _OPEN])
        elif spans and spans[-1][1] == _OPEN:
            spans[-1][1] = float(row["t"])

    def _release(self, row: Row) -> None:
        if row.get("reason") in ("watchdog", "block-close"):
            spans = self.blocks.get(str(row.get("app") or ""))
            if spans and spans[-1][1] == _OPEN:
                spans[-1][1] = float(row["t"])

    def _interrupt(self, row: Row) -> None:
        ab = row.get("ab")
        text = str(row.get("text") or "")
        if isinstance(ab, int) and text.startswith("for "):
            self.interrupts[ab] = text[4:].split("'s")[0]
        elif isinstance(ab, int) and row.get("reason") == "barge-in":
            self.user_cuts[ab] = "goes on after" not in text

    def _unload(self, row: Row) -> None:
        ex = self.open_exchange.pop(str(row.get("app") or ""), None)
        if ex is not None:
            ex.done = float(row["t"])

    # ---------------------------------------------------------------- looking up
    def at(self, ab: Ab) -> str:
        """Where the application's document asks for an AB."""
        for cid in ab.ids:
            found = self.cmd_at.get(cid) or self.cmd_at.get(self.precedes.get(cid, -1), "")
            if found:
                return found
        return ""

    def during(self, spans: list[list[float]] | None, t: float) -> bool:
        span = span_at(spans or (), t)
        return span is not None and t < span[1] - EPS

    def demoted_at(self, app: str, t: float, seq: int | None = None) -> bool:
        """Whether ``app`` had lost its precedence at ``t`` (for the line ``seq`` of that
        instant, if given: a line before the one that said it lost it is not)."""
        spans = self.demoted.get(app)
        if not spans:
            return False
        i = _begun(spans, t)
        if i < 0 or t >= spans[i][1] - EPS:
            return False
        seqs = self.demoted_seq.get(app, [])
        return not (seq is not None and abs(t - spans[i][0]) <= EPS and i < len(seqs)
                    and seq < seqs[i])

    def demoted_within(self, app: str, lo: float, hi: float) -> bool:
        return bool(spans_meeting(self.demoted.get(app, ()), lo, hi))

    def block_open(self, app: str, t: float) -> bool:
        return self.during(self.blocks.get(app), t)


_OPEN: Final = float("inf")
"""The end of a span still open."""


def _from(span: Sequence[float]) -> float:
    return span[0]


def _until(span: Sequence[float]) -> float:
    return span[1]


def span_at(spans: Sequence[list[float]], t: float) -> list[float] | None:
    """The last of ``spans`` that began at or before ``t`` (None: none did). Spans in time
    order and apart (each begins where or after the one before it ended, as a context
    keeps them) hold ``t`` only if that one does; found by bisection, so that a long
    trace's many spans cost no more per question."""
    i = _begun(spans, t)
    return spans[i] if i >= 0 else None


def _begun(spans: Sequence[list[float]], t: float) -> int:
    """Where the last of ``spans`` that began at or before ``t`` is among them (-1: none
    did), found by bisection (:func:`span_at`)."""
    return bisect.bisect_right(spans, t + EPS, key=_from) - 1


def covered(spans: Iterable[tuple[float, float]], lo: float, hi: float) -> float:
    """How much of [lo, hi] the spans (from, until) cover, counted once."""
    clipped = sorted((max(a, lo), min(b, hi)) for a, b in spans if b > lo and a < hi)
    total, reach = 0.0, lo
    for a, b in clipped:
        if b <= reach:
            continue
        total += b - max(a, reach)
        reach = b
    return total


def spans_meeting(spans: Sequence[list[float]], lo: float, hi: float) -> Sequence[list[float]]:
    """The ``spans`` that meet [lo, hi], of spans in time order and apart (their ends go
    on as their starts do), found by bisection."""
    first = bisect.bisect_right(spans, lo - EPS, key=_until)
    return spans[first:bisect.bisect_left(spans, hi + EPS, key=_from)]


_HANDLERS: Final = {
    "event": Context._event,
    "user": Context._user,
    "request": Context._request,
    "start": Context._start,
    "end": Context._end,
    "cancel": Context._cancel,
    "hold": Context._hold,
    "suspend": Context._suspend,
    "budget": Context._budget,
    "block": Context._block,
    "release": Context._release,
    "interrupt": Context._interrupt,
    "unload": Context._unload,
}
