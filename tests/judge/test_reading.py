"""The judge reading traces: trace files (every bad line located), a run's lines and
their jsonl alike, and whole runs of shipped scenarios (sample 5 under each set of rules;
each finder fed every kind of line it needs).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from prima.errors import TraceError
from prima.judge import MEASURES, Report, judge, judge_file, load_trace
from prima.judge._context import Ab
from tests.judge.helpers import ROOT, THESIS, counts
from tests.work import allocated


# ------------------------------------------------------------------ reading traces

def test_load_trace_locates_every_bad_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.jsonl"
    path.write_text("\n".join([
        '{"t": 0, "seq": 0, "kind": "load", "app": "fa"}',
        '{"t": 1, "seq": 1, "kind": "event", "text": "touched"',
        '',
        '{"t": 1, "kind": "event"}',
        '[1, 2]',
        '{"t": 2, "seq": 4, "kind": "start", "devices": "speaker"}',
        '{"t": 2, "seq": 5, "kind": "pose"}',
        '{"t": 0.5, "seq": 6, "kind": "pose"}',
        '{"t": 3, "seq": 7, "kind": "pose", "robot": {"x": 1}}',
    ]) + "\n", encoding="utf-8")
    with pytest.raises(TraceError) as caught:
        load_trace(path)
    assert [str(p) for p in caught.value.problems] == [
        f"{path}:2:54: error: not a JSON object: Expecting ',' delimiter",
        f"{path}:4:1: error: missing field 'seq'",
        f"{path}:5:1: error: a trace line must be a JSON object",
        f"{path}:6:1: error: field 'devices' has the wrong type (str)",
        f"{path}:8:1: error: time goes backwards (0.5 after 2)",
        f"{path}:9:1: error: field 'robot' needs numbers x, y and heading",
    ]


def test_a_line_too_long_is_read_past_never_held(tmp_path: Path) -> None:
    from prima.tracefile import MAX_LINE

    path = tmp_path / "long.jsonl"
    with path.open("w", encoding="utf-8") as out:  # 48 MiB on one line, then a good line
        out.write('{"t": 0, "seq": 0, "kind": "load", "app": "' + "x" * (48 << 20) + '"}\n'
                  '{"t": 1, "seq": 1, "kind": "load", "app": "fa"}\n')
    refused: list[TraceError] = []

    def read() -> None:
        try:
            load_trace(path)
        except TraceError as exc:
            refused.append(exc)

    _held, peak = allocated(read)
    assert [str(p) for p in refused[0].problems] == [
        f"{path}:1:1: error: the line is longer than {MAX_LINE:,} characters"]
    assert peak < 16 << 20, f"{peak:,} bytes to read past a long line"


def test_a_forged_start_line_that_names_no_command_is_judged_not_a_crash(
        tmp_path: Path) -> None:
    # (a start line's Command ids are optional to the reader: an AB that names none, one
    # linked after it, and one that never ends are judged, not an IndexError)
    path = tmp_path / "forged.jsonl"
    path.write_text("\n".join([
        '{"t": 0, "seq": 0, "kind": "start", "app": "a", "ab": 1, "devices": ["speaker"]}',
        '{"t": 0, "seq": 1, "kind": "request", "app": "a", "ab": 2, "before": 1, '
        '"detail": {"command_id": 2}}',
        '{"t": 100, "seq": 2, "kind": "log", "app": "a"}',
    ]) + "\n", encoding="utf-8")
    report = judge_file(path)
    assert [s.kind for s in report.of("stuck")] == ["ab"]


def test_an_empty_trace_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "empty.jsonl"
    path.write_text("\n", encoding="utf-8")
    with pytest.raises(TraceError, match="empty.jsonl:1:1: error: the trace has no lines"):
        load_trace(path)


def _forged(path: Path, running: int, poses: int) -> Path:
    """A trace in which ``running`` ABs that speak start and never end (their words' times
    unknown), then ``poses`` posed lines come."""
    poses_ = '"robot": {"x": 0, "y": 0, "heading": 0}, ' \
        '"user": {"x": 1, "y": 0, "heading": 180, "detectable": true}'
    lines = [f'{{"t": 0, "seq": {i}, "kind": "start", "app": "a", "ab": {i}, "tree": {i}, '
             f'"command": "Speak", "text": "hi", "devices": ["speaker"], '
             f'"detail": {{"command_id": {i}}}, {poses_}}}' for i in range(running)]
    lines += [f'{{"t": 0, "seq": {running + i}, "kind": "pose", {poses_}}}'
              for i in range(poses)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def test_a_forged_trace_with_more_abs_running_than_a_robot_has_is_refused(
        tmp_path: Path) -> None:
    from prima.tracefile import MAX_RUNNING

    path = _forged(tmp_path / "forged.jsonl", MAX_RUNNING + 2, 1)
    with pytest.raises(TraceError) as caught:
        judge_file(path)
    assert [str(p) for p in caught.value.problems] == [
        f"{path}:{line}:1: error: more than {MAX_RUNNING} atomic behaviors running at once "
        "(a robot runs one on each of its devices)" for line in (MAX_RUNNING + 1, MAX_RUNNING + 2)]


def test_abs_whose_words_are_not_yet_known_share_the_posed_lines_they_wait_for(
        tmp_path: Path) -> None:
    from prima.tracefile import MAX_RUNNING

    path = _forged(tmp_path / "forged.jsonl", MAX_RUNNING, 4000)
    _held, peak = allocated(lambda: judge_file(path))
    # (a pair per AB per posed line, for the unfaced and the leaving measures each, came
    # to about 37 MiB here; shared, the whole judging peaks at about 8)
    assert peak < 16 * 2**20, f"{peak / 2**20:.1f} MiB"


def test_a_trace_line_and_its_jsonl_are_judged_alike(tmp_path: Path) -> None:
    from prima.run import Run
    from prima.trace import jsonl_row

    lines = Run(THESIS / "fig5-7.xml").run()
    path = tmp_path / "fig5-7.jsonl"
    path.write_text("".join(map(jsonl_row, lines)), encoding="utf-8")
    assert judge(lines).to_dict() == judge(load_trace(path)).to_dict()


def test_lines_given_as_other_mappings_are_judged_as_their_dicts(tmp_path: Path) -> None:
    """The judge reads dicts (:data:`prima.tracefile.Row`: the compiled build reads their
    fields directly); a caller's read-only mappings, a line's and its detail's and poses',
    are judged as the same lines as dicts."""
    from types import MappingProxyType

    from prima.tracefile import rows

    lines = load_trace(_trace_file(tmp_path))
    frozen = [MappingProxyType({k: MappingProxyType(v) if isinstance(v, dict) else v
                                for k, v in line.items()}) for line in lines]
    made = list(rows(frozen))
    assert made == lines and all(type(r) is dict and all(
        type(v) is not MappingProxyType for v in r.values()) for r in made)
    assert judge(frozen).to_dict() == judge(lines).to_dict()


def _trace_file(folder: Path) -> Path:
    """Sample 3's trace, run and written to a jsonl file in ``folder``."""
    from prima.run import Run
    from prima.trace import jsonl_row

    path = folder / "sample-03.jsonl"
    path.write_text("".join(map(jsonl_row, Run(THESIS / "sample-03.xml").run())),
                    encoding="utf-8")
    return path


# ------------------------------------------------------------------ the shipped scenarios

def test_sample_05_is_natural_under_the_rules() -> None:
    """Figure 5.9's situation, mediated by every policy: no fault at all."""
    report = judge_file(THESIS / "sample-05.xml")
    assert report.ok and counts(report) == {}


def test_sample_05_under_the_thesis_rules_has_exactly_its_split_exchange() -> None:
    """With every policy off (the thesis' PaPeRo), FA5's news of the video server comes
    between the user's answer to EA2 and EA2's reply: the split the thesis' subjects
    disliked; EA2's reply, kept waiting for it, is late by the amended rules (7.4), and
    nothing else."""
    from prima.run import Switches

    report = judge_file(THESIS / "sample-05.xml", switches=Switches(policies=(("all", False),)))
    assert counts(report) == {"late": 1, "splits": 1}
    (s,) = report.of("splits")
    assert (s.kind, s.app, s.by, s.text, s.t) == (
        "reply", "ea2-library", "fa5-video-timer", "The video setting succeeds.", 40.8)
    answered = next(r for r in report.reactions if r.text == "The C Primer.")
    assert answered.t == 40.8 and answered.app == "ea2-library"
    assert s.anchor_seq < s.seq < answered.first_start_seq  # answer, FA5, EA2's reply


def test_sample_05_with_an_explicit_stream_has_none() -> None:
    """FA5's video-server exchange in an explicit stream keeps it whole, even with every
    other policy off."""
    from prima.run import Switches

    off = Switches(policies=(("all", False), ("streams", True)))
    assert judge_file(THESIS / "sample-05-stream.xml", switches=off).of("splits") == ()


@pytest.mark.parametrize("scenario", [
    "policies/connect-channel-off.xml", "policies/restore-state-off.xml",
    "policies/streams-off.xml", "examples/barge-in-question.xml", "thesis/sample-08.xml"])
def test_each_finder_is_fed_every_kind_of_line_it_needs(scenario: str,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    # A finder is fed only the kinds of line it names; fed every line, it finds the same.
    from prima.run import Run

    lines = Run(ROOT / "scenarios" / scenario).run()
    narrow = judge(lines)
    for m in MEASURES:
        monkeypatch.setattr(type(m.finder()), "kinds", None)
    every = judge(lines)
    assert (every.reactions, dict(every.findings)) == (narrow.reactions, dict(narrow.findings))
    assert any(narrow.findings.values()) or narrow.reactions


def test_a_scenario_is_judged_as_it_runs_holding_none_of_its_lines(tmp_path: Path) -> None:
    # (an EA whose timers fire on every step makes a long trace of lines no measure keeps:
    # judged after the run, they were all held, some 33 MiB here, growing with the run)
    (tmp_path / "map.xml").write_text(
        '<map xmlns="urn:prima:map:1" name="m"><place name="a" x="0" y="0"/></map>\n')
    timers = range(20)
    (tmp_path / "ea.pxml").write_text(
        '<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t">'
        + "".join(f'<on event="t{i}"><timer name="t{i}" after="0.01"/></on>' for i in timers)
        + '<state id="s" initial="true"><entry>'
        + "".join(f'<timer name="t{i}" after="0.01"/>' for i in timers)
        + "</entry></state></pxml>\n")
    scenario = tmp_path / "s.xml"
    scenario.write_text('<scenario xmlns="urn:prima:scenario:1" name="s" until="20">'
                        '<map href="map.xml"/><apps ea="ea.pxml"/><robot place="a"/>'
                        "</scenario>\n")
    reports: list[Report] = []
    _held, peak = allocated(lambda: reports.append(judge_file(scenario)))
    report = reports[0]
    assert report.lines > 30_000
    assert peak < 16 * 2**20, f"{peak / 2**20:.1f} MiB"


def test_an_ab_s_written_out_init_takes_its_fields_in_their_order() -> None:
    """``Ab.__init__`` is written out (compiled, it is not the one ``dataclass`` writes):
    a field added to the class and left out of it would be read as the class's default."""
    given = (7, "fa", 2, "Speak", (3,), frozenset({"speaker"}), 1.5, 9, "free", "hi", True,
             4, (1.5, 2.0), (1.6, 2.1), 3.0, 12, "done", True, True, 5)
    ab = Ab(*given)
    fields = dataclasses.fields(Ab)
    assert tuple(getattr(ab, f.name) for f in fields) == given
    short = Ab(*given[:9])
    for f in fields[9:]:
        assert getattr(short, f.name) == f.default
    assert ab == dataclasses.replace(ab) and repr(ab).startswith("Ab(id=7, app='fa',")
