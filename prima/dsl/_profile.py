"""Robot hardware profiles: what a robot has and what its FA may use beyond the common interface.

A profile (``schemas/robot.xsd``) lists the robot's devices and physical
figures, its gestures, robot-specific Commands, additional arguments of
common Commands, and robot-specific events. Only an FA may use the
robot-specific parts (MISSION.md section 4).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path

from lxml import etree

from prima.catalog import (
    STANDARD_DEVICES,
    Catalog,
    CommandSpec,
    Param,
    ParamKind,
    Priority,
)
from prima.dsl._elements import elements, flag
from prima.errors import DocumentError, Problem
from prima.vocab import PREDEFINED_EVENTS, Value
from prima.xmlio import XmlDocument, limit, local_name, parse_xml, read_source, validate

NAMESPACE = "urn:prima:robot:1"
DEFAULT_PROFILE = "home-robot.xml"

STANDARD_GESTURES = frozenset({"nod", "shake-head", "wave", "bow", "happy", "sad", "surprised"})
"""Gestures every robot offers; an EA may use only these."""


@dataclass(frozen=True)
class RobotProfile:
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
    _catalog: Catalog = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # built once: every document loaded against the profile asks for it
        object.__setattr__(self, "_catalog",
                           Catalog.standard().extended(self.commands, self.devices))

    def catalog(self) -> Catalog:
        """The common Commands plus this robot's own."""
        return self._catalog


def _num(el: etree._Element, name: str) -> float:
    return float(el.get(name, "0"))


def _param(el: etree._Element) -> Param:
    """A ``<param>`` of a robot-specific Command, or an ``<extra>`` argument."""
    kind = ParamKind(el.get("kind"))
    default: Value = el.get("default")
    if isinstance(default, str) and kind is ParamKind.NUMBER:
        try:
            default = float(default)
        except ValueError:
            default = None
    return Param(el.get("name", ""), kind, flag(el, "required"),
                 default, el.get("unit", ""), el.get("doc", ""))


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
    if reader.problems:
        raise DocumentError(limit(reader.problems, doc.name))
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

    def error(self, el: etree._Element, message: str, attribute: str | None = None) -> None:
        self.problems.append(self.doc.problem(el, message, attribute=attribute))

    def read(self) -> RobotProfile:
        """The profile; problems found on the way are in :attr:`problems`."""
        root = self.doc.root
        parts = {local_name(c): c for c in elements(root)}
        self._devices(parts["devices"])
        for el in elements(root):
            read = _ELEMENTS.get(local_name(el))
            if read is not None:
                read(self, el)
        body, head, camera = parts["body"], parts["head"], parts["camera"]
        self._check_ranges(head)
        return RobotProfile(
            name=root.get("name", ""),
            path=self.doc.name,
            radius=_num(body, "radius"),
            max_speed=_num(body, "max-speed"),
            max_accel=_num(body, "max-accel"),
            max_turn_rate=_num(body, "max-turn-rate"),
            speech_rate=_num(parts["speech"], "rate"),
            camera_fov=_num(camera, "fov"),
            camera_range=_num(camera, "range"),
            pan_range=(_num(head, "pan-min"), _num(head, "pan-max")),
            tilt_range=(_num(head, "tilt-min"), _num(head, "tilt-max")),
            devices=frozenset(self.devices),
            gestures=self.gestures,
            commands=tuple(self.commands),
            extras=self.extras,
            events=self.events,
        )

    def _devices(self, parent: etree._Element) -> None:
        for dev in elements(parent):
            name = dev.get("name", "")
            if name in self.devices:
                self.error(dev, f"device '{name}' is declared twice", "name")
            self.devices.add(name)
        for missing in (d for d in STANDARD_DEVICES if d not in self.devices):
            self.error(parent, f"a PRIMA robot needs the device '{missing}'")

    def gesture(self, el: etree._Element) -> None:
        name = el.get("name", "")
        if name in self.gestures:
            self.error(el, f"gesture '{name}' is declared twice", "name")
        self.gestures[name] = _num(el, "duration")

    def command(self, el: etree._Element) -> None:
        name = el.get("name", "")
        if name in self.standard:
            self.error(el, f"'{name}' is a common Command; a robot-specific "
                           "Command needs a name of its own", "name")
        elif self._own_command(name):
            self.error(el, f"Command '{name}' is declared twice", "name")
        used = el.get("devices", "").split()
        for device in used:
            if device not in self.devices:
                self.error(el, f"Command '{name}' uses undeclared device '{device}'", "devices")
        priority = el.get("priority")
        self.commands.append(CommandSpec(
            name=name,
            devices=frozenset(used),
            feedback=flag(el, "feedback"),
            breaks_cc=flag(el, "breaks-cc"),
            params=tuple(_param(p) for p in elements(el)),
            robot_specific=True,
            doc=el.get("doc", ""),
            priority_override=None if priority is None else
            (Priority.HIGH if priority == "high" else Priority.LOW),
            duration=_num(el, "duration") if el.get("duration") else None,
        ))

    def extra(self, el: etree._Element) -> None:
        name, command = el.get("name", ""), el.get("command", "")
        if command not in self.standard and not self._own_command(command):
            self.error(el, f"additional argument for unknown Command '{command}'", "command")
        if name in self.extras.get(command, {}):
            self.error(el, f"additional argument '{name}' of {command} is declared twice", "name")
        self.extras.setdefault(command, {})[name] = _param(el)

    def event(self, el: etree._Element) -> None:
        name = el.get("name", "")
        if name in PREDEFINED_EVENTS:
            self.error(el, f"'{name}' is a predefined event; a robot-specific "
                           "event needs a name of its own", "name")
        self.events[name] = flag(el, "reactive", default=True)

    def _own_command(self, name: str) -> bool:
        return any(c.name == name for c in self.commands)

    def _check_ranges(self, head: etree._Element) -> None:
        for lo, hi, what in (("pan-min", "pan-max", "pan"), ("tilt-min", "tilt-max", "tilt")):
            if _num(head, lo) > _num(head, hi):
                self.error(head, f"{what} range is empty: {lo} > {hi}", lo)


_ELEMENTS: Mapping[str, Callable[[_Reader, etree._Element], None]] = {
    "gesture": _Reader.gesture,
    "command": _Reader.command,
    "extra": _Reader.extra,
    "event": _Reader.event,
}
"""How each repeatable element of a profile is read."""


def load_profile(path: str | Path) -> RobotProfile:
    """Load a profile file; raise :class:`DocumentError` with every problem."""
    p = Path(path)
    return parse_profile(read_source(p, DocumentError), str(path))


@lru_cache(maxsize=1)
def default_profile() -> RobotProfile:
    """The shipped small home robot (``robots/home-robot.xml``)."""
    ref = resources.files("prima.robots").joinpath(DEFAULT_PROFILE)
    return parse_profile(ref.read_bytes(), f"robots/{DEFAULT_PROFILE}")
