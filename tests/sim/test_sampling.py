"""Pose samples (``Simulator.sample_poses``): at fixed instants; with ``moved``, those at
which nothing moves are skipped once a sample has seen the poses they would show, so that
a world standing still costs no sample however long it stands (a run's cost follows what
happens)."""

from __future__ import annotations

from prima.catalog import Catalog, CommandSpec, JointSpec, MoveJoint
from prima.sim import Pose, Simulator, TimedAction, UserScript, WorldMap
from tests.sim.helpers import call, runner, walk


def _sampled(moved: bool, *actions: TimedAction) -> list[float]:
    """When a robot standing at the origin, its user 1.5 m east of it, is sampled
    twice a second for 1,000 s."""
    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0),
                    user=UserScript(Pose(1.5, 0, 180), actions=actions))
    at: list[float] = []
    sim.sample_poses(2, lambda: at.append(sim.now()), moved=moved)
    sim.advance_to(1000.0)
    return at


def test_every_instant_is_sampled_whether_anything_moves_or_not() -> None:
    assert _sampled(False) == [k / 2 for k in range(1, 2001)]


def test_with_moved_a_world_standing_still_is_sampled_once() -> None:
    assert _sampled(True) == [0.5]


def test_with_moved_the_instants_the_user_walks_are_sampled_and_no_other() -> None:
    every = _sampled(False, walk(100.0, 1.5, 4.0))
    moved = _sampled(True, walk(100.0, 1.5, 4.0))
    walking = [t for t in moved if t > 0.5]
    assert set(moved) <= set(every)
    assert walking[0] == 100.5  # (the first instant after the user set off)
    assert walking == [k / 2 for k in range(201, 201 + len(walking))]  # (each, while walking)
    # (4 m at 0.3 m/s, a user's walk, about 13.3 s; then still again, and no more samples)
    assert 113.5 <= walking[-1] <= 114.0


def test_with_moved_a_joint_turning_alone_is_no_motion_to_sample() -> None:
    """A joint's angle is not a pose: while only the laser turns (150 degrees, 0.8 s) the
    poses stay as they were, and no instant is sampled after the first."""
    laser = JointSpec("laser-pan", "laser", -150.0, 150.0, 180.0)
    spec = CommandSpec("Light", frozenset({"laser"}), robot_specific=True,
                       perform=(MoveJoint(laser, to=-400.0),))
    r = runner("museum", Pose(9.5, 4, 90), catalog=Catalog.standard().extended([spec], {"laser"}))
    at: list[float] = []
    r.sim.sample_poses(20, lambda: at.append(r.sim.now()), moved=True)
    r.queue(call("Light"))
    r.run(5.0)
    assert r.ends("Light")[0].time > 0.8 and len(at) == 1 and at[0] < 0.1  # (the first)
