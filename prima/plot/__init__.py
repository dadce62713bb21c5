"""Pictures of a run for papers and pull requests: ``prima plot``.

Apart from the core: only ``prima plot`` imports it. :func:`timeline` turns a
run's jsonl records into the device timeline's data (plain Python, shared with
``prima show``: :mod:`prima.timeline`); drawing it
(:func:`save_timeline`) and animating a run (:func:`save_animation`) need
matplotlib, the ``plot`` extra (``pip install 'prima[plot]'``), which this
package imports only when asked to draw.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from prima.timeline import Bar, Mark, Span, Tick, Timeline, timeline
from prima.trace import Pose

if TYPE_CHECKING:
    from prima.sim import WorldMap

__all__ = ["FORMATS", "Bar", "Mark", "Pose", "Span", "Tick", "Timeline", "abbreviate",
           "save_animation", "save_timeline", "timeline"]

FORMATS = (".svg", ".png", ".pdf")
"""The timeline's picture formats, by file suffix; ``.gif`` is the animation."""


def abbreviate(command: str, parts: int = 2) -> str:
    """A grouped AB's name shortened: ``Speak+Gesture+PointByHand`` -> ``Speak+Gesture+...``."""
    names = command.split("+")
    if len(names) <= parts:
        return command
    return "+".join(names[:parts]) + "+..."


def save_timeline(tl: Timeline, path: str | Path, title: str = "") -> None:
    """Draw the device timeline and save it in the format of the file's suffix."""
    from prima.plot._draw import save_timeline as save

    save(tl, path, title)


def save_animation(tl: Timeline, path: str | Path, world: WorldMap | None = None, *,
                   title: str = "", step: float = 1.0, fps: float = 5.0) -> int:
    """Animate the run as a GIF; returns the number of frames."""
    from prima.plot._animate import save_animation as save

    return save(tl, path, world, title=title, step=step, fps=fps)
