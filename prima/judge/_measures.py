"""The measures of naturalness (docs/rules.md section 8): one entry each in :data:`MEASURES`.

An entry names the measure (its key, which is also its threshold ``max_<key>`` and
its option ``--max-<key>``), says what it finds, how ``prima judge`` shows one
finding and which row ``prima sweep`` gives it, and makes the object that finds
it: a *finder* sees every trace line after the shared :class:`~._context.Context`
has taken it in, and gives its findings at the end. Adding a measure is one
finder and one entry here; the report, the thresholds, the command-line options,
the sweep's rows and the docs' table all come from this table.
"""

from __future__ import annotations

import bisect
import heapq
import math
import re
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any, Final, Protocol

from prima.catalog import BODY_DEVICE, SEARCH_DEVICE, STANDARD_COMMANDS
from prima.judge import _blame as blame
from prima.judge._blame import Wheels, Whose
from prima.judge._context import (
    EPS,
    TRAVEL_COMMANDS,
    Ab,
    Context,
    Exchange,
    command_ids,
    covered,
    xy,
)
from prima.judge._findings import (
    BargeIn,
    Blame,
    Elsewhere,
    Finding,
    Ignored,
    Leaving,
    Recovery,
    Reaction,
    Silence,
    Split,
    Stuck,
    Unfaced,
)
from prima.judge._reading import Row
from prima.judge._thresholds import LIMITS, Limit

__all__ = ["MEASURES", "Finder", "Measure", "measure", "registered"]



_AIMING: Final = frozenset(c.name for c in STANDARD_COMMANDS if c.aims)


class Finder(Protocol):
    """What finds one measure's faults: every line of the kinds it looks at, then the
    findings. A finder may also have a ``feeder(kind)``: what to feed the lines of that
    kind to instead of :meth:`feed` (None: nothing), so that the judge asks a line's kind
    once for all the finders (each of PRIMA's own that looks at many lines has one). Its
    answer may depend on the finder's state (nothing to do with end lines until the user
    has said something, say): the finder then calls the context's ``reroute()`` when that
    state changes, and the judge asks it again from the next line on."""

    @property
    def kinds(self) -> frozenset[str] | None:
        """The kinds of line it is fed (None: every line; the others change nothing)."""

    def feed(self, row: Row, ctx: Context) -> None: ...

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]: ...


@dataclass(frozen=True)
class Measure(Limit):
    """One measure of naturalness: its :class:`Limit`, and how it finds faults."""

    finder: Callable[[], Finder]
    line: Callable[[Any], str]
    """One finding, in one line of ``prima judge``'s table."""
    blame: Callable[[Any, Wheels], Whose]
    """Whose one finding is (:mod:`._blame`): what ``prima check`` attributes it to."""


def _short(text: str, width: int = 30) -> str:
    text = " ".join(text.split())
    return text if len(text) <= width else text[: width - 3] + "..."


def _where(at: str) -> str:
    return f" ({at})" if at else ""


# ---------------------------------------------------------------- reactions

class _Reactions:
    """Late or unheard reactions: what :mod:`._reactions` found, filtered."""

    kinds: frozenset[str] | None = frozenset()

    def __init__(self, keep: Callable[[Reaction], bool]) -> None:
        self.keep = keep

    def feed(self, row: Row, ctx: Context) -> None:
        pass

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        return [r for r in reactions if self.keep(r)]


def _reaction_line(r: Reaction) -> str:
    cause = f'speech "{_short(r.text, 13)}"' if r.event == "speech" else r.event
    out = f"seq {r.seq} t={r.t:g} {r.app} {cause}{_where(r.at)}: {r.why or 'unheard'}"
    if r.waits:
        out += "; waited for " + "; ".join(str(w) for w in r.waits)
    if r.took is not None:
        out += f"; meanwhile {r.took}"
    return out


def _unheard_line(r: Reaction) -> str:
    cause = f'speech "{_short(r.text, 13)}"' if r.event == "speech" else r.event
    return (f"seq {r.seq} t={r.t:g} {r.app} {cause}{_where(r.at)}: its words were never "
            "heard whole")


# ---------------------------------------------------------------- facing

def _off_heading(robot: Row, user: Row) -> float | None:
    dx, dy = user["x"] - robot["x"], user["y"] - robot["y"]
    if math.hypot(dx, dy) < 1e-9:
        return None
    bearing = math.degrees(math.atan2(dy, dx))
    return float(abs((bearing - robot["heading"] + 180.0) % 360.0 - 180.0))


_POLICY_REASONS: Final = frozenset({"connect-channel", "restore-state"})
"""The reasons of the ABs a policy puts in a stream (none aims at anything of its app's)."""


def _about_something_else(row: Row, before: str | None) -> bool:
    """An utterance that is not for the user's face: its AB turns or points the robot
    itself (FaceHumanAndSpeak, a Speak grouped with a PointByHand), or the AB before
    it in its stream aimed the robot at something on purpose (a Turn, a PointByHand):
    the words are about that. (Its request may say so too: ``face_user`` false.)"""
    if BODY_DEVICE in (row.get("devices") or ()) \
            or not _AIMING.isdisjoint(str(row.get("command")).split("+")):
        return True
    return before is not None and not _AIMING.isdisjoint(before.split("+"))


class _Posed:
    """A posed line that ABs wait to judge until their words' times are known: one object
    for all of them (a tuple would be made anew for each in the compiled build)."""

    __slots__ = ("driven", "held", "mover", "row")

    def __init__(self, row: Row, mover: Blame | None, driven: bool = True,
                 held: Row | None = None) -> None:
        self.row = row
        self.mover = mover
        self.driven = driven
        """Something took the robot somewhere since the posed line before it."""
        self.held = held
        """The posed line before it."""


@dataclass
class _Words:
    """An utterance addressed to the user, while its words run."""

    row: Row
    """Its start line."""
    words: tuple[float, float] | None
    """When its words run, once known (they may follow something else in its AB)."""
    off_since: Row | None = None
    """The first posed line of the stretch in which the user is off, if they are now."""
    most: float = 0.0
    """The most degrees off in that stretch."""
    turner: Blame | None = None
    """What drove the wheels when that stretch began."""
    pending: list[_Posed] = field(default_factory=list)
    """Posed lines while its words' times are not known yet: judged at its end."""


ROUNDED_OFF: Final = 0.2
"""Degrees a trace's rounded poses (positions to the millimetre, headings to the tenth
of a degree) may put a user off the robot's heading, beyond the simulator's own
figure: a user found off by no more than the tolerance plus this is not off."""


def _off(row: Row, tolerance: float) -> float | None:
    """How far off the user is on a posed line, if detectable and beyond ``tolerance``
    (give or take what the trace's rounding moves it by)."""
    robot: dict[str, Any] | None = row.get("robot")
    user: dict[str, Any] | None = row.get("user")
    if robot is None or user is None or user.get("detectable") is not True:
        return None
    off = _off_heading(robot, user)
    return off if off is not None and off > tolerance + ROUNDED_OFF else None


class _Unfaced:
    """Utterances said while the user is detectable and more than the tolerance off the
    robot's heading: at their start, or for more than ``unfaced_for`` seconds in a row
    while their words run (docs/rules.md 7.6 (3): the robot keeps facing the user while
    its words run). The user's pose is known at each posed line and held until the
    next: a stretch runs from the first line that shows the user off to the first that
    does not (or the words' end), and is measured whole when it ends. While a turn to
    the user runs (reason ``connect-channel``: the robot turns to them as fast as it
    can), no stretch runs: the one running ends as the turn starts, and one starts anew
    if they are still off when it is over."""

    kinds: frozenset[str] | None = None

    def __init__(self) -> None:
        self.found: list[Unfaced] = []
        self.last_command: dict[int, str] = {}
        self.talking: dict[int, _Words] = {}
        self.before_of: dict[int, str | None] = {}
        """A started AB -> the Command that started before it in its stream (what its
        words may be about); a restart's is the AB's it starts again."""
        self.restarts: dict[int, int] = {}
        """A restart -> the cut AB it starts again."""
        self.after_ab: dict[int, int | None] = {}
        """A request's first Command -> the AB it follows in its stream, as the request
        says (None: none)."""
        self.after_command: dict[int, int] = {}
        """A chain's later Command -> the Command before it in the chain."""

    def feed(self, row: Row, ctx: Context) -> None:
        self.feeder(row["kind"])(row, ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None]:
        if kind == "request":
            return self._request
        if kind == "start":
            return self._start
        if kind == "end":
            return self._end
        return self._posed

    def _request(self, row: Row, ctx: Context) -> None:
        ab = row.get("ab")
        if row.get("reason") == "restart" and isinstance(ab, int):
            cut = row.get("before")
            if isinstance(cut, int):
                self.restarts[ab] = cut
        else:
            ids = command_ids(row)
            before = row.get("before")
            if ids:
                self.after_ab[ids[0]] = before if isinstance(before, int) else None
            self.after_command.update(zip(ids[1:], ids, strict=False))
        self._posed(row, ctx)

    def _start(self, row: Row, ctx: Context) -> None:
        ab = ctx.ab  # (the context's: None when the line names no AB)
        if ab is not None:
            self._started(row, ab, ctx)
        if self.talking:
            self._posed(row, ctx)

    def _end(self, row: Row, ctx: Context) -> None:
        if not self.talking:
            return  # (nothing said now: most end lines, a loop's)
        ab = row.get("ab")
        talk = self.talking.get(ab) if isinstance(ab, int) else None
        if talk is not None and isinstance(ab, int):
            if talk.words is None and ctx.ab is not None:
                talk.words = ctx.ab.words
                for posed in talk.pending:
                    if self._pose(ab, talk, posed.row, posed.mover, ctx):
                        break
            if ab in self.talking:
                self._ended(ab, talk, ctx.now, ctx)
        if self.talking:
            self._posed(row, ctx)

    def _posed(self, row: Row, ctx: Context) -> None:
        """Any line: one with poses is judged for each utterance running."""
        if self.talking and row.get("robot") is not None and row.get("user") is not None:
            mover = _wheels(ctx)
            posed = _Posed(row, mover)  # (one for every AB it waits in: not one each)
            for ab_id, talk in list(self.talking.items()):
                if talk.words is None:
                    talk.pending.append(posed)
                else:
                    self._pose(ab_id, talk, row, mover, ctx)

    def _before(self, row: Row, ids: tuple[int, ...], ctx: Context) -> str | None:
        """The Command of the AB an AB follows in its stream, as the mediator links them
        (docs/rules.md 7.3 (4)): the AB its request follows, or the one before it in its
        chain; not an AB of another request that started in between (an ``asap``
        StopMoving beside it). None: it follows none, or one that never ran or that a
        policy put there (aimed at nothing of the application's)."""
        first = ids[0] if ids else None
        if first in self.after_command:
            ab_id = ctx.cmd_ab.get(self.after_command[first])
        elif first in self.after_ab:
            ab_id = self.after_ab[first]
        else:  # (no request line seen for it: the latest start of its tree)
            tree = row.get("tree")
            return self.last_command.get(tree) if isinstance(tree, int) else None
        ab = ctx.abs.get(ab_id) if ab_id is not None else None
        if ab is None or ab.reason in _POLICY_REASONS:
            return None
        return ab.command

    def _started(self, row: Row, started: Ab, ctx: Context) -> None:
        ab = started.id
        tree = row.get("tree")
        before = self._before(row, started.ids, ctx)
        cut = self.restarts.pop(ab, None)
        if cut is not None:  # (said again, its words are about what they were about)
            before = self.before_of.get(cut, before)
        self.before_of[ab] = before
        if isinstance(tree, int):
            self.last_command[tree] = str(row.get("command"))
        if not started.text or _about_something_else(row, before) \
                or not ctx.elsewhere.isdisjoint(started.ids):
            return
        off = _off(row, ctx.th.face_tolerance)
        if off is not None:
            self.found.append(self._finding(row, off, ctx))
            return
        self.talking[ab] = _Words(row, started.words)

    def _pose(self, ab: int, talk: _Words, row: Row, mover: Blame | None,
              ctx: Context) -> bool:
        """One posed line while ``talk``'s AB runs: True when it is found unfaced."""
        words = talk.words
        t = float(row["t"])
        if words is None or t < words[0] - EPS or t > words[1] + EPS:
            return False
        off = _off(row, ctx.th.face_tolerance)
        if off is None or any(y.reason == "connect-channel" for y in ctx.running.values()):
            # (faced again; or the robot turns to them, as fast as it can)
            return self._stretch(ab, talk, t, ctx)
        if talk.off_since is None:
            talk.off_since, talk.most, talk.turner = row, off, mover
        talk.most = max(talk.most, off)
        return False

    def _stretch(self, ab: int, talk: _Words, t: float, ctx: Context) -> bool:
        """The stretch the user was off in, if one runs, ends at ``t``: found when it
        lasted longer than allowed (how long: the whole stretch, which a line with the
        same poses in the middle of it neither ends nor measures)."""
        since = talk.off_since
        if since is None:
            return False
        talk.off_since = None
        lasted = t - float(since["t"])
        if lasted > ctx.th.unfaced_for + EPS:
            self.found.append(self._finding(talk.row, talk.most, ctx, round(lasted, 3),
                                            int(since["seq"]), talk.turner))
            del self.talking[ab]
            return True
        return False

    def _ended(self, ab: int, talk: _Words, t: float, ctx: Context) -> None:
        """Its AB ended: a stretch still open lasted until its words' end."""
        words = talk.words
        if words is not None:
            self._stretch(ab, talk, min(t, words[1]), ctx)
        self.talking.pop(ab, None)

    @staticmethod
    def _finding(row: Row, off: float, ctx: Context, during: float | None = None,
                 during_seq: int | None = None, turner: Blame | None = None) -> Unfaced:
        ab = ctx.abs.get(row.get("ab", -1))
        return Unfaced(int(row["seq"]), float(row["t"]), str(row.get("app")),
                       str(row.get("command")), str(row.get("text")), round(off, 1),
                       ctx.at(ab) if ab is not None else "", during, during_seq, turner)

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        for ab, talk in list(self.talking.items()):
            if talk.words is not None:
                self._stretch(ab, talk, min(ctx.t, talk.words[1]), ctx)
        return sorted(self.found, key=lambda u: (u.seq, u.during_seq or 0))


def _wheels(ctx: Context) -> Blame | None:
    """The running AB that drives the wheels now, if any."""
    for ab in ctx.running.values():
        if "locomotion" in ab.devices:
            return Blame(ab.app, ab.id, ab.command, ctx.at(ab), "drove the wheels")
    return None


def _unfaced_line(u: Unfaced) -> str:
    head = f"seq {u.seq} t={u.t:g} {u.app} {u.command} \"{_short(u.text)}\"{_where(u.at)}: "
    if u.during is None:
        return head + f"{u.off:g} deg off"
    turned = f", turned by {u.turned_by}" if u.turned_by is not None else ""
    return head + (f"the user off for {u.during:g} s while its words ran (from seq "
                   f"{u.during_seq}, up to {u.off:g} deg){turned}")


# ---------------------------------------------------------------- leaving

@dataclass(init=False)
class _Talk:
    """(Its ``__init__`` written out, as ``Ab``'s is: compiled.)"""

    ab: int
    row: Row
    was: tuple[float, float] | None
    """Where the robot was when the words began (None: not yet)."""
    words: tuple[float, float] | None
    """When the words run, if known."""
    gap: float
    """How far it was from the user when the words began."""
    pending: list[_Posed]
    """Poses while its words' times are not known yet (they are said after something
    else in its AB): judged at its end."""

    def __init__(self, ab: int, row: Row, was: tuple[float, float] | None,
                 words: tuple[float, float] | None, gap: float = 0.0) -> None:
        self.ab, self.row, self.was, self.words, self.gap = ab, row, was, words, gap
        self.pending = []


class _Leaving:
    """The robot moving more than ``leave_distance`` farther from the user on its own
    while words addressed to them run (following the user is not leaving)."""

    kinds: frozenset[str] | None = None

    def __init__(self) -> None:
        self.found: list[Leaving] = []
        self.talking: dict[int, _Talk] = {}
        self.following = 0
        """How many ABs that follow the user run."""
        self.driving = 0
        """How many ABs that take the robot somewhere run (a move, following the user)."""
        self.drove = False
        """One of them ran since the last posed line."""
        self.held: Row | None = None
        """The last line with the robot's and the user's poses (they hold until the next)."""

    def feed(self, row: Row, ctx: Context) -> None:
        self.feeder(row["kind"])(row, ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None]:
        if kind == "start":
            return self._start
        if kind == "end":
            return self._end
        return self._posed

    def _start(self, row: Row, ctx: Context) -> None:
        ab = ctx.ab  # (the context's: None when the line names no AB)
        if ab is not None:
            if ctx.follows:  # (how many ABs follow the user, take the robot somewhere)
                self.following += 1
            if ctx.travels:
                self.driving += 1
                self.drove = True
            if ab.text and row.get("robot") is not None:
                self.talking[ab.id] = _Talk(ab.id, row, None, ab.words)
        self._posed(row, ctx)

    def _end(self, row: Row, ctx: Context) -> None:
        ab = row.get("ab")
        if isinstance(ab, int):
            if ctx.follows:  # (a forged trace's end of an AB never started: not below 0)
                self.following = max(0, self.following - 1)
            if ctx.travels:
                self.driving = max(0, self.driving - 1)
            talk = self.talking.pop(ab, None)
            if talk is not None and talk.words is None and ctx.ab is not None:
                talk.words = ctx.ab.words
                for posed in talk.pending:
                    if self._pose(talk, posed.row, posed.mover, ctx, posed.driven, posed.held):
                        break
        self._posed(row, ctx)

    def _posed(self, row: Row, ctx: Context) -> None:
        """Any line: one with poses is judged for each utterance running, and held."""
        if row.get("robot") is not None and row.get("user") is not None:
            if self.talking:
                mover = _wheels(ctx)
                driven = self.driving > 0 or self.drove
                posed = _Posed(row, mover, driven, self.held)  # (one for every AB it waits in)
                for ab_id, talk in list(self.talking.items()):
                    if talk.words is None:
                        talk.pending.append(posed)
                    elif self._pose(talk, row, mover, ctx, driven, self.held):
                        del self.talking[ab_id]
            self.drove = False
            self.held = row

    def _pose(self, talk: _Talk, row: Row, mover: Blame | None, ctx: Context,
              driven: bool = True, held: Row | None = None) -> bool:
        """One posed line during ``talk``'s AB: True when it counts as leaving.
        ``driven``: something took the robot somewhere since the last posed line (else
        it did not move on its own: a user who walked into it pushed it). ``held``: the
        posed line before it, whose poses held until it."""
        t = float(row["t"])
        words = talk.words
        if words is None or t < words[0] - EPS or t > words[1] + EPS:
            return False
        robot, user = xy(row["robot"]), xy(row["user"])
        if (talk.was is None and held is not None and t > words[0] + EPS
                and not self.following and driven):
            # (the first line in its words comes after they began: where the robot was
            # as they began is where the line before it put it)
            talk.was = xy(held["robot"])
            talk.gap = math.dist(talk.was, xy(held["user"]))
        elif talk.was is None or self.following or not driven:
            talk.was = robot  # (from where its words began; following moves it on)
            talk.gap = math.dist(robot, user)
            return False
        # The robot leaves when the distance to the user grew, and its own motion grew it:
        # a user who walks off, or follows the robot that guides them, is not left.
        now = math.dist(robot, user)
        away = min(now - talk.gap, now - math.dist(talk.was, user))
        if away <= ctx.th.leave_distance + EPS:
            return False
        start = talk.row
        ab = ctx.abs.get(talk.ab)
        self.found.append(Leaving(int(start["seq"]), float(start["t"]), str(start.get("app")),
                                  str(start.get("text")), int(row["seq"]), round(away, 3),
                                  ctx.at(ab) if ab is not None else "", mover))
        return True

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        return sorted(self.found, key=lambda x: x.seq)


def _leaving_line(x: Leaving) -> str:
    moved = f", moved by {x.moved_by}" if x.moved_by is not None else ""
    return (f"seq {x.seq} t={x.t:g} {x.app} \"{_short(x.text)}\"{_where(x.at)}: "
            f"{x.away:g} m farther at seq {x.at_seq}{moved}")


# ---------------------------------------------------------------- elsewhere

def _travels(row: Row) -> bool:
    """A start of the app's own that takes the robot somewhere (a move, following the
    user): where its stream then speaks is where it chose to go. The restore-state
    policy's return is not one: it takes the robot back."""
    return row.get("reason") != "restore-state" and \
        any(c in TRAVEL_COMMANDS for c in str(row.get("command") or "").split("+"))


class _Elsewhere:
    """A suspended stream's first utterance after it resumed, spoken more than
    ``resume_distance`` from where the stream was suspended."""

    kinds: frozenset[str] | None = frozenset({"request", "suspend", "resume", "start"})

    def __init__(self) -> None:
        self.found: list[Elsewhere] = []
        self.suspended_at: dict[int, tuple[int, tuple[float, float]]] = {}
        self.resumed: dict[int, tuple[int, tuple[float, float]]] = {}
        self.last_start: Row | None = None
        self.returns: set[int] = set()
        """The restore-state policy's returns (their Command ids)."""

    def feed(self, row: Row, ctx: Context) -> None:
        kind = row["kind"]
        tree = row.get("tree")
        if kind == "request" and row.get("reason") == "restore-state":
            self.returns.update(command_ids(row))
        elif kind == "request" and isinstance(tree, int) and (
                row.get("reactive") is True or row.get("reason") == "asap"):
            # a reaction, or a newer request, takes the stream on from where the robot is
            self.suspended_at.pop(tree, None)
            self.resumed.pop(tree, None)
        elif kind == "suspend" and isinstance(tree, int) and ctx.robot is not None:
            back = self.resumed.pop(tree, None)
            if back is not None and not self.returns.isdisjoint(command_ids(row)):
                # (suspended again on its way back: it still returns to where it was)
                self.suspended_at[tree] = back
            else:  # (suspended again before it spoke: from here)
                self.suspended_at[tree] = (int(row["seq"]), ctx.robot)
        elif kind == "resume" and isinstance(tree, int) and tree in self.suspended_at:
            self.resumed[tree] = self.suspended_at.pop(tree)
            start = self.last_start
            if start is not None and start.get("ab") == row.get("ab"):
                self._start(start, ctx)  # it resumed speaking
        elif kind == "start":
            self._started(row, ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None]:
        return self._started if kind == "start" else self.feed

    def _started(self, row: Row, ctx: Context) -> None:
        self.last_start = row
        if self.resumed:
            self._start(row, ctx)

    def _start(self, row: Row, ctx: Context) -> None:
        tree = row.get("tree")
        if not isinstance(tree, int) or tree not in self.resumed:
            return
        if _travels(row):
            del self.resumed[tree]  # it resumed going somewhere: not the same place
            return
        if not row.get("text"):
            return
        seq, was = self.resumed.pop(tree)
        robot = row.get("robot")
        away = math.dist(xy(robot), was) if robot is not None else 0.0
        if away > ctx.th.resume_distance + EPS:
            ab = ctx.abs.get(row.get("ab", -1))
            self.found.append(Elsewhere(int(row["seq"]), float(row["t"]), str(row.get("app")),
                                        str(row.get("text")), seq, round(away, 3),
                                        ctx.at(ab) if ab is not None else ""))

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        return self.found


def _elsewhere_line(x: Elsewhere) -> str:
    return (f"seq {x.seq} t={x.t:g} {x.app} \"{_short(x.text)}\"{_where(x.at)}: {x.away:g} m "
            f"from where its stream was suspended (seq {x.suspend_seq})")


# ---------------------------------------------------------------- split exchanges

class _Splits:
    """Another application's utterance inside an exchange (docs/rules.md 7.4): between an
    answer and the end of the words that reply to it (any utterance, a reaction's
    too; a reply cut splits it as well), or, when the app replies with its next
    question or with something else than words at once, a non-reactive one before
    that; or a non-reactive one inside an explicit stream. An answer its app asks
    nothing for at once ends its exchange."""

    kinds: frozenset[str] | None = frozenset({"stream", "unload", "start", "end"})

    def __init__(self) -> None:
        self.found: dict[int, Split] = {}
        self.streams: dict[str, Row] = {}
        self.live: list[Exchange] = []
        """The exchanges an utterance may still split, in the order they came (those
        over for good are dropped: :meth:`_live`)."""
        self.taken = 0
        """How many of the context's exchanges :attr:`live` has taken."""

    def feed(self, row: Row, ctx: Context) -> None:
        kind = row["kind"]
        app = str(row.get("app") or "")
        if kind == "stream":
            if row.get("text") == "open":
                self.streams[app] = row
            elif row.get("text") == "close":
                self.streams.pop(app, None)
        elif kind == "unload":
            self.streams.pop(app, None)
        elif kind == "start":
            self._start(row, ctx)
        elif kind == "end":
            self._end(row, ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None]:
        if kind == "start":
            return self._start
        if kind == "end":
            return self._end
        return self.feed

    def _start(self, row: Row, ctx: Context) -> None:
        if row.get("text"):
            self._utterance(row, str(row.get("app") or ""), ctx)

    def _end(self, row: Row, ctx: Context) -> None:
        if row.get("reason") == "interrupt":
            self._cut(row, str(row.get("app") or ""), ctx)

    def _utterance(self, row: Row, app: str, ctx: Context) -> None:
        t = float(row["t"])
        ab = ctx.abs.get(row.get("ab", -1))
        # part of a reaction: of its requests, or of a tree a reaction took over (what it
        # chains from its end and answer handlers is part of it too: docs/rules.md 7.1)
        reacting = ab is not None and (
            any(cid in ctx.reaction_cmds for cid in ab.ids)
            or ctx.tree_taken.get(ab.tree, math.inf) <= t + EPS)
        at = ctx.at(ab) if ab is not None else ""
        for ex in self._live(ctx, t):
            if ex.app == app or ex.t > t + EPS:
                continue
            if ex.kind == "none":
                continue  # (nothing asked for at the answer: the exchange ended with it)
            if ex.kind == "words" or not reacting:
                kind = "reply" if ex.kind == "words" else (
                    "question" if ex.kind == "question" else "answer")
                self._add(Split(int(row["seq"]), t, ex.app, app, str(row.get("text")), kind,
                                ex.seq, at))
        if not reacting:
            for other, opened in self.streams.items():
                if other != app:
                    self._add(Split(int(row["seq"]), t, other, app, str(row.get("text")),
                                    "stream", int(opened["seq"]), at))

    def _live(self, ctx: Context, t: float) -> list[Exchange]:
        """The exchanges not over at ``t``. One over stays over, as times only go on:
        its reply's words ended; it had nothing asked for at its answer (decided by
        the first request after it); or, replied to without words, its application has
        started something since. So each exchange is looked at until it is over, not
        at every utterance after it (a long trace's cost stays linear)."""
        fresh = ctx.exchanges[self.taken:]
        if fresh:
            self.live += fresh
            self.taken += len(fresh)
        self.live = [ex for ex in self.live if not (
            (ex.done is not None and ex.done <= t + EPS)
            or (ex.kind == "none" and ex.t < t - EPS)
            or (ex.kind == "other" and self._answered_since(ex, ctx, t)))]
        return self.live

    @staticmethod
    def _answered_since(ex: Any, ctx: Context, t: float) -> bool:
        """The app of an exchange replied with no words and has started something since
        its answer: that exchange is over."""
        return any(ab.app == ex.app and ex.t - EPS <= ab.start < t - EPS
                   for ab in ctx.tree_abs.get(ex.tree, ()))

    def _cut(self, row: Row, app: str, ctx: Context) -> None:
        ab = row.get("ab")
        for ex in sorted(ctx.replied.get(ab, ()) if isinstance(ab, int) else (),
                         key=lambda ex: ex.seq):  # (in the order they came)
            if ex.app == app:
                self._add(Split(int(row["seq"]), float(row["t"]), app,
                                ctx.interrupts.get(ab if isinstance(ab, int) else -1, "?"),
                                str(row.get("text") or ""), "reply", ex.seq, ex.at))

    def _add(self, split: Split) -> None:
        kept = self.found.get(split.seq)
        if kept is None or (kept.kind == "stream" and split.kind != "stream"):
            self.found[split.seq] = split

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        return sorted(self.found.values(), key=lambda s: s.seq)


def _split_line(s: Split) -> str:
    where = {
        "reply": f"between {s.app}'s answer (seq {s.anchor_seq}) and the end of its reply",
        "question": f"between {s.app}'s answer (seq {s.anchor_seq}) and its next question",
        "answer": f"between {s.app}'s answer (seq {s.anchor_seq}) and what it did next",
        "stream": f"inside {s.app}'s stream (opened seq {s.anchor_seq})",
    }[s.kind]
    return f'seq {s.seq} t={s.t:g} {s.by} "{_short(s.text)}"{_where(s.at)} {where}'


# ---------------------------------------------------------------- silences

class _Silences:
    """More than ``silence`` seconds with no robot output after a user's answer: no AB
    starts, and none runs that shows or says something (a gesture, a motion, words;
    a Q&A only while its prompt is said)."""

    kinds: frozenset[str] | None = frozenset({"start", "end"})

    def __init__(self) -> None:
        self.found: list[Silence] = []
        self.silent: list[tuple[Row, str, float | None]] = []
        """Answers not yet followed by output, each with when the silence after it
        began (None: output still runs)."""
        self.running: dict[int, tuple[str, float]] = {}
        """Running ABs -> their Command, and when their output ends (a Q&A's prompt's
        end; inf for anything else)."""

    def feed(self, row: Row, ctx: Context) -> None:
        kind = row["kind"]
        if kind == "start":
            self._start(row, ctx)
        elif kind == "end":
            self._end(row, ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None]:
        return self._start if kind == "start" else self._end if kind == "end" else self.feed

    def _start(self, row: Row, ctx: Context) -> None:
        t = ctx.now
        if self.silent:
            for end, at, since in self.silent:
                gap = round(t - since, 3) if since is not None else 0.0
                if gap > ctx.th.silence + EPS:
                    self.found.append(Silence(int(end["seq"]), float(end["t"]),
                                              str(end.get("app")), gap, at))
            self.silent = []
        ab = ctx.ab  # (the context's: None when the line names no AB)
        if ab is not None:
            command = ab.command
            listens = ctx.listens
            detail: dict[str, Any] = row.get("detail") or {}
            ends = detail.get("words_end") if listens else None
            self.running[ab.id] = (command,
                                float(ends) if isinstance(ends, (int, float)) else
                                (t if listens else math.inf))

    def _end(self, row: Row, ctx: Context) -> None:
        t = ctx.now
        ab = row.get("ab")
        if isinstance(ab, int):
            self.running.pop(ab, None)
        if ctx.exchanges and ctx.exchanges[-1].seq == row.get("seq"):
            self.silent.append((row, ctx.exchanges[-1].at, self._quiet_from(t)))
        elif self.silent and not self._showing(t):
            self.silent = [(r, at, t if since is None else since)
                           for r, at, since in self.silent]

    def _showing(self, t: float) -> bool:
        """Some running AB shows or says something at ``t``."""
        return any(ends > t + EPS for _c, ends in self.running.values())

    def _quiet_from(self, t: float) -> float | None:
        return None if self._showing(t) else t

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        for row, at, since in self.silent:
            if since is not None and ctx.t - since > ctx.th.silence + EPS:
                self.found.append(Silence(int(row["seq"]), float(row["t"]),
                                          str(row.get("app")), None, at))
        return sorted(self.found, key=lambda s: s.seq)


def _silence_line(s: Silence) -> str:
    gap = "until the end" if s.gap is None else f"{s.gap:g} s"
    return f"seq {s.seq} t={s.t:g} after {s.app}'s answer{_where(s.at)}: silent {gap}"


# ---------------------------------------------------------------- stuck

@dataclass(init=False)
class _Command:
    """(Its ``__init__`` written out, as ``Ab``'s is: compiled.)"""

    id: int
    app: str
    t: float
    seq: int
    pred: int | None
    """The Command ahead of it in its stream, if known."""
    devices: frozenset[str]
    """The devices its AB needs, as its request says (a request names its first
    Command's: empty for a chain's later ones)."""
    done: bool

    def __init__(self, id: int, app: str, t: float, seq: int, pred: int | None,
                 devices: frozenset[str] = frozenset(), done: bool = False) -> None:
        self.id, self.app, self.t, self.seq, self.pred = id, app, t, seq, pred
        self.devices, self.done = devices, done


@dataclass(init=False)
class _Running:
    """A Command's ABs (feedback iterations) as they run. (Its ``__init__`` written out,
    as ``Ab``'s is: compiled.)"""

    running: set[int]
    streak: float
    """When its current run of back-to-back ABs began."""
    last_end: float
    iterated: bool
    """An iteration (not the first AB) started in the current streak."""

    def __init__(self) -> None:
        self.running = set()
        self.streak, self.last_end, self.iterated = 0.0, -1.0, False


class _Stuck:
    """An application whose Commands wait behind its own endless loop, that searches
    for a user it never sees, whose Commands are still waiting at the end, or an
    atomic behavior that starts and never ends."""

    kinds: frozenset[str] | None = None

    def __init__(self) -> None:
        self.commands: dict[int, _Command] = {}
        self.waiting: dict[str, dict[int, _Command]] = {}
        self.behind: dict[int, list[int]] = {}
        self.runs: dict[int, _Running] = {}
        self.checks: list[tuple[float, int, int]] = []
        self.stuck: dict[str, Stuck] = {}
        self.t = 0.0
        self.following: dict[int, list[float | str]] = {}
        """ABs that follow the user (Tracking Human) -> [start, end (inf while it runs),
        app]: while the robot follows its user, another application's Commands that wait
        for the wheels are not stuck (the user leads: docs/rules.md 7.6 (1))."""

    def feed(self, row: Row, ctx: Context) -> None:
        self.feeder(row["kind"])(row, ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None]:
        return {"request": self._request, "start": self._start, "end": self._end,
                "cancel": self._cancel, "unload": self._unload}.get(kind, self._tick)

    def _tick(self, row: Row, ctx: Context) -> None:
        """Any line: the checks due before its time are made."""
        t = ctx.now
        if t > self.t + EPS:
            self._check(ctx, before=t)
            self.t = t

    def _request(self, row: Row, ctx: Context) -> None:
        self._tick(row, ctx)
        if row.get("reason") != "restart":
            # (a Command cut to start again has started once, as a feedback Command's
            # next iteration has: it is not counted as waiting again)
            self._requested(row, ctx)

    def _start(self, row: Row, ctx: Context) -> None:
        self._tick(row, ctx)
        ab = ctx.ab  # (the context's: None when the line names no AB)
        if ab is None:
            self._started(row, command_ids(row), (row.get("detail") or {}).get("iteration"),
                          SEARCH_DEVICE in (row.get("devices") or ()), None,
                          str(row.get("app") or ""), ctx)
            return
        if ctx.follows:
            self.following[ab.id] = [ctx.now, math.inf, ab.app]
        self._started(row, ab.ids, ab.iteration, SEARCH_DEVICE in ab.devices, ab.id, ab.app,
                      ctx)

    def _end(self, row: Row, ctx: Context) -> None:
        self._tick(row, ctx)
        t = ctx.now
        ab = row.get("ab")
        if isinstance(ab, int) and ctx.follows and ab in self.following:
            self.following[ab][1] = t
        detail: dict[str, Any] = row.get("detail") or {}
        cid = detail.get("command_id")
        run = self.runs.get(cid) if isinstance(cid, int) else None
        if run is not None and isinstance(ab, int):
            run.running.discard(ab)
            run.last_end = t

    def _cancel(self, row: Row, ctx: Context) -> None:
        self._tick(row, ctx)
        for cid in command_ids(row):
            self._done(cid)

    def _unload(self, row: Row, ctx: Context) -> None:
        self._tick(row, ctx)
        for command in list(self.waiting.pop(str(row.get("app") or ""), {}).values()):
            command.done = True

    def _requested(self, row: Row, ctx: Context) -> None:
        app = str(row.get("app") or "")
        before = row.get("before")
        pred = None
        if isinstance(before, int) and before in ctx.abs and ctx.abs[before].ids:
            pred = ctx.abs[before].ids[0]  # (a forged start line may name no Command)
        t = float(row["t"])
        devices = frozenset(str(d) for d in row.get("devices") or ())
        for cid in command_ids(row):
            command = _Command(cid, app, t, int(row["seq"]), pred, devices)
            devices = frozenset()
            self.commands[cid] = command
            self.waiting.setdefault(app, {})[cid] = command
            if pred is not None:
                self.behind.setdefault(pred, []).append(cid)
            heapq.heappush(self.checks, (t + ctx.th.stuck_after, int(row["seq"]), cid))
            pred = cid

    def _done(self, cid: int) -> None:
        command = self.commands.get(cid)
        if command is not None and not command.done:
            command.done = True
            self.waiting.get(command.app, {}).pop(cid, None)

    def _started(self, row: Row, ids: tuple[int, ...], iteration: object, searches: bool,
                 ab: int | None, app: str, ctx: Context) -> None:
        """A start line's Commands (its AB's, as the context took them in when it has
        one): its ``iteration`` detail, whether it ``searches`` for the user, its AB."""
        t = ctx.now
        for cid in ids:
            self._done(cid)
            run = self.runs.get(cid)
            if run is None:
                run = self.runs[cid] = _Running()
            if not run.running and abs(run.last_end - t) > EPS:
                run.streak, run.iterated = t, False  # a new run of back-to-back ABs
                for waiter in self.behind.get(cid, ()):
                    command = self.commands[waiter]
                    if not command.done:
                        due = max(command.t, t) + ctx.th.stuck_after
                        heapq.heappush(self.checks, (due, command.seq, waiter))
            if iteration:
                run.iterated = True
                if searches:
                    self._searching(row, app, cid, run, ctx)
            if ab is not None:
                run.running.add(ab)

    def _searching(self, row: Row, app: str, cid: int, run: _Running, ctx: Context) -> None:
        since = max(run.streak, ctx.last_seen)
        t = ctx.now
        if app not in self.stuck and t - since > ctx.th.search_after + EPS:
            self.stuck[app] = Stuck(app, round(since + ctx.th.search_after, 3),
                                    int(row["seq"]), cid, round(since, 3), "search",
                                    ctx.cmd_at.get(cid, ""))

    def _check(self, ctx: Context, before: float) -> None:
        while self.checks and self.checks[0][0] < before - EPS:
            due, _, cid = heapq.heappop(self.checks)
            command = self.commands[cid]
            if command.done or command.app in self.stuck or command.pred is None:
                continue
            run = self.runs.get(command.pred)
            if run is None or not run.running or not run.iterated:
                continue  # not behind a loop now: a new run of it schedules a new check
            since = max(command.t, run.streak) + ctx.th.stuck_after
            if since > due + EPS:
                heapq.heappush(self.checks, (since, command.seq, cid))
                continue
            loop = ctx.abs.get(ctx.cmd_ab.get(command.pred, -1))
            self.stuck[command.app] = Stuck(
                command.app, round(since, 3), command.seq, cid, command.t, "loop",
                ctx.cmd_at.get(cid, ""),
                None if loop is None else Blame(loop.app, loop.id, loop.command,
                                                ctx.at(loop), "its own loop"))

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        end = ctx.t
        self._check(ctx, before=end)
        for ab in sorted(ctx.running.values(), key=lambda a: a.seq):
            if end - ab.start > ctx.th.stuck_after + EPS and ab.app not in self.stuck:
                self.stuck[ab.app] = Stuck(  # (a forged start line may name no Command: -1)
                    ab.app, round(ab.start + ctx.th.stuck_after, 3), ab.seq,
                    ab.ids[0] if ab.ids else -1,
                    ab.start, "ab", ctx.at(ab),
                    Blame(ab.app, ab.id, ab.command, ctx.at(ab), "never ended"))
        for app, waiting in self.waiting.items():
            late = [c for c in waiting.values()
                    if not c.done and end - c.t - self._followed(app, c.t, end)
                    > ctx.th.stuck_after + EPS]
            if late and app not in self.stuck:
                first = min(late, key=lambda c: c.seq)
                self.stuck[app] = Stuck(app, round(first.t + ctx.th.stuck_after, 3),
                                        first.seq, first.id, first.t, "end",
                                        ctx.cmd_at.get(first.id, ""), self._in_way(ctx, first))
        return sorted(self.stuck.values(), key=lambda s: (s.t, s.seq))

    def _followed(self, app: str, lo: float, hi: float) -> float:
        """How long within [lo, hi] another application's AB followed the user."""
        return covered(((float(a), float(b)) for a, b, who in self.following.values()
                        if who != app), lo, hi)

    @staticmethod
    def _in_way(ctx: Context, command: _Command) -> Blame | None:
        """What ran when the trace ended on the devices a waiting Command's AB needs
        (as its AB or its request says; None when neither says)."""
        mine = next((ab for ab in ctx.abs.values() if command.id in ab.ids), None)
        devices = mine.devices if mine is not None else command.devices
        for ab in ctx.running.values():
            if ab.devices & devices:
                return Blame(ab.app, ab.id, ab.command, ctx.at(ab), "ran at the end")
        return None


def _stuck_line(s: Stuck) -> str:
    why = {"loop": "behind its own feedback loop", "search": "searching for an unseen user",
           "end": "still waiting at the end", "ab": "an atomic behavior that never ends"}
    behind = f"; {s.behind}" if s.behind is not None and s.kind != "ab" else ""
    return (f"seq {s.seq} t={s.t:g} {s.app}: Command {s.command_id}{_where(s.at)} "
            f"from {s.since:g} s, {why.get(s.kind, s.kind)}{behind}")


# ---------------------------------------------------------------- the user's voice

@dataclass
class _Said:
    seq: int
    t: float
    text: str
    backchannel: bool = False


class _BargeIn:
    """The robot's words running on over its user (docs/rules.md 7.5): from the user's
    first word over an utterance to its words stopping, more than the slack plus the
    word under way. A backchannel is no barge-in; speech the robot cannot hear (out of
    range, or a robot that hears only in its Q&As) is not measured."""

    kinds: frozenset[str] | None = frozenset({"user", "hear", "end"})

    def __init__(self) -> None:
        self.found: list[BargeIn] = []
        self.said: list[_Said] = []
        self.times: list[float] = []

    def feed(self, row: Row, ctx: Context) -> None:
        kind = row["kind"]
        if kind == "user":
            if row.get("action") == "say" and (row.get("detail") or {}).get("heard"):
                said = _Said(int(row["seq"]), float(row["t"]), str(row.get("text") or ""))
                if not self.said:
                    ctx.reroute()  # (end lines matter from now on: :meth:`feeder`)
                self.said.append(said)
                self.times.append(said.t)
        elif kind == "hear" and row.get("reason") == "backchannel" and self.said:
            self.said[-1].backchannel = True
        elif kind == "end":
            self._end(row, ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None] | None:
        """An end line is judged once the user has said something (before, no words of
        theirs ran over it: a loop's many end lines then go to nothing)."""
        if kind == "end":
            return self._end if self.said else None
        return self.feed

    def _end(self, row: Row, ctx: Context) -> None:
        ab = ctx.ab  # (the context's: the AB the line ends, if it started)
        if ab is not None and ab.text and ab.words is not None and ab.end is not None:
            self._ended(ab, ctx)

    def _ended(self, ab: Ab, ctx: Context) -> None:
        # (the words as planned, where the start line said: a cut one's end line says
        # them as said, up to the cut)
        ws, we = ab.planned or ab.words or (0.0, 0.0)
        words = len(ab.text.split()) or 1
        per_word = (we - ws) / words
        stopped = min(ab.end or we, we)
        allowed = ctx.th.barge_in_slack + per_word
        i = bisect.bisect_right(self.times, ws + EPS)  # (over its words: after they began)
        while i < len(self.said) and self.said[i].t < stopped - EPS:
            said = self.said[i]
            i += 1
            if said.backchannel:
                continue
            latency = stopped - said.t
            if latency > allowed + EPS:
                self.found.append(BargeIn(said.seq, said.t, said.text, ab.app, ab.command,
                                          stopped if stopped < we - EPS else None,
                                          round(latency, 3), round(allowed, 3), ctx.at(ab)))
            break  # (the first words over it are what it had to stop for)

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        return sorted(self.found, key=lambda b: b.seq)


def _barge_in_line(b: BargeIn) -> str:
    ran = "ran to its end" if b.stopped is None else f"stopped at t={b.stopped:g}"
    return (f"seq {b.seq} t={b.t:g} \"{_short(b.text, 20)}\" over {b.app} {b.command}"
            f"{_where(b.at)}: {ran}, {b.latency:g} s (allowed {b.allowed:g} s)")


class _Ignored:
    """User speech an application took (a hear line names it) that it did not answer:
    its reaction's first start came more than the answer slack after what the rules
    put before it, or it asked for nothing. Where its reaction asked for nothing, the
    finding names the handler that took the words (its ``handler`` line, in the
    document its ``load`` line names)."""

    kinds: frozenset[str] | None = frozenset({"user", "hear", "handler", "load"})

    def __init__(self) -> None:
        self.taken: list[tuple[int, float, str, str]] = []
        self.user: tuple[int, str] | None = None
        self.documents: dict[str, str] = {}
        """Each application's document, by its load line."""
        self.handled: dict[int, str] = {}
        """A taking (its index) -> the handler that took the words (``doc:line:col``)."""

    def feed(self, row: Row, ctx: Context) -> None:
        kind = row["kind"]
        if kind == "user" and row.get("action") == "say":
            self.user = (int(row["seq"]), str(row.get("text") or ""))
        elif kind == "hear" and row.get("app") and self.user is not None:
            self.taken.append((self.user[0], float(row["t"]), self.user[1], str(row["app"])))
        elif kind == "handler" and self.taken and len(self.taken) - 1 not in self.handled:
            _seq, t, _text, app = self.taken[-1]
            detail = row.get("detail") or {}
            line, col = detail.get("line"), detail.get("col")
            document = self.documents.get(app)
            if row.get("app") == app and abs(float(row["t"]) - t) <= EPS and document \
                    and isinstance(line, int) and isinstance(col, int):
                self.handled[len(self.taken) - 1] = f"{document}:{line}:{col}"
        elif kind == "load":
            document = (row.get("detail") or {}).get("document")
            if isinstance(document, str):
                self.documents[str(row.get("app") or "")] = document

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        mine = {(r.t, r.app): r for r in reactions if r.event == "speech"}
        found: list[Finding] = []
        for i, (seq, t, text, app) in enumerate(self.taken):
            r = mine.get((t, app))
            allowed = ctx.th.answer_slack + (r.residual if r is not None else 0.0)
            answered = r.first_start if r is not None else None
            if answered is None and ctx.t - t <= allowed + EPS:
                continue  # (the trace ended before it was due)
            if r is not None and self._withdrawn(i, r, t + allowed, ctx):
                continue
            if answered is None or answered - t > allowed + EPS:
                at = (r.at if r is not None else "") or self.handled.get(i, "")
                found.append(Ignored(seq, t, text, app, answered, round(allowed, 3), at))
        return found


    def _withdrawn(self, i: int, r: Reaction, due: float, ctx: Context) -> bool:
        """The user's own later words to the same application cancelled its answer before
        it was due (docs/rules.md section 8: "Stop." over an answer still to come)."""
        cancelled = [ctx.cancelled.get(cid) for cid in r.commands]
        if not r.commands or any(c is None for c in cancelled):
            return False
        gone = max(c for c in cancelled if c is not None)
        if gone > due + EPS or (r.first_start is not None and r.first_start < gone - EPS):
            return False
        app, t = self.taken[i][3], self.taken[i][1]
        return any(other == app and t + EPS < when <= gone + EPS
                   for _s, when, _x, other in self.taken[i + 1:])


def _ignored_line(x: Ignored) -> str:
    when = "never answered" if x.answered is None else \
        f"answered {x.answered - x.t:.3g} s later"
    return (f"seq {x.seq} t={x.t:g} \"{_short(x.text, 20)}\" taken by {x.app}"
            f"{_where(x.at)}: {when} (allowed {x.allowed:g} s)")


_PAUSE = re.compile(r"goes on after ([0-9.]+) s")


class _Recovery:
    """An utterance cut by user speech no application took (a hear line ``nomatch``, then
    its barge-in cut) that does not start again within the pause the cut line gives
    plus the slack."""

    kinds: frozenset[str] | None = frozenset({"interrupt", "end", "request", "start"})

    def __init__(self) -> None:
        self.pauses: dict[int, float] = {}
        """A falsely cut AB -> the robot's pause."""
        self.cut: dict[int, tuple[int, float]] = {}
        """A falsely cut AB -> its end line and when its words stopped."""
        self.again: dict[int, int] = {}
        """The AB that starts it again -> the cut AB."""
        self.found: list[Recovery] = []

    def feed(self, row: Row, ctx: Context) -> None:
        kind = row["kind"]
        ab = row.get("ab")
        if not isinstance(ab, int):
            return
        reason = row.get("reason")
        if kind == "interrupt" and reason == "barge-in":
            found = _PAUSE.search(str(row.get("text") or ""))
            if found is not None:
                if self._idle():
                    ctx.reroute()  # (the other kinds matter from now on: :meth:`feeder`)
                self.pauses[ab] = float(found.group(1))
        elif kind == "end" and reason == "barge-in" and ab in self.pauses:
            self.cut[ab] = (int(row["seq"]), float(row["t"]))
        elif kind == "request" and reason == "restart":
            before = row.get("before")
            if isinstance(before, int) and before in self.cut:
                self.again[ab] = before
        elif kind == "start" and ab in self.again:
            self._check(self.again.pop(ab), float(row["t"]), ctx)

    def feeder(self, kind: str) -> Callable[[Row, Context], None] | None:
        """While no falsely cut AB is known (:meth:`_idle`), only an interrupt line
        matters: a loop's many start and end lines then go to nothing."""
        if kind != "interrupt" and self._idle():
            return None
        return self._start if kind == "start" else self._end if kind == "end" else self.feed

    def _idle(self) -> bool:
        return not (self.pauses or self.cut or self.again)

    def _start(self, row: Row, ctx: Context) -> None:
        """A start line matters only while a cut AB waits to start again."""
        if self.again:
            self.feed(row, ctx)
            if self._idle():
                ctx.reroute()  # (back to interrupt lines alone)

    def _end(self, row: Row, ctx: Context) -> None:
        """An end line matters only while a falsely cut AB's pause is known."""
        if self.pauses:
            self.feed(row, ctx)

    def _check(self, cut: int, started: float | None, ctx: Context) -> None:
        seq, t = self.cut.pop(cut)
        allowed = self.pauses.pop(cut) + ctx.th.recovery_slack
        if started is None and ctx.t - t <= allowed + EPS:
            return  # (the trace ended before it was due)
        if started is None or started - t > allowed + EPS:
            ab = ctx.abs.get(cut)
            self.found.append(Recovery(seq, t, ab.app if ab else "", ab.command if ab else "",
                                       started, round(allowed, 3), ctx.at(ab) if ab else ""))

    def finish(self, ctx: Context, reactions: Sequence[Reaction]) -> Sequence[Finding]:
        for cut in sorted(self.cut):
            self._check(cut, None, ctx)
        return sorted(self.found, key=lambda r: r.seq)


def _recovery_line(x: Recovery) -> str:
    when = "never went on" if x.resumed is None else f"went on {x.resumed - x.t:.3g} s later"
    return (f"seq {x.seq} t={x.t:g} {x.app} {x.command}{_where(x.at)}: cut by words no "
            f"application took, {when} (allowed {x.allowed:g} s)")


# ---------------------------------------------------------------- the table

def _late() -> Finder:
    return _Reactions(lambda r: r.late)


def _unheard() -> Finder:
    return _Reactions(lambda r: r.unheard)


_FINDERS: dict[str, tuple[Callable[[], Finder], Callable[[Any], str],
                          Callable[[Any, Wheels], Whose]]] = {
    "late": (_late, _reaction_line, blame.reaction),
    "unheard": (_unheard, _unheard_line, blame.reaction),
    "unfaced": (_Unfaced, _unfaced_line, blame.unfaced),
    "leaving": (_Leaving, _leaving_line, blame.leaving),
    "elsewhere": (_Elsewhere, _elsewhere_line, blame.elsewhere),
    "splits": (_Splits, _split_line, blame.split),
    "silences": (_Silences, _silence_line, blame.silence),
    "stuck": (_Stuck, _stuck_line, blame.stuck),
    "barge_in": (_BargeIn, _barge_in_line, blame.barge_in),
    "ignored": (_Ignored, _ignored_line, blame.ignored),
    "recovery": (_Recovery, _recovery_line, blame.recovery),
}
"""Each measure's finder, its line in ``prima judge``'s table, and whose its findings
are, by key (the light part of each entry, name and threshold, is its
:class:`~._thresholds.Limit`)."""

MEASURES: list[Measure] = [
    Measure(m.key, m.title, m.allowed, m.finds, *_FINDERS[m.key]) for m in LIMITS]
"""Every measure, in the order reports show them: the registry every reader of
findings goes through (the judge, its report, ``prima sweep``'s rows, ``prima
check``'s attribution, ``prima live``, the MCAP recording). :func:`registered` adds
one for a while."""


@contextmanager
def registered(*measures: Measure) -> Iterator[None]:
    """While inside, ``measures`` are measures like the others (after them): judged,
    reported, thresholded (``max_<key>``), a row of ``prima sweep``'s table, attributed
    by ``prima check``. For a measure tried out, or a test's scratch one; a measure of
    PRIMA's own is an entry of :data:`~._thresholds.LIMITS` and of the finders' table."""
    known = {m.key for m in MEASURES}
    fresh = [m for m in measures if m.key not in known]
    if len(fresh) != len(measures) or len({m.key for m in fresh}) != len(fresh):
        raise ValueError("a measure is registered once, under a key of its own")
    MEASURES.extend(fresh)
    LIMITS.extend(fresh)
    try:
        yield
    finally:
        for m in fresh:
            MEASURES.remove(m)
            LIMITS.remove(m)


def measure(key: str) -> Measure:
    """The measure of that key."""
    for m in MEASURES:
        if m.key == key:
            return m
    raise KeyError(key)
