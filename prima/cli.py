"""The ``prima`` command line: ``prima validate ...``.

``main(argv)`` returns the exit status and never raises for a user's mistake:
0 when all is well, 1 when an input has errors, 2 for a usage error.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import importlib
import json
import math
import os
import re
import shlex
import signal
import sys
import threading
from pathlib import Path
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import TYPE_CHECKING, TextIO

from prima import __version__, compiled
from prima.errors import LocatedError, PrimaError, Problem, Severity
from prima.escape import shown_path, terminal
from prima.suggest import SuggestingParser, did_you_mean, unrecognized
from prima.term import BOLD, CYAN, GREEN, RED, WHEN, YELLOW, Paint, columns, is_terminal, \
    wants_colour
from prima.shipped import locate, shipped
from prima.signals import EXIT_TERMINATED, Terminated, note_terminated, terminate_as_interrupt
from prima.vocab import MAX_RUN_TIME, MAX_SEED, POLICIES

if TYPE_CHECKING:
    from prima.batch import Pool
    from prima.output import Inputs
    from prima.dsl import RobotProfile
    from prima.run import Switches

# Each command imports what it needs when it runs (``prima --help`` imports no lxml,
# lark or pymunk; ``prima validate`` of documents no simulator): a cold start pays
# only for its own command.

EXIT_OK, EXIT_ERRORS, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_PIPE = 0, 1, 2, 130, 141
"""141: as a shell reports a process its closed pipe stopped (128 + SIGPIPE)."""


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


def _colour_argument(parser: argparse.ArgumentParser, default: str = argparse.SUPPRESS) -> None:
    """``--color``, before the command or after it (there, only when given)."""
    parser.add_argument("--color", choices=WHEN, default=default,
                        help="colour the output: auto (default: on a terminal, unless "
                             "NO_COLOR is set; FORCE_COLOR forces it), always or never")


def build_parser() -> SuggestingParser:
    parser = SuggestingParser(
        prog="prima",
        description="PRIMA: mediate two robot applications sharing one personal robot.",
    )
    build = " (compiled)" if compiled() else ""
    parser.add_argument("--version", action="version", version=f"prima {__version__}{build}")
    _colour_argument(parser, "auto")
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
    _scenario_arguments(run)
    run.add_argument("--format", choices=("text", "jsonl", "chrome-trace", "mcap"),
                     help="trace format (default: by --out's extension, .jsonl, .json for "
                          "chrome-trace or .mcap; else text); chrome-trace: the Trace Event "
                          "Format, for Perfetto or chrome://tracing; mcap: a recording for "
                          "Foxglove (with --out; the mcap extra)")
    run.add_argument("-o", "--out", metavar="FILE",
                     help="write the trace to FILE instead of stdout")
    run.add_argument("--pose-rate", type=float, default=2.0, metavar="HZ",
                     help="pose samples per simulated second in the jsonl trace "
                          "(default: 2; 0: none)")
    _policy_argument(run)
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
    sweep = commands.add_parser(
        "sweep",
        help="re-run a scenario with its timings jittered and judge every run",
        description="Run a scenario N times with its user's actions, answer delays and "
                    "scheduled messages shifted by seeded random offsets in +-jitter, judge "
                    "each run (docs/judging.md), print the spread of every measure and "
                    "write the worst runs as scenario files that replay them exactly. "
                    "Exit status 1 when a run exceeded a threshold.",
    )
    sweep.add_argument("scenario", metavar="SCENARIO", help="a scenario file")
    _switch_arguments(sweep)
    sweep.add_argument("--runs", type=int, required=True, metavar="N", help="how many runs")
    sweep.add_argument("--jitter", type=float, required=True, metavar="SECONDS",
                       help="largest shift of a timing, either way")
    sweep.add_argument("--seed", type=_seed, default=0, metavar="S",
                       help="seed of the shifts (default 0); run i uses (S, i)")
    _batch_arguments(sweep)
    sweep.add_argument("--out", metavar="DIR",
                       help="where to write the worst runs, made if missing (default: "
                            "sweep-NAME/ in the current folder, NAME the scenario file's)")
    sweep.add_argument("--worst", type=int, default=3, metavar="K",
                       help="how many of the worst runs to write (default 3; 0: none)")
    add_threshold_options(sweep)
    _add_check(commands)
    show = commands.add_parser(
        "show",
        help="write a run as one HTML page: the map, a timeline per device, the trace",
        description="Write a run as one self-contained HTML page that works offline "
                    "(docs/show.md): the map with the robot, the user and their words; a "
                    "timeline with one row per device; the trace table; one playhead drives "
                    "all three. RUN is a jsonl trace (*.jsonl) or a scenario (*.xml, run "
                    "in-process). Needs the show extra: pip install 'prima[show]'.",
    )
    show.add_argument("input", metavar="RUN", help="a jsonl trace or a scenario file")
    _switch_arguments(show)
    show.add_argument("--scenario", metavar="SCENARIO",
                      help="the scenario a jsonl trace was run from: its map is drawn "
                           "(a trace does not name it)")
    show.add_argument("-o", "--out", metavar="FILE",
                      help="the page to write, its folder made if missing (default: "
                           "RUN's name with .html, in the current folder)")
    show.add_argument("--audio", action="store_true",
                      help="put each utterance in the page as sound, synthesised by "
                           "espeak-ng, played with the playhead (needs espeak-ng: "
                           "apt-get install espeak-ng)")
    show.add_argument("--speech-timing", choices=("model", "tts"), default="model",
                      help="how long utterances take in a scenario's run: model (default): "
                           "the robot's speech rate, as every other command; tts: as "
                           "espeak-ng says them, their words cut where it ends them")
    _add_plot(commands)
    _add_live(commands)
    for name in ("validate", "run", "debug", "test", "judge", "sweep", "show", "plot", "live"):
        _colour_argument(commands.choices[name])
    lsp = commands.add_parser(
        "lsp",
        help="serve the language server protocol on stdio (for editors)",
        description="A language server for PXML documents, robot profiles, scenarios and "
                    "maps: diagnostics as prima validate words them, completion, hover and "
                    "go-to-definition (docs/editors.md). An editor starts it; it talks "
                    "the Language Server Protocol on stdin and stdout. Needs the lsp extra: "
                    "pip install 'prima[lsp]'.",
    )
    lsp.add_argument("--robot", metavar="PROFILE",
                     help="robot hardware profile documents are checked against, over a "
                          "scenario's (as prima validate --robot; default: the scenario's "
                          "that runs the document, else the home robot)")
    completion = commands.add_parser(
        "completion",
        help="print the code that makes a shell complete prima's command lines",
        description="Print the code that makes SHELL complete prima's commands, options, "
                    "their values (policy names among them) and the files each argument "
                    "takes (argcomplete). Load it from the shell's start-up file: "
                    "eval \"$(prima completion bash)\" in ~/.bashrc (zsh: in ~/.zshrc, "
                    "after compinit); prima completion fish | source in fish's "
                    "config.fish.",
    )
    completion.add_argument("shell", choices=SHELLS, metavar="SHELL",
                            help=f"the shell: {', '.join(SHELLS)}")
    return parser


SHELLS = ("bash", "zsh", "fish")
"""The shells ``prima completion`` writes the code for."""


def _add_check(commands: argparse._SubParsersAction[SuggestingParser]) -> None:
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


def _add_live(commands: argparse._SubParsersAction[SuggestingParser]) -> None:
    live = commands.add_parser(
        "live",
        help="play the user of your applications in the browser, in real time",
        description="Run a scenario, or applications alone, in real time and serve one local "
                    "page (docs/live.md) that shows the map, the robot, the user, the device "
                    "timeline, the words, the mediator's decisions and the judge's findings "
                    "as they happen; act as the user from it (say, touch, walk, answer, send "
                    "a network message, pause, step) and save what you did as a scenario "
                    "that prima run replays to the same trace. Ctrl-C ends it. Needs the live "
                    "extra: pip install 'prima[live]'.",
    )
    live.add_argument("inputs", nargs="+", metavar="SCENARIO-or-APPS",
                      help="a scenario (*.xml), or applications' documents (*.pxml: an FA "
                           "and EAs, on the first map with every place they name)")
    _switch_arguments(live)
    live.add_argument("--seed", type=_seed, metavar="N",
                      help="random seed (default: the scenario's; 0 for applications)")
    live.add_argument("--script", action="store_true",
                      help="keep the scenario's scripted user (actions, answers) and its "
                           "timed messages, sounds and events; you act beside them")
    live.add_argument("--speed", type=float, default=1.0, metavar="X",
                      help="simulated seconds per second (default 1: real time)")
    live.add_argument("--until", type=float, default=3600.0, metavar="SECONDS",
                      help="when the run ends, in simulated time (default 3600)")
    live.add_argument("--paused", action="store_true",
                      help="start paused (default: the run plays when the page opens)")
    live.add_argument("--host", default="127.0.0.1",
                      help="the address to serve on (default 127.0.0.1: this machine only; "
                           "another is said to be open to whoever can reach it)")
    live.add_argument("--port", type=int, default=8400,
                      help="the page's port (default 8400; 0: any free one)")
    live.add_argument("--save", metavar="FILE",
                      help="where the page's Save writes the session as a scenario (rewritten "
                           "at each save; never one of the session's inputs)")
    live.add_argument("--save-dir", metavar="DIR",
                      help="a folder where each Save writes a new scenario, NAME-live-N.xml "
                           "(without --save or --save-dir, Save downloads it)")
    live.add_argument("--foxglove", nargs="?", type=int, const=8765, metavar="PORT",
                      help="serve the run to Foxglove too, on its WebSocket protocol "
                           "(default port 8765; the mcap extra)")
    live.add_argument("--map", metavar="MAP",
                      help="applications alone: the map to run them on (default: the first "
                           "shipped map with every place they name)")


def _live_usage(args: argparse.Namespace) -> str | None:
    """What is wrong with ``prima live``'s arguments, checked before anything runs."""
    inputs = [Path(p) for p in args.inputs]
    for path in [*inputs, *(Path(p) for p in (args.fa, args.ea, args.robot, args.map) if p)]:
        if not path.is_file():
            return f"no such file: {shown_path(path)}"
    scenario = inputs[0].suffix == ".xml"
    if scenario and len(inputs) > 1:
        return "give one scenario, or applications' documents (*.pxml), not both"
    if not scenario and any(p.suffix != ".pxml" for p in inputs):
        return "give a scenario (*.xml) or applications' documents (*.pxml)"
    if not scenario and (args.script or args.fa or args.ea):
        return "--script, --fa and --ea go with a scenario; applications alone have no script"
    if scenario and args.map:
        return "--map goes with applications alone; a scenario brings its own map"
    from prima.live import MAX_SPEED

    if not (math.isfinite(args.speed) and 0 < args.speed <= MAX_SPEED):
        return f"--speed must be a number above 0 and at most {MAX_SPEED:g}"
    if not (math.isfinite(args.until) and 0 < args.until <= MAX_RUN_TIME):
        return f"--until must be a number of seconds above 0 and at most {MAX_RUN_TIME:g}"
    for name, port in (("--port", args.port), ("--foxglove", args.foxglove)):
        if port is not None and not 0 <= port <= 65535:
            return f"{name} must be a port number from 0 to 65535"
    if args.save and args.save_dir:
        return "give --save FILE or --save-dir DIR, not both"
    return None


def _live(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    problem = (_live_usage(args) or _missing_extra("aiohttp", "aiohttp", "live")
               or _missing_extra("plotly", "Plotly", "live")
               or (_missing_extra("foxglove", "foxglove-sdk", "mcap")
                   if args.foxglove is not None else None))
    if problem:
        return _usage("live", problem, err)
    switches = _switches(args)
    if isinstance(switches, str):
        return _usage("live", switches, err)
    from prima.live import Options, SaveTo, base_of, check_save, serve

    inputs = tuple(Path(p) for p in args.inputs)
    apps = inputs[0].suffix != ".xml"
    options = Options(
        inputs=inputs, switches=switches, seed=args.seed, until=args.until, speed=args.speed,
        script=args.script, host=args.host, port=args.port, foxglove=args.foxglove,
        maps=shipped("scenarios", "maps") if apps else None,
        map_file=Path(args.map) if args.map else None,
        robot=Path(args.robot) if apps and args.robot else None, autoplay=not args.paused)
    base = base_of(options)
    save = SaveTo(file=Path(args.save) if args.save else None,
                  folder=Path(args.save_dir) if args.save_dir else None,
                  stem=inputs[0].stem)
    problem = check_save(save, base.inputs)
    if problem:
        return _usage("live", problem, err)
    return serve(options, base, save, out, err)


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


def _add_plot(commands: argparse._SubParsersAction[SuggestingParser]) -> None:
    plot = commands.add_parser(
        "plot",
        help="draw a run's device timeline (SVG, PNG, PDF) or animate it (GIF)",
        description="Draw a run as a picture: the device timeline (one row per device, "
                    "a bar per atomic behavior, coloured by application; suspensions, "
                    "holds, the user's actions and the events marked) as SVG, PNG or PDF, "
                    "or, for a .gif, an animation of the robot and the user on the map "
                    "with the words said and the timeline's playhead. INPUT is a jsonl "
                    "trace (*.jsonl) or a scenario (*.xml, run in-process). Needs the "
                    "plot extra (matplotlib).",
    )
    plot.add_argument("input", metavar="INPUT", help="a jsonl trace or a scenario file")
    _switch_arguments(plot)
    plot.add_argument("-o", "--out", required=True, metavar="FILE",
                      help="the picture: .svg, .png or .pdf (timeline) or .gif (animation)")
    plot.add_argument("--until", type=float, metavar="SECONDS",
                      help="simulated time to stop at (a scenario: the run's end; "
                           "a trace: where the picture ends)")
    plot.add_argument("--pose-rate", type=float, metavar="HZ",
                      help="a scenario's pose samples per simulated second (default 2)")
    plot.add_argument("--map", metavar="MAP",
                      help="the map file to draw under an animated jsonl trace "
                           "(default: the scenario's; a trace without it: no walls)")
    plot.add_argument("--step", type=float, default=1.0, metavar="SECONDS",
                      help="animation: simulated seconds between frames (default 1)")
    plot.add_argument("--fps", type=float, default=5.0, metavar="N",
                      help="animation: frames shown per second (default 5)")


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


def main(argv: Sequence[str] | None = None, out: TextIO | None = None,
         err: TextIO | None = None) -> int:
    global _colour
    out = out or sys.stdout
    err = err or sys.stderr
    parser = build_parser()
    given = list(sys.argv[1:] if argv is None else argv)
    if "_ARGCOMPLETE" in os.environ:  # the shell asks what may come next (prima completion)
        try:
            from prima.completion import autocomplete
        except ImportError:  # (no argcomplete: the shell completes file names instead)
            return EXIT_ERRORS
        autocomplete(parser)
    _colour = _colour_asked(given)
    error = _paint(sys.stderr)("error", RED, BOLD)
    for each in (parser, *_subparsers(parser)):
        each.given = given  # (for a did-you-mean in a "required" error)
        each.error_word = error
    try:
        args, extra = parser.parse_known_args(argv)
        if extra:  # as parse_args would say, with the option a misspelt one may be
            _subparser(parser, args.command).error(unrecognized(extra, _subparser(
                parser, args.command)))
    except SystemExit as exc:
        return int(exc.code or 0)
    _colour = args.color
    problem = _locate_inputs(args)
    if problem:
        return _usage(args.command, problem, err)
    command: Callable[[argparse.Namespace, TextIO, TextIO], int] = _COMMANDS[args.command]
    with terminate_as_interrupt() as signals:
        status = _main(command, args, out, err)
    return EXIT_TERMINATED if signals.terminated and status == EXIT_INTERRUPTED else status


_colour = "auto"
"""``--color`` as this command line gives it (``main`` sets it first)."""

_INPUTS = {"scenario": None, "input": None, "paths": None, "inputs": None, "map": "map",
           "eas": "ea", "fa": "fa", "ea": "ea", "robot": "robot"}
"""The options and arguments that name files to read, each with what a bare name there
names (:data:`prima.shipped.NAMED`: ``--fa fa2-follow``), or None."""


def _locate_inputs(args: argparse.Namespace) -> str | None:
    """Each file to read as :func:`prima.shipped.locate` finds it: one the current folder
    lacks may be shipped with PRIMA (``scenarios/thesis/sample-03.xml`` from an install,
    as from a checkout). Not for ``prima test --update``, which writes beside them: PRIMA's
    own golden traces are not rewritten from outside a checkout. What is wrong with a name
    no file can have (too long to look up), as a usage error, or None."""
    for name in _INPUTS:
        value = getattr(args, name, None)
        for text in value if isinstance(value, list) else [value]:
            problem = _unnameable(text) if isinstance(text, str) else None
            if problem:
                return problem
    if getattr(args, "update", False):
        return None
    for name, kind in _INPUTS.items():
        value = getattr(args, name, None)
        if isinstance(value, str):
            setattr(args, name, locate(value, kind))
        elif isinstance(value, list):
            setattr(args, name, [locate(v, kind) if isinstance(v, str) else v for v in value])
    return None


def _unnameable(text: str) -> str | None:
    """Why the system cannot look ``text`` up at all (a name longer than a file's or a
    path's may be), or None."""
    try:
        os.stat(text)
    except OSError as exc:
        if exc.errno == errno.ENAMETOOLONG:
            return f"{terminal(text[:40])}...: {os.strerror(exc.errno).lower()}"
    except ValueError:  # (a NUL in it: the commands say there is no such file)
        pass
    return None


def _colour_asked(given: Sequence[str]) -> str:
    """``--color WHEN`` as the words of a command line give it, before they are parsed
    (an error parsing them is coloured as asked)."""
    when = "auto"
    for i, word in enumerate(given):
        if word == "--":
            break
        value = word.partition("=")[2] if word.startswith("--color=") else \
            given[i + 1] if word == "--color" and i + 1 < len(given) else None
        when = value if value in WHEN else when
    return when


def _paint(stream: TextIO) -> Paint:
    """Colour for what goes to ``stream`` (:func:`prima.term.wants_colour`)."""
    return Paint(wants_colour(stream, _colour))


def _error(command: str, stream: TextIO) -> str:
    """``prima COMMAND: error:``, coloured for a terminal."""
    return f"prima {command}: {_paint(stream)('error', RED, BOLD)}:"


def _main(command: Callable[[argparse.Namespace, TextIO, TextIO], int],
          args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    try:
        return command(args, out, err)
    except LocatedError as exc:
        _report(exc.problems, err)
        return EXIT_ERRORS
    except PrimaError as exc:  # a user's error is a message, never a traceback
        print(f"{_error(args.command, err)} {exc}", file=err)
        return EXIT_ERRORS
    except BrokenPipeError:  # e.g. `prima validate apps/ | head`: the reader had enough
        sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - silence the flush at exit
        return EXIT_PIPE
    except OSError as exc:  # the file system refused (a name too long...): a message too
        from prima.output import shown

        reason = exc.strerror or str(exc)
        named = f"{shown(os.fsdecode(exc.filename))}: " if exc.filename is not None else ""
        print(f"{_error(args.command, err)} {named}{reason[:1].lower() + reason[1:]}",
              file=err)
        return EXIT_ERRORS
    except KeyboardInterrupt:  # Ctrl-C or SIGTERM: what was written so far stays written
        print(f"prima {args.command}: interrupted", file=err)
        return EXIT_INTERRUPTED


def _subparsers(parser: argparse.ArgumentParser) -> list[SuggestingParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return [p for p in action.choices.values() if isinstance(p, SuggestingParser)]


def _subparser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    chosen: argparse.ArgumentParser = action.choices[command]
    return chosen


def _report(problems: Iterable[Problem], to: TextIO) -> None:
    """One line per problem, its file's name and message escaped (they may hold control
    characters); under a fault inside an expression, its line and a caret. On a
    terminal, ``file:line:col:`` in bold, ``error`` in red, ``warning`` in yellow."""
    paint = _paint(to)
    for problem in problems:
        where = f"{terminal(problem.file)}:{problem.line}:{problem.col}:"
        severity = problem.severity.value
        if paint.on:
            print(paint(where, BOLD), paint(severity, RED if problem.severity is Severity.ERROR
                                             else YELLOW, BOLD) + ":",
                  terminal(problem.message), file=to)
        else:
            print(f"{where} {severity}: {terminal(problem.message)}", file=to)
        caret = _caret(problem)
        if caret:
            print(caret, file=to)


def _caret(problem: Problem) -> str:
    """``problem``'s source line and a caret under its column (:meth:`Problem.caret`),
    the line escaped as every row is (tabs kept, so the caret still lines up)."""
    if not problem.source:
        return ""
    line = problem.source.rstrip("\r\n")
    shown = "\t".join(terminal(part) for part in line.split("\t"))
    pad = "".join(c if c == "\t" else " " * len(terminal(c))
                  for c in line[: max(problem.col - 1, 0)])
    return f"    {shown}\n    {pad}^"


def _usage(command: str, message: str, err: TextIO) -> int:
    print(f"{_error(command, err)} {message}", file=err)
    return EXIT_USAGE


def _missing_extra(module: str, library: str, extra: str) -> str | None:
    """Why a viewer cannot run here: the optional extra it needs is not installed
    (checked before anything runs, like a usage error)."""
    try:
        importlib.import_module(module)
    except ImportError:
        return (f"{library} is not installed; install the {extra} extra: pip install "
                f"'prima[{extra}]' (in a checkout of PRIMA: pip install -e '.[{extra}]')")
    return None


def _profile(path: str | None) -> RobotProfile:
    from prima.dsl import default_profile, load_profile

    return load_profile(path) if path else default_profile()


def _validate(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


_FORMAT_OF = {".jsonl": "jsonl", ".json": "chrome-trace", ".mcap": "mcap"}
"""``prima run``'s trace format when ``--out``'s extension says it and ``--format`` not."""


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


def _mcap_usage(args: argparse.Namespace) -> str | None:
    """What ``prima run --format mcap`` needs besides: a file to write, and foxglove-sdk."""
    if not args.out:
        return "--format mcap writes a binary file: give --out FILE"
    return _missing_extra("foxglove", "foxglove-sdk", "mcap")


def _policies(given: list[str]) -> dict[str, bool] | str:
    """``--policy NAME=on|off`` switches, in order (a later one wins), or what is wrong."""
    out: dict[str, bool] = {}
    for text in given:
        name, _, state = text.partition("=")
        if name not in POLICIES and name != "all":
            return (f"--policy {text}: no policy {name!r} "
                    f"(known: all, {', '.join(POLICIES)}){did_you_mean(name, POLICY_NAMES)}")
        if state not in ("on", "off"):
            return f"--policy {text}: say {name}=on or {name}=off"
        if name == "all":
            out.clear()
        out[name] = state == "on"
    return out


POLICY_NAMES = ("all", *POLICIES)
"""What ``--policy NAME=on|off`` may name: every mediation policy, or all of them."""


def _run(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.output import written
    from prima.run import Run
    from prima.trace import TextTrace, TraceLine, jsonl_row

    if args.format is None:  # (the file's extension says, as its reader would read it)
        args.format = _FORMAT_OF.get(Path(args.out).suffix.lower() if args.out else "", "text")
    problem = _run_usage(args) or (_mcap_usage(args) if args.format == "mcap" else None)
    if problem:
        return _usage("run", problem, err)
    # Everything is loaded and checked before the output is opened; then each trace
    # line is written as the run makes it (``write`` is defined below, before the run).
    run = Run(args.scenario, fa=args.fa, ea=args.ea, robot=args.robot,
              seed=args.seed, until=args.until, sink=lambda line: write(line),
              pose_rate=args.pose_rate, policies=args.policy)
    with contextlib.ExitStack() as files:
        # (an MCAP recording is written by its recorder, a binary file of its own)
        to = files.enter_context(written(args.out, partial=True)) \
            if args.out and args.format != "mcap" else out
        if args.format == "text":
            text = TextTrace(run.app_names(), paint=_paint(to))
            print(text.header, file=to)

            def write(line: TraceLine) -> None:
                row = text.row(line)
                if row is not None:
                    to.write(row + "\n")
        elif args.format == "chrome-trace":
            from prima.chrome_trace import ChromeTraceWriter

            chrome = ChromeTraceWriter(to)
            ctrl_c = files.enter_context(_between_lines())

            def write(line: TraceLine) -> None:
                chrome.write(line)
                ctrl_c.check()  # Ctrl-C lands between two lines: the file stays whole
        elif args.format == "mcap":
            from prima.mcap import Recorder

            recorder = files.enter_context(Recorder(args.out, run.scenario.map))
            ctrl_c = files.enter_context(_between_lines())

            def write(line: TraceLine) -> None:
                recorder.write(line)
                ctrl_c.check()  # Ctrl-C lands between two lines: the file is finished whole
        else:
            def write(line: TraceLine) -> None:
                to.write(jsonl_row(line))
        try:
            run.run()
            if args.format == "chrome-trace":
                chrome.close()
        except KeyboardInterrupt:
            if args.format == "chrome-trace":
                chrome.close()  # the slices under way end where the run stopped
            to.flush()
            print(f"prima run: interrupted at t={run.sim.now():g} s; the trace up to then "
                  f"is written{' to ' + shown_path(args.out) if args.out else ''}", file=err)
            return EXIT_INTERRUPTED
    return EXIT_OK


def _debug(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


class _Deferred:
    """A Ctrl-C noted, to be raised at the next safe point (``check``)."""

    def __init__(self) -> None:
        self.asked = False
        self.terminated = False

    def handle(self, signum: int, _frame: object) -> None:
        if signum == signal.SIGTERM:
            self.terminated = True
            note_terminated()
        if self.asked:  # a second Ctrl-C: at once
            self.check()
        self.asked = True

    def check(self) -> None:
        if self.asked:
            raise Terminated if self.terminated else KeyboardInterrupt


@contextlib.contextmanager
def _between_lines() -> Iterator[_Deferred]:
    """While writing a file that a torn write would spoil (a chrome trace), Ctrl-C and
    SIGTERM are raised only between two trace lines (a second one at once)."""
    deferred = _Deferred()
    if threading.current_thread() is not threading.main_thread():
        yield deferred  # signals go to the main thread only
        return
    previous = signal.signal(signal.SIGINT, deferred.handle)
    terminate = signal.signal(signal.SIGTERM, deferred.handle)
    try:
        yield deferred
    finally:
        signal.signal(signal.SIGINT, previous)
        signal.signal(signal.SIGTERM, terminate)


def _test(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


def _thresholds(command: str, args: argparse.Namespace, err: TextIO) -> object:
    """The thresholds asked for, or None after a usage error's message."""
    try:
        return thresholds_from(args)
    except ValueError as exc:
        field, _, rest = str(exc).partition(" ")
        _usage(command, f"--{field.replace('_', '-')} {rest}", err)
        return None


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


def _judge(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


def _sweep_usage(args: argparse.Namespace) -> str | None:
    """What is wrong with ``prima sweep``'s options, checked before anything runs."""
    if not Path(args.scenario).is_file():
        return f"no such file: {args.scenario}"
    if not 1 <= args.runs <= MAX_RUNS:
        return f"--runs must be a whole number from 1 to {MAX_RUNS}"
    if not (math.isfinite(args.jitter) and 0 <= args.jitter <= MAX_RUN_TIME):
        return f"--jitter must be a number of seconds from 0 to {MAX_RUN_TIME:g}"
    inputs = _run_inputs(args, args.scenario)
    problem = _batch_usage(args, inputs)
    if problem:
        return problem
    if args.worst < 0:
        return "--worst must be a whole number from 0 up"
    from prima.output import check_folder, named_after

    args.out = args.out or str(named_after(args.scenario, "sweep-{stem}"))
    if not args.worst:
        return None
    problem = check_folder(args.out, inputs)
    if problem:
        return f"--out {problem}"
    return _worst_runs_named(args.out, inputs, re.escape(Path(args.scenario).stem), args.seed)


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


class _BarLine:
    """Standard error while a progress bar is drawn on it: whether the bar's line is
    still open. Leaving the block (``with``), however it is left, ends that line, so
    nothing printed next, on standard output or error, shares it with the bar."""

    def __init__(self, err: TextIO) -> None:
        self.err = err
        self.open = False

    def write(self, text: str) -> None:
        if text:
            self.err.write(text)
            self.err.flush()
            self.open = not text.endswith("\n")

    def end(self) -> None:
        if self.open:
            self.open = False
            self.err.write("\n")
            self.err.flush()

    def __enter__(self) -> _BarLine:
        return self

    def __exit__(self, *_exc: object) -> None:
        self.end()


def _pool(args: argparse.Namespace, runs: int) -> Pool:
    """The pool the options ask for; a Dask cluster that cannot take the runs is a
    ClusterError (a message)."""
    from prima.batch import pool_for

    return pool_for(args.executor, args.jobs, runs)


def _sweep(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.judge import Thresholds
    from prima.sweep import format_sweep, progress_bar, sweep

    problem = _sweep_usage(args)
    if problem:
        return _usage("sweep", problem, err)
    thresholds = _thresholds("sweep", args, err)
    if not isinstance(thresholds, Thresholds):
        return EXIT_USAGE
    switches = _switches(args)
    if isinstance(switches, str):
        return _usage("sweep", switches, err)

    pool = _pool(args, args.runs)
    bar = _BarLine(err)
    with bar:
        result = sweep(args.scenario, runs=args.runs, jitter=args.jitter, seed=args.seed,
                       jobs=args.jobs, thresholds=thresholds,
                       progress=progress_bar(bar.write, live=is_terminal(err)),
                       switches=switches, pool=pool,
                       results=args.results or args.resume, resume=bool(args.resume),
                       keep=args.worst)
    paint = _paint(out)
    out.write(format_sweep(result, paint))
    if result.interrupted:
        print(f"prima sweep: interrupted after {result.done} of {result.asked} runs",
              file=err)
        return EXIT_INTERRUPTED
    if result.lost:
        print(f"prima sweep: run(s) {', '.join(map(str, result.lost[:20]))} lost: the "
              "worker process died each time, the run alone too (out of memory?); the other "
              f"{result.done} run(s) are judged", file=err)
    for index, error in result.errors:
        print(f"prima sweep: run {index} failed: {terminal(str(error))}", file=err)
    if args.worst:
        folder = Path(args.out)
        worst = result.worst(args.worst)
        paths = result.write_worst(args.worst, folder)
        print(f"worst {len(paths)} run(s), written to {shown_path(folder)}/:", file=out)
        for run, path in zip(worst, paths, strict=True):
            exceeded = paint(", ".join(run.exceeded()), RED) or "no threshold exceeded"
            print(f"  {shown_path(path)}  {exceeded}; worst lateness "
                  f"{run.worst_lateness():.2f} s", file=out)
    return EXIT_ERRORS if result.breached or result.lost or result.failed else EXIT_OK


def _show_usage(args: argparse.Namespace) -> str | None:
    """What is wrong with ``prima show``'s arguments, checked before anything runs."""
    source = Path(args.input)
    if not source.is_file():
        return f"no such file: {args.input}"
    if source.suffix not in (".jsonl", ".xml"):
        return f"{args.input}: give a trace (*.jsonl) or a scenario (*.xml)"
    if args.scenario is not None:
        if source.suffix != ".jsonl":
            return "--scenario goes with a jsonl trace; a scenario brings its own map"
        if not Path(args.scenario).is_file():
            return f"no such file: {args.scenario}"
    from prima.output import named_after

    args.out = args.out or str(named_after(source, "{stem}.html"))
    scenario = source if source.suffix == ".xml" else args.scenario
    inputs = _run_inputs(args, scenario)
    if source.suffix == ".jsonl":
        inputs.append(("the trace shown", source))
    return _target(args.out, inputs)


def _show(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    from prima.output import written
    from prima.show import speech_timing, write_page

    problem = _show_usage(args) or _missing_extra("plotly", "Plotly", "show") \
        or _scenario_only(args, Path(args.input))
    tts = args.speech_timing == "tts"
    if not problem and tts and Path(args.input).suffix != ".xml":
        problem = "--speech-timing tts times a run: give a scenario, not a trace"
    if not problem and (args.audio or tts):
        from prima.audio import available

        problem = available()
    if problem:
        return _usage("show", problem, err)
    switches = _switches(args)
    if isinstance(switches, str):
        return _usage("show", switches, err)
    source = Path(args.input)
    timing = speech_timing(source) if tts else None
    scenario = source if source.suffix == ".xml" else args.scenario
    with written(args.out) as page:  # a jsonl trace streamed: never held whole
        abs_, end = write_page(source, page, scenario=scenario, title=source.stem,
                               switches=switches, audio=args.audio, timing=timing,
                               warn=lambda said: print(f"prima show: warning: {said}",
                                                       file=err))
    print(f"prima show: wrote {shown_path(args.out)} ({abs_} atomic behavior(s), "
          f"{end:g} s{'' if scenario else '; no map'})", file=err)
    return EXIT_OK


_PLOT_SUFFIXES = (".svg", ".png", ".pdf", ".gif")
_MAX_FRAMES = 3000


def _plot_usage(args: argparse.Namespace) -> str | None:
    """What is wrong with ``prima plot``'s arguments, checked before anything runs."""
    source, target = Path(args.input), Path(args.out)
    if not source.is_file():
        return f"no such file: {args.input}"
    if source.suffix not in (".jsonl", ".xml"):
        return f"{args.input}: give a trace (*.jsonl) or a scenario (*.xml)"
    if target.suffix.lower() not in _PLOT_SUFFIXES:
        from prima.output import shown

        return f"--out {shown(args.out)}: name a {', '.join(_PLOT_SUFFIXES)} file"
    inputs = _run_inputs(args, source if source.suffix == ".xml" else None)
    if source.suffix == ".jsonl":
        inputs.append(("the trace drawn", source))
    if args.map is not None:
        inputs.append(("the --map", Path(args.map)))
    problem = _target(args.out, inputs)
    if problem:
        return problem
    until = args.until
    if until is not None and not (math.isfinite(until) and 0 < until <= MAX_RUN_TIME):
        return f"--until must be a number of seconds above 0 and at most {MAX_RUN_TIME:g}"
    if args.pose_rate is not None and (source.suffix != ".xml" or not (
            math.isfinite(args.pose_rate) and 0 <= args.pose_rate <= 100)):
        return "--pose-rate must be a number from 0 to 100, with a scenario"
    if args.map is not None and not Path(args.map).is_file():
        return f"no such file: {args.map}"
    if not (math.isfinite(args.step) and args.step > 0):
        return "--step must be a number of seconds above 0"
    if not (math.isfinite(args.fps) and 0 < args.fps <= 50):
        return "--fps must be a number above 0 and at most 50"
    return None


def _plot(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    problem = _plot_usage(args) or _missing_extra("matplotlib", "matplotlib", "plot") \
        or _scenario_only(args, Path(args.input))
    if problem:
        return _usage("plot", problem, err)
    switches = _switches(args)
    if isinstance(switches, str):
        return _usage("plot", switches, err)
    from prima.plot import save_animation, save_timeline, timeline
    from prima.scenario import load_map

    source = Path(args.input)
    world = None
    if source.suffix == ".jsonl":
        from prima.tracefile import read_trace

        rows = [r for r in read_trace(source) if args.until is None or r["t"] <= args.until]
    else:
        from prima.run import Run

        pose_rate = 2.0 if args.pose_rate is None else args.pose_rate
        run = Run(source, until=args.until, pose_rate=pose_rate, **switches.run_options())
        rows = [line.to_dict() for line in run.run()]
        world = run.scenario.map
    if args.map is not None:
        world = load_map(args.map)
    drawn = timeline(rows)
    if Path(args.out).suffix.lower() != ".gif":
        save_timeline(drawn, args.out, title=source.stem)
        print(f"{shown_path(args.out)}: {len(drawn.bars)} bars on {len(drawn.devices)} "
              "devices", file=err)
        return EXIT_OK
    if drawn.end / args.step >= _MAX_FRAMES:
        return _usage("plot", f"--step {args.step:g} makes more than {_MAX_FRAMES} frames "
                              f"of a {drawn.end:g} s run", err)
    frames = save_animation(drawn, args.out, world, title=source.stem, step=args.step,
                            fps=args.fps)
    print(f"{shown_path(args.out)}: {frames} frames", file=err)
    return EXIT_OK


def _lsp(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    problem = _missing_extra("pygls", "pygls", "lsp")
    if problem is None and args.robot is not None and not Path(args.robot).is_file():
        problem = f"no such file: {args.robot}"
    if problem:
        return _usage("lsp", problem, err)
    from prima.lsp import serve

    return serve(Path(args.robot).resolve() if args.robot else None, err=err)


def _completion(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    try:
        from prima.completion import shellcode
    except ImportError:
        return _usage("completion", "argcomplete is not installed (PRIMA needs it to "
                                    "complete): pip install argcomplete", err)
    out.write(shellcode(args.shell))
    return EXIT_OK


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


def _check(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


_COMMANDS: dict[str, Callable[[argparse.Namespace, TextIO, TextIO], int]] = {
    "validate": _validate,
    "run": _run,
    "debug": _debug,
    "test": _test,
    "judge": _judge,
    "sweep": _sweep,
    "check": _check,
    "plot": _plot,
    "show": _show,
    "live": _live,
    "lsp": _lsp,
    "completion": _completion,
}
"""What each subcommand does: ``prima COMMAND`` calls ``_COMMANDS[COMMAND]``."""
