"""Short texts are compiled once per process, and every use is still located where it is."""

from __future__ import annotations

from prima.dsl import Scope, check_document, compile_expression, compile_template, parse_chain

SCOPE = Scope({"count": 2, "name": "Ann"})


def test_the_same_short_text_gives_the_same_compiled_expression() -> None:
    first = compile_expression("count + 1 == 3")
    again = compile_expression("count + 1 == 3")
    assert again is first
    assert again.evaluate(SCOPE) is True


def test_a_long_text_is_compiled_afresh_and_alike() -> None:
    text = "'" + "x" * 2_000 + "' == name"
    first, again = compile_expression(text), compile_expression(text)
    assert again is not first
    assert again == first and again.evaluate(SCOPE) is False


def test_each_setting_has_its_own_compiled_form() -> None:
    assert compile_template("Hi {name}", max_text=10) is not compile_template("Hi {name}")
    assert compile_template("Hi {name}", max_text=10).evaluate(SCOPE) == "Hi Ann"


def test_a_memoised_chain_is_a_new_list_each_time() -> None:
    first = parse_chain('Speak("Hello."), Turn(90)')
    again = parse_chain('Speak("Hello."), Turn(90)')
    assert again == first and again is not first
    again.pop()
    assert len(parse_chain('Speak("Hello."), Turn(90)')) == 2


DOC = """<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">
  <var name="count" expr="0"/>
  <state id="s" initial="true">
    <on event="human-found" cond="count > 1 and missing == 2"><goto state="s"/></on>
    <on event="human-lost" cond="count = 3"><goto state="s"/></on>
    <on event="touched"><chain>Speak("Hi."), Fly()</chain></on>
  </state>
  <state id="t">
      <on event="human-found"    cond="count > 1 and missing == 2"><goto state="s"/></on>
      <on event="human-lost"     cond="count = 3"><goto state="s"/></on>
      <on event="touched"><chain>Speak("Hi."), Fly()</chain></on>
  </state>
</pxml>"""


def _at(line: int, written: str) -> tuple[int, int]:
    """Line and column of ``written`` on a line of DOC."""
    return line, DOC.splitlines()[line - 1].index(written) + 1


def test_every_use_of_a_text_is_located_where_it_is_written() -> None:
    expected = [
        (*_at(4, "missing"), "undefined variable 'missing'"),
        (*_at(5, "= 3"), "expression: '=' assigns"),
        (*_at(6, "Fly"), "unknown Command 'Fly'"),
        (*_at(9, "missing"), "undefined variable 'missing'"),
        (*_at(10, "= 3"), "expression: '=' assigns"),
        (*_at(11, "Fly"), "unknown Command 'Fly'"),
    ]
    assert len({(line, col) for line, col, _ in expected}) == 6
    for _ in range(2):  # the second time, every text is already memoised
        _, problems = check_document(DOC.encode(), "t.pxml")
        found = [(p.line, p.col, p.message.split(";")[0].split(" (")[0]) for p in problems
                 if p.severity.value == "error"]
        assert found == expected
