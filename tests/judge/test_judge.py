"""The judge: each measure catches its fault, and only its fault.

Each test writes a small trace by hand (:class:`Trace` below) that contains one
fault once, and checks that its count is one and every other count is zero (where
one fault is, by their definitions, two measures' finding, an utterance that splits
an exchange and so delays the reply, the test says so). The expected numbers come
from the mediation rules and the judge's documented model (docs/judging.md).
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import pytest

from prima.cli import main
from prima.errors import TraceError
from prima.judge import (
    LIMITS,
    MEASURES,
    PARAMETERS,
    Blame,
    Report,
    Thresholds,
    format_table,
    judge,
    judge_file,
    load_trace,
)

pytest_plugins = ["pytester"]

ROOT = Path(__file__).parents[2]
THESIS = ROOT / "scenarios" / "thesis"

FACING = {"x": 0.0, "y": 0.0, "heading": 0.0}
"""The robot at the origin, facing east."""
USER = {"x": 1.0, "y": 0.0, "heading": 180.0, "detectable": True}
"""The user a metre east of it, facing it."""
TALK = ("speaker", "speech-recognition")
"""A Q&A's devices."""


class Trace:
    """A hand-written trace: each method appends one line, seq counted."""

    def __init__(self) -> None:
        self.rows: list[dict[str, Any]] = []
        self.robot = dict(FACING)
        self.user: dict[str, Any] = dict(USER)

    def line(self, t: float, kind: str, **fields: Any) -> dict[str, Any]:
        row = {"t": t, "seq": len(self.rows), "kind": kind}
        row.update({k: v for k, v in fields.items() if v is not None})
        if kind in ("start", "end", "user", "event", "pose"):
            row.setdefault("robot", dict(self.robot))
            row.setdefault("user", dict(self.user))
        self.rows.append(row)
        return row

    def sort(self) -> None:
        """Put lines written out of order where they belong in time (in the order
        they were written within an instant), and count their seqs again."""
        self.rows.sort(key=lambda r: r["t"])
        for seq, row in enumerate(self.rows):
            row["seq"] = seq

    def event(self, t: float, name: str) -> None:
        self.line(t, "event", text=name)

    def touch(self, t: float) -> None:
        """The user touches the robot: the user's line, then the event it posts."""
        self.line(t, "user", action="touch")
        self.event(t, "touched")

    def say(self, t: float, words: str, heard: bool = True) -> None:
        self.line(t, "user", action="say", text=words, detail={"heard": heard})

    def request(self, t: float, app: str, ab: int, cid: int | list[int], *, tree: int = 0,
                command: str = "Speak", text: str | None = None, reactive: bool = False,
                reason: str = "new-tree", devices: tuple[str, ...] = ("speaker",),
                before: int | None = None, at: str | None = None,
                precedes: int | None = None) -> None:
        ids = cid if isinstance(cid, list) else [cid]
        detail: dict[str, Any] = {"command_id": ids[0]}
        if at is not None:
            detail["at"] = at
        if precedes is not None:
            detail["precedes"] = precedes
        self.line(t, "request", app=app, ab=ab, tree=tree, command=command, text=text,
                  reactive=reactive, reason=reason, devices=list(devices),
                  command_ids=ids if len(ids) > 1 else None, before=before, detail=detail)

    def start(self, t: float, app: str, ab: int, cid: int, *, tree: int = 0,
              command: str = "Speak", text: str | None = None,
              devices: tuple[str, ...] = ("speaker",), iteration: int = 0,
              reason: str = "free-devices", cuttable: bool = False,
              words: tuple[float, float] | None = None) -> None:
        """``words``: when its words begin and end, if they begin as it starts."""
        detail: dict[str, Any] = {"command_id": cid}
        if iteration:
            detail["iteration"] = iteration
        if cuttable:
            detail["cuttable"] = True
        if words is not None:
            detail["words_start"], detail["words_end"] = words
        self.line(t, "start", app=app, ab=ab, tree=tree, command=command, text=text,
                  reason=reason, devices=list(devices), detail=detail)

    def end(self, t: float, app: str, ab: int, cid: int, *, tree: int = 0,
            command: str = "Speak", devices: tuple[str, ...] = ("speaker",),
            result: str = "duration=1.0", iteration: int = 0, reason: str = "completed",
            words: tuple[float, float] | None = None, text: str | None = None) -> None:
        """``words``: when its words began and ended, as said."""
        detail: dict[str, Any] = {"command_id": cid, "result": result}
        if iteration:
            detail["iteration"] = iteration
        if words is not None:
            detail["words_start"], detail["words_end"] = words
        self.line(t, "end", app=app, ab=ab, tree=tree, command=command, text=text,
                  reason=reason, devices=list(devices), detail=detail)

    def interrupt(self, t: float, app: str, ab: int, cid: int, *, by: str, by_ab: int,
                  tree: int = 0) -> None:
        """The interrupt policy asks to cut ``app``'s Speak ``ab`` for ``by``'s reaction."""
        self.line(t, "interrupt", app=app, ab=ab, tree=tree, command="Speak",
                  text=f"for {by}'s reaction (AB{by_ab})", reason="interrupt",
                  devices=["speaker"], detail={"command_id": cid})

    def speak(self, t: float, app: str, ab: int, cid: int, words: str, *, lasts: float = 1.0,
              tree: int = 0, request: bool = True, reactive: bool = False,
              cuttable: bool = False, at: str | None = None) -> None:
        """A Speak requested and started at ``t`` that ends ``lasts`` seconds later."""
        if request:
            self.request(t, app, ab, cid, tree=tree, text=words, reactive=reactive, at=at)
        said = (t, t + lasts)
        self.start(t, app, ab, cid, tree=tree, text=words, cuttable=cuttable, words=said)
        self.end(t + lasts, app, ab, cid, tree=tree, words=said, text=words)

    def ask(self, t: float, app: str, ab: int, cid: int, prompt: str, answer: str | None,
            at: float, *, tree: int = 0, request: bool = True, reactive: bool = False,
            cuttable: bool = False, prompt_lasts: float = 1.0) -> None:
        """A Q&A started at ``t`` (and requested then, unless ``request`` is False),
        saying its prompt for ``prompt_lasts`` seconds, answered with ``answer`` at
        ``at`` (None: it times out then)."""
        said = (t, t + min(prompt_lasts, at - t))
        if request:
            self.request(t, app, ab, cid, tree=tree, command="QA", text=prompt,
                         reactive=reactive, devices=TALK)
        self.start(t, app, ab, cid, tree=tree, command="QA", text=prompt, devices=TALK,
                   cuttable=cuttable, words=said)
        if answer is None:
            self.end(at, app, ab, cid, tree=tree, command="QA", devices=TALK,
                     result="status=timeout", words=said)
            return
        self.say(at, answer)
        self.end(at, app, ab, cid, tree=tree, command="QA", devices=TALK,
                 result=f"status=answered, utterance={answer}", words=said)

    def pose(self, t: float) -> None:
        self.line(t, "pose")

    def judge(self, **thresholds: Any) -> Report:
        return judge(self.rows, thresholds=Thresholds(**thresholds), name="hand-written")


def counts(report: Report) -> dict[str, int]:
    return {k: v for k, v in report.counts().items() if v}


# ------------------------------------------------------------------ a clean trace

def clean() -> Trace:
    """A short exchange with nothing wrong: a touch answered at once, a Q&A replied to."""
    tr = Trace()
    tr.line(0.0, "load", app="fa")
    tr.line(0.0, "load", app="ea")
    tr.speak(0.0, "ea", 1, 1, "Hello.")
    tr.touch(3.0)
    tr.request(3.0, "fa", 2, 2, tree=1, command="QA", text="Yes?", reactive=True, devices=TALK)
    tr.ask(3.0, "fa", 2, 2, "Yes?", "Nothing.", at=5.0, tree=1, request=False)
    tr.request(5.0, "fa", 3, 3, tree=1, text="O.K.", reason="end-event", before=2)
    tr.speak(5.0, "fa", 3, 3, "O.K.", tree=1, request=False)
    tr.pose(7.0)
    return tr


def test_a_clean_trace_has_no_fault() -> None:
    report = clean().judge()
    assert counts(report) == {}
    assert report.ok and report.breaches() == []
    assert [(r.event, r.app, r.user, r.latency, r.utterance_latency)
            for r in report.reactions] == [("touched", "fa", True, 0.0, 0.0),
                                           ("speech", "fa", True, 0.0, 0.0)]
    assert report.reactions[1].text == "Nothing."


# ------------------------------------------------------------------ reactions: the residual

def reaction_behind(speech_ends: float, reacts_at: float) -> Trace:
    """ea speaks from 8 s to ``speech_ends``; fa reacts to a touch at 10 s, starting at
    ``reacts_at``."""
    tr = Trace()
    tr.speak(8.0, "ea", 1, 1, "A long sentence.", lasts=speech_ends - 8.0, at="ea.pxml:3:5")
    tr.touch(10.0)
    tr.request(10.0, "fa", 2, 2, tree=1, text="Yes?", reactive=True, at="fa.pxml:12:5")
    tr.sort()  # (the end of ea's sentence where it belongs)
    tr.speak(reacts_at, "fa", 2, 2, "Yes?", tree=1, request=False)
    return tr


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
    devices = ("localization", "locomotion", "speaker")
    tr = Trace()
    tr.request(1.0, "ea", 1, [1, 2], command="SetPosition+Speak", text="Here is the panel.",
               devices=devices)
    tr.start(1.0, "ea", 1, 1, command="SetPosition+Speak", text="Here is the panel.",
             devices=devices)
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


# ------------------------------------------------------------------ thresholds and reports

def test_every_measure_has_a_threshold_and_an_option() -> None:
    """The measures, the report's counts, the thresholds and the options of ``prima
    judge`` all come from one table."""
    keys = ["late", "unheard", "unfaced", "leaving", "elsewhere", "splits", "silences",
            "barge_in", "ignored", "recovery", "stuck"]
    assert [m.key for m in MEASURES] == [m.key for m in LIMITS] == keys
    assert list(clean().judge().counts()) == keys
    assert [m.option for m in MEASURES] == [f"--max-{k.replace('_', '-')}" for k in keys]
    assert Thresholds().limits == {f"max_{k}": 0 for k in keys}
    assert [p.option for p in PARAMETERS] == [
        "--reaction-slack", "--utterance-slack", "--react-within", "--face-tolerance",
        "--unfaced-for", "--leave-distance", "--resume-distance", "--barge-in-slack",
        "--answer-slack", "--recovery-slack", "--silence", "--stuck-after", "--search-after"]


def test_thresholds_allow_what_they_say() -> None:
    tr = reaction_behind(speech_ends=12.0, reacts_at=12.4)
    assert not tr.judge().ok
    assert tr.judge(max_late=1).ok
    assert tr.judge(reaction_slack=0.5).ok
    assert Thresholds(max_splits=2).limit("splits") == 2
    assert Thresholds(max_splits=2).replace(silence=3).to_dict()["max_splits"] == 2


@pytest.mark.parametrize("bad, message", [
    ({"max_late": -1}, "max_late must be a number from 0 up"),
    ({"silence": float("nan")}, "silence must be a number from 0 up"),
    ({"max_splits": 1.5}, "max_splits must be a whole number"),
    ({"leave_distance": "far"}, "leave_distance must be a number"),
    ({"max_lat": 1}, "did you mean 'max_late'"),
])
def test_bad_thresholds_are_refused(bad: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Thresholds(**bad)


def test_report_dict_has_stable_keys_and_is_json() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    d = report.to_dict()
    assert list(d) == ["name", "end", "lines", "thresholds", "counts", "reactions", "late",
                       "unheard", "unfaced", "leaving", "elsewhere", "splits", "silences",
                       "barge_in", "ignored", "recovery", "stuck", "breaches", "ok"]
    assert d["counts"] == {"reactions": 1, "late": 1, "unheard": 0, "unfaced": 0,
                           "leaving": 0, "elsewhere": 0, "splits": 0, "silences": 0,
                           "barge_in": 0, "ignored": 0, "recovery": 0, "stuck": 0}
    assert d["late"] == [d["reactions"][0]]
    assert json.loads(json.dumps(d)) == d


def test_the_table_shows_reactions_counts_and_a_summary() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    table = format_table([report])
    assert "touched" in table and "LATE: started after 2.4 s: free to start for 0.4 s" in table
    assert table.splitlines()[-1].startswith("hand-written  reactions 1")
    assert table.splitlines()[-1].endswith("FAIL: late reactions 1 > 0")


# ------------------------------------------------------------------ reading traces

def test_load_trace_locates_every_bad_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.jsonl"
    path.write_text("\n".join([
        '{"t": 0, "seq": 0, "kind": "load", "app": "fa"}',
        '{"t": 1, "seq": 1, "kind": "event", "text": "touched"',
        '',
        '{"t": 1, "kind": "event"}',
        '[1, 2]',
        '{"t": 2, "seq": 4, "kind": "start", "devices": "speaker"}',
        '{"t": 2, "seq": 5, "kind": "pose"}',
        '{"t": 0.5, "seq": 6, "kind": "pose"}',
        '{"t": 3, "seq": 7, "kind": "pose", "robot": {"x": 1}}',
    ]) + "\n", encoding="utf-8")
    with pytest.raises(TraceError) as caught:
        load_trace(path)
    assert [str(p) for p in caught.value.problems] == [
        f"{path}:2:54: error: not a JSON object: Expecting ',' delimiter",
        f"{path}:4:1: error: missing field 'seq'",
        f"{path}:5:1: error: a trace line must be a JSON object",
        f"{path}:6:1: error: field 'devices' has the wrong type (str)",
        f"{path}:8:1: error: time goes backwards (0.5 after 2)",
        f"{path}:9:1: error: field 'robot' needs numbers x, y and heading",
    ]


def test_an_empty_trace_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / "empty.jsonl"
    path.write_text("\n", encoding="utf-8")
    with pytest.raises(TraceError, match="empty.jsonl:1:1: error: the trace has no lines"):
        load_trace(path)


def test_a_trace_line_and_its_jsonl_are_judged_alike(tmp_path: Path) -> None:
    from prima.run import Run
    from prima.trace import jsonl_row

    lines = Run(THESIS / "fig5-7.xml").run()
    path = tmp_path / "fig5-7.jsonl"
    path.write_text("".join(map(jsonl_row, lines)), encoding="utf-8")
    assert judge(lines).to_dict() == judge(load_trace(path)).to_dict()


# ------------------------------------------------------------------ the shipped scenarios

def test_sample_05_is_natural_under_the_rules() -> None:
    """Figure 5.9's situation, mediated by every policy: no fault at all."""
    report = judge_file(THESIS / "sample-05.xml")
    assert report.ok and counts(report) == {}


def test_sample_05_under_the_thesis_rules_has_exactly_its_split_exchange() -> None:
    """With every policy off (the thesis' PaPeRo), FA5's news of the video server comes
    between the user's answer to EA2 and EA2's reply: the split the thesis' subjects
    disliked; EA2's reply, kept waiting for it, is late by the amended rules (7.4), and
    nothing else."""
    from prima.run import Switches

    report = judge_file(THESIS / "sample-05.xml", switches=Switches(policies=(("all", False),)))
    assert counts(report) == {"late": 1, "splits": 1}
    (s,) = report.of("splits")
    assert (s.kind, s.app, s.by, s.text, s.t) == (
        "reply", "ea2-library", "fa5-video-timer", "The video setting succeeds.", 40.8)
    answered = next(r for r in report.reactions if r.text == "The C Primer.")
    assert answered.t == 40.8 and answered.app == "ea2-library"
    assert s.anchor_seq < s.seq < answered.first_start_seq  # answer, FA5, EA2's reply


def test_sample_05_with_an_explicit_stream_has_none() -> None:
    """FA5's video-server exchange in an explicit stream keeps it whole, even with every
    other policy off."""
    from prima.run import Switches

    off = Switches(policies=(("all", False), ("streams", True)))
    assert judge_file(THESIS / "sample-05-stream.xml", switches=off).of("splits") == ()


# ------------------------------------------------------------------ the command line

def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def write(tmp_path: Path, trace: Trace, name: str = "run.jsonl") -> Path:
    path = tmp_path / name
    path.write_text("".join(json.dumps(r) + "\n" for r in trace.rows), encoding="utf-8")
    return path


def test_cli_exit_codes_follow_the_thresholds(tmp_path: Path) -> None:
    good = write(tmp_path, clean(), "good.jsonl")
    late = write(tmp_path, reaction_behind(speech_ends=12.0, reacts_at=12.4), "late.jsonl")
    assert cli("judge", str(good))[0] == 0
    code, out, err = cli("judge", str(good), str(late))
    assert code == 1 and "FAIL: late reactions 1 > 0" in out
    assert "2 run(s) judged: 1 exceeded a threshold" in err
    assert cli("judge", "--max-late", "1", str(late))[0] == 0
    assert cli("judge", "--reaction-slack", "0.5", str(late))[0] == 0
    assert cli("judge", "--react-within", "0.2", str(good))[0] == 0


@pytest.mark.parametrize("limit", LIMITS, ids=lambda m: m.key)
def test_cli_has_an_option_for_every_measure(limit: Any, tmp_path: Path) -> None:
    good = write(tmp_path, clean(), "good.jsonl")
    code, _, err = cli("judge", limit.option, "2", "--format", "json", str(good))
    assert code == 0, err


def test_cli_json(tmp_path: Path) -> None:
    late = write(tmp_path, reaction_behind(speech_ends=12.0, reacts_at=12.4))
    code, out, _ = cli("judge", "--format", "json", str(late))
    data = json.loads(out)
    assert code == 1 and data["ok"] is False and data["errors"] == 0
    run = data["runs"][0]
    assert run["counts"]["late"] == 1 and run["counts"]["unheard"] == 0
    assert run["late"][0]["why"].startswith("started after 2.4 s")
    assert run["late"][0]["waits"][0]["rule"] == "uncut: not interruptible"


def test_cli_reports_a_bad_trace_located_without_a_traceback(tmp_path: Path) -> None:
    bad = tmp_path / "bad.jsonl"
    bad.write_text('{"t": 0, "seq": 0, "kind": "pose"}\nnot json\n', encoding="utf-8")
    good = write(tmp_path, clean(), "good.jsonl")
    code, out, err = cli("judge", str(bad), str(good))
    assert code == 1
    assert f"{bad}:2:1: error: not a JSON object" in err and "Traceback" not in err
    assert "good.jsonl" in out  # the other run is judged all the same


@pytest.mark.parametrize("argv, fragment", [
    (["judge", "no/such.jsonl"], "no such file or folder"),
    (["judge", "--max-late", "-1", "x.jsonl"], "--max-late must be a number from 0 up"),
    (["judge", "--silence", "soon", "x.jsonl"], "invalid float value"),
    (["judge", "README.md"], "give a trace (*.jsonl), a scenario (*.xml) or a folder"),
    (["judge", "schemas"], "no scenario in schemas"),
])
def test_cli_usage_errors_exit_2(argv: list[str], fragment: str,
                                 capsys: pytest.CaptureFixture[str],
                                 monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(ROOT)
    code, _, err = cli(*argv)
    assert code == 2
    assert fragment in err + capsys.readouterr().err


def test_cli_judges_a_scenario_in_process_and_writes_nothing(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    code, out, _ = cli("judge", str(THESIS / "fig5-7.xml"))
    assert code == 0 and out.splitlines()[-1].endswith("  ok")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ the pytest fixture

def test_the_prima_judge_fixture(pytester: pytest.Pytester) -> None:
    trace = pytester.path / "late.jsonl"
    rows = reaction_behind(speech_ends=12.0, reacts_at=12.4).rows
    trace.write_text("".join(json.dumps(r) + "\n" for r in rows), encoding="utf-8")
    pytester.makepyfile(test_mine="""
        def test_passes_with_a_looser_threshold(prima_judge):
            report = prima_judge("late.jsonl", max_late=1)
            assert report.counts()["late"] == 1

        def test_fails_with_the_report(prima_judge):
            prima_judge("late.jsonl")
    """)
    result = pytester.runpytest()
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["*late.jsonl: late reactions: 1 > 0*", "*LATE: started after*"])


@pytest.mark.parametrize("scenario", [
    "policies/connect-channel-off.xml", "policies/restore-state-off.xml",
    "policies/streams-off.xml", "examples/barge-in-question.xml", "thesis/sample-08.xml"])
def test_each_finder_is_fed_every_kind_of_line_it_needs(scenario: str,
                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    # A finder is fed only the kinds of line it names; fed every line, it finds the same.
    from prima.run import Run

    lines = Run(ROOT / "scenarios" / scenario).run()
    narrow = judge(lines)
    for m in MEASURES:
        monkeypatch.setattr(type(m.finder()), "kinds", None)
    every = judge(lines)
    assert (every.reactions, dict(every.findings)) == (narrow.reactions, dict(narrow.findings))
    assert any(narrow.findings.values()) or narrow.reactions
