"""The robot's physical specification: sizes, speeds, sensors, gestures.

A :class:`RobotSpec` is what the simulator needs to know about the body it
moves. The run loop converts a robot hardware profile into one; the simulator
never reads profiles itself. The defaults describe a small home robot in the
spirit of NEC's PaPeRo: round, wheeled, about 40 cm across, slow and careful.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Protocol

from prima.errors import SimulationError

__all__ = ["DEFAULT_GESTURES", "RobotSpec", "SpeechTiming"]

DEFAULT_GESTURES: Mapping[str, float] = MappingProxyType({
    "nod": 1.0,
    "shake-head": 1.2,
    "wave": 2.0,
    "bow": 1.5,
    "happy": 2.0,
    "sad": 2.0,
    "surprised": 1.0,
    "dance": 8.0,
})
"""Gestures every default robot knows, with their durations in seconds."""


class SpeechTiming(Protocol):
    """How long words take to say, from elsewhere than the speech rate (a synthesiser:
    ``prima show --speech-timing tts``); a :class:`Simulator` given one times every
    utterance by it, and cuts one (the interrupt policy) at the end of its word."""

    def said(self, text: str) -> tuple[float, tuple[float, ...]]:
        """How long saying ``text`` takes (s), and when each of its words (``text.split()``)
        ends, from its start (s, non-decreasing, the last at most the whole)."""
        ...


@dataclass(frozen=True)
class RobotSpec:
    """Physical limits of the simulated robot. Units: m, s, degrees."""

    radius: float = 0.2
    """Body radius (m)."""
    max_speed: float = 0.4
    """Top wheel speed (m/s)."""
    max_accel: float = 0.5
    """Linear acceleration and braking (m/s^2)."""
    max_turn_rate: float = 90.0
    """Top turning rate of the body (deg/s)."""
    turn_accel: float = 180.0
    """Angular acceleration of the body (deg/s^2)."""
    speech_rate: float = 2.5
    """Words spoken per second."""
    min_utterance: float = 0.5
    """Shortest time any utterance takes (s)."""
    camera_fov: float = 60.0
    """Horizontal field of view of the head camera (deg)."""
    camera_range: float = 4.0
    """Farthest distance at which the camera recognises the user (m)."""
    head_pan_range: tuple[float, float] = (-90.0, 90.0)
    """Head pan limits relative to the body (deg, counter-clockwise positive)."""
    head_tilt_range: tuple[float, float] = (-30.0, 30.0)
    """Head tilt limits (deg, up positive)."""
    head_rate: float = 90.0
    """Head pan/tilt speed (deg/s)."""
    arm_range: tuple[float, float] = (-120.0, 120.0)
    """Arm pointing limits relative to the body (deg)."""
    arm_rate: float = 90.0
    """Arm speed (deg/s)."""
    gestures: Mapping[str, float] = field(default_factory=lambda: DEFAULT_GESTURES)
    """Known gestures and their durations (s)."""
    hearing_range: float = 5.0
    """How far the microphone hears the user, and the user hears the robot (m)."""
    touch_reach: float = 0.5
    """How far from the robot's body the user can be and still touch it (m)."""
    lose_after: float = 1.0
    """The user counts as lost after this long unseen (s)."""
    place_tolerance: float = 0.15
    """Within this distance the robot counts as being at a place (m)."""
    passing_radius: float = 1.5
    """A place is reported as reached when the robot passes this close to it (m)
    while no Topological Move reports its own route (e.g. while tracking)."""
    position_tolerance: float = 0.05
    """Set Position is done within this distance of its target (m)."""
    control_period: float = 0.5
    """One iteration of a feedback Command (Topological Move, Set Position, Tracking
    Human): at most this long of motion (s), so that another application can act
    between any two, and a held motion stops within it."""
    tracking_band: float = 0.3
    """Tracking keeps the user within +-band of the wanted distance (m)."""
    search_time: float = 10.0
    """Active Sensing Human looks this long before turning the view (s)."""

    def __post_init__(self) -> None:
        positive = ("radius", "max_speed", "max_accel", "max_turn_rate", "turn_accel",
                    "speech_rate", "camera_fov", "camera_range", "head_rate", "arm_rate",
                    "control_period", "search_time")
        for name in positive:
            value = getattr(self, name)
            if not value > 0:
                raise SimulationError(f"RobotSpec.{name} must be positive, not {value!r}")
        for name, seconds in self.gestures.items():
            if not seconds > 0:
                raise SimulationError(
                    f"gesture {name!r} must last a positive time, not {seconds!r}")

    def speech_duration(self, text: str) -> float:
        """How long saying ``text`` takes, from its word count and the speech rate."""
        return max(self.min_utterance, len(text.split()) / self.speech_rate)

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = {}
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            if isinstance(value, tuple):
                value = list(value)
            elif isinstance(value, Mapping):
                value = dict(value)
            out[name] = value
        return out
