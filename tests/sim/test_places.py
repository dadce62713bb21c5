"""The places near the robot, found by the map's grid of its places, are exactly those
a scan measuring every place finds, at the same ticks."""

from __future__ import annotations

import math
import random

import pytest

from prima.errors import SimulationError
from prima.sim import CommandRunner, Place, PlaceKind, Pose, Simulator, Wall, WorldMap
from tests.sim.helpers import call, clear_as_each_wall_says, world_map
from tests.work import bytecodes

RADIUS = 1.5  # the robot spec's passing radius


def _scan(places: tuple[Place, ...], x: float, y: float, radius: float) -> list[int]:
    """What the simulator did before the spatial index: measure every place."""
    return [i for i, p in enumerate(places) if math.hypot(p.x - x, p.y - y) <= radius]


def _crowded(n: int, seed: int, size: float = 30.0) -> WorldMap:
    """A wall-less floor with ``n`` places: random ones, some on a shared spot, and a
    row of them exactly one passing radius from (10, 10) along the axes."""
    rnd = random.Random(seed)
    spots = [(rnd.uniform(0, size), rnd.uniform(0, size)) for _ in range(n)]
    spots += spots[:5]  # places on the very same spot
    spots += [(10 + RADIUS, 10.0), (10 - RADIUS, 10.0), (10.0, 10 + RADIUS), (10.0, 10 - RADIUS)]
    places = tuple(Place(f"p{i}", PlaceKind.POINT, round(x, 3), round(y, 3))
                   for i, (x, y) in enumerate(spots))
    return WorldMap("crowded", places=places)


def test_places_near_finds_exactly_what_a_scan_of_every_place_finds() -> None:
    floor = _crowded(600, seed=1)
    world = Simulator(floor).world
    rnd = random.Random(2)
    points = [(10.0, 10.0)] + [(rnd.uniform(-2, 32), rnd.uniform(-2, 32)) for _ in range(3000)]
    for x, y in points:
        for radius, slack in ((RADIUS, 1.0), (RADIUS, 0.0), (0.7, 2.0)):
            found, _clear = world.places_near(x, y, radius, slack)
            assert found == _scan(floor.places, x, y, radius), (x, y, radius)
    assert len(world.places_near(10.0, 10.0, RADIUS)[0]) >= 4  # the places on the radius


def _to_segment(px: float, py: float, ax: float, ay: float, bx: float, by: float) -> float:
    """How far the point p is from the segment from a to b."""
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    k = 0.0 if length2 == 0.0 else min(max(((px - ax) * dx + (py - ay) * dy) / length2, 0), 1)
    return math.hypot(ax + k * dx - px, ay + k * dy - py)


def _crossing(a: tuple[float, float, float, float], b: tuple[float, float, float, float]
              ) -> bool:
    def side(x1: float, y1: float, x2: float, y2: float, x: float, y: float) -> float:
        return (x2 - x1) * (y - y1) - (y2 - y1) * (x - x1)
    return (side(*a, *b[:2]) * side(*a, *b[2:]) < 0
            and side(*b, *a[:2]) * side(*b, *a[2:]) < 0)


def _between(a: tuple[float, float, float, float], b: tuple[float, float, float, float]
             ) -> float:
    """How far two segments are from each other (x1, y1, x2, y2 each)."""
    if _crossing(a, b):
        return 0.0
    return min(_to_segment(*a[:2], *b), _to_segment(*a[2:], *b),
               _to_segment(*b[:2], *a), _to_segment(*b[2:], *a))


def test_the_grid_offers_every_place_within_reach_of_a_segment_each_once() -> None:
    floor = WorldMap("signed", places=tuple(
        Place(f"p{i}", PlaceKind.POINT, x, y)
        for i, (x, y) in enumerate([(-3.0, -3.0), (-0.5, 0.5), (0.0, 0.0), (2.0, 2.0),
                                    (3.99, -4.0), (40.0, 40.0)])))
    crowded = _crowded(300, seed=6)
    rnd = random.Random(5)
    for _ in range(2000):
        for where, size in ((floor, 6.0), (crowded, 32.0)):
            ax, ay = rnd.uniform(-size, size), rnd.uniform(-size, size)
            bx, by = ax + rnd.uniform(-5, 5), ay + rnd.uniform(-5, 5)
            if rnd.random() < 0.1:
                bx, by = ax, ay  # (a point)
            reach = rnd.choice([0.0, 0.5, 1.5, 2.5])
            inside = {i for i, p in enumerate(where.places)
                      if _to_segment(p.x, p.y, ax, ay, bx, by) <= reach}
            offered = where.places_along(ax, ay, bx, by, reach)
            assert inside <= set(offered) and len(offered) == len(set(offered))
    assert floor.places_along(1.0, 1.0, 1.0, 1.0, 0.5) == [2]  # (a point: one square)
    assert len(crowded.places_along(10.0, 10.0, 12.0, 10.0, 1.0)) < 60  # (of 309)
    assert sorted(floor.places_along(-1e6, -1e6, 1e6, 1e6, 0.0)) == list(range(6))  # (all,
    # found without a walk over a million squares)


def _scattered(n: int, seed: int) -> WorldMap:
    """``n`` walls at random on a floor of 60 m: short and long, thin and thick, some
    of them longer than a map files by square."""
    rnd = random.Random(seed)
    walls = []
    for i in range(n):
        x, y = rnd.uniform(0, 60), rnd.uniform(0, 60)
        length = 200.0 if i % 25 == 0 else rnd.uniform(0.0, 8.0)
        heading = rnd.uniform(0, 2 * math.pi)
        walls.append(Wall(x, y, round(x + length * math.cos(heading), 3),
                          round(y + length * math.sin(heading), 3),
                          rnd.choice([0.05, 0.1, 0.4, 3.0])))
    return WorldMap("scattered", walls=tuple(walls))


def test_the_grid_offers_every_wall_within_reach_of_a_segment_each_once() -> None:
    floor = _scattered(400, seed=7)
    rnd = random.Random(8)
    few = 0
    for _ in range(1500):
        ax, ay = rnd.uniform(-5, 65), rnd.uniform(-5, 65)
        length, heading = rnd.uniform(0.0, 6.0), rnd.uniform(0, 2 * math.pi)
        bx, by = ax + length * math.cos(heading), ay + length * math.sin(heading)
        reach = rnd.choice([0.0, 0.1, 0.3, 1.0])
        near = {i for i, w in enumerate(floor.walls)
                if _between((w.x1, w.y1, w.x2, w.y2), (ax, ay, bx, by))
                <= reach + w.thickness / 2}
        offered = floor.walls_along(ax, ay, bx, by, reach)
        assert near <= set(offered) and len(offered) == len(set(offered))
        few += len(offered) < 60
    assert few > 1400  # (of 400 walls, the 16 long ones always among them)
    assert sorted(floor.walls_along(-1e4, -1e4, 1e4, 1e4, 0.5)) == list(range(400))


def test_a_fattened_segment_is_clear_of_a_building_of_walls_as_each_wall_asked_says(
) -> None:
    """World.clear asks only the walls the map files near the segment: its answer is
    asking every wall's."""
    floor = _scattered(300, seed=9)
    world = Simulator(floor, robot=Pose(-50, -50, 0)).world
    assert sum(s.body is world.space.static_body for s in world.space.shapes) == 300
    blocked, _beside = clear_as_each_wall_says(world, random.Random(10), (-5, -5), (70, 70),
                                               6.0, (0.0, 0.1, 0.3, 1.0), 1500)
    assert 300 < blocked < 1200


@pytest.mark.parametrize("at", [math.inf, -math.inf, math.nan])
def test_a_map_built_in_python_refuses_a_place_or_a_wall_at_no_finite_position(
        at: float) -> None:
    """A map file's numbers are bounded; a map built in Python says what is wrong with it
    (its places are filed by squares, which a position at infinity has none of)."""
    with pytest.raises(SimulationError, match="not at a finite position"):
        WorldMap("m", places=(Place("a", PlaceKind.HALL, at, 0.0),))
    with pytest.raises(SimulationError, match="not at a finite position"):
        WorldMap("m", walls=(Wall(0.0, 0.0, 1.0, at),))


def test_the_answer_holds_as_long_as_places_near_says() -> None:
    floor = _crowded(600, seed=3)
    world = Simulator(floor).world
    rnd = random.Random(4)
    for _ in range(500):
        x, y = rnd.uniform(0, 30), rnd.uniform(0, 30)
        found, clear = world.places_near(x, y, RADIUS, 1.0)
        assert clear <= 1.0
        for _ in range(20):  # anywhere within the clearance: the same places
            a, r = rnd.uniform(0, 2 * math.pi), rnd.uniform(0, max(clear, 0.0))
            qx, qy = x + r * math.cos(a), y + r * math.sin(a)
            if math.hypot(qx - x, qy - y) < clear:
                assert _scan(floor.places, qx, qy, RADIUS) == found


class _Scanning(Simulator):
    """The simulator as it was: every sensing tick measures every place."""

    def _check_passing(self) -> None:
        x, y = self.world.robot.position
        for place in self.map.places:
            near = math.hypot(place.x - x, place.y - y) <= self.spec.passing_radius
            if near and place.name not in self._near:
                self._near.add(place.name)
                if not self.navigating:
                    self.emit("place-reached", {"place": place.name, "kind": place.kind.value})
            elif not near:
                self._near.discard(place.name)


@pytest.mark.pure
def test_places_passed_are_reported_at_the_same_ticks_as_measuring_every_place() -> None:
    floor = _crowded(400, seed=5, size=20.0)
    reports = []
    for kind in (Simulator, _Scanning):
        r = CommandRunner(kind(floor, robot=Pose(10, 10, 0)))
        for spin in (12.0, -7.0, 25.0, 0.0, -15.0, 4.0):  # a wandering drive, no route
            r.queue(call("SetSpeedAndTime", speed=0.4, time=20.0, spin=spin))
        r.run(130)
        reports.append([(e.time, e.data["place"]) for e in r.events("place-reached")])
    assert len(reports[0]) > 50
    assert reports[0] == reports[1]


@pytest.mark.pure
def test_a_route_between_two_places_is_the_shortest_path_worked_out_once() -> None:
    # A move asks for the rest of its route at each of its iterations: the map works each
    # pair out once (it never changes), and answers as the search does.
    museum = world_map("museum")
    names = [p.name for p in museum.places]
    for start in names:
        for goal in names:
            path = museum.shortest_path({start: 0.0}, {goal: 0.0})
            assert [p.name for p in museum.route(start, goal)] == path
    assert museum.route("nowhere", names[0]) == museum.route(names[0], "nowhere") == ()
    fresh = WorldMap(museum.name, museum.walls, museum.places, museum.edges)
    first = bytecodes(lambda: fresh.route(names[0], names[-1]))
    again = bytecodes(lambda: fresh.route(names[0], names[-1]))
    assert len(fresh.route(names[0], names[-1])) > 2
    assert again < 0.1 * first, (again, first)


def test_a_route_to_a_target_asked_again_is_the_one_a_fresh_simulator_plans() -> None:
    # The places a target is reached from straight are kept for the last target (the
    # walls stand still): asked in turns, each route is the one a fresh simulator plans.
    asks = [(1.0, 1.0, 9.0, 6.0, 0.0), (1.0, 1.0, 9.0, 6.0, 0.3), (2.0, 6.0, 9.0, 6.0, 0.3),
            (9.0, 6.0, 1.0, 1.0, 0.0), (2.0, 6.0, 9.0, 6.0, 0.3), (8.0, 2.0, 9.0, 6.0, 0.0)]
    sim = Simulator(world_map("museum"))
    for ask in asks * 2:
        assert sim.route(*ask) == Simulator(world_map("museum")).route(*ask), ask


def test_a_move_from_off_the_map_joins_it_at_a_place_with_none_on_its_way() -> None:
    """A place 0.4 m beside the straight way to the goal, in a square the way does not
    cross, is on the way (within ON_THE_WAY): the robot joins the map there, not at the
    goal, and the map's grid finds it as a scan of every place would."""
    floor = WorldMap("way", places=(
        Place("goal", PlaceKind.POINT, 10.0, 5.9), Place("beside", PlaceKind.POINT, 5.0, 6.3),
        Place("far", PlaceKind.POINT, 5.0, 0.5),
        *(Place(f"away-{i}", PlaceKind.POINT, 40.0 + 3 * i, 40.0) for i in range(20))),
        edges=(("goal", "beside"), ("beside", "far")))  # (more places than squares on the way)
    at, way = Simulator(floor, robot=Pose(0.3, 5.9, 0)).plan("goal")
    assert at is None and [p.name for p in way] == ["beside", "goal"]
