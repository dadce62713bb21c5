"""A round the selector weighs the short way (``Selector._alone``, then
``Selector._goes_on``: the next iteration of a feedback loop, or the follow-up of the AB
that ended, alone on the devices it freed) decides what the full round would: checked
by playing random scenarios (every policy, holds, the channel rule, budgets) both
ways, and comparing every decision."""

from __future__ import annotations

from collections.abc import Set

import pytest

from prima.mediator._rounds import Selector
from prima.mediator._state import Node
from prima.mediator.random_driver import _Run, scenario

SEEDS = range(3_000_000_000, 3_000_000_000 + 1_500)


def _decisions(seed: int) -> list[str]:
    run = _Run(scenario(seed), 1e-6)
    result = run.play()
    assert not result.violations, (seed, result.violations)
    return [repr(d) for d in run.h.decisions]


@pytest.mark.pure
def test_a_round_weighed_the_short_way_decides_what_the_full_round_would(
        monkeypatch: pytest.MonkeyPatch) -> None:
    alone = Selector._alone
    short = 0

    def counted(self: Selector, x: Node, dirty: Set[str]) -> bool:
        nonlocal short
        found = alone(self, x, dirty)
        short += found
        return found

    def never(self: Selector, x: Node, dirty: Set[str]) -> bool:
        return False  # every round is weighed in full

    for seed in SEEDS:
        monkeypatch.setattr(Selector, "_alone", counted)
        fast = _decisions(seed)
        monkeypatch.setattr(Selector, "_alone", never)
        assert fast == _decisions(seed), seed
    assert short > 1_000, short  # (the short way was taken: the check checked something)
