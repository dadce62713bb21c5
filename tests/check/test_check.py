"""prima check: an EA judged beside FAs on robots; each failure attributed to the
application whose doing it is; the EA's coverage; JUnit and Markdown for CI; the worst
runs written as scenarios that replay them; the same results whatever runs them."""

from __future__ import annotations

import io
import json
import re
import time
from pathlib import Path

import pytest
from lxml import etree

from prima.batch import Inline, Processes
from prima.check import (
    VISITS,
    Coverage,
    Verdict,
    Visit,
    attribute,
    check,
    destinations,
    format_check,
    junit,
    map_for,
    visit_scenario,
)
from prima.cli import main
from prima.dsl import default_profile, load_document
from prima.shipped import shipped
from prima.judge import (
    MEASURES,
    BargeIn,
    Blame,
    Ignored,
    Recovery,
    Report,
    Split,
    Thresholds,
    Unfaced,
)
from prima.scenario import load_map, load_scenario

ROOT = Path(__file__).parents[2]
DATA = ROOT / "tests" / "data" / "check"
HOME = ROOT / "robots" / "home-robot.xml"
GUIDE = ROOT / "robots" / "guide-robot.xml"
TALKER, MUTE = DATA / "talker.pxml", DATA / "mute.pxml"
"""An EA that behaves, and one that says nothing when it does not understand."""
RUNAWAY, QUIET = DATA / "runaway.pxml", DATA / "quiet.pxml"
"""An FA that drives the robot away at once, and one that does nothing."""
STANDING = DATA / "standing.xml"
"""The EA's own scenario: a visitor who stands behind the robot."""
MAPS = ROOT / "scenarios" / "maps"


def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


# ------------------------------------------------------------ whose failure it is

def test_a_failure_the_fa_causes_is_the_fas_and_the_check_passes(tmp_path: Path) -> None:
    code, out, _ = cli("check", str(TALKER), "--fa", str(RUNAWAY), "--fa", str(QUIET),
                       "--robot", str(HOME), "--scenario", str(STANDING), "--runs", "2",
                       "--jobs", "1", "--out", str(tmp_path / "worst"))
    assert code == 0, out
    assert "runaway     fail FA" in out and "quiet       ok" in out
    assert ("leaving in 2 run(s): the FA's, runaway runaway.pxml:8:20: its SetSpeedAndTime "
            "took the robot away from the user while talker spoke") in out
    assert ("unfaced in 2 run(s): the FA's, runaway runaway.pxml:8:20: its SetSpeedAndTime "
            "moved the robot") in out
    assert "0 failed by the EA, 1 by others only" in out


def test_a_failure_the_ea_causes_is_the_eas_and_the_check_fails(tmp_path: Path) -> None:
    code, out, _ = cli("check", str(MUTE), "--fa", str(QUIET), "--robot", str(HOME),
                       "--runs", "2", "--jobs", "1", "--out", str(tmp_path / "worst"))
    assert code == 1
    assert "quiet       FAIL EA  silences 2/8" in out
    assert ("silences in 2 run(s): the EA's, mute mute.pxml:11:12: said nothing after the "
            "user's answer") in out


def _report(findings: dict[str, tuple[object, ...]]) -> Report:
    return Report("r", 10.0, 5, Thresholds(), (), findings)  # type: ignore[arg-type]


def test_a_split_is_the_intruders_and_an_unfaced_utterance_the_wheels_holders() -> None:
    split = Split(12, 3.0, "guide", "emotions", "Hee-hee!", "reply", 10, "fa1.pxml:38:7")
    unfaced = Unfaced(20, 5.0, "guide", "Speak", "Look.", 120.0, "guide.pxml:9:7")
    roles = {"guide": "ea", "emotions": "fa"}
    found = attribute(_report({"splits": (split,), "unfaced": (unfaced,)}), roles)
    assert [(f["measure"], f["app"], f["role"], f["at"]) for f in found] == [
        ("unfaced", "guide", "ea", "guide.pxml:9:7"),
        ("splits", "emotions", "fa", "fa1.pxml:38:7")]
    held = {20: Blame("emotions", 4, "Turn", "fa1.pxml:50:7", "on the wheels")}
    found = attribute(_report({"unfaced": (unfaced,)}), roles, held)
    assert (found[0]["app"], found[0]["role"], found[0]["at"]) == ("emotions", "fa",
                                                                   "fa1.pxml:50:7")
    assert attribute(_report({"splits": (split,)}), roles | {"emotions": "other"})[0][
        "role"] == "other"


def test_an_answer_over_a_prompt_hushed_before_its_words_runs() -> None:
    """EA1 beside FA2 on the home robot: a visitor's words hushed a Q&A whose words had
    not begun, and an answer came over that prompt at the same instant; the simulator
    looked for the words it was saying and the run failed (KeyError). Every run of the
    cell is judged now."""
    result = check(ROOT / "apps" / "ea" / "ea1-museum.pxml",
                   fas=[ROOT / "apps" / "fa" / "fa2-follow.pxml"], robots=[HOME], maps=MAPS,
                   runs=1, pool=Inline())
    (cell,) = result.cells
    assert (cell.done, cell.failed, cell.errors) == (4, 0, [])


def test_every_kind_of_finding_is_attributed() -> None:
    """The user's voice's measures too (a check of an EA that takes the user's words and
    leaves them unanswered failed every such run with 'not a finding')."""
    roles = {"guide": "ea", "emotions": "fa"}
    findings = {
        "barge_in": (BargeIn(30, 4.0, "Stop.", "guide", "Speak", None, 1.2, 0.5,
                             "guide.pxml:9:7"),),
        "ignored": (Ignored(31, 5.0, "Repeat that.", "guide", None, 1.0, "guide.pxml:12:3"),),
        "recovery": (Recovery(32, 6.0, "emotions", "Speak", None, 0.8, "fa1.pxml:38:7"),)}
    found = attribute(_report(findings), roles)
    assert [(f["measure"], f["app"], f["role"], f["rule"]) for f in found] == [
        ("barge_in", "guide", "ea", "its Speak talked on over the user"),
        ("ignored", "guide", "ea", "took the user's words and never answered them"),
        ("recovery", "emotions", "fa", "its Speak did not go on after a false interruption")]
    # (a new measure's findings need attributing too: this test names every measure)
    assert {m.key for m in MEASURES} == {"late", "unheard", "unfaced", "leaving", "elsewhere",
                                         "splits", "silences", "barge_in", "ignored",
                                         "recovery", "stuck"}


# ------------------------------------------------------------ coverage

def test_coverage_names_what_never_ran_and_min_coverage_fails_the_check(
        tmp_path: Path) -> None:
    result = check(TALKER, fas=[QUIET], robots=[HOME], maps=MAPS, runs=1, pool=Inline())
    missed = {(i.kind, i.label, i.line) for i in result.coverage.missed()}
    assert missed == {("states", "state 'never'", 23), ("commands", "Speak", 24)}
    assert result.coverage.lines() == [23, 24]
    assert round(result.coverage.percent) == 89
    code, out, err = cli("check", str(TALKER), "--fa", str(QUIET), "--robot", str(HOME),
                         "--runs", "1", "--jobs", "1", "--min-coverage", "95",
                         "--out", str(tmp_path))
    assert code == 1 and "coverage 89% is below --min-coverage 95" in err
    assert "lines not wholly exercised: 23-24" in out
    assert cli("check", str(TALKER), "--fa", str(QUIET), "--robot", str(HOME), "--runs", "1",
               "--jobs", "1", "--min-coverage", "80", "--out", str(tmp_path))[0] == 0


@pytest.mark.parametrize("pattern, nomatch", [("*", False), ("i am *", True)])
def test_a_grammar_that_takes_any_words_has_no_answer_it_does_not_take(
        tmp_path: Path, pattern: str, nomatch: bool) -> None:
    """Coverage lists what a run can reach: a pattern of ``*`` alone takes every answer."""
    ea = tmp_path / "who.pxml"
    ea.write_text('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="who">\n'
                  f'  <grammar id="g"><pattern>{pattern}</pattern></grammar>\n'
                  '  <state id="s" initial="true"><entry>'
                  '<chain>who: QA("Who are you?", g)</chain></entry></state>\n</pxml>\n')
    labels = [i.label for i in Coverage(load_document(ea, default_profile())).items
              if i.kind == "answers"]
    assert labels == [f"who: QA -> pattern '{pattern}'",
                      *(["who: QA -> an answer it does not take"] if nomatch else []),
                      "who: QA -> silence"]


def test_each_visitor_reaches_an_answer_the_others_do_not() -> None:
    answers = {}
    for visitor in VISITS:
        result = check(TALKER, fas=[QUIET], robots=[HOME], maps=MAPS, runs=1, pool=Inline(),
                       visitors=(visitor,))
        answers[visitor] = {i.key[2] for i in result.coverage.items
                            if i.kind == "answers" and result.coverage.covered(i)}
    assert answers == {"willing": {"choice:yes"}, "declining": {"choice:no"},
                       "hesitant": {"nomatch"}, "silent": {"noinput"}}


# ------------------------------------------------------------ generated visits

def test_a_visit_answers_from_the_grammars_and_sends_what_the_ea_listens_for(
        tmp_path: Path) -> None:
    ea = load_document(ROOT / "apps" / "ea" / "cafe.pxml", default_profile())
    fa = load_document(ROOT / "apps" / "fa" / "fa1-emotions.pxml", default_profile())
    maps = [(MAPS / "museum.xml", load_map(MAPS / "museum.xml"))]
    world = map_for(ea, maps)
    assert world is not None
    text = visit_scenario(Visit("willing"), ea, fa, world,
                          (ROOT / "apps" / "ea" / "cafe.pxml", ROOT / "apps" / "fa" /
                           "fa1-emotions.pxml"))
    path = tmp_path / "visit.xml"
    path.write_text(text)
    scenario = load_scenario(path)  # a valid scenario
    assert scenario.user is not None
    root = etree.fromstring(text.encode())
    ns = {"s": "urn:prima:scenario:1"}
    said = [(a.get("contains"), a.get("nth"), a.get("say")) for a in root.iterfind(
        "s:user/s:answer", ns)]
    assert said == [("Shall I keep a table for you?", "1", "Yes."),
                    ("Shall I keep a table for you?", None, "No.")]
    assert [(m.get("sender")) for m in root.iterfind("s:message", ns)] == ["cafe"]
    (reply,) = root.iterfind("s:reply", ns)
    assert reply.get("to") == "cafe" and reply.get("text", "").startswith("reserved")
    actions = [etree.QName(a).localname for a in root.find("s:user", ns) if
               etree.QName(a).localname != "answer"]
    assert actions == ["follow", "touch", "leave", "follow", "say", "touch"]
    (remark,) = root.iterfind("s:user/s:say", ns)  # (FA1 answers its name at any time)
    assert (remark.get("at"), remark.get("text")) == ("115", "Papero.")


def test_a_visit_lists_its_messages_and_sounds_in_time_order(tmp_path: Path) -> None:
    """An EA that listens to two senders (messages at 45 and 85 s) beside FA3, which
    listens for a tune (at 60 s): the sound goes between them, so that the visit loads
    (it was an n/a cell: a sound listed after a later message)."""
    ea_path = tmp_path / "desk.pxml"
    ea_path.write_text('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="desk">\n'
                       '  <on event="message" cond="event.sender == \'host\'">'
                       '<chain>Speak("From the host.")</chain></on>\n'
                       '  <on event="message" cond="event.sender == \'security\'">'
                       '<chain>Speak("From security.")</chain></on>\n'
                       '  <state id="s" initial="true"/>\n</pxml>\n')
    fa_path = ROOT / "apps" / "fa" / "fa3-dance.pxml"
    ea, fa = (load_document(p, default_profile()) for p in (ea_path, fa_path))
    maps = [(MAPS / "office.xml", load_map(MAPS / "office.xml"))]
    world = map_for(ea, maps)
    assert world is not None
    text = visit_scenario(Visit("willing"), ea, fa, world, (ea_path, fa_path))
    path = tmp_path / "visit.xml"
    path.write_text(text)
    load_scenario(path)  # a valid scenario
    root = etree.fromstring(text.encode())
    inputs = [(etree.QName(e).localname, e.get("at")) for e in root
              if etree.QName(e).localname in ("message", "sound")]
    assert inputs == [("message", "45"), ("sound", "60"), ("message", "85")]


@pytest.mark.parametrize("visitor, said", [
    ("willing", [("115", "Toilet."), ("127", "Stop."), ("139", "Repeat that."),
                 ("151", "Papero.")]),
    ("declining", [("115", "Exit."), ("127", "Stop."), ("139", "Repeat that."),
                   ("151", "Papero.")]),
    ("hesitant", [("115", "Uh-huh.")]),
    ("silent", [])])
def test_a_visitor_speaks_of_their_own_accord_to_what_the_apps_hear_at_any_time(
        visitor: str, said: list[tuple[str, str]]) -> None:
    """EA1 listens for a place at any time (its places grammar: the willing visitor says
    the first, the declining one the last) and for "stop" and "repeat" (its handlers
    look for those answers: both said); FA1 for its name. In time order with the
    second touch (135 s)."""
    ea_path = ROOT / "apps" / "ea" / "ea1-museum.pxml"
    fa_path = ROOT / "apps" / "fa" / "fa1-emotions.pxml"
    ea = load_document(ea_path, default_profile())
    fa = load_document(fa_path, default_profile())
    world = map_for(ea, [(MAPS / "museum.xml", load_map(MAPS / "museum.xml"))])
    assert world is not None
    root = etree.fromstring(visit_scenario(Visit(visitor), ea, fa, world,
                                           (ea_path, fa_path)).encode())
    ns = {"s": "urn:prima:scenario:1"}
    assert [(a.get("at"), a.get("text")) for a in root.iterfind("s:user/s:say", ns)] == said
    times = [float(a.get("at", "0")) for a in root.find("s:user", ns) if a.get("at")]
    assert times == sorted(times)


def test_a_map_given_that_lacks_the_eas_places_says_which_and_where(tmp_path: Path) -> None:
    museum = ROOT / "apps" / "ea" / "ea1-museum.pxml"
    code, _, err = cli("check", str(museum), "--fa", str(QUIET), "--robot", str(HOME),
                       "--map", str(MAPS / "office.xml"), "--runs", "1")
    assert code == 2, err
    assert (f"prima check: error: --map {MAPS / 'office.xml'} lacks panel-1 ({museum}:68:72: "
            f"TopologicalMove), panel-2 ({museum}:128:130: TopologicalMove)") in err


def test_no_shipped_map_with_the_eas_places_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"no map in .* has every place ea1-museum can go to "
                                         r"\(panel-1 \(.*ea1-museum.pxml:68:72: Topologic"):
        check(ROOT / "apps" / "ea" / "ea1-museum.pxml", fas=[QUIET], robots=[HOME],
              maps=_only(tmp_path, "office.xml", "library.xml"), runs=1)


def _only(folder: Path, *names: str) -> Path:
    """A folder of some of the shipped maps."""
    for name in names:
        (folder / name).write_bytes((MAPS / name).read_bytes())
    return folder


USHER = DATA / "usher.pxml"
"""An EA whose places come only through variables: a Q&A's answer, an answer heard at any
time, a constant and another variable; all on the office map, none on the library's."""


def test_the_places_an_ea_goes_to_through_its_variables_are_known() -> None:
    document = load_document(USHER, default_profile())
    found = [(d.command, d.loc.line, sorted(d.places or ())) for d in destinations(document)]
    assert found == [("TopologicalMove", 21, ["corner", "kidode-room", "poster"]),
                     ("TopologicalMove", 29, ["corner", "kidode-room", "poster"]),
                     ("TopologicalMove", 38, ["hall"])]


def test_an_ea_whose_places_come_through_a_variable_is_checked_on_a_map_with_them() -> None:
    """Not on the library map, the first shipped one, which has none of them: there the
    EA would never have guided anyone, and every cell would have said ok."""
    result = check(USHER, fas=[QUIET], robots=[HOME], maps=MAPS, runs=1, pool=Inline(),
                   visitors=("willing",))
    assert result.map == MAPS / "office.xml"
    (cell,) = result.cells
    assert cell.maps == [MAPS / "office.xml"] and cell.done == 1
    assert "on the map office (" in format_check(result)
    hit = {i.label for i in result.coverage.items if i.kind == "commands"
           and result.coverage.covered(i)}
    assert "TopologicalMove" in hit  # (it went somewhere: the map has the place)


def _ea(folder: Path, handlers: str, grammars: str = "") -> Path:
    path = folder / "guess.pxml"
    path.write_text('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="guess">\n'
                    f'  <var name="goal" expr="\'\'"/>\n{grammars}{handlers}'
                    '  <state id="s" initial="true"/>\n</pxml>\n')
    return path


@pytest.mark.parametrize("handlers, grammars, why", [
    ('  <on event="message">\n    <assign name="goal" expr="event.text"/>\n'
     "    <chain>TopologicalMove({goal})</chain>\n  </on>\n", "",
     "'goal' is set to event.text at line 4"),
    ('  <on event="speech" match="g">\n    <assign name="goal" expr="event.answer"/>\n'
     "    <chain>TopologicalMove({goal})</chain>\n  </on>\n",
     '  <grammar id="g"><pattern>go to *</pattern></grammar>\n',
     "grammar 'g' has patterns"),
    ('  <on event="human-found">\n    <chain>TopologicalMove({goal + \'-room\'})</chain>\n'
     "  </on>\n", "", "its to is the expression goal + '-room'"),
    ('  <on event="speech">\n    <assign name="goal" expr="event.answer"/>\n'
     "    <chain>TopologicalMove({goal})</chain>\n  </on>\n", "", "takes any words"),
])
def test_a_place_nobody_can_know_asks_for_a_map_at_its_command(
        tmp_path: Path, handlers: str, grammars: str, why: str) -> None:
    ea = _ea(tmp_path, handlers, grammars)
    line = next(i for i, text in enumerate(ea.read_text().splitlines(), start=1)
                if "TopologicalMove" in text)
    code, _, err = cli("check", str(ea), "--fa", str(QUIET), "--robot", str(HOME),
                       "--runs", "1", "--jobs", "1")
    assert code == 2, err
    assert f"prima check: error: {ea}:{line}:" in err and why in err, err
    assert "TopologicalMove goes to a place nobody can know before it runs" in err
    assert "give --map MAP" in err
    code, out, err = cli("check", str(ea), "--fa", str(QUIET), "--robot", str(HOME),
                         "--runs", "1", "--jobs", "1", "--map", str(MAPS / "office.xml"),
                         "--worst", "0")
    assert code == 0 and "on the map office" in out, err


def test_no_map_at_all_is_said_so(tmp_path: Path) -> None:
    """An install without the shipped maps (a wheel): the check says what is missing."""
    with pytest.raises(ValueError, match=r"no map to make visits on \(no .*/\*\.xml\): "
                                         "give --map or --scenario"):
        check(ROOT / "apps" / "ea" / "cafe.pxml", fas=[QUIET], robots=[HOME], maps=tmp_path,
              runs=1)


# ------------------------------------------------------------ the matrix and CI

def test_the_matrix_has_a_row_per_fa_and_a_column_per_robot_and_ci_files(
        tmp_path: Path) -> None:
    fa7 = ROOT / "apps" / "fa" / "fa7-spotlight.pxml"
    code, out, err = cli("check", str(MUTE), "--fa", str(QUIET), "--fa", str(fa7),
                         "--robot", str(HOME), "--robot", str(GUIDE), "--runs", "1",
                         "--jobs", "1", "--out", str(tmp_path / "worst"),
                         "--junit", str(tmp_path / "j.xml"),
                         "--summary", str(tmp_path / "s.md"))
    assert code == 1, err
    lines = out.splitlines()
    head = next(i for i, line in enumerate(lines) if "FA \\ robot" in line)
    assert lines[head].split() == ["FA", "\\", "robot", "home-robot", "guide-robot"]
    assert lines[head + 2].split()[:2] == ["fa7-spotlight", "n/a"]  # FA7 needs the guide
    assert "unknown Command 'Spotlight'" in out
    # every cell's map and robot: in the output, the JUnit and the summary
    assert "generated visits (willing, declining, hesitant, silent) on the map library" in out
    for fa in ("quiet", "fa7-spotlight"):
        for robot in ("home-robot", "guide-robot"):
            assert f"\n{fa} on {robot}, map library: " in out, out
    suite = etree.parse(str(tmp_path / "j.xml")).getroot()[0]
    cases = {c.get("name"): c for c in suite.iter("testcase")}
    assert set(cases) == {"quiet on home-robot, map library", "quiet on guide-robot, map library",
                          "fa7-spotlight on home-robot, map library",
                          "fa7-spotlight on guide-robot, map library"}
    assert suite.get("tests") == "4"
    assert cases["fa7-spotlight on home-robot, map library"].find("skipped") is not None
    assert cases["quiet on home-robot, map library"].find("failure") is not None
    named = {p.get("name"): Path(p.get("value", "")).resolve() for p in
             cases["quiet on guide-robot, map library"].iter("property")}
    # (the shipped maps the command found: in a copy of the checkout that imports its data
    # from the install's, the install's)
    maps = shipped("scenarios", "maps")
    assert maps is not None
    assert named == {"fa": QUIET, "robot": GUIDE, "map": (maps / "library.xml").resolve()}
    summary = (tmp_path / "s.md").read_text()
    assert "| FA | home-robot | guide-robot |" in summary and "| quiet | FAIL EA" in summary
    assert "on the map library (" in summary
    assert "| fa7-spotlight | home-robot | library | n/a | 0 |" in summary
    assert "| quiet | guide-robot | library | " in summary


def test_junit_says_each_cells_own_cpu_time() -> None:
    """The time of a test case is the CPU time its cell's runs took, summed: the cells'
    own (a cell that could not run took none), together no more than the check's."""
    start = time.process_time()
    result = check(MUTE, fas=[QUIET, RUNAWAY, ROOT / "apps" / "fa" / "fa7-spotlight.pxml"],
                   robots=[HOME], maps=MAPS, runs=2, pool=Inline())
    spent = time.process_time() - start
    suite = etree.fromstring(junit([result]).encode())[0]
    times = [float(c.get("time", "")) for c in suite.iter("testcase")]
    assert times == [round(c.cpu, 3) for c in result.cells]
    ran, na = [c for c in result.cells if c.done], [c for c in result.cells if not c.done]
    assert len(ran) == 2 and all(c.cpu > 0 for c in ran) and [c.cpu for c in na] == [0.0]
    assert 0 < sum(c.cpu for c in result.cells) <= spent
    assert float(suite.get("time", "")) == pytest.approx(sum(times), abs=0.002)


def test_a_written_worst_run_replays_the_failure(tmp_path: Path) -> None:
    result = check(MUTE, fas=[QUIET], robots=[HOME], maps=MAPS, runs=2, pool=Inline(),
                   out=tmp_path, worst=1)
    cell = result.cell(QUIET, HOME)
    assert cell.verdict == Verdict.EA
    (path,) = cell.written
    code, out, _ = cli("judge", str(path))
    assert code == 1 and re.search(r"\n  silences +1  > max 0\n", out), out


def test_the_results_are_the_same_whatever_runs_them(tmp_path: Path) -> None:
    files = []
    for name, pool in (("inline", Inline()), ("processes", Processes(2))):
        target = tmp_path / f"{name}.jsonl"
        check(MUTE, fas=[QUIET, RUNAWAY], robots=[HOME], maps=MAPS, runs=2, pool=pool,
              results=target)
        files.append(target.read_bytes())
    assert files[0] == files[1]
    records = [json.loads(line) for line in files[0].splitlines()[1:]]
    assert len(records) == 2 * len(VISITS) * 2 and all("check" in r for r in records)


@pytest.mark.parametrize("extra, fragment", [
    (["--min-coverage", "120"], "--min-coverage must be a percentage"),
    (["--runs", "0"], "--runs must be"),
    (["--fa", "no/such.pxml"], "no such file: no/such.pxml"),
    (["--worst", "-1"], "--worst must be"),
])
def test_check_usage_errors_exit_2(extra: list[str], fragment: str) -> None:
    code, _, err = cli("check", str(MUTE), "--robot", str(HOME), *extra)
    assert code == 2 and fragment in err, err


def test_a_broken_scenario_of_the_eas_own_is_located(tmp_path: Path) -> None:
    bad = tmp_path / "bad.xml"
    bad.write_text('<scenario xmlns="urn:prima:scenario:1" name="x" until="10">\n'
                   '  <map href="nowhere.xml"/>\n  <robot x="0" y="0"/>\n</scenario>\n')
    code, _, err = cli("check", str(TALKER), "--fa", str(QUIET), "--robot", str(HOME),
                       "--scenario", str(bad), "--runs", "1")
    assert code == 1 and f"{bad}:2:" in err and "Traceback" not in err


def test_a_broken_ea_is_located_not_a_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "bad.pxml"
    bad.write_text('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="bad">\n'
                   '  <state id="a" initial="true"><entry><goto state="b"/></entry></state>\n'
                   "</pxml>\n")
    code, _, err = cli("check", str(bad), "--fa", str(QUIET), "--robot", str(HOME),
                       "--runs", "1")
    assert code == 1 and f"{bad}:2:" in err and "Traceback" not in err


@pytest.mark.parametrize("text, fragment", [
    ("this is not XML\n", ":1:1: error: malformed XML"),
    ('<?xml version="1.0"?>\n<pxml xmlns="urn:prima:pxml:1" name="fa"><oops/></pxml>\n',
     ":2:1: error: <pxml>: missing required attribute 'kind'"),
])
def test_an_fa_that_is_no_document_stops_the_check_located(tmp_path: Path, text: str,
                                                            fragment: str) -> None:
    # (on every robot alike: not a row of n/a cells and a check that passes unchecked)
    bad = tmp_path / "bad.pxml"
    bad.write_text(text)
    code, out, err = cli("check", str(TALKER), "--fa", str(bad), "--robot", str(HOME),
                         "--runs", "1")
    assert code == 1 and f"{bad}{fragment}" in err and "Traceback" not in err
    assert out == ""


def test_an_ea_that_one_robot_cannot_run_is_n_a_there_and_checked_on_the_others(
        tmp_path: Path) -> None:
    """Its block needs an arm, which the guide robot lacks: that column is n/a, whichever
    robot comes first; only an EA that runs on no robot stops the check."""
    ea = tmp_path / "waver.pxml"
    ea.write_text('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="waver">\n'
                  '  <block id="b" devices="arm speaker">\n'
                  '    <state id="s" initial="true"><entry><chain>Speak("Hello.")</chain>'
                  "</entry></state>\n  </block>\n</pxml>\n")
    code, out, err = cli("check", str(ea), "--fa", str(QUIET), "--robot", str(GUIDE),
                         "--robot", str(HOME), "--runs", "1")
    assert code == 0, err
    assert f"quiet / guide-robot: n/a: {ea}:2:" in out and "unknown device 'arm'" in out
    assert re.search(r"quiet on home-robot, map \w+: ok", out), out
    code, out, err = cli("check", str(ea), "--fa", str(QUIET), "--robot", str(GUIDE),
                         "--runs", "1")
    assert (code, out) == (1, "") and f"{ea}:2:" in err and "unknown device 'arm'" in err


def test_a_check_in_which_no_cell_can_run_fails() -> None:
    fa7 = ROOT / "apps" / "fa" / "fa7-spotlight.pxml"  # (it needs the guide robot)
    code, out, err = cli("check", str(TALKER), "--fa", str(fa7), "--robot", str(HOME),
                         "--runs", "1")
    assert code == 1 and "fa7-spotlight / home-robot: n/a: " in out
    assert "no cell can run (each is n/a): nothing was checked" in err


def test_the_example_ea_written_from_the_docs_passes_every_cell(tmp_path: Path) -> None:
    result = check(ROOT / "scenarios" / "examples" / "info-desk.pxml",
                   fas=sorted((ROOT / "apps" / "fa").glob("*.pxml")),
                   robots=[HOME, GUIDE], maps=MAPS, runs=1, pool=Processes(2))
    assert result.failed_by_ea == []
    assert {c.verdict for c in result.cells} <= {Verdict.OK, Verdict.OTHER, Verdict.NA}
    assert sum(c.verdict == Verdict.OK for c in result.cells) >= 8


def test_a_forged_record_of_a_check_is_located_at_its_field(tmp_path: Path) -> None:
    """A check's records are read back checked too, what the check adds to them
    included (whose each failure is, what of the EA ran)."""
    target = tmp_path / "r.jsonl"
    argv = ["check", str(MUTE), "--fa", str(QUIET), "--robot", str(HOME), "--runs", "2",
            "--jobs", "1", "--worst", "0"]
    assert cli(*argv, "--results", str(target))[0] == 1  # (MUTE fails: the EA's doing)
    head, first, *rest = target.read_text().splitlines()
    record = json.loads(first)
    record["check"]["coverage"]["commands"][0] = ["12:7", "first"]
    target.write_text("\n".join([head, json.dumps(record), *rest]) + "\n")
    code, _, err = cli(*argv, "--resume", str(target))
    assert code == 1 and "Traceback" not in err, err
    assert (f"{target}:2:") in err and ("field 'check.coverage.commands[0][1]' must be a whole "
                                        'number from 0') in err, err
