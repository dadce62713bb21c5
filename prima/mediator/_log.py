"""The decision log: numbers every decision and hands it to the recorder."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from prima.mediator._decisions import Decision, DecisionKind, Rule
from prima.mediator._interface import Clock
from prima.mediator._state import Command, Node

__all__ = ["DecisionLog"]


class DecisionLog:
    """Numbers decisions in order (``seq`` increases by one) and records them.

    Without a recorder nothing is built: the count still moves.
    """

    def __init__(self, clock: Clock, record: Callable[[Decision], None] | None) -> None:
        self._clock = clock
        self._record = record
        self.count = 0
        """How many decisions were made so far."""

    @property
    def recording(self) -> bool:
        """Someone reads the decisions (worth building a detailed text)."""
        return self._record is not None

    def emit(self, kind: DecisionKind, rule: Rule, node: Node | None = None, *,
             app: str | None = None, command: Command | None = None,
             detail: str = "", tree: int | None = None,
             request: Sequence[Command] = (), before: int | None = None,
             precedes: int | None = None) -> None:
        """Record one decision about ``node`` (one of its Commands, or all the Commands of
        the ``request`` it roots), or about an app."""
        self.count += 1
        if self._record is None:
            return
        now = self._clock.now()
        if node is None:
            decision = Decision(t=now, seq=self.count, kind=kind, rule=rule, app=app, tree=tree,
                                detail=detail)
        else:
            commands = tuple(request) or (node.commands if command is None else (command,))
            first = commands[0]
            decision = Decision(
                t=now, seq=self.count, kind=kind, rule=rule, app=node.app.name, ab=node.id,
                tree=node.tree.id, command=node.name if command is None else first.spec.name,
                command_id=first.id, command_ids=tuple(c.id for c in commands),
                devices=node.sorted_devices, reactive=node.reactive, iteration=node.iteration,
                label=node.commands[0].call.label if command is None else first.call.label,
                detail=detail, calls=tuple(c.call for c in commands), before=before,
                precedes=precedes)
        self._record(decision)
