"""The device timeline both viewers draw (``prima show``, ``prima plot``): one digest
of a trace's rows, and what it decides a trace means."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from prima.run import Run
from prima.timeline import NO_DEVICE, Bar, Span, blended_devices, runs, timeline
from tests.work import allocated, bytecodes

ROOT = Path(__file__).resolve().parents[1]


def row(t: float, kind: str, app: str | None = "a", ab: int | None = None,
        **more: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"t": t, "seq": 0, "kind": kind, **more}
    if app is not None:
        out["app"] = app
    if ab is not None:
        out["ab"] = ab
    return out


def ab_rows(ab: int, t0: float, t1: float, devices: list[str], app: str = "a",
            **more: Any) -> list[dict[str, Any]]:
    return [row(t0, "start", app, ab, command="Move", devices=devices, **more),
            row(t1, "end", app, ab, command="Move", devices=devices)]


def spans(rows: list[dict[str, Any]], kind: str) -> list[tuple[int | None, float, float]]:
    return [(s.ab, s.t0, s.t1) for s in timeline(rows).spans if s.kind == kind]


# ------------------------------------------------------------------ suspensions

def test_a_suspension_ends_when_its_stream_resumes_even_at_another_ab() -> None:
    """restore-state: the stream resumes with a move of its own (another AB of the tree),
    long before the AB it was suspended at starts (show ended it at that AB's end,
    plot at its start)."""
    rows = [row(1.0, "suspend", ab=5, tree=0, command="Speak", devices=["speaker"]),
            *ab_rows(9, 4.0, 5.0, ["locomotion"], tree=0),
            row(4.0, "resume", ab=9, tree=0, devices=["locomotion"]),
            *ab_rows(5, 6.0, 8.0, ["speaker"], tree=0)]
    rows.sort(key=lambda r: r["t"])
    assert spans(rows, "suspend") == [(5, 1.0, 4.0)]


def test_a_suspension_ends_when_its_ab_starts() -> None:
    """The AB runs: its stream waits no more, resume line or not (show waited for a
    resume, a cancel or the AB's end)."""
    rows = [row(1.0, "suspend", ab=5, tree=0, devices=["speaker"]),
            *ab_rows(5, 3.0, 7.0, ["speaker"], tree=0)]
    assert spans(rows, "suspend") == [(5, 1.0, 3.0)]


def test_a_suspension_of_another_stream_or_app_goes_on() -> None:
    rows = [row(1.0, "suspend", ab=5, tree=0, devices=["speaker"]),
            row(2.0, "resume", ab=8, tree=1, devices=["speaker"]),
            row(3.0, "resume", "b", ab=9, tree=0, devices=["speaker"]),
            row(4.0, "cancel", ab=5, tree=0, devices=["speaker"])]
    assert spans(rows, "suspend") == [(5, 1.0, 4.0)]


def test_a_wait_still_open_at_the_end_lasts_to_the_end() -> None:
    rows = [row(1.0, "suspend", ab=5, tree=0, devices=["speaker"]), row(9.0, "event", None)]
    assert spans(rows, "suspend") == [(5, 1.0, 9.0)]


# ------------------------------------------------------------------ holds

def test_a_hold_is_a_span_until_its_ab_starts() -> None:
    """show marked a hold at an instant; it is a wait, like a suspension."""
    rows = [row(1.0, "hold", ab=5, reason="keep-channel", text="b is talking",
                devices=["locomotion"]),
            *ab_rows(5, 3.0, 4.0, ["locomotion"])]
    tl = timeline(rows)
    assert tl.spans == [Span("hold", "a", 5, "", 1.0, 3.0, "keep-channel", ("locomotion",), 0)]
    assert tl.marks == []


def test_a_hold_ends_when_its_holder_releases_but_not_the_channel_rules() -> None:
    rows = [row(1.0, "hold", ab=5, reason="block", text="devices kept for b",
                devices=["arm"]),
            row(1.5, "hold", ab=6, reason="stream-hold", text="devices kept for c",
                devices=["arm"]),
            row(2.0, "hold", ab=7, reason="keep-channel", text="b is talking",
                devices=["arm"]),
            row(3.0, "release", "b", reason="block-close", text="block on arm, neck"),
            row(5.0, "release", "c", reason="hold-timeout", text="stream hold on arm"),
            row(8.0, "event", None)]
    assert spans(rows, "hold") == [(5, 1.0, 3.0), (6, 1.5, 5.0), (7, 2.0, 8.0)]


def test_a_release_marks_the_devices_it_frees() -> None:
    rows = [*ab_rows(1, 0.0, 1.0, ["arm"]),
            row(3.0, "release", "b", reason="block-close", text="block on arm, neck")]
    (mark,) = timeline(rows).marks
    assert (mark.kind, mark.t, mark.app, mark.ab, mark.devices, mark.line) == (
        "release", 3.0, "b", None, ("arm", "neck"), 2)
    assert timeline(rows).devices == ["arm"]  # a release names devices, it gives no rows


# ------------------------------------------------------------------ bars and rows

def test_an_ab_without_devices_has_a_bar_on_the_no_device_row() -> None:
    """plot dropped it; every AB the trace started is drawn."""
    tl = timeline([*ab_rows(1, 0.0, 2.0, ["arm"]), *ab_rows(2, 1.0, 1.0, [])])
    assert [(b.ab, b.device) for b in tl.bars] == [(1, "arm"), (2, NO_DEVICE)]
    assert tl.devices == ["arm", NO_DEVICE]


def test_bars_keep_the_trace_times() -> None:
    """An AB that took no time is a bar of no width: widening it to be seen is the
    drawing's business (show widened the data)."""
    tl = timeline(ab_rows(1, 2.0, 2.0, ["arm"]))
    assert tl.bars == [Bar(1, "arm", "a", "Move", 2.0, 2.0)]


def test_devices_in_the_order_first_occupied_then_those_only_waited_for() -> None:
    """show sorted them by name (and gave a row to every device a request named)."""
    rows = [*ab_rows(1, 0.0, 1.0, ["speaker", "arm"]),
            row(0.5, "request", ab=3, devices=["camera"]),
            row(1.0, "suspend", ab=2, tree=0, devices=["neck"]),
            *ab_rows(4, 1.5, 2.0, ["locomotion", "arm"]),
            row(2.5, "cancel", ab=2, tree=0, devices=["neck"])]
    assert timeline(rows).devices == ["speaker", "arm", "locomotion", "neck"]


def test_a_blended_start_marks_its_shared_devices() -> None:
    """show drew a blended AB under the one it blended over."""
    rows = ab_rows(1, 0.0, 1.0, ["locomotion", "speaker"],
                   detail={"over": "over AB12 on locomotion"})
    assert {b.device: b.blended for b in timeline(rows).bars} == {"locomotion": True,
                                                                 "speaker": False}
    assert blended_devices("over AB3 on speaker, over AB4 on arm") == {"speaker", "arm"}
    assert blended_devices(None) == frozenset()


def test_a_bar_still_running_at_the_end() -> None:
    tl = timeline([row(1.0, "start", ab=1, command="Move", devices=["arm"], text="hi"),
                   row(4.0, "event", None, text="done")])
    assert tl.bars == [Bar(1, "arm", "a", "Move", 1.0, 4.0, "hi", ended=False)]
    assert tl.speech() == tl.bars and tl.end == 4.0


# ------------------------------------------------------------------ the world

def test_the_user_is_worded_as_the_text_trace_words_them() -> None:
    tl = timeline([row(1.0, "user", None, action="say", text="Hello",
                       detail={"heard": False}),
                   row(2.0, "user", None, action="walk", detail={"target": "hall"}),
                   row(3.0, "event", None, text="touched")])
    assert [(k.row, k.label, k.text, k.action) for k in tl.ticks] == [
        ("user", '"Hello" (not heard)', "Hello", "say"),
        ("user", "walks to hall", None, "walk"),
        ("event", "touched", None, "")]


def test_every_pose_is_kept_in_time_order() -> None:
    pose = {"x": 1.0, "y": 2.0, "heading": 90.0}
    tl = timeline([row(0.0, "pose", None, robot=pose), row(0.0, "start", ab=1, robot=pose,
                                                           user={"x": 0, "y": 0}, devices=[]),
                   row(1.0, "pose", None, robot={"x": 2.0, "y": 2.0, "heading": 90.0})])
    assert tl.robot == [(0.0, (1.0, 2.0, 90.0)), (0.0, (1.0, 2.0, 90.0)),
                        (1.0, (2.0, 2.0, 90.0))]
    assert tl.user == [(0.0, (0.0, 0.0, 0.0))]


def test_a_long_runs_poses_are_held_as_floats() -> None:
    """Four floats a pose sample (an array), not a tuple of a time and a tuple of floats:
    a long run has hundreds of thousands of them (``bench/big_trace.py``)."""
    samples = 20_000
    rows = (row(k * 0.5, "pose", None, robot={"x": k * 0.1, "y": 1.0, "heading": 90.0},
                user={"x": 2.0, "y": k * 0.1, "heading": 0.0}) for k in range(samples))
    made: list[Any] = []
    held, _peak = allocated(lambda: made.append(timeline(rows)))
    tl = made[0]
    assert len(tl.robot) == len(tl.user) == samples
    assert tl.robot[-1] == ((samples - 1) * 0.5, ((samples - 1) * 0.1, 1.0, 90.0))
    # (as tuples, about 174 bytes a sample)
    assert held < 48 * 2 * samples, f"{held / (2 * samples):.0f} bytes a sample"


@pytest.mark.parametrize("scenario", ["thesis/sample-03", "thesis/sample-07",
                                      "policies/interrupt-on"])
def test_every_wait_of_a_run_closes_where_the_trace_says(scenario: str) -> None:
    rows = [line.to_dict() for line in Run(ROOT / "scenarios" / f"{scenario}.xml").run()]
    tl = timeline(rows)
    for span in tl.spans:
        began = rows[span.line]
        assert (began["kind"], began["app"], began.get("ab")) == (span.kind, span.app, span.ab)
        assert began["t"] == span.t0 <= span.t1 <= tl.end
        closing = [r for r in rows if r["t"] == span.t1 and (
            r.get("ab") == span.ab or r["kind"] in ("resume", "release"))]
        assert closing or span.t1 == tl.end, span
    assert {b.ab for b in tl.bars} == {r["ab"] for r in rows if r["kind"] == "start"}


@pytest.mark.parametrize("scenario", ["thesis/sample-10", "policies/interrupt-on"])
def test_a_block_hold_ends_at_its_holders_release_in_a_real_run(scenario: str) -> None:
    """The contract with the mediator's wording: a block's ``hold`` line names its holder
    ("devices kept for fa4-picture") and the holder's ``release`` line names the devices
    it frees ("block on arm, camera, ..."). The timeline parses both; if the mediator
    words them otherwise, these spans and marks would silently change, so this fails."""
    rows = [line.to_dict() for line in Run(ROOT / "scenarios" / f"{scenario}.xml").run()]
    tl = timeline(rows)
    releases = [m for m in tl.marks if m.kind == "release" and m.reason == "block-close"]
    assert releases, "the scenario no longer has a block released"
    release = releases[0]
    holds = [s for s in tl.spans if s.kind == "hold" and s.reason == "block"]
    assert holds and all(s.holder == release.app != s.app for s in holds)
    assert [s.t1 for s in holds] == [release.t] * len(holds)  # the release, not the AB's start
    started = {r["ab"]: r["t"] for r in rows if r["kind"] == "start"}
    assert all(started.get(s.ab, tl.end) >= release.t for s in holds)  # (not before it)
    assert set(holds[0].devices) <= set(release.devices)  # parsed to the devices' names
    assert all(d.replace("-", "").isalpha() for d in release.devices), release.devices


def test_the_cost_is_linear_in_the_number_of_open_waits() -> None:
    """Thousands of waits open at once (suspended streams, holds of one holder) close by
    key, not by scanning every open wait on every line: 8x the rows take 8x the work,
    not 64x. The work is counted, not timed: the bytecodes run in prima/timeline.py."""
    import prima.timeline

    def rows(n: int) -> list[dict[str, Any]]:
        out = []
        for k in range(n):
            out.append(row(0.0, "suspend", "a", k, tree=k, devices=["arm"]))
            out.append(row(0.0, "hold", "b", k, text="devices kept for a", devices=["arm"]))
        for k in range(n):
            out += ab_rows(n + k, 1.0, 2.0, ["neck"], app="c")
        out.append(row(3.0, "release", "a", text="block on arm"))
        out += [row(4.0, "resume", "a", k, tree=k) for k in range(n)]
        return out

    def work(n: int) -> int:
        data = rows(n)
        made: list[Any] = []
        count = bytecodes(lambda: made.append(timeline(data)), only=prima.timeline.__file__)
        assert len(made[0].spans) == 2 * n
        return count

    small, large = work(200), work(1600)
    assert large < 8 * 1.25 * small, (small, large)  # (sorting adds a log factor)


def test_runs_are_a_commands_bars_that_follow_one_another_on_one_device() -> None:
    def bar(ab: int, t0: float, t1: float, device: str = "locomotion", app: str = "a",
            command: str = "Move", text: str | None = None) -> Bar:
        return Bar(ab, device, app, command, t0, t1, text)

    bars = [bar(1, 0, 1), bar(2, 1, 2), bar(3, 2.04, 3),         # one run (a 0.04 s gap)
            bar(4, 3.2, 4),                                       # too far: a run of its own
            bar(5, 4, 5, app="b"), bar(6, 5, 6, command="Turn"),  # another app, Command
            bar(7, 6, 7, text="hi"), bar(8, 7, 8, text="hi"),     # words: never joined
            bar(9, 1, 2, device="neck"), bar(10, 2, 3, device="neck")]
    assert [[b.ab for b in run] for run in runs(reversed(bars))] == [
        [1, 2, 3], [4], [5], [6], [7], [8], [9, 10]]


def test_labels_are_inked_to_read_on_their_bar() -> None:
    from prima.timeline import ink

    assert [ink(c) for c in ("#1f77b4", "#EF553B", "#FECB52", "#ffffff")] == [
        "white", "white", "black", "black"]
