"""What the page shows, gathered from a trace's rows (the jsonl dicts)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

Row = Mapping[str, Any]

USER_SAYS_FOR = 3.0
"""Seconds a user's words (or action) stay in their bubble."""

INSTANT = 0.05
"""The width (s) of the bar of an atomic behavior that took no time."""


@dataclass
class Bar:
    """One atomic behavior on one device."""

    ab: int
    app: str
    device: str
    start: float
    end: float
    command: str
    label: str


@dataclass
class Mark:
    """A hold, a release, a suspension (a span until its resumption) or a cut."""

    kind: str
    ab: int | None
    app: str
    device: str
    start: float
    end: float
    row: int
    """Index of its trace line."""


@dataclass
class Bubble:
    """Words (or an action) shown beside the robot or the user from ``start`` to ``end``."""

    who: str
    start: float
    end: float
    text: str


@dataclass
class Model:
    """The trace, digested: bars, marks, poses, bubbles and the table's rows."""

    rows: list[dict[str, Any]]
    """The trace's lines but its pose samples: the table's rows."""
    end: float
    apps: list[str] = field(default_factory=list)
    devices: list[str] = field(default_factory=list)
    bars: list[Bar] = field(default_factory=list)
    marks: list[Mark] = field(default_factory=list)
    bubbles: list[Bubble] = field(default_factory=list)
    robot: list[tuple[float, float, float, float]] = field(default_factory=list)
    """(t, x, y, heading) of the robot, in time order."""
    user: list[tuple[float, float, float, float]] = field(default_factory=list)
    abs: dict[int, dict[str, Any]] = field(default_factory=dict)
    """AB id -> its start row, end row (if it ended) and the indices of its lines."""


def _label(row: Row) -> str:
    text = row.get("text")
    command = str(row.get("command") or "?")
    return f'{command} "{text}"' if text else command


def _user_text(row: Row) -> str:
    action = row.get("action")
    target = (row.get("detail") or {}).get("target")
    if action == "say":
        heard = "" if (row.get("detail") or {}).get("heard", True) else " (not heard)"
        return f'"{row.get("text") or ""}"{heard}'
    words = {"touch": "touches the robot", "follow": "follows the robot", "stop": "stops",
             "walk": f"walks to {target}", "leave": f"walks away to {target}",
             "arrive": f"arrives at {target}"}
    return f"[{words.get(str(action), str(action))}]"


def _pose(row: Row, who: str) -> tuple[float, float, float, float] | None:
    pose = row.get(who)
    if not isinstance(pose, Mapping):
        return None
    return (float(row["t"]), float(pose["x"]), float(pose["y"]), float(pose["heading"]))


NO_DEVICE = "(no device)"
"""The timeline's row for an atomic behavior that occupies no device."""


def build(rows: Sequence[Row]) -> Model:
    """Digest a trace's rows (in trace order)."""
    model = Model(rows=[dict(r) for r in rows if r["kind"] != "pose"],
                  end=max((float(r["t"]) for r in rows), default=0.0))
    for row in rows:
        for who, poses in (("robot", model.robot), ("user", model.user)):
            pose = _pose(row, who)
            if pose is not None and (not poses or poses[-1] != pose):
                poses.append(pose)
    builder = _Builder(model)
    for i, row in enumerate(model.rows):
        builder.feed(i, row)
    builder.finish()
    return model


class _Builder:
    """Feeds the table's rows, one at a time, into the model's bars, marks and bubbles."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.running: dict[int, int] = {}
        """AB -> its start line, while it runs."""
        self.suspended: dict[int, int] = {}
        """AB -> its suspend line, while it is suspended."""
        self.held: dict[str, list[str]] = {}
        """An application -> the devices of its latest hold (a release names none)."""

    def feed(self, i: int, row: Row) -> None:
        model = self.model
        app = str(row.get("app") or "")
        if app and app not in model.apps:
            model.apps.append(app)
        devices = [str(d) for d in row.get("devices") or ()]
        for device in devices:
            if device not in model.devices:
                model.devices.append(device)
        kind = row["kind"]
        if row.get("ab") is not None:
            self._ab(i, row, int(row["ab"]))
        if kind == "hold":
            self.held[app] = devices
        if kind in ("hold", "release", "interrupt", "cancel"):
            for device in devices or self.held.get(app, []):
                model.marks.append(Mark(kind, row.get("ab"), app, device, row["t"], row["t"], i))
        if kind == "user":
            model.bubbles.append(Bubble("user", row["t"], row["t"] + USER_SAYS_FOR,
                                        _user_text(row)))

    def _ab(self, i: int, row: Row, ab: int) -> None:
        """A line about an atomic behavior: its start, end, suspension or resumption."""
        model = self.model
        kind = row["kind"]
        model.abs.setdefault(ab, {"lines": []})["lines"].append(i)
        if kind == "start":
            self.running[ab] = i
            model.abs[ab]["start"] = i
        elif kind == "end" and ab in self.running:
            model.abs[ab]["end"] = i
            self._bar(self.running.pop(ab), float(row["t"]))
        if kind == "suspend":
            self.suspended[ab] = i
        elif kind in ("resume", "cancel", "end") and ab in self.suspended:
            self._suspension(self.suspended.pop(ab), float(row["t"]))

    def finish(self) -> None:
        """What is still running or suspended when the trace ends."""
        for i in self.running.values():
            self._bar(i, self.model.end)
        for i in self.suspended.values():
            self._suspension(i, self.model.end)
        self.model.devices.sort()
        if any(b.device == NO_DEVICE for b in self.model.bars) or any(
                m.device == NO_DEVICE for m in self.model.marks):
            self.model.devices.append(NO_DEVICE)

    def _bar(self, i: int, end: float) -> None:
        start = self.model.rows[i]
        t = float(start["t"])
        for device in start.get("devices") or [NO_DEVICE]:
            self.model.bars.append(Bar(int(start["ab"]), str(start.get("app") or ""),
                                       str(device), t, max(end, t + INSTANT),
                                       str(start.get("command") or "?"), _label(start)))
        if start.get("text"):
            self.model.bubbles.append(Bubble("robot", t, max(end, t + 1.0), str(start["text"])))

    def _suspension(self, i: int, end: float) -> None:
        """A span from the suspend line ``i`` until the stream resumed (or was dropped)."""
        row = self.model.rows[i]
        t = float(row["t"])
        for device in row.get("devices") or [NO_DEVICE]:
            self.model.marks.append(Mark("suspend", row.get("ab"), str(row.get("app") or ""),
                                         str(device), t, max(end, t + INSTANT), i))
