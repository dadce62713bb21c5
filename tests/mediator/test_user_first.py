"""docs/rules.md 7.6, the user is answered first, face to face: one test per numbered
point, each written so that it fails when its mechanism is taken out (checked once by
taking it out).
"""

from __future__ import annotations

from prima.mediator import AppKind, DecisionKind, Event, Request, Rule, RunningOrder
from prima.mediator.testing import Harness
from tests.mediator.helpers import call, speak


def _starts(h: Harness, app: str) -> list[tuple[float, str]]:
    return [(d.t, d.command or "") for d in h.starts() if d.app == app]


# ---------------------------------------------------------------- 7.6 (2): asap is now

def test_an_asap_requests_first_command_starts_on_its_free_devices_at_once() -> None:
    """7.6 (2): the EA talks (3 s) when the user says "Stop."; its handler asks, as soon
    as possible, to stop moving and say "All right.". The StopMoving needs only the
    free wheels: it starts at once, not after the EA's own running words; "All right."
    then waits for the speaker, as any AB waits for its devices."""
    h = Harness(duration={"Speak": 3.0, "StopMoving": 0.1, "*": 1.0})
    m = h.mediator
    h.app("ea", AppKind.EA)
    m.submit(Request("ea", (speak("This panel shows research points of our laboratory."),
                            call("TopologicalMove", to="panel-2"))))
    h.at(1.0, lambda: m.submit(Request(
        "ea", (call("StopMoving"), speak("All right.")), order=RunningOrder.ASAP,
        reactive=True, reaction=True, user=True)))
    h.run(until=10.0)
    assert _starts(h, "ea") == [(0.0, "Speak"), (1.0, "StopMoving"), (3.0, "Speak")]
    cancelled = [d.command for d in h.kinds(DecisionKind.CANCEL)]
    assert cancelled == ["TopologicalMove"]  # (what it replaces is cancelled, as before)
    request = next(d for d in h.kinds(DecisionKind.REQUEST) if d.command == "StopMoving")
    assert request.rule is Rule.ASAP
