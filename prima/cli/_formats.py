"""The trace formats ``prima run`` writes: one table (:data:`FORMATS`) over one writer
protocol (:class:`TraceWriter`). A new format is one entry: its name, the suffix of
``--out`` that implies it, whether it writes a binary file of its own, the extra it
needs, and what opens its writer. What each writer needs is imported when it opens,
so that ``prima --help`` reads the table without importing any of them."""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Protocol, TextIO

from prima.cli._common import _between_lines, _missing_extra

if TYPE_CHECKING:
    from prima.run import Run
    from prima.term import Paint
    from prima.trace import TraceLine

__all__ = ["FORMATS", "Format", "Opening", "TraceWriter", "format_by_suffix", "format_usage"]


class TraceWriter(Protocol):
    """Where a run's trace goes, line by line as the run makes it."""

    def write(self, line: TraceLine) -> None: ...

    def close(self) -> None:
        """The run ended, or was interrupted: finish what the file needs whole."""


@dataclass(frozen=True)
class Opening:
    """What a format's writer is opened with: the run (its applications, its map), the
    ``--out`` file if any, the stream to write to (``--out`` opened, or standard output),
    the files the command closes when it ends, and the colour for a terminal."""

    run: Run
    out: str | None
    to: TextIO
    files: contextlib.ExitStack
    paint: Paint


@dataclass(frozen=True)
class Format:
    """One trace format of ``prima run --format``."""

    name: str
    suffix: str | None
    """The extension of ``--out`` that implies it when ``--format`` is not given."""
    opens: Callable[[Opening], TraceWriter]
    binary: bool = False
    """It writes a file of its own (``--out`` needed), not text to a stream."""
    extra: tuple[str, str, str] | None = None
    """(module, library, extra) it needs installed."""


class _Text:
    """The table the thesis' figures draw (:class:`prima.trace.TextTrace`)."""

    def __init__(self, opening: Opening) -> None:
        from prima.trace import TextTrace

        self._to = opening.to
        self._text = TextTrace(opening.run.app_names(), paint=opening.paint)
        print(self._text.header, file=self._to)

    def write(self, line: TraceLine) -> None:
        row = self._text.row(line)
        if row is not None:
            self._to.write(row + "\n")

    def close(self) -> None:
        pass


class _Jsonl:
    """One JSON object per line (:func:`prima.trace.jsonl_row`)."""

    def __init__(self, opening: Opening) -> None:
        from prima.trace import jsonl_row

        self._to = opening.to
        self._row = jsonl_row

    def write(self, line: TraceLine) -> None:
        self._to.write(self._row(line))

    def close(self) -> None:
        pass


class _ChromeTrace:
    """The Trace Event Format, for Perfetto (:class:`prima.chrome_trace.ChromeTraceWriter`)."""

    def __init__(self, opening: Opening) -> None:
        from prima.chrome_trace import ChromeTraceWriter

        self._chrome = ChromeTraceWriter(opening.to)
        self._ctrl_c = opening.files.enter_context(_between_lines())

    def write(self, line: TraceLine) -> None:
        self._chrome.write(line)
        self._ctrl_c.check()  # Ctrl-C lands between two lines: the file stays whole

    def close(self) -> None:
        self._chrome.close()  # the slices under way end where the run stopped


class _Mcap:
    """A recording for Foxglove (:class:`prima.mcap.Recorder`), a binary file of its own."""

    def __init__(self, opening: Opening) -> None:
        from prima.mcap import Recorder

        if opening.out is None:  # (format_usage says so first)
            raise ValueError("--format mcap writes a binary file: give --out FILE")
        self._recorder = opening.files.enter_context(Recorder(opening.out,
                                                              opening.run.scenario.map))
        self._ctrl_c = opening.files.enter_context(_between_lines())

    def write(self, line: TraceLine) -> None:
        self._recorder.write(line)
        self._ctrl_c.check()  # Ctrl-C lands between two lines: the file is finished whole

    def close(self) -> None:
        pass  # (the recorder finishes the file as the command's files close)


FORMATS: dict[str, Format] = {f.name: f for f in (
    Format("text", None, _Text),
    Format("jsonl", ".jsonl", _Jsonl),
    Format("chrome-trace", ".json", _ChromeTrace),
    Format("mcap", ".mcap", _Mcap, binary=True, extra=("foxglove", "foxglove-sdk", "mcap")),
)}
"""Every trace format, by name; the first is the default."""


def format_by_suffix(out: str | None) -> str:
    """The format ``--out``'s extension says (as its reader would read it), else text."""
    suffix = Path(out).suffix.lower() if out else ""
    return next((f.name for f in FORMATS.values() if f.suffix == suffix),
                next(iter(FORMATS)))


def format_usage(name: str, out: str | None) -> str | None:
    """What a format needs besides: a file to write (``--out -`` is standard output, no
    file), an extra installed."""
    chosen = FORMATS[name]
    if chosen.binary and (not out or out == "-"):
        return (f"--format {name} writes a binary file: give --out FILE"
                + (", not - (standard output)" if out == "-" else ""))
    return _missing_extra(*chosen.extra) if chosen.extra else None
