"""Colour and widths on a terminal, plain text everywhere else: one module for every
command's tables and messages.

Whether a stream gets colour (:func:`wants_colour`), the terminal's width
(:func:`columns`), and :func:`layout`, which sets rows of cells in columns as wide
as their content. Words are escaped before they are coloured (:class:`Paint` passes
them through :func:`prima.escape.terminal`), so no colour ever lets a run's words
drive the terminal; without colour, :class:`Paint` returns its text as it is, and
what goes to a pipe or a file is the plain text it always was.

Imports nothing of PRIMA but :mod:`prima.escape` (any module may use it, but the
core's packages have no business with terminals).
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from typing import TextIO

from prima.escape import terminal
from prima.record import Record

__all__ = ["BOLD", "CYAN", "DIM", "GREEN", "PLAIN", "RED", "WHEN", "YELLOW", "Cell", "Paint",
           "columns", "is_terminal", "layout", "wants_colour"]

BOLD, DIM, RED, GREEN, YELLOW, CYAN = "1", "2", "31", "32", "33", "36"
"""SGR codes: the styles PRIMA uses (the terminal's own palette picks the shades)."""

WHEN = ("auto", "always", "never")
"""``--color`` values: ``auto`` (a terminal, unless the environment says otherwise)."""


def is_terminal(stream: object) -> bool:
    """Whether ``stream`` is a terminal (a closed or unusual stream is not)."""
    try:
        return bool(stream.isatty())  # type: ignore[attr-defined]
    except (AttributeError, ValueError, OSError):
        return False


def wants_colour(stream: object, when: str = "auto",
                 environ: Mapping[str, str] | None = None) -> bool:
    """Whether to colour what goes to ``stream``; the first of these that applies:

    ``--color always`` or ``never`` (``when``); ``NO_COLOR`` set and not empty: no;
    ``FORCE_COLOR`` set and not empty, or ``CLICOLOR_FORCE`` set and not ``0``: yes;
    ``TERM=dumb``: no; else: yes on a terminal, no to a pipe or a file.
    (The order Python's own tracebacks follow, with ``CLICOLOR_FORCE`` beside
    ``FORCE_COLOR``.)"""
    if when != "auto":
        return when == "always"
    env = os.environ if environ is None else environ
    if env.get("NO_COLOR"):
        return False
    if env.get("FORCE_COLOR") or env.get("CLICOLOR_FORCE", "0") not in ("", "0"):
        return True
    if env.get("TERM") == "dumb":
        return False
    return is_terminal(stream)


def columns(stream: TextIO) -> int | None:
    """The width of the terminal ``stream`` is (``COLUMNS`` first, as
    :func:`shutil.get_terminal_size` takes it), or None for a pipe or a file: what is
    not shown on a terminal is laid out from its content alone, the same every time."""
    if not is_terminal(stream):
        return None
    given = os.environ.get("COLUMNS", "")
    if given.isdigit() and int(given) > 0:
        return int(given)
    try:
        return os.get_terminal_size(stream.fileno()).columns
    except (OSError, ValueError, AttributeError):
        return shutil.get_terminal_size().columns


@dataclass(frozen=True, repr=False, eq=False)
class Paint(Record):
    """Colours text when ``on``: ``paint(text, RED, BOLD)``. The text is escaped
    first (:func:`~prima.escape.terminal`); off, it is returned as it is."""

    on: bool = False

    def __call__(self, text: str, *styles: str) -> str:
        if not self.on or not styles or not text:
            return text
        return f"\x1b[{';'.join(styles)}m{terminal(text)}\x1b[0m"


PLAIN = Paint()
"""No colour: a pipe, a file, a test."""


@dataclass(frozen=True, repr=False, eq=False)
class Cell(Record):
    """A table cell and its styles."""

    text: str
    styles: tuple[str, ...] = ()


def layout(rows: Sequence[Sequence[str | Cell]], *, right: Collection[int] = (),
           minimum: Sequence[int] = (), indent: str = "", sep: str | Sequence[str] = " ",
           paint: Paint = PLAIN) -> list[str]:
    """``rows`` of cells set in columns: each column as wide as its longest cell (and at
    least ``minimum[i]``), the columns in ``right`` aligned right, ``sep`` between two
    (or ``sep[i]`` after column ``i``); trailing spaces cut.
    Cells are escaped for a terminal (a name cannot break a row); widths are measured
    on the text alone, and the padding stays outside the colour, so colour never
    moves a column."""
    cells = [[c if isinstance(c, Cell) else Cell(c) for c in row] for row in rows]
    for row in cells:
        for i, cell in enumerate(row):
            row[i] = Cell(terminal(cell.text), cell.styles)
    count = max((len(row) for row in cells), default=0)
    widths = [max([len(row[i].text) for row in cells if i < len(row)]
                  + [minimum[i] if i < len(minimum) else 0]) for i in range(count)]
    seps = [sep] * count if isinstance(sep, str) else list(sep)
    out = []
    for row in cells:
        line = indent
        for i, cell in enumerate(row):
            pad = " " * (widths[i] - len(cell.text))
            painted = paint(cell.text, *cell.styles)
            line += (seps[i - 1] if i else "") + (pad + painted if i in right else painted + pad)
        out.append(line.rstrip())
    return out
