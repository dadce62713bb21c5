"""The interrupt policy (thesis Sec. 5.3 (2), docs/rules.md 7.3 (2)): a reaction's AB cuts
the other application's running AB where the robot and the AB allow it; the cut AB
starts again from its beginning after the reaction (or is dropped, if its request
said so), and its application gets an ``interrupted`` event."""

from __future__ import annotations

from prima.catalog import Catalog
from prima.mediator import (
    AppKind,
    DecisionKind,
    Event,
    MediatorConfig,
    Request,
    Rule,
    RunningOrder,
)
from prima.mediator.testing import Harness, feedback_iterations
from prima.vocab import OnInterrupt
from tests.mediator.helpers import call, req, speak

CUTS = Catalog.standard().interruptible(["Speak", "Gesture"])
"""A robot that can cut speech and gestures (its profile's ``<interruptible>``)."""


def explain_then_touch(catalog: Catalog = CUTS, on_interrupt: OnInterrupt = OnInterrupt.RESTART,
                       config: MediatorConfig = MediatorConfig(interrupt=True, blend=True),
                       reaction: bool = True) -> tuple[Harness, list[Event], list[int]]:
    """The EA explains for 6 s; at 1 s a touch: the FA reacts with a 2 s utterance."""
    h = Harness(catalog, duration=lambda ab: 6.0 if ab.app == "ea" else 2.0,
                config=config, cut_after=0.3)
    events: list[Event] = []
    ended: list[int] = []
    h.app("ea", AppKind.EA, on_event=events.append, on_ended=lambda cid, _o: ended.append(cid))
    h.app("fa", AppKind.FA)
    h.mediator.submit(Request("ea", (speak("This panel shows research points."),
                                     speak("Look at this figure.")),
                              on_interrupt=on_interrupt))
    h.at(1.0, lambda: h.mediator.submit(
        Request("fa", (speak("Hee-hee! That tickles."),), reactive=reaction, reaction=reaction)))
    h.run(until=40.0)
    return h, events, ended


def starts(h: Harness) -> list[tuple[float, str, str, Rule]]:
    return [(d.t, d.app or "", d.calls[0].args.get("text", d.command) if d.calls else "", d.rule)
            for d in h.starts()]


def test_a_reaction_cuts_the_utterance_which_then_starts_again() -> None:
    h, events, ended = explain_then_touch()
    assert starts(h) == [
        (0.0, "ea", "This panel shows research points.", Rule.FREE_DEVICES),
        (1.3, "fa", "Hee-hee! That tickles.", Rule.REACTIVITY),   # the word under way ends
        (3.3, "ea", "This panel shows research points.", Rule.RESTART),  # from its beginning
        (9.3, "ea", "Look at this figure.", Rule.FREE_DEVICES)]
    (cut,) = h.kinds(DecisionKind.INTERRUPT)
    assert (cut.t, cut.app, cut.rule) == (1.0, "ea", Rule.INTERRUPT)
    first_end = h.kinds(DecisionKind.END)[0]
    assert (first_end.t, first_end.rule, first_end.detail) == (1.3, Rule.INTERRUPT, "to restart")
    (again,) = [d for d in h.kinds(DecisionKind.REQUEST) if d.rule is Rule.RESTART]
    assert again.command_ids == first_end.command_ids  # the same Command, not a new one
    (event,) = [e for e in events if e.name == "interrupted"]
    assert (event.data["restarts"], event.data["command"]) == (True, "Speak")
    # its application also hears that its stream lost the speaker, and got it back
    assert [(e.name, e.data.get("by")) for e in events if e.name != "interrupted"] == [
        ("suspended", "fa"), ("resumed", None)]
    assert len(ended) == 2  # each Command ends once, after its restart


def test_dropped_when_its_request_says_so() -> None:
    h, events, ended = explain_then_touch(on_interrupt=OnInterrupt.DROP)
    assert [(t, text) for t, _a, text, _r in starts(h)] == [
        (0.0, "This panel shows research points."), (1.3, "Hee-hee! That tickles."),
        (3.3, "Look at this figure.")]
    assert [d.detail for d in h.kinds(DecisionKind.END)][0] == "dropped"
    assert not [d for d in h.kinds(DecisionKind.REQUEST) if d.rule is Rule.RESTART]
    assert events[0].data["restarts"] is False
    assert len(ended) == 2  # the dropped one reported once, at the cut


def test_nothing_is_cut_without_a_declaration_an_opt_out_or_a_reaction() -> None:
    """The robot cannot cut (the thesis' PaPeRo), the request says never, the policy is
    off, or the waiting AB is no reaction: the reaction waits for the utterance's end."""
    for h, _e, _d in (explain_then_touch(Catalog.standard()),
                      explain_then_touch(on_interrupt=OnInterrupt.NEVER),
                      explain_then_touch(config=MediatorConfig(interrupt=False, blend=True)),
                      explain_then_touch(reaction=False)):
        assert not h.kinds(DecisionKind.INTERRUPT)
        assert [t for t, *_x in starts(h)][:2] == [0.0, 6.0]


def test_a_later_reaction_is_never_cut_for_an_earlier_one() -> None:
    """Two reactions: the latest wins (rule 4.2), so the earlier one's waiting AB never
    cuts the later one's running AB."""
    h = Harness(CUTS, duration=2.0, cut_after=0.3)
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA)
    h.mediator.submit(Request("ea", (call("Gesture", name="nod"), speak("Welcome.")),
                              reactive=True, reaction=True))
    h.at(0.5, lambda: h.mediator.submit(Request("fa", (speak("Hee-hee!"),), reactive=True,
                                                reaction=True)))
    h.run(until=20.0)
    assert not h.kinds(DecisionKind.INTERRUPT)
    assert [(t, a) for t, a, *_x in starts(h)] == [(0.0, "ea"), (0.5, "fa"), (2.5, "ea")]


def test_a_cut_that_the_ab_outlives_changes_nothing() -> None:
    """The driver declines (the AB is on its last word): no interrupt decision, the AB
    ends as usual and is not restarted."""
    h = Harness(CUTS, duration=lambda ab: 6.0 if ab.app == "ea" else 2.0)
    h.driver.cut = lambda _ab: False  # type: ignore[method-assign]
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("ea", speak("Good-bye.")))
    h.at(1.0, lambda: h.mediator.submit(Request("fa", (speak("Hee-hee!"),), reactive=True,
                                                reaction=True)))
    h.run(until=20.0)
    assert not h.kinds(DecisionKind.INTERRUPT)
    assert [(t, r) for t, _a, _x, r in starts(h)] == [(0.0, Rule.FREE_DEVICES),
                                                      (6.0, Rule.FREE_DEVICES)]


def test_a_touch_cuts_a_search_sweep_whose_app_reacted_to_finding_the_user() -> None:
    """The EA's search sweep says "Where are you?" (a feedback iteration); the user is
    found at once, and its handler asks as soon as possible for a stop and words, which
    stops the loop when the sweep ends and waits behind it. A touch then: the FA's
    reaction to the user's own action is the latest and outranks the EA's earlier one to
    a perception (docs/rules.md 7.1), so it cuts the sweep as it would cut any feedback
    iteration (7.3 (2), 7.6 (3)): the EA's own reaction waiting behind it changes
    nothing. The sweep is not started again (its app stopped its loop)."""
    h = Harness(Catalog.standard().interruptible(["Speak", "ActiveSensingHuman"]),
                duration=lambda ab: 3.0 if ab.calls[0].command == "ActiveSensingHuman"
                else 1.0, outcome=feedback_iterations(5), cut_after=0.2)
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("ea", call("ActiveSensingHuman", say="Where are you?")))  # AB1
    h.mediator.submit(Request("ea", (call("StopMoving"), call("FaceHumanAndSpeak",
                                                               text="There you are.")),
                              order=RunningOrder.ASAP, reactive=True, reaction=True))
    h.at(0.5, lambda: h.mediator.submit(Request(
        "fa", (speak("Hee-hee! That tickles."),), reactive=True, reaction=True, user=True)))
    h.run(until=20.0)
    (cut,) = h.kinds(DecisionKind.INTERRUPT)
    assert (cut.t, cut.app, cut.ab) == (0.5, "ea", 1)
    assert [(d.t, d.app, d.command) for d in h.starts()] == [
        (0.0, "ea", "ActiveSensingHuman"),
        (0.7, "fa", "Speak"),  # at the cut, not at the sweep's end (3.0)
        (1.7, "ea", "StopMoving"),  # after fa's words (7.6 (1)), the EA's reaction
        (2.7, "ea", "FaceHumanAndSpeak")]
    assert not [d for d in h.kinds(DecisionKind.REQUEST) if d.rule is Rule.RESTART]
