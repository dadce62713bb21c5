"""The simulated robot and its world (pymunk); implements the mediator's Driver.

Build a :class:`Simulator` from a scenario file (:func:`load_scenario`,
:meth:`Simulator.from_scenario`) or directly from a :class:`WorldMap`, wire
its callbacks, then drive it with ``next_time()`` / ``advance_to(t)``, or with
``advance_until(t)`` when the driver has nothing to do at the simulator's own times.
:class:`CommandRunner` drives it without documents or a mediator (tests,
benchmarks, ``python -m prima.sim run``).

Everything public is named here; the modules behind it are private.
"""

from prima.sim._behaviors import BEHAVIORS
from prima.sim._cli import main
from prima.sim._maps import Area, Place, PlaceKind, Wall, WorldMap
from prima.sim._records import (
    Picture,
    Pose,
    ReplyRule,
    ScheduledEvent,
    UserAction,
    UserActionKind,
    Zone,
    ZoneEntry,
)
from prima.sim._runner import CommandRunner, EntryKind, TraceEntry
from prima.sim._scenario import (
    MAP_NS,
    SCENARIO_NS,
    Reference,
    Scenario,
    load_map,
    load_scenario,
    scenario_references,
    late_inputs,
)
from prima.sim._simulator import Simulator
from prima.sim._spec import DEFAULT_GESTURES, RobotSpec, SpeechTiming
from prima.sim._user import ADDED_ACTIONS, AnswerRule, ScriptedUser, TimedAction, UserScript

__all__ = [
    "ADDED_ACTIONS",
    "BEHAVIORS",
    "DEFAULT_GESTURES",
    "MAP_NS",
    "SCENARIO_NS",
    "AnswerRule",
    "Area",
    "CommandRunner",
    "EntryKind",
    "Picture",
    "Place",
    "PlaceKind",
    "Pose",
    "Reference",
    "ReplyRule",
    "RobotSpec",
    "Scenario",
    "ScheduledEvent",
    "ScriptedUser",
    "Simulator",
    "SpeechTiming",
    "TimedAction",
    "TraceEntry",
    "UserAction",
    "UserActionKind",
    "UserScript",
    "Wall",
    "WorldMap",
    "Zone",
    "ZoneEntry",
    "late_inputs",
    "load_map",
    "load_scenario",
    "main",
    "scenario_references",
]
