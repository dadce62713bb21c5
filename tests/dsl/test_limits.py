"""Documents at and past their bounds: located errors, quickly, never a RecursionError."""

from __future__ import annotations

from collections.abc import Callable
from importlib import resources

import pytest

from prima.dsl import RobotProfile, check_document, parse_profile
from prima.errors import Problem
from prima.vocab import MAX_TEXT, AppKind
from tests.work import growth

HEAD = '<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">\n'
ENTRY = '<state id="s" initial="true"><entry>'


def _check(body: str, profile: RobotProfile | None = None) -> list[Problem]:
    return check_document(f"{HEAD}{body}</pxml>".encode(), "t.pxml", profile)[1]


def _small_text_budget() -> RobotProfile:
    """The shipped profile, with a text budget of 20 characters."""
    xml = resources.files("prima.robots").joinpath("home-robot.xml").read_text()
    xml = xml.replace("  </devices>\n", '  </devices>\n  <budgets text="20"/>\n', 1)
    return parse_profile(xml.encode(), "small.xml")


def test_a_literal_text_longer_than_the_limit_is_located_at_the_first_extra_character() -> None:
    [problem] = _check(f'{ENTRY}<log text="{"a" * (MAX_TEXT + 5)}"/></entry></state>')
    assert (problem.line, problem.col) == (2, len(ENTRY) + len('<log text="') + MAX_TEXT + 1)
    assert problem.message == "text: longer than 10,000 characters"
    assert _check(f'{ENTRY}<log text="{"a" * MAX_TEXT}"/></entry></state>') == []


def test_the_robot_profile_budget_bounds_literal_texts() -> None:
    profile = _small_text_budget()
    assert profile.budgets[AppKind.FA].text == profile.budgets[AppKind.EA].text == 20
    body = (f'{ENTRY}<request><speak text="{"b" * 21}"/></request>\n'
            f'<chain>Speak("{"c" * 20}"), Speak("{"d" * 21}")</chain></entry></state>')
    problems = _check(body, profile)
    assert [(p.line, p.col, p.message) for p in problems] == [
        (2, len(ENTRY) + len('<request><speak text="') + 21, "text: longer than 20 characters"),
        (3, len('<chain>Speak("') + 20 + len('"), Speak("') + 21,
         "text: longer than 20 characters"),
    ]
    assert _check(body) == []  # the default budget is 10,000


@pytest.mark.parametrize("shape, size, col, message", [
    (lambda n: "(" * n + "1" + ")" * n, 300_000, 10_001,
     "expression: longer than 10,000 characters"),
    (lambda n: "-" * n + "1", 9_000, 51, "expression: nested more than 50 levels deep"),
    (lambda n: "+".join(["x"] * n), 4_000, 102, "expression: nested more than 50 levels deep"),
])
def test_a_deep_expression_is_a_located_error_in_linear_work(
        shape: Callable[[int], str], size: int, col: int, message: str) -> None:
    def check(n: int) -> list[Problem]:
        return _check(f'<var name="x" expr="{shape(n)}"/><state id="s" initial="true"/>')
    [problem] = check(size)
    assert (problem.line, problem.col) == (2, len('<var name="x" expr="') + col)
    assert problem.message.startswith(message)
    assert growth(check, size // 4, size) < 1.2


def test_many_undefined_names_among_many_variables_stay_linear() -> None:
    def check(n: int) -> list[Problem]:
        variables = "".join(f'<var name="v{i}"/>' for i in range(n))
        uses = "".join(f'<log text="{{w{i}}}"/>' for i in range(n))
        return _check(f"{variables}{ENTRY}{uses}</entry></state>")
    problems = check(5_000)
    assert growth(check, 1_250, 5_000) < 1.2
    assert len(problems) == 51
    assert problems[0].message == "undefined variable 'w0'; did you mean 'v0'?"
    assert problems[-1].message.startswith("... and 4,950 more problems")


def test_many_unknown_events_among_many_events_stay_linear() -> None:
    def check(n: int) -> list[Problem]:
        events = "".join(f'<event name="e{i}"/>' for i in range(n))
        handlers = "".join(f'<on event="x{i}"/>' for i in range(n))
        return _check(f'{events}<state id="s" initial="true">{handlers}</state>')
    problems = check(3_000)
    assert growth(check, 750, 3_000) < 1.2
    assert len(problems) == 51 and "unknown event 'x0'" in problems[0].message
