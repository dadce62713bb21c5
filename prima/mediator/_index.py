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
Stale entries are dropped when they reach a heap's top; :meth:`WaitIndex.compact`
rebuilds everything when they outnumber the live ones. Every operation costs a
few heap operations per device, whatever the number of waiting ABs.

ROUND criteria (parent just finished) are not in the index: selection ranks
the ABs a round names against the index's answer (see ``_rounds``).
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Iterable

from prima.mediator._ranking import Keys, Ranking
from prima.mediator._state import Node, NodeState, Tree

__all__ = ["WaitIndex"]

_WAITING = NodeState.WAITING
_heappush = heapq.heappush

_NodeEntry = tuple[Keys, int, int, Node]
"""(the AB's order keys, its id, its version when filed, the AB)."""


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
            _keys_, _ab, version, node = heap[0]
            if node.state is _WAITING and node.version == version:
                return node
            heapq.heappop(heap)
            index.entries -= 1
        return None


_SlotEntry = tuple[Keys, int, _Slot]
"""(keys of the slot's best AB, a serial unique over all entries, the slot)."""


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
        self._tree_slots: dict[int, dict[tuple[str, Keys], _Slot]] = {}
        """Tree id -> its live slots, by (device, group head): a few per tree."""
        self._serial = itertools.count()
        self.entries = 0
        """Heap entries held, live and stale."""

    # ---------------------------------------------------------------- filing
    def add(self, node: Node) -> None:
        """File a waiting AB (again, after it was parked: its old entries go stale)."""
        node.version += 1
        if node.head is None:
            self.ranking.node_keys(node)
        head = node.head
        assert head is not None and node.order is not None
        entry = (node.order, node.id, node.version, node)
        tree = node.tree
        devices = self._devices
        for d in node.sorted_devices:
            # (``_slot``, its usual case inline: the device, group and slot exist)
            dev = devices.get(d)
            group = dev.groups.get(head) if dev is not None else None
            slot = group.slots.get(tree.id) if group is not None else None
            if slot is None:
                slot = self._slot(d, head, tree)
            heap = slot.heap
            _heappush(heap, entry)
            self.entries += 1
            if heap[0] is entry or slot.top(self) is node:
                self._push_slot(slot, node)

    def rerank(self, tree: Tree) -> set[str]:
        """The tree's TREE keys changed (suspended, resumed): re-rank its slots.

        Returns the devices on which the tree has waiting ABs.
        """
        tree.keys = None
        slots = self._tree_slots.get(tree.id)
        if not slots:
            return set()
        devices = set()
        for slot in list(slots.values()):
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
        for slot in list(self._tree_slots.get(tree.id, {}).values()):
            self._drop_slot(slot)

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
                _keys_, version, slot = gheap[0]
                sheap = slot.heap
                if version == slot.version and sheap:
                    _order, _ab, nversion, node = sheap[0]
                    if (node.state is _WAITING and node.version == nversion
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
    def _slot(self, device: str, head: Keys, tree: Tree) -> _Slot:
        dev = self._devices.get(device)
        if dev is None:
            dev = self._devices[device] = _Device()
        group = dev.groups.get(head)
        if group is None:
            group = dev.groups[head] = _Group(head)
            heapq.heappush(dev.heap, (head, next(self._serial), group))
            self.entries += 1
        slot = group.slots.get(tree.id)
        if slot is None:
            slot = group.slots[tree.id] = _Slot(tree, group, device)
            self._tree_slots.setdefault(tree.id, {})[device, head] = slot
        return slot

    def _push_slot(self, slot: _Slot, best: Node) -> None:
        """(Re-)rank a slot by the stable keys of its best AB; its older entries go stale."""
        slot.version = version = next(self._serial)  # unique: entries never tie up to the slot
        slot.ranked_by = best
        _heappush(slot.group.heap, (self.ranking.slot_keys(best), version, slot))
        self.entries += 1

    def _drop_slot(self, slot: _Slot) -> None:
        slot.version = -1
        # (its entries are all stale: dropped now, not when the slot's own entry reaches
        # its group's top, so that the ABs they name are freed at once)
        self.entries -= len(slot.heap)
        slot.heap.clear()
        slot.ranked_by = None
        tid = slot.tree.id
        if slot.group.slots.get(tid) is slot:
            del slot.group.slots[tid]
        slots = self._tree_slots.get(tid)
        if slots is not None and slots.get((slot.device, slot.group.head)) is slot:
            del slots[slot.device, slot.group.head]
            if not slots:
                del self._tree_slots[tid]

    def _group_top(self, group: _Group) -> Node | None:
        heap = group.heap
        while heap:
            _keys_, version, slot = heap[0]
            if version != slot.version:
                heapq.heappop(heap)
                self.entries -= 1
                continue
            best = slot.top(self)
            if best is None:
                heapq.heappop(heap)
                self.entries -= 1
                self._drop_slot(slot)
                continue
            if best is not slot.ranked_by:  # the AB it was ranked by left the waiting list
                heapq.heappop(heap)
                self.entries -= 1
                self._push_slot(slot, best)
                continue
            return best
        return None
