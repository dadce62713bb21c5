"""``prima plot``: a run's device timeline or its animation (:mod:`prima.plot`)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TextIO

from prima.cli._common import EXIT_OK, Command, Commands, _missing_extra, _usage
from prima.cli._options import (
    _colour_argument,
    _run_inputs,
    _scenario_only,
    _switch_arguments,
    _switches,
    _target,
)
from prima.escape import shown_path
from prima.vocab import MAX_RUN_TIME


def add(commands: Commands) -> None:
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
    _colour_argument(plot)


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


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


COMMAND = Command("plot", add, execute)
