"""Robot hardware profiles."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import pytest

from prima.catalog import STANDARD_DEVICES, Priority
from prima.dsl import RobotProfile, default_profile, parse_profile
from prima.errors import DocumentError
from prima.vocab import DEFAULT_BUDGETS, AppKind, Budgets


def test_default_profile_extends_the_catalog() -> None:
    profile = default_profile()
    catalog = profile.catalog()
    assert set(STANDARD_DEVICES) <= profile.devices
    assert catalog["TakePicture"].robot_specific
    assert catalog["TakePicture"].devices == {"camera"}
    assert catalog["TakePicture"].priority is Priority.HIGH
    assert catalog["TakePicture"].duration == 1.0
    assert catalog["Speak"].duration is None
    assert catalog["TopologicalMove"].priority is Priority.LOW
    assert profile.events == {"touched": True}
    assert profile.user_events == {"touched"}  # (the user's own action: docs/rules.md 7.1)
    assert "volume" in profile.extras["Speak"]
    assert profile.speech_rate == 2.5 and profile.gestures["nod"] == 1.0


PROFILE = """<robot xmlns="urn:prima:robot:1" name="r">
  <body radius="0.2" max-speed="0.4" max-accel="0.5" max-turn-rate="90"/>
  <speech rate="2.5"/>
  <camera fov="60" range="4"/>
  <head pan-min="-90" pan-max="90" tilt-min="{tilt}" tilt-max="30"/>
  <devices>
    {devices}
  </devices>
  {rest}
</robot>"""
ALL = "\n    ".join(f'<device name="{d}"/>' for d in STANDARD_DEVICES)


def _load(devices: str = ALL, rest: str = "", tilt: str = "-30") -> None:
    parse_profile(PROFILE.format(devices=devices, rest=rest, tilt=tilt).encode(), "r.xml")


def test_minimal_profile_loads() -> None:
    _load()


@pytest.mark.parametrize("kwargs, line, fragment", [
    ({"devices": '<device name="speaker"/>'}, 6, "needs the device 'locomotion'"),
    ({"rest": '<command name="Speak" devices="speaker"/>'}, 15, "is a common Command"),
    ({"rest": '<command name="Laser" devices="laser"/>'}, 15, "undeclared device 'laser'"),
    ({"rest": '<extra command="Fly" name="speed" kind="number"/>'}, 15, "unknown Command 'Fly'"),
    ({"rest": '<event name="message"/>'}, 15, "is a predefined event"),
    ({"tilt": "45"}, 5, "tilt range is empty"),
    ({"rest": '<gesture name="nod" duration="-1"/>'}, 15, "gesture"),
    # docs/rules.md 7.1: a touch is always the user's own action
    ({"rest": '<event name="touched" user="false"/>'}, 15, "always the user's own action"),
    # a local motion is a Command the profile declares for it, never one apps move with
    ({"rest": '<blend local="Turn" over="TopologicalMove" devices="locomotion"/>'}, 15,
     "makes the common Command 'Turn' a local motion"),
    ({"rest": '<command name="Wiggle" devices="arm"><perform>'
              '<sway degrees="10" period="1" seconds="2"/></perform></command>'}, 15,
     "a <sway> step moves the body"),
])
def test_profile_errors(kwargs: dict[str, str], line: int, fragment: str) -> None:
    with pytest.raises(DocumentError) as info:
        _load(**kwargs)
    assert any(p.line == line and fragment in p.message for p in info.value.problems), \
        info.value.problems


def test_a_touch_is_the_users_own_action_whatever_the_profile_says() -> None:
    """docs/rules.md 7.1: a profile that declares its touch sensor without ``user`` still
    has a touch that is the user's own action; it may name more such events."""
    profile = parse_profile(PROFILE.format(
        devices=ALL, tilt="-30",
        rest='<event name="touched"/><event name="patted" user="true"/>'
             '<event name="bumped"/>').encode(), "r.xml")
    assert profile.user_events == {"touched", "patted"}


def test_a_robot_specific_command_without_a_duration_has_none() -> None:
    profile = parse_profile(PROFILE.format(
        devices=ALL + '<device name="laser"/>', tilt="-30",
        rest='<command name="Laser" devices="laser"/>'
             '<command name="Blink" devices="laser" duration="0.5"/>').encode(), "r.xml")
    assert [(c.name, c.duration) for c in profile.commands] == [("Laser", None), ("Blink", 0.5)]


def _profile(body: str = 'radius="0.2" max-speed="0.4"', rest: str = "",
             budgets: str = "") -> RobotProfile:
    return parse_profile(_profile_text(body, rest, budgets).encode(), "r.xml")


def _problems(**kwargs: str) -> list[tuple[str, int, str]]:
    """Each problem's source line (stripped), column and message."""
    with pytest.raises(DocumentError) as info:
        _profile(**kwargs)
    lines = _profile_text(**kwargs).splitlines()
    return [(lines[p.line - 1].strip(), p.col, p.message) for p in info.value.problems]


def _profile_text(body: str = 'radius="0.2" max-speed="0.4"', rest: str = "",
                  budgets: str = "") -> str:
    text = PROFILE.format(devices=ALL, rest=rest, tilt="-30").replace(
        'radius="0.2" max-speed="0.4"', body)
    if budgets:
        text = text.replace("  </devices>\n", f"  </devices>\n  <budgets {budgets}/>\n")
    return text


def test_budgets_default_without_the_element() -> None:
    assert default_profile().budgets == DEFAULT_BUDGETS
    assert _profile().budgets == DEFAULT_BUDGETS


def test_budgets_without_a_role_are_every_applications() -> None:
    profile = _profile(budgets='text="2000" sends-per-second="0.5" waiting="10" longest-ab="20" '
                               'wait-share="5" wait-window="10" starts-per-instant="7"')
    expected = Budgets(text=2000, sends_per_second=0.5, waiting=10, longest_ab=20.0,
                       wait_share=5.0, wait_window=10.0, starts_per_instant=7)
    assert profile.budgets == {AppKind.FA: expected, AppKind.EA: expected}
    ea = profile.budgets[AppKind.EA]
    assert isinstance(ea.text, int) and isinstance(ea.waiting, int)
    assert _profile(budgets='waiting="3"').budgets == {
        kind: replace(DEFAULT_BUDGETS[kind], waiting=3) for kind in AppKind}


def test_a_roles_budgets_go_over_the_role_less_ones_and_its_defaults() -> None:
    profile = _profile(budgets='waiting="3"/>\n  <budgets role="ea" wait-share="10"/>\n'
                               '  <budgets role="fa" waiting="50"')
    assert profile.budgets[AppKind.EA] == Budgets(waiting=3, wait_share=10.0)
    assert profile.budgets[AppKind.FA] == replace(DEFAULT_BUDGETS[AppKind.FA], waiting=50)


def test_a_role_given_budgets_twice_is_an_error() -> None:
    with pytest.raises(DocumentError) as caught:
        _profile(budgets='role="ea" waiting="3"/>\n  <budgets role="ea" waiting="4"')
    [problem] = caught.value.problems
    assert "a second <budgets role='ea'>" in problem.message


HUGE = "1" + "0" * 400
TINY = "0." + "0" * 400 + "1"


@pytest.mark.parametrize("kwargs, col, fragment", [
    ({"budgets": 'text="10001"'}, 18, "text='10001' is too large: at most 10,000 characters"),
    ({"budgets": f'longest-ab="{HUGE}"'}, 24, "is too large: at most 1e+06 s"),
    ({"budgets": f'sends-per-second="{TINY}"'}, 30, "must be greater than 0"),
    ({"budgets": 'wait-share="90"'}, 24, "wait-share=90 s is longer than its window"),
    ({"budgets": 'wait-window="10"'}, 25, "(wait-window=10 s)"),
    ({"body": f'radius="{TINY}" max-speed="0.4"'}, 17, "radius='0.000000000000000...' must be"),
    ({"body": f'radius="0.2" max-speed="{HUGE}"'}, 33, "max-speed='10000000000000000...' is too"),
    ({"body": 'radius="11" max-speed="0.4"'}, 17, "radius='11' is too large: at most 10 m"),
])
def test_numbers_out_of_range_are_located(kwargs: dict[str, str], col: int,
                                          fragment: str) -> None:
    [(line, found_col, message)] = _problems(**kwargs)
    assert line.startswith(("<budgets", "<body")) and found_col == col, message
    assert fragment in message


@pytest.mark.parametrize("rest, fragment", [
    (f'<gesture name="g" duration="{TINY}"/>', "duration="),
    ('<gesture name="g" duration="3601"/>', "at most 3,600 s"),
    (f'<command name="Zap" devices="arm" duration="{HUGE}"/>', "duration="),
    ('<extra command="Speak" name="v" kind="number" default="nan"/>',
     "default='nan' is not a number a Command can take"),
    ('<extra command="Speak" name="v" kind="number" default="1e999"/>',
     "default='1e999' is not a number"),
])
def test_durations_and_defaults_must_be_usable(rest: str, fragment: str) -> None:
    [(_line, _col, message)] = _problems(rest=rest)
    assert fragment in message


def test_a_number_default_that_is_not_a_number_at_all_is_reported() -> None:
    [(_l, _c, message)] = _problems(rest='<extra command="Speak" name="v" kind="number" '
                                          'default="loud"/>')
    assert "default='loud'" in message


def test_an_ea_using_a_common_gesture_this_robot_lacks_is_an_error() -> None:
    """A robot should offer every common gesture, but one may not: an EA validated
    against it is told so, not left to fail when it gestures."""
    from prima.dsl import check_document

    source = (b'<pxml xmlns="urn:prima:pxml:1" kind="ea" name="e"><state id="s" initial="true">'
              b'<entry><chain>Gesture(bow), Gesture(nod)</chain></entry></state></pxml>')
    offered = _profile(rest='<gesture name="nod" duration="1.0"/>')
    assert "bow" not in offered.gestures
    _, problems = check_document(source, "e.pxml", offered)
    assert [p.message for p in problems] == [
        "unknown gesture 'bow' (a common gesture, but not one this robot offers; it knows: "
        "nod)"]
    _, problems = check_document(source, "e.pxml", default_profile())
    assert problems == []


def test_a_text_is_words_only_on_a_command_that_uses_the_speaker() -> None:
    """A robot's own Command may take a text it prints or shows: not words (no bubble, no
    turn to the user first, cut at once); the trace shows it as an argument."""
    from prima.run import _shown_args  # white box: the trace's rendering of arguments
    from prima.mediator import Call

    profile = parse_profile(PROFILE.format(
        devices=ALL + '<device name="printer"/>', tilt="-30",
        rest='<command name="PrintTicket" devices="printer" duration="2">'
             '<param name="label" kind="text"/></command>'
             '<command name="Announce" devices="speaker" duration="2">'
             '<param name="words" kind="text"/></command>').encode(), "r.xml")
    catalog = profile.catalog()
    assert catalog["PrintTicket"].spoken({"label": "Visitor Ada"}) == []
    assert catalog["Announce"].spoken({"words": "Hello"}) == ["Hello"]
    assert catalog["Speak"].spoken({"text": "Hi"}) == ["Hi"]
    assert _shown_args(catalog, Call("PrintTicket", {"label": "Visitor Ada"})) == [
        'label="Visitor Ada"']
    assert _shown_args(catalog, Call("Announce", {"words": "Hello"})) == []


def test_a_profile_without_every_common_gesture_is_warned_of(tmp_path: Path) -> None:
    from prima.dsl import Validation

    robot = tmp_path / "r.xml"
    robot.write_text(_profile_text(rest='<gesture name="nod" duration="1.0"/>'))
    report = Validation().run([robot])
    assert report.errors == 0
    assert sorted(p.message.split("'")[1] for p in report.problems) == sorted(
        {"shake-head", "wave", "bow", "happy", "sad", "surprised"})
    assert all(p.severity.value == "warning" for p in report.problems)
