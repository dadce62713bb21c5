"""Scenario and map files: the shipped ones load; bad ones get file:line:col errors."""

from __future__ import annotations

import io
import os
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from prima.errors import ScenarioError
from prima.scenario import load_map, load_scenario, main

from tests.sim.helpers import EXAMPLES, MAPS, ROOT

SCHEMAS = ROOT / "schemas"

HEAD = '<?xml version="1.0" encoding="UTF-8"?>\n'
MAP_REF = f'  <map href="{MAPS / "office.xml"}"/>\n'


def scenario_file(tmp_path: Path, body: str, *, attrs: str = 'name="t" until="10"') -> Path:
    path = tmp_path / "s.xml"
    path.write_text(f'{HEAD}<scenario xmlns="urn:prima:scenario:1" {attrs}>\n{body}</scenario>\n')
    return path


def problems(path: Path,
             loader: Callable[[Path], object] = load_scenario) -> list[tuple[int, int, str]]:
    with pytest.raises(ScenarioError) as info:
        loader(path)
    for p in info.value.problems:
        assert p.file == str(path) or p.file.endswith(".xml")
    return [(p.line, p.col, p.message) for p in info.value.problems]


@pytest.mark.parametrize("name", sorted(p.name for p in MAPS.glob("*.xml")))
def test_shipped_maps_load(name: str) -> None:
    world = load_map(MAPS / name)
    assert world.places and world.edges


@pytest.mark.parametrize("name", sorted(p.name for p in EXAMPLES.glob("*.xml")))
def test_shipped_scenarios_load(name: str) -> None:
    scenario = load_scenario(EXAMPLES / name)
    assert scenario.until > 0 and scenario.map.places


def test_the_maps_stage_the_thesis_situations() -> None:
    office = load_map(MAPS / "office.xml")
    kinds = {p.kind.value for p in office.places}
    assert {"entrance", "corner", "poster", "room"} <= kinds
    museum = load_map(MAPS / "museum.xml")
    assert [p.name for p in museum.places if p.kind.value == "panel"] == ["panel-1", "panel-2"]
    library = load_map(MAPS / "library.xml")
    assert {"counter", "shelf", "entrance"} <= {p.kind.value for p in library.places}


def test_malformed_xml(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, MAP_REF + '  <robot place="entrance">\n')
    [(line, col, message)] = problems(path)
    assert line == 5 and "malformed XML" in message


def test_schema_error_points_at_the_attribute(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, MAP_REF + '  <robot place="entrance"/>\n'
                         '  <message at="soon" sender="K" text="hi"/>\n')
    [(line, col, message)] = problems(path)
    assert (line, col) == (5, 16)
    assert "<message>" in message and "'soon'" in message


def test_schema_error_for_an_unknown_element(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, MAP_REF + '  <robot place="entrance"/>\n  <dance at="1"/>\n')
    [(line, col, message)] = problems(path)
    assert (line, col) == (5, 3) and "<dance> is not allowed" in message


def test_unknown_place(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, MAP_REF + '  <robot place="entrance"/>\n'
                         '  <user place="hall">\n'
                         '    <walk at="3" to="kitchen"/>\n'
                         '  </user>\n')
    [(line, col, message)] = problems(path)
    assert (line, col) == (6, 22)
    assert "unknown place 'kitchen' on map 'office'" in message and "kidode-room" in message


def test_several_problems_are_reported_together(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, MAP_REF + '  <robot place="lobby"/>\n'
                         '  <user x="1" y="2">\n'
                         '    <say at="5" text="hi"/>\n'
                         '    <touch at="2"/>\n'
                         '    <answer matches="(" say="x"/>\n'
                         '  </user>\n'
                         '  <zone name="z" ea="e.pxml" area="garden"/>\n')
    found = problems(path)
    lines = [(line, message.split(":")[0]) for line, _, message in found]
    assert [line for line, _ in lines] == [4, 7, 8, 10, 10]
    assert "unknown place 'lobby'" in found[0][2]
    assert "comes after an action at 5 s" in found[1][2]
    assert "a group ('(') is not in the safe subset" in found[2][2]
    assert {"file 'e.pxml' not found", "unknown area 'garden'"} == {
        m.split(" (")[0] for _, _, m in found[3:]}


def test_missing_map_file(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, '  <map href="nowhere.xml"/>\n  <robot x="0" y="0"/>\n')
    [(line, col, message)] = problems(path)
    assert (line, col) == (3, 14) and "map file 'nowhere.xml' not found" in message


def test_a_missing_file_says_where_it_was_looked_for(tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """Named relative to the scenario, found relative to the current folder: the message
    gives the absolute path, not the name again."""
    (tmp_path / "s").mkdir()
    path = scenario_file(tmp_path / "s", '  <map href="../maps/nowhere.xml"/>\n'
                                         '  <robot x="0" y="0"/>\n')
    monkeypatch.chdir(tmp_path / "s")
    [(_, _, message)] = problems(Path(path.name))
    assert message.endswith(f"(looked for {tmp_path / 'maps' / 'nowhere.xml'})"), message


def test_wrong_root_element(tmp_path: Path) -> None:
    path = tmp_path / "m.xml"
    path.write_text(HEAD + '<map xmlns="urn:prima:map:1" name="m">'
                    '<place name="a" x="0" y="0"/></map>\n')
    [(line, col, message)] = problems(path)
    assert line == 2 and "expected a <scenario> element" in message


def test_map_edge_through_a_wall_and_unknown_edge_place(tmp_path: Path) -> None:
    path = tmp_path / "m.xml"
    path.write_text(HEAD + '<map xmlns="urn:prima:map:1" name="m">\n'
                    '  <wall x1="5" y1="-5" x2="5" y2="5"/>\n'
                    '  <place name="a" x="0" y="0"/>\n'
                    '  <place name="b" x="10" y="0"/>\n'
                    '  <edge from="a" to="b"/>\n'
                    '  <edge from="a" to="c"/>\n'
                    '  <place name="a" x="1" y="1"/>\n'
                    '</map>\n')
    found = problems(path, load_map)
    assert [(line, col) for line, col, _ in found] == [(6, 3), (7, 22), (8, 16)]
    assert "edge a -> b crosses a wall at (4.95, 0.00)" in found[0][2]
    assert "unknown place 'c'" in found[1][2]
    assert "already defined on line 4" in found[2][2]


def test_a_bad_map_is_reported_in_the_map_file(tmp_path: Path) -> None:
    bad_map = tmp_path / "bad-map.xml"
    bad_map.write_text(HEAD + '<map xmlns="urn:prima:map:1" name="m">\n'
                       '  <place name="a" kind="kitchen" x="0" y="0"/>\n</map>\n')
    path = scenario_file(tmp_path, '  <map href="bad-map.xml"/>\n  <robot x="0" y="0"/>\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    [problem] = info.value.problems
    assert problem.file == str(bad_map) and (problem.line, problem.col) == (3, 25)
    assert "kitchen" in problem.message


def test_cli_check_prints_located_errors_and_exits_non_zero(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, MAP_REF + '  <robot place="kitchen"/>\n')
    out, err = io.StringIO(), io.StringIO()
    assert main(["check", str(path)], out, err) == 1
    assert err.getvalue().startswith(f"{path}:4:17: error: unknown place 'kitchen'")
    out, err = io.StringIO(), io.StringIO()
    assert main(["check", str(EXAMPLES / "museum-tour.xml")], out, err) == 0
    assert err.getvalue() == "" and out.getvalue().endswith(": ok\n")


def test_cli_run_prints_the_trace() -> None:
    out = io.StringIO()
    status = main(["run", str(EXAMPLES / "museum-tour.xml"), "--until", "30", "--command",
                   '{"command": "TopologicalMove", "args": {"to": "panel-1"}}'], out)
    assert status == 0
    text = out.getvalue()
    assert "place-reached" in text and "zone   exhibition" in text



def test_cli_run_rejects_a_bad_command_as_a_usage_error(
        capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as info:
        main(["run", str(EXAMPLES / "museum-tour.xml"), "--command", '{"to": "panel-1"}'])
    assert info.value.code == 2
    assert "bad --command" in capsys.readouterr().err


XMLLINT = shutil.which("xmllint")
SHIPPED = ([("map.xsd", p) for p in sorted(MAPS.glob("*.xml"))]
           + [("scenario.xsd", p) for p in sorted(EXAMPLES.glob("*.xml"))])


@pytest.mark.skipif(XMLLINT is None, reason="xmllint is not installed")
@pytest.mark.parametrize("schema, path", SHIPPED, ids=[p.name for _, p in SHIPPED])
def test_xmllint_accepts_the_schemas_and_the_shipped_files(schema: str, path: Path) -> None:
    result = subprocess.run([XMLLINT, "--noout", "--schema", str(SCHEMAS / schema), str(path)],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr


# ---------------------------------------------------------------- numbers the run can use

HUGE = "1" + "0" * 400   # a decimal the schema accepts; infinite as a float
TINY = "0." + "0" * 400 + "1"  # positive as a decimal; 0 as a float
ROBOT = '  <robot place="entrance"/>\n'


UNTIL = 'name="t" until="10"'


@pytest.mark.parametrize("attrs, body, where, fragment", [
    (f'name="t" until="{HUGE}"', ROBOT, (2, "until"),
     "until='10000000000000000...' is too large: at most 1e+06 s"),
    (f'name="t" until="{TINY}"', ROBOT, (2, "until"),
     "until='0.000000000000000...' must be greater than 0"),
    ('name="t" until="1000001"', ROBOT, (2, "until"),
     "until='1000001' is too large: at most 1e+06 s"),
    (f'{UNTIL} rate="15"', ROBOT, (2, "rate"), "rate must be a multiple of 10"),
    (f'{UNTIL} rate="1010"', ROBOT, (2, "rate"), "rate='1010' is too large: at most 1,000"),
    (f'{UNTIL} rate="{HUGE}"', ROBOT, (2, "rate"), "rate='10000000000000000...' is too"),
    (f'{UNTIL} seed="{"9" * 5000}"', ROBOT, (2, "seed"), "seed='99999999999999999...' is"),
    (UNTIL, '  <robot x="0" y="20000"/>\n', (4, "y"), "y='20000' is too large"),
    (UNTIL, f'  <robot x="0" y="0" heading="{HUGE}"/>\n', (4, "heading"), "heading="),
    (UNTIL, '  <robot x="0" y="0" noise="101"/>\n', (4, "noise"), "noise='101' is too"),
    (UNTIL, ROBOT + f'  <user x="0" y="0" speed="{TINY}"/>\n', (5, "speed"),
     "speed='0.000000000000000...' must be greater than 0"),
    (UNTIL, ROBOT + f'  <user x="0" y="0"><say at="{HUGE}" text="x"/></user>\n',
     (5, "at"), "at='10000000000000000...' is too large"),
    (UNTIL, ROBOT + f'  <user x="0" y="0"><follow at="1" distance="{TINY}"/></user>\n',
     (5, "distance"), "distance="),
    (UNTIL, ROBOT + f'  <user x="0" y="0"><walk at="1" x="{HUGE}" y="0"/></user>\n',
     (5, 'walk at="1" x'), "x="),
    (UNTIL, ROBOT + f'  <user x="0" y="0"><answer after="{HUGE}"/></user>\n',
     (5, "after"), "after="),
    (UNTIL, ROBOT + f'  <user x="0" y="0"><answer nth="{HUGE}"/></user>\n',
     (5, "nth"), "nth='10000000000000000...' is too large: at most 1,000,000"),
    (UNTIL, ROBOT + f'  <message at="{HUGE}" sender="s" text="t"/>\n', (5, "at"), "at="),
    (UNTIL, ROBOT + f'  <reply to="v" after="{HUGE}" text="t"/>\n', (5, "after"), "after="),
    (UNTIL, ROBOT + f'  <zone name="z" ea="s.xml" x1="0" y1="0" x2="{HUGE}" y2="1"/>\n',
     (5, "x2"), "x2="),
])
def test_numbers_the_simulator_cannot_use_are_located(
        tmp_path: Path, attrs: str, body: str, where: tuple[int, str], fragment: str) -> None:
    path = scenario_file(tmp_path, MAP_REF + body, attrs=attrs)
    found = problems(path)
    line, attr = where
    text = path.read_text().splitlines()[line - 1]
    col = text.index(f'{attr}="') + len(f'{attr}="') + 1  # where the value starts
    assert [(line_, col_) for line_, col_, _ in found] == [(line, col)], found
    assert fragment in found[0][2]


@pytest.mark.parametrize("words", ["", " ", "&#9;", " &#9; "])
def test_blank_words_in_a_scenario_are_located_errors(tmp_path: Path, words: str) -> None:
    """Blank words are no speech: a ``<say>`` or an answer rule's ``say`` that says
    nothing is refused where it is written (an answer that stays silent leaves say out)."""
    body = (MAP_REF + '  <robot place="entrance"/>\n  <user x="1" y="0">\n'
            f'    <answer contains="ready" say="{words}"/>\n'
            f'    <say at="1" text="{words}"/>\n  </user>\n')
    path = scenario_file(tmp_path, body)
    text = path.read_text().splitlines()
    found = problems(path)
    assert [(line, col) for line, col, _ in found] == [
        (6, text[5].index('say="') + 6), (7, text[6].index('text="') + 7)]
    assert "blank words are no answer" in found[0][2]
    assert "blank words are no speech" in found[1][2]


def test_map_numbers_are_located(tmp_path: Path) -> None:
    path = tmp_path / "m.xml"
    path.write_text(HEAD + '<map xmlns="urn:prima:map:1" name="m">\n'
                    f'  <wall x1="0" y1="0" x2="{HUGE}" y2="0" thickness="{TINY}"/>\n'
                    f'  <place name="a" x="0" y="0" facing="{HUGE}"/>\n'
                    '  <area name="r" x1="0" y1="0" x2="1" y2="-10001"/>\n'
                    '</map>\n')
    found = problems(path, load_map)
    assert [(line, col) for line, col, _ in found] == [(3, 27), (3, 448), (4, 39), (5, 43)]
    kinds = [next(f for f in ("too large", "must be greater than 0", "too small") if f in m)
             for _, _, m in found]
    assert kinds == ["too large", "must be greater than 0", "too large", "too small"]


@pytest.mark.parametrize("pattern, col, fragment", [
    ("(a+)+$", 1, "a group ('(') is not in the safe subset"),
    ("yes|no*", 7, "repetition ('*')"),
    ("[abc]", 1, "a character class ('[')"),
    ("a^b", 2, "'^' anchors only at the start"),
    ("a$b", 2, "'$' anchors only"),
    ("\\1", 1, "a backslash must escape punctuation"),
    ("x" * 201, 201, "matches: longer than 200 characters"),
])
def test_an_answer_pattern_outside_the_safe_subset_is_located(
        tmp_path: Path, pattern: str, col: int, fragment: str) -> None:
    path = scenario_file(tmp_path, MAP_REF + ROBOT +
                         f'  <user x="0" y="0"><answer matches="{pattern}" say="x"/></user>\n')
    [(line, found_col, message)] = problems(path)
    assert (line, found_col) == (5, 38 + col - 1) and fragment in message


@pytest.mark.parametrize("pattern", ["channel|station", "^yes$|^no$", "\\bok\\b", "a.c\\?",
                                     "\\d\\d:\\d\\d", "^|$"])
def test_safe_answer_patterns_load(tmp_path: Path, pattern: str) -> None:
    path = scenario_file(tmp_path, MAP_REF + ROBOT +
                         f'  <user x="0" y="0"><answer matches="{pattern}" say="x"/></user>\n')
    [rule] = load_scenario(path).user.answers  # type: ignore[union-attr]
    assert rule.pattern == pattern


def test_a_long_safe_pattern_searches_a_long_prompt(tmp_path: Path) -> None:
    # Without groups or nested repetition, the regular expression engine tries each
    # alternative once at each place: 9 alternatives of 20 characters, 10,000 places.
    pattern = "|".join(["a" * 19 + "b"] * 9)  # 188 characters
    path = scenario_file(tmp_path, MAP_REF + ROBOT +
                         f'  <user x="0" y="0"><answer matches="{pattern}" say="x"/></user>\n')
    [rule] = load_scenario(path).user.answers  # type: ignore[union-attr]
    assert not rule.matches("a" * 10_000)
    assert rule.matches("a" * 10_000 + "b")


def test_a_named_file_that_is_not_a_regular_file_is_located(tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "ea.pxml")
    (tmp_path / "maps").mkdir()
    path = scenario_file(tmp_path, '  <map href="maps"/>\n' + ROBOT)
    [(line, col, message)] = problems(path)
    assert (line, col) == (3, 14) and "map file 'maps' is not a regular file" in message
    path = scenario_file(tmp_path, MAP_REF + '  <apps ea="ea.pxml"/>\n' + ROBOT)
    [(line, col, message)] = problems(path)
    assert (line, col) == (4, 13) and "file 'ea.pxml' is not a regular file" in message
