"""Robot hardware profiles: what a robot has and what its FA may use beyond the common interface.

A profile (``schemas/robot.xsd``) lists the robot's devices and physical
figures, its gestures, robot-specific Commands, additional arguments of
common Commands, and robot-specific events. Only an FA may use the
robot-specific parts (MISSION.md section 4).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path
from typing import Mapping

from lxml import etree

from prima.xmlio import validate
from prima.xmlio import XmlDocument, local_name, parse_xml, read_source
from prima.errors import DocumentError, Problem
from prima.catalog import (
    STANDARD_DEVICES,
    Catalog,
    CommandSpec,
    Param,
    ParamKind,
    Priority,
)
from prima.vocab import PREDEFINED_EVENTS

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
    """Robot-specific Commands."""
    command_durations: Mapping[str, float]
    extras: Mapping[str, Mapping[str, Param]]
    """Additional arguments: Command name -> argument name -> declaration."""
    events: Mapping[str, bool]
    """Robot-specific events -> whether they are reactive."""

    def catalog(self) -> Catalog:
        """The common Commands plus this robot's own."""
        return Catalog.standard().extended(self.commands, self.devices)


def _num(el: etree._Element, name: str) -> float:
    return float(el.get(name, "0"))


def _param(el: etree._Element) -> Param:
    kind = ParamKind(el.get("kind"))
    default: str | float | None = el.get("default")
    if default is not None and kind is ParamKind.NUMBER:
        try:
            default = float(default)
        except ValueError:
            default = None
    return Param(el.get("name", ""), kind, el.get("required") in ("true", "1"),
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
    profile, problems = _build(doc)
    if problems:
        raise DocumentError(problems)
    return profile


def _build(doc: XmlDocument) -> tuple[RobotProfile, list[Problem]]:
    root = doc.root
    problems: list[Problem] = []
    parts = {local_name(c): c for c in root if isinstance(c.tag, str)}
    body, head = parts["body"], parts["head"]
    standard = Catalog.standard()

    devices: dict[str, etree._Element] = {}
    for dev in parts["devices"]:
        if not isinstance(dev.tag, str):
            continue
        name = dev.get("name", "")
        if name in devices:
            problems.append(doc.problem(dev, f"device '{name}' is declared twice", attribute="name"))
        devices[name] = dev
    for missing in (d for d in STANDARD_DEVICES if d not in devices):
        problems.append(doc.problem(parts["devices"],
                                    f"a PRIMA robot needs the device '{missing}'"))

    gestures: dict[str, float] = {}
    commands: list[CommandSpec] = []
    durations: dict[str, float] = {}
    extras: dict[str, dict[str, Param]] = {}
    events: dict[str, bool] = {}
    for el in root:
        if not isinstance(el.tag, str):
            continue
        tag = local_name(el)
        name = el.get("name", "")
        if tag == "gesture":
            if name in gestures:
                problems.append(doc.problem(el, f"gesture '{name}' is declared twice", attribute="name"))
            gestures[name] = _num(el, "duration")
        elif tag == "command":
            if name in standard:
                problems.append(doc.problem(el, f"'{name}' is a common Command; a robot-specific "
                                                "Command needs a name of its own", attribute="name"))
            elif any(c.name == name for c in commands):
                problems.append(doc.problem(el, f"Command '{name}' is declared twice", attribute="name"))
            used = el.get("devices", "").split()
            for dev in used:
                if dev not in devices:
                    problems.append(doc.problem(el, f"Command '{name}' uses undeclared device '{dev}'",
                                                attribute="devices"))
            priority = el.get("priority")
            commands.append(CommandSpec(
                name=name,
                devices=frozenset(used),
                feedback=el.get("feedback") in ("true", "1"),
                breaks_cc=el.get("breaks-cc") in ("true", "1"),
                params=tuple(_param(p) for p in el if isinstance(p.tag, str)),
                robot_specific=True,
                doc=el.get("doc", ""),
                priority_override=None if priority is None else
                (Priority.HIGH if priority == "high" else Priority.LOW),
            ))
            if el.get("duration"):
                durations[name] = _num(el, "duration")
        elif tag == "extra":
            command = el.get("command", "")
            if command not in standard and not any(c.name == command for c in commands):
                problems.append(doc.problem(el, f"additional argument for unknown Command '{command}'",
                                            attribute="command"))
            if name in extras.get(command, {}):
                problems.append(doc.problem(el, f"additional argument '{name}' of {command} is "
                                                "declared twice", attribute="name"))
            extras.setdefault(command, {})[name] = _param(el)
        elif tag == "event":
            if name in PREDEFINED_EVENTS:
                problems.append(doc.problem(el, f"'{name}' is a predefined event; a robot-specific "
                                                "event needs a name of its own", attribute="name"))
            events[name] = el.get("reactive", "true") in ("true", "1")

    for lo, hi, what in (("pan-min", "pan-max", "pan"), ("tilt-min", "tilt-max", "tilt")):
        if _num(head, lo) > _num(head, hi):
            problems.append(doc.problem(head, f"{what} range is empty: {lo} > {hi}", attribute=lo))

    profile = RobotProfile(
        name=root.get("name", ""),
        path=doc.name,
        radius=_num(body, "radius"),
        max_speed=_num(body, "max-speed"),
        max_accel=_num(body, "max-accel"),
        max_turn_rate=_num(body, "max-turn-rate"),
        speech_rate=_num(parts["speech"], "rate"),
        camera_fov=_num(parts["camera"], "fov"),
        camera_range=_num(parts["camera"], "range"),
        pan_range=(_num(head, "pan-min"), _num(head, "pan-max")),
        tilt_range=(_num(head, "tilt-min"), _num(head, "tilt-max")),
        devices=frozenset(devices),
        gestures=gestures,
        commands=tuple(commands),
        command_durations=durations,
        extras=extras,
        events=events,
    )
    return profile, problems


def load_profile(path: str | Path) -> RobotProfile:
    """Load a profile file; raise :class:`DocumentError` with every problem."""
    p = Path(path)
    return parse_profile(read_source(p, DocumentError), str(path))


@lru_cache(maxsize=1)
def default_profile() -> RobotProfile:
    """The shipped small home robot (``robots/home-robot.xml``)."""
    ref = resources.files("prima.robots").joinpath(DEFAULT_PROFILE)
    return parse_profile(ref.read_bytes(), f"robots/{DEFAULT_PROFILE}")
