"""``prima run``: a scenario's run, its trace written in one of the formats of
:data:`~prima.cli._formats.FORMATS` as the run makes it."""

from __future__ import annotations

import argparse
import contextlib
from typing import TextIO

from prima.cli._common import EXIT_INTERRUPTED, EXIT_OK, Command, Commands, _paint, _usage
from prima.cli._options import _colour_argument, _policy_argument, _run_usage, _scenario_arguments
from prima.escape import shown_path

from prima.cli._formats import FORMATS, Opening, format_by_suffix, format_usage


def add(commands: Commands) -> None:
    run = commands.add_parser(
        "run",
        help="run a scenario in the simulator and print its trace",
        description="Run a scenario: its FA and EA on the simulated robot, mediated by "
                    "PRIMA. Prints the trace: a table like the thesis' figures (text), or "
                    "one JSON object per line (jsonl).",
    )
    _scenario_arguments(run)
    run.add_argument("--format", choices=tuple(FORMATS),
                     help="trace format (default: by --out's extension, .jsonl, .json for "
                          "chrome-trace or .mcap; else text); chrome-trace: the Trace Event "
                          "Format, for Perfetto or chrome://tracing; mcap: a recording for "
                          "Foxglove (with --out; the mcap extra)")
    run.add_argument("-o", "--out", metavar="FILE",
                     help="write the trace to FILE instead of stdout (-: to stdout, as without it)")
    run.add_argument("--pose-rate", type=float, default=2.0, metavar="HZ",
                     help="pose samples per simulated second in the jsonl trace "
                          "(default: 2; 0: none)")
    _policy_argument(run)
    _colour_argument(run)


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.output import written
    from prima.run import Run
    from prima.scenario import checked_load

    if args.format is None:  # (the file's extension says, as its reader would read it)
        args.format = format_by_suffix(args.out)
    given = args.out
    if given == "-":  # standard output, as without --out (no file named "-" is written)
        args.out = None
    problem = _run_usage(args) or format_usage(args.format, given)
    if problem:
        return _usage("run", problem, err)
    chosen = FORMATS[args.format]
    # Everything is loaded and checked before the output is opened; then each trace
    # line is written as the run makes it (``writer`` is opened below, before the run).
    # A bad scenario is said as prima validate says it.
    def load() -> Run:
        return Run(args.scenario, fa=args.fa, ea=args.ea, robot=args.robot,
                   seed=args.seed, until=args.until, sink=lambda line: writer.write(line),
                   pose_rate=args.pose_rate, policies=args.policy)

    run = checked_load(args.scenario, args.robot, load, swapped=bool(args.fa or args.ea))
    with contextlib.ExitStack() as files:
        # (a binary format's file is written by its writer, a file of its own)
        to = files.enter_context(written(args.out, partial=True)) \
            if args.out and not chosen.binary else out
        writer = chosen.opens(Opening(run, args.out, to, files, _paint(to)))

        try:
            run.run()
            writer.close()
        except KeyboardInterrupt:
            writer.close()
            to.flush()
            print(f"prima run: interrupted at t={run.sim.now():g} s; the trace up to then "
                  f"is written{' to ' + shown_path(args.out) if args.out else ''}", file=err)
            return EXIT_INTERRUPTED
    return EXIT_OK


COMMAND = Command("run", add, execute)
