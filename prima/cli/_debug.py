"""``prima debug``: step through a run (:class:`prima.debug.Debugger`)."""

from __future__ import annotations

import argparse
import sys
from typing import TextIO

from prima.cli._common import EXIT_INTERRUPTED, EXIT_OK, Command, Commands, _usage
from prima.cli._options import _colour_argument, _policy_argument, _run_usage, _scenario_arguments


def add(commands: Commands) -> None:
    debug = commands.add_parser(
        "debug",
        help="step through a run: breakpoints, working memory, the apps' states",
        description="Run a scenario and stop where asked: at the next trace line, or at "
                    "a breakpoint on an application, a Command, a state, an event, the "
                    "user or a time. Stopped, show working memory (waiting, running, "
                    "suspended streams, holds) and each application's state and "
                    "variables. Commands come from standard input, one per line, so a "
                    "session can be scripted; 'help' lists them (docs/running.md).",
    )
    _scenario_arguments(debug)
    _policy_argument(debug)
    _colour_argument(debug)


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.debug import Debugger

    args.out, args.pose_rate = None, 0.0
    problem = _run_usage(args)
    if problem:
        return _usage("debug", problem, err)
    debugger = Debugger(args.scenario, _stdin(), out, fa=args.fa, ea=args.ea,
                        robot=args.robot, seed=args.seed, until=args.until,
                        policies=args.policy)
    try:
        debugger.start()
    except KeyboardInterrupt:
        print(f"prima debug: interrupted at t={debugger.run.sim.now():g} s", file=err)
        return EXIT_INTERRUPTED
    return EXIT_OK


def _stdin() -> TextIO:
    return sys.stdin


COMMAND = Command("debug", add, execute)
