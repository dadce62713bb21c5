"""Expressions and command chains: parsed once, compiled to closures.

A valid text is parsed by the hand-written parser (:mod:`prima.dsl._fastparse`),
any other by lark (LALR, from ``pxml.lark``), which words its syntax fault;
lark is imported only then. Both give the trees of :mod:`prima.dsl._syntax`.

Nothing here calls Python's ``eval`` or ``exec``: a parse tree becomes a tree
of small functions over a :class:`Scope`. Strings are templates
(``"Hello {name}"``). Syntax faults raise :class:`~prima.errors.ExpressionError`
with the character index of the fault, which the loader turns into
``file:line:col``.

Every input is bounded before lark sees it: an expression is at most
:data:`MAX_EXPRESSION` characters, a chain :data:`MAX_CHAIN` characters and
:data:`MAX_CHAIN_COMMANDS` Commands, and a linear pre-scan (:func:`measure`)
refuses anything nested deeper than :data:`MAX_NESTING` levels, at the
character where the limit is crossed. So neither the compiler's recursion nor
the compiled closures' can be exhausted by a document, and a literal text is at
most :data:`~prima.vocab.MAX_TEXT` characters (or a robot's smaller budget).
"""

from __future__ import annotations

import math
import operator
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING, Any, TypeGuard, TypeVar, cast

from prima.dsl._fastparse import parse_sized as fast_parse_sized
from prima.dsl._syntax import Node, Token, Tree, from_lark
from prima.errors import ExecutionError, ExpressionError
from prima.record import Record
from prima.vocab import MAX_NUMBER, MAX_TEXT, Value

if TYPE_CHECKING:
    from lark.exceptions import UnexpectedInput, UnexpectedToken

MAX_NESTING = 50
"""Deepest nesting of an expression or chain: each bracket, operator and function
call on the way from the whole to its innermost part counts one level, and so
does each string template inside another."""

MAX_EXPRESSION = 10_000
"""Longest expression (characters): a ``cond``, an ``expr``, one ``{...}``."""

MAX_CHAIN = 100_000
"""Longest command chain (characters)."""

MAX_CHAIN_COMMANDS = 100
"""Most Commands one chain (or ``<request>``) may hold."""


@dataclass(repr=False)
class Scope(Record):
    """What an expression can see while it runs."""

    variables: Mapping[str, Value]
    event: Mapping[str, Value] | None = None
    now: float = 0.0
    """The simulated time (s since the run began): ``now()``."""


Fn = Callable[[Scope], Value]
"""A compiled expression's function."""

@dataclass(frozen=True, repr=False, eq=False)
class Compiled(Record):
    """A compiled expression: call :meth:`evaluate` with a :class:`Scope`."""

    source: str
    fn: Fn = field(repr=False, compare=False)
    names: frozenset[tuple[str, int]] = frozenset()
    """Variables read, each with the index where it is named."""
    event_uses: tuple[int, ...] = ()
    """Indexes where ``event`` is read."""
    constant: bool = False
    """It reads nothing: its value was computed when it was compiled."""
    event_fields: frozenset[tuple[str, int]] = frozenset()
    """Fields of ``event`` read (``event.text``), each with the index of its name."""

    def evaluate(self, scope: Scope) -> Value:
        """The expression's value in ``scope``; raises ExecutionError on a bad value."""
        return self.fn(scope)


def constant(value: Value, source: str = "") -> Compiled:
    """A compiled expression that always yields ``value``."""
    return Compiled(source or to_text(value), lambda _s: value, constant=True)


# ---------------------------------------------------------------- values

def to_text(value: Value) -> str:
    """How a value reads when spoken or interpolated."""
    if value is None:
        return ""
    if value is True:
        return "true"
    if value is False:
        return "false"
    if isinstance(value, float) and value.is_integer():
        return str(int(value))
    return str(value)


def truthy(value: Value) -> bool:
    """Whether a value counts as true in a condition: all but null, false, 0 and ""."""
    return value not in (None, False, 0, "")


def _number(value: Value, what: str) -> float | int:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ExecutionError(f"{what} needs a number, got {_describe(value)}")
    return value


def _describe(value: Value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, str):
        return f"text {value[:30]!r}"
    return f"number {to_text(value)}"


def _bounded(text: str) -> str:
    if len(text) > MAX_TEXT:
        raise ExecutionError(f"text longer than {MAX_TEXT} characters")
    return text


def _to_number(value: Value) -> Value:
    if isinstance(value, str):
        try:
            f = float(value.strip())
        except ValueError:
            return None
        if not math.isfinite(f) or abs(f) > MAX_NUMBER:
            return None
        return int(f) if f.is_integer() else f
    if isinstance(value, bool) or value is None:
        return None
    return value


FUNCTIONS: Mapping[str, tuple[int, int, Callable[..., Value], str]] = {
    "len": (1, 1, lambda s: len(to_text(s)), "number of characters of a text"),
    "str": (1, 1, lambda v: to_text(v), "a value as text"),
    "number": (1, 1, _to_number, "text as a number, or null if it is not one"),
    "round": (1, 1, lambda v: round(_in_range(_number(v, "round()"), "round()")),
              "nearest whole number"),
    "abs": (1, 1, lambda v: abs(_number(v, "abs()")), "absolute value"),
    "min": (2, 8, lambda *a: min(_number(v, "min()") for v in a), "smallest of the numbers"),
    "max": (2, 8, lambda *a: max(_number(v, "max()") for v in a), "largest of the numbers"),
    "lower": (1, 1, lambda s: to_text(s).lower(), "text in lower case"),
    "upper": (1, 1, lambda s: to_text(s).upper(), "text in upper case"),
    "trim": (1, 1, lambda s: to_text(s).strip(), "text without surrounding spaces"),
    "contains": (2, 2, lambda s, t: to_text(t).lower() in to_text(s).lower(),
                 "whether the first text contains the second (ignoring case)"),
    "startswith": (2, 2, lambda s, t: to_text(s).lower().startswith(to_text(t).lower()),
                   "whether the first text starts with the second (ignoring case)"),
}
"""The only functions of values an expression may call: name -> (min args, max args,
fn, doc)."""

CLOCK_FUNCTIONS: Mapping[str, tuple[Fn, str]] = {
    "now": (lambda s: s.now, "the simulated time: seconds since the run began"),
}
"""Functions of no argument that read the running application's situation."""


def _arith(op: str, a: Value, b: Value) -> Value:
    if op == "+" and (isinstance(a, str) or isinstance(b, str)):
        return _bounded(to_text(a) + to_text(b))
    return _in_range(_compute(op, _number(a, f"'{op}'"), _number(b, f"'{op}'")), op)


def _in_range(value: float | int, op: str) -> float | int:
    if not (isinstance(value, int) or math.isfinite(value)) or abs(value) > MAX_NUMBER:
        raise ExecutionError(f"'{op}' gives a number too large (limit {MAX_NUMBER:.0f})")
    return value


def _compute(op: str, x: float | int, y: float | int) -> float | int:
    if op == "+":
        return x + y
    if op == "-":
        return x - y
    if op == "*":
        return x * y
    if y == 0:
        raise ExecutionError(f"'{op}' by zero")
    if op == "/":
        q = x / y
        return int(q) if q.is_integer() and isinstance(x, int) and isinstance(y, int) else q
    return x % y


def _compare(op: str, a: Value, b: Value) -> bool:
    if op == "==":
        return a == b and type(a) is type(b) or (_is_num(a) and _is_num(b) and a == b)
    if op == "!=":
        return not _compare("==", a, b)
    if _is_num(a) and _is_num(b):
        return _order(op, a, b)
    if isinstance(a, str) and isinstance(b, str):
        return _order(op, a, b)
    raise ExecutionError(f"cannot order {_describe(a)} and {_describe(b)} with '{op}'")


_Ordered = TypeVar("_Ordered", float, str)


def _order(op: str, a: _Ordered, b: _Ordered) -> bool:
    if op == "<":
        return a < b
    if op == "<=":
        return a <= b
    if op == ">":
        return a > b
    return a >= b


def _is_num(v: Value) -> TypeGuard[int | float]:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


_NUMBERS = (int, float)


def _arithmetic(op: str) -> Callable[[Value, Value], Value]:
    """``op``'s function, with a fast way for two plain numbers whose result is in range
    (the everyday counter); anything else takes :func:`_arith`'s checks."""
    compute = {"+": operator.add, "-": operator.sub, "*": operator.mul}.get(op)
    if compute is None:  # '/' and '%' check for zero: no fast way
        return lambda a, b: _arith(op, a, b)

    def fast(a: Value, b: Value) -> Value:
        if type(a) in _NUMBERS and type(b) in _NUMBERS:
            value = compute(a, b)
            if -MAX_NUMBER <= value <= MAX_NUMBER:  # False for nan and inf, as _in_range
                return value  # type: ignore[no-any-return]
        return _arith(op, a, b)
    return fast


def _comparison(op: str) -> Callable[[Value, Value], bool]:
    """``op``'s function, with a fast way for two plain numbers; else :func:`_compare`."""
    if op not in _ORDERINGS:
        return lambda a, b: _compare(op, a, b)
    order = _ORDERINGS[op]

    def fast(a: Value, b: Value) -> bool:
        if type(a) in _NUMBERS and type(b) in _NUMBERS:
            return order(a, b)  # type: ignore[no-any-return]
        return _compare(op, a, b)
    return fast


_ORDERINGS: Mapping[str, Callable[[Any, Any], Any]] = {
    "<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}


# ---------------------------------------------------------------- parsing

_READABLE = {
    "NUMBER": "a number", "STRING": "a string", "NAME": "a name", "LPAR": "'('",
    "RPAR": "')'", "COMMA": "','", "COLON": "':'", "DOT": "'.'", "LSQB": "'['",
    "RSQB": "']'", "LBRACE": "'{'", "RBRACE": "'}'", "EQUAL": "'='",
    "COMP_OP": "a comparison", "ADD_OP": "'+' or '-'", "MUL_OP": "'*', '/' or '%'",
    "MINUS": "'-'", "AND": "'and'", "OR": "'or'", "NOT": "'not'", "TRUE": "'true'",
    "FALSE": "'false'", "NULL": "'null'", "$END": "the end",
}
_OPERATORS = {"COMP_OP", "ADD_OP", "MUL_OP", "AND", "OR"}
_VALUE_START = {"NUMBER", "STRING", "NAME", "LPAR", "MINUS", "TRUE", "FALSE", "NULL", "NOT"}


def _syntax_fault(exc: UnexpectedInput, text: str, what: str) -> ExpressionError:
    """Lark's parse error as a fault in ``text``, worded for a document's author."""
    from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedToken

    index = exc.pos_in_stream if exc.pos_in_stream is not None else len(text)
    if isinstance(exc, UnexpectedCharacters):
        message = _bad_character(text, index)
    elif isinstance(exc, UnexpectedEOF) or (
        isinstance(exc, UnexpectedToken) and exc.token.type == "$END"
    ):
        index, message = len(text), f"ends too early; expected {_expected(exc)}"
    elif isinstance(exc, UnexpectedToken):
        message = _bad_token(exc, what)
    else:
        message = str(exc)
    return ExpressionError(index, f"{what}: {message}", text)


def _bad_character(text: str, index: int) -> str:
    pair = text[index : index + 2]
    if pair in ("&&", "||"):
        return f"'{pair}' is not an operator; write '{'and' if pair == '&&' else 'or'}'"
    ch = text[index : index + 1]
    if ch == "!":
        return "'!' is not an operator; write 'not' (or '!=')"
    if ch in "\"'":
        return "string is not closed"
    return f"unexpected character {ch!r}"


def _bad_token(exc: UnexpectedToken, what: str) -> str:
    tok = exc.token
    if tok.type == "EQUAL" and what == "expression":
        return "'=' assigns; write '==' to compare"
    if tok.type == "NAME" and "COMMA" in exc.expected and what == "chain":
        return f"missing ',' between Commands before {tok.value!r}"
    if what == "expression" and exc.expected & _OPERATORS:
        return f"unexpected {str(tok)!r} after a complete value; expected an operator or the end"
    return f"unexpected {str(tok)!r}; expected {_expected(exc)}"


def _expected(exc: UnexpectedInput) -> str:
    expected = set(getattr(exc, "expected", None) or getattr(exc, "allowed", None) or ())
    if expected & _VALUE_START:
        expected = (expected - _VALUE_START) | {"value"}
    names = sorted("a value" if e == "value" else _READABLE.get(e, e.lower()) for e in expected)
    if len(names) > 4:
        names = names[:4] + ["..."]
    return " or ".join(names) if names else "something else"


# ---------------------------------------------------------------- bounds

_SCAN = re.compile(r"""
    (?P<string>"(?:[^"\\\n]|\\.)*"?|'(?:[^'\\\n]|\\.)*'?)
  | (?P<atom>[0-9]+(?:\.[0-9]+)?|[A-Za-z_][A-Za-z0-9_]*(?:\s*\.\s*[A-Za-z_][A-Za-z0-9_]*)?)
  | (?P<op>==|!=|<=|>=|[<>+\-*/%])
  | (?P<open>[(\[{])
  | (?P<close>[)\]}])
  | (?P<sep>[,:=])
""", re.X)
_PRECEDENCE = {"or": 1, "and": 2, "not": 3, "==": 4, "!=": 4, "<": 4, "<=": 4, ">": 4,
               ">=": 4, "+": 5, "-": 5, "*": 6, "/": 6, "%": 6, "neg": 7}
_PREFIX = frozenset({"not", "neg"})


class _Frame:
    """One bracket level of :class:`_Measure`: pending operators and operand depths."""

    __slots__ = ("ops", "operands", "best")

    def __init__(self) -> None:
        self.ops: list[tuple[int, int]] = []  # (precedence, arity)
        self.operands: list[int] = []
        self.best = 0


class _Measure:
    """How deep an expression's tree will be, from its tokens, in one linear pass.

    An operator-precedence (shunting-yard) scan that builds no tree: it keeps
    the depth of each operand and the operators still waiting for their right
    operand. Those, and the open brackets, are all ancestors of the next token,
    so the depth is known as soon as it exceeds the limit.
    """

    def __init__(self, text: str, what: str, depth: int) -> None:
        self.text = text
        self.what = what
        self.frames = [_Frame()]
        self.pending = depth  # open brackets and waiting operators, all levels
        self.commands = 1
        self.after_value = False

    def run(self) -> None:
        for m in _SCAN.finditer(self.text):
            kind = m.lastgroup or ""
            _STEPS[kind](self, m)
        self.reduce_all(self.frames[-1], len(self.text))

    def fault(self, index: int) -> ExpressionError:
        return ExpressionError(index, f"{self.what}: nested more than {MAX_NESTING} levels "
                                      "deep (brackets, operators and calls)", self.text)

    def operand(self, depth: int, index: int) -> None:
        if depth + self.pending > MAX_NESTING:
            raise self.fault(index)
        self.frames[-1].operands.append(depth)
        self.after_value = True

    def push(self, precedence: int, arity: int, index: int) -> None:
        frame = self.frames[-1]
        if arity == 2:
            while frame.ops and frame.ops[-1][0] >= precedence:
                self.reduce(frame, index)
        frame.ops.append((precedence, arity))
        self.pending += 1
        if self.pending > MAX_NESTING:
            raise self.fault(index)
        self.after_value = False

    def reduce(self, frame: _Frame, index: int) -> None:
        _prec, arity = frame.ops.pop()
        self.pending -= 1
        depths = [frame.operands.pop() if frame.operands else 0 for _ in range(arity)]
        self.operand(max(depths) + 1, index)

    def reduce_all(self, frame: _Frame, index: int) -> int:
        while frame.ops:
            self.reduce(frame, index)
        deepest = max([frame.best, *frame.operands])
        frame.operands.clear()
        frame.best = deepest
        return deepest

    def string(self, m: re.Match[str]) -> None:
        self.operand(1, m.start())

    def atom(self, m: re.Match[str]) -> None:
        word = m.group()
        if word in ("and", "or"):
            self.push(_PRECEDENCE[word], 2, m.start())
        elif word == "not":
            self.push(_PRECEDENCE[word], 1, m.start())
        else:
            self.operand(1, m.start())

    def op(self, m: re.Match[str]) -> None:
        if m.group() == "-" and not self.after_value:
            self.push(_PRECEDENCE["neg"], 1, m.start())
        else:
            self.push(_PRECEDENCE[m.group()], 2, m.start())

    def open(self, m: re.Match[str]) -> None:
        self.frames.append(_Frame())
        self.pending += 1
        if self.pending > MAX_NESTING:
            raise self.fault(m.start())
        self.after_value = False

    def close(self, m: re.Match[str]) -> None:
        if len(self.frames) == 1:  # unbalanced: the parser says so
            return
        inner = self.reduce_all(self.frames.pop(), m.start())
        self.pending -= 1
        self.operand(inner + 1, m.start())

    def sep(self, m: re.Match[str]) -> None:
        self.reduce_all(self.frames[-1], m.start())
        self.after_value = False
        if m.group() == "," and len(self.frames) == 1:
            self.commands += 1
            if self.commands > MAX_CHAIN_COMMANDS:
                raise ExpressionError(_next_token(self.text, m.end()),
                                      f"{self.what}: more than {MAX_CHAIN_COMMANDS} Commands "
                                      "in one chain", self.text)


_STEPS: Mapping[str, Callable[[_Measure, re.Match[str]], None]] = {
    "string": _Measure.string, "atom": _Measure.atom, "op": _Measure.op,
    "open": _Measure.open, "close": _Measure.close, "sep": _Measure.sep,
}


def _next_token(text: str, i: int) -> int:
    while i < len(text) and text[i].isspace():
        i += 1
    return i


def measure(text: str, what: str = "expression", depth: int = 0) -> None:
    """Refuse ``text`` if it is too long or nests too deep; raise ExpressionError.

    ``what`` is ``expression`` or ``chain``; ``depth`` is how deep the text
    already is (a template inside a string inside another expression).
    """
    longest = MAX_CHAIN if what == "chain" else MAX_EXPRESSION
    if len(text) > longest:
        raise ExpressionError(longest, f"{what}: longer than {longest:,} characters", text)
    _Measure(text, what, depth).run()


def _parse(text: str, start: str, depth: int = 0) -> Tree:
    """``text`` parsed from the rule ``start``, ``depth`` levels deep already,
    checked by :func:`measure`: by the hand-written parser if it accepts it (the same tree,
    faster), else by lark, whose errors word every syntax fault.

    The measure is skipped when it cannot refuse the text: a text the hand-written
    parser split into at most ``MAX_NESTING - depth`` tokens nests no deeper than
    that (measure's own tokens are no more: it reads ``event.name`` as one), so
    it holds fewer than :data:`MAX_CHAIN_COMMANDS` Commands too.
    """
    longest = MAX_CHAIN if start == "chain" else MAX_EXPRESSION
    tree, tokens = fast_parse_sized(text, start) if len(text) <= longest else (None, 0)
    if tree is None or depth + tokens > MAX_NESTING:
        measure(text, start, depth)
    if tree is not None:
        return tree
    from lark.exceptions import UnexpectedInput

    from prima.dsl._grammar import parser

    try:
        parsed = parser().parse(text, start=start)
    except UnexpectedInput as exc:
        raise _syntax_fault(exc, text, start) from None
    tree = cast(Tree, from_lark(parsed))
    _words_apart(text, tree, start)
    return tree


_WORD = re.compile(r"[0-9]+(?:\.[0-9]+)?[A-Za-z0-9_]*|[A-Za-z_][A-Za-z0-9_]*")
"""One word as a reader sees it: a run of letters, digits and underscores (with a
number's decimals)."""

def _words_apart(text: str, tree: Tree, what: str) -> None:
    """Refuse a text in which lark's lexer split one word in two: it reads ``x andy`` as
    ``x and y``, ``1and 2`` as ``1 and 2`` (after a value it tries only what may follow,
    such as ``and``). Every word outside the string literals must be one of the tree's
    names or numbers, or, where the tree has none (lark leaves keywords out), a keyword
    alone. Only texts the hand-written parser declined get here (it never splits a
    word), so this costs nothing on the common path."""
    tokens: dict[int, int] = {}
    strings: list[tuple[int, int]] = []
    stack: list[Node] = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, Tree):
            stack.extend(node.children)
        elif isinstance(node, Token):
            if node.type == "STRING":
                strings.append((node.start_pos, node.end_pos))
            else:
                tokens[node.start_pos] = node.end_pos
    strings.sort()
    i = 0
    for m in _WORD.finditer(text):
        begin, end = m.span()
        while i < len(strings) and strings[i][1] <= begin:
            i += 1
        if i < len(strings) and strings[i][0] <= begin:
            continue  # (inside a string literal)
        if tokens.get(begin) == end or (begin not in tokens and m[0] in _KEYWORDS
                                        and not any(begin < t < end for t in tokens)):
            continue
        raise ExpressionError(begin, f"{what}: '{m[0]}' runs two words together: put a "
                                     "space between them", text)


def compile_expression(text: str, *, max_text: int = MAX_TEXT, depth: int = 0) -> Compiled:
    """Parse and compile one expression (e.g. a ``cond`` attribute).

    ``max_text`` bounds its literal texts (a robot profile's budget may be
    smaller than :data:`~prima.vocab.MAX_TEXT`); ``depth`` is how deeply it
    is already nested (inside a template). A short text is compiled once per
    process (see :data:`MEMO_TEXT`).
    """
    if len(text) <= MEMO_TEXT:
        return _expressions(text, max_text, depth)
    return _compile_expression(text, max_text, depth)


def _compile_expression(text: str, max_text: int, depth: int) -> Compiled:
    if not text.strip():
        raise ExpressionError(0, "expression: empty", text)
    bare = _BARE_NAME.fullmatch(text)
    if bare and bare.group(1) not in _KEYWORDS:  # {name}: the common case, without lark
        return _variable(bare.group(1), bare.start(1))
    return _Compiler(text, max_text, depth).compile(_parse(text, "expression", depth),
                                                    whole=True)


_BARE_NAME = re.compile(r"\s*([A-Za-z_][A-Za-z0-9_]*)\s*")
_KEYWORDS = frozenset({"and", "or", "not", "true", "false", "null"})


def _variable(name: str, index: int) -> Compiled:
    """A bare variable name (or ``event``) at ``index``, compiled as the grammar would."""
    if name == "event":
        return Compiled(name, lambda s: None if s.event is None else s.event.get("name"),
                        event_uses=(index,))
    return Compiled(name, lambda s: s.variables.get(name), frozenset({(name, index)}))


def compile_template(text: str, *, max_text: int = MAX_TEXT, depth: int = 0) -> Compiled:
    """Compile literal text with ``{expr}`` interpolation (e.g. ``text="Hi {name}"``).

    Its literal characters are at most ``max_text``: more, and the fault is at
    the first character beyond the limit. A short text is compiled once per
    process (see :data:`MEMO_TEXT`).
    """
    if len(text) <= MEMO_TEXT:
        return _templates(text, max_text, depth)
    return _compile_template(text, max_text, depth)


def _compile_template(text: str, max_text: int, depth: int) -> Compiled:
    parts: list[str | Compiled] = []
    i, n = 0, len(text)
    literal: list[str] = []
    written = 0  # literal characters so far, over every part
    while i < n:
        ch = text[i]
        if ch not in "{}" or text.startswith(ch * 2, i):
            written += 1
            if written > max_text:
                raise ExpressionError(i, f"text: longer than {max_text:,} characters", text)
        if ch in "{}" and text.startswith(ch * 2, i):
            literal.append(ch)
            i += 2
        elif ch == "}":
            raise ExpressionError(i, "text: '}' without '{' (write '}}' for a brace)", text)
        elif ch == "{":
            end = _closing_brace(text, i + 1)
            if end < 0:
                raise ExpressionError(i, "text: '{' is not closed (write '{{' for a brace)", text)
            if literal:
                parts.append("".join(literal))
                literal = []
            inner = text[i + 1 : end]
            try:
                sub = compile_expression(inner, max_text=max_text, depth=depth + 1)
            except ExpressionError as fault:
                raise ExpressionError(i + 1 + fault.index, fault.message, text) from None
            parts.append(_shift(sub, i + 1))
            i = end + 1
        else:
            literal.append(ch)
            i += 1
    if literal:
        parts.append("".join(literal))
    return _join(text, parts)


def _closing_brace(text: str, i: int) -> int:
    quote = ""
    while i < len(text):
        ch = text[i]
        if quote:
            if ch == "\\":
                i += 1
            elif ch == quote:
                quote = ""
        elif ch in "\"'":
            quote = ch
        elif ch == "}":
            return i
        i += 1
    return -1


def _shift(c: Compiled, by: int) -> Compiled:
    return Compiled(c.source, c.fn, frozenset((n, i + by) for n, i in c.names),
                    tuple(i + by for i in c.event_uses), c.constant,
                    frozenset((f, i + by) for f, i in c.event_fields))


def _join(source: str, parts: list[str | Compiled]) -> Compiled:
    names = frozenset().union(*(p.names for p in parts if isinstance(p, Compiled)))
    events = tuple(i for p in parts if isinstance(p, Compiled) for i in p.event_uses)
    fields = frozenset().union(*(p.event_fields for p in parts if isinstance(p, Compiled)))
    texts = [p for p in parts if isinstance(p, str)]
    if len(texts) == len(parts):
        return constant("".join(texts), source)
    pieces = [(p, None) if isinstance(p, str) else ("", p.fn) for p in parts]

    def fn(scope: Scope) -> Value:
        return _bounded("".join(text if f is None else to_text(f(scope)) for text, f in pieces))

    return Compiled(source, fn, names, events, event_fields=fields)


# ---------------------------------------------------------------- chains

@dataclass(frozen=True, repr=False, eq=False)
class ChainArg(Record):
    """One argument of a chain step, not yet bound to a Command's parameter."""

    name: str | None
    tree: Node
    index: int
    computed: bool = False
    name_index: int = -1
    """Where the argument's name is written (named arguments), else -1."""


@dataclass(frozen=True, repr=False, eq=False)
class ChainStep(Record):
    """One Command in a chain, as written: ``label: Name(args)[extras]``."""

    label: str | None
    command: str
    index: int
    args: tuple[ChainArg, ...]
    extras: tuple[ChainArg, ...]
    label_index: int = 0


def parse_chain(text: str) -> list[ChainStep]:
    """Parse a command chain into steps; arguments are bound later. A short chain is
    parsed once per process (see :data:`MEMO_TEXT`)."""
    if len(text) <= MEMO_TEXT:
        return list(_chains(text))
    return list(_parse_chain(text))


def _parse_chain(text: str) -> tuple[ChainStep, ...]:
    if not text.strip():
        raise ExpressionError(0, "chain: empty", text)
    return tuple(_step(_tree(step)) for step in _parse(text, "chain").children)


def _step(step: Tree) -> ChainStep:
    # [label ":"] Name "(" [arguments] ")" [extras]; an absent optional part is None
    label, name, *rest = step.children
    extras: list[Node] = []
    last = rest[-1] if rest else None
    if isinstance(last, Tree) and last.data == "extras":
        extras, rest = last.children, rest[:-1]
    index = _pos(_token(name))
    return ChainStep(
        label=None if label is None else str(label),
        command=str(name),
        index=index,
        args=tuple(_chain_arg(_tree(a)) for a in rest if a is not None),
        extras=tuple(_chain_arg(_tree(x)) for x in extras if x is not None),
        label_index=index if label is None else _pos(_token(label)),
    )


def _chain_arg(node: Tree) -> ChainArg:
    if node.data == "named":
        name, value = node.children
        return ChainArg(str(name), *_value(value), computed=_is_computed(value),
                        name_index=_pos(_token(name)))
    value = node.children[0]
    return ChainArg(None, *_value(value), computed=_is_computed(value))


def _is_computed(value: Node) -> bool:
    return isinstance(value, Tree) and value.data == "computed"


def _value(value: Node) -> tuple[Node, int]:
    if isinstance(value, Tree) and value.data == "computed":
        inner = value.children[0]
        return inner, _start(inner)
    return value, _start(value)


def _token(node: Node) -> Token:
    """A child the grammar makes a token (a name, a number, a string)."""
    return cast(Token, node)


def _tree(node: Node) -> Tree:
    """A child the grammar makes a subtree (a step, an argument)."""
    return cast(Tree, node)


def _pos(token: Token) -> int:
    return token.start_pos or 0


def _tokens(node: Node) -> list[Token]:
    """The subtree's tokens, in no particular order (callers take their extremes)."""
    if isinstance(node, Token):
        return [node]
    found: list[Token] = []
    trees = [node]
    while trees:  # a loop, not lark's recursive generators: this runs for every subtree
        for child in trees.pop().children:
            if isinstance(child, Tree):
                trees.append(child)
            elif isinstance(child, Token):
                found.append(child)
    return found


def _start(node: Node) -> int:
    """Where the subtree's first token is written; for a subtree without tokens (a
    keyword value, ``-true``), where its first word is, if the tree knows (else 0)."""
    tokens = _tokens(node)
    if tokens:
        return min(_pos(t) for t in tokens)
    while isinstance(node, Tree):
        if node.start_pos is not None:
            return node.start_pos
        children = [c for c in node.children if c is not None]
        if not children:
            break
        node = children[0]
    return 0


def bare_name(arg: ChainArg) -> str | None:
    """The name if the argument is written as a bare name, else None."""
    tree = arg.tree
    if not arg.computed and isinstance(tree, Tree) and tree.data == "var":
        return str(tree.children[0])
    return None


def string_literal(arg: ChainArg) -> str | None:
    """The raw content of the argument if it is a plain string literal."""
    tree = arg.tree
    if not arg.computed and isinstance(tree, Tree) and tree.data == "string":
        return str(tree.children[0])[1:-1]
    return None


def compile_chain_arg(arg: ChainArg, source: str, *, max_text: int = MAX_TEXT) -> Compiled:
    """Compile a chain argument as an expression (the chain was measured when parsed). The
    arguments of a short chain are compiled once per process (see :data:`MEMO_TEXT`)."""
    if len(source) <= MEMO_TEXT:
        return _chain_args(source, arg.index, max_text, _Along(arg))
    return _compile_chain_arg(source, max_text, _Along(arg))


def _compile_chain_arg(source: str, max_text: int, arg: _Along) -> Compiled:
    return _Compiler(source, max_text).compile(arg.value.tree)


class _Along:
    """A chain argument riding along a memo's key without being part of it: the chain's
    text and where the argument begins in it say which argument it is."""

    __slots__ = ("value",)

    def __init__(self, value: ChainArg) -> None:
        self.value = value

    def __hash__(self) -> int:
        return 0

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Along)


# ---------------------------------------------------------------- compiler

_ESCAPES = {"n": "\n", "t": "\t", "\\": "\\", '"': '"', "'": "'"}

Part = tuple[Fn, bool]
"""A compiled subtree: its function, and whether it is a constant."""


def _const(value: Value) -> Part:
    return (lambda _s: value), True


class _Compiler:
    """Turns a parse tree into a :class:`Compiled` closure tree.

    As in a lark ``Transformer``, each grammar rule has its own method, found
    by the rule's name in :data:`_RULES`; it compiles the rule's children.
    """

    def __init__(self, source: str, max_text: int = MAX_TEXT, depth: int = 0) -> None:
        self.source = source
        self.max_text = max_text
        self.depth = depth
        """How deep the source is already nested (a template inside a string)."""
        self.level = 0
        """How deep the subtree being compiled is (at most MAX_NESTING: measured)."""
        self.names: set[tuple[str, int]] = set()
        self.events: list[int] = []
        self.fields: set[tuple[str, int]] = set()

    def compile(self, tree: Node, *, whole: bool = False) -> Compiled:
        """Compile ``tree``; ``whole`` when it is all of the source (an expression, not
        one argument of a chain), which is then what it quotes."""
        fn, const = self.node(tree)
        if whole:
            text = self.source.strip(_SPACE)
        else:
            start, end = span(tree, self.source)
            text = self.source[start:end]
        if not const:
            return Compiled(text, fn, frozenset(self.names), tuple(self.events),
                            event_fields=frozenset(self.fields))
        value = self._value(fn, tree)
        if isinstance(value, str) and len(value) > self.max_text:
            raise ExpressionError(_start(tree), f"expression: text longer than "
                                                f"{self.max_text:,} characters", self.source)
        return constant(value, text)

    def node(self, node: Node) -> Part:
        """Compile a subtree with its rule's method."""
        kind = node.data if isinstance(node, Tree) else node.type
        rule = _RULES.get(kind)
        if rule is None or not isinstance(node, Tree):
            raise ExpressionError(_start(node), f"expression: unsupported construct {kind!r}",
                                  self.source)
        self.level += 1
        try:
            return rule(self, node.children)
        finally:
            self.level -= 1

    def operand(self, node: Node) -> Part:
        """Compile an operand of an operator or a function. A constant one is worked out
        now: one that cannot be computed (``1 + -true``) is a fault at load, as a whole
        expression that is constant is, even where it would not be reached
        (``x and -true``)."""
        fn, const = self.node(node)
        if not const:
            return fn, False
        return _const(self._value(fn, node))

    def _value(self, fn: Fn, node: Node) -> Value:
        """A constant's value; one that cannot be computed (``-'a'``) is a fault at its
        first character."""
        try:
            return fn(Scope({}))
        except ExecutionError as exc:
            raise ExpressionError(_start(node), f"expression: {exc}", self.source) from None

    def fault(self, token: Token, message: str) -> ExpressionError:
        """A fault at ``token``."""
        return ExpressionError(_pos(token), f"expression: {message}", self.source)

    # ------------------------------------------------------------ one per rule

    def number(self, ch: list[Node]) -> Part:
        tok = _token(ch[0])
        raw = str(tok)
        if len(raw) > 20:
            raise self.fault(tok, "number too long")
        value = float(raw) if "." in raw else int(raw)
        if value > MAX_NUMBER:
            raise self.fault(tok, f"number too large (the limit is {MAX_NUMBER:.0f})")
        return _const(value)

    def string(self, ch: list[Node]) -> Part:
        tok = _token(ch[0])
        t = self._template(str(tok), _pos(tok))
        return t.fn, t.constant

    def true(self, ch: list[Node]) -> Part:
        return _const(True)

    def false(self, ch: list[Node]) -> Part:
        return _const(False)

    def null(self, ch: list[Node]) -> Part:
        return _const(None)

    def var(self, ch: list[Node]) -> Part:
        tok = _token(ch[0])
        name = str(tok)
        if name == "event":
            self.events.append(_pos(tok))
            return (lambda s: None if s.event is None else dict(s.event).get("name")), False
        self.names.add((name, _pos(tok)))
        return (lambda s: s.variables.get(name)), False

    def field(self, ch: list[Node]) -> Part:
        tok = _token(ch[0])
        base, attr = str(tok), str(ch[1])
        if base != "event":
            raise self.fault(tok, f"only 'event' has fields ('{base}.{attr}')")
        self.events.append(_pos(tok))
        self.fields.add((attr, _pos(tok) + len(base) + 1))
        return (lambda s: None if s.event is None else s.event.get(attr)), False

    def call(self, ch: list[Node]) -> Part:
        tok, *given = ch
        name_tok = _token(tok)
        args = [a for a in given if a is not None]
        name = str(name_tok)
        if name in CLOCK_FUNCTIONS:
            if args:
                raise self.fault(name_tok, f"{name}() takes no argument, got {len(args)}")
            return CLOCK_FUNCTIONS[name][0], False  # never a constant
        if name not in FUNCTIONS:
            known = ", ".join(sorted([*FUNCTIONS, *CLOCK_FUNCTIONS]))
            raise self.fault(name_tok, f"unknown function '{name}' (known: {known})")
        lo, hi, impl, _doc = FUNCTIONS[name]
        if not lo <= len(args) <= hi:
            want = str(lo) if lo == hi else f"{lo} to {hi}"
            raise self.fault(name_tok, f"{name}() takes {want} argument(s), got {len(args)}")
        fns = [self.operand(a)[0] for a in args]
        return (lambda s: impl(*(f(s) for f in fns))), False

    def neg(self, ch: list[Node]) -> Part:
        f, c = self.node(ch[0])
        return (lambda s: -_number(f(s), "'-'")), c

    def not_(self, ch: list[Node]) -> Part:
        f, c = self.node(ch[0])
        return (lambda s: not truthy(f(s))), c

    def and_(self, ch: list[Node]) -> Part:
        (fa, ca), (fb, cb) = self.operand(ch[0]), self.operand(ch[1])
        return (lambda s: truthy(fa(s)) and truthy(fb(s))), ca and cb

    def or_(self, ch: list[Node]) -> Part:
        (fa, ca), (fb, cb) = self.operand(ch[0]), self.operand(ch[1])
        return (lambda s: truthy(fa(s)) or truthy(fb(s))), ca and cb

    def binary(self, ch: list[Node]) -> Part:
        fa, op, fb = self.operand(ch[0])[0], str(ch[1]), self.operand(ch[2])[0]
        arith = _arithmetic(op)
        return (lambda s: arith(fa(s), fb(s))), False

    def compare(self, ch: list[Node]) -> Part:
        fa, op, fb = self.operand(ch[0])[0], str(ch[1]), self.operand(ch[2])[0]
        compare = _comparison(op)
        return (lambda s: compare(fa(s), fb(s))), False

    # ------------------------------------------------------------ helpers

    def _template(self, raw: str, start: int) -> Compiled:
        """A string literal: a template, its faults and names located in the source."""
        body = raw[1:-1]
        decoded, index_map = _unescape(body) if "\\" in body else (body, [])

        def at(i: int) -> int:  # where decoded character i is written
            return start + 1 + (index_map[i] if i < len(index_map) else i)

        try:
            t = compile_template(decoded, max_text=self.max_text, depth=self.depth + self.level)
        except ExpressionError as fault:
            raise ExpressionError(at(fault.index), fault.message, self.source) from None
        self.names.update((n, at(i)) for n, i in t.names)
        self.events.extend(at(i) for i in t.event_uses)
        self.fields.update((f, at(i)) for f, i in t.event_fields)
        return t


_RULES: Mapping[str, Callable[[_Compiler, list[Node]], Part]] = {
    "number": _Compiler.number,
    "string": _Compiler.string,
    "true": _Compiler.true,
    "false": _Compiler.false,
    "null": _Compiler.null,
    "var": _Compiler.var,
    "field": _Compiler.field,
    "call": _Compiler.call,
    "neg": _Compiler.neg,
    "not_": _Compiler.not_,
    "and_": _Compiler.and_,
    "or_": _Compiler.or_,
    "binary": _Compiler.binary,
    "compare": _Compiler.compare,
}
"""How each rule of ``pxml.lark``'s expressions compiles."""


def _unescape(body: str) -> tuple[str, list[int]]:
    out: list[str] = []
    where: list[int] = []
    i = 0
    while i < len(body):
        if body[i] == "\\" and i + 1 < len(body):
            out.append(_ESCAPES.get(body[i + 1], body[i + 1]))
            where.append(i)
            i += 2
        else:
            out.append(body[i])
            where.append(i)
            i += 1
    return "".join(out), where


def span(node: Node, source: str) -> tuple[int, int]:
    """Where a subtree is written, with what the tree keeps no token of: the
    parentheses around or inside it, and the words at either end of it (a keyword
    value ``true``, ``false``, ``null``; a prefix ``-`` or ``not``)."""
    tokens = _tokens(node)
    if not tokens:  # words only ('not null', '-true'): from the first, if the tree knows it
        start = _start(node)
        end = _after_words(source, start, node)
        if end == start:  # not found where the tree says (lark made it): the whole text
            return _skip(source, 0, _SPACE, 1), _skip(source, len(source), _SPACE, -1)
        return start, end + _closing(source, source.count("(", start, end), end)
    start, end = min(_pos(t) for t in tokens), max(t.end_pos for t in tokens)
    end = _after_words(source, end, _last_without_tokens(node))
    for word in reversed(_first_words(node)):  # innermost first: a keyword, then '-', 'not'
        at = _skip(source, start, _SPACE + "()", -1)
        if not source.endswith(word, 0, at):
            break
        start = at - len(word)
    # parentheses opened and not closed within the span, outside its strings (which
    # may hold any): closed after it, or opened before it
    depth = source.count("(", start, end) - source.count(")", start, end)
    for token in tokens:
        if token.type == "STRING":
            depth -= token.count("(") - token.count(")")
    end += _closing(source, depth, end)
    while depth < 0 and start > 0 and source[start - 1] in _SPACE + "(":
        depth += source[start - 1] == "("
        start -= 1
    return start, end


_SPACE = " \t\f\r\n"
"""What the grammar skips between tokens."""

_UNWRITTEN = {"true": "true", "false": "false", "null": "null", "neg": "-", "not_": "not"}
"""Rules whose tree keeps no token of their word: a keyword value, or a prefix operator."""


def _first_words(node: Node) -> list[str]:
    """The words the tree keeps no token of along its first edge, outermost first:
    prefix operators, and a keyword value (``true``, ``false``, ``null``) last."""
    words: list[str] = []
    while isinstance(node, Tree):
        word = _UNWRITTEN.get(node.data)
        if word is not None:
            words.append(word)
        children = [c for c in node.children if c is not None]
        if not children:
            break
        node = children[0]
    return words


def _last_without_tokens(node: Node) -> Node | None:
    """The subtree at the end of the tree's last edge that holds no token ('-true'
    in 'x + -true'), if the tree ends so."""
    while isinstance(node, Tree):
        children = [c for c in node.children if c is not None]
        if not children:
            return None
        last = children[-1]
        if isinstance(last, Tree) and not _has_token(last):
            return last
        node = last
    return None


def _has_token(node: Tree) -> bool:
    """Whether the subtree holds a token (found at the first; only a subtree of
    keywords and prefix operators is walked whole)."""
    trees = [node]
    while trees:
        for child in trees.pop().children:
            if isinstance(child, Token):
                return True
            if isinstance(child, Tree):
                trees.append(child)
    return False


def _after_words(source: str, at: int, node: Node | None) -> int:
    """Past the words of a subtree without tokens (``node``) written from ``at`` on
    (spaces and opening parentheses between them); ``at`` if they are not there."""
    if node is None:
        return at
    end = at
    for word in _first_words(node):
        end = _skip(source, end, _SPACE + "(", 1)
        if not source.startswith(word, end):
            return at
        end += len(word)
    return end


def _closing(source: str, depth: int, end: int) -> int:
    """How many characters after ``end`` close ``depth`` open parentheses (spaces
    between them included)."""
    at = end
    while depth > 0 and at < len(source) and source[at] in _SPACE + ")":
        depth -= source[at] == ")"
        at += 1
    return at - end


def _skip(source: str, at: int, chars: str, step: int) -> int:
    """From ``at``, past the characters ``chars`` going forward (``step`` 1) or back (-1)."""
    if step > 0:
        while at < len(source) and source[at] in chars:
            at += 1
    else:
        while at > 0 and source[at - 1] in chars:
            at -= 1
    return at


# ---------------------------------------------------------------- memo

MEMO_TEXT = 256
"""Longest expression, template or chain whose compiled form (or parse, and its
arguments' compiled forms) is kept and reused for the same text in this process:
documents repeat many short texts (``0``, ``count + 1``, ``Speak("Please say yes
or no.")``), and ``prima lsp`` checks a document again at every pause in the
typing, most of its texts unchanged. What is kept holds positions relative to the
text only, so each use is located where it is written. Faults are not kept: a
faulty text is compiled again and fails again."""

MEMO_ENTRIES = 4096
"""How many texts of each kind are kept (the least recently used go first): every
text of a document of 5,000 lines, and a bound on the memory untrusted documents
can make the process keep (at most :data:`MEMO_TEXT` characters each)."""

_expressions = lru_cache(maxsize=MEMO_ENTRIES)(_compile_expression)
_templates = lru_cache(maxsize=MEMO_ENTRIES)(_compile_template)
_chains = lru_cache(maxsize=MEMO_ENTRIES)(_parse_chain)


@lru_cache(maxsize=MEMO_ENTRIES)
def _chain_args(source: str, index: int, max_text: int, arg: _Along) -> Compiled:
    return _compile_chain_arg(source, max_text, arg)
