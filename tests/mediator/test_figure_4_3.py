"""Thesis Figure 4.3, step by step: trees 0-3 (t=0) and 4-7 (t=1).

AB0 and AB4 share the speaker, so AB4 waits at t=1. At t=2 AB0 ends and its
child AB1 (also on the speaker) enters the waiting list next to AB4: AB4 wins
if it is reactive (rule 4.2), AB1 wins if not (rule 4.3, parent just finished).
Our AB ids start at 1, so the thesis' AB k is our AB k+1.
"""

from __future__ import annotations

import pytest

from prima.mediator import AppKind, DecisionKind, NodeState, Rule
from prima.mediator.testing import Harness

from tests.mediator.helpers import call, req, speak

AB = {k: k + 1 for k in range(8)}  # thesis AB number -> our AB id


def _tree(app: str, reactive: bool = False):
    # root Speak -> Speak -> MoveHead -> Speak: a chain, one tree.
    return req(app, speak(f"{app}-0"), speak(f"{app}-1"), call("MoveHead", pan=10.0),
               speak(f"{app}-3"), reactive=reactive)


@pytest.mark.parametrize("reactive", [True, False], ids=["AB4-reactive", "AB4-not-reactive"])
def test_figure_4_3(reactive: bool) -> None:
    h = Harness(duration=2.0)
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator

    # t=0: tree 0-3 is accepted; its root enters the waiting list and starts.
    m.submit(_tree("fa"))
    s0 = m.snapshot()
    assert s0.running == ((AB[0], ("speaker",)),)
    assert s0.waiting == ()
    (t0,) = s0.trees
    assert [n.ab for n in t0.nodes] == [AB[0], AB[1], AB[2], AB[3]]
    assert [n.parent for n in t0.nodes] == [None, AB[0], AB[1], AB[2]]
    assert [n.state for n in t0.nodes][1:] == [NodeState.PENDING] * 3
    assert s0.active_trees == (t0.id,)

    # t=1: tree 4-7 is accepted; AB4 waits: AB0 holds the speaker.
    h.at(1.0, lambda: m.submit(_tree("ea", reactive=reactive)))
    h.run(until=1.0)
    s1 = m.snapshot()
    assert s1.waiting == (AB[4],)
    assert s1.running == ((AB[0], ("speaker",)),)
    assert len(s1.trees) == 2 and s1.active_trees == (t0.id,)

    # t=2: AB0 ends, AB1 enters the waiting list; one of AB1/AB4 wins.
    h.run(until=2.0)
    s2 = m.snapshot()
    winner, loser = (AB[4], AB[1]) if reactive else (AB[1], AB[4])
    assert s2.running == ((winner, ("speaker",)),)
    assert s2.waiting == (loser,)
    start = [d for d in h.starts() if d.t == 2.0]
    assert [d.ab for d in start] == [winner]
    assert start[0].rule is (Rule.REACTIVITY if reactive else Rule.PARENT_FINISHED)
    # The losing tree is suspended, and AB0's end is recorded before AB winner's start.
    at2 = [d for d in h.decisions if d.t == 2.0]
    assert [d.kind for d in at2] == [DecisionKind.END, DecisionKind.START, DecisionKind.SUSPEND]
    assert at2[2].ab == loser
    assert s2.suspended == (s2.node(loser).tree,)


def test_figure_4_3_runs_to_completion_and_resumes_the_loser() -> None:
    h = Harness(duration=2.0)
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    h.mediator.submit(_tree("fa"))
    h.at(1.0, lambda: h.mediator.submit(_tree("ea", reactive=True)))
    h.run()
    # AB4 (reactive) interrupts tree 0-3 between IUs; tree 4-7 keeps its stream
    # (AB5's parent just finished). When it leaves the speaker for the neck (AB6), the
    # speaker stays kept for its next AB, AB7 (docs/rules.md 7.1: a reaction keeps the
    # devices it needs next): tree 0-3 resumes from AB1 (the suspended IU) only when
    # the reaction has left working memory, never restarting AB0.
    order = [(d.t, d.ab) for d in h.starts()]
    assert order == [(0.0, AB[0]), (2.0, AB[4]), (4.0, AB[5]), (6.0, AB[6]), (8.0, AB[7]),
                     (10.0, AB[1]), (12.0, AB[2]), (14.0, AB[3])]
    held = h.kinds(DecisionKind.HOLD)
    assert [(d.t, d.ab, d.rule) for d in held] == [(6.0, AB[1], Rule.RESERVED)]
    resumes = h.kinds(DecisionKind.RESUME)
    assert [(d.t, d.ab, d.rule) for d in resumes] == [(10.0, AB[1], Rule.FREE_DEVICES)]
    assert h.mediator.snapshot().trees == ()
