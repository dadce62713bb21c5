"""The parse trees of expressions and chains: PRIMA's own, so that lark is imported
only when a text needs it.

``import lark`` costs about 30 ms of CPU (its whole package: the grammar loader,
the parser front ends, logging), which every cold ``prima run`` and
``prima validate`` paid although the hand-written parser
(:mod:`prima.dsl._fastparse`) parses every valid text of the shipped
applications. So trees are made of these two small classes, shaped as lark's
(``Tree.data``, ``Tree.children`` with ``None`` placeholders; a ``Token`` is the
token's text with lark's ``type`` and positions), and a tree lark parses (a text
the hand-written parser declines) is copied into them by :func:`from_lark`.
"""

from __future__ import annotations

from typing import Any

__all__ = ["Node", "Token", "Tree", "from_lark"]


class Token(str):
    """A token: its text, the grammar's name for its kind (``NAME``, ``NUMBER``,
    ``COMP_OP``...) and where it is written (as lark's: ``start_pos`` and
    ``end_pos`` 0-based, ``line`` and ``column`` 1-based, ``end_column`` one past)."""

    __slots__ = ("type", "start_pos", "line", "column", "end_line", "end_column", "end_pos")

    type: str
    start_pos: int
    line: int
    column: int
    end_line: int
    end_column: int
    end_pos: int

    def __new__(cls, type_: str, value: str, start_pos: int, line: int, column: int,
                end_line: int, end_column: int, end_pos: int) -> Token:
        token = super().__new__(cls, value)
        token.type = type_
        token.start_pos = start_pos
        token.line = line
        token.column = column
        token.end_line = end_line
        token.end_column = end_column
        token.end_pos = end_pos
        return token

    @property
    def value(self) -> str:
        """The token's text (as lark's ``Token.value``)."""
        return str(self)

    def __repr__(self) -> str:
        return f"Token({self.type!r}, {str(self)!r})"

    def __reduce__(self) -> tuple[Any, ...]:
        return (Token, (self.type, str(self), self.start_pos, self.line, self.column,
                        self.end_line, self.end_column, self.end_pos))


class Tree:
    """A grammar rule's match: its name (``data``) and its children (subtrees,
    tokens, and ``None`` where an optional part is absent: typed as lark types
    them, without the ``None``)."""

    __slots__ = ("data", "children", "start_pos")

    def __init__(self, data: str, children: list[Node], start_pos: int | None = None) -> None:
        self.data = data
        self.children = children
        self.start_pos = start_pos
        """Where the rule's own word is written, for a rule that keeps no token of it
        (a keyword value, ``not``, a prefix ``-``), when the hand-written parser made
        the tree; None otherwise. Not compared: lark's trees have no such thing."""

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Tree):
            return NotImplemented
        return self.data == other.data and self.children == other.children

    __hash__ = None  # type: ignore[assignment]  # mutable, as lark's

    def __repr__(self) -> str:
        return f"Tree({self.data!r}, {self.children!r})"


Node = Tree | Token
"""A parse tree, or one of its tokens."""


def from_lark(node: Any) -> Any:
    """A tree (or token, or ``None``) lark parsed, copied into :class:`Tree` and
    :class:`Token`. The text was measured first, so its depth is bounded."""
    if node is None:
        return None
    if isinstance(node, str):  # lark's Token is a str too
        t: Any = node
        return Token(t.type, str(t), t.start_pos, t.line, t.column, t.end_line, t.end_column,
                     t.end_pos)
    return Tree(str(node.data), [from_lark(child) for child in node.children])
