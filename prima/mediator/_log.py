"""The decision log: numbers every decision and hands it to the recorder."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Final

from prima.mediator._decisions import Decision, DecisionKind, Rule
from prima.mediator._state import Command, Node

__all__ = ["DecisionLog"]

_new: Final = tuple.__new__
_REQUEST: Final = DecisionKind.REQUEST  # (read once: from its class, through the enum's metaclass)


class DecisionLog:
    """Numbers decisions in order (``seq`` increases by one) and records them.

    Without a recorder nothing is built: the count still moves.
    """

    def __init__(self, record: Callable[[Decision], None] | None) -> None:
        self._record = record
        self.count = 0
        """How many decisions were made so far."""
        self.news: list[tuple[str, str, dict[str, str]]] = []
        """What applications are to be told once the operation under way settles: an
        app's name, an event's name (suspended, resumed, held) and its data."""
        self.now = 0.0
        """The instant of the operation under way, which every decision carries: the
        mediator reads the clock when an operation begins (one made from a callback
        too, which reads it again)."""

    def tell(self, app: str, event: str, **data: str) -> None:
        """Tell ``app`` (a non-reactive event, once the operation settles)."""
        self.news.append((app, event, data))

    def ab(self, kind: DecisionKind, rule: Rule, node: Node, detail: str = "") -> None:
        """Record one decision about the AB ``node`` itself (most decisions: a start, an
        end, a suspension): :meth:`emit` for that case, with the AB's ``facts``."""
        self.count = count = self.count + 1
        record = self._record
        if record is not None:
            # (its fields as tuples added up: less work than unpacking ``facts`` into one;
            # with no detail, what follows the first four is kept on the AB: ``plain``)
            record(_new(Decision, (self.now, count, kind, rule) + (
                node.facts + (detail, node.calls, None, None) if detail else node.plain)))

    def requested(self, rule: Rule, node: Node, request: Sequence[Command], group: bool,
                  before: Node | None) -> None:
        """Record a request's decision (what :meth:`emit` records for ``REQUEST`` with
        these), positional: one per request. ``request``: its Commands (``group``: as one
        AB), ``node`` the AB it roots, ``before`` its before node. Its detail says how many
        Commands, and where."""
        if self._record is None:
            self.count += 1
            return
        # (the usual request, one Command, in one f-string)
        if len(request) == 1 and not group:
            detail = (f"1 Command(s) before AB{before.id}" if before is not None
                      else "1 Command(s) roots the tree")
        else:
            detail = (f"{len(request)} Command(s) {'as one AB ' if group else ''}"
                      + (f"before AB{before.id}" if before is not None else "roots the tree"))
        before_id = before.id if before is not None else None
        if len(request) != 1:
            self.emit(_REQUEST, rule, node, detail=detail, request=request, before=before_id)
            return
        # (one Command: the AB's own, so the decision is about the AB: its facts)
        self.count = count = self.count + 1
        self._record(_new(Decision, (self.now, count, _REQUEST, rule) + node.facts
                          + (detail, node.calls, before_id, None)))

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
        now = self.now
        # Built from a tuple in field order (``tuple.__new__``, what the named tuple's own
        # constructor does, without its keyword handling): one per decision.
        if node is None:
            decision = _new(Decision, (now, self.count, kind, rule, app, None, tree, None, None,
                                       (), (), False, 0, None, detail, (), None, None))
        elif request:  # all the Commands of the request it roots
            if len(request) == 1 == len(node.commands) and node.commands[0] is request[0]:
                decision = _new(Decision, (now, self.count, kind, rule, *node.facts, detail,
                                           node.calls, before, precedes))
            else:
                first = request[0]
                decision = _new(Decision, (
                    now, self.count, kind, rule, node.app.name, node.id, node.tree.id,
                    node.name, first.id, tuple([c.id for c in request]), node.sorted_devices,
                    node.reactive, node.iteration, node.commands[0].call.label, detail,
                    tuple([c.call for c in request]), before, precedes))
        elif command is not None:  # one of its Commands
            decision = _new(Decision, (
                now, self.count, kind, rule, node.app.name, node.id, node.tree.id,
                command.spec.name, command.id, (command.id,), node.sorted_devices,
                node.reactive, node.iteration, command.call.label, detail, (command.call,),
                before, precedes))
        else:  # the AB itself
            decision = _new(Decision, (now, self.count, kind, rule, *node.facts, detail,
                                       node.calls, before, precedes))
        self._record(decision)
