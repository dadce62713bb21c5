"""A round the selector skips as idle (``Selector._idle``) is one that would have
done nothing: checked by weighing every such round's candidates anyway, over
random scenarios (every policy, holds, the channel rule, budgets)."""

from __future__ import annotations

import pytest

from prima.mediator._rounds import Selector
from prima.mediator._state import Node
from prima.mediator.random_driver import play

SEEDS = range(2_000_000_000, 2_000_000_000 + 1000)


def test_a_round_skipped_as_idle_would_have_done_nothing(
        monkeypatch: pytest.MonkeyPatch) -> None:
    idle = Selector._idle
    weighed = Selector.round
    skipped = 0

    def round_(self: Selector) -> list[Node]:
        nonlocal skipped
        wm, holds = self._wm, self._holds
        verdict = idle(self, list(wm.new), set(wm.dirty))
        if not verdict:
            return weighed(self)
        skipped += 1
        before = (self._log.count, len(holds._parked), len(holds._talk_parked))
        with monkeypatch.context() as m:
            m.setattr(Selector, "_idle", lambda *_: False)
            started = weighed(self)  # every candidate weighed
        assert started == []
        assert (self._log.count, len(holds._parked), len(holds._talk_parked)) == before
        return started

    monkeypatch.setattr(Selector, "round", round_)
    for seed in SEEDS:
        assert not play(seed).violations, seed
    assert skipped > 1000
