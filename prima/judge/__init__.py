"""Naturalness, measured: what a user would notice, computed from a trace alone.

The thesis judged naturalness by showing videos to people; :func:`judge`
measures the same things on every jsonl trace (docs/rules.md section 8), one
measure per entry of :data:`MEASURES`: late and unheard reactions, talking
unfaced, leaving while talking, resumed elsewhere, split exchanges, silences,
stuck applications. Every finding names whose it is (the application, its
atomic behavior, and where its document asks for it).

Every definition is in ``docs/judging.md``. One pass over the trace, plus work
proportional to the reactions and atomic behaviors it holds: the cost is linear
in the trace's length. A trace is :class:`~prima.trace.TraceLine` objects or the
dicts of its jsonl form (:func:`load_trace` reads a file); both are judged
alike (a TraceLine is judged as the jsonl line it writes).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from prima.judge._thresholds import LIMITS, PARAMETERS, Limit, Parameter, Thresholds

if TYPE_CHECKING:
    from prima.judge._findings import (
        BargeIn,
        Blame,
        Elsewhere,
        Finding,
        Ignored,
        Leaving,
        Reaction,
        Recovery,
        Silence,
        Split,
        Stuck,
        Unfaced,
    )
    from prima.judge._judging import Judging, find_scenarios, judge, judge_file
    from prima.judge._measures import MEASURES, Measure, measure, registered
    from prima.judge._reading import load_trace
    from prima.judge._report import Report, format_summary, format_table

__all__ = ["LIMITS", "MEASURES", "PARAMETERS", "BargeIn", "Blame", "Elsewhere", "Finding",
           "Ignored", "Judging", "Leaving", "Limit", "Measure", "Parameter", "Reaction",
           "Recovery", "Report", "Silence", "Split", "Stuck", "Thresholds", "Unfaced",
           "find_scenarios", "format_summary", "format_table", "judge", "judge_file",
           "load_trace", "measure", "registered"]

_WHERE = {
    **dict.fromkeys(("BargeIn", "Blame", "Elsewhere", "Finding", "Ignored", "Leaving",
                     "Reaction", "Recovery", "Silence", "Split", "Stuck", "Unfaced"),
                    "_findings"),
    **dict.fromkeys(("Judging", "find_scenarios", "judge", "judge_file"), "_judging"),
    **dict.fromkeys(("MEASURES", "Measure", "measure", "registered"), "_measures"),
    "load_trace": "_reading",
    **dict.fromkeys(("Report", "format_summary", "format_table"), "_report"),
}


def __getattr__(name: str) -> object:
    """The judge itself is imported when first used: ``prima --help`` and tab completion
    read only the thresholds (:mod:`._thresholds`), which make the commands' options."""
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
