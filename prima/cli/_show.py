"""``prima show``: a run as one HTML page (:mod:`prima.show`)."""

from __future__ import annotations

import argparse
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


def add(commands: Commands) -> None:
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
    _colour_argument(show)


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


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
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


COMMAND = Command("show", add, execute)
