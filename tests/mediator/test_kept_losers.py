"""Whom the start of an AB weighed the short way beats (``Selector._goes_on``) is what
``Selector._alone`` found the index answering on its devices (``Selector._losers``),
kept rather than asked again: none where no AB waits (``WorkingMemory.ranked`` counts
every AB the index files), and where one does, the answers ``_beats`` ranked, which
nothing changes before the start. Checked by playing random scenarios (every policy,
holds, the channel rule, budgets) and asking the index again at every such start; and
counted: the answers are not asked again."""

from __future__ import annotations

import pytest

from prima.mediator._rounds import Selector
from prima.mediator._state import Node
from prima.mediator.random_driver import _Run, scenario

SEEDS = range(4_000_000_000, 4_000_000_000 + 600)


@pytest.mark.pure
def test_the_losers_kept_are_what_the_index_answers_at_the_start(
        monkeypatch: pytest.MonkeyPatch) -> None:
    goes_on = Selector._goes_on
    starts = beaten = 0

    def checked(self: Selector, x: Node) -> list[Node]:
        nonlocal starts, beaten
        start = self._wm.start
        kept = self._losers  # (``_goes_on`` takes them at once)

        def asked(node: Node) -> None:
            # (at the start, as the full round asks: after the policies' say)
            nonlocal starts, beaten
            start(node)
            if node is x:
                top = self._wm.index.top
                answers = [b for d in x.sorted_devices if (b := top(d)) is not None]
                assert kept == answers, (x, kept, answers)
                starts += 1
                beaten += bool(answers)
        self._wm.start = asked  # type: ignore[method-assign]
        try:
            return goes_on(self, x)
        finally:
            del self._wm.start

    monkeypatch.setattr(Selector, "_goes_on", checked)
    for seed in SEEDS:
        run = _Run(scenario(seed), 1e-6)
        result = run.play()
        assert not result.violations, (seed, result.violations)
    assert starts > 1_000 and beaten > 50, (starts, beaten)  # (it checked something)

