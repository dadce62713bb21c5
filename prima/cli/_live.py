"""``prima live``: play the user of applications in the browser (:mod:`prima.live`)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import TextIO

from prima.cli._common import Command, Commands, _missing_extra, _usage
from prima.cli._options import _colour_argument, _seed, _switch_arguments, _switches
from prima.escape import shown_path
from prima.shipped import shipped
from prima.vocab import MAX_RUN_TIME


def add(commands: Commands) -> None:
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
    _colour_argument(live)


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


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


COMMAND = Command("live", add, execute)
