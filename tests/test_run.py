"""The whole stack: documents, interpreters, mediator and simulator in one run."""

from __future__ import annotations

import dataclasses
import io
import json
import math
import random
import struct
from pathlib import Path

import pytest
from lxml import etree

import prima.trace
from prima.cli import main
from prima.errors import DocumentError, ScenarioError
from prima.mediator import DecisionKind
from prima.run import Loaded, Run
from prima.sim import Simulator
from prima.trace import Kind, TraceLine, device_overlaps, format_jsonl, format_text

ROOT = Path(__file__).parents[1]
OFFICE = ROOT / "scenarios" / "examples" / "office-kidode.xml"


def run_cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    return main(list(argv), out=out, err=err), out.getvalue(), err.getvalue()


@pytest.fixture(scope="module")
def office():  # type: ignore[no-untyped-def]
    return Run(OFFICE, until=120).run()


def test_same_inputs_give_a_byte_identical_trace(office) -> None:  # type: ignore[no-untyped-def]
    again = Run(OFFICE, until=120).run()
    assert format_jsonl(again) == format_jsonl(office)
    assert format_text(again) == format_text(office)


def test_no_two_behaviors_share_a_device_at_once(office) -> None:  # type: ignore[no-untyped-def]
    assert [line for line in office if line.kind is DecisionKind.START]
    assert device_overlaps(office) == []


def test_overlap_checker_catches_an_overlap(office) -> None:  # type: ignore[no-untyped-def]
    ends = [i for i, line in enumerate(office) if line.kind is DecisionKind.END]
    broken = office[: ends[0]] + office[ends[0] + 1:]  # drop one end: its device stays held
    assert device_overlaps(broken)


def test_the_navigation_story_runs(office) -> None:  # type: ignore[no-untyped-def]
    said = [line.text for line in office
            if line.kind is DecisionKind.START and line.command == "Speak"]
    assert said[:2] == ["Come on, let's go.", "I've just got a message."]
    assert "I've just reached the goal." in said
    reached = [line.detail.get("place") for line in office if line.kind is Kind.EVENT
               and line.text == "place-reached"]
    assert reached[-1] == "kidode-room" and "corner" in reached
    sent = [line for line in office if line.kind is Kind.SEND]
    assert [s.detail["to"] for s in sent] == ["host"]


def test_jsonl_records_have_the_documented_fields(office) -> None:  # type: ignore[no-untyped-def]
    records = [json.loads(line) for line in format_jsonl(office).splitlines()]
    assert [r["seq"] for r in records] == list(range(len(records)))
    assert all(set(r) >= {"t", "seq", "kind"} for r in records)
    start = next(r for r in records if r["kind"] == "start" and r.get("command") == "QA")
    assert start["text"] == "Where are you going?" and start["app"] == "ea3-navigate"
    assert start["devices"] == ["speaker", "speech-recognition"] and start["reason"]
    user = next(r for r in records if r["kind"] == "user")
    assert user["action"] in ("say", "follow", "walk", "touch")
    times = [r["t"] for r in records]
    assert times == sorted(times)


FAILING_FA = """<pxml xmlns="urn:prima:pxml:1" kind="fa" name="broken-fa">
  <var name="n" expr="0"/>
  <state id="s" initial="true">
    <on event="message"><assign name="n" expr="1 / n"/></on>
  </state>
</pxml>"""


def test_a_failing_application_is_unloaded_and_the_other_goes_on(tmp_path: Path) -> None:
    fa = tmp_path / "broken.pxml"
    fa.write_text(FAILING_FA)
    lines = Run(OFFICE, fa=fa, until=120).run()
    [error] = [line for line in lines if line.kind is Kind.ERROR]
    assert error.app == "broken-fa" and "by zero" in error.text and "broken.pxml:4:" in error.text
    unload = next(line for line in lines if line.kind is DecisionKind.UNLOAD)
    assert unload.app == "broken-fa" and unload.seq > error.seq
    later = [line for line in lines if line.seq > error.seq and line.app == "ea3-navigate"
             and line.kind is DecisionKind.START]
    assert later, "the EA must go on after the FA failed"
    assert not [line for line in lines if line.seq > unload.seq and line.app == "broken-fa"]


def test_cli_writes_text_or_jsonl(tmp_path: Path) -> None:
    code, out, _ = run_cli("run", str(OFFICE), "--until", "30")
    assert code == 0 and out.startswith("  No.") and '"Where are you going?"' in out
    target = tmp_path / "trace.jsonl"
    code, out, _ = run_cli("run", str(OFFICE), "--until", "30", "--format", "jsonl",
                           "--out", str(target), "--seed", "3")
    assert code == 0 and out == ""
    assert json.loads(target.read_text().splitlines()[0])["kind"] == "load"


def test_cli_writes_the_format_its_file_name_says(tmp_path: Path) -> None:
    for name, first in (("t.jsonl", '{"t": 0.0'), ("t.JSONL", '{"t": 0.0'),
                        ("t.json", "["), ("t.txt", "  No."), ("t", "  No.")):
        assert run_cli("run", str(OFFICE), "--until", "5", "--out", str(tmp_path / name))[0] == 0
        assert (tmp_path / name).read_text(encoding="utf-8").startswith(first), name
    # (--format says otherwise: as it says)
    assert run_cli("run", str(OFFICE), "--until", "5", "--format", "text",
                   "--out", str(tmp_path / "x.jsonl"))[0] == 0
    assert (tmp_path / "x.jsonl").read_text(encoding="utf-8").startswith("  No.")


@pytest.mark.parametrize("form", ["text", "jsonl", "chrome-trace"])
def test_out_dash_is_standard_output_not_a_file_named_dash(
        form: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli("run", str(OFFICE), "--until", "5", "--format", form, "-o", "-")
    assert (code, err) == (0, "") and not (tmp_path / "-").exists()
    assert out == run_cli("run", str(OFFICE), "--until", "5", "--format", form)[1]


def test_out_dash_is_refused_for_a_binary_recording(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli("run", str(OFFICE), "--format", "mcap", "-o", "-")
    assert (code, out) == (2, "") and not (tmp_path / "-").exists()
    assert err == ("prima run: error: --format mcap writes a binary file: give --out FILE, "
                   "not - (standard output)\n")


def test_cli_reports_bad_inputs(tmp_path: Path) -> None:
    assert run_cli("run", "nope.xml")[0] == 2
    assert run_cli("run", str(OFFICE), "--until", "-1")[0] == 2
    bad = tmp_path / "bad.pxml"
    bad.write_text('<pxml xmlns="urn:prima:pxml:1" kind="fa" name="x"><state id="s"/></pxml>')
    code, _, err = run_cli("run", str(OFFICE), "--fa", str(bad))
    assert code == 1 and f"{bad}:1:1: error: no initial state" in err


@pytest.mark.parametrize("where", ["entry", "timer"])
def test_failures_outside_mediator_callbacks_unload_too(tmp_path: Path, where: str) -> None:
    action = '<assign name="n" expr="1 / n"/>'
    body = (f"<entry>{action}</entry>" if where == "entry" else
            f'<entry><timer name="t" after="5"/></entry><on event="t">{action}</on>')
    fa = tmp_path / "broken.pxml"
    fa.write_text('<pxml xmlns="urn:prima:pxml:1" kind="fa" name="broken-fa">'
                  '<var name="n" expr="0"/>'
                  f'<state id="s" initial="true">{body}</state></pxml>')
    lines = Run(OFFICE, fa=fa, until=30).run()
    kinds = [(line.kind, line.app) for line in lines
             if line.kind in (Kind.ERROR, DecisionKind.UNLOAD)]
    assert kinds == [(Kind.ERROR, "broken-fa"), (DecisionKind.UNLOAD, "broken-fa")]
    assert any(line.app == "ea3-navigate" and line.kind is DecisionKind.START for line in lines)


def test_documents_must_fit_their_slot_and_have_distinct_names(tmp_path: Path) -> None:
    code, _, err = run_cli("run", str(OFFICE), "--fa", str(ROOT / "apps/ea/ea3-navigate.pxml"))
    assert code == 1 and 'this is an EA (kind="ea"); it cannot run as the FA' in err
    twin = tmp_path / "twin.pxml"
    twin.write_text((ROOT / "apps/ea/ea3-navigate.pxml").read_text().replace(
        'name="ea3-navigate"', 'name="fa2-follow"'))
    code, _, err = run_cli("run", str(OFFICE), "--ea", str(twin))
    assert code == 1 and "both named 'fa2-follow'" in err


ZONES = Path(__file__).parent / "data" / "zones"


def test_a_zone_loads_an_ea_and_the_next_zone_swaps_it() -> None:
    """docs/rules.md rule 7: an EA is loaded on entering its environment and replaced in
    the next one; unloading cancels its waiting work, its running AB is never cut."""
    lines = Run(ZONES / "swap.xml").run()
    loads = [(line.app, line.detail["role"]) for line in lines if line.kind is DecisionKind.LOAD]
    assert loads == [("walker", "fa"), ("hall-greeter", "ea"), ("gallery-guide", "ea")]
    unload = next(i for i, line in enumerate(lines) if line.kind is DecisionKind.UNLOAD)
    assert lines[unload].app == "hall-greeter" and lines[unload].reason == "unload"
    cancelled = [line for line in lines if line.kind is DecisionKind.CANCEL]
    assert cancelled and all(c.app == "hall-greeter" and c.reason == "unload" for c in cancelled)
    # the head move running at the swap finishes after it, and nothing shares a device
    running = [line.ab for line in lines[:unload] if line.kind is DecisionKind.START
               and line.app == "hall-greeter"][-1]
    assert any(line.kind is DecisionKind.END and line.ab == running for line in lines[unload:])
    assert device_overlaps(lines) == []
    # the new EA works, and the FA drives on into the gallery
    assert any(line.kind is DecisionKind.START and line.text == "This is the gallery."
               for line in lines[unload:])
    reached = [line.detail.get("place") for line in lines if line.kind is Kind.EVENT
               and line.text == "place-reached"]
    assert reached[-1] == "gallery"
    assert [line for line in lines if line.kind is Kind.ERROR] == []


def test_every_record_kind_reads_in_the_text_trace() -> None:
    from prima.trace import _DESCRIBE  # white box: the text form covers every kind

    assert set(_DESCRIBE) == set(Kind) | set(DecisionKind)


def test_a_failed_command_is_named_once() -> None:
    """The simulator's error names the Command (of a group, the one that failed)."""
    from prima.trace import describe

    def end(command: str, error: str) -> str:
        return describe(TraceLine(1.0, 0, DecisionKind.END, "a", 1, 0, command,
                                  detail={"error": error}))

    assert end("TopologicalMove", "TopologicalMove: unknown place 'x' on map 'office'") == (
        "TopologicalMove fails: unknown place 'x' on map 'office'")
    assert end("Speak+TopologicalMove", "TopologicalMove: unknown place 'x'") == (
        "Speak+TopologicalMove fails: TopologicalMove: unknown place 'x'")


def test_a_missed_touch_reads_as_one() -> None:
    from prima.trace import user_words

    assert user_words("touch", None, {}) == "touches the robot"
    assert user_words("touch", None, {"target": "missed"}) == (
        "does not reach the robot to touch it")


_POSED = (DecisionKind.START, DecisionKind.END, Kind.USER, Kind.EVENT, Kind.POSE)


@pytest.mark.pure  # (it has the run keep every sample: a compiled Run's methods are fixed)
def test_the_jsonl_trace_carries_poses_at_a_fixed_rate_where_they_changed(
        office, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    """Pose samples come at fixed instants (2 a second); the ones left out are exactly
    those that would repeat the poses of the line with poses before them: while the
    robot and the user stand still, time passes without a line. The last says where
    they are as the run ends, whatever it repeats (a trace ends when its run does)."""
    posed = [line for line in office if line.kind in _POSED]
    assert all(line.robot is not None and line.user is not None for line in posed)
    poses = [line for line in office if line.kind is Kind.POSE]
    assert all(line.t * 2 == round(line.t * 2) for line in poses)
    monkeypatch.setattr(Run, "_sample", lambda run: run._line(Kind.POSE))  # (every one,
    plain = Simulator.sample_poses  # at every instant, even one at which nothing moved)
    monkeypatch.setattr(Simulator, "sample_poses",
                        lambda sim, rate, on_sample, moved=False: plain(sim, rate, on_sample))
    every = [line for line in Run(OFFICE, until=120).run() if line.kind in _POSED]
    assert len([line for line in every if line.kind is Kind.POSE]) == 2 * 120 + 1
    kept = [line for before, line in zip([None, *every], every, strict=False)
            if line.kind is not Kind.POSE or before is None or line is every[-1]
            or (line.robot, line.user, line.detectable)
            != (before.robot, before.user, before.detectable)]
    assert office[-1].kind is Kind.POSE and office[-1].t == 120.0
    assert [(x.t, x.kind, x.robot, x.user) for x in kept] == \
        [(x.t, x.kind, x.robot, x.user) for x in posed]
    assert len(poses) < len(every) - len(posed) + len(poses) - 40  # (many were repeats)
    record = json.loads(format_jsonl(poses[:1]))
    assert set(record["robot"]) == {"x", "y", "heading"}


def test_standing_still_costs_a_run_no_pose_sample() -> None:
    """Fig. 5.7's robot and user stand still from 60 s on: a run to 6,000 s asks for no
    more samples than a run to 120 s, and writes the same lines but for the last pose's
    time (a run's cost follows what happens, not how long it goes on)."""
    def run(until: float) -> tuple[int, list[tuple[object, ...]]]:
        made = Run(ROOT / "scenarios" / "thesis" / "fig5-7.xml", until=until)
        asked = [0]
        sample = made.sim.on_sample

        def counted() -> None:
            asked[0] += 1
            sample()
        made.sim.on_sample = counted
        lines = made.run()
        assert lines[-1].kind is Kind.POSE and lines[-1].t == until
        return asked[0], [(x.t, x.kind, x.text, x.robot, x.user) for x in lines[:-1]]

    assert run(6000.0) == run(120.0)
    assert 0 < run(120.0)[0] < 40


def test_pose_samples_change_nothing_else() -> None:
    def without_poses(lines: list[TraceLine]) -> list[tuple[object, ...]]:
        return [(line.t, line.kind, line.app, line.text, line.reason) for line in lines
                if line.kind is not Kind.POSE]

    assert without_poses(Run(OFFICE, until=60, pose_rate=10).run()) == \
        without_poses(Run(OFFICE, until=60, pose_rate=0).run())


class _WakingEveryTime(Run):
    """A run whose loop wakes at every time the simulator names (``next_time``), and
    gives the mediator and the applications their turn at each, as the loop once did."""

    def run(self) -> list[TraceLine]:
        import math

        self._begin()
        sim, hz = self.sim, self.sim.kernel.hz
        while sim.now() < self.until:
            deadlines = [sim.next_time(), self.mediator.next_deadline()]
            deadlines += [a.interpreter.next_deadline() for a in list(self.apps.values())]
            t = min([d for d in deadlines if d is not None] + [self.until])
            sim.advance_to(max(math.ceil(t * hz - 1e-6) / hz, sim.now()), stop_on_report=True)
            self.mediator.advance()
            for app in list(self.apps.values()):
                self._guard(app, app.interpreter.advance)
        self._line(Kind.POSE)  # (where everyone ends)
        return self.lines


@pytest.mark.pure
@pytest.mark.parametrize("scenario", ["thesis/sample-03.xml", "thesis/sample-07.xml",
                                      "examples/barge-in-question.xml"])
def test_a_run_is_the_same_when_its_loop_wakes_at_every_simulator_time(scenario: str) -> None:
    # The loop sleeps through the simulator's own wake-ups (Simulator.advance_until);
    # sensing still looks at the user at each, so the user is found at the same tick.
    path = ROOT / "scenarios" / scenario
    assert format_jsonl(Run(path).run()) == format_jsonl(_WakingEveryTime(path).run())


def test_a_run_whose_end_is_a_hair_past_a_tick_ends_at_that_tick() -> None:
    # (it went round and round, short of an end it could never reach)
    lines = Run(ROOT / "scenarios" / "thesis" / "sample-03.xml", until=10.00000001).run()
    assert lines[-1].t <= 10.0 and Run(ROOT / "scenarios" / "thesis" / "sample-03.xml",
                                       until=10.0).run() == lines


def test_runs_sharing_their_loaded_files_run_as_alone(tmp_path: Path) -> None:
    files = Loaded()
    for name in ("sample-03", "sample-10", "sample-03"):
        path = ROOT / "scenarios" / "thesis" / f"{name}.xml"
        assert format_jsonl(Run(path, files=files).run()) == format_jsonl(Run(path).run())


def test_shared_loaded_files_are_read_again_when_they_change(tmp_path: Path) -> None:
    files = Loaded()
    fa = tmp_path / "fa.pxml"
    source = (ROOT / "apps" / "fa" / "fa1-emotions.pxml").read_text(encoding="utf-8")
    fa.write_text(source, encoding="utf-8")
    profile = files.profile(ROOT / "robots" / "home-robot.xml")
    assert files.profile(ROOT / "robots" / "home-robot.xml") is profile
    first = files.document(fa, profile)
    assert files.document(fa, profile) is first
    assert files.document(fa, files.profile(ROOT / "robots" / "guide-robot.xml")) is not first
    fa.write_text(source + "<!-- changed -->\n", encoding="utf-8")
    assert files.document(fa, profile) is not first
    fa.write_text("<pxml", encoding="utf-8")
    with pytest.raises(DocumentError):
        files.document(fa, profile)
    with pytest.raises(DocumentError):
        files.document(tmp_path / "missing.pxml", profile)
    building = tmp_path / "map.xml"
    plan = (ROOT / "scenarios" / "maps" / "office.xml").read_text(encoding="utf-8")
    building.write_text(plan, encoding="utf-8")
    first_map = files.map(building)
    assert files.map(building) is first_map
    building.write_text(plan + "<!-- changed -->\n", encoding="utf-8")
    assert files.map(building) is not first_map and files.map(building) == first_map
    building.write_text("<map", encoding="utf-8")
    with pytest.raises(ScenarioError):
        files.map(building)
    with pytest.raises(ScenarioError):
        files.map(tmp_path / "missing.xml")


def test_unchanging_loaded_files_are_read_once_and_their_paths_worked_out_once(
        tmp_path: Path) -> None:
    """A sweep's worker promises that its unpacked files do not change: a file is kept by
    its path alone, not read again (a change is not seen), and a scenario's paths are
    resolved and named once; a file that cannot be loaded is still not kept."""
    files = Loaded(unchanging=True)
    for name in ("sample-03", "sample-10", "sample-03"):
        path = ROOT / "scenarios" / "thesis" / f"{name}.xml"
        assert format_jsonl(Run(path, files=files).run()) == format_jsonl(Run(path).run())
    fa = tmp_path / "fa.pxml"
    source = (ROOT / "apps" / "fa" / "fa1-emotions.pxml").read_text(encoding="utf-8")
    fa.write_text(source, encoding="utf-8")
    profile = files.profile(ROOT / "robots" / "home-robot.xml")
    kept = files.document(fa, profile)
    fa.write_text("<pxml", encoding="utf-8")
    assert files.document(fa, profile) is kept  # (not read again)
    for _ in range(2):  # (not kept: asked again, it fails again)
        with pytest.raises(DocumentError):
            files.document(tmp_path / "missing.pxml", profile)
    loaded = dataclasses.replace(Run(ROOT / "scenarios" / "thesis" / "sample-03.xml").scenario,
                                 source=str(tmp_path / "bundle" / "run-1.xml"))
    place = files.resolve(loaded, "../robots/x.xml")
    assert place == tmp_path / "robots" / "x.xml"
    (tmp_path / "robots").mkdir()
    (tmp_path / "robots" / "x.xml").symlink_to(fa)
    assert files.resolve(loaded, "../robots/x.xml") is place  # (worked out once)
    assert Loaded().resolve(loaded, "../robots/x.xml") == fa  # (a Loaded whose files change)
    assert files.relative(str(fa), str(tmp_path / "bundle")) == "../fa.pxml"


def _commented(source: Path, out: Path, hrefs: dict[str, str] | None = None) -> Path:
    """``source`` written to ``out`` with a comment and a processing instruction before
    the first child of every element that has children and no text of its own (on the
    line of its start tag: no line moves), and the attributes ``hrefs`` names set."""
    tree = etree.parse(str(source))
    for el in list(tree.getroot().iter()):
        if isinstance(el.tag, str) and len(el) and not (el.text or "").strip():
            pi = etree.ProcessingInstruction("note", "x")
            pi.tail, el.text = el.text, None
            el.insert(0, etree.Comment(" a note "))
            el.insert(1, pi)
        for name, value in (hrefs or {}).items():
            if isinstance(el.tag, str) and el.get(name) is not None:
                el.set(name, value)
    tree.write(str(out), encoding="UTF-8", xml_declaration=True)
    return out


def test_comments_and_processing_instructions_anywhere_change_no_run(tmp_path: Path) -> None:
    """Their ``tag`` is a function, where lxml's stubs say a str: the compiled build, which
    checks what it reads against the stubs, must never read one as a str (``is_element``)."""
    apps = ROOT / "apps"
    fa = _commented(apps / "fa" / "fa2-follow.pxml", tmp_path / "fa2-follow.pxml")
    ea = _commented(apps / "ea" / "ea3-navigate.pxml", tmp_path / "ea3-navigate.pxml")
    thesis = ROOT / "scenarios" / "thesis"
    scenario = _commented(thesis / "sample-03.xml", tmp_path / "sample-03.xml",
                          {"fa": str(fa), "ea": str(ea),
                           "href": str(thesis.parent / "maps" / "office.xml")})

    def rows(path: Path) -> list[dict[str, object]]:
        made: list[dict[str, object]] = []
        Run(path, rows=made.append).run()
        for row in made:  # (where things are written: written again, lines may move)
            detail = row.get("detail")
            if isinstance(detail, dict):
                for key in ("at", "line", "col"):
                    detail.pop(key, None)
        return made

    assert rows(scenario) == rows(thesis / "sample-03.xml")


@pytest.mark.parametrize("at_once", [pytest.param(True, marks=pytest.mark.pure), False])
def test_a_line_made_in_one_go_is_the_line_the_class_makes(
        at_once: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """Alike whether the fields are stored at once (pure Python) or through the
    constructor (the compiled build: its lines keep no dict)."""
    monkeypatch.setattr(prima.trace, "_STORED_AT_ONCE", at_once)
    fields = {"app": "fa", "ab": 3, "command": "Speak", "text": 'say "hi"\n',
              "devices": ("speaker",), "detail": {"b": 1, "a": None},
              "robot": (1.0, 2.0, 90.0), "user": (3.0, 4.0, 0.0), "detectable": True}
    every: dict[str, object] = {  # (each field its own value, of its type)
        "app": "fa", "ab": 3, "tree": 4, "command": "Speak", "text": "hi",
        "devices": ("speaker",), "reactive": True, "reason": "free-devices", "action": "say",
        "detail": {"a": 1}, "command_ids": (5, 6), "before": 7, "robot": (1.0, 2.0, 3.0),
        "user": (4.0, 5.0, 6.0), "detectable": False}
    assert [*every] == [*prima.trace._DEFAULTS][3:]
    made = TraceLine.made(1.25, 7, DecisionKind.START, every)
    assert {name: getattr(made, name) for name in every} == every
    for given in ({}, fields, {"reason": "start", "before": 2}):
        made = TraceLine.made(1.25, 7, DecisionKind.START, given)
        assert made == TraceLine(1.25, 7, DecisionKind.START, **given)
        assert made.to_dict() == TraceLine(1.25, 7, DecisionKind.START, **given).to_dict()
    assert TraceLine.made(0.0, 0, Kind.POSE, {}).detail == {}
    with pytest.raises(TypeError, match="no field 'colour'"):
        TraceLine.made(0.0, 0, Kind.POSE, {"colour": "red"})
    with pytest.raises(TypeError, match="no field 'colour'"):  # (the first unknown, by name)
        TraceLine.made(0.0, 0, Kind.POSE, {"app": "fa", "zone": 1, "colour": "red"})


@pytest.mark.parametrize("scenario", ["thesis/sample-03.xml", "examples/museum-cafe.xml",
                                      "policies/interrupt-on.xml", "thesis/sample-07.xml"])
def test_a_run_made_as_rows_is_its_lines_jsonl_dicts(scenario: str) -> None:
    # (sample-03: loops; museum-cafe: a search's iterations that say nothing; sample-07:
    # a cut AB's restart, and a loop's Command whose AB goes from reactive to not: a
    # loop's row made from its last one's, or not, Run._ab_row)
    made: list[dict[str, object]] = []
    run = Run(ROOT / "scenarios" / scenario, rows=made.append)
    assert run.run() == []
    lines = [line.to_dict() for line in Run(ROOT / "scenarios" / scenario).run()]
    assert made == lines
    assert [list(row) for row in made] == [list(line) for line in lines]  # (in its order)
    rows = [row for row in made if "robot" in row]
    assert len({id(row["robot"]) for row in rows}) == len(rows)  # (dicts of their own)
    assert len({id(row["detail"]) for row in made if "detail" in row}) == \
        len([row for row in made if "detail" in row])


def test_a_loops_row_is_made_again_if_any_field_but_its_own_differs() -> None:
    # Run._ab_row compares a decision's fields but its own (time, number, kind, AB,
    # iteration) through three slices of the tuple: they cover every other field.
    from prima.mediator import Decision
    from prima.run import _OWN, _SAME_A, _SAME_B, _SAME_C

    fields = Decision._fields
    same = fields[_SAME_A] + fields[_SAME_B] + fields[_SAME_C]
    assert sorted(same + _OWN) == sorted(fields) and not set(same) & set(_OWN)


@pytest.mark.pure  # (it counts calls by patching the class: a compiled Run's are fixed)
def test_a_loops_rows_are_made_from_its_last_ones(monkeypatch: pytest.MonkeyPatch) -> None:
    """A loop's iterations' starts and ends are made from the rows of the ones before
    (``Run._ab_row``): their fields are not gathered again, but for a few."""
    gathered: list[object] = []
    gather = Run._decision_fields
    monkeypatch.setattr(Run, "_decision_fields",
                        lambda run, d: (gathered.append(d), gather(run, d))[1])
    made: list[dict[str, object]] = []
    Run(ROOT / "scenarios" / "thesis" / "sample-03.xml", rows=made.append).run()
    ends = [row for row in made if row["kind"] == "end"]
    assert len(ends) > 300
    assert len(gathered) < len(ends) / 3


@pytest.mark.pure  # (it counts roundings by patching the module's name: not in a compiled one)
def test_a_pose_equal_to_the_last_one_is_not_rounded_again(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # Kept by value, not by identity: the compiled build hands a pose over as three
    # floats, so a tuple kept by identity would never be found again there.
    calls: list[float] = []

    def counted(x: float, digits: int) -> float:
        calls.append(x)
        return round(x, digits)

    monkeypatch.setattr(prima.trace, "round", counted, raising=False)  # (the builtin, shadowed)
    x, y, heading = 1.23456, 2.0, 90.04
    first = prima.trace.rounded_pose((x, y, heading), 0)
    again = prima.trace.rounded_pose((x, y, heading), 0)  # (an equal tuple, made anew)
    assert again == first == {"x": 1.235, "y": 2.0, "heading": 90.0}
    assert again is not first  # (each line has a dict of its own)
    assert len(calls) == 3
    prima.trace.rounded_pose((x, 2.5, heading), 0)
    assert len(calls) == 6


def test_the_lines_numbers_are_rounded_as_round_rounds_them() -> None:
    # The compiled build rounds a line's numbers in floating point where that is exact
    # (trace._rounded): the same float as round(), its sign and all, halfway or not.
    rng = random.Random(7)
    values = [0.0, -0.0, 1e-9, -1e-9, 0.0004, -0.0004, 0.0005, -0.0005, 0.0015, 2.675,
              1.0005, 123.4565, 359.95, 359.96, 0.05, 0.15, 0.25, -2.5e-4, 1e300, -1e300,
              math.inf, -math.inf]
    for _ in range(20_000):
        scale = rng.choice([1.0, 10.0, 1000.0, 1e6, 1e13])
        values += [rng.uniform(-scale, scale), round(rng.uniform(-scale, scale), 4),
                   rng.randint(-10**6, 10**6) / 2000, rng.randint(-10**6, 10**6) / 20]
    for x in values:
        for digits in (1, 2, 3):
            assert struct.pack("<d", prima.trace._rounded(x, digits)) == \
                struct.pack("<d", round(x, digits)), (x, digits)
    assert math.isnan(prima.trace._rounded(math.nan, 3))
