"""The issue's acceptance tests for the simulator."""

from __future__ import annotations

import math
from itertools import pairwise

import pytest

from prima.mediator import Event
from prima.scenario import load_scenario
from prima.sim import CommandRunner, EntryKind, Pose, ReplyRule, Simulator, UserScript, WorldMap

from tests.sim.helpers import EXAMPLES, call, runner, walk, world_map


def test_topological_move_reaches_goal_through_graph_and_reports_corner() -> None:
    r = runner("office", Pose(1, 3, 0))
    r.queue(call("TopologicalMove", to="kidode-room"))
    r.run(200)
    legs = r.ends("TopologicalMove")
    arrivals = [e for e in legs if "place" in e.data]
    assert [e.data["place"] for e in arrivals] == [
        "hall", "poster", "corner", "kidode-door", "kidode-room"]
    # one short iteration at a time (one control period of motion), the last one terminal
    assert [e.iteration for e in legs] == list(range(len(legs)))
    assert [e.terminal for e in legs] == [False] * (len(legs) - 1) + [True]
    assert all(e.data["toward"] for e in legs if "place" not in e.data)
    times = [0.0] + [e.time for e in legs]
    spec = r.sim.spec
    assert max(b - a for a, b in pairwise(times)) <= spec.control_period + 1 / r.sim.kernel.hz
    corner = next(e for e in arrivals if e.data["place"] == "corner")
    assert corner.data["kind"] == "corner"
    reached = [(e.data["place"], e.data["kind"]) for e in r.events("place-reached")]
    assert ("corner", "corner") in reached
    assert reached[-1] == ("kidode-room", "room")
    # each place-reached event comes at the same time as the iteration that reached it
    assert [e.time for e in r.events("place-reached")] == [e.time for e in arrivals]
    pose = r.sim.robot_pose()
    assert math.hypot(pose.x - 18, pose.y - 10) < 0.01
    # 0.4 m/s over ~22 m with turns: well over 55 s of driving
    assert 55 < legs[-1].time < 120


def test_topological_move_replans_from_where_the_robot_is() -> None:
    r = runner("office", Pose(12, 3, 180))  # in the corridor, facing back to the hall
    r.queue(call("TopologicalMove", to="kidode-room"))
    r.run(200)
    places = [e.data["place"] for e in r.ends("TopologicalMove") if "place" in e.data]
    assert places == ["corner", "kidode-door", "kidode-room"]


def test_a_blocked_move_waits_and_tries_again() -> None:
    # the user stands in the corridor between the robot and the corner, then steps aside
    r = runner("office", Pose(11, 3, 0), Pose(13, 3, 180), walk(20, 10, 3.4))
    r.queue(call("TopologicalMove", to="corner"))
    r.run(80)
    legs = r.ends("TopologicalMove")
    blocked = [e for e in legs if e.data.get("blocked")]
    assert blocked and not any(e.terminal for e in blocked)
    assert legs[-1].terminal and legs[-1].data["place"] == "corner"
    assert legs[-1].time > 20


def test_tracking_human_keeps_the_distance_band_while_the_user_walks_a_route() -> None:
    # museum exhibition: the user walks east, then north-east, then back west
    r = runner("museum", Pose(7, 3, 0), Pose(8, 3, 0),
               walk(2, 12, 3), walk(20, 14, 5.5), walk(32, 9, 5.5))
    r.queue(call("TrackingHuman", distance=1.0))
    samples: list[float] = []
    sim = r.sim
    t = 0.0
    while t < 55:
        t += 0.5
        r.run(t)
        if t >= 3:
            samples.append(sim.world.user_distance())
    ends = r.ends("TrackingHuman")
    assert len(ends) >= 50 and not any(e.terminal for e in ends)
    assert not r.events("human-lost")
    band = sim.spec.tracking_band
    assert min(samples) > 1.0 - band, samples
    assert max(samples) < 1.0 + band, samples
    assert abs(sum(samples) / len(samples) - 1.0) < band
    # the robot really moved along: it ended near where the user ended
    assert sim.robot_pose().distance_to(9, 5.5) < 1.5


def test_a_robot_following_a_user_who_stands_comes_to_rest() -> None:
    # the user walks off and stops; the robot follows and settles at its distance: once
    # there, its wheels stand still and the world is no longer stepped (the controller's
    # last requests, far below the wheels' least speed, move nothing)
    r = runner("museum", Pose(7, 3, 0), Pose(8, 3, 0), walk(2, 10, 3))
    r.queue(call("TrackingHuman", distance=1.0))
    r.run(30)
    sim = r.sim
    assert abs(sim.world.user_distance() - 1.0) < sim.spec.tracking_band
    assert sim.robot_pose().distance_to(9, 3) < 0.1  # it really followed
    steps = sim.steps
    r.run(60)
    assert sim.world.mode == 0, "the wheels should stand still"
    assert sim.steps == steps, f"{sim.steps - steps} physics steps while nothing moved"
    assert len(r.ends("TrackingHuman")) >= 100  # it kept tracking all the while


def test_a_robot_tracking_a_user_who_stands_is_not_woken_for_nothing() -> None:
    # once it has settled at its distance, each iteration of TrackingHuman wakes only to
    # end: its control wakes in between (10 a second) would find nothing to do
    r = runner("museum", Pose(7, 3, 0), Pose(8, 3, 0), walk(2, 10, 3))
    r.queue(call("TrackingHuman", distance=1.0))
    r.run(30)
    sim = r.sim
    skipped, ends = sim.skipped, len(r.ends("TrackingHuman"))
    r.run(60)
    iterations = len(r.ends("TrackingHuman")) - ends
    wakes = 30 * 10  # its control wakes in 30 s, the iterations' ends among them
    assert iterations >= 50
    assert sim.skipped - skipped >= wakes - iterations - 2, (sim.skipped - skipped, iterations)


@pytest.mark.pure  # (it turns the skipping off by patching the simulator)
def test_a_run_whose_idle_wakes_are_skipped_is_the_run_that_wakes_them(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # a tracker, a user who stands and walks off again, then a search: the same trace
    # (events, starts, ends) and poses either way
    def run() -> tuple[list[object], int]:
        r = runner("museum", Pose(7, 3, 0), Pose(8, 3, 0), walk(2, 10, 3), walk(40, 6, 6))
        r.queue(call("TrackingHuman", distance=1.0))
        r.run(50)
        r.queue(call("ActiveSensingHuman", turn=45))
        r.run(70)
        return [*r.trace, r.sim.robot_pose(), r.sim.world.user_pose()], r.sim.skipped

    skipping, skipped = run()
    assert skipped > 100
    monkeypatch.setattr(Simulator, "_skip_idle", lambda self, limit: None)
    waking, none = run()
    assert none == 0
    assert len(skipping) > 100
    assert skipping == waking


def test_tracking_human_loses_a_user_who_walks_behind_a_wall() -> None:
    # office: robot in the hall, user walks out of the hall and behind its wall
    r = runner("office", Pose(3, 3, 0), Pose(4.2, 3, 0), walk(1, 7, 3), walk(5, 7.5, 3.5))
    r.queue(call("TrackingHuman", distance=1.0))
    r.run(5)
    assert not r.events("human-lost")
    r.sim.world.put_user(8, 6)  # teleport the user behind the corridor wall
    r.run(12)
    lost = r.events("human-lost")
    assert len(lost) == 1
    last = r.ends("TrackingHuman")[-1]
    assert last.terminal and last.data["lost"] is True


def test_a_wall_hides_the_user_from_human_detection() -> None:
    # library: robot at (6, 4) looking east down at the first bookshelf (x = 8)
    sim = Simulator(_library(), robot=Pose(6, 4, 0),
                    user=_script(Pose(7.5, 4, 0)))
    assert sim.user_visible()
    sim.world.put_user(9, 4)  # same direction, 3 m away, behind the shelf
    assert not sim.user_visible()
    sim.world.put_user(9, 8.5)  # 5.1 m: out of camera range even in the open
    assert not sim.user_visible()


def test_human_found_only_when_the_user_comes_out_from_behind_the_shelf() -> None:
    # the user walks up aisle-1 (behind the shelf) and out into the robot's view
    r = runner("library", Pose(6.5, 7.5, 0), Pose(9, 3, 90), walk(1, 9, 7.6), walk(20, 8.6, 8.4))
    r.queue(call("ActiveSensingHuman", turn=0))
    r.run(30)
    found = r.events("human-found")
    assert len(found) == 1
    # from (6.5, 7.5) the shelf (x 8, y up to 7.2) hides the user until they are past y ~ 7.3
    arrive = [e.time for e in r.trace if e.kind is EntryKind.USER and e.name == "arrive"][0]
    assert 1 + (7.0 - 3) / 0.3 < found[0].time <= arrive + 0.1
    assert r.ends("ActiveSensingHuman")[-1].data["found"] is True


def test_active_sensing_turns_after_10_s_and_finds_a_user_behind_the_robot() -> None:
    r = runner("museum", Pose(9.5, 4, 0), Pose(8, 4, 0))  # user 1.5 m straight behind
    r.queue(call("ActiveSensingHuman", say="Where are you?"))
    r.run(60)
    ends = r.ends("ActiveSensingHuman")
    # 10 s unseen (20 control periods), turn 90; 10 s unseen, turn 90 more: the user
    # comes into view. Each iteration is short, so another app can act between any two.
    # The first iteration of a retry lasts until "Where are you?" is said.
    assert [e.terminal for e in ends] == [False] * (len(ends) - 1) + [True]
    said = r.sim.spec.speech_duration("Where are you?")
    watch = [e for e in ends[:20] if "unseen" in e.data]
    assert watch[0].time == pytest.approx(said) and watch[-1].time == pytest.approx(10.0)
    assert all(0 < b.time - a.time <= 0.5 + 1e-9 for a, b in pairwise(watch))
    assert [e.data["unseen"] for e in watch] == [pytest.approx(e.time) for e in watch]
    turn = _turn_time(90)
    first_turn = ends[len(watch)]
    assert first_turn.time == pytest.approx(10.0 + turn, abs=0.1)
    assert first_turn.data == {"found": False, "turned": 90.0}
    # the second turn stops as soon as the user comes into the 60 degree field of view
    assert 2 * 10.0 + turn < ends[-1].time < 2 * (10.0 + turn)
    assert ends[-1].data["found"] is True and ends[-1].data["distance"] == 1.5
    found = r.events("human-found")
    assert len(found) == 1 and 10 + turn + 10 < found[0].time <= ends[-1].time
    heading = r.sim.robot_pose().heading
    assert 150.0 < heading < 180.0  # turned only until the user (at 180) was in view


def test_active_sensing_finds_a_visible_user_at_once() -> None:
    r = runner("museum", Pose(9.5, 4, 0), Pose(11, 4, 180))
    r.queue(call("ActiveSensingHuman"))
    r.run(5)
    [end] = r.ends("ActiveSensingHuman")
    assert end.time == 0.0 and end.terminal and end.data["found"] is True
    assert [e.time for e in r.events("human-found")] == [0.0]


@pytest.mark.parametrize("words", [1, 5, 10, 25])
def test_speak_lasts_as_long_as_its_text_takes(words: int) -> None:
    r = runner("museum", Pose(2, 4, 0))
    text = " ".join(["word"] * words)
    r.queue(call("Speak", text=text))
    r.run(30)
    [end] = r.ends("Speak")
    rate = r.sim.spec.speech_rate
    expected = max(r.sim.spec.min_utterance, words / rate)
    assert end.time == pytest.approx(expected, abs=0.02)
    assert end.data["duration"] == pytest.approx(expected, abs=0.02)


def _run_example() -> list[dict[str, object]]:
    scenario = load_scenario(EXAMPLES / "office-kidode.xml")
    r = CommandRunner(Simulator.from_scenario(scenario))
    r.queue(call("QA", prompt="Where are you going?", grammar="g"),
            call("Speak", text="Come on, let's go."),
            call("TopologicalMove", to="kidode-room"),
            call("ActiveSensingHuman", say="Where are you?"),
            call("TrackingHuman", distance=1.2))
    r.run(scenario.until)
    return [e.to_dict() for e in r.trace]


def test_two_runs_of_the_same_scenario_give_identical_event_sequences() -> None:
    first = _run_example()
    second = _run_example()
    assert first == second
    kinds = {e["kind"] for e in first}
    assert {"end", "event", "user"} <= kinds


def test_advancing_in_chunks_gives_the_same_run_as_event_by_event() -> None:
    scenario = load_scenario(EXAMPLES / "office-kidode.xml")

    def run(step: float | None) -> list[dict[str, object]]:
        r = CommandRunner(Simulator.from_scenario(scenario))
        r.queue(call("TopologicalMove", to="kidode-room"), call("TrackingHuman"))
        if step is None:
            r.run(150)
        else:
            t = 0.0
            while t < 150:
                t = min(150, t + step)
                r.sim.advance_to(t)
        return [e.to_dict() for e in r.trace]

    assert run(None) == run(0.37) == run(7.0)


def _library() -> WorldMap:
    return world_map("library")


def _script(start: Pose) -> UserScript:
    return UserScript(start)


def _turn_time(degrees: float) -> float:
    # trapezoid profile: 180 deg/s^2 up to 90 deg/s
    accel, top = 180.0, 90.0
    ramp = top * top / accel
    if degrees <= ramp:
        return 2 * math.sqrt(degrees / accel)
    return 2 * top / accel + (degrees - ramp) / top


def test_stop_on_report_returns_at_each_report_and_changes_nothing() -> None:
    scenario = load_scenario(EXAMPLES / "office-kidode.xml")

    def run(stop: bool) -> tuple[list[dict[str, object]], list[float]]:
        r = CommandRunner(Simulator.from_scenario(scenario))
        r.queue(call("TopologicalMove", to="kidode-room"))
        returns = []
        while r.sim.now() < 60:
            seen = r.sim.reports
            r.sim.advance_to(60, stop_on_report=stop)
            returns.append(r.sim.now())
            if stop:
                assert r.sim.reports > seen or r.sim.now() == 60
        return [e.to_dict() for e in r.trace], returns

    plain, _ = run(False)
    stopping, returns = run(True)
    assert stopping == plain
    report_times = sorted({e["time"] for e in plain if e["time"] < 60})
    assert set(report_times) <= set(returns) and len(returns) > 5


def test_places_passed_while_tracking_are_reported() -> None:
    # the user leads the robot round the office corner: localization notices the corner
    r = runner("office", Pose(11, 3, 0), Pose(12.2, 3, 0), walk(1, 15, 3), walk(10, 15, 8))
    r.queue(call("TrackingHuman", distance=1.0))
    r.run(40)
    reached = [e.data["place"] for e in r.events("place-reached")]
    assert reached.count("corner") == 1
    assert "kidode-room" not in reached  # never came near it


def test_servers_reply_to_what_applications_send() -> None:
    events = []
    sim = Simulator(_library(), robot=Pose(2, 2, 0), on_event=events.append, replies=(
        ReplyRule("video", "OK: {text}", after=4.0, contains="record"),
        ReplyRule("video", "unknown request"),
    ))
    sim.advance_to(1.0)
    sim.send("video", "Record channel 12")
    sim.send("library", "search: nothing")      # no rule for this server: no reply
    sim.advance_to(3.0)
    sim.send("video", "status?")
    sim.advance_to(10.0)
    assert [(e.time, e.name, dict(e.data)) for e in events] == [
        (4.0, "message", {"sender": "video", "text": "unknown request"}),
        (5.0, "message", {"sender": "video", "text": "OK: Record channel 12"}),
    ]
    assert [m["to"] for m in sim.outbox] == ["video", "library", "video"]


def test_a_server_replying_at_once_still_lets_time_move() -> None:
    sim = Simulator(_library(), robot=Pose(2, 2, 0), replies=(ReplyRule("srv", "pong", after=0.0),))
    pongs = []

    def ping_back(event: Event) -> None:
        pongs.append(event.time)
        sim.send("srv", "ping")

    sim.on_event = ping_back
    sim.send("srv", "ping")
    sim.advance_to(1.0)  # would never return if the reply came at the same instant
    assert len(pongs) == 50 and pongs[0] == pytest.approx(0.02)


def test_topological_move_from_off_the_map_visits_every_place_on_its_way() -> None:
    r = runner("office", Pose(2, 3, 0))  # between the entrance and the hall, not at a place
    r.queue(call("TopologicalMove", to="corner"))
    r.run(120)
    reached = [e.data["place"] for e in r.events("place-reached")]
    assert reached == ["hall", "poster", "corner"]  # it headed straight for the corner
