"""The guide robot (robots/guide-robot.xml) in whole runs: its own Command performed
from its profile's primitives, and the museum guide EA1, written for the home
robot, pointing with the laser pointer."""

from __future__ import annotations

from pathlib import Path

import pytest

from prima.mediator import DecisionKind
from prima.run import Run
from prima.trace import Kind, device_overlaps

ROOT = Path(__file__).parents[1]
EXAMPLES = ROOT / "scenarios" / "examples"


@pytest.mark.parametrize("name", ["guide-spotlight", "museum-laser"])
def test_a_guide_robot_scenario_matches_its_reviewed_golden(  # type: ignore[no-untyped-def]
        name: str, prima_golden) -> None:
    prima_golden(EXAMPLES / f"{name}.xml")


@pytest.fixture(scope="module")
def spotlight():  # type: ignore[no-untyped-def]
    return Run(EXAMPLES / "guide-spotlight.xml").run()


def test_spotlight_holds_its_devices_and_its_events_reach_the_fa(spotlight) -> None:  # type: ignore[no-untyped-def]
    starts = [line for line in spotlight if line.kind is DecisionKind.START]
    ends = [line for line in spotlight if line.kind is DecisionKind.END]
    lights = [(s, e) for s in starts for e in ends if s.command == "Spotlight" and e.ab == s.ab]
    assert len(lights) == 2
    for start, end in lights:
        assert set(start.devices or ()) == {"laser-pointer", "neck"}
        # head 45 deg at 90 deg/s and back, laser tilt 10 deg once, pan 45 deg and back at
        # 180 deg/s, and the spot held for time=4
        first = start is lights[0][0]
        travel = 2 * 0.5 + 2 * 0.25 + (10 / 180 if first else 0.0)
        assert end.t - start.t == pytest.approx(4 + travel, abs=0.03)
    events = [line for line in spotlight if line.kind is Kind.EVENT]
    on = [line.t for line in events if line.text == "spot-on"]
    off = [line.t for line in events if line.text == "spot-off"]
    assert len(on) == len(off) == 2
    said = {line.text: line.t for line in starts if line.command == "Speak"}
    # the FA heard each event: it speaks at once on spot-on (the spot still on) and spot-off
    assert said["Look where the red dot is."] == on[1]
    assert said["Touch my head, and I will show you more."] == off[1]
    assert device_overlaps(spotlight) == []


def test_the_museum_guide_points_with_the_laser_on_the_guide_robot() -> None:
    lines = Run(EXAMPLES / "museum-laser.xml").run()
    points = [line for line in lines if line.kind is DecisionKind.START
              and "PointByHand" in (line.command or "")]
    assert len(points) == 2
    for line in points:
        assert "laser-pointer" in (line.devices or ()) and "arm" not in (line.devices or ())
    assert not any("arm" in (line.devices or ()) for line in lines)
    # the FA's Spotlight took the laser pointer first: the guide's pointing waited for it
    light = next(line for line in lines if line.kind is DecisionKind.END
                 and line.command == "Spotlight")
    assert points[0].t >= light.t
    assert not [line for line in lines if line.kind is Kind.ERROR]
    assert device_overlaps(lines) == []
