"""Builders shared by the simulator tests."""

from __future__ import annotations

import math
import random
from pathlib import Path
from typing import Any

from prima.mediator import Call
from prima.scenario import load_map
from prima.sim import (
    AnswerRule,
    CommandRunner,
    Pose,
    Simulator,
    TimedAction,
    UserActionKind,
    UserScript,
    WorldMap,
)
from prima.vocab import Value

ROOT = Path(__file__).resolve().parents[2]
MAPS = ROOT / "scenarios" / "maps"
EXAMPLES = ROOT / "scenarios" / "examples"

_maps: dict[str, WorldMap] = {}


def world_map(name: str) -> WorldMap:
    if name not in _maps:
        _maps[name] = load_map(MAPS / f"{name}.xml")
    return _maps[name]


def call(command: str, **args: Value) -> Call:
    return Call(command, dict(args))


def walk(at: float, x: float, y: float, speed: float | None = None) -> TimedAction:
    return TimedAction(at, UserActionKind.WALK, x=x, y=y, speed=speed)


def runner(map_name: str, robot: Pose, user: Pose | None = None, *actions: TimedAction,
           answers: tuple[AnswerRule, ...] = (), **kwargs: Any) -> CommandRunner:
    script = None if user is None else UserScript(user, actions=tuple(actions),
                                                  answers=tuple(answers))
    sim = Simulator(world_map(map_name), robot=robot, user=script, **kwargs)
    return CommandRunner(sim)


def clear_as_each_wall_says(world: Any, rng: random.Random, corner: tuple[float, float],
                            size: tuple[float, float], longest: float,
                            radii: tuple[float, ...], n: int) -> tuple[int, int]:
    """Ask ``world.clear`` about ``n`` random segments (starting in the box from
    ``corner`` of ``size``, at most ``longest`` long, fattened by one of ``radii``), and
    check each answer against every wall of the space asked itself. Returns how many were
    blocked and how many were clear thin but not fattened."""
    space = world.space
    walls = [s for s in space.shapes if s.body is space.static_body]
    blocked = beside = 0
    for _ in range(n):
        ax, ay = corner[0] + rng.uniform(0, size[0]), corner[1] + rng.uniform(0, size[1])
        length, heading = rng.uniform(0.0, longest), rng.uniform(0, 2 * math.pi)
        b = (ax + length * math.cos(heading), ay + length * math.sin(heading))
        radius = rng.choice(radii)
        near = any(w.segment_query((ax, ay), b, radius) is not None for w in walls)
        assert world.clear(ax, ay, *b, radius) is not near, ((ax, ay), b, radius)
        blocked += near
        beside += near and world.clear(ax, ay, *b)
    return blocked, beside
