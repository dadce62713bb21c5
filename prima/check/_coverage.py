"""What of an EA a check exercised: its states, handlers, Q&A answers and Commands.

Every item is located in the EA's document (``line:col``); the runs' records say
which ran (:mod:`._observe`). A state counts when it was entered, a handler when it
ran, a Command when one of its atomic behaviors started, and an answer of a Q&A
when the Q&A ended with it: each choice of its grammar (and each pattern), a reply
the grammar does not take (``nomatch``), and silence (``noinput``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from prima.check._visits import handlers, requests
from prima.dsl import CommandCall, Document, Grammar, Handler, HandlerKind, match_pattern, words

__all__ = ["KINDS", "Coverage", "Item", "answer_value", "items", "spans"]

KINDS = ("states", "handlers", "answers", "commands")
"""The kinds of items, in the order reports list them."""

_ATTRIBUTE = {HandlerKind.EVENT: "event"}


@dataclass(frozen=True)
class Item:
    """One thing of the EA a check may exercise."""

    kind: str
    """``states``, ``handlers``, ``answers`` or ``commands``."""
    key: tuple[Any, ...]
    line: int
    col: int
    label: str
    """How reports name it."""


def _handler_label(h: Handler) -> str:
    attribute = _ATTRIBUTE.get(h.kind, "of")
    return f'<{h.kind.value} {attribute}="{h.key}">'


def _call_label(call: CommandCall) -> str:
    return f"{call.label}: {call.command}" if call.label else call.command


def _answer_values(grammar: Grammar) -> list[tuple[str, str]]:
    """(value, label) for each answer a grammar takes, then nomatch and noinput (no
    nomatch for a grammar with a pattern of ``*`` alone: it takes every answer)."""
    out = [(f"choice:{c.value}", f"'{c.value}'") for c in grammar.choices]
    out += [(f"pattern:{k}", f"pattern '{p.source}'") for k, p in enumerate(grammar.patterns)]
    if not any(all(item == "*" for item in p.items) for p in grammar.patterns):
        out.append(("nomatch", "an answer it does not take"))
    return [*out, ("noinput", "silence")]


def items(document: Document) -> list[Item]:
    """Every item of a document, by kind, each in document order."""
    out = [Item("states", (s.id,), s.loc.line, s.loc.col, f"state '{s.id}'")
           for s in sorted(document.states.values(), key=lambda s: (s.loc.line, s.loc.col))]
    out += [Item("handlers", (f"{h.loc.line}:{h.loc.col}",), h.loc.line, h.loc.col,
                 _handler_label(h))
            for h in sorted(handlers(document), key=lambda h: (h.loc.line, h.loc.col))]
    calls: list[Item] = []
    answers: list[Item] = []
    for request in requests(document):
        where = f"{request.loc.line}:{request.loc.col}"
        for position, call in enumerate(request.calls):
            calls.append(Item("commands", (where, position), call.loc.line, call.loc.col,
                              _call_label(call)))
            grammar = document.grammars.get(call.grammar or "")
            if call.command == "QA" and grammar is not None:
                answers += [Item("answers", (where, position, value), call.loc.line,
                                 call.loc.col, f"{_call_label(call)} -> {label}")
                            for value, label in _answer_values(grammar)]
    return out + answers + calls


def answer_value(grammar: Grammar, status: str, said: str) -> str:
    """Which of a grammar's answers a Q&A that ended so heard."""
    if status != "answered":
        return "noinput"
    value = grammar.match(said)
    if value is None:
        return "nomatch"
    if any(c.value == value for c in grammar.choices):
        return f"choice:{value}"
    heard = words(said)
    for k, pattern in enumerate(grammar.patterns):
        if match_pattern(pattern.items, heard) is not None:
            return f"pattern:{k}"
    return "nomatch"


@dataclass
class Coverage:
    """A document's items, and those a check's runs exercised."""

    document: Document
    items: list[Item] = field(init=False)
    hit: set[tuple[str, tuple[Any, ...]]] = field(default_factory=set)
    _grammars: dict[tuple[str, int], Grammar] = field(init=False)

    def __post_init__(self) -> None:
        self.items = items(self.document)
        self._grammars = {}
        for request in requests(self.document):
            for position, call in enumerate(request.calls):
                grammar = self.document.grammars.get(call.grammar or "")
                if grammar is not None:
                    self._grammars[(f"{request.loc.line}:{request.loc.col}", position)] = grammar

    def add(self, seen: Mapping[str, Any]) -> None:
        """Take in what one run's record says it exercised."""
        self.hit.update(("states", (s,)) for s in seen.get("states", ()))
        self.hit.update(("handlers", (h,)) for h in seen.get("handlers", ()))
        self.hit.update(("commands", (c[0], c[1])) for c in seen.get("commands", ()))
        for where, position, status, said in seen.get("answers", ()):
            grammar = self._grammars.get((where, position))
            if grammar is not None:
                self.hit.add(("answers", (where, position, answer_value(grammar, status, said))))

    def covered(self, item: Item) -> bool:
        return (item.kind, item.key) in self.hit

    def of(self, kind: str) -> list[Item]:
        return [i for i in self.items if i.kind == kind]

    def missed(self, kind: str | None = None) -> list[Item]:
        """The items never exercised (of one kind)."""
        return [i for i in self.items if (kind is None or i.kind == kind) and not self.covered(i)]

    @property
    def percent(self) -> float:
        """How much of the document was exercised (100 for a document without items)."""
        if not self.items:
            return 100.0
        return 100.0 * sum(map(self.covered, self.items)) / len(self.items)

    def lines(self) -> list[int]:
        """The lines of the items never exercised."""
        return sorted({i.line for i in self.missed()})


def spans(lines: Sequence[int]) -> str:
    """Lines as a short list (``12, 40, 41, 42`` reads ``12, 40-42``)."""
    out: list[str] = []
    run: list[int] = []
    for line in [*lines, -10]:
        if run and line != run[-1] + 1:
            out.append(str(run[0]) if len(run) == 1 else f"{run[0]}-{run[-1]}")
            run = []
        run.append(line)
    return ", ".join(out)


