"""One FA and several EAs at once (docs/rules.md 7.3 item 6): a building's guide beside
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
from prima.scenario import load_scenario
from prima.sweep import write_variant
from prima.trace import Kind, TraceLine, device_overlaps
from prima.vocab import MAX_EAS

ROOT = Path(__file__).parents[1]
MUSEUM_CAFE = ROOT / "scenarios" / "examples" / "museum-cafe.xml"
ZONES = ROOT / "tests" / "data" / "zones"


def _cli(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    return main(list(args), out=out, err=err), out.getvalue(), err.getvalue()


def _loads(lines: list[TraceLine]) -> list[tuple[str | None, object]]:
    return [(ln.app, ln.detail["role"]) for ln in lines if ln.kind is DecisionKind.LOAD]


def test_museum_cafe_matches_its_reviewed_golden(prima_golden) -> None:  # type: ignore[no-untyped-def]
    prima_golden(MUSEUM_CAFE)


def test_three_streams_are_suspended_and_resume_most_recent_first() -> None:
    """The cafe's reaction suspends the guide's explanation; the FA's reaction to a
    touch suspends the cafe's stream; the cafe's stream resumes first, then the guide's."""
    lines = Run(MUSEUM_CAFE).run()
    assert _loads(lines) == [("fa1-emotions", "fa"), ("ea1-museum", "ea"), ("cafe", "ea")]
    turns = [(ln.kind, ln.app) for ln in lines
             if ln.kind in (DecisionKind.SUSPEND, DecisionKind.RESUME)]
    assert turns == [(DecisionKind.SUSPEND, "ea1-museum"), (DecisionKind.SUSPEND, "cafe"),
                     (DecisionKind.RESUME, "cafe"), (DecisionKind.RESUME, "ea1-museum")]
    suspend_cafe = next(ln for ln in lines if ln.kind is DecisionKind.SUSPEND
                        and ln.app == "cafe")
    touch = next(ln for ln in lines if ln.kind is DecisionKind.START
                 and ln.app == "fa1-emotions")
    assert suspend_cafe.text == f"lost to AB{touch.ab} (fa1-emotions)"
    resumed = [ln.text for ln in lines if ln.kind is DecisionKind.START and ln.text and (
        ln.app == "cafe" or ln.command == "SetDirection+PointByHand+Speak")]
    assert resumed[1].startswith("Today's cake")  # the cafe's news, where it was cut off
    assert resumed[-2].startswith("Take attention")  # the guide's panel, after the cafe
    assert device_overlaps(lines) == []
    assert [ln for ln in lines if ln.kind is Kind.ERROR] == []


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
    assert errors[0].text.startswith(f"{path.name}:5:")  # (relative: no absolute path)
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


def test_several_eas_load_and_validate_and_sweep() -> None:
    scenario = load_scenario(MUSEUM_CAFE)
    assert scenario.ea == "../../apps/ea/ea1-museum.pxml"
    assert scenario.eas == ("../../apps/ea/cafe.pxml",)
    assert scenario.to_dict()["eas"] == ["../../apps/ea/cafe.pxml"]
    assert "eas" not in load_scenario(ZONES / "swap.xml").to_dict()
    code, _, err = _cli("validate", str(MUSEUM_CAFE))  # scenario, map, FA and both EAs
    assert code == 0 and "5 files checked: 0 error(s)" in err


def test_a_sweep_variant_keeps_every_ea(tmp_path: Path) -> None:
    variant = write_variant(MUSEUM_CAFE, tmp_path / "v.xml", seed=1, index=0, jitter=0.0)
    loaded = load_scenario(variant)
    assert Path(loaded.resolve(loaded.eas[0])) == (ROOT / "apps" / "ea" / "cafe.pxml").resolve()
