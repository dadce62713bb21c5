"""One FA and several EAs at once: suspended streams resume most recent first.

With three applications, a reaction of app C can suspend app B's stream that
had itself suspended app A's. The suspended stack then holds A's tree under
B's, and the streams resume from the top: B's, then A's (rule 4.4,
``resume-stream``: suspended trees, the most recently suspended first).
"""

from __future__ import annotations

import dataclasses

from collections.abc import Collection

import pytest

import prima.mediator._ranking as ranking_module
from prima.mediator import AppKind, CommandId, DecisionKind, Outcome, Rule
from prima.mediator._state import Node
from prima.mediator.testing import Harness, ScriptedApp

from tests.mediator.helpers import call, ghost, req, speak, start_of


def _three_levels(h: Harness) -> None:
    """A (museum, EA) loses the speaker to B's (cafe, EA) older request at t=2: A is
    suspended. B's stream goes on from its end handler; C's (the FA's) reaction takes
    the speaker at t=4: B is suspended on top of A."""
    m = h.mediator
    ghost(h, speak("nobody's"))                                      # AB1 speaker 0-2
    h.app("fa", AppKind.FA)
    h.app("museum", AppKind.EA)

    def cafe_follows(command: CommandId, _outcome: Outcome) -> None:
        if command == cafe_first[0]:                                 # b2 follows b1's end
            m.submit(req("cafe", speak("b2: and a cake?"), follows=command))

    h.mediator.register("cafe", AppKind.EA, ScriptedApp("cafe", on_ended=cafe_follows))
    cafe_first = m.submit(req("cafe", speak("b1: coffee?")))          # AB2 waits (oldest)
    m.submit(req("museum", call("MoveHead", pan=10.0), speak("a2: this panel")))  # AB3 -> AB4
    h.at(3.0, lambda: m.submit(req("fa", speak("c1: what's up?"), reactive=True)))


def _durations() -> dict[str, float]:
    return {"Speak": 2.0, "MoveHead": 1.0}


def test_three_streams_resume_most_recent_first() -> None:
    """Without ``resume-stream`` (or with the stack read from the bottom), the
    museum's older request would take the speaker back at t=6 before the cafe's
    suspended stream, which the FA's reaction interrupted last."""
    h = Harness(duration=_durations())
    _three_levels(h)
    h.run()
    suspends = [(d.t, d.app, d.rule) for d in h.kinds(DecisionKind.SUSPEND)]
    assert suspends == [(2.0, "museum", Rule.OLDEST), (4.0, "cafe", Rule.REACTIVITY)]
    resumes = [(d.t, d.app, d.rule) for d in h.kinds(DecisionKind.RESUME)]
    assert resumes == [(6.0, "cafe", Rule.RESUME_STREAM), (8.0, "museum", Rule.FREE_DEVICES)]
    speaker = [(d.t, d.app) for d in h.starts() if "speaker" in d.devices and d.app != "ghost"]
    assert speaker == [(2.0, "cafe"), (4.0, "fa"), (6.0, "cafe"), (8.0, "museum")]
    assert h.mediator.snapshot().suspended == ()


def test_the_stack_holds_both_streams_most_recent_on_top() -> None:
    h = Harness(duration=_durations())
    _three_levels(h)
    h.run(until=5.0)
    snap = h.mediator.snapshot()
    museum_tree = start_of(h, 3).tree
    cafe_tree = start_of(h, 2).tree
    assert snap.suspended == (cafe_tree, museum_tree)  # top first


@pytest.mark.parametrize("broken", ["left-out", "oldest-first"])
def test_without_the_criterion_the_oldest_stream_comes_back_first(
        monkeypatch: pytest.MonkeyPatch, broken: str) -> None:
    """The rule above fails when the mechanism is removed or reversed."""
    def key(node: Node, _pjf: Collection[int]) -> tuple[int, ...]:
        suspended = node.tree.suspended
        if broken == "left-out" or suspended is None:
            return (1, 0)
        return (0, suspended)  # the least recently suspended first

    criteria = tuple(
        dataclasses.replace(c, key=key) if c.rule is Rule.RESUME_STREAM else c
        for c in ranking_module.CRITERIA)
    monkeypatch.setattr(ranking_module, "CRITERIA", criteria)
    h = Harness(duration=_durations())
    _three_levels(h)
    h.run()
    resumes = [(d.t, d.app) for d in h.kinds(DecisionKind.RESUME)]
    assert resumes[0] == (6.0, "museum")


def test_three_reactions_resume_most_recent_first() -> None:
    """The everyday case: the museum's tour, the cafe's reaction to a message, the
    FA's reaction to a touch. The cafe's stream, a reaction, outranks the tour it
    interrupted, so it resumes first (``reactivity``); the tour comes back last."""
    h = Harness(duration={"Speak": 2.0})
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("museum", AppKind.EA)
    h.app("cafe", AppKind.EA)
    m.submit(req("museum", speak("a1"), speak("a2"), speak("a3")))          # AB1 -> 2 -> 3
    h.at(1.0, lambda: m.submit(req("cafe", speak("b1"), speak("b2"), reactive=True)))
    h.at(3.0, lambda: m.submit(req("fa", speak("c1"), reactive=True)))      # AB6
    h.run()
    suspends = [(d.t, d.app) for d in h.kinds(DecisionKind.SUSPEND)]
    assert suspends == [(2.0, "museum"), (4.0, "cafe")]
    resumes = [(d.t, d.app, d.rule) for d in h.kinds(DecisionKind.RESUME)]
    assert resumes == [(6.0, "cafe", Rule.REACTIVITY), (8.0, "museum", Rule.FREE_DEVICES)]
    order = [d.app for d in h.starts()]
    assert order == ["museum", "cafe", "fa", "cafe", "museum", "museum"]
