"""The judge's measures beyond a reaction's lateness: a clean trace has no fault,
reactions never heard, talking unfaced, leaving while talking, resumed elsewhere, split
exchanges, silences and talking over the user. Each test writes a small trace by hand
(:class:`tests.judge.helpers.Trace`) that contains one fault once, and checks that its
count is one and every other count is zero (docs/judging.md).
"""

from __future__ import annotations

from typing import Any

import pytest

from prima.judge import Blame, Report, format_table, judge
from tests.judge.helpers import FACING, ROOT, TALK, Trace, USER, clean, counts


# ------------------------------------------------------------------ a clean trace

def test_a_clean_trace_has_no_fault() -> None:
    report = clean().judge()
    assert counts(report) == {}
    assert report.ok and report.breaches() == []
    assert [(r.event, r.app, r.user, r.latency, r.utterance_latency)
            for r in report.reactions] == [("touched", "fa", True, 0.0, 0.0),
                                           ("speech", "fa", True, 0.0, 0.0)]
    assert report.reactions[1].text == "Nothing."


# ------------------------------------------------------------------ reactions never heard

def _message_cut_by_a_touch(*, said_again: bool, dropped: bool = False,
                            ends: float = 12.0) -> Report:
    """fa says a message (a reaction, 10 s to 12.5 s); at 10.5 s the user touches the
    robot and ea's reaction cuts it (at 10.6 s) and speaks for 1 s. With
    ``said_again``, fa's message restarts at 11.6 s; otherwise it waits to be said
    again until the trace ends at ``ends`` (12 s: before fa's words were free for
    1.2 s), or, ``dropped``, its request said to drop it."""
    message = "A message from your host."
    tr = Trace()
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text=message, reactive=True)
    tr.start(10.0, "fa", 1, 1, text=message, cuttable=True, words=(10.0, 12.5))
    tr.touch(10.5)
    tr.request(10.5, "ea", 2, 2, tree=1, text="Yes?", reactive=True)
    tr.interrupt(10.5, "fa", 1, 1, by="ea", by_ab=2)
    tr.end(10.6, "fa", 1, 1, reason="interrupt", words=(10.0, 12.5), text=message)
    if dropped:
        tr.rows[-1]["detail"]["interrupt"] = "dropped"
    else:
        tr.request(10.6, "fa", 3, 1, text=message, reactive=True, reason="restart", before=1)
    tr.speak(10.6, "ea", 2, 2, "Yes?", tree=1, request=False)
    if said_again:
        tr.start(11.6, "fa", 3, 1, text=message, reason="restart", words=(11.6, 14.1))
        tr.end(14.1, "fa", 3, 1, words=(11.6, 14.1), text=message)
    else:
        tr.pose(ends)
    return tr.judge()


@pytest.mark.parametrize("dropped, ends, unheard", [
    (False, 12.0, False),   # (still to be said again when the trace ends: not yet)
    (False, 80.0, True),    # (still waiting 69 s after the cut: more than anything may)
    (True, 12.0, False),    # (its request said to drop it: its application's choice)
])
def test_a_reaction_cut_and_never_said_again_is_unheard_once_overdue(
        dropped: bool, ends: float, unheard: bool) -> None:
    report = _message_cut_by_a_touch(said_again=False, dropped=dropped, ends=ends)
    fa, ea = report.reactions
    assert (fa.unheard, fa.first_utterance) == (unheard, None)
    assert not ea.unheard
    if unheard:
        assert counts(report) == {"unheard": 1, "late": 1}
        assert report.seqs("unheard") == [fa.seq]
        assert "its words were never heard whole" in format_table([report])
    else:
        assert counts(report) == {}


def test_a_reaction_cut_counts_its_words_once_said_again_whole() -> None:
    report = _message_cut_by_a_touch(said_again=True)
    fa, _ea = report.reactions
    assert (fa.unheard, fa.first_utterance, fa.utterance_latency, fa.words_free) == (
        False, 11.6, 1.6, 0.0)
    assert counts(report) == {}


def test_words_being_said_again_when_the_trace_ends_are_not_unheard_yet() -> None:
    """fa's message, cut for ea's reaction, is being said again when the trace ends
    (11.6 s to 14.1 s, the trace over at 13.0 s): not unheard (they may yet be heard
    whole); said again and cut again, they are."""
    message = "A message from your host."

    def unheard(again_cut: bool) -> bool:
        tr = Trace()
        tr.event(10.0, "message")
        tr.request(10.0, "fa", 1, 1, text=message, reactive=True)
        tr.start(10.0, "fa", 1, 1, text=message, cuttable=True, words=(10.0, 12.5))
        tr.touch(10.5)
        tr.request(10.5, "ea", 2, 2, tree=1, text="Yes?", reactive=True)
        tr.interrupt(10.5, "fa", 1, 1, by="ea", by_ab=2)
        tr.end(10.6, "fa", 1, 1, reason="interrupt", words=(10.0, 12.5), text=message)
        tr.request(10.6, "fa", 3, 1, text=message, reactive=True, reason="restart", before=1)
        tr.speak(10.6, "ea", 2, 2, "Yes?", tree=1, request=False)
        tr.start(11.6, "fa", 3, 1, text=message, reason="restart", words=(11.6, 14.1))
        if again_cut:
            tr.end(12.5, "fa", 3, 1, reason="barge-in", words=(11.6, 12.5), text=message)
        tr.pose(13.0)
        fa = next(r for r in tr.judge().reactions if r.app == "fa")
        return fa.unheard

    assert (unheard(False), unheard(True)) == (False, True)


def _never_started(ends: float, *, cancelled: bool = False) -> Report:
    """A touch at 1 s; fa's reaction waits behind ea's sentence (uncut, to 3 s) and
    never starts: the trace ends at ``ends``. With ``cancelled``, fa's own newer request
    replaced it at 2 s."""
    tr = Trace()
    tr.speak(0.0, "ea", 1, 1, "A sentence.", lasts=3.0)
    tr.touch(1.0)
    tr.request(1.0, "fa", 2, 2, tree=1, text="Yes?", reactive=True)
    if cancelled:
        tr.line(2.0, "cancel", app="fa", ab=2, command="Speak", reason="asap",
                detail={"command_id": 2})
    tr.sort()
    tr.pose(ends)
    return tr.judge()


def test_a_reaction_that_never_starts_is_late() -> None:
    report = _never_started(5.0)
    (r,) = report.reactions
    assert (r.latency, r.residual, r.free, r.late) == (None, 2.0, 2.0, True)
    assert r.why == ("never started: free to start for 2 s (the rules let it wait 2 s, and "
                     "0.2 s more)")
    assert not r.unheard  # (its words may still come)
    assert counts(report) == {"late": 1}
    assert report.worst_lateness() == float("inf")


def test_a_reaction_never_said_long_after_its_event_is_unheard_too() -> None:
    """One fault, three measures: late (never started), unheard (its words not said
    60 s after the event) and stuck (its request still waiting at the end)."""
    report = _never_started(62.0)
    (r,) = report.reactions
    assert r.unheard and r.late
    assert counts(report) == {"late": 1, "unheard": 1, "stuck": 1}


def test_a_reaction_its_own_app_cancelled_is_neither_late_nor_unheard() -> None:
    report = _never_started(62.0, cancelled=True)
    (r,) = report.reactions
    assert (r.residual, r.free, r.late, r.unheard) == (1.0, 0.0, False, False)
    assert counts(report) == {}


def test_words_a_later_request_of_its_own_app_cancelled_after_its_first_ab_are_not_unheard(
        ) -> None:
    """The EA's reaction to a message stops the robot (its StopMoving runs), then would
    say the message; a place reached in the meantime makes the EA ask for other words as
    soon as possible, which cancels the message's words: its own choice, not unheard
    (it would be, were they left waiting)."""
    def unheard(cancelled: bool) -> bool:
        tr = Trace()
        tr.event(1.0, "message")
        tr.request(1.0, "ea", 1, [1, 2], command="StopMoving", reactive=True,
                   text="I've just got a message.", devices=("locomotion",))
        tr.start(1.0, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
        tr.end(1.1, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
        if cancelled:
            tr.line(1.2, "cancel", app="ea", ab=2, tree=0, command="Speak",
                    reason="asap", devices=["speaker"], detail={"command_id": 2})
        tr.line(70.0, "pose")
        (r,) = tr.judge().reactions
        return r.unheard

    assert (unheard(True), unheard(False)) == (False, True)


# ------------------------------------------------------------------ talking unfaced

def test_a_user_off_by_the_tolerance_within_the_traces_rounding_is_not_unfaced() -> None:
    """The trace rounds poses (millimetres, tenths of a degree): a user 30.1 degrees off
    on its lines may be 30 or less in the run, which turned the robot for more only;
    30.5 degrees is off."""
    import math

    def unfaced(off: float) -> int:
        tr = Trace()
        rad = math.radians(off)
        tr.user = {"x": round(math.cos(rad), 3), "y": round(math.sin(rad), 3),
                   "heading": 180.0, "detectable": True}
        tr.speak(1.0, "ea", 1, 1, "May I go to the next panel?")
        return len(tr.judge().of("unfaced"))

    assert (unfaced(30.1), unfaced(30.5)) == (0, 1)


def test_words_after_an_aiming_command_are_about_what_it_aims_at() -> None:
    """FA4 turns the way its user said, then asks "May I take a picture?": the words
    are about what the robot aims at, not unfaced; after a Gesture they are."""
    def after(command: str) -> int:
        tr = Trace()
        tr.user = {"x": 0.0, "y": 1.0, "heading": 0.0, "detectable": True}
        tr.start(0.0, "fa", 1, 1, command=command, devices=("locomotion",))
        tr.end(1.0, "fa", 1, 1, command=command, devices=("locomotion",))
        tr.start(1.0, "fa", 2, 2, text="May I take a picture?", words=(1.0, 2.0))
        tr.end(2.0, "fa", 2, 2)
        return len(tr.judge().of("unfaced"))

    assert (after("Turn"), after("Gesture")) == (0, 1)


def test_the_ab_words_follow_is_the_one_their_request_follows() -> None:
    """A panel's words ask "Do you like it?" after the group that aimed the robot at the
    panel (their request follows it), while a message's ``asap`` StopMoving joins the
    stream beside them and starts first: the words are still about the panel, as the
    mediator has it (it does not turn the robot to the user for them). Words whose
    request follows the StopMoving are not."""
    def asked(follows: int) -> int:
        tr = Trace()
        tr.user = {"x": -1.0, "y": 0.0, "heading": 0.0, "detectable": True}
        aim = ("localization", "locomotion", "speaker")
        tr.request(0.0, "ea", 1, 1, command="SetDirection+Speak", text="Look.", devices=aim)
        tr.start(0.0, "ea", 1, 1, command="SetDirection+Speak", text="Look.", devices=aim,
                 words=(0.0, 1.0))
        tr.request(0.5, "ea", 2, 2, command="StopMoving", devices=("locomotion",), before=1)
        tr.request(0.5, "ea", 3, 3, command="QA", text="Do you like it?", devices=TALK,
                   before=follows, reason="end-event")
        tr.end(1.0, "ea", 1, 1, command="SetDirection+Speak", devices=aim, words=(0.0, 1.0))
        tr.start(1.0, "ea", 2, 2, command="StopMoving", devices=("locomotion",))
        tr.ask(1.0, "ea", 3, 3, "Do you like it?", "Yes.", at=3.0, request=False)
        tr.end(1.0, "ea", 2, 2, command="StopMoving", devices=("locomotion",))
        return len(tr.judge().of("unfaced"))

    assert (asked(follows=1), asked(follows=2)) == (0, 1)


def test_words_whose_request_says_they_are_about_something_else_are_not_unfaced() -> None:
    """FA7's "Look where the red dot is." (face-user="false": about the spot its laser
    shows): its request line says so, and it is not counted; the same words asked for
    without it are."""
    def said(face_user: bool) -> int:
        tr = Trace()
        tr.user = {"x": 0.0, "y": 1.0, "heading": 0.0, "detectable": True}
        tr.request(0.0, "fa", 1, 1, text="Look where the red dot is.")
        if not face_user:
            tr.rows[-1]["detail"]["face_user"] = False
        tr.start(0.0, "fa", 1, 1, text="Look where the red dot is.", words=(0.0, 2.0))
        tr.end(2.0, "fa", 1, 1)
        return len(tr.judge().of("unfaced"))

    assert (said(face_user=False), said(face_user=True)) == (0, 1)


def test_a_request_line_says_when_its_words_are_about_something_else() -> None:
    from prima.run import Run

    lines = Run(ROOT / "scenarios" / "examples" / "museum-laser.xml").run()
    requests = {ln.text: ln for ln in lines if ln.kind.value == "request" and ln.text}
    assert requests["Look where the red dot is."].detail.get("face_user") is False
    assert "face_user" not in requests["Touch my head, and I will show you more."].detail


@pytest.mark.parametrize("user, command, found", [
    ({"x": 0.0, "y": 1.0, "detectable": True}, "Speak", 1),          # 90 degrees off
    ({"x": 0.0, "y": 1.0, "detectable": False}, "Speak", 0),         # cannot be seen
    ({"x": 0.0, "y": 1.0, "detectable": True}, "FaceHumanAndSpeak", 0),  # turns first
    ({"x": 1.0, "y": 0.5, "detectable": True}, "Speak", 0),          # 26.6 degrees off
    ({"x": -1.0, "y": -0.1, "detectable": True}, "Speak+Gesture", 1),  # behind it
    ({"x": -1.0, "y": -0.1, "detectable": True}, "PointByHand+Speak", 0),  # about a place
])
def test_talking_unfaced(user: dict[str, Any], command: str, found: int) -> None:
    devices = {"Speak": ("speaker",), "Speak+Gesture": ("arm", "neck", "speaker"),
               "FaceHumanAndSpeak": ("human-detection", "locomotion", "speaker"),
               "PointByHand+Speak": ("arm", "speaker")}[command]
    tr = Trace()
    tr.user = {"heading": 0.0, **user}
    tr.request(1.0, "fa", 1, 1, command=command, text="Hello.", devices=devices,
               at="fa.pxml:7:5")
    tr.start(1.0, "fa", 1, 1, command=command, text="Hello.", devices=devices)
    tr.end(2.0, "fa", 1, 1, command=command, devices=devices)
    report = tr.judge()
    assert counts(report) == ({"unfaced": 1} if found else {})
    if found:
        (u,) = report.of("unfaced")
        assert (u.seq, u.app, u.command, u.text, u.at) == (1, "fa", command, "Hello.",
                                                           "fa.pxml:7:5")
        assert u.off > 30


def test_a_motion_with_no_words_is_not_talking() -> None:
    tr = Trace()
    tr.user = {"x": 0.0, "y": 1.0, "heading": 0.0, "detectable": True}
    tr.request(1.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    tr.start(1.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    tr.end(2.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    assert counts(tr.judge()) == {}


# ------------------------------------------------------------------ leaving while talking

def _talking_while(poses: list[tuple[float, dict[str, float], dict[str, Any]]], *,
                   mover: str | None = None) -> Report:
    """ea says something from 1 s to 3 s, the robot and the user at each of ``poses``
    (time, robot, user) in between; ``mover``: fa's Command that runs on the wheels
    meanwhile (from 0.5 s)."""
    tr = Trace()
    if mover is not None:
        devices = ("human-detection", "locomotion") if mover == "TrackingHuman" \
            else ("localization", "locomotion")
        tr.request(0.5, "fa", 9, 9, tree=5, command=mover, devices=devices)
        tr.start(0.5, "fa", 9, 9, tree=5, command=mover, devices=devices)
    tr.request(1.0, "ea", 1, 1, text="Come on.")
    tr.start(1.0, "ea", 1, 1, text="Come on.", words=(1.0, 3.0))
    for t, robot, user in poses:
        tr.robot, tr.user = robot, user
        tr.pose(t)
    tr.end(3.0, "ea", 1, 1, words=(1.0, 3.0), text="Come on.")
    return tr.judge()


def test_leaving_while_talking_counts_once_per_utterance() -> None:
    report = _talking_while([(t, {"x": x, "y": 0.0, "heading": 0.0}, USER)
                             for t, x in ((1.5, -0.2), (2.0, -0.4), (2.5, -0.6))],
                            mover="TopologicalMove")
    assert counts(report) == {"leaving": 1}
    (x,) = report.of("leaving")
    assert (x.seq, x.at_seq, x.away) == (3, 5, 0.4)
    assert x.moved_by == Blame("fa", 9, "TopologicalMove", "", "drove the wheels")


def test_the_robot_pushed_while_nothing_drives_it_is_not_leaving() -> None:
    """The robot ends 0.4 m farther from its user while it turns in place to them (a
    FaceHuman on the wheels) or stands: a user who walked into it pushed it, it did not
    move on its own. The same displacement while a TopologicalMove drives it is."""
    poses = [(t, {"x": x, "y": 0.0, "heading": 0.0}, USER)
             for t, x in ((1.5, -0.2), (2.0, -0.4), (2.5, -0.6))]
    assert counts(_talking_while(poses, mover="FaceHuman")) == {}
    assert counts(_talking_while(poses)) == {}
    assert counts(_talking_while(poses, mover="TopologicalMove")) == {"leaving": 1}


def test_the_user_walking_away_is_not_the_robot_leaving() -> None:
    report = _talking_while([(2.0, FACING, {**USER, "x": 3.0})])
    assert counts(report) == {}


# The user walks round the robot to its back; the robot, behind, rolls on 0.5 m first.
_WALKS_ROUND = [(1.5, {"x": 0.3, "y": 0.0, "heading": 0.0}, {**USER, "x": 0.5, "y": 1.0}),
                (2.0, {"x": 0.5, "y": 0.0, "heading": 90.0}, {**USER, "x": -1.0, "y": 0.0})]


def test_following_the_user_is_not_leaving() -> None:
    """The robot gets 0.5 m farther from its user, by its own motion, while it follows
    them (a TrackingHuman runs): that is no leaving; the same motion driven by a
    TopologicalMove is. (The user walks round behind the robot while it talks: that is
    talking unfaced over the words, whoever drives.)"""
    assert counts(_talking_while(_WALKS_ROUND, mover="TrackingHuman")) == {"unfaced": 1}
    report = _talking_while(_WALKS_ROUND, mover="TopologicalMove")
    assert counts(report) == {"leaving": 1, "unfaced": 1}
    assert report.of("leaving")[0].away == 0.5


def test_moving_after_the_utterance_is_not_leaving_while_talking() -> None:
    tr = Trace()
    tr.speak(1.0, "ea", 1, 1, "Bye.")
    tr.robot = {"x": -2.0, "y": 0.0, "heading": 0.0}
    tr.pose(3.0)
    assert counts(tr.judge()) == {}


@pytest.mark.parametrize("moves_while_it_speaks, found", [(False, 0), (True, 1)])
def test_in_a_grouped_ab_only_moving_while_its_words_run_is_leaving(
        moves_while_it_speaks: bool, found: int) -> None:
    """A SetPosition+Speak drives 1 m away from the user, then speaks (its words from
    3 s to 4 s, known from its end line): the drive before the words is no leaving."""
    tr = Trace()
    devices = tr.drives_then_speaks(1.0, "Here is the panel.")
    for t, x in ((1.5, -0.4), (2.0, -0.8), (3.0, -1.0)):
        tr.robot = {"x": x, "y": 0.0, "heading": 0.0}
        tr.pose(t)
    if moves_while_it_speaks:
        tr.robot = {"x": -1.4, "y": 0.0, "heading": 0.0}
    tr.pose(3.5)
    tr.end(4.0, "ea", 1, 1, command="SetPosition+Speak", devices=devices, words=(3.0, 4.0),
           text="Here is the panel.")
    report = tr.judge()
    assert counts(report) == ({"leaving": 1} if found else {})
    if found:
        assert report.of("leaving")[0].away == 0.4


# ------------------------------------------------------------------ resumed elsewhere

@pytest.mark.parametrize("case, found", [
    ("here", 0),          # back where it was suspended before it speaks
    ("away", 1),          # resumes 2 m from there
    ("travels", 0),       # it resumed going somewhere of its own
    ("restored", 0),      # the restore-state policy's return took it back
    ("speaks-first", 1),  # the resume line follows the utterance's own start line
    ("reacted", 0),       # its app reacted in the stream: from where the robot is
    ("asap", 0),          # its app asked anew, as soon as possible: likewise
    ("suspended-again", 0),  # suspended again where it then resumes speaking
])
def test_resumed_elsewhere(case: str, found: int) -> None:
    """A suspended stream's first utterance after it resumes counts only when the
    robot is farther than 0.3 m from where it was when the stream was last suspended,
    and the stream did not itself go somewhere or ask anew."""
    tr = Trace()
    tr.user = {**tr.user, "detectable": False}  # (not a matter of facing)
    tr.pose(0.5)
    tr.line(1.0, "suspend", app="ea", ab=2, tree=0, command="Speak", reason="reactivity")
    tr.robot = {**tr.robot, "x": 2.0}  # the other app's reaction moved the robot
    tr.pose(5.0)
    if case in ("reacted", "asap"):
        tr.request(5.5, "ea", 4, 4, command="Gesture", devices=("arm",),
                   reactive=case == "reacted", reason="asap" if case == "asap" else "after-latest")
    if case == "suspended-again":
        tr.start(5.5, "ea", 3, 3, command="Gesture", devices=("arm",))
        tr.line(5.5, "resume", app="ea", ab=3, tree=0, command="Gesture")
        tr.line(5.6, "suspend", app="ea", ab=2, tree=0, command="Speak", reason="reactivity")
        tr.end(5.6, "ea", 3, 3, command="Gesture", devices=("arm",))
    if case in ("speaks-first", "reacted", "asap", "suspended-again"):
        tr.start(6.0, "ea", 2, 2, text="Look at this figure.", words=(6.0, 7.0))
        tr.line(6.0, "resume", app="ea", ab=2, tree=0, command="Speak")
        tr.end(7.0, "ea", 2, 2)
    else:
        command = {"travels": "TopologicalMove", "away": "Gesture"}.get(case, "SetPosition")
        tr.start(6.0, "ea", 3, 3, command=command, devices=("locomotion",))
        if case == "restored":
            tr.rows[-1]["reason"] = "restore-state"
        tr.line(6.0, "resume", app="ea", ab=3, tree=0, command=command)
        if case in ("here", "restored"):
            tr.robot = {**tr.robot, "x": 0.1}
        tr.end(9.0, "ea", 3, 3, command=command, devices=("locomotion",))
        tr.start(9.0, "ea", 2, 2, text="Look at this figure.", words=(9.0, 10.0))
        tr.end(10.0, "ea", 2, 2)
    report = tr.judge()
    assert counts(report) == ({"elsewhere": 1} if found else {})
    if found:
        (e,) = report.of("elsewhere")
        assert (e.app, e.text, e.suspend_seq, e.away) == ("ea", "Look at this figure.", 1, 2.0)
        assert "from where its stream was suspended (seq 1)" in format_table([report])


def test_a_return_suspended_on_its_way_back_still_returns_where_the_stream_was() -> None:
    """The restore-state policy's return is itself suspended halfway back (another
    application's reaction takes the wheels) and resumes later; the stream's words are
    said where the stream was first suspended: not elsewhere, though 1 m from where its
    return was suspended (prima check of EA3 beside FA3: 17 runs in 800)."""
    tr = Trace()
    tr.user = {**tr.user, "detectable": False}  # (not a matter of facing)
    tr.pose(0.5)
    tr.line(1.0, "suspend", app="ea", ab=2, tree=0, command="Speak", reason="reactivity")
    tr.robot = {**tr.robot, "x": 2.0}  # the other app's reaction moved the robot
    tr.pose(5.0)
    tr.request(6.0, "ea", 3, 3, command="SetPosition", reason="restore-state", before=2,
               devices=("locomotion",))
    tr.start(6.0, "ea", 3, 3, command="SetPosition", devices=("locomotion",),
             reason="restore-state")
    tr.line(6.0, "resume", app="ea", ab=3, tree=0, command="SetPosition")
    tr.robot = {**tr.robot, "x": 1.0}
    tr.end(7.0, "ea", 3, 3, command="SetPosition", devices=("locomotion",))
    tr.line(7.0, "suspend", app="ea", ab=4, tree=0, command="SetPosition",
            reason="priority", detail={"command_id": 3})
    tr.start(8.0, "ea", 4, 3, command="SetPosition", devices=("locomotion",),
             reason="restore-state")
    tr.line(8.0, "resume", app="ea", ab=4, tree=0, command="SetPosition")
    tr.robot = {**tr.robot, "x": 0.1}
    tr.end(9.0, "ea", 4, 3, command="SetPosition", devices=("locomotion",))
    tr.start(9.0, "ea", 2, 2, text="Look at this figure.", words=(9.0, 10.0))
    tr.end(10.0, "ea", 2, 2)
    assert counts(tr.judge()) == {}


# ------------------------------------------------------------------ split exchanges

def _answered(reply: str, *, reactive: bool = False) -> Report:
    """ea's Q&A is answered at 3 s and ea replies with ``reply`` (words, its next
    question, a Turn, or nothing); fa says something at 3 s, before ea's reply (in
    reaction to a message, if ``reactive``); ea's words or question follow at 4 s."""
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Which book?", "The C Primer.", at=3.0)
    if reply == "words":
        tr.request(3.0, "ea", 2, 2, text="Wait a minute.", reason="end-event", before=1)
    elif reply == "question":
        tr.request(3.0, "ea", 2, 2, command="QA", text="Which edition?", reason="end-event",
                   before=1, devices=TALK)
    elif reply == "turn":
        tr.request(3.0, "ea", 2, 2, command="Turn", reason="end-event", before=1,
                   devices=("locomotion",))
    if reactive:
        tr.event(3.0, "message")
    tr.speak(3.0, "fa", 3, 3, "The video is set.", tree=1, reactive=reactive,
             at="fa.pxml:40:7")
    if reply == "words":
        tr.speak(4.0, "ea", 2, 2, "Wait a minute.", request=False)
    elif reply == "question":
        tr.ask(4.0, "ea", 2, 2, "Which edition?", "The second.", 6.0, request=False)
    elif reply == "turn":
        tr.start(3.0, "ea", 2, 2, command="Turn", devices=("locomotion",))
        tr.end(4.0, "ea", 2, 2, command="Turn", devices=("locomotion",))
    tr.pose(6.0)
    return tr.judge()


def test_another_apps_utterance_between_an_answer_and_the_reply_splits_it() -> None:
    """7.4: the reply's words belong to the exchange. fa's words split it, and delay the
    reply 1 s: the reply is late too, and names fa's words as what took the speaker."""
    report = _answered("words")
    assert counts(report) == {"splits": 1, "late": 1}
    (s,) = report.of("splits")
    assert (s.kind, s.app, s.by, s.text, s.t, s.at) == (
        "reply", "ea", "fa", "The video is set.", 3.0, "fa.pxml:40:7")
    assert s.anchor_seq == 3  # the answered Q&A's end line
    (r,) = report.reactions
    assert (r.event, r.took.app, r.took.ab) == ("speech", "fa", 3)


def test_a_reaction_between_an_answer_and_the_reply_splits_it_too() -> None:
    report = _answered("words", reactive=True)
    assert [(s.kind, s.by) for s in report.of("splits")] == [("reply", "fa")]


def test_another_apps_utterance_before_the_next_question_splits_the_exchange() -> None:
    """fa's words come before ea's next question (and delay it 1 s: late)."""
    report = _answered("question")
    assert counts(report) == {"splits": 1, "late": 1}
    assert [(s.kind, s.by) for s in report.of("splits")] == [("question", "fa")]


def test_a_reaction_before_the_next_question_splits_nothing() -> None:
    assert counts(_answered("question", reactive=True)) == {}


def test_another_apps_utterance_before_a_reply_without_words_splits_the_exchange() -> None:
    """ea replies by turning (no words); fa's words come first: kind ``answer``."""
    report = _answered("turn")
    assert counts(report) == {"splits": 1}
    assert [(s.kind, s.by) for s in report.of("splits")] == [("answer", "fa")]
    assert counts(_answered("turn", reactive=True)) == {}


def _answered_aiming_first(first: str, *, reactive: bool) -> Report:
    """ea's Q&A is answered at 3 s and its answer handler asks for a chain whose first
    Command says nothing (``SetDirection`` to a shelf, or a robot's own ``Beep`` on the
    speaker), then says where the book is; fa says something at 3.5 s, between the two
    (in reaction to a touch, if ``reactive``)."""
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Which book?", "The C Primer.", at=3.0)
    aim = ("localization", "locomotion") if first == "SetDirection" else ("speaker",)
    tr.request(3.0, "ea", 2, [2, 3], command=first, text="It is on shelf A.",
               reason="end-event", before=1, devices=aim)
    tr.start(3.0, "ea", 2, 2, command=first, devices=aim)
    if reactive:
        tr.touch(3.5)
    tr.speak(3.5, "fa", 4, 4, "Hee-hee!", tree=1, reactive=reactive, at="fa.pxml:40:7")
    tr.end(4.0, "ea", 2, 2, command=first, devices=aim)
    tr.sort()
    tr.speak(4.5, "ea", 3, 3, "It is on shelf A.", request=False)
    tr.pose(6.0)
    return tr.judge()


@pytest.mark.parametrize("first", ["SetDirection", "Beep"])
def test_a_reply_that_aims_before_its_words_is_no_reply_of_words(first: str) -> None:
    """7.4 keeps a reply with its answer when the first AB the answer handler asks for
    is an utterance (the mediator protects that AB): a reply that aims first, then
    speaks, is one without words, as a turn is: the exchange ended as it began to aim,
    and another application's words before the reply's (a reaction's or not) split
    nothing."""
    assert counts(_answered_aiming_first(first, reactive=True)) == {}
    assert counts(_answered_aiming_first(first, reactive=False)) == {}


def test_no_reply_no_split() -> None:
    """An exchange that ends with the answer has no second half to split."""
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Shall I go on?", "No.", at=3.0)
    tr.speak(3.0, "fa", 3, 3, "The video is set.", tree=1)
    tr.speak(20.0, "fa", 4, 4, "It is sunny today.", tree=1)
    assert counts(tr.judge()) == {}


def test_a_reply_cut_splits_the_exchange() -> None:
    """7.4: the interrupt policy never cuts a reply's words; when it does, the cut
    splits the exchange (found at the reply's end line, by the app that cut it)."""
    words = "Wait a minute, please."
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Which book?", "The C Primer.", at=3.0)
    tr.request(3.0, "ea", 2, 2, text=words, reason="end-event", before=1)
    tr.start(3.0, "ea", 2, 2, text=words, cuttable=True, words=(3.0, 5.0))
    tr.touch(3.5)
    tr.request(3.5, "fa", 3, 3, tree=1, text="Hee-hee!", reactive=True)
    tr.interrupt(3.5, "ea", 2, 2, by="fa", by_ab=3)
    tr.end(3.5, "ea", 2, 2, reason="interrupt", words=(3.0, 5.0), text=words)
    tr.request(3.5, "ea", 4, 2, text=words, reason="restart", before=2)
    tr.speak(3.5, "fa", 3, 3, "Hee-hee!", tree=1, request=False)
    tr.start(4.5, "ea", 4, 2, text=words, reason="restart", words=(4.5, 6.5))
    tr.end(6.5, "ea", 4, 2, words=(4.5, 6.5), text=words)
    report = tr.judge()
    assert counts(report) == {"splits": 1}
    (s,) = report.of("splits")
    assert (s.kind, s.app, s.by, s.text, s.seq) == ("reply", "ea", "fa", words, 10)
    fa = next(r for r in report.reactions if r.app == "fa")
    assert [w.rule for w in fa.waits] == ["uncut: a reply to its answer (7.4)"]


def test_another_apps_utterance_inside_an_explicit_stream_splits_it() -> None:
    tr = Trace()
    tr.line(1.0, "stream", app="fa", text="open", detail={"id": "video"})
    tr.speak(1.0, "fa", 1, 1, "Connecting.")
    tr.speak(2.0, "ea", 2, 2, "Which book?", tree=1)
    tr.speak(3.0, "fa", 3, 3, "Done.")
    tr.line(4.0, "stream", app="fa", text="close", detail={"id": "video"})
    tr.speak(5.0, "ea", 4, 4, "Which book, then?", tree=1)
    report = tr.judge()
    assert counts(report) == {"splits": 1}
    (s,) = report.of("splits")
    assert (s.kind, s.app, s.by, s.anchor_seq) == ("stream", "fa", "ea", 0)


def test_a_reaction_may_speak_inside_another_apps_stream() -> None:
    tr = Trace()
    tr.line(1.0, "stream", app="fa", text="open", detail={"id": "video"})
    tr.touch(2.0)
    tr.speak(2.0, "ea", 2, 2, "Yes?", tree=1, reactive=True)
    assert counts(tr.judge()) == {}


# ------------------------------------------------------------------ silences

def answered_then(reply_at: float, ends: float) -> Trace:
    tr = Trace()
    tr.ask(0.0, "fa", 1, 1, "Shall I?", "Yes.", at=2.0)
    if reply_at < ends:
        tr.request(2.0, "fa", 2, 2, text="O.K.", reason="end-event", before=1)
        tr.speak(reply_at, "fa", 2, 2, "O.K.", request=False)
    tr.pose(ends)
    return tr


def test_a_pause_over_two_seconds_after_an_answer_is_a_silence() -> None:
    report = answered_then(reply_at=4.5, ends=8.0).judge(reaction_slack=5.0)
    assert counts(report) == {"silences": 1}
    (s,) = report.of("silences")
    assert (s.seq, s.gap) == (3, 2.5)
    assert counts(answered_then(reply_at=3.9, ends=8.0).judge(reaction_slack=5.0)) == {}


def test_no_output_until_the_end_is_a_silence_only_if_the_end_is_far() -> None:
    report = answered_then(reply_at=99.0, ends=4.5).judge()
    assert counts(report) == {"silences": 1} and report.of("silences")[0].gap is None
    assert counts(answered_then(reply_at=99.0, ends=3.5).judge()) == {}


def test_the_robot_dancing_after_an_answer_is_no_silence() -> None:
    """The FA's dance (a gesture from 1.0) runs on after the EA's question is answered
    at 2.0: the robot is not silent while it dances; once the dance ends, the pause
    before the reply (at 4.5) counts from then."""
    def pause(dance_ends: float) -> dict[str, int]:
        tr = answered_then(reply_at=4.5, ends=8.0)
        tr.start(1.0, "ea", 9, 9, tree=4, command="Gesture", devices=("arm", "neck"))
        tr.end(dance_ends, "ea", 9, 9, tree=4, command="Gesture", devices=("arm", "neck"))
        tr.sort()
        return counts(tr.judge(reaction_slack=5.0))

    assert pause(5.0) == {}
    assert pause(2.6) == {}  # (1.9 s from the dance's end to the reply)
    assert pause(2.1) == {"silences": 1}  # (2.4 s)


# ------------------------------------------------------------------ talking over the user

def test_a_prompt_cut_by_its_answer_is_allowed_the_word_under_way() -> None:
    """The Q&A's prompt (ten words, 4.4 s as its start line plans them) is answered at
    0.5 s over its second word, and stops at 0.9 s, as said on its end line: within
    0.3 s plus one word (0.44 s) of the answer. Stopping 0.8 s later is not."""
    def over(stops: float) -> dict[str, int]:
        tr = Trace()
        prompt = "Please tell me a title or an author of a book."
        tr.request(0.0, "ea", 1, 1, command="QA", text=prompt, devices=TALK)
        tr.start(0.0, "ea", 1, 1, command="QA", text=prompt, devices=TALK,
                 words=(0.0, 4.4), cuttable=True)
        tr.say(0.5, "Uh-huh.")
        tr.end(stops, "ea", 1, 1, command="QA", devices=TALK, words=(0.0, stops),
               result="barge_in=True, spoken=Please tell, status=answered")
        return {k: v for k, v in counts(tr.judge()).items() if k == "barge_in"}

    assert over(0.9) == {}
    assert over(1.3) == {"barge_in": 1}


def test_end_lines_are_judged_for_barge_in_from_the_users_first_words_on() -> None:
    """The barge-in measure is fed end lines only once the user has said something (its
    feeder says so, ctx.reroute() when the first words come): an end line before them,
    a gesture's, does not leave the prompt's end unjudged after them."""
    tr = Trace()
    prompt = "Please tell me a title or an author of a book."
    tr.start(0.0, "fa", 2, 2, command="Gesture", devices=("arms",))
    tr.request(0.0, "ea", 1, 1, command="QA", text=prompt, devices=TALK)
    tr.start(0.0, "ea", 1, 1, command="QA", text=prompt, devices=TALK, words=(0.0, 4.4),
             cuttable=True)
    tr.end(0.2, "fa", 2, 2, command="Gesture", devices=("arms",))
    tr.say(0.5, "Uh-huh.")
    tr.end(1.3, "ea", 1, 1, command="QA", devices=TALK, words=(0.0, 1.3),
           result="barge_in=True, spoken=Please tell, status=answered")
    assert {k: v for k, v in counts(tr.judge()).items() if k == "barge_in"} == {"barge_in": 1}


def test_a_false_interruption_is_followed_from_its_interrupt_line_on() -> None:
    """The recovery measure is fed start, end and request lines only once a false
    interruption is known (its interrupt line: ctx.reroute()), after lines of those kinds
    came: a cut utterance that never goes on is found."""
    from prima.run import Run

    lines = [line.to_dict() for line in
             Run(ROOT / "scenarios" / "examples" / "barge-in-cough.xml").run()]
    again = {row["ab"] for row in lines if row["kind"] == "request"
             and row.get("reason") == "restart"}
    first = next(i for i, row in enumerate(lines) if row["kind"] == "interrupt")
    assert again and {"start", "end", "request"} <= {row["kind"] for row in lines[:first]}
    # (the user's lines left out: the barge-in measure, fed its first words, would have
    # every kind asked again for it too)
    kept = [row for row in lines if row["kind"] != "user"
            and not (row["kind"] == "start" and row.get("ab") in again)]
    assert counts(judge(lines)).get("recovery") is None
    assert counts(judge(kept))["recovery"] == len(again)


