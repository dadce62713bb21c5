"""Rule 3, feedback Commands: one AB per loop iteration."""

from __future__ import annotations

from prima.mediator import AppKind, DecisionKind, NodeState, Rule
from prima.mediator.testing import Harness, feedback_iterations

from tests.mediator.helpers import call, req, speak, start_of


def _h(**kw) -> Harness:
    h = Harness(**kw)
    h.fa = h.app("fa", AppKind.FA)  # type: ignore[attr-defined]
    h.ea = h.app("ea", AppKind.EA)  # type: ignore[attr-defined]
    return h


def test_each_iteration_is_an_ab_inserted_before_the_next_command() -> None:
    h = _h(duration=1.0, outcome=feedback_iterations(3))
    m = h.mediator
    m.submit(req("ea", call("TopologicalMove", to="room"), speak("arrived")))   # AB1 -> AB2
    h.run(until=1.0)
    snap = m.snapshot()
    # Iteration 1 (AB3) sits between iteration 0 (AB1, done) and the Speak (AB2).
    it1 = snap.node(3)
    assert (it1.iteration, it1.parent, it1.state) == (1, 1, NodeState.RUNNING)
    assert snap.node(2).parent == 3 and snap.node(2).state is NodeState.PENDING
    h.run()
    assert [(d.t, d.command, d.iteration) for d in h.starts()] == [
        (0.0, "TopologicalMove", 0), (1.0, "TopologicalMove", 1), (2.0, "TopologicalMove", 2),
        (3.0, "Speak", 0)]
    # One end event for the Command, at its terminal iteration.
    assert h.ea.ended_ids == [1, 2]  # type: ignore[attr-defined]
    ends = [d.detail for d in h.kinds(DecisionKind.END) if d.command == "TopologicalMove"]
    assert ends == ["not terminal", "not terminal", "terminal"]


def test_other_apps_abs_run_between_iterations() -> None:
    """Without per-iteration ABs the reactive FA request would wait for the whole move."""
    h = _h(duration={"TrackingHuman": 2.0, "*": 1.0}, outcome=feedback_iterations(3))
    m = h.mediator
    m.submit(req("ea", call("TrackingHuman")))                                       # AB1
    h.at(1.0, lambda: m.submit(req("fa", call("Turn", angle=90.0), reactive=True)))   # AB2
    h.run()
    assert [(d.t, d.ab) for d in h.starts()][:3] == [(0.0, 1), (2.0, 2), (3.0, 3)]
    assert start_of(h, 2).rule is Rule.REACTIVITY
    # The interrupted loop was suspended and resumes with its next iteration.
    assert [d.ab for d in h.kinds(DecisionKind.SUSPEND)] == [3]
    assert [d.ab for d in h.kinds(DecisionKind.RESUME)] == [3]


def test_a_cc_breaking_loop_yields_to_cc_keeping_requests_between_iterations() -> None:
    """Priority: a waiting FA Turn goes before the move's next iteration (Fig. 5.3 line 16)."""
    h = _h(duration={"TopologicalMove": 2.0, "*": 1.0}, outcome=feedback_iterations(2))
    m = h.mediator
    m.submit(req("ea", call("TopologicalMove", to="room")))        # AB1 LOW
    h.at(1.0, lambda: m.submit(req("fa", call("Turn", angle=90.0))))  # AB2 HIGH, plain
    h.run()
    assert [(d.t, d.ab, d.rule) for d in h.starts()] == [
        (0.0, 1, Rule.FREE_DEVICES), (2.0, 2, Rule.PRIORITY), (3.0, 3, Rule.FREE_DEVICES)]
    assert [(d.t, d.ab) for d in h.kinds(DecisionKind.RESUME)] == [(3.0, 3)]


def test_the_next_iteration_ranks_as_parent_finished() -> None:
    """A non-reactive request of the other app does not get between iterations."""
    h = _h(duration={"TrackingHuman": 2.0, "*": 1.0}, outcome=feedback_iterations(3))
    m = h.mediator
    m.submit(req("fa", call("TrackingHuman")))                     # AB1
    h.at(1.0, lambda: m.submit(req("ea", call("FaceHuman"))))       # AB2 (older than AB3)
    h.run()
    assert [(d.t, d.ab) for d in h.starts()] == [(0.0, 1), (2.0, 3), (4.0, 4), (6.0, 2)]
    assert start_of(h, 3).rule is Rule.PARENT_FINISHED


def test_a_feedback_command_may_say_something_on_extra_devices() -> None:
    h = _h(duration=1.0, outcome=feedback_iterations(2))
    h.mediator.submit(req("fa", call("ActiveSensingHuman", say="Where are you?").__class__(
        "ActiveSensingHuman", {"say": "Where are you?"}, extra_devices=frozenset({"speaker"}))))
    h.run()
    assert all("speaker" in ab.devices for ab in h.driver.started)
    assert [ab.iteration for ab in h.driver.started] == [0, 1]
