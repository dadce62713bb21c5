"""The budgets the mediator enforces: starts per instant, behaviors waiting, the wait share.

An EA is written by a stranger: whatever it does, the FA is kept waiting only
within documented bounds, time moves on, and the EA fails alone.
"""

from __future__ import annotations

import pytest

from prima.errors import MediationError
from prima.mediator import (
    AppKind,
    Call,
    DecisionKind,
    MediatorConfig,
    Outcome,
    Request,
    Rule,
)
from prima.mediator.testing import Harness, ScriptedApp
from prima.vocab import DEFAULT_BUDGETS, Budgets
from tests.mediator.helpers import call, req, speak


def starts(h: Harness, app: str) -> list[float]:
    return [d.t for d in h.starts() if d.app == app]


def test_an_app_that_starts_too_much_at_one_instant_fails_alone() -> None:
    """Zero-length Commands requested again and again from their own end handler
    (a head move to where the head already is) would freeze simulated time."""
    h = Harness(duration={"MoveHead": 0.0, "*": 1.0}, immediate=True)
    m = h.mediator

    def again(_cid: int, _o: Outcome) -> None:
        m.submit(Request("ea", (call("MoveHead", pan=0.0),)))

    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA, on_ended=again)
    m.submit(req("ea", call("MoveHead", pan=0.0)))
    h.at(0.5, lambda: m.submit(req("fa", speak("still here"))))
    h.run(until=10.0)
    limit = DEFAULT_BUDGETS[AppKind.EA].starts_per_instant
    assert starts(h, "ea") == [0.0] * limit
    [failure] = h.kinds(DecisionKind.FAILURE)
    assert (failure.app, failure.rule) == ("ea", Rule.STARTS_PER_INSTANT)
    assert "t=0 s" in failure.detail
    assert m.apps() == ("fa",)
    assert starts(h, "fa") == [0.5]


def test_an_app_cannot_queue_more_behaviors_than_its_waiting_budget() -> None:
    budgets = {AppKind.FA: Budgets(), AppKind.EA: Budgets(waiting=5)}
    h = Harness(duration=100.0, config=MediatorConfig(budgets=budgets))
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.submit(req("ea", *(speak(str(i)) for i in range(4))))
    m.submit(req("ea", speak("5")))
    before = m.snapshot()
    with pytest.raises(MediationError, match="more than 5 behaviors"):
        m.submit(req("ea", speak("6")))
    assert m.snapshot() == before
    h.run(until=100.0)  # the first utterance ended: room for one more
    m.submit(req("ea", speak("6")))


def test_an_endless_chain_of_end_handler_requests_keeps_the_fa_waiting_only_30_s() -> None:
    """Each utterance follows the last (the end-event rule keeps the stream), so the
    EA's next AB always ranks 'parent just finished' above the FA's waiting speech."""
    h = Harness(duration=2.0)
    m = h.mediator

    def chain(cid: int, _o: Outcome) -> None:
        m.submit(Request("ea", (speak("and another thing"),), follows=cid))

    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA, on_ended=chain)
    m.submit(req("ea", speak("let me tell you")))
    h.at(1.0, lambda: m.submit(req("fa", speak("excuse me"))))
    h.run(until=100.0)
    [fa_start] = starts(h, "fa")
    share = DEFAULT_BUDGETS[AppKind.EA].wait_share
    assert fa_start <= 1.0 + share + 2.0  # its share, plus the utterance under way
    budget = h.kinds(DecisionKind.BUDGET)[0]
    assert (budget.app, budget.rule, budget.t) == ("ea", Rule.WAIT_SHARE, 1.0 + share)


def test_a_stream_hold_re_armed_after_every_request_is_bounded_too() -> None:
    """The EA opens a stream, speaks briefly, goes idle (its hold arms), and speaks
    again just before the hold would time out: the hold lapses and re-arms forever."""
    h = Harness(duration=0.5)
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.open_stream("ea", hold=30.0)
    for i in range(40):
        h.at(i * 5.0, lambda: m.submit(req("ea", speak("psst"))))
    h.at(1.0, lambda: m.submit(req("fa", speak("my turn"))))
    h.run(until=200.0)
    [fa_start] = starts(h, "fa")
    assert fa_start <= 1.0 + DEFAULT_BUDGETS[AppKind.EA].wait_share + 0.5


def test_the_fa_following_its_user_is_not_cut_by_a_waiting_ea() -> None:
    """The FA's share is five minutes out of six: a long, legitimate feedback loop
    (Tracking Human) is not interrupted by an EA waiting on the same devices."""
    h = Harness(duration=1.0, outcome=lambda ab: Outcome(terminal=ab.iteration >= 199))
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(req("fa", call("TrackingHuman")))
    h.at(5.0, lambda: m.submit(req("ea", call("FaceHumanAndSpeak", text="look here"))))
    h.run(until=400.0)
    assert starts(h, "ea") == [200.0]  # after the 200 iterations
    assert h.kinds(DecisionKind.BUDGET) == []


def test_a_channel_held_move_does_not_reserve_a_free_device() -> None:
    """The EA's move waits while the FA talks (the channel rule); it must not keep
    the FA's own lower-ranked move off the localization it leaves free."""
    h = Harness(duration={"QA": 10.0, "*": 1.0})
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(req("fa", call("QA", prompt="Tell me?", grammar="g")))
    m.submit(req("ea", call("TopologicalMove", to="room")))   # held: the FA is talking
    m.submit(req("fa", call("SetPosition", x=1.0, y=1.0), asap=True))  # newer, also LOW
    h.run(until=5.0)
    assert [d.command for d in h.starts()] == ["QA", "SetPosition"]


def test_a_failing_listener_is_still_unloaded_alone_under_budgets() -> None:
    h = Harness(duration=1.0)

    def boom(_event: object) -> None:
        raise RuntimeError("crash")

    h.mediator.register("fa", AppKind.FA, ScriptedApp("fa"))
    h.mediator.register("ea", AppKind.EA, ScriptedApp("ea", on_event=boom))
    from prima.mediator import Event

    h.mediator.post(Event("touched"))
    assert h.mediator.apps() == ("fa",)
    assert [d.kind for d in h.decisions][-2:] == [DecisionKind.FAILURE, DecisionKind.UNLOAD]


def test_calls_are_checked_before_anything_changes() -> None:
    h = Harness()
    h.app("ea", AppKind.EA)
    with pytest.raises(MediationError):
        h.mediator.submit(Request("ea", (Call("Speak", {"text": "x"}, extra={"volume": 1}),)))
