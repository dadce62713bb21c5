"""The simulated robot and its world (pymunk); implements the mediator's Driver.

Build a :class:`Simulator` from a loaded scenario (:meth:`Simulator.from_scenario`:
anything shaped as a :class:`Setting`, such as :class:`prima.scenario.Scenario`; this
package reads no scenario file) or directly from a :class:`WorldMap`, wire
its callbacks, then drive it with ``next_time()`` / ``advance_to(t)``, or with
``advance_until(t)`` when the driver has nothing to do at the simulator's own times.
:class:`CommandRunner` drives it without documents or a mediator (tests,
benchmarks, ``python -m prima.sim run``).

Everything public is named here; the modules behind it are private.
"""

from prima.sim._behaviors import BEHAVIORS
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
from prima.sim._host import Body, Stage
from prima.sim._setting import Setting
from prima.sim._simulator import SENSE_HZ, Simulator
from prima.sim._spec import DEFAULT_GESTURES, RobotSpec, SpeechTiming
from prima.sim._user import ADDED_ACTIONS, AnswerRule, ScriptedUser, TimedAction, UserScript

__all__ = [
    "ADDED_ACTIONS",
    "BEHAVIORS",
    "DEFAULT_GESTURES",
    "SENSE_HZ",
    "AnswerRule",
    "Area",
    "Body",
    "CommandRunner",
    "EntryKind",
    "Picture",
    "Place",
    "PlaceKind",
    "Pose",
    "ReplyRule",
    "RobotSpec",
    "ScheduledEvent",
    "ScriptedUser",
    "Setting",
    "Simulator",
    "SpeechTiming",
    "Stage",
    "TimedAction",
    "TraceEntry",
    "UserAction",
    "UserActionKind",
    "UserScript",
    "Wall",
    "WorldMap",
    "Zone",
    "ZoneEntry",
]
