"""``python -m prima.sim``: check scenario files, or run one headless.

``check FILE...`` validates scenarios (and their maps) and prints
``file:line:col: error: message`` for every problem; exit status 1 if any.
``run FILE`` plays a scenario's user script and environment with no
applications loaded (the robot stays put unless ``--command`` gives it
Commands to perform in order) and prints what happens.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import TextIO

from prima.errors import ScenarioError
from prima.mediator import Call
from prima.scenario._file import load_map, load_scenario
from prima.sim import CommandRunner, Simulator

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m prima.sim",
                                     description="PRIMA robot simulator")
    sub = parser.add_subparsers(dest="action", required=True)
    check = sub.add_parser("check", help="validate scenario or map files")
    check.add_argument("files", nargs="+")
    check.add_argument("--map", action="store_true", help="the files are maps")
    run = sub.add_parser("run", help="run a scenario headless (no applications)")
    run.add_argument("file")
    run.add_argument("--until", type=float, help="stop at this time instead of the scenario's")
    run.add_argument("--command", action="append", default=[], metavar="JSON", type=_call,
                     help='a Command to perform, e.g. \'{"command": "TopologicalMove", '
                          '"args": {"to": "corner"}}\' (repeatable)')
    run.add_argument("--json", action="store_true", help="print one JSON object per line")
    return parser


def main(argv: Sequence[str] | None = None, out: TextIO | None = None,
         err: TextIO | None = None) -> int:
    out = out or sys.stdout
    err = err or sys.stderr
    args = build_parser().parse_args(argv)
    if args.action == "check":
        status = 0
        for name in args.files:
            try:
                (load_map if args.map else load_scenario)(name)
            except ScenarioError as exc:
                for problem in exc.problems:
                    print(problem, file=err)
                status = 1
            else:
                print(f"{name}: ok", file=out)
        return status
    try:
        scenario = load_scenario(args.file)
    except ScenarioError as exc:
        for problem in exc.problems:
            print(problem, file=err)
        return 1
    runner = CommandRunner(Simulator.from_scenario(scenario))
    runner.queue(*args.command)
    for entry in runner.run(args.until if args.until is not None else scenario.until):
        print(json.dumps(entry.to_dict()) if args.json else str(entry), file=out)
    return 0


def _call(text: str) -> Call:
    """A ``--command`` argument: a JSON object with ``command`` and optional ``args``."""
    try:
        data = json.loads(text)
        return Call(str(data["command"]), dict(data.get("args", {})))
    except (json.JSONDecodeError, KeyError, TypeError, AttributeError) as exc:
        raise argparse.ArgumentTypeError(f"bad --command {text!r}: {exc}") from exc
