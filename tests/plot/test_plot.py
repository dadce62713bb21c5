"""``prima plot``: a run's device timeline as a picture (SVG, PNG, PDF), and the
run animated as a GIF; matplotlib is the plot extra's."""

from __future__ import annotations

import io
import sys
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from lxml import etree

from prima.cli import main
from prima.plot import abbreviate, timeline
from prima.run import Run

ROOT = Path(__file__).resolve().parents[2]
SAMPLE_03 = ROOT / "scenarios" / "thesis" / "sample-03.xml"

pytest.importorskip("matplotlib")


@pytest.fixture(scope="module")
def rows() -> list[dict[str, Any]]:
    return [line.to_dict() for line in Run(SAMPLE_03).run()]


def plot(*argv: str) -> tuple[int, str]:
    err = io.StringIO()
    status = main(["plot", *argv], out=io.StringIO(), err=err)
    return status, err.getvalue()


def test_one_bar_per_atomic_behavior_and_device(rows: list[dict[str, Any]]) -> None:
    tl = timeline(rows)
    starts = [r for r in rows if r["kind"] == "start"]
    expected = Counter((r["ab"], d) for r in starts for d in r["devices"])
    assert Counter((b.ab, b.device) for b in tl.bars) == expected
    assert max(expected.values()) == 1
    ends = {r["ab"]: r["t"] for r in rows if r["kind"] == "end"}
    for bar in tl.bars:
        assert bar.t0 <= bar.t1 == ends.get(bar.ab, tl.end)
    assert tl.apps == ["fa2-follow", "ea3-navigate"]
    assert set(tl.devices) == {d for r in starts for d in r["devices"]}


def test_waits_and_the_world(rows: list[dict[str, Any]]) -> None:
    tl = timeline(rows)
    assert {(s.kind, s.app) for s in tl.spans} == {
        ("suspend", "ea3-navigate"), ("hold", "ea3-navigate"), ("suspend", "fa2-follow")}
    for span in tl.spans:
        assert span.t0 < span.t1
    # the navigation, suspended at the touch, resumes after the second touch's talk
    resumed = [s for s in tl.spans if s.kind == "suspend" and s.app == "ea3-navigate"][-1]
    resume = next(r for r in rows if r["kind"] == "resume" and r["app"] == "ea3-navigate")
    assert resumed.t1 == resume["t"]
    assert Counter(k.row for k in tl.ticks) == Counter(
        {"user": sum(r["kind"] == "user" for r in rows),
         "event": sum(r["kind"] == "event" for r in rows)})
    user = [k for k in tl.ticks if k.row == "user"][:2]
    assert [k.action for k in user] == ["say", "follow"]  # an action's tick: its name
    # and worded as the text trace words it
    assert [k.label for k in user] == ['"Prof. Kidode\'s room."', "follows the robot"]
    assert len(tl.robot) > 400 and len(tl.user) > 400  # poses at 2 Hz and on events


def test_blended_behaviors_are_marked_on_the_devices_they_shared() -> None:
    import re

    rows = [line.to_dict() for line in Run(ROOT / "scenarios/policies/blend-on.xml").run()]
    tl = timeline(rows)
    shared = {(r["ab"], d) for r in rows if r["kind"] == "start"
              for d in re.findall(r" on ([^,\s]+)", str(r.get("detail", {}).get("over", "")))}
    assert shared  # the scenario blends
    assert {(b.ab, b.device) for b in tl.bars if b.blended} == shared
    # the dance's sway holds the wheels; EA1's move iterations blend over it
    assert {b.app for b in tl.bars if b.blended} == {"ea1-museum"}


def test_group_names_are_abbreviated() -> None:
    assert abbreviate("Speak") == "Speak"
    assert abbreviate("Speak+Gesture") == "Speak+Gesture"
    assert abbreviate("Speak+Gesture+PointByHand") == "Speak+Gesture+..."
    assert abbreviate("Speak+Gesture+PointByHand", 1) == "Speak+..."


def test_the_svg_is_valid_and_byte_identical_twice(tmp_path: Path) -> None:
    first, second = tmp_path / "a.svg", tmp_path / "b.svg"
    assert plot(str(SAMPLE_03), "-o", str(first))[0] == 0
    assert plot(str(SAMPLE_03), "--out", str(second))[0] == 0
    assert first.read_bytes() == second.read_bytes()
    root = etree.parse(str(first)).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    text = first.read_text()
    for label in ("fa2-follow", "ea3-navigate", "locomotion", "speaker", "suspended",
                  "TrackingHuman"):
        assert label in text


def test_a_trace_and_its_scenario_make_the_same_picture(
        rows: list[dict[str, Any]], tmp_path: Path) -> None:
    import json

    trace = tmp_path / "sample-03.jsonl"
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows))
    assert plot(str(trace), "-o", str(tmp_path / "trace.png"))[0] == 0
    assert plot(str(SAMPLE_03), "-o", str(tmp_path / "run.png"))[0] == 0
    png = (tmp_path / "trace.png").read_bytes()
    assert png.startswith(b"\x89PNG\r\n\x1a\n")
    assert png == (tmp_path / "run.png").read_bytes()
    assert plot(str(trace), "-o", str(tmp_path / "t.pdf"))[0] == 0
    assert (tmp_path / "t.pdf").read_bytes().startswith(b"%PDF")


def test_the_animation_has_a_frame_per_step(tmp_path: Path) -> None:
    from PIL import Image

    gif = tmp_path / "run.gif"
    status, err = plot(str(SAMPLE_03), "-o", str(gif), "--until", "20", "--step", "2")
    assert status == 0, err
    with Image.open(gif) as image:
        assert image.format == "GIF"
        assert image.n_frames == 11  # t = 0, 2, ..., 20


def test_a_bad_trace_line_is_located(tmp_path: Path) -> None:
    trace = tmp_path / "bad.jsonl"
    trace.write_text('{"t": 0, "seq": 0, "kind": "load", "app": "a"}\nnot json\n')
    status, err = plot(str(trace), "-o", str(tmp_path / "x.svg"))
    assert status == 1
    assert err.splitlines() == [f"{trace}:2:1: error: not a JSON object: Expecting value"]
    assert not (tmp_path / "x.svg").exists()


@pytest.mark.parametrize("argv, message", [
    (["missing.jsonl", "-o", "x.svg"], "no such file: missing.jsonl"),
    ([str(SAMPLE_03), "-o", "x.jpg"], "--out x.jpg: name a .svg, .png, .pdf, .gif file"),
    ([str(SAMPLE_03), "-o", f"{SAMPLE_03}/x.svg"], f"--out {SAMPLE_03}/x.svg: {SAMPLE_03} "
                                                   "is not a folder"),
    ([str(SAMPLE_03), "-o", "x.svg", "--until", "0"], "--until must be"),
    ([str(SAMPLE_03), "-o", "x.gif", "--step", "-1"], "--step must be"),
    ([str(SAMPLE_03), "-o", "x.gif", "--fps", "0"], "--fps must be"),
])
def test_usage_errors_are_one_line(argv: list[str], message: str, tmp_path: Path,
                                   monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    status, err = plot(*argv)
    assert status == 2
    assert len(err.splitlines()) == 1 and message in err and "Traceback" not in err


@pytest.mark.parametrize("suffix", [".svg", ".png", ".pdf"])
def test_a_full_disk_is_one_line(suffix: str, tmp_path: Path) -> None:
    full = tmp_path / f"full{suffix}"
    full.symlink_to("/dev/full")  # (a target that is not a regular file is written directly)
    status, err = plot(str(SAMPLE_03), "-o", str(full), "--until", "5")
    assert (status, err) == (1, f"prima plot: error: cannot write {full}: no space left on "
                                "device\n")


def test_a_trace_of_a_thousand_devices_draws_the_first_64(tmp_path: Path) -> None:
    """A forged trace whose every AB names a device of its own (a picture of gigabytes,
    drawn whole): the first MAX_ROWS devices are drawn, the rest said under them."""
    import json

    from prima.timeline import MAX_ROWS

    trace = tmp_path / "many.jsonl"
    lines = []
    for i in range(1_000):
        row = {"app": "ea", "ab": i, "command": "Speak", "devices": [f"d{i}"]}
        lines.append({"t": i / 10, "seq": 2 * i, "kind": "start", **row})
        lines.append({"t": i / 10 + 0.05, "seq": 2 * i + 1, "kind": "end", **row})
    trace.write_text("".join(json.dumps(r) + "\n" for r in lines), encoding="utf-8")
    tl = timeline(lines)
    assert (tl.devices, tl.hidden) == ([f"d{i}" for i in range(MAX_ROWS)], 1_000 - MAX_ROWS)
    assert {b.device for b in tl.bars} == set(tl.devices)
    out = tmp_path / "many.svg"
    assert plot(str(trace), "-o", str(out))[0] == 0
    assert f"{1_000 - MAX_ROWS} more devices not drawn" in out.read_text(encoding="utf-8")


def test_without_matplotlib_it_says_how_to_install_it(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib fails
    status, err = plot(str(SAMPLE_03), "-o", str(tmp_path / "x.svg"))
    assert status == 2
    assert err == ("prima plot: error: matplotlib is not installed; install the plot extra: "
                   "pip install 'prima[plot]' (in a checkout of PRIMA: pip install -e "
                   "'.[plot]')\n")


def test_a_run_without_behaviors_still_draws(tmp_path: Path) -> None:
    import warnings

    trace = tmp_path / "quiet.jsonl"
    trace.write_text('{"t": 0, "seq": 0, "kind": "load", "app": "a"}\n')
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in ("quiet.svg", "quiet.gif"):
            status, err = plot(str(trace), "-o", str(tmp_path / name))
            assert status == 0, err
            assert (tmp_path / name).stat().st_size > 0
