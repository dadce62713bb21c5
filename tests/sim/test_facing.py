"""The simulator tells, while the robot says words, when its user goes off to the side
(docs/rules.md 7.6 (3): a run's mediator turns the robot back to them)."""

from __future__ import annotations

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
