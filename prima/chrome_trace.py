"""A run as a Chrome Trace Event Format file, for Perfetto and chrome://tracing.

``prima run --format chrome-trace`` writes the JSON Array Format: one event per
line, streamed as the run makes its trace lines, so a run cut short (Ctrl-C) still
loads (the format lets the closing ``]`` be missing). Three processes group the
tracks:

- ``devices`` (pid 1): one track per device, a complete event (``X``) per atomic
  behavior on each device it occupied, named by its Command and its words;
- ``applications`` (pid 2): one track per application, its atomic behaviors as
  async slices (``b``/``e``: an application's ABs may overlap), and its other
  decisions (suspend, resume, hold, cancel, cut) as instant events (``i``);
- ``world`` (pid 3): the events posted to the applications and what the user did,
  as instant events.

Times are microseconds of simulated time (the format's unit). A blended AB (the
blend policy) is drawn on its application's track, and on the device tracks only
where it is not blended: two slices of one device track must nest.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import TextIO

from prima.escape import json_line
from prima.timeline import blended_devices
from prima.trace import TraceLine

__all__ = ["ChromeTrace", "ChromeTraceWriter", "chrome_trace_events"]

DEVICES, APPS, WORLD = 1, 2, 3
_PROCESSES = ((DEVICES, "devices"), (APPS, "applications"), (WORLD, "world"))
_WORLD_TRACKS = {"event": 1, "user": 2}
_INSTANT_DECISIONS = frozenset({"suspend", "resume", "hold", "release", "cancel", "interrupt",
                                "failure", "budget", "load", "unload", "error"})


def _us(t: float) -> int:
    return round(t * 1_000_000)


class ChromeTrace:
    """Turns trace lines into trace events, one line at a time (``feed``), then the
    atomic behaviors still running at the end (``finish``)."""

    def __init__(self) -> None:
        self._tracks: dict[tuple[int, str], int] = {}
        self._open: dict[int, TraceLine] = {}
        self._t = 0.0

    def header(self) -> list[dict[str, object]]:
        """The processes' names (metadata events)."""
        return [{"name": "process_name", "ph": "M", "pid": pid, "tid": 0,
                 "args": {"name": name}} for pid, name in _PROCESSES]

    def _track(self, pid: int, name: str, out: list[dict[str, object]]) -> int:
        """The track (thread id) of ``name`` in process ``pid``, named on first use."""
        key = (pid, name)
        tid = self._tracks.get(key)
        if tid is None:
            tid = self._tracks[key] = len(self._tracks) + 1
            out.append({"name": "thread_name", "ph": "M", "pid": pid, "tid": tid,
                        "args": {"name": name}})
        return tid

    def feed(self, line: TraceLine) -> list[dict[str, object]]:
        """The events this line makes (an AB's slices come with its end)."""
        out: list[dict[str, object]] = []
        self._t = max(self._t, line.t)
        kind = line.kind.value
        if kind == "start" and line.ab is not None:
            self._open[line.ab] = line
            if line.app is not None:
                out.append(self._async("b", line, line.t, out))
        elif kind == "end" and line.ab is not None:
            start = self._open.pop(line.ab, None)
            if start is not None:
                out += self._slices(start, line.t, line)
        elif kind in _WORLD_TRACKS:
            name = f"{line.action or ''} {line.text or ''}".strip() if kind == "user" \
                else line.text or kind
            out.append(self._instant(WORLD, kind, name, line, out))
        elif kind in _INSTANT_DECISIONS and line.app is not None:
            name = f"{kind} {line.command or ''}".strip()
            out.append(self._instant(APPS, line.app, name, line, out))
        return out

    def finish(self) -> list[dict[str, object]]:
        """Slices for the atomic behaviors still running when the trace ended."""
        out: list[dict[str, object]] = []
        for start in list(self._open.values()):
            out += self._slices(start, self._t, None)
        self._open.clear()
        return out

    # ---------------------------------------------------------------- events
    @staticmethod
    def _name(line: TraceLine) -> str:
        name = line.command or "AB"
        return f'{name} "{line.text}"' if line.text else name

    def _args(self, start: TraceLine, end: TraceLine | None) -> dict[str, object]:
        args: dict[str, object] = {"ab": start.ab, "app": start.app, "tree": start.tree,
                                   "reason": start.reason, "seq": start.seq}
        if start.text:
            args["text"] = start.text
        if end is not None:
            args["end_reason"] = end.reason
            result = end.detail.get("result")
            if result is not None:
                args["result"] = result
        else:
            args["end_reason"] = "still running when the trace ended"
        return args

    def _async(self, ph: str, start: TraceLine, t: float,
               out: list[dict[str, object]], end: TraceLine | None = None) -> dict[str, object]:
        """An application track's slice begins (``b``: what it is) or ends (``e``: how it
        ended, which a viewer merges into the slice's arguments)."""
        tid = self._track(APPS, start.app or "?", out)
        event: dict[str, object] = {"name": self._name(start), "cat": "ab", "ph": ph,
                                    "id": start.ab, "pid": APPS, "tid": tid, "ts": _us(t)}
        args = self._args(start, end)
        if ph == "b":
            del args["end_reason"]  # not known yet: the end says it
        else:
            args = {k: v for k, v in args.items() if k in ("end_reason", "result")}
        event["args"] = args
        return event

    def _slices(self, start: TraceLine, t: float, end: TraceLine | None
                ) -> list[dict[str, object]]:
        out: list[dict[str, object]] = []
        blended = blended_devices(start.detail.get("over"))
        args = self._args(start, end)
        for device in start.devices or ():
            if device in blended:
                continue
            tid = self._track(DEVICES, device, out)
            out.append({"name": self._name(start), "cat": start.app or "ab", "ph": "X",
                        "pid": DEVICES, "tid": tid, "ts": _us(start.t),
                        "dur": max(0, _us(t) - _us(start.t)), "args": args})
        if start.app is not None:
            out.append(self._async("e", start, t, out, end))
        return out

    def _instant(self, pid: int, track: str, name: str, line: TraceLine,
                 out: list[dict[str, object]]) -> dict[str, object]:
        tid = self._track(pid, track, out)
        args: dict[str, object] = {"seq": line.seq}
        if line.reason:
            args["reason"] = line.reason
        if line.text and line.text != name:
            args["text"] = line.text
        return {"name": name, "cat": line.kind.value, "ph": "i", "s": "t", "pid": pid,
                "tid": tid, "ts": _us(line.t), "args": args}


def chrome_trace_events(lines: Iterable[TraceLine]) -> list[dict[str, object]]:
    """Every trace event of a finished run, in order (the JSON Array Format's items)."""
    builder = ChromeTrace()
    events = builder.header()
    for line in lines:
        events += builder.feed(line)
    events += builder.finish()
    return events


class ChromeTraceWriter:
    """Streams a run's trace events to ``to`` as its lines come (``write``), one JSON
    object per line; ``close`` adds the slices still open and the closing bracket.
    Cut short before ``close``, the file is still a loadable trace (the format
    allows the bracket to be missing)."""

    def __init__(self, to: TextIO) -> None:
        self._to = to
        self._builder = ChromeTrace()
        self._first = True
        to.write("[")
        self._put(self._builder.header())

    def _put(self, events: Iterable[dict[str, object]]) -> None:
        for event in events:
            self._to.write(("\n" if self._first else ",\n") + json_line(event))
            self._first = False

    def write(self, line: TraceLine) -> None:
        self._put(self._builder.feed(line))

    def close(self) -> None:
        self._put(self._builder.finish())
        self._to.write("\n]\n")
