"""An ``advance`` with nothing changed since the last operation settled (``Mediator._quiet``)
handles the wait share's deadlines alone: it decides what the whole operation would.
Checked by playing random scenarios (every policy, holds, the channel rule, budgets)
both ways, and comparing every decision and deadline: as the harness plays them (an
``advance`` when a deadline is due, most often the wait share's), and with an
``advance`` after every step too (as a run asks after every report of its simulator,
most often with nothing due); and counted: such an ``advance`` does a fraction of the
operation's work."""

from __future__ import annotations

import pytest

from prima.mediator import AppKind, Mediator
from prima.mediator.random_driver import _Run, scenario
from prima.mediator.testing import Harness, feedback_iterations
from tests.mediator.helpers import call, req
from tests.work import bytecodes

SEEDS = range(300)


def _played(seed: int, every: bool) -> tuple[list[str], list[float | None]]:
    """The decisions of the scenario of ``seed``, and the deadlines asked after each step;
    with ``every``, an ``advance`` after every step."""
    run = _Run(scenario(seed), 1e-6)
    h, m = run.h, run.m
    deadlines: list[float | None] = []
    step = h.step

    def stepped() -> bool:
        went = step()
        if went:
            if every:
                m.advance()
            deadlines.append(m.next_deadline())
        return went
    h.step = stepped  # type: ignore[method-assign]
    result = run.play()
    assert not result.violations, (seed, result.violations)
    return [repr(d) for d in h.decisions], deadlines


@pytest.mark.pure
def test_a_quiet_advance_decides_what_the_whole_operation_would(
        monkeypatch: pytest.MonkeyPatch) -> None:
    advance = Mediator.advance
    quiet = 0

    def counted(self: Mediator) -> None:
        nonlocal quiet
        quiet += self._quiet
        advance(self)

    def never_quiet(self: Mediator) -> None:
        self._quiet = False  # every advance is a whole operation
        advance(self)

    for seed in SEEDS:
        for every in (False, True):
            monkeypatch.setattr(Mediator, "advance", counted)
            fast = _played(seed, every)
            monkeypatch.setattr(Mediator, "advance", never_quiet)
            assert fast == _played(seed, every), (seed, every)
    assert quiet > 5_000, quiet  # (the short way was taken: the check checked something)


@pytest.mark.parametrize("stream, most", [(False, 120), (True, 200)])
def test_an_advance_with_nothing_due_does_little_work(stream: bool, most: int) -> None:
    # (with a stream open too: its hold, armed or not, has no deadline past)
    h = Harness(duration=1.0, outcome=feedback_iterations(1_000))
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    if stream:
        m.open_stream("ea", 30.0)
    m.submit(req("ea", call("TrackingHuman")))
    m.submit(req("fa", call("Speak", text="hello")))  # (waits, on the neck)
    h.run(until=5.0)
    m.advance()
    assert m._quiet and m._holds.opened == stream  # white box: what the short way needs
    work = bytecodes(m.advance)
    assert work < most, work  # (the whole operation: some 400)
