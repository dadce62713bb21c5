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
from collections.abc import Callable, Iterable, Sequence
from typing import TextIO

from prima import __version__
from prima.dsl import NAMESPACE as PXML_NS
from prima.dsl import ROBOT_NAMESPACE as ROBOT_NS
from prima.dsl import (
    Checker,
    Header,
    RobotProfile,
    Validation,
    collect,
    default_profile,
    load_profile,
    root_namespace,
)
from prima.errors import DocumentError, LocatedError, PrimaError, Problem, Severity
from prima.xmlio import read_source

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
    run = commands.add_parser(
        "run",
        help="run a scenario in the simulator and print its trace",
        description="Run a scenario: its FA and EA on the simulated robot, mediated by "
                    "PRIMA. Prints the trace: a table like the thesis' figures (text), or "
                    "one JSON object per line (jsonl).",
    )
    run.add_argument("scenario", metavar="SCENARIO", help="a scenario file")
    run.add_argument("--fa", metavar="DOC", help="the FA document (default: the scenario's)")
    run.add_argument("--ea", metavar="DOC", help="the EA document (default: the scenario's)")
    run.add_argument("--robot", metavar="PROFILE",
                     help="robot hardware profile (default: the scenario's, else the home robot)")
    run.add_argument("--seed", type=int, metavar="N", help="random seed (default: the scenario's)")
    run.add_argument("--until", type=float, metavar="SECONDS",
                     help="simulated time to stop at (default: the scenario's)")
    run.add_argument("--format", choices=("text", "jsonl"), default="text",
                     help="trace format (default: text)")
    run.add_argument("--out", metavar="FILE", help="write the trace to FILE instead of stdout")
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
    command: Callable[[argparse.Namespace, TextIO, TextIO], int] = _COMMANDS[args.command]
    try:
        return command(args, out, err)
    except LocatedError as exc:
        _report(exc.problems, err)
        return EXIT_ERRORS
    except PrimaError as exc:  # a user's error is a message, never a traceback
        print(f"prima {args.command}: error: {exc}", file=err)
        return EXIT_ERRORS
    except BrokenPipeError:  # e.g. `prima validate apps/ | head`
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the flush at exit
        return EXIT_ERRORS


def _report(problems: Iterable[Problem], to: TextIO) -> None:
    """One line per problem; under a fault inside an expression, its line and a caret."""
    for problem in problems:
        print(problem, file=to)
        caret = problem.caret()
        if caret:
            print(caret, file=to)


def _usage(command: str, message: str, err: TextIO) -> int:
    print(f"prima {command}: error: {message}", file=err)
    return EXIT_USAGE


def _problems(load: Callable[[Path], object], path: Path) -> list[Problem]:
    try:
        load(path)
    except LocatedError as exc:
        return list(exc.problems)
    return []


def _scenario_checkers(validation: Validation, robot: bool) -> dict[str, Checker]:
    """Scenario and map files are the simulator's; the CLI joins both worlds.

    A scenario's check also checks every file it names, each once in the whole
    validation: its map, its robot profile, and its FA, EA and zone EAs against
    that profile (``robot``: the ``--robot`` profile instead, as ``prima run``
    does), and that each names the right kind of file and each application
    fits its slot.
    """
    from prima.sim import MAP_NS, SCENARIO_NS, load_map, load_scenario

    def check_scenario(path: Path) -> list[Problem]:
        # problems loading the scenario found in its map are the map's own check's
        problems = _problems(load_scenario, path)
        own = [p for p in problems if Path(p.file).resolve() == path.resolve()]
        return own + _check_named(validation, path, robot, MAP_NS)

    return {SCENARIO_NS: check_scenario, MAP_NS: lambda path: _problems(load_map, path)}


_SLOTS = {"fa": "fa", "ea": "ea", "zone": "ea"}
"""A scenario's reference role -> the kind of application that runs there."""


def _check_named(validation: Validation, scenario: Path, robot: bool,
                 map_ns: str) -> list[Problem]:
    """Check the files ``scenario`` names; the problems of the scenario itself (a file of
    the wrong kind, an application in the wrong slot, two applications of one name) are
    returned, located at the attribute that names the file."""
    from prima.sim import scenario_references

    expected = {"map": (map_ns, "map"), "profile": (ROBOT_NS, "robot profile")}
    out: list[Problem] = []
    refs = []
    for ref in scenario_references(scenario):
        if not ref.path.is_file():  # the scenario's own check says it is not found
            continue
        namespace, what = expected.get(ref.role, (PXML_NS, "PXML document"))
        found = _namespace(ref.path)
        if found is not None and found != namespace:
            out.append(Problem(str(scenario), ref.line, ref.col, Severity.ERROR,
                               f"'{ref.value}' is not a {what} (its root is in {found!r})"))
        else:
            refs.append(ref)
    profile = validation.profile
    for ref in refs:
        if ref.role == "map":
            validation.add(ref.path)
        elif ref.role == "profile":
            named = validation.robot(ref.path)
            profile = profile if robot else named
    if profile is None:  # the named profile has errors: its documents wait until it is fixed
        return out
    fa_name: str | None = None
    for ref in (r for r in refs if r.role in _SLOTS):
        header = validation.document(ref.path, profile)
        message = None if header is None else _slot_fault(ref.role, ref.value, header, fa_name)
        if message:
            out.append(Problem(str(scenario), ref.line, ref.col, Severity.ERROR, message))
        elif header is not None and ref.role == "fa":
            fa_name = header.name
    return out


def _namespace(path: Path) -> str | None:
    """The namespace of a file's root element, or None if it cannot be read or parsed."""
    try:
        return root_namespace(read_source(path, DocumentError))
    except DocumentError:
        return None


def _slot_fault(role: str, written: str, header: Header, fa_name: str | None) -> str | None:
    """What ``prima run`` would refuse about this application in this slot, if anything."""
    slot = _SLOTS[role]
    if header.kind in _SLOTS.values() and header.kind != slot:
        return (f"'{written}' is an {header.kind.upper()} (kind=\"{header.kind}\"); "
                f"it cannot run as the {slot.upper()}")
    if role != "fa" and header.name == fa_name:
        whose = "the EA" if role == "ea" else "this zone's EA"
        return (f"the FA and {whose} are both named '{header.name}'; each application "
                "needs a name of its own")
    return None


def _profile(path: str | None) -> RobotProfile:
    return load_profile(path) if path else default_profile()


def _validate(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    try:
        files = collect(args.paths)
    except FileNotFoundError as exc:
        return _usage("validate", f"no such file or folder: {exc}", err)
    validation = Validation(_profile(args.robot))
    validation.checkers.update(_scenario_checkers(validation, robot=args.robot is not None))
    report = validation.run(files)
    if not report.files:
        return _usage("validate", f"no PRIMA files in {' '.join(args.paths)}", err)
    if args.format == "json":
        json.dump(report.to_dict(), out, indent=2)
        out.write("\n")
    else:
        _report(report.problems, out)
        n = len(report.files)
        print(f"{n} file{'s' if n != 1 else ''} checked: {report.errors} error(s), "
              f"{report.warnings} warning(s)", file=err)
    return EXIT_ERRORS if report.errors else EXIT_OK


def _run(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.run import Run
    from prima.trace import format_text, format_jsonl

    if args.until is not None and args.until <= 0:
        return _usage("run", "--until must be positive", err)
    for path in (args.scenario, args.fa, args.ea, args.robot):
        if path is not None and not Path(path).is_file():
            return _usage("run", f"no such file: {path}", err)
    lines = Run(args.scenario, fa=args.fa, ea=args.ea, robot=args.robot,
                seed=args.seed, until=args.until).run()
    text = format_text(lines) if args.format == "text" else format_jsonl(lines)
    if args.out:
        Path(args.out).write_text(text, encoding="utf-8")
    else:
        out.write(text)
    return EXIT_OK


def _test(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.golden import Status, check, scenarios_with_goldens

    try:
        scenarios = scenarios_with_goldens(args.paths)
    except FileNotFoundError as exc:
        return _usage("test", f"no such file or folder: {exc}", err)
    if not scenarios:
        return _usage("test", f"no scenario with a golden trace in {' '.join(args.paths)}", err)
    failed = 0
    for scenario in scenarios:
        try:
            result = check(scenario, update=args.update)
        except LocatedError as exc:
            _report(exc.problems, err)
            failed += 1
            continue
        print(f"{result.status.value:9} {scenario}", file=out)
        if result.status in (Status.DIFFERENT, Status.MISSING):
            failed += 1
            out.write(result.diff)
    print(f"{len(scenarios)} scenario(s): {failed} failed", file=err)
    return EXIT_ERRORS if failed else EXIT_OK


_COMMANDS: dict[str, Callable[[argparse.Namespace, TextIO, TextIO], int]] = {
    "validate": _validate,
    "run": _run,
    "test": _test,
}
"""What each subcommand does: ``prima COMMAND`` calls ``_COMMANDS[COMMAND]``."""
