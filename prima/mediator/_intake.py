"""Accepting a request: checking it, then finding its before node (rule 3, 6).

The before node is decided in this order:

1. ``follows=X`` within ``end_grace`` of X's end: a child of X, in X's tree
   (rule ``end-event``; CS exceptions (a) and (b)).
2. As soon as possible: cancel the app's own not-yet-started work in trees
   that share a device with the request (a running feedback Command stops
   after its current iteration); the newest running AB there that shares a
   device with the request's first AB (docs/rules.md 7.6 (2): never one on
   devices it does not use), else the newest cancelled node, is the before
   node; with no such tree the request roots a new one (rule ``asap`` in every
   case).
3. After latest: the app's latest Command if still in working memory
   (rule ``after-latest``); inside an open stream or block, its tree even if
   the latest Command already finished (rule ``stream``); else a new tree
   (rule ``new-tree``).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping, Sequence
from typing import Final

from prima.catalog import Catalog, CommandSpec, Param, Priority
from prima.errors import MediationError
from prima.mediator._config import MediatorConfig
from prima.mediator._decisions import DecisionKind, Rule
from prima.mediator._holds import Holds
from prima.mediator._interface import Call, CommandId, Driver, Request
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import IN_MEMORY, App, Command, Node, NodeState, Tree
from prima.vocab import AppKind, RunningOrder

__all__ = ["Intake", "Link"]

Specs = list[tuple[CommandSpec, frozenset[str], Priority]]
"""Each call's spec, the devices it occupies and its priority (what ``check`` found)."""


Link = tuple[Rule, Node | None, Tree | None, bool, bool, bool]
"""Where a request's root goes: ``(rule, parent, tree, enter_now, parent_finished,
reactive_allowed)``: the rule that links it, its before node and its tree (None: a new
tree), whether it enters the waiting list at once (no before node still to run), whether
it ranks as 'parent just finished', and whether it may be reactive. (A plain tuple, read
once by ``Intake.accept``: a named tuple costs several times more to build, and one is
built for most requests.)"""

_NEW_TREE: Final[Link] = (Rule.NEW_TREE, None, None, True, False, True)
_ASAP_NEW_TREE: Final[Link] = (Rule.ASAP, None, None, True, False, True)
_NONE_CANCELLED: Final[tuple[Command, ...]] = ()
# (enum members read once: reading one from its class goes through the enum's
# metaclass, many times slower than a global)
_RUNNING: Final = NodeState.RUNNING
_END_EVENT: Final = Rule.END_EVENT
_ASAP_RULE: Final = Rule.ASAP
_AFTER_LATEST: Final = Rule.AFTER_LATEST
_STREAM: Final = Rule.STREAM
_CANCEL: Final = DecisionKind.CANCEL
_EA: Final = AppKind.EA
_ASAP: Final = RunningOrder.ASAP
_NO_PARAMS: Final[tuple[Param, ...]] = ()


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
        self._answer_hold = config.max_answer_hold
        """How long a reaction to the user's own action may keep the streams it
        interrupted waiting before its first words (docs/rules.md 7.6 (1))."""
        self._user_first = config.reactions
        """The reactions policy: a reaction to the user's own action goes first."""
        self._exchange = config.exchange
        """The exchange policy: a reply to an answer belongs to the exchange."""
        self._turns = turns
        """The connect-channel policy may turn the robot to the user (else no AB is
        ``turnable``, and it is not worked out)."""
        self.next_command: CommandId = 1
        """The id the next requested Command will get."""
        self._next_seq = 1
        self._specs: dict[str, tuple[CommandSpec, tuple[Param, ...], Priority]] = {}
        """Command name -> its spec, its parameters that add devices, its priority (the
        catalog never changes: looked up once)."""
        self._recent: dict[CommandId, Command] = {}
        """Commands that ended within ``end_grace``, by id (what ``follows`` may name).

        A Command's ``node`` is looked up only through here (a request that follows its
        end) and through its app's ``latest`` (after latest). Once it is done (ended or
        cancelled) and in neither, it is *forgotten*: its ``node`` is set to None. Its
        node and it point at each other: without that, every finished AB would be freed
        only by the cyclic garbage collector, whose collections its allocations trigger."""
        self._recent_q: deque[Command] = deque()

    # ------------------------------------------------------------------ checks
    def check(self, name: str, calls: Sequence[Call], order: RunningOrder,
              group: bool) -> tuple[App, Specs]:
        """Validate a request (its app, calls, order and grouping) before anything
        changes; the app and each call's spec, devices and priority."""
        app = self._apps.get(name)
        if app is None:
            raise MediationError(f"unknown application {name!r}: register it first")
        if not calls:
            raise MediationError(f"{name}: a request needs at least one Command")
        if not isinstance(order, RunningOrder):
            raise MediationError(f"{name}: unknown running order {order!r}")
        needed = 1 if group else len(calls)
        if app.live + needed > app.budgets.waiting:
            raise MediationError(
                f"{name}: more than {app.budgets.waiting} behaviors would be waiting "
                "or running (its waiting budget)")
        out: Specs = []
        known = self._specs
        for call in calls:
            found = known.get(call.command)
            if found is None:
                found = self._spec(name, call.command)
            spec, params, priority = found
            extra_devices = call.extra_devices
            if app.kind is _EA:
                if spec.robot_specific:
                    raise MediationError(
                        f"{name}: {spec.name} is robot-specific; only the FA may use it")
                if call.extra:
                    raise MediationError(
                        f"{name}: additional arguments to {spec.name} are FA-only")
            if extra_devices:
                unknown = extra_devices - self._catalog.devices
                if unknown:
                    raise MediationError(
                        f"{name}: {spec.name} names unknown devices {sorted(unknown)}")
            if group and spec.feedback and len(calls) > 1:
                raise MediationError(
                    f"{name}: feedback Command {spec.name} cannot be grouped into one "
                    "AB (each loop iteration is its own AB)")
            # (``spec.devices_for``, asked only when a parameter can add devices)
            devices = spec.devices_for(call.args) if params else spec.devices
            if extra_devices:
                devices = devices | extra_devices
            out.append((spec, devices, priority))
        return app, out

    def _spec(self, name: str, command: str) -> tuple[CommandSpec, tuple[Param, ...],
                                                             Priority]:
        """A Command's spec, its parameters that add devices, and its priority, looked up
        in the catalog once (it never changes); an unknown Command is an error."""
        spec = self._catalog.get(command)
        if spec is None:
            known = ", ".join(sorted(self._catalog.commands))
            raise MediationError(
                f"{name}: unknown Command {command!r} (known: {known})")
        params = tuple(p for p in spec.params if p.devices) or _NO_PARAMS
        found = self._specs[command] = (spec, params, spec.priority)
        return found

    # ------------------------------------------------------------------ accept
    def accept(self, request: Request,
               now: float) -> tuple[tuple[CommandId, ...], Sequence[Command]]:
        """Check a request (:meth:`check`: nothing changes if it fails), then put it in
        working memory; its Command ids, and the Commands it cancelled (their apps are
        told once the request is in)."""
        # (its fields unpacked once, here: a named tuple's fields are slow to read one by
        # one, and it unpacks in several times the time a plain tuple takes)
        name, calls, order, group, reactive, reaction, follows, face_user, on_interrupt, \
            user = request
        app, specs = self.check(name, calls, order, group)
        seq = self._next_seq
        self._next_seq = seq + 1
        cid = self.next_command
        one = len(specs) == 1  # (one call: the usual request)
        if one:
            spec, all_devices, prio = specs[0]
            last = Command(cid, app, calls[0], spec, None, on_interrupt)
            cmds: tuple[Command, ...] = (last,)  # (its AB's ``commands`` too)
            self.next_command = cid + 1
        else:
            cmds = tuple([Command(cid + i, app, call, spec, None, on_interrupt)
                          for i, (call, (spec, _d, _p))
                          in enumerate(zip(calls, specs, strict=True))])
            last = cmds[-1]
            all_devices = frozenset().union(*(d for _s, d, _p in specs))
            prio = min(p for _s, _d, p in specs)  # (of the AB they make if grouped)
            self.next_command = cid + len(cmds)
        # Where its root goes (the module's docstring). A newer request wins even when it
        # is made in an end handler: the app's own waiting work on its devices is
        # cancelled; the end-event link only chooses the tree when nothing of the app
        # was in the way.
        link = self._link_follows(app, follows, now) if follows is not None else None
        cancelled: Sequence[Command] = _NONE_CANCELLED
        if order is _ASAP:
            asap, cancelled = self._link_asap(app, all_devices,
                                              all_devices if one or group else specs[0][1], now)
            if link is None or asap[1] is not None:  # (its before node)
                link = asap
        elif link is None:
            link = self._link_after_latest(app)
        app.fresh = False  # (the words' first request took its place: the rest follow it)
        rule, parent, tree, enter_now, parent_finished, reactive_allowed = link
        wm = self._wm
        if tree is None:
            tree = wm.new_tree(app)
        elif tree.pose is not None and ((reactive or reaction) or order is _ASAP):
            # a reaction, or a newer request, takes the stream on from where the robot is:
            # nothing is restored of where it was suspended (restore-state)
            tree.pose = None
        # before its nodes are filed, so that they rank as its reaction
        if reactive or reaction:
            self._react(app, tree, seq, reactive, reactive_allowed, user, now)
        turns = self._turns and face_user
        reply = rule is _END_EVENT and parent is not None and self._replies(parent, tree, seq)
        if one or group:  # one AB: the usual request, or its calls grouped
            root = wm.new_node(app, tree, cmds, all_devices, prio,
                               reactive and reactive_allowed, seq)
            if turns:
                root.turnable = root.faces = _turnable(root, parent)
            if reply:
                root.protected = _replies(root)
            if parent is not None:
                wm.link(parent, root)
        else:
            root = self._chain(app, tree, cmds, specs, parent, reactive and reactive_allowed,
                               turns, seq, reply)
        old = app.latest
        app.latest = last
        if old is not None and (old.cancelled or old.ended and old.id not in self._recent):
            old.node = None  # (forgotten: see ``_recent``)
        if self._holds.opened:  # (else no stream or block continues a tree)
            self._holds.requested(app, tree)
        self._log.requested(rule, root, cmds, group, parent)
        if enter_now:
            wm.enter_waiting(root, parent_finished)
        # (one call: its AB's ``command_ids`` are ``(cid,)``)
        return root.command_ids if one else tuple([c.id for c in cmds]), cancelled

    def _replies(self, parent: Node, tree: Tree, seq: int) -> bool:
        """A request that follows the end of ``parent``: whether its words reply to the
        user's answer to the app's own Q&A (docs/rules.md 7.4: they belong to the
        exchange). Whatever follows such an answer replies to the user's own action, not
        rationed by the wait share until its first words (7.6 (4))."""
        if not any(c.answered for c in parent.commands):
            return False
        if self._user_first:
            self._wm.replies(tree, seq)
        return self._exchange

    def _react(self, app: App, tree: Tree, seq: int, reactive: bool, allowed: bool,
               user: bool, now: float) -> None:
        """A request made while handling a reactive event (``reactive``: the handling's
        first): its tree takes over as that reaction (docs/rules.md 7.1), unless it only
        continues its tree (``allowed`` false: it follows an end). The handling's later
        requests are the same reaction as its first."""
        if reactive:
            app.reacting = seq
        if allowed and self._wm.react(tree, seq if reactive or not app.reacting
                                      else app.reacting, user and self._user_first,
                                      now + self._answer_hold):
            self._holds.reranked(tree)

    def _chain(self, app: App, tree: Tree, cmds: tuple[Command, ...], specs: Specs,
               parent: Node | None, reactive: bool, turns: bool, seq: int,
               reply: bool) -> Node:
        """The chain of ABs after ``parent`` of a request of several calls not grouped,
        one per call; returns the first (the one ``reactive``). ``turns``: its
        utterances may be ``turnable``; ``reply``: it follows an answer (its first AB,
        if words, is protected)."""
        wm = self._wm
        first: Node | None = None
        for c, (_spec, devs, prio) in zip(cmds, specs, strict=True):
            node = wm.new_node(app, tree, (c,), devs, prio, reactive and first is None, seq)
            if turns:
                node.turnable = node.faces = _turnable(node, parent)
            if reply and first is None:
                node.protected = _replies(node)
            wm.link(parent, node)
            if first is None:
                first = node
            parent = node
        assert first is not None
        return first

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
        node.protected = x.protected  # (what gets a reply said is part of the exchange)
        parent = wm.nodes.get(x.parent) if x.parent is not None else None
        if parent is not None and x in parent.children:
            parent.children[parent.children.index(x)] = node
        node.parent, node.children, x.parent = x.parent, [x], node.id
        wm.unwait(x)
        x.deferred = True  # (it stays in line for its devices: it reserves them)
        self._log.emit(DecisionKind.REQUEST, rule, node, detail=detail, request=[cmd],
                       before=node.parent, precedes=x.commands[0].id)
        wm.enter_waiting(node, parent_finished)
        return node

    def beside(self, x: Node, call: Call, spec: CommandSpec, rule: Rule,
               detail: str) -> Node:
        """Put an AB of the mediator's own (a policy's) in the running ``x``'s tree to run
        beside it, at once if its devices allow: it waits for nothing of the tree and
        nothing waits for it. Its Command is the app's but internal."""
        wm = self._wm
        cmd = Command(self.next_command, x.app, call, spec, internal=rule)
        self.next_command += 1
        node = wm.new_node(x.app, x.tree, (cmd,), spec.devices_for(call.args), spec.priority,
                           False, x.seq)
        self._log.emit(DecisionKind.REQUEST, rule, node, detail=detail, request=[cmd])
        wm.enter_waiting(node, True)  # (its tree's active stream goes on with it)
        return node

    # ------------------------------------------------------------------ links
    def _link_follows(self, app: App, follows: CommandId, now: float) -> Link | None:
        """CS exceptions (a)/(b): a request made while handling X's end stays in X's tree."""
        q = self._recent_q
        if q and q[0].ended_at < now - self._end_grace:  # (``_prune``'s first test)
            self._prune(now)
        cmd = self._recent.get(follows)
        if cmd is None or cmd.app is not app:
            return None
        node = cmd.node
        if node is None or now - cmd.ended_at > self._end_grace:
            return None
        return (_END_EVENT, node, node.tree, True, True, False)

    def _link_asap(self, app: App, devices: frozenset[str], first: frozenset[str],
                   now: float) -> tuple[Link, Sequence[Command]]:
        """As soon as possible: cancel the app's own trees that share a device with the
        request (``devices``). Its first AB (on ``first``) waits only for a running AB of
        theirs that holds one of its own devices, which it needs anyway; never for one
        on devices it does not use (docs/rules.md 7.6 (2)): the rest of the request waits
        for its devices as any AB does."""
        on = app.trees_on
        if len(devices) == 1:  # (one device: its trees, as they are)
            (device,) = devices
            sharing = on.get(device)
        else:
            sharing = {t.id: t for d in devices if d in on for t in on[d].values()}
        if not sharing:
            return _ASAP_NEW_TREE, _NONE_CANCELLED  # nothing shares a device: a new tree
        # the app's trees with a node that shares a device, oldest first (taken out
        # first: cancelling their nodes changes ``trees_on``)
        trees = [sharing[tid] for tid in sorted(sharing)] if len(sharing) > 1 \
            else list(sharing.values())
        running: Node | None = None
        last: Node | None = None
        cancelled: list[Command] = []
        for tree in trees:
            for n in list(tree.nodes.values()):
                if n.state is _RUNNING:
                    if n.feedback and not n.commands[0].cut:
                        n.commands[0].cut = True
                    if n.cutting:
                        n.dropped = True  # (what is being cut goes: it does not restart)
                    if n.devices & first and (running is None or n.id > running.id):
                        running = n
                elif n.state in IN_MEMORY:
                    cancelled.extend(self.cancel(n, _ASAP_RULE, now))
                    if last is None or n.id > last.id:
                        last = n
        if running is not None:
            return (_ASAP_RULE, running, running.tree, False, False, True), cancelled
        if last is not None:
            return (_ASAP_RULE, last, last.tree, True, False, True), cancelled
        return _ASAP_NEW_TREE, cancelled  # nothing shares a device: a new tree at once

    def _link_after_latest(self, app: App) -> Link:
        """Rule 3, after latest (with the explicit-stream exception, rule 6c); the first
        request of a reaction to the user's words the app took starts a stream of its
        own (docs/rules.md 7.5: ``App.fresh``)."""
        if app.fresh:
            app.fresh = False
            return _NEW_TREE
        latest = app.latest
        node = latest.node if latest is not None else None
        if node is not None and node.state in IN_MEMORY:
            return (_AFTER_LATEST, node, node.tree, False, False, True)
        if node is not None and self._holds.opened and self._holds.continues(app, node.tree):
            return (_STREAM, node, node.tree, True, True, True)
        return _NEW_TREE

    # ------------------------------------------------------------------ ends
    def cancel(self, node: Node, rule: Rule, now: float) -> tuple[Command, ...]:
        """Cancel a not-yet-started node; returns its Commands (for callbacks)."""
        log = self._log
        commands = node.commands
        for cmd in commands:
            cmd.cancelled = True
            if len(commands) == 1:  # (the decision about the AB itself: its facts)
                log.ab(_CANCEL, rule, node)
            else:
                log.emit(_CANCEL, rule, node, command=cmd)
            if node.iteration > 0:
                self._driver.abandon(cmd.id)
            if cmd.app.latest is not cmd:
                cmd.node = None  # (forgotten: see ``_recent``)
        self._holds.cancelled(node)
        self._wm.cancel(node, now)
        return commands

    def ended(self, commands: tuple[Command, ...], now: float) -> None:
        """Commands ended: requests that follow them are linked for ``end_grace``."""
        recent = self._recent
        q = self._recent_q
        for cmd in commands:
            cmd.ended = True
            cmd.ended_at = now
            recent[cmd.id] = cmd
            q.append(cmd)
        if q[0].ended_at < now - self._end_grace:  # (``_prune``'s first test)
            self._prune(now)

    def _prune(self, now: float) -> None:
        horizon = now - self._end_grace
        q = self._recent_q
        recent = self._recent
        while q and q[0].ended_at < horizon:
            cmd = q.popleft()
            recent.pop(cmd.id, None)
            if cmd.app.latest is not cmd:
                cmd.node = None  # (forgotten: see ``_recent``)


def _replies(node: Node) -> bool:
    """The first AB an answer handler requested is the reply that belongs to the
    exchange (docs/rules.md 7.4): it has words, and is no question of its own (the app's
    next question ends the exchange: a reaction may take over before it)."""
    return node.speaks and not any(c.spec.listens for c in node.commands)


def _turnable(node: Node, before: Node | None) -> bool:
    """An utterance the connect-channel policy may turn the robot for: it does not
    orient the robot itself, and the AB before it in its stream did not aim the
    robot at something on purpose (the words are about that; a policy's return, or an
    AB cancelled before it ran, aimed at nothing)."""
    return (node.speaks and not any(c.spec.orients for c in node.commands)
            and (before is None or not any(c.spec.aims and c.internal is None
                                           and not c.cancelled for c in before.commands)))
