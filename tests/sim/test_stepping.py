"""The world stepped a stretch at a time (:meth:`World.run`, as the simulator steps it)
ends each stretch exactly as stepping it one :meth:`World.step` at a time does: the
same poses and speeds to the last bit, the same motions ended at the same ticks. And
it costs less: a stretch of steps runs in a loop of its motion's own, a straight
drive cruising at its top speed does only its push and lag checks at each step, and a
push check reads the robot's speed only after a step in which it touched something."""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable

import pytest

from prima.sim import Pose, RobotSpec, WorldMap
from prima.sim._world import World
from tests.sim.helpers import world_map
from tests.work import bytecodes

Stepper = Callable[[World, int, int], tuple[int, Callable[[], None] | None]]
Action = Callable[[World, list[object]], None]


def _one_by_one(world: World, tick: int, bound: int) -> tuple[int, Callable[[], None] | None]:
    """:meth:`World.run` as single steps: what the simulator did before it."""
    while world.mode or world.human_moving or tick < world.joints_until or world.swaying:
        done = world.step()
        tick += 1
        if done is not None or tick >= bound:
            return tick, done
    return tick, None


def _run(world: World, tick: int, bound: int) -> tuple[int, Callable[[], None] | None]:
    return world.run(tick, bound)


def _state(world: World) -> tuple[object, ...]:
    r, h = world.robot, world.human
    return (tuple(r.position), r.angle, tuple(r.velocity), r.angular_velocity,
            tuple(h.position), h.angle, tuple(h.velocity), world.mode, world.version,
            world._s, world._v, world._w, world._steps, world.swaying)


def _play(stepper: Stepper, robot: Pose, user: Pose, actions: dict[int, Action],
          until: int, state: Callable[[World], object] = _state,
          worlds: list[World] | None = None) -> list[object]:
    """Steps a fresh museum world to ``until`` in stretches of changing lengths (cut at
    the ticks of ``actions``), recording the ``state`` after each stretch and each end
    (and the world in ``worlds``)."""
    world = World(world_map("museum"), RobotSpec(), 50, robot, user)
    if worlds is not None:
        worlds.append(world)
    log: list[object] = []
    lengths = itertools.cycle((5, 1, 3, 5, 7, 2, 40))
    tick = 0
    while tick < until:
        if tick in actions:
            actions[tick](world, log)
        bound = min([tick + next(lengths), until] + [t for t in actions if t > tick])
        if not (world.mode or world.human_moving or tick < world.joints_until
                or world.swaying):
            tick = bound
            continue
        tick, done = stepper(world, tick, bound)
        if done is not None:
            done()
        log.append((tick, state(world)))
    log.append(_state(world))
    return log


def _drive(x: float, y: float, speed: float = math.inf) -> Action:
    return lambda w, log: log.append(("drive", w.drive_to(x, y, log.append, speed)))


def _turn(angle: float) -> Action:
    return lambda w, log: log.append(("turn", w.turn_by(angle, log.append)))


def _walk(vx: float, vy: float) -> Action:
    return lambda w, _log: w.walk_user(vx, vy)


CASES: dict[str, tuple[Pose, Pose, dict[int, Action], int]] = {
    # idle while the user walks past, then into the robot and on (a push to hold off)
    # (against a wall)
    "idle-pushed": (Pose(6.0, 2.0, 0), Pose(9.0, 2.1, 0),
                    {0: _walk(-0.3, 0.0), 90: _walk(-1.0, 0.0), 300: _walk(0.0, 0.0)}, 400),
    # a long drive: accelerating, cruising, braking, arriving
    "drive": (Pose(5.0, 2.0, 0), Pose(8.0, 6.0, 0), {0: _drive(14.0, 5.0)}, 1400),
    # a drive into a wall (blocked: it lags behind)
    "drive-walled": (Pose(1.5, 1.5, 0), Pose(8.0, 6.0, 0), {0: _drive(6.0, 1.5)}, 500),
    # a drive slowed, then sped up again under way (a blend), and a second drive
    "drive-limited": (Pose(1.5, 1.5, 0), Pose(8.0, 6.0, 0),
                      {0: _drive(6.0, 1.5), 60: lambda w, _log: w.speed_limit(0.2),
                       140: lambda w, _log: w.speed_limit(math.inf),
                       400: _drive(2.0, 2.5, 0.3)}, 900),
    # a drive at a user standing in the way (pushed, then blocked: it lags behind)
    "drive-blocked": (Pose(1.5, 1.5, 0), Pose(3.5, 1.5, 0), {0: _drive(6.0, 1.5)}, 500),
    # a drive at a user walking into the robot
    "drive-met": (Pose(5.0, 2.0, 0), Pose(12.0, 2.05, 0),
                  {0: _drive(14.0, 2.0), 1: _walk(-0.6, 0.0)}, 800),
    # turns, one while the user walks into the robot
    "turns": (Pose(4.0, 2.0, 0), Pose(6.0, 2.0, 0),
              {0: _turn(2.5), 30: _walk(-0.8, 0.0), 100: _turn(-4.0)}, 400),
    # turns in the open, the user walking up from far off and into the robot as it turns
    "turns-in-the-open": (Pose(6.0, 2.0, 0), Pose(9.0, 2.1, 0),
                          {0: _turn(2.5), 20: _walk(-0.3, 0.0), 100: _turn(-4.0),
                           130: _walk(-1.0, 0.0), 200: _turn(1.0)}, 400),
    # velocity commands: speeding up, turning, stopping (with whoever waits told)
    "velocity": (Pose(2.0, 2.0, 0), Pose(8.0, 6.0, 0),
                 {0: lambda w, _log: w.command(0.3, 0.0),
                  60: lambda w, _log: w.command(0.3, 0.5),
                  120: lambda w, _log: w.command(0.0, -0.4),
                  180: lambda w, log: log.append(("stop", w.stop(lambda: log.append("still"))))},
                 400),
    # a sway alone, then over a drive; a joint moving meanwhile
    "sway": (Pose(3.0, 3.0, 0), Pose(8.0, 6.0, 0),
             {0: lambda w, _log: w.sway(0.3, 2, 60, 1), 80: _drive(3.0, 5.5),
              90: lambda w, _log: w.sway(0.2, 3, 90, 2),
              300: lambda w, _log: setattr(w, "joints_until", 330)}, 600),
    # a joint moving while nothing else does, twice
    "joint": (Pose(3.0, 3.0, 0), Pose(8.0, 6.0, 0),
              {10: lambda w, _log: setattr(w, "joints_until", 37),
               50: lambda w, _log: setattr(w, "joints_until", 121)}, 200),
}


def _put(x: float, y: float) -> Action:
    return lambda w, _log: w.put_user(x, y)


def _teleport(x: float, y: float) -> Action:
    def act(w: World, _log: list[object]) -> None:
        w.robot.position = (x, y)
        w.moved()
    return act


CASES.update({
    # the user put at the robot and walking into it, after stretches untouched
    "put-at-robot": (Pose(6.0, 2.0, 0), Pose(14.0, 2.05, 0),
                     {0: _walk(-0.5, 0.0), 120: _put(6.6, 2.05), 160: _turn(1.0)}, 400),
    # the robot put next to a user walking into it
    "robot-put-at-user": (Pose(3.0, 3.0, 0), Pose(9.0, 2.05, 0),
                          {0: _walk(-0.2, 0.0), 60: _teleport(8.3, 2.0)}, 300),
    # a user far off, walking slowly, then fast into the robot
    "faster": (Pose(6.0, 2.0, 0), Pose(8.5, 2.05, 0),
               {0: _walk(-0.001, 0.0), 50: _walk(-3.0, 0.0), 70: _walk(-0.5, 0.0)}, 300),
    # drives in the open, the user walking into the second's path (it is blocked)
    "drive-crossed": (Pose(6.0, 2.0, 0), Pose(12.5, 4.5, 0),
                      {0: _drive(9.0, 2.0), 150: _drive(12.0, 6.5), 160: _walk(-0.25, 0.0)},
                      700),
    # a velocity command into a wall from far off, then turning along it
    "velocity-walled": (Pose(8.0, 2.0, 270), Pose(14.0, 7.0, 0),
                        {0: lambda w, _log: w.command(0.5, 0.0),
                         300: lambda w, _log: w.command(0.5, 0.6)}, 500),
    # a slow velocity command, the user walking into the robot from behind and stopping:
    # the push leaves the robot the user's speed (a steady command sets none again), on
    # to the wall
    "velocity-pushed": (Pose(8.0, 4.0, 0), Pose(5.0, 4.0, 0),
                        {0: lambda w, _log: w.command(0.2, 0.0), 1: _walk(1.2, 0.0),
                         130: _walk(0.0, 0.0)}, 700),
})


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_stretch_run_at_once_ends_as_stepped_one_step_at_a_time(case: str) -> None:
    robot, user, actions, until = CASES[case]
    expected = _play(_one_by_one, robot, user, actions, until)
    assert _play(_run, robot, user, actions, until) == expected
    assert len(expected) > 10


def _in_chipmunk(world: World, tick: int, bound: int
                 ) -> tuple[int, Callable[[], None] | None]:
    """:meth:`World.run` with every step Chipmunk's: the robot is never calm enough to
    glide."""
    world._persist = 1 << 30
    return world.run(tick, bound)


def _kept(world: World) -> str:
    """What the world says of the poses (its kept reads: a glided user is not written to
    Chipmunk for them), to the last bit."""
    return repr((world.robot_xy(), world.robot_angle(), world.user_xy(), world.version,
                 world.mode, world._s, world._v))


def test_steps_worked_out_without_chipmunk_end_as_chipmunk_steps_them() -> None:
    # Idle or turning in place, with the user out of reach, a stretch is worked out
    # without Chipmunk (World._glides): every stretch ends as Chipmunk's steps end it, to
    # the last bit, the user walking into the robot and pushing it included; and at the
    # end the bodies in Chipmunk are where they would be.
    glided = 0
    for case in sorted(CASES):
        robot, user, actions, until = CASES[case]
        worlds: list[World] = []
        expected = _play(_in_chipmunk, robot, user, actions, until, _kept)
        assert _play(_run, robot, user, actions, until, _kept, worlds) == expected, case
        assert worlds[0].glided < until
        glided += worlds[0].glided
    assert glided > 4000  # (of their 8,900 steps)


def test_a_user_glided_up_to_the_robot_pushes_it_as_in_chipmunk() -> None:
    # Walking at it from far off, the user is moved without Chipmunk until the stretch
    # that could bring them within reach: that one Chipmunk steps, and the push is the
    # same. Stretches of every length from every tick on the way.
    def walked(stepper: Stepper, ticks: int, length: int) -> tuple[str, int]:
        world = World(world_map("museum"), RobotSpec(), 50, Pose(6.0, 2.0, 0),
                      Pose(9.0, 2.1, 0))
        world.walk_user(-1.2, 0.0)
        tick = 0
        while tick < ticks:
            tick = stepper(world, tick, min(ticks, tick + length))[0]
        return repr(_state(world)), world.glided

    for length in (1, 3, 7, 25):
        for ticks in (60, 90, 101, 102, 103, 110, 140):
            expected, none = walked(_in_chipmunk, ticks, length)
            got, glided = walked(_run, ticks, length)
            assert got == expected, (length, ticks)
            assert none == 0 and (glided > 0 or length > ticks)


def test_a_robot_left_the_least_speed_drifts_as_in_chipmunk() -> None:
    # A push can leave an idle robot a speed too small for the wheels to hold
    # (World._hold: up to 1e-9 m/s); its steps then move it, so Chipmunk steps them.
    def drifted(stepper: Stepper) -> tuple[str, int]:
        world = _fresh()
        world.walk_user(0.0, -0.5)
        world.robot.velocity = (1e-10, 0.0)
        tick = 0
        while tick < 200:
            tick = stepper(world, tick, tick + 7)[0]
        return repr(_state(world)), world.glided

    assert drifted(_run) == drifted(_in_chipmunk)


def test_a_cruise_ends_where_the_drive_brakes_whatever_stretch_it_ends_in() -> None:
    # A stretch run as cruising must end before the step that brakes: from each tick
    # near the first braking step, stretches of each length end as single steps do.
    def driving(ticks: int) -> World:
        world = _fresh()
        world.drive_to(3.0, 0.0, lambda _arrived: None)
        for _ in range(ticks):
            world.step()
        return world

    braking = next(t for t in range(1000) if driving(t + 1)._v < driving(t)._v)
    for start in range(braking - 12, braking + 1):
        assert driving(start)._v == driving(start)._vmax
        for length in range(1, 13):
            one, many = driving(start), driving(start)
            assert many.run(start, start + length) == (start + length, None)
            for _ in range(length):
                assert one.step() is None
            assert _state(one) == _state(many), (start, length)


def _fresh() -> World:
    return World(WorldMap("open"), RobotSpec(), 50, Pose(0.0, 0.0, 0), Pose(5.0, 5.0, 0))


@pytest.mark.pure
def test_an_idle_stretch_costs_a_fraction_of_its_single_steps() -> None:
    # While only the user walks, a step of a stretch is the physics step and a look at
    # the robot's speed: about 24 bytecodes, where a single step() (a stretch of one)
    # pays for choosing its loop too.
    one, many = _fresh(), _fresh()
    one.walk_user(0.0, -0.5)
    many.walk_user(0.0, -0.5)
    stepped = bytecodes(lambda: [one.step() for _ in range(50)]) / 50
    run = bytecodes(lambda: many.run(0, 50)) / 50
    assert run < 0.4 * stepped, (run, stepped)
    assert _state(one) == _state(many)


@pytest.mark.pure
def test_a_cruising_drive_does_only_its_checks_at_each_step() -> None:
    # At its top speed, far from braking: about 56 bytecodes a step, 100 when each step
    # works its speed out again (as accelerating and braking do, and a stretch of one).
    one, many = _fresh(), _fresh()
    for world in (one, many):
        world.drive_to(20.0, 0.0, lambda _arrived: None)
        world.run(0, 100)
        assert world._v == world._vmax
    cruising = bytecodes(lambda: many.run(100, 150)) / 50
    for _ in range(50):
        one.step()
    assert cruising < 70, cruising
    assert _state(one) == _state(many)


@pytest.mark.pure
@pytest.mark.parametrize("motion", ["idle", "drive", "turn"])
def test_a_stretch_reads_the_robot_s_speed_only_after_a_step_that_touched(
        motion: str, monkeypatch: pytest.MonkeyPatch) -> None:
    # A push check reads the speed through Chipmunk (a call that releases the GIL:
    # some 850 instructions compiled, for a copy of two floats): after a stretch's
    # first step, and after each step in which the robot touched something. Untouched,
    # ten stretches of ten steps read it ten times, where each step read it before.
    import prima.sim._world as world_module

    reads = [0]
    real = world_module._cpBodyGetVelocity

    def counted(body: object) -> object:
        reads[0] += 1
        return real(body)

    monkeypatch.setattr(world_module, "_cpBodyGetVelocity", counted)
    world = _fresh()
    world.walk_user(0.0, -0.1)  # (idle: something moves, far off)
    if motion == "drive":
        world.drive_to(20.0, 0.0, lambda _arrived: None)
    elif motion == "turn":
        world.turn_by(30.0, lambda _arrived: None)
    reads[0] = 0  # (a motion's start may look too: not a stretch's)
    for tick in range(0, 100, 10):
        world.run(tick, tick + 10)
    assert reads[0] <= 10, reads[0]
    assert not world._touched[0]


def _velocity_step(world: World) -> None:
    """One step of the velocity command, worked out in full (each speed toward the
    command's within its acceleration): what a stretch did at every step before it
    kept a speed and a rate that no longer change."""
    a, al = world._a_dt, world._alpha_dt
    cmd_v, cmd_w, v, w = world._cmd_v, world._cmd_w, world._v, world._w
    dv, dw = cmd_v - v, cmd_w - w
    nv = v + (dv if -a <= dv <= a else (a if dv > 0 else -a))
    nw = w + (dw if -al <= dw <= al else (al if dw > 0 else -al))
    body = world.robot
    if nv != 0.0 and (nv != v or w != 0.0 or nw != w):
        body.velocity = (math.cos(body.angle) * nv, math.sin(body.angle) * nv)
    elif nv == 0.0 and v != 0.0:
        body.velocity = (0.0, 0.0)
    if nw != w:
        body.angular_velocity = nw
    world._v, world._w = nv, nw
    world.space.step(world.dt)
    world.version += 1


@pytest.mark.parametrize("v, w", [(0.3, 0.0), (0.3, 0.5), (0.0, -0.4), (-0.2, 0.7)])
def test_a_steady_velocity_command_steps_as_worked_out_in_full(v: float, w: float) -> None:
    # Once the speed and the rate stay as they are, a stretch only steps (and sets the
    # velocity along a heading that turns): to the last bit what working each step out
    # in full gives, from the ramp on.
    one, many = _fresh(), _fresh()
    for world in (one, many):
        world.command(v, w)
    for _ in range(150):
        _velocity_step(one)
    assert many.run(0, 150) == (150, None)
    assert _state(one) == _state(many)
    assert (many._v, many._w) == (v, w)


@pytest.mark.pure
def test_a_steady_velocity_command_costs_little_a_step() -> None:
    # Steady and turning: about 35 bytecodes a step (the velocity set along the heading),
    # where working the speeds out again at each step costs about 110.
    world = _fresh()
    world.command(0.3, 0.5)
    world.run(0, 50)
    assert (world._v, world._w) == (0.3, 0.5)
    steady = bytecodes(lambda: world.run(50, 100)) / 50
    assert steady < 55, steady
