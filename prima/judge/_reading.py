"""Reading a trace file: every line checked, every bad one located."""

from __future__ import annotations

import json
import math
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

from prima.errors import Problem, Severity, TraceError

__all__ = ["Row", "as_rows", "load_trace"]

_EPS = 1e-6
"""Times in a trace are rounded to the millisecond: comparisons allow this much."""

Row = Mapping[str, Any]
"""One line of a trace, as its jsonl dict."""


_FIELD_TYPES: dict[str, tuple[type, ...]] = {
    "app": (str,), "ab": (int,), "tree": (int,), "command": (str,), "text": (str,),
    "reactive": (bool,), "reason": (str,), "action": (str,), "detail": (dict,),
    "devices": (list,), "command_ids": (list,), "before": (int,),
    "robot": (dict,), "user": (dict,),
}


def _check_row(row: object) -> str | None:
    """What is wrong with one decoded jsonl line (None: nothing)."""
    if not isinstance(row, dict):
        return "a trace line must be a JSON object"
    required: tuple[tuple[str, tuple[type, ...]], ...] = (
        ("t", (int, float)), ("seq", (int,)), ("kind", (str,)))
    for key, kinds in required:
        value = row.get(key)
        if value is None:
            return f"missing field '{key}'"
        if isinstance(value, bool) or not isinstance(value, kinds):
            return f"field '{key}' has the wrong type ({type(value).__name__})"
    if not math.isfinite(row["t"]) or row["t"] < 0:
        return f"field 't' must be a time from 0 up, not {row['t']}"
    for key, kinds in _FIELD_TYPES.items():
        value = row.get(key)
        if value is not None and (isinstance(value, bool) and bool not in kinds
                                  or not isinstance(value, kinds)):
            return f"field '{key}' has the wrong type ({type(value).__name__})"
    for key in ("robot", "user"):
        pose = row.get(key)
        if pose is not None and not all(
                isinstance(pose.get(k), (int, float)) and not isinstance(pose.get(k), bool)
                for k in ("x", "y", "heading")):
            return f"field '{key}' needs numbers x, y and heading"
    if not all(isinstance(d, str) for d in row.get("devices") or ()):
        return "field 'devices' must be a list of names"
    ids = row.get("command_ids") or ()
    if not all(isinstance(c, int) and not isinstance(c, bool) for c in ids):
        return "field 'command_ids' must be a list of numbers"
    return None


def load_trace(path: str | Path) -> list[dict[str, Any]]:
    """Read a jsonl trace file (``prima run --format jsonl``).

    Raises :class:`~prima.errors.TraceError` with every bad line located as
    ``file:line:col`` (at most 20; blank lines are skipped), or for an empty file.
    """
    path = Path(path)
    name = str(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        message = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise TraceError([Problem(name, 1, 1, Severity.ERROR,
                                  f"cannot read the trace: {message}")]) from exc
    rows: list[dict[str, Any]] = []
    problems: list[Problem] = []
    last_t = 0.0
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            row = json.loads(line)
        except json.JSONDecodeError as exc:
            problems.append(Problem(name, number, exc.colno, Severity.ERROR,
                                    f"not a JSON object: {exc.msg}"))
            continue
        wrong = _check_row(row)
        if wrong is None and row["t"] < last_t - _EPS:
            wrong = f"time goes backwards ({row['t']} after {last_t})"
        if wrong is not None:
            problems.append(Problem(name, number, 1, Severity.ERROR, wrong))
        else:
            last_t = row["t"]
            rows.append(row)
        if len(problems) >= 20:
            break
    if not rows and not problems:
        problems.append(Problem(name, 1, 1, Severity.ERROR, "the trace has no lines"))
    if problems:
        raise TraceError(problems)
    return rows


def as_rows(trace: Iterable[object]) -> Iterator[Row]:
    for line in trace:
        if isinstance(line, Mapping):
            yield line
        else:
            to_dict = getattr(line, "to_dict", None)
            if to_dict is None:
                raise TypeError(f"a trace line is a TraceLine or a dict, not {type(line).__name__}")
            yield to_dict()


