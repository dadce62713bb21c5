"""A loop's start lines start their ABs from what the context kept of the last start line
of their Command (``Context._shape``): only a line that is the same but for its AB, time,
line, iteration and poses is started so, and it costs less than a line worked out anew.
Any other difference (words, devices, a reason, a cut policy, the words' times) makes its
AB anew."""

from __future__ import annotations

from typing import Any

import pytest

from prima.judge import Thresholds
from prima.judge._context import Context
from tests.work import bytecodes

_POSE = {"robot": {"x": 0.0, "y": 0.0, "heading": 0.0},
         "user": {"x": 1.0, "y": 0.0, "heading": 180.0, "detectable": True}}


def _start(seq: int, ab: int, iteration: int, **changed: Any) -> dict[str, Any]:
    detail: dict[str, Any] = {"args": "distance=1.0", "command_id": 13, "cuttable": True,
                              "iteration": iteration, "label": "track"}
    detail.update(changed.pop("detail", {}))
    row: dict[str, Any] = {"t": 0.5 * ab, "seq": seq, "kind": "start", "app": "fa",
                           "ab": ab, "tree": 1, "command": "TrackingHuman",
                           "reactive": False, "reason": "reactivity",
                           "devices": ["human-detection", "locomotion"], "detail": detail}
    row.update(changed)
    row.update(_POSE)
    return row


def _end(seq: int, ab: int) -> dict[str, Any]:
    return {"t": 0.5 * (ab + 1), "seq": seq, "kind": "end", "app": "fa", "ab": ab, "tree": 1,
            "command": "TrackingHuman", "reactive": False, "reason": "completed",
            "devices": ["human-detection", "locomotion"],
            "detail": {"command_id": 13, "result": "lost=False"}, **_POSE}


def _loop(last: dict[str, Any]) -> Context:
    """A loop's first two iterations, then ``last``: the third's start line."""
    ctx = Context(Thresholds())
    for row in (_start(0, 1, 0), _end(1, 1), _start(2, 2, 1), _end(3, 2), last):
        ctx.feed(row)
    return ctx


@pytest.mark.parametrize(("changed", "field", "value"), [
    ({"text": "hello"}, "text", "hello"),
    ({"app": "ea"}, "app", "ea"),
    ({"tree": 4}, "tree", 4),
    ({"command": "Move"}, "command", "Move"),
    ({"reason": "blend"}, "reason", "blend"),
    ({"devices": ["locomotion"]}, "devices", frozenset({"locomotion"})),
    ({"command_ids": [13, 14]}, "ids", (13, 14)),
    ({"detail": {"cuttable": False}}, "cuttable", False),
    ({"detail": {"words_start": 1.5, "words_end": 2.5}}, "words", (1.5, 2.5)),
    ({"detail": {"iteration": 7}}, "iteration", 7),
    ({}, "iteration", 2),
])
def test_a_loop_start_that_differs_starts_its_ab_as_it_says(
        changed: dict[str, Any], field: str, value: object) -> None:
    ctx = _loop(_start(4, 3, 2, **changed))
    ab = ctx.abs[3]
    assert getattr(ab, field) == value
    assert (ab.start, ab.seq) == (1.5, 4) and ctx.tree_abs[ab.tree][ab.place] is ab
    assert ctx.running == {3: ab} and ctx.cmd_ab[13] == 3
    assert [a.id for a in ctx.on_device["locomotion"]] == [1, 2, 3]


@pytest.mark.pure
def test_the_same_start_line_costs_less_the_next_time() -> None:
    first = _loop(_start(4, 3, 2))
    again = Context(Thresholds())
    for row in (_start(0, 1, 0), _end(1, 1)):
        again.feed(row)
    fresh = bytecodes(lambda: first.feed(_start(6, 4, 3, text="now new")))
    kept = bytecodes(lambda: again.feed(_start(2, 2, 1)))
    assert kept < fresh - 40, (kept, fresh)
