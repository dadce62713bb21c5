"""The simulator tells, while the robot says words, when its user goes off to the side
(docs/rules.md 7.6 (3): a run's mediator turns the robot back to them)."""

from __future__ import annotations

from prima.mediator import Outcome
from prima.sim import CommandRunner, Pose, Simulator, UserScript, WorldMap
from tests.sim.helpers import call, walk


def _talking(user_walks_to: tuple[float, float] | None, *, at: float = 1.0,
             says: str = "This panel shows research points of our laboratory, "
                         "and the figure above shows a wearable computer.") -> list[float]:
    """The robot at the origin facing east, its user 1.5 m east of it; it speaks (about
    5 s) from 0; the user walks to ``user_walks_to`` at ``at``. When it was told."""
    actions = () if user_walks_to is None else (walk(at, *user_walks_to),)
    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0),
                    user=UserScript(Pose(1.5, 0, 180), actions=actions))
    told: list[float] = []
    sim.watch_facing(30.0, lambda: told.append(sim.now()))
    runner = CommandRunner(sim)
    runner.queue(call("Speak", text=says))
    runner.run(8.0)
    return told


def test_the_user_walking_round_the_talking_robot_is_told_once() -> None:
    told = _talking((0.0, 1.5))
    assert len(told) == 1 and 1.0 < told[0] < 5.0


def test_a_user_who_stays_in_front_is_never_told() -> None:
    assert _talking(None) == []
    assert _talking((2.5, 0.2)) == []  # (walks off straight ahead: still faced)


def test_going_off_after_the_words_is_not_told() -> None:
    assert _talking((0.0, 1.5), at=6.0) == []


def test_new_words_with_the_user_still_off_are_told_again() -> None:
    """The user walks round the robot during its first words (told) and stands off to
    its side while nothing moves; then walks on slowly during its next words: told
    again (the watch starts afresh with each utterance: it missed the second, which
    began with them off)."""
    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0),
                    user=UserScript(Pose(1.5, 0, 180), speed=0.8,
                                    actions=(walk(1.0, 0.0, 1.5), walk(8.5, -0.6, 1.5, 0.3))))
    told: list[float] = []
    sim.watch_facing(30.0, lambda: told.append(sim.now()))
    runner = CommandRunner(sim)
    runner.queue(call("Speak", text="This panel shows research points of our laboratory, "
                                    "and the figure above shows a wearable computer."))
    runner.run(8.0)
    runner.queue(call("Speak", text="The next panel is about the robot you are talking to."))
    runner.run(14.0)
    assert len(told) == 2 and told[1] > 8.0, told


def _facing_a_walker(walks: bool) -> tuple[float, float]:
    """The robot faces east; its user, 1 m north of it, walks west at 0.4 m/s (or
    stands): Face Human. How far off the user is when it ends (degrees), and when."""
    import math

    actions = (walk(0.0, -3.0, 1.0),) if walks else ()
    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0),
                    user=UserScript(Pose(0, 1.0, 180), actions=actions, speed=0.4))
    runner = CommandRunner(sim)
    ended: list[tuple[float, float]] = []
    finished = sim.finished

    def noted(ab: int, outcome: Outcome) -> None:
        ended.append((math.degrees(abs(sim.world.user_bearing())), sim.now()))
        finished(ab, outcome)

    sim.finished = noted
    runner.queue(call("FaceHuman"))
    runner.run(6.0)
    (found,) = ended
    return found


def test_face_human_follows_a_user_who_walks_round_the_robot() -> None:
    """Face Human ends facing its user (within 5 degrees as it stops, a few more once it
    has stopped after one who walks on), whether they stand or walk."""
    off, _t = _facing_a_walker(walks=False)
    assert off <= 5.0
    off, t = _facing_a_walker(walks=True)
    assert off <= 10.0 and t < 4.0


def test_face_human_on_a_robot_still_driving_turns_as_it_brakes() -> None:
    """A move's leg ends with the robot still driving at speed: Face Human turns to the
    user at once, braking as it turns, rather than stopping first (a user to its left
    is faced sooner)."""
    import math

    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0),
                    user=UserScript(Pose(0.5, 2.0, 270)))
    headings: list[tuple[float, float]] = []
    sim.sample_poses(20, lambda: headings.append((sim.now(), math.degrees(
        sim.world.robot_angle()))))
    runner = CommandRunner(sim)
    sim.world.command(0.4, 0.0)  # (as a move's leg leaves it: driving on)
    runner.run(1.0)
    runner.queue(call("FaceHuman"))
    runner.run(6.0)
    turned = [h for t, h in headings if 1.0 < t <= 1.5]
    assert turned and max(turned) > 10.0  # (turning within half a second)


def test_a_turn_braked_to_a_new_command_keeps_turning() -> None:
    """A turn under way that is braked (stop) and given a turning rate (Face Human's
    follow) keeps turning: braking leaves the body its speed, as the controller thinks."""
    import math

    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0), user=UserScript(Pose(3, 0, 180)))
    world = sim.world
    world.turn_by(math.radians(170.0), lambda: None)
    sim.advance_to(0.8)  # (turning at full rate by now)
    world.stop()
    world.command(0.0, math.radians(90.0))
    before = world.robot_angle()
    sim.advance_to(1.3)
    assert math.degrees(world.robot_angle() - before) > 30.0


def test_face_human_far_off_does_not_turn_past_its_user() -> None:
    """The robot drives on (a move's leg left running) with its user far behind it
    (about 145 degrees off): Face Human turns at full rate, and brakes in time to face
    them: it never turns past them by more than a few degrees (it went 30 degrees past,
    braking from full rate only once it faced them)."""
    import math

    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0),
                    user=UserScript(Pose(-1.2, 0.8, 0)))
    offs: list[float] = []
    sim.sample_poses(20, lambda: offs.append(math.degrees(sim.world.user_bearing())))
    runner = CommandRunner(sim)
    sim.world.command(0.4, 0.0)
    runner.run(1.0)
    start = len(offs)
    runner.queue(call("FaceHuman"))
    runner.run(6.0)
    turned = offs[start:]
    assert turned[0] > 120.0 and abs(turned[-1]) <= 5.0
    assert min(turned) >= -5.0  # (the user is to its left all the way: never passed)
