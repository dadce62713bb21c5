"""What each Command physically does: one generator per Command.

A behavior is a kernel process: ``behavior(sim, call, command_id, iteration)``
yields waits and returns ``(values, terminal)``. For a feedback Command one
call is one loop iteration; ``terminal`` says whether the loop is done. For
any other Command ``terminal`` is True. Arguments the call leaves out take the
defaults of the simulator's catalog (:class:`~prima.catalog.Catalog`, built from
the robot profile), the one table both the DSL and the simulator read; so does
a robot-specific Command's duration. A Command whose profile says how to
perform it (a ``<perform>``: hold the devices, move a joint, raise an event)
has no behavior of its own here: :func:`perform_steps` runs its steps, the same
for every such Command.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Generator, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Final

from prima import compiled
from prima.catalog import (
    EXTRAS_ACTED_ON,
    HOLD_SECONDS,
    SWAY_DEGREES,
    SWAY_PERIOD,
    SWAY_SECONDS,
    ArgRef,
    CommandSpec,
    Hold,
    JointSpec,
    MoveJoint,
    Range,
    SwayBody,
)
from prima.errors import CommandError
from prima.mediator import AtomicBehavior, Call
from prima.sim._kernel import Wait, finish, idle, signal, sleep, until
from prima.sim._maps import Place
from prima.sim._records import Picture
from prima.sim._world import World, wrap_angle
from prima.vocab import Value

if TYPE_CHECKING:
    from prima.sim._host import Body

__all__ = ["BEHAVIORS", "perform"]

Values = dict[str, Value]
Result = tuple[Values, bool]
Gen = Generator[Wait, Any, Result]
Behavior = Callable[["Body", Call, int, int], Gen]


# ---- arguments -------------------------------------------------------------------

def _arg(sim: Body, call: Call, name: str) -> Value:
    """The argument as given, else its parameter's default in the robot's catalog."""
    args = call.args
    if name in args:  # (nearly always: the catalog is asked only for a default)
        return args[name]
    return sim.catalog.commands[call.command].arg(args, name)


def _number(sim: Body, call: Call, name: str, required: bool = True) -> float | None:
    """A number argument, within the ranges its Command's catalog entry gives it
    (:meth:`~prima.catalog.CommandSpec.refusal`: the rules ``prima validate`` checks a
    constant argument against, so that a document that validates is not refused here
    for one)."""
    value = _arg(sim, call, name)
    if value is None:
        if required:
            raise CommandError(f"missing argument {name!r}")
        return None
    number = _finite(value, f"argument {name!r}")
    spec = sim.catalog.commands[call.command]
    if name in spec.ranges:  # (most numbers have no range to be refused by)
        refusal = spec.refusal(name, number)
        if refusal is not None:
            raise CommandError(refusal)
    return number


def _extra(sim: Body, call: Call, name: str, default: float) -> float:
    """An additional argument the robot acts on (:data:`~prima.catalog.EXTRAS_ACTED_ON`),
    else ``default`` (what it is when none is given: no cap, the gesture's own tempo):
    within its range, else the Command ends with the error ``prima validate`` gives a
    constant outside it."""
    value = call.extra.get(name)
    if value is None:
        return default
    return _within(_finite(value, f"argument {name!r}"), EXTRAS_ACTED_ON[call.command, name])


def _req(sim: Body, call: Call, name: str) -> float:
    value = _number(sim, call, name)
    if value is None:
        raise CommandError(f"missing argument {name!r}")
    return value


def _text(sim: Body, call: Call, name: str) -> str:
    value = _arg(sim, call, name)
    return "" if value is None else str(value)


def _place(sim: Body, call: Call, name: str) -> Place | None:
    value = _arg(sim, call, name)
    if value is None:
        return None
    place = sim.map.place(str(value))
    if place is None:
        raise CommandError(f"unknown place {value!r} on map {sim.map.name!r}")
    return place


def _pose(sim: Body) -> Values:
    p = sim.localize()
    return {"x": round(p.x, 3), "y": round(p.y, 3), "heading": round(p.heading, 1) % 360.0}


# ---- motion helpers -------------------------------------------------------------------

def _stop(sim: Body) -> Generator[Wait, Any, None]:
    world = sim.world
    yield signal(lambda wake: world.stop(lambda: wake(True)))


def _turn(sim: Body, delta: float, rate: float = math.inf) -> Generator[Wait, Any, None]:
    """Turn by ``delta`` (rad), stopping first, no faster than ``rate`` (rad/s)."""
    world = sim.world
    if world.mode:
        yield from _stop(sim)
    yield signal(lambda wake: world.turn_by(delta, wake, rate))


def _face(sim: Body, heading: float) -> Generator[Wait, Any, None]:
    yield from _turn(sim, wrap_angle(heading - sim.world.robot_angle()))


ARRIVED: Final = "arrived"
UNDER_WAY: Final = "under way"
BLOCKED: Final = "blocked"


def _period_toward(sim: Body, x: float, y: float,
                   speed: float = math.inf) -> Generator[Wait, Any, str]:
    """One control period of going to (x, y): turn toward it, then drive straight (no
    faster than ``speed``, m/s).

    A turn or a drive toward it that is already running goes on (a feedback
    Command's iterations flow into each other, without stopping). When the period
    is over, the motion is left running: the next iteration continues it, and if
    none follows at once, the simulator stops the wheels. Returns ``ARRIVED``,
    ``UNDER_WAY`` (the period ended first) or ``BLOCKED`` (something in the way).
    """
    world, k = sim.world, sim.kernel
    end = k.tick + sim.ticks(sim.spec.control_period)
    while True:
        px, py = world.robot_xy()
        if math.hypot(x - px, y - py) < 1e-6:
            return ARRIVED
        bearing = math.atan2(y - py, x - px)
        target = world.heading_to()
        turning = world.turning_to()
        if target is not None and math.hypot(target[0] - x, target[1] - y) < 1e-9:
            ended = yield signal(functools.partial(_rewake, world), end - k.tick)
            if ended is None:
                return UNDER_WAY
            return ARRIVED if ended else BLOCKED
        if turning is not None and abs(wrap_angle(turning - bearing)) < 1e-6:
            turned = yield signal(functools.partial(_rewake, world), end - k.tick)
        else:
            if world.mode:
                yield from _stop(sim)
            delta = wrap_angle(bearing - world.robot_angle())
            if abs(delta) > math.radians(1.0):
                turned = yield signal(functools.partial(_turn_by, world, delta), end - k.tick)
            else:
                ended = yield signal(lambda wake: world.drive_to(x, y, wake, speed),
                                     end - k.tick)
                if ended is None:
                    return UNDER_WAY
                return ARRIVED if ended else BLOCKED
        if turned is None or k.tick >= end:
            return UNDER_WAY


def _turn_by(world: World, delta: float, wake: Callable[..., None]) -> bool:
    return world.turn_by(delta, wake)


def _rewake(world: World, wake: Callable[..., None]) -> bool:
    world.when_done(wake)
    return True


def _heading_to(sim: Body, place: Place) -> float | None:
    """Map heading (radians) from the robot toward a place (its ``facing`` when there)."""
    x, y = sim.world.robot_xy()
    if math.hypot(place.x - x, place.y - y) <= sim.spec.place_tolerance:
        return None if place.facing is None else math.radians(place.facing)
    return math.atan2(place.y - y, place.x - x)


# ---- talking ------------------------------------------------------------------------------

def speak(sim: Body, call: Call, cid: int, it: int) -> Gen:
    text = _text(sim, call, "text")
    n = sim.ticks(sim.speech_duration(text))
    sim.utter(cid, text, n)
    yield sleep(n)
    return {"duration": n / sim.kernel.hz}, True


def qa(sim: Body, call: Call, cid: int, it: int) -> Gen:
    prompt = _text(sim, call, "prompt")
    timeout = _req(sim, call, "timeout")
    n = sim.ticks(sim.speech_duration(prompt))
    sim.asking(prompt, n)
    sim.utter(cid, prompt, n)
    early = yield signal(functools.partial(sim.open_prompt, cid), n, timeout=None)
    sim.close_prompt(cid)
    if early is not None:  # answered over the prompt: it stops at a word boundary
        text, at, spoken, unspoken = early
        yield sleep(max(0, at - sim.kernel.tick))
        return {"status": "answered", "utterance": str(text), "barge_in": True,
                "spoken": spoken, "unspoken": unspoken}, True
    sim.ask(prompt)
    heard = yield signal(sim.open_mic, sim.ticks(timeout), timeout=None)
    sim.close_mic()
    if heard is None:
        return {"status": "noinput"}, True
    return {"status": "answered", "utterance": str(heard)}, True


# ---- turning --------------------------------------------------------------------------------

FACE_AIM: Final = math.radians(5.0)
"""Face Human turns until the robot is this close to facing its user."""
FACE_GAIN: Final = 6.0
"""How fast Face Human turns after a user who walks (rad/s per rad off them): a user
who walks round the robot stays within a few degrees (a walk round at 1 m, about
25 degrees a second, is followed within about 5)."""
FACE_WITHIN: Final = 4.0
"""Seconds Face Human follows a user who keeps walking round the robot, at most."""


FACE_STILL: Final = math.radians(10.0)
"""Face Human is done turning only below this turning rate (rad/s): the robot brakes
from there within a degree and a half."""


def _face_rate(sim: Body, off: float, period: float) -> float:
    """The turning rate toward a user ``off`` radians away, set for the next ``period``
    seconds: ``FACE_GAIN`` times how far off they are, but never faster than the robot can
    brake from within what is left once that period is over (it would turn past them)."""
    alpha = math.radians(sim.spec.turn_accel)
    turning = abs(sim.world.turning_rate())
    left = max(0.0, abs(off) - turning * period)
    return math.copysign(min(FACE_GAIN * abs(off), math.sqrt(2.0 * alpha * left)), off)


def face_human(sim: Body, call: Call, cid: int, it: int) -> Gen:
    """Turn to the user: while the user and the robot stand, one turn toward them; while
    they walk (or walked on while it turned), or the robot still moves (it slows down as
    it turns), after them, the turning rate set every tenth of a second from how far
    off they are (never faster than it can brake from before it faces them), until the
    robot faces them (within ``FACE_AIM``, nearly still) or ``FACE_WITHIN`` has passed."""
    world, k = sim.world, sim.kernel
    seen, distance = world.sees_user(k.tick, any_direction=True)
    if not seen:
        return {"found": False}, True
    if world.mode:
        world.stop()  # (it brakes as it turns: no stop first)
    elif not world.human_moving:
        yield from _turn(sim, world.user_bearing())
    end = k.tick + sim.ticks(FACE_WITHIN)
    period = k.hz // 10
    while k.tick < end:
        off = world.user_bearing()
        if abs(off) <= FACE_AIM and abs(world.turning_rate()) <= FACE_STILL:
            break
        world.command(0.0, _face_rate(sim, off, period / k.hz))
        yield sleep(period)
    if world.mode:
        yield from _stop(sim)
    return {"found": True, "distance": round(distance, 3), **_pose(sim)}, True


def face_human_and_speak(sim: Body, call: Call, cid: int, it: int) -> Gen:
    values, _ = yield from face_human(sim, call, cid, it)
    said, _ = yield from speak(sim, call, cid, it)
    return {**values, **said}, True


def turn(sim: Body, call: Call, cid: int, it: int) -> Gen:
    yield from _turn(sim, math.radians(_req(sim, call, "angle")),
                     math.radians(_extra(sim, call, "rate", math.inf)))
    return _pose(sim), True


def turn_and_speak(sim: Body, call: Call, cid: int, it: int) -> Gen:
    angle = _req(sim, call, "angle")
    text = _text(sim, call, "text")
    n = sim.ticks(sim.speech_duration(text))
    sim.utter(cid, text, n)
    end = sim.kernel.tick + n
    yield from _turn(sim, math.radians(angle))
    if end > sim.kernel.tick:
        yield sleep(end - sim.kernel.tick)
    return {**_pose(sim), "duration": n / sim.kernel.hz}, True


def set_direction(sim: Body, call: Call, cid: int, it: int) -> Gen:
    heading = _number(sim, call, "heading", required=False)
    toward = _place(sim, call, "toward")
    if heading is not None and toward is None:
        target: float | None = math.radians(heading)
    elif toward is not None and heading is None:
        target = _heading_to(sim, toward)
    else:
        raise CommandError("give exactly one of 'heading' and 'toward'")
    if target is not None:
        yield from _face(sim, target)
    return _pose(sim), True


# ---- wheels ---------------------------------------------------------------------------------

def set_speed_and_time(sim: Body, call: Call, cid: int, it: int) -> Gen:
    speed, seconds = _req(sim, call, "speed"), _req(sim, call, "time")
    spin = _req(sim, call, "spin")
    world = sim.world
    if world.mode:
        yield from _stop(sim)
    world.command(speed, math.radians(spin))
    yield sleep(sim.ticks(seconds))
    yield from _stop(sim)
    return _pose(sim), True


def stop_moving(sim: Body, call: Call, cid: int, it: int) -> Gen:
    yield from _stop(sim)
    return _pose(sim), True


# ---- head and arm ---------------------------------------------------------------------------

def _clamp(value: float, limits: tuple[float, float]) -> float:
    return max(limits[0], min(limits[1], value))


def move_head(sim: Body, call: Call, cid: int, it: int) -> Gen:
    spec, world, tick = sim.spec, sim.world, sim.kernel.tick
    pan = _clamp(_req(sim, call, "pan"), spec.head_pan_range)
    tilt = _clamp(_req(sim, call, "tilt"), spec.head_tilt_range)
    change = max(abs(pan - world.head_pan.at(tick)), abs(tilt - world.head_tilt.at(tick)))
    n = sim.ticks(change / spec.head_rate)
    world.head_pan.move(pan, tick, n)
    world.head_tilt.move(tilt, tick, n)
    world.joints_until = max(world.joints_until, tick + n)
    yield sleep(n)
    return {"pan": pan, "tilt": tilt}, True


def point_by_hand(sim: Body, call: Call, cid: int, it: int) -> Gen:
    spec, world, tick = sim.spec, sim.world, sim.kernel.tick
    angle = _number(sim, call, "angle", required=False)
    toward = _place(sim, call, "toward")
    if (angle is None) == (toward is None):
        raise CommandError("give exactly one of 'toward' and 'angle'")
    if toward is not None:
        target = _heading_to(sim, toward)
        angle = 0.0 if target is None else math.degrees(wrap_angle(target - world.robot_angle()))
    angle = _clamp(angle or 0.0, spec.arm_range)
    n = sim.ticks(abs(angle - world.arm.at(tick)) / spec.arm_rate)
    world.arm.move(angle, tick, n)
    yield sleep(n)
    return {"angle": round(angle, 1)}, True


def gesture(sim: Body, call: Call, cid: int, it: int) -> Gen:
    name = _text(sim, call, "name")
    seconds = _gesture_time(sim, call)
    if name not in sim.spec.gestures:
        return {"error": f"the robot has no gesture {name!r}"}, True
    yield sleep(sim.ticks(seconds))
    return {"gesture": name}, True


def take_picture(sim: Body, call: Call, cid: int, it: int) -> Gen:
    """Capture what the camera sees now; the capture lasts the profile's duration."""
    duration = sim.catalog[call.command].duration
    if duration is None:
        return {"error": f"the robot profile gives {call.command} no duration"}, True
    world, tick = sim.world, sim.kernel.tick
    seen, distance = world.sees_user(tick)
    pose = sim.localize()
    heading = round(math.degrees(world.camera_heading(tick)) % 360.0, 1) % 360.0
    yield sleep(sim.ticks(duration))
    picture = Picture(sim.now(), round(pose.x, 3), round(pose.y, 3), heading, seen,
                      round(distance, 3) if seen else None)
    sim.pictures.append(picture)
    sim.picture_count += 1
    return {"saw_user": seen, "heading": heading, "picture": sim.picture_count}, True


# ---- a robot profile's <perform> -------------------------------------------------------------

def _given(call: Call, operand: float | str | ArgRef) -> Value:
    """A step's operand: a literal, or the call's argument (else its default)."""
    if isinstance(operand, ArgRef):
        return call.args.get(operand.name, operand.default)
    return operand


def _finite(value: Value, what: str) -> float:
    if isinstance(value, bool) or value is None:
        raise CommandError(f"{what} must be a number, not {value!r}")
    try:
        number = float(value)
    except ValueError:
        raise CommandError(f"{what} must be a number, not {value!r}") from None
    if not math.isfinite(number):
        raise CommandError(f"{what} must be finite, not {value!r}")
    return number


def _within(value: float, limits: Range) -> float:
    refusal = limits.refusal(value)
    if refusal is not None:
        raise CommandError(refusal)
    return value


def _hold_seconds(call: Call, step: Hold) -> float:
    return _within(_finite(_given(call, step.seconds), "a hold's seconds"), HOLD_SECONDS)


def _sway_figures(call: Call, step: SwayBody) -> tuple[float, int, float]:
    """A sway's amplitude (deg), its number of whole sways and its length (s): as many
    whole periods as fit in its seconds, at least one."""
    degrees = _finite(_given(call, step.degrees), "a sway's degrees")
    period = _finite(_given(call, step.period), "a sway's period")
    seconds = _finite(_given(call, step.seconds), "a sway's seconds")
    degrees = _within(degrees, SWAY_DEGREES)
    period = _within(period, SWAY_PERIOD)
    seconds = _within(seconds, SWAY_SECONDS)
    sways = max(1, int(seconds / period + 1e-9))
    return degrees, sways, sways * period


def _joint_figures(sim: Body, joint: JointSpec) -> tuple[tuple[float, float], float]:
    """A joint's limits (deg) and rate (deg/s): the robot's own for a built-in joint."""
    if joint.low is not None and joint.high is not None and joint.rate is not None:
        return (joint.low, joint.high), joint.rate
    spec = sim.spec
    if joint.name == "arm":
        return spec.arm_range, spec.arm_rate
    return (spec.head_pan_range if joint.name == "head-pan" else spec.head_tilt_range,
            spec.head_rate)


def _joint_target(sim: Body, call: Call, step: MoveJoint) -> float:
    """Where a step moves its joint (deg, within its limits): to an angle, or toward a
    place (its bearing from the body, as PointByHand aims the arm)."""
    name = step.joint.name
    to = None if step.to is None else _given(call, step.to)
    toward = None if step.toward is None else _given(call, step.toward)
    if (to is None) == (toward is None):
        raise CommandError(f"joint {name!r}: give exactly one of an angle and a place")
    if toward is not None:
        place = sim.map.place(str(toward))
        if place is None:
            raise CommandError(f"unknown place {toward!r} on map {sim.map.name!r}")
        target = _heading_to(sim, place)
        angle = 0.0 if target is None else math.degrees(
            wrap_angle(target - sim.world.robot_angle()))
    else:
        angle = _finite(to, f"joint {name!r}'s angle")
    return _clamp(angle, _joint_figures(sim, step.joint)[0])


def perform_steps(sim: Body, call: Call, cid: int, it: int) -> Gen:
    """A Command the robot profile performs with a ``<perform>``: its steps in order.

    A hold keeps the devices for its time; a joint step moves the joint at its
    rate and waits until it is there (its angle is among the values); a sway swings
    the body about its heading for its time, on top of whatever drives the wheels; a
    raise posts the robot-specific event to the applications at once.
    """
    world = sim.world
    values: Values = {}
    for step in sim.catalog[call.command].perform:
        if isinstance(step, Hold):
            yield sleep(sim.ticks(_hold_seconds(call, step)))
        elif isinstance(step, SwayBody):
            degrees, sways, seconds = _sway_figures(call, step)
            n = sim.ticks(seconds)
            world.sway(math.radians(degrees), sways, n, cid)
            values["sways"] = sways
            yield sleep(n)
        elif isinstance(step, MoveJoint):
            tick, name = sim.kernel.tick, step.joint.name
            target = _joint_target(sim, call, step)
            joint = world.joint(name)
            n = sim.ticks(abs(target - joint.at(tick)) / _joint_figures(sim, step.joint)[1])
            joint.move(target, tick, n)
            if name in ("head-pan", "head-tilt"):  # the camera turns with the head
                world.joints_until = max(world.joints_until, tick + n)
            values[name] = round(target, 1)
            yield sleep(n)
        else:
            sim.emit(step.event, {"command": call.command})
    return values, True


def hold_for_duration(sim: Body, call: Call, cid: int, it: int) -> Gen:
    """A robot-specific Command with a duration and nothing else to say how it is
    performed: it keeps its devices for its duration (a ``<hold>`` of it)."""
    yield sleep(sim.ticks(sim.catalog[call.command].duration or 0.0))
    return {}, True


def _perform_time(sim: Body, call: Call, spec: CommandSpec) -> float:
    """How long a ``<perform>`` will take from now, at least: its holds, and each
    joint's travel from where it is (or where an earlier step left it) at its rate.

    Every step's arguments are checked here, before anything moves. A joint turned
    toward a place counts no travel: the body may turn first in the same atomic
    behavior (SetDirection, then PointByHand), which changes the place's bearing.
    """
    total, tick = 0.0, sim.kernel.tick
    at: dict[str, float] = {}
    for step in spec.perform:
        if isinstance(step, Hold):
            total += _hold_seconds(call, step)
        elif isinstance(step, SwayBody):
            total += _sway_figures(call, step)[2]
        elif isinstance(step, MoveJoint):
            name = step.joint.name
            target = _joint_target(sim, call, step)
            start = at.get(name, sim.world.joint_angle(name, tick))
            if step.to is None or _given(call, step.to) is None:
                start = target  # toward a place
            total += abs(target - start) / _joint_figures(sim, step.joint)[1]
            at[name] = target
    return total


# ---- feedback loops --------------------------------------------------------------------------

def active_sensing_human(sim: Body, call: Call, cid: int, it: int) -> Gen:
    """One iteration: one control period of watching for the user with the view
    still or, once the user has stayed unseen for ``search_time``, one turn of the
    view (Turn-and-Search; it stops as soon as the user comes into view).

    Short iterations keep the robot responsive: another application's reaction
    can take the robot between any two (a search is mostly waiting). A retry
    (a watch then a turn) says ``say`` at its start; that iteration lasts until
    the words are said, and the trace shows the words on that iteration only
    (:meth:`~._simulator.Simulator.quiet`).
    """
    say = _text(sim, call, "say")
    angle = _req(sim, call, "turn")
    k = sim.kernel
    state = sim.loop_state(cid)
    watched = int(state.get("watched") or 0)
    search = sim.ticks(sim.spec.search_time)
    if watched < search:
        speech_end = k.tick
        if watched == 0:
            sim.search()
            if say:
                speech_end += sim.ticks(sim.speech_duration(say))
                sim.utter(cid, say, speech_end - k.tick)
        period = min(sim.ticks(sim.spec.control_period), search - watched)
        start = k.tick
        found = yield until(lambda: sim.seen, period)
        if speech_end > k.tick:
            yield sleep(speech_end - k.tick)
        if found:
            sim.end_loop(cid)
            return {"found": True, "distance": round(sim.world.user_distance(), 3)}, True
        watched += k.tick - start
        state["watched"] = watched
        state["quiet"] = True  # the retry goes on: its next iterations say nothing
        return {"found": False, "unseen": round(watched / k.hz, 3)}, False
    state["watched"] = 0
    state["quiet"] = False  # the next retry says its words again
    # Turn the view; stop as soon as the user comes into view (Turn-and-Search).
    world = sim.world
    if world.mode:
        yield from _stop(sim)
    turned: list[bool] = []
    if world.turn_by(math.radians(angle), turned.append):
        yield until(lambda: bool(turned) or sim.seen)
    if sim.seen and not turned:
        yield from _stop(sim)
    seen, distance = world.sees_user(k.tick)
    if seen or sim.seen:
        sim.end_loop(cid)
        return {"found": True, "distance": round(world.user_distance(), 3),
                "turned": angle}, True
    return {"found": False, "turned": angle}, False


def tracking_human(sim: Body, call: Call, cid: int, it: int) -> Gen:
    want = _req(sim, call, "distance")
    k, world = sim.kernel, sim.world
    if not sim.seen:
        found = yield until(lambda: sim.seen, sim.ticks(sim.spec.lose_after))
        if not found:
            sim.announce_lost()
            yield from _stop(sim)
            sim.end_loop(cid)
            return {"lost": True}, True
    end = k.tick + sim.ticks(sim.spec.control_period)
    period = k.hz // 10
    dead = sim.spec.tracking_band / 6
    distance = world.user_distance()
    while k.tick < end:
        if not sim.seen:  # the monitor has posted human-lost
            yield from _stop(sim)
            sim.end_loop(cid)
            return {"lost": True}, True
        still = not world.mode
        version = world.version
        seen, d = world.sees_user(k.tick)
        if seen:
            distance = d
            err = d - want
            v = 0.0 if abs(err) < dead else 2.0 * (err - math.copysign(dead, err))
            world.command(max(v, -0.5 * sim.spec.max_speed), 3.0 * world.user_bearing())
        if still and not world.mode:  # (at its distance and facing the user: it stays)
            yield idle(min(period, end - k.tick), _settled(sim, version, k.tick), end)
        else:
            yield sleep(min(period, end - k.tick))
    return {"lost": False, "distance": round(distance, 3)}, False


def _settled(sim: Body, version: int, tick: int) -> Callable[[], bool]:
    """Whether a robot that tracks the user, and found nothing to do at ``tick``, would
    find nothing again: no body has moved since ``version``, the camera looks the same
    way, and the user is still seen (:func:`idle`)."""
    world = sim.world
    pan = world.head_pan.at(tick)
    return lambda: (world.version == version and sim.seen and not world.mode
                    and world.head_pan.at(sim.kernel.tick) == pan)


def topological_move(sim: Body, call: Call, cid: int, it: int) -> Gen:
    """One iteration: one control period of going to the next place on the route.

    Short iterations keep the robot responsive (another application can act
    between any two, and a held move stops within one period). A blocked
    iteration (someone in the way) waits a second and ends non-terminal, so the
    loop tries again; after ``MAX_BLOCKED`` blocked iterations in a row it gives
    up. While it runs, the simulator leaves reporting the places reached to it
    (``sim.navigating``).
    """
    sim.navigating += 1
    try:
        return (yield from _move_leg(sim, call, cid))
    finally:
        sim.navigating -= 1


def _move_leg(sim: Body, call: Call, cid: int) -> Gen:
    goal = _place(sim, call, "to")
    if goal is None:
        raise CommandError("missing argument 'to'")
    speed = _extra(sim, call, "speed", math.inf)
    state = sim.loop_state(cid)
    at, path = _route(sim, goal, state)
    if at is not None and at.name == goal.name:
        sim.emit("place-reached", {"place": goal.name, "kind": goal.kind.value})
        sim.end_loop(cid)
        return {"place": goal.name, "kind": goal.kind.value, "goal": goal.name,
                "remaining": 0}, True
    if not path:
        sim.end_loop(cid)
        return {"error": f"no route to {goal.name!r}"}, True
    nxt = path[0]
    bound = sim.blend_bound()
    if bound is not None and sim.world.has_user and _would_leave(sim, nxt.x, nxt.y, bound):
        # blending (a dance while it guides): the robot never gets farther than the
        # bound from its user; it waits for them this period, stopping before it would
        if sim.world.mode:
            yield from _stop(sim)
        yield sleep(sim.ticks(sim.spec.control_period))
        return {"waiting": "user", "toward": nxt.name, "goal": goal.name, **_pose(sim)}, False
    outcome = yield from _period_toward(sim, nxt.x, nxt.y, speed)
    if outcome is BLOCKED and math.dist(sim.world.robot_xy(), (nxt.x, nxt.y)) <= PASS_BY:
        # someone stands on the place: the robot is there, as near as it can get
        state["blocked"] = 0
        sim.emit("place-reached", {"place": nxt.name, "kind": nxt.kind.value})
        done = nxt.name == goal.name
        if done:
            state["toward"] = None
            sim.end_loop(cid)
        else:  # on to the next place, from here (not back to this one)
            state["toward"] = path[1].name
            state["x"], state["y"] = sim.world.robot_xy()
        return {"place": nxt.name, "kind": nxt.kind.value, "goal": goal.name,
                "remaining": len(path) - 1, "occupied": True}, done
    if outcome is BLOCKED:
        blocked = int(state.get("blocked") or 0) + 1
        state["blocked"] = blocked
        if blocked >= MAX_BLOCKED:
            sim.end_loop(cid)
            return {"error": f"blocked on the way to {nxt.name!r}", **_pose(sim)}, True
        yield sleep(sim.ticks(1.0))
        return {"blocked": True, "toward": nxt.name, "goal": goal.name, **_pose(sim)}, False
    state["blocked"] = 0
    if outcome is UNDER_WAY:
        state["toward"] = nxt.name
        state["x"], state["y"] = sim.world.robot_xy()
        return {"toward": nxt.name, "goal": goal.name, "remaining": len(path)}, False
    state["toward"] = None
    sim.emit("place-reached", {"place": nxt.name, "kind": nxt.kind.value})
    done = nxt.name == goal.name
    if done:
        sim.end_loop(cid)
    return {"place": nxt.name, "kind": nxt.kind.value, "goal": goal.name,
            "remaining": len(path) - 1}, done


def _would_leave(sim: Body, x: float, y: float, bound: float) -> bool:
    """Whether going on toward (x, y) for one more control period could take the robot
    farther than ``bound`` from its user, should they stay where they are: as far as
    it could drive in the period at its speed limit, and then brake to a stop. Asked
    before each period, so the robot stops within the bound, ahead of time."""
    world = sim.world
    px, py = world.robot_xy()
    ux, uy = world.user_xy()
    if math.hypot(ux - px, uy - py) > bound:
        return True
    left = math.hypot(x - px, y - py)
    if left < 1e-9:
        return False
    v = world.speed_cap()
    reach = min(left, v * sim.spec.control_period + v * v / (2.0 * sim.spec.max_accel))
    ax, ay = px + (x - px) / left * reach, py + (y - py) / left * reach
    return math.hypot(ux - ax, uy - ay) > bound


def _route(sim: Body, goal: Place,
           state: dict[str, Value]) -> tuple[Place | None, Sequence[Place]]:
    """The places still to visit; on the way to one, keep heading for it.

    Replanning from scratch only when the robot is not near where this loop left
    it (another application moved it; stopping the wheels between two iterations
    slides it a little): otherwise a place visible further on would make the
    robot skip, and not report, the places on its way.
    """
    toward = sim.map.place(str(state.get("toward") or ""))
    if toward is not None:
        x, y = sim.world.robot_xy()
        lx, ly = state.get("x"), state.get("y")
        moving_on = sim.world.heading_to() == (toward.x, toward.y)
        if moving_on or (isinstance(lx, float) and isinstance(ly, float)
                         and math.hypot(x - lx, y - ly) < KEEP_COURSE):
            places = sim.map.route(toward.name, goal.name)
            if places:
                return None, places
    return sim.plan(goal.name)


PASS_BY: Final = 0.5
"""A move blocked this close (m) to the place it heads for (its user stands on it, say)
has reached it: it reports it and goes on to the next place, instead of waiting for
the place to clear."""

MAX_BLOCKED: Final = 30
"""Blocked iterations in a row after which a move gives up (about 30 s of waiting)."""

KEEP_COURSE: Final = 0.3
"""A move keeps heading for the same place when the robot is this close (m) to where
its last iteration left it (the wheels stopping in between slide it a little)."""


def _set_position(sim: Body, call: Call, cid: int,
                  heading: float | None) -> Gen:
    tx, ty = _req(sim, call, "x"), _req(sim, call, "y")
    speed = _extra(sim, call, "speed", math.inf)
    world, spec = sim.world, sim.spec
    tol = spec.position_tolerance
    x, y = world.robot_xy()
    if math.hypot(tx - x, ty - y) > tol:
        points = sim.route(x, y, tx, ty, spec.radius / 2)
        if not points:
            return {"error": f"no route to ({tx:g}, {ty:g})"}, True
        if (yield from _period_toward(sim, *points[0], speed)) is BLOCKED:
            # someone in the way (the user walking by): wait a second and try again, as
            # a Topological Move does, up to MAX_BLOCKED times in a row
            state = sim.loop_state(cid)
            blocked = int(state.get("blocked") or 0) + 1
            state["blocked"] = blocked
            if blocked >= MAX_BLOCKED:
                sim.end_loop(cid)
                return {"error": "blocked", **_pose(sim)}, True
            yield sleep(sim.ticks(1.0))
            return {"blocked": True, **_pose(sim)}, False
        sim.loop_state(cid)["blocked"] = 0
        x, y = world.robot_xy()
    reached = math.hypot(tx - x, ty - y) <= tol
    if reached and heading is not None:
        yield from _face(sim, math.radians(heading))
    if reached:
        sim.end_loop(cid)
    return {**_pose(sim), "reached": reached}, reached


def set_position(sim: Body, call: Call, cid: int, it: int) -> Gen:
    return (yield from _set_position(sim, call, cid, None))


def set_position_and_direction(sim: Body, call: Call, cid: int, it: int) -> Gen:
    return (yield from _set_position(sim, call, cid, _req(sim, call, "heading")))


BEHAVIORS: Final[Mapping[str, Behavior]] = {
    "ActiveSensingHuman": active_sensing_human,
    "FaceHuman": face_human,
    "QA": qa,
    "TrackingHuman": tracking_human,
    "FaceHumanAndSpeak": face_human_and_speak,
    "TurnAndSpeak": turn_and_speak,
    "SetDirection": set_direction,
    "Turn": turn,
    "SetSpeedAndTime": set_speed_and_time,
    "StopMoving": stop_moving,
    "Speak": speak,
    "MoveHead": move_head,
    "PointByHand": point_by_hand,
    "Gesture": gesture,
    "TopologicalMove": topological_move,
    "SetPosition": set_position,
    "SetPositionAndDirection": set_position_and_direction,
    "TakePicture": take_picture,
}
"""Every Command the simulated robot performs with a behavior of its own (the standard
ones plus TakePicture); a Command with a ``<perform>`` in the robot's profile is
performed by :func:`perform_steps` instead, and a robot-specific one with only a
duration by :func:`hold_for_duration`."""


# ---- planned durations (the longest-AB budget) ---------------------------------------

def _said(sim: Body, call: Call, name: str) -> float:
    text = _text(sim, call, name)
    return sim.speech_duration(text) if text else 0.0


def _turning(sim: Body, degrees: float, rate: float = math.inf) -> float:
    return abs(degrees) / min(rate, sim.spec.max_turn_rate)


def _gesture_time(sim: Body, call: Call) -> float:
    """How long the gesture plays: its own time, at the call's tempo if it gives one."""
    return sim.spec.gestures.get(_text(sim, call, "name"), 0.0) / _extra(sim, call, "tempo", 1.0)


def _search_time(sim: Body, call: Call) -> float:
    look = max(sim.spec.search_time, _said(sim, call, "say"))
    return look + _turning(sim, _req(sim, call, "turn"))


PLANNED: Final[Mapping[str, Callable[[Body, Call], float]]] = {
    "Speak": lambda sim, call: _said(sim, call, "text"),
    "QA": lambda sim, call: _said(sim, call, "prompt") + _req(sim, call, "timeout"),
    "FaceHumanAndSpeak": lambda sim, call: _turning(sim, 180.0) + _said(sim, call, "text"),
    "TurnAndSpeak": lambda sim, call: max(_turning(sim, _req(sim, call, "angle")),
                                          _said(sim, call, "text")),
    "Turn": lambda sim, call: _turning(sim, _req(sim, call, "angle"),
                                       _extra(sim, call, "rate", math.inf)),
    "SetSpeedAndTime": lambda sim, call: _req(sim, call, "time"),
    "Gesture": lambda sim, call: _gesture_time(sim, call),
    "ActiveSensingHuman": lambda sim, call: _search_time(sim, call),
}
"""How long a Command whose length depends on its arguments will take, at least
(s); a robot-specific Command takes its catalog duration; the others are bounded
by the robot itself (a leg of a move, a head turn)."""


def blended_motion(sim: Body, call: Call, cid: int, it: int) -> Gen:
    """A local motion blended over a global one on the devices they share (the blend
    policy): a dance step while the robot guides. The global motion keeps the wheels
    (it slows down meanwhile); the local one sways the robot in place of commanding
    them, taking the time it would take alone."""
    seconds = planned(sim, call)
    yield sleep(sim.ticks(seconds))
    return {"blended": True, "duration": seconds}, True


def planned(sim: Body, call: Call) -> float:
    """How long performing ``call`` will take, as far as it can be known at its start."""
    spec = sim.catalog.commands.get(call.command)
    if spec is not None and spec.perform:
        return _perform_time(sim, call, spec)
    estimate = PLANNED.get(call.command)
    if estimate is not None:
        return estimate(sim, call)
    return (spec.duration or 0.0) if spec is not None else 0.0


def perform(sim: Body, ab: AtomicBehavior) -> Generator[Wait, Any, Result]:
    """Perform an atomic behavior's calls in order; return merged values and terminal.

    In a grouped AB each feedback call performs one iteration; the AB is
    terminal only if every feedback call in it is. An error (a Command the
    robot lacks, one its catalog does not declare, an unusable argument) ends
    the AB at once with an ``error`` value.
    """
    values: Values = {}
    terminal = True
    length = 0.0
    commands = sim.catalog.commands  # (the catalog's own lookups are one call more each)
    for call in ab.calls:
        try:
            length += planned(sim, call) if call.command in commands else 0.0
        except CommandError as exc:  # an unusable argument: nothing has started
            return {"error": f"{call.command}: {exc}"}, True
    if length > sim.longest_for(ab.app):
        return {"error": f"{ab.calls[0].command} would take {length:g} s; no atomic behavior "
                         f"of {ab.app} may take more than {sim.longest_for(ab.app):g} s "
                         "(its longest-AB budget)"}, True
    for i, call in enumerate(ab.calls):
        cid = ab.command_ids[i] if i < len(ab.command_ids) else 0
        spec = commands.get(call.command)
        behavior = perform_steps if spec is not None and spec.perform else BEHAVIORS.get(
            call.command)
        if (behavior is None and spec is not None and spec.robot_specific
                and spec.duration is not None):
            behavior = hold_for_duration
        if spec is not None and not spec.perform and spec.devices & ab.blended \
                and sim.blended_locally(ab, call.command):
            behavior = blended_motion  # (a <perform>'s steps never command the wheels)
        if behavior is None or spec is None:
            values["error"] = f"the simulated robot has no Command {call.command!r}"
            return values, True
        sim.performing(ab, call)
        try:
            out, done = yield from behavior(sim, call, cid, ab.iteration)
        except CommandError as exc:
            values["error"] = f"{call.command}: {exc}"
            return values, True
        values.update(out)
        if "error" in out:
            return values, True
        terminal = terminal and done
    if _FINISH:
        yield finish((values, terminal))
    return values, terminal


_FINISH: Final = compiled()
"""Whether :func:`perform` ends by yielding :func:`finish`, not by returning: in the
compiled build, where a generator's return raises a StopIteration with a traceback
(some 4,000 instructions at every atomic behavior's end). Interpreted, returning costs
less: a return there is a plain one, and the yield would make a wait."""
