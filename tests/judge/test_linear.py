"""The judge's cost is linear in the trace: no line, reaction or hold looks again at
every exchange, hold or span of lost precedence before it.

The work is counted, not timed (:func:`tests.work.bytecodes`): the bytecodes per line
of a chatty run 8 times as long as another are within 10% of the shorter run's (they
grew by 18% when each utterance went through every exchange and each reaction through
every hold and every span of its application's lost precedence). Also: the spans the
context keeps are found by bisection as by the definitions they replace."""

from __future__ import annotations

import math
import random
from pathlib import Path
from typing import Any

import pytest

from prima.judge import Thresholds, judge
from prima.judge._context import EPS, Context, span_at
from prima.run import Run
from tests.judge.helpers import Trace
from tests.work import bytecodes

CHATTY = Path(__file__).parents[2] / "bench" / "data" / "chatty.xml"


@pytest.mark.pure
def test_the_work_per_line_does_not_grow_with_the_trace() -> None:
    def per_line(until: float) -> float:
        rows: list[dict[str, Any]] = []
        Run(CHATTY, rows=rows.append, until=until).run()
        return bytecodes(lambda: judge(rows)) / len(rows)

    short, long = per_line(400), per_line(3200)
    assert long <= 1.1 * short, (short, long)


@pytest.mark.pure
def test_a_feedback_loop_s_lines_go_only_where_they_are_read() -> None:
    # A loop's iterations (an end line and the next start at one instant, a pose line
    # between) are most of a judged run's lines: each finder is handed only its own
    # handling of their kind (its feeder), and reads what the context found of the line
    # (its time, its AB, whether its Commands move the robot) rather than work it out
    # again. About 655 bytecodes a line; 880 when every finder sorted out every line.
    loop = ("human-detection", "locomotion")
    tr = Trace()
    tr.line(0.0, "load", app="fa")
    tr.request(0.0, "fa", 1, 1, command="TrackingHuman", devices=loop)
    for i in range(200):
        if i:
            tr.end(i / 2, "fa", i, 1, command="TrackingHuman", devices=loop, iteration=i - 1,
                   result="distance=1.0, lost=False")
        tr.start(i / 2, "fa", i + 1, 1, command="TrackingHuman", devices=loop, iteration=i,
                 cuttable=True)
        tr.pose(i / 2 + 0.25)
    per_line = bytecodes(tr.judge) / len(tr.rows)
    assert per_line < 750, per_line


def _spans(rng: random.Random) -> list[list[float]]:
    """Spans in time order and apart, as a context keeps them; the last maybe open."""
    out, t = [], 0.0
    for _ in range(rng.randrange(0, 8)):
        t += rng.choice([0.0, 0.5, 1.0, 2.0])
        end = t + rng.choice([0.0, 0.5, 1.0, 3.0])
        out.append([t, end])
        t = end
    if out and rng.random() < 0.5:
        out[-1][1] = math.inf
    return out


def test_spans_are_found_as_their_definitions_say() -> None:
    rng = random.Random(7)
    ctx = Context(Thresholds())
    for _ in range(500):
        spans = _spans(rng)
        seqs = [rng.randrange(100) for _ in spans]
        ctx.demoted["a"], ctx.demoted_seq["a"] = spans, seqs
        for t in [k / 4 for k in range(-2, 60)] + [s[0] + d for s in spans
                                                   for d in (-EPS / 2, EPS / 2)]:
            inside = [lo - EPS <= t < hi - EPS for lo, hi in spans]
            assert ctx.during(spans, t) is any(inside)
            found = span_at(spans, t)
            if any(inside):
                assert found is spans[inside.index(True)]
            seq = rng.randrange(100)
            assert ctx.demoted_at("a", t, seq) is any(
                inside[i] and not (abs(t - lo) <= EPS and seq < seqs[i])
                for i, (lo, _hi) in enumerate(spans))
            hi = t + rng.choice([0.0, 0.5, 2.0])
            assert ctx.demoted_within("a", t, hi) is any(
                a < hi + EPS and b > t - EPS for a, b in spans)
