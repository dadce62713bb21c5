"""``prima sweep``: a scenario re-run with jittered timings, every run judged
(:func:`prima.sweep.sweep`)."""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path
from typing import TextIO

from prima.cli._common import (
    EXIT_ERRORS,
    EXIT_INTERRUPTED,
    EXIT_OK,
    EXIT_USAGE,
    Command,
    Commands,
    _BarLine,
    _paint,
    _usage,
)
from prima.cli._options import (
    MAX_RUNS,
    _batch_arguments,
    _batch_usage,
    _colour_argument,
    _pool,
    _run_inputs,
    _seed,
    _switch_arguments,
    _switches,
    _thresholds,
    _worst_runs_named,
    add_threshold_options,
)
from prima.escape import shown_path, terminal
from prima.term import RED, is_terminal
from prima.vocab import MAX_RUN_TIME


def add(commands: Commands) -> None:
    sweep = commands.add_parser(
        "sweep",
        help="re-run a scenario with its timings jittered and judge every run",
        description="Run a scenario N times with its user's actions, answer delays and "
                    "scheduled messages shifted by seeded random offsets in +-jitter, judge "
                    "each run (docs/judging.md), print the spread of every measure and "
                    "write the worst runs as scenario files that replay them exactly. "
                    "Exit status 1 when a run exceeded a threshold.",
    )
    sweep.add_argument("scenario", metavar="SCENARIO", help="a scenario file")
    _switch_arguments(sweep)
    sweep.add_argument("--runs", type=int, required=True, metavar="N", help="how many runs")
    sweep.add_argument("--jitter", type=float, required=True, metavar="SECONDS",
                       help="largest shift of a timing, either way")
    sweep.add_argument("--seed", type=_seed, default=0, metavar="S",
                       help="seed of the shifts (default 0); run i uses (S, i)")
    _batch_arguments(sweep)
    sweep.add_argument("--out", metavar="DIR",
                       help="where to write the worst runs, made if missing (default: "
                            "sweep-NAME/ in the current folder, NAME the scenario file's)")
    sweep.add_argument("--worst", type=int, default=3, metavar="K",
                       help="how many of the worst runs to write (default 3; 0: none)")
    add_threshold_options(sweep)
    _colour_argument(sweep)


def _sweep_usage(args: argparse.Namespace) -> str | None:
    """What is wrong with ``prima sweep``'s options, checked before anything runs."""
    if not Path(args.scenario).is_file():
        return f"no such file: {args.scenario}"
    if not 1 <= args.runs <= MAX_RUNS:
        return f"--runs must be a whole number from 1 to {MAX_RUNS}"
    if not (math.isfinite(args.jitter) and 0 <= args.jitter <= MAX_RUN_TIME):
        return f"--jitter must be a number of seconds from 0 to {MAX_RUN_TIME:g}"
    inputs = _run_inputs(args, args.scenario)
    problem = _batch_usage(args, inputs)
    if problem:
        return problem
    if args.worst < 0:
        return "--worst must be a whole number from 0 up"
    from prima.output import check_folder, named_after

    args.out = args.out or str(named_after(args.scenario, "sweep-{stem}"))
    if not args.worst:
        return None
    problem = check_folder(args.out, inputs)
    if problem:
        return f"--out {problem}"
    return _worst_runs_named(args.out, inputs, re.escape(Path(args.scenario).stem), args.seed)


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.judge import Thresholds
    from prima.sweep import format_sweep, progress_bar, sweep

    problem = _sweep_usage(args)
    if problem:
        return _usage("sweep", problem, err)
    thresholds = _thresholds("sweep", args, err)
    if not isinstance(thresholds, Thresholds):
        return EXIT_USAGE
    switches = _switches(args)
    if isinstance(switches, str):
        return _usage("sweep", switches, err)

    pool = _pool(args, args.runs)
    bar = _BarLine(err)
    with bar:
        result = sweep(args.scenario, runs=args.runs, jitter=args.jitter, seed=args.seed,
                       jobs=args.jobs, thresholds=thresholds,
                       progress=progress_bar(bar.write, live=is_terminal(err)),
                       switches=switches, pool=pool,
                       results=args.results or args.resume, resume=bool(args.resume),
                       keep=args.worst)
    paint = _paint(out)
    out.write(format_sweep(result, paint))
    if result.interrupted:
        print(f"prima sweep: interrupted after {result.done} of {result.asked} runs",
              file=err)
        return EXIT_INTERRUPTED
    if result.lost:
        print(f"prima sweep: run(s) {', '.join(map(str, result.lost[:20]))} lost: the "
              "worker process died each time, the run alone too (out of memory?); the other "
              f"{result.done} run(s) are judged", file=err)
    for index, error in result.errors:
        print(f"prima sweep: run {index} failed: {terminal(str(error))}", file=err)
    if args.worst:
        folder = Path(args.out)
        worst = result.worst(args.worst)
        paths = result.write_worst(args.worst, folder)
        print(f"worst {len(paths)} run(s), written to {shown_path(folder)}/:", file=out)
        for run, path in zip(worst, paths, strict=True):
            exceeded = paint(", ".join(run.exceeded()), RED) or "no threshold exceeded"
            print(f"  {shown_path(path)}  {exceeded}; worst lateness "
                  f"{run.worst_lateness():.2f} s", file=out)
    return EXIT_ERRORS if result.breached or result.lost or result.failed else EXIT_OK


COMMAND = Command("sweep", add, execute)
