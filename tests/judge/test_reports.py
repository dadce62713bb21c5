"""The judge's thresholds and reports, ``prima judge``'s command line, and the
``prima_judge`` pytest fixture.
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import pytest

from prima.cli import main
from prima.judge import LIMITS, MEASURES, PARAMETERS, Thresholds, format_table
from tests.judge.helpers import ROOT, THESIS, Trace, clean, reaction_behind

pytest_plugins = ["pytester"]


# ------------------------------------------------------------------ thresholds and reports

def test_every_measure_has_a_threshold_and_an_option() -> None:
    """The measures, the report's counts, the thresholds and the options of ``prima
    judge`` all come from one table."""
    keys = ["late", "unheard", "unfaced", "leaving", "elsewhere", "splits", "silences",
            "barge_in", "ignored", "recovery", "stuck"]
    assert [m.key for m in MEASURES] == [m.key for m in LIMITS] == keys
    assert list(clean().judge().counts()) == keys
    assert [m.option for m in MEASURES] == [f"--max-{k.replace('_', '-')}" for k in keys]
    assert Thresholds().limits == {f"max_{k}": 0 for k in keys}
    assert [p.option for p in PARAMETERS] == [
        "--reaction-slack", "--utterance-slack", "--react-within", "--face-tolerance",
        "--unfaced-for", "--leave-distance", "--resume-distance", "--barge-in-slack",
        "--answer-slack", "--recovery-slack", "--silence", "--stuck-after", "--search-after"]


def test_thresholds_allow_what_they_say() -> None:
    tr = reaction_behind(speech_ends=12.0, reacts_at=12.4)
    assert not tr.judge().ok
    assert tr.judge(max_late=1).ok
    assert tr.judge(reaction_slack=0.5).ok
    assert Thresholds(max_splits=2).limit("splits") == 2
    assert Thresholds(max_splits=2).replace(silence=3).to_dict()["max_splits"] == 2


@pytest.mark.parametrize("bad, message", [
    ({"max_late": -1}, "max_late must be a number from 0 up"),
    ({"silence": float("nan")}, "silence must be a number from 0 up"),
    ({"max_splits": 1.5}, "max_splits must be a whole number"),
    ({"leave_distance": "far"}, "leave_distance must be a number"),
    ({"max_lat": 1}, "did you mean 'max_late'"),
])
def test_bad_thresholds_are_refused(bad: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Thresholds(**bad)


def test_report_dict_has_stable_keys_and_is_json() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    d = report.to_dict()
    assert list(d) == ["name", "end", "lines", "thresholds", "counts", "reactions", "late",
                       "unheard", "unfaced", "leaving", "elsewhere", "splits", "silences",
                       "barge_in", "ignored", "recovery", "stuck", "breaches", "ok"]
    assert d["counts"] == {"reactions": 1, "late": 1, "unheard": 0, "unfaced": 0,
                           "leaving": 0, "elsewhere": 0, "splits": 0, "silences": 0,
                           "barge_in": 0, "ignored": 0, "recovery": 0, "stuck": 0}
    assert d["late"] == [d["reactions"][0]]
    assert json.loads(json.dumps(d)) == d


def test_the_table_shows_reactions_counts_and_a_summary() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    table = format_table([report])
    assert "touched" in table and "LATE: started after 2.4 s: free to start for 0.4 s" in table
    assert table.splitlines()[-1].startswith("hand-written  reactions 1")
    assert table.splitlines()[-1].endswith("FAIL: late reactions 1 > 0")


def test_the_counts_of_every_measure_stand_in_one_column() -> None:
    """The longest title (unrecovered interruptions) does not push its count out."""
    table = format_table([reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()])
    titled = {m.title: line for line in table.splitlines() for m in MEASURES
              if line.startswith(f"  {m.title} ")}
    assert len(titled) == len(MEASURES)
    columns = {line.index(line.split()[-1] if "max" not in line else line.split()[-4])
               for line in titled.values()}
    assert len(columns) == 1, titled


# ------------------------------------------------------------------ the command line

def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def write(tmp_path: Path, trace: Trace, name: str = "run.jsonl") -> Path:
    path = tmp_path / name
    path.write_text("".join(json.dumps(r) + "\n" for r in trace.rows), encoding="utf-8")
    return path


def test_cli_exit_codes_follow_the_thresholds(tmp_path: Path) -> None:
    good = write(tmp_path, clean(), "good.jsonl")
    late = write(tmp_path, reaction_behind(speech_ends=12.0, reacts_at=12.4), "late.jsonl")
    assert cli("judge", str(good))[0] == 0
    code, out, err = cli("judge", str(good), str(late))
    assert code == 1 and "FAIL: late reactions 1 > 0" in out
    assert "2 run(s) judged: 1 exceeded a threshold" in err
    assert cli("judge", "--max-late", "1", str(late))[0] == 0
    assert cli("judge", "--reaction-slack", "0.5", str(late))[0] == 0
    assert cli("judge", "--react-within", "0.2", str(good))[0] == 0


@pytest.mark.parametrize("limit", LIMITS, ids=lambda m: m.key)
def test_cli_has_an_option_for_every_measure(limit: Any, tmp_path: Path) -> None:
    good = write(tmp_path, clean(), "good.jsonl")
    code, _, err = cli("judge", limit.option, "2", "--format", "json", str(good))
    assert code == 0, err


def test_cli_json(tmp_path: Path) -> None:
    late = write(tmp_path, reaction_behind(speech_ends=12.0, reacts_at=12.4))
    code, out, _ = cli("judge", "--format", "json", str(late))
    data = json.loads(out)
    assert code == 1 and data["ok"] is False and data["errors"] == 0
    run = data["runs"][0]
    assert run["counts"]["late"] == 1 and run["counts"]["unheard"] == 0
    assert run["late"][0]["why"].startswith("started after 2.4 s")
    assert run["late"][0]["waits"][0]["rule"] == "uncut: not interruptible"


def test_cli_reports_a_bad_trace_located_without_a_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"t": 0, "seq": 0, "kind": "pose"}\nnot json\n', encoding="utf-8")
    good = write(tmp_path, clean(), "good.jsonl")
    code, out, err = cli("judge", str(bad), str(good))
    assert code == 1
    assert f"{bad}:2:1: error: not a JSON object" in err and "Traceback" not in err
    assert "good.jsonl" in out  # the other run is judged all the same


@pytest.mark.parametrize("argv, fragment", [
    (["judge", "no/such.jsonl"], "no such file or folder"),
    (["judge", "--max-late", "-1", "x.jsonl"], "--max-late must be a number from 0 up"),
    (["judge", "--silence", "soon", "x.jsonl"], "invalid float value"),
    (["judge", "README.md"], "give a trace (*.jsonl), a scenario (*.xml) or a folder"),
    (["judge", "schemas"], "no scenario in schemas"),
])
def test_cli_usage_errors_exit_2(argv: list[str], fragment: str,
                                 capsys: pytest.CaptureFixture[str],
                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    code, _, err = cli(*argv)
    assert code == 2
    assert fragment in err + capsys.readouterr().err


def test_cli_judges_a_scenario_in_process_and_writes_nothing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    code, out, _ = cli("judge", str(THESIS / "fig5-7.xml"))
    assert code == 0 and out.splitlines()[-1].endswith("  ok")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ the pytest fixture

def test_the_prima_judge_fixture(pytester: pytest.Pytester) -> None:
    trace = pytester.path / "late.jsonl"
    rows = reaction_behind(speech_ends=12.0, reacts_at=12.4).rows
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows), encoding="utf-8")
    pytester.makepyfile(test_mine="""
        def test_passes_with_a_looser_threshold(prima_judge):
            report = prima_judge("late.jsonl", max_late=1)
            assert report.counts()["late"] == 1

        def test_fails_with_the_report(prima_judge):
            prima_judge("late.jsonl")
    """)
    result = pytester.runpytest()
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["*late.jsonl: late reactions: 1 > 0*", "*LATE: started after*"])


