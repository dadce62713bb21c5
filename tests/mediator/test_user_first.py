"""docs/rules.md 7.6, the user is answered first, face to face: one test per numbered
point, each written so that it fails when its mechanism is taken out (checked once by
taking it out).
"""

from __future__ import annotations

from prima.mediator import (
    AppKind,
    DecisionKind,
    Event,
    MediatorConfig,
    Request,
    Rule,
    RunningOrder,
)
from prima.mediator.testing import Harness
from prima.vocab import DEFAULT_BUDGETS, AppKind as Role, Budgets
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


# ---------------------------------------------------------------- 7.6 (4): not rationed

def test_the_users_own_words_are_answered_past_the_wait_share() -> None:
    """7.6 (4): the EA's question (3 s) kept the FA's reaction to a message waiting
    beyond its share of 0.5 s: the EA lost its precedence at 1.0. At 3.5, while the
    FA says its news, the user asks the EA something: its answer goes before the FA's
    next words all the same (the user's own action first, 7.1), as if the EA had
    kept its precedence: the user paces these, one per action."""
    budgets = {Role.FA: DEFAULT_BUDGETS[Role.FA],
               Role.EA: Budgets(wait_share=0.5, wait_window=60.0)}
    h = Harness(duration={"QA": 3.0, "*": 2.0}, config=MediatorConfig(budgets=budgets))
    m = h.mediator
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA, on_event=lambda e: e.name == "message" and m.submit(Request(
        "fa", (speak("I've just got a message."), speak("The host will be late.")),
        reactive=True, reaction=True)))
    m.submit(Request("ea", (call("QA", prompt="May I go to the next panel?", grammar="g"),)))
    h.at(0.5, lambda: m.post(Event("message")))
    h.at(3.5, lambda: m.submit(Request("ea", (speak("The toilets are by the door."),),
                                       reactive=True, reaction=True, user=True)))
    h.run(until=12.0)
    lost = [d for d in h.kinds(DecisionKind.BUDGET) if d.app == "ea"]
    assert lost and lost[0].t == 1.0
    said = [(d.t, str(d.calls[0].args.get("text"))) for d in h.starts()
            if d.command == "Speak"]
    assert said == [(3.0, "I've just got a message."), (5.0, "The toilets are by the door."),
                    (7.0, "The host will be late.")]
