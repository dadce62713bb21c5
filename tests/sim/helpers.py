"""Builders shared by the simulator tests."""

from __future__ import annotations

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
