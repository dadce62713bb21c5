"""Robot profiles: Commands performed from primitives (<perform>), common Commands
implemented a robot's own way (<implement>), and joints (<joint>)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from prima.catalog import (
    STANDARD_DEVICES,
    ArgRef,
    Catalog,
    Hold,
    JointSpec,
    MoveJoint,
    RaiseEvent,
)
from prima.dsl import RobotProfile, check_file, load_profile, parse_profile
from prima.errors import DocumentError
from tests.dsl.test_profile import PROFILE as BASE
from tests.work import growth

ROOT = Path(__file__).parents[2]
GUIDE = ROOT / "robots" / "guide-robot.xml"

PROFILE = BASE.replace('tilt-min="{tilt}"', 'tilt-min="-30"').replace("  {rest}\n", """\
  <joint name="laser-pan" device="laser" min="-150" max="150" rate="180"/>
  <event name="lit"/>
{rest}
""")
"""A profile with a laser and its joint, and an event; ``rest`` from line 11 on."""

DEVICES = " ".join(f'<device name="{d}"/>' for d in (*STANDARD_DEVICES, "laser"))
LASER = '<command name="Light" devices="laser neck">\n' \
        '  <param name="angle" kind="number" unit="deg"/>\n' \
        '  <param name="time" kind="number" default="2"/>\n' \
        '  <param name="at" kind="place"/>\n' \
        '  <perform>\n{steps}\n  </perform>\n</command>'
"""A robot-specific Command whose steps begin on line 16."""


def _text(rest: str, devices: str = DEVICES) -> str:
    return PROFILE.format(devices=devices, rest=rest)


def _profile(rest: str, devices: str = DEVICES) -> RobotProfile:
    return parse_profile(_text(rest, devices).encode(), "r.xml")


def _problems(rest: str, devices: str = DEVICES) -> list[tuple[str, int, int, str]]:
    """Each problem: its source line (stripped), line, column and message."""
    with pytest.raises(DocumentError) as info:
        _profile(rest, devices)
    lines = _text(rest, devices).splitlines()
    return [(lines[p.line - 1].strip(), p.line, p.col, p.message) for p in info.value.problems]


def test_a_perform_compiles_to_primitives_in_order() -> None:
    profile = _profile(LASER.format(steps='<joint name="head-pan" to="{angle}"/>\n'
                                          '<joint name="laser-pan" toward="{at}"/>\n'
                                          '<raise event="lit"/>\n'
                                          '<hold seconds="{time}"/>\n'
                                          '<hold seconds="0.5"/>'))
    spec = profile.catalog()["Light"]
    laser = JointSpec("laser-pan", "laser", -150.0, 150.0, 180.0)
    assert spec.perform == (
        MoveJoint(JointSpec("head-pan", "neck"), to=ArgRef("angle")),
        MoveJoint(laser, toward=ArgRef("at")),
        RaiseEvent("lit"),
        Hold(ArgRef("time", 2.0)),
        Hold(0.5),
    )
    assert spec.duration is None and spec.robot_specific
    assert profile.joints == {"laser-pan": laser}


def test_a_step_may_name_an_extra_argument_declared_anywhere() -> None:
    profile = _profile(LASER.format(steps='<hold seconds="{pause}"/>')
                       + '\n<extra command="Light" name="pause" kind="number" default="1"/>')
    assert profile.catalog()["Light"].perform == (Hold(ArgRef("pause", 1.0)),)


STEP_ERRORS = [
    ('<joint name="laser-tilt" to="5"/>', 16, "unknown joint 'laser-tilt' (this robot's "
     "joints: head-pan, head-tilt, arm, laser-pan)"),
    ('<joint name="arm" to="5"/>', 16, "joint 'arm' is moved by the device 'arm', which "
     "Light does not use (its devices: laser, neck)"),
    ('<hold seconds="{speed}"/>', 16, "'{speed}' is not an argument of Light (its arguments: "
     "angle, time, at)"),
    ('<joint name="laser-pan" to="{at}"/>', 16, "'{at}' is a place argument of Light; to= "
     "takes a number"),
    ('<joint name="laser-pan" toward="{angle}"/>', 16, "'{angle}' is a number argument of "
     "Light; toward= takes a place"),
    ('<raise event="dark"/>', 16, "'dark' is not an event this robot declares (declare it "
     'with <event name="dark"/>)'),
    ('<raise event="touched"/>', 16, "'touched' is not an event this robot declares"),
    ('<joint name="laser-pan"/>', 16, "a <joint> step needs to= (an angle) or toward="),
    ('<joint name="laser-pan" to="5" toward="{at}"/>', 16, "to= and toward= would both always"),
    ('<joint name="laser-pan" to="400"/>', 16, "to='400' is too large: at most 360 deg"),
    ('<hold seconds="0"/>', 16, "seconds='0' must be greater than 0"),
    ('<hold seconds="3601"/>', 16, "seconds='3601' is too large: at most 3,600 s"),
    ('<hold seconds="1"/>\n' * 32 + '<hold seconds="1"/>', 48, "a <perform> has at most 32 steps"),
]


@pytest.mark.parametrize("steps, line, fragment", STEP_ERRORS)
def test_a_bad_step_is_a_located_error(steps: str, line: int, fragment: str) -> None:
    [(source, found, _col, message)] = _problems(LASER.format(steps=steps))
    assert found == line and fragment in message, message
    assert source.startswith(("<hold", "<joint", "<raise"))


def test_a_step_that_is_not_a_literal_or_a_reference_fails_the_schema() -> None:
    for steps in ('<hold seconds="{time} + 1"/>', '<hold seconds="2*{time}"/>',
                  '<joint name="laser-pan" to="{__import__}()"/>'):
        [(_source, line, _col, _message)] = _problems(LASER.format(steps=steps))
        assert line == 16


COMMAND_ERRORS = [
    ('<command name="Blink" devices="laser" duration="1"><perform><hold seconds="1"/>'
     '</perform></command>', "has a <perform>: it lasts as long as its steps take"),
    ('<command name="Sweep" devices="laser" feedback="true"><perform><hold seconds="1"/>'
     '</perform></command>', "Sweep is a feedback Command; a <perform> cannot perform it"),
    ('<implement command="Fly" devices="laser"/>', "'Fly' is not a common Command"),
    ('<command name="Blink" devices="laser"/><implement command="Blink"/>',
     "'Blink' is not a common Command (a robot-specific Command gives its <perform> in its"),
    ('<implement command="Speak"/><implement command="Speak"/>',
     "Command 'Speak' is implemented twice"),
    ('<implement command="PointByHand" devices="pointer"/>',
     "Command 'PointByHand' uses undeclared device 'pointer'"),
    ('<implement command="TopologicalMove"><perform><hold seconds="1"/></perform></implement>',
     "TopologicalMove is a feedback Command; a <perform> cannot perform it"),
    ('<implement command="QA"><perform><hold seconds="1"/></perform></implement>',
     "QA is a Q&A; a <perform> cannot perform it"),
    ('<joint name="arm" device="arm" min="0" max="1" rate="1"/>', "'arm' is a built-in joint"),
    ('<joint name="laser-pan" device="laser" min="0" max="1" rate="1"/>',
     "joint 'laser-pan' is declared twice"),
    ('<joint name="j" device="pointer" min="0" max="1" rate="1"/>',
     "joint 'j' belongs to undeclared device 'pointer'"),
    ('<joint name="j" device="laser" min="2" max="1" rate="1"/>',
     "joint 'j' has an empty range: min > max"),
    ('<joint name="j" device="laser" min="0" max="1" rate="3601"/>',
     "rate='3601' is too large: at most 3,600 deg/s"),
    ("\n".join(f'<joint name="j{i}" device="laser" min="0" max="1" rate="1"/>'
               for i in range(32)), "a robot declares at most 32 joints"),
]


@pytest.mark.parametrize("rest, fragment", COMMAND_ERRORS)
def test_a_bad_command_implementation_or_joint_is_a_located_error(rest: str,
                                                                  fragment: str) -> None:
    problems = _problems(rest)
    assert len(problems) == 1, problems
    [(source, line, col, message)] = problems
    assert line >= 11 and col > 0 and source.startswith("<") and fragment in message, message


def test_an_armless_robot_must_implement_what_uses_the_arm() -> None:
    armless = DEVICES.replace('<device name="arm"/> ', "")
    [(source, line, _col, message)] = _problems("", devices=armless)
    assert (source, line) == ("<devices>", 6)
    assert message == ("a PRIMA robot needs the device 'arm' (used by PointByHand, Gesture; "
                       "a robot without it must <implement> those on devices of its own)")
    [(_s, _l, _c, message)] = _problems('<implement command="Gesture" devices="neck"/>',
                                        devices=armless)
    assert "(used by PointByHand;" in message
    profile = _profile('<implement command="Gesture" devices="neck"/>\n'
                       '<implement command="PointByHand" devices="laser"/>', devices=armless)
    catalog = profile.catalog()
    assert "arm" not in catalog.devices and "arm" not in profile.devices
    assert catalog["PointByHand"].devices == {"laser"} and catalog["PointByHand"].perform == ()


def test_the_guide_robot_points_with_its_laser_pointer() -> None:
    profile = load_profile(GUIDE)
    catalog = profile.catalog()
    standard = Catalog.standard()
    assert "arm" not in profile.devices and "arm" not in catalog.devices
    assert {"laser-pointer", "neck", "touch-sensor"} <= catalog.devices
    point = catalog["PointByHand"]
    assert point.devices == {"laser-pointer"}
    assert [step.joint.name for step in point.perform if isinstance(step, MoveJoint)] == [
        "laser-tilt", "laser-pan"]
    # everything else about PointByHand is the common Command's
    assert (point.params, point.one_of, point.aims, point.priority, point.robot_specific) == (
        standard["PointByHand"].params, standard["PointByHand"].one_of, True,
        standard["PointByHand"].priority, False)
    assert catalog["Gesture"].devices == {"neck"} and catalog["Gesture"].perform == ()
    assert dataclasses.replace(catalog["Speak"], interruptible=False) == standard["Speak"]
    # no common Command uses a device the robot lacks
    assert all(c.devices <= profile.devices for c in catalog)
    spotlight = catalog["Spotlight"]
    assert spotlight.devices == {"laser-pointer", "neck"} and spotlight.robot_specific
    assert RaiseEvent("spot-on") in spotlight.perform and Hold(ArgRef("time", 3.0)) in \
        spotlight.perform
    assert {"spot-on", "spot-off"} <= set(profile.events)


def test_the_shipped_profiles_and_the_museum_guide_validate_on_the_guide_robot() -> None:
    assert check_file(GUIDE) == []
    assert check_file(ROOT / "robots" / "home-robot.xml") == []
    guide = load_profile(GUIDE)
    for app in ("ea/ea1-museum.pxml", "ea/ea3-navigate.pxml", "fa/fa1-emotions.pxml",
                "fa/fa7-spotlight.pxml"):
        assert check_file(ROOT / "apps" / app, guide) == [], app


def test_many_commands_with_bad_steps_load_in_linear_time() -> None:
    def commands(n: int) -> str:
        return "\n".join(
            f'<command name="C{i}" devices="laser"><param name="p{i}" kind="number"/>'
            f'<perform><hold seconds="{{q{i}}}"/><raise event="e{i}"/></perform></command>'
            for i in range(n))
    problems = _problems(commands(2_000))
    assert len(problems) == 51
    assert problems[0][3] == "'{q0}' is not an argument of C0 (its arguments: p0)"
    assert problems[-1][3].startswith("... and 3,950 more problems")
    assert growth(lambda n: _problems(commands(n)), 500, 2_000) < 1.2


def test_a_perform_of_many_steps_is_one_error_at_the_first_too_many() -> None:
    def steps(n: int) -> list[tuple[str, int, int, str]]:
        return _problems(LASER.format(steps='<hold seconds="1"/>\n' * n))
    [(_source, line, _col, message)] = steps(20_000)
    assert line == 16 + 32 and message == "a <perform> has at most 32 steps"
    assert growth(steps, 2_000, 20_000) < 1.2
