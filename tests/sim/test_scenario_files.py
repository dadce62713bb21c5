"""Scenario and map files: the shipped ones load; bad ones get file:line:col errors."""

from __future__ import annotations

import io
import shutil
import subprocess
from collections.abc import Callable
from pathlib import Path

import pytest

from prima.errors import ScenarioError
from prima.sim import load_map, load_scenario, main

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
    assert "bad regular expression" in found[2][2]
    assert {"file 'e.pxml' not found", "unknown area 'garden'"} == {
        m.split(" (")[0] for _, _, m in found[3:]}


def test_missing_map_file(tmp_path: Path) -> None:
    path = scenario_file(tmp_path, '  <map href="nowhere.xml"/>\n  <robot x="0" y="0"/>\n')
    [(line, col, message)] = problems(path)
    assert (line, col) == (3, 14) and "map file 'nowhere.xml' not found" in message


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
