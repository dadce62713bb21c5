"""Ranking waiting ABs (MISSION.md rule 4): one ordered list of named criteria.

A waiting AB's rank is the tuple of its keys under :data:`CRITERIA`, in
order; the smaller rank wins. Each criterion names the :class:`Rule` that a
``start`` decision reports when that criterion is the one that separated the
winner from the AB it beat. To add a criterion, add one entry: the index
(:mod:`._index`) builds its keys from this list, and selection ranks with it.

A criterion's :class:`Scope` says when its key can change while the AB waits,
which is all the index needs to know:

- ``NODE``: fixed from the moment the AB enters the waiting list;
- ``TREE``: a property of the AB's tree or application that can change
  (suspension, a spent wait share); the index re-ranks the tree, not each of
  its ABs;
- ``ROUND``: true for one selection round only (parent just finished). Such a
  key must be ``(0,)`` for the ABs the round names and ``(1,)`` for all others.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Collection
from dataclasses import dataclass

from prima.mediator._decisions import Rule
from prima.mediator._state import Node

__all__ = ["CRITERIA", "Criterion", "Key", "Rank", "Scope", "preempts", "rank", "separating_rule"]

Key = tuple[int, ...]
Rank = tuple[Key, ...]


class Scope(str, enum.Enum):
    """When a criterion's key can change while an AB waits."""

    NODE = "node"
    """Never: fixed when the AB enters the waiting list."""
    TREE = "tree"
    """When the AB's tree or application changes (suspended, resumed, demoted)."""
    ROUND = "round"
    """Every selection round (the ABs whose parent just finished)."""


@dataclass(frozen=True)
class Criterion:
    """One criterion of rule 4: a key per waiting AB, smaller wins."""

    rule: Rule
    """What a ``start`` decision names when this criterion decided it."""
    scope: Scope
    key: Callable[[Node, Collection[int]], Key]
    """The AB's key; the collection holds the ids of the ABs whose parent just
    finished (only ``ROUND`` criteria look at it)."""


def _priority(node: Node, _pjf: Collection[int]) -> Key:
    return (-int(node.priority),)


def _wait_share(node: Node, _pjf: Collection[int]) -> Key:
    return (1,) if node.app.demoted else (0,)


def _reactivity(node: Node, _pjf: Collection[int]) -> Key:
    reaction = node.tree.reaction
    return (1, 0) if reaction is None else (0, -reaction)


def _parent_finished(node: Node, pjf: Collection[int]) -> Key:
    return (0,) if node.id in pjf else (1,)


def _resume_stream(node: Node, _pjf: Collection[int]) -> Key:
    suspended = node.tree.suspended
    return (1, 0) if suspended is None else (0, -suspended)


def _oldest(node: Node, _pjf: Collection[int]) -> Key:
    return (node.seq, node.id)


CRITERIA: tuple[Criterion, ...] = (
    Criterion(Rule.PRIORITY, Scope.NODE, _priority),
    # 1. HIGH (keeps the Communication Channel) before LOW (breaks it).
    Criterion(Rule.WAIT_SHARE, Scope.TREE, _wait_share),
    # (budget) an app that kept the others waiting beyond its share ranks after them.
    Criterion(Rule.REACTIVITY, Scope.TREE, _reactivity),
    # 2. ABs of a reaction first, the latest reaction first (response speed; MISSION.md
    #    7.1: a reaction takes over as a stream until its trees leave working memory).
    Criterion(Rule.PARENT_FINISHED, Scope.ROUND, _parent_finished),
    # 3. ABs whose before node just finished (keep the active stream).
    Criterion(Rule.RESUME_STREAM, Scope.TREE, _resume_stream),
    # 4. ABs of a suspended stream, the most recently suspended first ...
    Criterion(Rule.OLDEST, Scope.NODE, _oldest),
    # ... then the oldest request first, then the AB id.
)
"""Rule 4, in order."""


_KEYS = tuple(c.key for c in CRITERIA)


def rank(node: Node, pjf: Collection[int]) -> Rank:
    """The full rank of a waiting AB; ``pjf`` holds the ids whose parent just finished."""
    return tuple([key(node, pjf) for key in _KEYS])


def preempts(x: Node, y: Node) -> bool:
    """Whether the waiting AB ``x`` outranks the running AB ``y`` on what a running
    AB keeps: its priority, then being the latest reaction (not on waiting order).
    The interrupt policy cuts ``y`` for ``x`` only then, and never for an app that
    lost its precedence (the wait share): a budget that flips back and forth must
    not cut and restart the same ABs over and over."""
    if x.app.demoted:
        return False
    return (_priority(x, ()), _reactivity(x, ())) < (_priority(y, ()), _reactivity(y, ()))


def separating_rule(winner: Node, loser: Node, pjf: Collection[int]) -> Rule:
    """The first criterion on which ``winner`` beats ``loser`` (their keys worked out
    one criterion at a time, up to the first that differs: most often the first)."""
    for criterion in CRITERIA:
        key = criterion.key
        if key(winner, pjf) != key(loser, pjf):
            return criterion.rule
    return Rule.OLDEST
