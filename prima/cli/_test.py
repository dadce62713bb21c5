"""``prima test``: run scenarios and compare their traces with golden traces."""

from __future__ import annotations

import argparse
import shlex
from typing import TextIO

from prima.cli._common import EXIT_ERRORS, EXIT_OK, Command, Commands, _paint, _report, _usage
from prima.cli._options import _colour_argument, _run_inputs, _switch_arguments, _switches, _target
from prima.errors import LocatedError
from prima.escape import shown_path, terminal
from prima.term import BOLD, CYAN, GREEN, RED, YELLOW, Paint


def add(commands: Commands) -> None:
    test = commands.add_parser(
        "test",
        help="run scenarios and compare their traces with golden traces",
        description="Run every scenario that has a golden trace beside it "
                    "(NAME.golden.txt next to NAME.xml) and show a diff where the trace "
                    "changed. --update rewrites the golden traces: review them first.",
    )
    test.add_argument("paths", nargs="+", metavar="PATH", help="scenario files or folders")
    test.add_argument("--update", action="store_true",
                      help="rewrite the golden traces with this run's traces")
    _switch_arguments(test)
    _colour_argument(test)


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.golden import Status, check, golden_path, scenarios_with_goldens

    switches = _switches(args)
    if isinstance(switches, str):
        return _usage("test", switches, err)
    try:
        scenarios = scenarios_with_goldens(args.paths)
    except FileNotFoundError as exc:
        return _usage("test", f"no such file or folder: {exc}", err)
    if not scenarios:
        return _usage("test", f"no scenario with a golden trace in {' '.join(args.paths)}", err)
    if args.update:
        for scenario in scenarios:
            problem = _target(str(golden_path(scenario)), _run_inputs(args, scenario),
                              "--update")
            if problem:
                return _usage("test", problem, err)
    failed = 0
    paint = _paint(out)
    styles = {Status.SAME: (GREEN,), Status.DIFFERENT: (RED, BOLD), Status.MISSING: (YELLOW,),
              Status.UPDATED: (CYAN,)}
    for scenario in scenarios:
        try:
            result = check(scenario, update=args.update, switches=switches)
        except LocatedError as exc:
            _report(exc.problems, err)
            failed += 1
            continue
        except Exception as exc:  # noqa: BLE001 - report it, and test the other scenarios
            print(f"{paint('error', RED, BOLD)}     {shown_path(scenario)}: "
                  f"{type(exc).__name__}: {terminal(str(exc))}", file=out)
            failed += 1
            continue
        status = result.status.value
        print(f"{paint(status, *styles[result.status])}{' ' * (9 - len(status))} "
              f"{shown_path(scenario)}", file=out)
        if result.status is Status.MISSING:
            failed += 1
            print(f"          no golden trace {shown_path(golden_path(scenario).name)}: create "
                  f"it with prima test --update {terminal(shlex.quote(str(scenario)))}",
                  file=out)
        elif result.status is Status.DIFFERENT:
            failed += 1
            out.write(_diff(result.diff, paint))
    summary = f"{failed} failed"
    print(f"{len(scenarios)} scenario(s): "
          f"{_paint(err)(summary, RED, BOLD) if failed else summary}", file=err)
    return EXIT_ERRORS if failed else EXIT_OK


def _diff(diff: str, paint: Paint) -> str:
    """A golden trace's diff, its lines escaped (a file's name may hold anything) and, for
    a terminal, coloured as git colours them."""
    if not diff:
        return ""
    styles = {"---": (BOLD,), "+++": (BOLD,), "@@": (CYAN,), "-": (RED,), "+": (GREEN,)}
    out = []
    for line in diff.split("\n")[:-1] if diff.endswith("\n") else diff.split("\n"):
        mark = next((m for m in styles if line.startswith(m)), None)
        out.append(paint(terminal(line), *styles[mark]) if mark else terminal(line))
    return "".join(f"{line}\n" for line in out)


COMMAND = Command("test", add, execute)
