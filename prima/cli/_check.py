"""``prima check``: an EA beside every FA and robot (:func:`prima.check.check`)."""

from __future__ import annotations

import argparse
import math
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
    _usage,
)
from prima.cli._options import (
    MAX_RUNS,
    _batch_arguments,
    _batch_usage,
    _pool,
    _scenario_inputs,
    _seed,
    _target,
    _thresholds,
    _worst_runs_named,
    add_threshold_options,
)
from prima.errors import LocatedError
from prima.escape import shown_path
from prima.shipped import shipped
from prima.term import is_terminal
from prima.vocab import MAX_RUN_TIME


def add(commands: Commands) -> None:
    check = commands.add_parser(
        "check",
        help="judge an EA beside every FA and robot, at jittered timings, with coverage",
        description="Run an EA beside every shipped FA (or --fa) on every robot profile "
                    "(or --robot), on its own scenarios (--scenario) or on generated visits, "
                    "each swept with jittered timings; print a matrix of verdicts (rows FA, "
                    "columns robot) with the worst measure per cell, say whose each failure "
                    "is, write the worst runs as scenarios, and list what of the EA never "
                    "ran (docs/checking.md). Exit status 1 when a cell fails by the EA's "
                    "doing, no cell can run, or the coverage is below --min-coverage.",
    )
    check.add_argument("eas", nargs="+", metavar="EA", help="the EA documents to check")
    check.add_argument("--fa", action="append", default=[], metavar="DOC",
                       help="an FA to check beside, or a shipped FA's name (repeatable; "
                            "default: every shipped FA, apps/fa/*.pxml)")
    check.add_argument("--robot", action="append", default=[], metavar="PROFILE",
                       help="a robot profile to check on, or a shipped one's name (repeatable; "
                            "default: every shipped robot, robots/*.xml)")
    check.add_argument("--scenario", action="append", default=[], metavar="FILE",
                       help="the EA's own scenario (repeatable; default: generated visits)")
    check.add_argument("--map", metavar="MAP",
                       help="the map of the generated visits (default: the first shipped map "
                            "with every place the EA can go to; needed when some cannot be "
                            "known before it runs)")
    check.add_argument("--runs", type=int, default=20, metavar="N",
                       help="runs per scenario and cell (default 20)")
    check.add_argument("--jitter", type=float, default=5.0, metavar="SECONDS",
                       help="largest shift of a timing, either way (default 5)")
    check.add_argument("--seed", type=_seed, default=0, metavar="S",
                       help="seed of the shifts (default 0); run i uses (S, i)")
    check.add_argument("--until", type=float, default=180.0, metavar="SECONDS",
                       help="how long a generated visit lasts (default 180)")
    check.add_argument("--min-coverage", type=float, metavar="PERCENT",
                       help="exit 1 when less of the EA than this ran (0 to 100)")
    check.add_argument("--junit", metavar="FILE", help="write JUnit XML: a test case per cell")
    check.add_argument("--summary", metavar="FILE", help="write a short Markdown summary")
    check.add_argument("--out", metavar="DIR",
                       help="where to write the worst runs of failing cells (default: "
                            "check-<EA name>/)")
    check.add_argument("--worst", type=int, default=1, metavar="K",
                       help="worst runs written per failing cell (default 1; 0: none)")
    _batch_arguments(check)
    add_threshold_options(check)


def _shipped_files(folder: str, pattern: str) -> list[Path]:
    """The files of a shipped folder (``apps/fa``, ``robots``: prima.shipped), by name."""
    found = shipped(folder)
    return sorted(found.glob(pattern)) if found is not None else []


def _check_usage(args: argparse.Namespace) -> str | None:
    """What is wrong with ``prima check``'s arguments, checked before anything runs."""
    for path in [*args.eas, *args.fa, *args.robot, *args.scenario, args.map]:
        if path is not None and not Path(path).is_file():
            return f"no such file: {path}"
    if not args.fa and not _shipped_files("apps/fa", "*.pxml"):
        return "no shipped FAs (apps/fa/*.pxml) here: name them with --fa"
    if not args.robot and not _shipped_files("robots", "*.xml"):
        return "no shipped robot profiles (robots/*.xml) here: name them with --robot"
    if not 1 <= args.runs <= MAX_RUNS:
        return f"--runs must be a whole number from 1 to {MAX_RUNS}"
    if not (math.isfinite(args.jitter) and 0 <= args.jitter <= MAX_RUN_TIME):
        return f"--jitter must be a number of seconds from 0 to {MAX_RUN_TIME:g}"
    if not (math.isfinite(args.until) and 0 < args.until <= MAX_RUN_TIME):
        return f"--until must be a number of seconds above 0 and at most {MAX_RUN_TIME:g}"
    if args.min_coverage is not None and not 0 <= args.min_coverage <= 100:
        return "--min-coverage must be a percentage from 0 to 100"
    if args.worst < 0:
        return "--worst must be a whole number from 0 up"
    return _check_outputs(args)


def _check_outputs(args: argparse.Namespace) -> str | None:
    """What stops ``prima check``'s outputs from being written: each refused where it
    names an input, or another of its outputs."""
    from prima.output import check_folder, input_named

    inputs = _check_inputs(args)
    written: list[tuple[str, Path]] = []
    for option in ("junit", "summary", "results", "resume"):
        given = getattr(args, option)
        if not given:
            continue
        problem = _target(given, inputs, f"--{option}") if option in ("junit", "summary") \
            else None
        twice = input_named(given, written)
        if twice:
            problem = (f"--{option} {shown_path(given)} is also {twice[0]}: give each output "
                       "a file of its own (nothing was written)")
        if problem:
            return problem
        written.append((f"the --{option} file", Path(given)))

    if args.worst:
        folder = args.out or "check-NAME"
        problem = check_folder(folder, inputs)
        if problem:
            return f"--out {problem}"
        problem = _worst_runs_named(folder, inputs, ".*", args.seed)
        if problem:
            return problem
    return _batch_usage(args, inputs)


def _check_inputs(args: argparse.Namespace) -> list[tuple[str, Path]]:
    """``prima check``'s input files: the EAs, FAs, robot profiles, scenarios (and what
    they name) and map."""
    found = [("an EA checked", Path(p)) for p in args.eas]
    found += [("an FA checked beside", Path(p)) for p in args.fa]
    found += [("a robot profile checked on", Path(p)) for p in args.robot]
    for scenario in args.scenario:
        found += _scenario_inputs(scenario, "a scenario checked")
    if args.map:
        found.append(("the --map", Path(args.map)))
    return found


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.judge import Thresholds

    problem = _check_usage(args)
    if problem:
        return _usage("check", problem, err)
    if len(args.eas) > 1 and (args.results or args.resume):
        return _usage("check", "--results and --resume take one EA at a time", err)
    thresholds = _thresholds("check", args, err)
    if not isinstance(thresholds, Thresholds):
        return EXIT_USAGE
    from prima.check import Verdict, check, format_check, junit, markdown
    from prima.output import written
    from prima.sweep import progress_bar

    fas = [Path(p) for p in args.fa] or _shipped_files("apps/fa", "*.pxml")
    robots = [Path(p) for p in args.robot] or _shipped_files("robots", "*.xml")

    results = []
    status = EXIT_OK
    for ea in args.eas:
        pool = _pool(args, args.runs * len(fas) * len(robots))
        try:
            with _BarLine(err) as bar:
                result = check(ea, fas=fas, robots=robots,
                               scenarios=[Path(s) for s in args.scenario],
                               maps=shipped("scenarios/maps"),
                               map_file=Path(args.map) if args.map else None,
                               runs=args.runs, jitter=args.jitter, seed=args.seed,
                               until=args.until, thresholds=thresholds, pool=pool,
                               results=args.results or args.resume, resume=bool(args.resume),
                               out=Path(args.out) if args.out
                               else Path(f"check-{Path(ea).stem}"),
                               worst=args.worst,
                               progress=progress_bar(bar.write, live=is_terminal(err)))
        except ValueError as exc:
            if isinstance(exc, LocatedError):
                raise
            return _usage("check", str(exc), err)
        results.append(result)
        out.write(format_check(result))
        if result.interrupted:
            print(f"prima check: interrupted after {result.total_runs} runs", file=err)
            status = EXIT_INTERRUPTED
            break
        if result.failed_by_ea or any(c.verdict == Verdict.ERROR for c in result.cells):
            status = EXIT_ERRORS
        if all(c.verdict == Verdict.NA for c in result.cells):
            print(f"prima check: {result.ea.name}: no cell can run (each is n/a): nothing "
                  "was checked", file=err)
            status = EXIT_ERRORS
        if args.min_coverage is not None and result.coverage.percent < args.min_coverage:
            print(f"prima check: {result.ea.name}: coverage {result.coverage.percent:.0f}% is "
                  f"below --min-coverage {args.min_coverage:g}", file=err)
            status = EXIT_ERRORS
    if args.junit:
        with written(args.junit) as file:
            file.write(junit(results))
    if args.summary:
        with written(args.summary) as file:
            file.write("\n".join(markdown(r) for r in results))
    return status


COMMAND = Command("check", add, execute)
