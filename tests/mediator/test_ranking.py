"""The criteria table's contract: each criterion's key holds as many ints for every AB
(its width), so ranks laid end to end compare as the keys would, criterion by criterion."""

from __future__ import annotations

import dataclasses
from collections.abc import Collection

import pytest

import prima.mediator._ranking as ranking_module
from prima.mediator import AppKind, Rule
from prima.mediator._state import Node
from prima.mediator.testing import Harness
from tests.mediator.helpers import req, speak


def _with(monkeypatch: pytest.MonkeyPatch, rule: Rule, **change: object) -> None:
    criteria = tuple(dataclasses.replace(c, **change) if c.rule is rule else c  # type: ignore[arg-type]
                     for c in ranking_module.CRITERIA)
    monkeypatch.setattr(ranking_module, "CRITERIA", criteria)


def test_a_key_of_the_wrong_width_is_named_when_it_is_worked_out(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def key(node: Node, _pjf: Collection[int]) -> tuple[int, ...]:
        return (node.seq, node.id) if node.seq == 1 else (node.seq,)  # two ints, then one

    _with(monkeypatch, Rule.OLDEST, key=key)
    h = Harness(duration={"Speak": 1.0})
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    h.mediator.submit(req("fa", speak("one")))
    with pytest.raises(ValueError, match=r"criterion oldest: its key for AB2 is \(2,\), "
                                         r"not a tuple of 2 int\(s\) \(its width\)"):
        h.mediator.submit(req("ea", speak("two")))  # waits for the speaker


def test_a_round_criterion_is_one_int_wide(monkeypatch: pytest.MonkeyPatch) -> None:
    _with(monkeypatch, Rule.PARENT_FINISHED, width=2)
    with pytest.raises(ValueError, match="criterion parent-finished: a round key's width "
                                         "must be 1, not 2"):
        Harness()


def test_ranks_lay_the_keys_end_to_end_in_the_tables_order() -> None:
    h = Harness(duration={"Speak": 1.0})
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.submit(req("fa", speak("busy")))
    m.submit(req("ea", speak("waits")))
    node = m._wm.nodes[2]  # white box: the AB that waits
    flat = m._wm.index.ranking.unnamed(node)
    keys = ranking_module.rank(node, ())
    assert flat == tuple(i for key in keys for i in key)
    assert len(flat) == sum(c.width for c in ranking_module.CRITERIA)


def test_a_round_key_of_the_wrong_width_is_named_when_a_round_names_the_ab(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def key(node: Node, pjf: Collection[int]) -> tuple[int, ...]:
        return (0, 0) if node.id in pjf else (1,)

    _with(monkeypatch, Rule.PARENT_FINISHED, key=key)
    h = Harness(duration={"Speak": 1.0})
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.submit(req("fa", speak("one")))  # AB1 starts
    m.submit(req("ea", speak("waits")))  # AB2 waits for the speaker
    m.submit(req("fa", speak("two")))  # AB3, after AB1
    with pytest.raises(ValueError, match=r"criterion parent-finished: its key for AB3 is "
                                         r"\(0, 0\), not a tuple of 1 int\(s\)"):
        m.finish(1)  # AB3's parent just finished: the round names it
