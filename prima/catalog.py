"""The Command catalog: docs/rules.md section 4 (thesis Table 4.2) as data.

This is the one place that knows what a Command is: the devices its atomic
behaviors occupy, whether it is a feedback loop (one AB per iteration), whether
it breaks the Communication Channel (which gives it low priority), whether it
prompts and then listens for an answer, which of its arguments are words the
robot says (and which devices saying them adds), its parameters with their
defaults, and, for a robot-specific Command, how long it takes. The DSL checks
arguments against it, the interpreter and the mediator read devices from it,
the simulator reads defaults and durations from it, the trace reads what is
spoken from it. No other module special-cases a Command by its name.

A robot hardware profile extends the catalog with robot-specific Commands
(only an FA may use those) via :meth:`Catalog.extended`. Like
:mod:`prima.vocab`, this module imports nothing heavy.
"""

from __future__ import annotations

import dataclasses
import enum
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Final

from prima.record import Record
from prima.vocab import Value

__all__ = [
    "BODY_DEVICE",
    "Blend",
    "BUILTIN_JOINTS",
    "CONNECT_COMMAND",
    "EXTRAS_ACTED_ON",
    "HOLD_SECONDS",
    "MAX_HOLD",
    "MAX_SWAY",
    "MAX_SWAY_PERIOD",
    "RESTORE_COMMAND",
    "RESTORE_POSITION_COMMAND",
    "SEARCH_DEVICE",
    "STANDARD_COMMANDS",
    "STANDARD_DEVICES",
    "STEP_LIMITS",
    "SWAY_DEGREES",
    "SWAY_PERIOD",
    "SWAY_SECONDS",
    "SYMBOLIC_KINDS",
    "TALK_DEVICES",
    "ArgRef",
    "Catalog",
    "CommandSpec",
    "Hold",
    "JointSpec",
    "MoveJoint",
    "Param",
    "ParamKind",
    "Primitive",
    "Priority",
    "RaiseEvent",
    "Range",
    "SwayBody",
]

STANDARD_DEVICES: tuple[str, ...] = (
    "human-detection",
    "locomotion",
    "localization",
    "speaker",
    "speech-recognition",
    "neck",
    "arm",
)
"""Devices every PRIMA robot has (thesis Sec. 2.4, Figure 2.4)."""

TALK_DEVICES = frozenset({"speaker", "speech-recognition"})
"""Devices through which the robot talks with its user: while another application
uses them, a Command that breaks the Communication Channel waits (thesis Sec. 3.3)."""

SPEAKER: Final = "speaker"
"""The device words are said through: a Command's text arguments are words only if
its call occupies it."""

BODY_DEVICE: Final = "locomotion"
"""The wheels: a Command that uses them turns or moves the robot's body."""

SEARCH_DEVICE: Final = "human-detection"
"""The camera's human detection: a Command on it looks for, faces or follows the user."""

CONNECT_COMMAND = "FaceHuman"
"""The Command the connect-channel policy runs before an utterance."""

RESTORE_COMMAND = "SetPositionAndDirection"
"""The Command the restore-state policy runs before a resumed stream."""

RESTORE_POSITION_COMMAND = "SetPosition"
"""The one it runs before a resumed AB that turns the robot itself (its heading
would be undone at once)."""
BUILTIN_JOINTS: Mapping[str, str] = MappingProxyType(
    {"head-pan": "neck", "head-tilt": "neck", "arm": "arm"})
"""Joints the simulated robot always models (MoveHead's and PointByHand's), by the
device that moves them; a profile's ``<perform>`` may move them too, within the
robot's own limits and at its own rates."""


class Priority(enum.IntEnum):
    """Scheduling priority of a Command's atomic behaviors (thesis Sec. 4.3)."""

    LOW = 0
    """The Command breaks the Communication Channel (moves away from the user)."""
    HIGH = 1
    """The Command keeps the Communication Channel."""


class ParamKind(str, enum.Enum):
    """What an argument is, which decides how it is written and checked."""

    TEXT = "text"
    """Words the robot says: a string with ``{expr}`` interpolation."""
    NUMBER = "number"
    """A number (its unit is given by :attr:`Param.unit`)."""
    PLACE = "place"
    """A place on the building's map, written as a bare name."""
    GESTURE = "gesture"
    """A gesture the robot's profile knows, written as a bare name."""
    GRAMMAR = "grammar"
    """The id of an answer grammar declared in the document (Q&A only)."""
    VARIABLE = "variable"
    """The name of a document variable that receives a result (Q&A only)."""
    SYMBOL = "symbol"
    """Any other bare word (robot-specific Commands)."""


SYMBOLIC_KINDS = frozenset({ParamKind.PLACE, ParamKind.GESTURE, ParamKind.GRAMMAR,
                            ParamKind.VARIABLE, ParamKind.SYMBOL})
"""Kinds written as bare names rather than expressions."""


@dataclass(frozen=True, repr=False, eq=False)
class Range(Record):
    """The numbers a number argument may take, and how a value outside them is refused.

    The one rule for both checks: ``prima validate`` reports an argument whose value
    is a constant outside it (``QA(..., timeout=-3)``), and the simulated robot ends a
    Command whose argument's value is outside it with that error, word for word.
    """

    says: str
    """The refusal, without the value: ``timeout must not be negative``."""
    low: float | None = None
    high: float | None = None
    above: bool = False
    """A value must be greater than ``low``, not equal to it."""

    def refusal(self, value: float) -> str | None:
        """Why ``value`` is refused (``timeout must not be negative, not -3``), or None."""
        fits = ((self.low is None or (value > self.low if self.above else value >= self.low))
                and (self.high is None or value <= self.high))
        return None if fits else f"{self.says}, not {value:g}"


@dataclass(frozen=True, repr=False, eq=False)
class Param(Record):
    """One motion argument of a Command."""

    name: str
    kind: ParamKind
    required: bool = True
    default: Value = None
    unit: str = ""
    doc: str = ""
    devices: frozenset[str] = frozenset()
    """Devices the Command occupies in addition when this argument is given (not
    empty): Active Sensing Human's ``say`` adds the speaker."""
    shown: bool = True
    """Shown among the Command's arguments in the trace (a Q&A's timeout is not)."""
    limits: Range | None = None
    """For a number: the values the robot takes (None: any finite number)."""

    def describe(self) -> str:
        """One line for people: its kind, unit, whether it may be left out and its default,
        and what it is (``number in deg, optional, default 90: how far ...``). The schema's
        documentation of the attribute and the language server's hover both show it."""
        head = self.kind.value + (f" in {self.unit}" if self.unit else "")
        if not self.required:
            head += ", optional"
            if self.default is not None and self.default != "":
                head += f", default {_shown_value(self.default)}"
        return f"{head}: {self.doc}" if self.doc else head


@dataclass(frozen=True, repr=False, eq=False)
class ArgRef(Record):
    """``{name}`` in a primitive of a ``<perform>``: the Command's argument ``name``,
    else ``default`` (its parameter's default; None: no value)."""

    name: str
    default: Value = None


@dataclass(frozen=True, repr=False, eq=False)
class JointSpec(Record):
    """A joint a ``<perform>`` moves: built in (:data:`BUILTIN_JOINTS`; limits and
    rate None: the robot's own) or declared by the profile's ``<joint>``."""

    name: str
    device: str
    low: float | None = None
    """Lowest angle (deg)."""
    high: float | None = None
    """Highest angle (deg)."""
    rate: float | None = None
    """Speed (deg/s)."""


MAX_HOLD = 3_600.0
"""Longest one ``<hold>`` step of a ``<perform>`` may last (s), written or given."""

HOLD_SECONDS = Range(f"a hold lasts 0 to {MAX_HOLD:g} s", 0.0, MAX_HOLD)
"""The seconds a ``<hold>`` step is given by its Command's argument."""


@dataclass(frozen=True, repr=False, eq=False)
class Hold(Record):
    """Keep the Command's devices for a time (s): a literal, or a number argument."""

    seconds: float | ArgRef


@dataclass(frozen=True, repr=False, eq=False)
class MoveJoint(Record):
    """Move a joint to an angle (deg, relative to the body) or toward a place on the
    map; exactly one of the two must have a value when the step runs. It takes the
    travel over the joint's rate; a target beyond its limits stops at the limit."""

    joint: JointSpec
    to: float | ArgRef | None = None
    toward: str | ArgRef | None = None


MAX_SWAY = 90.0
"""Widest a ``<sway>`` step may sway the body either way (deg)."""

MAX_SWAY_PERIOD = 60.0
"""Longest one whole sway of a ``<sway>`` step may take (s)."""

SWAY_DEGREES = Range(f"a sway turns more than 0 and at most {MAX_SWAY:g} degrees either way",
                     0.0, MAX_SWAY, above=True)
SWAY_PERIOD = Range(f"a sway's period is more than 0 and at most {MAX_SWAY_PERIOD:g} s",
                    0.0, MAX_SWAY_PERIOD, above=True)
SWAY_SECONDS = Range(f"a sway lasts more than 0 and at most {MAX_HOLD:g} s", 0.0, MAX_HOLD,
                     above=True)


@dataclass(frozen=True, repr=False, eq=False)
class SwayBody(Record):
    """Sway the body about its heading: +- ``degrees``, one whole sway every ``period``
    seconds, for ``seconds`` (whole sways only: it ends facing where it began). Alone
    it turns the robot to and fro in place; blended over a global motion (the blend
    policy) it is superimposed on that motion's course."""

    degrees: float | ArgRef
    period: float | ArgRef
    seconds: float | ArgRef


@dataclass(frozen=True, repr=False, eq=False)
class RaiseEvent(Record):
    """Post a robot-specific event (one the profile declares) to the applications."""

    event: str


Primitive = Hold | MoveJoint | SwayBody | RaiseEvent
"""One step of a ``<perform>``: what the simulator does, in order, to perform a
Command a profile declares or implements its own way."""

STEP_LIMITS: Mapping[type, Mapping[str, Range]] = MappingProxyType({
    Hold: MappingProxyType({"seconds": HOLD_SECONDS}),
    SwayBody: MappingProxyType({"degrees": SWAY_DEGREES, "period": SWAY_PERIOD,
                                "seconds": SWAY_SECONDS}),
})
"""The range of each number a step takes from its Command's arguments (``{name}``), by
the step's kind and field: an argument a step takes must lie in the step's range too
(:meth:`CommandSpec.limits`). A joint's angle is any finite number (it stops at the
joint's limit)."""

_POSITIVE_SPEED = Range("speed must be positive", 0.0, above=True)

EXTRAS_ACTED_ON: Mapping[tuple[str, str], Range] = MappingProxyType({
    ("Gesture", "tempo"): Range("tempo must be positive", 0.0, above=True),
    ("TopologicalMove", "speed"): _POSITIVE_SPEED,
    ("SetPosition", "speed"): _POSITIVE_SPEED,
    ("SetPositionAndDirection", "speed"): _POSITIVE_SPEED,
    ("Turn", "rate"): Range("rate must be positive", 0.0, above=True),
})
"""The additional arguments (a profile's ``<extra>``, numbers) the simulated robot acts
on, by Command and name, with the values it takes: a gesture played at a tempo (1 is
its own; 2 takes half its time), a move or a drive to a position no faster than a
speed (m/s), a turn no faster than a rate (deg/s); either at most the robot's own
limit. Any other additional argument is shown in the trace and changes nothing the
simulator does. ``prima validate`` refuses a constant outside the range, and the
robot a value outside it, in the same words."""


@dataclass(frozen=True, repr=False, eq=False)
class CommandSpec(Record):
    """A Command type: what it occupies and how PRIMA schedules it."""

    name: str
    devices: frozenset[str]
    feedback: bool = False
    breaks_cc: bool = False
    params: tuple[Param, ...] = ()
    one_of: tuple[frozenset[str], ...] = ()
    """Groups of parameters of which exactly one must be given."""
    robot_specific: bool = False
    doc: str = ""
    priority_override: Priority | None = None
    listens: bool = False
    """It says a prompt, then listens for the user's answer until a timeout, as one
    atomic behavior (a Q&A); its application handles the answer, a no-match or the
    silence (``<on-answer>``, ``<on-nomatch>``, ``<on-noinput>``)."""
    duration: float | None = None
    """For a robot-specific Command: how long it keeps its devices (s)."""
    aims: bool = False
    """It aims the robot, its head or its arm at something on purpose (a Turn, a
    PointByHand): an utterance that follows it in its stream is about that, so the
    connect-channel policy does not turn the robot back to the user before it."""
    interruptible: bool = False
    """The robot can cut it for another application's reaction (the interrupt policy:
    the robot profile's ``<interruptible>`` says which Commands): speech at a word
    boundary, anything else at once."""
    travels: bool = False
    """It takes the robot somewhere of its own (a move, following the user): when it
    resumes a suspended stream, the restore-state policy does not return the robot
    to where the stream was suspended first."""
    perform: tuple[Primitive, ...] = ()
    """How the simulator performs it, when a robot profile says (its ``<perform>``):
    these steps in order, instead of a behavior of its own. Empty: the simulator's
    own behavior for the Command."""
    ranges: Mapping[str, tuple[Range, ...]] = field(init=False, repr=False, compare=False)
    """Argument -> every range it must lie in (:meth:`limits`), found once: the robot
    asks at every number argument of every Command it starts."""

    def __post_init__(self) -> None:
        found: dict[str, list[Range]] = {}
        for p in self.params:
            if p.limits is not None:
                found.setdefault(p.name, []).append(p.limits)
        for step in self.perform:
            for field_name, limits in STEP_LIMITS.get(type(step), {}).items():
                operand = getattr(step, field_name)
                if isinstance(operand, ArgRef):
                    found.setdefault(operand.name, []).append(limits)
        object.__setattr__(self, "ranges", MappingProxyType(
            {name: tuple(ranges) for name, ranges in found.items()}))

    @property
    def follows_user(self) -> bool:
        """It moves the robot after its user, keeping the channel (Tracking Human):
        following the user is not leaving them (docs/rules.md 7.6 (1), section 8)."""
        return self.travels and not self.breaks_cc and SEARCH_DEVICE in self.devices

    @property
    def orients(self) -> bool:
        """It turns the robot's body or aims it on purpose: an utterance in the same
        atomic behavior (FaceHumanAndSpeak, a Speak grouped with a PointByHand) is
        spoken the way it turns."""
        return self.aims or BODY_DEVICE in self.devices

    @property
    def priority(self) -> Priority:
        if self.priority_override is not None:
            return self.priority_override
        return Priority.LOW if self.breaks_cc else Priority.HIGH

    def signature(self) -> str:
        """How a chain writes it: ``QA(prompt, grammar, into?, timeout=8)`` (``?``: it
        may be left out; ``=``: its default)."""
        parts = []
        for p in self.params:
            if p.required:
                parts.append(p.name)
            elif p.default is None or p.default == "":
                parts.append(f"{p.name}?")
            else:
                parts.append(f"{p.name}={_shown_value(p.default)}")
        return f"{self.name}({', '.join(parts)})"

    def describe(self) -> str:
        """A paragraph for people: what it does, how a chain writes it, its devices and how
        it is scheduled. The one text a Command has: ``schemas/pxml.xsd`` documents its
        element with it (generated: ``python -m prima.dsl._build_schema``) and the
        language server's hover shows it."""
        text = [self.doc or f"The robot's own Command {self.name}.",
                f"Chain: {self.signature()}."]
        text += [f"Give exactly one of {' or '.join(sorted(g))}." for g in self.one_of]
        text.append(f"Devices: {', '.join(sorted(self.devices)) or 'none'}.")
        if self.feedback:
            text.append("A feedback loop: one atomic behavior per iteration, and the other "
                        "application may act between two.")
        if self.breaks_cc:
            text.append("It breaks the Communication Channel: low priority, delayed while the "
                        "other application talks with the user.")
        if self.robot_specific:
            text.append("Robot-specific: only an FA may use it.")
        return " ".join(text)

    def param(self, name: str) -> Param | None:
        for p in self.params:
            if p.name == name:
                return p
        return None

    def limits(self, name: str) -> tuple[Range, ...]:
        """Every range argument ``name`` must lie in: its parameter's own, and that of
        each step of the Command's ``<perform>`` that takes it (a hold's seconds)."""
        return self.ranges.get(name, ())

    def refusal(self, name: str, value: float) -> str | None:
        """Why the robot refuses ``value`` for argument ``name`` (``timeout must not be
        negative, not -3``), or None: the first of its :meth:`limits` it is outside."""
        for limits in self.limits(name):
            said = limits.refusal(value)
            if said is not None:
                return said
        return None

    def arg(self, args: Mapping[str, Value], name: str) -> Value:
        """An argument's value as given, else its parameter's default (None if neither)."""
        if name in args:
            return args[name]
        p = self.param(name)
        return None if p is None else p.default

    def devices_for(self, args: Mapping[str, Value]) -> frozenset[str]:
        """The devices a call with these arguments occupies."""
        devices = self.devices
        for p in self.params:
            if p.devices and args.get(p.name):
                devices = devices | p.devices
        return devices

    def spoken(self, args: Mapping[str, Value]) -> list[str]:
        """The words a call with these arguments says: its non-empty text arguments, if
        it occupies the :data:`SPEAKER` (a robot's own Command may take a text it does not
        say: a label it prints or shows)."""
        if SPEAKER not in self.devices_for(args):
            return []
        return [str(args[p.name]) for p in self.params
                if p.kind is ParamKind.TEXT and args.get(p.name)]


def _shown_value(value: Value) -> str:
    """A default as a chain would write it: ``90``, ``1.5``, ``""``, ``user``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


def _spec(name: str, devices: str, *, fb: bool = False, breaks: bool = False,
          listens: bool = False, params: Iterable[Param] = (),
          one_of: Iterable[Iterable[str]] = (), doc: str = "",
          aims: bool = False, travels: bool = False) -> CommandSpec:
    return CommandSpec(
        name=name,
        devices=frozenset(devices.split()),
        feedback=fb,
        breaks_cc=breaks,
        params=tuple(params),
        one_of=tuple(frozenset(g) for g in one_of),
        doc=doc,
        listens=listens,
        aims=aims,
        travels=travels or breaks,
    )


_P = Param
_T, _N, _PL = ParamKind.TEXT, ParamKind.NUMBER, ParamKind.PLACE

STANDARD_COMMANDS: tuple[CommandSpec, ...] = (
    _spec("ActiveSensingHuman", "human-detection locomotion localization", fb=True,
          params=[_P("say", _T, False, "",
                     doc="said at each retry; adds the speaker to the devices",
                     devices=frozenset({"speaker"})),
                  _P("turn", _N, False, 90.0, "deg", "how far to turn the view after 10 s unseen")],
          doc="Stay still until the camera sees the user; after 10 s unseen, "
              "turn the view and retry."),
    _spec("FaceHuman", "human-detection locomotion", doc="Turn the body to face the user."),
    _spec("QA", "speaker speech-recognition", listens=True,
          params=[_P("prompt", _T, doc="the question said before listening"),
                  _P("grammar", ParamKind.GRAMMAR, doc="answer grammar declared in the document"),
                  _P("into", ParamKind.VARIABLE, False, doc="variable that receives the answer"),
                  _P("timeout", _N, False, 8.0, "s", "how long to listen for an answer",
                     shown=False, limits=Range("timeout must not be negative", 0.0))],
          doc="Say a prompt, then listen for an answer until a timeout: one atomic behavior."),
    _spec("TrackingHuman", "human-detection locomotion", fb=True, travels=True,
          params=[_P("distance", _N, False, 1.0, "m", "comfortable distance to keep",
                     limits=Range("distance must be positive", 0.0, above=True))],
          doc="Follow the user at a comfortable distance, one iteration at a time, until stopped."),
    _spec("FaceHumanAndSpeak", "human-detection locomotion speaker",
          params=[_P("text", _T, doc="the words said once the robot faces the user")],
          doc="Face the user, then speak."),
    _spec("TurnAndSpeak", "locomotion localization speaker",
          params=[_P("angle", _N, unit="deg", doc="counter-clockwise turn"),
                  _P("text", _T, doc="the words said while turning")],
          doc="Turn by an angle while speaking."),
    _spec("SetDirection", "locomotion localization",
          params=[_P("heading", _N, False, unit="deg", doc="map heading, 0 = east, 90 = north"),
                  _P("toward", _PL, False, doc="a place to face")],
          one_of=[("heading", "toward")], doc="Turn to a map heading or toward a place.",
          aims=True),
    _spec("Turn", "locomotion", params=[_P("angle", _N, unit="deg", doc="counter-clockwise")],
          doc="Turn the body in place by an angle.", aims=True),
    _spec("SetSpeedAndTime", "locomotion", travels=True,
          params=[_P("speed", _N, unit="m/s", doc="forward speed (negative: backward)"),
                  _P("time", _N, unit="s", doc="how long to drive",
                     limits=Range("time must not be negative", 0.0)),
                  _P("spin", _N, False, 0.0, "deg/s", "turning rate while moving")],
          doc="Drive at a speed for a time."),
    _spec("StopMoving", "locomotion", doc="Stop the wheels."),
    _spec("Speak", "speaker", params=[_P("text", _T, doc="the words said")],
          doc="Say an utterance."),
    _spec("MoveHead", "neck",
          params=[_P("pan", _N, unit="deg", doc="left (positive) or right, relative to the body"),
                  _P("tilt", _N, False, 0.0, "deg", "up (positive) or down")],
          doc="Point the head (pan left/right, tilt up/down).", aims=True),
    _spec("PointByHand", "arm",
          params=[_P("toward", _PL, False, doc="a place to point at"),
                  _P("angle", _N, False, unit="deg", doc="direction relative to the body")],
          one_of=[("toward", "angle")], doc="Point the arm at a place or a direction.", aims=True),
    _spec("Gesture", "arm neck",
          params=[_P("name", ParamKind.GESTURE, doc="a gesture the robot profile declares")],
          doc="Play a named gesture with the arm and the head."),
    _spec("TopologicalMove", "locomotion localization", fb=True, breaks=True,
          params=[_P("to", _PL, doc="goal place on the building's map")],
          doc="Drive to a named place over the map's place graph, one leg per iteration."),
    _spec("SetPosition", "locomotion localization", fb=True, breaks=True,
          params=[_P("x", _N, unit="m", doc="map x (east)"),
                  _P("y", _N, unit="m", doc="map y (north)")],
          doc="Drive to map coordinates."),
    _spec("SetPositionAndDirection", "locomotion localization", fb=True, breaks=True,
          params=[_P("x", _N, unit="m", doc="map x (east)"),
                  _P("y", _N, unit="m", doc="map y (north)"),
                  _P("heading", _N, unit="deg",
                     doc="map heading at the end, 0 = east, 90 = north")],
          doc="Drive to map coordinates, then turn to a heading.", aims=True),
)


@dataclass(frozen=True, repr=False, eq=False)
class Blend(Record):
    """Commands a robot runs together on a shared device (docs/rules.md 7.3 (5)): a
    local motion over a global one (a dance step while it guides), speech over
    quieter sound (ducking). Declared by the robot profile's ``<blend>``."""

    local: frozenset[str]
    """Commands that may start over a running one of ``over`` on ``devices``."""
    over: frozenset[str]
    devices: frozenset[str]
    """The devices they share."""
    max_user_distance: float | None = None
    """While they blend the robot never gets farther than this from its user (m):
    a blend starts only within it, and the global motion waits for the user."""
    slowdown: float = 1.0
    """The global motion's speed while a local one runs over it, as a fraction."""


@dataclass(frozen=True, repr=False, eq=False)
class Catalog(Record):
    """An immutable set of Command types, looked up by name."""

    commands: Mapping[str, CommandSpec] = field(default_factory=dict)
    devices: frozenset[str] = frozenset(STANDARD_DEVICES)
    talk_devices: frozenset[str] = TALK_DEVICES
    """Devices through which the robot talks with its user (the channel rule)."""
    blends: tuple[Blend, ...] = ()
    """Interfering Commands the robot runs together (the blend policy)."""

    @classmethod
    def standard(cls) -> Catalog:
        """The common interface every robot offers, FA and EA alike."""
        return cls({c.name: c for c in STANDARD_COMMANDS}, frozenset(STANDARD_DEVICES))

    def usually_interruptible(self) -> frozenset[str]:
        """What a robot that declares nothing can cut when the interrupt policy is
        switched on: utterances, gestures and feedback iterations (docs/rules.md 7.3
        (2)); ``<interruptible>`` in a robot profile says otherwise."""
        return frozenset(c.name for c in self.commands.values()
                         if c.feedback or c.name == "Gesture"
                         or any(p.kind is ParamKind.TEXT for p in c.params))

    def extended(self, commands: Iterable[CommandSpec], devices: Iterable[str] = ()) -> Catalog:
        """A catalog with robot-specific Commands and devices added (a Command of
        the same name as one already there replaces it)."""
        merged = dict(self.commands)
        for c in commands:
            merged[c.name] = c
        return Catalog(merged, self.devices | frozenset(devices), self.talk_devices, self.blends)

    def interruptible(self, names: Iterable[str]) -> Catalog:
        """A catalog in which the Commands ``names`` may be cut (the interrupt policy)."""
        chosen = set(names)
        merged = {name: dataclasses.replace(c, interruptible=name in chosen)
                  for name, c in self.commands.items()}
        return Catalog(merged, self.devices, self.talk_devices, self.blends)

    def with_blends(self, blends: Iterable[Blend]) -> Catalog:
        """A catalog with these blends declared (the blend policy)."""
        return dataclasses.replace(self, blends=tuple(blends))

    def blend(self, starting: Iterable[CommandSpec], running: Iterable[CommandSpec],
              device: str) -> Blend | None:
        """The declared blend that lets an AB of the Commands ``starting`` share
        ``device`` with a running AB of the Commands ``running``, if any: every Command
        of one that uses the device is a local one of the blend, and of the other one
        it runs over (a local motion over a global one; or a global motion's next
        iteration under the local one still running)."""
        a = {c.name for c in starting if device in c.devices}
        b = {c.name for c in running if device in c.devices}
        for blend in self.blends:
            if device in blend.devices and a and b and (
                    (a <= blend.local and b <= blend.over)
                    or (a <= blend.over and b <= blend.local)):
                return blend
        return None

    def for_robot(self, commands: Iterable[CommandSpec], devices: Iterable[str]) -> Catalog:
        """This catalog as one robot offers it: ``commands`` added or replacing
        their namesakes (a common Command the robot implements its own way), on
        exactly the robot's ``devices`` (an armless robot has no ``arm``)."""
        extended = self.extended(commands)
        return Catalog(extended.commands, frozenset(devices), self.talk_devices, self.blends)

    @property
    def channel_devices(self) -> frozenset[str]:
        """Devices of the Commands that break the Communication Channel."""
        return frozenset().union(*(c.devices for c in self.commands.values() if c.breaks_cc))

    def __getitem__(self, name: str) -> CommandSpec:
        return self.commands[name]

    def __contains__(self, name: object) -> bool:
        return name in self.commands

    def __iter__(self) -> Iterator[CommandSpec]:
        return iter(self.commands.values())

    def get(self, name: str) -> CommandSpec | None:
        return self.commands.get(name)
