"""The waiting index: for each device, its best waiting AB in logarithmic time.

Selection asks, for a device, which waiting AB that needs it ranks best
(:mod:`._ranking`). The index answers from the parts of the rank that do not
change every round (the keys :class:`._ranking.Ranking` keeps on each AB and
tree, so no key function is called to file or re-rank), split by the criteria's
scopes:

- a *slot* holds the ABs of one tree with equal head keys (the NODE criteria
  before the first TREE criterion: priority); it is ranked by the stable keys
  of its best AB: the head keys, the TREE criteria (the same for every AB of a
  tree) and the NODE criteria after the head;
- within a slot, ABs are ordered by those NODE criteria alone.

Each device keeps a heap of slots, each slot a heap of its ABs. When a tree's
keys change (it is suspended or resumed, its application loses or regains its
precedence), its slots are re-ranked, a few per device, never its ABs one by
one. Entries are removed lazily: an AB's
entries go stale when it leaves the waiting list or its ``version`` changes
(it was parked); a slot's entry goes stale when the slot's ``version`` changes.
Stale entries are dropped when they reach a heap's top (a slot's stale entry at
its device's top is replaced when the slot is re-ranked, and a dropped slot lets
go of its own entries at once); :meth:`WaitIndex.compact` rebuilds everything
when they outnumber the live ones. Every operation costs a
few heap operations per device, whatever the number of waiting ABs.

ROUND criteria (parent just finished) are not in the index: selection ranks
the ABs a round names against the index's answer (see ``_rounds``).
"""

from __future__ import annotations

import heapq
from collections.abc import Iterable, Set
from typing import Any, Final

from prima.mediator._ranking import Keys, Ranking
from prima.mediator._state import Node, NodeState, Tree

__all__ = ["WaitIndex"]

_WAITING: Final = NodeState.WAITING
_heappush: Final = heapq.heappush
_NO_DEVICES: Final[frozenset[str]] = frozenset()

_NodeEntry = tuple[Any, ...]
"""The AB's order keys spliced in, then its id, its version when filed and the AB:
``(*order, id, version, node)``, read from its end (every entry holds as many keys;
the id is unique, so entries never compare up to the AB)."""


class _Slot:
    """One tree's waiting ABs with equal head keys on one device: a heap by order keys."""

    __slots__ = ("tree", "head", "device", "ranked", "heap", "version", "ranked_by")

    def __init__(self, tree: Tree, head: Keys, device: str, ranked: list[_SlotEntry]) -> None:
        self.tree = tree
        self.head = head
        self.device = device
        self.ranked = ranked
        """Its device's heap of slots."""
        self.heap: list[_NodeEntry] = []
        self.version = -1
        """The serial of its one live entry in its device's heap (-1: none)."""
        self.ranked_by: Node | None = None
        """The AB whose keys the slot's live entry carries."""

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
"""The keys of the slot's best AB (its head, tree and order keys, laid end to end)
spliced in, then a serial unique over all entries, then the slot: ``(*keys, serial,
slot)``, read from its end. Every entry holds as many keys, so entries compare as
``(keys, serial, slot)`` would, but a level of nesting less for the heaps to walk,
compare after compare."""


class _Device:
    """One device's waiting ABs: a heap of slots."""

    __slots__ = ("slots", "heap")

    def __init__(self) -> None:
        self.slots: dict[tuple[int, Keys], _Slot] = {}
        """(tree id, head keys) -> its live slot."""
        self.heap: list[_SlotEntry] = []


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
        """The serial of the latest slot entry (never reused). It advances whenever a
        device's answer (:meth:`top`) may change but for its AB leaving the waiting list
        or being parked: an AB filed first in its slot, a slot re-ranked. (It also
        advances when a top drops stale entries, which changes no answer.) Selection
        relies on this to ask a device once per round (``_rounds``)."""
        self.entries = 0
        """Heap entries held, live and stale."""

    # ---------------------------------------------------------------- filing
    def add(self, node: Node) -> None:
        """File a waiting AB (again, after it was parked: its old entries go stale)."""
        node.version += 1
        node.unfiled = False
        if node.head is None:
            self.ranking.node_keys(node)
        head = node.head
        order = node.order
        assert head is not None and order is not None
        entry = order + (node.id, node.version, node)
        tree = node.tree
        key = (tree.id, head)
        devices = self._devices
        for d in node.sorted_devices:
            dev = devices.get(d)
            if dev is None:
                dev = devices[d] = _Device()
            slot = dev.slots.get(key)
            if slot is None:
                slot = dev.slots[key] = _Slot(tree, head, d, dev.heap)
                self._tree_slots.setdefault(tree.id, {})[slot] = None
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
            first = heap[0]
            slot: _Slot = first[-1]
            if first[-2] != slot.version:  # (a stale entry of its slot)
                heapq.heappop(heap)
                self.entries -= 1
                continue
            # (the common case inline: no stale entry in the slot)
            sheap = slot.heap
            if sheap:
                entry = sheap[0]
                node: Node = entry[-1]
                if (node.state is _WAITING and node.version == entry[-2]
                        and node is slot.ranked_by):
                    return node
            best = slot.top(self)
            if best is None:
                self._drop_slot(slot)  # (its entry, at the top, with it)
            elif best is not slot.ranked_by:  # the AB it was ranked by left the waiting list
                self._push_slot(slot, best)  # (its entry at the top is replaced)
            else:
                return best
        return None

    def compact(self, live: Iterable[Node]) -> None:
        """Rebuild every heap from the live waiting ABs (drops stale entries)."""
        self._devices.clear()
        self._tree_slots.clear()
        self.entries = 0
        for node in live:
            self.add(node)

    # -------------------------------------------------------------- internals
    def _push_slot(self, slot: _Slot, best: Node) -> None:
        """(Re-)rank a slot by the stable keys of its best AB; its older entries go stale."""
        # (a serial unique over all entries: entries never tie up to the slot)
        self.serial = slot.version = version = self.serial + 1
        slot.ranked_by = best
        entry: _SlotEntry = self.ranking.slot_keys(best) + (version, slot)
        heap = slot.ranked
        if heap and heap[0][-1] is slot:
            # (an entry of its own at the top, now stale: replaced, not left for a pop)
            heapq.heapreplace(heap, entry)
        else:
            _heappush(heap, entry)
            self.entries += 1

    def _drop_slot(self, slot: _Slot) -> None:
        """Drop a live slot: out of its device's heap and its tree's books."""
        self._discard(slot)
        tid = slot.tree.id
        slots = self._tree_slots.get(tid)
        if slots is not None and slot in slots:
            del slots[slot]
            if not slots:
                del self._tree_slots[tid]

    def _discard(self, slot: _Slot) -> None:
        """Take a live slot out of its device (its tree's books are the caller's). What
        stale entries it holds are dropped now, and its device's top entry if that is
        its own: else they would keep its ABs and their tree alive until they reached
        a top or a compaction (an ASAP request's tree, cancelled, leaves at once)."""
        slot.version = -1
        self.entries -= len(slot.heap)
        slot.heap = []
        slot.ranked_by = None
        slots = self._devices[slot.device].slots
        key = (slot.tree.id, slot.head)
        if slots.get(key) is slot:
            del slots[key]
        heap = slot.ranked
        if heap and heap[0][-1] is slot:
            heapq.heappop(heap)
            self.entries -= 1
