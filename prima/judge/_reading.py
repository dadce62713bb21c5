"""Reading a trace: :mod:`prima.tracefile` reads every trace file, for every reader
(streamed, every line checked, every bad one located); the judge takes its lines as
jsonl dicts, TraceLine objects as the line each writes."""

from __future__ import annotations

from prima.tracefile import Row, load_trace, read_trace
from prima.tracefile import rows as as_rows

__all__ = ["Row", "as_rows", "load_trace", "read_trace"]
