"""What keeps a ready AB from starting besides its devices: holds.

Three things hold an AB back, and this module owns all their state:

- **Explicit stream blocks** (rule 6c). A stream's hold is *armed* when its
  app has nothing waiting or running inside the open stream: the other apps'
  *new* streams that need the stream's devices wait (trees none of whose ABs
  has started, and suspended ones: resuming an interrupted dialogue is taking
  the floor anew); a reaction, and a stream under way (a reply to the app's
  own Q&A, docs/rules.md 7.2), do not. It lapses as soon as
  the app is busy again (its own ABs then compete as usual, the stream's
  continuation ranking as "parent just finished"), and is released by
  ``close_stream``, by the hold timeout, or by unloading the app.
- **Begin/end blocks.** A block reserves its devices for its app alone,
  reactive requests included, from its first AB's start until
  ``close_block``, the watchdog, or unloading.
- **The channel rule** (thesis Sec. 3.3). A Command that breaks the
  Communication Channel (moving away) does not start while another
  application talks with the user.

A held AB is *parked*: out of its devices' ranking, so it reserves nothing
while it cannot start. Parked ABs take their places again when a hold ends,
lapses or loses its force, or when a talk ends; one still held is parked again
in the next round. An application that lost its precedence (the wait-share
budget, :mod:`._fairness`) holds nothing with its streams and blocks.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Final

from prima.catalog import Catalog, Priority
from prima.errors import MediationError
from prima.mediator._decisions import DecisionKind, Rule
from prima.mediator._interface import AbId, Clock, CommandId
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import App, Node, NodeState, Tree

__all__ = ["Block", "Holds", "Stream"]

# Enum members read on hot paths (:meth:`Holds.holder`), bound once: reading a member
# from its class costs far more than a module global in Python 3.11.
_LOW: Final = Priority.LOW
_KEEP_CHANNEL: Final = Rule.KEEP_CHANNEL
_RESTORE_STATE: Final = Rule.RESTORE_STATE
_BLOCK: Final = Rule.BLOCK
_STREAM_HOLD: Final = Rule.STREAM_HOLD


class Stream:
    """An explicit stream block (``open_stream`` ... ``close_stream``)."""

    __slots__ = ("hold", "tree", "devices", "armed", "deadline", "lapsed", "held")

    def __init__(self, hold: float, tree: Tree | None) -> None:
        self.hold = hold
        self.tree = tree
        """The tree that continues the stream (rule ``stream``)."""
        self.devices: set[str] = set()
        """Devices the stream's ABs used: what its hold keeps."""
        self.armed = False
        """The hold is in force (the app is idle)."""
        self.deadline = 0.0
        self.lapsed = False
        """The hold timed out in this idle period; it re-arms after the next activity."""
        self.held: set[AbId] = set()
        """ABs already recorded as held in this hold period."""


class Block:
    """A begin/end block (``open_block`` ... ``close_block``)."""

    __slots__ = ("devices", "watchdog", "first_command", "tree", "started",
                 "deadline", "expired", "held")

    def __init__(self, devices: frozenset[str], watchdog: float, first_command: CommandId,
                 tree: Tree | None) -> None:
        self.devices = devices
        self.watchdog = watchdog
        self.first_command = first_command
        """Commands from this id on belong to the block."""
        self.tree = tree
        self.started = False
        self.deadline = 0.0
        self.expired = False
        self.held: set[AbId] = set()

    @property
    def reserving(self) -> bool:
        """Its devices are reserved now (it started, and the watchdog has not fired)."""
        return self.started and not self.expired


class Holds:
    """Streams, blocks, the channel rule, parked ABs and their deadlines."""

    def __init__(self, apps: Mapping[str, App], wm: WorkingMemory, log: DecisionLog,
                 catalog: Catalog, clock: Clock, resting: Sequence[Node] = ()) -> None:
        self._apps = apps
        self._resting = resting
        """Words a false interruption cut, waiting out the robot's pause to go on: their
        application is still talking with the user (the channel rule)."""
        self._clock = clock
        self._wm = wm
        self._log = log
        self._catalog = catalog
        self._talk = tuple(sorted(catalog.talk_devices))
        self._channel_devices = catalog.channel_devices
        self._streams: dict[str, Stream] = {}
        self._blocks: dict[str, Block] = {}
        self._parked: list[Node] = []
        """ABs parked by streams and blocks."""
        self._talk_parked: list[Node] = []
        """ABs parked by the channel rule: they take their places again at every end."""
        self._reserve_parked: list[Node] = []
        """ABs parked because a reaction's next AB keeps one of their devices: they take
        their places again at every end, and when a next AB is cancelled."""
        self._answer_parked: list[Node] = []
        """ABs parked because a reaction to the user's own action answers first
        (docs/rules.md 7.6 (1)): they take their places again when one stops keeping
        the streams it interrupted waiting."""
        self._answer_held: dict[AbId, tuple[int, int | None]] = {}
        """Waiting ABs of streams not yet under way held back while a reaction answers
        the user (a hold decision was emitted) -> that reaction (its tree, its order): a
        later reaction to the user that holds them again is said anew."""
        self._channel_held: set[AbId] = set()
        """Waiting ABs held back by the channel rule (a hold decision was emitted)."""
        self._reserved: dict[AbId, AbId] = {}
        """ABs said to be kept for another reaction's next AB -> that AB."""
        """Waiting ABs kept from a reaction's reserved device (a hold decision was
        emitted)."""
        self._behind: dict[AbId, AbId] = {}
        """ABs said to wait on behind the feedback loop that such a next AB started ->
        that AB."""
        self._kept: dict[AbId, str] = {}
        """ABs parked by a stream hold or block -> the holder's name."""
        self.opened = False
        """Some app has an open stream or block (else no AB can be held by one): what
        :meth:`open` says, kept in step by the methods that open and close them."""
        self.keeping: dict[str, int] = {}
        """Holder's name -> how many other apps' ABs its streams and blocks park now."""

    # ------------------------------------------------------------------ queries
    def open(self) -> bool:
        """Some app has an open stream or block (else no AB can be held by one)."""
        return bool(self._streams) or bool(self._blocks)

    def stream(self, app: App) -> Stream | None:
        return self._streams.get(app.name)

    def block(self, app: App) -> Block | None:
        return self._blocks.get(app.name)

    def continues(self, app: App, tree: Tree) -> bool:
        """An open stream or live block of the app owns this tree (rule ``stream``)."""
        st, blk = self._streams.get(app.name), self._blocks.get(app.name)
        return ((st is not None and st.tree is tree)
                or (blk is not None and not blk.expired and blk.tree is tree))

    def holder(self, node: Node) -> tuple[Rule, App] | None:
        """Another app's talk (its words under way, or waiting out the robot's pause after
        a false interruption), block or armed stream hold that keeps ``node`` from
        starting. A return of the restore-state policy's waits for any talk, its own
        application's too: the mediator's own move never turns the robot away from words
        addressed to the user (docs/rules.md 7.6 (3))."""
        if node.priority is _LOW:
            busy = self._wm.busy
            anyone = node.commands[0].internal is _RESTORE_STATE
            for d in self._talk:
                talker = busy.get(d)
                if talker is not None and (talker.app is not node.app or anyone):
                    return _KEEP_CHANNEL, talker.app
            if self._resting:  # (a pause in its words is no end of its talk: 7.5)
                now = self._clock.now()
                for n in self._resting:
                    if n.state is NodeState.WAITING and (n.app is not node.app or anyone) \
                            and n.not_before > now:
                        return _KEEP_CHANNEL, n.app
        if not self.opened:
            return None
        for other in self._apps.values():
            rule = self._holds_back(other, node)
            if rule is not None:
                return rule, other
        return None

    def holds_back(self, app: App, node: Node) -> bool:
        """Whether ``app``'s block or armed stream hold keeps ``node`` from starting
        (whatever the channel rule does meanwhile)."""
        return self.opened and self._holds_back(app, node) is not None

    def _holds_back(self, other: App, node: Node) -> Rule | None:
        if other is node.app or other.demoted:
            return None
        blk = self._blocks.get(other.name)
        if blk is not None and blk.reserving and not node.devices.isdisjoint(blk.devices):
            return _BLOCK
        st = self._streams.get(other.name)
        if (st is not None and st.armed and _new_stream(node.tree)
                and not node.devices.isdisjoint(st.devices)):
            return _STREAM_HOLD
        return None

    # ----------------------------------------------------------- streams, blocks
    def open_stream(self, app: App, hold: float, tree: Tree | None) -> None:
        if app.name in self._streams:
            raise MediationError(f"{app.name}: a stream is already open")
        st = Stream(hold, tree)
        wm = self._wm  # the devices its running ABs hold (or are blended over)
        st.devices.update(d for occupied in (wm.busy, wm.blending)
                          for d, n in occupied.items() if n.app is app)
        self._streams[app.name] = st
        self.opened = True

    def close_stream(self, app: App, rule: Rule) -> None:
        """End the app's stream (if open); an armed hold is released."""
        st = self._streams.pop(app.name, None)
        self.opened = bool(self._streams) or bool(self._blocks)
        if st is not None and st.armed:
            self._release(st.devices)
            self._log.emit(DecisionKind.RELEASE, rule, app=app.name,
                           detail="stream hold on " + ", ".join(sorted(st.devices)))

    def open_block(self, app: App, devices: frozenset[str], watchdog: float,
                   first_command: CommandId, tree: Tree | None) -> None:
        if app.name in self._blocks:
            raise MediationError(f"{app.name}: a block is already open")
        self._blocks[app.name] = Block(devices, watchdog, first_command, tree)
        self.opened = True

    def close_block(self, app: App, rule: Rule) -> None:
        """End the app's block (if open); a reservation is released."""
        blk = self._blocks.pop(app.name, None)
        self.opened = bool(self._streams) or bool(self._blocks)
        if blk is not None and blk.reserving:
            self._release(blk.devices)
            self._log.emit(DecisionKind.RELEASE, rule, app=app.name,
                           detail="block on " + ", ".join(sorted(blk.devices)))

    def _release(self, devices: set[str] | frozenset[str]) -> None:
        self._wm.dirty.update(devices)
        self.unpark_all()

    # ----------------------------------------------------------- the AB's life
    def requested(self, app: App, tree: Tree) -> None:
        """The app's request joined ``tree``: its open stream and live block continue it."""
        st, blk = self._streams.get(app.name), self._blocks.get(app.name)
        if st is not None:
            st.tree = tree
        if blk is not None and not blk.expired:
            blk.tree = tree

    def started(self, node: Node) -> None:
        """An AB started: a block's first AB arms its watchdog; a stream learns devices."""
        if self._channel_held:
            self._channel_held.discard(node.id)
        if self._reserved:
            self._reserved.pop(node.id, None)
            self._behind.pop(node.id, None)
        if self._answer_held:
            self._answer_held.pop(node.id, None)
        if not self.opened:
            return
        app = node.app
        blk = self._blocks.get(app.name)
        if (blk is not None and not blk.started and not blk.expired
                and node.commands[0].id >= blk.first_command):
            blk.started = True
            blk.deadline = self._clock.after(blk.watchdog)
            self._step_aside(blk.devices)
            self.refile_answering()  # (a block under way is concluded: 7.6 (1) holds
            # none of its app's ABs on its devices any more)
        st = self._streams.get(app.name)
        if st is not None:
            st.devices.update(node.devices)

    def ended(self, node: Node) -> None:
        """An AB ended: what the channel rule parked may go (a talk ended, or it freed
        a device they wait for), and what a reaction's next AB kept (it may wait now,
        or rank otherwise); those still held are parked again."""
        if self._channel_held and not node.devices.isdisjoint(self._talk):
            self._wm.dirty.update(self._channel_devices)
        self.refile_talk()
        if self._reserve_parked:
            self.refile_reserved()

    def refile_talk(self) -> None:
        """Re-file what the channel rule parked: a talk ended, or the robot's pause after
        a false interruption is over (one still held is parked again in the next round)."""
        if self._talk_parked:
            parked, self._talk_parked = self._talk_parked, []
            for n in parked:
                self._wm.refile(n)

    def refile_reserved(self) -> None:
        """Re-file the ABs parked for a reaction's next AB (one still kept is parked
        again in the next round)."""
        if not self._reserve_parked:
            return
        parked, self._reserve_parked = self._reserve_parked, []
        for n in parked:
            self._unkeep(n)
            self._wm.refile(n)

    def refile_answering(self) -> None:
        """Re-file the ABs a reaction to the user's own action held (one still held, by
        it or another, is parked again in the next round)."""
        if not self._answer_parked:
            return
        parked, self._answer_parked = self._answer_parked, []
        for n in parked:
            self._unkeep(n)
            self._wm.refile(n)

    def answering(self, node: Node, by: Tree) -> None:
        """Record that ``by``, a reaction to the user's own action, holds back ``node``, of
        a stream not yet under way (once per AB and reaction: docs/rules.md 7.6 (1))."""
        key = (by.id, by.reaction)
        if self._answer_held.get(node.id) != key:
            self._answer_held[node.id] = key
            name = by.app.name
            self._log.ab(DecisionKind.HOLD, Rule.ANSWERING, node, f"while {name} answers the user")
            self._log.tell(node.app.name, "held", by=name, rule=Rule.ANSWERING.value)

    def cancelled(self, node: Node) -> None:
        self._channel_held.discard(node.id)
        self._reserved.pop(node.id, None)
        self._behind.pop(node.id, None)
        self._answer_held.pop(node.id, None)
        if node.reserving and self._reserve_parked:
            self.refile_reserved()  # a next AB that kept devices is gone
        if node.not_before and node in self._resting:
            self.refile_talk()  # words whose pause kept others are gone (7.5)
        self._unkeep(node)

    def update(self) -> None:
        """Arm a stream hold when its app goes idle; let it lapse when it is busy again."""
        if not self._streams:
            return
        for app in self._apps.values():
            st = self._streams.get(app.name)
            if st is None:
                continue
            if app.active == 0:
                if not st.armed and not st.lapsed and st.devices:
                    st.armed = True
                    st.deadline = self._clock.after(st.hold, since=app.idle_since)
                    st.held = set()
                    self._step_aside(st.devices)
            else:
                st.lapsed = False
                if st.armed:
                    st.armed = False
                    self._release(st.devices)

    # ----------------------------------------------------------- held ABs
    def park(self, node: Node, rule: Rule, holder: App) -> None:
        """Take a held AB out of its devices' ranking, so it reserves nothing while it
        cannot start (the holder's block, stream or talk goes on meanwhile)."""
        self._wm.park(node, holder)
        if rule is Rule.KEEP_CHANNEL:
            self._talk_parked.append(node)
            return
        if rule is Rule.RESERVED:
            self._reserve_parked.append(node)
        elif rule is Rule.ANSWERING:
            self._answer_parked.append(node)
        else:
            self._parked.append(node)
        if node.id not in self._kept and holder is not node.app:  # (an app's own waits
            # for its reaction to the user's words are no budget matter)
            self._kept[node.id] = holder.name
            self.keeping[holder.name] = self.keeping.get(holder.name, 0) + 1

    def unpark_all(self) -> None:
        """A hold, block or talk ended or lost its force: re-file the parked ABs (one
        still held is parked again in the next round)."""
        parked, self._parked = (self._parked + self._talk_parked + self._reserve_parked
                                + self._answer_parked), []
        self._talk_parked = []
        self._reserve_parked = []
        self._answer_parked = []
        for node in parked:
            self._unkeep(node)
            self._wm.refile(node)

    def _unkeep(self, node: Node) -> None:
        holder = self._kept.pop(node.id, None)
        if holder is not None:
            left = self.keeping[holder] - 1
            if left:
                self.keeping[holder] = left
            else:
                del self.keeping[holder]

    def reserved(self, node: Node, by: Node) -> None:
        """Record that the next AB ``by`` of another application's reaction (or reply)
        keeps the ready ``node`` from its devices (once per AB: docs/rules.md 7.1)."""
        if self._reserved.get(node.id) != by.id:  # (once per AB it is kept for)
            self._reserved[node.id] = by.id
            what = "reply" if by.protected else "reaction"
            self._log.emit(DecisionKind.HOLD, Rule.RESERVED, node,
                           detail=f"devices kept for {by.app.name}'s {what} (AB{by.id} next)",
                           before=by.id)
            self._log.tell(node.app.name, "held", by=by.app.name, rule=Rule.RESERVED.value)

    def kept_for(self, node: Node, by: Node) -> bool:
        """Whether a hold said ``node`` was kept for the next AB ``by`` of another
        application's reaction, and no line has said yet that it waits on behind it."""
        return self._reserved.get(node.id) == by.id and self._behind.get(node.id) != by.id

    def behind(self, node: Node, by: Node, rule: Rule) -> None:
        """Record that ``node``, which a hold said was kept for the next AB ``by`` of
        another application's reaction (or reply), waits on behind it now that ``by``
        starts a feedback loop: its iterations rank as ``by`` does, by ``rule``, while
        their tree is in working memory (docs/rules.md 7.1: following the user goes on),
        so no other line would say why ``node`` still waits (once per AB and loop)."""
        if self.kept_for(node, by):
            self._behind[node.id] = by.id
            what = "reply" if by.protected else "reaction"
            self._log.emit(DecisionKind.HOLD, rule, node,
                           detail=f"waits for {by.app.name}'s {what} (its loop AB{by.id} "
                                  f"{by.name} goes on)", before=by.id)
            self._log.tell(node.app.name, "held", by=by.app.name, rule=rule.value)

    def note(self, node: Node, rule: Rule, holder: App) -> None:
        """Record that ``holder`` keeps ``node`` waiting (once per hold)."""
        if rule is Rule.KEEP_CHANNEL:
            if node.id not in self._channel_held:
                self._channel_held.add(node.id)
                self._log.ab(DecisionKind.HOLD, rule, node, f"{holder.name} is talking")
                self._log.tell(node.app.name, "held", by=holder.name, rule=rule.value)
            return
        box: Block | Stream | None = (self._blocks.get(holder.name) if rule is Rule.BLOCK
                                      else self._streams.get(holder.name))
        if box is None or node.id in box.held:
            return
        box.held.add(node.id)
        self._log.ab(DecisionKind.HOLD, rule, node, f"devices kept for {holder.name}")
        self._log.tell(node.app.name, "held", by=holder.name, rule=rule.value)

    # ----------------------------------------------------------- deadlines
    def next_deadline(self) -> float | None:
        """The earliest pending hold timeout or watchdog, if any."""
        if not self.opened:  # (no stream or block is open: asked at every wake of a run)
            return None
        best: float | None = None
        for app in self._apps.values():
            st, blk = self._streams.get(app.name), self._blocks.get(app.name)
            if st is not None and st.armed and (best is None or st.deadline < best):
                best = st.deadline
            if blk is not None and blk.reserving and (best is None or blk.deadline < best):
                best = blk.deadline
        return best

    def due(self, now: float) -> bool:
        """Some hold's timeout or block's watchdog has passed: :meth:`expire` ends it."""
        best = self.next_deadline()
        return best is not None and best <= now

    def expire(self, now: float) -> None:
        """End every hold whose timeout and every block whose watchdog has passed."""
        if not self.opened:
            return
        for app in list(self._apps.values()):
            st, blk = self._streams.get(app.name), self._blocks.get(app.name)
            if st is not None and st.armed and st.deadline <= now:
                st.armed = False
                st.lapsed = True
                self._release(st.devices)
                self._log.emit(DecisionKind.RELEASE, Rule.HOLD_TIMEOUT, app=app.name,
                               detail="stream hold on " + ", ".join(sorted(st.devices)))
            if blk is not None and blk.reserving and blk.deadline <= now:
                blk.expired = True
                self._release(blk.devices)
                self._log.emit(DecisionKind.RELEASE, Rule.WATCHDOG, app=app.name,
                               detail="block on " + ", ".join(sorted(blk.devices)))

    # ----------------------------------------------------------- looking
    def reranked(self, tree: Tree) -> None:
        """``tree`` took over as a (later) reaction: a stream hold no longer keeps it
        (7.2), and what reactions kept from others may rank otherwise now (7.1)."""
        if tree.parked:
            self.unpark_all()
        elif self._reserve_parked:
            self.refile_reserved()

    def regained(self, app: App) -> None:
        """The app regained its precedence: its holds are in force again; what the others'
        reactions kept from it may rank otherwise now."""
        if self._reserve_parked:
            self.refile_reserved()
        st, blk = self._streams.get(app.name), self._blocks.get(app.name)
        if st is not None and st.armed:
            self._step_aside(st.devices)
        if blk is not None and blk.reserving:
            self._step_aside(blk.devices)

    def _step_aside(self, devices: set[str] | frozenset[str]) -> None:
        """A hold took force on ``devices``: every waiting AB it holds steps aside now
        (is parked, so it reserves nothing), not only the best on each device, which
        may be the holder's own. It looks only at the trees with waiting ABs on those
        devices that a hold could keep (a stream hold keeps only new streams), and at
        their ABs there: the ABs it parks, not the whole waiting list."""
        wm = self._wm
        wm.dirty.update(devices)
        # (a reaction's next AB that waits behind what the hold keeps keeps nothing from
        # the holder any more: what it kept is looked at again)
        self.refile_reserved()
        found: dict[AbId, Node] = {}
        wm.count_named()  # (``on`` counts them)
        for d in devices:
            for tree, nodes in wm.on.get(d, {}).items():
                if self._may_hold(tree):
                    found.update(nodes)
        for ab in sorted(found):  # in the order the ABs were created
            node = found[ab]
            if node.state is NodeState.WAITING and node.parked is None:
                held = self.holder(node)
                if held is not None and held[0] is not Rule.KEEP_CHANNEL:
                    self.note(node, *held)
                    self.park(node, *held)

    def _may_hold(self, tree: Tree) -> bool:
        """Whether another app's block or stream hold could keep an AB of ``tree``
        (what :meth:`holder` asks of each AB, asked once for the tree)."""
        for other in self._apps.values():
            if other is tree.app or other.demoted:
                continue
            blk = self._blocks.get(other.name)
            if blk is not None and blk.reserving:
                return True
            st = self._streams.get(other.name)
            if st is not None and st.armed and _new_stream(tree):
                return True
        return False

    def demoted(self) -> tuple[str, ...]:
        """Apps that have lost their precedence (their holds hold nothing)."""
        return tuple(app.name for app in self._apps.values() if app.demoted)

    def in_force(self) -> list[tuple[str, str, tuple[str, ...], float]]:
        """Holds in force: (app, ``stream`` or ``block``, devices, deadline)."""
        out = []
        for app in self._apps.values():
            st, blk = self._streams.get(app.name), self._blocks.get(app.name)
            if st is not None and st.armed:
                out.append((app.name, "stream", tuple(sorted(st.devices)), st.deadline))
            if blk is not None and blk.reserving:
                out.append((app.name, "block", tuple(sorted(blk.devices)), blk.deadline))
        return out


def _new_stream(tree: Tree) -> bool:
    """A stream hold delays this tree: no reaction, and not under way (docs/rules.md 7.2)."""
    return tree.reaction is None and (not tree.started or tree.suspended is not None)
