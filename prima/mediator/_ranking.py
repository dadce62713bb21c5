"""Ranking waiting ABs (docs/rules.md rule 4): one ordered list of named criteria.

A criterion's key is a tuple of ints, as many for every AB (its ``width``); a
waiting AB's rank is its keys under :data:`CRITERIA`, in order, laid end to end
in one flat tuple of ints; the smaller rank wins (flat, two ranks compare as
their keys would, one criterion after the other, but without a tuple compared
per criterion). Each criterion names the :class:`Rule` that a
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

The mediator does not call every key function each time it compares two ABs:
a :class:`Ranking` (one per mediator, built from :data:`CRITERIA` when the
mediator is made) keeps each AB's ``NODE`` keys on the AB, worked out once when
it first enters the waiting list, and each tree's ``TREE`` keys on the tree,
worked out again only after they may have changed; it assembles ranks from
those parts, in the table's order.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from operator import itemgetter
from typing import NoReturn

from prima.catalog import Priority
from prima.mediator._decisions import Rule
from prima.mediator._state import Node, Tree

__all__ = ["CRITERIA", "Criterion", "Key", "Keys", "Rank", "Ranking", "Scope", "keeps_for",
           "outranks",
           "preempts", "rank", "separating_rule"]

Key = tuple[int, ...]
Keys = tuple[int, ...]
"""Several criteria's keys laid end to end, in one tuple."""
Rank = Keys


class Scope(str, enum.Enum):
    """When a criterion's key can change while an AB waits."""

    NODE = "node"
    """Never: fixed when the AB enters the waiting list."""
    TREE = "tree"
    """When the AB's tree or application changes (suspended, resumed, demoted). The
    key is the same for every AB of a tree."""
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
    width: int = 1
    """How many ints its key holds, for every AB (one for a ``ROUND`` criterion)."""
    standing: bool = False
    """Part of what an AB keeps whatever the waiting order (priority, an exchange's
    reply, precedence, reactions): what a reservation and a cut compare
    (:func:`outranks`). The standing criteria come first in the table."""


_AS_HIGH: Key = (-int(Priority.HIGH),)


def _priority(node: Node, _pjf: Collection[int]) -> Key:
    # (a reply to an answer ranks as an utterance, which keeps the channel; so does
    # what a policy put before it, a return that moves the robot: docs/rules.md 7.4)
    return _AS_HIGH if node.protected else (-int(node.priority),)


def _exchange(node: Node, _pjf: Collection[int]) -> Key:
    return (0,) if node.protected else (1,)


def _wait_share(node: Node, _pjf: Collection[int]) -> Key:
    # (docs/rules.md 7.6 (4): a reaction to the user's own action, and a reply to the user's
    # answer, is not rationed until its first utterance is said in full: the user paces
    # these, one per action)
    if node.app.demoted:
        tree = node.tree
        return (0,) if (tree.user and tree.reaction is not None) or tree.answered_since \
            else (1,)
    return (0,)


def _user_first(node: Node, _pjf: Collection[int]) -> Key:
    tree = node.tree
    return (0,) if tree.user and tree.reaction is not None else (1,)


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
    Criterion(Rule.PRIORITY, Scope.NODE, _priority, standing=True),
    # 1. HIGH (keeps the Communication Channel) before LOW (breaks it).
    Criterion(Rule.EXCHANGE, Scope.NODE, _exchange, standing=True),
    # (docs/rules.md 7.4) the words that reply to the user's answer belong to the exchange,
    # also when their app lost its precedence: one AB per answer the user gave (the
    # user paces it), and the wait share's bound allows one AB past the share.
    Criterion(Rule.WAIT_SHARE, Scope.TREE, _wait_share, standing=True),
    # (budget) an app that kept the others waiting beyond its share ranks after them, but
    # for its reaction to the user's own action until its first words (7.6 (4)).
    Criterion(Rule.USER_FIRST, Scope.TREE, _user_first, standing=True),
    # 2. ABs of a reaction first: a reaction to the user's own action until its first
    #    utterance is said in full (docs/rules.md 7.1), ...
    Criterion(Rule.REACTIVITY, Scope.TREE, _reactivity, 2, standing=True),
    #    ... then the latest reaction first (response speed; docs/rules.md 7.1: a reaction
    #    takes over as a stream until its trees leave working memory).
    Criterion(Rule.PARENT_FINISHED, Scope.ROUND, _parent_finished),
    # 3. ABs whose before node just finished (keep the active stream).
    Criterion(Rule.RESUME_STREAM, Scope.TREE, _resume_stream, 2),
    # 4. ABs of a suspended stream, the most recently suspended first ...
    Criterion(Rule.OLDEST, Scope.NODE, _oldest, 2),
    # ... then the oldest request first, then the AB id.
)
"""Rule 4, in order."""


def rank(node: Node, pjf: Collection[int]) -> tuple[Key, ...]:
    """The keys of a waiting AB, worked out the plain way from :data:`CRITERIA` as it is
    now (the tests' slow oracle; the mediator keeps keys in its :class:`Ranking`), one
    tuple per criterion: they compare as its rank does; ``pjf`` holds the ids whose
    parent just finished."""
    return tuple([c.key(node, pjf) for c in CRITERIA])


def _standing(node: Node) -> tuple[Key, ...]:
    """The AB's keys under the standing criteria, in order (read from the table each
    time: asked only for a reservation or a cut)."""
    return tuple([c.key(node, ()) for c in CRITERIA if c.standing])


def outranks(x: Node, y: Node) -> bool:
    """Whether ``x`` outranks ``y`` on what an AB keeps whatever the waiting order (the
    standing criteria: priority, an exchange's reply, precedence, reactions): what a
    reaction's reservation of the devices of its next AB compares (docs/rules.md 7.1)."""
    return _standing(x) < _standing(y)


def goes_before(r: Node, x: Node) -> bool:
    """Whether ``r``'s stream goes before ``x``'s on what an AB keeps whatever the waiting
    order, priority aside (an exchange's reply, precedence, the user first, the latest
    reaction): the same for every AB of a tree but a reply's own, so no two trees go
    before each other, and no chain of ABs waiting for those that go before them
    closes on itself."""
    return _standing(r)[1:] < _standing(x)[1:]


def keeps_for(r: Node, x: Node) -> bool:
    """Whether the pending next AB ``r`` of a reaction (or a reply) keeps a device it
    will use from the waiting ``x`` of another application (docs/rules.md 7.1): ``r``'s
    priority is not lower, and it outranks ``x`` on the rest of what an AB keeps
    whatever the waiting order (a reply, precedence, the user first, the latest
    reaction). Priority is compared apart, so that no two reactions keep devices from
    each other (the rest is the same for every AB of a tree but a reply's own)."""
    rank_r, rank_x = _standing(r), _standing(x)
    return rank_r[0] <= rank_x[0] and rank_r[1:] < rank_x[1:]


def preempts(x: Node, y: Node) -> bool:
    """Whether the waiting AB ``x`` outranks the running AB ``y`` on what a running
    AB keeps (:func:`outranks`). The interrupt policy cuts ``y`` for ``x`` only then,
    and never for an app that lost its precedence (the wait share): a budget that
    flips back and forth must not cut and restart the same ABs over and over. A
    reaction to the user's own action is not rationed until its first words (7.6 (4)):
    the user paces those, one per action."""
    tree = x.tree
    if x.app.demoted and not ((tree.user and tree.reaction is not None) or tree.answered_since):
        return False
    return outranks(x, y)


def separating_rule(winner: Node, loser: Node, pjf: Collection[int]) -> Rule:
    """The first criterion on which ``winner`` beats ``loser`` (their keys worked out
    one criterion at a time, up to the first that differs: most often the first)."""
    for criterion in CRITERIA:
        key = criterion.key
        if key(winner, pjf) != key(loser, pjf):
            return criterion.rule
    return Rule.OLDEST


def _arrange(table: Sequence[Criterion], parts: Sequence[int],
             order: Sequence[int]) -> Callable[[Keys], Keys] | None:
    """How to put keys laid end to end as ``parts`` (criterion positions, in the order
    they are laid) in the order ``order``, each criterion's key ``width`` ints; None if
    they already are."""
    at = 0
    where: dict[int, range] = {}
    for i in parts:
        where[i] = range(at, at + table[i].width)
        at += table[i].width
    perm = [j for i in order for j in where[i]]
    if perm == list(range(at)):
        return None
    if len(perm) == 1:
        only = perm[0]
        return lambda keys: (keys[only],)
    return itemgetter(*perm)  # (of two or more positions: a tuple, without a Python call)


class Ranking:
    """Rule 4 worked out from a criteria table, from keys kept on the ABs and trees.

    The table's criteria fall in four parts, by scope and place:

    - *head*: the ``NODE`` criteria before the first ``TREE`` one (priority);
    - *tree*: the ``TREE`` criteria;
    - *round*: the ``ROUND`` criteria;
    - *order*: the ``NODE`` criteria after the first ``TREE`` one (oldest).

    Caches, and the invariants they keep:

    - ``Node.head`` and ``Node.order``: the AB's head and order keys, worked out by
      :meth:`node_keys` when the AB first enters the waiting list (None before);
      ``NODE`` keys never change after that.
    - ``Tree.keys``: the tree's ``TREE`` keys, worked out by :meth:`tree_keys` when
      first asked; None when they may have changed. Whatever changes what a
      ``TREE`` key reads (suspension, reaction, the app's precedence) has the
      index re-rank the tree, which clears them (``WaitIndex.rerank``), as does
      the tree leaving working memory (``WaitIndex.forget``).

    - ``Node.ranked``: the AB's full rank when no round names it, with the tree
      keys it was assembled from; valid while the tree holds that same tuple.

    A ``ROUND`` key is ``(1,)`` for every AB a round does not name (the table's
    contract), so only the named ABs' are worked out.
    """

    def __init__(self, criteria: Sequence[Criterion] | None = None) -> None:
        table = tuple(CRITERIA if criteria is None else criteria)
        self.criteria = table
        for c in table:
            if c.width < 1 or (c.scope is Scope.ROUND and c.width != 1):
                raise ValueError(f"criterion {c.rule.value}: a {c.scope.value} key's width "
                                 f"must be {'1' if c.scope is Scope.ROUND else '1 or more'}, "
                                 f"not {c.width}")
        self.rules = tuple(c.rule for c in table for _ in range(c.width))
        """The rule of each position of a rank (each criterion's, ``width`` times)."""
        first_tree = next((i for i, c in enumerate(table) if c.scope is Scope.TREE),
                          len(table))
        node = [i for i, c in enumerate(table) if c.scope is Scope.NODE]
        head = [i for i in node if i < first_tree]
        order = [i for i in node if i > first_tree]
        tree = [i for i, c in enumerate(table) if c.scope is Scope.TREE]
        rnd = [i for i, c in enumerate(table) if c.scope is Scope.ROUND]
        self._head_criteria = tuple(table[i] for i in head)
        self._order_criteria = tuple(table[i] for i in order)
        self._tree_criteria = tuple(table[i] for i in tree)
        self._head = tuple(c.key for c in self._head_criteria)
        self._order = tuple(c.key for c in self._order_criteria)
        self._tree = tuple(c.key for c in self._tree_criteria)
        self._head_width = sum(c.width for c in self._head_criteria)
        self._order_width = sum(c.width for c in self._order_criteria)
        self._tree_width = sum(c.width for c in self._tree_criteria)
        self._round_criteria = tuple(table[i] for i in rnd)
        self._round = tuple(c.key for c in self._round_criteria)
        self._not_named: Keys = (1,) * len(rnd)
        # A rank is head + tree + round + order keys, put in the table's order.
        self._full = _arrange(table, head + tree + rnd + order, range(len(table)))
        # The index ranks a tree's slot by its head + tree + order keys, in the table's
        # order.
        self._slot = _arrange(table, head + tree + order, sorted(head + tree + order))

    # ------------------------------------------------------------------ caches
    def node_keys(self, node: Node) -> None:
        """Work out the AB's NODE keys (when it first enters the waiting list)."""
        none: tuple[int, ...] = ()
        head: Keys = ()
        for key in self._head:
            head += key(node, none)
        order: Keys = ()
        for key in self._order:
            order += key(node, none)
        if len(head) != self._head_width or len(order) != self._order_width:
            _malformed(self._head_criteria + self._order_criteria, node)
        node.head = head
        node.order = order

    def tree_keys(self, node: Node) -> Keys:
        """The TREE keys of the AB's tree (kept on the tree until they may change)."""
        tree: Tree = node.tree
        keys = tree.keys
        if keys is None:
            none: tuple[int, ...] = ()
            keys = ()
            for key in self._tree:
                keys += key(node, none)
            if len(keys) != self._tree_width:
                _malformed(self._tree_criteria, node)
            tree.keys = keys
        return keys

    # ------------------------------------------------------------------ ranks
    def slot_keys(self, node: Node) -> Keys:
        """What the index ranks the AB's slot by (its tree's ABs with the same head keys
        on a device): its stable keys, head, tree and order, in the table's order."""
        tree = node.tree.keys
        if tree is None:
            tree = self.tree_keys(node)
        keys = node.head + tree + node.order  # type: ignore[operator]
        return keys if self._slot is None else self._slot(keys)

    def rank(self, node: Node, pjf: Collection[int]) -> Rank:
        """The AB's full rank; ``pjf`` holds the ids of the ABs the round names."""
        if node.id not in pjf:
            return self.unnamed(node)
        keys: Keys = ()
        for key in self._round:
            keys += key(node, pjf)
        if len(keys) != len(self._round):
            _malformed(self._round_criteria, node, pjf)
        return self._assemble(node, keys)

    def unnamed(self, node: Node) -> Rank:
        """The AB's full rank when the round does not name it.

        It is kept on the AB (``Node.ranked``), with the tree keys it was assembled
        from: while its tree keeps those same keys (the same tuple), it is still its
        rank.
        """
        kept = node.ranked
        if kept is not None and kept[0] is node.tree.keys:
            return kept[1]
        keys = self._assemble(node, self._not_named)
        node.ranked = (node.tree.keys, keys)
        return keys

    def _assemble(self, node: Node, rnd: Keys) -> Rank:
        """A rank from the AB's kept keys (worked out if missing) and its round keys."""
        tree = node.tree.keys
        if tree is None:
            tree = self.tree_keys(node)
        if node.head is None:
            self.node_keys(node)
        keys = node.head + tree + rnd + node.order  # type: ignore[operator]
        return keys if self._full is None else self._full(keys)

    def separating(self, winner: Rank, loser: Rank) -> Rule:
        """The rule of the first criterion on which two ranks differ (the winner's)."""
        rules = self.rules
        for i, key in enumerate(winner):  # (twice as fast as zipping the three)
            if key != loser[i]:
                return rules[i]
        return Rule.OLDEST


def _malformed(criteria: Sequence[Criterion], node: Node,
               pjf: Collection[int] = ()) -> NoReturn:
    """Say which criterion's key does not hold as many ints as its width."""
    for c in criteria:
        key = c.key(node, pjf)
        if not isinstance(key, tuple) or len(key) != c.width:
            raise ValueError(f"criterion {c.rule.value}: its key for AB{node.id} is "
                               f"{key!r}, not a tuple of {c.width} int(s) (its width)")
    raise ValueError("criteria keys of the wrong width")  # (not reached)
