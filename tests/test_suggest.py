"""Did you mean ...? for misspelt state names, element names and command-line options,
as misspelt Commands already had."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from prima.cli import main
from prima.suggest import similar

PXML = ('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="t">{}</pxml>\n')


def _validate(tmp_path: Path, body: str) -> str:
    path = tmp_path / "t.pxml"
    path.write_text(PXML.format(body))
    out = io.StringIO()
    main(["validate", str(path)], out=out, err=io.StringIO())
    return out.getvalue()


@pytest.mark.parametrize("name, names, meant", [
    ("guid", ["asking", "guide"], "guide"), ("b", ["a", "bb"], None), ("GUIDE", ["guide"], "guide"),
    ("gudie", ["guide"], "guide"), ("far", ["guide"], None),
])
def test_similar(name: str, names: list[str], meant: str | None) -> None:
    assert similar(name, names) == meant


def test_a_misspelt_state_name(tmp_path: Path) -> None:
    said = _validate(tmp_path, '<state id="guide" initial="true"><entry><goto state="gide"/>'
                               "</entry></state>")
    assert "no state has the id 'gide'; did you mean 'guide'?" in said, said


def test_a_misspelt_element_name(tmp_path: Path) -> None:
    said = _validate(tmp_path, '<stat id="s" initial="true"/><state id="t" initial="true"/>')
    assert "<stat> is not allowed at the top of the document; did you mean <state>?" in said


@pytest.mark.parametrize("argv, hint", [
    (["run", "x.xml", "--fomat", "jsonl"], "(--fomat: did you mean --format?)"),
    (["validate", "apps", "-robot", "r.xml"], "(-robot: did you mean --robot?)"),
    (["judge", "x.jsonl", "--max-lates=2"], "(--max-lates: did you mean --max-late?)"),
])
def test_a_misspelt_option(argv: list[str], hint: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"prima {argv[0]}: error: unrecognized arguments: " in err and hint in err, err


def test_a_misspelt_event_field_is_warned_of(tmp_path: Path) -> None:
    said = _validate(tmp_path, '<state id="s" initial="true"><entry><chain>hi: Speak("hi")'
                               '</chain></entry><on-end of="hi" cond="event.eror == null">'
                               '<log text="{event.txet} {event.text}"/></on-end></state>')
    lines = [x for x in said.splitlines() if "warning" in x]
    assert len(lines) == 2, said
    assert "event field 'eror' is not one PRIMA's events carry" in lines[0]
    assert lines[0].endswith("did you mean 'error'?") and lines[1].endswith("'text'?")


def test_a_scenario_input_after_its_end_is_warned_of(tmp_path: Path) -> None:
    (tmp_path / "map.xml").write_text('<map xmlns="urn:prima:map:1" name="m">'
                                      '<place name="a" x="0" y="0"/></map>\n')
    path = tmp_path / "s.xml"
    path.write_text('<scenario xmlns="urn:prima:scenario:1" name="s" until="10">\n'
                    '  <map href="map.xml"/>\n  <robot place="a"/>\n'
                    '  <user x="1" y="0"><touch at="4"/><touch at="12"/></user>\n'
                    '  <message at="9.9" sender="host" text="in time"/>\n'
                    '  <message at="20" sender="host" text="late"/>\n</scenario>\n')
    out = io.StringIO()
    assert main(["validate", str(path)], out=out, err=io.StringIO()) == 0
    assert out.getvalue().splitlines() == [
        f"{path}:4:47: warning: the user's <touch> at 12 s is timed at or after the run ends "
        "(until=10 s): it never happens",
        f"{path}:6:16: warning: this <message> at 20 s is timed at or after the run ends "
        "(until=10 s): it never happens"]


def test_a_misspelt_required_option(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["sweep", "x.xml", "--runs", "2", "--jiter", "3"]) == 2
    err = capsys.readouterr().err
    assert err.rstrip().endswith("prima sweep: error: the following arguments are required: "
                                 "--jitter (--jiter: did you mean --jitter?)"), err


@pytest.mark.parametrize("argv, hint, meant", [
    (["valdiate", "apps"], "argument COMMAND: invalid choice: 'valdiate' (choose from ",
     "validate"),
    (["run", "x.xml", "--format", "jsnol"], "argument --format: invalid choice: 'jsnol'",
     "jsonl"),
    (["judge", "x.jsonl", "--color", "alwyas"], "argument --color: invalid choice: 'alwyas'",
     "always"),
    (["completion", "bahs"], "argument SHELL: invalid choice: 'bahs'", "bash"),
])
def test_a_misspelt_choice(argv: list[str], hint: str, meant: str,
                           capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.rstrip()
    assert hint in err and err.endswith(f"; did you mean '{meant}'?"), err


@pytest.mark.parametrize("command", ["run", "debug", "test", "judge", "sweep", "show", "plot"])
def test_a_misspelt_policy_name(command: str) -> None:
    scenario = Path(__file__).parents[1] / "scenarios" / "thesis" / "sample-03.xml"
    argv = [command, str(scenario), "--policy", "interupt=on"]
    argv += {"sweep": ["--runs", "1", "--jitter", "0"], "plot": ["-o", "x.svg"]}.get(command, [])
    err = io.StringIO()
    assert main(argv, out=io.StringIO(), err=err) == 2
    assert err.getvalue() == (
        f"prima {command}: error: --policy interupt=on: no policy 'interupt' (known: all, "
        "restore-state, interrupt, blend, streams, connect-channel, reactions, barge-in, "
        "exchange); did you mean 'interrupt'?\n")
