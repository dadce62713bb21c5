"""The hand-written parser builds lark's very trees, or leaves the text to lark.

``prima.dsl._fastparse`` parses valid expressions and chains without lark; a
syntax fault, or any text it does not accept, goes to lark. So for every text
either it declines, or lark parses the text too, into the same tree: the same
rule names, children and ``None`` placeholders, and tokens of the same type,
value and position (compared one by one here, PRIMA's ``ParseTree`` and
``ParseToken`` against lark's own ``Tree`` and ``Token``).
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from lark import Token, Tree
from lark.exceptions import UnexpectedInput

import prima.dsl
from prima.dsl import ParseToken, ParseTree, collect, fast_parse, parser, validate_paths
from prima.errors import ExpressionError

fast_parse_sized = prima.dsl._fastparse.parse_sized  # type: ignore[attr-defined]  # private
measure = prima.dsl._expr.measure  # type: ignore[attr-defined]  # private
MAX_NESTING = prima.dsl._expr.MAX_NESTING  # type: ignore[attr-defined]  # private

ROOT = Path(__file__).resolve().parents[2]
_POSITIONS = ("start_pos", "line", "column", "end_line", "end_column", "end_pos")


def _differences(fast: object, slow: object, where: str = "") -> Iterator[str]:
    if isinstance(slow, Token):
        if type(fast) is not ParseToken:
            yield f"{where}: {fast!r} is not the token {slow!r}"
            return
        for attr in ("type", "value", *_POSITIONS):
            if getattr(fast, attr) != getattr(slow, attr) or str(fast) != str(slow):
                yield f"{where}: {attr} {getattr(fast, attr)!r} != {getattr(slow, attr)!r}"
    elif isinstance(slow, Tree):
        if type(fast) is not ParseTree:
            yield f"{where}: {fast!r} is not the tree {slow!r}"
            return
        if type(fast.data) is not type(slow.data) or fast.data != slow.data:
            yield f"{where}: rule {fast.data!r} != {slow.data!r}"
        if len(fast.children) != len(slow.children):
            yield f"{where}/{slow.data}: {len(fast.children)} != {len(slow.children)} children"
        for i, (f, s) in enumerate(zip(fast.children, slow.children, strict=False)):
            yield from _differences(f, s, f"{where}/{slow.data}[{i}]")
    elif fast is not slow:  # None placeholders
        yield f"{where}: {fast!r} != {slow!r}"


def _lark(text: str, start: str) -> Tree[Token] | None:
    try:
        return parser().parse(text, start=start)
    except UnexpectedInput:
        return None


def check(text: str, start: str) -> bool:
    """Assert the two parsers agree on ``text``; whether the fast one accepted it. And
    that the measure skipped for a text of few tokens would not have refused it."""
    fast, tokens = fast_parse_sized(text, start)
    assert (fast is None) == (fast_parse(text, start) is None)
    if fast is None:
        return False
    if tokens <= MAX_NESTING:
        measure(text, start, MAX_NESTING - tokens)  # raises if the skip were unsound
    slow = _lark(text, start)
    assert slow is not None, f"only the fast parser accepts {start} {text!r}"
    problems = list(_differences(fast, slow))
    assert not problems, f"{start} {text!r}:\n" + "\n".join(problems)
    return True


# ---------------------------------------------------------------- every text of the documents

def _corpus(folder: Path) -> None:
    bench = str(ROOT / "bench")
    sys.path.insert(0, bench)
    try:
        spec = importlib.util.spec_from_file_location("_bench_validate",
                                                      ROOT / "bench" / "validate.py")
        assert spec and spec.loader
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        module.make_corpus(folder, 13)
    finally:
        sys.path.remove(bench)


# Recording which texts the loader parses needs its private seam: the loader's
# call of the fast parser (patched to record and decline, so that lark parses
# every text meanwhile), and its memos (cleared, so that no text is skipped).
_EXPR = "prima.dsl._expr"


def _clear_memos() -> None:
    expr = prima.dsl._expr  # type: ignore[attr-defined]  # the private seam, see above
    for memo in (expr._expressions, expr._templates, expr._chains):
        memo.cache_clear()


@pytest.fixture(scope="module")
def document_texts(tmp_path_factory: pytest.TempPathFactory) -> list[tuple[str, str]]:
    """Every expression and chain the loader parses in the shipped applications,
    tests/dsl/data and bench/validate.py's generated corpus, as (text, rule)."""
    corpus = tmp_path_factory.mktemp("corpus")
    _corpus(corpus)
    seen: dict[tuple[str, str], None] = {}

    def record(text: str, start: str) -> tuple[None, int]:
        seen[(text, start)] = None
        return None, 0  # lark parses every text while recording

    mp = pytest.MonkeyPatch()
    mp.setattr(f"{_EXPR}.fast_parse_sized", record)
    _clear_memos()
    try:
        folders = [ROOT / "apps", ROOT / "tests" / "dsl" / "data", ROOT / "bench" / "data",
                   corpus]
        validate_paths(collect(folders))
    finally:
        mp.undo()
        _clear_memos()
    return list(seen)


def test_documents_parse_alike(document_texts: list[tuple[str, str]]) -> None:
    starts = {start for _text, start in document_texts}
    assert starts == {"expression", "chain"}
    assert len(document_texts) > 3000
    accepted = [check(text, start) for text, start in document_texts]
    valid = [_lark(text, start) is not None for text, start in document_texts]
    # it declines only what lark refuses
    assert accepted == valid


# ---------------------------------------------------------------- generated texts

_WORDS = ("x", "event", "name", "and", "or", "not", "true", "false", "null", "andy",
          "orx", "nothing", "len", "now", "f", "Speak", "l", "_a1", "e5")
_PIECES = (
    *_WORDS, "0", "12", "3.5", "1.", ".5", "'a'", '"b {x}"', '"c\\"d"', "'e\\n'", '"open',
    "==", "!=", "<", "<=", ">", ">=", "=", "+", "-", "*", "/", "%", "(", ")", ",", ".", ":",
    "[", "]", "{", "}", "!", "&&", "#", "é",
)
_SPACE = st.sampled_from(["", "", " ", "  ", "\n", "\t", " \n ", "\r\n", "\x0b"])


@st.composite
def _soup(draw: st.DrawFn) -> str:
    """Any sequence of the languages' pieces, mostly invalid."""
    pieces = draw(st.lists(st.tuples(_SPACE, st.sampled_from(_PIECES)), max_size=14))
    return "".join(space + piece for space, piece in pieces) + draw(_SPACE)


def _expressions() -> st.SearchStrategy[str]:
    sp = _SPACE

    atoms = st.sampled_from(["x", "event", "event.name", "event . text", "now()", "12", "3.5",
                             "'a'", '"b {x}"', "true", "false", "null", "and", "or"])

    def extend(inner: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
        binary = st.tuples(inner, st.sampled_from(["or", "and", "==", "!=", "<", ">=", "+",
                                                   "-", "*", "/", "%"]), inner, sp)
        return st.one_of(
            binary.map(lambda t: f"{t[0]}{t[3] or ' '}{t[1]}{t[3] or ' '}{t[2]}"),
            inner.map(lambda e: f"not {e}"),
            inner.map(lambda e: f"-{e}"),
            inner.map(lambda e: f"({e})"),
            st.lists(inner, max_size=3).map(lambda a: f"f({', '.join(a)})"),
        )

    return st.recursive(atoms, extend, max_leaves=8)


@st.composite
def _chains(draw: st.DrawFn) -> str:
    steps = []
    for _ in range(draw(st.integers(1, 3))):
        label = draw(st.sampled_from(["", "ask: ", "l :", "not:"]))
        command = draw(st.sampled_from(["Speak", "Move", "true", "and"]))
        args = []
        for _ in range(draw(st.integers(0, 3))):
            value = draw(_expressions())
            value = draw(st.sampled_from([value, f"{{{value}}}"]))
            name = draw(st.sampled_from(["", "to=", "and = ", "true="]))
            args.append(name + value)
        extras = draw(st.sampled_from(["", "[]", "[a=1]", "[a={x}, b='c']", "[true=1]"]))
        steps.append(f"{label}{command}({', '.join(args)}){extras}")
    return draw(st.sampled_from([", ", ",", " ,\n "])).join(steps)


@settings(max_examples=400)
@given(_soup(), st.sampled_from(["expression", "chain"]))
def test_any_text_parses_alike(text: str, start: str) -> None:
    check(text, start)


@settings(max_examples=400)
@given(_expressions())
def test_expressions_parse_alike(text: str) -> None:
    check(text, "expression")


@settings(max_examples=200)
@given(_chains())
def test_chains_parse_alike(text: str) -> None:
    check(text, "chain")


def _nested(levels: int) -> str:
    return "(" * levels + "x" + ")" * levels


@pytest.mark.parametrize("text, start", [
    (_nested(24), "expression"), ("-" * 49 + "x", "expression"), ("not " * 49 + "x", "expression"),
    ("f(" * 16 + ")" * 16, "expression"), ("A(" + "-" * 45 + "1)", "chain"),
    ("x andy", "expression"), ("1and 2", "expression"), ("-not", "expression"),
    ("a == not", "expression"), ("and.x", "expression"), ("event.true", "expression"),
    ("not not", "expression"), ("a < b < c", "expression"), ("f(a,)", "expression"),
    ("x\n  + y\n*'z'", "expression"), ("A()[]", "chain"), ("not()", "chain"),
    ("a: B(and=1, {x}, -2)[c=d]", "chain"), ("A(true=1)", "chain"), ("A() B()", "chain"),
])
def test_corners(text: str, start: str) -> None:
    check(text, start)


def test_valid_texts_are_taken_fast() -> None:
    for text, start in [("x + 1 > 2 and not (y or z)", "expression"),
                        ("f(a, b) == 'q'", "expression"),
                        ('a: Speak("hi {x}"), Move(to=hall)[speed=1]', "chain")]:
        assert check(text, start)


def test_lark_trees_become_prima_trees() -> None:
    """What lark parses (a text the hand-written parser declines) is handed on as
    PRIMA's own trees."""
    parsed = _lark("Speak(text={x and y})", "chain")
    assert parsed is not None
    (step,) = prima.dsl._syntax.from_lark(parsed).children  # type: ignore[attr-defined]
    tree = step.children[2].children[1].children[0]  # named -> computed -> and_
    assert type(tree) is ParseTree and tree.data == "and_", tree
    names = [child.children[0] for child in tree.children]
    assert [(type(n), n.type, n.start_pos) for n in names] == [
        (ParseToken, "NAME", 12), (ParseToken, "NAME", 18)]
    assert names == ["x", "y"]


@pytest.mark.parametrize("text, start, at, word", [
    ("x andy", "expression", 2, "andy"), ("1and 2", "expression", 0, "1and"),
    ("x andnot y", "expression", 2, "andnot"), ("x ortrue", "expression", 2, "ortrue"),
    ("3.5or x", "expression", 0, "3.5or"), ("Speak(text={x andy})", "chain", 14, "andy"),
])
def test_a_word_lark_would_split_in_two_is_refused(text: str, start: str, at: int,
                                                   word: str) -> None:
    """Lark's lexer, after a value, tries only what may follow it: it would read
    ``x andy`` as ``x and y``. A reader sees one word there, and so does PRIMA."""
    assert fast_parse(text, start) is None
    with pytest.raises(ExpressionError) as caught:
        prima.dsl._expr._parse(text, start)  # type: ignore[attr-defined]  # private
    assert caught.value.index == at
    assert f"'{word}' runs two words together: put a space between them" in str(caught.value)


@pytest.mark.parametrize("text", ["x and y", "not(x)", "x == 'andy' and y", "(x)or(y)",
                                  "event.name == \"a.b1\"", "-1", "x or-1"])
def test_words_apart_are_taken(text: str) -> None:
    prima.dsl.compile_expression(text)
