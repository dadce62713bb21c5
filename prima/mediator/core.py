"""The mediator: accepts requests, selects ABs, drives devices, records why.

Every public method is one *operation*. Operations may nest: an
application's listener or the driver may call back into the mediator while
it is calling them. Working memory is updated at once, but selection runs
only when the outermost operation completes, round after round until nothing
more can start, so the result does not depend on how callbacks nest.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from typing import Callable

from prima.errors import MediationError
from prima.catalog import Catalog, CommandSpec, Priority
from prima.mediator.decisions import Decision, DecisionKind, Rule
from prima.mediator.interface import (
    AbId,
    AppKind,
    AppListener,
    AtomicBehavior,
    Clock,
    CommandId,
    Driver,
    Event,
    Outcome,
    Request,
    RunningOrder,
)
from prima.mediator.holds import HoldsMixin
from prima.mediator.memory import WorkingMemory
from prima.mediator.requests import IN_MEMORY, Link, check_request, link_after_latest
from prima.mediator.rounds import RoundsMixin
from prima.mediator.snapshot import Snapshot, take
from prima.mediator.state import NodeState, _App, _Command, _Node

__all__ = ["Mediator", "MediatorConfig"]


class _Op:
    """One public operation: selection runs when the outermost one completes."""

    __slots__ = ("_m", "_outer")

    def __init__(self, mediator: Mediator) -> None:
        self._m = mediator
        self._outer = False

    def __enter__(self) -> None:
        m = self._m
        self._outer = m._depth == 0 and not m._settling
        m._depth += 1

    def __exit__(self, exc_type: object, exc: object, tb: object) -> bool:
        m = self._m
        m._depth -= 1
        if exc_type is None and self._outer:
            m._settle()
        return False


@dataclass(frozen=True)
class MediatorConfig:
    """Tunable bounds of the mediation rules."""

    end_grace: float = 0.5
    """Seconds after a Command's end within which a ``follows`` request stays in
    its tree (CS exceptions (a)/(b)). A handler that requests at once is always
    in time; one that waits on a timer or polls is not."""

    max_stream_hold: float = 30.0
    """Upper bound on an explicit stream's hold, whatever the document asks: the
    other application's response speed stays bounded (rule 6c)."""

    max_block_watchdog: float = 60.0
    """Upper bound on a begin/end block's watchdog, whatever the document asks:
    a runaway block cannot starve the other application (rule 3)."""

    def to_dict(self) -> dict[str, object]:
        return {"end_grace": self.end_grace, "max_stream_hold": self.max_stream_hold,
                "max_block_watchdog": self.max_block_watchdog}


class Mediator(HoldsMixin, RoundsMixin):
    """PRIMA's mediator (MISSION.md sections 3-5)."""

    def __init__(self, catalog: Catalog, driver: Driver, clock: Clock, *,
                 config: MediatorConfig = MediatorConfig(),
                 record: Callable[[Decision], None] | None = None) -> None:
        self._catalog = catalog
        self._driver = driver
        self._clock = clock
        self._config = config
        self._record_cb = record
        self._wm = WorkingMemory()
        self._wm.channel_devices = frozenset().union(
            *(c.devices for c in catalog if c.breaks_cc))
        self._apps: dict[str, _App] = {}
        self._parked: list[_Node] = []
        self._app_order = 0
        self._next_command = 1
        self._next_seq = 1
        self._seq = 0
        self._recent: dict[CommandId, _Command] = {}
        self._recent_q: deque[_Command] = deque()
        self._depth = 0
        self._settling = False
        self._decisions = 0

    # ================================================================ plumbing
    @property
    def _apps_with_holds(self) -> bool:
        """Some app has an open stream or block (else no AB can be held)."""
        for app in self._apps.values():
            if app.stream is not None or app.block is not None:
                return True
        return False

    @property
    def catalog(self) -> Catalog:
        return self._catalog

    @property
    def config(self) -> MediatorConfig:
        return self._config

    @property
    def decisions(self) -> int:
        """How many decisions were recorded so far."""
        return self._decisions

    def apps(self) -> tuple[str, ...]:
        """Registered applications, in registration order."""
        return tuple(self._apps)

    def _op(self) -> _Op:
        return _Op(self)

    def _emit(self, kind: DecisionKind, rule: Rule, node: _Node | None = None, *,
              app: str | None = None, command: _Command | None = None,
              detail: str = "", tree: int | None = None) -> None:
        self._seq += 1
        self._decisions += 1
        if self._record_cb is None:
            return
        if node is None:
            d = Decision._build(self._clock.now(), self._seq, kind, rule, app, None, tree, None,
                                None, (), (), False, 0, None, detail)
        elif command is None:
            d = Decision._build(self._clock.now(), self._seq, kind, rule, node.app.name, node.id,
                                node.tree.id, node.name, node.command_ids[0], node.command_ids,
                                node.sorted_devices, node.reactive, node.iteration,
                                node.commands[0].call.label, detail, node.calls)
        else:
            d = Decision._build(self._clock.now(), self._seq, kind, rule, node.app.name, node.id,
                                node.tree.id, command.spec.name, command.id, (command.id,),
                                node.sorted_devices, node.reactive, node.iteration,
                                command.call.label, detail, (command.call,))
        self._record_cb(d)

    def _call(self, app: _App, method: str, *args: object) -> None:
        """Call an app's listener; an exception removes the app, never the mediator."""
        if not app.alive:
            return
        try:
            getattr(app.listener, method)(*args)
        except Exception as exc:  # noqa: BLE001 - a failing app must not stop the robot
            if app.alive:
                self._emit(DecisionKind.ERROR, Rule.APP_FAILURE, app=app.name,
                           detail=f"{method}: {type(exc).__name__}: {exc}")
                self._unload(app, Rule.APP_FAILURE)

    # ============================================================ applications
    def register(self, app: str, kind: AppKind, listener: AppListener) -> None:
        """Load an application: one FA, at most one EA (swap: unregister the old EA first)."""
        kind = AppKind(kind)
        if not app:
            raise MediationError("an application needs a name")
        if app in self._apps:
            raise MediationError(f"application {app!r} is already registered")
        for other in self._apps.values():
            if other.kind is kind:
                raise MediationError(
                    f"cannot register {app!r}: {kind.name} {other.name!r} is loaded "
                    f"(one FA, at most one EA; unregister {other.name!r} first)")
        with self._op():
            self._app_order += 1
            self._apps[app] = _App(app, kind, listener, self._app_order)
            self._emit(DecisionKind.REGISTER, Rule.REGISTER, app=app, detail=kind.name)

    def unregister(self, app: str) -> None:
        """Unload an application: cancel its waiting work, free its holds; running ABs finish."""
        a = self._apps.get(app)
        if a is None:
            raise MediationError(f"unknown application {app!r}")
        with self._op():
            self._unload(a, Rule.UNLOAD)

    def _unload(self, app: _App, rule: Rule) -> None:
        now = self._clock.now()
        app.alive = False
        self._apps.pop(app.name, None)
        for tree in sorted(app.trees.values(), key=lambda t: t.id):
            for node in list(tree.nodes.values()):
                if node.state is NodeState.RUNNING:
                    if node.feedback:
                        node.commands[0].cut = True
                else:
                    self._cancel_node(node, Rule.UNLOAD, now)
        if app.stream is not None:
            self._end_stream(app, Rule.UNLOAD)
        if app.block is not None:
            self._end_block(app, Rule.UNLOAD)
        self._emit(DecisionKind.UNREGISTER, rule, app=app.name)

    def _cancel_node(self, node: _Node, rule: Rule, now: float) -> list[_Command]:
        """Cancel a not-yet-started node; returns its Commands (for callbacks)."""
        for cmd in node.commands:
            cmd.cancelled = True
            self._emit(DecisionKind.CANCEL, rule, node, command=cmd)
            if node.iteration > 0:
                self._driver.abandon(cmd.id)
        self._wm.cancel(node, now)
        return list(node.commands)

    # ================================================================ requests
    def submit(self, request: Request) -> tuple[CommandId, ...]:
        """Accept a request; returns one Command id per Call (MISSION.md rule 3)."""
        app, specs = check_request(self._catalog, self._apps, request)
        with self._op():
            return self._accept(app, request, specs)

    def _accept(self, app: _App, request: Request,
                specs: list[tuple[CommandSpec, frozenset[str]]]) -> tuple[CommandId, ...]:
        now = self._clock.now()
        seq = self._next_seq
        self._next_seq += 1
        cid = self._next_command
        cmds = [_Command(cid + i, app, call, spec)
                for i, (call, (spec, _d)) in enumerate(zip(request.calls, specs))]
        self._next_command = cid + len(cmds)
        if len(specs) == 1:
            all_devices = specs[0][1]
        else:
            all_devices = frozenset().union(*(d for _s, d in specs))
        cancelled: list[_Command] = []
        link = self._link_follows(app, request, now) if request.follows is not None else None
        if request.order is RunningOrder.ASAP:
            # A newer request wins even when it is made in an end handler: the app's
            # own waiting work on its devices is cancelled; the end-event link only
            # chooses the tree when nothing of the app was in the way.
            asap, cancelled = self._link_asap(app, all_devices, now)
            if link is None or asap.parent is not None:
                link = asap
        if link is None:
            link = link_after_latest(app)
        tree = link.tree if link.tree is not None else self._wm.new_tree(app)
        reactive = request.reactive and link.reactive_allowed
        wm = self._wm
        if request.group:
            prio = min((s.priority for s, _d in specs), default=Priority.HIGH)
            root = wm.new_node(app, tree, tuple(cmds), all_devices, prio, reactive, seq)
            wm.link(link.parent, root)
        else:
            parent = link.parent
            root = None
            for c, (spec, devs) in zip(cmds, specs):
                node = wm.new_node(app, tree, (c,), devs, spec.priority,
                                   reactive and root is None, seq)
                wm.link(parent, node)
                if root is None:
                    root = node
                parent = node
        if root is None:  # pragma: no cover - check_request guarantees a call
            raise MediationError("empty request")
        app.latest = cmds[-1]
        if app.stream is not None:
            app.stream.tree = tree
        if app.block is not None and not app.block.expired:
            app.block.tree = tree
        if self._record_cb is not None:
            before = f"before AB{link.parent.id}" if link.parent is not None else "roots the tree"
            grouped = "as one AB " if request.group else ""
            self._emit(DecisionKind.REQUEST, link.rule, root,
                       detail=f"{len(cmds)} Command(s) {grouped}{before}")
        else:
            self._emit(DecisionKind.REQUEST, link.rule, root)
        if link.enter_now:
            wm.enter_waiting(root, parent_finished=link.parent_finished)
        for cmd in cancelled:
            self._call(cmd.app, "command_cancelled", cmd.id)
        return tuple(c.id for c in cmds)

    def _link_follows(self, app: _App, request: Request, now: float) -> Link | None:
        """CS exceptions (a)/(b): a request made while handling X's end stays in X's tree."""
        self._prune_recent(now)
        cmd = self._recent.get(request.follows)
        if cmd is None or cmd.app is not app or cmd.node is None:
            return None
        if now - cmd.ended_at > self._config.end_grace:
            return None
        return Link(Rule.END_EVENT, cmd.node, cmd.node.tree, enter_now=True,
                    parent_finished=True, reactive_allowed=False)

    def _prune_recent(self, now: float) -> None:
        horizon = now - self._config.end_grace
        q = self._recent_q
        while q and q[0].ended_at < horizon:
            self._recent.pop(q.popleft().id, None)

    def _link_asap(self, app: _App, devices: frozenset[str],
                   now: float) -> tuple[Link, list[_Command]]:
        """As soon as possible: cancel the app's own trees that share a device."""
        running: _Node | None = None
        last: _Node | None = None
        cancelled: list[_Command] = []
        for tree in sorted(app.trees.values(), key=lambda t: t.id):
            nodes = list(tree.nodes.values())
            if not any(n.devices & devices for n in nodes):
                continue
            for n in nodes:
                if n.state is NodeState.RUNNING:
                    if n.feedback and not n.commands[0].cut:
                        n.commands[0].cut = True
                    if n.devices & devices and (running is None or n.id > running.id):
                        running = n
                elif n.state in IN_MEMORY:
                    cancelled.extend(self._cancel_node(n, Rule.ASAP, now))
                    if last is None or n.id > last.id:
                        last = n
        if running is not None:
            return Link(Rule.ASAP, running, running.tree, enter_now=False), cancelled
        if last is not None:
            return Link(Rule.ASAP, last, last.tree, enter_now=True), cancelled
        return Link(Rule.ASAP), cancelled  # nothing shares a device: a new tree at once

    # ================================================================= driver
    def finish(self, ab_id: AbId, outcome: Outcome = Outcome()) -> None:
        """The driver reports an AB's end (MISSION.md rule 3, feedback iterations)."""
        node = self._wm.nodes.get(ab_id)
        if node is None or node.state is not NodeState.RUNNING:
            raise MediationError(f"AB{ab_id} is not running")
        with self._op():
            self._end(node, outcome)

    def _end(self, node: _Node, outcome: Outcome) -> None:
        now = self._clock.now()
        wm = self._wm
        children = wm.end(node, now)
        detail = ""
        if node.feedback:
            detail = "terminal" if outcome.terminal else "not terminal"
        self._emit(DecisionKind.END, Rule.COMPLETED, node, detail=detail)
        app = node.app
        cmd0 = node.commands[0]
        ended: tuple[_Command, ...] = ()
        cancelled: _Command | None = None
        if node.feedback and not outcome.terminal and not cmd0.cut:
            # Insert the next iteration between this one and the next Command.
            nxt = wm.new_node(app, node.tree, node.commands, node.devices, node.priority,
                              False, node.seq, node.iteration + 1)
            nxt.parent = node.id
            nxt.children = children
            for c in children:
                c.parent = nxt.id
            children = []
            wm.enter_waiting(nxt, parent_finished=True)
        elif node.feedback and not outcome.terminal:
            cancelled = cmd0
            cmd0.cancelled = True
            self._emit(DecisionKind.CANCEL, Rule.ASAP if app.alive else Rule.UNLOAD, node,
                       detail="feedback loop stopped between iterations")
            self._driver.abandon(cmd0.id)
        else:
            ended = node.commands
            for cmd in ended:
                cmd.ended = True
                cmd.ended_at = now
                self._recent[cmd.id] = cmd
                self._recent_q.append(cmd)
            self._prune_recent(now)  # ended Commands are kept only for the end grace
        for child in children:
            if child.state is NodeState.PENDING:
                wm.enter_waiting(child, parent_finished=True)
        wm.leave(node)
        if cancelled is not None:
            self._call(app, "command_cancelled", cancelled.id)
        for cmd in ended:
            self._call(app, "command_ended", cmd.id, outcome)

    # ================================================================= events
    def post(self, event: Event) -> None:
        """Broadcast a predefined or robot event to every registered app (rule 5)."""
        with self._op():
            for app in list(self._apps.values()):
                self._call(app, "event", event)

    # ================================================================ looking
    def snapshot(self) -> Snapshot:
        """A frozen, comparable view of working memory."""
        return take(self._clock.now(), self._wm, self._apps.values())

    @staticmethod
    def _ab(node: _Node) -> AtomicBehavior:
        # Built without the frozen __init__ (hot path; AtomicBehavior has no checks).
        ab = object.__new__(AtomicBehavior)
        object.__setattr__(ab, "__dict__", {
            "id": node.id, "app": node.app.name, "tree": node.tree.id,
            "calls": tuple(c.call for c in node.commands), "command_ids": node.command_ids,
            "devices": node.devices, "iteration": node.iteration, "reactive": node.reactive})
        return ab
