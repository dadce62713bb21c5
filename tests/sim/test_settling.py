"""Where the simulator leaves out settling again (:meth:`Simulator._settle` said it would
do nothing, and nothing has run since), settling would have changed nothing: runs that
settle again every time make the same traces, poses and events. (Thesis samples: a
tracker, searches that wait for the user to come into view, a user who follows.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from prima.run import Run
from prima.sim import Simulator
from prima.sim._kernel import ProcGen, sleep, until
from tests.sim.helpers import world_map

THESIS = Path(__file__).resolve().parents[2] / "scenarios" / "thesis"


def test_a_process_resumed_while_settling_is_settled_after() -> None:
    # A resumed at tick 10 lets B go on, and B waits on a predicate asked before A's:
    # settling again at once finds it true, at tick 10, not at the next settling
    sim = Simulator(world_map("museum"))
    k = sim.kernel
    log: list[tuple[str, int]] = []
    go = [False, False]

    def waits(name: str, i: int) -> ProcGen:
        yield until(lambda: go[i])
        log.append((name, k.tick))
        go[1] = True  # (B's turn: nothing due now, nothing reported)
        yield sleep(1000)

    k.spawn(waits("B", 1))
    k.spawn(waits("A", 0))
    k.at(10, lambda: go.__setitem__(0, True))
    sim.advance_until(20.0)
    assert log == [("A", 10), ("B", 10)]


@pytest.mark.pure  # (it makes the simulator settle every time by patching it)
@pytest.mark.parametrize("sample", ["sample-03", "sample-07"])
def test_a_settling_left_out_would_have_done_nothing(
        monkeypatch: pytest.MonkeyPatch, sample: str) -> None:
    settle = Simulator._settle
    settled = [0]
    again = [False]

    def counted(self: Simulator) -> bool:
        settled[0] += 1
        return settle(self) and not again[0]

    monkeypatch.setattr(Simulator, "_settle", counted)
    leaving_out = Run(THESIS / f"{sample}.xml").run()
    fewer = settled[0]
    settled[0] = 0
    again[0] = True
    settling = Run(THESIS / f"{sample}.xml").run()
    assert settled[0] - fewer > 500, (fewer, settled[0])  # (about a third fewer)
    assert len(leaving_out) > 1000
    assert leaving_out == settling
