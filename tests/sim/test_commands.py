"""Each Command does what a user would expect of the robot."""

from __future__ import annotations

import math

import pytest

from prima.catalog import Catalog, CommandSpec
from prima.errors import SimulationError
from prima.mediator import AtomicBehavior, Call
from prima.sim import (
    CommandRunner,
    EntryKind,
    Pose,
    RobotSpec,
    ScheduledEvent,
    Simulator,
    TimedAction,
    UserActionKind,
    WorldMap,
    Zone,
)

from tests.sim.helpers import call, runner, world_map

CENTER = Pose(9.5, 4, 0)


@pytest.mark.parametrize("angle, heading", [(90, 90), (-90, 270), (270, 270), (450, 90)])
def test_turn_rotates_the_body_counter_clockwise(angle: float, heading: float) -> None:
    r = runner("museum", CENTER)
    r.queue(call("Turn", angle=angle))
    r.run(20)
    assert r.sim.robot_pose().heading == pytest.approx(heading, abs=0.01)
    end = r.ends("Turn")[0]
    assert end.time == pytest.approx(abs(angle) / 90 + 0.5, abs=0.1)  # ramp + cruise


def test_set_direction_to_a_heading_and_toward_a_place() -> None:
    r = runner("museum", CENTER)
    r.queue(call("SetDirection", heading=135), call("SetDirection", toward="panel-2"))
    r.run(20)
    first, second = r.ends("SetDirection")
    assert first.data["heading"] == pytest.approx(135, abs=0.1)
    expected = math.degrees(math.atan2(6.4 - 4, 12 - 9.5))
    assert second.data["heading"] == pytest.approx(expected, abs=0.1)


def test_set_direction_at_a_panel_faces_the_panel() -> None:
    r = runner("museum", Pose(12, 6.4, 0))
    r.queue(call("SetDirection", toward="panel-2"), call("PointByHand", toward="panel-2"))
    r.run(20)
    assert r.ends("SetDirection")[0].data["heading"] == pytest.approx(90, abs=0.1)
    assert r.ends("PointByHand")[0].data["angle"] == 0.0


def test_set_position_drives_in_short_legs_around_walls() -> None:
    # from the lobby into the exhibition room: the straight line is blocked by the partition
    r = runner("museum", Pose(1.5, 1.5, 0))
    r.queue(call("SetPosition", x=6.0, y=1.5))
    r.run(120)
    ends = r.ends("SetPosition")
    assert ends[-1].terminal and ends[-1].data["reached"] is True
    assert len(ends) >= 4 and not any(e.terminal for e in ends[:-1])
    assert r.sim.robot_pose().distance_to(6.0, 1.5) <= r.sim.spec.position_tolerance


def test_set_position_and_direction_ends_facing_the_heading() -> None:
    r = runner("museum", CENTER)
    r.queue(call("SetPositionAndDirection", x=11, y=5, heading=90))
    r.run(60)
    last = r.ends("SetPositionAndDirection")[-1]
    assert last.terminal and last.data["heading"] == pytest.approx(90, abs=0.1)
    assert (last.data["x"], last.data["y"]) == (pytest.approx(11, abs=0.05),
                                                 pytest.approx(5, abs=0.05))


def test_set_speed_and_time_drives_and_a_wall_stops_it() -> None:
    r = runner("museum", Pose(14, 4, 0))  # 2 m from the east wall at x = 16
    r.queue(call("SetSpeedAndTime", speed=0.4, time=10))
    r.run(30)
    pose = r.sim.robot_pose()
    assert 15.7 < pose.x < 16 - 0.05 - 0.2 + 0.03  # pressed against the wall, not through it


def test_stop_moving_brakes_within_the_acceleration_limit() -> None:
    r = runner("museum", CENTER)
    r.sim.world.command(0.4, 0.0)
    r.sim.advance_to(2.0)
    r.queue(call("StopMoving"))
    r.run(5)
    end = r.ends("StopMoving")[0]
    assert end.time == pytest.approx(2.0 + 0.4 / 0.5, abs=0.05)
    assert r.sim.world.mode == 0


def test_move_head_changes_what_the_camera_sees() -> None:
    r = runner("museum", CENTER, Pose(9.5, 6, 0))  # user to the robot's left
    assert not r.sim.user_visible()
    r.queue(call("MoveHead", pan=90, tilt=10))
    r.run(5)
    assert r.ends("MoveHead")[0].data == {"pan": 90.0, "tilt": 10.0}
    assert r.ends("MoveHead")[0].time == pytest.approx(1.0)
    assert r.sim.user_visible()


def test_face_human_turns_toward_the_user_even_out_of_view() -> None:
    r = runner("museum", CENTER, Pose(9.5, 2, 0))  # to the robot's right
    r.queue(call("FaceHumanAndSpeak", text="Hello there"))
    r.run(10)
    end = r.ends("FaceHumanAndSpeak")[0]
    assert end.data["found"] is True and end.data["heading"] == pytest.approx(270, abs=0.1)


def test_gestures_last_their_profile_time_and_unknown_ones_fail() -> None:
    r = runner("museum", CENTER)
    r.queue(call("Gesture", name="bow"), call("Gesture", name="juggle"))
    r.run(10)
    bow, juggle = r.ends("Gesture")
    assert bow.time == pytest.approx(1.5) and bow.data == {"gesture": "bow"}
    assert "juggle" in str(juggle.data["error"])


def test_the_additional_arguments_the_robot_acts_on_change_what_it_does() -> None:
    """A gesture's tempo, a drive's speed and a turn's rate (a profile's ``<extra>``s,
    EXTRAS_ACTED_ON) show in the times and the poses. They used to reach the simulator
    and change nothing: fa3-dance's ``Gesture(dance)[tempo=1.5]`` danced at its own
    tempo."""
    r = runner("museum", CENTER)
    r.queue(Call("Gesture", {"name": "bow"}, {"tempo": 2.0}),
            Call("Turn", {"angle": 90}, {"rate": 30.0}))
    r.run(20)
    assert r.ends("Gesture")[0].time == pytest.approx(0.75, abs=0.02)  # (1.5 s, tempo 2)
    turn = r.ends("Turn")[0]
    assert turn.time - 0.75 == pytest.approx(90 / 30, abs=0.25)  # (1.5 s at 90 deg/s)
    assert r.sim.robot_pose().heading == pytest.approx(90, abs=0.01)
    slow = runner("museum", CENTER)
    slow.queue(Call("SetPosition", {"x": 9.5, "y": 6.0}, {"speed": 0.1}))
    slow.run(5)
    made = slow.sim.robot_pose().y - CENTER.y
    assert 0.25 < made <= 0.35  # (a turn to face the way, then 0.1 m/s: at the robot's
    #                               0.4 m/s it would have gone over a metre)


def test_an_additional_argument_outside_its_range_ends_the_command_with_an_error() -> None:
    r = runner("museum", CENTER)
    r.queue(Call("Gesture", {"name": "bow"}, {"tempo": 0.0}),
            Call("Turn", {"angle": 90}, {"rate": "fast"}))
    r.run(5)
    gesture, turn = r.ends("Gesture")[0], r.ends("Turn")[0]
    assert gesture.data["error"] == "Gesture: tempo must be positive, not 0"
    assert "argument 'rate' must be a number" in str(turn.data["error"])


def _with_camera(duration: float | None) -> Catalog:
    """The standard catalog plus a robot-specific TakePicture lasting ``duration``."""
    picture = CommandSpec("TakePicture", frozenset({"camera"}), robot_specific=True,
                          duration=duration)
    return Catalog.standard().extended([picture], ["camera"])


def test_take_picture_captures_what_the_camera_sees() -> None:
    r = runner("museum", CENTER, Pose(11, 4, 180), catalog=_with_camera(0.8))
    r.queue(call("TakePicture"), call("Turn", angle=180), call("TakePicture"))
    r.run(10)
    first, second = r.ends("TakePicture")
    assert first.data["saw_user"] is True and second.data["saw_user"] is False
    assert second.data["heading"] == pytest.approx(180)
    assert len(r.sim.pictures) == 2
    # each capture lasts the duration the robot's catalog gives it
    assert first.time == pytest.approx(0.8)
    assert second.time - r.ends("Turn")[0].time == pytest.approx(0.8)


def test_a_robot_specific_command_needs_its_catalog() -> None:
    r = runner("museum", CENTER, catalog=_with_camera(None))
    r.queue(call("TakePicture"))
    r.run(1)
    assert "no duration" in str(r.ends("TakePicture")[0].data["error"])
    r = runner("museum", CENTER)  # the standard catalog has no TakePicture
    r.queue(call("TakePicture"))
    r.run(1)
    assert "no Command 'TakePicture'" in str(r.ends("TakePicture")[0].data["error"])


def test_unknown_commands_and_bad_arguments_end_with_an_error_not_a_crash() -> None:
    r = runner("museum", CENTER)
    r.queue(call("Fly", height=3), call("Turn", angle="left"),
            call("TopologicalMove", to="nowhere"))
    r.run(1)
    errors = [e.data["error"] for e in r.ends()]
    assert "no Command 'Fly'" in errors[0]
    assert "must be a number" in errors[1]
    assert "unknown place 'nowhere'" in errors[2]
    assert all(e.time == 0.0 and e.terminal for e in r.ends())


def test_finished_is_never_called_from_inside_start() -> None:
    calls: list[int] = []
    sim = Simulator(world_map("museum"), robot=CENTER, finished=lambda ab, o: calls.append(ab))
    sim.start(AtomicBehavior(1, "fa", 0, (call("Fly"),), (1,), frozenset()))
    assert calls == [] and sim.next_time() == 0.0
    sim.advance_to(0.0)
    assert calls == [1]


@pytest.mark.parametrize("past", [1e-9, 1e-12])
def test_advancing_until_a_hair_past_a_tick_stops_at_that_tick(
        monkeypatch: pytest.MonkeyPatch, past: float) -> None:
    # (12.3 + 0.3 is 12.600000000000001: such a time is the tick of 12.6, not one that
    # is never reached; the simulator is stopped if it goes round and round instead)
    sim = Simulator(world_map("museum"), robot=CENTER)
    calls = [0]
    real = Simulator._wake_at

    def counted(self: Simulator, last: int) -> int:
        calls[0] += 1
        if calls[0] > 100:
            raise AssertionError("advance_until goes round and round")
        return real(self, last)

    monkeypatch.setattr(Simulator, "_wake_at", counted)
    sim.advance_until(12.6 + past)
    assert sim.now() == 12.6 == sim.on_grid(12.6 + past) and calls[0] <= 2
    assert sim.on_grid(12.61) == 12.62 and sim.on_grid(12.6 - past) == 12.6


def test_misuse_raises_simulation_errors() -> None:
    museum = world_map("museum")
    with pytest.raises(SimulationError, match="multiple of 10"):
        Simulator(museum, hz=55)
    sim = Simulator(museum, robot=CENTER)
    ab = AtomicBehavior(1, "fa", 0, (call("Speak", text="hello"),), (1,), frozenset({"speaker"}))
    sim.start(ab)
    with pytest.raises(SimulationError, match="already running"):
        sim.start(ab)
    sim.advance_to(2.0)
    with pytest.raises(SimulationError, match="cannot go back"):
        sim.advance_to(1.0)
    with pytest.raises(SimulationError, match="must be positive"):
        RobotSpec(radius=0.0)
    with pytest.raises(SimulationError, match="duplicate place names"):
        WorldMap("m", places=(museum.places[0], museum.places[0]))


def test_a_grouped_ab_performs_its_calls_in_order() -> None:
    ends: list[tuple[float, dict]] = []
    sim = Simulator(world_map("museum"), robot=CENTER,
                    finished=lambda ab, o: ends.append((sim.now(), dict(o.values))))
    sim.start(AtomicBehavior(1, "fa", 0, (call("Speak", text="one two three four five"),
                                         call("Turn", angle=90)), (1, 2),
                             frozenset({"speaker", "locomotion"})))
    sim.advance_to(10)
    [(time, values)] = ends
    assert time == pytest.approx(2.0 + 1.5, abs=0.1)
    assert values["duration"] == 2.0 and values["heading"] == pytest.approx(90)


def test_abandoned_tracking_holds_still() -> None:
    r = runner("museum", Pose(7, 3, 0), Pose(8.5, 3, 0),
               TimedAction(1, UserActionKind.WALK, x=13, y=3))
    r.queue(call("TrackingHuman"))
    r.run(6)
    r.stop_loop()
    r.run(12)
    x = r.sim.robot_pose().x
    r.run(20)
    assert r.sim.robot_pose().x == x and r.sim.world.mode == 0


def test_network_messages_sounds_and_zones() -> None:
    events = (ScheduledEvent(3, "message", {"sender": "Kidode", "text": "Late."}),
              ScheduledEvent(4, "sound-heard", {"sound": "tune"}))
    museum = world_map("museum")
    exhibition = museum.area("exhibition")
    assert exhibition is not None
    zone = Zone("exhibition", "ea1.pxml", exhibition)
    r = CommandRunner(Simulator(museum, robot=Pose(1.5, 4, 0), events=events, zones=(zone,)))
    r.queue(call("TopologicalMove", to="center"))
    r.run(60)
    names = [(e.kind, e.name) for e in r.trace if e.kind in (EntryKind.EVENT, EntryKind.ZONE)]
    assert (EntryKind.EVENT, "message") in names and (EntryKind.EVENT, "sound-heard") in names
    assert (EntryKind.ZONE, "exhibition") in names
    zone_entry = [e for e in r.trace if e.kind is EntryKind.ZONE][0]
    assert zone_entry.data["ea"] == "ea1.pxml" and 5 < zone_entry.time < 20
    assert r.sim.inbox[0]["sender"] == "Kidode"


def test_touch_walks_up_to_the_robot_and_posts_touched() -> None:
    r = runner("museum", CENTER, Pose(12, 4, 180), TimedAction(1, UserActionKind.TOUCH))
    r.run(30)
    touched = r.events("touched")
    assert len(touched) == 1
    # walks 2.5 - 0.95 m at 0.3 m/s before touching
    assert 5 < touched[0].time < 8


def test_a_touch_replaced_before_it_lands_is_reported_missed() -> None:
    """The user is still walking up to the robot when the script's next motion (a follow)
    replaces the touch: no ``touched`` event, and a ``touch`` line says it missed, at
    once and before the follow, so the trace never loses a scripted action."""
    r = runner("museum", CENTER, Pose(14, 4, 180), TimedAction(1, UserActionKind.TOUCH),
               TimedAction(3, UserActionKind.FOLLOW, distance=1.2))
    r.run(30)
    assert not r.events("touched")
    users = [(e.time, e.name, e.data.get("target")) for e in r.trace
             if e.kind is EntryKind.USER]
    assert users[:2] == [(3.0, "touch", "missed"), (3.0, "follow", "robot")]


def test_a_touch_that_lands_is_reported_once() -> None:
    r = runner("museum", CENTER, Pose(12, 4, 180), TimedAction(1, UserActionKind.TOUCH),
               TimedAction(20, UserActionKind.FOLLOW, distance=1.2))
    r.run(30)
    users = [(e.name, e.data.get("target")) for e in r.trace if e.kind is EntryKind.USER]
    assert users == [("touch", None), ("follow", "robot")]


def test_idle_stretches_are_jumped_over() -> None:
    sim = Simulator(world_map("museum"), robot=CENTER,
                    events=(ScheduledEvent(3000, "sound-heard", {"sound": "tune"}),))
    assert sim.next_time() == 3000.0
    sim.advance_to(3600)
    assert sim.steps == 0 and sim.now() == 3600.0


def test_localization_noise_is_seeded() -> None:
    def poses(seed: int) -> list[tuple[float, float]]:
        sim = Simulator(world_map("museum"), robot=CENTER, seed=seed, noise=0.05)
        return [(p.x, p.y) for p in (sim.localize() for _ in range(3))]
    assert poses(1) == poses(1) != poses(2)
    assert all(abs(x - 9.5) < 0.3 for x, _ in poses(1))


def test_a_cut_utterance_stops_at_the_end_of_the_word_under_way() -> None:
    """The interrupt policy's cut: five words in 2 s (0.4 s each); cut at 0.5 s, during
    the second word, it ends at 0.8 s with two words said. On its last word, or not
    running, nothing is cut."""
    ends: list[tuple[float, dict]] = []
    sim = Simulator(world_map("museum"), robot=CENTER,
                    finished=lambda ab, o: ends.append((sim.now(), dict(o.values))))
    sim.start(AtomicBehavior(1, "fa", 0, (call("Speak", text="one two three four five"),),
                             (1,), frozenset({"speaker"})))
    sim.advance_to(0.5)
    assert sim.cut(1) and sim.cut(1)  # asked twice: cut once
    sim.advance_to(10)
    assert ends == [(pytest.approx(0.8), {"interrupted": True, "spoken": "one two",
                                          "unspoken": "three four five"})]
    assert not sim.cut(1)
    sim.start(AtomicBehavior(2, "fa", 0, (call("Speak", text="one two"),), (2,),
                             frozenset({"speaker"})))
    sim.advance_to(10.5)
    assert not sim.cut(2)  # on its last word
    sim.advance_to(20)
    assert ends[-1][1] == {"duration": pytest.approx(0.8)}
    sim.start(AtomicBehavior(3, "fa", 0, (call("Gesture", name="nod"),), (3,),
                             frozenset({"arm", "neck"})))
    sim.advance_to(20.2)
    assert sim.cut(3)  # no words: at once
    sim.advance_to(30)
    assert ends[-1] == (pytest.approx(20.2), {"interrupted": True, "spoken": "",
                                              "unspoken": ""})


def test_the_world_reads_and_writes_the_bodies_as_pymunk_does() -> None:
    # The world steps and reads its bodies straight through Chipmunk (pymunk's own
    # binding): what it reads is what pymunk's properties say, drive after drive.
    r = runner("museum", Pose(1.5, 1.5, 0), Pose(3.0, 2.0, 180))
    world = r.sim.world
    r.queue(call("SetPosition", x=6.0, y=1.5), call("Turn", angle=90))
    seen = set()
    for t in range(1, 40):
        r.run(t * 0.5)
        assert world.robot_xy() == tuple(world.robot.position)
        assert world.user_xy() == tuple(world.human.position)
        assert world.robot_angle() == world.robot.angle
        pose = world.robot_pose()
        assert (pose.x, pose.y) == tuple(world.robot.position)
        assert pose.heading == math.degrees(world.robot.angle) % 360.0
        seen.add(world.robot_xy())
    assert len(seen) > 20  # (it drove all along)


@pytest.mark.parametrize("command", [call("TrackingHuman", distance=1.0), call("FaceHuman"),
                                     call("FaceHumanAndSpeak", text="Hello."),
                                     call("ActiveSensingHuman")], ids=lambda c: c.command)
def test_a_user_placed_on_the_robot_who_follows_it_runs(command: Call) -> None:
    """A user who stands exactly on the robot (placed there) and follows it: nothing
    divides by the distance between them, and the user steps out of the robot's way."""
    r = runner("museum", CENTER, Pose(CENTER.x, CENTER.y, 0),
               TimedAction(0, UserActionKind.FOLLOW, distance=1.0),
               TimedAction(8, UserActionKind.TOUCH))
    r.queue(command)
    r.run(20)
    assert r.sim.world.user_distance() > 0.1
    assert r.events("touched")
