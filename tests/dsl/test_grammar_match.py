"""Answer grammars: choices with synonyms and patterns."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from prima.dsl import (
    Choice,
    Grammar,
    Loc,
    Pattern,
    check_document,
    load_document,
    match_pattern,
    words,
)
from tests.work import growth

DOC = b"""<pxml xmlns="urn:prima:pxml:1" kind="fa" name="g">
  <grammar id="rooms">
    <choice value="kidode_room">Prof. Kidode's room | Kidode</choice>
    <choice>hall | the hall</choice>
  </grammar>
  <grammar id="reply"><choice value="no">no | nothing</choice><pattern>yes *</pattern></grammar>
  <grammar id="hour"><pattern>#</pattern><pattern>at # o'clock</pattern></grammar>
  <state id="s" initial="true"/>
</pxml>"""


@pytest.fixture(scope="module")
def grammars(tmp_path_factory: pytest.TempPathFactory) -> Mapping[str, Grammar]:
    path: Path = tmp_path_factory.mktemp("g") / "g.pxml"
    path.write_bytes(DOC)
    return load_document(path).grammars


@pytest.mark.parametrize("grammar, heard, value", [
    ("rooms", "Prof. Kidode's room.", "kidode_room"),
    ("rooms", "I'm going to KIDODE, please", "kidode_room"),
    ("rooms", "The hall", "hall"),
    ("rooms", "the kitchen", None),
    ("rooms", "Kidodes", None),
    ("reply", "No.", "no"),
    ("reply", "Yes. I see. I'll wait in your room.", "i see ill wait in your room"),
    ("rooms", "Kidode's office", "kidode_room"),
    ("reply", "yes", "yes"),
    ("reply", "maybe", None),
    ("hour", "18", "18"),
    ("hour", "at 7 o'clock", "7"),
    ("hour", "at 7 oclock", "7"),
    ("hour", "eighteen", None),
])
def test_match(grammars: Mapping[str, Grammar], grammar: str, heard: str,
               value: str | None) -> None:
    assert grammars[grammar].match(heard) == value


# ---------------------------------------------------------------- patterns, word by word

def _reference(items: tuple[str, ...], heard: list[str]) -> list[str] | None:
    """Every way to split ``heard``, the first in lazy order (fewest words to the first
    ``*``, then the next): exponential, for checking small cases only."""
    def go(i: int, j: int) -> list[str] | None:
        if i == len(items):
            return [] if j == len(heard) else None
        item = items[i]
        if item == "*":
            for k in range(j, len(heard) + 1):
                rest = go(i + 1, k)
                if rest is not None:
                    return [" ".join(heard[j:k]), *rest]
            return None
        if j == len(heard):
            return None
        if item == "#":
            rest = go(i + 1, j + 1) if heard[j].isdigit() else None
            return None if rest is None else [heard[j], *rest]
        return go(i + 1, j + 1) if heard[j] == item else None
    return go(0, 0)


@given(st.lists(st.sampled_from(["*", "#", "a", "b"]), min_size=1, max_size=6),
       st.lists(st.sampled_from(["a", "b", "7", "12"]), max_size=8))
def test_the_matcher_agrees_with_trying_every_split(items: list[str], heard: list[str]) -> None:
    assert match_pattern(tuple(items), heard) == _reference(tuple(items), heard)


@pytest.mark.parametrize("items, heard, captured", [
    (("*", "and", "*"), "a and b and c", ["a", "b and c"]),  # '*' is lazy
    (("#", "#"), "3 4", ["3", "4"]),
    (("#",), "3.5", None),          # words: 3, 5
    (("*",), "", [""]),             # '*' may take no word
    (("yes", "*"), "yes", [""]),
])
def test_pattern_semantics(items: tuple[str, ...], heard: str,
                           captured: list[str] | None) -> None:
    assert match_pattern(items, words(heard)) == captured


def test_a_hostile_pattern_against_a_long_answer_is_linear() -> None:
    # The regex this replaces, (.*?) four times, backtracked for minutes here.
    items = ("*", "a", "*", "b", "*", "c", "*", "d")
    grammar = Grammar("g", (), (Pattern("* a * b * c * d", items),), Loc(1, 1))

    def hostile(n: int) -> None:
        answer = ["word"] * n
        assert match_pattern(items, answer) is None
        assert match_pattern(("*", "*", "*", "*", "word"), answer) == [
            "", "", "", " ".join(answer[1:])]
        assert grammar.match("word " * n) is None
    assert growth(hostile, 125, 500) < 1.2


def test_many_long_synonyms_are_looked_up_not_scanned() -> None:
    phrases = tuple(tuple(f"w{i} x{j}".split()) for i in range(200) for j in range(5))
    grammar = Grammar("g", (Choice("v", phrases),), (), Loc(1, 1))

    def match(n: int) -> None:
        assert grammar.match("say " * n + "w199 x4") == "v"
    # 1,000 lookups whatever the utterance (0.11 here); a scan of the utterance for each
    # synonym grows with it (0.76)
    assert growth(match, 10, 100) < 0.3


@pytest.mark.parametrize("body, fragment", [
    ("<pattern>a b c d e f g h i j k l m n o p q r s t u</pattern>", "1 to 20 words"),
    ("<choice>" + " ".join(["w"] * 21) + "</choice>", "at most 20 words"),
    ("<pattern>x</pattern>" * 51, "at most 50 patterns"),
])
def test_grammar_limits(body: str, fragment: str) -> None:
    source = DOC.replace(b'<grammar id="hour">', f'<grammar id="big">{body}</grammar>'
                         '<grammar id="hour">'.encode())
    _document, problems = check_document(source, "g.pxml")
    assert [fragment in p.message for p in problems] == [True]
