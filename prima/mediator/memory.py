"""Working memory (thesis Figure 4.3): trees, the waiting list, running ABs,
device occupancy, active trees and the suspended-stream stack.

:class:`WorkingMemory` only keeps the books; the mediator decides. Its
primitive updates are the ones Figure 4.3 names: a root enters the waiting
list when its tree is accepted, an AB's children enter it when the AB ends.
It also tracks what a selection round must look at next: ABs that just
entered the waiting list, ABs whose parent just finished, and *dirty* devices
(freed, released, or whose best waiting AB may have changed).
"""

from __future__ import annotations

from typing import Iterator

from prima.catalog import Priority
from prima.mediator.interface import AbId, TreeId
from prima.mediator.selection import WaitIndex
from prima.mediator.state import TALK_DEVICES, NodeState, _App, _Command, _Node, _Tree

__all__ = ["WorkingMemory"]


class WorkingMemory:
    """The mediator's books. Internal: use :meth:`Mediator.snapshot` to look."""

    def __init__(self) -> None:
        self.nodes: dict[AbId, _Node] = {}
        """Nodes pending, waiting or running."""
        self.trees: dict[TreeId, _Tree] = {}
        """Trees in working memory (with at least one such node)."""
        self.busy: dict[str, _Node] = {}
        self.channel_devices: frozenset[str] = frozenset()
        """Devices of the Commands that break the Communication Channel."""
        self.channel_held: set[int] = set()
        """Waiting ABs held back by the channel rule (a hold decision was emitted)."""
        """Device -> the running AB that occupies it."""
        self.index = WaitIndex()
        self.waiting = 0
        self.new: list[_Node] = []
        """ABs that entered the waiting list since the last selection round."""
        self.pjf: dict[AbId, _Node] = {}
        """ABs whose parent finished since the last selection round."""
        self.dirty: set[str] = set()
        self.suspended: dict[TreeId, _Tree] = {}
        """The suspended-stream stack (``_Tree.suspended`` orders it)."""
        self._next_ab = 1
        self._next_tree = 0
        self._next_susp = 1

    # ----------------------------------------------------------------- building
    def new_tree(self, app: _App) -> _Tree:
        tree = _Tree(self._next_tree, app)
        self._next_tree += 1
        return tree

    def new_node(self, app: _App, tree: _Tree, commands: tuple[_Command, ...],
                 devices: frozenset[str], priority: Priority, reactive: bool, seq: int,
                 iteration: int = 0) -> _Node:
        node = _Node(self._next_ab, app, tree, commands, devices, priority, reactive, seq,
                     iteration)
        self._next_ab += 1
        self.nodes[node.id] = node
        tree.nodes[node.id] = node
        tree.live += 1
        self.trees[tree.id] = tree
        app.trees[tree.id] = tree
        for c in commands:
            c.node = node
        return node

    @staticmethod
    def link(parent: _Node | None, child: _Node) -> None:
        if parent is None:
            return
        child.parent = parent.id
        if parent.state in (NodeState.PENDING, NodeState.WAITING, NodeState.RUNNING):
            parent.children.append(child)

    # ------------------------------------------------------------------ changes
    def enter_waiting(self, node: _Node, *, parent_finished: bool) -> None:
        """Put a node on the waiting list (Figure 4.3)."""
        node.state = NodeState.WAITING
        node.app.active += 1
        self.waiting += 1
        self.index.add(node)
        self.new.append(node)
        if parent_finished:
            self.pjf[node.id] = node

    def start(self, node: _Node) -> None:
        node.state = NodeState.RUNNING
        self.channel_held.discard(node.id)
        self.waiting -= 1
        for d in node.sorted_devices:
            self.busy[d] = node
        node.tree.running += 1

    def end(self, node: _Node, now: float) -> list[_Node]:
        """A running AB ended: free its devices; returns its children (now orphans)."""
        node.state = NodeState.DONE
        for d in node.sorted_devices:
            if self.busy.get(d) is node:
                del self.busy[d]
        self.dirty.update(node.devices)
        if self.channel_held and not TALK_DEVICES.isdisjoint(node.devices):
            # A CC-breaking AB waited for this talk to end (the channel rule).
            self.dirty.update(self.channel_devices)
        node.tree.running -= 1
        self._inactive(node.app, now)
        children = node.children
        node.children = []
        return children

    def cancel(self, node: _Node, now: float) -> None:
        """Remove a not-yet-started node."""
        was_waiting = node.state is NodeState.WAITING
        node.state = NodeState.CANCELLED
        self.channel_held.discard(node.id)
        node.children = []
        if was_waiting:
            self.waiting -= 1
            self.dirty.update(node.devices)
            self._inactive(node.app, now)
        self.leave(node)

    def leave(self, node: _Node) -> None:
        """Take a finished or cancelled node out of working memory."""
        self.nodes.pop(node.id, None)
        tree = node.tree
        if tree.nodes.pop(node.id, None) is None:
            return
        tree.live -= 1
        if tree.live == 0:
            self.trees.pop(tree.id, None)
            tree.app.trees.pop(tree.id, None)
            if tree.suspended is not None:
                self.suspended.pop(tree.id, None)
                tree.suspended = None

    @staticmethod
    def _inactive(app: _App, now: float) -> None:
        app.active -= 1
        if app.active == 0:
            app.idle_since = now

    # -------------------------------------------------------- suspended stack
    def suspend(self, tree: _Tree) -> bool:
        """Push a tree on the suspended stack (once). True if it was pushed."""
        if tree.suspended is not None or tree.live == 0:
            return False
        tree.suspended = self._next_susp
        self._next_susp += 1
        self.suspended[tree.id] = tree
        self._refile(tree)
        return True

    def resume(self, tree: _Tree) -> None:
        if tree.suspended is None:
            return
        tree.suspended = None
        self.suspended.pop(tree.id, None)
        self._refile(tree)

    def _refile(self, tree: _Tree) -> None:
        for n in self.waiting_in(tree):
            self.index.add(n)
            self.dirty.update(n.devices)

    # ------------------------------------------------------------------ queries
    @staticmethod
    def waiting_in(tree: _Tree) -> Iterator[_Node]:
        return (n for n in list(tree.nodes.values()) if n.state is NodeState.WAITING)

    def stack(self) -> list[_Tree]:
        """The suspended stack, top (most recently suspended) first."""
        return sorted(self.suspended.values(), key=lambda t: -(t.suspended or 0))

    def maybe_compact(self) -> None:
        """Drop stale index entries once they outnumber live ones."""
        if self.index.entries() > 4 * (self.waiting * 3 + 64):
            self.index.compact(n for n in self.nodes.values() if n.state is NodeState.WAITING)
