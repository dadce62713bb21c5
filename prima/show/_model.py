"""What the page shows: the run's device timeline (:mod:`prima.timeline`, shared with
``prima plot``), and what the page adds to it: the trace table, the words in
bubbles, and each AB's lines.

Built in one pass over the trace's lines, none of them kept: the table's rows go,
as the page's JSON, to a spool file (or a list) as they come, and only what the
page needs of them stays (the timeline, each AB's line numbers), so a trace of a
million lines is never held whole.
"""

from __future__ import annotations

from array import array
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, TextIO

from prima.escape import script_json
from prima.timeline import Builder, Poses, Timeline
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
    """The trace's lines but its pose samples: the table's rows (empty when they were
    spooled or not asked for: :func:`build`)."""
    table: Sequence[int] = field(default_factory=list)
    """A trace line's index -> its row in the table (-1: a pose sample, not in it)."""
    bubbles: list[Bubble] = field(default_factory=list)
    robot: Sequence[tuple[float, Pose]] = field(default_factory=Poses)
    """(t, (x, y, heading)) of the robot, in time order (:func:`build` moves the
    timeline's poses here)."""
    user: Sequence[tuple[float, Pose]] = field(default_factory=Poses)
    abs: dict[int, array[int]] = field(default_factory=dict)
    """AB id -> its start row, its end row (-1 until it has one) and the rows of its
    lines (:meth:`ab_json` writes them as the page reads them), as an array of whole
    numbers: a long run has hundreds of thousands of ABs."""
    count: int = 0
    """The table's rows."""
    starts: int = 0
    """The atomic behaviors started (start lines)."""

    def ab_json(self) -> Iterator[str]:
        """The ABs as the page's JSON object, in pieces."""
        yield "{"
        for k, (ab, (start, end, *lines)) in enumerate(self.abs.items()):
            info: dict[str, Any] = {"lines": lines}
            if start >= 0:
                info["start"] = start
            if end >= 0:
                info["end"] = end
            yield f'{"," if k else ""}"{ab}":{script_json(info)}'
        yield "}"


def _distinct(poses: Poses) -> Poses:
    """The pose samples, a repeat of the one before (the same time and pose) dropped."""
    out = Poses()
    last = None
    for sample in poses:
        if sample != last:
            out.append(sample)
        last = sample
    return out


def build(rows: Iterable[Row], spool: TextIO | None = None, *,
          table_rows: bool = True) -> Model:
    """Digest a trace's rows (in trace order); with ``spool``, the table's rows are
    written there as JSON (comma-separated) instead of kept; without ``table_rows``,
    neither (a timeline alone needs none, and they are most of what a model holds)."""
    builder = Builder()
    table = array("q")
    kept: list[dict[str, Any]] = []
    abs_: dict[int, array[int]] = {}
    j = starts = 0
    for i, row in enumerate(rows):
        builder.feed(i, row)
        kind = row["kind"]
        if kind == "pose":
            table.append(-1)
            continue
        table.append(j)
        starts += kind == "start"
        if spool is not None:
            spool.write(("," if j else "") + script_json(row))
        elif table_rows:
            kept.append(dict(row))
        ab = row.get("ab")
        if ab is not None:
            info = abs_.setdefault(int(ab), array("q", (-1, -1)))
            info.append(j)
            if kind == "start":
                info[0], info[1] = j, -1
            elif kind == "end" and info[0] >= 0 and info[1] < 0:
                info[1] = j
        j += 1
    tl = builder.finish()
    model = Model(tl, kept, table, robot=_distinct(tl.robot), user=_distinct(tl.user),
                  abs=abs_, count=j, starts=starts)
    tl.robot, tl.user = Poses(), Poses()  # moved into the model's (one copy is enough)
    model.bubbles = sorted(
        [Bubble("robot", b.t0, max(b.t1, b.t0 + ROBOT_SAYS_FOR), b.text or "")
         for b in tl.speech()]
        + [Bubble("user", k.t, k.t + USER_SAYS_FOR, k.label if k.text is not None
                  else f"[{k.label}]") for k in tl.ticks if k.row == "user"],
        key=lambda b: b.start)
    return model
