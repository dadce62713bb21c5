"""Rebuild :mod:`prima.dsl._tables` from ``pxml.lark``: a developer's step, after
editing the grammar (``tests/dsl/test_grammar_tables.py`` fails until it is done)::

    python -m prima.dsl._build_tables
"""

from __future__ import annotations

import pprint
import sys
from pathlib import Path

import lark
from lark.grammar import Rule
from lark.lexer import TerminalDef

from prima.dsl._grammar import build, grammar

TABLES = Path(__file__).with_name("_tables.py")


def tables_source(source: str) -> str:
    """The text of ``_tables.py`` for the grammar ``source``."""
    data, memo = build(source).memo_serialize([TerminalDef, Rule])
    lines = "".join(f"    {line!r}\n" for line in source.splitlines(keepends=True))
    return (
        '"""The LALR tables of pxml.lark, prebuilt by ``python -m prima.dsl._build_tables``.\n\n'
        "Generated: do not edit. :func:`prima.dsl._grammar.parser` loads them only while\n"
        "GRAMMAR is the text of pxml.lark and LARK_VERSION the installed lark's version.\n"
        '"""\n\n'
        "from typing import Any\n\n"
        f"LARK_VERSION = {lark.__version__!r}\n\n"
        f"GRAMMAR = (\n{lines})\n\n"
        f"DATA: dict[str, Any] = {pprint.pformat(data, width=100)}\n\n"
        f"MEMO: dict[int, Any] = {pprint.pformat(memo, width=100)}\n"
    )


def main() -> None:
    TABLES.write_text(tables_source(grammar()), encoding="utf-8")
    print(f"wrote {TABLES}", file=sys.stderr)


if __name__ == "__main__":
    main()
