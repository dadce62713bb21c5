"""The waiting index: for each device, its best waiting AB in logarithmic time.

Selection asks, for a device, which waiting AB that needs it ranks best
(:mod:`._ranking`). The index answers from the parts of the rank that do not
change every round, split by scope as the criteria list says:

- ``head``: the NODE criteria before the first TREE criterion (priority,
  reactivity): ABs with equal head keys form a *group*;
- ``tree``: the TREE criteria (the suspended-stream order): within a group,
  each tree's ABs form a *slot*, ranked by the tree's key;
- ``tail``: the NODE criteria after them (the oldest request): the order
  within a slot.

Each device keeps a heap of groups, each group a heap of slots keyed by (tree
key, the slot's best tail key), each slot a heap of its ABs. Suspending or
resuming a tree re-ranks its slots (a few per device), never its ABs one by
one. Entries are removed lazily: an AB's entries go stale when it leaves the
waiting list or its ``version`` changes (it was parked); a slot's entry goes
stale when the slot's ``version`` changes. Stale entries are dropped when they
reach a heap's top; :meth:`WaitIndex.compact` rebuilds everything when they
outnumber the live ones. Every operation costs a few heap operations per
device, whatever the number of waiting ABs.

ROUND criteria (parent just finished) are not in the index: selection ranks
the ABs a round names against the index's answer (see ``_rounds``).
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Iterable

from prima.mediator._ranking import CRITERIA, Criterion, Key, Scope
from prima.mediator._state import Node, NodeState, Tree

__all__ = ["WaitIndex"]


def _split(criteria: tuple[Criterion, ...]) -> tuple[tuple[Criterion, ...], ...]:
    """The head, tree and tail criteria; ROUND criteria are left out."""
    scopes = [c.scope for c in criteria if c.scope is not Scope.ROUND]
    first_tree = scopes.index(Scope.TREE) if Scope.TREE in scopes else len(scopes)
    stable = [c for c in criteria if c.scope is not Scope.ROUND]
    head = tuple(stable[:first_tree])
    rest = stable[first_tree:]
    tree = tuple(c for c in rest if c.scope is Scope.TREE)
    tail = tuple(c for c in rest if c.scope is Scope.NODE)
    if rest and any(c.scope is Scope.TREE for c in rest[len(tree):]):
        raise TypeError("the waiting index needs the TREE criteria in one run; "
                        "reorder CRITERIA")
    return head, tree, tail


_HEAD, _TREE, _TAIL = _split(CRITERIA)
_NO_ROUND: tuple[int, ...] = ()


def _keys(node: Node, criteria: tuple[Criterion, ...]) -> tuple[Key, ...]:
    return tuple(c.key(node, _NO_ROUND) for c in criteria)


class _Slot:
    """One tree's waiting ABs in one group: a heap by tail key."""

    __slots__ = ("tree", "group", "device", "heap", "version")

    def __init__(self, tree: Tree, group: _Group, device: str) -> None:
        self.tree = tree
        self.group = group
        self.device = device
        self.heap: list[tuple[tuple[Key, ...], int, int, Node]] = []
        self.version = 0

    def top(self, index: WaitIndex) -> tuple[tuple[Key, ...], Node] | None:
        """The slot's best live AB with its tail key, dropping stale entries."""
        heap = self.heap
        while heap:
            tail, _ab, version, node = heap[0]
            if node.state is NodeState.WAITING and node.version == version:
                return tail, node
            heapq.heappop(heap)
            index.entries -= 1
        return None


_SlotEntry = tuple[tuple[Key, ...], tuple[Key, ...], int, int, _Slot]


class _Group:
    """The waiting ABs of one device with equal head keys: a heap of slots."""

    __slots__ = ("head", "slots", "heap")

    def __init__(self, head: tuple[Key, ...]) -> None:
        self.head = head
        self.slots: dict[int, _Slot] = {}
        self.heap: list[_SlotEntry] = []


class _Device:
    __slots__ = ("groups", "heap")

    def __init__(self) -> None:
        self.groups: dict[tuple[Key, ...], _Group] = {}
        self.heap: list[tuple[tuple[Key, ...], int, _Group]] = []


class WaitIndex:
    """Waiting ABs per device, ranked by the stable part of rule 4."""

    def __init__(self) -> None:
        self._devices: dict[str, _Device] = {}
        self._tree_slots: dict[int, list[_Slot]] = {}
        self._serial = itertools.count()
        self.entries = 0
        """Heap entries held, live and stale."""

    # ---------------------------------------------------------------- filing
    def add(self, node: Node) -> None:
        """File a waiting AB (again, after it was parked: its old entries go stale)."""
        node.version += 1
        head = _keys(node, _HEAD)
        tail = _keys(node, _TAIL)
        for d in node.sorted_devices:
            slot = self._slot(d, head, node.tree)
            heapq.heappush(slot.heap, (tail, node.id, node.version, node))
            self.entries += 1
            best = slot.top(self)
            if best is not None and best[1] is node:
                self._push_slot(slot, tail, node)

    def rerank(self, tree: Tree) -> set[str]:
        """The tree's TREE keys changed (suspended, resumed): re-rank its slots.

        Returns the devices on which the tree has waiting ABs.
        """
        slots = self._tree_slots.get(tree.id)
        if not slots:
            return set()
        devices = set()
        for slot in slots:
            best = slot.top(self)
            if best is None:
                self._drop_slot(slot)
            else:
                self._push_slot(slot, *best)
                devices.add(slot.device)
        self._tree_slots[tree.id] = [s for s in slots if s.group.slots.get(tree.id) is s]
        return devices

    def forget(self, tree: Tree) -> None:
        """The tree left working memory: drop its slots."""
        for slot in self._tree_slots.pop(tree.id, ()):
            self._drop_slot(slot)

    def top(self, device: str) -> Node | None:
        """The best-ranked waiting AB that needs ``device`` (ROUND criteria aside)."""
        dev = self._devices.get(device)
        if dev is None:
            return None
        heap = dev.heap
        while heap:
            head, _serial, group = heap[0]
            node = self._group_top(group)
            if node is not None:
                return node
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
    def _slot(self, device: str, head: tuple[Key, ...], tree: Tree) -> _Slot:
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
            self._tree_slots.setdefault(tree.id, []).append(slot)
        return slot

    def _push_slot(self, slot: _Slot, tail: tuple[Key, ...], best: Node) -> None:
        """(Re-)rank a slot by its tree's key (read from its best AB) and its best tail."""
        slot.version += 1
        entry = (_keys(best, _TREE), tail, slot.tree.id, slot.version, slot)
        heapq.heappush(slot.group.heap, entry)
        self.entries += 1

    def _drop_slot(self, slot: _Slot) -> None:
        slot.version += 1
        if slot.group.slots.get(slot.tree.id) is slot:
            del slot.group.slots[slot.tree.id]

    def _group_top(self, group: _Group) -> Node | None:
        heap = group.heap
        while heap:
            _tree_key, tail, _tid, version, slot = heap[0]
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
            if best[0] != tail:  # its recorded best left the waiting list
                heapq.heappop(heap)
                self.entries -= 1
                self._push_slot(slot, *best)
                continue
            return best[1]
        return None
