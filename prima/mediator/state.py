"""The parts of working memory: applications, Commands, AB trees and their nodes.

A *node* is one atomic behavior (AB) in an AB tree (thesis Figure 4.3). It
holds one Command, or several for a grouped request, or one iteration of a
feedback Command. Its state moves PENDING (in the tree, before node not yet
finished) -> WAITING (on the waiting list) -> RUNNING -> DONE, or to
CANCELLED before it starts. A tree is in working memory while any node is
pending, waiting or running, and *active* while any node runs.

Everything here is internal and mutable; :mod:`prima.mediator.snapshot`
gives the frozen public view.
"""

from __future__ import annotations

import enum
from typing import TYPE_CHECKING

from prima.catalog import CommandSpec, Priority
from prima.mediator.interface import AbId, AppKind, Call, CommandId, TreeId

if TYPE_CHECKING:
    from prima.mediator.interface import AppListener

__all__ = ["NodeState"]


class NodeState(str, enum.Enum):
    """Where an AB is in its life."""

    PENDING = "pending"
    """In its tree; its before node has not finished yet."""
    WAITING = "waiting"
    """On the waiting list: it starts when selection picks it."""
    RUNNING = "running"
    """Handed to the driver; never cut."""
    DONE = "done"
    """The driver reported its end."""
    CANCELLED = "cancelled"
    """Removed before it started."""


IN_MEMORY = (NodeState.PENDING, NodeState.WAITING, NodeState.RUNNING)


class _Stream:
    """An explicit stream block (``open_stream`` ... ``close_stream``)."""

    __slots__ = ("hold", "tree", "devices", "armed", "deadline", "lapsed", "held")

    def __init__(self, hold: float, tree: _Tree | None) -> None:
        self.hold = hold
        self.tree = tree
        self.devices: set[str] = set()
        self.armed = False
        """The hold is in force (the app is idle)."""
        self.deadline = 0.0
        self.lapsed = False
        """The hold timed out in this idle period; it re-arms after the next activity."""
        self.held: set[AbId] = set()
        """ABs already recorded as held in this hold period."""


class _Block:
    """A begin/end block (``open_block`` ... ``close_block``)."""

    __slots__ = ("devices", "watchdog", "first_command", "tree", "started",
                 "deadline", "expired", "held")

    def __init__(self, devices: frozenset[str], watchdog: float, first_command: CommandId,
                 tree: _Tree | None) -> None:
        self.devices = devices
        self.watchdog = watchdog
        self.first_command = first_command
        self.tree = tree
        self.started = False
        self.deadline = 0.0
        self.expired = False
        self.held: set[AbId] = set()

    @property
    def reserving(self) -> bool:
        return self.started and not self.expired


class _App:
    """One registration of an application."""

    __slots__ = ("name", "kind", "listener", "alive", "order", "latest", "active",
                 "idle_since", "trees", "stream", "block")

    def __init__(self, name: str, kind: AppKind, listener: AppListener, order: int) -> None:
        self.name = name
        self.kind = kind
        self.listener = listener
        self.alive = True
        self.order = order
        self.latest: _Command | None = None
        self.active = 0
        """Nodes of this app that are waiting or running."""
        self.idle_since = 0.0
        """When ``active`` last dropped to zero."""
        self.trees: dict[TreeId, _Tree] = {}
        self.stream: _Stream | None = None
        self.block: _Block | None = None


TALK_DEVICES = frozenset({"speaker", "speech-recognition"})
"""Devices through which the robot talks with its user: while another app uses
them, a Command that breaks the Communication Channel waits."""


class _Command:
    """One requested Command."""

    __slots__ = ("id", "app", "call", "spec", "node", "ended", "cancelled", "cut", "ended_at")

    def __init__(self, cid: CommandId, app: _App, call: Call, spec: CommandSpec) -> None:
        self.id = cid
        self.app = app
        self.call = call
        self.spec = spec
        self.node: _Node | None = None
        """Its current node (the latest iteration for a feedback Command)."""
        self.ended = False
        self.cancelled = False
        self.cut = False
        """Cancelled while an iteration runs: the loop stops when that iteration ends."""
        self.ended_at = 0.0


class _Tree:
    """One AB tree (one Communication Stream)."""

    __slots__ = ("id", "app", "live", "running", "suspended", "nodes")

    def __init__(self, tid: TreeId, app: _App) -> None:
        self.id = tid
        self.app = app
        self.live = 0
        """Nodes pending, waiting or running."""
        self.running = 0
        self.suspended: int | None = None
        """Position on the suspended stack (larger = more recent), or None."""
        self.nodes: dict[AbId, _Node] = {}
        """Nodes in working memory, in creation order."""


_SORTED: dict[frozenset[str], tuple[str, ...]] = {}


def _sorted(devices: frozenset[str]) -> tuple[str, ...]:
    """Device sets, sorted once (there are few distinct ones: one per Command type)."""
    out = _SORTED.get(devices)
    if out is None:
        if len(_SORTED) > 4096:
            _SORTED.clear()
        out = _SORTED[devices] = tuple(sorted(devices))
    return out


class _Node:
    """One atomic behavior in a tree."""

    __slots__ = ("id", "app", "tree", "commands", "devices", "sorted_devices", "priority",
                 "reactive", "iteration", "parent", "children", "state", "seq", "version",
                 "tier", "name", "command_ids", "feedback", "calls", "parked")

    def __init__(self, ab: AbId, app: _App, tree: _Tree, commands: tuple[_Command, ...],
                 devices: frozenset[str], priority: Priority, reactive: bool, seq: int,
                 iteration: int = 0) -> None:
        self.id = ab
        self.app = app
        self.tree = tree
        self.commands = commands
        self.devices = devices
        self.sorted_devices = _sorted(devices)
        self.priority = priority
        self.reactive = reactive
        self.iteration = iteration
        self.parent: AbId | None = None
        """The before node's id (kept as an id so finished nodes can be freed)."""
        self.children: list[_Node] = []
        self.state = NodeState.PENDING
        self.seq = seq
        """The request's sequence number: smaller is older."""
        self.version = 0
        """Bumped whenever its waiting-index entries must be re-filed."""
        self.tier = 0
        self.parked = False
        """Held by another app's block or stream hold: out of the device ranking."""
        if len(commands) == 1:
            first = commands[0]
            self.calls: tuple[Call, ...] = (first.call,)
            self.name = first.spec.name
            self.command_ids: tuple[CommandId, ...] = (first.id,)
            self.feedback = first.spec.feedback
        else:
            self.calls = tuple([c.call for c in commands])
            self.name = "+".join(c.spec.name for c in commands)
            self.command_ids = tuple(c.id for c in commands)
            self.feedback = False


