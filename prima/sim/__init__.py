"""The simulated robot and its world (pymunk); implements the mediator's Driver.

Build a :class:`Simulator` from a scenario file (:func:`load_scenario`,
:meth:`Simulator.from_scenario`) or directly from a :class:`WorldMap`, wire
its callbacks, then drive it with ``next_time()`` / ``advance_to(t)``.
"""

from prima.sim.behaviors import BEHAVIORS
from prima.sim.maps import Area, Place, PlaceKind, Wall, WorldMap
from prima.sim.records import (
    Picture,
    Pose,
    ReplyRule,
    ScheduledEvent,
    UserAction,
    UserActionKind,
    Zone,
    ZoneEntry,
)
from prima.sim.runner import CommandRunner, TraceEntry
from prima.sim.scenario import Scenario, load_map, load_scenario
from prima.sim.simulator import Simulator
from prima.sim.spec import DEFAULT_GESTURES, RobotSpec
from prima.sim.user import AnswerRule, ScriptedUser, TimedAction, UserScript

__all__ = [
    "BEHAVIORS",
    "DEFAULT_GESTURES",
    "AnswerRule",
    "Area",
    "CommandRunner",
    "Picture",
    "Place",
    "PlaceKind",
    "Pose",
    "ReplyRule",
    "RobotSpec",
    "Scenario",
    "ScheduledEvent",
    "ScriptedUser",
    "Simulator",
    "TimedAction",
    "TraceEntry",
    "UserAction",
    "UserActionKind",
    "UserScript",
    "Wall",
    "WorldMap",
    "Zone",
    "ZoneEntry",
    "load_map",
    "load_scenario",
]
