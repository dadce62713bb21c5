"""The trace of a run: one record per thing that happened, in order.

Records are frozen and serialise to a stable dict (``--format jsonl`` writes
one per line); :func:`format_text` renders them like the thesis' own tables
(Figures 5.3 and 5.9): numbered lines, simulated time, ``R`` (robot) or
``U`` (user), the application, the behavior with utterances quoted, and
``(o)`` where an event caused it. Golden traces are the text form.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any, Final, NoReturn

from prima.escape import json_line, terminal
from prima.mediator import DecisionKind
from prima.term import BOLD, DIM, PLAIN, Paint
from prima.vocab import TraceKind, Value

__all__ = ["APP_WIDTH", "Kind", "Pose", "RecordKind", "TextTrace", "TraceLine",
           "describe", "device_overlaps", "format_jsonl", "format_text", "jsonl_row",
           "rounded", "rounded_pose", "row_of", "user_words"]


Kind = TraceKind
"""What the run itself records (:class:`prima.vocab.TraceKind`); the mediator's
decisions are recorded with their own :class:`~prima.mediator.DecisionKind`."""


RecordKind = Kind | DecisionKind
"""The kind of a trace line: the run's own, or a mediator decision's."""

Pose = tuple[float, float, float]
"""x and y (m) on the map, heading (degrees, 0 = east, 90 = north)."""


@dataclass(frozen=True, init=False)
class TraceLine:
    """One record of a run. (Its ``__init__`` is written out, as the other records made
    once for everything that happens have theirs: compiled, it runs at C speed, where
    the one ``dataclass`` writes runs as Python; ``test_record.py`` checks it takes the
    fields in order, with their defaults.)"""

    t: float
    seq: int
    kind: RecordKind
    app: str | None = None
    ab: int | None = None
    tree: int | None = None
    command: str | None = None
    text: str | None = None
    devices: tuple[str, ...] | None = None
    reactive: bool | None = None
    reason: str | None = None
    action: str | None = None
    detail: Mapping[str, Value] = field(default_factory=dict)
    command_ids: tuple[int, ...] | None = None
    """All the Commands of a request, or of a grouped AB (the first is ``detail.command_id``)."""
    before: int | None = None
    """A request: the AB its first Command follows, if any."""
    robot: Pose | None = None
    """The robot's pose (x, y in metres, heading in degrees) at the line's time, on
    start, end, user, event and pose lines."""
    user: Pose | None = None
    """The user's pose, likewise (None in a scenario without a user)."""
    detectable: bool | None = None
    """With ``user``: whether the robot could see the user now if it looked their way
    (in camera range, nothing in between)."""

    def __init__(self, t: float, seq: int, kind: RecordKind, app: str | None = None,
                 ab: int | None = None, tree: int | None = None, command: str | None = None,
                 text: str | None = None, devices: tuple[str, ...] | None = None,
                 reactive: bool | None = None, reason: str | None = None,
                 action: str | None = None, detail: Mapping[str, Value] | None = None,
                 command_ids: tuple[int, ...] | None = None, before: int | None = None,
                 robot: Pose | None = None, user: Pose | None = None,
                 detectable: bool | None = None) -> None:
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "seq", seq)
        object.__setattr__(self, "kind", kind)
        object.__setattr__(self, "app", app)
        object.__setattr__(self, "ab", ab)
        object.__setattr__(self, "tree", tree)
        object.__setattr__(self, "command", command)
        object.__setattr__(self, "text", text)
        object.__setattr__(self, "devices", devices)
        object.__setattr__(self, "reactive", reactive)
        object.__setattr__(self, "reason", reason)
        object.__setattr__(self, "action", action)
        object.__setattr__(self, "detail", {} if detail is None else detail)
        object.__setattr__(self, "command_ids", command_ids)
        object.__setattr__(self, "before", before)
        object.__setattr__(self, "robot", robot)
        object.__setattr__(self, "user", user)
        object.__setattr__(self, "detectable", detectable)

    @classmethod
    def made(cls, t: float, seq: int, kind: RecordKind, fields: dict[str, Any]) -> TraceLine:
        """The line ``TraceLine(t, seq, kind, **fields)`` makes, made at a third of the
        cost (a run makes one for everything that happens): its fields are stored at
        once rather than one by one through the frozen class's guard."""
        if not _STORED_AT_ONCE:
            # (compiled: the fields given by position, to the native ``__init__``. By name,
            # its 18 keywords were parsed again for every line: some 10,000 instructions,
            # a fifth of a run of Fig. 5.7. ``fields`` a dict: each ``get`` a C call.)
            known = _DEFAULTS
            for name in fields:
                if name not in known:
                    _no_field(fields)
            return TraceLine(t, seq, kind, fields.get("app"), fields.get("ab"),
                             fields.get("tree"), fields.get("command"), fields.get("text"),
                             fields.get("devices"), fields.get("reactive"),
                             fields.get("reason"), fields.get("action"), fields.get("detail"),
                             fields.get("command_ids"), fields.get("before"),
                             fields.get("robot"), fields.get("user"),
                             fields.get("detectable"))
        if not fields.keys() <= _DEFAULTS.keys():
            _no_field(fields)
        line = object.__new__(cls)
        state = dict(_DEFAULTS)
        state.update(fields)
        state["t"], state["seq"], state["kind"] = t, seq, kind
        if "detail" not in fields:
            state["detail"] = {}
        line.__dict__.update(state)
        return line

    def to_dict(self) -> dict[str, object]:
        fields = (self.__dict__ if _STORED_AT_ONCE
                  else {name: getattr(self, name) for name in _DEFAULTS})
        return row_of(self.t, self.seq, self.kind, fields)


def _no_field(fields: Mapping[str, Any]) -> NoReturn:
    """Refuse fields a line does not have, as ``TraceLine(**fields)`` would."""
    unknown = sorted(fields.keys() - _DEFAULTS.keys())
    raise TypeError(f"TraceLine has no field {unknown[0]!r}")


_STORED_AT_ONCE = "__dict__" in vars(TraceLine)
"""Whether a line keeps its fields in a dict of its own, to be stored at once (not when
the module is compiled: a compiled class keeps its fields in fixed slots)."""


def _rounded(x: float, digits: int) -> float:
    """``round(x, digits)`` (the same float), worked out in floating point where that is
    exact. ``round`` finds the decimal nearest ``x`` exactly (some 2,000 instructions: a
    decimal string made and read back), and returns the float nearest it: that of ``k /
    10**digits``, which a float division gives exactly, ``k`` being the integer nearest
    ``x * 10**digits`` (exactly). The product's rounding is less than a millionth of its
    size: unless it lies that near halfway between two integers (or is huge, or not
    finite), the integer nearest it is ``k``. Else, and for a zero (its sign), ``round``."""
    # (the usual scales written out: compiled, ``10.0**digits`` is a generic power)
    scale = (1000.0 if digits == 3 else 10.0 if digits == 1 else 100.0 if digits == 2
             else 10.0**digits)
    y = x * scale
    if -1e12 < y < 1e12:
        k = math.floor(y + 0.5)
        if k and abs(y - k) < 0.4999:
            return k / scale
    return round(x, digits)


rounded: Final[Callable[[float, int], float]] = round if _STORED_AT_ONCE else _rounded
"""``round`` for the numbers of the lines (times, poses): where the module is compiled,
:func:`_rounded`, some ten times cheaper than ``round``; else ``round`` itself, one call
where :func:`_rounded` would run some twenty bytecodes."""
_NATIVE: Final = not _STORED_AT_ONCE
"""Whether this module is compiled (where :func:`_rounded` is the rounding of choice)."""

_DEFAULTS: dict[str, Any] = {
    f.name: None if f.default is dataclasses.MISSING else f.default
    for f in dataclasses.fields(TraceLine)}
"""Every field of a line, in order, with its default (``detail``'s is made per line)."""


def row_of(t: float, seq: int, kind: RecordKind, fields: Mapping[str, Any]) -> dict[str, object]:
    """The jsonl dict of ``TraceLine(t, seq, kind, **fields)`` (its :meth:`~TraceLine.to_dict`),
    made without the line: a judged run that writes no trace makes only these."""
    out: dict[str, object] = {"t": rounded(t, 3), "seq": seq, "kind": kind._value_}
    get = fields.get
    for name in _PLAIN:
        value = get(name)
        if value is not None:
            out[name] = value
    value = get("devices")
    if value is not None:
        out["devices"] = list(value)
    value = get("command_ids")
    if value is not None:
        out["command_ids"] = list(value)
    value = get("before")
    if value is not None:
        out["before"] = value
    value = get("detail")
    if value:
        out["detail"] = dict(sorted(value.items()))
    value = get("robot")
    if value is not None:
        out["robot"] = rounded_pose(value, 0)
    value = get("user")
    if value is not None:
        out["user"] = rounded_pose(value, 1, get("detectable"))
    return out


_ROUNDED: Final[list[tuple[object, dict[str, float]]]] = [(None, {}), (None, {})]
"""The robot's and the user's last pose and its rounded dict: a run's lines of one
instant, or of a still robot, carry the same pose (``Simulator.poses``). Compared by
value, not by identity: the compiled build passes a pose as three floats, not a tuple,
so it would never find the tuple it kept (and a pose back where it was is found too)."""


def rounded_pose(pose: Pose, which: int, detectable: bool | None = None) -> dict[str, Any]:
    """A pose as a jsonl line writes it (a dict of its own): ``which`` 0 the robot's, 1
    the user's, with whether they are ``detectable`` unless that is None."""
    kept = _ROUNDED[which]
    if kept[0] != pose:
        x, y, heading = pose
        if _NATIVE:  # (compiled: :func:`_rounded` called in C; ``rounded`` is a call by
            # name, its floats boxed and parsed again: some 400 instructions each)
            shown = {"x": _rounded(x, 3), "y": _rounded(y, 3), "heading": _rounded(heading, 1)}
        else:
            shown = {"x": round(x, 3), "y": round(y, 3), "heading": round(heading, 1)}
        kept = _ROUNDED[which] = (pose, shown)
    out = dict(kept[1])
    if detectable is not None:
        out["detectable"] = detectable
    return out


_PLAIN: Final = ("app", "ab", "tree", "command", "text", "reactive", "reason", "action")
"""The fields a jsonl line writes as they are, in its order."""


def _describe_start(line: TraceLine) -> str:
    d = line.detail
    parts = [line.command or "?"]
    if line.text:
        parts.append(f'"{line.text}"')
    args = d.get("args")
    if isinstance(args, str) and args:
        parts.append(args)
    if d.get("iteration"):
        parts.append(f"(iteration {d['iteration']})")
    return " ".join(parts)


def _describe_event(line: TraceLine) -> str:
    data = ", ".join(f"{key}={value!r}" for key, value in sorted(line.detail.items()))
    return f"event {line.text}" + (f": {data}" if data else "")


def _describe_send(line: TraceLine) -> str:
    said = f'sends to {line.detail.get("to")}: "{line.text}"'
    dropped = line.detail.get("dropped")
    return f"{said} (dropped: {dropped})" if dropped else said


def _describe_end(line: TraceLine) -> str | None:
    if "error" in line.detail:
        error = str(line.detail["error"])
        own = f"{line.command}: "  # the simulator names the Command (of a group, which)
        return f"{line.command} fails: {error.removeprefix(own)}"
    if line.reason in ("interrupt", "barge-in"):
        said, then = line.detail.get("spoken") or "", line.detail.get("interrupt") or ""
        if said:
            return f'{line.command} cut after "{said}", {then}'
        if line.detail.get("unspoken"):
            return f"{line.command} cut before its first word, {then}"
        return f"{line.command} cut, {then}"  # (it says nothing: a move's iteration)
    return None


def _describe_hold(line: TraceLine) -> str:
    return f"holds {line.command} back ({line.text})" if line.text else f"holds {line.command} back"


_DESCRIBE: Mapping[RecordKind, Callable[[TraceLine], str | None]] = {
    DecisionKind.LOAD: lambda line: (f"loads {line.detail.get('document', '')} "
                                     f"({line.detail.get('role', '')})"),
    DecisionKind.UNLOAD: lambda line: f"unloads the application ({line.reason})",
    DecisionKind.REQUEST: lambda _line: None,  # requests and ends: in the jsonl trace only
    DecisionKind.START: lambda line: _describe_start(line),
    DecisionKind.END: lambda line: _describe_end(line),
    DecisionKind.INTERRUPT: lambda line: f"is cut at {line.command} {line.text}",
    DecisionKind.CANCEL: lambda line: f"cancels {line.command}",
    DecisionKind.SUSPEND: lambda line: f"suspends its stream at {line.command}",
    DecisionKind.RESUME: lambda line: f"resumes its stream at {line.command}",
    DecisionKind.HOLD: _describe_hold,
    DecisionKind.RELEASE: lambda line: f"releases its hold ({line.reason})",
    DecisionKind.FAILURE: lambda line: f"ERROR: {line.text}",
    DecisionKind.BUDGET: lambda line: f"budget: {line.text}",
    DecisionKind.HEAR: lambda line: f"hears {line.text}",
    Kind.EVENT: _describe_event,
    Kind.USER: lambda line: user_words(line.action, line.text, line.detail),
    Kind.ERROR: lambda line: f"ERROR: {line.text}",
    Kind.SEND: lambda line: _describe_send(line),
    Kind.LOG: lambda line: f"log: {line.text}",
    Kind.POSE: lambda _line: None,  # the records below are in the jsonl trace only
    Kind.STATE: lambda _line: None,
    Kind.HANDLER: lambda _line: None,
    Kind.TIMER: lambda _line: None,
    Kind.STREAM: lambda _line: None,
    Kind.BLOCK: lambda _line: None,
    Kind.ZONE: lambda _line: None,
}
"""How each kind of line reads in the text trace (None: not shown there)."""

_REASON_SHOWN = frozenset({DecisionKind.START, DecisionKind.CANCEL, DecisionKind.SUSPEND,
                           DecisionKind.RESUME, DecisionKind.HOLD, DecisionKind.BUDGET,
                           DecisionKind.INTERRUPT, DecisionKind.HEAR})
"""Kinds whose text line ends with the mediation rule in brackets."""


def _describe(line: TraceLine) -> str | None:
    return _DESCRIBE[line.kind](line)


def describe(line: TraceLine) -> str:
    """What a line says, as the text trace's behavior column does (with its rule in
    brackets), or, for a line the text trace does not show, its kind and what it is
    about."""
    text = _describe(line)
    if text is None:
        text = f"{line.kind.value} {line.command or line.text or ''}".rstrip()
    marks = " (o)" if line.kind is Kind.EVENT or (line.kind is DecisionKind.START
                                                  and line.reactive) else ""
    why = f"  [{line.reason}]" if line.reason else ""
    return _escape(text + marks + why)


def user_words(action: str | None, text: str | None, detail: Mapping[str, object]) -> str:
    """What the user did, as the text trace words it: ``"words"`` (`` (not heard)``
    when the robot missed them), ``walks to hall``, ``touches the robot``, ..."""
    target = detail.get("target")
    if action == "say":
        heard = "" if detail.get("heard", True) else " (not heard)"
        return f'"{text or ""}"{heard}'
    if action == "touch":
        return "touches the robot" if target is None else "does not reach the robot to touch it"
    if action in ("walk", "leave"):
        return f"{'walks' if action == 'walk' else 'walks away'} to {target}"
    if action == "arrive":
        return f"arrives at {target}"
    if action == "follow":
        return "follows the robot"
    if action == "stop":
        return "stops"
    return str(action)


def format_jsonl(lines: Iterable[TraceLine]) -> str:
    """One JSON object per line, keys in a stable order."""
    return "".join(map(jsonl_row, lines))


def _escape(row: str) -> str:
    """Control characters (a newline in a Speak text, an escape sequence, C1) as escapes:
    a document cannot forge a row of the text trace or drive the terminal."""
    return terminal(row)


APP_WIDTH = 12
"""The text trace's app column: at least this wide, wider for a longer name."""


class TextTrace:
    """The text form of a trace, one row at a time: a run streams through it.

    The app column is as wide as the longest of ``apps`` (the applications the run
    may load), and at least :data:`APP_WIDTH`; ``paint`` colours the header and the
    rules' names for a terminal."""

    def __init__(self, apps: Iterable[str] = (), paint: Paint = PLAIN) -> None:
        self._n = 0
        self._last_start: dict[str | None, object] = {}
        self.width = max([APP_WIDTH, *map(len, map(terminal, apps))])
        self._paint = paint

    @property
    def header(self) -> str:
        """The table's header row."""
        return self._paint(f"  No.     time  R/U  {'app':<{self.width}} behavior", BOLD)

    def row(self, line: TraceLine) -> str | None:
        """The row for ``line``, or None if the text form does not show it."""
        text = _describe(line)
        if text is None:
            return None
        if line.kind is DecisionKind.START:
            # A feedback loop's iterations show once, and again after an interruption.
            command_id = line.detail.get("command_id")
            repeat = line.detail.get("iteration") and self._last_start.get(line.app) == command_id
            self._last_start[line.app] = command_id
            if repeat:
                return None
        who = "U" if line.kind is Kind.USER else "R"
        reactive_start = line.kind is DecisionKind.START and line.reactive
        mark = " (o)" if line.kind is Kind.EVENT or reactive_start else ""
        why = f"[{line.reason}]" if line.reason and line.kind in _REASON_SHOWN else ""
        app = _escape(line.app or "")
        # (the number, the time and R or U are digits and letters: nothing to escape)
        row = f"{self._n:5d} {line.t:8.2f}   {who}   {app:<{self.width}} " \
            + _escape(f"{text}{mark}")
        self._n += 1
        return row + ("  " + self._paint(_escape(why), DIM) if why else "")


def format_text(lines: Iterable[TraceLine], apps: Iterable[str] = ()) -> str:
    """The trace as a table like the thesis' figures (one behavior per row); the app
    column as wide as the longest name among ``apps`` and the lines'."""
    lines = list(lines)
    trace = TextTrace([*apps, *(line.app or "" for line in lines)])
    rows = [trace.header]
    rows += [row for row in map(trace.row, lines) if row is not None]
    return "\n".join(rows) + "\n"


def jsonl_row(line: TraceLine) -> str:
    """One line of the jsonl form (with its newline)."""
    return json_line(line.to_dict()) + "\n"


def device_overlaps(lines: Iterable[TraceLine]) -> list[str]:
    """Every moment two running atomic behaviors held the same device (should be none).

    Lines are taken in trace order, so at one instant an AB's end must come
    before the start of the next AB on its devices.
    """
    holder: dict[str, TraceLine] = {}
    problems = []
    for line in lines:
        if line.kind is DecisionKind.START:
            for device in line.devices or ():
                other = holder.get(device)
                if other is not None:
                    problems.append(f"t={line.t}: AB {line.ab} ({line.command}) started on "
                                    f"{device} held by AB {other.ab} ({other.command})")
                holder[device] = line
        elif line.kind is DecisionKind.END:
            for device in line.devices or ():
                if holder.get(device) is not None and holder[device].ab == line.ab:
                    del holder[device]
    return problems
