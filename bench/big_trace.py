"""Benchmark: peak memory of ``prima judge`` and ``prima show`` on a long jsonl trace.

Usage: python bench/big_trace.py [--lines 1000000] [--keep DIR]

Writes the trace of the chatty scenario (``bench/data/chatty.xml``: two chatty
applications and a robot driving back and forth) run long enough for the lines
asked (a million: about 55 simulated hours, two minutes), then runs ``prima judge``
and ``prima show`` on it, each in its own process, and prints each one's peak
resident memory as a ratio to the trace's size. Both read the trace as a stream
(:mod:`prima.tracefile`): the promise is a peak within twice the trace's size.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LINES_PER_SECOND = 4.81
"""Trace lines per simulated second of the chatty scenario (pose samples at 2 Hz included,
where the poses changed)."""


def peak(argv: list[str]) -> tuple[int, float, int]:
    """Run a command; its exit status, wall time (s) and peak resident memory (bytes)."""
    start = time.perf_counter()
    child = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, status, usage = os.wait4(child.pid, 0)
    return os.waitstatus_to_exitcode(status), time.perf_counter() - start, usage.ru_maxrss * 1024


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--lines", type=int, default=1_000_000)
    p.add_argument("--keep", metavar="DIR", help="write the trace and the page there")
    args = p.parse_args(argv)
    folder = Path(args.keep or tempfile.mkdtemp(prefix="prima-big-"))
    folder.mkdir(parents=True, exist_ok=True)
    trace = folder / "big.jsonl"
    until = max(10, round(args.lines / LINES_PER_SECOND))
    prima = [sys.executable, "-m", "prima"]
    subprocess.run([*prima, "run", str(ROOT / "bench" / "data" / "chatty.xml"), "--until",
                    str(until), "--format", "jsonl", "--out", str(trace)], check=True)
    size = trace.stat().st_size
    with trace.open("rb") as f:
        lines = sum(1 for _ in f)
    print(f"trace: {lines:,} lines, {size / 2**20:.0f} MiB ({until} simulated s)")
    worst = 0.0
    for name, command in (("judge", ["judge", str(trace)]),
                          ("show", ["show", str(trace), "-o", str(folder / "big.html")])):
        code, wall, rss = peak([*prima, *command])
        ratio = rss / size
        worst = max(worst, ratio)
        print(f"prima {name:<6} exit {code}  peak {rss / 2**20:6.0f} MiB  "
              f"{ratio:4.2f}x the trace  {wall:5.0f} s")
    if not args.keep:
        for path in folder.iterdir():
            path.unlink()
        folder.rmdir()
    print(f"worst: {worst:.2f}x (the promise: at most 2x)")
    return 0 if worst <= 2.0 else 1


if __name__ == "__main__":
    sys.exit(main())
