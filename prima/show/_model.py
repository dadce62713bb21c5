"""What the page shows: the run's device timeline (:mod:`prima.timeline`, shared with
``prima plot``), and what the page adds to it: the trace table, the words in
bubbles, and each AB's lines."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from prima.timeline import Timeline, timeline
from prima.trace import Pose

Row = Mapping[str, Any]

USER_SAYS_FOR = 3.0
"""Seconds a user's words (or action) stay in their bubble."""

ROBOT_SAYS_FOR = 1.0
"""The least time (s) the robot's words stay in their bubble."""


@dataclass
class Bubble:
    """Words (or an action) shown beside the robot or the user from ``start`` to ``end``."""

    who: str
    start: float
    end: float
    text: str


@dataclass
class Model:
    """The trace, digested: its timeline, the table's rows, bubbles and ABs."""

    timeline: Timeline
    rows: list[dict[str, Any]]
    """The trace's lines but its pose samples: the table's rows."""
    table: dict[int, int] = field(default_factory=dict)
    """A trace line's index -> its row in the table."""
    bubbles: list[Bubble] = field(default_factory=list)
    robot: list[tuple[float, float, float, float]] = field(default_factory=list)
    """(t, x, y, heading) of the robot, in time order."""
    user: list[tuple[float, float, float, float]] = field(default_factory=list)
    abs: dict[int, dict[str, Any]] = field(default_factory=dict)
    """AB id -> its start row, end row (if it ended) and the indices of its lines."""


def _distinct(poses: Sequence[tuple[float, Pose]]) -> list[tuple[float, float, float, float]]:
    """(t, x, y, heading) of each pose, a repeat of the one before dropped."""
    return [(t, *pose) for k, (t, pose) in enumerate(poses) if k == 0 or poses[k - 1] != (t, pose)]


def build(rows: Sequence[Row]) -> Model:
    """Digest a trace's rows (in trace order)."""
    tl = timeline(rows)
    kept = [i for i, row in enumerate(rows) if row["kind"] != "pose"]
    model = Model(tl, [dict(rows[i]) for i in kept], {i: j for j, i in enumerate(kept)},
                  robot=_distinct(tl.robot), user=_distinct(tl.user))
    model.bubbles = sorted(
        [Bubble("robot", b.t0, max(b.t1, b.t0 + ROBOT_SAYS_FOR), b.text or "")
         for b in tl.speech()]
        + [Bubble("user", k.t, k.t + USER_SAYS_FOR, k.label if k.text is not None
                  else f"[{k.label}]") for k in tl.ticks if k.row == "user"],
        key=lambda b: b.start)
    for j, row in enumerate(model.rows):
        if row.get("ab") is None:
            continue
        info = model.abs.setdefault(int(row["ab"]), {"lines": []})
        info["lines"].append(j)
        if row["kind"] == "start":
            info["start"] = j
            info.pop("end", None)
        elif row["kind"] == "end" and "start" in info and "end" not in info:
            info["end"] = j
    return model
