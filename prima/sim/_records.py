"""Plain records: poses, user actions, zone entries, pictures, scheduled events, zones.

All are frozen dataclasses with a ``to_dict()`` giving plain data (for JSON). Those a run
makes many of (poses, user actions) have their ``__init__`` written out: compiled, it runs
at C speed, where the one ``dataclass`` writes runs as Python.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from prima.sim._maps import Area
from prima.vocab import Value

__all__ = ["Picture", "Pose", "ScheduledEvent", "UserAction", "UserActionKind", "Zone",
           "ZoneEntry"]


@dataclass(frozen=True, init=False)
class Pose:
    """A position on the map (m) and a heading (deg, 0 = east, 90 = north)."""

    x: float
    y: float
    heading: float = 0.0

    def __init__(self, x: float, y: float, heading: float = 0.0) -> None:
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "heading", heading)

    def distance_to(self, x: float, y: float) -> float:
        return math.hypot(x - self.x, y - self.y)

    def to_dict(self) -> dict[str, float]:
        return {"x": self.x, "y": self.y, "heading": self.heading}


class UserActionKind(str, enum.Enum):
    """What the scripted user did (the trace prints these as ``U`` lines)."""

    SAY = "say"
    """Said something (``text``); ``heard`` tells whether the robot's microphone caught it."""
    TOUCH = "touch"
    """Touched the robot's touch sensor."""
    WALK = "walk"
    """Started walking to a place or position (``target``)."""
    ARRIVE = "arrive"
    """Reached the place or position of a walk or leave (``target``)."""
    FOLLOW = "follow"
    """Started following the robot."""
    LEAVE = "leave"
    """Started walking away from the robot to ``target``."""
    STOP = "stop"
    """Stopped walking or following and stands still."""


@dataclass(frozen=True, init=False)
class UserAction:
    """One thing the scripted user did, at simulated time ``time`` (s)."""

    time: float
    action: UserActionKind
    text: str | None = None
    target: str | None = None
    heard: bool | None = None
    """For ``say``: whether a listening Q&A heard it."""

    def __init__(self, time: float, action: UserActionKind, text: str | None = None,
                 target: str | None = None, heard: bool | None = None) -> None:
        object.__setattr__(self, "time", time)
        object.__setattr__(self, "action", action)
        object.__setattr__(self, "text", text)
        object.__setattr__(self, "target", target)
        object.__setattr__(self, "heard", heard)

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = {"time": self.time, "action": self.action.value}
        if self.text is not None:
            out["text"] = self.text
        if self.target is not None:
            out["target"] = self.target
        if self.heard is not None:
            out["heard"] = self.heard
        return out


@dataclass(frozen=True)
class ZoneEntry:
    """The robot entered a zone of the scenario; the run loop loads its EA."""

    time: float
    zone: str
    ea: str
    """The EA document path as the scenario wrote it (relative to the scenario file)."""

    def to_dict(self) -> dict[str, object]:
        return {"time": self.time, "zone": self.zone, "ea": self.ea}


@dataclass(frozen=True)
class Picture:
    """What one camera capture (Take a Picture) saw."""

    time: float
    x: float
    y: float
    heading: float
    """Direction the camera looked (deg)."""
    saw_user: bool
    user_distance: float | None = None

    def to_dict(self) -> dict[str, object]:
        return {"time": self.time, "x": self.x, "y": self.y, "heading": self.heading,
                "saw_user": self.saw_user, "user_distance": self.user_distance}


@dataclass(frozen=True)
class ScheduledEvent:
    """Something the environment posts at time ``at`` (s): a network message,
    a sound, or any other named event with its data."""

    at: float
    name: str
    data: Mapping[str, Value] = field(default_factory=dict)

    def to_dict(self) -> dict[str, object]:
        return {"at": self.at, "name": self.name, "data": dict(self.data)}


@dataclass(frozen=True)
class ReplyRule:
    """How a server of the environment answers what an application sends it."""

    to: str
    """The server's name, as applications address it (``<send to="...">``)."""
    text: str
    """The reply; ``{text}`` stands for the message that was sent."""
    after: float = 1.0
    """Seconds between the send and the reply."""
    contains: str | None = None
    """Reply only to messages containing this (ignoring case); None: any message."""

    def matches(self, to: str, text: str) -> bool:
        return to == self.to and (self.contains is None or self.contains.lower() in text.lower())

    def to_dict(self) -> dict[str, object]:
        return {"to": self.to, "text": self.text, "after": self.after, "contains": self.contains}


@dataclass(frozen=True)
class Zone:
    """An area of the map whose entry by the robot loads an EA document."""

    name: str
    ea: str
    area: Area
    join: bool = False
    """Its EA joins the EAs running (``join="true"``) instead of replacing them."""
    line: int = field(default=0, compare=False)
    col: int = field(default=0, compare=False)
    """Where the zone is written in the scenario file (for errors at run time)."""

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = {"name": self.name, "ea": self.ea,
                                  "area": self.area.to_dict()}
        if self.join:
            out["join"] = True
        return out
