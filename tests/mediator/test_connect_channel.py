"""The connect-channel policy (thesis Sec. 5.3 (4)): before an utterance starts with
the robot facing away from a detectable user, the mediator turns the robot to the
user first, in the same stream."""

from __future__ import annotations


from prima.mediator import AppKind, DecisionKind, MediatorConfig, Outcome, Request, Rule
from prima.mediator.testing import Harness
from tests.mediator.helpers import Facing, call, req, speak




def starts(h: Harness) -> list[tuple[float, str, str, Rule]]:
    return [(d.t, d.app or "", d.command or "", d.rule) for d in h.starts()]


def test_an_unfaced_utterance_waits_for_a_turn_to_the_user() -> None:
    facing = Facing()
    h = Harness(duration={"FaceHuman": 1.5, "*": 2.0}, channel=facing)
    told: list[int] = []
    h.app("fa", AppKind.FA, on_ended=lambda cid, _o: told.append(cid))
    (cid,) = h.mediator.submit(req("fa", speak("What's the matter with you?")))
    h.run(until=10.0)
    assert starts(h) == [(0.0, "fa", "FaceHuman", Rule.CONNECT_CHANNEL),
                         (1.5, "fa", "Speak", Rule.FREE_DEVICES)]
    (turn,) = [d for d in h.decisions if d.kind is DecisionKind.REQUEST
               and d.rule is Rule.CONNECT_CHANNEL]
    assert (turn.precedes, turn.tree) == (cid, h.starts()[1].tree)  # the same stream
    assert told == [cid]  # the app hears of its own Command only


def test_a_faced_or_aimed_utterance_is_left_as_it_is() -> None:
    """Facing the user already; or the words are about what the robot aims at (a
    PointByHand before them, a FaceHumanAndSpeak, an app that says so)."""
    h = Harness(duration=1.0, channel=Facing(faced=True))
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("fa", speak("Hello.")))
    h.run(until=5.0)
    assert [c for _t, _a, c, _r in starts(h)] == ["Speak"]

    h = Harness(duration=1.0, channel=Facing())
    h.app("ea", AppKind.EA)
    h.mediator.submit(req("ea", call("PointByHand", toward="panel-1"), speak("Look at this.")))
    h.mediator.submit(req("ea", call("FaceHumanAndSpeak", text="Welcome.")))
    h.mediator.submit(Request("ea", (speak("The panel says so."),), face_user=False))
    h.run(until=20.0)
    assert "FaceHuman" not in [c for _t, _a, c, _r in starts(h)]


def test_no_channel_no_turn_and_words_wait_for_busy_wheels_to_turn_first() -> None:
    """Without a channel, no turn. With one, face first or wait (docs/rules.md 7.6 (3)):
    the FA's words never start unfaced to be early; they wait for the EA's 5 s drive
    on the wheels, which no reaction cuts, then for the turn to the user."""
    h = Harness(duration=2.0)
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("fa", speak("Hello.")))
    h.run(until=5.0)
    assert [c for _t, _a, c, _r in starts(h)] == ["Speak"]

    facing = Facing()
    h = Harness(duration={"SetSpeedAndTime": 5.0, "*": 1.0}, channel=facing)
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("ea", call("SetSpeedAndTime", speed=0.3, time=5.0)))
    h.mediator.submit(req("fa", speak("I am over here.")))
    h.run(until=10.0)
    assert [(t, c) for t, _a, c, _r in starts(h)] == [
        (0.0, "SetSpeedAndTime"), (5.0, "FaceHuman"), (6.0, "Speak")]


def test_a_reply_to_an_answer_is_turned_for_too() -> None:
    """An end-event reply continues its stream: the turn goes in before it."""
    facing = Facing()
    h = Harness(duration={"FaceHuman": 1.0, "QA": 3.0, "*": 2.0}, channel=facing)
    asked: list[int] = []

    def reply(cid: int, _o: Outcome) -> None:
        if cid in asked:
            facing.faced = False  # the user walked around the robot meanwhile
            h.mediator.submit(Request("fa", (speak("O.K."),), follows=cid))

    h.app("fa", AppKind.FA, on_ended=reply)
    asked.extend(h.mediator.submit(req("fa", call("QA", prompt="Shall we?", grammar="g"))))
    h.run(until=20.0)
    assert [(t, c) for t, _a, c, _r in starts(h)] == [
        (0.0, "FaceHuman"), (1.0, "QA"), (4.0, "FaceHuman"), (5.0, "Speak")]


def test_the_turn_waits_for_an_iteration_on_the_wheels() -> None:
    """Face first, or wait (docs/rules.md 7.6 (3)): a Topological Move's iteration (it
    breaks the channel) or a search's ends within a control period, and the reaction's
    turn outranks the next one: the turn waits for it, and the words for the turn. (No
    iteration is cut on this robot, which declares nothing interruptible.)"""
    def run(command: str) -> list[tuple[float, str, str]]:
        h = Harness(duration={"TopologicalMove": 0.5, "ActiveSensingHuman": 0.5,
                              "FaceHuman": 1.0, "*": 2.0},
                    outcome=lambda ab: Outcome(terminal=ab.iteration >= 5), channel=Facing())
        h.app("ea", AppKind.EA)
        h.app("fa", AppKind.FA)
        h.mediator.submit(req("ea", call(command, to="hall") if command == "TopologicalMove"
                              else call(command)))
        h.at(0.2, lambda: h.mediator.submit(
            Request("fa", (speak("Hee-hee!"),), reactive=True, reaction=True)))
        h.run(until=20.0)
        return [(t, a, c) for t, a, c, _r in starts(h)][:4]

    assert run("TopologicalMove")[:3] == [(0.0, "ea", "TopologicalMove"),
                                          (0.5, "fa", "FaceHuman"), (1.5, "fa", "Speak")]
    assert run("ActiveSensingHuman")[:3] == [(0.0, "ea", "ActiveSensingHuman"),
                                             (0.5, "fa", "FaceHuman"), (1.5, "fa", "Speak")]


def test_a_stream_suspended_after_its_turn_is_turned_for_again_when_it_resumes() -> None:
    """The FA's words wait for a turn to the user (to 1.5 s); meanwhile (at 1 s) the
    EA's reaction asks to turn the robot to its panel and speak about it: its words
    keep the speaker, the FA's stream is suspended. When the FA's stream resumes, the
    turn made before is undone: the robot turns to the user again before the words,
    with the restore-state policy on or off."""
    def run(config: MediatorConfig) -> list[tuple[float, str, str, Rule]]:
        facing = Facing()
        h = Harness(duration={"FaceHuman": 1.5, "*": 2.0}, channel=facing, config=config)
        h.app("fa", AppKind.FA)
        h.app("ea", AppKind.EA)
        h.mediator.submit(req("fa", speak("What's the matter with you?")))
        h.at(1.0, lambda: h.mediator.submit(Request(
            "ea", (call("SetDirection", toward="panel"), speak("Look at this panel.")),
            reactive=True, reaction=True, face_user=False)))
        h.at(1.5, lambda: setattr(facing, "faced", True))  # (the turn ends)
        h.at(2.0, lambda: setattr(facing, "faced", False))  # (the EA's turn to its panel)
        h.run(until=20.0)
        return starts(h)

    for config in (MediatorConfig(interrupt=True, blend=True),
                   MediatorConfig(restore_state=False, interrupt=True, blend=True)):
        assert run(config) == [(0.0, "fa", "FaceHuman", Rule.CONNECT_CHANNEL),
                               (1.5, "ea", "SetDirection", Rule.FREE_DEVICES),
                               (3.5, "ea", "Speak", Rule.REACTIVITY),
                               (5.5, "fa", "FaceHuman", Rule.CONNECT_CHANNEL),
                               (7.0, "fa", "Speak", Rule.FREE_DEVICES)]


def test_words_that_waited_after_their_turn_look_at_the_user_again() -> None:
    """Face first, or wait (docs/rules.md 7.6 (3)): the FA's words are turned for (to
    1.5 s); meanwhile the EA took the speaker (0.5 to 3.5 s). The user walks off to the
    side at 2.0 s: when the speaker is free, the FA's words, which waited after their
    turn, turn to the user again before they start, not 3.5 s later unfaced. Words that
    start in the instant their turn ends are not looked at twice (no second turn)."""
    facing = Facing()
    h = Harness(duration={"FaceHuman": 1.5, "Speak": 3.0}, channel=facing)
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    h.mediator.submit(req("fa", speak("What's the matter with you?")))
    h.at(0.5, lambda: h.mediator.submit(Request(
        "ea", (speak("This panel shows robots."),), face_user=False)))
    h.at(1.5, lambda: setattr(facing, "faced", True))  # (the turn ends)
    h.at(2.0, lambda: setattr(facing, "faced", False))  # (the user walks off)
    h.run(until=20.0)
    assert starts(h) == [(0.0, "fa", "FaceHuman", Rule.CONNECT_CHANNEL),
                         (0.5, "ea", "Speak", Rule.FREE_DEVICES),
                         (3.5, "fa", "FaceHuman", Rule.CONNECT_CHANNEL),
                         (5.0, "fa", "Speak", Rule.FREE_DEVICES)]
