"""Accepting a request: checking it, then finding its before node (rule 3, 6).

The before node is decided in this order:

1. ``follows=X`` within ``end_grace`` of X's end: a child of X, in X's tree
   (rule ``end-event``; CS exceptions (a) and (b)).
2. As soon as possible: cancel the app's own not-yet-started work in trees
   that share a device with the request (a running feedback Command stops
   after its current iteration); the newest running AB there that shares a
   device, else the newest cancelled node, is the before node; with no such
   tree the request roots a new one (rule ``asap`` in every case).
3. After latest: the app's latest Command if still in working memory
   (rule ``after-latest``); inside an open stream or block, its tree even if
   the latest Command already finished (rule ``stream``); else a new tree
   (rule ``new-tree``).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

from prima.catalog import Catalog, CommandSpec, Priority
from prima.errors import MediationError
from prima.mediator._decisions import DecisionKind, Rule
from prima.mediator._holds import Holds
from prima.mediator._interface import Call, CommandId, Driver, Request
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import IN_MEMORY, App, Command, Node, NodeState, Tree

if TYPE_CHECKING:
    from prima.mediator._mediator import MediatorConfig
from prima.vocab import AppKind, RunningOrder

__all__ = ["Intake", "Link"]

Specs = list[tuple[CommandSpec, frozenset[str]]]


@dataclass
class Link:
    """Where a request's root goes."""

    rule: Rule
    parent: Node | None = None
    tree: Tree | None = None
    enter_now: bool = True
    """The root enters the waiting list at once (no before node still to run)."""
    parent_finished: bool = False
    """The root ranks as 'parent just finished'."""
    reactive_allowed: bool = True


class Intake:
    """Checks requests, links them into working memory, and cancels what they replace."""

    def __init__(self, catalog: Catalog, apps: Mapping[str, App], wm: WorkingMemory,
                 holds: Holds, log: DecisionLog, driver: Driver, config: MediatorConfig,
                 turns: bool) -> None:
        self._catalog = catalog
        self._apps = apps
        self._wm = wm
        self._holds = holds
        self._log = log
        self._driver = driver
        self._end_grace = config.end_grace
        self._turns = turns
        """The connect-channel policy may turn the robot to the user (else no AB is
        ``turnable``, and it is not worked out)."""
        self.next_command: CommandId = 1
        """The id the next requested Command will get."""
        self._next_seq = 1
        self._recent: dict[CommandId, Command] = {}
        self._recent_q: deque[Command] = deque()

    # ------------------------------------------------------------------ checks
    def check(self, request: Request) -> tuple[App, Specs]:
        """Validate a request before anything changes; the app and each call's spec/devices."""
        app = self._apps.get(request.app)
        if app is None:
            raise MediationError(f"unknown application {request.app!r}: register it first")
        if not request.calls:
            raise MediationError(f"{request.app}: a request needs at least one Command")
        if not isinstance(request.order, RunningOrder):
            raise MediationError(f"{request.app}: unknown running order {request.order!r}")
        needed = 1 if request.group else len(request.calls)
        if app.live + needed > app.budgets.waiting:
            raise MediationError(
                f"{request.app}: more than {app.budgets.waiting} behaviors would be waiting "
                "or running (its waiting budget)")
        out: Specs = []
        for call in request.calls:
            spec = self._catalog.get(call.command)
            if spec is None:
                known = ", ".join(sorted(self._catalog.commands))
                raise MediationError(
                    f"{request.app}: unknown Command {call.command!r} (known: {known})")
            self._check_call(app, request, spec, call.extra_devices, bool(call.extra))
            out.append((spec, spec.devices_for(call.args) | call.extra_devices))
        return app, out

    def _check_call(self, app: App, request: Request, spec: CommandSpec,
                    extra_devices: frozenset[str], extra_args: bool) -> None:
        if app.kind is AppKind.EA and spec.robot_specific:
            raise MediationError(
                f"{request.app}: {spec.name} is robot-specific; only the FA may use it")
        if app.kind is AppKind.EA and extra_args:
            raise MediationError(
                f"{request.app}: additional arguments to {spec.name} are FA-only")
        unknown = extra_devices - self._catalog.devices
        if unknown:
            raise MediationError(
                f"{request.app}: {spec.name} names unknown devices {sorted(unknown)}")
        if request.group and spec.feedback and len(request.calls) > 1:
            raise MediationError(
                f"{request.app}: feedback Command {spec.name} cannot be grouped into one AB "
                "(each loop iteration is its own AB)")

    # ------------------------------------------------------------------ accept
    def accept(self, app: App, request: Request, specs: Specs,
               now: float) -> tuple[tuple[CommandId, ...], list[Command]]:
        """Put a checked request in working memory; its Command ids, and the Commands
        it cancelled (their apps are told once the request is in)."""
        seq = self._next_seq
        self._next_seq += 1
        cid = self.next_command
        cmds = [Command(cid + i, app, call, spec, on_interrupt=request.on_interrupt)
                for i, (call, (spec, _d)) in enumerate(zip(request.calls, specs, strict=True))]
        self.next_command = cid + len(cmds)
        all_devices = (specs[0][1] if len(specs) == 1
                       else frozenset().union(*(d for _s, d in specs)))
        link, cancelled = self._link(app, request, all_devices, now)
        tree = link.tree if link.tree is not None else self._wm.new_tree(app)
        # before its nodes are filed, so that they rank as its reaction
        if ((request.reactive or request.reaction) and link.reactive_allowed
                and self._wm.react(tree, seq)
                and tree.parked):
            self._holds.unpark_all()  # a stream hold no longer keeps the tree (7.2)
        root = self._build(app, tree, request, cmds, specs, link, seq)
        app.latest = cmds[-1]
        self._holds.requested(app, tree)
        detail = ""
        if self._log.recording:
            before = f"before AB{link.parent.id}" if link.parent is not None else "roots the tree"
            grouped = "as one AB " if request.group else ""
            detail = f"{len(cmds)} Command(s) {grouped}{before}"
        self._log.emit(DecisionKind.REQUEST, link.rule, root, detail=detail, request=cmds,
                       before=link.parent.id if link.parent is not None else None)
        if link.enter_now:
            self._wm.enter_waiting(root, parent_finished=link.parent_finished)
        return tuple([c.id for c in cmds]), cancelled

    def _link(self, app: App, request: Request, devices: frozenset[str],
              now: float) -> tuple[Link, list[Command]]:
        cancelled: list[Command] = []
        link = self._link_follows(app, request, now) if request.follows is not None else None
        if request.order is RunningOrder.ASAP:
            # A newer request wins even when it is made in an end handler: the app's
            # own waiting work on its devices is cancelled; the end-event link only
            # chooses the tree when nothing of the app was in the way.
            asap, cancelled = self._link_asap(app, devices, now)
            if link is None or asap.parent is not None:
                link = asap
        if link is None:
            link = self._link_after_latest(app)
        return link, cancelled

    def _build(self, app: App, tree: Tree, request: Request, cmds: list[Command],
               specs: Specs, link: Link, seq: int) -> Node:
        """The request's nodes: one AB (grouped) or a chain; returns the root."""
        wm = self._wm
        reactive = request.reactive and link.reactive_allowed
        turns = self._turns and request.face_user
        if request.group:
            prio = min((s.priority for s, _d in specs), default=Priority.HIGH)
            devices = frozenset().union(*(d for _s, d in specs))
            root = wm.new_node(app, tree, tuple(cmds), devices, prio, reactive, seq)
            root.turnable = turns and _turnable(root, link.parent)
            wm.link(link.parent, root)
            return root
        parent = link.parent
        nodes: list[Node] = []
        for c, (spec, devs) in zip(cmds, specs, strict=True):
            node = wm.new_node(app, tree, (c,), devs, spec.priority, reactive and not nodes, seq)
            node.turnable = turns and _turnable(node, parent)
            wm.link(parent, node)
            nodes.append(node)
            parent = node
        return nodes[0]

    def insert_before(self, x: Node, call: Call, spec: CommandSpec, rule: Rule,
                      detail: str) -> Node:
        """Put an AB of the mediator's own (a policy's) before the waiting AB ``x``, in
        its tree and with its rank: ``x`` waits for it. Its Command is the app's but
        internal (the app hears nothing of it)."""
        wm = self._wm
        cmd = Command(self.next_command, x.app, call, spec, internal=rule)
        self.next_command += 1
        parent_finished = x.id in wm.pjf
        node = wm.new_node(x.app, x.tree, (cmd,), spec.devices_for(call.args), spec.priority,
                           x.reactive, x.seq)
        parent = wm.nodes.get(x.parent) if x.parent is not None else None
        if parent is not None and x in parent.children:
            parent.children[parent.children.index(x)] = node
        node.parent, node.children, x.parent = x.parent, [x], node.id
        wm.unwait(x)
        self._log.emit(DecisionKind.REQUEST, rule, node, detail=detail, request=[cmd],
                       before=node.parent, precedes=x.commands[0].id)
        wm.enter_waiting(node, parent_finished=parent_finished)
        return node

    # ------------------------------------------------------------------ links
    def _link_follows(self, app: App, request: Request, now: float) -> Link | None:
        """CS exceptions (a)/(b): a request made while handling X's end stays in X's tree."""
        self._prune(now)
        cmd = self._recent.get(request.follows) if request.follows is not None else None
        if cmd is None or cmd.app is not app or cmd.node is None:
            return None
        if now - cmd.ended_at > self._end_grace:
            return None
        return Link(Rule.END_EVENT, cmd.node, cmd.node.tree, enter_now=True,
                    parent_finished=True, reactive_allowed=False)

    def _link_asap(self, app: App, devices: frozenset[str],
                   now: float) -> tuple[Link, list[Command]]:
        """As soon as possible: cancel the app's own trees that share a device."""
        running: Node | None = None
        last: Node | None = None
        cancelled: list[Command] = []
        on = app.trees_on
        sharing = {t.id: t for d in devices if d in on for t in on[d].values()}
        for tid in sorted(sharing):  # the app's trees with a node that shares a device
            for n in list(sharing[tid].nodes.values()):
                if n.state is NodeState.RUNNING:
                    if n.feedback and not n.commands[0].cut:
                        n.commands[0].cut = True
                    if n.devices & devices and (running is None or n.id > running.id):
                        running = n
                elif n.state in IN_MEMORY:
                    cancelled.extend(self.cancel(n, Rule.ASAP, now))
                    if last is None or n.id > last.id:
                        last = n
        if running is not None:
            return Link(Rule.ASAP, running, running.tree, enter_now=False), cancelled
        if last is not None:
            return Link(Rule.ASAP, last, last.tree, enter_now=True), cancelled
        return Link(Rule.ASAP), cancelled  # nothing shares a device: a new tree at once

    def _link_after_latest(self, app: App) -> Link:
        """Rule 3, after latest (with the explicit-stream exception, rule 6c)."""
        latest = app.latest
        node = latest.node if latest is not None else None
        if node is not None and node.state in IN_MEMORY:
            return Link(Rule.AFTER_LATEST, node, node.tree, enter_now=False)
        if node is not None and self._holds.continues(app, node.tree):
            return Link(Rule.STREAM, node, node.tree, enter_now=True, parent_finished=True)
        return Link(Rule.NEW_TREE)

    # ------------------------------------------------------------------ ends
    def cancel(self, node: Node, rule: Rule, now: float) -> list[Command]:
        """Cancel a not-yet-started node; returns its Commands (for callbacks)."""
        for cmd in node.commands:
            cmd.cancelled = True
            self._log.emit(DecisionKind.CANCEL, rule, node, command=cmd)
            if node.iteration > 0:
                self._driver.abandon(cmd.id)
        self._holds.cancelled(node)
        self._wm.cancel(node, now)
        return list(node.commands)

    def ended(self, commands: tuple[Command, ...], now: float) -> None:
        """Commands ended: requests that follow them are linked for ``end_grace``."""
        for cmd in commands:
            cmd.ended = True
            cmd.ended_at = now
            self._recent[cmd.id] = cmd
            self._recent_q.append(cmd)
        self._prune(now)

    def _prune(self, now: float) -> None:
        horizon = now - self._end_grace
        q = self._recent_q
        while q and q[0].ended_at < horizon:
            self._recent.pop(q.popleft().id, None)


def _turnable(node: Node, before: Node | None) -> bool:
    """An utterance the connect-channel policy may turn the robot for: it does not
    orient the robot itself, and the AB before it in its stream did not aim the
    robot at something on purpose (the words are about that)."""
    return (not any(c.spec.orients for c in node.commands)
            and any(c.spec.spoken(c.call.args) for c in node.commands)
            and (before is None or not any(c.spec.aims for c in before.commands)))
