"""The ``prima`` command line: ``prima validate ...``.

``main(argv)`` returns the exit status and never raises for a user's mistake:
0 when all is well, 1 when an input has errors, 2 for a usage error.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Callable, Sequence, TextIO

from prima import __version__
from prima.dsl.profile import RobotProfile, default_profile, load_profile
from prima.dsl.validate import Checker, collect, validate_paths
from prima.errors import LocatedError, Problem

EXIT_OK, EXIT_ERRORS, EXIT_USAGE = 0, 1, 2


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="prima",
        description="PRIMA: mediate two robot applications sharing one personal robot.",
    )
    parser.add_argument("--version", action="version", version=f"prima {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    validate = commands.add_parser(
        "validate",
        help="check PXML documents, robot profiles, scenarios and maps",
        description="Check PXML documents, robot profiles, scenarios and maps: "
                    "well-formedness, schema, meaning. Prints one line per problem as "
                    "file:line:col: error|warning: message. Folders are searched for "
                    "*.pxml and *.xml files.",
    )
    validate.add_argument("paths", nargs="+", metavar="PATH", help="files or folders")
    validate.add_argument("--robot", metavar="PROFILE",
                          help="robot hardware profile (default: the shipped home robot)")
    validate.add_argument("--format", choices=("text", "json"), default="text",
                          help="output format (default: text)")
    return parser


def main(argv: Sequence[str] | None = None, out: TextIO | None = None,
         err: TextIO | None = None) -> int:
    out = out or sys.stdout
    err = err or sys.stderr
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:
        return int(exc.code or 0)
    try:
        if args.command == "validate":
            return _validate(args, out, err)
    except BrokenPipeError:  # e.g. `prima validate apps/ | head`
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the flush at exit
        return EXIT_ERRORS
    return EXIT_USAGE  # pragma: no cover - argparse enforces the choice


def _scenario_checkers() -> dict[str, Checker]:
    """Scenario and map files are the simulator's; the CLI joins both worlds."""
    from prima.sim.scenario import MAP_NS, SCENARIO_NS, load_map, load_scenario

    def checker(load: Callable[[Path], object]) -> Checker:
        def check(path: Path) -> list[Problem]:
            try:
                load(path)
            except LocatedError as exc:
                return list(exc.problems)
            return []
        return check

    return {SCENARIO_NS: checker(load_scenario), MAP_NS: checker(load_map)}


def _profile(path: str | None, err: TextIO) -> RobotProfile | None:
    try:
        return load_profile(path) if path else default_profile()
    except LocatedError as exc:
        for problem in exc.problems:
            print(problem, file=err)
        return None


def _validate(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    try:
        files = collect(args.paths)
    except FileNotFoundError as exc:
        print(f"prima validate: error: no such file or folder: {exc}", file=err)
        return EXIT_USAGE
    profile = _profile(args.robot, err)
    if profile is None:
        return EXIT_ERRORS
    report = validate_paths(files, profile, _scenario_checkers())
    if not report.files:
        print(f"prima validate: error: no PRIMA files in {' '.join(args.paths)}", file=err)
        return EXIT_USAGE
    if args.format == "json":
        json.dump(report.to_dict(), out, indent=2)
        out.write("\n")
    else:
        for problem in report.problems:
            print(problem, file=out)
        n = len(report.files)
        print(f"{n} file{'s' if n != 1 else ''} checked: {report.errors} error(s), "
              f"{report.warnings} warning(s)", file=err)
    return EXIT_ERRORS if report.errors else EXIT_OK
