"""Benchmark: the whole stack (documents, interpreters, mediator, simulator).

Usage: python bench/run.py [SCENARIO_FOLDER]

Reports the wall time of running every thesis scenario (scenarios/thesis by
default) and the full stack's simulated seconds per wall second.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

from prima.run import Run

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "scenarios" / "thesis"
    scenarios = sorted(folder.glob("*.xml"))
    if not scenarios:
        sys.exit(f"no scenarios in {folder}")
    total_wall = total_sim = 0.0
    lines = 0
    for path in scenarios:
        start = time.perf_counter()
        run = Run(path)
        trace = run.run()
        wall = time.perf_counter() - start
        total_wall += wall
        total_sim += run.sim.now()
        lines += len(trace)
        print(f"{path.stem:18s} {run.sim.now():7.1f} s simulated in {wall * 1000:6.0f} ms "
              f"({run.sim.now() / wall:8,.0f} x real time, {len(trace)} trace lines)")
    print(f"suite: {len(scenarios)} scenarios, {total_sim:.0f} simulated seconds, "
          f"{lines} trace lines, {total_wall:.2f} s wall")
    print(f"full stack: {total_sim / total_wall:,.0f} simulated seconds per wall second")


if __name__ == "__main__":
    main()
