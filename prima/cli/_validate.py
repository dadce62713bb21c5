"""``prima validate``: check documents, robot profiles, scenarios and maps
(:func:`prima.scenario.make_validation`)."""

from __future__ import annotations

import argparse
import json
from typing import TextIO

from prima.cli._common import EXIT_ERRORS, EXIT_OK, Command, Commands, _paint, _report, _usage
from prima.cli._options import _colour_argument, _profile
from prima.term import BOLD, RED, YELLOW


def add(commands: Commands) -> None:
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
    _colour_argument(validate)


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.dsl import collect
    from prima.scenario import make_validation

    try:
        files = collect(args.paths)
    except FileNotFoundError as exc:
        return _usage("validate", f"no such file or folder: {exc}", err)
    validation = make_validation(_profile(args.robot), robot=args.robot is not None)
    from prima.collecting import fewer_collections

    with fewer_collections():
        report = validation.run(files)
    if not report.files:
        return _usage("validate", f"no PRIMA files in {' '.join(args.paths)}", err)
    if args.format == "json":
        json.dump(report.to_dict(), out, indent=2)
        out.write("\n")
    else:
        _report(report.problems, out)
        n, paint = len(report.files), _paint(err)
        errors = paint(f"{report.errors} error(s)", RED, BOLD) if report.errors \
            else f"{report.errors} error(s)"
        warnings = paint(f"{report.warnings} warning(s)", YELLOW) if report.warnings \
            else f"{report.warnings} warning(s)"
        print(f"{n} file{'s' if n != 1 else ''} checked: {errors}, {warnings}", file=err)
    return EXIT_ERRORS if report.errors else EXIT_OK


COMMAND = Command("validate", add, execute)
