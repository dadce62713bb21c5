"""The lark parser of ``pxml.lark``, loaded from tables prebuilt from the grammar.

Building the LALR tables from the grammar costs 40 to 90 ms of CPU, which a
cold ``prima validate`` or ``prima run`` would pay in every process. So the
tables are built once, by a developer, into :mod:`prima.dsl._tables` (plain
Python data: no pickle, nothing written at run time, so a read-only install
works), and loaded from there in about 5 ms. They are used only if they were
built from this very grammar by this version of lark; otherwise the parser is
built from the grammar as before, only slower. After editing ``pxml.lark``,
rebuild them::

    python -m prima.dsl._build_tables

(``tests/dsl/test_grammar_tables.py`` fails until the tables match the grammar.)

lark itself is imported only when a parser is made: most documents never need
one (see :mod:`prima.dsl._syntax`).
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

from prima.shipped import packaged

if TYPE_CHECKING:
    from lark import Lark


def grammar() -> str:
    """The text of ``pxml.lark``."""
    return packaged("prima.dsl", "pxml.lark").read_text(encoding="utf-8")


def build(source: str | None = None) -> Lark:
    """A parser built from the grammar ``source`` (default: pxml.lark's text), the slow
    way: what the prebuilt tables are checked against."""
    from lark import Lark

    source = grammar() if source is None else source
    # Positions come from tokens (see _expr.span): propagate_positions would cost
    # about a third of every parse.
    return Lark(source, parser="lalr", start=["expression", "chain"], maybe_placeholders=True)


def prebuilt(source: str | None = None) -> Lark | None:
    """The parser loaded from :mod:`prima.dsl._tables`, or None if those tables were not
    built from the grammar ``source`` (default: pxml.lark's text) by this version of lark."""
    import lark

    from prima.dsl import _tables

    source = grammar() if source is None else source
    if source != _tables.GRAMMAR or lark.__version__ != _tables.LARK_VERSION:
        return None
    # how lark's own standalone parsers load their tables (lark leaves it unannotated)
    loaded: Lark = lark.Lark._load_from_dict(  # type: ignore[no-untyped-call]
        _tables.DATA, _tables.MEMO)
    return loaded


@lru_cache(maxsize=1)
def parser() -> Lark:
    """The LALR parser for expressions and chains, made once per process, when first
    needed: from the prebuilt tables if they match the grammar, else from the grammar."""
    source = grammar()
    return prebuilt(source) or build(source)
