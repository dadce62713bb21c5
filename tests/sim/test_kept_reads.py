"""The world reads its bodies' poses once per version (:attr:`World.version`) and keeps
them: every write of a pose must move the version on, or a later read answers with the
pose before it. Each writer is checked here against pymunk's own properties, read right
after it, with the kept reads taken just before it."""

from __future__ import annotations

import math
from collections.abc import Callable

import pytest

from prima.run import Run
from prima.sim import Pose, RobotSpec, Simulator, UserScript, WorldMap
from prima.sim._world import World, wrap_angle
from tests.sim.helpers import ROOT


def _world() -> World:
    return World(WorldMap("open"), RobotSpec(), 50, Pose(0.0, 0.0, 0), Pose(2.0, 1.0, 90))


def _kept(world: World) -> tuple[object, ...]:
    """What the world answers (each read kept once a version)."""
    return (world.robot_xy(), world.user_xy(), world.robot_angle(), world.robot_pose(),
            world.user_pose(), world.user_distance(), world.user_bearing(),
            world.sees_user(0), world.sees_user(0, any_direction=True))


def _fresh(world: World) -> tuple[object, ...]:
    """The same, worked out from pymunk's properties now."""
    r, h = world.robot, world.human
    rx, ry = r.position
    ux, uy = h.position
    d = math.hypot(ux - rx, uy - ry)
    bearing = wrap_angle(math.atan2(uy - ry, ux - rx) - r.angle)
    clear = world.clear(rx, ry, ux, uy)
    return ((rx, ry), (ux, uy), r.angle,
            Pose(rx, ry, math.degrees(r.angle) % 360.0),
            Pose(ux, uy, math.degrees(h.angle) % 360.0), d, bearing,
            (clear and abs(bearing) <= math.radians(world.spec.camera_fov) / 2
             and d <= world.spec.camera_range, d),
            (clear and d <= world.spec.camera_range, d))


def _ran(ticks: int = 400) -> Callable[[World], object]:
    return lambda w: w.run(0, ticks)


def _nothing(_world: World) -> None:
    pass


def _swaying(world: World) -> None:
    world.sway(0.5, 2, 100, 1)
    world.run(0, 30)


def _written(world: World) -> None:
    world.robot.position = (1.0, -1.0)  # (written from outside: then moved())
    world.robot.angle = 2.0
    world.human.position = (-1.0, 2.0)
    world.moved()


WRITERS: dict[str, tuple[Callable[[World], object], Callable[[World], object]]] = {
    # what sets the write up, and the write (the reads are kept in between)
    "put_user": (_nothing, lambda w: w.put_user(1.0, -2.0)),
    "user walking": (lambda w: w.walk_user(-0.3, 0.4), _ran(20)),
    "drive ends, snapped": (lambda w: w.drive_to(1.0, 0.5, lambda _a: None), _ran()),
    "drive blocked": (lambda w: w.drive_to(4.0, 2.0, lambda _a: None), _ran()),
    "turn ends at its angle": (lambda w: w.turn_by(1.0, lambda _a: None), _ran()),
    "turn stopped": (lambda w: (w.turn_by(3.0, lambda _a: None), w.run(0, 10), w.stop()),
                     _ran()),
    "velocity command": (lambda w: w.command(0.3, 0.5), _ran(30)),
    "end_sway": (_swaying, lambda w: w.end_sway()),
    "moved": (_nothing, _written),
}


@pytest.mark.parametrize("setup, write", WRITERS.values(), ids=WRITERS.keys())
def test_every_writer_of_a_pose_moves_the_kept_reads_on(
        setup: Callable[[World], object], write: Callable[[World], object]) -> None:
    world = _world()
    setup(world)
    before = _kept(world)
    assert before == _fresh(world)
    write(world)
    assert _fresh(world) != before  # (the write did move a body)
    assert _kept(world) == _fresh(world)


def test_the_user_turned_to_walk_moves_the_simulators_kept_poses_on() -> None:
    # (the simulator keeps the user's heading too, once a version: :meth:`Simulator.poses`)
    sim = Simulator(WorldMap("open"), robot=Pose(0, 0, 0), user=UserScript(Pose(2, 1, 90)))
    assert sim.poses()[1] == (2.0, 1.0, 90.0)
    sim.world.walk_user(-0.3, 0.0)
    assert sim.poses()[1] == (2.0, 1.0, 180.0)


def test_the_reads_are_kept_while_the_version_stays() -> None:
    # Kept, the reads do not look at the bodies again: a pose written without
    # ``moved()`` goes unseen until the version moves on (what the writers above check
    # they do not leave undone).
    world = _world()
    before = _kept(world)
    world.robot.position = (1.0, -1.0)
    world.robot.angle = 2.0
    world.human.position = (-1.0, 2.0)
    assert _kept(world) == before
    world.moved()
    assert _kept(world) == _fresh(world) != before


def _checked_run(name: str) -> int:
    """Run a thesis scenario, checking every read of the poses from outside the world
    against pymunk's properties; how many reads were checked."""
    run = Run(ROOT / "scenarios" / "thesis" / f"{name}.xml")
    world = run.sim.world
    asked = 0

    def checked(read: Callable[[], object], fresh: Callable[[], object]
                ) -> Callable[[], object]:
        def reading() -> object:
            nonlocal asked
            asked += 1
            kept = read()
            assert kept == fresh(), (name, read.__name__)
            return kept
        return reading

    # (``world.robot`` and ``world.human``: where the world has them, written to
    # Chipmunk if it worked steps out without it)
    world.robot_xy = checked(  # type: ignore
        world.robot_xy, lambda: tuple(world.robot.position))
    world.user_xy = checked(world.user_xy, lambda: tuple(world.human.position))  # type: ignore
    world.robot_angle = checked(world.robot_angle, lambda: world.robot.angle)  # type: ignore
    run.run()
    return asked


@pytest.mark.pure
def test_in_whole_runs_every_kept_read_is_the_fresh_one() -> None:
    """Every read of the poses in runs that drive, turn, track, guide, follow and dance
    is what pymunk's properties say at that moment."""
    assert sum(_checked_run(name) for name in ("sample-03", "sample-07")) > 8_000  # (about 9,500)
