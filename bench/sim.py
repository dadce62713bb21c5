"""Benchmark: how much faster than real time does the simulator run?

The robot drives the whole time: topological moves back and forth across the
office floor (entrance <-> Prof. Kidode's room, five legs each way, one
feedback iteration per leg) while the user walks to and fro in the hall,
out of its way. Prints simulated
seconds per wall-clock second, microseconds per physics step (everything
included: controllers, sensing, the event kernel) and, for comparison, the
cost of a bare pymunk step of the same world.

Run: python bench/sim.py [--seconds 3600]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

try:
    import prima  # noqa: F401
except ModuleNotFoundError:  # running from a checkout without installing
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from prima.mediator import Call  # noqa: E402
from prima.sim import (  # noqa: E402
    CommandRunner,
    EntryKind,
    Pose,
    Simulator,
    TimedAction,
    UserActionKind,
    UserScript,
    load_map,
)

MAP = Path(__file__).resolve().parents[1] / "scenarios" / "maps" / "office.xml"


def build(seconds: float) -> CommandRunner:
    world = load_map(MAP)
    walks = tuple(TimedAction(20.0 * i, UserActionKind.WALK, x=1.0 if i % 2 else 4.5, y=5.2)
                  for i in range(int(seconds / 20) + 1))
    user = UserScript(Pose(1.0, 5.2, 0), speed=0.35, actions=walks)
    runner = CommandRunner(Simulator(world, robot=Pose(1, 3, 0), user=user, seed=1))
    # a round trip takes about 150 s; queue more than enough of them
    trips = int(seconds / 100) + 2
    for _ in range(trips):
        runner.queue(Call("TopologicalMove", {"to": "kidode-room"}),
                     Call("TopologicalMove", {"to": "entrance"}))
    return runner


def bare_step_cost(runner: CommandRunner, n: int = 200_000) -> float:
    space = runner.sim.world.space
    dt = runner.sim.world.dt
    start = time.perf_counter()
    for _ in range(n):
        space.step(dt)
    return (time.perf_counter() - start) / n * 1e6


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=3600.0,
                        help="simulated seconds to run (default 3600)")
    args = parser.parse_args(argv)
    runner = build(args.seconds)
    sim = runner.sim
    start = time.perf_counter()
    runner.run(args.seconds)
    wall = time.perf_counter() - start
    legs = len(runner.ends("TopologicalMove"))
    moving = sim.steps / sim.kernel.hz
    print(f"simulated {args.seconds:.0f} s in {wall:.3f} s wall: "
          f"{args.seconds / wall:,.0f} simulated seconds per wall second")
    print(f"physics steps: {sim.steps:,} ({moving / args.seconds:.0%} of the run moving), "
          f"{wall / max(sim.steps, 1) * 1e6:.2f} us per step, all included")
    print(f"{legs} topological-move legs, {len(runner.events())} events, "
          f"{len([e for e in runner.trace if e.kind is EntryKind.USER])} user actions")
    print(f"bare pymunk step of this world: {bare_step_cost(build(10)):.2f} us")
    return 0


if __name__ == "__main__":
    sys.exit(main())
