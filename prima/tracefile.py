"""Reading a jsonl trace back: one reader for every reader (``prima judge``, ``show``,
``plot``, the timeline, the Chrome trace, golden checks).

A trace file may be damaged (cut short, edited by hand) or forged (written by
someone else entirely). :func:`read_trace` streams it line by line, so a trace of
a million lines is never held as text, and checks every line before a reader
sees it: each field a reader uses has the type it expects, so what reads a
trace never fails on a value of the wrong type. Bad lines are reported located
(``file:line:col``) as one :class:`~prima.errors.TraceError` once the file is
read (at most :data:`MAX_PROBLEMS` of them: reading stops there). Lines are
split at ``\\n`` only (a ``\\r`` before it is allowed), never at the other
characters ``str.splitlines`` takes for line ends: a writer escapes those
(:func:`prima.escape.json_line`) and a reader does not split a line there. Numbers
are bounded where they are read: a whole number of more than :data:`MAX_DIGITS`
digits (or, for ``t`` and ``seq``, beyond 2^63) is a located error, never a crash
of the reader that would turn it into a float or a text. At most :data:`MAX_RUNNING`
atomic behaviors run at once (a start line past them is a located error): what reads a
trace works on the ABs running at each line, and a forged trace of thousands running at
once would cost it time and memory by their square.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any, TextIO

from prima.errors import Problem, Severity, TraceError

__all__ = ["MAX_DIGITS", "MAX_LINE", "MAX_NUMBER", "MAX_PROBLEMS", "MAX_RUNNING", "Row",
           "bounded_lines", "check_row", "load_trace", "read_trace", "rows"]

Row = dict[str, Any]
"""One line of a trace, as its jsonl dict: a dict, and its ``detail``, ``robot`` and
``user`` dicts too, as :func:`read_trace` yields it (:func:`check_row`) and a run makes
it. (A dict, not any mapping: the compiled build reads a dict's fields directly, where
it would call a mapping's ``get`` as a method, the judge's most frequent call.)"""

MAX_PROBLEMS = 20
"""Bad lines reported before reading stops."""

MAX_LINE = 1 << 20
"""The longest trace line read, in characters (1 MiB; a run's longest is a few kB)."""

MAX_DIGITS = 19
"""The most digits a whole number in a trace has (2^63 has 19): a longer one is refused
where it is read, located, before any reader turns it into a float or a text."""

MAX_NUMBER = 64
"""The most characters of a number with a fraction or an exponent in a trace."""

MAX_RUNNING = 64
"""The most atomic behaviors a trace has running at once (started, not yet ended): a
robot runs at most one on each of its devices, two where the blend policy shares one."""

_LARGEST = 2**63

_EPS = 1e-6
"""Times are rounded to the millisecond: a time this much earlier is not earlier."""

_FIELD_TYPES: dict[str, tuple[type, ...]] = {
    "app": (str,), "ab": (int,), "tree": (int,), "command": (str,), "text": (str,),
    "reactive": (bool,), "reason": (str,), "action": (str,), "detail": (dict,),
    "devices": (list,), "command_ids": (list,), "before": (int,),
    "robot": (dict,), "user": (dict,),
}
"""The optional fields of a line and their types (a bool is not a number here)."""

_DETAIL_TYPES: dict[str, tuple[type, ...]] = {
    "command_id": (int,), "iteration": (int,), "precedes": (int,), "heard": (bool,),
    "dropped": (str, int, bool), "result": (str,), "error": (str,), "spoken": (str,),
    "interrupt": (str,), "over": (str,), "args": (str,), "document": (str,), "role": (str,),
    "to": (str,), "place": (str,), "kind": (str,), "goal": (str,), "toward": (str,),
    "unspoken": (str,), "at": (str,), "cuttable": (bool,), "face_user": (bool,),
    "words_start": (int, float), "words_end": (int, float),
}
"""Details a reader uses, and their types; any other detail is a JSON scalar."""


def _number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) \
        and math.isfinite(value)


def _typed(value: object, kinds: tuple[type, ...]) -> bool:
    return (bool in kinds or not isinstance(value, bool)) and isinstance(value, kinds)


def _check_detail(detail: Mapping[str, object]) -> str | None:
    for key, value in detail.items():
        kinds = _DETAIL_TYPES.get(key)
        if value is None:
            continue
        if kinds is not None and not _typed(value, kinds):
            return f"detail '{key}' has the wrong type ({type(value).__name__})"
        if kinds is None and not isinstance(value, (str, int, float, bool)):
            return f"detail '{key}' must be a text, a number or true/false"
        if isinstance(value, float) and not math.isfinite(value):
            return f"detail '{key}' must be a finite number"
    return None


def check_row(row: object) -> str | None:
    """What is wrong with one decoded jsonl line (None: nothing)."""
    if not isinstance(row, dict):
        return "a trace line must be a JSON object"
    required: tuple[tuple[str, tuple[type, ...]], ...] = (
        ("t", (int, float)), ("seq", (int,)), ("kind", (str,)))
    for key, kinds in required:
        value = row.get(key)
        if value is None:
            return f"missing field '{key}'"
        if not _typed(value, kinds):
            return f"field '{key}' has the wrong type ({type(value).__name__})"
    if not math.isfinite(row["t"]) or row["t"] < 0:
        return f"field 't' must be a time from 0 up, not {row['t']}"
    for key, kinds in _FIELD_TYPES.items():
        value = row.get(key)
        if value is not None and not _typed(value, kinds):
            return f"field '{key}' has the wrong type ({type(value).__name__})"
    for key in ("robot", "user"):
        pose = row.get(key)
        if pose is not None and not all(_number(pose.get(k)) for k in ("x", "y", "heading")):
            return f"field '{key}' needs numbers x, y and heading"
    if not all(isinstance(d, str) for d in row.get("devices") or ()):
        return "field 'devices' must be a list of names"
    ids = row.get("command_ids") or ()
    if not all(_typed(c, (int,)) for c in ids):
        return "field 'command_ids' must be a list of numbers"
    return _check_detail(row.get("detail") or {})


def _problem(name: str, line: int, col: int, message: str) -> Problem:
    return Problem(name, line, col, Severity.ERROR, message)


def read_trace(path: str | Path) -> Iterator[dict[str, Any]]:
    """The lines of a jsonl trace file (``prima run --format jsonl``), checked, one at
    a time (blank lines skipped).

    Once the file is read, raises :class:`~prima.errors.TraceError` with every bad
    line located as ``file:line:col`` (the bad lines are not yielded), or for a file
    that cannot be read or has no lines.
    """
    path = Path(path)
    name = str(path)
    problems: list[Problem] = []
    last_t = 0.0
    count = 0
    running: set[int] = set()
    try:
        with path.open(encoding="utf-8", newline="\n") as lines:
            for number, line in enumerate(bounded_lines(lines, MAX_LINE), start=1):
                if line is None:
                    problems.append(_problem(name, number, 1, "the line is longer than "
                                                              f"{MAX_LINE:,} characters"))
                elif line.strip():
                    row, wrong, col = _decode(line.removesuffix("\n").removesuffix("\r"))
                    if wrong is None and row["t"] < last_t - _EPS:
                        wrong = f"time goes backwards ({row['t']} after {last_t})"
                    if wrong is None:
                        wrong = _running(row, running)
                    if wrong is not None:
                        problems.append(_problem(name, number, col, wrong))
                    else:
                        last_t = row["t"]
                        count += 1
                        yield row
                if len(problems) >= MAX_PROBLEMS:
                    break
    except (OSError, UnicodeDecodeError) as exc:
        message = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        problems.append(_problem(name, 1, 1, f"cannot read the trace: {message}"))
    if not count and not problems:
        problems.append(_problem(name, 1, 1, "the trace has no lines"))
    if problems:
        raise TraceError(problems)


def bounded_lines(file: TextIO, limit: int) -> Iterator[str | None]:
    """The file's lines, read as they are asked for; None for one longer than ``limit``
    characters, which is read past a piece at a time, never held whole (a file of
    gigabytes with no line break, ``/dev/zero``)."""
    while line := file.readline(limit + 1):
        if len(line) <= limit:
            yield line
            continue
        while not line.endswith("\n") and (line := file.readline(limit)):
            pass
        yield None


def _running(row: Row, running: set[int]) -> str | None:
    """Keep ``running`` (the ABs started and not yet ended) up to date with a checked line;
    what is wrong with a start line past :data:`MAX_RUNNING` of them."""
    ab = row.get("ab")
    if not isinstance(ab, int):
        return None
    if row["kind"] == "start" and ab not in running:
        if len(running) >= MAX_RUNNING:
            return (f"more than {MAX_RUNNING} atomic behaviors running at once (a robot runs "
                    "one on each of its devices)")
        running.add(ab)
    elif row["kind"] == "end":
        running.discard(ab)
    return None


class _Unbounded(ValueError):
    """A number in a line beyond what a trace holds (:data:`MAX_DIGITS`)."""

    def __init__(self, text: str, message: str) -> None:
        super().__init__(message)
        self.text = text


def _whole(text: str) -> int:
    """A JSON whole number, read only if it is of at most :data:`MAX_DIGITS` digits."""
    digits = len(text.lstrip("-"))
    if digits > MAX_DIGITS:
        raise _Unbounded(text, f"a whole number of {digits:,} digits: a trace's have at most "
                               f"{MAX_DIGITS}")
    return int(text)


def _decimal(text: str) -> float:
    """A JSON number with a fraction or an exponent, read only if it is of at most
    :data:`MAX_NUMBER` characters (a float's value is bounded; its text is not)."""
    if len(text) > MAX_NUMBER:
        raise _Unbounded(text, f"a number written with {len(text):,} characters: a trace's "
                               f"have at most {MAX_NUMBER}")
    return float(text)


def _decode(line: str) -> tuple[Any, str | None, int]:
    """A line's JSON value, what is wrong with it, and where."""
    try:
        row = json.loads(line, parse_int=_whole, parse_float=_decimal)
    except json.JSONDecodeError as exc:
        return None, f"not a JSON object: {exc.msg}", exc.colno
    except RecursionError:
        return None, "not a JSON object: nested too deep", 1
    except _Unbounded as exc:
        return None, str(exc), line.find(exc.text) + 1
    except ValueError as exc:  # (whatever else json's number reading refuses)
        return None, f"not a JSON object: {exc}", 1
    if isinstance(row, dict) and any(_too_large(row.get(key)) for key in ("t", "seq")):
        return row, "fields 't' and 'seq' must be at most 2^63", 1
    return row, check_row(row), 1


def _too_large(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and abs(value) > _LARGEST


def load_trace(path: str | Path) -> list[dict[str, Any]]:
    """Every line of a jsonl trace file, checked (:func:`read_trace`), as a list."""
    return list(read_trace(path))


def rows(trace: Iterable[object]) -> Iterator[Row]:
    """A trace's lines as jsonl dicts (:data:`Row`): TraceLine objects as the line each
    writes, dicts as they are, other mappings as dicts (their mappings too)."""
    for line in trace:
        if type(line) is dict:  # (a run's rows: no abstract class asked)
            yield line
        elif isinstance(line, Mapping):
            yield {key: dict(value) if isinstance(value, Mapping) else value
                   for key, value in line.items()}
        else:
            to_dict = getattr(line, "to_dict", None)
            if to_dict is None:
                raise TypeError(f"a trace line is a TraceLine or a dict, not {type(line).__name__}")
            yield to_dict()
