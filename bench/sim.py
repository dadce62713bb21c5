"""Benchmark: the full stack on moving robots, against bare pymunk stepping.

Usage: python bench/sim.py [--repeats 5] [--until S] [--compiled] [SCENARIO ...]

Each scenario runs through the whole stack, ``prima.run.Run``: its documents,
their interpreters, the mediator and the simulator, with every trace line made
and formatted as ``prima run`` formats it (then dropped). The documents are
loaded before the clock starts: this measures the run, not the cold start.
The scenarios, all kept in the repository, keep the robot moving:

- ``patrol`` (bench/data/patrol.xml): an FA drives the robot round the office
  floor for two simulated hours, one Topological Move per leg;
- ``tracking`` (bench/data/tracking.xml): FA2 follows a user who walks round
  the office hall for two simulated hours (TrackingHuman, one iteration every
  half second, each an atomic behavior through the mediator);
- ``sample-03`` and ``sample-09`` (scenarios/thesis): two applications
  compete for the robot while it guides, searches, tracks and dances; each
  runs ``--loops`` times per round, as one run of either is short.

The peer of each scenario is a bare pymunk space of the same world (walls,
robot, user) stepped as many times as the full stack stepped it, every step
Chipmunk's (the full stack works out without Chipmunk the steps in which nothing can
touch the robot: the report says how many), measured in the same rounds. Printed
per scenario: the CPU time of both (medians of interleaved rounds) and their ratio;
then simulated seconds per CPU second, against the target of 1,000x real time.

Any other scenario files may be named instead (``scenarios/thesis/*.xml``).

``--compiled`` measures this checkout's compiled build (``setup.py``,
``PRIMA_MYPYC=1``), built first in a temporary copy, and holds each scenario's
full stack to at most 5x its bare peer (Fig. 5.7, mostly a robot standing
still, to 10x).
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from _measure import (COMPILED_HELP, ROOT, compiled_copy, cpu, in_checkout, interleaved,
                      interpreter, report)

import prima

from prima.run import Run
from prima.scenario import load_scenario
from prima.sim import Simulator
from prima.trace import TextTrace, TraceLine

TARGET = 1000.0
"""Simulated seconds per CPU second the full stack must reach on a moving robot."""

SCENARIOS = {
    "patrol": ROOT / "bench" / "data" / "patrol.xml",
    "tracking": ROOT / "bench" / "data" / "tracking.xml",
    "sample-03": ROOT / "scenarios" / "thesis" / "sample-03.xml",
    "sample-09": ROOT / "scenarios" / "thesis" / "sample-09.xml",
}
PEER_TARGET = {"fig5-7": 10.0}
"""The compiled build's full stack at most this many times its bare peer (by the
scenario's name; :data:`PEER_TARGET_DEFAULT` for any other)."""
PEER_TARGET_DEFAULT = 5.0
SHORT = 600.0
"""Scenarios shorter than this (simulated seconds) run ``--loops`` times per round."""


@dataclass
class Case:
    """One scenario: what its full-stack runs measured, for its peer and the summary."""

    path: Path
    until: float | None
    loops: int
    steps: int = 0
    glided: int = 0
    simulated: float = 0.0
    lines: int = 0

    def full(self) -> float:
        """CPU seconds of ``loops`` full-stack runs (loaded beforehand)."""
        sink = _TextSink()
        runs = [Run(self.path, until=self.until, sink=sink) for _ in range(self.loops)]
        spent = cpu(lambda: [r.run() for r in runs])
        self.steps = sum(r.sim.steps for r in runs)
        self.glided = sum(r.sim.world.glided for r in runs)
        self.simulated = sum(r.sim.now() for r in runs)
        self.lines = sink.lines
        return spent

    def bare(self) -> float:
        """CPU seconds of stepping the same world's bare pymunk space as many times."""
        scenario = load_scenario(self.path)
        world = Simulator.from_scenario(scenario).world
        space, dt, steps = world.space, world.dt, self.steps

        def step() -> None:
            for _ in range(steps):
                space.step(dt)
        return cpu(step)


class _TextSink:
    """Formats each trace line as ``prima run`` does, counts it, and drops it."""

    def __init__(self) -> None:
        self.lines = 0
        self._text = TextTrace()

    def __call__(self, line: TraceLine) -> None:
        self._text.row(line)
        self.lines += 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", type=Path,
                        help="scenario files (default: patrol, tracking, sample-03, sample-09)")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved rounds (default 5)")
    parser.add_argument("--until", type=float, default=None,
                        help="end every run at this simulated time (default: the scenario's)")
    parser.add_argument("--loops", type=int, default=10,
                        help="runs per round of a scenario shorter than 600 s (default 10)")
    parser.add_argument("--compiled", action="store_true", help=COMPILED_HELP)
    args = parser.parse_args(argv)
    if args.compiled:
        given = [a for a in (sys.argv[1:] if argv is None else argv) if a != "--compiled"]
        with tempfile.TemporaryDirectory(prefix="prima-compiled-") as scratch:
            tree = compiled_copy(Path(scratch))
            return subprocess.run(in_checkout(tree, [__file__, *given]), check=False).returncode
    named = {p.stem: p for p in args.scenarios} if args.scenarios else SCENARIOS
    cases: dict[str, Case] = {}
    for name, path in named.items():
        short = load_scenario(path).until < SHORT
        cases[name] = Case(path, args.until, args.loops if short else 1)
    work: dict[str, Callable[[], float]] = {}
    for name, case in cases.items():
        work[f"{name} full stack"] = case.full
        work[f"{name} bare pymunk"] = case.bare
    medians = interleaved(work, args.repeats)
    for name, case in cases.items():
        report(f"{name}: {case.simulated:,.0f} simulated s, {case.steps:,} physics steps "
               f"({case.glided:,} without Chipmunk), {case.lines:,} trace lines",
               {k: v for k, v in medians.items() if k.startswith(f"{name} ")},
               f"{name} bare pymunk", repeats=args.repeats)
    print(f"\nsimulated seconds per CPU second, full stack (target: {TARGET:,.0f}x "
          f"real time on every moving scenario)")
    met = True
    width = max(len(name) for name in cases)
    for name, case in cases.items():
        speed = case.simulated / medians[f"{name} full stack"]
        ok = speed >= TARGET
        met = met and ok
        print(f"  {name:<{width}}  {speed:>9,.0f}x  {'met' if ok else 'NOT met'}")
    print("target met on every scenario" if met else "target NOT met on every scenario")
    if prima.compiled():
        others = ", ".join(f"{k} {v:g}x" for k, v in PEER_TARGET.items())
        print("\nfull stack / bare pymunk, the compiled build (target: at most "
              f"{PEER_TARGET_DEFAULT:g}x; {others})")
        for name in cases:
            ratio = medians[f"{name} full stack"] / medians[f"{name} bare pymunk"]
            ok = ratio <= PEER_TARGET.get(name, PEER_TARGET_DEFAULT)
            met = met and ok
            print(f"  {name:<{width}}  {ratio:>8.2f}x  {'met' if ok else 'NOT met'}")
    print(interpreter())
    return 0 if met else 1


if __name__ == "__main__":
    sys.exit(main())
