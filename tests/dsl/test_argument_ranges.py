"""Argument values a Command would refuse when performed: validation reports a constant
one, in the words the robot uses when it refuses it, from the same rule
(:class:`~prima.catalog.Range`), so the two cannot disagree."""

from __future__ import annotations

import pytest

from prima.catalog import EXTRAS_ACTED_ON, CommandSpec, Param, ParamKind, Range
from prima.dsl import check_document, default_profile
from prima.errors import Problem
from prima.mediator import Call
from prima.sim import Pose
from prima.vocab import Value
from tests.dsl.test_profile_perform import LASER, _problems
from tests.sim.helpers import call, runner

HEAD = ('<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">\n'
        '<var name="n" expr="0"/><grammar id="yn"><choice>yes</choice></grammar>\n'
        '<state id="s" initial="true"><entry>\n')
TAIL = '\n</entry></state></pxml>'


def _check(entry: str) -> list[Problem]:
    return check_document(f"{HEAD}{entry}{TAIL}".encode(), "t.pxml")[1]


def _errors(entry: str) -> list[str]:
    return [f"{p.line}:{p.col}: {p.message}" for p in _check(entry)]


def test_the_newcomers_negative_timeout_and_text_timer_are_validation_errors() -> None:
    """The document of the report: it validated, then failed when it ran (``after must
    be a number, got 'soon'``; ``QA fails: timeout must not be negative, not -3``)."""
    assert _errors('<chain>q: QA("Ready?", yn, n, timeout=-3)</chain>\n'
                   '<timer name="t" after="{\'soon\'}"/>') == [
        "4:39: QA: timeout must not be negative, not -3",
        "5:24: attribute after={'soon'}: expected a number, or an expression giving one",
    ]


def _ranged() -> list[tuple[CommandSpec, Param, Range]]:
    """Every argument of the default robot's Commands that has a range, with each range."""
    return [(spec, param, limits) for spec in default_profile().catalog()
            for param in spec.params for limits in spec.limits(param.name)]


def test_the_default_robot_has_ranged_arguments_of_both_kinds() -> None:
    """Ranges of a parameter (QA's timeout) and of a ``<perform>`` step (Sway's)."""
    found = {(spec.name, param.name) for spec, param, _limits in _ranged()}
    assert {("QA", "timeout"), ("TrackingHuman", "distance"), ("SetSpeedAndTime", "time"),
            ("Sway", "degrees"), ("Sway", "period"), ("Sway", "time")} <= found


def _outside(limits: Range) -> list[float]:
    """Values just outside the range: at or below its low end, above its high end."""
    out = []
    if limits.low is not None:
        out.append(limits.low if limits.above else limits.low - 0.5)
    if limits.high is not None:
        out.append(limits.high + 1)
    return out


_FILL: dict[ParamKind, tuple[str, Value]] = {
    ParamKind.TEXT: ('"x"', "x"), ParamKind.NUMBER: ("1", 1), ParamKind.GRAMMAR: ("yn", "yn"),
    ParamKind.GESTURE: ("wave", "wave"), ParamKind.SYMBOL: ("user", "user")}
"""A value for each other argument a Command needs: as a chain writes it, as it is passed."""


CASES = [(spec, param, value) for spec, param, limits in _ranged() for value in _outside(limits)]


@pytest.mark.parametrize("spec, param, value", CASES,
                         ids=[f"{s.name}-{p.name}={v:g}" for s, p, v in CASES])
def test_validation_refuses_a_constant_as_the_robot_refuses_it(
        spec: CommandSpec, param: Param, value: float) -> None:
    others = [p for p in spec.params if p.required and p is not param]
    written = ", ".join([f"{p.name}={_FILL[p.kind][0]}" for p in others]
                        + [f"{param.name}={value:g}"])
    refusal = f"{spec.name}: {spec.refusal(param.name, value)}"
    [problem] = _check(f"<chain>{spec.name}({written})</chain>")
    assert problem.message == refusal
    at = len("<chain>") + len(spec.name) + 1 + len(written) - len(f"{value:g}")
    assert (problem.line, problem.col) == (4, at + 1)  # at the value
    # the simulated robot, given the same value at run time (from a variable, say)
    r = runner("museum", Pose(9.5, 4, 0), Pose(11, 4, 180), catalog=default_profile().catalog())
    r.queue(call(spec.name, **{p.name: _FILL[p.kind][1] for p in others}, **{param.name: value}))
    r.run(5)
    [end] = r.ends(spec.name)
    assert end.data["error"] == refusal and end.time == 0.0  # refused before it starts


EXTRA_CASES = [(command, name, limits, value) for (command, name), limits
               in EXTRAS_ACTED_ON.items() if name in default_profile().extras.get(command, {})
               for value in _outside(limits)]
"""Each additional argument the robot acts on that the default robot (the home robot)
declares: a gesture's tempo, a move's speed, a turn's rate."""
_EXTRA_ARGS = {"Gesture": ("wave", {"name": "wave"}),
               "TopologicalMove": ("center", {"to": "center"}),
               "SetPosition": ("x=9.5, y=5", {"x": 9.5, "y": 5.0}),
               "SetPositionAndDirection": ("x=9.5, y=5, heading=0",
                                           {"x": 9.5, "y": 5.0, "heading": 0.0}),
               "Turn": ("90", {"angle": 90.0})}
"""How each Command with an additional argument the robot acts on is written, and called."""


@pytest.mark.parametrize("command, name, limits, value", EXTRA_CASES,
                         ids=[f"{c}-{n}={v:g}" for c, n, _limits, v in EXTRA_CASES])
def test_an_additional_argument_the_robot_acts_on_is_refused_as_the_robot_refuses_it(
        command: str, name: str, limits: Range, value: float) -> None:
    refusal = f"{command}: {limits.refusal(value)}"
    written, args = _EXTRA_ARGS[command]
    [problem] = _check(f"<chain>{command}({written})[{name}={value:g}]</chain>")
    assert problem.message == refusal
    r = runner("museum", Pose(9.5, 4, 0), Pose(11, 4, 180), catalog=default_profile().catalog())
    r.queue(Call(command, args, {name: value}))
    r.run(5)
    [end] = r.ends(command)
    assert end.data["error"] == refusal


@pytest.mark.parametrize("entry", [
    '<chain>Gesture(wave)[tempo=0.5], TopologicalMove(center)[speed=9], Turn(90)[rate=1]</chain>',
    '<chain>Gesture(wave)[tempo={n}], Speak("Hi")[volume=-5]</chain>',  # (not acted on)
    '<chain>QA("Ready?", yn, timeout=0), SetSpeedAndTime(0.2, 0), TrackingHuman(0.1)</chain>',
    '<request><qa prompt="Ready?" grammar="yn" timeout="0"/>'
    '<command name="Sway"><arg name="degrees" value="90"/></command></request>',
    '<chain>QA("Ready?", yn, timeout=n), QA("Ready?", yn, timeout={n - 3})</chain>',
    '<chain>QA("Ready?", yn, timeout=0 - 3), Sway(time=n)</chain>',  # (not folded: an operation)
    '<timer name="t" after="{n}"/><timer name="t" after="{-1}"/><timer name="t" after="-1"/>',
])
def test_a_value_within_its_range_or_not_known_before_the_run_is_no_error(entry: str) -> None:
    """A value computed from a variable is checked when the Command is performed; a
    timer's negative time is no error (it fires at once)."""
    assert _check(entry) == []


@pytest.mark.parametrize("entry, fragment", [
    ('<request><command name="QA"><arg name="prompt" value="x"/><arg name="grammar" value="yn"/>'
     '<arg name="timeout" value="-1"/></command></request>', "4:118: QA: timeout must not"),
    ('<request><qa prompt="x" grammar="yn" timeout="-0.5"/></request>', "4:47: QA: timeout"),
    ('<chain>QA("x", yn, timeout={-2})</chain>', "4:29: QA: timeout must not be negative, not -2"),
    ('<chain>QA("x", yn, n, -1)</chain>', "4:23: QA: timeout must not be negative, not -1"),
    ('<timer name="t" after="{true}"/>', "4:24: attribute after={true}: expected a number"),
])
def test_each_way_of_writing_a_constant_is_checked_where_it_is_written(
        entry: str, fragment: str) -> None:
    [error] = _errors(entry)
    assert error.startswith(fragment), error


def test_a_profile_default_a_step_would_refuse_is_a_profile_error() -> None:
    """A call that leaves the argument out would fail with its default."""
    steps = '<hold seconds="{time}"/>'
    [(source, line, _col, message)] = _problems(
        LASER.format(steps=steps).replace('name="time" kind="number" default="2"',
                                          'name="time" kind="number" default="-1"'))
    assert source == steps and line == 16
    assert message == ("'{time}' defaults to -1: Light called without it would fail "
                       "(a hold lasts 0 to 3600 s, not -1)")


def test_a_range_says_its_refusal_with_the_value() -> None:
    timeout = Range("timeout must not be negative", 0.0)
    assert timeout.refusal(0) is None and timeout.refusal(8.5) is None
    assert timeout.refusal(-3) == "timeout must not be negative, not -3"
    distance = Range("distance must be positive", 0.0, above=True)
    assert distance.refusal(0) == "distance must be positive, not 0"
    hold = Range("a hold lasts 0 to 3600 s", 0.0, 3600.0)
    assert hold.refusal(3600) is None and hold.refusal(3600.5) is not None
    assert hold.refusal(float("nan")) is not None

