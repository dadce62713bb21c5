"""The restore-state policy (thesis Sec. 5.3 (1), docs/rules.md 7.3 (1)): when a suspended
stream resumes with the robot moved away from where it was suspended, the mediator
first returns the robot to that pose, as part of the resumed stream."""

from __future__ import annotations

from collections.abc import Mapping

from prima.mediator import AppKind, DecisionKind, MediatorConfig, Request, Rule
from prima.mediator.testing import Harness
from prima.vocab import Value
from tests.mediator.helpers import call, speak

SUSPENDED_AT = {"x": 7.0, "y": 6.4, "heading": 98.8}


class Robot:
    """A robot that the other app's reaction moves away (``moved``)."""

    def __init__(self, moved: bool = True) -> None:
        self.moved = moved
        self.asked: list[Mapping[str, Value]] = []

    def unfaced(self) -> bool:
        return False

    def near(self, distance: float) -> bool:
        return True

    def pose(self) -> Mapping[str, Value]:
        return SUSPENDED_AT

    def displaced(self, pose: Mapping[str, Value]) -> bool:
        self.asked.append(pose)
        return self.moved


def explain_and_interrupt(robot: Robot, second: object = None,
                          config: MediatorConfig = MediatorConfig(),
                          face_user: bool = False) -> Harness:
    """The EA explains in two utterances (about its panel, unless ``face_user``); a
    touch at 0.5 s: the FA's reaction (an utterance, then a move) takes the speaker
    from EA's second utterance, which is suspended, and moves the robot."""
    h = Harness(duration={"SetPositionAndDirection": 3.0, "SetPosition": 3.0, "*": 2.0},
                channel=robot, config=config)
    told: list[int] = []
    h.app("ea", AppKind.EA, on_ended=lambda cid, _o: told.append(cid))
    h.app("fa", AppKind.FA)
    h.mediator.submit(Request("ea", (speak("This panel shows our lab."),
                                     second or speak("Look at this figure.")),
                              face_user=face_user))
    h.at(0.5, lambda: h.mediator.submit(
        Request("fa", (speak("What?"), call("SetSpeedAndTime", speed=0.3, time=2.0)),
                reactive=True, reaction=True)))
    h.run(until=30.0)
    h.told = told  # type: ignore[attr-defined]
    return h


def commands(h: Harness) -> list[tuple[float, str, str, Rule]]:
    return [(d.t, d.app or "", d.command or "", d.rule) for d in h.starts()]


def test_a_resumed_stream_first_returns_to_where_it_was_suspended() -> None:
    robot = Robot()
    h = explain_and_interrupt(robot)
    assert commands(h) == [
        (0.0, "ea", "Speak", Rule.FREE_DEVICES),
        (2.0, "fa", "Speak", Rule.REACTIVITY),
        (4.0, "fa", "SetSpeedAndTime", Rule.FREE_DEVICES),
        (6.0, "ea", "SetPositionAndDirection", Rule.RESTORE_STATE),
        (9.0, "ea", "Speak", Rule.FREE_DEVICES)]
    (suspend,) = [d for d in h.decisions if d.kind is DecisionKind.SUSPEND]
    (resume,) = [d for d in h.decisions if d.kind is DecisionKind.RESUME]
    (back,) = [d for d in h.decisions if d.kind is DecisionKind.REQUEST
               and d.rule is Rule.RESTORE_STATE]
    assert suspend.tree == resume.tree == back.tree  # part of the resumed stream
    assert resume.command == "SetPositionAndDirection"
    assert dict(back.calls[0].args) == SUSPENDED_AT
    assert robot.asked == [SUSPENDED_AT]  # once
    assert len(h.told) == 2  # type: ignore[attr-defined]  # the app hears of its own only


def test_before_words_to_the_user_only_the_position_is_restored() -> None:
    """Words addressed to the user: the connect-channel policy turns the robot to the
    user before them where it must, so the heading it had then does not matter."""
    h = explain_and_interrupt(Robot(), face_user=True)
    assert [(c, r) for _t, _a, c, r in commands(h)][-2:] == [
        ("SetPosition", Rule.RESTORE_STATE), ("Speak", Rule.FREE_DEVICES)]
    (back,) = [d for d in h.decisions if d.kind is DecisionKind.REQUEST
               and d.rule is Rule.RESTORE_STATE]
    assert dict(back.calls[0].args) == {"x": 7.0, "y": 6.4}


def test_not_moved_not_on_or_a_travelling_ab_no_return() -> None:
    for robot, config in ((Robot(moved=False), MediatorConfig()),
                          (Robot(), MediatorConfig(restore_state=False))):
        h = explain_and_interrupt(robot, config=config)
        assert [c for _t, _a, c, _r in commands(h)] == [
            "Speak", "Speak", "SetSpeedAndTime", "Speak"]
    # the resumed AB takes the robot somewhere itself: going back first is pointless
    h = explain_and_interrupt(Robot(), second=call("TopologicalMove", to="panel-2"))
    assert [c for _t, _a, c, _r in commands(h)][-1] == "TopologicalMove"
    assert Rule.RESTORE_STATE not in [r for *_x, r in commands(h)]


def test_before_an_ab_that_turns_the_robot_only_the_position_is_restored() -> None:
    h = explain_and_interrupt(Robot(), second=call("FaceHumanAndSpeak", text="Look."))
    assert [(c, r) for _t, _a, c, r in commands(h)][-2:] == [
        ("SetPosition", Rule.RESTORE_STATE), ("FaceHumanAndSpeak", Rule.FREE_DEVICES)]
    (back,) = [d for d in h.decisions if d.kind is DecisionKind.REQUEST
               and d.rule is Rule.RESTORE_STATE]
    assert dict(back.calls[0].args) == {"x": 7.0, "y": 6.4}


def test_before_words_that_aim_the_robot_only_the_position_is_restored() -> None:
    """A resumed explanation that turns to its panel and points at it as it speaks (a
    grouped SetDirection, PointByHand and Speak) first goes back to where it stood."""
    robot = Robot()
    h = Harness(duration={"SetPosition": 3.0, "*": 2.0}, channel=robot)
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA)
    h.mediator.submit(Request("ea", (speak("This panel shows our lab."),), face_user=False))
    h.mediator.submit(Request("ea", (call("SetDirection", toward="panel"),
                                     call("PointByHand", toward="panel"),
                                     speak("Look at this figure.")), group=True,
                              face_user=False))
    h.at(0.5, lambda: h.mediator.submit(
        Request("fa", (speak("What?"), call("SetSpeedAndTime", speed=0.3, time=2.0)),
                reactive=True, reaction=True)))
    h.run(until=30.0)
    assert [(c, r) for _t, _a, c, r in commands(h)][-2:] == [
        ("SetPosition", Rule.RESTORE_STATE),
        ("SetDirection+PointByHand+Speak", Rule.FREE_DEVICES)]



def test_the_return_waits_for_its_own_applications_other_words() -> None:
    """7.6 (3), in a visit prima check made: EA3's words at a corner are cut for FA6's
    answer to a touch; its message, asked for meanwhile, starts when the answer is
    over, and the corner's words are to be said again after a return to where they
    were suspended. That return, the mediator's own move, waits for the message's
    words (it turned the robot away from the visitor mid-sentence)."""
    from pathlib import Path

    from prima.judge import judge
    from prima.run import Run

    visit = Path(__file__).parents[1] / "data" / "visits" / "ea3-message-at-a-corner.xml"
    lines = Run(visit).run()
    held = [ln for ln in lines if ln.kind.value == "hold" and ln.reason == "keep-channel"
            and ln.command == "SetPositionAndDirection"]
    assert held and held[0].app == "ea3-navigate"
    assert judge(lines).of("unfaced") == ()
