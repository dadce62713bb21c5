"""Working memory (thesis Figure 4.3): trees, the waiting list, running ABs,
device occupancy and the suspended-stream stack.

:class:`WorkingMemory` only keeps the books; the mediator decides. Its
primitive updates are the ones Figure 4.3 names: a root enters the waiting
list when its tree is accepted, an AB's children enter it when the AB ends.
It also tracks what the next selection round must look at: ABs that just
entered the waiting list, ABs whose parent just finished, and *dirty* devices
(freed, released, or whose best waiting AB may have changed).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from types import MappingProxyType
from typing import Final

from prima.catalog import Priority
from prima.mediator._index import WaitIndex
from prima.mediator._interface import AbId, TreeId
from prima.mediator._ranking import Ranking
from prima.mediator._state import IN_MEMORY, App, Command, Node, NodeState, Tree

__all__ = ["WorkingMemory"]

# (enum members read once: reading one from its class goes through the enum's
# metaclass, many times slower than a global)
_PENDING: Final = NodeState.PENDING
_WAITING: Final = NodeState.WAITING
_RUNNING: Final = NodeState.RUNNING
_DONE: Final = NodeState.DONE
_CANCELLED: Final = NodeState.CANCELLED
_NONE_NAMED: Final[Mapping[AbId, Node]] = MappingProxyType({})


class WorkingMemory:
    """The mediator's books. Internal: use :meth:`Mediator.snapshot` to look."""

    def __init__(self, keep_next: bool = True) -> None:
        self.keep_next = keep_next
        """A reaction's next AB keeps its devices (the reactions policy, docs/rules.md
        7.1); replies and ABs a policy deferred keep theirs whatever it says."""
        self.nodes: dict[AbId, Node] = {}
        """Nodes pending, waiting or running."""
        self.trees: dict[TreeId, Tree] = {}
        """Trees in working memory (with at least one such node)."""
        self.busy: dict[str, Node] = {}
        """Device -> the running AB that occupies it."""
        self.blending: dict[str, Node] = {}
        """Device -> the running AB blended over its occupant (the blend policy)."""
        self.index = WaitIndex(Ranking())
        """The waiting ABs by device, ranked by rule 4 as ``_ranking.CRITERIA`` says
        when the mediator is made."""
        self.waiting = 0
        """How many ABs are on the waiting list."""
        self.new: list[Node] = []
        """ABs that entered the waiting list since the last selection round."""
        self.pjf: dict[AbId, Node] = {}
        """ABs whose parent finished since the last selection round."""
        self.named: Mapping[AbId, Node] = _NONE_NAMED
        """The ABs the selection round under way names (``pjf`` as it took it)."""
        self.dirty: set[str] = set()
        """Devices whose best waiting AB may have changed since the last round."""
        self.suspended: dict[TreeId, Tree] = {}
        """The suspended-stream stack (``Tree.suspended`` orders it)."""
        self.ranked: dict[str, dict[tuple[str, Priority], int]] = {}
        """Device -> (app, priority) -> how many of its waiting, unparked ABs need it."""
        self.on: dict[str, dict[Tree, dict[AbId, Node]]] = {}
        """Device -> tree -> its waiting, unparked ABs that need the device (what a hold
        taking force on the device looks at)."""
        self.beside: dict[str, dict[str, int]] = {}
        """Device -> the other devices its waiting, unparked ABs need, with how many
        need each: what an AB kept from the device (docs/rules.md 7.1) stops reserving."""
        self.unreserved = False
        """Some AB stopped reserving its devices since the selector last looked: what it
        kept from others may go (``Holds`` re-files them)."""
        self.reserving: dict[str, dict[AbId, Node]] = {}
        """Device -> the pending ABs that reserve it (``Node.reserving``): each is the
        next AB of a reaction (or a reply to an answer, or an AB a policy put an AB of
        its own before) right after one of its tree's waiting or running ABs
        (docs/rules.md 7.1, 7.4)."""
        self.answering: dict[TreeId, Tree] = {}
        """Reactions to the user's own action in working memory that have not said their
        first words in full (``Tree.user``): they keep the streams they interrupted
        waiting on every device (docs/rules.md 7.6 (1)), within their bound."""
        self.answered = False
        """Some reaction stopped keeping the streams it interrupted waiting (it said its
        first words, or left) since the selector last looked: what it held may go
        (``Holds`` re-files them)."""
        self.after_reactions: dict[AbId, Node] = {}
        """Restarts that may wait for the reaction's AB they were cut for (``Node.cut_for``):
        whether they wait turns on ranks, so a re-ranked tree has them looked at again."""
        self._next_ab = 1
        self._next_tree = 0
        self._next_susp = 1

    # ----------------------------------------------------------------- building
    def new_tree(self, app: App) -> Tree:
        tree = Tree(self._next_tree, app)
        self._next_tree += 1
        return tree

    def new_node(self, app: App, tree: Tree, commands: tuple[Command, ...],
                 devices: frozenset[str], priority: Priority, reactive: bool, seq: int,
                 iteration: int = 0) -> Node:
        ab = self._next_ab
        self._next_ab = ab + 1
        node = Node(ab, app, tree, commands, devices, priority, reactive, seq, iteration)
        self.nodes[ab] = node
        tree.nodes[ab] = node
        tid = tree.id
        if not tree.live:  # it enters working memory (else it is there: see ``leave``)
            self.trees[tid] = tree
            app.trees[tid] = tree
            if tree.user:  # (again: an end handler's request continues it, rule 6a)
                self.answering[tid] = tree
                self._holding()
        tree.live += 1
        app.live += 1
        counts = tree.devices
        for d in node.sorted_devices:
            n = counts.get(d, 0)
            counts[d] = n + 1
            if not n:
                on = app.trees_on.get(d)
                if on is None:
                    on = app.trees_on[d] = {}
                on[tid] = tree
        for c in commands:
            c.node = node
        return node

    def next_iteration(self, node: Node) -> Node:
        """The next iteration of the feedback AB ``node``, which just ended, in its place
        in its tree: its tree and app count it instead of ``node``, which leaves working
        memory next (``leave(node, True)``), so their counts of nodes, by device too, do
        not change (``new_node`` and ``leave`` would count one in and one out)."""
        ab = self._next_ab
        self._next_ab = ab + 1
        commands = node.commands
        nxt = Node(ab, node.app, node.tree, commands, node.devices, node.priority, False,
                   node.seq, node.iteration + 1, node)
        self.nodes[ab] = nxt
        node.tree.nodes[ab] = nxt
        for c in commands:
            c.node = nxt
        return nxt

    def link(self, parent: Node | None, child: Node) -> None:
        if parent is None:
            return
        child.parent = parent.id
        state = parent.state
        if state in IN_MEMORY:
            parent.children.append(child)
            if (state is not _PENDING or parent.deferred) and (
                    (self.keep_next and child.tree.reaction is not None)
                    or child.protected or child.deferred):
                self._reserve(child)

    # --------------------------------------------------------------- reserving
    def _reserve(self, node: Node) -> None:
        """The pending ``node`` is next after a waiting or running AB of its reaction
        (or it is a reply to an answer): it reserves its devices."""
        if node.reserving or node.state is not _PENDING:
            return
        node.reserving = True
        self.count_named()  # (``beside`` counts them)
        dirty = self.dirty
        dirty.update(node.devices)  # (what it keeps steps aside now, and reserves no
        beside = self.beside        # more the other devices it waits for)
        reserving = self.reserving
        for d in node.sorted_devices:
            others = beside.get(d)
            if others:
                dirty.update(others)
            on = reserving.get(d)
            if on is None:
                reserving[d] = {node.id: node}
            else:
                on[node.id] = node

    def _unreserve(self, node: Node) -> None:
        """``node`` reserves nothing any more (it waits, started, or left)."""
        node.reserving = False
        self.unreserved = True
        reserving = self.reserving
        for d in node.sorted_devices:
            on = reserving.get(d)
            if on is not None:
                on.pop(node.id, None)
                if not on:
                    del reserving[d]
        self.dirty.update(node.devices)

    def _reserve_children(self, node: Node) -> None:
        """``node`` waits or runs: its pending children that a reaction (or an
        exchange) keeps reserve their devices."""
        for child in node.children:
            if child.state is _PENDING and not child.reserving and (
                    (self.keep_next and child.tree.reaction is not None)
                    or child.protected or child.deferred):
                self._reserve(child)

    # ------------------------------------------------------------------ changes
    def _rank_in(self, node: Node) -> None:
        """Count a waiting AB in its devices' rankings (``ranked``, ``on``, ``beside``)."""
        node.counted = True
        key = (node.app.name, node.priority)
        tree = node.tree
        ranked = self.ranked
        on = self.on
        for d in node.sorted_devices:
            counts = ranked.get(d)
            if counts is None:
                counts = ranked[d] = {}
            counts[key] = counts.get(key, 0) + 1
            trees = on.get(d)
            if trees is None:
                trees = on[d] = {}
            nodes = trees.get(tree)
            if nodes is None:
                nodes = trees[tree] = {}
            nodes[node.id] = node
        devices = node.sorted_devices
        if len(devices) > 1:
            beside = self.beside
            for d in devices:
                others = beside.get(d)
                if others is None:
                    others = beside[d] = {}
                for e in devices:
                    if e != d:
                        others[e] = others.get(e, 0) + 1

    def _rank_out(self, node: Node) -> None:
        """Count a waiting AB out of its devices' rankings, if it was counted in."""
        if not node.counted:
            return  # (parked, or named and left out: ``enter_waiting``)
        node.counted = False
        key = (node.app.name, node.priority)
        tree = node.tree
        ranked = self.ranked
        on = self.on
        for d in node.sorted_devices:
            counts = ranked[d]
            n = counts[key] - 1
            if n:
                counts[key] = n
            else:
                del counts[key]
            trees = on[d]
            nodes = trees[tree]
            del nodes[node.id]
            if not nodes:
                del trees[tree]
        devices = node.sorted_devices
        if len(devices) > 1:
            beside = self.beside
            for d in devices:
                others = beside[d]
                for e in devices:
                    if e != d:
                        k = others[e] - 1
                        if k:
                            others[e] = k
                        else:
                            del others[e]

    def enter_waiting(self, node: Node, parent_finished: bool) -> None:
        """Put a node on the waiting list (Figure 4.3); ``parent_finished``: it ranks as
        'parent just finished' in the next round. (Positional: a call with a keyword
        argument costs more, and one is made for every AB.)"""
        if node.reserving:
            self._unreserve(node)
        node.state = _WAITING
        if node.children:
            self._reserve_children(node)
        node.app.active += 1
        self.waiting += 1
        if parent_finished:
            # Not filed in the index yet: the next round names it, and ranks it against
            # the index's answer on each device (``_rounds._Round``) as it would if it
            # were filed; that round files it only if it still waits then (most ABs whose
            # parent just finished start in it: the next iteration of a feedback loop).
            # Nor is it counted in its devices' rankings until something reads them
            # (``count_named``) or that round files it: where it starts, counting it in
            # and out again would have changed nothing.
            node.unfiled = True
            self.pjf[node.id] = node
        else:
            self.index.add(node)
            self._rank_in(node)
        self.new.append(node)

    def count_named(self) -> None:
        """Count in their devices' rankings the waiting, unparked ABs that the next
        round or the one under way names and that ``enter_waiting`` left out: before
        anything reads the rankings (``ranked``, ``on``, ``beside``), as if they had
        been counted in when they entered the waiting list. (``Selector._idle`` reads
        ``ranked`` at each round and makes up for them itself.)"""
        if not (self.pjf or self.named):
            return
        for named in (self.pjf, self.named):
            for n in named.values():
                if n.state is _WAITING and n.parked is None and not n.counted:
                    self._rank_in(n)

    def file(self, node: Node) -> None:
        """A named AB still waits, unparked, after its round: it is filed in the index,
        and counted in its devices' rankings if it is not yet."""
        if node.unfiled:
            self.index.add(node)
        if not node.counted:
            self._rank_in(node)

    def unwait(self, node: Node) -> None:
        """A waiting, unparked AB goes back to pending: an AB was put before it (a
        policy's turn or return, after which it waits again: what its next ABs
        reserve, they keep meanwhile)."""
        node.state = _PENDING
        node.version += 1
        self._rank_out(node)
        self.waiting -= 1
        node.app.active -= 1
        self.pjf.pop(node.id, None)
        self.dirty.update(node.devices)  # what it reserved may go to another AB now

    def refile(self, node: Node) -> None:
        """A parked AB takes its place in the ranking again."""
        if node.parked is None:
            return
        node.parked = None
        if node.tree.nodes.get(node.id) is node:  # (one cancelled meanwhile has left)
            node.tree.parked -= 1
        if node.state is _WAITING:
            self.index.add(node)
            self._rank_in(node)
            self.dirty.update(node.devices)

    def park(self, node: Node, holder: App) -> None:
        """Take a waiting AB out of its devices' ranking (its index entries go stale)."""
        node.parked = holder
        node.tree.parked += 1
        node.version += 1
        self._rank_out(node)
        self.dirty.update(node.devices)

    def start(self, node: Node) -> None:
        node.state = _RUNNING
        tree = node.tree
        tree.started = True
        self._rank_out(node)
        self.waiting -= 1
        busy = self.busy
        blended = node.blended
        for d in node.sorted_devices:
            if blended and d in blended:
                self.blending[d] = node  # the AB it blends over keeps the device
            else:
                busy[d] = node
        tree.running += 1

    def end(self, node: Node, now: float) -> list[Node]:
        """A running AB ended: free its devices; returns its children (now orphans)."""
        node.state = _DONE
        busy = self.busy
        blending = self.blending
        for d in node.sorted_devices:
            if busy.get(d) is node:
                local = blending.pop(d, None) if blending else None
                if local is None:
                    del busy[d]
                else:  # the AB blended over it keeps the device now
                    busy[d] = local
                    local.blended = local.blended - {d}
            elif blending and blending.get(d) is node:
                del blending[d]
        self.dirty.update(node.devices)
        node.tree.running -= 1
        self._inactive(node.app, now)
        children = node.children
        node.children = []
        return children

    def cancel(self, node: Node, now: float) -> None:
        """Remove a not-yet-started node."""
        if node.reserving:
            self._unreserve(node)
        was_waiting = node.state is _WAITING
        node.state = _CANCELLED
        node.children = []
        if was_waiting:
            if node.parked is None:
                self._rank_out(node)
            self.waiting -= 1
            self.dirty.update(node.devices)
            self._inactive(node.app, now)
        self.leave(node)

    def leave(self, node: Node, replaced: bool = False) -> None:
        """Take a finished or cancelled node out of working memory; ``replaced``: its next
        iteration took its place in its tree's and app's counts (``next_iteration``)."""
        if node.reserving:
            self._unreserve(node)
        ab = node.id
        self.nodes.pop(ab, None)
        tree = node.tree
        if tree.nodes.pop(ab, None) is None:
            return
        if node.parked is not None:
            tree.parked -= 1
        if replaced:
            return
        app = tree.app
        counts = tree.devices
        for d in node.sorted_devices:
            n = counts[d] - 1
            if n:
                counts[d] = n
            else:
                del counts[d]
                on = app.trees_on[d]
                del on[tree.id]
                if not on:
                    del app.trees_on[d]
        app.live -= 1
        tree.live = live = tree.live - 1
        if not live:
            self.trees.pop(tree.id, None)
            app.trees.pop(tree.id, None)
            if self.answering.pop(tree.id, None) is not None:
                self.answered = True
            if tree.suspended is not None:
                self.suspended.pop(tree.id, None)
                tree.suspended = None
                tree.started = False  # a request joining it takes the floor anew (7.2)
            self.index.forget(tree)

    @staticmethod
    def _inactive(app: App, now: float) -> None:
        app.active -= 1
        if app.active == 0:
            app.idle_since = now

    def _rerank(self, tree: Tree) -> None:
        """The tree's rank changed: the index re-ranks its waiting ABs, and the devices
        its next ABs reserve are looked at again (whom they outrank changed)."""
        dirty = self.dirty
        dirty.update(self.index.rerank(tree))
        if tree.parked:  # (an AB of it kept for another's next AB may outrank that one now)
            self.unreserved = True
        if self.pjf:  # (the devices of its ABs the index does not hold yet: as if it did)
            for n in self.pjf.values():
                if n.tree is tree and n.unfiled and n.state is _WAITING and n.parked is None:
                    dirty.update(n.devices)
        if self.after_reactions:  # (whether a restart waits for its reaction may change with it)
            for ab, n in list(self.after_reactions.items()):
                if n.state is _WAITING:
                    dirty.update(n.devices)
                    if n.parked is not None:  # (stepped aside for its reaction: looked
                        self.unreserved = True  # at again, as what a next AB kept)
                elif n.state is not _PENDING:
                    del self.after_reactions[ab]
        if self.reserving:
            self._rekept(tree)

    def _rekept(self, tree: Tree) -> None:
        """The tree's rank changed: the devices its next ABs reserve are looked at again,
        and the other devices that the ABs waiting for those need (whom they keep, and so
        what those reserve, changed)."""
        self.count_named()  # (``beside`` counts them)
        dirty = self.dirty
        beside = self.beside
        for d, on in self.reserving.items():
            for r in on.values():
                if r.tree is tree:
                    dirty.add(d)
                    others = beside.get(d)
                    if others:
                        dirty.update(others)
                    break

    # -------------------------------------------------------- suspended stack
    def suspend(self, tree: Tree) -> bool:
        """Push a tree on the suspended stack (once). True if it was pushed."""
        if tree.suspended is not None or tree.live == 0:
            return False
        tree.suspended = self._next_susp
        tree.suspensions += 1
        self._next_susp += 1
        self.suspended[tree.id] = tree
        self._rerank(tree)
        return True

    def resume(self, tree: Tree) -> None:
        if tree.suspended is None:
            return
        tree.suspended = None
        self.suspended.pop(tree.id, None)
        self._rerank(tree)

    def _holding(self) -> None:
        """A reaction to the user's own action now keeps the streams it interrupted
        waiting on every device (docs/rules.md 7.6 (1)): the best waiting AB of each
        device is looked at again (one it holds steps aside, reserving nothing)."""
        self.count_named()
        ranked = self.ranked
        self.dirty.update(d for d, apps in ranked.items() if apps)

    def react(self, tree: Tree, reaction: int, user: bool = False,
              answers_until: float = 0.0) -> bool:
        """The tree takes over as (a later) reaction, to the user's own action if ``user``
        (it keeps the streams it interrupted waiting until its first words, at the latest
        until ``answers_until``): re-rank it. Whether its rank changed."""
        before = tree.reaction
        if before is None or before < reaction:
            tree.reaction = reaction
            # (a later reaction to a perception that joins a reaction to the user's own
            # action whose first words are ahead leaves it that: the user's words first)
            if user:
                tree.user = True
                tree.user_since = reaction
                tree.answers_until = answers_until
                tree.answers_from = self._next_tree  # (what came into being before it)
                self.answering[tree.id] = tree
                self._holding()
            elif tree.user:  # (a later reaction joins a reaction to the user whose words
                self._holding()  # are ahead: it is the latest now, whom it holds changed)
            if tree.live:  # (else it has no AB in the index, nor keys: ``forget`` cleared them)
                self._rerank(tree)
                if before is None and self.keep_next:  # its next ABs keep their devices
                    for node in list(tree.nodes.values()):
                        if node.state is not _PENDING or node.deferred:
                            self._reserve_children(node)
            return True
        return False

    def replies(self, tree: Tree, seq: int) -> None:
        """The tree replies (request ``seq``) to the user's answer to its Q&A: its first
        words from then on are not rationed by the wait share (docs/rules.md 7.6 (4))."""
        if not tree.answered_since:
            tree.answered_since = seq
            if tree.live:
                self._rerank(tree)
            if self.answering:  # (an earlier reaction to the user no longer holds it: 7.6 (1))
                self.answered = True

    def replied(self, tree: Tree) -> None:
        """The tree said the first words of its reply to the user's answer in full."""
        if tree.answered_since:
            tree.answered_since = 0
            if tree.live:
                self._rerank(tree)

    def heard(self, tree: Tree) -> None:
        """A reaction to the user's own action said its first utterance in full: from now
        on it ranks as any reaction (docs/rules.md 7.1)."""
        if tree.user:
            tree.user = False
            if self.answering.pop(tree.id, None) is not None:
                self.answered = True
            if tree.live:
                self._rerank(tree)

    def rerank_app(self, app: App) -> None:
        """The app's precedence changed: re-rank its trees, and look again at the
        devices its running ABs hold (a waiting reaction may outrank them now, and the
        interrupt policy may cut them)."""
        for tree in app.trees.values():
            self._rerank(tree)
        dirty = self.dirty
        for d, y in self.busy.items():
            if y.app is app:
                dirty.add(d)

    # ------------------------------------------------------------------ queries
    @staticmethod
    def waiting_in(tree: Tree) -> Iterator[Node]:
        return (n for n in list(tree.nodes.values()) if n.state is _WAITING)

    def stack(self) -> list[Tree]:
        """The suspended stack, top (most recently suspended) first."""
        return sorted(self.suspended.values(), key=lambda t: -(t.suspended or 0))

    def maybe_compact(self) -> None:
        """Drop stale index entries once they outnumber live ones."""
        if self.index.entries > 12 * self.waiting + 256:  # (4 * (waiting * 3 + 64))
            self.index.compact(n for n in self.nodes.values()
                               if n.state is _WAITING and n.parked is None)
