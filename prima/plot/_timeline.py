"""The device timeline of a run, as data: what ``prima plot`` draws.

Pure Python (no matplotlib): a run's jsonl records (``TraceLine.to_dict()``, or
:func:`prima.judge.load_trace`) become bars (one per atomic behavior and device
it occupied), the spans an application's stream waited (suspended, or held
back), and the world's ticks (the user's actions, the events posted).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from prima.trace import Pose

__all__ = ["Bar", "Pose", "Span", "Tick", "Timeline", "abbreviate", "timeline"]

_OVER = re.compile(r" on ([^,\s]+)")
"""The devices in a blended start's ``over`` detail (``over AB12 on locomotion``)."""

_ENDS_WAIT = frozenset({"start", "end", "cancel", "resume"})
"""What ends an AB's suspension or hold: the AB starts, ends, or is cancelled, or its
stream resumes."""
_MARKS = frozenset({"cancel", "interrupt", "failure", "error", "unload"})
"""Decisions marked on the application's row."""


@dataclass(frozen=True)
class Bar:
    """An atomic behavior on one device, from its ``start`` to its ``end``."""

    ab: int
    device: str
    app: str
    command: str
    t0: float
    t1: float
    text: str | None = None
    blended: bool = False
    """It shared this device with another AB (the blend policy)."""
    ended: bool = True
    """False: still running when the trace ended (``t1`` is the trace's end)."""


@dataclass(frozen=True)
class Span:
    """A while an application's AB waited: ``suspend`` (its stream lost a device) or
    ``hold`` (another application's hold, or the channel rule, kept it back)."""

    kind: str
    app: str
    ab: int | None
    command: str
    t0: float
    t1: float
    reason: str = ""


@dataclass(frozen=True)
class Tick:
    """A moment on a top row: ``user`` (what the user did) or ``event``."""

    row: str
    t: float
    label: str
    text: str | None = None
    """The words, when the user said something."""


@dataclass
class Timeline:
    """Everything ``prima plot`` draws of one run."""

    devices: list[str] = field(default_factory=list)
    """In the order they were first occupied."""
    apps: list[str] = field(default_factory=list)
    """In the order they were loaded (or first seen)."""
    bars: list[Bar] = field(default_factory=list)
    spans: list[Span] = field(default_factory=list)
    ticks: list[Tick] = field(default_factory=list)
    marks: list[tuple[float, str, str]] = field(default_factory=list)
    """Instant decisions on an application's row: (t, app, kind): release, cancel,
    interrupt, failure, error, unload."""
    robot: list[tuple[float, Pose]] = field(default_factory=list)
    user: list[tuple[float, Pose]] = field(default_factory=list)
    """The poses on every line that has them, in time order."""
    end: float = 0.0

    def speech(self) -> list[Bar]:
        """The robot's words: one bar per AB with text on the speaker (or, without a
        speaker row, on its first device)."""
        seen: set[int] = set()
        out = []
        for bar in self.bars:
            if bar.text and bar.ab not in seen and (bar.device == "speaker"
                                                    or "speaker" not in self.devices):
                seen.add(bar.ab)
                out.append(bar)
        return out


def abbreviate(command: str, parts: int = 2) -> str:
    """A grouped AB's name shortened: ``Speak+Gesture+PointByHand`` -> ``Speak+Gesture+...``."""
    names = command.split("+")
    if len(names) <= parts:
        return command
    return "+".join(names[:parts]) + "+..."


def _pose(value: Any) -> Pose | None:
    if not isinstance(value, Mapping):
        return None
    try:
        return (float(value["x"]), float(value["y"]), float(value.get("heading", 0.0)))
    except (KeyError, TypeError, ValueError):
        return None


def _user_label(row: Mapping[str, Any]) -> tuple[str, str | None]:
    action = str(row.get("action") or "user")
    text = row.get("text")
    if action == "say" and text:
        return f'"{text}"', str(text)
    return action, None


class _Builder:
    def __init__(self) -> None:
        self.out = Timeline()
        self.open: dict[int, Mapping[str, Any]] = {}
        self.waiting: dict[tuple[str, str, int | None], Mapping[str, Any]] = {}
        """(kind, app, ab) -> the suspend or hold record that began the wait."""

    def app(self, name: object) -> str:
        app = str(name) if name is not None else "?"
        if app not in self.out.apps:
            self.out.apps.append(app)
        return app

    def feed(self, row: Mapping[str, Any]) -> None:
        t = float(row["t"])
        self.out.end = max(self.out.end, t)
        kind = str(row["kind"])
        for who, poses in (("robot", self.out.robot), ("user", self.out.user)):
            pose = _pose(row.get(who))
            if pose is not None:
                poses.append((t, pose))
        ab = row.get("ab")
        ab = ab if isinstance(ab, int) else None
        app = None if row.get("app") is None else self.app(row.get("app"))
        if app is not None and ab is not None and kind in _ENDS_WAIT:
            for what in ("suspend", "hold"):
                self.close_key((what, app, ab), t)
        if kind in ("start", "end") and ab is not None:
            self.behavior(kind, ab, row, t)
        elif kind in ("suspend", "hold") and app is not None:
            self.waiting.setdefault((kind, app, ab), row)
        elif kind == "release":
            for key, held in list(self.waiting.items()):
                if key[0] == "hold" and held.get("reason") != "keep-channel":
                    self.close_key(key, t)
            if app is not None:
                self.out.marks.append((t, app, kind))
        elif kind in _MARKS and app is not None:
            self.out.marks.append((t, app, kind))
        elif kind == "user":
            label, text = _user_label(row)
            self.out.ticks.append(Tick("user", t, label, text))
        elif kind == "event":
            self.out.ticks.append(Tick("event", t, str(row.get("text") or "event")))

    def behavior(self, kind: str, ab: int, row: Mapping[str, Any], t: float) -> None:
        """An AB starts (its devices get rows) or ends (its bars are drawn)."""
        if kind == "start":
            for device in row.get("devices") or ():
                if device not in self.out.devices:
                    self.out.devices.append(str(device))
            self.open[ab] = row
            return
        start = self.open.pop(ab, None)
        if start is not None:
            self.bars(start, t, ended=True)

    def close_key(self, key: tuple[str, str, int | None], t: float) -> None:
        row = self.waiting.pop(key, None)
        if row is not None:
            self.out.spans.append(Span(key[0], key[1], key[2], str(row.get("command") or ""),
                                       float(row["t"]), t, str(row.get("reason") or "")))

    def bars(self, start: Mapping[str, Any], t1: float, ended: bool) -> None:
        detail = start.get("detail")
        over = detail.get("over") if isinstance(detail, Mapping) else None
        blended = set(_OVER.findall(str(over or "")))
        text = start.get("text")
        for device in start.get("devices") or ():
            self.out.bars.append(Bar(
                ab=int(start["ab"]), device=str(device), app=str(start.get("app") or "?"),
                command=str(start.get("command") or "AB"), t0=float(start["t"]), t1=t1,
                text=str(text) if text else None, blended=device in blended, ended=ended))

    def finish(self) -> Timeline:
        for start in list(self.open.values()):
            self.bars(start, self.out.end, ended=False)
        self.open.clear()
        for key in list(self.waiting):
            self.close_key(key, self.out.end)
        self.out.bars.sort(key=lambda b: (b.t0, b.ab, self.out.devices.index(b.device)))
        self.out.spans.sort(key=lambda s: (s.t0, s.app))
        return self.out


def timeline(rows: Iterable[Mapping[str, Any]]) -> Timeline:
    """The timeline of a run's jsonl records, in trace order."""
    builder = _Builder()
    for row in rows:
        builder.feed(row)
    return builder.finish()
