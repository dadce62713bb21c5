"""Rule 7: applications come and go; a failing one never takes the other down."""

from __future__ import annotations

import pytest

from prima.errors import MediationError
from prima.mediator import AppKind, DecisionKind, Event, MediatorConfig, Rule
from prima.mediator.testing import Harness, ScriptedApp, feedback_iterations
from prima.vocab import MAX_EAS

from tests.mediator.helpers import call, req, speak, start_of


def test_one_fa_and_a_bounded_number_of_eas() -> None:
    h = Harness(config=MediatorConfig(max_eas=2))
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("museum", AppKind.EA)
    h.app("cafe", AppKind.EA)
    with pytest.raises(MediationError, match="2 EAs are loaded .museum, cafe.; at most 2 EAs"):
        m.register("library", AppKind.EA, ScriptedApp("library"))
    with pytest.raises(MediationError, match="one FA"):
        m.register("fa2", AppKind.FA, ScriptedApp("fa2"))
    with pytest.raises(MediationError, match="already registered"):
        m.register("fa", AppKind.EA, ScriptedApp("fa"))
    with pytest.raises(MediationError, match="unknown application"):
        m.unregister("library")
    assert m.apps() == ("fa", "museum", "cafe")
    m.unregister("cafe")
    m.register("library", AppKind.EA, ScriptedApp("library"))  # room again
    assert m.apps() == ("fa", "museum", "library")


def test_the_default_bound_on_eas_is_max_eas() -> None:
    h = Harness()
    for i in range(MAX_EAS):
        h.app(f"ea{i}", AppKind.EA)
    with pytest.raises(MediationError, match=f"at most {MAX_EAS} EAs"):
        h.mediator.register("one-more", AppKind.EA, ScriptedApp("one-more"))


def test_an_ea_swap_cancels_its_work_frees_its_devices_and_never_cuts() -> None:
    h = Harness(duration={"Speak": 3.0, "*": 1.0}, outcome=feedback_iterations(50))
    m = h.mediator
    fa = h.app("fa", AppKind.FA)
    museum = h.app("museum", AppKind.EA)
    m.submit(req("museum", speak("Panel 1"), speak("Panel 2")))          # AB1 -> AB2
    m.submit(req("museum", call("TrackingHuman"), asap=True))            # AB3 loop
    m.submit(req("fa", speak("hello")))                                  # AB4 waits
    h.at(1.5, lambda: (m.unregister("museum"),
                       m.register("library", AppKind.EA, library)))
    library = ScriptedApp("library")
    h.run()
    # The running utterance and tracking iteration finished; nothing else of museum ran.
    museum_starts = [d for d in h.starts() if d.app == "museum"]
    assert [(d.t, d.ab) for d in museum_starts] == [(0.0, 1), (0.0, 3), (1.0, 5)]
    cancels = [d for d in h.kinds(DecisionKind.CANCEL) if d.app == "museum"]
    assert {d.rule for d in cancels} == {Rule.UNLOAD}
    assert h.driver.abandoned == [3]
    assert museum.cancelled == [] and museum.ended == []  # unloaded: no more callbacks
    assert start_of(h, 4).t == 3.0 and fa.ended_ids == [4]
    unreg = h.kinds(DecisionKind.UNLOAD)
    assert [(d.t, d.app, d.rule) for d in unreg] == [(1.5, "museum", Rule.UNLOAD)]
    assert m.snapshot().trees == ()


def test_a_failing_app_is_removed_and_the_other_goes_on() -> None:
    h = Harness(duration=1.0)
    m = h.mediator

    def boom(_event: Event) -> None:
        raise RuntimeError("interpreter crashed")

    fa = h.app("fa", AppKind.FA)
    ea = h.app("ea", AppKind.EA, on_event=boom)
    m.submit(req("ea", speak("one"), speak("two")))      # AB1 -> AB2
    m.submit(req("fa", speak("mine")))                   # AB3 waits
    h.at(0.5, lambda: m.post(Event("human-found")))
    h.run()
    (err,) = h.kinds(DecisionKind.FAILURE)
    assert (err.app, err.rule) == ("ea", Rule.APP_FAILURE)
    assert "interpreter crashed" in err.detail
    assert [(d.app, d.rule) for d in h.kinds(DecisionKind.UNLOAD)] == [("ea", Rule.APP_FAILURE)]
    # Its running AB finished (never cut) but no more callbacks reached it.
    assert ea.ended == [] and start_of(h, 3).t == 1.0
    assert fa.events and fa.ended_ids == [3]
    assert m.apps() == ("fa",)
    # The failed app is gone: the other can keep requesting, an EA can be loaded again.
    m.register("ea2", AppKind.EA, ScriptedApp("ea2"))


def test_a_failure_inside_an_end_handler_is_contained() -> None:
    h = Harness(duration=1.0)
    m = h.mediator

    def bad(_cid: int, _o: object) -> None:
        raise ValueError("bad handler")

    h.app("fa", AppKind.FA, on_ended=bad)
    ea = h.app("ea", AppKind.EA)
    m.submit(req("fa", speak("x"), speak("y")))
    m.submit(req("ea", speak("z")))
    h.run()
    assert [d.app for d in h.kinds(DecisionKind.FAILURE)] == ["fa"]
    assert ea.ended_ids == [3]
    assert m.snapshot().trees == ()


def test_events_are_broadcast_to_every_app_in_registration_order() -> None:
    h = Harness()
    seen: list[str] = []
    h.app("fa", AppKind.FA, on_event=lambda e: seen.append("fa:" + e.name))
    h.app("ea", AppKind.EA, on_event=lambda e: seen.append("ea:" + e.name))
    h.mediator.post(Event("touched"))
    assert seen == ["fa:touched", "ea:touched"]
