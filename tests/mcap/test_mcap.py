"""``prima run --format mcap``: the recording read back with the mcap reader, every message
decoded (Foxglove's schemas as protobuf, PRIMA's as JSON) and every schema named."""

from __future__ import annotations

import collections
import io
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("foxglove")
reader = pytest.importorskip("mcap.reader")
decoder = pytest.importorskip("mcap.decoder")
protobuf = pytest.importorskip("mcap_protobuf.decoder")

from prima.cli import main  # noqa: E402
from prima.judge import judge  # noqa: E402
from prima.mcap import TOPICS  # noqa: E402
from prima.run import Run  # noqa: E402
from prima.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SAMPLE_03 = ROOT / "scenarios" / "thesis" / "sample-03.xml"


class _Json(decoder.DecoderFactory):  # type: ignore[misc]
    def decoder_for(self, message_encoding: str,
                    schema: Any) -> Callable[[bytes], Any] | None:
        return json.loads if message_encoding == "json" else None


def read(path: Path) -> list[tuple[str, str, str, Any, int]]:
    """Every message: (topic, schema name, schema encoding, decoded, log time)."""
    with path.open("rb") as f:
        raw = sum(1 for _ in reader.make_reader(f).iter_messages())
    with path.open("rb") as f:
        found = [(channel.topic, schema.name if schema else "", schema.encoding if schema else "",
                  decoded, message.log_time)
                 for schema, channel, message, decoded in reader.make_reader(
                     f, decoder_factories=[protobuf.DecoderFactory(), _Json()])
                 .iter_decoded_messages()]
    assert len(found) == raw  # every message decoded
    return found


def record(scenario: Path, out: Path) -> list[tuple[str, str, str, Any, int]]:
    err = io.StringIO()
    assert main(["run", str(scenario), "--format", "mcap", "-o", str(out)], err=err) == 0, \
        err.getvalue()
    return read(out)


def test_a_recording_of_sample_03_reads_back_whole(tmp_path: Path) -> None:
    messages = record(SAMPLE_03, tmp_path / "run.mcap")
    counts = collections.Counter(topic for topic, *_ in messages)
    schemas = {topic: (name, encoding) for topic, name, encoding, *_ in messages}
    assert all(name for name, _ in schemas.values())  # every schema named
    assert schemas["/map"] == ("foxglove.SceneUpdate", "protobuf")
    assert schemas["/tf"] == ("foxglove.FrameTransforms", "protobuf")
    assert schemas["/robot/pose"] == ("foxglove.PoseInFrame", "protobuf")
    assert schemas["/user/path"] == ("foxglove.PosesInFrame", "protobuf")
    assert schemas["/words"] == ("foxglove.Log", "protobuf")
    assert schemas["/mediator"] == ("prima.Decision", "jsonschema")
    assert schemas["/devices/speaker"] == ("prima.DeviceState", "jsonschema")
    topics = set(counts)
    assert {t for t in TOPICS if "DEVICE" not in t and "APP" not in t} <= topics
    # the counts are the trace's
    lines = Run(SAMPLE_03).run()
    rows = [line.to_dict() for line in lines]
    decisions = [r for r in rows if r["kind"] in (
        "load", "unload", "request", "start", "end", "interrupt", "cancel", "suspend",
        "resume", "hold", "release", "failure", "budget")]
    assert counts["/mediator"] == len(decisions)
    said = [r for r in rows if r["kind"] == "start" and r.get("text")]
    heard = [r for r in rows if r["kind"] == "user" and r.get("action") == "say"]
    assert counts["/words"] == len(said) + len(heard)
    assert counts["/events"] == sum(r["kind"] == "event" for r in rows)
    assert counts["/tf"] == counts["/robot/pose"] == counts["/user/pose"]
    assert counts["/map"] == counts["/bodies"] == counts["/robot/path"] == 1
    # the map: every place of the office map, named
    [scene] = [m for topic, _, _, m, _ in messages if topic == "/map"]
    labels = {text.text for entity in scene.entities for text in entity.texts}
    assert {p.name for p in load_scenario(SAMPLE_03).map.places} <= labels
    # a device's states: an application's Command while it holds it, idle after
    states = [m["state"] for topic, _, _, m, _ in messages if topic == "/devices/speaker"]
    assert "ea3-navigate: QA" in states and states[-1] == "idle"
    # the decisions carry their reasons, in time order as the trace has them
    starts = [m for topic, _, _, m, _ in messages if topic == "/mediator" and m["kind"] == "start"]
    assert {m["reason"] for m in starts} >= {"free-devices", "connect-channel", "priority"}
    times = [t for topic, *_, t in messages if topic == "/mediator"]
    assert times == sorted(times) and times[-1] == round(decisions[-1]["t"] * 1e9)


def test_the_judges_findings_are_in_the_recording(tmp_path: Path) -> None:
    """scenarios/policies/streams-off.xml: EA2's question inside FA5's stream, the one
    split exchange the judge finds, is a message on /judge at its time, said as the
    judge's table says it."""
    streams_off = ROOT / "scenarios" / "policies" / "streams-off.xml"
    messages = record(streams_off, tmp_path / "streams-off.mcap")
    found = [(m.name, m.message, t) for topic, _, _, m, t in messages if topic == "/judge"]
    report = judge(Run(streams_off).run())
    (s,) = report.of("splits")
    [split] = [f for f in found if f[0] == "splits"]
    assert split[2] == round(s.t * 1e9)
    assert "ea2-library" in split[1] and "inside fa5-video-timer-stream's stream" in split[1]
    assert found[-1][0] == "summary" and "1 splits" in found[-1][1]


def test_an_mcap_recording_needs_a_file(tmp_path: Path) -> None:
    err = io.StringIO()
    assert main(["run", str(SAMPLE_03), "--format", "mcap"], err=err) == 2
    assert "--format mcap writes a binary file: give --out FILE" in err.getvalue()


def _panels(content: dict[str, Any]) -> list[dict[str, Any]]:
    """Every panel of a layout's content, in order."""
    if content.get("type") == "split":
        return [p for item in content["items"] for p in _panels(item["content"])]
    return [content]


def test_a_recording_carries_its_foxglove_layout(tmp_path: Path) -> None:
    """A 3D panel on the map, the bodies and the paths; the device timeline as state
    transitions, and the applications' states; the words, the decisions, the findings:
    every topic the layout names is one of the recording's, which has the layout as an
    attachment (foxglove.layouts)."""
    from prima.mcap import ATTACHMENT

    messages = record(SAMPLE_03, tmp_path / "run.mcap")
    topics = {topic for topic, *_ in messages}
    with (tmp_path / "run.mcap").open("rb") as f:
        attachments = list(reader.make_reader(f).iter_attachments())
    assert [a.name for a in attachments] == [ATTACHMENT]
    assert attachments[0].media_type == "application/json"
    layout = json.loads(attachments[0].data)
    panels = _panels(layout["content"])
    kinds = [p["panelType"] for p in panels]
    assert kinds == ["ThreeDee", "StateTransitions", "StateTransitions", "Log", "RawMessages",
                     "Log"]
    assert set(panels[0]["config"]["topics"]) == {"/map", "/bodies", "/robot/path",
                                                  "/user/path"} <= topics
    series = [s["value"] for p in panels[1:3] for s in p["config"]["paths"]]
    assert "/devices/speaker.state" in series and "/apps/ea3-navigate/state.state" in series
    assert {s.rsplit(".", 1)[0] for s in series} <= topics
    assert [panels[k]["config"].get("topicToRender", panels[k]["config"].get("topicPath"))
            for k in (3, 4, 5)] == ["/words", "/mediator", "/judge"]


def test_the_shipped_layout_is_the_one_the_code_makes() -> None:
    """``prima/mcap/foxglove-layout.json`` (the home robot's devices, to import into
    Foxglove by hand) is what :func:`prima.mcap.layout` makes now."""
    from prima.mcap import layout, shipped

    assert json.loads(shipped()) == json.loads(layout().to_json())


def test_a_full_disk_is_one_line(tmp_path: Path) -> None:
    """foxglove-sdk printed an error of its own for every message after a failed write,
    then raised; the recording is written through a file of PRIMA's: one line."""
    import subprocess
    import sys

    scenario = ROOT / "scenarios" / "thesis" / "fig5-7.xml"
    done = subprocess.run([sys.executable, "-m", "prima", "run", str(scenario), "--format",
                           "mcap", "--out", "/dev/full"], capture_output=True, text=True,
                          timeout=120)
    assert (done.returncode, done.stderr) == (
        1, "prima run: error: cannot write /dev/full: no space left on device\n")


def test_a_killed_recording_leaves_the_earlier_one_whole(tmp_path: Path) -> None:
    """SIGKILL mid-write: the recording was written in place (14 MB the reader rejects
    in place of a good one); it is written beside it and renamed when finished."""
    import os
    import signal
    import subprocess
    import sys
    import time

    target = tmp_path / "run.mcap"
    assert main(["run", str(ROOT / "scenarios" / "thesis" / "fig5-7.xml"), "--format",
                 "mcap", "-o", str(target)], err=io.StringIO()) == 0
    earlier = target.read_bytes()
    child = subprocess.Popen([sys.executable, "-m", "prima", "run", str(SAMPLE_03), "--until",
                              "100000", "--format", "mcap", "--out", str(target)],
                             stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 120  # (until the recording is being written: not a pace)
    while time.monotonic() < deadline and not any(
            p.stat().st_size for p in tmp_path.glob(".prima-*.part")) and child.poll() is None:
        time.sleep(0.05)
    os.kill(child.pid, signal.SIGKILL)
    child.wait(timeout=60)
    assert target.read_bytes() == earlier
    assert len(read(target)) > 0  # still a recording the reader reads whole
