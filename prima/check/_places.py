"""Where an EA can go: the places each of its Commands' place arguments can name, worked
out from the document alone, so that ``prima check`` makes visits on a map that has them.

A place argument written as a name (``TopologicalMove(hall)``) names that place. One
computed from a variable (``TopologicalMove({goal})``) names whatever the variable can
hold: the values of the ``<var>``'s ``expr`` and of each ``<assign>`` to it that are
constants or other such variables; the answers of each Q&A that puts its answer
``into`` it; and, for an ``<assign expr="event.answer">`` in a Q&A's answer handler or
in an ``<on event="speech" match="G">`` handler, the answers of that Q&A's grammar or
of G. A grammar answers its choices' values; a pattern answers the words it captured,
which nobody can know. Anything else (a message's text, an expression, a speech
handler without a grammar) makes the argument's places unknown, and the check asks
for a map instead of guessing one. An empty text or null is no place (the Command
would fail at once), so it is none of the places.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from prima.catalog import STANDARD_COMMANDS, ParamKind
from prima.check._visits import handlers
from prima.dsl import (
    Action,
    Assign,
    CommandCall,
    Compiled,
    Document,
    Grammar,
    Handler,
    HandlerKind,
    If,
    Loc,
    Request,
    Scope,
    to_text,
)
from prima.sim import WorldMap

__all__ = ["Destination", "destinations", "known_places", "map_for", "unknown_destinations"]

_PLACE_PARAMS = {spec.name: tuple(p.name for p in spec.params if p.kind is ParamKind.PLACE)
                 for spec in STANDARD_COMMANDS}
"""Command -> its place arguments (``TopologicalMove``: ``to``)."""

_NOTHING = Scope({})


@dataclass(frozen=True)
class Destination:
    """One place argument of a Command in a document: the places it can name (None: they
    cannot be known before it runs, and ``why`` says why)."""

    command: str
    param: str
    loc: Loc
    """Where the Command is written."""
    places: frozenset[str] | None
    why: str = ""

    def where(self, document: Document) -> str:
        """``file:line:col`` of the Command in ``document``."""
        return f"{document.path}:{self.loc.line}:{self.loc.col}"


@dataclass(frozen=True)
class _Unknown:
    why: str


_Source = str | _Unknown
"""What a variable may be given: a value, the variable whose values it takes (written
``@name``), or something nobody can know."""


def _walk(actions: Sequence[Action], handler: Handler | None
          ) -> Iterator[tuple[Action, Handler | None]]:
    for action in actions:
        yield action, handler
        if isinstance(action, If):
            for _cond, branch in action.branches:
                yield from _walk(branch, handler)
            yield from _walk(action.otherwise, handler)


def _actions(document: Document) -> Iterator[tuple[Action, Handler | None]]:
    """Every action of the document, with the handler it is in (None: a state's entry)."""
    for h in handlers(document):
        yield from _walk(h.actions, h)
    for state in document.states.values():
        yield from _walk(state.entry, None)


def _calls(document: Document) -> Iterator[CommandCall]:
    for action, _handler in _actions(document):
        if isinstance(action, Request):
            yield from action.calls


def _bare(compiled: Compiled) -> str | None:
    """The variable an expression is, when it is one variable alone (``goal``)."""
    names = {name for name, _at in compiled.names}
    if len(names) == 1 and not compiled.event_uses and compiled.source.strip() in names:
        return compiled.source.strip()
    return None


def _grammar_values(grammar: Grammar | None, what: str) -> list[_Source]:
    if grammar is None:
        return [_Unknown(f"{what} takes any words")]
    if grammar.patterns:
        return [_Unknown(f"{what}'s grammar '{grammar.id}' has patterns, whose answers are "
                         "the words the user said")]
    return [c.value for c in grammar.choices]


def _answers(document: Document, handler: Handler | None, line: int) -> list[_Source]:
    """What ``event.answer`` can be in ``handler``."""
    if handler is not None and handler.kind is HandlerKind.ANSWER:
        call = document.commands.get(handler.key)
        grammar = document.grammars.get(call.grammar or "") if call is not None else None
        return _grammar_values(grammar, f"the Q&A '{handler.key}'")
    if handler is not None and handler.kind is HandlerKind.EVENT and handler.key == "speech":
        grammar = document.grammars.get(handler.match) if handler.match else None
        return _grammar_values(grammar, f"the speech handler at line {handler.loc.line}")
    return [_Unknown(f"line {line} sets it to event.answer outside an answer's handler")]


def _value(compiled: Compiled, document: Document, handler: Handler | None, line: int,
           variable: str) -> list[_Source]:
    """What a variable is given by an expression written at ``line``."""
    if compiled.constant:
        return [to_text(compiled.evaluate(_NOTHING))]
    bare = _bare(compiled)
    if bare is not None:
        return ["@" + bare]
    if compiled.source.strip() == "event.answer":
        return _answers(document, handler, line)
    return [_Unknown(f"'{variable}' is set to {compiled.source.strip()} at line {line}")]


def _sources(document: Document) -> dict[str, list[_Source]]:
    """What each variable may be given, from anywhere in the document."""
    found: dict[str, list[_Source]] = {name: [] for name in document.variables}
    for name, variable in document.variables.items():
        if variable.init is not None:
            found[name] += _value(variable.init, document, None, variable.loc.line, name)
    for action, handler in _actions(document):
        if isinstance(action, Assign):
            found.setdefault(action.name, []).extend(
                _value(action.expr, document, handler, action.loc.line, action.name))
        elif isinstance(action, Request):
            for call in action.calls:
                if call.into:
                    grammar = document.grammars.get(call.grammar or "")
                    found.setdefault(call.into, []).extend(
                        _grammar_values(grammar, f"the Q&A at line {call.loc.line}"))
    return found


class _Values:
    """The values each variable can hold (None: unknown, with why)."""

    def __init__(self, document: Document) -> None:
        self.sources = _sources(document)
        self.done: dict[str, frozenset[str] | _Unknown] = {}

    def of(self, name: str, seen: frozenset[str] = frozenset()) -> frozenset[str] | _Unknown:
        if name in self.done:
            return self.done[name]
        out: set[str] = set()
        for source in self.sources.get(name, []):
            if isinstance(source, _Unknown):
                self.done[name] = source
                return source
            if source.startswith("@"):
                other = source[1:]
                if other in seen or other == name:
                    continue  # (a cycle adds nothing new)
                values = self.of(other, seen | {name})
                if isinstance(values, _Unknown):
                    self.done[name] = values
                    return values
                out |= values
            elif source:
                out.add(source)
        self.done[name] = frozenset(out)
        return self.done[name]


def destinations(document: Document) -> list[Destination]:
    """Every place argument of the document's Commands, in document order, with the places
    it can name (see the module)."""
    values = _Values(document)
    out: list[Destination] = []
    for call in _calls(document):
        for param in _PLACE_PARAMS.get(call.command, ()):
            arg = call.args.get(param)
            if arg is None:
                continue
            if arg.constant:
                name = to_text(arg.evaluate(_NOTHING))
                out.append(Destination(call.command, param, call.loc, frozenset({name} - {""})))
                continue
            bare = _bare(arg)
            held = values.of(bare) if bare is not None else _Unknown(
                f"its {param} is the expression {arg.source.strip()}")
            if isinstance(held, _Unknown):
                out.append(Destination(call.command, param, call.loc, None, held.why))
            else:
                out.append(Destination(call.command, param, call.loc, held))
    return sorted(out, key=lambda d: (d.loc.line, d.loc.col))


def known_places(found: Sequence[Destination]) -> frozenset[str]:
    """Every place the known destinations can name."""
    return frozenset(p for d in found if d.places is not None for p in d.places)


def unknown_destinations(found: Sequence[Destination]) -> list[Destination]:
    """The destinations whose places cannot be known before the document runs."""
    return [d for d in found if d.places is None]


def map_for(document: Document,
            maps: Sequence[tuple[Path, WorldMap]]) -> tuple[Path, WorldMap] | None:
    """The first map that has every place the document can go to, as far as that can be
    known (:func:`destinations`; None: no map has them)."""
    named = known_places(destinations(document))
    for path, world in maps:
        if named <= {p.name for p in world.places}:
            return path, world
    return None
