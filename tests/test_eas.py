"""One FA and several EAs at once (MISSION.md 7.3 item 6): a building's guide beside
a shop's app, from the start (``<apps><ea href/></apps>``) or joining on entering a
zone (``<zone join="true">``), at most ``MAX_EAS``; their suspended streams resume
most recent first."""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from prima.cli import main
from prima.errors import DocumentError, ScenarioError
from prima.mediator import DecisionKind
from prima.run import Run
from prima.sim import load_scenario
from prima.trace import Kind, TraceLine, device_overlaps
from prima.vocab import MAX_EAS

ROOT = Path(__file__).parents[1]
ZONES = ROOT / "tests" / "data" / "zones"


def _cli(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    return main(list(args), out=out, err=err), out.getvalue(), err.getvalue()


def _loads(lines: list[TraceLine]) -> list[tuple[str | None, object]]:
    return [(ln.app, ln.detail["role"]) for ln in lines if ln.kind is DecisionKind.LOAD]


def test_a_joining_zone_loads_its_ea_beside_the_others() -> None:
    lines = Run(ZONES / "join.xml").run()
    assert _loads(lines) == [("walker", "fa"), ("hall-greeter", "ea"), ("gallery-guide", "ea")]
    assert [ln for ln in lines if ln.kind is DecisionKind.UNLOAD] == []
    zones = [(ln.text, ln.detail) for ln in lines if ln.kind is Kind.ZONE]
    assert zones == [("hall", {"ea": "greeter.pxml"}),
                     ("gallery", {"ea": "guide.pxml", "join": True})]
    greeter = [ln.t for ln in lines if ln.kind is DecisionKind.START and ln.app == "hall-greeter"]
    guide = next(ln.t for ln in lines if ln.kind is DecisionKind.START
                 and ln.app == "gallery-guide")
    assert greeter[-1] > guide  # the greeter goes on looking around beside the guide
    assert device_overlaps(lines) == []
    assert [ln for ln in lines if ln.kind is Kind.ERROR] == []


def _eas(tmp_path: Path, n: int) -> list[Path]:
    """``n`` EAs of distinct names (the gallery's guide, renamed)."""
    text = (ZONES / "guide.pxml").read_text()
    out = []
    for i in range(n):
        path = tmp_path / f"ea{i}.pxml"
        path.write_text(text.replace('name="gallery-guide"', f'name="ea{i}"'))
        out.append(path)
    return out


def _scenario(tmp_path: Path, apps: str, zones: str = "") -> Path:
    path = tmp_path / "s.xml"
    path.write_text(
        '<scenario xmlns="urn:prima:scenario:1" name="s" until="60" seed="1">\n'
        f'  <map href="{ZONES / "two-rooms.xml"}"/>\n'
        f'  {apps}\n'
        '  <robot place="entrance" heading="0"/>\n'
        f'  {zones}\n'
        '</scenario>\n')
    return path


def test_a_zone_joining_past_the_bound_is_a_located_error_and_the_run_goes_on(
        tmp_path: Path) -> None:
    eas = _eas(tmp_path, MAX_EAS)
    children = "".join(f'<ea href="{p}"/>' for p in eas[1:])
    path = _scenario(tmp_path, f'<apps fa="{ZONES / "walker.pxml"}" ea="{eas[0]}">{children}'
                               '</apps>',
                     f'<zone name="gallery" area="gallery" ea="{ZONES / "guide.pxml"}" '
                     'join="true"/>')
    lines = Run(path).run()
    assert [app for app, role in _loads(lines) if role == "ea"] == [f"ea{i}" for i in
                                                                   range(MAX_EAS)]
    errors = [ln for ln in lines if ln.kind is Kind.ERROR]
    assert len(errors) == 1 and errors[0].detail == {"zone": "gallery"}
    assert errors[0].text is not None
    assert errors[0].text.startswith(f"{path}:5:")
    assert f"{MAX_EAS} EAs are running" in errors[0].text
    assert f"at most {MAX_EAS} run at once" in errors[0].text
    reached = [ln.detail.get("place") for ln in lines if ln.kind is Kind.EVENT
               and ln.text == "place-reached"]
    assert reached[-1] == "gallery"  # the FA drove on


def test_a_replacing_zone_replaces_every_ea(tmp_path: Path) -> None:
    eas = _eas(tmp_path, 2)
    path = _scenario(tmp_path, f'<apps fa="{ZONES / "walker.pxml"}" ea="{eas[0]}">'
                               f'<ea href="{eas[1]}"/></apps>',
                     f'<zone name="gallery" area="gallery" ea="{ZONES / "guide.pxml"}"/>')
    lines = Run(path).run()
    assert [ln.app for ln in lines if ln.kind is DecisionKind.UNLOAD] == ["ea0", "ea1"]
    assert _loads(lines)[-1] == ("gallery-guide", "ea")


def test_more_eas_than_the_bound_from_the_start_is_a_located_error(tmp_path: Path) -> None:
    eas = _eas(tmp_path, MAX_EAS + 1)
    children = "\n    ".join(f'<ea href="{p}"/>' for p in eas[1:])
    path = _scenario(tmp_path, f'<apps ea="{eas[0]}">\n    {children}\n  </apps>')
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    [problem] = info.value.problems
    assert (problem.line, problem.col) == (3 + MAX_EAS, 15)
    assert f"at most {MAX_EAS} EAs run at once" in problem.message


def test_the_same_ea_twice_is_a_located_error(tmp_path: Path) -> None:
    [ea] = _eas(tmp_path, 1)
    path = _scenario(tmp_path, f'<apps ea="{ea}"><ea href="{ea}"/></apps>')
    with pytest.raises(ScenarioError, match="already running from the start"):
        load_scenario(path)


def test_two_eas_of_one_name_are_refused(tmp_path: Path) -> None:
    [ea] = _eas(tmp_path, 1)
    twin = tmp_path / "twin.pxml"
    twin.write_text(ea.read_text())
    path = _scenario(tmp_path, f'<apps ea="{ea}"><ea href="{twin}"/></apps>')
    with pytest.raises(DocumentError, match="both named 'ea0'"):
        Run(path)
    code, out, _ = _cli("validate", str(path))
    assert code == 1 and f"{path}:3:" in out and "both named 'ea0'" in out
