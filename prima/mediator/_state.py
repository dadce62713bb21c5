"""The parts of working memory: applications, Commands, AB trees and their nodes.

A *node* is one atomic behavior (AB) in an AB tree (thesis Figure 4.3). It
holds one Command, or several for a grouped request, or one iteration of a
feedback Command. Its state moves PENDING (in the tree, before node not yet
finished) -> WAITING (on the waiting list) -> RUNNING -> DONE, or to
CANCELLED before it starts. A tree is in working memory while any node is
pending, waiting or running, and *active* while any node runs.

Everything here is internal and mutable; :mod:`._snapshot` gives the frozen
public view.
"""

from __future__ import annotations

import enum
from collections.abc import Mapping
from typing import TYPE_CHECKING, Final

from prima.catalog import CommandSpec, Priority
from prima.mediator._interface import AbId, Call, CommandId, TreeId
from prima.vocab import AppKind, Budgets, OnInterrupt, Value

if TYPE_CHECKING:
    from prima.mediator._decisions import Rule
    from prima.mediator._interface import AppListener

__all__ = ["IN_MEMORY", "App", "Command", "Node", "NodeState", "Tree"]


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
"""The states of a node that is still in working memory."""


class App:
    """One registration of an application."""

    __slots__ = ("name", "kind", "listener", "alive", "order", "latest", "active",
                 "idle_since", "trees", "trees_on", "live", "demoted", "budgets", "fresh",
                 "reacting")

    def __init__(self, name: str, kind: AppKind, listener: AppListener, order: int,
                 budgets: Budgets) -> None:
        self.name = name
        self.kind = kind
        self.budgets = budgets
        """What it may consume (its role's budgets)."""
        self.listener = listener
        self.alive = True
        self.order = order
        """Registration order (1 for the first application)."""
        self.latest: Command | None = None
        """The application's latest requested Command (rule 3, after latest)."""
        self.active = 0
        """Nodes of this app that are waiting or running."""
        self.idle_since = 0.0
        """When ``active`` last dropped to zero."""
        self.trees: dict[TreeId, Tree] = {}
        """Its trees in working memory."""
        self.trees_on: dict[str, dict[TreeId, Tree]] = {}
        """Device -> its trees with a node in working memory that needs the device."""
        self.live = 0
        """Its ABs in working memory (pending, waiting or running): the waiting budget."""
        self.demoted = False
        """It kept others waiting beyond its wait-share budget: it has lost its precedence."""
        self.reacting = 0
        """The sequence number of its latest reaction's first request (``reactive``): the
        requests it makes later in the same handling (``reaction``) are that same reaction
        (docs/rules.md 7.1), not later ones."""
        self.fresh = False
        """It is handling words of the user's it took (docs/rules.md 7.5): its first request
        after latest starts a stream of its own, which goes before the stream it talked
        in, as another application's reaction would."""


class Command:
    """One requested Command."""

    __slots__ = ("id", "app", "call", "spec", "node", "ended", "cancelled", "cut", "ended_at",
                 "internal", "on_interrupt", "answered")

    def __init__(self, cid: CommandId, app: App, call: Call, spec: CommandSpec,
                 internal: Rule | None = None,
                 on_interrupt: OnInterrupt = OnInterrupt.RESTART) -> None:
        self.id = cid
        self.internal = internal
        """The policy that requested it, for the app (a turn to the user, a return to a
        pose); the app never hears of it. None: the app requested it."""
        self.app = app
        self.call = call
        self.spec = spec
        self.node: Node | None = None
        """Its current node (the latest iteration for a feedback Command); None before
        it has one, and once it is done and forgotten (see ``Intake._recent``)."""
        self.ended = False
        self.cancelled = False
        self.cut = False
        """Cancelled while an iteration runs: the loop stops when that iteration ends."""
        self.ended_at = 0.0
        self.on_interrupt = on_interrupt
        """What the interrupt policy may do to its ABs (its request said)."""
        self.answered = False
        """A Command that listens, which ended with the user's answer: a request that
        follows it with words is the reply that belongs to the exchange (docs/rules.md
        7.4)."""


class Tree:
    """One AB tree (one Communication Stream)."""

    __slots__ = ("id", "app", "live", "running", "suspended", "nodes", "reaction",
                 "user", "started", "pose", "devices", "parked", "keys", "suspensions",
                 "answers_until", "answers_from", "user_since", "answered_since")

    def __init__(self, tid: TreeId, app: App) -> None:
        self.id = tid
        self.app = app
        self.live = 0
        """Nodes pending, waiting or running."""
        self.running = 0
        self.suspended: int | None = None
        """Position on the suspended stack (larger = more recent), or None."""
        self.suspensions = 0
        """How many times it was suspended."""
        self.nodes: dict[AbId, Node] = {}
        """Nodes in working memory, in creation order."""
        self.devices: dict[str, int] = {}
        """Device -> how many of its nodes in working memory need it."""
        self.parked = 0
        """How many of its nodes in working memory are parked (out of the ranking)."""
        self.keys: tuple[int, ...] | None = None
        """Its keys under the TREE ranking criteria, kept by ``_ranking.Ranking``;
        None when they may have changed (the waiting index clears them whenever it
        re-ranks or forgets the tree)."""
        self.reaction: int | None = None
        """The sequence number of the reaction it belongs to (docs/rules.md 7.1: a reaction
        takes over as a stream), larger is later; None if it is no reaction."""
        self.user = False
        """A reaction to the user's own action (a touch, heard speech) that has not yet
        said its first utterance in full: no later reaction of another application to
        a perception or network event overtakes it (docs/rules.md 7.1); a later reaction
        to such an event that joins the tree leaves it so until then."""
        self.answered_since = 0
        """The sequence number of the request with which it replies to the user's answer to
        its Q&A (words, or its next question), until its first utterance from then on is
        said in full (0: none): the user's own action, not rationed by the wait share
        (docs/rules.md 7.6 (4))."""
        self.user_since = 0
        """With ``user``: the sequence number of that reaction: its first utterance is
        the first one of its requests or later ones said in full."""
        self.started = False
        """Some AB of it has started: it is a stream under way, not a new one."""
        self.answers_until = 0.0
        """With ``user``: until when, at the latest, it keeps the streams it interrupted
        waiting on every device before its first words (docs/rules.md 7.6 (1);
        ``MediatorConfig.max_answer_hold`` after it became a reaction to the user)."""
        self.answers_from = 0
        """With ``user``: the first tree id that came into being after it became a reaction
        to the user: only trees before it (and no later reaction) are streams it
        interrupted (docs/rules.md 7.6 (1))."""
        self.pose: Mapping[str, Value] | None = None
        """The robot's pose when it was last suspended, until the restore-state
        policy has put its return before the stream's next AB (or found none needed)."""


_PENDING: Final = NodeState.PENDING
_NO_DEVICES: Final[frozenset[str]] = frozenset()
_SORTED: Final[dict[frozenset[str], tuple[str, ...]]] = {}


def _sorted(devices: frozenset[str]) -> tuple[str, ...]:
    """Device sets, sorted once (there are few distinct ones: one per Command type)."""
    out = _SORTED.get(devices)
    if out is None:
        if len(_SORTED) > 4096:
            _SORTED.clear()
        out = _SORTED[devices] = tuple(sorted(devices))
    return out


class Node:
    """One atomic behavior in a tree."""

    __slots__ = ("id", "app", "tree", "commands", "devices", "sorted_devices", "priority",
                 "reactive", "iteration", "parent", "children", "state", "seq", "version",
                 "name", "command_ids", "feedback", "calls", "parked", "turnable", "cutting",
                 "restarts", "blended", "head", "order", "ranked", "facts", "plain",
                 "protected", "reserving", "faces", "started_at", "cut_by", "deferred",
                 "looked", "once", "by_user", "taker", "not_before", "dropped", "cut_for",
                 "speaks", "unfiled", "counted", "faced_at", "relooked")

    def __init__(self, ab: AbId, app: App, tree: Tree, commands: tuple[Command, ...],
                 devices: frozenset[str], priority: Priority, reactive: bool, seq: int,
                 iteration: int = 0, like: Node | None = None) -> None:
        # (each value kept in a local too where ``facts`` needs it again: one node
        # per request, on the hot path. ``like``: a node of the same Commands and
        # devices, whose next iteration this one is: what they say of it is the same)
        self.id = ab
        self.app = app
        self.tree = tree
        self.commands = commands
        self.devices = devices
        if like is None:
            ordered = _SORTED.get(devices) or _sorted(devices)
            speaks = any(c.spec.spoken(c.call.args) for c in commands)
        else:
            ordered = like.sorted_devices
            speaks = like.speaks
        self.sorted_devices: tuple[str, ...] = ordered
        self.speaks: bool = speaks
        """Some Command of it says words (an utterance, a Q&A's prompt)."""
        self.priority = priority
        self.reactive = reactive
        self.iteration = iteration
        self.parent: AbId | None = None
        """The before node's id (kept as an id so finished nodes can be freed)."""
        self.children: list[Node] = []
        self.state = _PENDING
        self.seq = seq
        """The request's sequence number: smaller is older."""
        self.version = 0
        """Bumped whenever its waiting-index entries go stale."""
        self.unfiled = False
        """Waiting, but not yet in the waiting index: its parent just finished, and the
        round that names it files it only if it still waits then
        (``WorkingMemory.enter_waiting``)."""
        self.counted = False
        """Counted in its devices' rankings (``WorkingMemory.ranked``, ``on``,
        ``beside``): waiting, unparked, and not left out of them with ``unfiled``."""
        self.head: tuple[int, ...] | None = None
        self.order: tuple[int, ...] | None = None
        """Its keys under the NODE ranking criteria before and after the first TREE
        one, worked out by ``_ranking.Ranking`` when it first enters the waiting
        list (None before): they never change after that."""
        self.ranked: tuple[object, tuple[int, ...]] | None = None
        """Its full rank when no round names it, with the tree keys it was worked out
        from (``_ranking.Ranking.rank`` keeps it: valid while the tree keeps them)."""
        self._clear_policy_state()
        first = commands[0]
        call = first.call
        calls: tuple[Call, ...]
        ids: tuple[CommandId, ...]
        if len(commands) == 1:
            spec = first.spec
            calls = (call,)
            ids = (first.id,)
            name = spec.name
            self.feedback = spec.feedback
        else:
            calls = tuple([c.call for c in commands])
            ids = tuple([c.id for c in commands])
            name = "+".join(c.spec.name for c in commands)
            self.feedback = False
        self.calls = calls
        self.command_ids = ids
        self.name = name
        label = call.label
        self.facts = (app.name, ab, tree.id, name, first.id, ids, ordered, reactive, iteration,
                      label)
        """What every decision about the AB itself says of it, in the fields of
        ``Decision`` from ``app`` to ``label`` (none of them changes)."""
        # (``facts`` and four more, written out: adding them up costs 0.4% of an operation)
        self.plain = (app.name, ab, tree.id, name, first.id, ids, ordered, reactive, iteration,
                      label, "", calls, None, None)
        """The fields from ``app`` on of a decision about the AB itself with no detail
        (most starts and ends): ``facts``, then no detail, its calls, no ``before`` and
        no ``precedes`` (built once, not added up for each such decision)."""

    def _clear_policy_state(self) -> None:
        """What the policies note of a new node: nothing yet (a blend, a cut and its
        restart, a turn to the user, a hold, the exchange's protection)."""
        self.blended: frozenset[str] = _NO_DEVICES
        """Devices it shares with another running AB (the blend policy): held by that
        one, not by this one."""
        self.cutting = False
        """Running, and the mediator asked the driver to cut it (the interrupt policy)."""
        self.restarts: AbId | None = None
        """The AB the interrupt policy cut, which this one starts again."""
        self.turnable = False
        """An utterance that does not orient the robot itself, whose app lets the
        mediator turn the robot to the user first (the connect-channel policy), not
        yet looked at by the policy."""
        self.faces = False
        """What ``turnable`` was when the AB was requested (a restart of it is looked at
        again: it starts like any other AB, docs/rules.md 7.3 (2))."""
        self.looked = 0
        """Its tree's ``suspensions`` when the connect-channel policy last set
        ``turnable``: after a suspension, whether it faces the user is looked at anew
        (a turn made before it may have been undone meanwhile)."""
        self.faced_at: float | None = None
        """When the turn to the user put before it ended; words that did not start in that
        instant (they waited for the speaker) look whether they face the user again."""
        self.relooked = False
        """They did, once: another wait after the second turn starts them as they are
        (two apps' turns and returns could otherwise take the wheels from each other
        for ever)."""
        self.protected = False
        """The words with which an application replies to the answer of its own Q&A: they
        belong to the exchange (docs/rules.md 7.4): they outrank every other application's
        AB, reactions included, and are never cut."""
        self.deferred = False
        """A policy put an AB of its own before it when it was ready (a turn to the user,
        a return): it stays in line for its devices meanwhile."""
        self.reserving = False
        """Pending right after a waiting or running AB of a reaction, or behind a policy's
        AB (``deferred``): its devices are kept from the ABs it outranks (docs/rules.md
        7.1), in ``WorkingMemory.reserving``."""
        self.started_at = 0.0
        """When it started (running, or done)."""
        self.cut_by: App | None = None
        """The application whose reaction had it cut (the interrupt policy)."""
        self.cut_for: Node | None = None
        """The reaction's AB it was cut for; on its restart: that AB, which goes first
        (docs/rules.md 7.3 (2): the restart comes after the reaction)."""
        self.parked: App | None = None
        """The app whose hold (block, stream hold, talk) keeps it: out of the ranking."""
        self.once = False
        """Another application's reaction cut it, or the AB it starts again: it is not
        cut again by another application (docs/rules.md 7.3 (2)); the user may."""
        self.by_user = False
        """Running, and being cut because the user spoke over it (barge-in)."""
        self.taker: App | None = None
        """With ``by_user``: the application that took the user's words (None: none
        did, a false interruption)."""
        self.dropped = False
        """Being cut, and its application asked for what shares its devices to go (a
        request ``order="asap"``): it is dropped, not started again."""
        self.not_before = 0.0
        """It may not start before this instant (an utterance a false interruption cut
        goes on after the robot's pause)."""
