"""The waiting index: for each device, its best waiting AB in logarithmic time.

Selection asks, for a device, which waiting AB that needs it ranks best
(:mod:`._ranking`). The index answers from the parts of the rank that do not
change every round (the keys :class:`._ranking.Ranking` keeps on each AB and
tree, so no key function is called to file or re-rank), split by the criteria's
scopes:

- ``head``: the NODE criteria before the first TREE criterion (priority): ABs
  with equal head keys form a *group*;
- within a group, each tree's ABs form a *slot*, ranked by the stable key of
  its best AB (the TREE criteria, which are the same for every AB of a tree,
  and the NODE criteria after the head);
- within a slot, ABs are ordered by those NODE criteria alone.

Each device keeps a heap of groups, each group a heap of slots, each slot a
heap of its ABs. When a tree's keys change (it is suspended or resumed, its
application loses or regains its precedence), its slots are re-ranked, a few
per device, never its ABs one by one. Entries are removed lazily: an AB's
entries go stale when it leaves the waiting list or its ``version`` changes
(it was parked); a slot's entry goes stale when the slot's ``version`` changes.
Stale entries are dropped when they reach a heap's top (a slot's stale entry at
its group's top is replaced when the slot is re-ranked, and a dropped slot lets
go of its own entries at once); :meth:`WaitIndex.compact` rebuilds everything
when they outnumber the live ones. Every operation costs a
few heap operations per device, whatever the number of waiting ABs.

ROUND criteria (parent just finished) are not in the index: selection ranks
the ABs a round names against the index's answer (see ``_rounds``).
"""

from __future__ import annotations

import heapq
from collections.abc import Iterable, Set
from typing import Any

from prima.mediator._ranking import Keys, Ranking
from prima.mediator._state import Node, NodeState, Tree

__all__ = ["WaitIndex"]

_WAITING = NodeState.WAITING
_heappush = heapq.heappush
_NO_DEVICES: frozenset[str] = frozenset()

_NodeEntry = tuple[Any, ...]
"""The AB's order keys spliced in, then its id, its version when filed and the AB:
``(*order, id, version, node)``, read from its end (every entry holds as many keys;
the id is unique, so entries never compare up to the AB)."""


class _Slot:
    """One tree's waiting ABs in one group: a heap by order keys."""

    __slots__ = ("tree", "group", "device", "heap", "version", "ranked_by")

    def __init__(self, tree: Tree, group: _Group, device: str) -> None:
        self.tree = tree
        self.group = group
        self.device = device
        self.heap: list[_NodeEntry] = []
        self.version = -1
        """The serial of its one live entry in its group's heap (-1: none)."""
        self.ranked_by: Node | None = None
        """The AB whose keys the slot's live entry in its group carries."""

    def top(self, index: WaitIndex) -> Node | None:
        """The slot's best live AB, dropping stale entries."""
        heap = self.heap
        while heap:
            entry = heap[0]
            node: Node = entry[-1]
            if node.state is _WAITING and node.version == entry[-2]:
                return node
            heapq.heappop(heap)
            index.entries -= 1
        return None


_SlotEntry = tuple[Any, ...]
"""The keys of the slot's best AB (its tree and order keys, laid end to end) spliced
in, then a serial unique over all entries, then the slot: ``(*keys, serial, slot)``,
read from its end. Every entry holds as many keys, so entries compare as ``(keys,
serial, slot)`` would, but a level of nesting less for the heaps to walk, compare
after compare."""


class _Group:
    """The waiting ABs of one device with equal head keys: a heap of slots."""

    __slots__ = ("head", "slots", "heap")

    def __init__(self, head: Keys) -> None:
        self.head = head
        self.slots: dict[int, _Slot] = {}
        self.heap: list[_SlotEntry] = []


class _Device:
    __slots__ = ("groups", "heap")

    def __init__(self) -> None:
        self.groups: dict[Keys, _Group] = {}
        self.heap: list[tuple[Keys, int, _Group]] = []


class WaitIndex:
    """Waiting ABs per device, ranked by the stable part of rule 4."""

    def __init__(self, ranking: Ranking) -> None:
        self.ranking = ranking
        """The criteria's keys, kept on the ABs and trees (:class:`._ranking.Ranking`)."""
        self._devices: dict[str, _Device] = {}
        self._tree_slots: dict[int, dict[_Slot, None]] = {}
        """Tree id -> its live slots (a few per tree; a dict as an ordered set: its order
        is the order they were made in, whatever their addresses)."""
        self.serial = 0
        """The serial of the latest slot or group entry (never reused). It advances
        whenever a device's answer (:meth:`top`) may change but for its AB leaving the
        waiting list or being parked: an AB filed first in its slot, a slot re-ranked, a
        group made. (It also advances when a top drops stale entries, which changes no
        answer.) Selection relies on this to ask a device once per round (``_rounds``)."""
        self.entries = 0
        """Heap entries held, live and stale."""

    # ---------------------------------------------------------------- filing
    def add(self, node: Node) -> None:
        """File a waiting AB (again, after it was parked: its old entries go stale)."""
        node.version += 1
        if node.head is None:
            self.ranking.node_keys(node)
        head = node.head
        order = node.order
        assert head is not None and order is not None
        entry = order + (node.id, node.version, node)
        tree = node.tree
        devices = self._devices
        for d in node.sorted_devices:
            dev = devices.get(d)
            group = dev.groups.get(head) if dev is not None else None
            slot = group.slots.get(tree.id) if group is not None else None
            if slot is None:
                slot = self._slot(d, head, tree, group)
            heap = slot.heap
            _heappush(heap, entry)
            self.entries += 1
            # It ranks its slot when it is first in it: at the top, or next below stale
            # entries (``_Slot.top`` drops them; not asked when the top entry is live).
            first = heap[0]
            top = first[-1]
            if first is entry or (
                    (top.state is not _WAITING or top.version != first[-2])
                    and slot.top(self) is node):
                self._push_slot(slot, node)

    def rerank(self, tree: Tree) -> Set[str]:
        """The tree's TREE keys changed (suspended, resumed): re-rank its slots.

        Returns the devices on which the tree has waiting ABs.
        """
        tree.keys = None
        slots = self._tree_slots.get(tree.id)
        if not slots:
            return _NO_DEVICES
        devices = set()
        for slot in list(slots):
            best = slot.top(self)
            if best is None:
                self._drop_slot(slot)
            else:
                self._push_slot(slot, best)
                devices.add(slot.device)
        return devices

    def forget(self, tree: Tree) -> None:
        """The tree left working memory: drop its slots (and its keys)."""
        tree.keys = None
        slots = self._tree_slots.pop(tree.id, None)
        if slots:
            for slot in slots:
                self._discard(slot)

    def top(self, device: str) -> Node | None:
        """The best-ranked waiting AB that needs ``device`` (ROUND criteria aside)."""
        dev = self._devices.get(device)
        if dev is None:
            return None
        heap = dev.heap
        while heap:
            head, _serial, group = heap[0]
            # (the common case inline: no stale entry on the way down)
            gheap = group.heap
            if gheap:
                first = gheap[0]
                version: int = first[-2]
                slot: _Slot = first[-1]
                sheap = slot.heap
                if version == slot.version and sheap:
                    entry = sheap[0]
                    node: Node = entry[-1]
                    if (node.state is _WAITING and node.version == entry[-2]
                            and node is slot.ranked_by):
                        return node
            found = self._group_top(group)
            if found is not None:
                return found
            heapq.heappop(heap)
            self.entries -= 1
            if dev.groups.get(head) is group:
                del dev.groups[head]
        return None

    def compact(self, live: Iterable[Node]) -> None:
        """Rebuild every heap from the live waiting ABs (drops stale entries)."""
        self._devices.clear()
        self._tree_slots.clear()
        self.entries = 0
        for node in live:
            self.add(node)

    # -------------------------------------------------------------- internals
    def _slot(self, device: str, head: Keys, tree: Tree, group: _Group | None) -> _Slot:
        """A new slot for ``tree`` in the group ``head`` of ``device`` (the group is
        made if None)."""
        if group is None:
            dev = self._devices.get(device)
            if dev is None:
                dev = self._devices[device] = _Device()
            group = dev.groups[head] = _Group(head)
            self.serial = serial = self.serial + 1
            heapq.heappush(dev.heap, (head, serial, group))
            self.entries += 1
        slot = group.slots[tree.id] = _Slot(tree, group, device)
        self._tree_slots.setdefault(tree.id, {})[slot] = None
        return slot

    def _push_slot(self, slot: _Slot, best: Node) -> None:
        """(Re-)rank a slot by the stable keys of its best AB; its older entries go stale."""
        # (a serial unique over all entries: entries never tie up to the slot)
        self.serial = slot.version = version = self.serial + 1
        slot.ranked_by = best
        entry: _SlotEntry = self.ranking.slot_keys(best) + (version, slot)
        heap = slot.group.heap
        if heap and heap[0][-1] is slot:
            # (an entry of its own at the top, now stale: replaced, not left for a pop)
            heapq.heapreplace(heap, entry)
        else:
            _heappush(heap, entry)
            self.entries += 1

    def _drop_slot(self, slot: _Slot) -> None:
        """Drop a live slot: out of its group and its tree's books."""
        self._discard(slot)
        tid = slot.tree.id
        slots = self._tree_slots.get(tid)
        if slots is not None and slot in slots:
            del slots[slot]
            if not slots:
                del self._tree_slots[tid]

    def _discard(self, slot: _Slot) -> None:
        """Take a live slot out of its group (its tree's books are the caller's). What
        stale entries it holds are dropped now, and its group's top entry if that is
        its own: else they would keep its ABs and their tree alive until they reached
        a top or a compaction (an ASAP request's tree, cancelled, leaves at once)."""
        slot.version = -1
        self.entries -= len(slot.heap)
        slot.heap = []
        slot.ranked_by = None
        group = slot.group
        tid = slot.tree.id
        if group.slots.get(tid) is slot:
            del group.slots[tid]
        heap = group.heap
        if heap and heap[0][-1] is slot:
            heapq.heappop(heap)
            self.entries -= 1

    def _group_top(self, group: _Group) -> Node | None:
        heap = group.heap
        while heap:
            entry = heap[0]
            version: int = entry[-2]
            slot: _Slot = entry[-1]
            if version != slot.version:
                heapq.heappop(heap)
                self.entries -= 1
                continue
            best = slot.top(self)
            if best is None:
                self._drop_slot(slot)  # (its entry, at the top, with it)
                continue
            if best is not slot.ranked_by:  # the AB it was ranked by left the waiting list
                self._push_slot(slot, best)  # (its entry at the top is replaced)
                continue
            return best
        return None
