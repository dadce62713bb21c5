"""Human detection worked out once per pose must answer exactly as working it out
afresh would."""

from __future__ import annotations

import math
import random

import pytest

from prima.run import Run
from prima.sim import Pose, Simulator, UserScript, WorldMap
from tests.sim.helpers import ROOT, clear_as_each_wall_says, world_map


def _sighted(robot: Pose, user: Pose) -> Simulator:
    return Simulator(WorldMap("open"), robot=robot, user=UserScript(user))


def test_a_turn_within_a_tick_is_seen_at_once() -> None:
    sim = _sighted(Pose(0, 0, 0), Pose(2, 0, 0))
    world, tick = sim.world, sim.kernel.tick
    assert world.sees_user(tick)[0]
    world.robot.angle = math.pi  # the robot turns its back on the user, same tick
    world.moved()
    assert not world.sees_user(tick)[0]
    assert world.sees_user(tick, any_direction=True)[0]  # still detectable around it


def test_the_camera_panning_within_a_tick_is_seen_at_once() -> None:
    sim = _sighted(Pose(0, 0, 0), Pose(2, 0, 0))
    world, tick = sim.world, sim.kernel.tick
    assert world.sees_user(tick)[0]
    world.head_pan.move(90.0, tick, 0)  # the head looks left, at once
    assert not world.sees_user(tick)[0]


def test_the_camera_panning_over_ticks_is_seen_where_it_looks_at_each() -> None:
    # nothing moves but the head, panning left over 100 ticks: the camera looks where
    # the head is at each tick asked (60 degrees wide: 30 either way)
    sim = _sighted(Pose(0, 0, 0), Pose(2, 0, 0))
    world = sim.world
    world.head_pan.move(90.0, 0, 100)
    assert [world.sees_user(t)[0] for t in (0, 30, 34, 100, 40)] == [
        True, True, False, False, False]
    assert world.sees_user(100, any_direction=True)[0]


def test_the_user_put_elsewhere_within_a_tick_is_seen_at_once() -> None:
    sim = _sighted(Pose(0, 0, 0), Pose(2, 0, 0))
    world, tick = sim.world, sim.kernel.tick
    assert world.sees_user(tick) == (True, 2.0)
    world.put_user(0, 2)  # left of the robot: out of the camera's view
    assert world.sees_user(tick) == (False, 2.0)
    world.put_user(3, 0)
    assert world.sees_user(tick) == (True, 3.0)


def test_a_step_moves_the_answer_on_even_at_the_same_tick_number() -> None:
    sim = _sighted(Pose(0, 0, 0), Pose(3.99, 0, 0))
    world, tick = sim.world, sim.kernel.tick
    assert world.sees_user(tick)[0]
    world.walk_user(10.0, 0.0)  # 20 cm per step: out of the camera's 4 m range
    world.step()
    seen, distance = world.sees_user(tick)
    assert not seen and distance > 4.0
    world.walk_user(0.0, 0.0)
    world.turn_by(math.pi, lambda _arrived: None)
    world.put_user(-2, 0)  # behind the robot, which is turning toward them
    assert not world.sees_user(tick)[0]
    for _ in range(200):
        world.step()
        if world.sees_user(tick)[0]:
            break
    else:
        raise AssertionError("the robot turned and never saw the user")


def _fresh(sim: Simulator, any_direction: bool) -> tuple[bool, float]:
    """Human detection worked out from the bodies' poses now (docs/scenarios.md: within
    the camera's range, inside its field of view, no wall in between)."""
    world = sim.world
    rx, ry = world.robot.position
    ux, uy = world.human.position
    d = math.hypot(ux - rx, uy - ry)
    if d > sim.spec.camera_range:
        return False, d
    if not any_direction:
        off = math.atan2(uy - ry, ux - rx) - world.camera_heading(sim.kernel.tick)
        if abs((off + math.pi) % (2 * math.pi) - math.pi) > math.radians(sim.spec.camera_fov) / 2:
            return False, d
    return world.clear(rx, ry, ux, uy), d


def _checked_run(name: str) -> int:
    """Run a thesis scenario, checking every answer of human detection against
    :func:`_fresh`; how many answers were checked."""
    run = Run(ROOT / "scenarios" / "thesis" / f"{name}.xml")
    sim = run.sim
    kept = sim.world.sees_user
    asked = 0

    def checking(tick: int, *, any_direction: bool = False) -> tuple[bool, float]:
        nonlocal asked
        answer = kept(tick, any_direction=any_direction)
        assert tick == sim.kernel.tick
        assert answer == _fresh(sim, any_direction), (name, tick, any_direction)
        asked += 1
        return answer

    sim.world.sees_user = checking  # type: ignore[method-assign]
    run.run()
    return asked


@pytest.mark.pure
def test_in_whole_runs_the_kept_answer_is_always_the_fresh_one() -> None:
    """Every answer human detection gives in runs that search, turn, track, guide and
    dance is the one working it out afresh from the poses gives."""
    asked = sum(_checked_run(name) for name in ("sample-03", "sample-09", "fig5-2", "sample-07"))
    assert asked > 5_000  # (about 8,000: fewer since wakes that would find nothing are skipped)


def test_a_segment_fattened_is_clear_only_of_every_wall_within_its_radius() -> None:
    """Chipmunk's query of the space asks only the shapes whose bounding boxes the thin
    segment crosses: a wall beside a segment, within its radius, went unseen, and a
    drive that passed by it was worked out without Chipmunk. Random segments about the
    office, some 1,000 of them by walls, are clear exactly when no wall, asked itself,
    lies within the radius."""
    world = Simulator(world_map("office"), robot=Pose(8, 5, 0)).world
    _blocked, beside = clear_as_each_wall_says(world, random.Random(5), (-1, -1), (22, 14),
                                               3.0, (0.0, 0.1, 0.26, 0.5), 3000)
    assert beside > 200
    # the case that showed it: 0.12 m from the wall x = 14, in no box the segment crosses
    assert not world.clear(13.5839, 12.1535, 13.8379, 10.3305, 0.3)
    assert world.clear(13.5839, 12.1535, 13.8379, 10.3305)
