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
import sys
from pathlib import Path
from types import CodeType, FrameType
from typing import Any

import pytest

from prima.judge import Blame, Judging, Report, Thresholds, judge
from prima.judge._context import EPS, Context, ReactionState, span_at
from prima.judge._reactions import _Analyst
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


def _calls(tr: Trace, *functions: Any) -> tuple[Report, dict[CodeType, int]]:
    """The trace judged, and how often each of ``functions`` was called meanwhile."""
    calls = {f.__code__: 0 for f in functions}

    def count(frame: FrameType, event: str, _arg: Any) -> None:
        if event == "call" and frame.f_code in calls:
            calls[frame.f_code] += 1

    previous = sys.gettrace()
    sys.settrace(count)
    try:
        return tr.judge(), calls
    finally:
        sys.settrace(previous)


@pytest.mark.pure  # (compiled, Blame's written-out __init__ is native: no trace sees it)
def test_a_reaction_s_waits_make_the_blames_of_what_they_show_alone() -> None:
    # A reaction that waits through another application's loop in its begin/end block
    # is rightly kept by each of its ABs (hundreds a run, in a thesis sample), and shows
    # the longest three: the Blames of those alone are made (one for each AB was 1.2% of
    # a sample-7 run's bytecodes).
    tr = Trace()
    tr.line(9.0, "block", app="ea", text="open", detail={"id": "camera-work"})
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
    for i in range(100):
        tr.speak(10.0 + i / 4 + (i == 50), "ea", i + 2, 2, "Smile.", tree=1, lasts=0.25,
                 request=i == 0)
    tr.line(40.0, "block", app="ea", text="close", detail={"id": "camera-work"})
    tr.speak(40.0, "fa", 1, 1, "A message.", request=False)
    report, calls = _calls(tr, Blame.__init__)
    made = calls[Blame.__init__.__code__]
    (r,) = report.reactions
    assert [(w.ab, w.rule, w.until) for w in r.waits] == [
        (52, "its begin/end block (rule 3)", 23.75), (2, "its begin/end block (rule 3)", 10.25),
        (3, "its begin/end block (rule 3)", 10.5)]
    assert made <= 8, made


@pytest.mark.pure
def test_a_reaction_s_words_wait_through_a_loop_once() -> None:
    # A reaction turns at once; its words, in an AB of three Commands, wait through
    # another application's 100 ABs in its begin/end block. The words' wait, and their
    # AB's from its request, each go through those ABs: that AB is among the reaction's
    # own once (its wait was worked out once for each of its Commands: 5 passes through
    # the loop in all), and whether each of the 100 went first is worked out once (400
    # times; in a sample-7 run, 3% and 1.4% of its bytecodes).
    turn, group = ("locomotion",), ("arm", "locomotion", "speaker")
    command = "SetDirection+PointByHand+Speak"
    tr = Trace()
    tr.line(9.0, "block", app="ea", text="open", detail={"id": "camera-work"})
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, tree=1, command="SetDirection", devices=turn, reactive=True)
    tr.request(10.0, "fa", 2, [2, 3, 4], tree=1, command=command, text="Over there.",
               devices=group, reason="end-event", before=1)
    tr.start(10.0, "fa", 1, 1, tree=1, command="SetDirection", devices=turn)
    tr.end(10.5, "fa", 1, 1, tree=1, command="SetDirection", devices=turn)
    for i in range(100):
        tr.speak(10.25 + i / 4, "ea", i + 3, i + 5, "Smile.", tree=2, lasts=0.25,
                 request=i == 0)
    tr.line(35.25, "block", app="ea", text="close", detail={"id": "camera-work"})
    said = (35.25, 36.25)
    tr.start(35.25, "fa", 2, 2, tree=1, command=command, text="Over there.", devices=group,
             words=said)
    tr.end(36.25, "fa", 2, 2, tree=1, command=command, devices=group, words=said,
           text="Over there.")
    for row in tr.rows[-2:]:
        row["command_ids"] = [2, 3, 4]
    report, calls = _calls(tr, _Analyst.goes_first, _Analyst.near)
    (r,) = report.reactions
    assert (r.first_utterance, r.words_free, r.late) == (35.25, 0.0, False)
    assert calls[_Analyst.goes_first.__code__] <= 100, calls
    assert calls[_Analyst.near.__code__] <= 3, calls


@pytest.mark.pure
def test_when_a_loop_s_tree_was_over_is_worked_out_once() -> None:
    # Each answering hold asks, of every reaction of its application to the user's own
    # action, when the last AB of that reaction's trees ended: a tree that loops has
    # hundreds of ABs (12 passes through a 114-iteration loop, 0.35% of a sample-7 run's
    # bytecodes, when each question went through them all).
    loop = ("human-detection", "locomotion")
    tr = Trace()
    tr.request(0.0, "fa", 1, 1, tree=1, command="TrackingHuman", devices=loop)
    for i in range(200):
        if i:
            tr.end(i / 2, "fa", i, 1, tree=1, command="TrackingHuman", devices=loop,
                   iteration=i - 1)
        tr.start(i / 2, "fa", i + 1, 1, tree=1, command="TrackingHuman", devices=loop,
                 iteration=i)
    tr.end(100.0, "fa", 200, 1, tree=1, command="TrackingHuman", devices=loop,
           iteration=199)
    judging = Judging()
    judging.feed_all(tr.rows)
    analyst = _Analyst(judging.ctx, 100.0)
    touch, speech = (ReactionState(event, 1.0, 1, "fa", True, "", 1, trees=[1])
                     for event in ("touched", "speech"))
    assert analyst._gone(touch) == analyst._gone(speech) == 100.0
    fresh = _Analyst(judging.ctx, 100.0)
    first = bytecodes(lambda: fresh._gone(touch))
    again = bytecodes(lambda: fresh._gone(speech))
    assert again * 20 < first, (first, again)


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
