"""Selection rounds (docs/rules.md rule 4), suspension and resumption.

A round looks only at ABs that may have become startable since the last one:
ABs that just entered the waiting list, and the best waiting AB on each
*dirty* device. An AB starts when all its devices are free, no hold keeps it
(:mod:`._holds`), and it is the best-ranked waiting AB on each of its devices
(:mod:`._ranking`). This is exactly what walking the whole waiting list in
rank order would start (a better AB that cannot start reserves its devices),
but without touching the ABs that cannot start.

When an AB starts and, on one of its devices, the best AB it beat belongs to
another tree and was ready (its devices free, nothing holding it), that tree
is suspended; when an AB of a suspended tree starts, the tree resumes.
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Mapping, Set
from types import MappingProxyType
from typing import Final

from prima.catalog import Priority
from prima.mediator._decisions import DecisionKind, Rule
from prima.mediator._holds import Holds
from prima.mediator._index import WaitIndex
from prima.mediator._interface import AbId, AtomicBehavior, Driver
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._policies import Policies
from prima.mediator._ranking import Rank, goes_before, keeps_for
from prima.mediator._state import App, Node, NodeState, Tree

__all__ = ["Selector", "atomic_behavior"]

# Enum members read on hot paths, bound once: in Python 3.11 reading a member from its
# class costs about as much as a short function call, a module global almost nothing.
_WAITING: Final = NodeState.WAITING
_LOW: Final = Priority.LOW
_START: Final = DecisionKind.START
_RESUME: Final = DecisionKind.RESUME
_SUSPEND: Final = DecisionKind.SUSPEND
_BLEND: Final = Rule.BLEND
_RESTART: Final = Rule.RESTART
_FREE_DEVICES: Final = Rule.FREE_DEVICES
_KEEP_CHANNEL: Final = Rule.KEEP_CHANNEL
_ANSWERING: Final = Rule.ANSWERING
_NO_DEVICES: Final[frozenset[str]] = frozenset()
_NO_NODES: Final[list[Node]] = []  # (never changed)
_NONE_NAMED: Final[Mapping[AbId, Node]] = MappingProxyType({})
_new: Final = tuple.__new__


def atomic_behavior(node: Node) -> AtomicBehavior:
    """What the driver is asked to perform for a node."""
    # (built from a tuple in field order, ``tuple.__new__``: what the named tuple's own
    # constructor does, without calling it; one is built for every start)
    return _new(AtomicBehavior, (node.id, node.app.name, node.tree.id, node.calls,
                                 node.command_ids, node.devices, node.iteration, node.reactive,
                                 node.blended))


class _Round:
    """One round's ranking: the index, plus the ABs whose parent just finished.

    Parent-finished lasts one round, so it is not in the index: each device's
    parent-finished ABs are heaped here (built on first need; not for a round that
    names one AB, the most common), and a device's best AB is the better of the
    index's answer and this heap's top. (The ABs a round names are not even filed in
    the index until the round is over, and then only those that still wait: most
    start in it. The answer is the same: an AB ranks better named than filed, so
    whether the index holds it does not change which of the two is better.) A round
    that names no AB ranks as the index does. The selector keeps two views and
    reuses them round after round (so no round leaves a view behind as garbage:
    ``best`` holds a bound method of its view, a reference cycle): the plain one,
    and the one it points at the ABs each round names (:meth:`name`).
    """

    __slots__ = ("pjf", "best", "after", "rank", "_index", "_ranking", "_heaps", "_named",
                 "_kept", "_one", "_alive")

    def __init__(self, index: WaitIndex, *, names: bool) -> None:
        self.pjf: Mapping[AbId, Node] = _NONE_NAMED
        self._index = index
        self._ranking = ranking = index.ranking
        self._heaps: dict[str, list[tuple[Rank, Node]]] | None = None
        self._named: dict[AbId, Rank] = {}
        """The ranks of the ABs the round names, worked out once per round (the others'
        are kept on the ABs)."""
        self._kept: dict[str, tuple[Node | None, int, int]] = {}
        """Device -> the best AB :meth:`_best` found, its version, the index's serial."""
        self._one: Node | None = None
        """The AB the round names when it names one (most rounds that name any: the next
        iteration of a feedback loop, or the follow-up of the AB that ended): its heaps
        are not built (:meth:`_find`)."""
        self._alive: frozenset[str] | None = None
        """With ``_one``: the devices on which its heap would still hold it (None: not
        built yet)."""
        self.best: Callable[[str], Node | None] = self._best if names else index.top
        """The best-ranked waiting AB that needs a device, or None (the index's own
        answer for the view of rounds that name no AB)."""
        self.after: Callable[[str], Node | None] = self._find if names else index.top
        """What :attr:`best` answers for a device once the AB it answered last has
        started (whom that start beat there): worked out, as :meth:`_best` would, which
        finds the AB it kept for the device running."""
        self.rank: Callable[[Node], Rank] = self._rank if names else ranking.unnamed
        """The AB's rank (no key changes within a round: trees are suspended or resumed,
        and apps demoted, between rounds): the one kept on it when the round names no
        AB."""

    def name(self, pjf: Mapping[AbId, Node]) -> None:
        """Point the view at the ABs a round names (what it kept of the last is gone)."""
        self.pjf = pjf
        self._heaps = None
        self._one = next(iter(pjf.values())) if len(pjf) == 1 else None
        self._alive = None
        self._named.clear()
        self._kept.clear()

    def _rank(self, node: Node) -> Rank:
        """:attr:`rank` when the round names ABs."""
        pjf = self.pjf
        if node.id not in pjf:
            return self._ranking.unnamed(node)
        r = self._named.get(node.id)
        if r is None:
            r = self._named[node.id] = self._ranking.rank(node, pjf)
        return r

    def separating(self, winner: Node, loser: Node) -> Rule:
        """The first criterion on which ``winner`` beats ``loser``: what a start names."""
        return self._ranking.separating(self.rank(winner), self.rank(loser))

    def _best(self, device: str) -> Node | None:
        """:attr:`best` when the round names ABs: the better of the index's answer and
        the best of the named ABs that need ``device`` (the top of its heap here).

        A round asks for a device's best several times (its candidates, whether one
        ranks best on its devices, whom a start beat), and here each answer costs ranks
        compared: it is kept, and stands while it still waits unparked (same version)
        and the index's serial has not moved (no AB that could rank better was filed,
        no tree re-ranked; the ABs a round names are fixed for the round)."""
        index = self._index
        kept = self._kept.get(device)
        if kept is not None:
            found, version, serial = kept
            if serial == index.serial and (
                    found is None or (found.state is _WAITING and found.version == version)):
                return found
        found = self._find(device)
        self._kept[device] = (found, -1 if found is None else found.version, index.serial)
        return found

    def _find(self, device: str) -> Node | None:
        """What :meth:`_best` answers, worked out."""
        top = self._index.top(device)
        one = self._one
        if one is not None:
            # One named AB: what its heaps would answer, without them. They would be built
            # at the first ask, with an entry on each of its devices if it waits then, and
            # its entry on a device dropped when an ask finds it waiting no more or parked.
            alive = self._alive
            if alive is None:
                alive = self._alive = one.devices if one.state is _WAITING else _NO_DEVICES
            if device not in alive or one.state is not _WAITING:
                return top  # (an AB that waits no more does not wait again in its round)
            if one.parked is not None:
                self._alive = alive - {device}
                return top
            if top is None or top is one:
                return one
            return top if self.rank(top) < self.rank(one) else one
        heaps = self._heaps
        if heaps is None:
            heaps = self._heaps = self._heap_named()
        found = heaps.get(device)
        while found:
            rank, finished = found[0]
            if finished.state is _WAITING and finished.parked is None:
                break
            heapq.heappop(found)
        else:
            return top  # no named AB waits for the device
        if top is None or top is finished:
            return finished
        return top if self.rank(top) < rank else finished

    def _heap_named(self) -> dict[str, list[tuple[Rank, Node]]]:
        """Each device's waiting named ABs, heaped by rank."""
        heaps: dict[str, list[tuple[Rank, Node]]] = {}
        for n in self.pjf.values():
            if n.state is _WAITING:
                entry = (self._rank(n), n)
                for d in n.sorted_devices:
                    heap = heaps.get(d)
                    if heap is None:
                        heaps[d] = [entry]
                    else:
                        heap.append(entry)
        for heap in heaps.values():
            if len(heap) > 1:
                heapq.heapify(heap)
        return heaps


class Selector:
    """Runs selection rounds and hands the ABs they start to the driver."""

    def __init__(self, wm: WorkingMemory, holds: Holds, log: DecisionLog, driver: Driver,
                 overrun: Callable[[App, str], None], policies: Policies) -> None:
        self._wm = wm
        self._holds = holds
        self._log = log
        self._driver = driver
        self._overrun = overrun
        self._policies = policies
        """What the mediation policies decide about an AB weighed (docs/rules.md 7.3)."""
        self._instant = -1.0
        self._starts: dict[str, int] = {}
        """Starts per app at ``_instant`` (the starts-per-instant budget)."""
        self._plain = _Round(wm.index, names=False)
        """The view of every round that names no AB (it keeps nothing of a round)."""
        self._naming = _Round(wm.index, names=True)
        """The view of every round that names ABs (pointed at them round by round)."""
        self._answered: list[tuple[Node, Tree]] = []
        """ABs of streams under way that a round held for a reaction to the user's own
        action, with its tree: their streams are suspended once the round is over."""
        self._losers: list[Node] = _NO_NODES
        """What :meth:`_alone` found the index answering on the devices of the AB it found
        alone (none where no AB waits): whom its start beats, for :meth:`_goes_on`."""

    def settle(self) -> None:
        """Run rounds until nothing more can start."""
        wm = self._wm
        holds = self._holds
        start = self._driver.start
        while True:
            if holds.opened:  # (else there is no stream to arm or let lapse)
                holds.update()
            if wm.unreserved:  # what a reaction's next AB kept may go now (7.1)
                wm.unreserved = False
                holds.refile_reserved()
            if wm.answered:  # what a reaction to the user held may go now (7.6 (1))
                wm.answered = False
                holds.refile_answering()
            new, dirty, pjf = wm.new, wm.dirty, wm.pjf
            if not (new or dirty or pjf):
                break
            if len(new) == 1 and len(pjf) == 1 and self._alone(new[0], dirty):
                started = self._goes_on(new[0])
            elif self._idle(new, dirty):
                # The round is skipped: what it would take is emptied where it is
                # (nothing of it is kept), and parent-finished ends with it.
                new.clear()
                dirty.clear()
                if pjf:
                    wm.pjf = {}
                    self._unname(pjf)
                elif not holds.opened:
                    break  # (nothing is left for another round)
                continue
            else:
                started = self.round()
            for node in started:
                start(atomic_behavior(node))
        wm.maybe_compact()

    def round(self) -> list[Node]:
        """One round: start every AB that can start now; returns them. (:meth:`settle`
        runs none that :meth:`_idle` finds idle.)"""
        wm = self._wm
        # What the round looks at is taken from working memory, which collects anew
        # for the next round (what is empty stays there: nothing to take).
        pjf: Mapping[AbId, Node] = wm.pjf
        if pjf:
            wm.pjf = {}
            wm.named = pjf
        else:
            pjf = _NONE_NAMED
        new = wm.new
        if new:
            wm.new = []
        else:
            new = _NO_NODES
        dirty: Set[str] = wm.dirty
        if dirty:
            wm.dirty = set()
        else:
            dirty = _NO_DEVICES
        if pjf:
            view = self._naming
            view.name(pjf)
        else:
            view = self._plain
        started: list[Node] = []
        later: list[tuple[bool, Tree]] = []
        overrun: dict[str, App] | None = None
        for x in self._candidates(new, dirty, view):
            # (an earlier start of this round may have parked it: a block took force)
            if x.state is _WAITING and x.parked is None and self._startable(x, view):
                if self._counted(x.app):
                    self._start(x, view, started, later)
                else:
                    if overrun is None:
                        overrun = {}
                    overrun[x.app.name] = x.app
        if later:
            self._suspend_resume(later)
        if self._answered:
            self._suspend_for_answers()
        if pjf:
            self._unname(pjf)
            wm.named = _NONE_NAMED
            view.name(_NONE_NAMED)  # (it keeps no AB past its round)
        if overrun is not None:
            for app in overrun.values():
                self._overrun(app, self._overran(app))
        return started

    def _overran(self, app: App) -> str:
        """What the failure of an app past its starts-per-instant budget says."""
        return (f"started {app.budgets.starts_per_instant} atomic behaviors at "
                f"t={self._instant:g} s and asked for more (Commands that take no time, "
                "requested again and again?)")

    def _alone(self, x: Node, dirty: Set[str]) -> bool:
        """Whether the round that names the new AB ``x`` alone weighs ``x`` alone and finds
        it ready, with nothing of a hold, a reservation or a pause on it: what
        :meth:`_goes_on` takes for granted. Most often ``x`` is the next iteration of a
        feedback loop, on the devices its predecessor just freed. The round's candidates
        are ``x`` and the best on each dirty device, all of them ``x``'s: ``x`` is that
        best where nothing else waits (``WorkingMemory.ranked`` counts every waiting,
        unparked AB but ``x``, the one the round names) and where it ranks better than
        the index's answer (:meth:`_beats`). Its devices are free, so :meth:`_idle` would
        not skip the round; no reaction answers the user, no talk, block or stream hold
        keeps ``x`` (:meth:`Holds.holder`), no reaction's next AB keeps its devices from
        it (:meth:`_reserved`), all of which only read: of :meth:`_startable` only the
        policies' say is left (:meth:`Policies.prepare`)."""
        if x.state is not _WAITING or x.parked is not None or self._wm.pjf.get(x.id) is not x:
            return False
        wm = self._wm
        if wm.answering or x.cut_for is not None \
                or x.not_before > self._log.now or not dirty <= x.devices:
            return False
        busy = wm.busy
        ranked = wm.ranked
        contested = False
        for d in x.sorted_devices:
            if d in busy:
                return False
            if ranked.get(d):
                contested = True
        holds = self._holds
        if (holds.opened or x.priority is _LOW) and holds.holder(x) is not None:
            return False
        if wm.reserving and self._reserved(x) is not None:
            return False
        if not contested:
            # (no AB waits on its devices: the index answers none there, ``ranked``
            # counting every AB it files, so its start beats nobody)
            self._losers = _NO_NODES
            return True
        return self._beats(x)

    def _beats(self, x: Node) -> bool:
        """Whether ``x``, the AB the round names, ranks better on each of its devices than
        the best AB filed there: what the round's view would answer for them. If it does,
        the view is left pointed at the round's ABs, for :meth:`_goes_on` to rank whom
        ``x``'s start beats, and those answers are kept (:attr:`_losers`): nothing files,
        parks or re-ranks an AB before ``x`` starts (``x`` itself is not filed; a policy
        that puts its AB before ``x`` keeps it from starting), so they stand."""
        view = self._naming
        view.name(self._wm.pjf)
        top = self._wm.index.top
        rank = view.rank
        losers = []
        for d in x.sorted_devices:
            t = top(d)
            if t is not None:
                if t is not x and rank(t) < rank(x):
                    view.name(_NONE_NAMED)
                    return False
                losers.append(t)
        self._losers = losers
        return True

    def _goes_on(self, x: Node) -> list[Node]:
        """The round of an AB :meth:`_alone` found alone, as :meth:`round` would weigh it
        (the same decisions, in the same order), without finding its candidates nor
        asking whether it is ready: ``x`` starts unless a policy puts an AB of its own
        before it, or its application has started its last AB of the instant. Returns
        what it starts. (Most AB ends of a run of a thesis sample end a feedback
        iteration whose next one starts so, for less than half of what the round costs:
        299 of 325 in sample 3.)"""
        wm = self._wm
        pjf = wm.pjf
        wm.pjf = {}
        wm.named = pjf
        wm.new = []
        if wm.dirty:
            wm.dirty = set()
        view = self._naming
        started: list[Node] = []
        x.blended = _NO_DEVICES
        overran = False
        losers = self._losers  # (the index's answers on its devices: ``_alone``)
        self._losers = _NO_NODES  # (it keeps no AB past its round)
        if not self._policies.prepare(x):
            if not self._counted(x.app):
                overran = True
            else:
                wm.start(x)
                x.started_at = self._log.now
                started.append(x)
                later: list[tuple[bool, Tree]] = []
                if losers and view.pjf is not pjf:  # (named by ``_beats`` where they wait)
                    view.name(pjf)
                self._started(x, losers, view, started, later)
                if later:
                    self._suspend_resume(later)
        if x.state is _WAITING:  # (a policy put its AB before it, or its app overran)
            self._unname(pjf)
        wm.named = _NONE_NAMED
        if view.pjf is pjf:
            view.name(_NONE_NAMED)  # (it keeps no AB past its round)
        if overran:
            self._overrun(x.app, self._overran(x.app))
        return started

    def _suspend_resume(self, later: list[tuple[bool, Tree]]) -> None:
        """Suspend and resume the trees a round's starts said (in their order)."""
        wm = self._wm
        for is_suspend, tree in later:
            if is_suspend:
                if wm.suspend(tree):
                    self._policies.suspending(tree)
            else:
                wm.resume(tree)
                if self._holds.opened:
                    self._holds.unpark_all()  # a stream under way again: no hold keeps it

    def _suspend_for_answers(self) -> None:
        """Suspend the streams whose next AB a round held for a reaction to the user's own
        action (docs/rules.md 7.6 (1)): at their IU boundary, on every device."""
        held, self._answered = self._answered, []
        wm = self._wm
        log = self._log
        for x, by in held:
            tree = x.tree
            if tree.suspended is None and tree.live:
                log.ab(_SUSPEND, _ANSWERING, x, f"while {by.app.name} answers the user")
                log.tell(x.app.name, "suspended", by=by.app.name, rule=_ANSWERING.value)
                if wm.suspend(tree):
                    self._policies.suspending(tree)
            elif tree.live:  # (suspended by another AB's start in the round: held, said so)
                self._holds.answering(x, by)

    def _kept_back(self, x: Node, ready: bool) -> bool:
        """Whether ``x``, held by no hold, waits all the same: kept for another
        reaction's next AB (then parked), in its pause after a false interruption, or
        after the reaction it was cut for."""
        if self._wm.reserving:
            r = self._reserved(x)
            if r is not None:
                # Kept for the reaction's next AB (docs/rules.md 7.1): it steps aside, like
                # an AB another app's hold keeps, so that it reserves nothing meanwhile.
                if ready or self._policies.acts_on_busy(x):  # (it would start, or cut
                    self._holds.reserved(x, r)  # what holds its devices: said so)
                self._holds.park(x, Rule.RESERVED, r.app)
                return True
        if x.not_before > self._log.now:
            return True  # (its pause after a false interruption: it keeps its rank)
        # (one a hold keeps is parked below: it reserves nothing)
        if x.cut_for is not None:
            r = self._after_its_reaction(x, x.cut_for)
            if r is not None:
                # It waits for the reaction it was cut for, which steps aside for ``r``:
                # it steps aside too, reserving nothing, as what ``r`` keeps (else what
                # goes before ``r`` in its stream, a return, could wait for it: all
                # three would wait for each other)
                self._holds.park(x, Rule.RESERVED, r.app)
                return True
        return False

    def _held_for_answer(self, x: Node) -> bool:
        """Whether ``x``'s stream waits while a reaction answers the user (docs/rules.md
        7.6 (1)): then ``x`` is parked, and its stream, if under way, is suspended once
        the round is over (else the hold is noted)."""
        answering = self._answering(x)
        if answering is None:
            return False
        if x.tree.started and x.tree.suspended is None:
            self._answered.append((x, answering))  # (suspended once the round is over)
        else:  # (a new stream, or one suspended already, by another AB: held, said so)
            self._holds.answering(x, answering)
        self._holds.park(x, _ANSWERING, answering.app)
        return True

    def _answering(self, x: Node) -> Tree | None:
        """The reaction to the user's own action that keeps ``x``'s stream waiting now
        (docs/rules.md 7.6 (1)): the latest that has not said its first words (or, with
        none, is in working memory), within its bound, that interrupted ``x``'s stream
        (a stream that was there when it became a reaction to the user, and no later
        reaction). A reply to an answer (7.4),
        following the user, and an AB of a block under way (rule 3: a started block is
        concluded) are never held so."""
        if x.protected:
            return None
        tree = x.tree
        now = self._log.now
        mine = tree.reaction
        if tree.answered_since and (mine is None or tree.answered_since > mine):
            mine = tree.answered_since  # (its reply to the user's answer: as a reaction)
        found: Tree | None = None
        for t in self._wm.answering.values():
            if t is tree or t.answers_until <= now or tree.id >= t.answers_from:
                continue  # (its own, its bound passed, or a stream that came after it)
            reaction = t.reaction or 0
            if mine is not None and mine > reaction:
                continue  # (a later reaction is a stream of its own, not interrupted; so
                # is the reply to the user's later answer)
            if found is None or reaction > (found.reaction or 0):
                found = t
        if found is None or all(c.spec.follows_user for c in x.commands):
            return None
        block = self._holds.block(x.app)
        if block is not None and block.reserving and not block.devices.isdisjoint(x.devices):
            return None
        return found

    def _unname(self, pjf: Mapping[AbId, Node]) -> None:
        """"Parent just finished" lasts one round: at its end, others may rank above
        the ABs it named (their devices are dirty); those that still wait unparked are
        filed in the index and counted in their devices' rankings now
        (``WorkingMemory.enter_waiting`` left them out: most start in the round that
        names them)."""
        wm = self._wm
        dirty = wm.dirty
        for n in pjf.values():
            if n.state is _WAITING:
                dirty.update(n.devices)
                if n.parked is None:
                    wm.file(n)

    def _counted(self, app: App) -> bool:
        """Count one more start of ``app`` at this instant; False past its budget."""
        now = self._log.now  # (the operation's instant)
        if now != self._instant:
            self._instant = now
            self._starts = {}
        n = self._starts.get(app.name, 0) + 1
        if n > app.budgets.starts_per_instant:
            return False
        self._starts[app.name] = n
        return True

    def _idle(self, new: list[Node], dirty: Set[str]) -> bool:
        """Whether the round provably does nothing (it need not find its candidates).

        A round weighs the waiting ABs that are new and the best on each dirty device
        (:meth:`_candidates`); it does nothing when there are none, or each has a busy
        device (it cannot start: no policy's AB is put before it) and nothing acts on
        it while it waits: no hold parks it (no stream or block is open, and it breaks
        no channel: only a LOW AB is held by another app's talk) and no policy acts on
        busy devices for it (blend, interrupt: not on a busy device it needs that
        :meth:`Policies.may_act_on` rules out), and no reaction answers the user (7.6 (1):
        it may hold what the round looks at). What the index's answer for a dirty device
        is need not be known: ``WorkingMemory.ranked`` counts the waiting, unparked ABs
        on each device by priority, which is whom the index (and a round's named ABs)
        can answer with. (It leaves out the ABs a round names until that round files
        them, ``WorkingMemory.enter_waiting``: they are among the new ones, and one of
        them on a dirty device it does not find busy makes the round, as its count
        would.) This is the common round that follows a start or an end on a busy
        device: most of what a round would cost is finding its candidates.
        """
        wm = self._wm
        if wm.answering:
            return False  # (a reaction answers the user: what a round looks at may be held)
        busy = wm.busy
        ranked = wm.ranked
        opened = self._holds.opened
        policies = self._policies
        on_busy = policies.on_busy
        reserving = wm.reserving
        for x in new:
            if x.state is _WAITING and x.parked is None:
                if opened or x.priority is _LOW or (
                        reserving and not reserving.keys().isdisjoint(x.devices)):
                    return False
                kept = False
                counted = x.counted
                for d in x.sorted_devices:
                    if d in busy and not (on_busy and policies.may_act_on(d)):
                        kept = True  # a busy device that keeps it waiting
                        if counted:
                            break
                    elif not counted and d in dirty:
                        return False  # (what ``ranked`` would say of the device with it)
                if not kept:
                    return False
        for d in dirty:
            counts = ranked.get(d)
            if not counts:
                continue  # no AB waits for it
            if opened or d not in busy or (on_busy and policies.may_act_on(d)) \
                    or d in reserving:  # (one kept for a reaction steps aside now)
                return False
            for _app, priority in counts:
                if priority is _LOW:
                    return False
        return True

    @staticmethod
    def _candidates(new: list[Node], dirty: Set[str], view: _Round) -> list[Node]:
        """What may start: ABs new on the waiting list, the best on each dirty device."""
        if not dirty and len(new) == 1:  # (one request, one AB: nothing to order)
            return new if new[0].state is _WAITING else []
        if not new and len(dirty) == 1:  # (one device freed or re-ranked: its best)
            (d,) = dirty
            b = view.best(d)
            return [] if b is None else [b]
        cands: dict[int, Node] = {}
        for n in new:  # (a loop: in Python 3.11 a comprehension is a call of its own)
            if n.state is _WAITING:
                cands[n.id] = n
        best = view.best
        for d in sorted(dirty) if len(dirty) > 1 else dirty:
            b = best(d)
            if b is not None:
                cands[b.id] = b
        order = list(cands.values())
        if len(order) > 1:
            order.sort(key=view.rank)
        return order

    def _reserved(self, x: Node, besides: Tree | None = None) -> Node | None:
        """The pending next AB of another application's reaction (or reply) that
        reserves one of ``x``'s devices and keeps it from ``x`` (docs/rules.md 7.1,
        :func:`keeps_for`): ``x`` may not have that device now, whatever else holds it.
        None if there is none (none of the tree ``besides``). A restart of words the user
        cut for a reaction of their own application's is kept by that reaction's next AB
        too (7.5: it waits for the taker's reaction)."""
        reserving = self._wm.reserving
        found: Node | None = None
        taker = x.taker  # (a restart of words the user cut for this app's reaction)
        for d in x.sorted_devices:
            on = reserving.get(d)
            if on:
                for r in on.values():
                    if (r.app is not x.app or (r.app is taker and r.tree is not x.tree)) \
                            and (found is None or r.id < found.id) \
                            and r.tree is not besides \
                            and keeps_for(r, x) and not self._held_by(r, x.app):
                        found = r
        return found

    def _held_by(self, r: Node, app: App) -> bool:
        """Whether the reaction's next AB ``r`` waits behind an AB that ``app``'s block or
        stream hold keeps: then it keeps nothing from ``app``, whose block must go on
        for it to start (they would wait for each other)."""
        before = self._wm.nodes.get(r.parent) if r.parent is not None else None
        return before is not None and before.state is _WAITING \
            and self._holds.holds_back(app, before)

    def _step_aside(self, y: Node) -> bool:
        """``y`` ranks best on a device another AB asks for, but it is kept for another
        application's reaction (docs/rules.md 7.1) on a device of its own, which this
        round may not have looked at: it steps aside now (parked), so that it reserves
        nothing. True if it did."""
        if y.parked is not None or self._holds.holder(y) is not None:
            return False
        r = self._reserved(y)
        if r is None:
            return False
        self._holds.park(y, Rule.RESERVED, r.app)
        return True

    def _after_its_reaction(self, x: Node, cut_for: Node) -> Node | None:
        """The next AB of another reaction (7.1) that the reaction's AB the restart ``x``
        was cut for steps aside for, while its stream goes before ``x``'s, priority aside
        (``x``'s stream may have become a later reaction since, to the user's own action:
        then it goes first): ``x`` waits for it too (7.3 (2)); not for a next AB after
        ``x`` in its own tree (that one waits for ``x``: they would wait for each other).
        None: ``x`` does not wait."""
        if cut_for.state is not _WAITING or not goes_before(cut_for, x):
            return None
        # (as it is now, ranks may have moved since; one in x's own tree waits for x)
        return self._reserved(cut_for, besides=x.tree)

    def _ready(self, x: Node, best: Callable[[str], Node | None]) -> bool:
        """Whether ``x``'s devices are free and it ranks best on each."""
        busy = self._wm.busy
        reserving = self._wm.reserving
        for d in x.sorted_devices:
            if d in busy:
                return False
            b = best(d)
            while reserving and b is not None and b is not x and self._step_aside(b):
                b = best(d)  # (what ranked best there was kept for a reaction: gone now)
            if b is not x:
                return False
        return True

    def _startable(self, x: Node, view: _Round) -> bool:
        wm = self._wm
        holds = self._holds
        held = holds.holder(x) if holds.opened or x.priority is _LOW else None
        if held is None and wm.answering and self._held_for_answer(x):
            return False
        best = view.best
        ready = self._ready(x, best)
        if held is None and self._kept_back(x, ready):
            return False
        x.blended = _NO_DEVICES
        policies = self._policies
        if ready:
            if held is None:
                return not policies.prepare(x)  # (False: it waits for the policy's AB)
        else:
            # Ranking best with some devices busy matters only to a policy that may act on
            # what runs there (blend, interrupt): only then is it worked out.
            ranks_best = policies.on_busy and policies.acts_on_busy(x) and all(
                best(d) is x for d in x.sorted_devices)
            if ranks_best:
                blend = policies.blend(x)
                if blend is not None:
                    (x.blended, bounded), ready = blend, True
                    if held is not None and held[0] is _KEEP_CHANNEL and bounded:
                        held = None  # a move blended with a local motion keeps within the
                        # blend's bound of the user: it does not break the channel
            if held is None:
                if ready and policies.prepare(x):
                    return False  # it waits for the policy's AB put before it
                if ranks_best and not ready and x.tree.reaction is not None:
                    policies.cut(x)
                return ready
        # Held by another app's block, stream hold or talk: out of the ranking at
        # once, so it reserves nothing meanwhile. The channel rule is noted only
        # when the talk is what keeps it (its devices are free and it ranks best).
        if ready or held[0] is not _KEEP_CHANNEL:
            holds.note(x, *held)
        holds.park(x, *held)
        return False

    def _over(self, x: Node) -> str:
        """A blended start's detail: what it blends over, on which devices."""
        if not x.blended:
            return ""
        return "over " + ", ".join(f"AB{self._wm.busy[d].id} on {d}"
                                   for d in sorted(x.blended))

    def _start(self, x: Node, view: _Round, started: list[Node],
               later: list[tuple[bool, Tree]]) -> None:
        self._wm.start(x)
        x.started_at = self._log.now
        started.append(x)
        # Who did it beat? The best remaining waiting AB on each of its devices (it
        # ranked best on each: it was the last answer for each).
        after = view.after
        losers = []
        for d in x.sorted_devices:
            b = after(d)
            if b is not None:
                losers.append(b)
        self._started(x, losers, view, started, later)

    def _started(self, x: Node, losers: list[Node], view: _Round, started: list[Node],
                 later: list[tuple[bool, Tree]]) -> None:
        """What ``x``'s start says and does, ``losers`` the ABs it beat."""
        if x.blended:
            rule = _BLEND
        elif x.restarts is not None:
            rule = _RESTART
        elif x.commands[0].internal is not None:
            rule = x.commands[0].internal
        elif losers:
            top = min(losers, key=view.rank) if len(losers) > 1 else losers[0]
            rule = view.separating(x, top)
        else:
            rule = _FREE_DEVICES
        log = self._log
        log.ab(_START, rule, x, self._over(x) if x.blended else "")
        self._holds.started(x)  # a block it starts takes force: what it holds steps aside
        if x.tree.suspended is not None or (later and any(
                is_suspend and t is x.tree for is_suspend, t in later)):
            # (suspended, or lost in this very round and now blended in after all)
            log.ab(_RESUME, rule, x, "resumed from the suspended IU")
            log.tell(x.app.name, "resumed", rule=rule.value)
            later.append((False, x.tree))
        if losers:
            self._suspend_losers(x, losers, rule, started, later, view)

    def _suspend_losers(self, x: Node, losers: list[Node], rule: Rule, started: list[Node],
                        later: list[tuple[bool, Tree]], view: _Round) -> None:
        busy = self._wm.busy
        for loser in losers:
            tree = loser.tree
            if tree is x.tree:
                continue
            if tree.suspended is not None:
                if x.feedback:  # (a loop it was kept for starts: it may wait on for good)
                    self._behind(x, loser, started, view)
                continue
            if later and any(is_suspend and t is tree for is_suspend, t in later):
                continue
            # "Ready": it lost only to this round's starts, not to ABs already running.
            for d in loser.sorted_devices:
                running = busy.get(d)
                if running is not None and running not in started:
                    break
            else:
                if self._holds.holder(loser) is None:
                    self._log.ab(_SUSPEND, rule, loser,
                                 f"lost to AB{x.id} ({x.app.name})")
                    self._log.tell(loser.app.name, "suspended", by=x.app.name, rule=rule.value)
                    later.append((True, tree))

    def _behind(self, x: Node, loser: Node, started: list[Node], view: _Round) -> None:
        """The first iteration ``x`` of a feedback loop of another application's reaction
        (or reply) starts, and ``loser``, of a suspended stream, which a hold said was kept
        for ``x``, lost to it on rank alone. The loop's iterations win as ``x`` did for as
        long as their tree is in working memory (docs/rules.md 7.1: following the user
        goes on), and no line would say why ``loser`` still waits: a hold line says it,
        and its application is told (7.5)."""
        holds = self._holds
        if not holds.kept_for(loser, x):
            return
        busy = self._wm.busy
        for d in loser.sorted_devices:
            running = busy.get(d)
            if running is not None and running not in started:
                return  # (it waits for an AB already running: that is why)
        if holds.holder(loser) is None and self._reserved(loser) is None:
            holds.behind(loser, x, view.separating(x, loser))
