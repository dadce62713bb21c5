"""The scripted user: timed actions plus answer rules, played in the world.

A :class:`UserScript` is plain data (a scenario file produces one; tests may
build one directly). :class:`ScriptedUser` plays it inside a
:class:`~prima.sim.Simulator`: it walks (over the place graph when a
wall is in the way), follows or leaves the robot, touches it, and answers the
robot's questions by its rules ("when the robot asks something containing X,
after D seconds say Y"). A question no rule matches gets no answer, and so
does one asked while the user is out of earshot.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from prima.errors import SimulationError

from prima.sim._kernel import ProcGen, Process, Room, idle, sleep
from prima.sim._records import Pose, UserAction, UserActionKind

if TYPE_CHECKING:
    from prima.sim._host import Stage
    from prima.sim._world import World

__all__ = ["ADDED_ACTIONS", "AnswerRule", "ScriptedUser", "TimedAction", "UserScript"]


@dataclass(frozen=True)
class TimedAction:
    """One thing the user does at time ``at`` (s).

    ``action`` is one of say, touch, walk, follow, leave, stop. Walk and leave
    go to ``place`` or to (``x``, ``y``); follow keeps ``distance`` behind
    the robot; say says ``text``.
    """

    at: float
    action: UserActionKind
    text: str | None = None
    place: str | None = None
    x: float | None = None
    y: float | None = None
    speed: float | None = None
    distance: float = 1.0

    def target(self) -> str | None:
        if self.place is not None:
            return self.place
        if self.x is not None and self.y is not None:
            return f"({self.x:g}, {self.y:g})"
        return None

    def to_dict(self) -> dict[str, object]:
        return {"at": self.at, "action": self.action.value, "text": self.text,
                "place": self.place, "x": self.x, "y": self.y, "speed": self.speed,
                "distance": self.distance}


@dataclass(frozen=True)
class AnswerRule:
    """When the robot asks something matching, answer ``say`` after ``after`` s.

    ``contains`` is a case-insensitive substring, ``pattern`` a regular
    expression searched in the prompt; give one (neither matches any prompt).
    ``say`` None means: stay silent (the Q&A times out). With ``nth`` the rule
    applies only to the n-th prompt it matches (1-based).
    """

    say: str | None
    contains: str | None = None
    pattern: str | None = None
    after: float = 1.0
    nth: int | None = None

    def matches(self, prompt: str) -> bool:
        if self.contains is not None:
            return self.contains.casefold() in prompt.casefold()
        if self.pattern is not None:
            return re.search(self.pattern, prompt, re.IGNORECASE) is not None
        return True

    def to_dict(self) -> dict[str, object]:
        return {"say": self.say, "contains": self.contains, "pattern": self.pattern,
                "after": self.after, "nth": self.nth}


@dataclass(frozen=True)
class UserScript:
    """Where the user starts, how fast they walk, what they do and answer."""

    start: Pose
    speed: float = 0.3
    """Walking speed (m/s)."""
    actions: tuple[TimedAction, ...] = ()
    answers: tuple[AnswerRule, ...] = ()

    def to_dict(self) -> dict[str, object]:
        return {"start": self.start.to_dict(), "speed": self.speed,
                "actions": [a.to_dict() for a in self.actions],
                "answers": [r.to_dict() for r in self.answers]}


ADDED_ACTIONS = 10_000
"""How many actions may be added to a run as it goes (:meth:`ScriptedUser.add`): a live
session's bound (``prima live``)."""

_FOLLOW_PERIOD: Final = 0.1
_STEP_ASIDE: Final = 0.6
"""A following user steps out of the robot's way when it comes this close (a fraction
of the following distance) heading their way: people do not stand in a robot's path."""
_APPROACH_GAP: Final = 0.15


class ScriptedUser:
    """Plays a :class:`UserScript` in a simulator (created by the simulator)."""

    def __init__(self, script: UserScript, sim: Stage) -> None:
        self.script = script
        self._sim = sim
        self._motion: Process | None = None
        self._touching = False
        """A touch's walk up to the robot is under way (replaced, it is reported missed)."""
        self._matched = [0] * len(script.answers)
        self._asked: tuple[str, AnswerRule | None] | None = None
        """The prompt the robot is asking, and the rule that answers it (None: none)."""
        self._room: Room | None = None
        """The insertion numbers kept for actions added as the run goes (:meth:`add`)."""

    def begin(self) -> None:
        """Put every timed action on the agenda, and keep room after them for
        :data:`ADDED_ACTIONS` more (:meth:`add`)."""
        k = self._sim.kernel
        for action in self.script.actions:
            k.at(round(action.at * k.hz), functools.partial(self._do, action))
        self._room = Room(k, ADDED_ACTIONS, "action")

    def add(self, action: TimedAction) -> None:
        """Do ``action`` at its time, after now, as if the script had listed it last among
        the actions of that tick: what a user does live (``prima live``), played so that a
        script of the same actions at the same times makes the same run. Its tick is a
        report, so the run loop gets control there as it would from the script's own
        reckoning. Raises SimulationError for a time not after now, or past the bound."""
        if self._room is None:
            raise SimulationError("actions are added once the user's script has begun")
        self._room.add(action.at, functools.partial(self._added, action))

    def _added(self, action: TimedAction) -> None:
        self._sim.reports += 1
        self._do(action)

    # ---- hearing and speaking ---------------------------------------------------

    def begin_question(self, prompt: str, ticks: int = 0) -> None:
        """The robot starts asking ``prompt``: which rule answers it is decided now, so
        that ``nth`` counts the times the robot asks (a prompt cut and asked again
        counts twice: the user heard it begin). Asked out of hearing range, it counts
        for no rule."""
        sim = self._sim
        self._asked = (prompt, None)
        if sim.world.user_distance() > sim.spec.hearing_range:
            return
        chosen = None
        for i, rule in enumerate(self.script.answers):
            if not rule.matches(prompt):
                continue
            self._matched[i] += 1  # (every rule that matches counts the asking: nth)
            if chosen is None and (rule.nth is None or self._matched[i] == rule.nth):
                chosen = rule
        if chosen is not None:
            self._asked = (prompt, chosen)
            if chosen.after < 0 and chosen.say is not None:  # over the prompt, before its end
                k = sim.kernel
                at = k.tick + max(1, ticks + round(chosen.after * k.hz))
                k.at(at, functools.partial(self.say, chosen.say))

    def hear_question(self, prompt: str) -> None:
        """The robot asked ``prompt`` and now listens: answer by the rule chosen when it
        began asking, if the user is still within hearing range."""
        sim = self._sim
        asked, self._asked = self._asked, None
        if asked is None or asked[0] != prompt:
            self.begin_question(prompt)  # (a prompt asked without its beginning heard)
            asked, self._asked = self._asked, None
        rule = asked[1] if asked is not None else None
        if rule is None or rule.after < 0 or sim.world.user_distance() > sim.spec.hearing_range:
            return  # (an early answer was said over the prompt, heard or not)
        if rule.say is not None:
            k = sim.kernel
            k.at(k.tick + round(rule.after * k.hz), functools.partial(self.say, rule.say))

    def say(self, text: str) -> None:
        sim = self._sim
        if sim.listening():  # a Q&A's answer: it ends the Q&A, then the line follows
            self._record(UserActionKind.SAY, text=text, heard=sim.hear(text))
            return
        # (said outside a Q&A: the line first, then what the robot makes of it)
        self._record(UserActionKind.SAY, text=text, heard=sim.hearable() and bool(text.strip()))
        sim.hear(text)

    # ---- actions ----------------------------------------------------------------

    def _do(self, a: TimedAction) -> None:
        kind = a.action
        if kind is not UserActionKind.SAY and self._touching:  # the chase is replaced
            self._touching = False
            self._record(UserActionKind.TOUCH, target="missed")
        if kind is UserActionKind.SAY:
            self.say(a.text or "")
        elif kind is UserActionKind.STOP:
            self._halt()
            self._record(kind)
        elif kind is UserActionKind.FOLLOW:
            self._record(kind, target="robot")
            self._move(self._follow(a.distance, a.speed or self.script.speed))
        elif kind is UserActionKind.TOUCH:
            self._touching = True
            self._move(self._touch(a.speed or self.script.speed))
        else:  # walk, leave
            self._record(kind, target=a.target())
            self._move(self._walk(a, a.speed or self.script.speed))

    def _record(self, kind: UserActionKind, *, text: str | None = None,
                target: str | None = None, heard: bool | None = None) -> None:
        self._sim.report_user(UserAction(self._sim.now(), kind, text, target, heard))

    def _move(self, gen: ProcGen) -> None:
        self._halt()
        self._motion = self._sim.kernel.spawn(gen)

    def _halt(self) -> None:
        self._sim.kernel.kill(self._motion)
        self._motion = None
        self._set_velocity(0.0, 0.0)

    def _set_velocity(self, vx: float, vy: float) -> None:
        self._sim.world.walk_user(vx, vy)

    def _leg(self, x: float, y: float, speed: float) -> ProcGen:
        world = self._sim.world
        hx, hy = world.user_xy()
        length = math.hypot(x - hx, y - hy)
        if length < 1e-6:
            return
        k = self._sim.kernel
        n = max(1, math.ceil(length / (speed / k.hz)))
        self._set_velocity((x - hx) * k.hz / n, (y - hy) * k.hz / n)
        yield sleep(n)
        world.put_user(x, y)

    def _walk(self, a: TimedAction, speed: float) -> ProcGen:
        sim = self._sim
        if a.place is not None:
            place = sim.map.place(a.place)
            here = sim.world.user_pose()
            tx, ty = (place.x, place.y) if place is not None else (here.x, here.y)
        else:
            tx, ty = float(a.x or 0.0), float(a.y or 0.0)
        hx, hy = sim.world.user_xy()
        for x, y in sim.route(hx, hy, tx, ty, 0.0) or [(tx, ty)]:
            yield from self._leg(x, y, speed)
        self._set_velocity(0.0, 0.0)
        self._record(UserActionKind.ARRIVE, target=a.target())

    def _follow(self, distance: float, speed: float) -> ProcGen:
        world = self._sim.world
        period = self._sim.kernel.ticks(_FOLLOW_PERIOD)
        while True:
            rx, ry = world.robot_xy()
            hx, hy = world.user_xy()
            d = math.hypot(rx - hx, ry - hy)
            if d > distance + 0.1:
                v = min(speed, (d - distance) * 2.0)
                wx, wy = self._toward_robot(hx, hy, rx, ry)
                w = math.hypot(wx - hx, wy - hy)
                self._set_velocity((wx - hx) / w * v, (wy - hy) / w * v)
            elif d < distance * _STEP_ASIDE and self._in_the_way(rx, ry, hx, hy, d):
                self._step_aside(rx, ry, hx, hy, d, speed)
            elif world.human_moving:
                self._set_velocity(0.0, 0.0)
            else:  # (where they stand, it stays so until someone moves)
                yield idle(period, _unmoved(world, world.version))
                continue
            yield sleep(period)

    def _in_the_way(self, rx: float, ry: float, hx: float, hy: float, d: float) -> bool:
        """The robot heads toward the user (within 45 degrees); a user standing on the
        robot itself (``d`` 0, placed there) is in its way whichever way it heads."""
        if d < 1e-9:
            return True
        angle = self._sim.world.robot_angle()
        ahead = ((hx - rx) * math.cos(angle) + (hy - ry) * math.sin(angle)) / d
        return ahead > math.cos(math.radians(45))

    def _step_aside(self, rx: float, ry: float, hx: float, hy: float, d: float,
                    speed: float) -> None:
        """Step sideways out of the robot's way, to the side the user already leans to
        (left of the robot's heading when squarely in front: people keep right)."""
        angle = self._sim.world.robot_angle()
        fx, fy = math.cos(angle), math.sin(angle)
        side = fx * (hy - ry) - fy * (hx - rx)  # > 0: the user is left of the robot's path
        sign = 1.0 if side >= 0 else -1.0
        self._set_velocity(-fy * sign * speed, fx * sign * speed)

    def _toward_robot(self, hx: float, hy: float, rx: float, ry: float) -> tuple[float, float]:
        """Where to head for to reach the robot: straight, or over the place graph."""
        sim = self._sim
        if sim.world.clear(hx, hy, rx, ry):
            return rx, ry
        for wx, wy in sim.route(hx, hy, rx, ry, 0.0):
            if math.hypot(wx - hx, wy - hy) > 0.05:
                return wx, wy
        return rx, ry

    def _touch(self, speed: float) -> ProcGen:
        sim = self._sim
        world = sim.world
        reach = sim.spec.radius + sim.spec.touch_reach + 0.25
        for _ in range(240):  # give up after about two minutes of chasing
            rx, ry = world.robot_xy()
            hx, hy = world.user_xy()
            d = math.hypot(rx - hx, ry - hy)
            if d <= reach:
                break
            wx, wy = self._toward_robot(hx, hy, rx, ry)
            w = math.hypot(wx - hx, wy - hy)
            step = min(d - (reach - _APPROACH_GAP) if (wx, wy) == (rx, ry) else w, speed * 0.5)
            yield from self._leg(hx + (wx - hx) / w * step, hy + (wy - hy) / w * step, speed)
        self._set_velocity(0.0, 0.0)
        touched = world.user_distance() <= reach
        self._touching = False
        self._record(UserActionKind.TOUCH, target=None if touched else "missed")
        if touched:
            sim.emit("touched", {})


def _unmoved(world: World, version: int) -> Callable[[], bool]:
    """Whether no body has moved since ``version`` and the user stands: a following
    user who found nothing to do then finds nothing again (:func:`idle`)."""
    return lambda: world.version == version and not world.human_moving
