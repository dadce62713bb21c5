"""A results file's lines read back: bounded JSON, then each record's fields checked.

A results file is a user's file like any other input: resumed, it may have been
edited, damaged or forged. Each line is decoded within bounds (at most
:data:`MAX_LINE` bytes, :data:`MAX_DEPTH` levels of arrays and objects, numbers of
at most :data:`MAX_DIGITS` digits and below :data:`MAX_NUMBER` in size, no NaN or
Infinity) and each record is checked against the shape a worker writes
(:func:`record_shape`), so what is wrong is said once, naming the field
(``counts.late``), and never as an exception of the code that reads the records.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from prima.judge import MEASURES

if TYPE_CHECKING:
    from prima.batch._work import Analysis

__all__ = ["ANY", "MAX_DEPTH", "MAX_DIGITS", "MAX_LINE", "MAX_NUMBER", "Nullable", "Shape",
           "Unreadable", "decode", "field_column", "record_shape", "shape_problem", "shown"]

MAX_LINE = 1 << 24
"""The longest line (bytes) a results file may have: 16 MiB (a header of many jobs)."""
MAX_DEPTH = 16
"""The most arrays and objects nested in one line (a record nests four)."""
MAX_DIGITS = 16
"""The most digits a whole number may have."""
MAX_NUMBER = 1e15
"""Numbers are below this in size (a count, a time in seconds)."""


class Unreadable(ValueError):
    """A line that is no JSON within the bounds; ``col`` is where (1-based)."""

    def __init__(self, message: str, col: int = 1) -> None:
        super().__init__(message)
        self.col = col


@dataclass(frozen=True)
class _Unusable:
    """A number too large, or NaN or Infinity, as written (said where its field is read)."""

    text: str

    def __str__(self) -> str:
        return self.text if len(self.text) <= 20 else self.text[:17] + "..."


def _integer(text: str) -> int | _Unusable:
    return int(text) if len(text.lstrip("-")) <= MAX_DIGITS else _Unusable(text)


def _real(text: str) -> float | _Unusable:
    value = float(text)
    return value if math.isfinite(value) and abs(value) < MAX_NUMBER else _Unusable(text)


_STRING = re.compile(r'"(?:[^"\\]|\\.)*"?')
_BRACKET = re.compile(r"[\[\]{}]")


def _too_deep(text: str) -> int:
    """Where ``text`` nests arrays and objects more than :data:`MAX_DEPTH` deep (its
    1-based column), or 0. Strings are skipped (their brackets are text)."""
    flat = _STRING.sub(lambda m: "x" * len(m.group()), text)
    depth = 0
    for found in _BRACKET.finditer(flat):
        depth += 1 if found.group() in "[{" else -1
        if depth > MAX_DEPTH:
            return found.start() + 1
    return 0


def decode(raw: bytes) -> Any:
    """One line's JSON value, bounded. Raises :class:`Unreadable` for a line that is too
    long, not UTF-8, nested too deep or not JSON."""
    if len(raw) > MAX_LINE:
        raise Unreadable(f"the line is longer than {MAX_LINE:,} bytes")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise Unreadable(f"not UTF-8 (byte {exc.start + 1})") from None
    deep = _too_deep(text)
    if deep:
        raise Unreadable(f"not a JSON object: nested more than {MAX_DEPTH} levels deep", deep)
    try:
        return json.loads(text, parse_int=_integer, parse_float=_real, parse_constant=_Unusable)
    except json.JSONDecodeError as exc:
        raise Unreadable(f"not a JSON object: {exc.msg}", exc.colno) from None


def shown(value: Any) -> str:
    """A decoded value, briefly, as JSON (a number too large as written)."""
    text = json.dumps(value, default=str)
    return text if len(text) <= 80 else text[:77] + "..."


# ---------------------------------------------------------------------------- shapes

class _Any:
    """Any value: a field that is never read."""

    def __repr__(self) -> str:
        return "ANY"


ANY = _Any()
"""The shape of any value."""


@dataclass(frozen=True)
class Nullable:
    """A shape that may also be ``null``."""

    shape: Any


Shape = Any
"""What a value must be: ``int`` (a whole number from 0), ``float`` (a number), ``str``,
``bool``, ``True`` (exactly true), ``[S]`` (an array of S), ``(S1, S2, ...)`` (an array of
those, in order), ``{key: S}`` (an object of exactly those keys), :class:`Nullable`."""

_WHAT = {int: f"a whole number from 0 to {MAX_NUMBER:,.0f}", float: "a number",
         str: "a text", bool: "true or false"}


def _path(where: str, key: str | int) -> str:
    return f"{where}[{key}]" if isinstance(key, int) else f"{where}.{key}" if where else key


def shape_problem(value: Any, shape: Shape, where: str = "") -> tuple[str, str] | None:
    """What is wrong with ``value`` for ``shape``: (the field, as ``counts.late`` or
    ``failures[0].app``, and what is wrong), or None."""
    if shape is ANY:
        return None
    if isinstance(shape, Nullable):
        return None if value is None else shape_problem(value, shape.shape, where)
    if isinstance(value, _Unusable):
        if value.text.lstrip("-") in ("NaN", "Infinity"):
            return where, f"is {value}, not a number"
        return where, f"is {value}: too large a number (below {MAX_NUMBER:,.0f})"
    if shape is True:
        return None if value is True else (where, f"must be true, not {shown(value)}")
    if isinstance(shape, type):
        fits = isinstance(value, shape) and not (shape is not bool and isinstance(value, bool))
        if shape is float:
            fits = isinstance(value, (int, float)) and not isinstance(value, bool)
        if shape is int:
            fits = fits and 0 <= value < MAX_NUMBER
        return None if fits else (where, f"must be {_WHAT[shape]}, not {shown(value)}")
    if isinstance(shape, (list, tuple)):
        if not isinstance(value, list):
            return where, f"must be an array, not {shown(value)}"
        if isinstance(shape, tuple) and len(value) != len(shape):
            return where, f"must be an array of {len(shape)}, not {len(value)}"
        shapes = shape if isinstance(shape, tuple) else [shape[0]] * len(value)
        for i, (item, inner) in enumerate(zip(value, shapes, strict=True)):
            wrong = shape_problem(item, inner, _path(where, i))
            if wrong is not None:
                return wrong
        return None
    return _object_problem(value, shape, where)


def _object_problem(value: Any, shape: Mapping[str, Shape], where: str) -> tuple[str, str] | None:
    if not isinstance(value, dict):
        return where, f"must be an object, not {shown(value)}"
    for key, inner in shape.items():
        if key not in value:
            return _path(where, key), "is missing"
        wrong = shape_problem(value[key], inner, _path(where, key))
        if wrong is not None:
            return wrong
    extra = next((k for k in value if k not in shape), None)
    return None if extra is None else (_path(where, extra), "is not a field of this record")


def record_shape(found: Mapping[str, Any], analysis: Analysis | None) -> Mapping[str, Shape]:
    """The shape of a run's record as a worker writes it: lost (``"lost": true``), failed
    (its ``error``; what else it holds is never read), or judged (the judge's counts and
    times, and what the job's ``analysis`` says, in the analysis' own shape)."""
    if "lost" in found:
        return {"job": int, "run": int, "lost": True}
    if "error" in found:
        return {"job": int, "run": int, "error": str,
                **{k: ANY for k in found if k not in ("job", "run", "error")}}
    shape: dict[str, Shape] = {
        "job": int, "run": int, "end": float, "reactions": int,
        "counts": {m.key: int for m in MEASURES},
        "worst_lateness": Nullable(float), "worst_latency": Nullable(float), "breaches": [str]}
    if analysis is not None:
        shape[analysis.key] = analysis.shape
    return shape


def field_column(line: str, field: str) -> int:
    """Where ``field`` (``counts.late``, ``failures[0].app``) is written in a line: the
    column of its innermost key (1-based), or 1 when it cannot be found."""
    col, start = 1, 0
    for key in re.findall(r"[^.\[\]]+", field):
        if key.isdigit():
            continue
        at = line.find(json.dumps(key), start)
        if at < 0:
            return col
        col, start = at + 1, at + 1
    return col
