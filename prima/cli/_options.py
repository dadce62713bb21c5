"""The arguments several commands share, and their checks: what changes a scenario's run
(``--fa``, ``--ea``, ``--robot``, ``--policy``), the judge's thresholds, where many runs
go, and what an output must not overwrite."""

from __future__ import annotations

import argparse
import math
import re
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

from prima.cli._common import _colour_argument as _colour_argument  # (re-exported)
from prima.cli._common import _usage
from prima.escape import shown_path
from prima.suggest import did_you_mean
from prima.vocab import MAX_RUN_TIME, MAX_SEED, POLICIES

if TYPE_CHECKING:
    from prima.batch import Pool
    from prima.dsl import RobotProfile
    from prima.output import Inputs
    from prima.run import Switches


def _seed(text: str) -> int:
    """A random seed given on the command line: a whole number from 0 to 2^63 - 1."""
    try:
        seed = int(text)
    except ValueError:
        seed = -1
    if not 0 <= seed <= MAX_SEED:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number from 0 to 2^63 - 1")
    return seed


def _switch_arguments(parser: argparse.ArgumentParser, policies: bool = True) -> None:
    """What changes a scenario's own choices, the same on every command that runs one:
    its FA, its EA, its robot (and, with ``policies``, policy switches)."""
    parser.add_argument("--fa", metavar="DOC",
                        help="the FA document, or a shipped FA's name (fa2-follow; default: "
                             "the scenario's)")
    parser.add_argument("--ea", metavar="DOC",
                        help="the EA document, or a shipped EA's name (default: the scenario's)")
    parser.add_argument("--robot", metavar="PROFILE",
                        help="robot hardware profile, or a shipped one's name (guide-robot; "
                             "default: the scenario's, else the home robot)")
    if policies:
        _policy_argument(parser)


def _scenario_arguments(parser: argparse.ArgumentParser) -> None:
    """What runs a scenario: the scenario, the documents, the robot, seed and time."""
    parser.add_argument("scenario", metavar="SCENARIO", help="a scenario file")
    _switch_arguments(parser, policies=False)
    parser.add_argument("--seed", type=_seed, metavar="N",
                        help="random seed (default: the scenario's)")
    parser.add_argument("--until", type=float, metavar="SECONDS",
                        help="simulated time to stop at (default: the scenario's)")


def _policy_argument(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--policy", action="append", default=[], metavar="NAME=on|off",
                        help="switch a mediation policy, over the profile's and the "
                             f"scenario's (repeatable; NAME: all, {', '.join(POLICIES)}; "
                             "docs/mediator.md, Policies)")


def _batch_arguments(parser: argparse.ArgumentParser) -> None:
    """Where many runs go and where their records are kept (``sweep``, ``check``)."""
    parser.add_argument("--jobs", type=int, metavar="J",
                        help="parallel processes on this machine (default: every core)")
    parser.add_argument("--executor", metavar="WHERE",
                        help="where the runs go: processes (default: this machine's, --jobs) "
                             "or dask://HOST:PORT, a Dask cluster's scheduler (the dask "
                             "extra; how long a cluster may keep the runs waiting: "
                             "PRIMA_DASK_CONNECT_TIMEOUT, PRIMA_DASK_WORKER_TIMEOUT, "
                             "PRIMA_DASK_PROGRESS_TIMEOUT; docs/judging.md, Many runs)")
    parser.add_argument("--results", metavar="FILE",
                        help="write every run's record to FILE (jsonl) as it comes")
    parser.add_argument("--resume", metavar="FILE",
                        help="go on with the batch whose results FILE holds: the runs it "
                             "has are not run again, the others are added to it")


def add_threshold_options(parser: argparse.ArgumentParser) -> None:
    """The threshold options: ``--max-<measure>`` for each measure of
    :data:`prima.judge.LIMITS`, then the measures' parameters."""
    from prima.judge import LIMITS, PARAMETERS

    group = parser.add_argument_group("thresholds")
    for m in LIMITS:
        group.add_argument(m.option, dest=m.limit, type=int, metavar="N",
                           help=f"{m.allowed} (default 0)")
    for p in PARAMETERS:
        group.add_argument(p.option, dest=p.name, type=float, metavar=p.metavar, help=p.help)


def thresholds_from(args: argparse.Namespace) -> object:
    """The :class:`prima.judge.Thresholds` the options ask for; ValueError if one is bad."""
    from prima.judge import LIMITS, PARAMETERS, Thresholds

    names = [m.limit for m in LIMITS] + [p.name for p in PARAMETERS]
    given = {name: getattr(args, name) for name in names if getattr(args, name) is not None}
    return Thresholds(**given)


def _thresholds(command: str, args: argparse.Namespace, err: TextIO) -> object:
    """The thresholds asked for, or None after a usage error's message."""
    try:
        return thresholds_from(args)
    except ValueError as exc:
        field, _, rest = str(exc).partition(" ")
        _usage(command, f"--{field.replace('_', '-')} {rest}", err)
        return None


def _profile(path: str | None) -> RobotProfile:
    from prima.dsl import default_profile, load_profile

    return load_profile(path) if path else default_profile()


def _run_usage(args: argparse.Namespace) -> str | None:
    """What is wrong with ``prima run``'s options, checked before anything runs."""
    until = args.until
    if until is not None and not (math.isfinite(until) and 0 < until <= MAX_RUN_TIME):
        return f"--until must be a number of seconds above 0 and at most {MAX_RUN_TIME:g}"
    if not (math.isfinite(args.pose_rate) and 0 <= args.pose_rate <= 100):
        return "--pose-rate must be a number of samples per second from 0 to 100"
    switches = _policies(args.policy)
    if isinstance(switches, str):
        return switches
    args.policy = switches
    for path in (args.scenario, args.fa, args.ea, args.robot):
        if path is not None and not Path(path).is_file():
            return f"no such file: {path}"
    if args.out:
        return _target(args.out, _run_inputs(args, args.scenario))
    return None


def _switches(args: argparse.Namespace) -> Switches | str:
    """The command line's FA, EA, robot and policy switches, or what is wrong with them."""
    from prima.run import Switches

    switches = _policies(args.policy)
    if isinstance(switches, str):
        return switches
    for path in (args.fa, args.ea, args.robot):
        if path is not None and not Path(path).is_file():
            return f"no such file: {path}"
    return Switches(args.fa, args.ea, args.robot, tuple(switches.items()))


def _scenario_only(args: argparse.Namespace, source: Path) -> str | None:
    """Switches make sense only where a scenario runs (a trace is what it is)."""
    if source.suffix == ".jsonl" and (args.fa or args.ea or args.robot or args.policy):
        return "--fa, --ea, --robot and --policy change a scenario's run, not a trace"
    return None


def _target(path: str, inputs: Inputs = (), option: str = "--out") -> str | None:
    """What stops ``--out PATH`` from being written (it names one of ``inputs``, say), as
    a usage error."""
    from prima.output import check_target

    problem = check_target(path, inputs)
    return f"{option} {problem}" if problem else None


_REFERENCE_ROLES = {"fa": "the FA", "ea": "an EA", "zone": "a zone's EA", "map": "the map",
                    "profile": "the robot profile"}
"""What a file a scenario names is, by its role (``scenario_references``)."""


def _scenario_inputs(scenario: str | Path, what: str = "the scenario") -> list[tuple[str, Path]]:
    """A scenario and every file it names (its documents, map and robot profile), each
    with what it is: what an output must not overwrite."""
    from prima.scenario import scenario_references

    path = Path(scenario)
    found: list[tuple[str, Path]] = [(what, path)]
    for ref in scenario_references(path):
        role = _REFERENCE_ROLES.get(ref.role, "a file")
        found.append((f"{role} of {shown_path(path.name)}", ref.path))
    return found


def _run_inputs(args: argparse.Namespace, scenario: str | Path | None) -> list[tuple[str, Path]]:
    """The input files of a command that runs ``scenario`` (if any) with the command
    line's ``--fa``, ``--ea`` and ``--robot``."""
    found = _scenario_inputs(scenario) if scenario is not None else []
    for option, what in (("fa", "the --fa document"), ("ea", "the --ea document"),
                         ("robot", "the --robot profile")):
        given = getattr(args, option, None)
        if isinstance(given, str):
            found.append((what, Path(given)))
    return found


def _worst_runs_named(folder: str, inputs: Inputs, stem: str, seed: int) -> str | None:
    """An input that a worst run written in ``folder`` could be named as
    (``STEM-runN-seedS.xml``, ``stem`` a regular expression), as a usage error: it is
    refused before any run."""
    from prima.output import same_file

    pattern = re.compile(stem + rf"-run\d+-seed{seed}\.xml")
    for what, path in inputs:
        given = Path(path)
        if pattern.fullmatch(given.name) and same_file(given.parent, folder):
            return (f"--out {shown_path(folder)}: a worst run written there may be named "
                    f"{shown_path(given.name)}, which is {what}, an input of this command: "
                    "name another folder (nothing was written)")
    return None


def _policies(given: list[str]) -> dict[str, bool] | str:
    """``--policy NAME=on|off`` switches, in order (a later one wins), or what is wrong."""
    out: dict[str, bool] = {}
    for text in given:
        name, _, state = text.partition("=")
        if name not in POLICIES and name != "all":
            return (f"--policy {text}: no policy {name!r} "
                    f"(known: all, {', '.join(POLICIES)}){did_you_mean(name, policy_names())}")
        if state not in ("on", "off"):
            return f"--policy {text}: say {name}=on or {name}=off"
        if name == "all":
            out.clear()
        out[name] = state == "on"
    return out


def policy_names() -> tuple[str, ...]:
    """What ``--policy NAME=on|off`` may name: every mediation policy of the registry
    (:data:`prima.vocab.POLICIES`), or all of them."""
    return ("all", *POLICIES)


MAX_RUNS = 1_000_000
"""The most runs one sweep or check cell may ask for."""


def _batch_usage(args: argparse.Namespace, inputs: Inputs = ()) -> str | None:
    """What is wrong with ``--jobs``, ``--executor``, ``--results`` and ``--resume``
    (a results file must not be one of ``inputs``)."""
    from prima.batch import executor_problem

    if args.jobs is not None and not 1 <= args.jobs <= 1024:
        return "--jobs must be a whole number from 1 to 1024"
    problem = executor_problem(args.executor)
    if problem:
        return problem
    if args.results and args.resume:
        return "--resume FILE goes on writing FILE: give it alone, without --results"
    if args.resume and not Path(args.resume).is_file():
        return f"--resume: no such file: {args.resume}"
    target = args.results or args.resume
    if target:
        return _target(target, inputs, "--results" if args.results else "--resume")
    return None


def _pool(args: argparse.Namespace, runs: int) -> Pool:
    """The pool the options ask for; a Dask cluster that cannot take the runs is a
    ClusterError (a message)."""
    from prima.batch import pool_for

    return pool_for(args.executor, args.jobs, runs)
