"""The judge's stuck measure: an application behind an endless loop, a search that
never sees the user, a Command still waiting at the end. Each trace is written by hand
(:class:`tests.judge.helpers.Trace`).
"""

from __future__ import annotations

from prima.judge import Blame, Report
from tests.judge.helpers import TALK, Trace, counts

WHEELS = ("localization", "locomotion")


# ------------------------------------------------------------------ stuck

def search_loop(until: float, *, other_app: bool = False) -> Trace:
    """An ActiveSensingHuman iterating every 10 s from 0 s, with a Speak after it in the
    same request (or, with ``other_app``, the search is the FA's and the Speak the EA's,
    requested on its own)."""
    tr = Trace()
    devices = ("human-detection", "locomotion", "speaker")
    if other_app:
        tr.request(0.0, "fa", 1, 1, command="ActiveSensingHuman", devices=devices)
        tr.request(0.0, "ea", 100, 2, text="Found you.", tree=1)
    else:
        tr.request(0.0, "fa", 1, [1, 2], command="ActiveSensingHuman", text="Found you.",
                   devices=devices)
    t, ab = 0.0, 1
    while t < until:
        tr.start(t, "fa", ab, 1, command="ActiveSensingHuman", devices=devices,
                 iteration=ab - 1)
        tr.end(t + 10.0, "fa", ab, 1, command="ActiveSensingHuman", devices=devices,
               result="found=False", iteration=ab - 1)
        t, ab = t + 10.0, ab + 1
    return tr


def test_an_app_behind_its_own_endless_loop_is_stuck() -> None:
    report = search_loop(until=70.0).judge()
    assert counts(report) == {"stuck": 1}
    (s,) = report.of("stuck")
    assert (s.app, s.kind, s.t, s.since, s.command_id, s.seq) == ("fa", "loop", 60.0, 0.0, 2, 0)
    assert s.behind is not None and (s.behind.command, s.behind.rule) == (
        "ActiveSensingHuman", "its own loop")
    assert counts(search_loop(until=60.0).judge()) == {}  # 60 s, not more


def test_the_loop_must_run_back_to_back_for_the_whole_wait() -> None:
    """A pause in the search (its next iteration waited 5 s) starts the 60 s afresh."""
    tr = search_loop(until=110.0)
    for row in tr.rows:
        if row["t"] >= 30.0 and not (row["kind"] == "end" and row["t"] == 30.0):
            row["t"] += 5.0  # iterations from the 4th on start at 35, 45, ...
    report = tr.judge()
    assert [(s.kind, s.t) for s in report.of("stuck")] == [("loop", 95.0)]
    tr.rows = [r for r in tr.rows if r["t"] <= 95.0]
    assert [(s.kind, s.t) for s in tr.judge().of("stuck")] == [("end", 60.0)]


def lone_search(until: float, command: str = "ActiveSensingHuman",
                devices: tuple[str, ...] = ("human-detection", "locomotion", "speaker"),
                seen_at: float | None = None) -> Trace:
    """The FA's search (nothing behind it), iterating every 0.5 s from 0 s, while the
    user stands out of sight (seen once at ``seen_at``, if given)."""
    tr = Trace()
    tr.user["detectable"] = False
    tr.request(0.0, "fa", 1, 1, command=command, devices=devices)
    t, ab = 0.0, 1
    while t < until:
        if seen_at is not None and abs(t - seen_at) < 1e-9:
            tr.pose(t)
            tr.rows[-1]["user"] = dict(tr.user, detectable=True)
        tr.start(t, "fa", ab, 1, command=command, devices=devices, iteration=ab - 1)
        tr.end(t + 0.5, "fa", ab, 1, command=command, devices=devices, iteration=ab - 1)
        t, ab = t + 0.5, ab + 1
    return tr


def test_a_search_that_never_sees_the_user_is_stuck() -> None:
    """sample-07 before issue 10: EA1 searched for its visitor to the end of the run."""
    report = lone_search(until=100.0).judge()
    assert counts(report) == {"stuck": 1}
    (s,) = report.of("stuck")
    assert (s.app, s.kind, s.t, s.since, s.command_id) == ("fa", "search", 90.0, 0.0, 1)
    assert counts(lone_search(until=90.0).judge()) == {}  # 90 s, not more
    assert counts(lone_search(until=70.0).judge(search_after=60)) == {"stuck": 1}


def test_a_sight_of_the_user_starts_the_search_afresh() -> None:
    assert counts(lone_search(until=115.0, seen_at=30.0).judge()) == {}
    [s] = lone_search(until=125.0, seen_at=30.0).judge().of("stuck")
    assert (s.kind, s.t, s.since) == ("search", 120.0, 30.0)


def test_a_long_motion_out_of_the_users_sight_is_no_search() -> None:
    """A navigation leads a user who walks behind the robot, out of its camera's view."""
    tr = lone_search(until=200.0, command="TopologicalMove",
                     devices=("localization", "locomotion"))
    assert counts(tr.judge()) == {}


def test_waiting_for_another_apps_loop_is_not_stuck_while_the_run_goes_on() -> None:
    tr = search_loop(until=80.0, other_app=True)
    tr.speak(80.0, "ea", 100, 2, "Found you.", tree=1, request=False)
    assert counts(tr.judge()) == {}


def test_a_command_still_waiting_at_the_end_is_stuck() -> None:
    report = search_loop(until=80.0, other_app=True).judge()
    assert counts(report) == {"stuck": 1}
    (s,) = report.of("stuck")
    assert (s.app, s.kind, s.t, s.command_id) == ("ea", "end", 60.0, 2)
    assert counts(search_loop(until=50.0, other_app=True).judge()) == {}


def test_waiting_while_the_robot_follows_its_user_is_not_stuck() -> None:
    """The FA follows the user (Tracking Human, as they asked) from 0 s to the end; the
    EA's guide move waits for the wheels meanwhile: the user leads, nobody is stuck. The
    same wait behind a search is."""
    def waits_behind(command: str) -> dict[str, int]:
        tr = Trace()
        wheels = ("human-detection", "locomotion")
        tr.request(0.0, "fa", 1, 1, command=command, devices=wheels)
        tr.request(5.0, "ea", 100, 2, tree=1, command="TopologicalMove",
                   devices=("localization", "locomotion"))
        t, ab = 0.0, 1
        while t < 80.0:
            tr.start(t, "fa", ab, 1, command=command, devices=wheels, iteration=ab - 1)
            tr.end(t + 0.5, "fa", ab, 1, command=command, devices=wheels, iteration=ab - 1)
            t, ab = t + 0.5, ab + 1
        tr.sort()
        return counts(tr.judge())

    assert waits_behind("TrackingHuman") == {}
    assert waits_behind("ActiveSensingHuman") == {"stuck": 1}


def test_a_command_stuck_at_the_end_names_what_ran_then() -> None:
    tr = search_loop(until=80.0, other_app=True)
    del tr.rows[-1]  # the search's last look still runs when the trace ends
    (s,) = tr.judge().of("stuck")
    assert s.behind == Blame("fa", 8, "ActiveSensingHuman", "", "ran at the end")


def test_what_ran_at_the_end_is_named_only_on_the_devices_the_request_needs() -> None:
    """The EA's move never started: its request says it needs the wheels. The FA's Q&A,
    on the speaker, was not in its way; the FA's own move, on the wheels, was."""
    def behind(fa_moves: bool) -> Blame | None:
        tr = Trace()
        tr.request(0.0, "fa", 1, 1, command="QA", text="Shall we?", devices=TALK)
        tr.start(0.0, "fa", 1, 1, command="QA", text="Shall we?", devices=TALK)
        if fa_moves:
            tr.request(0.0, "fa", 2, 2, tree=2, command="TopologicalMove", devices=WHEELS)
            tr.start(0.0, "fa", 2, 2, tree=2, command="TopologicalMove", devices=WHEELS)
        tr.request(1.0, "ea", 100, 3, tree=1, command="TopologicalMove", devices=WHEELS)
        tr.pose(80.0)
        tr.sort()
        (s,) = [s for s in tr.judge().of("stuck") if s.app == "ea"]
        assert (s.kind, s.command_id) == ("end", 3)
        return s.behind

    assert behind(fa_moves=False) is None
    assert behind(fa_moves=True) == Blame("fa", 2, "TopologicalMove", "", "ran at the end")


def test_a_cancelled_command_is_not_waiting() -> None:
    tr = search_loop(until=80.0, other_app=True)
    tr.line(5.0, "cancel", app="ea", ab=100, command="Speak", reason="asap",
            detail={"command_id": 2})
    tr.sort()
    assert counts(tr.judge()) == {}


def test_an_unloaded_app_is_not_stuck() -> None:
    tr = search_loop(until=80.0, other_app=True)
    tr.line(80.0, "unload", app="ea", reason="unload")
    assert counts(tr.judge()) == {}


def test_an_ab_that_never_ends_is_stuck() -> None:
    def gesture_then_nothing(until: float) -> Report:
        tr = Trace()
        tr.request(0.0, "fa", 1, 1, command="Gesture", devices=("arm",), at="fa.pxml:9:5")
        tr.start(0.0, "fa", 1, 1, command="Gesture", devices=("arm",))
        tr.pose(until)
        return tr.judge()

    report = gesture_then_nothing(61.0)
    assert counts(report) == {"stuck": 1}
    (s,) = report.of("stuck")
    assert (s.app, s.kind, s.t, s.since, s.seq, s.at) == ("fa", "ab", 60.0, 0.0, 1,
                                                          "fa.pxml:9:5")
    assert s.behind == Blame("fa", 1, "Gesture", "fa.pxml:9:5", "never ended")
    assert counts(gesture_then_nothing(60.0)) == {}  # 60 s, not more


def test_a_cut_command_waiting_to_start_again_is_not_waiting_anew() -> None:
    """fa's reaction cuts ea's sentence at 1.1 s and follows the user to the end of the
    run (70 s): ea's sentence, started once, waits to start again all that while. A
    Command that waits to restart has started once: it is no request left waiting."""
    track = ("human-detection", "locomotion")
    tr = Trace()
    tr.request(0.0, "ea", 1, 1, text="Hello there, visitor.")
    tr.start(0.0, "ea", 1, 1, text="Hello there, visitor.", cuttable=True, words=(0.0, 2.0))
    tr.touch(1.0)
    tr.request(1.0, "fa", 2, 2, tree=1, command="TrackingHuman", reactive=True,
               devices=track)
    tr.interrupt(1.0, "ea", 1, 1, by="fa", by_ab=2)
    tr.end(1.1, "ea", 1, 1, reason="interrupt", words=(0.0, 2.0),
           text="Hello there, visitor.")
    tr.request(1.1, "ea", 3, 1, text="Hello there, visitor.", reason="restart", before=1)
    t, ab = 1.1, 2
    while t < 70.0:
        tr.start(t, "fa", ab, 2, tree=1, command="TrackingHuman", devices=track,
                 iteration=ab - 2)
        tr.end(t + 0.5, "fa", ab, 2, tree=1, command="TrackingHuman", devices=track,
               iteration=ab - 2)
        t, ab = round(t + 0.5, 3), ab + 1
    report = tr.judge()
    assert report.end > 1.1 + 60.0
    assert counts(report) == {}


