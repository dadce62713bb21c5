"""A forgiving reading of a chain or an expression as it is being typed.

``<chain>Speak("Hi"), nav: TopologicalMove(to=hall)</chain>`` and ``cond="x > 1"`` are
texts no XML schema can see into. The language server tokenizes them without
the DSL's parser (which refuses a text half written): strings (with their
``{expression}`` parts), names, numbers and punctuation, and a stack of the
brackets open at the cursor says whether it is at a Command's name, among a
Command's arguments (which one, by position or by name), among its additional
arguments (``[...]``) or in an expression, and whether it follows ``event.``.
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass, field

__all__ = ["At", "ChainContext", "Token", "calls", "context", "labels", "tokenize", "token_at"]

_TOKEN = re.compile(r"""(?P<string>"(?:[^"\\]|\\.)*"?|'(?:[^'\\]|\\.)*'?)"""
                    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
                    r"|(?P<number>\d+(?:\.\d*)?|\.\d+)"
                    r"|(?P<op>==|!=|<=|>=|\S)", re.S)


@dataclass(frozen=True)
class Token:
    kind: str
    """``string``, ``name``, ``number`` or ``op``."""
    start: int
    end: int
    text: str

    @property
    def closed(self) -> bool:
        """A string: whether its closing quote is written."""
        return len(self.text) >= 2 and self.text[-1] == self.text[0]


def tokenize(text: str) -> list[Token]:
    out = []
    for m in _TOKEN.finditer(text):
        kind = m.lastgroup or "op"
        out.append(Token(kind, m.start(), m.end(), m.group()))
    return out


class At(enum.Enum):
    """Where a cursor is in a chain or an expression."""

    COMMAND = "command"
    """Where a Command's name goes (a chain's step)."""
    ARGUMENT = "argument"
    """Among a Command's arguments, at the start of one (a name or a value)."""
    VALUE = "value"
    """In the value of a Command's argument (after ``name=``, or a positional one)."""
    EXTRA = "extra"
    """Among a Command's additional arguments, ``[...]``."""
    EXPRESSION = "expression"
    """In an expression (a variable, a function, ``event``)."""
    FIELD = "field"
    """After ``event.``: a field of the event's data."""


@dataclass
class ChainContext:
    at: At
    prefix: str = ""
    """What is typed of the name under the cursor."""
    prefix_start: int = 0
    command: str | None = None
    """The Command whose arguments the cursor is among."""
    index: int = 0
    """Which positional argument (0-based), when no name is given."""
    name: str | None = None
    """The argument named before ``=``, if any."""
    given: set[str] = field(default_factory=set)
    """The arguments already given by name."""
    in_string: bool = False
    """The cursor is inside a string literal (outside its ``{...}`` parts)."""


@dataclass
class _Frame:
    bracket: str
    callee: str | None
    index: int = 0
    name: str | None = None
    given: set[str] = field(default_factory=set)
    fresh: bool = True
    """Nothing written yet in the current argument."""
    first: str | None = None
    """The current argument's first token, when it is a name (``name`` of ``name=``)."""


def _in_template(string: str, k: int) -> bool:
    """Whether index ``k`` of a string literal (with its quote) is inside a ``{...}``."""
    depth = 0
    i = 1
    while i < k:
        c = string[i]
        if c == "\\":
            i += 2
            continue
        if string.startswith("{{", i) or string.startswith("}}", i):
            i += 2
            continue
        if c == "{":
            depth += 1
        elif c == "}" and depth:
            depth -= 1
        i += 1
    return depth > 0


class _Reader:
    """The brackets open after each token, as the tokens are fed in order."""

    def __init__(self, chain: bool) -> None:
        self.chain = chain
        self.stack: list[_Frame] = []
        self.last_call: str | None = None
        """The Command of the last call closed at the top level (for its ``[...]``)."""

    def feed(self, tok: Token, previous: Token | None) -> None:
        text, stack = tok.text, self.stack
        if text in ("(", "[", "{"):
            callee = previous.text if previous is not None and previous.kind == "name" else None
            if text == "[" and not stack:
                callee = self.last_call
            if stack:
                stack[-1].fresh = False
            stack.append(_Frame(text, callee))
        elif text in (")", "]", "}"):
            if stack:
                frame = stack.pop()
                if not stack and frame.bracket == "(":
                    self.last_call = frame.callee
        elif text == "," and stack:
            frame = stack[-1]
            frame.index += 0 if frame.name else 1
            frame.name, frame.fresh, frame.first = None, True, None
        elif text == "," and not stack:
            self.last_call = None
        elif text == "=" and stack and stack[-1].first is not None \
                and previous is not None and previous.text == stack[-1].first:
            frame = stack[-1]
            frame.name = previous.text
            frame.given.add(previous.text)
        elif stack:
            frame = stack[-1]
            frame.first = text if frame.fresh and tok.kind == "name" else None
            frame.fresh = False

    def result(self, prefix: str, prefix_start: int, before: list[Token]) -> ChainContext:
        """The context at the cursor; ``before``: the tokens before the name being typed."""
        if len(before) >= 2 and before[-1].text == "." and before[-2].text == "event":
            return ChainContext(At.FIELD, prefix, prefix_start)
        stack = self.stack
        if not stack:
            at = At.COMMAND if self.chain else At.EXPRESSION
            return ChainContext(at, prefix, prefix_start)
        frame = stack[-1]
        if self.chain and len(stack) == 1 and frame.bracket == "(" and frame.callee:
            at = At.VALUE if frame.name or not frame.fresh else At.ARGUMENT
            return ChainContext(at, prefix, prefix_start, frame.callee, frame.index, frame.name,
                                set(frame.given))
        if self.chain and len(stack) == 1 and frame.bracket == "[":
            return ChainContext(At.EXTRA, prefix, prefix_start, frame.callee,
                                given=set(frame.given))
        return ChainContext(At.EXPRESSION, prefix, prefix_start)


def context(text: str, k: int, *, chain: bool = True) -> ChainContext:
    """What the cursor at index ``k`` of ``text`` is among (``chain``: a chain; else an
    expression)."""
    tokens = tokenize(text)
    reader = _Reader(chain)
    previous: Token | None = None
    for i, tok in enumerate(tokens):
        if tok.start >= k:
            break
        if tok.end > k or (tok.end == k and (tok.kind == "name" or (
                tok.kind == "string" and not tok.closed))):
            if tok.kind == "string":
                if _in_template(tok.text, k - tok.start):
                    inner = tok.text[1:k - tok.start]
                    brace = inner.rfind("{")
                    sub = context(inner[brace + 1:], len(inner) - brace - 1, chain=False)
                    sub.prefix_start += tok.start + 2 + brace
                    return sub
                out = reader.result(text[tok.start + 1:k], tok.start + 1, tokens[:i])
                out.in_string = True
                return out
            if tok.kind == "name":
                return reader.result(text[tok.start:k], tok.start, tokens[:i])
            break
        reader.feed(tok, previous)
        previous = tok
    else:
        i = len(tokens)
    return reader.result("", k, [t for t in tokens[:i] if t.end <= k])


def calls(text: str) -> list[tuple[str, int, str | None]]:
    """The chain's Commands: (name, where the name starts, its label or None)."""
    out = []
    tokens = tokenize(text)
    depth = 0
    label: str | None = None
    for i, tok in enumerate(tokens):
        if tok.text in ("(", "["):
            depth += 1
        elif tok.text in (")", "]"):
            depth = max(0, depth - 1)
        elif depth == 0 and tok.kind == "name":
            nxt = tokens[i + 1].text if i + 1 < len(tokens) else ""
            if nxt == ":":
                label = tok.text
            elif nxt == "(":
                out.append((tok.text, tok.start, label))
                label = None
    return out


def labels(text: str) -> list[tuple[str, int]]:
    """The chain's Command ids (``nav:``): (label, where it starts)."""
    out = []
    tokens = tokenize(text)
    depth = 0
    for i, tok in enumerate(tokens):
        if tok.text in ("(", "["):
            depth += 1
        elif tok.text in (")", "]"):
            depth = max(0, depth - 1)
        elif depth == 0 and tok.kind == "name" and i + 1 < len(tokens) \
                and tokens[i + 1].text == ":":
            out.append((tok.text, tok.start))
    return out


def token_at(text: str, k: int) -> tuple[Token | None, ChainContext]:
    """The token under index ``k`` (a name or a string, if any) and what it is among."""
    for tok in tokenize(text):
        if tok.start <= k < tok.end or (tok.kind == "name" and tok.end == k):
            if tok.kind in ("name", "string"):
                return tok, context(text, tok.start + 1 if tok.kind == "name" else tok.start)
            break
        if tok.start > k:
            break
    return None, context(text, k)
