"""A fault inside an expression carries its source line, so a caret can point at it."""

from __future__ import annotations

import pytest

from prima.dsl import check_document
from prima.errors import Severity

DOC = """<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">
{line}
  <state id="s" initial="true"/>
</pxml>"""


@pytest.mark.parametrize("line, at, fragment", [
    ('  <var name="x" expr="1 +"/>', '"/>', "ends too early"),
    ('\t<var name="x" expr="x = 1"/>', "= 1", "write '==' to compare"),
    ('\t \t<var name="x" expr="\'&lt;{x +}\'"/>', "}'", "ends too early"),
    ('\t<state id="t"><entry><chain>Speak("x") Speak("y")</chain></entry></state>',
     'Speak("y")', "missing ','"),
    ('\t<state id="t"><entry><log text="x }"/></entry></state>', "}", "'}' without '{'"),
])
def test_expression_fault_carries_its_line_and_a_caret_under_the_fault(
        line: str, at: str, fragment: str) -> None:
    _, problems = check_document(DOC.format(line=line).encode(), "t.pxml")
    [problem] = [p for p in problems if p.severity is Severity.ERROR]
    assert fragment in problem.message
    assert (problem.line, problem.source) == (2, line)
    col = line.index(at) + 1
    assert problem.col == col
    source, caret = problem.caret().split("\n")
    assert source == "    " + line
    assert caret == "    " + "".join(c if c == "\t" else " " for c in line[: col - 1]) + "^"
    assert len(caret) == len("    " + line[:col])


def test_other_problems_carry_no_source_line() -> None:
    line = '  <var name="x"/><var name="x"/>'
    _, problems = check_document(DOC.format(line=line).encode(), "t.pxml")
    [problem] = problems
    assert "declared twice" in problem.message
    assert problem.source == "" and problem.caret() == ""
