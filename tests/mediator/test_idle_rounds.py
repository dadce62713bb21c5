"""A round the selector skips as idle (``Selector._idle``) is one that would have
done nothing: checked by weighing every such round's candidates anyway, over
random scenarios (every policy, holds, the channel rule, budgets)."""

from __future__ import annotations

from collections.abc import Set

import pytest

from prima.mediator._rounds import Selector
from prima.mediator._state import Node
from prima.mediator.random_driver import play

SEEDS = range(2_000_000_000, 2_000_000_000 + 1_000)


@pytest.mark.pure
def test_a_round_skipped_as_idle_would_have_done_nothing(
        monkeypatch: pytest.MonkeyPatch) -> None:
    idle = Selector._idle
    weigh = Selector.round
    verdicts: list[bool] = []
    skipped = 0
    with_policies = 0  # (skipped while a policy may act on busy devices)

    def never_idle(self: Selector, new: list[Node], dirty: Set[str]) -> bool:
        verdicts.append(idle(self, new, dirty))
        return False  # every round is weighed

    def checked_round(self: Selector) -> list[Node]:
        nonlocal skipped, with_policies
        holds = self._holds
        before = (self._log.count, len(holds._parked), len(holds._talk_parked))
        started = weigh(self)
        if verdicts.pop():
            skipped += 1
            with_policies += self._policies.on_busy
            assert started == []
            assert (self._log.count, len(holds._parked), len(holds._talk_parked)) == before
        return started

    monkeypatch.setattr(Selector, "_idle", never_idle)
    monkeypatch.setattr(Selector, "round", checked_round)
    for seed in SEEDS:
        assert not play(seed).violations, seed
        assert not verdicts
    assert skipped > 1000
    assert with_policies > 1_000, with_policies
