"""``prima run --format chrome-trace``: the Trace Event Format (the JSON Array
Format of Google's "Trace Event Format" document), one track per device and per
application, so that a run opens in Perfetto or chrome://tracing."""

from __future__ import annotations

import io
import json
from collections import Counter
from pathlib import Path
from typing import Any

from prima.chrome_trace import chrome_trace_events
from prima.cli import main
from prima.run import Run

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_03 = ROOT / "scenarios" / "thesis" / "sample-03.xml"

PHASES = {"M", "X", "b", "e", "i"}


def check_event(event: dict[str, Any]) -> None:
    """One event against the format's documented structure."""
    assert isinstance(event["name"], str) and event["name"]
    assert event["ph"] in PHASES
    assert isinstance(event["pid"], int) and isinstance(event["tid"], int)
    if event["ph"] == "M":
        assert event["name"] in ("process_name", "thread_name")
        assert isinstance(event["args"]["name"], str)
        return
    assert isinstance(event["ts"], int) and event["ts"] >= 0  # microseconds
    if event["ph"] == "X":
        assert isinstance(event["dur"], int) and event["dur"] >= 0
    if event["ph"] in ("b", "e"):
        assert isinstance(event["id"], int) and event["cat"]
    if event["ph"] == "i":
        assert event["s"] in ("g", "p", "t")


def test_sample_03_is_valid_trace_event_format_with_a_track_per_device() -> None:
    out = io.StringIO()
    assert main(["run", str(SAMPLE_03), "--format", "chrome-trace"], out=out,
                err=io.StringIO()) == 0
    events = json.loads(out.getvalue())
    assert isinstance(events, list)
    for event in events:
        check_event(event)
    tracks = {(e["pid"], e["tid"]): e["args"]["name"] for e in events
              if e["ph"] == "M" and e["name"] == "thread_name"}
    processes = {e["pid"]: e["args"]["name"] for e in events
                 if e["ph"] == "M" and e["name"] == "process_name"}
    assert processes == {1: "devices", 2: "applications", 3: "world"}
    lines = Run(SAMPLE_03).run()
    starts = [ln for ln in lines if ln.kind.value == "start"]
    devices = {d for ln in starts for d in ln.devices or ()}
    assert {name for (pid, _t), name in tracks.items() if pid == 1} == devices
    assert {name for (pid, _t), name in tracks.items() if pid == 2} == \
        {ln.app for ln in starts}
    # every AB is a slice on each of its devices' tracks, and one on its app's track
    slices = Counter((e["args"]["ab"], tracks[(e["pid"], e["tid"])]) for e in events
                     if e["ph"] == "X")
    assert slices == Counter((ln.ab, d) for ln in starts for d in ln.devices or ())
    begins = Counter(e["id"] for e in events if e["ph"] == "b")
    ends = Counter(e["id"] for e in events if e["ph"] == "e")
    assert begins == ends == Counter(ln.ab for ln in starts)
    # slices on one device track never overlap (the viewers need them nested)
    for (pid, tid), _name in tracks.items():
        spans = sorted((e["ts"], e["ts"] + e["dur"]) for e in events
                       if e["ph"] == "X" and (e["pid"], e["tid"]) == (pid, tid))
        assert all(a[1] <= b[0] for a, b in zip(spans, spans[1:], strict=False))
    touches = [e for e in events if e["ph"] == "i" and e["name"].startswith("touch")]
    assert touches and all(processes[e["pid"]] == "world" for e in touches)


def test_a_trace_cut_short_still_loads_and_open_abs_end_with_it() -> None:
    lines = [ln for ln in Run(SAMPLE_03).run() if ln.t <= 30.0]
    events = chrome_trace_events(lines)
    running = [e for e in events if e["ph"] == "X"
               and e["args"]["end_reason"] == "still running when the trace ended"]
    assert running  # the move under way at 30 s, ended with the trace
    assert all(e["ts"] + e["dur"] <= 30_000_000 for e in running)


def test_application_slices_say_how_they_ended() -> None:
    from prima.run import Run

    events = chrome_trace_events(Run(ROOT / "scenarios" / "thesis" / "sample-03.xml").run())
    ends = [e for e in events if e["ph"] == "e"]
    assert ends and all("end_reason" in e["args"] for e in ends)  # type: ignore[operator]
    assert {e["args"]["end_reason"] for e in ends} >= {"completed"}  # type: ignore[index]
    assert all("end_reason" not in e["args"] for e in events  # type: ignore[operator]
               if e["ph"] == "b")
    still = sum(e["args"]["end_reason"] == "still running when the trace ended"  # type: ignore[index]
                for e in ends)
    assert still <= 2  # (the ABs running at the run's end)
