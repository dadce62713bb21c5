"""The waiting index keeps its books bounded, however long a stream lives."""

from __future__ import annotations

from pathlib import Path

from prima.run import Run
from prima.trace import TraceLine

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
