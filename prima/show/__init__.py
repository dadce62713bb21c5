"""``prima show``: a run as one self-contained HTML page, to watch and to question.

The page draws the map (walls, places, areas) with the robot and the user
moving and the words being spoken in bubbles; below it a timeline, one row per
device, each atomic behavior a bar coloured by its application and labelled by
its Command, suspensions and holds hatched, releases, cancels and cuts marked
(the digest ``prima plot`` draws too: :mod:`prima.timeline`); below that the
trace table.
One playhead drives all three. Plotly draws the map and the timeline (its
JavaScript is inlined: the page works offline, from ``file://``); a small
player script moves the playhead. With ``audio``, every utterance is in the page
as sound too (:mod:`prima.audio`, espeak-ng), played in time with the playhead.

A viewer, apart from the core: only ``prima show`` imports it, and it needs
the ``show`` extra (``pip install 'prima[show]'``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from prima.errors import PrimaError

if TYPE_CHECKING:
    from prima.audio import SynthesisedTiming
    from prima.sim import SpeechTiming

__all__ = ["read_rows", "render", "speech_timing"]


def read_rows(path: str | Path, speech: SpeechTiming | None = None) -> list[dict[str, Any]]:
    """A run's rows: a jsonl trace read (located errors), or a scenario run in-process
    (its utterances timed by ``speech``, if given: :func:`speech_timing`)."""
    path = Path(path)
    if path.suffix == ".jsonl":
        from prima.judge import load_trace

        return load_trace(path)
    from prima.run import Run

    return [line.to_dict() for line in Run(path, speech=speech).run()]


def speech_timing(scenario: str | Path) -> SynthesisedTiming:
    """Utterances timed by espeak-ng at the speech rate of the scenario's robot
    (``prima show --speech-timing tts``), for :func:`read_rows` and :func:`render`."""
    from prima.show._sound import speech_timing as timing

    return timing(scenario)


def render(rows: Sequence[Mapping[str, Any]], scenario: str | Path | None = None,
           title: str = "run", *, audio: bool = False,
           timing: SynthesisedTiming | None = None) -> str:
    """The page of a run whose trace lines are ``rows``; the map is ``scenario``'s (if any).
    With ``audio``, each utterance is in the page as sound (espeak-ng), played with the
    playhead; ``timing``: the one the run was timed by, if it was by the synthesiser."""
    try:
        from prima.show._page import page
    except ImportError as exc:  # the plotting library is an optional extra
        raise PrimaError(f"prima show needs Plotly ({exc.name} is missing): "
                         "pip install 'prima[show]'") from exc
    from prima.show._model import build
    from prima.sim import load_scenario

    world = load_scenario(scenario).map if scenario is not None else None
    sounds = ""
    if audio:
        from prima.show._sound import clips, elements

        sounds = elements(clips(rows, scenario, timing))
    return page(build(rows), world, title, sounds)
