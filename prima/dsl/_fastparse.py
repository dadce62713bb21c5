"""A hand-written parser for valid expressions and chains: lark's trees, faster.

lark's LALR parser costs about 50 us per expression and 150 us per chain in
pure Python, most of it in its generic lexer and parser loop; a document has
dozens of them. This recursive-descent parser builds exactly the tree lark
builds from ``pxml.lark`` (the same ``Tree.data``, children, ``None``
placeholders, and tokens with the same types, values and positions, in
:mod:`prima.dsl._syntax`'s classes), in one pass over a regex-split token list,
or returns ``None``. Without importing lark.

It is for valid input only. On anything it does not accept (a syntax fault,
or a corner where lark's contextual lexer splits a word in two, such as
``x andy`` read as ``x and y``, which the caller then refuses) it returns
``None``, and the caller parses with lark, so every syntax fault is still
worded from lark's own error and ``pxml.lark`` stays the reference grammar.
``tests/dsl/test_fastparse.py`` checks both parsers agree, tree for tree.

It runs before :func:`prima.dsl._expr.measure` (which the caller skips for a
text of few tokens: see ``_expr._parse``), so it bounds its own recursion: past
``_MAX_DEPTH`` levels, or at Python's recursion limit, it gives up, and the
caller measures the text (refusing one that nests too deep) before lark sees it.
"""

from __future__ import annotations

import re
from bisect import bisect_right
from typing import Any

from prima.dsl._syntax import Token, Tree

_LEX = re.compile(r"""[ \t\f\r\n]*(?:
    (?P<w>[A-Za-z_][A-Za-z0-9_]*)
  | (?P<n>[0-9]+(?:\.[0-9]+)?(?![A-Za-z0-9_]))
  | (?P<s>"(?:[^"\\\n]|\\.)*"|'(?:[^'\\\n]|\\.)*')
  | (?P<c>==|!=|<=|>=|<|>)
  | (?P<p>[-+*/%(),.:\[\]={}])
  | (?P<bad>[^ \t\f\r\n])
)""", re.X)
"""One token after optional whitespace (lark's ``common.WS``): a word, a number
(not run into a word: ``1and`` is left to lark, and refused), a string, a
comparison, a punctuation mark; anything else is ``bad``.
Trailing whitespace matches nothing, so the matches cover the text with no gap."""

_NEWLINE = re.compile("\n")
_END = ("", "", -1)
_VALUE_WORDS = {"true": "true", "false": "false", "null": "null"}
_ARGUMENT_KEYWORDS = frozenset({"not", "true", "false", "null"})
_MAX_DEPTH = 200
"""Recursion this parser allows itself before giving up (measure allows far less)."""


class _GiveUp(Exception):
    """Not accepted here: the caller asks lark."""


class _Parser:
    __slots__ = ("text", "toks", "i", "depth", "lines")

    def __init__(self, text: str) -> None:
        self.text = text
        toks: list[tuple[str, str, int]] = []
        for m in _LEX.finditer(text):
            kind = m.lastgroup or "bad"
            if kind == "bad":
                raise _GiveUp
            toks.append((kind if kind in "wnsc" else m.group(kind), m.group(kind),
                         m.start(kind)))
        toks.append(_END)
        self.toks = toks
        self.i = 0
        self.depth = 0
        self.lines = [m.start() for m in _NEWLINE.finditer(text)] if "\n" in text else None

    # ------------------------------------------------------------ tokens

    def token(self, type_: str, value: str, start: int) -> Token:
        """A token, positioned as lark's lexer positions it."""
        if self.lines is None:
            line, column = 1, start + 1
        else:
            before = bisect_right(self.lines, start - 1)
            line = before + 1
            column = start - (self.lines[before - 1] + 1 if before else 0) + 1
        return Token(type_, value, start, line, column, line, column + len(value),
                     start + len(value))

    def expect(self, kind: str) -> None:
        if self.toks[self.i][0] != kind:
            raise _GiveUp
        self.i += 1

    def word(self) -> Token:
        """A NAME where the grammar accepts only a name (every word is one there)."""
        kind, value, start = self.toks[self.i]
        if kind != "w":
            raise _GiveUp
        self.i += 1
        return self.token("NAME", value, start)

    # ------------------------------------------------------------ expressions

    def or_(self) -> Tree:
        self.depth += 1
        if self.depth > _MAX_DEPTH:
            raise _GiveUp
        left = self.and_()
        toks = self.toks
        while toks[self.i][0] == "w" and toks[self.i][1] == "or":
            self.i += 1
            left = Tree("or_", [left, self.and_()])
        self.after_value()
        self.depth -= 1
        return left

    def and_(self) -> Tree:
        left = self.not_()
        toks = self.toks
        while toks[self.i][0] == "w" and toks[self.i][1] == "and":
            self.i += 1
            left = Tree("and_", [left, self.not_()])
        return left

    def not_(self) -> Tree:
        kind, value, at = self.toks[self.i]
        if kind == "w" and value == "not":
            self.i += 1
            self.depth += 1
            if self.depth > _MAX_DEPTH:
                raise _GiveUp
            tree: Tree = Tree("not_", [self.not_()], at)
            self.depth -= 1
            return tree
        left = self.sum()
        kind, value, start = self.toks[self.i]
        if kind == "c":
            self.i += 1
            return Tree("compare", [left, self.token("COMP_OP", value, start), self.sum()])
        return left

    def sum(self) -> Tree:
        left = self.product()
        toks = self.toks
        while toks[self.i][0] in ("+", "-"):
            _kind, value, start = toks[self.i]
            self.i += 1
            left = Tree("binary", [left, self.token("ADD_OP", value, start), self.product()])
        return left

    def product(self) -> Tree:
        left = self.unary()
        toks = self.toks
        while toks[self.i][0] in ("*", "/", "%"):
            _kind, value, start = toks[self.i]
            self.i += 1
            left = Tree("binary", [left, self.token("MUL_OP", value, start), self.unary()])
        return left

    def unary(self) -> Tree:
        kind, _value, at = self.toks[self.i]
        if kind == "-":
            self.i += 1
            self.depth += 1
            if self.depth > _MAX_DEPTH:
                raise _GiveUp
            tree: Tree = Tree("neg", [self.unary()], at)
            self.depth -= 1
            return tree
        return self.atom()

    def atom(self) -> Tree:
        kind, value, start = self.toks[self.i]
        self.i += 1
        if kind == "n":
            return Tree("number", [self.token("NUMBER", value, start)])
        if kind == "s":
            return Tree("string", [self.token("STRING", value, start)])
        if kind == "(":
            inner = self.or_()
            self.expect(")")
            return inner
        if kind != "w":
            raise _GiveUp
        if value in _VALUE_WORDS:  # after '-' or an operator 'not' is a name, as in lark
            return Tree(_VALUE_WORDS[value], [], start)
        name = self.token("NAME", value, start)
        follow = self.toks[self.i][0]
        if follow == ".":
            self.i += 1
            return Tree("field", [name, self.word()])
        if follow == "(":
            self.i += 1
            if self.toks[self.i][0] == ")":
                self.i += 1
                return Tree("call", [name, None])  # type: ignore[list-item]  # a placeholder, as lark's
            args: list[Any] = [name, self.or_()]  # lark's trees hold None placeholders too
            while self.toks[self.i][0] == ",":
                self.i += 1
                args.append(self.or_())
            self.expect(")")
            return Tree("call", args)
        return Tree("var", [name])

    def after_value(self) -> None:
        """After a complete expression: a word here is one lark would split ('x andy'),
        or a fault; either way, lark's."""
        if self.toks[self.i][0] == "w":
            raise _GiveUp

    # ------------------------------------------------------------ chains

    def chain(self) -> Tree:
        steps: list[Any] = [self.step()]
        while self.toks[self.i][0] == ",":
            self.i += 1
            steps.append(self.step())
        return Tree("chain", steps)

    def step(self) -> Tree:
        first = self.word()
        label: Token | None = None
        if self.toks[self.i][0] == ":":
            self.i += 1
            label, first = first, self.word()
        self.expect("(")
        children: list[Any] = [label, first]
        if self.toks[self.i][0] == ")":
            children.append(None)
        else:
            children.append(self.argument())
            while self.toks[self.i][0] == ",":
                self.i += 1
                children.append(self.argument())
        self.expect(")")
        if self.toks[self.i][0] == "[":
            self.i += 1
            extras: list[Any] = []
            if self.toks[self.i][0] == "]":
                extras.append(None)
            else:
                extras.append(self.named())
                while self.toks[self.i][0] == ",":
                    self.i += 1
                    extras.append(self.named())
            self.expect("]")
            children.append(Tree("extras", extras))
        else:
            children.append(None)
        return Tree("step", children)

    def argument(self) -> Tree:
        kind, value, _start = self.toks[self.i]
        if kind == "w" and value not in _ARGUMENT_KEYWORDS and self.toks[self.i + 1][0] == "=":
            return self.named()
        return Tree("positional", [self.value()])

    def named(self) -> Tree:
        name = self.word()
        self.expect("=")
        return Tree("named", [name, self.value()])

    def value(self) -> Tree:
        if self.toks[self.i][0] == "{":
            self.i += 1
            inner = self.or_()
            self.expect("}")
            return Tree("computed", [inner])
        return self.or_()


def parse(text: str, start: str) -> Tree | None:
    """``text`` parsed from the rule ``start`` (``expression`` or ``chain``) as lark would
    parse it, or None if this parser does not accept it (ask lark)."""
    return parse_sized(text, start)[0]


def parse_sized(text: str, start: str) -> tuple[Tree | None, int]:
    """As :func:`parse`, with the number of tokens the text was split into (0 if it
    was not accepted). No nesting can be deeper than that number of levels: each
    level takes at least a token of its own (an operator, a bracket, a call)."""
    try:
        parser = _Parser(text)
        tree = parser.or_() if start == "expression" else parser.chain()
        if parser.toks[parser.i] != _END:  # (by value: compiled, a tuple is boxed anew)
            return None, 0
        return tree, len(parser.toks) - 1
    except (_GiveUp, RecursionError):
        return None, 0
