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
        the ``request`` it roots: never both), or about an app."""
        self.count += 1
        if self._record is None:
            return
        now = self._clock.now()
        # Built with positional arguments, in field order: a named tuple takes them
        # over twice as fast as keywords, and the mediator makes one per decision.
        if node is None:
            decision = Decision(now, self.count, kind, rule, app, None, tree, None, None,
                                (), (), False, 0, None, detail)
            self._record(decision)
            return
        app = node.app.name
        label = node.commands[0].call.label
        if request:  # all the Commands of the request it roots
            first = request[0]
            decision = Decision(
                now, self.count, kind, rule, app, node.id, node.tree.id, node.name,
                first.id, tuple(c.id for c in request), node.sorted_devices, node.reactive,
                node.iteration, label, detail, tuple(c.call for c in request), before,
                precedes)
        elif command is not None:  # one of its Commands
            decision = Decision(
                now, self.count, kind, rule, app, node.id, node.tree.id, command.spec.name,
                command.id, (command.id,), node.sorted_devices, node.reactive,
                node.iteration, command.call.label, detail, (command.call,), before,
                precedes)
        else:  # the AB itself (most decisions)
            decision = Decision(
                now, self.count, kind, rule, app, node.id, node.tree.id, node.name,
                node.command_ids[0], node.command_ids, node.sorted_devices, node.reactive,
                node.iteration, label, detail, node.calls, before, precedes)
        self._record(decision)
