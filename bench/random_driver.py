"""The long run of the random driver: many random scenarios, each checked by the
independent oracle (:mod:`prima.mediator.oracle`).

Run (from the repository root)::

    python bench/random_driver.py --scenarios 1000000 [--jobs N] [--seed S]

Scenario ``i`` plays seed ``S * 10**9 + i``, so the results (and the seeds
reported) do not depend on the number of jobs. Prints progress, then the
number of scenarios, decisions, violations (the first seeds, replayable with
``python -m prima.mediator.random_driver SEED``), the literal wait-share
overruns the oracle excuses, and the CPU time of all processes.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import concurrent.futures.process
import os
import signal
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from prima.mediator.random_driver import play  # noqa: E402

CHUNK = 2_000
SHOWN = 10


@dataclass
class Tally:
    """What a range of scenarios did."""

    scenarios: int = 0
    decisions: int = 0
    steps: int = 0
    cpu: float = 0.0
    violations: list[tuple[int, str]] = field(default_factory=list)
    """(seed, first violation), for the first few failing seeds."""
    failing: int = 0
    noted: list[tuple[int, str]] = field(default_factory=list)
    excused: int = 0

    def add(self, other: Tally) -> None:
        self.scenarios += other.scenarios
        self.decisions += other.decisions
        self.steps += other.steps
        self.cpu += other.cpu
        self.failing += other.failing
        self.excused += other.excused
        self.violations = sorted(self.violations + other.violations)[:SHOWN]
        self.noted = sorted(self.noted + other.noted)[:SHOWN]


def run_range(seeds: range) -> Tally:
    """Play a range of seeds (in a worker process)."""
    start = time.process_time()
    t = Tally()
    for seed in seeds:
        r = play(seed)
        t.scenarios += 1
        t.decisions += r.decisions
        t.steps += r.steps
        if r.violations:
            t.failing += 1
            if len(t.violations) < SHOWN:
                t.violations.append((seed, r.violations[0]))
        if r.notes:
            t.excused += 1
            if len(t.noted) < SHOWN:
                t.noted.append((seed, r.notes[0]))
    t.cpu = time.process_time() - start
    return t


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scenarios", type=int, default=10_000)
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    p.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    base = args.seed * 10**9
    chunks = [range(base + i, base + min(i + CHUNK, args.scenarios))
              for i in range(0, args.scenarios, CHUNK)]
    total = Tally()
    wall = time.perf_counter()
    cpu0 = time.process_time()
    print(f"{args.scenarios} scenarios from seed {base}, {args.jobs} job(s)", flush=True)
    step = max(1, len(chunks) // 20)
    interrupted = False
    lost: list[range] = []
    # the workers leave Ctrl-C to this process, which stops them and reports what was done;
    # a worker that dies (killed, out of memory) breaks the pool: the driver stops at once
    # and names the seeds left unchecked
    pool = concurrent.futures.ProcessPoolExecutor(
        min(args.jobs, len(chunks)) or 1, initializer=signal.signal,
        initargs=(signal.SIGINT, signal.SIG_IGN))
    futures = {pool.submit(run_range, chunk): chunk for chunk in chunks}
    try:
        for i, future in enumerate(concurrent.futures.as_completed(futures), 1):
            try:
                t = future.result()
            except concurrent.futures.process.BrokenProcessPool:
                lost = sorted((c for f, c in futures.items() if not f.done() or f.exception()),
                              key=lambda c: c.start)
                break
            for seed, v in t.violations[:3]:
                print(f"  VIOLATION seed {seed}: {v}", flush=True)
            total.add(t)
            if i % step == 0 or i == len(chunks):
                done = total.scenarios / args.scenarios
                left = (time.perf_counter() - wall) * (1 - done) / max(done, 1e-9)
                print(f"  {total.scenarios:>9} scenarios  {total.decisions:>11} decisions  "
                      f"{total.failing} failing  {time.perf_counter() - wall:7.0f} s "
                      f"(about {left:.0f} s to go)", flush=True)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        pool.shutdown(wait=False, cancel_futures=True)
        for process in list((getattr(pool, "_processes", None) or {}).values()):
            process.terminate()
    if lost:
        print(f"stopped: a worker process died (out of memory?); seeds not checked: "
              f"{', '.join(f'{c.start}-{c.stop - 1}' for c in lost)}", flush=True)
    if interrupted:
        print(f"interrupted: the {total.scenarios} scenarios checked so far", flush=True)
    cpu = total.cpu + time.process_time() - cpu0
    print(f"scenarios:  {total.scenarios}")
    print(f"decisions:  {total.decisions}")
    print(f"steps:      {total.steps}")
    print(f"violations: {total.failing} scenario(s)")
    for seed, v in total.violations:
        print(f"  seed {seed}: {v}")
    print(f"excused:    {total.excused} scenario(s) overran the literal wait-share bound "
          "in the ways no mediator can avoid (see prima/mediator/oracle.py)")
    for seed, v in total.noted[:3]:
        print(f"  seed {seed}: {v}")
    print(f"CPU time:   {cpu:.0f} s ({1e6 * cpu / max(1, total.scenarios):.0f} µs per scenario), "
          f"wall {time.perf_counter() - wall:.0f} s")
    return 1 if total.failing or lost else 130 if interrupted else 0


if __name__ == "__main__":
    sys.exit(main())
