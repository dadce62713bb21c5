"""Ranking waiting ABs, and the per-device index that keeps selection cheap.

The rank of a waiting AB (smaller wins) follows MISSION.md rule 4:

1. priority: HIGH (keeps the Communication Channel) before LOW;
2. reactivity: reactive ABs first, the latest reactive first;
3. parent-finished: ABs whose before node just finished (in this event);
4. resume-stream: ABs of a suspended tree, the most recently suspended first;
5. oldest: the oldest request first, then the AB id.

Selection starts an AB when all its devices are free and it is the best-ranked
waiting AB on every one of them (so a better AB that cannot start reserves its
devices against worse ones: no priority inversion). :class:`WaitIndex` keeps,
for each device, heaps of waiting ABs ordered by the parts of the rank that do
not change while they wait, so finding the best AB on a device costs a few
heap peeks, whatever the number of waiting ABs that cannot start.
"""

from __future__ import annotations

import heapq
from typing import Iterable

from prima.catalog import Priority
from prima.mediator.decisions import Rule
from prima.mediator.state import NodeState, _Node

__all__ = ["WaitIndex", "rank", "separating_rule"]

Rank = tuple[int, int, int, int, int, int, int, int]

_REACTIVE, _SUSPENDED, _PLAIN = 0, 1, 2
_TIERS = 3


def rank(node: _Node, pjf: frozenset[int] | set[int] | dict[int, _Node]) -> Rank:
    """The full rank of a waiting AB; ``pjf`` holds the ids whose parent just finished."""
    if node.reactive:
        r0, r1 = 0, -node.seq
    else:
        r0, r1 = 1, 0
    susp = node.tree.suspended
    if susp is not None:
        s0, s1 = 0, -susp
    else:
        s0, s1 = 1, 0
    return (-int(node.priority), r0, r1, 0 if node.id in pjf else 1, s0, s1, node.seq, node.id)


_CRITERIA: tuple[Rule, ...] = (
    Rule.PRIORITY,
    Rule.REACTIVITY, Rule.REACTIVITY,
    Rule.PARENT_FINISHED,
    Rule.RESUME_STREAM, Rule.RESUME_STREAM,
    Rule.OLDEST, Rule.OLDEST,
)


def separating_rule(winner: Rank, loser: Rank) -> Rule:
    """The first rank criterion on which ``winner`` beats ``loser``."""
    for i, (a, b) in enumerate(zip(winner, loser)):
        if a != b:
            return _CRITERIA[i]
    return Rule.OLDEST


class WaitIndex:
    """Waiting ABs per device, in heaps with lazy deletion.

    Each device has one heap per (priority, tier): reactive ABs by recency,
    ABs of suspended trees by suspension recency, others by age. An entry is
    stale once its AB leaves the waiting list or is re-filed (its version
    changes); stale entries are dropped when they reach the top.
    """

    def __init__(self) -> None:
        self._heaps: dict[str, list[list[tuple]]] = {}
        self._entries = 0

    def _device(self, device: str) -> list[list[tuple]]:
        heaps = self._heaps.get(device)
        if heaps is None:
            heaps = [[] for _ in range(2 * _TIERS)]
            self._heaps[device] = heaps
        return heaps

    def add(self, node: _Node) -> None:
        """File a waiting AB (or re-file it after its tree's suspension changed)."""
        node.version += 1
        if node.reactive:
            tier = _REACTIVE
            entry: tuple = (-node.seq, node.id, node.version, node)
        elif node.tree.suspended is not None:
            tier = _SUSPENDED
            entry = (-node.tree.suspended, node.seq, node.id, node.version, node)
        else:
            tier = _PLAIN
            entry = (node.seq, node.id, node.version, node)
        node.tier = tier
        slot = (0 if node.priority == Priority.HIGH else _TIERS) + tier
        heaps = self._heaps
        for d in node.sorted_devices:
            dev = heaps.get(d)
            if dev is None:
                dev = self._device(d)
            heapq.heappush(dev[slot], entry)
        self._entries += len(node.sorted_devices)

    def best(self, device: str, pjf: dict[int, _Node],
             pjf_on: dict[str, list[_Node]]) -> _Node | None:
        """The best-ranked waiting AB that needs ``device``, or None."""
        heaps = self._heaps.get(device)
        extra = pjf_on.get(device) if pjf_on else None
        if heaps is None and not extra:
            return None
        waiting = NodeState.WAITING
        for base, prio in ((0, Priority.HIGH), (_TIERS, Priority.LOW)):
            found: list[_Node] = []
            if heaps is not None:
                for slot in range(base, base + _TIERS):
                    heap = heaps[slot]
                    while heap:
                        entry = heap[0]
                        node = entry[-1]
                        if node.state is waiting and node.version == entry[-2]:
                            found.append(node)
                            break
                        heapq.heappop(heap)
                        self._entries -= 1
            if extra:
                for n in extra:
                    if n.state is waiting and n.priority == prio and not n.parked:
                        found.append(n)
            if found:
                if len(found) == 1:
                    return found[0]
                return min(found, key=lambda n: rank(n, pjf))
        return None

    def entries(self) -> int:
        """How many heap entries (live and stale) the index holds."""
        return self._entries

    def compact(self, live: Iterable[_Node]) -> None:
        """Rebuild every heap from the live waiting ABs (drops stale entries)."""
        self._heaps.clear()
        self._entries = 0
        for node in live:
            self.add(node)
