"""The prebuilt LALR tables (prima/dsl/_tables.py) are those of pxml.lark.

If a test here fails after an edit of ``pxml.lark``, rebuild the tables:
``python -m prima.dsl._build_tables``.
"""

from __future__ import annotations

import re
from importlib import resources
from pathlib import Path

import pytest
from lark import Lark
from lark.exceptions import UnexpectedInput

from prima.dsl import build_parser, parser, prebuilt_parser

REBUILD = "pxml.lark changed: rebuild the tables with python -m prima.dsl._build_tables"
ROOT = Path(__file__).resolve().parents[2]

_TEXTS = re.compile(r"""<chain[^>]*>(?P<chain>[^<]*)</chain>|\b(?:cond|expr)="(?P<expr>[^"]*)\"""")


def _samples() -> list[tuple[str, str]]:
    """Every chain and expression of the shipped applications and the test documents."""
    found = []
    for path in sorted([*ROOT.glob("apps/**/*.pxml"), *ROOT.glob("tests/dsl/data/**/*.pxml")]):
        for m in _TEXTS.finditer(path.read_text(encoding="utf-8")):
            text = m.group("chain") or m.group("expr") or ""
            text = text.replace("&lt;", "<").replace("&gt;", ">").replace("&amp;", "&")
            found.append((text, "chain" if m.group("chain") else "expression"))
    return found


SAMPLES = _samples()
FAULTS = ["count = 3", "a && b", "f(", "Speak('a') Speak('b')", "x ! y", "'open", "1 +", ""]


GRAMMAR = resources.files("prima.dsl").joinpath("pxml.lark").read_text(encoding="utf-8")


def test_the_tables_were_built_from_this_grammar_by_this_lark() -> None:
    assert prebuilt_parser() is not None, REBUILD


def test_the_parser_is_the_prebuilt_one() -> None:
    assert parser().source_path == "<deserialized>"  # lark's mark of loaded tables


def test_another_grammar_is_built_from_its_text() -> None:
    assert prebuilt_parser(GRAMMAR) is not None
    assert prebuilt_parser(GRAMMAR + "\n// edited\n") is None
    assert build_parser(GRAMMAR + "\n// edited\n").source_path != "<deserialized>"


@pytest.fixture(scope="module")
def built() -> Lark:
    return build_parser()


def test_there_are_samples_of_both_kinds() -> None:
    assert len(SAMPLES) > 100
    assert {start for _text, start in SAMPLES} == {"chain", "expression"}


def _outcome(one: Lark, text: str, start: str) -> object:
    """The tree, or the fault: its kind, where, and what was expected there."""
    try:
        return one.parse(text, start=start)
    except UnexpectedInput as fault:
        return (type(fault), fault.pos_in_stream, sorted(getattr(fault, "expected", ()) or ()))


def test_prebuilt_and_built_parsers_give_the_same_trees(built: Lark) -> None:
    loaded = prebuilt_parser()
    assert loaded is not None
    for text, start in SAMPLES:
        assert _outcome(loaded, text, start) == _outcome(built, text, start), text


@pytest.mark.parametrize("text", FAULTS)
@pytest.mark.parametrize("start", ["expression", "chain"])
def test_prebuilt_and_built_parsers_fail_alike(built: Lark, text: str, start: str) -> None:
    loaded = prebuilt_parser()
    assert loaded is not None
    fault = _outcome(loaded, text, start)
    assert isinstance(fault, tuple)
    assert fault == _outcome(built, text, start)
