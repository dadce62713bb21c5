"""The judge's reading of what goes first (a reply to an answer, the user's own action,
an AB that keeps the channel) and of holds (a reaction's next AB, blocks, streams, an
application that lost its precedence): what a reaction may wait for, and whom a late one
blames. Each trace is written by hand (:class:`tests.judge.helpers.Trace`).
"""

from __future__ import annotations

import pytest

from prima.judge import Report
from tests.judge.helpers import TALK, Trace, counts


# ------------------------------------------------------------------ reactions: what goes first

def _message_during_an_exchange(reply: str, first: str) -> Report:
    """ea's Q&A listens from 9 s; a message comes for fa at 10 s; the user answers at
    10.3 s and ea replies with ``reply`` (words, or its next question); ``first`` (ea's
    reply or fa's reaction) takes the speaker for 2 s, the other follows."""
    tr = Trace()
    tr.ask(8.0, "ea", 1, 1, "Which book?", "The C Primer.", 10.3, cuttable=True)
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 2, 2, tree=1, text="A message.", reactive=True)
    tr.sort()
    if reply == "words":
        tr.request(10.3, "ea", 3, 3, text="Wait a minute.", reason="end-event", before=1)
    else:
        tr.request(10.3, "ea", 3, 3, command="QA", text="Which edition?", reason="end-event",
                   before=1, devices=TALK)

    def ea(t: float) -> None:
        if reply == "words":
            tr.speak(t, "ea", 3, 3, "Wait a minute.", lasts=2.0, request=False)
        else:
            tr.ask(t, "ea", 3, 3, "Which edition?", "The second.", t + 2.0, request=False)

    def fa(t: float) -> None:
        tr.speak(t, "fa", 2, 2, "A message.", tree=1, lasts=2.0, request=False)

    if first == "ea":
        ea(10.3)
        fa(12.3)
    else:
        fa(10.3)
        ea(12.3)
    tr.pose(15.0)
    return tr.judge()


def test_a_reply_to_an_answer_goes_before_a_reaction() -> None:
    """7.4: the answer asks for the robot's words; a reaction that arrived while the
    user spoke takes over right after them."""
    report = _message_during_an_exchange("words", first="ea")
    fa = next(r for r in report.reactions if r.app == "fa")
    assert (fa.latency, fa.residual, fa.late) == (2.3, 2.3, False)
    assert {(w.ab, w.rule) for w in fa.waits} == {
        (3, "a reply to its answer (7.4)"), (1, "uncut: a Q&A listening")}
    assert counts(report) == {}


def test_a_reaction_before_a_reply_delays_the_reply() -> None:
    """7.4: no other app's AB on the talk devices starts between the answer and the end
    of the reply's words, a reaction included: the reply that waited 2 s for one is
    late, as well as split."""
    report = _message_during_an_exchange("words", first="fa")
    assert counts(report) == {"late": 1, "splits": 1}


def test_a_reaction_goes_before_the_next_question() -> None:
    """7.4: when the app replies with its next question, the exchange ended with the
    answer: the reaction goes first, and the question waits for it."""
    report = _message_during_an_exchange("question", first="fa")
    fa, ea = report.reactions
    assert (fa.latency, fa.late) == (0.3, False)
    assert (ea.event, ea.latency, ea.late) == ("speech", 2.0, False)
    assert [(w.app, w.rule) for w in ea.waits] == [("fa", "the latest reaction first (4.2)")]
    assert counts(report) == {}


def test_a_question_before_the_reaction_makes_it_late() -> None:
    report = _message_during_an_exchange("question", first="ea")
    fa = report.reactions[0]
    assert (fa.free, fa.late) == (2.0, True)
    assert (fa.took.app, fa.took.ab, fa.took.command) == ("ea", 3, "QA")
    assert counts(report) == {"late": 1}


def _touch_then_found(*, users: bool, first: str) -> Report:
    """ea's explanation runs (uncut) until 11 s. At 10 s the user touches the robot (or,
    without ``users``, a "touched" event comes with no user's line: not the user's own
    action): fa waves at once and waits with its words. At 10.5 s ea reacts to the
    user found. ``first`` speaks from 11 s to 13 s, the other from 13 s."""
    tr = Trace()
    tr.speak(8.0, "ea", 1, 1, "A long explanation.", lasts=3.0)
    if users:
        tr.touch(10.0)
    else:
        tr.event(10.0, "touched")
    tr.request(10.0, "fa", 2, [2, 3], tree=1, command="Gesture", reactive=True,
               devices=("arm",))
    tr.start(10.0, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
    tr.end(10.5, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
    tr.event(10.5, "human-found")
    tr.request(10.5, "ea", 4, 4, tree=2, text="There you are.", reactive=True)
    tr.sort()
    fa = ("fa", 3, 3, "Hee-hee!", 1)
    ea = ("ea", 4, 4, "There you are.", 2)
    one, other = (fa, ea) if first == "fa" else (ea, fa)
    tr.speak(11.0, *one[:4], tree=one[4], lasts=2.0, request=False)
    tr.speak(13.0, *other[:4], tree=other[4], request=False)
    return tr.judge()


def test_the_users_own_action_is_answered_before_a_later_perception() -> None:
    """7.1: the touch's reaction is not overtaken by the later reaction to the user
    found until its first words have been said."""
    report = _touch_then_found(users=True, first="fa")
    fa, ea = report.reactions
    assert (fa.user, ea.user) == (True, False)
    assert (ea.latency, ea.residual, ea.late) == (2.5, 2.5, False)
    assert ("fa", 3, "the user's own action first (7.1)") in [
        (w.app, w.ab, w.rule) for w in ea.waits]
    assert counts(report) == {}


def test_a_later_perception_before_the_users_own_action_makes_its_words_late() -> None:
    report = _touch_then_found(users=True, first="ea")
    fa, ea = report.reactions
    assert (fa.words_free, fa.late, ea.late) == (2.0, True, False)
    assert counts(report) == {"late": 1}


def test_the_users_own_action_goes_first_only_until_its_first_words() -> None:
    """7.1: once the touch's reaction has said its first words (10 s to 11 s), the later
    reaction to the user found (10.5 s) goes before its second sentence (rule 4.2): ea
    waiting 2 s for that sentence is late."""
    tr = Trace()
    tr.touch(10.0)
    tr.request(10.0, "fa", 1, [1, 2], text="Hee-hee!", reactive=True)
    tr.event(10.5, "human-found")
    tr.request(10.5, "ea", 3, 3, tree=1, text="There you are.", reactive=True)
    tr.sort()
    tr.speak(10.0, "fa", 1, 1, "Hee-hee!", request=False)
    tr.sort()
    tr.speak(11.0, "fa", 2, 2, "You tickle me.", lasts=2.0, request=False)
    tr.speak(13.0, "ea", 3, 3, "There you are.", tree=1, request=False)
    report = tr.judge()
    fa, ea = report.reactions
    assert (fa.late, fa.first_utterance) == (False, 10.0)
    assert (ea.free, ea.late) == (2.0, True)
    assert (ea.took.app, ea.took.ab) == ("fa", 2)
    assert counts(report) == {"late": 1}


def test_without_the_users_own_action_the_latest_reaction_goes_first() -> None:
    assert counts(_touch_then_found(users=False, first="ea")) == {}
    report = _touch_then_found(users=False, first="fa")
    _fa, ea = report.reactions
    assert (ea.free, ea.late) == (2.0, True)
    assert counts(report) == {"late": 1}


def _another_ab_after_the_event(case: str) -> Report:
    """A message comes for fa at 10 s; right after, an AB of ea starts on fa's devices
    and runs until 12 s, when fa starts: a Turn while fa's reaction is a TopologicalMove
    (``channel``), a Speak in ea's begin/end block (``block``), or a plain Speak."""
    loco = ("localization", "locomotion")
    tr = Trace()
    if case == "block":
        tr.line(9.0, "block", app="ea", text="open", detail={"id": "camera-work"})
    tr.event(10.0, "message")
    if case == "channel":
        tr.request(10.0, "fa", 1, 1, command="TopologicalMove", reactive=True, devices=loco)
        tr.request(10.0, "ea", 2, 2, tree=1, command="Turn", devices=("locomotion",))
        tr.start(10.0, "ea", 2, 2, tree=1, command="Turn", devices=("locomotion",))
        tr.end(12.0, "ea", 2, 2, tree=1, command="Turn", devices=("locomotion",))
        tr.start(12.0, "fa", 1, 1, command="TopologicalMove", devices=loco)
        tr.end(20.0, "fa", 1, 1, command="TopologicalMove", devices=loco)
    else:
        tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
        tr.speak(10.0, "ea", 2, 2, "Smile, please.", tree=1, lasts=2.0)
        tr.speak(12.0, "fa", 1, 1, "A message.", request=False)
    if case == "block":
        tr.line(13.0, "block", app="ea", text="close", detail={"id": "camera-work"})
    return tr.judge()


@pytest.mark.parametrize("case, rule", [
    ("channel", "keeps the channel (rule 4.1)"),
    ("block", "its begin/end block (rule 3)"),
])
def test_an_ab_that_keeps_the_channel_or_is_in_a_block_goes_first(case: str,
                                                                   rule: str) -> None:
    """Rule 4.1: an AB that keeps the channel goes before one that breaks it, a reaction
    included; a started begin/end block is concluded."""
    report = _another_ab_after_the_event(case)
    (r,) = report.reactions
    assert [(w.app, w.ab, w.rule) for w in r.waits] == [("ea", 2, rule)]
    assert (r.residual, r.late) == (2.0, False)
    assert counts(report) == {}


def test_another_apps_stream_does_not_go_before_a_reaction() -> None:
    report = _another_ab_after_the_event("plain")
    (r,) = report.reactions
    assert (r.free, r.late, r.took.ab) == (2.0, True, 2)


# ------------------------------------------------------------------ reactions: holds

def _reaction_kept_from_a_free_speaker(hold: str | None) -> Report:
    """A message comes for fa at 10 s, then ea reacts to the user found: it stops the
    robot (0.5 s), then speaks (2 s). fa's words, ready at once on the free speaker, wait
    until 12.5 s; ``hold``: the hold line the mediator wrote for them (None: none)."""
    tr = Trace()
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
    tr.event(10.0, "human-found")
    tr.request(10.0, "ea", 2, [2, 3], tree=1, command="StopMoving", text="There you are.",
               reactive=True, devices=("locomotion",))
    tr.start(10.0, "ea", 2, 2, tree=1, command="StopMoving", devices=("locomotion",))
    if hold == "reserved":
        tr.line(10.0, "hold", app="fa", ab=1, tree=0, command="Speak", reason="reserved",
                text="devices kept for ea's reaction (AB3 next)", devices=["speaker"],
                before=3, detail={"command_id": 1})
    tr.end(10.5, "ea", 2, 2, tree=1, command="StopMoving", devices=("locomotion",))
    tr.speak(10.5, "ea", 3, 3, "There you are.", tree=1, lasts=2.0, request=False)
    tr.speak(12.5, "fa", 1, 1, "A message.", request=False)
    return tr.judge()


def test_a_reaction_keeps_the_devices_its_next_ab_needs() -> None:
    """7.1: ea's reaction (the latest) keeps the speaker for its words while its
    StopMoving runs; the mediator says so (a ``reserved`` hold)."""
    report = _reaction_kept_from_a_free_speaker("reserved")
    fa, _ea = report.reactions
    assert (fa.latency, fa.residual, fa.late) == (2.5, 2.5, False)
    assert (("ea", 3, "kept for a reaction's next AB (7.1)", 10.5)
            in [(w.app, w.ab, w.rule, w.until) for w in fa.waits])
    assert counts(report) == {}


def test_without_the_mediators_hold_a_free_speaker_is_free() -> None:
    fa, _ea = _reaction_kept_from_a_free_speaker(None).reactions
    assert (fa.free, fa.late) == (0.5, True)


def test_devices_kept_for_a_next_ab_its_app_cancelled_are_kept_until_then() -> None:
    """7.1: ea's reaction keeps the speaker for its words (AB3, after its StopMoving);
    ea cancels those words at 11.0 (a newer request of its own): fa's words were
    rightly kept until then, not after (then they were free)."""
    tr = Trace()
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
    tr.event(10.0, "human-found")
    tr.request(10.0, "ea", 2, [2, 3], tree=1, command="StopMoving", text="There you are.",
               reactive=True, devices=("locomotion",))
    tr.start(10.0, "ea", 2, 2, tree=1, command="StopMoving", devices=("locomotion",))
    tr.line(10.0, "hold", app="fa", ab=1, tree=0, command="Speak", reason="reserved",
            text="devices kept for ea's reaction (AB3 next)", devices=["speaker"],
            before=3, detail={"command_id": 1})
    tr.line(11.0, "cancel", app="ea", ab=3, tree=1, command="Speak", reason="asap",
            devices=["speaker"], detail={"command_id": 3})
    tr.end(11.5, "ea", 2, 2, tree=1, command="StopMoving", devices=("locomotion",))
    tr.speak(12.0, "fa", 1, 1, "A message.", request=False)
    fa, _ea = tr.judge().reactions
    assert (fa.residual, fa.free, fa.late) == (1.0, 1.0, True)
    assert (("ea", 3, "kept for a reaction's next AB (7.1)", 11.0)
            in [(w.app, w.ab, w.rule, w.until) for w in fa.waits])


def test_a_reaction_that_goes_first_keeps_the_speaker_while_its_turn_runs() -> None:
    """7.1: ea's reaction (the latest) stops the robot (0.1 s), then the connect-channel
    policy turns the robot to the user (1 s) before ea's words: the speaker is theirs
    from the stop's end on, though nothing runs on it until 11.1 s."""
    turn = ("human-detection", "locomotion")
    tr = Trace()
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
    tr.event(10.0, "human-found")
    tr.request(10.0, "ea", 2, [2, 3], tree=1, command="StopMoving", text="There you are.",
               reactive=True, devices=("locomotion",))
    tr.start(10.0, "ea", 2, 2, tree=1, command="StopMoving", devices=("locomotion",))
    tr.end(10.1, "ea", 2, 2, tree=1, command="StopMoving", devices=("locomotion",))
    tr.request(10.1, "ea", 4, 4, tree=1, command="FaceHuman", reactive=True,
               reason="connect-channel", devices=turn, precedes=3)
    tr.start(10.1, "ea", 4, 4, tree=1, command="FaceHuman", devices=turn)
    tr.end(11.1, "ea", 4, 4, tree=1, command="FaceHuman", devices=turn)
    tr.speak(11.1, "ea", 3, 3, "There you are.", tree=1, lasts=2.0, request=False)
    tr.speak(13.1, "fa", 1, 1, "A message.", request=False)
    report = tr.judge()
    fa, _ea = report.reactions
    assert (fa.latency, fa.free, fa.late) == (3.1, 0.1, False)
    assert counts(report) == {}


def _words_behind_a_later_reaction_that_follows(until: float) -> Report:
    """ea reacts to the user found at 10 s: StopMoving (0.5 s), then FaceHumanAndSpeak
    "There you are." (the wheels, the camera and the speaker). fa reacts to the user found
    a moment later (its own search's end): "I found you." (2 s), then it follows the user
    (TrackingHuman, 0.5 s iterations) until ``until``. ea's words, kept for fa's next AB as
    the mediator says (a ``reserved`` hold, which names their devices), never start: fa's
    reaction is the latest, and its tree, following the user, goes first (4.2, 7.1)."""
    tr = Trace()
    follow = ("human-detection", "locomotion")
    words = ("human-detection", "locomotion", "speaker")
    tr.event(10.0, "human-found")
    tr.request(10.0, "ea", 1, [1, 2], command="StopMoving", text="There you are.",
               reactive=True, devices=("locomotion",))
    tr.start(10.0, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
    tr.event(10.2, "human-found")
    tr.request(10.2, "fa", 3, [3, 4], tree=1, text="I found you.", reactive=True)
    tr.start(10.2, "fa", 3, 3, tree=1, text="I found you.", words=(10.2, 12.2))
    tr.end(10.5, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
    tr.line(10.5, "hold", app="ea", ab=2, tree=0, command="FaceHumanAndSpeak",
            reason="reserved", text="devices kept for fa's reaction (AB4 next)",
            devices=list(words), before=4, detail={"command_id": 2})
    tr.end(12.2, "fa", 3, 3, tree=1, words=(10.2, 12.2), text="I found you.")
    t, ab = 12.2, 4
    while t < until - 1e-9:
        tr.start(t, "fa", ab, 4, tree=1, command="TrackingHuman", devices=follow,
                 iteration=ab - 4, reason="reactivity")
        tr.end(t + 0.5, "fa", ab, 4, tree=1, command="TrackingHuman", devices=follow,
               iteration=ab - 4, result="distance=1.0, lost=False")
        t, ab = round(t + 0.5, 3), ab + 1
    return tr.judge()


@pytest.mark.parametrize("until", [40.2, 100.2])
def test_words_that_wait_for_a_later_reaction_following_the_user_are_not_late(
        until: float) -> None:
    """7.1 and 4.2: the latest reaction's tree goes first for as long as it is in working
    memory, its following the user too (7.6 (1): following is not leaving). ea's words
    wait for fa's TrackingHuman on the wheels and the camera, which their
    FaceHumanAndSpeak needs (as the hold line says), not only for the free speaker:
    neither late nor, while fa follows the user, unheard (as a Command kept waiting by
    following is not stuck)."""
    report = _words_behind_a_later_reaction_that_follows(until)
    ea, fa = report.reactions
    assert (ea.app, ea.latency, ea.first_utterance, ea.words_free) == ("ea", 0.0, None, 0.0)
    assert (ea.late, ea.unheard, fa.late) == (False, False, False)
    assert counts(report) == {}


def _held_by(hold: str | None) -> Report:
    """A message comes for fa at 10 s and fa starts at 12 s, though nothing runs on its
    devices: ea's begin/end block (open from 9 s to 12 s) reserves the speaker, or, for
    fa's TopologicalMove that breaks the channel, ea talks to the user until 12 s."""
    loco = ("localization", "locomotion")
    tr = Trace()
    if hold == "keep-channel" or hold is None:
        tr.speak(8.0, "ea", 1, 1, "A long explanation.", lasts=4.0, tree=1)
        command, devices, text = "TopologicalMove", loco, "ea is talking"
    else:
        tr.line(9.0, "block", app="ea", text="open", detail={"id": "camera-work"})
        command, devices, text = "Speak", ("speaker",), "devices kept for ea"
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 2, 2, command=command, reactive=True, devices=devices)
    if hold is not None:
        tr.line(10.0, "hold", app="fa", ab=2, tree=0, command=command, text=text,
                reason=hold, devices=list(devices), detail={"command_id": 2})
    tr.sort()
    if hold == "block":
        tr.line(12.0, "block", app="ea", text="close", detail={"id": "camera-work"})
        tr.line(12.0, "release", app="ea", text="block on speaker", reason="block-close")
    tr.start(12.0, "fa", 2, 2, command=command, devices=devices)
    tr.end(15.0, "fa", 2, 2, command=command, devices=devices)
    return tr.judge()


@pytest.mark.parametrize("hold, rule", [
    ("block", "its begin/end block (rule 3)"),
    ("keep-channel", "keeps the channel (rule 4.1)"),
])
def test_a_hold_the_rules_allow_is_waited_for(hold: str, rule: str) -> None:
    report = _held_by(hold)
    (r,) = report.reactions
    assert [(w.app, w.rule) for w in r.waits] == [("ea", rule)]
    assert (r.residual, r.late) == (2.0, False)
    assert counts(report) == {}


def test_a_block_hold_lasts_until_the_block_that_holds_closes() -> None:
    """ea opened and closed a block before (1 s to 2 s): the hold comes from its second
    block (9 s to 12 s), which fa's reaction may wait for."""
    tr = Trace()
    tr.line(1.0, "block", app="ea", text="open", detail={"id": "camera-work"})
    tr.line(2.0, "block", app="ea", text="close", detail={"id": "camera-work"})
    tr.line(9.0, "block", app="ea", text="open", detail={"id": "camera-work"})
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
    tr.line(10.0, "hold", app="fa", ab=1, tree=0, command="Speak", text="devices kept for ea",
            reason="block", devices=["speaker"], detail={"command_id": 1})
    tr.line(12.0, "block", app="ea", text="close", detail={"id": "camera-work"})
    tr.speak(12.0, "fa", 1, 1, "A message.", request=False)
    assert counts(tr.judge()) == {}


def test_a_reaction_that_breaks_the_channel_is_not_held_without_the_hold() -> None:
    (r,) = _held_by(None).reactions
    assert (r.free, r.late) == (2.0, True)


def _message_while_demoted(demoted: bool) -> Report:
    """fa has kept the others waiting beyond its wait share and lost its precedence
    from 9 s to 15 s (``demoted``); a message comes for it at 10 s; ea's stream speaks
    first, from 10 s to 12 s."""
    tr = Trace()
    if demoted:
        tr.line(9.0, "budget", app="fa", reason="wait-share",
                text="kept other applications waiting 5 s within 30 s: it loses its "
                     "precedence until t=15 s")
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 1, 1, text="A message.", reactive=True)
    tr.speak(10.0, "ea", 2, 2, "The exhibition closes at six.", tree=1, lasts=2.0)
    tr.speak(12.0, "fa", 1, 1, "A message.", request=False)
    if demoted:
        tr.line(15.0, "budget", app="fa", text="regains its precedence", reason="wait-share")
    return tr.judge()


def test_an_app_that_lost_its_precedence_waits_for_anything() -> None:
    report = _message_while_demoted(True)
    (r,) = report.reactions
    assert (r.residual, r.late) == (2.0, False)
    assert [w.rule for w in r.waits] == ["it had lost its precedence (its wait share)"]
    assert counts(report) == {}
    (r,) = _message_while_demoted(False).reactions
    assert (r.free, r.late) == (2.0, True)
    assert (r.took.app, r.took.ab) == ("ea", 2)


def test_what_started_in_the_instant_before_its_app_lost_its_precedence_went_first() -> None:
    """ea's reaction (the latest) asks its question at 6.0 and, in that same instant but
    after it, loses its precedence (the budget line): the question started with its
    precedence and went first over fa's older reaction. Had the budget line come first,
    it took fa's devices."""
    def late(budget_first: bool) -> bool:
        tr = Trace()
        tr.event(4.0, "message")
        tr.request(4.0, "fa", 1, 1, text="A message.", reactive=True)
        tr.event(4.0, "human-found")
        tr.speak(4.0, "ea", 2, 2, "There you are.", tree=1, reactive=True, lasts=2.0)
        budget = {"app": "ea", "reason": "wait-share",
                  "text": "kept other applications waiting 2 s within 60 s: it loses its "
                          "precedence until t=66 s"}
        if budget_first:
            tr.line(6.0, "budget", **budget)
        tr.request(6.0, "ea", 3, 3, tree=1, command="QA", text="Shall I go on?",
                   reason="end-event", devices=TALK, before=2)
        tr.start(6.0, "ea", 3, 3, tree=1, command="QA", text="Shall I go on?",
                 devices=TALK, words=(6.0, 7.0))
        if not budget_first:
            tr.line(6.0, "budget", **budget)
        tr.end(9.0, "ea", 3, 3, tree=1, command="QA", devices=TALK, words=(6.0, 7.0),
               result="status=noinput")
        tr.speak(9.0, "fa", 1, 1, "A message.", request=False)
        fa = next(r for r in tr.judge().reactions if r.app == "fa")
        return fa.late

    assert (late(False), late(True)) == (False, True)


def test_a_perception_in_the_instant_the_user_says_what_nobody_heard_is_no_user_action() -> None:
    """The user says something the robot does not hear (out of its range) in the very
    instant the camera finds them: the reaction to the user found is a reaction to a
    perception, not the user's own action; the FA's later reaction to a touch, whose
    first words are ahead, goes first over it (7.1)."""
    def ranks_as_user(heard: bool) -> bool:
        tr = Trace()
        tr.say(2.0, "Repeat that.", heard=heard)
        tr.event(2.0, "speech" if heard else "human-found")
        tr.request(2.0, "ea", 1, 1, text="This panel shows our robot.", reactive=True)
        tr.speak(2.5, "ea", 1, 1, "This panel shows our robot.", request=False)
        (r,) = tr.judge().reactions
        return r.user

    assert (ranks_as_user(False), ranks_as_user(True)) == (False, True)


