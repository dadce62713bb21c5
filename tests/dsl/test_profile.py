"""Robot hardware profiles."""

from __future__ import annotations

import pytest

from prima.catalog import STANDARD_DEVICES, Priority
from prima.dsl import default_profile, parse_profile
from prima.errors import DocumentError


def test_default_profile_extends_the_catalog() -> None:
    profile = default_profile()
    catalog = profile.catalog()
    assert set(STANDARD_DEVICES) <= profile.devices
    assert catalog["TakePicture"].robot_specific
    assert catalog["TakePicture"].devices == {"camera"}
    assert catalog["TakePicture"].priority is Priority.HIGH
    assert catalog["TakePicture"].duration == 1.0
    assert catalog["Speak"].duration is None
    assert catalog["TopologicalMove"].priority is Priority.LOW
    assert profile.events == {"touched": True}
    assert "volume" in profile.extras["Speak"]
    assert profile.speech_rate == 2.5 and profile.gestures["nod"] == 1.0


PROFILE = """<robot xmlns="urn:prima:robot:1" name="r">
  <body radius="0.2" max-speed="0.4" max-accel="0.5" max-turn-rate="90"/>
  <speech rate="2.5"/>
  <camera fov="60" range="4"/>
  <head pan-min="-90" pan-max="90" tilt-min="{tilt}" tilt-max="30"/>
  <devices>
    {devices}
  </devices>
  {rest}
</robot>"""
ALL = "\n    ".join(f'<device name="{d}"/>' for d in STANDARD_DEVICES)


def _load(devices: str = ALL, rest: str = "", tilt: str = "-30") -> None:
    parse_profile(PROFILE.format(devices=devices, rest=rest, tilt=tilt).encode(), "r.xml")


def test_minimal_profile_loads() -> None:
    _load()


@pytest.mark.parametrize("kwargs, line, fragment", [
    ({"devices": '<device name="speaker"/>'}, 6, "needs the device 'locomotion'"),
    ({"rest": '<command name="Speak" devices="speaker"/>'}, 15, "is a common Command"),
    ({"rest": '<command name="Laser" devices="laser"/>'}, 15, "undeclared device 'laser'"),
    ({"rest": '<extra command="Fly" name="speed" kind="number"/>'}, 15, "unknown Command 'Fly'"),
    ({"rest": '<event name="message"/>'}, 15, "is a predefined event"),
    ({"tilt": "45"}, 5, "tilt range is empty"),
    ({"rest": '<gesture name="nod" duration="-1"/>'}, 15, "gesture"),
])
def test_profile_errors(kwargs: dict[str, str], line: int, fragment: str) -> None:
    with pytest.raises(DocumentError) as info:
        _load(**kwargs)
    assert any(p.line == line and fragment in p.message for p in info.value.problems), \
        info.value.problems


def test_a_robot_specific_command_without_a_duration_has_none() -> None:
    profile = parse_profile(PROFILE.format(
        devices=ALL + '<device name="laser"/>', tilt="-30",
        rest='<command name="Laser" devices="laser"/>'
             '<command name="Blink" devices="laser" duration="0.5"/>').encode(), "r.xml")
    assert [(c.name, c.duration) for c in profile.commands] == [("Laser", None), ("Blink", 0.5)]
