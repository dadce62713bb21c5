"""The judge's late reactions: what a reaction may wait for (the residual of what holds
its devices, the slack), when its first words may come, what is no reaction at all, and
what may not be cut for it. Each test writes a small trace by hand
(:class:`tests.judge.helpers.Trace`) that contains one fault once, and checks that its
count is one and every other count is zero (docs/judging.md).
"""

from __future__ import annotations

import pytest

from prima.judge import Blame, Report, format_table
from tests.judge.helpers import Trace, counts, reaction_behind


# ------------------------------------------------------------------ reactions: the residual

def test_a_reaction_may_wait_for_an_uncuttable_ab_and_the_slack() -> None:
    """Without the interrupt policy a started AB is never cut: the reaction may wait
    for its end (the residual) and 0.2 s more."""
    report = reaction_behind(speech_ends=12.0, reacts_at=12.2).judge()
    (r,) = report.reactions
    assert (r.event, r.app, r.user, r.t, r.residual, r.free, r.latency, r.utterance_latency) \
        == ("touched", "fa", True, 10.0, 2.0, 0.2, 2.2, 2.2)
    assert r.waits == (Blame("ea", 1, "Speak", "ea.pxml:3:5", "uncut: not interruptible",
                             12.0),)
    assert not r.late and r.took is None and counts(report) == {}


def test_a_reaction_free_longer_than_the_slack_is_late() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    (r,) = report.reactions
    assert (r.residual, r.free, r.late) == (2.0, 0.4, True)
    assert r.why == ("started after 2.4 s: free to start for 0.4 s (the rules let it wait "
                     "2 s, and 0.2 s more)")
    assert r.at == "fa.pxml:12:5"
    assert counts(report) == {"late": 1}
    assert report.seqs("late") == [r.seq]
    assert report.breaches() == [f"late reactions: 1 > 0 (seq {r.seq})"]


def test_react_within_replaces_the_rules() -> None:
    tr = reaction_behind(speech_ends=12.0, reacts_at=12.0)
    assert counts(tr.judge()) == {}
    report = tr.judge(react_within=0.2)
    assert counts(report) == {"late": 1}
    assert report.reactions[0].why == "started after 2 s (allowed 0.2 s)"


def test_the_apps_own_running_ab_counts_in_the_residual() -> None:
    """A started AB is never cut, the reacting app's own no more than the other's: a
    reaction queued after its application's own AB waits for it."""
    tr = Trace()
    tr.speak(8.0, "fa", 1, 1, "My own long sentence.", lasts=4.0)
    tr.touch(10.0)
    tr.request(10.0, "fa", 2, 2, text="Yes?", reactive=True, reason="after-latest", before=1)
    tr.sort()
    tr.speak(12.0, "fa", 2, 2, "Yes?", request=False)
    report = tr.judge()
    (r,) = report.reactions
    assert (r.residual, r.free, r.words_free) == (2.0, 0.0, 0.0)
    assert [w.rule for w in r.waits] == ["after its own AB"]
    assert counts(report) == {}


def test_the_apps_own_ab_said_again_counts_in_the_residual() -> None:
    """The reaction queued after its application's own AB waits for that AB said again
    when it was cut (its restart, 7.3 (2)), not only for the cut: a check's visitor who
    spoke over the robot found a reaction 'free' between the cut and the restart."""
    tr = Trace()
    tr.speak(8.0, "fa", 1, 1, "My own long sentence.", lasts=5.0)
    tr.rows.pop()  # (it does not end: it is cut)
    tr.say(9.0, "Pardon?")
    tr.end(9.2, "fa", 1, 1, reason="barge-in", result="spoken=My own, unspoken=long sentence.")
    tr.request(9.2, "fa", 3, 1, text="My own long sentence.", reason="restart", before=1)
    tr.touch(10.0)
    tr.request(10.0, "fa", 2, 2, text="Yes?", reactive=True, reason="after-latest", before=1)
    tr.start(10.5, "fa", 3, 1, text="My own long sentence.", reason="restart")
    tr.end(13.5, "fa", 3, 1)
    tr.speak(13.5, "fa", 2, 2, "Yes?", request=False)
    [r] = [r for r in tr.judge().reactions if r.event == "touched"]
    assert (r.residual, r.free, r.late) == (3.5, 0.0, False)
    assert [w.rule for w in r.waits] == ["after its own AB"]


def test_the_reactions_own_first_ab_is_no_residual() -> None:
    tr = Trace()
    tr.event(10.0, "touched")
    tr.speak(10.0, "fa", 1, 1, "Yes?", lasts=3.0, reactive=True)
    [r] = tr.judge().reactions
    assert (r.latency, r.residual, r.free, r.words_free, r.waits) == (0.0, 0.0, 0.0, 0.0, ())


def _found_by_both(*, latest_first: bool) -> Report:
    """sample-07: the user comes into view and both apps react once the EA's word under
    way ends (0.3 s); the FA's request comes first, the EA's last (the latest reaction,
    rule 4.2). The one that speaks first takes 3 s."""
    tr = Trace()
    tr.speak(9.0, "ea", 1, 1, "Hm.", lasts=1.3, tree=1)
    tr.event(10.0, "human-found")
    tr.request(10.0, "fa", 2, 2, text="I found you.", reactive=True)
    tr.request(10.0, "ea", 3, 3, text="Here you are.", reactive=True, tree=1)
    tr.sort()
    fa = ("fa", 2, 2, "I found you.", 0)
    ea = ("ea", 3, 3, "Here you are.", 1)
    first, second = (ea, fa) if latest_first else (fa, ea)
    tr.speak(10.3, *first[:4], tree=first[4], lasts=3.0, request=False)
    tr.speak(13.3, *second[:4], tree=second[4], request=False)
    return tr.judge()


def test_of_two_reactions_the_earlier_may_wait_for_the_latest() -> None:
    fa, ea = _found_by_both(latest_first=True).reactions
    assert (ea.latency, ea.residual, ea.late) == (0.3, 0.3, False)
    assert (fa.latency, fa.residual, fa.late) == (3.3, 3.3, False)
    assert {(w.app, w.ab, w.rule) for w in fa.waits} == {
        ("ea", 3, "the latest reaction first (4.2)"), ("ea", 1, "uncut: not interruptible")}


def test_of_two_reactions_the_latest_does_not_wait_for_the_earlier() -> None:
    report = _found_by_both(latest_first=False)
    fa, ea = report.reactions
    assert not fa.late
    assert (ea.latency, ea.residual, ea.free, ea.late) == (3.3, 0.3, 3.0, True)
    assert (ea.took.app, ea.took.ab, ea.took.rule) == ("fa", 2, "took its devices")
    assert counts(report) == {"late": 1}


def _found_then_touched(touched_at: float) -> Report:
    """The EA reacts to human-found at 10 s and waits 0.3 s for its own search
    iteration; the user touches the robot at ``touched_at`` and the FA's reaction takes
    the speaker at once for 2.4 s; the EA speaks right after it."""
    tr = Trace()
    tr.start(9.8, "ea", 1, 1, command="ActiveSensingHuman", devices=("locomotion",))
    tr.event(10.0, "human-found")
    tr.request(10.0, "ea", 2, 2, text="Here you are.", reactive=True,
               devices=("speaker", "locomotion"))
    tr.end(10.3, "ea", 1, 1, command="ActiveSensingHuman", devices=("locomotion",))
    tr.touch(touched_at)
    tr.request(touched_at, "fa", 3, 3, text="Hee-hee!", reactive=True, tree=1)
    tr.sort()
    tr.speak(touched_at, "fa", 3, 3, "Hee-hee!", tree=1, lasts=2.4, request=False)
    tr.speak(touched_at + 2.4, "ea", 2, 2, "Here you are.", request=False)
    return tr.judge()


def test_a_later_reaction_of_another_app_goes_first() -> None:
    """sample-08 swept: the touch comes at 10.2 s, while the EA still waits for its own
    search look: the FA's reaction (the latest, and to the user's own action) goes
    first, the EA's words wait for it."""
    ea, fa = _found_then_touched(10.2).reactions
    assert (ea.app, ea.latency, ea.residual, ea.late) == ("ea", 2.6, 2.6, False)
    assert [(w.app, w.rule) for w in ea.waits] == [("fa", "the user's own action first (7.1)")]
    assert (fa.latency, fa.late) == (0.0, False)


def test_a_later_reaction_does_not_excuse_one_already_late() -> None:
    """The EA could have spoken at 10.3 s but did not; the FA's reaction to a touch at
    11 s then takes the speaker: the 0.7 s the EA was free are still too long."""
    ea, _fa = _found_then_touched(11.0).reactions
    assert (ea.residual, ea.free, ea.late) == (2.7, 0.7, True)
    assert ea.why == ("started after 3.4 s: free to start for 0.7 s (the rules let it wait "
                      "2.7 s, and 0.2 s more)")


# ------------------------------------------------------------------ reactions: the words

def test_the_first_words_may_wait_for_what_holds_the_speaker() -> None:
    """sample-08: the FA's gesture starts at once on the free arm; its words wait for
    the EA's explanation under way (2 s), then may be free to start 1.2 s more."""
    def touched(speaks_at: float) -> Report:
        tr = Trace()
        tr.speak(8.0, "ea", 1, 1, "A long explanation.", lasts=4.0)
        tr.touch(10.0)
        tr.request(10.0, "fa", 2, [2, 3], tree=1, command="Gesture", reactive=True,
                   devices=("arm",))
        tr.start(10.0, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
        tr.end(11.0, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
        tr.sort()
        tr.speak(speaks_at, "fa", 3, 3, "Hee-hee!", tree=1, request=False)
        return tr.judge()

    [r] = touched(speaks_at=13.2).reactions
    assert (r.residual, r.latency, r.utterance_latency, r.words_free) == (0.0, 0.0, 3.2, 1.2)
    assert not r.late
    [r] = touched(speaks_at=13.4).reactions
    assert r.late and r.why == ("spoke after 3.4 s: its words were free to start for 1.4 s "
                                "(allowed 1.2 s)")


def test_a_reaction_late_for_its_words_names_what_took_their_devices() -> None:
    """The FA's gesture starts at once on the free arm; as it ends, the EA starts a
    sentence on the speaker its words were waiting for: the finding names that sentence,
    what the words waited behind, not the gesture's wait (there was none)."""
    tr = Trace()
    tr.touch(10.0)
    tr.request(10.0, "fa", 2, [2, 3], tree=1, command="Gesture", reactive=True,
               devices=("arm",))
    tr.start(10.0, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
    tr.end(10.5, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
    tr.speak(10.5, "ea", 5, 5, "Meanwhile, look at this panel.", lasts=2.5, tree=3)
    tr.speak(13.0, "fa", 3, 3, "Hee-hee!", tree=1, request=False)
    [r] = tr.judge().reactions
    assert r.late and r.why.startswith("spoke after 3 s: its words were free to start for")
    assert r.took is not None and (r.took.app, r.took.ab, r.took.rule) == (
        "ea", 5, "took its devices")


def _message_while_moving(turn_starts: float) -> Report:
    """The user's reception EA (its own TopologicalMove iterating, 0.5 s each) answers a
    message with an ASAP Speak; the connect-channel policy puts a FaceHuman before the
    words, and the turn waits for the move's iteration under way (until 70.34): the
    interrupt policy could cut another app's iteration, never the reacting app's own."""
    loco = ("localization", "locomotion")
    turn = ("human-detection", "locomotion")
    tr = Trace()
    tr.start(69.84, "ea", 109, 5, command="TopologicalMove", devices=loco, iteration=101,
             cuttable=True)
    tr.event(70.0, "message")
    tr.request(70.0, "ea", 110, 9, tree=2, text="A message.", reactive=True, reason="asap")
    tr.request(70.0, "ea", 111, 10, tree=2, command="FaceHuman", reactive=True,
               reason="connect-channel", devices=turn, precedes=9)
    tr.end(70.34, "ea", 109, 5, command="TopologicalMove", devices=loco, iteration=101)
    tr.start(turn_starts, "ea", 111, 10, tree=2, command="FaceHuman", devices=turn)
    tr.end(turn_starts + 3.04, "ea", 111, 10, tree=2, command="FaceHuman", devices=turn)
    tr.speak(turn_starts + 3.04, "ea", 110, 9, "A message.", tree=2, request=False)
    return tr.judge()


def test_a_policys_turn_before_the_first_command_is_the_reactions_first_ab() -> None:
    """The turn is the reaction's first AB: it waits for what runs on its wheels (the
    app's own move iteration, never cut), not only for what runs on the speaker its
    first request names; the words wait for the turn, the reaction's own."""
    [r] = _message_while_moving(turn_starts=70.34).reactions
    assert (r.latency, r.residual, r.utterance_latency, r.words_free) == (
        0.34, 0.34, 3.38, 0.0)
    assert set(r.devices) == {"speaker", "human-detection", "locomotion"}
    assert [(w.ab, w.rule) for w in r.waits] == [(109, "its own application's")]
    assert not r.late
    [r] = _message_while_moving(turn_starts=70.6).reactions  # the wheels free since 70.34
    assert (r.free, r.late) == (0.26, True)


def _turn_put_in_line_at(ready: float) -> Report:
    """The FA's words are ready only when the EA's sentence ends (12 s): the turn put
    before them then waits for the FA's own search look, started 0.2 s before on the
    wheels the words did not need, until 0.3 s later."""
    turn = ("human-detection", "locomotion")
    tr = Trace()
    tr.speak(8.0, "ea", 1, 1, "A long explanation.", lasts=4.0, tree=1)
    tr.touch(10.0)
    tr.request(10.0, "fa", 2, 2, tree=2, text="Hee-hee!", reactive=True)
    tr.start(ready - 0.2, "fa", 3, 3, command="ActiveSensingHuman", devices=turn)
    tr.sort()
    tr.request(ready, "fa", 4, 4, tree=2, command="FaceHuman", reactive=True,
               reason="connect-channel", devices=turn, precedes=2)
    tr.end(ready + 0.3, "fa", 3, 3, command="ActiveSensingHuman", devices=turn)
    tr.start(ready + 0.3, "fa", 4, 4, tree=2, command="FaceHuman", devices=turn)
    tr.end(ready + 1.3, "fa", 4, 4, tree=2, command="FaceHuman", devices=turn)
    tr.speak(ready + 1.3, "fa", 2, 2, "Hee-hee!", tree=2, request=False)
    return tr.judge()


def test_a_turn_put_in_line_later_waits_for_what_runs_on_its_wheels_then() -> None:
    """The look is a started IU (never cut) that held the wheels when the turn was put
    in line at 12 s: the turn may wait for it (0.3 s)."""
    [r] = _turn_put_in_line_at(12.0).reactions
    assert (r.latency, r.late) == (2.3, False)


def test_a_turn_put_in_line_after_the_bound_is_late() -> None:
    """Put in line at 12.5 s, when the speaker had been free since 12 s: late however
    its wait on the wheels is counted."""
    [r] = _turn_put_in_line_at(12.5).reactions
    assert (r.latency, r.late) == (2.8, True)


def test_a_turn_after_the_first_utterance_does_not_excuse_it() -> None:
    """A reaction waves at once (its own AB: a filler) and says two sentences; its first
    words come 1.5 s after the wave. The policy's turn before its second sentence is no
    wait of the first one."""
    turn = ("human-detection", "locomotion")
    tr = Trace()
    tr.touch(10.0)
    tr.request(10.0, "fa", 1, [1, 2, 3], command="Gesture", reactive=True, devices=("arm",))
    tr.start(10.0, "fa", 1, 1, command="Gesture", devices=("arm",))
    tr.end(11.0, "fa", 1, 1, command="Gesture", devices=("arm",))
    tr.speak(12.5, "fa", 2, 2, "Hello.", request=False)
    tr.request(13.5, "fa", 4, 4, command="FaceHuman", reactive=True, reason="connect-channel",
               devices=turn, precedes=3)
    tr.start(13.5, "fa", 4, 4, command="FaceHuman", devices=turn)
    tr.end(16.0, "fa", 4, 4, command="FaceHuman", devices=turn)
    tr.speak(16.0, "fa", 3, 3, "Nice to see you.", request=False)
    [r] = tr.judge().reactions
    assert (r.utterance_latency, r.words_free) == (2.5, 1.5)
    assert r.late and r.why == ("spoke after 2.5 s: its words were free to start for 1.5 s "
                                "(allowed 1.2 s)")


def test_a_reactions_first_words_may_come_a_second_later() -> None:
    def message(speaks_at: float) -> Report:
        tr = Trace()
        tr.event(1.0, "message")
        tr.request(1.0, "ea", 1, [1, 2], command="StopMoving", text="A message.",
                   reactive=True, reason="asap", devices=("locomotion",))
        tr.start(1.0, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
        tr.end(1.0, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
        tr.speak(speaks_at, "ea", 2, 2, "A message.", request=False)
        return tr.judge()

    report = message(2.2)
    (r,) = report.reactions
    assert (r.latency, r.utterance_latency, r.words_free) == (0.0, 1.2, 1.2)
    assert counts(report) == {}
    report = message(2.3)
    assert report.reactions[0].why == ("spoke after 1.3 s: its words were free to start "
                                       "for 1.3 s (allowed 1.2 s)")
    assert counts(report) == {"late": 1}


def test_a_reactions_utterance_is_one_of_its_own_commands() -> None:
    """A later request's Speak in the same tree is not the reaction's utterance."""
    tr = Trace()
    tr.event(1.0, "message")
    tr.request(1.0, "ea", 1, 1, command="TopologicalMove", reactive=True,
               devices=("locomotion",))
    tr.start(1.0, "ea", 1, 1, command="TopologicalMove", devices=("locomotion",))
    tr.end(30.0, "ea", 1, 1, command="TopologicalMove", devices=("locomotion",))
    tr.request(30.0, "ea", 2, 2, text="Here we are.", reason="end-event", before=1)
    tr.speak(30.0, "ea", 2, 2, "Here we are.", request=False)
    report = tr.judge()
    assert report.reactions[0].utterance_latency is None
    assert not report.reactions[0].words
    assert counts(report) == {}


# ------------------------------------------------------------------ reactions: what is no reaction

def test_the_robot_arriving_somewhere_is_no_reaction_to_measure() -> None:
    tr = Trace()
    tr.event(10.0, "place-reached")
    tr.request(10.0, "ea", 1, 1, command="SetDirection", reactive=True, devices=("locomotion",))
    tr.start(10.0, "ea", 1, 1, command="SetDirection", devices=("locomotion",))
    tr.end(11.5, "ea", 1, 1, command="SetDirection", devices=("locomotion",))
    tr.speak(11.5, "ea", 2, 2, "Here is the book you searched for.")
    report = tr.judge()
    assert report.reactions == () and counts(report) == {}


def test_heard_speech_is_a_reaction_of_the_app_that_asked() -> None:
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Which book?", "The C Primer.", at=3.0)
    tr.request(3.0, "ea", 2, 2, text="Wait a minute.", reason="end-event", before=1)
    tr.speak(3.5, "ea", 2, 2, "Wait a minute.", request=False)
    report = tr.judge()
    (r,) = report.reactions
    assert (r.event, r.app, r.user, r.text, r.t, r.latency) == (
        "speech", "ea", True, "The C Primer.", 3.0, 0.5)
    assert r.late and counts(report) == {"late": 1}


def test_speech_not_heard_is_no_reaction() -> None:
    tr = Trace()
    tr.say(1.0, "Hello?", heard=False)
    tr.speak(1.0, "fa", 1, 1, "Hi.")
    assert tr.judge().reactions == ()


def test_requests_that_are_not_reactive_are_no_reaction() -> None:
    tr = Trace()
    tr.event(1.0, "place-reached")
    tr.speak(1.0, "ea", 1, 1, "We are in the hall.")
    assert tr.judge().reactions == ()


def test_a_touch_without_the_users_line_is_no_action_of_the_users() -> None:
    tr = Trace()
    tr.event(1.0, "touched")
    tr.speak(1.0, "fa", 1, 1, "Hee-hee!", reactive=True)
    tr.touch(3.0)
    tr.speak(3.0, "fa", 2, 2, "Hee-hee!", reactive=True)
    assert [r.user for r in tr.judge().reactions] == [False, True]


# ------------------------------------------------------------------ reactions: what may not be cut

def _prompt_then_message(message_at: float) -> Report:
    """ea's Q&A (the interrupt policy may cut it) says its five-word prompt from 8 s to
    9 s, then listens until it times out at 12 s; a message comes for fa at
    ``message_at``, and fa speaks at 12 s."""
    tr = Trace()
    tr.ask(8.0, "ea", 1, 1, "Which book do you want?", None, 12.0, cuttable=True)
    tr.event(message_at, "message")
    tr.request(message_at, "fa", 2, 2, tree=1, text="A message.", reactive=True)
    tr.sort()
    tr.speak(12.0, "fa", 2, 2, "A message.", tree=1, request=False)
    return tr.judge()


@pytest.mark.parametrize("message_at, rule, late", [
    (10.0, "uncut: a Q&A listening", False),
    (8.9, "uncut: a Q&A on the last word of its prompt, then listening", False),
    (8.1, "cut at a word boundary", True),
])
def test_a_qa_listening_is_never_cut_its_prompt_may_be(message_at: float, rule: str,
                                                       late: bool) -> None:
    """The user's turn is never cut: a reaction waits for the listening's end. During
    the prompt the reaction could have cut it at the next word (8.2 s): waiting for the
    listening is late; on the last word, the cut would come when the listening begins."""
    report = _prompt_then_message(message_at)
    (r,) = report.reactions
    assert [w.rule for w in r.waits] == [rule]
    assert r.late is late
    assert counts(report) == ({"late": 1} if late else {})


def _sentence_and_touch(*, cuttable: bool, cut: bool) -> Report:
    """ea says eight words from 8 s to 12 s (0.5 s each); the user touches the robot at
    10.1 s, in the fifth word. With ``cut``, the sentence stops at that word's end
    (10.5 s), fa answers, and ea says its sentence again at 11.5 s."""
    words = "one two three four five six seven eight"
    tr = Trace()
    tr.request(8.0, "ea", 1, 1, text=words, at="ea.pxml:3:5")
    tr.start(8.0, "ea", 1, 1, text=words, cuttable=cuttable, words=(8.0, 12.0))
    tr.touch(10.1)
    tr.request(10.1, "fa", 2, 2, tree=1, text="Yes?", reactive=True, at="fa.pxml:12:5")
    if cut:
        tr.interrupt(10.1, "ea", 1, 1, by="fa", by_ab=2)
        tr.end(10.5, "ea", 1, 1, reason="interrupt", words=(8.0, 12.0), text=words)
        tr.request(10.5, "ea", 3, 1, text=words, reason="restart", before=1, at="ea.pxml:3:5")
        tr.speak(10.5, "fa", 2, 2, "Yes?", tree=1, request=False)
        tr.start(11.5, "ea", 3, 1, text=words, reason="restart", words=(11.5, 15.5))
        tr.end(15.5, "ea", 3, 1, words=(11.5, 15.5), text=words)
    else:
        tr.end(12.0, "ea", 1, 1, words=(8.0, 12.0), text=words)
        tr.speak(12.0, "fa", 2, 2, "Yes?", tree=1, request=False)
    return tr.judge()


def test_a_cuttable_utterance_holds_a_reaction_to_its_word_boundary() -> None:
    report = _sentence_and_touch(cuttable=True, cut=True)
    (r,) = report.reactions
    assert (r.latency, r.residual, r.free) == (0.4, 0.4, 0.0)
    assert r.waits == (Blame("ea", 1, "Speak", "ea.pxml:3:5", "cut at a word boundary",
                             10.5),)
    assert counts(report) == {}


def test_a_late_reaction_names_what_it_waited_for_and_what_took_its_devices() -> None:
    """The sentence could have been cut at the fifth word's end (10.5 s, the cut a step
    later) but ran on to 12 s: the reaction was free to start 1.48 s. It names where its
    request is written, what the rules let it wait for and what ran instead."""
    report = _sentence_and_touch(cuttable=True, cut=False)
    (r,) = report.reactions
    assert (r.at, r.residual, r.free, r.late) == ("fa.pxml:12:5", 0.42, 1.48, True)
    assert r.waits == (Blame("ea", 1, "Speak", "ea.pxml:3:5", "cut at a word boundary",
                             10.52),)
    assert r.took == Blame("ea", 1, "Speak", "ea.pxml:3:5", "took its devices", 12.0)
    assert counts(report) == {"late": 1}
    table = format_table([report])
    assert ("seq 3 t=10.1 fa touched (fa.pxml:12:5): started after 1.9 s: free to start for "
            "1.48 s (the rules let it wait 0.42 s, and 0.2 s more); waited for ea AB1 Speak "
            "ea.pxml:3:5 [cut at a word boundary]; meanwhile ea AB1 Speak ea.pxml:3:5 "
            "[took its devices]") in table
    assert r.to_dict()["took"] == {"app": "ea", "ab": 1, "command": "Speak",
                                   "at": "ea.pxml:3:5", "rule": "took its devices",
                                   "until": 12.0}


def test_an_utterance_the_robot_may_not_cut_is_waited_for_whole() -> None:
    (r,) = _sentence_and_touch(cuttable=False, cut=False).reactions
    assert (r.residual, r.late) == (1.9, False)
    assert [w.rule for w in r.waits] == ["uncut: not interruptible"]


def _cuttable_but(case: str) -> Report:
    """ea's cuttable AB runs from 8 s to 12 s; a message comes for fa at 10 s; fa
    starts at 12 s. ``case`` says why fa's reaction may not cut it all the same."""
    tr = Trace()
    command, devices, text = "Speak", ("speaker",), "A long sentence."
    mine, my_devices = "Speak", ("speaker",)
    reason = {"restart": "restart", "blend": "blend"}.get(case, "free-devices")
    if case == "block":
        tr.line(7.0, "block", app="ea", text="open", detail={"id": "camera-work"})
    if case == "channel":  # a reaction that breaks the channel, an AB that keeps it
        command, devices, text = "Turn", ("locomotion",), None
        mine, my_devices = "TopologicalMove", ("localization", "locomotion")
    tr.request(8.0, "ea", 1, 1, command=command, text=text, devices=devices)
    tr.start(8.0, "ea", 1, 1, command=command, text=text, devices=devices, reason=reason,
             cuttable=True, words=None if text is None else (8.0, 12.0))
    tr.event(10.0, "message")
    tr.request(10.0, "fa", 2, 2, tree=1, command=mine, reactive=True, devices=my_devices)
    tr.end(12.0, "ea", 1, 1, command=command, devices=devices)
    tr.start(12.0, "fa", 2, 2, tree=1, command=mine, devices=my_devices)
    tr.end(15.0, "fa", 2, 2, tree=1, command=mine, devices=my_devices)
    if case == "block":
        tr.line(15.0, "block", app="ea", text="close", detail={"id": "camera-work"})
    return tr.judge()


@pytest.mark.parametrize("case, rule", [
    ("restart", "uncut: a restart (cut at most once)"),
    ("blend", "uncut: blended"),
    ("block", "uncut: in a begin/end block"),
    ("channel", "uncut: it keeps the channel"),
])
def test_a_cuttable_ab_that_the_rules_keep_uncut_is_waited_for_whole(case: str,
                                                                      rule: str) -> None:
    """An AB is cut at most once; a blended AB, one in a begin/end block, and one that
    keeps the channel over a reaction that breaks it, are never cut."""
    report = _cuttable_but(case)
    (r,) = report.reactions
    assert [w.rule for w in r.waits] == [rule]
    assert (r.residual, r.late) == (2.0, False)
    assert counts(report) == {}


def test_without_a_reason_to_keep_it_the_cuttable_ab_is_cut() -> None:
    (r,) = _cuttable_but("plain").reactions
    assert [w.rule for w in r.waits] == ["cut at a word boundary"]
    assert r.late


