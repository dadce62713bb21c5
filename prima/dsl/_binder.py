"""What binding a Command asks of the document's builder: a narrow interface, so the
binder (:mod:`._commands`) knows the loader's :class:`~._loader.Builder` only by what it
uses, and the loader imports the binder without the binder importing it back."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from lxml import etree

from prima.record import Record

if TYPE_CHECKING:
    from prima.catalog import Catalog
    from prima.dsl._expr import Compiled
    from prima.dsl._kept import Kept
    from prima.dsl._model import CommandCall, HandlerKind, Loc
    from prima.dsl._profile import RobotProfile
    from prima.errors import Problem
    from prima.vocab import AppKind

__all__ = ["Binder", "Refs", "Spot"]

Spot = tuple[etree._Element, str | None, int]
"""Where to point: (element, None | "#text" | attribute name, character index)."""


@dataclass(repr=False)
class Refs(Record):
    """References collected during the walk, checked once everything is known."""

    gotos: list[tuple[str, Spot]] = field(default_factory=list)
    variables: list[tuple[str, Spot]] = field(default_factory=list)
    grammars: list[tuple[str, Spot]] = field(default_factory=list)
    handlers: list[tuple[HandlerKind, str, Spot, bool | None]] = field(default_factory=list)
    raises: list[tuple[str, Spot]] = field(default_factory=list)
    cancels: list[tuple[str, Spot]] = field(default_factory=list)


class Binder(Protocol):
    """The builder as the binder sees it: the setting a Command is bound in, where its
    problems go, and what it asks to be checked once the whole document is read."""

    profile: RobotProfile
    catalog: Catalog
    kind: AppKind
    max_text: int
    in_handler: bool
    variable_names: dict[str, None]
    variable_key: frozenset[str]
    element_commands: dict[str, str]
    kept: Kept | None
    problems: list[Problem]
    refs: Refs
    places: list[tuple[str, Spot, str, str]]

    def loc(self, spot: Spot) -> Loc: ...

    def error(self, spot: Spot, message: str) -> None: ...

    def warning(self, spot: Spot, message: str) -> None: ...

    def compile(self, spot: Spot, make: Callable[[], Compiled]) -> Compiled | None: ...

    def similar(self, name: str, names: Iterable[str]) -> str | None: ...

    def check_gesture(self, name: str, spot: Spot) -> None: ...

    def literal_place(self, name: str, spot: Spot, command: str, param: str) -> None: ...

    def need_grammar(self, name: str, spot: Spot) -> None: ...

    def need_variable(self, name: str, spot: Spot) -> None: ...

    def add_label(self, label: str, call: CommandCall, spot: Spot) -> None: ...
