"""Commands a robot profile performs from primitives (its <perform>): the simulator's
one generic behavior holds the devices, moves joints and raises events."""

from __future__ import annotations

import math

import pytest

from prima.catalog import (
    ArgRef,
    Catalog,
    CommandSpec,
    Hold,
    JointSpec,
    MoveJoint,
    Param,
    ParamKind,
    Primitive,
    RaiseEvent,
)
import prima.sim._behaviors as behaviors_module
from prima.sim import Pose

from tests.sim.helpers import call, runner

CENTER = Pose(9.5, 4, 90)
LASER = JointSpec("laser-pan", "laser", -150.0, 150.0, 180.0)
PARAMS = (Param("angle", ParamKind.NUMBER, False), Param("time", ParamKind.NUMBER, False, 2.0),
          Param("at", ParamKind.PLACE, False))


def _catalog(*steps: Primitive, name: str = "Light",
             devices: str = "laser neck") -> Catalog:
    spec = CommandSpec(name, frozenset(devices.split()), params=PARAMS, robot_specific=True,
                       perform=tuple(steps))
    return Catalog.standard().extended([spec], {"laser"})


def _run(catalog: Catalog, *calls: object, until: float = 30.0, **kwargs: object):  # type: ignore[no-untyped-def]
    r = runner("museum", CENTER, catalog=catalog, **kwargs)
    r.queue(*calls)
    r.run(until)
    return r


def test_a_hold_keeps_the_devices_for_its_time() -> None:
    r = _run(_catalog(Hold(1.5), Hold(ArgRef("time", 2.0))), call("Light"),
             call("Light", time=0.5))
    first, second = r.ends("Light")
    assert (first.time, second.time) == (pytest.approx(1.5 + 2.0), pytest.approx(3.5 + 1.5 + 0.5))
    assert first.data == {} and "error" not in second.data


def test_an_ab_ends_the_same_whether_it_returns_or_yields_finish(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # (the compiled build ends an AB by yielding finish, the interpreted one by returning)
    def ends(by_finish: bool) -> list[tuple[float, dict[str, object]]]:
        monkeypatch.setattr(behaviors_module, "_FINISH", by_finish)
        r = _run(_catalog(Hold(1.5), MoveJoint(LASER, to=ArgRef("angle"))),
                 call("Light", angle=90), call("Light", angle="wide"), call("Light", angle=-40))
        return [(e.time, dict(e.data)) for e in r.ends("Light")]

    assert ends(by_finish=True) == ends(by_finish=False)
    assert [(t, sorted(data)) for t, data in ends(by_finish=True)] == [
        (pytest.approx(2.0), ["laser-pan"]), (pytest.approx(2.0), ["error"]),
        (pytest.approx(2.0 + 1.5 + 130 / 180, abs=0.02), ["laser-pan"])]  # (in whole ticks)


def test_a_joint_moves_at_its_rate_within_its_limits() -> None:
    r = _run(_catalog(MoveJoint(LASER, to=ArgRef("angle"))), call("Light", angle=90),
             call("Light", angle=-400))
    first, second = r.ends("Light")
    assert first.time == pytest.approx(0.5) and first.data == {"laser-pan": 90.0}
    # beyond the limit: stops at -150, 240 degrees away at 180 deg/s
    assert second.data == {"laser-pan": -150.0}
    assert second.time == pytest.approx(0.5 + 240 / 180, abs=0.02)
    assert r.sim.world.joint_angle("laser-pan", r.sim.kernel.tick) == -150.0
    assert r.sim.world.arm.at(r.sim.kernel.tick) == 0.0  # the arm never moved


def test_a_joint_is_interpolated_while_it_moves() -> None:
    r = runner("museum", CENTER, catalog=_catalog(MoveJoint(LASER, to=90.0)))
    r.queue(call("Light"))
    r.run(0.2)  # 90 degrees at 180 deg/s: 0.5 s, 40% of the way
    assert r.sim.world.joint_angle("laser-pan", r.sim.kernel.tick) == pytest.approx(36.0)


def test_a_joint_turned_toward_a_place_aims_at_its_bearing() -> None:
    r = _run(_catalog(MoveJoint(LASER, to=ArgRef("angle"), toward=ArgRef("at"))),
             call("Light", at="panel-2"))
    bearing = math.degrees(math.atan2(6.4 - 4, 12 - 9.5)) - 90
    assert r.ends("Light")[0].data["laser-pan"] == pytest.approx(bearing, abs=0.1)


def test_the_built_in_head_pan_turns_the_camera() -> None:
    r = _run(_catalog(MoveJoint(JointSpec("head-pan", "neck"), to=ArgRef("angle"))),
             call("Light", angle=120))
    end = r.ends("Light")[0]
    assert end.data == {"head-pan": 90.0}  # the head's own limit
    assert end.time == pytest.approx(1.0)  # 90 degrees at the head's 90 deg/s
    tick = r.sim.kernel.tick
    assert math.degrees(r.sim.world.camera_heading(tick)) == pytest.approx(180.0)


def test_a_raise_posts_the_event_when_its_step_comes() -> None:
    r = _run(_catalog(MoveJoint(LASER, to=90.0), RaiseEvent("lit"), Hold(1.0)), call("Light"))
    [event] = r.events("lit")
    assert event.time == pytest.approx(0.5) and event.data == {"command": "Light"}
    assert r.ends("Light")[0].time == pytest.approx(1.5)


@pytest.mark.parametrize("args, fragment", [
    ({}, "give exactly one of an angle and a place"),
    ({"angle": 10, "at": "panel-1"}, "give exactly one of an angle and a place"),
    ({"angle": "wide"}, "must be a number, not 'wide'"),
    ({"angle": math.inf}, "must be finite"),
    ({"at": "cafe"}, "unknown place 'cafe'"),
])
def test_an_unusable_joint_argument_ends_the_command_with_an_error(
        args: dict[str, object], fragment: str) -> None:
    r = _run(_catalog(Hold(1.0), MoveJoint(LASER, to=ArgRef("angle"), toward=ArgRef("at"))),
             call("Light", **args))  # type: ignore[arg-type]
    end = r.ends("Light")[0]
    assert fragment in str(end.data["error"]) and end.time == 0.0  # checked before it starts


@pytest.mark.parametrize("time, fragment", [(-1, "a hold lasts 0 to 3600 s, not -1"),
                                            (4000, "not 4000"), (True, "not True")])
def test_an_unusable_hold_ends_the_command_with_an_error(time: object, fragment: str) -> None:
    r = _run(_catalog(Hold(ArgRef("time"))), call("Light", time=time))
    assert fragment in str(r.ends("Light")[0].data["error"])


def test_the_planned_length_counts_holds_and_joint_travel() -> None:
    """The longest-AB budget: 90 degrees out (0.5 s), the hold, 90 degrees back (0.5 s)."""
    steps = (MoveJoint(LASER, to=ArgRef("angle")), Hold(ArgRef("time")), MoveJoint(LASER, to=0.0))
    for budget, refused in ((3.0, False), (2.9, True)):
        r = runner("museum", CENTER, catalog=_catalog(*steps))
        r.sim.longest["runner"] = budget
        r.queue(call("Light", angle=90, time=2.0))
        r.run(30)
        error = str(r.ends("Light")[0].data.get("error", ""))
        assert ("Light would take 3 s; no atomic behavior of runner may take more than "
                f"{budget:g} s" in error) is refused, error


def test_a_common_command_with_a_perform_is_performed_by_it_not_by_its_own_behavior() -> None:
    standard = Catalog.standard()["PointByHand"]
    point = CommandSpec("PointByHand", frozenset({"laser"}), params=standard.params,
                        one_of=standard.one_of, aims=True,
                        perform=(MoveJoint(LASER, to=ArgRef("angle"), toward=ArgRef("toward")),))
    catalog = Catalog.standard().for_robot([point], {"laser", "neck"})
    r = _run(catalog, call("PointByHand", angle=30))
    assert r.ends("PointByHand")[0].data == {"laser-pan": 30.0}
    assert r.sim.world.arm.at(r.sim.kernel.tick) == 0.0
    home = _run(Catalog.standard(), call("PointByHand", angle=30))
    assert home.ends("PointByHand")[0].data == {"angle": 30.0}


def test_without_the_generic_behavior_the_command_would_fail() -> None:
    """The guard that the generic behavior is what performs a profile's Command: the
    same Command without steps is one the simulated robot does not have."""
    r = _run(_catalog(), call("Light"))
    assert "no Command 'Light'" in str(r.ends("Light")[0].data["error"])
    r = _run(_catalog(Hold(1.0)), call("Light"))
    assert r.ends("Light")[0].data == {} and r.ends("Light")[0].time == pytest.approx(1.0)


def test_a_robot_specific_command_with_only_a_duration_holds_its_devices_that_long() -> None:
    blink = CommandSpec("Blink", frozenset({"laser"}), robot_specific=True, duration=1.5)
    r = _run(Catalog.standard().extended([blink], {"laser"}), call("Blink"), call("Blink"))
    assert [(e.time, dict(e.data)) for e in r.ends("Blink")] == [(1.5, {}), (3.0, {})]
    # a common Command has no duration to fall back on: its own behavior performs it
    assert _run(_catalog(), call("Light")).ends("Light")[0].data["error"]


def test_a_joint_turned_toward_a_place_counts_no_travel_in_the_plan() -> None:
    """The body may turn before it in the same atomic behavior: only the hold counts."""
    steps = (MoveJoint(LASER, toward=ArgRef("at")), Hold(1.0))
    r = runner("museum", CENTER, catalog=_catalog(*steps))
    r.sim.longest["runner"] = 1.0
    r.queue(call("Light", at="entrance"))  # to the left: 90 degrees of travel, 0.5 s
    r.run(30)
    end = r.ends("Light")[0]
    assert "error" not in end.data and end.data["laser-pan"] == 90.0
    assert end.time == pytest.approx(1.5)
