"""Work and memory counted, not timed: the Python bytecodes a call executes
(``sys.settrace`` with opcode events), the same on a loaded machine as on an idle one,
and the memory Python allocates while it runs (``tracemalloc``). A test of how work
grows compares the counts of a small and a large input (the pure build only: compiled
code executes no bytecodes to count; the DSL, the scenarios and the audio are never
compiled). Tests count where they would otherwise time: a CPU-time bound fails when a
loaded machine, or a collection of the whole session's objects, lands inside it (one did,
at 23 times its usual time)."""

from __future__ import annotations

import gc
import sys
import tracemalloc
from collections.abc import Callable
from types import FrameType
from typing import Any


def bytecodes(fn: Callable[[], object], only: str | None = None) -> int:
    """How many Python bytecodes ``fn()`` executes (its callees' included; with
    ``only``, those of the code in that file alone). Garbage is collected before, and
    not while it counts: the finalizers of what earlier work left in a cycle (a world's
    pymunk space, say) are not ``fn``'s work."""
    count = 0

    def trace(frame: FrameType, event: str, _arg: Any) -> Any:
        nonlocal count
        if only is not None and frame.f_code.co_filename != only:
            return None
        frame.f_trace_opcodes = True
        if event == "opcode":
            count += 1
        return trace

    collecting = gc.isenabled()
    gc.collect()
    gc.disable()
    previous = sys.gettrace()
    sys.settrace(trace)
    try:
        fn()
    finally:
        sys.settrace(previous)
        if collecting:
            gc.enable()
    return count


def growth(work: Callable[[int], object], small: int, large: int,
           only: str | None = None) -> float:
    """How many times faster than its input the bytecodes ``work(size)`` executes grow
    from ``small`` to ``large`` (with ``only``, those of the code in that file): about 1
    for linear work (less when a part does not grow), about ``large / small`` for
    quadratic work."""
    return (bytecodes(lambda: work(large), only) / bytecodes(lambda: work(small), only)
            / (large / small))


def allocated(fn: Callable[[], object]) -> tuple[int, int]:
    """The bytes Python allocated for ``fn()`` and still held when it returned, and the
    most it held meanwhile (its peak)."""
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
