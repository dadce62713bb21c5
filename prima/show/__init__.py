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

import importlib
import io
import tempfile
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from prima.errors import PrimaError
from prima.show._model import Model

if TYPE_CHECKING:
    from prima.audio import SynthesisedTiming
    from prima.run import Switches
    from prima.sim import SpeechTiming, WorldMap

__all__ = ["Model", "digest", "drawing", "map_figure", "read_rows", "render", "speech_timing",
           "style", "timeline_figure", "write_page"]

_Pose = tuple[float, float, float]


def read_rows(path: str | Path, switches: Switches | None = None,
              speech: SpeechTiming | None = None) -> list[dict[str, Any]]:
    """A run's rows: a jsonl trace read (located errors), or a scenario run in-process
    (``switches``: its FA, EA, robot or policies changed; its utterances timed by
    ``speech``, if given: :func:`speech_timing`)."""
    path = Path(path)
    if path.suffix == ".jsonl":
        from prima.tracefile import load_trace

        return load_trace(path)
    return list(_run_rows(path, switches, speech))


def _run_rows(path: Path, switches: Switches | None,
              speech: SpeechTiming | None) -> Iterable[dict[str, Any]]:
    from prima.run import Run

    options = switches.run_options() if switches else {}
    return (line.to_dict() for line in Run(path, speech=speech, **options).run())


def speech_timing(scenario: str | Path) -> SynthesisedTiming:
    """Utterances timed by espeak-ng at the speech rate of the scenario's robot
    (``prima show --speech-timing tts``), for :func:`read_rows` and :func:`render`."""
    from prima.show._sound import speech_timing as timing

    return timing(scenario)


def render(rows: Iterable[Mapping[str, Any]], scenario: str | Path | None = None,
           title: str = "run", *, audio: bool = False,
           timing: SynthesisedTiming | None = None) -> str:
    """The page of a run whose trace lines are ``rows``; the map is ``scenario``'s (if any).
    With ``audio``, each utterance is in the page as sound (espeak-ng), played with the
    playhead; ``timing``: the one the run was timed by, if it was by the synthesiser."""
    out = io.StringIO()
    _write(rows, out, scenario, title, audio=audio, timing=timing)
    return out.getvalue()


def write_page(path: str | Path, out: TextIO, scenario: str | Path | None = None,
               title: str = "run", switches: Switches | None = None, *,
               audio: bool = False, timing: SynthesisedTiming | None = None,
               warn: Callable[[str], object] | None = None) -> tuple[int, float]:
    """Write the page of a run to ``out``: a jsonl trace streamed (never held whole:
    its table's rows are spooled to a temporary file; with ``audio``, held whole, the
    sound of every utterance being made before the page), or a scenario run in-process
    (``switches``: its FA, EA, robot or policies changed; ``timing``: its utterances
    timed by the synthesiser; ``warn``: told what of the sound was shortened or left out,
    :func:`prima.show._sound.clips`). Returns the atomic behaviors started and the run's
    end (s)."""
    path = Path(path)
    rows: Iterable[Mapping[str, Any]]
    if path.suffix == ".jsonl":
        from prima.tracefile import read_trace

        rows = read_trace(path)
    else:
        rows = _run_rows(path, switches, timing)
    with tempfile.TemporaryFile("w+", encoding="utf-8") as spool:
        return _write(rows, out, scenario, title, spool, audio=audio, timing=timing,
                      warn=warn)


def _write(rows: Iterable[Mapping[str, Any]], out: TextIO, scenario: str | Path | None,
           title: str, spool: TextIO | None = None, *, audio: bool = False,
           timing: SynthesisedTiming | None = None,
           warn: Callable[[str], object] | None = None) -> tuple[int, float]:
    try:
        from prima.show._page import write_page as page
    except ImportError as exc:  # the plotting library is an optional extra
        raise PrimaError(f"prima show needs Plotly ({exc.name} is missing): "
                         "pip install 'prima[show]'") from exc
    from prima.show._model import build
    from prima.scenario import load_scenario

    world = load_scenario(scenario).map if scenario is not None else None
    sounds = ""
    if audio:
        from prima.show._sound import clips, elements

        rows = list(rows)  # (every utterance's sound is made before the page)
        sounds = elements(clips(rows, scenario, timing, warn))
    model = build(rows, spool)
    page(model, world, title, out, spool, sounds)
    return model.starts, model.timeline.end


# ------------------------------------------------------------ what prima live draws too

def _drawn() -> Any:
    """The page's module (Plotly's figures), or what is missing to make them."""
    try:
        return importlib.import_module("prima.show._page")
    except ImportError as exc:  # the plotting library is an optional extra
        raise PrimaError(f"prima show needs Plotly ({exc.name} is missing): "
                         "pip install 'prima[show]'") from exc


def map_figure(world: WorldMap | None, robot: _Pose | None,
               user: _Pose | None) -> dict[str, Any]:
    """The map as the page draws it, the robot and the user at these poses (x, y,
    heading): Plotly's JSON (``data``, ``layout``, ``config``), and which traces are the
    robot's and the user's markers (``robot``, ``user``), to move them."""
    from prima.timeline import Timeline

    page = _drawn()
    model = Model(Timeline(), [], robot=[(0.0, robot)] if robot else [],
                  user=[(0.0, user)] if user else [])
    fig, index = page.map_figure(model, world)
    return {**page.figure_json(fig), **index}


def digest(rows: Iterable[Mapping[str, Any]]) -> Model:
    """A run's trace lines (in trace order) digested for :func:`timeline_figure`, once for
    as many of its figures as are asked (the table's rows are not kept)."""
    from prima.show._model import build

    return build(rows, table_rows=False)


def timeline_figure(digested: Model, window: tuple[float, float] | None = None
                    ) -> dict[str, Any]:
    """The device timeline of a run (:func:`digest`), as the page draws it: Plotly's JSON
    (``data``, ``layout``, ``config``). With ``window`` (from, to: simulated seconds),
    only what is seen in it: the bars, waits and marks that overlap it, each whole (one
    begun before it too), and the rest laid out as the whole run's (its rows, its time
    axis's range, its legend): what a page draws there looks as the whole figure's does
    (but for the labels' size: Plotly sets them all at the size the tightest one needs,
    of the bars it has)."""
    page = _drawn()
    fig, _traces = page.timeline_figure(digested, window)
    return dict(page.figure_json(fig))


def drawing() -> str:
    """The script both pages draw with (``PrimaDraw``: a line's words, the table's rows,
    poses between samples, bubbles, markers)."""
    return str(_drawn().drawing())


def style() -> str:
    """The style both pages share."""
    return str(_drawn().style())
