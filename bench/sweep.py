"""Benchmark: judged sweep runs per CPU second, against bare pymunk stepping the same
worlds; and the peak memory of a sweep as its runs grow.

Usage: python bench/sweep.py [--repeats 5] [--runs 10] [--compiled] [SCENARIO ...]
       python bench/sweep.py --instructions [--runs 3] [--against TREE] [SCENARIO ...]
       python bench/sweep.py --memory 1000,100000 [--scenario S] [--jobs 2] [--compiled]

Each round runs, for each scenario (default: samples 3, 7 and 10 of the thesis), a
cold process that does what a sweep's worker does for ``--runs`` runs: each run's
variant jittered by 5 s (new run indices every round: distinct inputs), run, judged,
its record made (``prima.batch.run_chunk``: one task of that many runs), with its
bytecode cached as an install has it (bench/cold.py's ``use_bytecode``). The process
times its runs alone (``time.process_time``, its imports left out: the run machinery
and the judge, which both builds import on their first run, are imported before the
clock starts, as a worker imports them once for all its runs) and says how many
physics steps they took (and how many of them the world worked out without Chipmunk,
where nothing could touch the robot: ``World.glided``); the peer, measured in the same
rounds in this process, steps a bare pymunk space of the same world (walls, robot,
user) as many times, every step Chipmunk's.
Printed per scenario: both medians, their ratio, and runs per CPU second; with
``--against TREE`` (a checkout of an earlier build: ``git worktree add /tmp/before
<commit>``), that build's runs of the same scenarios in the same rounds (its own copy
of each, with the documents as they were then), and the speed-up over it, against
the target: 2x in the pure build, 4x in the compiled one (over 74e2f0f, the build
before the compiled one).

``--memory N,M`` runs ``prima sweep`` of N and then M runs of ``--scenario``
(default fig5-7, a one-minute scenario) with ``--results`` to a file, each in its
own process, and prints each one's peak memory: of the whole process tree (the
sweeping process and its workers, their proportional set sizes summed, sampled ten
times a second: what they hold at once) and of its largest process (``ru_maxrss`` of
the process waited for), and their ratios, against the promise that the larger
stays within 10% of the smaller.

``--instructions`` counts instructions instead of timing (valgrind's callgrind, which
counts the same for the same program and inputs whatever else the machine does): for
each scenario and build, a cold process of ``--runs`` + 1 runs and one of a single run,
the difference shared among the ``--runs`` runs (the first run, which also loads the
documents, left out). Not the targets' measure (CPU time), but one that does not drift:
for a change too small for this machine's noise to show (a few percent). It takes
about fifty times the runs' CPU time.

``--compiled`` measures this checkout's compiled build (``setup.py``,
``PRIMA_MYPYC=1``) instead of its pure Python one: it is built first in a temporary
copy of the checkout (mypy, a C compiler and Python's headers; about three minutes of CPU time).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from cold import bytecode_mode, use_bytecode
from _measure import (COMPILED_HELP, ROOT, compiled_copy, cpu, in_checkout, in_tree,
                      interleaved, interpreter, report)

SCENARIOS = {name: ROOT / "scenarios" / "thesis" / f"{name}.xml"
             for name in ("sample-03", "sample-07", "sample-10")}
JITTER = 5.0
TARGET = 2.0
"""The speed-up in runs per CPU second the sweep must reach over the baseline (74e2f0f,
the build before the compiled one) in the pure build."""
TARGET_COMPILED = 4.0
"""The same, in the compiled build (``--compiled``)."""


def child(scenario: Path, runs: int, first: int) -> None:
    """In a cold process: ``runs`` judged runs of a sweep of ``scenario`` (indices from
    ``first``); print their CPU time and physics steps as JSON."""
    import prima.run  # (a worker imports the run machinery once, not per run: it is
    from prima.judge import Thresholds, judge  # noqa: F401 (imported before the clock starts)

    steps = [0, 0]
    real = prima.run.Run

    class Counted:
        """A run that adds its simulator's physics steps to ``steps``. (Both builds' sweeps
        take ``Run`` from its module when they run; the class is replaced there, not
        changed: in the compiled build it is compiled, and a compiled class is fixed.)"""

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            self.real = real(*args, **kwargs)

        def run(self) -> Any:
            lines = self.real.run()
            steps[0] += self.real.sim.steps
            steps[1] += getattr(self.real.sim.world, "glided", 0)  # (an earlier build: none)
            return lines

    setattr(prima.run, "Run", Counted)  # noqa: B010 (mypy: a class is not assigned to)
    try:
        from prima.batch import Chunk, Job, bundle_scenario, run_chunk
    except ImportError:  # an earlier build (--against): its sweep's own worker function
        from prima.sweep import _Task, _work  # type: ignore[attr-defined]

        with tempfile.TemporaryDirectory() as scratch:
            tasks = [_Task(scenario, Path(scratch), 0, first + i, JITTER, Thresholds())
                     for i in range(runs)]
            start = time.process_time()
            for task in tasks:
                _work(task)
            print(json.dumps({"cpu": time.process_time() - start, "steps": steps[0],
                              "glided": steps[1]}))
        return
    job = Job(bundle_scenario(scenario), first + runs, 0, JITTER, Thresholds())
    start = time.process_time()
    records = run_chunk(Chunk(0, job, first, runs))  # (what a worker does with a task)
    spent = time.process_time() - start
    failed = [r for r in records if "error" in r]
    if failed:
        sys.exit(f"a run failed: {failed[0]['error']}")
    print(json.dumps({"cpu": spent, "steps": steps[0], "glided": steps[1]}))


class Case:
    """One scenario: its cold sweep runs, and its peer."""

    def __init__(self, name: str, path: Path, runs: int, tree: Path = ROOT) -> None:
        self.name, self.path, self.runs, self.tree = name, path, runs, tree
        self.round = 0
        self.steps = self.glided = 0

    def sweep(self) -> float:
        first = self.round * self.runs  # distinct runs every round
        self.round += 1
        done = subprocess.run(in_checkout(self.tree, [__file__, "--child", str(self.path),
                                                      "--runs", str(self.runs),
                                                      "--first", str(first)]),
                              capture_output=True, text=True, check=False)
        if done.returncode:
            sys.exit(done.stderr)
        out = json.loads(done.stdout)
        self.steps = int(out["steps"])
        self.glided = int(out["glided"])
        return float(out["cpu"])

    def instructions(self) -> float:
        """Instructions a judged run takes (:func:`counted` of cold processes of
        ``runs`` + 1 runs and of one run, the difference per run)."""
        def child(runs: int) -> list[str]:
            return in_checkout(self.tree, [__file__, "--child", str(self.path),
                                           "--runs", str(runs), "--first", "0"])
        with ThreadPoolExecutor(2) as pool:  # (one per core: each takes a while)
            more, one = pool.map(counted, [child(self.runs + 1), child(1)])
        return (more - one) / self.runs

    def bare(self) -> float:
        from prima.scenario import load_scenario
        from prima.sim import Simulator

        world = Simulator.from_scenario(load_scenario(self.path)).world
        space, dt, steps = world.space, world.dt, self.steps or 1

        def step() -> None:
            for _ in range(steps):
                space.step(dt)
        return cpu(step)


def counted(argv: list[str]) -> int:
    """The instructions a cold process of ``argv`` takes, as callgrind counts them."""
    done = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null",
                           *argv], capture_output=True, text=True, check=False)
    found = re.search(r"Collected : (\d+)", done.stderr)
    if done.returncode or found is None:
        sys.exit(f"valgrind: {done.stderr.strip().splitlines()[-1] if done.stderr else 'failed'}")
    return int(found.group(1))


def instructions(args: argparse.Namespace, tree: Path) -> int:
    """Instructions per judged run of each scenario, in this build and ``--against``'s."""
    if shutil.which("valgrind") is None:
        sys.exit("--instructions needs valgrind (apt-get install valgrind)")
    named = {p.stem: p for p in args.scenarios} if args.scenarios else SCENARIOS
    for name, path in named.items():
        here = Case(name, path, args.runs, tree).instructions()
        line = f"{name}: {here / 1e6:,.1f} M instructions a judged run"
        if args.against is not None:
            other = args.against.resolve()
            there = Case(name, in_tree(path, other) or path, args.runs, other).instructions()
            line += (f"; the earlier build's {there / 1e6:,.1f} M: {there / here:.3f}x fewer"
                     " (not the targets' measure: CPU time)")
        print(line, flush=True)
    print(f"(callgrind, runs 2 to {args.runs + 1} of a cold process) {interpreter()}")
    return 0


def speed(args: argparse.Namespace, tree: Path) -> int:
    named = {p.stem: p for p in args.scenarios} if args.scenarios else SCENARIOS
    cases = {name: Case(name, path, args.runs, tree) for name, path in named.items()}
    # (the earlier build runs its own copy of each scenario, if it has one: today's
    # documents may use what that build lacks)
    earlier = {name: Case(name, in_tree(path, args.against.resolve()) or path, args.runs,
                          args.against.resolve())
               for name, path in named.items()} if args.against else {}
    pyc = tempfile.TemporaryDirectory(prefix="prima-pyc-")
    use_bytecode(pyc.name)  # (as an install has it, whatever the environment says)
    for case in [*cases.values(), *earlier.values()]:
        case.sweep()  # (a round not counted: the bytecode cache, the steps for the peer)
    work = {}
    for name, case in cases.items():
        work[f"{name} sweep runs"] = case.sweep
        if name in earlier:
            work[f"{name} earlier build"] = earlier[name].sweep
        work[f"{name} bare pymunk"] = case.bare
    medians = interleaved(work, args.repeats)
    met = True
    for name, case in cases.items():
        report(f"{name}: {case.runs} judged runs a round, {case.steps:,} physics steps "
               f"({case.glided:,} without Chipmunk)",
               {key: v for key, v in medians.items() if key.startswith(f"{name} ")},
               f"{name} bare pymunk", repeats=args.repeats)
        rate = case.runs / medians[f"{name} sweep runs"]
        line = f"  runs per CPU second: {rate:.1f}"
        if name in earlier:
            before = case.runs / medians[f"{name} earlier build"]
            ratio = rate / before
            target = TARGET_COMPILED if args.compiled else TARGET
            met = met and ratio >= target
            line += (f"; the earlier build's {before:.1f}: {ratio:.2f}x (target {target:g}x: "
                     f"{'met' if ratio >= target else 'NOT met'})")
        print(line)
    print(f"{interpreter()}; bytecode: {bytecode_mode()}")
    pyc.cleanup()
    return 0 if met else 1


def _children() -> dict[int, list[int]]:
    """Each process's children, as /proc says now (Linux)."""
    out: dict[int, list[int]] = {}
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat", "rb") as f:
                stat = f.read()
        except OSError:
            continue  # (gone meanwhile)
        ppid = int(stat[stat.rindex(b")") + 2:].split()[1])
        out.setdefault(ppid, []).append(int(entry.name))
    return out


def _pss(pid: int) -> int:
    """A process's proportional set size in KiB (its own pages, and its share of the
    pages it shares with the processes forked beside it), 0 if it is gone."""
    try:
        with open(f"/proc/{pid}/smaps_rollup", "rb") as f:
            for line in f:
                if line.startswith(b"Pss:"):
                    return int(line.split()[1])
    except OSError:
        pass
    return 0


def _tree_pss(root: int) -> int:
    """The PSS (KiB) of ``root`` and every process below it, summed: what the whole
    process tree holds, shared pages counted once."""
    children = _children()
    total, todo = 0, [root]
    while todo:
        pid = todo.pop()
        total += _pss(pid)
        todo += children.get(pid, [])
    return total


def peak(argv: list[str], tree: Path) -> tuple[float, float, float]:
    """The peak memory (MiB) of one process running argv: of its whole process tree
    (summed PSS, sampled ten times a second while it runs: what all its processes hold
    at once) and of its largest process (``ru_maxrss`` of the process waited for: the
    largest of the process and its children); and its CPU seconds, with its children."""
    process = subprocess.Popen(in_checkout(tree, argv), stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL, cwd=tree)
    whole = 0
    sampling = os.path.exists("/proc/self/smaps_rollup")
    while True:
        pid, status, usage = os.wait4(process.pid, os.WNOHANG)
        if pid:
            break
        if sampling:
            whole = max(whole, _tree_pss(process.pid))
        time.sleep(0.1)
    process.returncode = os.waitstatus_to_exitcode(status)  # (reaped: Popen must not wait)
    if process.returncode not in (0, 1):
        sys.exit(f"{' '.join(argv)} failed")
    return whole / 1024, usage.ru_maxrss / 1024, usage.ru_utime + usage.ru_stime


def memory(args: argparse.Namespace, tree: Path) -> int:
    counts = [int(n) for n in args.memory.split(",")]
    wholes, peaks = [], []
    with tempfile.TemporaryDirectory() as scratch:
        for n in counts:
            argv = ["-m", "prima", "sweep", str(args.scenario), "--runs", str(n),
                    "--jitter", str(JITTER), "--worst", "0", "--results",
                    str(Path(scratch) / f"{n}.jsonl")]
            if args.jobs:
                argv += ["--jobs", str(args.jobs)]
            start = time.perf_counter()
            whole, mib, spent = peak(argv, tree)
            wholes.append(whole)
            peaks.append(mib)
            print(f"prima sweep --runs {n:>7,}: whole tree {whole:7.1f} MiB, largest process "
                  f"{mib:7.1f} MiB, {spent:8.1f} s of CPU (with its workers), "
                  f"{time.perf_counter() - start:7.1f} s")
    ok = True
    for what, values in (("whole tree", wholes), ("largest process", peaks)):
        if not values[0]:
            print(f"{what}: not measured (no /proc/PID/smaps_rollup)")
            continue
        growth = values[-1] / values[0]
        met = growth <= 1.10
        ok = ok and met
        print(f"{what}: peak of {counts[-1]:,} runs / peak of {counts[0]:,} runs: {growth:.3f} "
              f"(the promise: at most 1.10): {'met' if met else 'NOT met'}")
    return 0 if ok else 1


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenarios", nargs="*", type=Path,
                        help="scenario files (default: samples 3, 7 and 10)")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved rounds (default 5)")
    parser.add_argument("--runs", type=int,
                        help="judged runs per scenario and round (default 10; 3 with "
                             "--instructions)")
    parser.add_argument("--against", type=Path, metavar="TREE",
                        help="an earlier build of PRIMA (a checkout) measured in the same "
                             "rounds: the speed-up over it, against the target of 2x")
    parser.add_argument("--memory", metavar="N,M", help="peak memory of sweeps of N and M runs")
    parser.add_argument("--scenario", type=Path, default=ROOT / "scenarios" / "thesis" /
                        "fig5-7.xml", help="the scenario --memory sweeps (default fig5-7)")
    parser.add_argument("--jobs", type=int, help="--memory: the sweeps' --jobs")
    parser.add_argument("--compiled", action="store_true", help=COMPILED_HELP)
    parser.add_argument("--instructions", action="store_true",
                        help="count instructions (valgrind) instead of timing: the same on a "
                             "noisy machine; --runs defaults to 3 then")
    parser.add_argument("--child", type=Path, help=argparse.SUPPRESS)
    parser.add_argument("--first", type=int, default=0, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.runs is None:
        args.runs = 3 if args.instructions else 10
    if args.child is not None:
        child(args.child, args.runs, args.first)
        return 0
    measure = memory if args.memory else instructions if args.instructions else speed
    if not args.compiled:
        return measure(args, ROOT)
    with tempfile.TemporaryDirectory(prefix="prima-compiled-") as scratch:
        return measure(args, compiled_copy(Path(scratch)))


if __name__ == "__main__":
    sys.exit(main())
