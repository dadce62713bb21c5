"""Robot hardware profiles: what a robot has and what its FA may use beyond the common interface.

A profile (``schemas/robot.xsd``) lists the robot's devices and physical
figures, what one application may consume (its budgets), its gestures,
robot-specific Commands, additional arguments of common Commands, and
robot-specific events. Only an FA may use the robot-specific parts
(docs/rules.md section 4).

Every number is checked as the run will use it: a decimal the schema accepts
can still be infinite or zero once it is a float (``1`` followed by 400
zeros, ``0.`` followed by 400 zeros), so each figure must be finite and within
the range docs/robot-profile.md gives, or the profile has a located error.

A robot-specific Command, or a common Command the robot implements its own way
(``<implement>``), may say how the simulator performs it: a ``<perform>`` of at
most :data:`MAX_STEPS` primitive steps (hold the devices for a time, move a
joint, raise an event), compiled here into :class:`~prima.catalog.Primitive`
data that the simulator runs generically. An attribute of a step is a literal
or exactly ``{name}``, one of the Command's arguments: no expression is ever
evaluated.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any
from functools import lru_cache
from pathlib import Path

from lxml import etree

from prima.catalog import (
    BUILTIN_JOINTS,
    MAX_HOLD,
    MAX_SWAY,
    Blend,
    STANDARD_DEVICES,
    ArgRef,
    Catalog,
    CommandSpec,
    Hold,
    JointSpec,
    MoveJoint,
    Param,
    ParamKind,
    Primitive,
    Priority,
    RaiseEvent,
    Range,
    STEP_LIMITS,
    SwayBody,
)
from prima.dsl._elements import elements, flag
from prima.dsl._model import words
from prima.errors import DocumentError, Problem
from prima.record import Record
from prima.shipped import packaged
from prima.vocab import (
    DEFAULT_BUDGETS,
    MAX_NUMBER,
    MAX_RUN_TIME,
    MAX_TEXT,
    PREDEFINED_EVENTS,
    USER_ACTION_EVENTS,
    AppKind,
    Budgets,
    Value,
)
from prima.xmlio import (
    Bound,
    XmlDocument,
    limit,
    local_name,
    number,
    parse_xml,
    read_source,
    validate,
)

NAMESPACE = "urn:prima:robot:1"
DEFAULT_PROFILE = "home-robot.xml"

STANDARD_GESTURES = frozenset({"nod", "shake-head", "wave", "bow", "happy", "sad", "surprised"})
"""Gestures every robot offers; an EA may use only these."""


BACKCHANNELS = ("uh-huh", "mm-hmm", "mhm", "yes", "yeah", "okay", "ok", "right", "i see",
                "sure")
"""What a user says to show they follow, not to take the turn: a robot that hears at any
time goes on talking over these (``<hearing backchannels>`` replaces them)."""

RESUME_PAUSE = 0.6
"""Seconds a robot waits, after user speech no application took cut its utterance (a
false interruption: a cough, a remark to someone else), before it goes on."""

MAX_BACKCHANNELS = 100
"""Most phrases ``<hearing backchannels>`` may list."""


@dataclass(frozen=True, repr=False, eq=False)
class Hearing(Record):
    """When the robot hears its user (``<hearing>``, docs/rules.md 7.5)."""

    always: bool = False
    """It hears at any time (the barge-in policy, on by default then); else only while
    a Q&A listens, as the thesis' PaPeRo did."""
    backchannels: frozenset[tuple[str, ...]] = frozenset(
        tuple(words(b)) for b in BACKCHANNELS)
    """Phrases (as normalised words) it talks on over."""
    pause: float = RESUME_PAUSE
    """Seconds before an utterance cut by speech no application took goes on."""

    def backchannel(self, text: str) -> bool:
        """Whether the user saying ``text`` only shows they follow: every phrase of it
        (split at punctuation) is a backchannel."""
        said = [tuple(words(part)) for part in _PHRASES.split(text)]
        said = [p for p in said if p]
        return bool(said) and all(p in self.backchannels for p in said)


_PHRASES = re.compile(r"[.,;:!?]+")


@dataclass(frozen=True, repr=False, eq=False)
class RobotProfile(Record):
    """A loaded, checked robot hardware profile."""

    name: str
    path: str
    radius: float
    max_speed: float
    max_accel: float
    max_turn_rate: float
    speech_rate: float
    camera_fov: float
    camera_range: float
    pan_range: tuple[float, float]
    tilt_range: tuple[float, float]
    devices: frozenset[str]
    gestures: Mapping[str, float]
    """Gesture name -> duration in seconds."""
    commands: tuple[CommandSpec, ...]
    """Robot-specific Commands (with their durations, when the profile gives one)."""
    extras: Mapping[str, Mapping[str, Param]]
    """Additional arguments: Command name -> argument name -> declaration."""
    events: Mapping[str, bool]
    """Robot-specific events -> whether they are reactive."""
    user_events: frozenset[str] = frozenset()
    """The robot-specific events that are the user's own action (a touch): a reaction
    to one goes before another application's later reaction to a perception or
    network event until it has said its first words (docs/mediator.md, *The user's own
    action first*)."""
    budgets: Mapping[AppKind, Budgets] = field(default_factory=lambda: DEFAULT_BUDGETS)
    """What one application of each role may consume on this robot (its
    ``<budgets>`` elements over :data:`~prima.vocab.DEFAULT_BUDGETS`)."""
    policies: Mapping[str, bool] = field(default_factory=dict)
    """The mediation policies this robot switches (``all`` switches every one first);
    a scenario and ``prima run --policy`` switch over them."""
    blends: tuple[Blend, ...] = ()
    """Interfering Commands this robot runs together (its ``<blend>`` elements; the
    blend policy, on by default when there is one)."""
    interruptible: frozenset[str] = frozenset()
    """The Commands this robot can cut for another application's reaction (its
    ``<interruptible>``; the interrupt policy, on by default when it is given). Empty:
    none declared; switched on, the policy cuts utterances, gestures and feedback
    iterations."""
    implemented: tuple[CommandSpec, ...] = ()
    """Common Commands this robot performs its own way (``<implement>``): on its own
    devices, and with a ``<perform>`` if it gives one."""
    joints: Mapping[str, JointSpec] = field(default_factory=dict)
    """Joints the profile declares (``<joint>``), beyond :data:`BUILTIN_JOINTS`."""
    hearing: Hearing = Hearing()
    """When it hears its user (``<hearing>``): by default only while a Q&A listens."""
    _catalog: Catalog = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # built once: every document loaded against the profile asks for it
        catalog = Catalog.standard().for_robot(self.implemented + self.commands, self.devices)
        catalog = catalog.interruptible(self.interruptible or catalog.usually_interruptible())
        if self.blends:
            catalog = catalog.with_blends(self.blends)
        object.__setattr__(self, "_catalog", catalog)

    def catalog(self) -> Catalog:
        """The common Commands plus this robot's own."""
        return self._catalog


MAX_STEPS = 32
"""Most steps a ``<perform>`` may have."""

MAX_JOINTS = 32
"""Most joints a profile may declare."""

_BUDGET_COUNTS = ("text", "waiting", "starts-per-instant")
_BUDGET_SECONDS = ("sends-per-second", "longest-ab", "wait-share", "wait-window")

MAX_BLENDS = 64
"""Most ``<blend>`` elements in one profile."""

MAX_SECONDS = MAX_RUN_TIME
"""Longest duration a budget may give (s)."""

MAX_COUNT = 1_000_000
"""Largest count a budget may give."""

FIGURES: Mapping[tuple[str, str], Bound] = {
    ("body", "radius"): Bound(10.0, "m"),
    ("body", "max-speed"): Bound(100.0, "m/s"),
    ("body", "max-accel"): Bound(1_000.0, "m/s²"),
    ("body", "max-turn-rate"): Bound(3_600.0, "deg/s"),
    ("speech", "rate"): Bound(100.0, "words/s"),
    ("camera", "fov"): Bound(360.0, "deg"),
    ("camera", "range"): Bound(10_000.0, "m"),
    ("head", "pan-min"): Bound(360.0, "deg", -360.0, positive=False),
    ("head", "pan-max"): Bound(360.0, "deg", -360.0, positive=False),
    ("head", "tilt-min"): Bound(360.0, "deg", -360.0, positive=False),
    ("head", "tilt-max"): Bound(360.0, "deg", -360.0, positive=False),
    ("gesture", "duration"): Bound(3_600.0, "s"),
    ("command", "duration"): Bound(3_600.0, "s"),
    ("blend", "max-user-distance"): Bound(1_000.0, "m"),
    ("hearing", "resume-after"): Bound(60.0, "s", 0.0, positive=False),
    ("blend", "slowdown"): Bound(1.0, "", positive=True),
    ("joint", "min"): Bound(360.0, "deg", -360.0, positive=False),
    ("joint", "max"): Bound(360.0, "deg", -360.0, positive=False),
    ("joint", "rate"): Bound(3_600.0, "deg/s"),
    ("joint", "to"): Bound(360.0, "deg", -360.0, positive=False),
    ("hold", "seconds"): Bound(MAX_HOLD, "s"),
    ("sway", "degrees"): Bound(MAX_SWAY, "deg"),
    ("sway", "period"): Bound(60.0, "s"),
    ("sway", "seconds"): Bound(MAX_HOLD, "s"),
    ("budgets", "text"): Bound(MAX_TEXT, "characters"),
    ("budgets", "sends-per-second"): Bound(MAX_COUNT, "messages/s"),
    ("budgets", "waiting"): Bound(MAX_COUNT, "Commands"),
    ("budgets", "longest-ab"): Bound(MAX_SECONDS, "s"),
    ("budgets", "wait-share"): Bound(MAX_SECONDS, "s"),
    ("budgets", "wait-window"): Bound(MAX_SECONDS, "s"),
    ("budgets", "starts-per-instant"): Bound(MAX_COUNT, "behaviors"),
}
"""The range of every number of a profile: (element, attribute) -> bound."""

def _param(el: etree._Element) -> Param:
    """A ``<param>`` of a robot-specific Command, or an ``<extra>`` argument (its default is
    checked by :meth:`_Reader.param`)."""
    kind = ParamKind(el.get("kind"))
    default: Value = el.get("default")
    if isinstance(default, str) and kind is ParamKind.NUMBER:
        number = _float(default)
        default = number if number is not None and abs(number) <= MAX_NUMBER else None
    return Param(el.get("name", ""), kind, flag(el, "required"),
                 default, el.get("unit", ""), el.get("doc", ""))


def _float(text: str) -> float | None:
    """``text`` as a finite float, or None."""
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


def parse_profile(data: bytes, name: str) -> RobotProfile:
    """Load a profile from bytes; raise :class:`DocumentError` with every problem."""
    return profile_from_xml(parse_xml(data, name, DocumentError))


def profile_from_xml(doc: XmlDocument) -> RobotProfile:
    """Load a profile already parsed securely; raise :class:`DocumentError`."""
    if doc.root.tag != f"{{{NAMESPACE}}}robot":
        raise DocumentError([doc.problem(
            doc.root, f'not a robot profile: expected <robot xmlns="{NAMESPACE}">')])
    problems = validate(doc, "robot.xsd")
    if problems:
        raise DocumentError(problems)
    reader = _Reader(doc)
    profile = reader.read()
    if reader.problems:  # in source order: some are found once everything is read
        raise DocumentError(limit(sorted(reader.problems, key=lambda p: (p.line, p.col)),
                                  doc.name))
    return profile


class _Reader:
    """Reads a schema-valid profile, one method per element kind, collecting problems."""

    def __init__(self, doc: XmlDocument) -> None:
        self.doc = doc
        self.problems: list[Problem] = []
        self.standard = Catalog.standard()
        self.devices: set[str] = set()
        self.gestures: dict[str, float] = {}
        self.commands: list[CommandSpec] = []
        self.extras: dict[str, dict[str, Param]] = {}
        self.events: dict[str, bool] = {}
        self.user_events: set[str] = set()
        self.policies: dict[str, bool] = {}
        self.command_names: set[str] = set()
        self.implemented: dict[str, CommandSpec] = {}
        self.joints: dict[str, JointSpec] = {}
        self.performs: list[tuple[etree._Element, str, int]] = []
        """``<perform>`` elements, their Commands' names and places in
        :attr:`commands` (-1: implemented), compiled once every argument, joint and
        event is known (:meth:`_compile`)."""

    def error(self, el: etree._Element, message: str, attribute: str | None = None) -> None:
        self.problems.append(self.doc.problem(el, message, attribute=attribute))

    def number(self, el: etree._Element, name: str, default: float = 1.0) -> float:
        """A number of the profile, checked against its :data:`FIGURES` bound.

        Out of range (infinite, zero where it must be positive, too large):
        a problem at the attribute, and ``default`` so that reading goes on.
        """
        value = number(self.doc, el, name, FIGURES[(local_name(el), name)], default)
        if isinstance(value, Problem):
            self.problems.append(value)
            return default
        return value

    def read(self) -> RobotProfile:
        """The profile; problems found on the way are in :attr:`problems`."""
        root = self.doc.root
        parts = {local_name(c): c for c in elements(root)}
        self._devices(parts["devices"])
        for el in elements(root):
            read = _ELEMENTS.get(local_name(el))
            if read is not None:
                read(self, el)
        self._compile()
        self._check_devices(parts["devices"])
        body, head, camera = parts["body"], parts["head"], parts["camera"]
        self._check_ranges(head)
        return RobotProfile(
            name=root.get("name", ""),
            path=self.doc.name,
            radius=self.number(body, "radius"),
            max_speed=self.number(body, "max-speed"),
            max_accel=self.number(body, "max-accel"),
            max_turn_rate=self.number(body, "max-turn-rate"),
            speech_rate=self.number(parts["speech"], "rate"),
            camera_fov=self.number(camera, "fov"),
            camera_range=self.number(camera, "range"),
            pan_range=(self.number(head, "pan-min", 0.0), self.number(head, "pan-max", 0.0)),
            tilt_range=(self.number(head, "tilt-min", 0.0), self.number(head, "tilt-max", 0.0)),
            devices=frozenset(self.devices),
            gestures=self.gestures,
            commands=tuple(self.commands),
            implemented=tuple(self.implemented.values()),
            joints=MappingProxyType(self.joints),
            extras=self.extras,
            events=self.events,
            user_events=frozenset(self.user_events),
            budgets=self._role_budgets([el for el in elements(root)
                                        if local_name(el) == "budgets"]),
            interruptible=(interruptible := self._interruptible(root)),
            blends=(blends := self._blends(root)),
            hearing=(hearing := self._hearing(root)),
            policies=MappingProxyType(self._declared_on(interruptible=bool(interruptible),
                                                        blend=bool(blends),
                                                        hearing=hearing.always)),
        )

    def _declared_on(self, **declared: bool) -> dict[str, bool]:
        """The profile's policy switches: a policy the profile declares the means of
        (``<interruptible>``, ``<blend>``) is on unless a ``<policy>`` says otherwise."""
        if "all" in self.policies:
            return self.policies
        on = {"interrupt": declared["interruptible"], "blend": declared["blend"],
              "barge-in": declared["hearing"]}
        return {**{name: True for name, yes in on.items() if yes}, **self.policies}

    def _blends(self, root: etree._Element) -> tuple[Blend, ...]:
        """The ``<blend>`` elements: Commands and devices each known."""
        known = {c.name for c in Catalog.standard()} | {c.name for c in self.commands}
        out: list[Blend] = []
        for el in elements(root):
            if local_name(el) != "blend":
                continue
            names = {a: frozenset((el.get(a) or "").split()) for a in ("local", "over")}
            for attr, found in names.items():
                for name in sorted(found - known):
                    self.error(el, f"<blend> names {name!r}, which is no Command of this "
                                   "robot", attr)
            own = {c.name for c in self.commands}
            for name in sorted(names["local"] & known - own):
                # a local motion is a Command declared for that purpose (a dance step, a
                # nod), never one applications use for real motion (a Turn)
                self.error(el, f"<blend> makes the common Command {name!r} a local motion; "
                               "a local motion is a Command this robot declares for it "
                               '(<command name="Sway" ...> with a <perform>)', "local")
            devices = frozenset((el.get("devices") or "").split())
            for name in sorted(devices - self.devices):
                self.error(el, f"<blend> shares the device {name!r}, which this robot "
                               "does not declare", "devices")
            bound = el.get("max-user-distance")
            out.append(Blend(names["local"], names["over"], devices,
                             self.number(el, "max-user-distance") if bound else None,
                             self.number(el, "slowdown", 1.0)))
            if len(out) > MAX_BLENDS:
                self.error(el, f"more than {MAX_BLENDS} <blend> elements")
                break
        return tuple(out)

    def _role_budgets(self, found: list[etree._Element]) -> Mapping[AppKind, Budgets]:
        """Each role's budgets: a ``<budgets>`` without ``role`` sets both roles',
        then ``<budgets role="fa|ea">`` sets that role's, over its defaults."""
        budgets = dict(DEFAULT_BUDGETS)
        seen: set[str] = set()
        for el in sorted(found, key=lambda e: e.get("role") is not None):
            role = el.get("role", "")
            if role in seen:
                self.error(el, f"a second <budgets{f' role={role!r}' if role else ''}>: "
                               "give each role's budgets once", "role" if role else None)
                continue
            seen.add(role)
            given = self._budget_values(el)
            kinds = [AppKind(role)] if role else list(AppKind)
            for kind in kinds:
                budgets[kind] = replace(budgets[kind], **given)
            self._check_share(el, {kind: budgets[kind] for kind in kinds})
        return MappingProxyType(budgets)

    def _budget_values(self, el: etree._Element) -> dict[str, Any]:
        """The attributes ``el`` gives, by :class:`Budgets` field name."""
        given: dict[str, Any] = {}
        for attribute in _BUDGET_COUNTS + _BUDGET_SECONDS:
            if el.get(attribute) is not None:
                value = self.number(el, attribute)
                given[attribute.replace("-", "_")] = (
                    int(value) if attribute in _BUDGET_COUNTS else value)  # schema: integers
        return given

    def _check_share(self, el: etree._Element, set_here: Mapping[AppKind, Budgets]) -> None:
        """One problem at ``el`` if a role's wait share it sets outlasts its window."""
        for kind, budgets in set_here.items():
            if budgets.wait_share > budgets.wait_window:
                self.error(el, f"wait-share={budgets.wait_share:g} s is longer than its window "
                               f"(wait-window={budgets.wait_window:g} s) for the {kind.name}",
                           "wait-share" if el.get("wait-share") is not None else "wait-window")
                return

    def _devices(self, parent: etree._Element) -> None:
        for dev in elements(parent):
            name = dev.get("name", "")
            if name in self.devices:
                self.error(dev, f"device '{name}' is declared twice", "name")
            self.devices.add(name)

    def _check_devices(self, parent: etree._Element) -> None:
        """Every common device the robot lacks must be one no common Command uses
        here: each that does is implemented on the robot's own devices."""
        specs = [self.implemented.get(c.name, c) for c in self.standard]
        for missing in (d for d in STANDARD_DEVICES if d not in self.devices):
            users = [c.name for c in specs
                     if missing in c.devices or any(missing in p.devices for p in c.params)]
            if users:
                self.error(parent, f"a PRIMA robot needs the device '{missing}' "
                                   f"(used by {_listed(users)}; a robot without it "
                                   "must <implement> those on devices of its own)")

    def _hearing(self, root: etree._Element) -> Hearing:
        """``<hearing>``: when the robot hears, the phrases it talks on over, its pause."""
        el = next((e for e in elements(root) if local_name(e) == "hearing"), None)
        if el is None:
            return Hearing()
        listed = el.get("backchannels")
        phrases = Hearing().backchannels
        if listed is not None:
            found = [tuple(words(p)) for p in listed.split("|")]
            phrases = frozenset(p for p in found if p)
            if len(found) > MAX_BACKCHANNELS:
                self.error(el, f"backchannels lists {len(found)} phrases; at most "
                               f"{MAX_BACKCHANNELS}", "backchannels")
        pause = self.number(el, "resume-after", RESUME_PAUSE)
        return Hearing(always=el.get("always") == "true", backchannels=phrases, pause=pause)

    def _interruptible(self, root: etree._Element) -> frozenset[str]:
        """The Commands named by ``<interruptible commands="...">``, each one known."""
        names: set[str] = set()
        known = {c.name for c in Catalog.standard()} | {c.name for c in self.commands}
        for el in elements(root):
            if local_name(el) != "interruptible":
                continue
            for name in (el.get("commands") or "").split():
                if name not in known:
                    self.error(el, f"<interruptible> names {name!r}, which is no Command "
                                   "of this robot", "commands")
                names.add(name)
        return frozenset(names)

    def policy(self, el: etree._Element) -> None:
        name = el.get("name", "")
        if name in self.policies:
            self.error(el, f"a second <policy name={name!r}>: switch each policy once", "name")
        self.policies[name] = el.get("state") == "on"

    def gesture(self, el: etree._Element) -> None:
        name = el.get("name", "")
        if name in self.gestures:
            self.error(el, f"gesture '{name}' is declared twice", "name")
        self.gestures[name] = self.number(el, "duration")

    def command(self, el: etree._Element) -> None:
        name = el.get("name", "")
        if name in self.standard:
            self.error(el, f"'{name}' is a common Command; a robot-specific "
                           "Command needs a name of its own", "name")
        elif self._own_command(name):
            self.error(el, f"Command '{name}' is declared twice", "name")
        self.command_names.add(name)
        used = self._used_devices(el, name)
        priority = el.get("priority")
        perform = _perform_of(el)
        if perform is not None and el.get("duration") is not None:
            self.error(el, f"Command '{name}' has a <perform>: it lasts as long as its steps "
                           "take, so it gives no duration", "duration")
        spec = CommandSpec(
            name=name,
            devices=frozenset(used),
            feedback=flag(el, "feedback"),
            breaks_cc=flag(el, "breaks-cc"),
            params=tuple(self.param(p) for p in elements(el) if local_name(p) == "param"),
            robot_specific=True,
            doc=el.get("doc", ""),
            priority_override=None if priority is None else
            (Priority.HIGH if priority == "high" else Priority.LOW),
            duration=self.number(el, "duration") if el.get("duration") else None,
        )
        self.commands.append(spec)
        if perform is not None and self._performable(perform, spec):
            self.performs.append((perform, name, len(self.commands) - 1))

    def _used_devices(self, el: etree._Element, name: str) -> list[str]:
        used = el.get("devices", "").split()
        for device in used:
            if device not in self.devices:
                self.error(el, f"Command '{name}' uses undeclared device '{device}'", "devices")
        return used

    def _performable(self, perform: etree._Element, spec: CommandSpec) -> bool:
        """A feedback loop or a Q&A has a behavior of its own; steps cannot perform it."""
        what = "a feedback Command" if spec.feedback else "a Q&A" if spec.listens else None
        if what is not None:
            self.error(perform, f"{spec.name} is {what}; a <perform> cannot perform it")
        return what is None

    def implement(self, el: etree._Element) -> None:
        """``<implement command="PointByHand" devices="laser-pointer">``: a common Command
        performed on this robot's own devices, by its ``<perform>`` if it gives one."""
        name = el.get("command", "")
        spec = self.standard.get(name)
        if spec is None:
            hint = (" (a robot-specific Command gives its <perform> in its <command>)"
                    if self._own_command(name) else "")
            self.error(el, f"'{name}' is not a common Command{hint}", "command")
            return
        if name in self.implemented:
            self.error(el, f"Command '{name}' is implemented twice", "command")
            return
        if el.get("devices") is not None:
            spec = replace(spec, devices=frozenset(self._used_devices(el, name)))
        self.implemented[name] = spec
        perform = _perform_of(el)
        if perform is not None and self._performable(perform, spec):
            self.performs.append((perform, name, -1))

    def joint(self, el: etree._Element) -> None:
        """``<joint name="laser-pan" device="laser-pointer" min max rate>``."""
        name, device = el.get("name", ""), el.get("device", "")
        if name in BUILTIN_JOINTS:
            self.error(el, f"'{name}' is a built-in joint (of the device "
                           f"'{BUILTIN_JOINTS[name]}'); a declared joint needs a name of "
                           "its own", "name")
            return
        if name in self.joints:
            self.error(el, f"joint '{name}' is declared twice", "name")
            return
        if len(self.joints) == MAX_JOINTS:
            self.error(el, f"a robot declares at most {MAX_JOINTS} joints")
            return
        if device not in self.devices:
            self.error(el, f"joint '{name}' belongs to undeclared device '{device}'", "device")
        low, high = self.number(el, "min", 0.0), self.number(el, "max", 0.0)
        if low > high:
            self.error(el, f"joint '{name}' has an empty range: min > max", "min")
        self.joints[name] = JointSpec(name, device, low, high, self.number(el, "rate"))

    # ---- <perform>: compiled once everything it may name is known ----

    def _compile(self) -> None:
        for perform, name, index in self.performs:
            spec = self.implemented[name] if index < 0 else self.commands[index]
            args = {p.name: p for p in spec.params}
            args.update(self.extras.get(name, {}))
            done = replace(spec, perform=tuple(self._steps(perform, spec, args)))
            if index < 0:
                self.implemented[name] = done
            else:
                self.commands[index] = done

    def _steps(self, perform: etree._Element, spec: CommandSpec,
               args: Mapping[str, Param]) -> list[Primitive]:
        steps: list[Primitive] = []
        for i, step in enumerate(elements(perform)):
            if i == MAX_STEPS:
                self.error(step, f"a <perform> has at most {MAX_STEPS} steps")
                break
            kind = local_name(step)
            if kind == "hold":
                seconds = self._operand(step, "seconds", spec, args, ParamKind.NUMBER,
                                        STEP_LIMITS[Hold]["seconds"])
                if seconds is not None and not isinstance(seconds, str):
                    steps.append(Hold(seconds))
            elif kind == "joint":
                move = self._move(step, spec, args)
                if move is not None:
                    steps.append(move)
            elif kind == "sway":
                sway = self._sway(step, spec, args)
                if sway is not None:
                    steps.append(sway)
            elif step.get("event", "") in self.events:
                steps.append(RaiseEvent(step.get("event", "")))
            else:
                event = step.get("event", "")
                self.error(step, f"'{event}' is not an event this robot declares (declare it "
                                 f'with <event name="{event}"/>)', "event")
        return steps

    def _sway(self, step: etree._Element, spec: CommandSpec,
              args: Mapping[str, Param]) -> SwayBody | None:
        """A ``<sway>`` step: the Command must drive the wheels (``locomotion``)."""
        if "locomotion" not in spec.devices:
            self.error(step, f"a <sway> step moves the body: {spec.name} must use the device "
                             f"'locomotion' (its devices: {_listed(sorted(spec.devices))})")
        found = [self._operand(step, a, spec, args, ParamKind.NUMBER, STEP_LIMITS[SwayBody][a])
                 for a in ("degrees", "period", "seconds")]
        numbers = [f for f in found if f is not None and not isinstance(f, str)]
        if len(numbers) != 3:
            return None
        degrees, period, seconds = numbers
        return SwayBody(degrees, period, seconds)

    def _move(self, step: etree._Element, spec: CommandSpec,
              args: Mapping[str, Param]) -> MoveJoint | None:
        name = step.get("name", "")
        joint = self.joints.get(name)
        if joint is None and name in BUILTIN_JOINTS:
            joint = JointSpec(name, BUILTIN_JOINTS[name])
        if joint is None:
            self.error(step, f"unknown joint '{name}' (this robot's joints: "
                             f"{_listed([*BUILTIN_JOINTS, *self.joints])})", "name")
            return None
        if joint.device not in spec.devices:
            self.error(step, f"joint '{name}' is moved by the device '{joint.device}', which "
                             f"{spec.name} does not use (its devices: "
                             f"{_listed(sorted(spec.devices))})", "name")
        given = [a for a in ("to", "toward") if step.get(a) is not None]
        if not given:
            self.error(step, "a <joint> step needs to= (an angle) or toward= (a place)")
            return None
        if len(given) == 2 and not all(step.get(a, "").startswith("{") for a in given):
            self.error(step, "to= and toward= would both always have a value; give one, "
                             "or give both as arguments of which a call gives one", "toward")
            return None
        to = self._operand(step, "to", spec, args, ParamKind.NUMBER)
        toward = self._operand(step, "toward", spec, args, ParamKind.PLACE)
        if to is None and toward is None:
            return None
        return MoveJoint(joint, None if isinstance(to, str) else to,
                         None if isinstance(toward, float) else toward)

    def _operand(self, step: etree._Element, attribute: str, spec: CommandSpec,
                 args: Mapping[str, Param], kind: ParamKind,
                 limits: Range | None = None) -> float | str | ArgRef | None:
        """A step's attribute: ``{name}`` (an argument of ``kind``; its default, when the
        call gives it none, within the step's ``limits``), else a literal (a number within
        its :data:`FIGURES` bound, or a place name); None if absent or wrong (with a
        problem)."""
        raw = step.get(attribute)
        if raw is None:
            return None
        if raw.startswith("{"):  # the schema's pattern: exactly {name}
            name = raw[1:-1]
            param = args.get(name)
            if param is None:
                self.error(step, f"'{raw}' is not an argument of {spec.name} (its arguments: "
                                 f"{_listed(list(args)) or 'none'})", attribute)
                return None
            if param.kind is not kind:
                self.error(step, f"'{raw}' is a {param.kind.value} argument of {spec.name}; "
                                 f"{attribute}= takes a {kind.value}", attribute)
                return None
            default = param.default
            refusal = (limits.refusal(default) if limits is not None and not param.required
                       and isinstance(default, (int, float)) else None)
            if refusal is not None:
                self.error(step, f"'{raw}' defaults to {default:g}: {spec.name} called "
                                 f"without it would fail ({refusal})", attribute)
                return None
            return ArgRef(name, default)
        if kind is not ParamKind.NUMBER:
            return raw
        value = number(self.doc, step, attribute, FIGURES[(local_name(step), attribute)], 0.0)
        if isinstance(value, Problem):
            self.problems.append(value)
            return None
        return value

    def extra(self, el: etree._Element) -> None:
        name, command = el.get("name", ""), el.get("command", "")
        if command not in self.standard and not self._own_command(command):
            self.error(el, f"additional argument for unknown Command '{command}'", "command")
        if name in self.extras.get(command, {}):
            self.error(el, f"additional argument '{name}' of {command} is declared twice", "name")
        self.extras.setdefault(command, {})[name] = self.param(el)

    def param(self, el: etree._Element) -> Param:
        """A ``<param>`` or ``<extra>``; a number's default must be a finite number."""
        param = _param(el)
        raw = el.get("default")
        if raw is not None and param.kind is ParamKind.NUMBER and param.default is None:
            shown = raw if len(raw) <= 20 else raw[:17] + "..."
            self.error(el, f"default={shown!r} is not a number a Command can take "
                           f"(finite, at most {MAX_NUMBER:.0f} in size)", "default")
        return param

    def event(self, el: etree._Element) -> None:
        name = el.get("name", "")
        if name in PREDEFINED_EVENTS:
            self.error(el, f"'{name}' is a predefined event; a robot-specific "
                           "event needs a name of its own", "name")
        self.events[name] = flag(el, "reactive", default=True)
        if name in USER_ACTION_EVENTS:
            if el.get("user") in ("false", "0"):
                self.error(el, f"'{name}' is always the user's own action (docs/rules.md "
                               "7.1): a profile may name more such events, never fewer",
                           "user")
            self.user_events.add(name)
        elif flag(el, "user", default=False):
            self.user_events.add(name)

    def _own_command(self, name: str) -> bool:
        return name in self.command_names

    def _check_ranges(self, head: etree._Element) -> None:
        for lo, hi, what in (("pan-min", "pan-max", "pan"), ("tilt-min", "tilt-max", "tilt")):
            low, high = _float(head.get(lo, "0")), _float(head.get(hi, "0"))
            if low is not None and high is not None and low > high:
                self.error(head, f"{what} range is empty: {lo} > {hi}", lo)


def _perform_of(el: etree._Element) -> etree._Element | None:
    """The ``<perform>`` child of a ``<command>`` or ``<implement>``, if any (the schema
    allows one, last)."""
    found = elements(el)
    return found[-1] if found and local_name(found[-1]) == "perform" else None


def _listed(names: list[str], most: int = 10) -> str:
    """Names for a message: the first ``most``, then how many more."""
    shown = ", ".join(names[:most])
    return shown + (f" and {len(names) - most} more" if len(names) > most else "")


_ELEMENTS: Mapping[str, Callable[[_Reader, etree._Element], None]] = {
    "gesture": _Reader.gesture,
    "command": _Reader.command,
    "implement": _Reader.implement,
    "joint": _Reader.joint,
    "extra": _Reader.extra,
    "event": _Reader.event,
    "policy": _Reader.policy,
}
"""How each repeatable element of a profile is read."""


def load_profile(path: str | Path) -> RobotProfile:
    """Load a profile file; raise :class:`DocumentError` with every problem."""
    p = Path(path)
    return parse_profile(read_source(p, DocumentError), str(path))


@lru_cache(maxsize=1)
def default_profile() -> RobotProfile:
    """The shipped small home robot (``robots/home-robot.xml``)."""
    return parse_profile(packaged("prima.robots", DEFAULT_PROFILE).read_bytes(),
                         f"robots/{DEFAULT_PROFILE}")
