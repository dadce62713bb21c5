"""The judge's reading of docs/rules.md 7.6 and the amended section 8, one test per
point: talking unfaced over the words, a reaction to the user's own action not rationed
by the wait share, the user's cut ending an exchange's protection, a turn to the user
that may cut its own application's sweep, streams held while the user is answered, and
ignored speech that the user's own later words withdrew. Each trace is written by hand
(:class:`tests.judge.helpers.Trace`), and each test fails when the judge's reading of its
point is taken out (checked once by taking it out)."""

from __future__ import annotations

import pytest

from prima.judge import Report
from tests.judge.helpers import TALK, Trace, counts

WHEELS = ("human-detection", "localization", "locomotion")


# ---------------------------------------------------------------- talking unfaced

def _talking(offs: list[tuple[float, float]], turn: tuple[float, float] | None = None
             ) -> Report:
    """The EA speaks from 1 to 5 s, faced at its start; the user is at ``offs`` (time,
    degrees off the robot's heading) on pose lines meanwhile; with ``turn``, a turn to
    the user (connect-channel) runs beside the words then."""
    import math

    tr = Trace()
    tr.speak(1.0, "ea", 1, 1, "This panel shows research points of our laboratory.", lasts=4.0)
    end = tr.rows.pop()
    if turn is not None:
        tr.start(turn[0], "ea", 2, 2, command="FaceHuman", devices=WHEELS,
                 reason="connect-channel")
        tr.end(turn[1], "ea", 2, 2, command="FaceHuman", devices=WHEELS)
    for t, off in offs:
        rad = math.radians(off)
        tr.user = {"x": math.cos(rad), "y": math.sin(rad), "heading": 180.0,
                   "detectable": True}
        tr.pose(t)
    tr.rows.append(end)
    tr.sort()
    return tr.judge()


def test_the_user_off_to_the_side_for_over_a_second_while_the_words_run_is_unfaced() -> None:
    report = _talking([(2.0, 0.0), (2.5, 60.0), (3.0, 70.0), (3.5, 70.0), (4.0, 0.0)])
    assert counts(report) == {"unfaced": 1}
    (u,) = report.of("unfaced")
    assert (u.t, u.during, u.off) == (1.0, 1.5, 70.0)


def test_the_user_off_while_the_robot_turns_to_them_is_not() -> None:
    """The user walks round the robot; it turns to them beside its words (keeping
    facing them, 7.6 (3)) as fast as it can: the time the turn takes is no stretch
    unfaced (one starts anew if they are still off when it is over)."""
    offs = [(2.0, 0.0), (2.5, 60.0), (3.0, 70.0), (3.5, 70.0), (4.0, 0.0)]
    assert counts(_talking(offs, turn=(2.5, 3.6))) == {}
    assert counts(_talking(offs + [(4.2, 80.0), (4.9, 80.0)], turn=(2.5, 3.6))) == {}
    late = [(2.0, 0.0), (2.5, 60.0), (3.0, 70.0), (3.5, 70.0), (4.0, 70.0), (4.7, 70.0)]
    assert counts(_talking(late, turn=(2.5, 3.0))) == {"unfaced": 1}


def test_the_user_off_for_a_second_or_less_while_the_words_run_is_not() -> None:
    report = _talking([(2.0, 0.0), (2.5, 60.0), (3.0, 70.0), (3.5, 0.0)])
    assert counts(report) == {}


def test_the_user_off_only_after_the_words_is_not() -> None:
    report = _talking([(2.0, 0.0), (5.5, 90.0), (7.0, 90.0)])
    assert counts(report) == {}


# ---------------------------------------------------------------- the user's cut (7.6 (5))

def _reply_cut_by_the_user(taker_goes_first: bool = True) -> Report:
    """The EA asks; "No." at 3.0; its reply ("O.K. Take your time.", 2 s) starts at once.
    At 3.5 the user asks the FA something over it: it stops at 3.7, the FA answers
    (3.7-5.7), then the reply is said again (5.7-7.7)."""
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Shall we go on?", "No.", at=3.0)
    tr.request(3.0, "ea", 2, 2, text="O.K. Take your time.", reason="end-event", before=1)
    tr.start(3.0, "ea", 2, 2, text="O.K. Take your time.", cuttable=True, words=(3.0, 5.0))
    tr.say(3.5, "Where is the toilet?")
    tr.line(3.5, "event", text="speech", detail={"words": "Where is the toilet?"})
    tr.line(3.5, "hear", app="fa", text="'Where is the toilet?': fa takes it",
            reason="stream-runs")
    tr.line(3.5, "interrupt", app="ea", ab=2, tree=0, command="Speak",
            text="as the user spoke over it", reason="barge-in", devices=["speaker"],
            detail={"command_id": 2})
    tr.request(3.5, "fa", 4, 3, tree=1, text="Next to the door.", reactive=True)
    tr.end(3.7, "ea", 2, 2, text="O.K. Take your time.", reason="barge-in",
           words=(3.0, 3.7), result="interrupted=True, spoken=O.K., unspoken=Take your time.")
    tr.request(3.7, "ea", 3, 2, text="O.K. Take your time.", reason="restart", before=2)
    first, then = ((3.7, 5.7), (5.7, 7.7)) if taker_goes_first else ((5.7, 7.7), (3.7, 5.7))
    tr.start(first[0], "fa", 4, 3, tree=1, text="Next to the door.", words=first,
             reason="user-first")
    tr.end(first[1], "fa", 4, 3, tree=1, text="Next to the door.", words=first)
    tr.start(then[0], "ea", 3, 2, text="O.K. Take your time.", words=then, reason="restart")
    tr.end(then[1], "ea", 3, 2, text="O.K. Take your time.", words=then)
    tr.sort()
    return tr.judge()


def test_what_the_users_cut_starts_goes_first_the_reply_is_not_late_nor_split() -> None:
    """docs/rules.md 7.6 (5): the user's cut ends the exchange's protection: the FA's
    answer to the user's words goes first; the delay counts neither as the reply's
    lateness nor as a split."""
    report = _reply_cut_by_the_user()
    assert counts(report) == {}
    reply = next(r for r in report.reactions if r.app == "ea")
    assert reply.first_utterance == 5.7 and not reply.late


def test_the_users_words_still_answered_at_once_when_the_reply_goes_on_first() -> None:
    """The other way round, the FA's answer to the user's words waits for the reply said
    again: it is late (what the user's cut starts goes first)."""
    report = _reply_cut_by_the_user(taker_goes_first=False)
    assert counts(report).get("late") == 1
    (late,) = report.of("late")
    assert late.app == "fa"


# ---------------------------------------------------------------- the wait share (7.6 (4))

def _touched_while_demoted(words_before: bool) -> Report:
    """The FA lost its precedence at 1.0. The user touches the robot at 2.0; the EA's
    next words (not a reaction) take the speaker then, and the FA's "Hee-hee!" comes
    at 5.0, after them. With ``words_before``, the FA's reaction said its first words
    at once (2.0-2.5) and its second words are the ones that wait."""
    tr = Trace()
    tr.line(1.0, "budget", app="fa", reason="wait-share",
            text="kept other applications waiting 2 s within 60 s: it loses its precedence "
                 "until t=61 s")
    tr.touch(2.0)
    if words_before:
        tr.request(2.0, "fa", 2, 2, tree=1, text="Oh!", reactive=True)
        tr.start(2.0, "fa", 2, 2, tree=1, text="Oh!", words=(2.0, 2.5))
        tr.end(2.5, "fa", 2, 2, tree=1, text="Oh!", words=(2.0, 2.5))
        tr.request(2.0, "fa", 3, 3, tree=1, text="Hee-hee!", reason="after-latest", before=2)
    else:
        tr.request(2.0, "fa", 3, 3, tree=1, text="Hee-hee!", reactive=True)
    tr.speak(2.5, "ea", 1, 1, "This panel shows research points.", lasts=2.5)
    tr.start(5.0, "fa", 3, 3, tree=1, text="Hee-hee!", words=(5.0, 6.0))
    tr.end(6.0, "fa", 3, 3, tree=1, text="Hee-hee!", words=(5.0, 6.0))
    tr.sort()
    return tr.judge()


def test_a_reaction_to_the_user_is_not_excused_by_its_lost_precedence() -> None:
    """docs/rules.md 7.6 (4): before its first words, a reaction to the user's own action
    ranks before its application's lost precedence: waiting for another application's
    words that came after the touch is late."""
    report = _touched_while_demoted(words_before=False)
    assert counts(report) == {"late": 1}


def test_after_its_first_words_the_lost_precedence_excuses_it_again() -> None:
    report = _touched_while_demoted(words_before=True)
    assert counts(report) == {}


def test_the_reply_to_the_users_answer_is_not_rationed_by_the_lost_precedence() -> None:
    """docs/rules.md 7.6 (4) with 7.4: the FA's reaction to a message (0.2) waits while
    the EA talks and while the EA's later reaction (it found the user, 0.5) asks its
    question. The EA lost its precedence at 2.0. The user answers at 3.0; the EA's
    reply, its next question, goes on in its reaction's tree before the FA's words:
    the user's answer is not rationed until its first words, so that is the latest
    reaction going first, not a precedence the EA no longer had."""
    tr = Trace()
    tr.speak(0.0, "ea", 1, 1, "Welcome to the laboratory.", lasts=1.0)
    tr.event(0.2, "message")
    tr.request(0.2, "fa", 2, 2, tree=1, text="A message for you.", reactive=True)
    tr.event(0.5, "human-found")
    tr.ask(1.0, "ea", 3, 3, "May I repeat the explanation?", "No.", at=3.0, tree=2,
           reactive=True)
    tr.line(2.0, "budget", app="ea", reason="wait-share",
            text="kept other applications waiting 2 s within 60 s: it loses its precedence "
                 "until t=62 s")
    tr.request(3.0, "ea", 4, 4, tree=2, command="QA", text="May I go to the next panel?",
               reason="end-event", devices=TALK, before=3)
    tr.start(3.0, "ea", 4, 4, tree=2, command="QA", text="May I go to the next panel?",
             devices=TALK, words=(3.0, 5.0))
    tr.end(5.5, "ea", 4, 4, tree=2, command="QA", devices=TALK, words=(3.0, 5.0),
           result="status=timeout")
    tr.start(5.5, "fa", 2, 2, tree=1, text="A message for you.", words=(5.5, 7.0))
    tr.end(7.0, "fa", 2, 2, tree=1, text="A message for you.", words=(5.5, 7.0))
    tr.sort()
    # (the EA's reaction to the user found is requested at 0.5, with its Q&A)
    for row in tr.rows:
        if row["kind"] == "request" and row.get("ab") == 3:
            row["t"] = 0.5
    tr.sort()
    report = tr.judge()
    assert not [r for r in report.reactions if r.app == "fa" and r.late]


# ---------------------------------------------------------------- ignored speech (section 8)

def _withdrawn(stop_at: float) -> Report:
    """The FA plays a tune (the speaker, uncut) from 0.5 to 4.0. The user asks the EA
    "Where is the toilet?" at 1.0: its answer waits for the speaker. At ``stop_at`` the
    user says "Stop." to the EA, which drops the answer still to come (asap) and says
    "All right." once the speaker is free."""
    tr = Trace()
    tr.request(0.5, "fa", 1, 1, command="PlayTune")
    tr.start(0.5, "fa", 1, 1, command="PlayTune")
    tr.end(4.0, "fa", 1, 1, command="PlayTune")
    for t, words, ab, cid, text in ((1.0, "Where is the toilet?", 2, 2, "Next to the door."),
                                    (stop_at, "Stop.", 3, 3, "All right.")):
        tr.say(t, words)
        tr.line(t, "event", text="speech", detail={"words": words})
        tr.line(t, "hear", app="ea", text=f"{words!r}: ea takes it", reason="stream-runs")
        if cid == 3:
            tr.line(t, "cancel", app="ea", ab=2, tree=1, command="Speak", reason="asap",
                    detail={"command_id": 2})
        tr.request(t, "ea", ab, cid, tree=cid - 1, text=text, reactive=True,
                   reason="asap" if cid == 3 else "new-tree")
    tr.start(4.0, "ea", 3, 3, tree=2, text="All right.", words=(4.0, 4.5))
    tr.end(4.5, "ea", 3, 3, tree=2, text="All right.", words=(4.0, 4.5))
    tr.pose(12.0)
    tr.sort()
    return tr.judge()


def test_words_the_users_own_later_words_withdrew_are_not_ignored() -> None:
    """Section 8: "Stop." at 2.0 cancelled the answer to "Where is the toilet?" before it
    was due (the speaker was rightly held to 4.0): no speech was ignored."""
    assert counts(_withdrawn(2.0)) == {}


def test_words_withdrawn_only_after_their_answer_was_due_were_ignored() -> None:
    """The answer to "Where is the toilet?" was due at 5.0 (1 s after the speaker was
    free); "Stop." came at 6.0: it was ignored meanwhile."""
    report = _withdrawn(6.0)
    assert counts(report).get("ignored") == 1


# ---------------------------------------------------------------- face first (7.6 (3))

def _turn_over_own_sweep(cut: bool) -> Report:
    """The FA sweeps the room for its user (a search, cuttable, 0-3 s). The user touches
    the robot at 1.0, off to its side: the FA's answer waits for a turn to the user put
    before it. With ``cut``, the turn cuts the sweep at once (1.02); else it waits for
    the sweep's end."""
    tr = Trace()
    tr.request(0.0, "fa", 1, 1, command="ActiveSensingHuman", devices=WHEELS)
    tr.start(0.0, "fa", 1, 1, command="ActiveSensingHuman", devices=WHEELS, cuttable=True)
    tr.touch(1.0)
    tr.request(1.0, "fa", 2, 2, tree=1, text="Hee-hee!", reactive=True)
    tr.request(1.0, "fa", 3, 3, tree=1, command="FaceHuman", reason="connect-channel",
               devices=("human-detection", "locomotion"), precedes=2)
    swept = 1.02 if cut else 3.0
    if cut:
        tr.line(1.0, "interrupt", app="fa", ab=1, tree=0, command="ActiveSensingHuman",
                text="for fa's reaction (AB3)", reason="interrupt", devices=list(WHEELS),
                detail={"command_id": 1})
    tr.end(swept, "fa", 1, 1, command="ActiveSensingHuman", devices=WHEELS,
           reason="interrupt" if cut else "completed")
    tr.start(swept, "fa", 3, 3, tree=1, command="FaceHuman", reason="connect-channel",
             devices=("human-detection", "locomotion"))
    tr.end(swept + 1.0, "fa", 3, 3, tree=1, command="FaceHuman",
           devices=("human-detection", "locomotion"))
    said = (swept + 1.0, swept + 2.0)
    tr.start(said[0], "fa", 2, 2, tree=1, text="Hee-hee!", words=said)
    tr.end(said[1], "fa", 2, 2, tree=1, text="Hee-hee!", words=said)
    tr.sort()
    return tr.judge()


def test_a_turn_to_the_user_cuts_its_own_apps_sweep() -> None:
    """docs/rules.md 7.6 (1) and (3): the touch's turn to the user may cut the FA's own
    sweep: it is on time when it does, late when it waits for the sweep."""
    assert counts(_turn_over_own_sweep(cut=True)) == {}
    report = _turn_over_own_sweep(cut=False)
    assert counts(report) == {"late": 1}
    (late,) = report.of("late")
    assert late.took is not None and late.took.command == "ActiveSensingHuman"


# ---------------------------------------------------------------- held while answering

def _held_while_the_user_is_answered(until: float) -> Report:
    """The FA nods (0-1.2 s, uncut); a message for the EA at 0.5: its answer, a wave,
    waits for the arm. At 1.0 the user touches the robot and the FA answers (1.0-3.0):
    the EA's wave is held meanwhile (7.6 (1)) and starts at ``until``."""
    arm = ("arm", "neck")
    tr = Trace()
    tr.request(0.0, "fa", 1, 1, command="Gesture", devices=arm)
    tr.start(0.0, "fa", 1, 1, command="Gesture", devices=arm)
    tr.end(1.2, "fa", 1, 1, command="Gesture", devices=arm)
    tr.event(0.5, "message")
    tr.request(0.5, "ea", 2, 2, tree=1, command="Gesture", reactive=True, devices=arm)
    tr.touch(1.0)
    tr.request(1.0, "fa", 3, 3, tree=2, text="Hee-hee! That tickles.", reactive=True)
    tr.start(1.0, "fa", 3, 3, tree=2, text="Hee-hee! That tickles.", words=(1.0, 3.0))
    tr.end(3.0, "fa", 3, 3, tree=2, text="Hee-hee! That tickles.", words=(1.0, 3.0))
    tr.line(1.2, "hold", app="ea", ab=2, tree=1, command="Gesture",
            text="while fa answers the user", reason="answering", devices=list(arm))
    tr.start(until, "ea", 2, 2, tree=1, command="Gesture", devices=arm)
    tr.end(until + 1.0, "ea", 2, 2, tree=1, command="Gesture", devices=arm)
    tr.sort()
    return tr.judge()


def test_a_stream_held_while_the_user_is_answered_waits_rightly_until_the_words() -> None:
    """docs/rules.md 7.6 (1): the EA's reaction to the message, there before the touch,
    is held while the FA answers the user, until its words end (3.0): on time. Held
    past them (to 5.0), it is late."""
    assert counts(_held_while_the_user_is_answered(3.0)) == {}
    assert counts(_held_while_the_user_is_answered(5.0)) == {"late": 1}


def test_a_hold_lasts_for_the_latest_reaction_to_the_user_that_holds() -> None:
    """7.6 (1): the FA answers a touch (its words 1.0-3.0); at 2.5 the user says
    something the FA takes, and it answers that too (a nod, then words 3.5-5.0). The EA's
    reaction, held at 2.5 while the FA answers the user, waits rightly until the latest
    answer's words (5.0), not only until the first one's (3.0)."""
    arm = ("arm", "neck")
    tr = Trace()
    tr.speak(0.0, "fa", 1, 1, "Hello.", lasts=1.0)
    tr.event(0.5, "message")
    tr.request(0.5, "ea", 2, 2, tree=1, text="A message.", reactive=True)
    tr.touch(1.0)
    tr.request(1.0, "fa", 3, 3, tree=2, text="Hee-hee! That tickles.", reactive=True)
    tr.start(1.0, "fa", 3, 3, tree=2, text="Hee-hee! That tickles.", words=(1.0, 3.0))
    tr.end(3.0, "fa", 3, 3, tree=2, text="Hee-hee! That tickles.", words=(1.0, 3.0))
    tr.say(2.5, "Papero.")
    tr.line(2.5, "event", text="speech", detail={"words": "Papero."})
    tr.request(2.5, "fa", 4, [4, 5], tree=3, command="Gesture", text="Yes? I'm here.",
               reactive=True, devices=arm)
    tr.line(2.5, "hold", app="ea", ab=2, tree=1, command="Speak",
            text="while fa answers the user", reason="answering", devices=["speaker"])
    tr.start(2.5, "fa", 4, 4, tree=3, command="Gesture", devices=arm)
    tr.end(3.5, "fa", 4, 4, tree=3, command="Gesture", devices=arm)
    tr.start(3.5, "fa", 5, 5, tree=3, text="Yes? I'm here.", words=(3.5, 5.0))
    tr.end(5.0, "fa", 5, 5, tree=3, text="Yes? I'm here.", words=(3.5, 5.0))
    tr.speak(5.0, "ea", 2, 2, "A message.", tree=1, request=False)
    tr.sort()
    ea = next(r for r in tr.judge().reactions if r.app == "ea")
    assert not ea.late, ea.why


def test_what_started_while_an_app_had_lost_its_precedence_is_waited_for_as_running() -> None:
    """Section 8, with the wait share: fa lost its precedence (9-15 s); ea's uncut
    utterance started meanwhile (10-17 s), rightly. When fa regains its precedence, ea's
    words are as words running at the event: fa's message waits for them rightly."""
    tr = Trace()
    tr.line(9.0, "budget", app="fa", reason="wait-share",
            text="kept other applications waiting 5 s within 30 s: it loses its precedence "
                 "until t=15 s")
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
    tr.speak(10.0, "ea", 2, 2, "The exhibition closes at six, and the cafe at five.",
             tree=1, lasts=7.0)
    tr.line(15.0, "budget", app="fa", text="regains its precedence", reason="wait-share")
    tr.speak(17.0, "fa", 1, 1, "A message.", request=False)
    tr.sort()
    report = tr.judge()
    assert counts(report) == {}
    (r,) = report.reactions
    assert r.residual == 7.0


@pytest.mark.parametrize("asked", ["before the cut", "after the cut"])
def test_a_reaction_after_its_own_cut_ab_waits_for_its_restart(asked: str) -> None:
    """Rule 3, 7.3 (2): the EA's question, asked after its own search (its latest), waits
    for it. The user's touch had the search cut for the FA's answer; the search starts
    again after the FA's reaction, which goes on (the FA follows its user): the trace
    ends with the restart still waiting. The question waited rightly all along, whether
    it was asked before the cut (after the search) or after it (after the restart, which
    never started: a visit prima check made, EA1 beside FA2)."""
    wheels = ("human-detection", "locomotion")
    tr = Trace()
    tr.request(0.0, "ea", 1, 1, command="ActiveSensingHuman", devices=WHEELS)
    tr.start(0.0, "ea", 1, 1, command="ActiveSensingHuman", devices=WHEELS, cuttable=True)
    if asked == "before the cut":
        tr.event(1.0, "human-found")
        tr.request(1.0, "ea", 3, 3, command="QA", text="May I go on?", reactive=True,
                   reason="after-latest", before=1, devices=TALK)
    else:
        tr.event(1.8, "human-found")
        tr.request(1.8, "ea", 3, 3, command="QA", text="May I go on?", reactive=True,
                   reason="after-latest", before=2, devices=TALK)
    tr.touch(1.5)
    tr.request(1.5, "fa", 4, 4, tree=1, command="TrackingHuman", reactive=True, devices=wheels)
    tr.line(1.5, "interrupt", app="ea", ab=1, tree=0, command="ActiveSensingHuman",
            text="for fa's reaction (AB4)", reason="interrupt", devices=list(WHEELS),
            detail={"command_id": 1})
    tr.end(1.6, "ea", 1, 1, command="ActiveSensingHuman", devices=WHEELS, reason="interrupt")
    tr.request(1.6, "ea", 2, 1, command="ActiveSensingHuman", reason="restart", before=1,
               devices=WHEELS)
    tr.start(1.6, "fa", 4, 4, tree=1, command="TrackingHuman", devices=wheels)
    tr.pose(20.0)
    tr.sort()
    report = tr.judge()
    assert "late" not in counts(report)
    (r,) = [r for r in report.reactions if r.app == "ea"]
    assert [(w.app, w.ab, w.rule) for w in r.waits][:1] == [
        ("ea", 1 if asked == "before the cut" else 2,
         "after its own AB" if asked == "before the cut" else
         "after its own AB, never started")]


def test_words_said_again_are_about_what_they_were_about() -> None:
    """A Turn aims the robot (at what the FA will photograph), then its question is
    about that: not unfaced. The user cuts the question and it is asked again: still
    about that, still not unfaced."""
    tr = Trace()
    tr.request(0.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    tr.start(0.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    tr.end(1.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    tr.user = {"x": 0.0, "y": 1.0, "heading": 270.0, "detectable": True}  # (90 deg off)
    tr.request(0.0, "fa", 2, 2, command="QA", text="May I take a picture?",
               reason="after-latest", before=1, devices=TALK)
    tr.start(1.0, "fa", 2, 2, command="QA", text="May I take a picture?", devices=TALK,
             words=(1.0, 3.0))
    tr.line(1.5, "interrupt", app="fa", ab=2, tree=0, command="QA",
            text="as the user spoke over it", reason="barge-in", devices=list(TALK),
            detail={"command_id": 2})
    tr.end(1.6, "fa", 2, 2, command="QA", devices=TALK, reason="barge-in", words=(1.0, 1.6))
    tr.request(1.6, "fa", 3, 2, command="QA", text="May I take a picture?", reason="restart",
               before=2, devices=TALK)
    tr.start(1.6, "fa", 3, 2, command="QA", text="May I take a picture?", devices=TALK,
             words=(1.6, 3.6), reason="restart")
    tr.end(6.0, "fa", 3, 2, command="QA", devices=TALK, words=(1.6, 3.6),
           result="status=timeout")
    tr.sort()
    assert "unfaced" not in counts(tr.judge())


@pytest.mark.parametrize("stopped", [1.3, 1.1])
def test_words_wait_for_a_prompt_on_its_last_word_when_they_are_ready(stopped: float) -> None:
    """Section 8 with 7.5: the user touches the robot (0.9) while the EA asks a question
    (its prompt 0-1.6, four words); the FA's reaction stops its wheels first (to
    ``stopped``), then asks its own question. Its words may ask for a cut only once the
    stop is over: at 1.3 the EA's prompt is on its last word, which is then listened to
    for its answer (to 5.0), and the FA's words wait for it rightly. Stopped at 1.1, they
    could have cut the prompt at its third word: then the wait is theirs (prima check of
    EA1 beside FA2, 1 run in 200)."""
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "May I go on?", "No.", 5.0, prompt_lasts=1.6, cuttable=True)
    tr.touch(0.9)
    tr.request(0.9, "fa", 10, [10, 11], tree=1, command="StopMoving", reactive=True,
               reason="asap", devices=("locomotion",))
    tr.start(0.9, "fa", 10, 10, tree=1, command="StopMoving", devices=("locomotion",))
    tr.end(stopped, "fa", 10, 10, tree=1, command="StopMoving", devices=("locomotion",))
    tr.ask(5.0, "fa", 11, 11, "May I stop following you?", "Yes.", 8.0, tree=1,
           request=False, prompt_lasts=2.0)
    tr.sort()
    report = tr.judge()
    (r,) = [r for r in report.reactions if r.app == "fa"]
    assert r.late == (stopped < 1.2), r.why


def test_a_touch_answered_in_a_trees_later_words_goes_first_until_its_own_words() -> None:
    """7.1, 7.6 (1): the FA says "Connecting the video server." (0-0.6, uncut); its
    reaction to a message (0.4) is to say "The video setting succeeds.", then a gesture.
    The user's words at 0.5 go to the EA; the user's touch at 0.6 goes to the FA, whose
    reaction joins its message's tree (a stop, then its question, said 3.7-5.7 and
    answered at 9.0). The message's words start as the touch comes (0.6-2.2), but the
    touch ranks first until its own words are said, not the message's: the EA's answer,
    held meanwhile, waits for the question and its listening rightly (prima check of EA1
    beside FA5, 1 run in 200)."""
    tr = Trace()
    tr.speak(0.0, "fa", 0, 0, "Connecting the video server.", lasts=0.6)
    tr.event(0.4, "message")
    tr.request(0.4, "fa", 1, [1, 2], tree=1, text="The video setting succeeds.",
               reactive=True)
    tr.say(0.5, "Repeat that.")
    tr.line(0.5, "event", text="speech", detail={"words": "Repeat that."})
    tr.request(0.5, "ea", 10, 10, tree=5, text="We are on a tour.", reactive=True)
    tr.touch(0.6)
    tr.request(0.6, "fa", 3, [3, 4], tree=1, command="StopMoving", reactive=True,
               reason="after-latest", before=2, devices=("locomotion",))
    tr.start(0.6, "fa", 1, 1, tree=1, text="The video setting succeeds.", words=(0.6, 2.2))
    tr.line(0.6, "hold", app="ea", ab=10, tree=5, command="Speak",
            text="while fa answers the user", reason="answering", devices=["speaker"])
    tr.end(2.2, "fa", 1, 1, tree=1, text="The video setting succeeds.", words=(0.6, 2.2))
    tr.start(2.2, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
    tr.end(3.7, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
    tr.start(3.7, "fa", 3, 3, tree=1, command="StopMoving", devices=("locomotion",))
    tr.end(3.7, "fa", 3, 3, tree=1, command="StopMoving", devices=("locomotion",))
    tr.ask(3.7, "fa", 4, 4, "What's the matter with you?", "Video timer.", 9.0, tree=1,
           request=False, prompt_lasts=2.0)
    tr.speak(9.0, "ea", 10, 10, "We are on a tour.", tree=5, request=False)
    tr.sort()
    ea = next(r for r in tr.judge().reactions if r.app == "ea")
    assert not ea.late, ea.why


def test_a_cut_is_due_at_the_end_of_the_word_under_way_as_the_words_were_planned() -> None:
    """Section 8: the EA's prompt "May I go to the next panel?" (seven words, 0-2.8 s as
    planned) is under way when the user touches the robot (0.44, in its second word): the
    cut is due at that word's end (0.8), where the FA's words start, on time. The end
    line of the cut Q&A says only the words said (0-0.8): spread over those, the word
    under way ended at 0.46, and the FA was read as late (prima check of EA1 beside FA1,
    1 run in 8,000)."""
    tr = Trace()
    tr.request(0.0, "ea", 1, 1, command="QA", text="May I go to the next panel?", devices=TALK)
    tr.start(0.0, "ea", 1, 1, command="QA", text="May I go to the next panel?", devices=TALK,
             cuttable=True, words=(0.0, 2.8))
    tr.touch(0.44)
    tr.request(0.44, "fa", 2, 2, tree=1, text="Hee-hee! That tickles.", reactive=True,
               reason="asap")
    tr.interrupt(0.44, "ea", 1, 1, by="fa", by_ab=2)
    tr.end(0.8, "ea", 1, 1, command="QA", devices=TALK, reason="interrupt",
           words=(0.0, 0.8), text="May I go to the next panel?")
    tr.speak(0.8, "fa", 2, 2, "Hee-hee! That tickles.", tree=1, request=False)
    tr.sort()
    fa = next(r for r in tr.judge().reactions if r.app == "fa")
    assert not fa.late, fa.why
