"""Selection rounds (MISSION.md rule 4), holds and suspension (rules 6c, 4.4).

A round looks only at ABs that may have become startable since the last one:
ABs that just entered the waiting list, and the best waiting AB on each
*dirty* device. An AB starts when all its devices are free, no stream hold or
block of another app keeps them from it, and it is the best-ranked waiting AB
on each of them. This is exactly what walking the whole waiting list in rank
order would start (a better AB that cannot start reserves its devices), but
without touching the ABs that cannot start.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from prima.mediator.decisions import DecisionKind, Rule
from prima.mediator.selection import rank, separating_rule
from prima.catalog import Priority
from prima.mediator.state import TALK_DEVICES, NodeState, _App, _Node, _Tree

if TYPE_CHECKING:
    from prima.mediator.core import Mediator

__all__ = ["RoundsMixin"]


class RoundsMixin:
    """Selection for :class:`~prima.mediator.core.Mediator` (split out for size)."""

    def _settle(self: Mediator) -> None:
        """Run rounds until nothing more can start; then hand the starts to the driver."""
        self._settling = True
        wm = self._wm
        try:
            while True:
                for app in self._apps.values():
                    if app.stream is not None:
                        self._update_holds()
                        break
                if not (wm.new or wm.dirty or wm.pjf):
                    break
                for node in self._round():
                    self._driver.start(self._ab(node))
            wm.maybe_compact()
        finally:
            self._settling = False

    def _update_holds(self: Mediator) -> None:
        """Arm a stream hold when its app goes idle; let it lapse when it is busy again."""
        for app in self._apps.values():
            st = app.stream
            if st is None:
                continue
            if app.active == 0:
                if not st.armed and not st.lapsed and st.devices:
                    st.armed = True
                    st.deadline = app.idle_since + st.hold
                    st.held = set()
            else:
                st.lapsed = False
                if st.armed:
                    st.armed = False
                    self._wm.dirty.update(st.devices)
                    self._unpark_all()

    def _holder(self: Mediator, node: _Node) -> tuple[Rule, _App] | None:
        """Another app's block, armed stream hold, or talk that keeps ``node`` from starting.

        The talk: a Command that breaks the Communication Channel (moving away)
        never starts while another application talks with the user, so the robot
        does not leave in the middle of a conversation (thesis Sec. 3.3).
        """
        if node.priority is Priority.LOW:
            busy = self._wm.busy
            for d in TALK_DEVICES:
                talker = busy.get(d)
                if talker is not None and talker.app is not node.app:
                    return Rule.KEEP_CHANNEL, talker.app
            if not self._apps_with_holds:
                return None
        for other in self._apps.values():
            if other is node.app:
                continue
            blk = other.block
            if blk is not None and blk.reserving and not node.devices.isdisjoint(blk.devices):
                return Rule.BLOCK, other
            st = other.stream
            if (st is not None and st.armed and not node.reactive
                    and not node.devices.isdisjoint(st.devices)):
                return Rule.STREAM_HOLD, other
        return None

    def _round(self: Mediator) -> list[_Node]:
        wm = self._wm
        pjf = wm.pjf
        wm.pjf = {}
        new = wm.new
        wm.new = []
        dirty = wm.dirty
        wm.dirty = set()
        busy = wm.busy
        pjf_on: dict[str, list[_Node]] = {}
        for n in pjf.values():
            if n.state is NodeState.WAITING:
                for d in n.sorted_devices:
                    pjf_on.setdefault(d, []).append(n)
        best = wm.index.best

        cands: dict[int, _Node] = {}
        for n in new:
            if n.state is NodeState.WAITING:
                cands[n.id] = n
        for d in (sorted(dirty) if len(dirty) > 1 else dirty):
            b = best(d, pjf, pjf_on)
            if b is not None:
                cands[b.id] = b
        if not cands:
            return []
        order = list(cands.values())
        if len(order) > 1:
            order.sort(key=lambda n: rank(n, pjf))
        later: list[tuple[bool, _Tree]] = []
        started: list[_Node] = []
        for x in order:
            if x.state is not NodeState.WAITING:
                continue
            devices = x.sorted_devices
            held = self._holder(x) if self._apps_with_holds or x.priority is Priority.LOW else None
            if held is not None and held[0] is not Rule.KEEP_CHANNEL:
                # Held by another app's block or stream hold: out of the ranking at
                # once, busy devices or not, so it reserves nothing meanwhile.
                self._note_hold(x, *held)
                self._park(x)
                continue
            blocked = False
            for d in devices:
                if d in busy or best(d, pjf, pjf_on) is not x:
                    blocked = True
                    break
            if blocked:
                continue
            if held is not None:  # the channel rule: it waits, still ranked
                self._note_hold(x, *held)
                continue
            x_rank = rank(x, pjf)
            wm.start(x)
            started.append(x)
            self._on_start(x)
            # Who did it beat? The best remaining waiting AB on each of its devices.
            losers = []
            for d in devices:
                b = best(d, pjf, pjf_on)
                if b is not None:
                    losers.append(b)
            rule = Rule.FREE_DEVICES
            if losers:
                top = min(losers, key=lambda n: rank(n, pjf)) if len(losers) > 1 else losers[0]
                rule = separating_rule(x_rank, rank(top, pjf))
            self._emit(DecisionKind.START, rule, x)
            if x.tree.suspended is not None:
                self._emit(DecisionKind.RESUME, rule, x, detail="resumed from the suspended IU")
                later.append((False, x.tree))
            for loser in losers:
                tree = loser.tree
                if tree is x.tree or tree.suspended is not None:
                    continue
                if any(is_suspend and t is tree for is_suspend, t in later):
                    continue
                # "Ready": it lost only to this round's starts, not to ABs already running.
                ready = all(busy.get(d) is None or busy[d] in started for d in loser.devices)
                if ready and self._holder(loser) is None:
                    self._emit(DecisionKind.SUSPEND, rule, loser,
                               detail=f"lost to AB{x.id} ({x.app.name})")
                    later.append((True, tree))
        for is_suspend, tree in later:
            if is_suspend:
                wm.suspend(tree)
            else:
                wm.resume(tree)
        # "Parent just finished" lasts one round: others may now rank above.
        for n in pjf.values():
            if n.state is NodeState.WAITING:
                wm.dirty.update(n.devices)
        return started

    def _park(self: Mediator, node: _Node) -> None:
        """Take a held AB out of its devices' ranking, so it does not reserve them
        against the holder's own ABs (the block or stream goes on meanwhile)."""
        node.parked = True
        node.version += 1  # its index entries are stale from now on
        self._parked.append(node)
        self._wm.dirty.update(node.devices)

    def _unpark_all(self: Mediator) -> None:
        """A hold or block ended: re-file the parked ABs (a hold still in force parks
        them again in the next round)."""
        wm = self._wm
        for node in self._parked:
            node.parked = False
            if node.state is NodeState.WAITING:
                wm.index.add(node)
                wm.dirty.update(node.devices)
        self._parked = []

    def _note_hold(self: Mediator, node: _Node, rule: Rule, holder: _App) -> None:
        if rule is Rule.KEEP_CHANNEL:
            held = self._wm.channel_held
            if node.id not in held:
                held.add(node.id)
                self._emit(DecisionKind.HOLD, rule, node, detail=f"{holder.name} is talking")
            return
        box = holder.block if rule is Rule.BLOCK else holder.stream
        if box is None or node.id in box.held:
            return
        box.held.add(node.id)
        self._emit(DecisionKind.HOLD, rule, node, detail=f"devices kept for {holder.name}")

    def _on_start(self: Mediator, node: _Node) -> None:
        app = node.app
        blk = app.block
        if (blk is not None and not blk.started and not blk.expired
                and node.commands[0].id >= blk.first_command):
            blk.started = True
            blk.deadline = self._clock.now() + blk.watchdog
        st = app.stream
        if st is not None:
            st.devices.update(node.devices)
