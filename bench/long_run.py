"""Benchmark: memory over a ten-hour run of two chatty applications.

Usage: python bench/long_run.py [--hours 10] [--scenario bench/data/chatty.xml]

Runs the scenario (a chatty FA and a chatty EA: the FA chats and asks its user
every few seconds, the EA drives back and forth and messages its host, who
replies to every message) for the given simulated hours, streaming the trace
to nowhere as ``prima run --out`` would stream it to a file. Every simulated
ten minutes it samples the process's resident memory; it prints one row per
hour and how much memory moved after the first hour (the run's promise: less
than 10%), with the CPU time, as a ratio to real time.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
from pathlib import Path

from prima.run import Run
from prima.trace import TraceLine

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_EVERY = 600.0
"""Simulated seconds between two memory samples."""


def rss_mb() -> float:
    """The process's resident memory now (Linux), in MiB."""
    with open("/proc/self/statm") as statm:
        pages = int(statm.read().split()[1])
    return pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hours", type=float, default=10.0)
    parser.add_argument("--scenario", default=str(ROOT / "bench" / "data" / "chatty.xml"))
    args = parser.parse_args()
    samples: list[tuple[float, float]] = []
    lines = [0]
    next_sample = [0.0]

    def sink(line: TraceLine) -> None:
        lines[0] += 1
        if line.t >= next_sample[0]:
            samples.append((line.t, rss_mb()))
            next_sample[0] += SAMPLE_EVERY

    until = args.hours * 3600
    start_cpu, start_wall = cpu(), time.perf_counter()
    run = Run(args.scenario, until=until, sink=sink)
    run.run()
    if not samples or samples[-1][0] < run.sim.now():  # (the last hour's sample is the end)
        samples.append((run.sim.now(), rss_mb()))
    used, wall = cpu() - start_cpu, time.perf_counter() - start_wall
    print(f"{'hour':>6} {'rss MiB':>9}")
    for t, mb in samples:
        if t % 3600 < SAMPLE_EVERY or t == samples[-1][0]:
            print(f"{t / 3600:6.2f} {mb:9.1f}")
    after = [mb for t, mb in samples if t >= 3600]
    drift = 0.0
    if after:
        base = after[0]
        drift = (max(after) - min(after)) / base * 100
        print(f"after the first hour: {min(after):.1f} to {max(after):.1f} MiB "
              f"({drift:.1f}% of {base:.1f} MiB; the promise is under 10%)")
    print(f"{lines[0]:,} trace lines; {until:,.0f} simulated s in {used:.1f} s CPU "
          f"({until / used:,.0f} x real time; wall {wall:.1f} s)")
    return 0 if drift < 10 else 1


if __name__ == "__main__":
    sys.exit(main())
