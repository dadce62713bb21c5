"""``prima validate`` of a scenario checks the places its applications name against its map.

A place written by name (``to="hall"``, ``TopologicalMove("kidode-room")``) that the
scenario's map lacks fails for certain when the application runs there; validating the
scenario reports it in the application's file, at the name. A place computed with
``{expression}`` is not checked, and a document validated alone knows no map.
"""

from __future__ import annotations

import io
from pathlib import Path

from prima.cli import main
from prima.dsl import PlaceRef, literal_places, load_document
from tests.work import growth

ROOT = Path(__file__).parents[2]


def run(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def _map(folder: Path, name: str, places: list[str]) -> Path:
    path = folder / f"{name}.xml"
    body = "".join(f'<place name="{p}" x="{i}" y="0"/>' for i, p in enumerate(places))
    path.write_text(f'<map xmlns="urn:prima:map:1" name="{name}">{body}</map>\n')
    return path


def _scenario(folder: Path, name: str, map_name: str, apps: str, zones: str = "") -> Path:
    path = folder / f"{name}.xml"
    path.write_text(f'<scenario xmlns="urn:prima:scenario:1" name="{name}" until="10">\n'
                    f'  <map href="{map_name}.xml"/>\n'
                    f'  {apps}\n'
                    '  <robot x="0" y="0"/>\n'
                    f'  {zones}\n'
                    '</scenario>\n')
    return path


def _pxml(folder: Path, name: str, kind: str, *lines: str) -> Path:
    path = folder / f"{name}.pxml"
    path.write_text(f'<pxml xmlns="urn:prima:pxml:1" kind="{kind}" name="{name}">\n'
                    '  <var name="goal" expr="\'nowhere\'"/>\n'
                    '  <state id="s" initial="true"><entry>\n'
                    + "".join(f"    {line}\n" for line in lines)
                    + "  </entry></state>\n</pxml>\n")
    return path


OFFICE_PLACES = ["entrance", "hall", "poster", "corner", "kidode-door", "kidode-room"]


def test_every_literal_place_of_every_application_is_checked_against_the_map(
        tmp_path: Path) -> None:
    _map(tmp_path, "office", OFFICE_PLACES)
    fa = _pxml(tmp_path, "fa", "fa",
               '<chain>TopologicalMove(kidode_room), TopologicalMove({goal}), '
               'TopologicalMove(hall)</chain>',
               '<request><set-direction toward="posters"/><topological-move to="{goal}"/>'
               '</request>')
    ea = _pxml(tmp_path, "ea", "ea",
               '<chain>PointByHand(toward="lobby"), SetDirection(toward=\'cornr\')</chain>',
               '<request><command name="TopologicalMove"><arg name="to" value="kidode-rom"/>'
               '</command></request>')
    zone = _pxml(tmp_path, "zone", "ea", '<request><topological-move to="roof"/></request>')
    path = _scenario(tmp_path, "s", "office", '<apps fa="fa.pxml" ea="ea.pxml"/>',
                     zones='<zone name="z" ea="zone.pxml" x1="0" y1="0" x2="1" y2="1"/>')
    code, out, err = run("validate", str(path))
    known = "(known: corner, entrance, hall, kidode-door, kidode-room, poster)"
    assert code == 1
    assert out.splitlines() == [
        f"{fa}:4:28: error: unknown place 'kidode_room' on map 'office' "
        "(did you mean 'kidode-room'?)",
        f"{fa}:5:37: error: unknown place 'posters' on map 'office' (did you mean 'poster'?)",
        f"{ea}:4:31: error: unknown place 'lobby' on map 'office' {known}",
        f"{ea}:4:61: error: unknown place 'cornr' on map 'office' (did you mean 'corner'?)",
        f"{ea}:5:68: error: unknown place 'kidode-rom' on map 'office' "
        "(did you mean 'kidode-room'?)",
        f"{zone}:4:36: error: unknown place 'roof' on map 'office' {known}",
    ]
    assert "5 files checked: 6 error(s)" in err
    # alone, a document knows no map: its places are the run's to check
    assert run("validate", str(fa), str(ea), str(zone))[:2] == (0, "")


def test_a_document_is_checked_once_per_map_it_runs_on(tmp_path: Path) -> None:
    _map(tmp_path, "office", OFFICE_PLACES)
    _map(tmp_path, "museum", ["entrance", "center", "panel-1"])
    ea = _pxml(tmp_path, "ea", "ea", '<chain>TopologicalMove("panel-1")</chain>')
    one = _scenario(tmp_path, "one", "office", '<apps ea="ea.pxml"/>')
    two = _scenario(tmp_path, "two", "office", '<apps ea="ea.pxml"/>')
    three = _scenario(tmp_path, "three", "museum", '<apps ea="ea.pxml"/>')
    code, out, _ = run("validate", str(one), str(two), str(three))
    assert code == 1
    assert out.splitlines() == [
        f"{ea}:4:28: error: unknown place 'panel-1' on map 'office' (known: corner, entrance, "
        "hall, kidode-door, kidode-room, poster)"]
    assert run("validate", str(three))[:2] == (0, "")


def test_a_large_map_is_not_listed_and_a_file_reports_at_most_50(tmp_path: Path) -> None:
    many = [f"room-{i}" for i in range(20)]
    _map(tmp_path, "big", many)
    chain = ", ".join(f"TopologicalMove(x{i})" for i in range(60))
    ea = _pxml(tmp_path, "ea", "ea", f"<chain>{chain}</chain>",
               "<chain>TopologicalMove(room_3)</chain>")
    path = _scenario(tmp_path, "s", "big", '<apps ea="ea.pxml"/>')
    code, out, _ = run("validate", str(path))
    lines = out.splitlines()
    assert code == 1 and len(lines) == 51
    assert lines[0] == (f"{ea}:4:28: error: unknown place 'x0' on map 'big' "
                        f"(20 places; see {tmp_path / 'big.xml'})")
    assert lines[-1] == f"{ea}:1:1: error: ... and 11 more problems (a file reports at most 50)"


def test_the_cost_stays_linear_in_the_places_written(tmp_path: Path) -> None:
    _map(tmp_path, "office", OFFICE_PLACES)

    def validate(n: int) -> None:
        lines = ["<chain>" + ", ".join(["TopologicalMove(lobby)"] * 100) + "</chain>"] * (n // 100)
        _pxml(tmp_path, "ea", "ea", *lines)
        path = _scenario(tmp_path, "s", "office", '<apps ea="ea.pxml"/>')
        code, out, _ = run("validate", str(path))
        assert code == 1 and out.count("\n") == 51

    validate(1000)  # (what is loaded once a process)
    assert growth(validate, 1000, 8000) < 1.2


def test_the_dsl_lists_a_documents_literal_places_with_where_they_are(tmp_path: Path) -> None:
    path = _pxml(tmp_path, "fa", "fa",
                 '<chain>TopologicalMove(hall), PointByHand(toward="panel-1")</chain>',
                 '<request><topological-move to="{goal}"/><set-direction toward="corner"/>'
                 '</request>')
    [hall, panel, corner] = literal_places(load_document(path))
    assert hall == PlaceRef("hall", hall.loc, "TopologicalMove", "to")
    assert (hall.loc.line, hall.loc.col) == (4, 28)
    assert (panel.name, panel.command, panel.param) == ("panel-1", "PointByHand", "toward")
    assert (panel.loc.line, panel.loc.col) == (4, 54)
    assert (corner.name, corner.loc.line, corner.loc.col) == ("corner", 5, 68)


def test_a_run_refuses_what_validating_the_scenario_refuses(tmp_path: Path) -> None:
    """``prima run`` (and so judge, sweep, test and the fixtures) loads the applications as
    ``prima validate`` checks them: an unknown literal place stops the run before it
    starts, in the application's file (a zone's EA with one is left out and reported,
    as any broken zone EA is)."""
    _map(tmp_path, "office", OFFICE_PLACES)
    _pxml(tmp_path, "fa", "fa")
    _pxml(tmp_path, "guide", "ea", '<chain>TopologicalMove("kidode_room")</chain>')
    scenario = _scenario(tmp_path, "s", "office", '<apps fa="fa.pxml" ea="guide.pxml"/>')
    code, _, err = run("run", str(scenario))
    assert code == 1
    assert err.startswith(f"{tmp_path / 'guide.pxml'}:4:") and (
        "unknown place 'kidode_room' on map 'office' (did you mean 'kidode-room'?)" in err), err
