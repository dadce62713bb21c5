"""The waiting index keeps its books bounded, however long a stream lives."""

from __future__ import annotations

from pathlib import Path

import pytest

from prima.mediator import AppKind
from prima.mediator._index import WaitIndex
from prima.mediator._state import Node
from prima.mediator.testing import Harness, feedback_iterations, plain_scan
from prima.run import Run
from prima.trace import TraceLine

from tests.mediator.helpers import call, req

CHATTY = Path(__file__).parents[2] / "bench" / "data" / "chatty.xml"


def test_a_stream_that_never_ends_leaves_no_bookkeeping_behind() -> None:
    """The chatty EA's navigation is one endless stream (each trip chained from the
    last one's end): its tree files itself on its devices again and again; the
    index's books about it must stay a few entries, not grow with the run."""
    run = Run(CHATTY, until=3600, sink=lambda _line: None)
    index = run.mediator._wm.index  # white box: the index's own books
    sizes: list[int] = []

    def sample(line: TraceLine) -> None:
        if line.t >= 600 * (len(sizes) + 1):
            sizes.append(sum(len(slots) for slots in index._tree_slots.values()))

    run._sink = sample
    run.run()
    assert len(sizes) >= 5 and max(sizes) <= 20, sizes


@pytest.mark.pure  # (it counts calls by patching WaitIndex: a compiled class is not patched)
def test_an_ab_whose_parent_just_finished_is_filed_only_if_it_waits(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """An AB end re-ranks only what it touches: the next iteration of a feedback loop
    that starts at once, in the round that names it, is never filed in the waiting
    index (nor dropped from it again); one that must wait is filed when that round is
    over. Counted, so that the saving cannot quietly go."""
    filed: list[int] = []
    original = WaitIndex.add

    def add(self: WaitIndex, node: Node) -> None:
        filed.append(node.id)
        original(self, node)

    monkeypatch.setattr(WaitIndex, "add", add)
    h = Harness(duration=1.0, outcome=feedback_iterations(5))
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.submit(req("fa", call("TrackingHuman")))                   # AB1, iterations 0-4
    h.run(until=2.0)  # iterations 1 (AB2) and 2 (AB3) started at once: not filed
    assert [d.ab for d in h.starts()] == [1, 2, 3] and filed == [1]  # (AB1: a request)
    h.at(2.5, lambda: m.submit(req("ea", call("TrackingHuman"), reactive=True)))  # AB4 waits
    h.run()
    # AB4 (a request) is filed; at t=3 it takes the devices, and the FA loop's next
    # iteration (AB5), named by that round, waits: filed as the round ends. The EA's
    # own iterations (AB6-AB9) start at once, each in the round that names it.
    assert filed == [1, 4, 5]
    assert [(d.t, d.ab) for d in h.starts()] == [
        (0.0, 1), (1.0, 2), (2.0, 3), (3.0, 4), (4.0, 6), (5.0, 7), (6.0, 8), (7.0, 9),
        (8.0, 5), (9.0, 10)]
    assert plain_scan(m) == []
