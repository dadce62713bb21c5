"""Pictures of a run for papers and pull requests: ``prima plot``.

Apart from the core: only ``prima plot`` imports it. :func:`timeline` turns a
run's jsonl records into the device timeline's data (plain Python); drawing it
(:func:`save_timeline`) needs matplotlib, the ``plot`` extra
(``pip install 'prima[plot]'``), which this package imports only when asked
to draw.
"""

from __future__ import annotations

from pathlib import Path

from prima.plot._timeline import Bar, Pose, Span, Tick, Timeline, abbreviate, timeline

__all__ = ["FORMATS", "Bar", "Pose", "Span", "Tick", "Timeline", "abbreviate",
           "save_timeline", "timeline"]

FORMATS = (".svg", ".png", ".pdf")
"""The timeline's picture formats, by file suffix."""


def save_timeline(tl: Timeline, path: str | Path, title: str = "") -> None:
    """Draw the device timeline and save it in the format of the file's suffix."""
    from prima.plot._draw import save_timeline as save

    save(tl, path, title)

