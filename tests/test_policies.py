"""Mediation policies (docs/rules.md 7.3): their switches in the robot profile, the
scenario and ``prima run --policy``, and what each one does to a run."""

from __future__ import annotations

import io
import math
import re
from pathlib import Path

import pytest

from prima.cli import main
from prima.dsl import parse_profile
from prima.errors import DocumentError, ScenarioError
from prima.judge import judge
from prima.run import Run
from prima.trace import TraceLine, format_text
from prima.scenario import load_scenario
from prima.vocab import POLICIES, policy_settings
from tests.dsl.test_profile import ALL, PROFILE

ROOT = Path(__file__).resolve().parents[1]
SAMPLE_05_STREAM = ROOT / "scenarios" / "thesis" / "sample-05-stream.xml"

def _profile(policies: str) -> dict[str, bool]:
    text = PROFILE.format(devices=ALL, rest=policies, tilt="-30")
    return dict(parse_profile(text.encode(), "r.xml").policies)


def test_every_policy_has_a_default_and_all_switches_every_one() -> None:
    assert policy_settings() == {name: p.default for name, p in POLICIES.items()}
    assert set(policy_settings({"all": False}).values()) == {False}
    # ``all`` first in its layer, then that layer's named ones; later layers win
    assert policy_settings({"all": False, "streams": True}) == \
        {"restore-state": False, "interrupt": False, "blend": False, "streams": True,
         "connect-channel": False, "reactions": False, "exchange": False,
         "barge-in": False}
    assert policy_settings({"streams": False}, {"all": True})["streams"] is True
    assert policy_settings({"no-such-policy": False}) == policy_settings()


@pytest.mark.parametrize("schema", ["robot.xsd", "scenario.xsd"])
def test_the_schemas_know_exactly_the_policies(schema: str) -> None:
    text = (ROOT / "schemas" / schema).read_text()
    block = text[text.index('<xs:simpleType name="PolicyName">'):]
    block = block[:block.index("</xs:simpleType>")]
    assert set(re.findall(r'<xs:enumeration value="([^"]+)"/>', block)) == {"all", *POLICIES}


def test_a_robot_profile_switches_policies() -> None:
    assert _profile("") == {}
    assert _profile('<policy name="streams" state="off"/>') == {"streams": False}
    assert _profile('<policy name="all" state="off"/><policy name="streams" state="on"/>') \
        == {"all": False, "streams": True}


@pytest.mark.parametrize("policies, fragment", [
    ('<policy name="teleport" state="on"/>', "teleport"),
    ('<policy name="streams" state="maybe"/>', "maybe"),
    ('<policy name="streams" state="on"/><policy name="streams" state="off"/>',
     "a second <policy name='streams'>"),
])
def test_a_bad_policy_switch_in_a_profile_is_located(policies: str, fragment: str) -> None:
    with pytest.raises(DocumentError) as info:
        _profile(policies)
    assert any(p.line == 15 and fragment in p.message for p in info.value.problems), \
        info.value.problems


def _scenario(tmp_path: Path, policies: str) -> Path:
    text = SAMPLE_05_STREAM.read_text()
    text = re.sub(r'(<robot [^>]*/>)', lambda m: m.group(1) + policies, text, count=1)
    text = text.replace('href="../', f'href="{SAMPLE_05_STREAM.parent.parent}/')
    text = re.sub(r'(fa|ea)="\.\./\.\./', lambda m: f'{m.group(1)}="{ROOT}/', text)
    path = tmp_path / "s.xml"
    path.write_text(text)
    return path


def test_a_scenario_switches_policies(tmp_path: Path) -> None:
    path = _scenario(tmp_path, '<policy name="streams" state="off"/>')
    assert dict(load_scenario(path).policies) == {"streams": False}
    path = _scenario(tmp_path, '<policy name="streams" state="off"/>'
                               '<policy name="streams" state="on"/>')
    with pytest.raises(ScenarioError, match="a second <policy name='streams'>"):
        load_scenario(path)


def _splits(policies: dict[str, bool] | None = None) -> int:
    return len(judge(Run(SAMPLE_05_STREAM, policies=policies).run()).of("splits"))


def test_streams_off_is_the_thesis_prima(tmp_path: Path) -> None:
    """Fig. 5.9's fix: FA5's video-server exchange inside an explicit stream keeps the
    robot from splitting EA2's question from its reply. With the policy off, the
    stream is a plain sequence again and the thesis' split comes back; a scenario
    and the run's caller switch it alike, the caller last."""
    assert _splits() == 0
    assert _splits(policies={"streams": False}) > 0
    assert _splits(policies={"all": False}) > 0
    off = _scenario(tmp_path, '<policy name="streams" state="off"/>')
    assert len(judge(Run(off).run()).of("splits")) > 0
    assert len(judge(Run(off, policies={"streams": True}).run()).of("splits")) == 0


@pytest.mark.parametrize("switch, message", [
    ("teleport=on",
     "--policy teleport=on: no policy 'teleport' "
     "(known: all, restore-state, interrupt, blend, streams, connect-channel, reactions, "
     "barge-in, exchange)"),
    ("streams=maybe", "--policy streams=maybe: say streams=on or streams=off"),
    ("streams", "--policy streams: say streams=on or streams=off"),
])
def test_prima_run_checks_its_policy_switches(switch: str, message: str) -> None:
    err = io.StringIO()
    assert main(["run", str(SAMPLE_05_STREAM), "--policy", switch],
                out=io.StringIO(), err=err) == 2
    assert message in err.getvalue()


def test_prima_run_switches_policies_in_order() -> None:
    def trace(*switches: str) -> str:
        out = io.StringIO()
        args = ["run", str(SAMPLE_05_STREAM)]
        for s in switches:
            args += ["--policy", s]
        assert main(args, out=out, err=io.StringIO()) == 0
        return out.getvalue()

    on = trace()
    assert "stream-hold" in on
    assert "stream-hold" not in trace("streams=off")
    # (every policy is on by default on the home robot, interrupt included: its profile
    # declares <interruptible>)
    assert trace("streams=off", "all=on") == on
    assert "stream-hold" not in trace("all=on", "streams=off")


POLICY_SCENARIOS = sorted((ROOT / "scenarios" / "policies").glob("*.xml"))


@pytest.mark.parametrize("scenario", POLICY_SCENARIOS, ids=lambda p: p.stem)
def test_a_policy_scenario_matches_its_reviewed_golden(  # type: ignore[no-untyped-def]
        scenario: Path, prima_golden) -> None:
    prima_golden(scenario)


def test_streams_off_shows_the_split_the_stream_prevents() -> None:
    """With the stream off, EA2's question comes between FA5's "Connecting the video
    server." and its result (Fig. 5.9); the reply to the user's "Yes." stays whole (the
    exchange policy, docs/rules.md 7.4)."""
    off = judge(Run(ROOT / "scenarios" / "policies" / "streams-off.xml").run())
    on = judge(Run(SAMPLE_05_STREAM).run())
    assert (len(off.of("splits")), len(on.of("splits"))) == (1, 0)
    (split,) = off.of("splits")
    assert (split.app, split.by, split.kind) == ("fa5-video-timer-stream", "ea2-library", "stream")


THESIS = ROOT / "scenarios" / "thesis"


@pytest.mark.parametrize("scenario", sorted(THESIS.glob("*.xml")), ids=lambda p: p.stem)
def test_every_policy_off_is_the_thesis_prima_byte_for_byte(scenario: Path) -> None:
    """``--policy all=off`` is the baseline: each thesis scenario's trace is the one
    the thesis' PRIMA (no policy, none of the rules that extend it) gives on this
    simulator (scenarios/thesis/all-off/: re-pinned only when the simulator or a
    document changes, never for a mediation rule)."""
    expected = (THESIS / "all-off" / f"{scenario.stem}.txt").read_text()
    assert format_text(Run(scenario, policies={"all": False}).run()) == expected


def _unfaced(path: Path, policies: dict[str, bool] | None = None) -> int:
    return len(judge(Run(path, policies=policies).run()).of("unfaced"))


def test_connect_channel_turns_the_robot_to_its_user_before_it_speaks() -> None:
    """Thesis Fig. 5.3 lines 9-10 and sample-04: touched from behind, the robot used to
    ask "What's the matter with you?" with its back to the user, and EA3's whole
    message followed unfaced. With the policy, a FaceHuman of the mediator's own
    (reason connect-channel) comes first, in the same stream."""
    sample_04 = THESIS / "sample-04.xml"
    assert _unfaced(sample_04, {"connect-channel": False}) > 10
    assert _unfaced(sample_04) == 0
    lines = Run(sample_04).run()
    turns = [ln for ln in lines if ln.reason == "connect-channel"
             and ln.kind.value in ("request", "start")]
    assert {ln.command for ln in turns} == {"FaceHuman"}
    assert {ln.kind.value for ln in turns} == {"request", "start"}
    request = next(ln for ln in turns if ln.kind.value == "request")
    assert isinstance((request.detail or {}).get("precedes"), int)


def test_connect_channel_off_is_the_baseline_of_its_pair() -> None:
    """scenarios/policies/connect-channel-off.xml against thesis/sample-04.xml."""
    off = judge(Run(ROOT / "scenarios" / "policies" / "connect-channel-off.xml").run())
    on = judge(Run(THESIS / "sample-04.xml").run())
    assert (len(off.of("unfaced")), len(on.of("unfaced"))) == (14, 0)


def test_restore_state_resumes_the_explanation_in_front_of_its_panel() -> None:
    """sample-07: FA2's tracking took the robot 2.4 m from panel-1 while EA1's
    explanation was suspended. With the policy the stream first drives back (a
    SetPosition of the mediator's own, in EA1's stream) and is explained there,
    facing the user; scenarios/policies/restore-state-off.xml is the baseline."""
    lines = Run(THESIS / "sample-07.xml").run()
    back = next(ln for ln in lines if ln.reason == "restore-state" and ln.kind.value == "start")
    suspended = next(ln for ln in lines if ln.kind.value == "suspend" and ln.app == "ea1-museum")
    assert (back.app, back.command, back.tree) == ("ea1-museum", "SetPosition", suspended.tree)
    on = judge(lines)
    off = judge(Run(ROOT / "scenarios" / "policies" / "restore-state-off.xml").run())
    assert (len(off.of("elsewhere")), len(on.of("elsewhere"))) == (1, 0)
    assert off.of("elsewhere")[0].away > 2.0
    assert len(on.of("unfaced")) == 0


def test_interrupt_cuts_explanation_1_1_for_the_touch_and_says_it_again() -> None:
    """Fig. 5.12 line 7, the thesis' own example: a touch during Explanation-1-1.
    With the policy, FA4's reaction starts within 0.2 s plus one word (0.4 s at 2.5
    words a second), and Explanation-1-1 is spoken again from its beginning after the
    picture dialogue; without it, the reaction waits for the whole explanation."""
    def run(state: str) -> list[TraceLine]:
        return Run(ROOT / "scenarios" / "policies" / f"interrupt-{state}.xml").run()

    def touch_reaction(lines: list[TraceLine]) -> float:
        touch = next(ln for ln in lines if ln.kind.value == "event" and ln.text == "touched")
        first = next(ln for ln in lines if ln.kind.value == "start" and ln.app == "fa4-picture"
                     and ln.t >= touch.t)
        return first.t - touch.t

    on, off = run("on"), run("off")
    assert touch_reaction(on) <= 0.2 + 0.4
    assert touch_reaction(off) > 1.5
    explanation = "This panel shows research points of our laboratory."
    (cut,) = [ln for ln in on if ln.kind.value == "end" and ln.reason == "interrupt"]
    assert (cut.app, cut.text, cut.detail["spoken"]) == ("ea1-museum", explanation,
                                                         "This panel shows")
    (again,) = [ln for ln in on if ln.kind.value == "start" and ln.reason == "restart"]
    assert (again.text, again.detail["command_id"]) == (explanation, cut.detail["command_id"])
    assert again.t > max(ln.t for ln in on if ln.app == "fa4-picture"
                         and ln.kind.value == "start" and ln.t < again.t)
    assert not [ln for ln in off if ln.reason in ("interrupt", "restart")]


def test_interrupt_is_on_by_default_only_where_the_profile_declares_it() -> None:
    home = policy_settings(_profile(""))
    declared = _profile('<interruptible commands="Speak Gesture"/>')
    assert (home["interrupt"], policy_settings(declared)["interrupt"]) == (False, True)
    assert policy_settings(_profile('<policy name="interrupt" state="off"/>'
                                    '<interruptible commands="Speak"/>'))["interrupt"] is False
    with pytest.raises(DocumentError, match="no Command of this robot"):
        _profile('<interruptible commands="Speak Teleport"/>')


def test_blend_the_robot_dances_while_it_guides_within_the_bound() -> None:
    """scenarios/policies/blend-on.xml: the tune plays while EA1 guides the user to
    panel-2. FA3's dance sways the body (the home robot's Sway, declared to blend
    over TopologicalMove within 2.5 m, at half speed): EA1's move goes on during the
    dance, the sway shows in the poses as a swing of the heading about the course, the
    robot is never farther than 2.5 m from the user, and it reaches panel-2 before it
    does with the policy off, where the move waits for the dance."""
    def run(state: str) -> list[TraceLine]:
        return Run(ROOT / "scenarios" / "policies" / f"blend-{state}.xml",
                   pose_rate=4.0).run()

    def arrival(lines: list[TraceLine]) -> float:
        """When EA1's move to panel-2 ends there."""
        return next(ln.t for ln in lines if ln.kind.value == "end"
                    and ln.command == "TopologicalMove"
                    and "place=panel-2, remaining=0" in str(ln.detail.get("result")))

    on, off = run("on"), run("off")
    dance = next(ln for ln in on if ln.kind.value == "start" and ln.app == "fa3-dance"
                 and "Sway" in (ln.command or ""))
    end = next(ln for ln in on if ln.kind.value == "end" and ln.ab == dance.ab)
    assert any(ln.kind.value == "start" and ln.command == "TopologicalMove"
               and ln.reason == "blend" and dance.t <= ln.t < end.t for ln in on)
    during = [ln for ln in on if dance.t <= ln.t <= end.t and ln.robot and ln.user]
    assert during[-1].robot[0] - during[0].robot[0] > 2.0  # it went on guiding
    assert max(math.dist(ln.robot[:2], ln.user[:2]) for ln in during) <= 2.5
    # the course is due east (heading 0) once the move is under way; the sway swings
    # the body 15 then 20 degrees either side of it
    swing = [(ln.robot[2] + 180.0) % 360.0 - 180.0 for ln in during
             if ln.kind.value == "pose" and ln.robot[0] > during[0].robot[0] + 0.2]
    assert max(swing) >= 10.0 and min(swing) <= -10.0
    assert arrival(on) < arrival(off) - 3.0
    # every blended behavior ends
    blended = {ln.ab for ln in on if ln.kind.value == "start" and ln.reason == "blend"}
    assert blended <= {ln.ab for ln in on if ln.kind.value == "end"}


def test_a_blend_keeps_its_bound_ahead_of_time_when_the_user_stops(tmp_path: Path) -> None:
    """blend-on.xml with the user stopping during the dance: the move goes on under the
    sways only while it cannot take the robot farther than 2.5 m from the user, so the
    robot stops within the bound (it is never noticed after the fact), and the dance
    still ends."""
    text = (ROOT / "scenarios" / "policies" / "blend-on.xml").read_text()
    text = text.replace('<follow at="64" distance="1.2"/>',
                        '<follow at="64" distance="1.2"/><stop at="75"/>')
    text = text.replace('href="../', f'href="{ROOT / "scenarios"}/')
    text = re.sub(r'(fa|ea)="\.\./\.\./', lambda m: f'{m.group(1)}="{ROOT}/', text)
    stops = tmp_path / "blend-stop.xml"
    stops.write_text(text)
    lines = Run(stops, pose_rate=10.0).run()
    dance = next(ln for ln in lines if ln.kind.value == "start" and ln.app == "fa3-dance"
                 and "Sway" in (ln.command or ""))
    end = next(ln for ln in lines if ln.kind.value == "end" and ln.ab == dance.ab)
    during = [ln for ln in lines if dance.t <= ln.t <= end.t and ln.robot and ln.user]
    assert max(math.dist(ln.robot[:2], ln.user[:2]) for ln in during) <= 2.5
    assert during[-1].robot[0] - during[0].robot[0] > 0.5  # it did guide on for a while
