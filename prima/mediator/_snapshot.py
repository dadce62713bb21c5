"""A frozen, comparable view of working memory, for tests and tools."""

from __future__ import annotations

from dataclasses import dataclass

from prima.catalog import Priority
from prima.mediator._holds import Holds
from prima.mediator._interface import AbId, CommandId, TreeId
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import Node, NodeState

__all__ = ["HoldView", "NodeView", "Snapshot", "TreeView"]


@dataclass(frozen=True)
class NodeView:
    """One AB of a tree."""

    ab: AbId
    app: str
    tree: TreeId
    parent: AbId | None
    command: str
    command_ids: tuple[CommandId, ...]
    devices: tuple[str, ...]
    state: NodeState
    reactive: bool
    iteration: int
    priority: Priority
    seq: int
    """Its request's order among all requests (smaller is older)."""
    parked_by: str | None
    """The app whose hold (stream, block, talk) keeps it out of the ranking, if any."""


@dataclass(frozen=True)
class TreeView:
    """One tree in working memory."""

    id: TreeId
    app: str
    active: bool
    """Some node of it is running."""
    suspended: bool
    nodes: tuple[NodeView, ...]
    """Its pending, waiting and running nodes, in id order."""


@dataclass(frozen=True)
class HoldView:
    """A stream hold or a block reservation in force."""

    app: str
    kind: str
    """``stream`` or ``block``."""
    devices: tuple[str, ...]
    deadline: float


@dataclass(frozen=True)
class Snapshot:
    """Working memory at one instant."""

    t: float
    waiting: tuple[AbId, ...]
    """The waiting list, in AB id order."""
    running: tuple[tuple[AbId, tuple[str, ...]], ...]
    """Running ABs (id order) with their devices."""
    trees: tuple[TreeView, ...]
    suspended: tuple[TreeId, ...]
    """The suspended-stream stack, top (most recently suspended) first."""
    holds: tuple[HoldView, ...]
    busy: tuple[tuple[str, AbId], ...]
    """Device -> running AB, by device name."""
    demoted: tuple[str, ...] = ()
    """Apps that kept the others waiting beyond their wait share: they have lost
    their precedence for a while."""

    def node(self, ab: AbId) -> NodeView | None:
        """The view of one AB still in working memory."""
        for tree in self.trees:
            for n in tree.nodes:
                if n.ab == ab:
                    return n
        return None

    @property
    def active_trees(self) -> tuple[TreeId, ...]:
        return tuple(t.id for t in self.trees if t.active)


def _node_view(n: Node) -> NodeView:
    return NodeView(
        ab=n.id, app=n.app.name, tree=n.tree.id, parent=n.parent, command=n.name,
        command_ids=tuple(c.id for c in n.commands), devices=n.sorted_devices,
        state=n.state, reactive=n.reactive, iteration=n.iteration, priority=n.priority,
        seq=n.seq, parked_by=n.parked.name if n.parked is not None else None,
    )


def take(t: float, wm: WorkingMemory, in_force: Holds) -> Snapshot:
    """Build a :class:`Snapshot` (costs a scan: for tests and tools, not the hot path)."""
    nodes = sorted(wm.nodes.values(), key=lambda n: n.id)
    holds = [HoldView(app, kind, devices, deadline)
             for app, kind, devices, deadline in in_force.in_force()]
    return Snapshot(
        t=t,
        waiting=tuple(n.id for n in nodes if n.state is NodeState.WAITING),
        running=tuple((n.id, n.sorted_devices) for n in nodes if n.state is NodeState.RUNNING),
        trees=tuple(
            TreeView(tree.id, tree.app.name, tree.running > 0, tree.suspended is not None,
                     tuple(_node_view(n) for n in sorted(tree.nodes.values(), key=lambda n: n.id)))
            for tree in sorted(wm.trees.values(), key=lambda tr: tr.id)
        ),
        suspended=tuple(tr.id for tr in wm.stack()),
        holds=tuple(holds),
        busy=tuple((d, wm.busy[d].id) for d in sorted(wm.busy)),
        demoted=in_force.demoted(),
    )
