"""Benchmark: event dispatch of a PXML interpreter against pytransitions and sismic.

Usage: python bench/dispatch.py [--states 20] [--events 20000] [--repeats 7]

The same state machine is written three times: as a PXML document run by
PRIMA's interpreter, as a ``transitions.Machine`` and as a sismic statechart.
Its states form a ring (``s0`` ... ``s19``); in every state

- ``advance`` goes on to the next state, whose entry counts a visit
  (``visits = visits + 1``);
- ``ping``, handled once for the whole machine, counts itself while a guard
  holds (``count < 10**9``: evaluated, always true), and stays in the state.

The stream of events is ``advance, ping, ping, ping`` over and over; each
library handles each event to completion (its guard evaluated, its actions
run, its state entered) before the next is posted. The three must agree at the
end (same state, same counts), or the benchmark stops: it measures the same
job. Reports the CPU time per event (median of interleaved rounds) and each
library's ratio to PRIMA's.

pytransitions and sismic are installed by the ``bench`` extra
(``pip install -e '.[bench]'``).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable

from _measure import cpu, interleaved, interpreter, report

from prima.dsl import check_document, default_profile
from prima.interpreter import Interpreter
from prima.mediator import Event, ManualClock, Request

PATTERN = ("advance", "ping", "ping", "ping")
INITIAL = ' initial="true"'
Final = tuple[str, int, int]
"""Where a machine ends: its state, its visits, its pings."""


class _Port:
    """The mediator port of an application that requests no Commands."""

    def submit(self, request: Request) -> tuple[int, ...]:
        raise AssertionError("the benchmark machine requests no Commands")

    def open_stream(self, app: str, hold: float) -> None: ...

    def close_stream(self, app: str) -> None: ...

    def open_block(self, app: str, *, devices: frozenset[str] | None = None,
                   watchdog: float) -> None: ...

    def close_block(self, app: str) -> None: ...


def pxml_machine(states: int) -> Callable[[list[str]], Final]:
    ring = "".join(
        f'<state id="s{i}"{INITIAL if i == 0 else ""}>'
        f'<entry><assign name="visits" expr="visits + 1"/></entry>'
        f'<on event="advance"><goto state="s{(i + 1) % states}"/></on></state>'
        for i in range(states))
    source = ('<pxml xmlns="urn:prima:pxml:1" kind="fa" name="ring">'
              '<var name="visits" expr="0"/><var name="count" expr="0"/>'
              '<event name="advance"/><event name="ping"/>'
              '<on event="ping" cond="count &lt; 1000000000">'
              '<assign name="count" expr="count + 1"/></on>'
              f'{ring}</pxml>').encode()
    document, problems = check_document(source, "ring.pxml")
    if document is None:
        sys.exit("\n".join(str(p) for p in problems))
    profile = default_profile()

    def play(events: list[str]) -> Final:
        interp = Interpreter(document, "fa", _Port(), ManualClock(), catalog=profile.catalog(),
                             robot_events=profile.events)
        interp.start()
        posted = [Event(name) for name in events]
        for event in posted:
            interp.event(event)
        visits, count = interp.variables["visits"], interp.variables["count"]
        assert isinstance(visits, int) and isinstance(count, int)
        return str(interp.state), visits, count
    return play


def transitions_machine(states: int) -> Callable[[list[str]], Final]:
    from transitions import Machine

    class Model:
        def __init__(self) -> None:
            self.visits = 0
            self.count = 0

        def visited(self) -> None:
            self.visits += 1

        def below(self) -> bool:
            return self.count < 10**9

        def pinged(self) -> None:
            self.count += 1

    names = [f"s{i}" for i in range(states)]
    spec = [{"name": n, "on_enter": "visited"} for n in names]
    moves = [{"trigger": "advance", "source": n, "dest": names[(i + 1) % states]}
             for i, n in enumerate(names)]
    moves.append({"trigger": "ping", "source": "*", "dest": None,
                  "conditions": "below", "after": "pinged"})

    def play(events: list[str]) -> Final:
        model = Model()
        Machine(model, states=spec, transitions=moves, initial="s0")
        model.visits = 1  # PXML and sismic count the initial state's entry too
        for name in events:
            model.trigger(name)  # type: ignore[attr-defined]
        return str(model.state), model.visits, model.count  # type: ignore[attr-defined]
    return play


def sismic_machine(states: int) -> Callable[[list[str]], Final]:
    from sismic.interpreter import Interpreter as Statechart
    from sismic.io import import_from_yaml

    ring = "\n".join(
        f"      - name: s{i}\n"
        f"        on entry: visits = visits + 1\n"
        f"        transitions:\n"
        f"          - target: s{(i + 1) % states}\n"
        f"            event: advance"
        for i in range(states))
    chart = import_from_yaml(
        "statechart:\n"
        "  name: ring\n"
        "  preamble: |\n"
        "    visits = 0\n"
        "    count = 0\n"
        "  root state:\n"
        "    name: root\n"
        "    initial: s0\n"
        "    transitions:\n"
        "      - event: ping\n"
        "        guard: count < 10**9\n"
        "        action: count = count + 1\n"
        "    states:\n" + ring + "\n")

    def play(events: list[str]) -> Final:
        machine = Statechart(chart)
        machine.execute_once()  # enter the initial state
        for name in events:
            machine.queue(name)
            machine.execute_once()
        context = machine.context
        leaf = [s for s in machine.configuration if s != "root"]
        return leaf[0], context["visits"], context["count"]
    return play


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--states", type=int, default=20, help="states in the ring (20)")
    parser.add_argument("--events", type=int, default=20_000, help="events per round (20000)")
    parser.add_argument("--repeats", type=int, default=7, help="interleaved rounds (7)")
    args = parser.parse_args(argv)
    try:
        peers = {"transitions": transitions_machine(args.states),
                 "sismic": sismic_machine(args.states)}
    except ModuleNotFoundError as missing:
        sys.exit(f"bench/dispatch.py: {missing.name} is not installed: "
                 "pip install -e '.[bench]'")
    machines = {"prima (PXML)": pxml_machine(args.states), **peers}
    events = [PATTERN[i % len(PATTERN)] for i in range(args.events)]
    finals = {name: play(events) for name, play in machines.items()}
    if len(set(finals.values())) != 1:
        sys.exit(f"the machines disagree: {finals}")
    medians = interleaved({name: (lambda play=play: cpu(lambda: play(events)) / len(events))
                           for name, play in machines.items()}, args.repeats)
    state, visits, count = finals["prima (PXML)"]
    print(f"{args.states} states in a ring, {len(events)} events per round; every machine "
          f"ends in {state} with {visits} visits and {count} pings")
    report("CPU time per event", medians, "prima (PXML)", repeats=args.repeats)
    faster = medians["prima (PXML)"] < medians["transitions"]
    print(f"target: PXML dispatch faster than pytransitions: {'met' if faster else 'NOT met'}")
    print(interpreter())
    return 0 if faster else 1


if __name__ == "__main__":
    sys.exit(main())
