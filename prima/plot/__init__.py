"""Pictures of a run for papers and pull requests: ``prima plot``.

Apart from the core: only ``prima plot`` imports it. :func:`timeline` turns a
run's jsonl records into the device timeline's data (plain Python, shared with
``prima show``: :mod:`prima.timeline`); drawing it
(:func:`save_timeline`) and animating a run (:func:`save_animation`) need
matplotlib, the ``plot`` extra (``pip install 'prima[plot]'``), which this
package imports only when asked to draw.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import TYPE_CHECKING

from prima.escape import terminal
from prima.plot._names import abbreviate
from prima.timeline import Bar, Mark, Span, Tick, Timeline, timeline
from prima.trace import Pose

if TYPE_CHECKING:
    from prima.sim import WorldMap

__all__ = ["FORMATS", "Bar", "Mark", "Pose", "Span", "Tick", "Timeline", "abbreviate", "plain",
           "save_animation", "save_timeline", "timeline"]

FORMATS = (".svg", ".png", ".pdf")
"""The timeline's picture formats, by file suffix; ``.gif`` is the animation."""


def _shown(text: str | None) -> str | None:
    return None if text is None else terminal(text)


def plain(tl: Timeline) -> Timeline:
    """``tl`` with every word as a picture draws it: control characters (which no font
    has) as escapes. (Nor is a ``$`` mathematics: the pictures are drawn under
    :data:`prima.escape.PLAIN_TEXT`.)"""
    t, replace = terminal, dataclasses.replace
    return replace(
        tl, devices=[t(d) for d in tl.devices], apps=[t(a) for a in tl.apps],
        bars=[replace(b, device=t(b.device), app=t(b.app), command=t(b.command),
                      text=_shown(b.text)) for b in tl.bars],
        spans=[replace(s, app=t(s.app), command=t(s.command), reason=t(s.reason),
                       holder=t(s.holder), devices=tuple(map(t, s.devices)))
               for s in tl.spans],
        marks=[replace(m, app=t(m.app), reason=t(m.reason), devices=tuple(map(t, m.devices)))
               for m in tl.marks],
        ticks=[replace(k, row=t(k.row), label=t(k.label), text=_shown(k.text),
                       action=t(k.action)) for k in tl.ticks])


def save_timeline(tl: Timeline, path: str | Path, title: str = "") -> None:
    """Draw the device timeline and save it in the format of the file's suffix."""
    from prima.plot._draw import save_timeline as save

    save(plain(tl), path, terminal(title))


def save_animation(tl: Timeline, path: str | Path, world: WorldMap | None = None, *,
                   title: str = "", step: float = 1.0, fps: float = 5.0) -> int:
    """Animate the run as a GIF; returns the number of frames."""
    from prima.plot._animate import save_animation as save

    return save(plain(tl), path, world, title=terminal(title), step=step, fps=fps)
