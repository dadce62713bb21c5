"""``prima judge``: measure the naturalness of runs (:mod:`prima.judge`)."""

from __future__ import annotations

import argparse
import json
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

from prima.cli._common import (
    EXIT_ERRORS,
    EXIT_OK,
    EXIT_USAGE,
    Command,
    Commands,
    _error,
    _paint,
    _report,
    _usage,
)
from prima.cli._options import (
    _colour_argument,
    _scenario_only,
    _switch_arguments,
    _switches,
    _thresholds,
    add_threshold_options,
)
from prima.errors import LocatedError
from prima.term import BOLD, RED, columns


def add(commands: Commands) -> None:
    judge = commands.add_parser(
        "judge",
        help="measure the naturalness of runs: reactions, facing, splits, silences",
        description="Measure what a user would notice in runs (docs/judging.md): reaction "
                    "latency, talking unfaced, leaving while talking, split exchanges, "
                    "silences, stuck applications. PATH is a jsonl trace (*.jsonl), a "
                    "scenario (*.xml, run in-process; nothing is written) or a folder "
                    "searched for scenarios. Exit status 1 when a threshold is exceeded.",
    )
    judge.add_argument("paths", nargs="+", metavar="PATH",
                       help="jsonl traces, scenario files or folders")
    _switch_arguments(judge)
    judge.add_argument("--format", choices=("text", "json"), default="text",
                       help="output format (default: text)")
    add_threshold_options(judge)
    _colour_argument(judge)


def _judge_inputs(paths: Sequence[str]) -> list[Path] | str:
    """The files ``prima judge`` reads, or what is wrong with its arguments."""
    from prima.judge import find_scenarios

    inputs: list[Path] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            found = find_scenarios(path)
            if not found:
                return f"no scenario in {raw}"
            inputs += found
        elif not path.is_file():
            return f"no such file or folder: {raw}"
        elif path.suffix not in (".jsonl", ".xml"):
            return f"{raw}: give a trace (*.jsonl), a scenario (*.xml) or a folder"
        else:
            inputs.append(path)
    return inputs


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.judge import Report, Thresholds, format_table, judge_file

    thresholds = _thresholds("judge", args, err)
    if not isinstance(thresholds, Thresholds):
        return EXIT_USAGE
    inputs = _judge_inputs(args.paths)
    if isinstance(inputs, str):
        return _usage("judge", inputs, err)
    switches = _switches(args)
    if isinstance(switches, str):
        return _usage("judge", switches, err)
    for path in inputs:
        problem = _scenario_only(args, path)
        if problem:
            return _usage("judge", problem, err)
    reports: list[Report] = []
    failed = 0
    for path in inputs:
        try:
            reports.append(judge_file(path, thresholds=thresholds, switches=switches))
        except LocatedError as exc:
            _report(exc.problems, err)
            failed += 1
        except Exception as exc:  # noqa: BLE001 - report it, and judge the other runs
            print(f"{_error('judge', err)} {path}: {type(exc).__name__}: {exc}", file=err)
            failed += 1
    if args.format == "json":
        json.dump({"runs": [r.to_dict() for r in reports], "errors": failed,
                   "ok": not failed and all(r.ok for r in reports)}, out, indent=2)
        out.write("\n")
    elif reports:
        out.write(format_table(reports, _paint(out), columns(out)))
    breached = sum(not r.ok for r in reports)
    paint = _paint(err)
    said = f"{breached} exceeded a threshold"
    print(f"{len(reports)} run(s) judged: {paint(said, RED, BOLD) if breached else said}"
          + (paint(f", {failed} could not be judged", RED, BOLD) if failed else ""), file=err)
    return EXIT_ERRORS if failed or breached else EXIT_OK


COMMAND = Command("judge", add, execute)
