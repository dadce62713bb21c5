"""docs/rules.md 7.6, the user is answered first, face to face: one test per numbered
point, each written so that it fails when its mechanism is taken out (checked once by
taking it out).
"""

from __future__ import annotations

import functools

import pytest

from prima.catalog import Catalog
from prima.mediator import (
    AppKind,
    DecisionKind,
    Event,
    MediatorConfig,
    Outcome,
    Request,
    Rule,
    RunningOrder,
)
from prima.mediator.testing import Harness, feedback_iterations
from prima.vocab import DEFAULT_BUDGETS, AppKind as Role, Budgets
from tests.mediator.helpers import Facing, call, speak


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
    h = Harness(duration={"QA": 3.0, "*": 2.0},
                config=MediatorConfig(budgets=budgets, interrupt=True, blend=True))
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


@pytest.mark.parametrize("reply", ["words", "question"])
def test_the_users_answer_is_replied_to_past_the_wait_share(reply: str) -> None:
    """7.6 (4) with 7.4: the EA's question (3 s) kept the FA's news waiting beyond its
    share of 0.5 s: the EA lost its precedence at 1.0. The user answers at 3.0; the
    EA's reply (words, or its next question) goes before the FA's waiting news all the
    same (the user's answer asks for the robot's output), and the FA's news follows
    it: past the reply's first words, the EA is demoted again."""
    budgets = {Role.FA: DEFAULT_BUDGETS[Role.FA],
               Role.EA: Budgets(wait_share=0.5, wait_window=60.0)}
    h = Harness(duration={"QA": 3.0, "*": 2.0},
                config=MediatorConfig(budgets=budgets, interrupt=True, blend=True),
                outcome=lambda ab: Outcome({"status": "answered", "utterance": "no"}))
    m = h.mediator
    asked: list[int] = []

    def replied(cid: int, _o: Outcome) -> None:
        if cid in asked:
            first = call("QA", prompt="Shall I tell you more?", grammar="g") \
                if reply == "question" else speak("All right.")
            m.submit(Request("ea", (first, speak("Here is the next panel.")), follows=cid))

    h.app("ea", AppKind.EA, on_ended=replied)
    h.app("fa", AppKind.FA)
    asked.extend(m.submit(Request("ea", (call("QA", prompt="May I go to the next panel?",
                                                 grammar="g"),))))
    h.at(0.5, lambda: m.submit(Request("fa", (speak("The host will be late."),))))
    h.run(until=20.0)
    lost = [d for d in h.kinds(DecisionKind.BUDGET) if d.app == "ea"]
    assert lost and lost[0].t == 1.0
    said = [(d.t, d.app, d.command) for d in h.starts() if d.command in ("Speak", "QA")]
    first = "QA" if reply == "question" else "Speak"
    assert said[:3] == [(0.0, "ea", "QA"), (3.0, "ea", first),
                        (6.0 if reply == "question" else 5.0, "fa", "Speak")]


def test_the_reply_to_a_later_answer_is_no_stream_an_earlier_reaction_holds() -> None:
    """7.6 (1) with 7.4: the user touches the robot (0.5) while the EA asks them a
    question; the FA's reaction is a gesture with no words (till 6.5), which holds
    the streams it interrupted while it lasts. The user answers the EA at 3.0: the
    EA's reply, its next question, answers the user's later action and goes as soon
    as the speaker is free, not after the gesture."""
    h = Harness(duration={"QA": 3.0, "Gesture": 6.0, "*": 2.0},
                outcome=lambda ab: Outcome({"status": "answered", "utterance": "no"}))
    m = h.mediator
    asked: list[int] = []

    def replied(cid: int, _o: Outcome) -> None:
        if cid in asked:
            m.submit(Request("ea", (call("QA", prompt="May I go to the next panel?",
                                         grammar="g"),), follows=cid))
            asked.clear()

    h.app("ea", AppKind.EA, on_ended=replied)
    h.app("fa", AppKind.FA, on_event=lambda e: e.name == "touched" and m.submit(Request(
        "fa", (call("Gesture", name="happy"),), order=RunningOrder.ASAP, reactive=True,
        reaction=True, user=True)))
    asked.extend(m.submit(Request("ea", (call("QA", prompt="May I repeat that?",
                                                 grammar="g"),))))
    h.at(0.5, lambda: m.post(Event("touched")))
    h.run(until=20.0)
    assert _starts(h, "ea") == [(0.0, "QA"), (3.0, "QA")]
    assert _starts(h, "fa") == [(0.5, "Gesture")]


# ---------------------------------------------------------------- 7.6 (1): own stream too

def _guide(h: Harness, follow: bool = False) -> None:
    """The EA guides (a TopologicalMove, 0.5 s a leg, or following the user) and, at
    2.2, the user asks it something: it answers (3 s) in a stream of its own."""
    m = h.mediator

    def answer(e: Event) -> None:
        if e.name == "speech":
            m.submit(Request("ea", (speak("The toilets are by the door."),), reactive=True,
                             reaction=True, user=True))

    ea = h.app("ea", AppKind.EA, on_event=answer)
    ea.listens_for = ("toilet",)
    move = call("TrackingHuman") if follow else call("TopologicalMove", to="panel-2")
    m.submit(Request("ea", (move,)))
    h.at(2.2, lambda: m.hear(Event("speech", {"words": "Where is the toilet?"})))


def test_a_guides_move_stops_while_it_answers_the_user() -> None:
    """7.6 (1): the guide's own move is suspended at its next IU boundary (the leg under
    way ends at 2.5) and waits, on the wheels its answer does not use, until the answer's
    words are said (5.2); then it resumes."""
    h = Harness(duration={"TopologicalMove": 0.5, "Speak": 3.0},
                outcome=feedback_iterations(100))
    _guide(h)
    h.run(until=8.0)
    legs = [d.t for d in h.starts() if d.command == "TopologicalMove"]
    assert 2.0 in legs and not [t for t in legs if 2.0 < t < 5.2] and 5.2 in legs
    suspend = next(d for d in h.kinds(DecisionKind.SUSPEND) if d.app == "ea")
    assert (suspend.t, suspend.rule) == (2.5, Rule.ANSWERING)
    assert any(d.t == 5.2 for d in h.kinds(DecisionKind.RESUME) if d.app == "ea")


def test_following_the_user_goes_on_while_the_robot_answers() -> None:
    """7.6 (1): following the user is not leaving: it goes on meanwhile."""
    h = Harness(duration={"TrackingHuman": 0.5, "Speak": 3.0},
                outcome=feedback_iterations(100))
    _guide(h, follow=True)
    h.run(until=8.0)
    steps = [d.t for d in h.starts() if d.command == "TrackingHuman"]
    assert [t for t in steps if 2.2 < t < 5.2] == [2.5, 3.0, 3.5, 4.0, 4.5, 5.0]
    assert not h.kinds(DecisionKind.SUSPEND)


def test_the_other_apps_stream_waits_on_every_device_while_the_user_is_answered() -> None:
    """7.6 (1): the FA's gestures (arm, neck) share no device with the EA's answer to the
    user's touch, yet its stream is suspended at its next IU boundary (2.0) until the
    answer's words are said (4.5). The FA's block, once under way, is concluded."""
    h = Harness(duration={"Gesture": 1.0, "Speak": 3.0})
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(Request("fa", tuple(call("Gesture", name="wave") for _ in range(4))))
    h.at(1.5, lambda: m.submit(Request("ea", (speak("The toilets are by the door."),),
                                       reactive=True, reaction=True, user=True)))
    h.run(until=10.0)
    assert [d.t for d in h.starts() if d.app == "fa"] == [0.0, 1.0, 4.5, 5.5]
    suspend = next(d for d in h.kinds(DecisionKind.SUSPEND))
    assert (suspend.app, suspend.t, suspend.rule) == ("fa", 2.0, Rule.ANSWERING)


def test_what_waits_for_a_busy_device_steps_aside_when_the_user_is_answered() -> None:
    """7.6 (1) with 7.6 (2): the FA's words wait for the speaker (the EA talks till 3.0)
    and, ranking first there, keep the wheels for themselves. The user touches the
    robot at 1.0: the EA's reaction, as soon as possible, is a move. The FA's stream,
    which the reaction interrupted, is held: its waiting words keep nothing from it,
    and the move starts at once (it waited for the EA's words to end)."""
    h = Harness(duration={"Speak": 3.0, "TopologicalMove": 0.5, "*": 1.0},
                outcome=feedback_iterations(2))
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA, on_event=lambda e: e.name == "touched" and m.submit(Request(
        "ea", (call("TopologicalMove", to="panel-2"),), order=RunningOrder.ASAP,
        reactive=True, reaction=True, user=True)))
    m.submit(Request("ea", (speak("This panel shows research points of our laboratory."),)))
    h.at(0.5, lambda: m.submit(Request("fa", (call("FaceHumanAndSpeak", text="Hello."),))))
    h.at(1.0, lambda: m.post(Event("touched")))
    h.run(until=10.0)
    assert _starts(h, "ea") == [(0.0, "Speak"), (1.0, "TopologicalMove"),
                                (1.5, "TopologicalMove")]
    assert _starts(h, "fa") == [(3.0, "FaceHumanAndSpeak")]


def test_a_stream_suspended_by_the_answers_turn_is_said_to_be_held_for_the_answer() -> None:
    """7.6 (1): the EA's reaction to a message (its StopMoving, as soon as its move's
    leg is over) is suspended by the FA's turn to the user who touched the robot, and
    then waits for the FA's words as a stream the FA's reaction interrupted: a `hold`
    decision says so (rule answering), so that what reads the trace (the judge) knows
    why it waits past the turn."""
    h = Harness(duration={"TopologicalMove": 0.5, "FaceHuman": 2.0, "Speak": 1.2,
                          "StopMoving": 0.1}, outcome=feedback_iterations(100))
    m = h.mediator
    h.app("fa", AppKind.FA, on_event=lambda e: e.name == "touched" and m.submit(Request(
        "fa", (call("FaceHuman"), speak("Hee-hee! That tickles.")), order=RunningOrder.ASAP,
        reactive=True, reaction=True, user=True)))
    h.app("ea", AppKind.EA, on_event=lambda e: e.name == "message" and m.submit(Request(
        "ea", (call("StopMoving"), speak("A message from your host.")),
        order=RunningOrder.ASAP, reactive=True, reaction=True)))
    m.submit(Request("ea", (call("TopologicalMove", to="room"),)))
    h.at(1.2, lambda: m.post(Event("message")))
    h.at(1.3, lambda: m.post(Event("touched")))
    h.run(until=8.0)
    said = [(d.t, d.kind, d.rule, d.command) for d in h.decisions
            if d.app == "ea" and d.kind in (DecisionKind.SUSPEND, DecisionKind.HOLD)]
    assert said == [(1.5, DecisionKind.SUSPEND, Rule.USER_FIRST, "StopMoving"),
                    (1.5, DecisionKind.HOLD, Rule.ANSWERING, "StopMoving")]
    assert _starts(h, "ea")[-2:] == [(4.7, "StopMoving"), (4.8, "Speak")]


def test_a_later_reaction_is_no_stream_the_answer_interrupted() -> None:
    """7.6 (1) beside 7.1: while the FA asks the user what they want (its touch
    reaction's first words, a Q&A to 5.0), a message comes for the EA: its reaction is
    a stream of its own, not one the touch interrupted. Its StopMoving takes the free
    wheels at once; its words wait for the FA's (the user's own action first, 7.1)."""
    h = Harness(duration={"QA": 4.0, "StopMoving": 0.2, "*": 2.0})
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA, on_event=lambda e: e.name == "message" and m.submit(Request(
        "ea", (call("StopMoving"), speak("I've just got a message.")), reactive=True,
        reaction=True)))
    m.submit(Request("fa", (call("QA", prompt="What's the matter with you?", grammar="g"),),
                     reactive=True, reaction=True, user=True))
    h.at(2.0, lambda: m.post(Event("message")))
    h.run(until=10.0)
    assert _starts(h, "ea") == [(2.0, "StopMoving"), (4.0, "Speak")]
    assert not [d for d in h.decisions if d.rule is Rule.ANSWERING]


def test_an_answer_whose_app_is_unloaded_holds_the_others_no_more() -> None:
    """7.6 (1): the EA's answer to the user's touch is a turn (till 4.5), then words;
    the FA's gestures wait meanwhile (from 2.0). The EA is unloaded at 2.5 (its words
    cancelled, its turn, under way, concluded): it answers nobody any more, and the
    FA's stream goes on at once, not when the turn ends."""
    h = Harness(duration={"Gesture": 1.0, "Turn": 3.0, "Speak": 3.0})
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(Request("fa", tuple(call("Gesture", name="wave") for _ in range(4))))
    h.at(1.5, lambda: m.submit(Request(
        "ea", (call("Turn", angle=90.0), speak("The toilets are by the door.")),
        reactive=True, reaction=True, user=True)))
    h.at(2.5, lambda: m.unregister("ea"))
    h.run(until=10.0)
    assert [d.t for d in h.starts() if d.app == "fa"] == [0.0, 1.0, 2.5, 3.5]
    assert [(d.t, d.command) for d in h.starts() if d.app == "ea"] == [(1.5, "Turn")]


def test_a_stream_held_for_a_second_answer_is_said_to_be_held_again() -> None:
    """7.6 (1): a second EA's head move (asked at 0.2) waits for the first EA's (to
    3.0); it is held while the FA answers the user's touch at 0.5 (its words to 1.5).
    The user touches the robot again at 2.5: the FA's second answer holds it anew, and
    a second `hold` says so (what reads the trace, the judge, knows why it waits
    then)."""
    h = Harness(duration={"Speak": 1.0, "MoveHead": 3.0, "*": 2.0})
    m = h.mediator
    h.app("fa", AppKind.FA, on_event=lambda e: e.name == "touched" and m.submit(Request(
        "fa", (speak("Hee-hee! That tickles."), call("PointByHand", angle=0.5)),
        reactive=True, reaction=True, user=True)))
    h.app("ea", AppKind.EA)
    h.app("eb", AppKind.EA)
    m.submit(Request("ea", (call("MoveHead", pan=0.3),)))
    h.at(0.2, lambda: m.submit(Request("eb", (call("MoveHead", pan=-0.5),))))
    h.at(0.5, lambda: m.post(Event("touched")))
    h.at(2.5, lambda: m.post(Event("touched")))
    h.run(until=12.0)
    held = [(d.t, d.rule) for d in h.kinds(DecisionKind.HOLD) if d.app == "eb"]
    assert held == [(0.5, Rule.ANSWERING), (2.5, Rule.ANSWERING)]
    assert _starts(h, "eb") == [(4.5, "MoveHead")]


def test_a_block_under_way_is_concluded_while_the_user_is_answered() -> None:
    """Rule 3 beside 7.6 (1): a started block is always concluded."""
    h = Harness(duration={"Gesture": 1.0, "Speak": 3.0})
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.open_block("fa", devices=frozenset({"arm", "neck"}), watchdog=30.0)
    m.submit(Request("fa", tuple(call("Gesture", name="wave") for _ in range(4))))
    h.at(1.5, lambda: m.submit(Request("ea", (speak("The toilets are by the door."),),
                                       reactive=True, reaction=True, user=True)))
    h.run(until=10.0)
    assert [d.t for d in h.starts() if d.app == "fa"] == [0.0, 1.0, 2.0, 3.0]


def test_an_answer_whose_words_never_come_holds_the_others_at_most_its_bound() -> None:
    """7.6 (1), bounded: a reaction whose words wait behind its own endless loop keeps the
    FA's stream waiting no longer than ``max_answer_hold`` (here 5 s)."""
    h = Harness(duration={"Gesture": 1.0, "TrackingHuman": 0.5, "Speak": 3.0},
                outcome=feedback_iterations(10_000),
                config=MediatorConfig(max_answer_hold=5.0, interrupt=True, blend=True))
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(Request("fa", tuple(call("Gesture", name="wave") for _ in range(4))))
    h.at(1.5, lambda: m.submit(Request("ea", (call("TrackingHuman"), speak("Follow me.")),
                                       reactive=True, reaction=True, user=True)))
    h.run(until=10.0)
    assert [d.t for d in h.starts() if d.app == "fa"] == [0.0, 1.0, 6.5, 7.5]


# ---------------------------------------------------------------- 7.6 (3): face first

CUTS = Catalog.standard().interruptible(Catalog.standard().usually_interruptible())
"""A robot that cuts utterances, Q&A prompts, gestures and feedback iterations."""



def _sweeping(own: bool, catalog: Catalog | None) -> Harness:
    """An app sweeps the room for its user (a search, 2 s a sweep); at 1.0 the user
    touches the robot, whose user is off to the side, and the FA (or, if ``own``, the
    searching app itself) answers."""
    facing = Facing()
    h = Harness(catalog, duration={"ActiveSensingHuman": 2.0, "FaceHuman": 1.0, "*": 2.0},
                outcome=feedback_iterations(100), channel=facing)
    m = h.mediator
    searcher = "fa" if own else "ea"
    h.app("fa", AppKind.FA)
    if not own:
        h.app("ea", AppKind.EA)
    m.submit(Request(searcher, (call("ActiveSensingHuman"),)))
    h.at(1.0, lambda: m.submit(Request("fa", (speak("Hee-hee! That tickles."),),
                                       order=RunningOrder.ASAP if own else
                                       RunningOrder.AFTER_LATEST,
                                       reactive=True, reaction=True, user=True)))
    return h


def _answer(h: Harness) -> list[tuple[float, str]]:
    return [(d.t, d.command or "") for d in h.starts()
            if d.app == "fa" and d.command in ("FaceHuman", "Speak")]


def test_a_reactions_turn_to_the_user_cuts_a_search_sweep() -> None:
    """7.6 (3) with 7.3 (2): on a robot that may cut a feedback iteration, the touch's
    turn to the user cuts the EA's search sweep under way at once; the words follow the
    turn, face to face. The FA's own sweep is cut alike (7.6 (1): its own stream too)."""
    for own in (False, True):
        h = _sweeping(own, CUTS)
        h.run(until=8.0)
        assert _answer(h) == [(1.0, "FaceHuman"), (2.0, "Speak")], own
        cut = h.kinds(DecisionKind.INTERRUPT)
        assert cut and cut[0].t == 1.0 and cut[0].command == "ActiveSensingHuman", own


def test_words_wait_for_what_may_not_be_cut_on_the_wheels_to_turn_first() -> None:
    """7.6 (3): on a robot that cuts nothing, the touch's words never start unfaced to
    be early: they wait for the sweep under way (to 2.0), then for the turn."""
    for own in (False, True):
        h = _sweeping(own, None)
        h.run(until=8.0)
        assert _answer(h) == [(2.0, "FaceHuman"), (3.0, "Speak")], own
        assert not h.kinds(DecisionKind.INTERRUPT)


def test_the_robot_keeps_facing_the_user_while_its_words_run() -> None:
    """7.6 (3): the user walks round the robot (at 1.0) while it says a long utterance:
    a turn to the user runs beside the words, in their stream, at once. With the wheels
    busy (the FA's gesture does not use them; its drive, to 3.0, does), the turn comes
    when they are free, the words still running."""
    for drives in (False, True):
        facing = Facing()
        facing.faced = True
        h = Harness(duration={"Speak": 4.0, "FaceHuman": 0.5, "*": 3.0}, channel=facing)
        m = h.mediator
        h.app("fa", AppKind.FA)
        h.app("ea", AppKind.EA)
        m.submit(Request("ea", (speak("This panel shows research points of our lab."),)))
        m.submit(Request("fa", (call("SetSpeedAndTime", speed=0.2, time=3.0) if drives
                                else call("Gesture", name="nod"),)))
        h.at(1.0, functools.partial(setattr, facing, "faced", False))
        h.at(1.0, m.regard)
        h.run(until=8.0)
        turns = [(d.t, d.app, d.rule) for d in h.starts() if d.command == "FaceHuman"]
        assert turns == [(3.0 if drives else 1.0, "ea", Rule.CONNECT_CHANNEL)], drives
        assert not h.kinds(DecisionKind.CANCEL)


def test_a_turn_beside_words_ends_with_them() -> None:
    """7.6 (3): the user walks on round the robot while it asks its question; the turn
    to them beside the prompt (a Face Human that follows them) ends with the Q&A, so
    that the reply to their answer (its words on the wheels too) starts at once, not
    when the turn gives up following them (a silence after the answer)."""
    facing = Facing()
    facing.faced = True
    h = Harness(duration={"QA": 2.0, "FaceHuman": 4.0, "*": 1.0}, channel=facing,
                outcome=lambda ab: Outcome({"status": "answered", "utterance": "yes"}))
    m = h.mediator
    asked: list[int] = []

    def replied(cid: int, _o: Outcome) -> None:
        if cid in asked:
            m.submit(Request("ea", (call("FaceHumanAndSpeak", text="Here we go."),),
                             follows=cid))

    h.app("ea", AppKind.EA, on_ended=replied)
    asked.extend(m.submit(Request("ea", (call("QA", prompt="May I repeat that?",
                                                 grammar="g"),))))
    h.at(0.5, functools.partial(setattr, facing, "faced", False))
    h.at(0.5, m.regard)
    h.run(until=10.0)
    assert [(d.t, d.command) for d in h.starts()] == [
        (0.0, "QA"), (0.5, "FaceHuman"), (2.0, "FaceHumanAndSpeak")]


def test_words_face_first_while_another_app_drives_the_robot_away() -> None:
    """7.6 (3): the robot faces its user, but the EA is turning it to a heading of its own
    (a SetPositionAndDirection, 0-3.0) when the FA's reaction to a message is to speak
    (1.0). Started now, the words would run while the robot turns away: they face first,
    or wait. The turn to the user cuts the EA's drive where the robot may cut it, then
    the words follow; where it may cut nothing, the turn waits for the drive to end (a
    visit prima check made: FA5's words ran 1 s unfaced beside EA3's return, 1 run in
    800)."""
    for catalog, turn in ((CUTS, 1.0), (None, 3.0)):
        facing = Facing()
        facing.faced = True
        h = Harness(catalog, duration={"SetPositionAndDirection": 3.0, "FaceHuman": 0.5,
                                       "*": 2.0},
                    outcome=feedback_iterations(1), channel=facing)
        m = h.mediator
        h.app("fa", AppKind.FA)
        h.app("ea", AppKind.EA)
        m.submit(Request("ea", (call("SetPositionAndDirection", x=1.0, y=2.0, heading=90.0),)))
        h.at(1.0, lambda m=m: m.submit(Request("fa", (speak("The video setting succeeds."),),
                                               reactive=True, reaction=True)))
        h.run(until=8.0)
        assert _answer(h) == [(turn, "FaceHuman"), (turn + 0.5, "Speak")], catalog


# ---------------------------------------------------------------- 7.1: one handling

def test_what_one_handling_asks_is_one_reaction_its_first_words_end_its_precedence() -> None:
    """7.1: the user says "Stop."; the EA's handler says "All right." and, in the same
    handling, asks its next question (a second request). That is one reaction: once
    "All right." is said (1.0), it no longer goes before another application's later
    reaction to a message (0.5), which then goes first, as the latest reaction."""
    h = Harness(duration={"QA": 3.0, "*": 1.0})
    m = h.mediator

    def stop(e: Event) -> None:
        if e.name == "speech":
            m.submit(Request("ea", (speak("All right."),), reactive=True, reaction=True,
                             user=True))
            m.submit(Request("ea", (call("QA", prompt="May I go on?", grammar="g"),),
                             reaction=True, user=True))

    ea = h.app("ea", AppKind.EA, on_event=stop)
    ea.listens_for = ("stop",)
    h.app("fa", AppKind.FA, on_event=lambda e: e.name == "message" and m.submit(Request(
        "fa", (speak("I've just got a message."),), reactive=True, reaction=True)))
    m.hear(Event("speech", {"words": "Stop."}))
    h.at(0.5, lambda: m.post(Event("message")))
    h.run(until=10.0)
    said = [(d.t, d.app) for d in h.starts() if d.command in ("Speak", "QA")]
    assert said == [(0.0, "ea"), (1.0, "fa"), (2.0, "ea")]


def test_a_later_perception_reaction_joining_an_answer_leaves_it_the_users() -> None:
    """7.1: the EA answers the user (a wave, then words); before its words, it sees the
    user and reacts again, in the same stream. That later reaction to a perception does
    not take away the user's precedence: the EA's words still go before the FA's still
    later reaction to a message, as the user's own action first."""
    h = Harness(duration={"Gesture": 1.0, "*": 2.0})
    m = h.mediator
    h.app("ea", AppKind.EA, on_event=lambda e: e.name == "human-found" and m.submit(Request(
        "ea", (speak("Hello again."),), reactive=True, reaction=True)))
    h.app("fa", AppKind.FA, on_event=lambda e: e.name == "message" and m.submit(Request(
        "fa", (speak("A message."),), reactive=True, reaction=True)))
    m.submit(Request("ea", (call("Gesture", name="wave"), speak("The tour starts here.")),
                     reactive=True, reaction=True, user=True))
    h.at(0.5, lambda: m.post(Event("human-found")))
    h.at(0.6, lambda: m.post(Event("message")))
    h.run(until=10.0)
    said = [(d.t, str(d.calls[0].args["text"])) for d in h.starts() if d.command == "Speak"]
    assert said[0] == (1.0, "The tour starts here.")


def test_a_pause_after_a_false_interruption_is_no_end_of_the_talk() -> None:
    """7.5 with the channel rule (thesis Sec. 3.3): a cough cuts the FA's words (at 1.1),
    which go on after the robot's pause (1.7). Meanwhile the FA is still talking with
    the user: the EA's move, which breaks the channel, does not drive off in the pause."""
    h = Harness(CUTS, duration={"Speak": 4.0, "TopologicalMove": 0.5}, cut_after=0.1,
                outcome=feedback_iterations(100),
                config=MediatorConfig(barge_in=True, resume_pause=0.6, interrupt=True, blend=True))
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(Request("fa", (speak("Let me tell you about the lab's robots."),)))
    m.submit(Request("ea", (call("TopologicalMove", to="panel-2"),)))
    h.at(1.0, lambda: m.hear(Event("speech", {"words": "ahem"})))
    h.run(until=10.0)
    moves = [round(d.t, 6) for d in h.starts() if d.command == "TopologicalMove"]
    words = [round(d.t, 6) for d in h.starts() if d.command == "Speak"]
    assert words == [0.0, 1.7] and moves and moves[0] == 5.7


def test_what_the_pause_held_goes_when_the_pause_is_over() -> None:
    """7.5 with the channel rule: a cough cuts the FA's words (1.1); they are to go on
    after the robot's pause (1.7), but wait there for the EA's reaction, which comes
    first. The EA's move, held while the FA was talking (and pausing), starts when the
    pause is over: the FA is no longer talking (it waited for ever)."""
    h = Harness(CUTS, duration={"Speak": 4.0, "TopologicalMove": 0.5}, cut_after=0.1,
                outcome=feedback_iterations(2),
                config=MediatorConfig(barge_in=True, resume_pause=0.6, interrupt=True, blend=True))
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(Request("fa", (speak("Let me tell you about the lab's robots."),)))
    m.submit(Request("ea", (call("TopologicalMove", to="panel-2"), speak("Here is panel 2."))))
    m.submit(Request("ea", (speak("Hello."),), reactive=True, reaction=True))
    h.at(1.0, lambda: m.hear(Event("speech", {"words": "ahem"})))
    h.run(until=20.0)
    starts = [(round(d.t, 6), d.app, d.command) for d in h.starts()]
    assert starts[1] == (1.7, "ea", "TopologicalMove")
    assert starts[-1] == (10.7, "fa", "Speak")


def test_what_the_pause_held_goes_when_the_words_it_paused_are_gone() -> None:
    """7.5 with the channel rule: a cough cuts the FA's words (1.1); in the robot's
    pause, the FA is unloaded (1.3): its words will not go on, and the EA's move, held
    while the FA was talking, starts then (it waited for ever)."""
    h = Harness(CUTS, duration={"Speak": 4.0, "TopologicalMove": 0.5}, cut_after=0.1,
                outcome=feedback_iterations(2),
                config=MediatorConfig(barge_in=True, resume_pause=0.6, interrupt=True, blend=True))
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(Request("fa", (speak("Let me tell you about the lab's robots."),)))
    m.submit(Request("ea", (call("TopologicalMove", to="panel-2"),)))
    h.at(1.0, lambda: m.hear(Event("speech", {"words": "ahem"})))
    h.at(1.3, lambda: m.unregister("fa"))
    h.run(until=20.0)
    starts = [(round(d.t, 6), d.app, d.command) for d in h.starts()]
    assert starts[:2] == [(0.0, "fa", "Speak"), (1.3, "ea", "TopologicalMove")]


def test_a_reaction_to_a_touch_with_no_words_holds_the_guide_while_it_lasts() -> None:
    """7.6 (1): the user touches the robot as the EA guides them; the FA's reaction is a
    gesture with no words (2 s). The EA's move stops at its next leg and waits until the
    reaction is over, then goes on: the robot does not drive off while it responds."""
    h = Harness(duration={"TopologicalMove": 0.5, "Gesture": 2.0},
                outcome=feedback_iterations(100))
    m = h.mediator
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA)
    m.submit(Request("ea", (call("TopologicalMove", to="panel-2"),)))
    h.at(2.2, lambda: m.submit(Request("fa", (call("Gesture", name="happy"),), reactive=True,
                                       reaction=True, user=True)))
    h.run(until=8.0)
    legs = [d.t for d in h.starts() if d.command == "TopologicalMove"]
    assert 2.0 in legs and not [t for t in legs if 2.0 < t < 4.2] and 4.2 in legs


def test_what_is_kept_for_a_reaction_is_said_again_for_the_next_one() -> None:
    """7.1, in a visit prima check made: FA5's next question is kept for EA3's corner
    remark (a reaction's next AB); EA3 replaces the remark with its message, whose first
    AB keeps the wheels FA5's question needs (its turn to the user) in turn. The trace
    says so a second time, naming that AB, so that the judge knows why FA5 waits (it
    read the wait for the message as lateness)."""
    from pathlib import Path

    from prima.judge import judge
    from prima.run import Run

    visit = Path(__file__).parents[1] / "data" / "visits" / "ea3-message-over-fa5-reply.xml"
    lines = Run(visit).run()
    kept = [ln.before for ln in lines if ln.kind.value == "hold" and ln.reason == "reserved"
            and ln.app == "fa5-video-timer"]
    assert len(set(kept)) >= 2, kept
    assert [r for r in judge(lines).reactions if r.late] == []


def test_a_stream_held_for_one_answer_then_another_is_said_to_be_held_for_each() -> None:
    """7.6 (1): the EA's explanation waits while it answers the user's question (from
    2.0 to 4.0); at 3.0 the user touches the robot and the FA answers with a nod (to
    7.0). Once the EA's words are said, the explanation is held for the FA's answer: the
    trace says so a second time, naming the FA, so that the judge knows why it waits past
    the EA's words (in a visit prima check made, it read that wait as lateness)."""
    h = Harness(duration={"Speak": 2.0, "Gesture": 4.0})
    m = h.mediator

    def answer(e: Event) -> None:
        if e.name == "speech":
            m.submit(Request("ea", (speak("The toilets are by the door."),), reactive=True,
                             reaction=True, user=True))

    ea = h.app("ea", AppKind.EA, on_event=answer)
    ea.listens_for = ("toilet",)
    h.app("fa", AppKind.FA, on_event=lambda e: e.name == "touched" and m.submit(Request(
        "fa", (call("Gesture", name="nod"),), order=RunningOrder.ASAP, reactive=True,
        reaction=True, user=True)))
    m.submit(Request("ea", (speak("This panel shows our laboratory."),
                            speak("Look at this robot."))))
    h.at(1.0, lambda: m.hear(Event("speech", {"words": "Where is the toilet?"})))
    h.at(3.0, lambda: m.post(Event("touched")))
    h.run(until=12.0)
    held = [(d.t, d.detail) for d in h.kinds(DecisionKind.HOLD)
            if d.app == "ea" and d.rule == Rule.ANSWERING]
    assert held == [(2.0, "while ea answers the user"), (4.0, "while fa answers the user")]


def test_what_an_apps_own_asap_request_drops_as_it_is_cut_has_no_end_event() -> None:
    """docs/pxml.md: a Command cancelled before it ended by a newer `order="asap"` request
    has no end event. The user says "Stop." over the EA's question; its handler, as soon
    as possible, says "All right." and asks again. The question, cut at a word boundary,
    is dropped: the EA is told it was cancelled, not that it ended, so that no no-input
    handler runs for it (EA1 went looking for its visitor and then asked twice: prima
    check of EA1 beside FA3, 1 run in 200)."""
    h = Harness(CUTS, duration={"QA": 4.0, "*": 1.0}, cut_after=0.2,
                config=MediatorConfig(barge_in=True, interrupt=True, blend=True))
    m = h.mediator
    ended: list[int] = []
    cancelled: list[int] = []

    def stop(e: Event) -> None:
        if e.name == "speech":
            m.submit(Request("ea", (speak("All right."),), order=RunningOrder.ASAP,
                             reactive=True, reaction=True, user=True))

    ea = h.app("ea", AppKind.EA, on_event=stop, on_ended=lambda cid, _o: ended.append(cid),
               on_cancelled=cancelled.append)
    ea.listens_for = ("stop",)
    (asked,) = m.submit(Request("ea", (call("QA", prompt="May I go to the next panel?",
                                            grammar="g"),)))
    h.at(1.0, lambda: m.hear(Event("speech", {"words": "Stop."})))
    h.run(until=10.0)
    assert [d.detail for d in h.kinds(DecisionKind.END) if d.command == "QA"] == ["dropped"]
    assert asked in cancelled and asked not in ended
