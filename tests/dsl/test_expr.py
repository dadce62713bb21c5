"""Expressions: values, operators, templates, functions and located syntax faults."""

from __future__ import annotations

import math
import operator
import re
from collections.abc import Callable

import pytest
from hypothesis import given
from hypothesis import strategies as st

from prima.dsl import (
    Scope,
    compile_expression,
    compile_template,
    parse_chain,
    parser,
    to_text,
)
from prima.errors import ExecutionError, ExpressionError
from prima.vocab import MAX_NUMBER, MAX_TEXT
from tests.work import bytecodes, growth

SCOPE = Scope({"a": 2, "name": "Ann", "ch": 12, "nothing": None},
              {"name": "message", "text": "hi", "sender": "kidode"})


@pytest.mark.parametrize("source, value", [
    ("1 + 2 * 3", 7),
    ("(1 + 2) * 3", 9),
    ("7 / 2", 3.5),
    ("6 / 3", 2),
    ("7 % 3", 1),
    ("a - 1", 1),
    ("-a", -2),
    ("1 - -2", 3),
    ("a * 3 + 1 == 7", True),
    ("1 == 1.0", True),
    ("'1' == 1", False),
    ("a != 2", False),
    ("'abc' < 'abd'", True),
    ("not a > 1 or false", False),
    ("true and null", False),
    ("nothing == null", True),
    ('"Hello {name}!"', "Hello Ann!"),
    ("'{{literal}}'", "{literal}"),
    ('"Channel " + ch', "Channel 12"),
    ('"say \\"hi\\""', 'say "hi"'),
    ("event", "message"),
    ("event.text + ' from ' + event.sender", "hi from kidode"),
    ("event.missing", None),
    ("len(name)", 3),
    ("number('18') + 1", 19),
    ("number('eighteen')", None),
    ("upper(name) + lower('X')", "ANNx"),
    ("contains('The C Primer', 'c primer')", True),
    ("startswith(trim('  yes please'), 'YES')", True),
    ("min(3, a, 5) + max(1, 4)", 6),
    ("round(2.6) + abs(-1)", 4),
    ("str(1.0) + str(true) + str(null)", "1true"),
])
def test_values(source: str, value: object) -> None:
    result = compile_expression(source).evaluate(SCOPE)
    assert result == value and type(result) is type(value)


def test_compiled_records_variables_and_event_uses_with_positions() -> None:
    c = compile_expression("a + len(name) > 0 and event.text == '{ch}'")
    assert c.names == {("a", 0), ("name", 8), ("ch", 38)}
    assert c.event_uses == (22,)


def test_constants_are_folded() -> None:
    assert compile_expression("'hi'").constant
    assert not compile_expression("a").constant


@pytest.mark.parametrize("source, index, fragment", [
    ("a = 1", 2, "write '==' to compare"),
    ("a +", 3, "ends too early"),
    ("(a", 2, "expected ')'"),
    ("a && b", 2, "write 'and'"),
    ("a || b", 2, "write 'or'"),
    ("!a", 0, "write 'not'"),
    ("1 2", 2, "after a complete value"),
    ("foo(1)", 0, "unknown function 'foo'"),
    ("len(1, 2)", 0, "len() takes 1 argument(s), got 2"),
    ("now(1)", 0, "now() takes no argument, got 1"),
    ("nowt()", 0, "(known: abs, contains, len, lower, max, min, now, number,"),
    ("'abc", 0, "string is not closed"),
    ("x.y", 0, "only 'event' has fields"),
    ("'{a +}'", 5, "ends too early"),
    ("'a {'", 3, "'{' is not closed"),
    ("'a }'", 3, "'}' without '{'"),
    ("", 0, "empty"),
])
def test_syntax_faults_point_at_the_fault(source: str, index: int, fragment: str) -> None:
    with pytest.raises(ExpressionError) as info:
        compile_expression(source)
    assert info.value.index == index
    assert fragment in info.value.message


@pytest.mark.parametrize("source, fragment", [
    ("'a' - 1", "'-' needs a number"),
    ("1 / 0", "by zero"),
    ("'a' < 1", "cannot order"),
    ("round('x')", "round() needs a number"),
])
def test_runtime_errors_are_execution_errors(source: str, fragment: str) -> None:
    compiled = compile_expression(source)
    with pytest.raises(ExecutionError, match=re.escape(fragment)):
        compiled.evaluate(SCOPE)


def test_text_cannot_grow_without_bound() -> None:
    big = Scope({"s": "x" * MAX_TEXT})
    with pytest.raises(ExecutionError, match="longer than"):
        compile_expression("s + s").evaluate(big)


def test_template_positions() -> None:
    t = compile_template("Hi {name}")
    assert t.names == {("name", 4)}
    with pytest.raises(ExpressionError) as info:
        compile_template("Hi {na me}")
    assert info.value.index == 7


def test_chain_steps_labels_and_extras() -> None:
    steps = parse_chain('Speak("Come on, let\'s go."), '
                        'nav: TopologicalMove(kidode_room)[speed=0.3]')
    assert [(s.label, s.command) for s in steps] == [(None, "Speak"), ("nav", "TopologicalMove")]
    assert steps[1].index == 34 and steps[1].label_index == 29
    [extra] = steps[1].extras
    assert (extra.name, extra.name_index, extra.index) == ("speed", 63, 69)


@pytest.mark.parametrize("source, index, fragment", [
    ('Speak("x") Speak("y")', 11, "missing ','"),
    ("Speak(", 6, "ends too early"),
    ("", 0, "empty"),
])
def test_chain_syntax_faults(source: str, index: int, fragment: str) -> None:
    with pytest.raises(ExpressionError) as info:
        parse_chain(source)
    assert info.value.index == index and fragment in info.value.message


def test_parser_is_lalr_and_built_once() -> None:
    assert parser() is parser()
    assert parser().options.parser == "lalr"


@pytest.mark.parametrize("source", ["99999999 * 99999999 * 99999999", "number('1e300') * 2",
                                    "round(9007199254740993.0 * 2)"])
def test_numbers_stay_bounded(source: str) -> None:
    with pytest.raises(ExecutionError, match="too large|needs a number"):
        compile_expression(source).evaluate(SCOPE)


def test_overlong_number_literal_is_a_syntax_fault() -> None:
    with pytest.raises(ExpressionError, match="number too long"):
        compile_expression("1" * 30)


def test_an_expression_error_on_its_own_is_located_in_its_text() -> None:
    with pytest.raises(ExpressionError) as info:
        compile_expression("a and\n  b = 1")
    fault = info.value
    assert (fault.index, fault.text) == (10, "a and\n  b = 1")
    [problem] = fault.problems
    assert (problem.file, problem.line, problem.col) == ("<expression>", 2, 5)
    assert problem.source == "  b = 1" and problem.message == fault.message
    assert problem.caret() == "      b = 1\n        ^"


def test_a_fault_in_a_string_inside_an_expression_points_into_the_string() -> None:
    with pytest.raises(ExpressionError) as info:
        compile_expression(r"'say \"{a +}\"'")
    assert info.value.index == 11 and "ends too early" in info.value.message


@pytest.mark.parametrize("source, index, fragment", [
    ("-'a'", 1, "'-' needs a number, got text 'a'"),
    ("not -null", 0, "'-' needs a number, got null"),
    # a constant operand of an expression that is not constant, even where it would
    # not be reached
    ("1 + -true", 4, "'-' needs a number, got a boolean"),
    ("x == (-'a')", 7, "'-' needs a number, got text 'a'"),
    ("max(x, -null)", 7, "'-' needs a number, got null"),
    ("x and -true", 6, "'-' needs a number, got a boolean"),
    ("false and -true", 10, "'-' needs a number, got a boolean"),
])
def test_a_constant_that_cannot_be_computed_is_a_fault(source: str, index: int,
                                                       fragment: str) -> None:
    with pytest.raises(ExpressionError) as info:
        compile_expression(source)
    assert info.value.index == index and fragment in info.value.message


# ---------------------------------------------------------------- bounds

DEEP = "expression: nested more than 50 levels deep"


@pytest.mark.parametrize("source, index", [
    ("-" * 100 + "1", 50),                         # the 51st unary minus
    ("not " * 60 + "x", 200),                      # the 51st 'not'
    ("(" * 100 + "1" + ")" * 100, 50),             # the 51st bracket
    ("+".join(["1"] * 60), 101),                   # the 51st '+' of a chain of sums
    ("min(" * 60 + "1" + ", 2)" * 60, 200),        # the 51st call
    ("(" * 30 + "a or " * 25 + "b" + ")" * 30, 132),  # brackets and operators add up
])
def test_nesting_is_bounded_at_the_character_that_crosses_it(source: str, index: int) -> None:
    with pytest.raises(ExpressionError) as info:
        compile_expression(source)
    assert info.value.index == index
    assert info.value.message.startswith(DEEP)


@pytest.mark.parametrize("source", [
    " or ".join(f"x == {i}" for i in range(25)),   # 25 alternatives: 25 levels
    "+".join(["1"] * 50),
    "-" * 49 + "1",
    "a * b + c * d - e / f % g < 3 and not (x or y)",
])
def test_ordinary_expressions_stay_within_the_bound(source: str) -> None:
    compile_expression(source)


def test_a_string_template_counts_as_a_level() -> None:
    # 45 '-' outside the string, then the string and its template: the fourth '-' inside
    # the template is the 51st level
    inner = '"{' + "-" * 5 + '1}"'
    with pytest.raises(ExpressionError) as info:
        compile_expression("-" * 45 + inner)
    assert info.value.message.startswith(DEEP)
    assert info.value.index == 45 + 2 + 3
    compile_expression("-" * 40 + inner)


@pytest.mark.parametrize("shape", [lambda n: "(" * n + "1" + ")" * n,
                                   lambda n: "-" * n + "1",
                                   lambda n: "+".join(["1"] * n)])
def test_a_huge_expression_is_refused_at_its_length(shape: Callable[[int], str]) -> None:
    def refuse(size: int) -> None:
        with pytest.raises(ExpressionError) as info:
            compile_expression(shape(size))
        assert (info.value.index, info.value.message) == (
            10_000, "expression: longer than 10,000 characters")
    # what comes after the 10,000th character is never looked at
    assert bytecodes(lambda: refuse(300_000)) == bytecodes(lambda: refuse(10_001))


def test_a_deep_expression_within_the_length_is_refused_in_linear_work() -> None:
    def refuse(depth: int) -> None:
        with pytest.raises(ExpressionError, match="nested more than"):
            compile_expression("(" * depth + "1" + ")" * depth)
    assert growth(refuse, 1_000, 4_999) < 1.2


@given(st.text(alphabet="()[]{}-+*/%<=!,:'\"\\ ab1notrd.", max_size=300))
def test_no_input_exhausts_the_compiler(source: str) -> None:
    for compile_ in (compile_expression, compile_template, parse_chain):
        try:
            compile_(source)
        except ExpressionError:
            pass
        except ExecutionError:  # a constant's fault is reported as an ExpressionError
            raise


def test_a_chain_holds_at_most_100_commands() -> None:
    parse_chain(", ".join(["StopMoving()"] * 100))
    source = ", ".join(["StopMoving()"] * 101)
    with pytest.raises(ExpressionError) as info:
        parse_chain(source)
    assert info.value.index == 100 * len("StopMoving(), ")
    assert info.value.message == "chain: more than 100 Commands in one chain"


def test_a_chain_is_at_most_100_000_characters() -> None:
    with pytest.raises(ExpressionError) as info:
        parse_chain('Speak("' + "a" * 100_000 + '")')
    assert (info.value.index, info.value.message) == (100_000,
                                                      "chain: longer than 100,000 characters")


def test_number_literals_are_bounded() -> None:
    compile_expression("9007199254740992")
    with pytest.raises(ExpressionError, match="number too large"):
        compile_expression("9007199254740993")


@pytest.mark.parametrize("fits, source, max_text, index", [
    ("a" * MAX_TEXT, "a" * (MAX_TEXT + 1), MAX_TEXT, MAX_TEXT),
    ("abc{x}de", "abc{x}def", 5, 8),   # literal parts add up; the sixth is 'f'
    ("{{" * 5, "{{" * 6, 5, 10),       # an escaped brace is one character
])
def test_literal_text_is_bounded(fits: str, source: str, max_text: int, index: int) -> None:
    compile_template(fits, max_text=max_text)
    with pytest.raises(ExpressionError) as info:
        compile_template(source, max_text=max_text)
    assert info.value.index == index
    assert info.value.message == f"text: longer than {max_text:,} characters"


def test_a_string_literal_is_bounded_by_the_budget() -> None:
    compile_expression("'abcde'", max_text=5)
    with pytest.raises(ExpressionError, match="text: longer than 5 characters"):
        compile_expression("'abcdef'", max_text=5)


def test_now_is_the_scopes_time_and_never_a_constant() -> None:
    compiled = compile_expression("now() + 5")
    assert not compiled.constant
    assert compiled.evaluate(Scope({}, None, 12.5)) == 17.5
    assert compile_template("at {now()} s").evaluate(Scope({}, None, 3.0)) == "at 3 s"



_OPERANDS = st.one_of(st.integers(-10**16, 10**16), st.floats(allow_nan=True, allow_infinity=True),
                      st.booleans(), st.none(), st.text(max_size=3))
_ORDERS = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}
_ARITH = {"+": operator.add, "-": operator.sub, "*": operator.mul}


def _as_the_reference_says(op: str, a: object, b: object) -> object:
    """What docs/pxml.md says ``a op b`` is: a value, or "error"."""
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (a, b))
    if op in _ORDERS:
        both_text = isinstance(a, str) and isinstance(b, str)
        return _ORDERS[op](a, b) if numbers or both_text else "error"
    if op == "+" and (isinstance(a, str) or isinstance(b, str)):
        return to_text(a) + to_text(b)  # type: ignore[arg-type]
    if not numbers:
        return "error"
    value = _ARITH[op](a, b)
    return value if math.isfinite(value) and abs(value) <= MAX_NUMBER else "error"


@given(_OPERANDS, _OPERANDS, st.sampled_from([*_ARITH, *_ORDERS]))
def test_arithmetic_and_ordering_of_any_two_values(a: object, b: object, op: str) -> None:
    """`+ - *` and the orderings take a short cut for two plain numbers: the values and
    the errors (out of range, not a number, not ordered) stay those of the reference."""
    scope = Scope({"a": a, "b": b})  # type: ignore[dict-item]
    try:
        value: object = compile_expression(f"a {op} b").evaluate(scope)
    except ExecutionError:
        value = "error"
    expected = _as_the_reference_says(op, a, b)
    assert value == expected or value != value and expected != expected  # noqa: PLR0124 - nan


@pytest.mark.parametrize("text", [
    "x == true", "true == x", "(true) == x", "x == (true)", "(x) == y", "-(x)", "not x and -y",
    "not (- x) == 1", "x + - - y", 'x == "a("', "((x + 1)) * 2", "null", "not true",
    "not  ( null )", "not (not false)", "x + -(y)", "x == (not null)", "-x - -(-(y))",
])
def test_a_compiled_expression_keeps_its_whole_source(text: str) -> None:
    # keyword values, prefix operators and parentheses leave no token in the tree
    assert compile_expression(f" {text} ").source == text



def test_a_chain_argument_of_words_only_is_placed_where_it_is_written() -> None:
    chain = 'Speak(text="hi"), Turn(angle=-true), Move(a=not null, b=false)'
    args = [a for step in parse_chain(chain) for a in step.args]
    assert [a.index for a in args] == [11, 29, 44, 56]
    with pytest.raises(ExpressionError) as fault:  # a constant fault, at its '-'
        compile_expression("  -true")
    assert fault.value.index == 2
