"""Inputs added as a run goes (``prima live``): the user's actions and the network's
messages given to the simulator while it runs make the run a script of them makes.

The simulator keeps room in its agenda after the script's own inputs
(``Kernel.reserve``), so an added one goes, within its tick, where a scripted one
goes; its tick ends the run loop's round as a scripted one's own reckoning would; and
the pacing hook that a wall clock drives (``Simulator.pace``) changes nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import pytest
from lxml import etree

from prima.errors import SimulationError
from prima.run import Run
from prima.scenario import load_scenario
from prima.sim import ScheduledEvent, TimedAction, UserActionKind
from prima.xmlio import local_name

ROOT = Path(__file__).parents[2]
_TIMED = {"say", "touch", "walk", "leave", "follow", "stop"}
KEPT = 0.5
"""Inputs before this time (s) stay in the script: a run cannot be given one at 0."""

# sample-07 and its like: a touch's tick, with no report of its own, must end the round
# (without it, human-found comes at 29.46 s instead of 29.5 s)
SCENARIOS = ["thesis/sample-07.xml", "thesis/sample-03.xml", "policies/restore-state-off.xml",
             "examples/museum-cafe.xml", "examples/barge-in-question.xml",
             "policies/interrupt-on.xml"]


def _rows(path: Path, pace: Callable[[Run], Callable[[int], None]] | None = None
          ) -> list[dict[str, object]]:
    rows: list[dict[str, object]] = []
    run = Run(path, rows=rows.append)
    if pace is not None:
        run.sim.pace = pace(run)
    run.run()
    return rows


def _unscripted(path: Path, folder: Path) -> Path:
    """The scenario without its user's actions and its messages, sounds and events from
    :data:`KEPT` on (its answer rules stay)."""
    tree = etree.parse(str(path))
    root = tree.getroot()
    for el in [e for e in root if isinstance(e.tag, str)]:
        if local_name(el) == "user":
            for action in [c for c in el if isinstance(c.tag, str) and local_name(c) in _TIMED]:
                if float(action.get("at", "0")) >= KEPT:
                    el.remove(action)
        elif local_name(el) in ("message", "sound", "event") \
                and float(el.get("at", "0")) >= KEPT:
            root.remove(el)
    out = path.parent / f"{path.stem}.unscripted.xml"  # (beside it: its paths are relative)
    tree.write(str(out))
    return out


def _pace(path: Path, early: bool) -> Callable[[Run], Callable[[int], None]]:
    """A pacing hook that adds the scenario's inputs from :data:`KEPT` on: each at the first
    call of the hook (``early``), or at the last call before it is due."""
    scenario = load_scenario(path)
    actions = [a for a in (scenario.user.actions if scenario.user else ()) if a.at >= KEPT]
    events = [e for e in scenario.events if e.at >= KEPT]
    pending: list[TimedAction | ScheduledEvent] = sorted([*actions, *events],
                                                         key=lambda x: x.at)

    def make(run: Run) -> Callable[[int], None]:
        hz = run.sim.kernel.hz

        def pace(tick: int) -> None:
            while pending and (early or round(pending[0].at * hz) <= tick + hz // 10):
                given = pending.pop(0)
                if isinstance(given, TimedAction):
                    assert run.sim.user is not None
                    run.sim.user.add(given)
                else:
                    run.sim.add_event(given)
        return pace
    return make


@pytest.mark.parametrize("name", SCENARIOS)
@pytest.mark.parametrize("early", [False, True], ids=["when-due", "at-once"])
def test_inputs_added_as_the_run_goes_make_the_scripted_run(name: str, early: bool) -> None:
    path = ROOT / "scenarios" / name
    unscripted = _unscripted(path, path.parent)
    try:
        assert _rows(unscripted, _pace(path, early)) == _rows(path)
    finally:
        unscripted.unlink()


def test_a_pacing_hook_that_only_waits_changes_nothing() -> None:
    path = ROOT / "scenarios" / "thesis" / "sample-03.xml"
    ticks: list[int] = []
    assert _rows(path, lambda _run: ticks.append) == _rows(path)
    assert len(ticks) > 100 and ticks == sorted(ticks)


def test_an_input_for_a_tick_already_run_is_refused() -> None:
    run = Run(ROOT / "scenarios" / "thesis" / "sample-03.xml", until=5.0)
    run.run()
    user = run.sim.user
    assert user is not None
    with pytest.raises(SimulationError, match="too late"):
        user.add(TimedAction(run.sim.now(), UserActionKind.TOUCH))
    with pytest.raises(SimulationError, match="too late"):
        run.sim.add_event(ScheduledEvent(1.0, "message", {"sender": "a", "text": "b"}))
    user.add(TimedAction(run.sim.now() + 0.02, UserActionKind.TOUCH))  # the next tick: fine


def test_the_inputs_added_to_a_run_are_bounded() -> None:
    """A run keeps room for a bounded number of added inputs (the simulator's and the
    scripted user's, each ADDED_ACTIONS): one more is refused, as is one for now."""
    from prima.sim._kernel import Kernel, Room

    kernel = Kernel(50)
    room = Room(kernel, 2, "input")
    room.add(1.0, lambda: None)
    room.add(0.5, lambda: None)
    with pytest.raises(SimulationError, match="at most 2 inputs may be added to a run"):
        room.add(2.0, lambda: None)
    with pytest.raises(SimulationError, match="an input added at 0 s comes too late"):
        Room(kernel, 1, "input").add(0.0, lambda: None)
