"""A line's poses hold until the next line that has some: a pose line that repeats the
poses before it changes no finding (a run leaves such samples out: a still robot and
user make no lines). Each case is judged twice, with the repeats and without, and must
find the same (the seqs of the lines both traces have mapped); each fails when its
measure reads the samples rather than the poses they hold (checked once each)."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from prima.judge import Report
from tests.judge.helpers import USER, Trace, counts
from tests.judge.test_stuck import lone_search

REPEAT = "repeat"
"""A pose line marked as a repeat of the poses before it (left out of the second trace)."""


def _both(tr: Trace) -> tuple[Report, Report]:
    """``tr`` judged with its repeated pose lines, and without them (seqs renumbered)."""
    held: tuple[Any, Any] | None = None
    for row in tr.rows:  # (each repeat does repeat the poses before it)
        if row.get(REPEAT):
            assert held is not None and (row["robot"], row["user"]) == held
        if "robot" in row:
            held = (row["robot"], row["user"])
    full = [{k: v for k, v in row.items() if k != REPEAT} for row in tr.rows]
    kept = [dict(row) for row, marked in zip(full, tr.rows, strict=True)
            if not marked.get(REPEAT)]
    renumbered = {row["seq"]: seq for seq, row in enumerate(kept)}
    for row in kept:
        row["seq"] = renumbered[row["seq"]]
    with_repeats, without = Trace(), Trace()
    with_repeats.rows, without.rows = full, kept
    return _mapped(with_repeats.judge(), renumbered), without.judge()


def _mapped(report: Report, seqs: dict[int, int]) -> Report:
    """``report``'s findings with every seq field as the trace without repeats numbers it."""
    def each(finding: Any) -> Any:
        changes = {f.name: seqs.get(getattr(finding, f.name), -1)
                   for f in dataclasses.fields(finding)
                   if (f.name == "seq" or f.name.endswith("_seq"))
                   and isinstance(getattr(finding, f.name), int)}
        return dataclasses.replace(finding, **changes)
    return dataclasses.replace(report, findings={
        key: tuple(each(f) for f in found) for key, found in report.findings.items()})


def _repeat(tr: Trace, t: float) -> None:
    """A pose sample at ``t`` that repeats the poses of the line with poses before it."""
    tr.pose(t)
    tr.rows[-1][REPEAT] = True


def _assert_same(tr: Trace) -> Report:
    full, sparse = _both(tr)
    assert full.findings == sparse.findings
    return sparse


def test_a_stretch_unfaced_is_measured_whole_whatever_samples_lie_inside_it() -> None:
    """The user stands 60 degrees off from 2.5 s to 4.5 s of the robot's words: the
    stretch is 2 s, whether or not samples at 3, 3.5 and 4 s say so again."""
    tr = Trace()
    tr.speak(1.0, "ea", 1, 1, "This panel shows research points of our laboratory.", lasts=4.0)
    end = tr.rows.pop()
    tr.pose(2.0)
    rad = math.radians(60.0)
    tr.user = {"x": math.cos(rad), "y": math.sin(rad), "heading": 180.0, "detectable": True}
    tr.pose(2.5)
    for t in (3.0, 3.5, 4.0):
        _repeat(tr, t)
    tr.user = dict(USER)
    tr.pose(4.5)
    tr.rows.append(end)
    tr.sort()
    report = _assert_same(tr)
    assert counts(report) == {"unfaced": 1}
    assert report.of("unfaced")[0].during == 2.0


def test_where_the_robot_was_as_its_words_began_is_where_the_line_before_put_it() -> None:
    """A SetPosition+Speak's words begin at 2 s, after its drive; the first line in them
    is at 2.5 s, once the robot has rolled on 0.5 m away from its user: it left them
    while talking, whether or not a sample at 2 s repeats where it stood."""
    tr = Trace()
    devices = tr.drives_then_speaks(1.0, "Here is the panel.")
    _repeat(tr, 1.5)
    _repeat(tr, 2.0)
    tr.robot = {"x": -0.5, "y": 0.0, "heading": 0.0}
    tr.pose(2.5)
    tr.end(3.0, "ea", 1, 1, command="SetPosition+Speak", devices=devices,
           words=(2.0, 3.0), text="Here is the panel.")
    report = _assert_same(tr)
    assert counts(report) == {"leaving": 1}


def test_a_search_sees_the_user_for_as_long_as_the_poses_hold_them_detectable() -> None:
    """The user is seen at 30 s and stays in sight until the 31 s line shows them gone:
    the search starts afresh from then, whether or not samples repeat the sight."""
    tr = lone_search(until=125.0, seen_at=30.0)
    seen = next(k for k, row in enumerate(tr.rows)
                if row["kind"] == "pose" and row["user"]["detectable"])
    held = dict(tr.rows[seen]["user"])
    gone = next(k for k, row in enumerate(tr.rows) if row["t"] >= 31.0 - 1e-9)
    for row in tr.rows[seen + 1:gone]:
        if "user" in row:
            row["user"] = dict(held)
    tr.rows.insert(gone, {"t": 31.0, "seq": -1, "kind": "pose", "robot": dict(tr.robot),
                          "user": dict(tr.user)})
    for t in (30.5,):
        tr.rows.insert(seen + 1, {"t": t, "seq": -1, "kind": "pose", "robot": dict(tr.robot),
                                  "user": dict(held), REPEAT: True})
    tr.sort()
    report = _assert_same(tr)
    [s] = report.of("stuck")
    assert (s.kind, s.since) == ("search", 31.0)
