"""Callbacks and the driver may call back into the mediator synchronously."""

from __future__ import annotations

from prima.mediator import (
    AppKind,
    AtomicBehavior,
    Catalog,
    DecisionKind,
    ManualClock,
    Mediator,
    Outcome,
    Rule,
)
from prima.mediator.testing import Harness, ScriptedApp, plain_scan

from tests.mediator.helpers import call, req, speak


def test_a_driver_may_finish_an_ab_from_inside_start() -> None:
    """Zero-length ABs: the end is processed after the current round, in order."""
    h = Harness(duration=0.0, immediate=True)
    fa = h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    h.mediator.submit(req("fa", speak("a"), speak("b"), call("Turn", angle=1.0)))
    h.mediator.submit(req("ea", speak("c")))
    assert fa.ended_ids == [1, 2, 3]
    kinds = [(d.kind.value, d.ab) for d in h.decisions if d.kind in (DecisionKind.START,
                                                                      DecisionKind.END)]
    assert kinds == [("start", 1), ("end", 1), ("start", 2), ("end", 2), ("start", 3),
                     ("end", 3), ("start", 4), ("end", 4)]
    assert h.mediator.snapshot().trees == ()


def test_a_handler_may_submit_and_stream_inside_a_callback() -> None:
    h = Harness(duration=1.0)
    m = h.mediator

    def on_event(_e: object) -> None:
        m.open_stream("fa", hold=1.0)
        m.submit(req("fa", speak("reacting"), reactive=True))
        m.close_stream("fa")

    h.app("fa", AppKind.FA, on_event=on_event)
    h.app("ea", AppKind.EA)
    m.submit(req("ea", speak("busy")))
    from prima.mediator import Event
    h.at(0.5, lambda: m.post(Event("touched")))
    h.run()
    assert [(d.t, d.app) for d in h.starts()] == [(0.0, "ea"), (1.0, "fa")]


def test_selection_runs_once_after_the_outermost_operation() -> None:
    """Both apps react to one event; the latest reactive request wins, whatever the nesting."""
    h = Harness(duration=1.0)
    m = h.mediator
    h.app("fa", AppKind.FA, on_event=lambda e: m.submit(req("fa", speak("fa"), reactive=True)))
    h.app("ea", AppKind.EA, on_event=lambda e: m.submit(req("ea", speak("ea"), reactive=True)))
    from prima.mediator import Event
    m.post(Event("human-found"))
    # Had selection run inside fa's handler, fa would have taken the speaker first.
    first = h.starts()[0]
    assert (first.app, first.rule) == ("ea", Rule.REACTIVITY)


class _Recorder:
    def __init__(self) -> None:
        self.mediator: Mediator | None = None
        self.log: list[int] = []

    def start(self, ab: AtomicBehavior) -> None:
        self.log.append(ab.id)
        assert self.mediator is not None
        if ab.calls[0].command == "Speak":
            self.mediator.finish(ab.id, Outcome())

    def abandon(self, command_id: int) -> None:
        pass


def test_mediator_without_the_harness() -> None:
    driver = _Recorder()
    clock = ManualClock()
    m = Mediator(Catalog.standard(), driver, clock)
    driver.mediator = m
    app = ScriptedApp("fa", on_ended=lambda cid, o: cid == 1 and m.submit(
        req("fa", call("MoveHead", pan=1.0), follows=1)))
    m.register("fa", AppKind.FA, app)
    m.submit(req("fa", speak("hi")))
    assert driver.log == [1, 2]
    assert plain_scan(m) == []
    clock.set(1.0)
    m.finish(2)
    assert app.ended_ids == [1, 2]
