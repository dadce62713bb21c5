"""No operation rescans the waiting list: its work does not grow with it.

The work is counted, not timed: the Python bytecodes executed (``sys.settrace``
with opcode events) per operation of each workload of ``bench/mediator.py``,
with 20 and with 2,000 ABs waiting. A loop over the waiting ABs, a tree's ABs
or an app's trees shows as many times more bytecodes with 2,000 ABs; heaps show
as a few more (at most 10% here). Also: the books that spare those scans (who
waits on which device, an app's trees by device, a tree's devices and parked
ABs) agree with working memory after every step of random scenarios, and the
devices' rankings count every waiting AB whenever they are read.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

import pytest

from prima.mediator import Mediator
from prima.mediator.random_driver import _Run, scenario
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import NodeState
from tests.work import bytecodes

BENCH = Path(__file__).parents[2] / "bench" / "mediator.py"
SMALL, LARGE = 20, 2_000
CYCLES = 10


def _bench() -> ModuleType:
    sys.path.insert(0, str(BENCH.parent))
    try:
        spec = importlib.util.spec_from_file_location("bench_mediator", BENCH)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module
    finally:
        sys.path.remove(str(BENCH.parent))


bench = _bench()


def _per_operation(name: str, n: int) -> float:
    load = bench.WORKLOADS[name](n)
    for _ in range(20):
        load.cycle()

    def cycles() -> None:
        for _ in range(CYCLES):
            load.cycle()
    work = bytecodes(cycles) / (CYCLES * load.ops)
    load.check()
    return work


@pytest.mark.parametrize("name", sorted(bench.WORKLOADS))
def test_an_operation_does_the_same_work_with_100_times_more_waiting(name: str) -> None:
    small, large = _per_operation(name, SMALL), _per_operation(name, LARGE)
    assert large <= 1.1 * small, (name, small, large)


def test_a_burst_is_linear_in_the_abs_it_releases() -> None:
    def per_ab(n: int) -> float:
        w = bench.World()
        w.submit("eb", bench.SPEAK)
        cid = w.submit("ea", bench.HEAD, order=bench.RunningOrder.ASAP)
        w.plans[cid] = [bench.SPEAK] * n
        ab = w.driver.on["neck"]
        return bytecodes(lambda: w.finish(ab)) / n

    small, large = per_ab(SMALL), per_ab(LARGE)
    assert large <= 1.1 * small, (small, large)


# ------------------------------------------------------------- the books
def _check_books(m: Mediator) -> None:
    wm = m._wm  # white box: the books against what they summarize
    _check_rankings(wm)
    for tree in wm.trees.values():
        counts: dict[str, int] = {}
        for node in tree.nodes.values():
            for d in node.devices:
                counts[d] = counts.get(d, 0) + 1
        assert tree.devices == counts, tree.id
        assert tree.parked == sum(n.parked is not None for n in tree.nodes.values()), tree.id
    for app in {node.app for node in wm.nodes.values()} | set(m._apps.values()):
        expected: dict[str, set[int]] = {}
        for tree in app.trees.values():
            for d in tree.devices:
                expected.setdefault(d, set()).add(tree.id)
        assert {d: set(trees) for d, trees in app.trees_on.items()} == expected, app.name


def _check_rankings(wm: WorkingMemory, entering: Any = None) -> None:
    """The devices' rankings (``on``, ``ranked``, ``beside``) against the waiting,
    unparked ABs (but ``entering``, which enters the waiting list and is counted last)."""
    on: dict[str, dict[int, set[int]]] = {}
    ranked: dict[str, dict[tuple[str, Any], int]] = {}
    beside: dict[str, dict[str, int]] = {}
    for node in wm.nodes.values():
        if node is entering:
            continue
        if node.state is NodeState.WAITING and node.parked is None:
            assert node.counted, node.id
            for d in node.devices:
                on.setdefault(d, {}).setdefault(node.tree.id, set()).add(node.id)
                counts = ranked.setdefault(d, {})
                key = (node.app.name, node.priority)
                counts[key] = counts.get(key, 0) + 1
                others = beside.setdefault(d, {})
                for e in node.devices - {d}:
                    others[e] = others.get(e, 0) + 1
        else:
            assert not node.counted, node.id
    # (read as plain dicts: a watched one would check itself)
    assert {d: {t.id: set(ns) for t, ns in trees.items()}
            for d, trees in dict.items(wm.on) if trees} == on
    assert {d: c for d, c in dict.items(wm.ranked) if c} == ranked
    assert {d: c for d, c in dict.items(wm.beside) if c} == {
        d: c for d, c in beside.items() if c}


class _Watched(dict[Any, Any]):
    """A ranking of working memory's that checks, whenever it is read, that it counts
    every waiting AB (``WorkingMemory.enter_waiting`` leaves out the ABs a round names
    until something reads the rankings): only the counting itself, and
    ``Selector._idle`` and ``Selector._alone``, which make up for them, may read it
    meanwhile."""

    ALLOWED = frozenset({"_rank_in", "_rank_out", "_idle", "_alone"})

    def __init__(self, wm: WorkingMemory, reads: list[int]) -> None:
        super().__init__()
        self._wm = wm
        self._reads = reads

    def _check(self) -> None:
        frame = sys._getframe(2)
        if frame.f_code.co_name not in self.ALLOWED:
            self._reads[0] += 1
            entering = None
            while frame is not None:
                if frame.f_code.co_name == "enter_waiting":
                    entering = frame.f_locals["node"]
                    break
                frame = frame.f_back
            _check_rankings(self._wm, entering)

    def get(self, key: Any, default: Any = None) -> Any:
        self._check()
        return super().get(key, default)

    def __getitem__(self, key: Any) -> Any:
        self._check()
        return super().__getitem__(key)

    def items(self) -> Any:
        self._check()
        return super().items()


@pytest.mark.pure  # (a compiled WorkingMemory reads its dicts without their methods)
@pytest.mark.parametrize("seeds", [range(0, 150), range(150, 300)], ids=str)
def test_the_rankings_count_every_waiting_ab_when_read(seeds: range) -> None:
    reads = [0]
    for seed in seeds:
        run = _Run(scenario(seed), 1e-6)
        wm = run.m._wm  # white box
        wm.ranked, wm.on, wm.beside = (_Watched(wm, reads), _Watched(wm, reads),
                                       _Watched(wm, reads))
        result = run.play()
        assert not result.violations, (seed, result.violations)
    assert reads[0] > 1000  # (they were read: the check checked something)


@pytest.mark.parametrize("seeds", [range(0, 150), range(150, 300)], ids=str)
def test_the_books_agree_with_working_memory_after_every_step(seeds: range) -> None:
    for seed in seeds:
        run = _Run(scenario(seed), 1e-6)
        observe = run.oracle.observe

        def checked(decisions: Any, snap: Any, run: _Run = run, observe: Any = observe) -> None:
            _check_books(run.m)
            observe(decisions, snap)
        run.oracle.observe = checked  # type: ignore[method-assign]
        result = run.play()
        assert not result.violations, (seed, result.violations)
