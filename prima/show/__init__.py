"""``prima show``: a run as one self-contained HTML page, to watch and to question.

The page draws the map (walls, places, areas) with the robot and the user
moving and the words being spoken in bubbles; below it a timeline, one row per
device, each atomic behavior a bar coloured by its application and labelled by
its Command, suspensions and holds hatched, releases, cancels and cuts marked
(the digest ``prima plot`` draws too: :mod:`prima.timeline`); below that the
trace table.
One playhead drives all three. Plotly draws the map and the timeline (its
JavaScript is inlined: the page works offline, from ``file://``); a small
player script moves the playhead.

A viewer, apart from the core: only ``prima show`` imports it, and it needs
the ``show`` extra (``pip install 'prima[show]'``).
"""

from __future__ import annotations

import io
import tempfile
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any, TextIO

from prima.errors import PrimaError

if TYPE_CHECKING:
    from prima.run import Switches

__all__ = ["read_rows", "render", "write_page"]


def read_rows(path: str | Path, switches: Switches | None = None) -> list[dict[str, Any]]:
    """A run's rows: a jsonl trace read (located errors), or a scenario run in-process
    (``switches``: its FA, EA, robot or policies changed)."""
    path = Path(path)
    if path.suffix == ".jsonl":
        from prima.tracefile import load_trace

        return load_trace(path)
    from prima.run import Run

    options = switches.run_options() if switches else {}
    return [line.to_dict() for line in Run(path, **options).run()]


def render(rows: Iterable[Mapping[str, Any]], scenario: str | Path | None = None,
           title: str = "run") -> str:
    """The page of a run whose trace lines are ``rows``; the map is ``scenario``'s (if any)."""
    out = io.StringIO()
    _write(rows, out, scenario, title)
    return out.getvalue()


def write_page(path: str | Path, out: TextIO, scenario: str | Path | None = None,
               title: str = "run", switches: Switches | None = None) -> tuple[int, float]:
    """Write the page of a run to ``out``: a jsonl trace streamed (never held whole:
    its table's rows are spooled to a temporary file), or a scenario run in-process
    (``switches``: its FA, EA, robot or policies changed). Returns the atomic
    behaviors started and the run's end (s)."""
    path = Path(path)
    if path.suffix == ".jsonl":
        from prima.tracefile import read_trace

        rows: Iterable[Mapping[str, Any]] = read_trace(path)
    else:
        from prima.run import Run

        options = switches.run_options() if switches else {}
        rows = (line.to_dict() for line in Run(path, **options).run())
    with tempfile.TemporaryFile("w+", encoding="utf-8") as spool:
        return _write(rows, out, scenario, title, spool)


def _write(rows: Iterable[Mapping[str, Any]], out: TextIO, scenario: str | Path | None,
           title: str, spool: TextIO | None = None) -> tuple[int, float]:
    try:
        from prima.show._page import write_page as page
    except ImportError as exc:  # the plotting library is an optional extra
        raise PrimaError(f"prima show needs Plotly ({exc.name} is missing): "
                         "pip install 'prima[show]'") from exc
    from prima.show._model import build
    from prima.sim import load_scenario

    world = load_scenario(scenario).map if scenario is not None else None
    model = build(rows, spool)
    page(model, world, title, out, spool)
    return model.starts, model.timeline.end
