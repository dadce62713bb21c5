"""An independent oracle for the mediator: the rules of docs/mediator.md as a plain model.

It looks only at what anyone outside the mediator can see: the :class:`Decision`
records (the ``record=`` callback), :meth:`Mediator.snapshot` at quiescent
points (after every outermost operation), the catalog, the configuration, and
what the caller tells it (the Commands it requested, the callbacks its apps
got, the longest AB it scripted). It imports no private module of the mediator
and reuses none of its ranking or hold code: each rule is written again here,
the slow, obvious way.

Checked after every operation (:meth:`Oracle.observe`):

- *devices*: no two running ABs share a device, from the decisions and from
  the snapshot, and the two agree;
- *never cut*: an AB starts at most once, never after it was cancelled, ends
  at most once and only while running; a ``cancel`` names a started AB only
  for a feedback loop stopped between iterations, after that AB ended;
- *holds respected*: no AB started while another, non-demoted app's block (or,
  for the first AB of a new stream that is no reaction, its armed stream hold)
  was in force on one of its devices all along, nor, for a Command that breaks
  the channel, while another app talked all along;
- *nothing startable waits*: a plain walk of the waiting list in rank order
  (:func:`left_waiting`) finds nothing the mediator should have started;
- *callbacks*: a Command gets at most one ended/cancelled callback, and none
  once its app is unloaded.

Over the whole run: the time each app keeps the others waiting
(:func:`keeping`) stays within its wait share plus the longest AB in any
window of its budget (:meth:`Oracle.conclude`), except where no mediator that
never cuts an AB could promise it (see ``Oracle._check_share``: windows in
which the app kept waiting had itself lost its precedence, and waits for an AB
that started with no rival; such overruns of the literal bound are kept in
:attr:`Oracle.notes`); at the end every started AB ended, working memory is
empty, and every Command of an app still loaded got exactly one callback.

Which trees are reactions (docs/rules.md 7.1) and which streams are under way
(7.2) the oracle works out itself (:class:`Streams`): a tree is a reaction
from the moment a request the caller made while handling a reactive event
(:meth:`Oracle.requested` with ``reaction=True``) files into it, unless that
request follows an end (it then only continues its tree); the latest such
request ranks first. A tree is under way once any of its ABs started, unless it is suspended
(resuming an interrupted stream is taking the floor anew).

Where the model differs from :func:`prima.mediator.testing.plain_scan` (which
reuses the mediator's ranking and hold code): it ranks from the snapshot alone
(no "parent just finished": at a quiescent point it is empty); an AB held by
the channel rule reserves nothing, like one held by a block or stream hold; it
also checks holds over each operation, the two device books against each
other, the callbacks, and the wait share.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from prima.mediator import (
    AbId,
    TreeId,
    AppKind,
    Blend,
    Catalog,
    CommandId,
    Decision,
    DecisionKind,
    HoldView,
    MediatorConfig,
    NodeState,
    NodeView,
    Priority,
    Rule,
    Snapshot,
    TreeView,
)
from prima.vocab import DEFAULT_BUDGETS, Budgets

__all__ = ["FEEDBACK_STOPPED", "Oracle", "Streams", "keeping", "left_waiting", "rank_key",
           "window_peak"]

FEEDBACK_STOPPED = "feedback loop stopped between iterations"
"""The one ``cancel`` that may name an AB that ran (docs: ASAP, unloading)."""

TALK = frozenset({"speaker", "speech-recognition"})

_RankKey = tuple[int, int, int, int, tuple[int, int], tuple[int, int], int, int]
_RankKeyFn = Callable[[NodeView], _RankKey]


# ---------------------------------------------------------------- the model
@dataclass
class Streams:
    """What the oracle knows of each tree, worked out from the decisions."""

    reaction: dict[TreeId, int] = field(default_factory=dict)
    """Reaction trees -> the order of their latest reaction request (larger: later)."""
    started: set[TreeId] = field(default_factory=set)
    """Trees some AB of which started: streams under way."""
    user: set[TreeId] = field(default_factory=set)
    """Reactions to the user's own action (a touch, heard speech) whose first utterance
    has not been said in full yet: no later reaction to a perception or network event
    overtakes them (docs/rules.md 7.1)."""
    replies: set[AbId] = field(default_factory=set)
    """The words with which an app replied to its own Q&A's answer: they belong to the
    exchange (docs/rules.md 7.4): they go first, and are never cut."""
    before_replies: set[CommandId] = field(default_factory=set)
    """The Commands of a policy's ABs put before a reply (a return: each of its
    iterations ranks as the reply does)."""

    def replying(self, n: NodeView) -> bool:
        """``n`` is a reply's AB, or an AB a policy put before one."""
        return n.ab in self.replies or not self.before_replies.isdisjoint(n.command_ids)
    deferred: set[CommandId] = field(default_factory=set)
    """Commands a policy put an AB of its own before (a turn, a return): their AB stays
    in line for its devices meanwhile."""
    taken_for: dict[AbId, str] = field(default_factory=dict)
    """Restarts of words the user cut for the app that took them -> that app: they wait
    for its reaction (7.5), whose next AB keeps their devices as another app's would."""
    user_order: dict[TreeId, int] = field(default_factory=dict)
    """Reactions to the user's own action -> the order of that reaction's first request
    (its first words are the first of its requests or later ones said whole)."""
    user_since: dict[TreeId, float] = field(default_factory=dict)
    """Reactions to the user's own action -> when they became one (7.6 (1)'s bound)."""
    user_from: dict[TreeId, TreeId] = field(default_factory=dict)
    """... -> the first tree id no decision had named by then: the trees before it are
    the streams it interrupted (a later one is a stream of its own)."""
    newest: TreeId = -1
    """The largest tree id any decision named so far."""
    answer_hold: float = 30.0
    """How long a reaction to the user keeps the streams it interrupted waiting, at most,
    while its first words are ahead (``MediatorConfig.max_answer_hold``)."""
    following: frozenset[str] = frozenset()
    """The Commands that follow the user (never held so: following is not leaving)."""
    answered: dict[TreeId, int] = field(default_factory=dict)
    """Trees replying to the user's answer to their Q&A -> the order of that request,
    until their first words from then on are said in full: the user's own action, not
    rationed by the wait share (7.6 (4))."""
    returns: set[CommandId] = field(default_factory=set)
    """The restore-state policy's returns (they wait for any talk: 7.6 (3))."""
    unloaded: set[str] = field(default_factory=set)
    """Apps unloaded: a reaction of theirs answers nobody (what ABs of it still run)."""
    resting: dict[AbId, float] = field(default_factory=dict)
    """Restarts of words a false interruption cut -> the instant the robot's pause ends
    (they may not start before it; their application is still talking meanwhile)."""

    def keeps(self, r: NodeView, n: NodeView) -> bool:
        """Whether ``r`` (a reaction's next AB) is of an app it may keep ``n`` from: another
        application's, or, for a restart of words the user cut, the taker's reaction."""
        return r.app != n.app or (self.taken_for.get(n.ab) == r.app and r.tree != n.tree)

    def held_by_stream(self, tree: TreeId, suspended: Collection[TreeId]) -> bool:
        """A stream hold delays only new streams that are no reaction (7.1, 7.2): trees
        none of whose ABs started, or ``suspended`` ones (resuming is starting anew)."""
        return tree not in self.reaction and (tree not in self.started or tree in suspended)


@dataclass(frozen=True)
class _View:
    """What one snapshot says, indexed for the model."""

    snap: Snapshot
    nodes: dict[AbId, NodeView]
    waiting: list[NodeView]
    """Waiting ABs, best-ranked first."""
    busy: dict[str, NodeView]
    talkers: frozenset[str]
    """Apps running an AB on a talk device."""
    streams: Streams
    nexts: list[NodeView]
    """The next ABs of reactions, and replies, pending right after a waiting or running
    AB of their tree: they keep their devices from the ABs they outrank (7.1)."""
    standing: Callable[[NodeView], tuple[int, int, int, int, tuple[int, int]]]

    @classmethod
    def of(cls, snap: Snapshot, talk: frozenset[str], streams: Streams) -> _View:
        nodes = {n.ab: n for tree in snap.trees for n in tree.nodes}
        busy = {d: nodes[ab] for d, ab in snap.busy}
        # (an app whose words a false interruption cut, waiting out the pause to go on,
        # is still talking: 7.5)
        talkers = frozenset([n.app for d, n in busy.items() if d in talk] + [
            nodes[ab].app for ab, due in streams.resting.items()
            if due > snap.t and ab in nodes and nodes[ab].state is NodeState.WAITING])
        waiting = sorted((nodes[ab] for ab in snap.waiting), key=rank_key(snap, streams))
        def in_line(p: NodeView) -> bool:
            """Waiting or running, or pending behind a policy's AB put before it (that
            AB is in line: what comes after it keeps its devices meanwhile)."""
            return p.state in (NodeState.WAITING, NodeState.RUNNING) or (
                p.state is NodeState.PENDING and p.parent in nodes
                and not streams.deferred.isdisjoint(p.command_ids)
                and nodes[p.parent].state in (NodeState.WAITING, NodeState.RUNNING))

        nexts = [n for n in nodes.values()
                 if n.state is NodeState.PENDING and n.parent in nodes
                 and in_line(nodes[n.parent])
                 and (n.tree in streams.reaction or streams.replying(n)
                      or not streams.deferred.isdisjoint(n.command_ids))]
        return cls(snap, nodes, waiting, busy, talkers, streams, nexts,
                   standing_key(snap, streams))

    def kept_for(self, n: NodeView, nexts: Sequence[NodeView] | None = None,
                 besides: TreeId | None = None) -> NodeView | None:
        """The next AB of another app's reaction (or reply) that keeps one of ``n``'s
        devices from it (7.1): its priority is not lower, and it outranks ``n`` on the
        rest of what an AB keeps whatever the waiting order (of ``nexts``, if given)."""
        mine = self.standing(n)
        for r in self.nexts if nexts is None else nexts:
            theirs = self.standing(r)
            if self.streams.keeps(r, n) and r.tree != besides \
                    and set(r.devices) & set(n.devices) \
                    and theirs[0] <= mine[0] and theirs[1:] < mine[1:] \
                    and not self.behind_hold(r, n.app):
                return r
        return None

    def behind_hold(self, r: NodeView, app: str) -> bool:
        """The next AB ``r`` waits behind an AB that ``app``'s block or stream hold keeps:
        it keeps nothing from ``app`` (they would wait for each other)."""
        before = self.nodes.get(r.parent) if r.parent is not None else None
        return before is not None and before.state is NodeState.WAITING \
            and app in self.holders(before)

    def keepers(self, n: NodeView, excused: Collection[AbId] = ()) -> list[str]:
        """The apps whose reaction's (or reply's) next AB keeps a device from ``n``
        (but the ``excused`` ones)."""
        mine = self.standing(n)
        return [r.app for r in self.nexts
                if r.app != n.app and r.ab not in excused  # (an app's own: no budget matter)
                and set(r.devices) & set(n.devices)
                and (theirs := self.standing(r))[0] <= mine[0] and theirs[1:] < mine[1:]
                and not self.behind_hold(r, n.app)]

    def channel_held(self, n: NodeView) -> bool:
        """A Command that breaks the channel waits while another app talks; the
        restore-state policy's return, while any app talks (its own too: 7.6 (3))."""
        return n.priority is Priority.LOW and bool(
            self.talkers if not self.streams.returns.isdisjoint(n.command_ids)
            else self.talkers - {n.app})

    def holders(self, n: NodeView) -> list[str]:
        """Other, non-demoted apps whose block or armed stream hold keeps ``n``."""
        return [h.app for h in self.snap.holds
                if _applies(h, n, self.snap.demoted, self.streams, self.snap.suspended)]

    def held(self, n: NodeView) -> bool:
        """Held by the channel rule, another app's hold, kept for another app's reaction
        (7.1), or waiting while a reaction answers the user (7.6 (1)): it reserves
        nothing."""
        return self.channel_held(n) or bool(self.holders(n)) or self.kept_for(n) is not None \
            or self.answer_holder(n) is not None

    def answer_holder(self, n: NodeView) -> TreeView | None:
        """The reaction to the user's own action (of another tree) that has not said its
        first words, within its bound, that keeps ``n``'s stream waiting on every device
        (7.6 (1)), the latest of them: only a stream there when it became one, and no
        later reaction (that is a stream of its own); never for a reply to an answer,
        following the user, or an AB of its app's block under way."""
        streams = self.streams
        if streams.replying(n) or not streams.user:
            return None
        if all(c in streams.following for c in n.command.split("+")):
            return None
        if any(h.kind == "block" and h.app == n.app and set(h.devices) & set(n.devices)
               for h in self.snap.holds):
            return None
        mine = streams.reaction.get(n.tree)
        replying = streams.answered.get(n.tree)
        if replying is not None and (mine is None or replying > mine):
            mine = replying  # (the reply to the user's later answer is no stream it holds)
        found: TreeView | None = None
        for tree in self.snap.trees:
            if tree.id == n.tree or tree.id not in streams.user or tree.app in streams.unloaded \
                    or tree.id not in streams.reaction or n.tree >= streams.user_from[tree.id]:
                continue
            if self.snap.t >= streams.user_since[tree.id] + streams.answer_hold:
                continue  # (its bound passed)
            order = streams.reaction[tree.id]
            if mine is not None and mine > order:
                continue
            if found is None or order > streams.reaction[found.id]:
                found = tree
        return found


def _applies(h: HoldView, n: NodeView, demoted: Iterable[str], streams: Streams,
             suspended: Collection[TreeId]) -> bool:
    if h.app == n.app or h.app in demoted or not set(h.devices) & set(n.devices):
        return False
    return h.kind == "block" or streams.held_by_stream(n.tree, suspended)


def rank_key(snap: Snapshot, streams: Streams) -> _RankKeyFn:
    """Rule 4 at a quiescent point (nothing's parent *just* finished): HIGH first;
    apps that lost their precedence after the others; the ABs of reactions
    first, the latest reaction first; suspended trees, the most recently
    suspended first; the oldest request; the lowest AB id."""
    order = {tree: i for i, tree in enumerate(snap.suspended)}  # top of the stack first
    standing = standing_key(snap, streams)

    def key(n: NodeView) -> _RankKey:
        return (
            *standing(n),
            (0, order[n.tree]) if n.tree in order else (1, 0),
            n.seq,
            n.ab,
        )
    return key


def standing_key(snap: Snapshot, streams: Streams
                 ) -> Callable[[NodeView], tuple[int, int, int, int, tuple[int, int]]]:
    """What an AB keeps whatever the waiting order: HIGH first (a reply to an answer
    ranks as HIGH, and so does a return put before it); the reply to an answer (7.4);
    apps that lost their precedence after the others (but for their reactions to the
    user's own action, 7.6 (4)); reactions to the user's own action whose first words
    are not yet said; the latest reaction (7.1)."""
    demoted = set(snap.demoted)
    reaction = streams.reaction
    user = streams.user
    answered = streams.answered
    replying = streams.replying

    def key(n: NodeView) -> tuple[int, int, int, int, tuple[int, int]]:
        answering = n.tree in user and n.tree in reaction
        return (
            0 if n.priority is Priority.HIGH or replying(n) else 1,
            0 if replying(n) else 1,
            # (7.6 (4): the user's own action is answered past the share, until its words;
            # so is the user's answer to a Q&A)
            1 if n.app in demoted and not (answering or n.tree in answered) else 0,
            0 if answering else 1,
            (0, -reaction[n.tree]) if n.tree in reaction else (1, 0),
        )
    return key


def left_waiting(snap: Snapshot, streams: Streams, talk: frozenset[str] = TALK,
                 cut_for: Mapping[AbId, AbId] | None = None) -> list[AbId]:
    """Waiting ABs a plain rank-order walk would start now (must be none); ``cut_for``:
    restarts -> the reaction's AB each was cut for (:func:`_after_its_reaction`).

    A held AB (another app's block or, for a new stream that is no reaction,
    stream hold; or, for a
    Command that breaks the channel, another app talking) reserves nothing. Any
    other AB whose devices are free and not reserved by a better-ranked waiting
    AB should be running; one that cannot start reserves its devices.
    """
    return _left_waiting(_View.of(snap, talk, streams), cut_for or {})


def _left_waiting(v: _View, cut_for: Mapping[AbId, AbId]) -> list[AbId]:
    reserved: set[str] = set()
    out: list[AbId] = []
    for n in v.waiting:
        if v.held(n) or v.kept_for(n) is not None or _after_its_reaction(v, n, cut_for):
            continue  # (kept for a reaction's next AB, it steps aside too: 7.1; so does a
            # restart waiting for the reaction it was cut for, reserving nothing: 7.3 (2))
        devices = set(n.devices)
        if not devices & reserved and not any(d in v.busy for d in devices):
            out.append(n.ab)
        reserved |= devices
    return out


def _after_its_reaction(v: _View, n: NodeView, cut_for: Mapping[AbId, AbId]) -> bool:
    """A restart waits (stepping aside) for the reaction's AB it was cut for while that AB
    steps aside for another reaction's next AB (not one after the restart in its own
    tree) and its stream goes before the restart's, priority aside (7.3 (2), 7.1)."""
    r = v.nodes.get(cut_for.get(n.ab, -1))
    if r is None or r.state is not NodeState.WAITING:
        return False
    return v.kept_for(r, besides=n.tree) is not None \
        and v.standing(r)[1:] < v.standing(n)[1:]


def keeping(snap: Snapshot, streams: Streams, talk: frozenset[str] = TALK,
            uncontended: Collection[AbId] = ()) -> set[str]:
    """The apps that keep another app waiting now (the wait-share definition)."""
    return _keeping(_View.of(snap, talk, streams), uncontended)


def _keeping(v: _View, uncontended: Collection[AbId] = (),
             excused: Collection[AbId] = ()) -> set[str]:
    """App A keeps another waiting when, on some device, another app has a waiting,
    unparked AB whose priority is not lower than that of A's AB holding the device
    (running on it or, on a free device, the best-ranked waiting unparked AB), or
    when A's stream hold or block parks another app's AB (the channel rule at work
    is not a budget matter; of several apps whose holds apply, the one that parked
    it). A running AB in ``uncontended`` (it started while no
    other app's AB wanted its devices) keeps nobody: waiting for it is first come,
    first served, not a precedence taken. A reply's AB in ``excused`` (its
    application lost its precedence: the reply goes first past the share, 7.4), next
    or waiting first in line, keeps nobody either."""
    out: set[str] = set()
    wanting: dict[str, list[NodeView]] = {}
    for n in v.waiting:
        if n.parked_by is None:
            for d in n.devices:
                wanting.setdefault(d, []).append(n)
        elif n.parked_by == n.app:
            pass  # (a restart waiting for its own app's reaction to the user's words, 7.5)
        elif not v.channel_held(n):
            holders = v.holders(n)
            if n.parked_by in holders:  # (another app's block parked it: that hold's doing,
                out.add(n.parked_by)    # whoever answers the user meanwhile)
                continue
            answering = v.answer_holder(n)
            if answering is not None:
                # held while another app's reaction answers the user (7.6 (1))
                if answering.app != n.app and answering.app not in v.snap.demoted:
                    out.add(answering.app)
                continue
            # Kept by several apps' holds (three apps or more): the wait is the
            # parking hold's doing; the others would keep nothing it did not.
            if not holders:  # kept for another app's reaction (7.1): its precedence
                holders = v.keepers(n, excused)
            out.update([n.parked_by] if n.parked_by in holders else holders)
    for d, ws in wanting.items():
        holder = v.busy.get(d) or ws[0]
        if holder.ab in uncontended or holder.ab in excused:
            continue
        if any(w.app != holder.app and w.priority >= holder.priority for w in ws):
            out.add(holder.app)
    return out


Spans = list[tuple[float, float]]


def window_peak(intervals: Sequence[tuple[float, float]], window: float,
                exempt: Callable[[float, float], bool] | None = None) -> tuple[float, float]:
    """The most time that disjoint ``intervals`` cover within any window of length
    ``window`` (leaving out the windows ``exempt(lo, hi)`` names); returns (that
    time, where such a window starts)."""
    best, where = 0.0, 0.0
    # A best window starts where an interval starts, or ends where one ends.
    for lo in [b for b, _ in intervals] + [e - window for _, e in intervals]:
        hi = lo + window
        total = sum(min(e, hi) - max(b, lo) for b, e in intervals if b < hi and e > lo)
        if total > best and (exempt is None or not exempt(lo, hi)):
            best, where = total, lo
    return best, where


class _Timeline:
    """When each app was in some state (keeping others waiting, demoted), from the
    quiescent points: a state seen at one lasts until the next."""

    def __init__(self) -> None:
        self.spans: dict[str, Spans] = {}
        self._since: dict[str, float] = {}

    def update(self, now: float, active: Iterable[str]) -> None:
        active = set(active)
        for app in [a for a in self._since if a not in active]:
            self._close(app, now)
        for app in active:
            self._since.setdefault(app, now)

    def close(self, now: float) -> None:
        self.update(now, ())

    def _close(self, app: str, now: float) -> None:
        begin = self._since.pop(app)
        if now <= begin:
            return
        spans = self.spans.setdefault(app, [])
        if spans and spans[-1][1] >= begin:
            spans[-1] = (spans[-1][0], now)
        else:
            spans.append((begin, now))

    def during(self, app: str, lo: float, hi: float) -> bool:
        """Was ``app`` in the state at some time within [lo, hi]?"""
        return any(b <= hi and e >= lo for b, e in self.spans.get(app, ()))


# ---------------------------------------------------------------- the oracle
@dataclass
class _Books:
    """What the decisions told so far."""

    kinds: dict[str, AppKind] = field(default_factory=dict)
    started: set[AbId] = field(default_factory=set)
    ended: set[AbId] = field(default_factory=set)
    cancelled: set[AbId] = field(default_factory=set)
    running: dict[AbId, tuple[str, ...]] = field(default_factory=dict)
    occupied: dict[str, AbId] = field(default_factory=dict)
    commands: dict[AbId, str] = field(default_factory=dict)
    """Running AB -> its Commands (``A+B``)."""
    blending: dict[str, AbId] = field(default_factory=dict)
    """Device -> the running AB blended over its occupant (a declared blend)."""


class Oracle:
    """Checks one run of a mediator, from outside. Call :meth:`observe` after every
    operation, :meth:`requested` and :meth:`callback` as they happen, and
    :meth:`conclude` at the end; :attr:`violations` says what went wrong."""

    def __init__(self, catalog: Catalog, config: MediatorConfig, *, longest: float,
                 tolerance: float = 1e-6, limit: int = 5) -> None:
        self._catalog = catalog
        self._config = config
        self._talk = catalog.talk_devices
        self._longest = longest
        self._tolerance = tolerance
        self._limit = limit
        self.violations: list[str] = []
        self.books = _Books()
        self._seen = 0
        self._prev: _View | None = None
        self._kept = _Timeline()
        """When each app kept another waiting (the literal definition)."""
        self._took = _Timeline()
        """... not counting waits for ABs that started with no rival (first come)."""
        self.notes: list[str] = []
        """Overruns of the literal bound that the checked one excuses (by design)."""
        self._demoted = _Timeline()
        """When each app had lost its precedence."""
        self._uncontended: set[AbId] = set()
        """Running ABs that started while no other app wanted their devices."""
        self._requested: dict[CommandId, str] = {}
        self.streams = Streams(answer_hold=config.max_answer_hold, following=frozenset(
            c.name for c in catalog.commands.values() if c.follows_user))
        self._reactions: set[CommandId] = set()
        """First Commands of the requests made while handling a reactive event."""
        self._users: set[CommandId] = set()
        """... of those, the ones handling the user's own action (7.1)."""
        self._continuing: set[CommandId] = set()
        """... of those, the ones a handling asked for after its first request: the same
        reaction as that one (7.1)."""
        self._reacting: dict[str, int] = {}
        """App -> the order of its latest reaction's first request."""
        self._answering: set[CommandId] = set()
        """First Commands of the requests made while handling a Q&A's answer (7.4)."""
        self._reply_commands: dict[CommandId, AbId] = {}
        """The Commands of replies (7.4), and the AB of each."""
        self._order: dict[CommandId, int] = {}
        """Command -> the order of the request that asked for it."""
        self._reranked: list[Decision] = []
        """The ends in this operation that said a user reaction's first words in full, or
        a reply's to the user's answer (7.6 (4)), and the unloads in it (an app gone
        answers nobody, 7.6 (1)): ranks and holds changed within the operation."""
        self._restarts: set[AbId] = set()
        """ABs that start a cut AB again: never cut by another application (7.3 (2): at
        most one cut; the user's barge-in may cut them, 7.5)."""
        self._by_user: dict[AbId, Decision] = {}
        """ABs cut because the user spoke over them, with the hear decision (7.5)."""
        self._rest: dict[AbId, float] = {}
        """Cut by words no app took, ended: when the robot's pause is over."""
        self._resting: dict[AbId, float] = self.streams.resting
        """ABs that start such a cut AB again, and the instant they may start."""
        self._cut_for: dict[AbId, AbId] = {}
        """A cut AB, then its restart -> the reaction's AB it was cut for."""
        self._hear: Decision | None = None
        """The latest hear decision of the operation under way."""
        self._requests = 0
        self._exempt: set[AbId] = set()
        """ABs that started in a reaction or a stream under way (no stream hold applies)."""
        self._callbacks: dict[CommandId, int] = {}
        self._cutting: set[AbId] = set()
        """ABs the mediator asked the driver to cut (the interrupt policy)."""
        self._to_restart: set[AbId] = set()
        """Cut ABs whose restart must be requested in the same operation."""
        self._interrupted: set[AbId] = set()
        """Cut ABs restarted or dropped (each exactly once)."""
        self._bounded: set[AbId] = set()
        """ABs that started blended within a bound of the user (the channel rule does
        not hold them)."""

    # ------------------------------------------------------------ reporting
    def fail(self, what: str) -> None:
        if len(self.violations) < self._limit:
            self.violations.append(what)

    # ------------------------------------------------------------ the app side
    def requested(self, app: str, ids: Sequence[CommandId], reaction: bool = False,
                  user: bool = False, answer: bool = False, first: bool = True) -> None:
        """``app`` requested the Commands ``ids``; ``reaction``: while handling a
        reactive event (the caller set ``Request.reactive`` or ``reaction``), ``user``:
        the user's own action (``Request.user``), ``first``: the handling's first request
        (``Request.reactive``: a later one is the same reaction, 7.1); ``answer``:
        ``follows`` names a Q&A the user answered (its reply, if words, belongs to the
        exchange: 7.4)."""
        for c in ids:
            self._requested[c] = app
        if reaction and ids:
            self._reactions.add(ids[0])
            if not first:
                self._continuing.add(ids[0])
            if user:
                self._users.add(ids[0])
        if answer and ids:
            self._answering.add(ids[0])

    def callback(self, app: str, command: CommandId, what: str, loaded: bool) -> None:
        """An app was told its Command ``what`` (ended/cancelled); ``loaded``: the
        app is registered at that moment."""
        n = self._callbacks.get(command, 0) + 1
        self._callbacks[command] = n
        if n > 1:
            self.fail(f"Command {command} of {app} got a second callback ({what})")
        if not loaded:
            self.fail(f"{app} was told Command {command} {what} after it was unloaded")
        if self._requested.get(command, app) != app:
            self.fail(f"{app} was told about Command {command} of {self._requested[command]}")

    # ------------------------------------------------------------ each operation
    def observe(self, decisions: Sequence[Decision], snap: Snapshot) -> None:
        """After an operation: read the new decisions, then check the snapshot."""
        new = decisions[self._seen:]
        self._seen = len(decisions)
        self._reranked.clear()
        before = set(self._prev.snap.suspended) if self._prev is not None else set()
        suspended = set(before)  # what this operation's starts resume leaves it
        for d in new:
            self._decision(d, suspended)
        for ab in sorted(self._to_restart):
            self.fail(f"t={snap.t:g}: AB{ab} was cut to restart, and no restart was requested")
        self._to_restart.clear()
        # A suspended tree that left the stack without resuming left working memory:
        # a request that joins it again takes the floor anew (7.2).
        starts = {d.tree for d in new if d.kind is DecisionKind.START}
        for tree in before - set(snap.suspended) - starts:
            self.streams.started.discard(tree)
        v = _View.of(snap, self._talk, self.streams)
        self._check_running(v)
        if self._prev is not None:
            self._check_holds(self._prev, v, new)
            self._check_outranked(self._prev, v, new)
            self._contention(self._prev, v, new)
        # (what waits out the robot's pause after a false interruption may wait)
        # (exactly: the pause ends at the clock's own sum, which the mediator compares)
        left = [ab for ab in _left_waiting(v, self._cut_for)
                if self._resting.get(ab, snap.t) <= snap.t]
        if left:
            self.fail(f"t={snap.t:g}: AB{left[0]} could start but waits "
                      f"({self._describe(v, left[0])})")
        self._account(v)
        self._prev = v

    def _decision(self, d: Decision, suspended: set[TreeId]) -> None:
        b = self.books
        if d.kind is DecisionKind.LOAD and d.app is not None:
            b.kinds[d.app] = AppKind[d.detail]
        elif d.kind is DecisionKind.UNLOAD and d.app is not None:
            self.streams.unloaded.add(d.app)
            self._reranked.append(d)  # (its reaction to the user holds nothing from now on)
        elif d.kind is DecisionKind.HEAR:
            self._hear = d
        elif d.kind is DecisionKind.INTERRUPT or (d.kind is DecisionKind.REQUEST
                                                  and d.rule is Rule.RESTART):
            self._interrupt(d)
        elif d.kind is DecisionKind.REQUEST:
            self._request(d)
        elif d.kind is DecisionKind.START and d.ab is not None:
            self._start(d.ab, d, suspended)
        elif d.kind is DecisionKind.END and d.ab is not None:
            self._end(d.ab, d)
        elif d.kind is DecisionKind.CANCEL and d.ab is not None:
            if d.ab not in b.started:
                b.cancelled.add(d.ab)
            elif d.detail != FEEDBACK_STOPPED or d.ab not in b.ended:
                self.fail(f"t={d.t:g}: AB{d.ab} was cancelled after it started "
                          f"({d.rule.value}: {d.detail or 'no detail'})")

    def _request(self, d: Decision) -> None:
        """A request joined working memory: its order, its words, whether its tree is now
        a reaction (to the user's own action), whether it is a reply."""
        self._requests += 1
        if d.tree is not None and d.tree > self.streams.newest:
            self.streams.newest = d.tree
        for cid in d.command_ids:
            self._order[cid] = self._requests
        if d.command_id in self._reactions and d.command_id not in self._continuing \
                and d.app is not None:
            self._reacting[d.app] = self._requests
        if (d.command_id in self._reactions and d.rule is not Rule.END_EVENT
                and d.tree is not None):
            order = self._requests
            if d.command_id in self._continuing and d.app in self._reacting:
                order = self._reacting[d.app]  # (the same reaction as its first request)
            if self.streams.reaction.get(d.tree, -1) >= order:
                self._reply(d)
                return  # (already that reaction, or a later one)
            self.streams.reaction[d.tree] = order
            if d.command_id in self._users:
                self.streams.user.add(d.tree)
                self.streams.user_order[d.tree] = order
                self.streams.user_since[d.tree] = d.t
                self.streams.user_from[d.tree] = self.streams.newest + 1
            # (a later reaction to a perception leaves a reaction to the user whose first
            # words are ahead one: the user's words first, 7.1)
        if (d.command_id in self._answering and d.rule is Rule.END_EVENT
                and d.tree is not None and self._config.reactions):
            self.streams.answered.setdefault(d.tree, self._requests)
        self._reply(d)

    def _reply(self, d: Decision) -> None:
        """A request's root AB is a reply (7.4): the first AB an answer handler requested,
        with words and no question of its own; or a policy's AB put before one."""
        if d.ab is None:
            return
        if d.rule is Rule.RESTORE_STATE:
            self.streams.returns.update(d.command_ids)
        if d.precedes is not None:
            self.streams.deferred.add(d.precedes)
            first = self._reply_commands.get(d.precedes)
            if first is not None and first not in self.books.started:
                # put before the reply's words (not before its loop's later iteration,
                # which comes after them: the exchange is over by then)
                self.streams.replies.add(d.ab)
                self.streams.before_replies.update(d.command_ids)
            return
        if d.command_id not in self._answering or d.rule is not Rule.END_EVENT:
            return
        root = d.calls[:len((d.command or "").split("+"))]
        specs = [(self._catalog[c.command], c) for c in root]
        if any(spec.spoken(c.args) for spec, c in specs) and \
                not any(spec.listens for spec, _c in specs):
            self.streams.replies.add(d.ab)
            for cid in d.command_ids[:len(root)]:
                self._reply_commands[cid] = d.ab

    def _end(self, ab: AbId, d: Decision) -> None:
        b = self.books
        if ab not in b.running:
            self.fail(f"t={d.t:g}: AB{ab} ended but was not running")
            return
        if (d.rule is Rule.COMPLETED and d.tree in self.streams.user
                and self._order.get(d.command_id or 0, 0) >= self.streams.user_order[d.tree]
                and any(self._catalog[c.command].spoken(c.args) for c in d.calls)):
            self.streams.user.discard(d.tree)  # the reaction's first words were said in full
            self._reranked.append(d)
        answered = self.streams.answered
        if (d.rule is Rule.COMPLETED and d.tree in answered
                and self._order.get(d.command_id or 0, 0) >= answered[d.tree]
                and any(self._catalog[c.command].spoken(c.args) for c in d.calls)):
            del answered[d.tree]  # the reply's first words were said in full
            self._reranked.append(d)
        if d.rule in (Rule.INTERRUPT, Rule.BARGE_IN):
            self._interrupt(d)
        b.ended.add(ab)
        b.commands.pop(ab, None)
        for dev in b.running.pop(ab):
            if b.occupied.get(dev) == ab:
                b.occupied.pop(dev)
                if dev in b.blending:  # what blended over it keeps the device
                    b.occupied[dev] = b.blending.pop(dev)
            elif b.blending.get(dev) == ab:
                b.blending.pop(dev)

    def _interrupt(self, d: Decision) -> None:
        """The interrupt policy: a cut is asked for a running AB, once; the AB ends cut
        only then; it is restarted (in the same operation) or dropped, exactly once."""
        ab = d.ab if d.ab is not None else -1
        if d.kind is DecisionKind.INTERRUPT:
            if ab not in self.books.running or ab in self._cutting:
                self.fail(f"t={d.t:g}: AB{ab} was cut while not running, or twice")
            if d.rule is Rule.BARGE_IN:
                self._barge_in(ab, d)
            else:
                if d.before is not None:
                    self._cut_for[ab] = d.before
                if ab in self._restarts:
                    self.fail(f"t={d.t:g}: AB{ab} was cut again (it restarts a cut AB)")
                if ab in self.streams.replies:
                    self.fail(f"t={d.t:g}: AB{ab} was cut, but it replies to an answer")
            self._cutting.add(ab)
        elif d.kind is DecisionKind.END:
            self._cut_ended(ab, d)
        elif d.kind is DecisionKind.REQUEST:
            self._restarted(d)

    def _restarted(self, d: Decision) -> None:
        """A cut AB's restart was asked for: it was cut to restart, once; it is bound by
        the one cut by another app; cut by words no app took, it goes on after the pause,
        and as the reply it was (7.4)."""
        self._requests += 1
        cut = d.before if d.before is not None else -1
        if cut not in self._to_restart:
            self.fail(f"t={d.t:g}: AB{cut} was restarted but not cut to restart")
        self._to_restart.discard(cut)
        self._interrupted.add(cut)
        if d.ab is None:
            return
        if cut not in self._by_user or cut in self._restarts:
            self._restarts.add(d.ab)  # (the bound of one cut by another app)
        hear = self._by_user.get(cut)
        if hear is not None and hear.app is not None:
            self.streams.taken_for[d.ab] = hear.app  # (it waits for the taker's reaction)
        if cut in self._rest:
            self._resting[d.ab] = self._rest.pop(cut)
            if cut in self.streams.replies:
                # a reply cut by words no app took goes on as the reply (7.4): the
                # exchange is not over, and what a policy puts before it is part of it
                self.streams.replies.add(d.ab)
                for cid in d.command_ids:
                    if cid in self._reply_commands:
                        self._reply_commands[cid] = d.ab
        if cut in self._cut_for:
            self._cut_for[d.ab] = self._cut_for.pop(cut)

    def _cut_ended(self, ab: AbId, d: Decision) -> None:
        """A cut AB ended: it was being cut (for the user's words if its end says so),
        and is restarted or dropped; cut for words no app took, not before the pause."""
        if ab not in self._cutting or ab in self._interrupted:
            self.fail(f"t={d.t:g}: AB{ab} ended cut, but was not being cut")
        if (d.rule is Rule.BARGE_IN) != (ab in self._by_user):
            self.fail(f"t={d.t:g}: AB{ab} ended cut for {d.rule.value}, but it was cut "
                      f"{'by the user' if ab in self._by_user else 'for a reaction'}")
        hear = self._by_user.get(ab)
        if hear is not None and hear.rule is Rule.NOMATCH:
            self._rest[ab] = d.t + self._config.resume_pause
        if d.detail == "dropped":
            self._interrupted.add(ab)
        else:
            self._to_restart.add(ab)

    def _barge_in(self, ab: AbId, d: Decision) -> None:
        """A cut for the user's words (7.5): asked after the operation's hear decision,
        which was not a backchannel, with the barge-in policy on, of an AB with words."""
        hear = self._hear
        if not self._config.barge_in:
            self.fail(f"t={d.t:g}: AB{ab} was cut for the user's words with barge-in off")
        if hear is None or hear.t != d.t or hear.rule is Rule.BACKCHANNEL:
            self.fail(f"t={d.t:g}: AB{ab} was cut for the user's words, but none were heard "
                      "(or only a backchannel)")
        elif not any(self._catalog[c.command].spoken(c.args) for c in d.calls):
            self.fail(f"t={d.t:g}: AB{ab} was cut for the user's words, but says none")
        if hear is not None:
            self._by_user[ab] = hear

    def _start(self, ab: AbId, d: Decision, suspended: set[TreeId]) -> None:
        b = self.books
        due = self._resting.pop(ab, None)
        if due is not None and d.t < due - self._tolerance:
            self.fail(f"t={d.t:g}: AB{ab} went on after a false interruption before the "
                      f"robot's pause was over (at {due:g})")
        if ab in b.started:
            self.fail(f"t={d.t:g}: AB{ab} started twice")
        if ab in b.cancelled:
            self.fail(f"t={d.t:g}: AB{ab} started after it was cancelled")
        for dev in d.devices:
            other = b.occupied.get(dev)
            if other is None:
                b.occupied[dev] = ab
            elif d.rule is Rule.BLEND and (blend := self._declared_blend(d.command, other, dev)):
                b.blending[dev] = ab
                if blend.max_user_distance is not None:
                    self._bounded.add(ab)
            else:
                self.fail(f"t={d.t:g}: AB{ab} started on {dev}, held by running AB{other}")
        b.started.add(ab)
        b.running[ab] = d.devices
        b.commands[ab] = d.command or ""
        if d.tree is not None:
            if not self.streams.held_by_stream(d.tree, suspended):
                self._exempt.add(ab)
            self.streams.started.add(d.tree)
            suspended.discard(d.tree)  # resumed: a stream under way again

    def _declared_blend(self, command: str | None, other: AbId, dev: str) -> Blend | None:
        """The robot-declared blend that lets ``command`` run over ``other`` on ``dev``,
        if nothing runs blended over ``other`` there yet and ``other`` is no blend."""
        b = self.books
        if dev in b.blending or other in b.blending.values():
            return None
        specs = self._catalog.commands
        local = [specs[c] for c in (command or "").split("+") if c in specs]
        over = [specs[c] for c in b.commands.get(other, "").split("+") if c in specs]
        return self._catalog.blend(local, over, dev)

    def _check_running(self, v: _View) -> None:
        snap = v.snap
        mine = {ab: tuple(sorted(devs)) for ab, devs in self.books.running.items()}
        theirs = {ab: tuple(sorted(devs)) for ab, devs in snap.running}
        if mine != theirs:
            self.fail(f"t={snap.t:g}: running ABs per decisions {sorted(mine)} "
                      f"!= per snapshot {sorted(theirs)}")
        owners: dict[str, AbId] = {}
        blending = self.books.blending
        for ab, devs in snap.running:
            for dev in devs:
                if blending.get(dev) == ab:
                    continue  # a declared blend (checked when it started)
                if dev in owners:
                    self.fail(f"t={snap.t:g}: AB{ab} and AB{owners[dev]} both run on {dev}")
                owners[dev] = ab
        if owners != dict(snap.busy):
            self.fail(f"t={snap.t:g}: device occupancy {dict(snap.busy)} != running ABs")

    def _check_holds(self, prev: _View, v: _View, new: Sequence[Decision]) -> None:
        """No AB started in this operation while a hold was in force all along."""
        starts = [d for d in new if d.kind is DecisionKind.START]
        if not starts:
            return
        busy_apps = {d.app for d in new if d.kind in (DecisionKind.REQUEST, DecisionKind.START,
                                                      DecisionKind.END, DecisionKind.CANCEL)}
        lasting = [h for h in prev.snap.holds if h in v.snap.holds
                   and h.app not in busy_apps and h.app not in v.snap.demoted]
        ended = {d.ab for d in new if d.kind is DecisionKind.END}
        talkers = {n.app for dev, n in prev.busy.items()
                   if dev in self._talk and n.ab not in ended}
        for d in starts:
            prio = self._priority(d)
            for h in lasting:
                if (h.app != d.app and h.app not in prev.snap.demoted
                        and set(h.devices) & set(d.devices)
                        and (h.kind == "block" or d.ab not in self._exempt)):
                    self.fail(f"t={d.t:g}: AB{d.ab} ({d.app} {d.command}) started while "
                              f"{h.app}'s {h.kind} held {', '.join(h.devices)}")
            if prio is Priority.LOW and talkers - {d.app} and d.ab not in self._bounded:
                self.fail(f"t={d.t:g}: AB{d.ab} ({d.app} {d.command}) breaks the channel "
                          f"but started while {sorted(talkers - {d.app})} talked")

    def _check_outranked(self, prev: _View, v: _View, new: Sequence[Decision]) -> None:
        """No AB started in this operation on a device that another app's AB wanted all
        along and that outranks it on what an AB keeps whatever the waiting order
        (priority, a reply to an answer, precedence, the user's own action first, the
        latest reaction): waiting for it unheld, or kept for it as a reaction's next AB
        (7.1, 7.4). A blend shares the device instead of taking it."""
        starts = [d for d in new if d.kind is DecisionKind.START and d.rule is not Rule.BLEND
                  and d.ab in v.nodes]
        if not starts or any(d.kind is DecisionKind.BUDGET for d in new):
            return  # (a precedence changed within the operation: ranks moved meanwhile)
        if self._reranked:
            # a reaction to the user's own action (or a reply to the user's answer) said
            # its first words within the operation (an utterance that takes no time), or
            # its app was unloaded: the starts before that were ranked with it first (and
            # its hold in force), the view knows it no longer is
            last = max(new.index(h) for h in self._reranked)
            starts = [d for d in starts if new.index(d) > last]
        held = {d.ab for d in new if d.kind is DecisionKind.HOLD}
        before = {n.ab for n in prev.waiting if not prev.held(n) and prev.kept_for(n) is None
                  and n.ab not in held}
        # An AB that entered the waiting list in this operation (asked for in it, or
        # pending before it; it may have started since) may have been a reaction's next
        # AB, keeping its devices, while the operation's rounds ran (the ABs before it
        # ended meanwhile): what it kept then was no rival.
        # So may one pending before it and cancelled within it (its app unloaded
        # after the rounds that kept its devices).
        cancelled = [prev.nodes[d.ab] for d in new if d.kind is DecisionKind.CANCEL
                     and d.ab is not None and d.ab in prev.nodes and d.ab not in v.nodes
                     and prev.nodes[d.ab].state is NodeState.PENDING]
        were_next = [n for n in [*v.nodes.values(), *cancelled]
                     if (n.state is not NodeState.PENDING or n in cancelled)
                     and (n.ab not in prev.nodes or prev.nodes[n.ab].state is NodeState.PENDING)
                     and (n.tree in self.streams.reaction or self.streams.replying(n))]
        # A move is held while another app talks: one that talked within the operation
        # (an utterance that took no time) may have held it while the rounds ran.
        talked = {d.app for d in new if d.kind is DecisionKind.START
                  and not self._talk.isdisjoint(d.devices)}
        rivals = [n for n in v.waiting
                  if n.ab in before and not v.held(n) and v.kept_for(n) is None
                  and not _after_its_reaction(v, n, self._cut_for)  # (it steps aside)
                  and (not were_next or v.kept_for(n, were_next) is None)
                  and not (n.priority is Priority.LOW and talked - {n.app})]
        kept = {n.ab for n in prev.nexts}
        nexts = [n for n in v.nexts if n.ab in kept]
        # An app unloaded within the operation: a hold of its own that took force within
        # it (a block, its stream hold armed as it went idle) ended with the unload and
        # is seen in neither view; what it held back was no rival of its starts.
        unloaded = {d.app for d in new if d.kind is DecisionKind.UNLOAD}
        starts = [d for d in starts if d.app not in unloaded]
        for d in starts:
            x = v.nodes[d.ab if d.ab is not None else -1]
            mine = v.standing(x)
            for w in rivals + nexts:
                if w.app == x.app or not set(w.devices) & set(x.devices):
                    continue
                theirs = v.standing(w)
                # (behind x's app's hold after the operation, or before it: an unload
                # within it ends the hold)
                if (theirs[0] <= mine[0] and theirs[1:] < mine[1:]
                        and not v.behind_hold(w, x.app) and not prev.behind_hold(w, x.app)) \
                        if w in nexts else theirs < mine:
                    self.fail(f"t={d.t:g}: AB{x.ab} ({x.app} {x.command}) started on "
                              f"{', '.join(sorted(set(w.devices) & set(x.devices)))}, which "
                              f"AB{w.ab} ({w.app} {w.command}, {w.state.value}) outranks it "
                              f"for")
                    break

    def _contention(self, prev: _View, v: _View, new: Sequence[Decision]) -> None:
        """Note the ABs started in this operation while no other app's AB that wanted
        one of their devices (with a priority not lower) was waiting, apart from ABs
        another app's hold kept (that app is charged for them) and moves the channel
        rule held back (that rule is not a budget matter)."""
        # (a waiting AB a policy put an AB of its own before is pending again: the
        # policy's AB is the rival, entered in this operation)
        rivals = [n for n in prev.waiting if not prev.held(n)
                  and not (n.ab in v.nodes and v.nodes[n.ab].state is NodeState.PENDING)
                  and not (n.ab in v.nodes and v.held(v.nodes[n.ab]))]
        entered: set[AbId] = set()
        ended: set[AbId] = set()
        gone: set[AbId] = set()
        """Started or cancelled earlier in this operation: no rival any more."""
        for d in new:
            if d.ab is None:
                continue
            if d.kind is DecisionKind.REQUEST:
                entered.add(d.ab)
            elif d.kind is DecisionKind.END:
                ended.add(d.ab)
            elif d.kind is DecisionKind.CANCEL:
                gone.add(d.ab)
            elif d.kind is DecisionKind.START:
                fresh = [n for n in v.waiting if (n.ab in entered or n.parent in ended)
                         and not v.held(n)]
                prio = self._priority(d)
                devices = set(d.devices)
                if not any(n.app != d.app and n.priority >= prio and devices & set(n.devices)
                           and n.ab not in gone for n in rivals + fresh):
                    self._uncontended.add(d.ab)
                elif (d.ab in self.streams.replies
                      or not self.streams.before_replies.isdisjoint(d.command_ids)
                      or d.tree in self.streams.user
                      or d.tree in self.streams.answered) and (
                        d.app in prev.snap.demoted or d.app in v.snap.demoted):
                    # the words that reply to an answer go first past the share too
                    # (7.4): one AB per answer the user gave, the user's pace (and what
                    # a policy put before them: each iteration of a return); so does a
                    # reaction to the user's own action until its first words (7.6 (4))
                    self._uncontended.add(d.ab)
                gone.add(d.ab)

    def _priority(self, d: Decision) -> Priority:
        return min(self._catalog[c].priority for c in (d.command or "").split("+"))

    def _describe(self, v: _View, ab: AbId) -> str:
        n = v.nodes[ab]
        return (f"{n.app} {n.command} on {', '.join(n.devices)}, prio {n.priority.name}, "
                f"seq {n.seq}, parked by {n.parked_by}; busy {sorted(v.busy)}; "
                f"holds {[(h.app, h.kind, h.devices) for h in v.snap.holds]}")

    # ------------------------------------------------------------ the wait share
    def _account(self, v: _View) -> None:
        running = {ab for ab, _ in v.snap.running}
        self._uncontended &= running
        self._kept.update(v.snap.t, _keeping(v))
        # (a demoted app's reply goes first past its share, and its turn before it, 7.4:
        # what is kept for it, and what it keeps as it waits first in line for a device
        # still busy, is not a precedence taken within the share)
        excused = {r.ab for r in [*v.nexts, *v.waiting]
                   if (self.streams.replying(r) or r.tree in self.streams.user
                       or r.tree in self.streams.answered)
                   and r.app in v.snap.demoted}
        self._took.update(v.snap.t, _keeping(v, self._uncontended, excused))
        self._demoted.update(v.snap.t, v.snap.demoted)

    def budgets(self, app: str) -> Budgets:
        kind = self.books.kinds.get(app, AppKind.EA)
        return self._config.budgets.get(kind, DEFAULT_BUDGETS[kind])

    def kept(self, app: str) -> list[tuple[float, float]]:
        """When ``app`` kept the others waiting (closed intervals so far)."""
        return list(self._kept.spans.get(app, []))

    def _check_share(self, app: str) -> None:
        """Within any window of its budget, ``app`` keeps the others waiting at most its
        wait share plus one AB (L).

        Two waits cannot be bounded so, by any mediator that never cuts an AB, and are
        left out of the check (each becomes a note when the literal bound is overrun):

        - windows in which another app had lost its precedence (from L before): once
          both apps have overrun their shares, neither has precedence, and both cannot
          be held to their bounds while they contend;
        - waits for an AB that started while no other app's AB wanted its devices
          (but for moves the channel rule held back): a demoted app may still use
          idle devices, and a request that comes later waits for that AB (at most L
          each time, but several times in one window).
        """
        budget = self.budgets(app)
        bound = budget.wait_share + self._longest + self._tolerance
        others = [a for a in self._demoted.spans if a != app]

        def exempt(lo: float, hi: float) -> bool:
            return any(self._demoted.during(a, lo - self._longest, hi) for a in others)

        peak, at = window_peak(self._took.spans.get(app, []), budget.wait_window, exempt)
        what = (f"{app} kept others waiting {{:g}} s within the {budget.wait_window:g} s "
                f"from t={{:g}} (share {budget.wait_share:g} s + longest AB "
                f"{self._longest:g} s)")
        if peak > bound:
            self.fail(what.format(peak, at))
            return
        peak, at = window_peak(self._kept.spans.get(app, []), budget.wait_window)
        if peak > bound:
            self.notes.append(what.format(peak, at))

    # ------------------------------------------------------------ the end
    def conclude(self, snap: Snapshot, loaded: Iterable[str]) -> None:
        """After the run: shares, drained memory, every AB ended, every Command told."""
        for timeline in (self._kept, self._took, self._demoted):
            timeline.close(snap.t)
        for app in self._kept.spans:
            self._check_share(app)
        if snap.trees or snap.waiting or snap.running:
            self.fail(f"t={snap.t:g}: working memory did not drain: waiting {snap.waiting}, "
                      f"running {[ab for ab, _ in snap.running]}, "
                      f"{len(snap.trees)} tree(s)")
        b = self.books
        if b.started != b.ended:
            self.fail(f"ABs started but never ended: {sorted(b.started - b.ended)}")
        alive = set(loaded)
        missing = sorted(c for c, app in self._requested.items()
                         if app in alive and c not in self._callbacks)
        if missing:
            self.fail(f"Commands {missing} of a loaded app never ended nor were cancelled")
