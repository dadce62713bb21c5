"""The judge: each measure catches its fault, and only its fault.

Each test writes a small trace by hand (:class:`Trace` below) that contains one
fault once, and checks that its count is one and every other count is zero.
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import Any

import pytest

from prima.cli import main
from prima.errors import TraceError
from prima.judge import Report, Thresholds, format_table, judge, judge_file, load_trace

pytest_plugins = ["pytester"]

ROOT = Path(__file__).parents[1]
THESIS = ROOT / "scenarios" / "thesis"

FACING = {"x": 0.0, "y": 0.0, "heading": 0.0}
"""The robot at the origin, facing east."""
USER = {"x": 1.0, "y": 0.0, "heading": 180.0, "detectable": True}
"""The user a metre east of it, facing it."""


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

    def event(self, t: float, name: str) -> None:
        self.line(t, "event", text=name)

    def say(self, t: float, words: str, heard: bool = True) -> None:
        self.line(t, "user", action="say", text=words, detail={"heard": heard})

    def request(self, t: float, app: str, ab: int, cid: int | list[int], *, tree: int = 0,
                command: str = "Speak", text: str | None = None, reactive: bool = False,
                reason: str = "new-tree", devices: tuple[str, ...] = ("speaker",),
                before: int | None = None) -> None:
        ids = cid if isinstance(cid, list) else [cid]
        self.line(t, "request", app=app, ab=ab, tree=tree, command=command, text=text,
                  reactive=reactive, reason=reason, devices=list(devices),
                  command_ids=ids if len(ids) > 1 else None, before=before,
                  detail={"command_id": ids[0]})

    def start(self, t: float, app: str, ab: int, cid: int, *, tree: int = 0,
              command: str = "Speak", text: str | None = None,
              devices: tuple[str, ...] = ("speaker",), iteration: int = 0) -> None:
        detail: dict[str, Any] = {"command_id": cid}
        if iteration:
            detail["iteration"] = iteration
        self.line(t, "start", app=app, ab=ab, tree=tree, command=command, text=text,
                  reason="free-devices", devices=list(devices), detail=detail)

    def end(self, t: float, app: str, ab: int, cid: int, *, tree: int = 0,
            command: str = "Speak", devices: tuple[str, ...] = ("speaker",),
            result: str = "duration=1.0", iteration: int = 0) -> None:
        detail: dict[str, Any] = {"command_id": cid, "result": result}
        if iteration:
            detail["iteration"] = iteration
        self.line(t, "end", app=app, ab=ab, tree=tree, command=command, reason="completed",
                  devices=list(devices), detail=detail)

    def speak(self, t: float, app: str, ab: int, cid: int, words: str, *, lasts: float = 1.0,
              tree: int = 0, request: bool = True) -> None:
        """A Speak requested and started at ``t`` that ends ``lasts`` seconds later."""
        if request:
            self.request(t, app, ab, cid, tree=tree, text=words)
        self.start(t, app, ab, cid, tree=tree, text=words)
        self.end(t + lasts, app, ab, cid, tree=tree)

    def ask(self, t: float, app: str, ab: int, cid: int, prompt: str, answer: str,
            at: float, *, tree: int = 0) -> None:
        """A Q&A requested and started at ``t``, answered with ``answer`` at ``at``."""
        devices = ("speaker", "speech-recognition")
        self.request(t, app, ab, cid, tree=tree, command="QA", text=prompt, devices=devices)
        self.start(t, app, ab, cid, tree=tree, command="QA", text=prompt, devices=devices)
        self.say(at, answer)
        self.end(at, app, ab, cid, tree=tree, command="QA", devices=devices,
                 result=f"status=answered, utterance={answer}")

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
    tr.line(3.0, "user", action="touch")
    tr.event(3.0, "touched")
    tr.request(3.0, "fa", 2, 2, tree=1, command="QA", text="Yes?", reactive=True,
               devices=("speaker", "speech-recognition"))
    tr.start(3.0, "fa", 2, 2, tree=1, command="QA", text="Yes?",
             devices=("speaker", "speech-recognition"))
    tr.say(5.0, "Nothing.")
    tr.end(5.0, "fa", 2, 2, tree=1, command="QA", devices=("speaker", "speech-recognition"),
           result="status=answered, utterance=Nothing.")
    tr.request(5.0, "fa", 3, 3, tree=1, text="O.K.", reason="end-event", before=2)
    tr.start(5.0, "fa", 3, 3, tree=1, text="O.K.")
    tr.end(6.0, "fa", 3, 3, tree=1)
    tr.pose(7.0)
    return tr


def test_a_clean_trace_has_no_fault() -> None:
    report = clean().judge()
    assert counts(report) == {}
    assert report.ok and report.breaches() == []
    assert [(r.event, r.app, r.latency, r.utterance_latency) for r in report.reactions] == [
        ("touched", "fa", 0.0, 0.0), ("speech", "fa", 0.0, 0.0)]
    assert report.reactions[1].text == "Nothing."


# ------------------------------------------------------------------ reactions

def reaction_behind(speech_ends: float, reacts_at: float) -> Trace:
    """ea speaks from 8 s to ``speech_ends``; fa reacts to a touch at 10 s, starting at
    ``reacts_at``."""
    tr = Trace()
    tr.speak(8.0, "ea", 1, 1, "A long sentence.", lasts=speech_ends - 8.0)
    tr.event(10.0, "touched")
    tr.request(10.0, "fa", 2, 2, tree=1, text="Yes?", reactive=True)
    tr.rows.sort(key=lambda r: (r["t"], r["kind"] != "end"))  # the end where it belongs
    for seq, row in enumerate(tr.rows):
        row["seq"] = seq
    tr.start(reacts_at, "fa", 2, 2, tree=1, text="Yes?")
    tr.end(reacts_at + 1.0, "fa", 2, 2, tree=1)
    return tr


def test_a_reaction_may_wait_for_the_residual_and_the_slack() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.2).judge()
    (r,) = report.reactions
    assert (r.event, r.app, r.t, r.residual, r.latency, r.utterance_latency) == (
        "touched", "fa", 10.0, 2.0, 2.2, 2.2)
    assert not r.late and counts(report) == {}


def test_a_reaction_later_than_the_residual_and_the_slack_is_late() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    (r,) = report.reactions
    assert r.late and r.why == "started after 2.4 s (allowed 2.2 s)"
    assert counts(report) == {"late": 1}
    assert report.seqs("late") == [r.seq]
    assert report.breaches() == [f"late reactions: 1 > 0 (seq {r.seq})"]


def test_react_within_replaces_the_residual_rule() -> None:
    tr = reaction_behind(speech_ends=12.0, reacts_at=12.0)
    assert counts(tr.judge()) == {}
    report = tr.judge(react_within=0.2)
    assert counts(report) == {"late": 1}
    assert report.reactions[0].why == "started after 2 s (allowed 0.2 s)"


def test_the_apps_own_running_ab_counts_in_the_residual() -> None:
    """A started AB is never cut, the reacting app's own no more than the other's."""
    tr = Trace()
    tr.speak(8.0, "fa", 1, 1, "My own long sentence.", lasts=4.0)
    tr.event(10.0, "touched")
    tr.request(10.0, "fa", 2, 2, text="Yes?", reactive=True, reason="after-latest", before=1)
    tr.rows.sort(key=lambda r: r["t"])
    for seq, row in enumerate(tr.rows):
        row["seq"] = seq
    tr.speak(12.0, "fa", 2, 2, "Yes?", request=False)
    report = tr.judge()
    assert (report.reactions[0].residual, report.reactions[0].talk_residual) == (2.0, 2.0)
    assert counts(report) == {}


def test_the_reactions_own_first_ab_is_no_residual() -> None:
    tr = Trace()
    tr.event(10.0, "touched")
    tr.speak(10.0, "fa", 1, 1, "Yes?", lasts=3.0)
    tr.rows[1]["reactive"] = True
    [r] = tr.judge().reactions
    assert (r.latency, r.residual, r.talk_residual) == (0.0, 0.0, 0.0)


def test_of_two_reactions_to_one_event_the_second_may_wait_for_the_firsts_ab() -> None:
    """sample-07 swept: the user comes into view and both apps react once the EA's
    utterance under way ends (0.3 s); the FA's words go first (3 s), so the EA's,
    which need the speaker too, wait for them: not late. An AB of the first reaction
    that shares no device with the second is no wait."""
    def found(fa_devices: tuple[str, ...]) -> Report:
        tr = Trace()
        tr.speak(9.0, "ea", 1, 1, "Hm.", lasts=1.3, tree=1)
        tr.event(10.0, "human-found")
        tr.request(10.0, "fa", 2, 2, text="I found you.", reactive=True,
                   devices=fa_devices)
        tr.request(10.0, "ea", 3, 3, text="Here you are.", reactive=True, tree=1)
        tr.rows.sort(key=lambda r: r["t"])
        for seq, row in enumerate(tr.rows):
            row["seq"] = seq
        tr.start(10.3, "fa", 2, 2, text="I found you.", devices=fa_devices)
        tr.end(13.3, "fa", 2, 2, devices=fa_devices)
        tr.start(13.3, "ea", 3, 3, text="Here you are.", tree=1)
        return tr.judge()

    fa, ea = found(("speaker",)).reactions
    assert (fa.residual, ea.latency, ea.residual) == (0.3, 3.3, 3.3)
    assert not ea.late
    _fa, ea = found(("arm",)).reactions
    assert ea.late and ea.residual == 0.3


def _found_then_touched(touched_at: float) -> Report:
    """The EA reacts to human-found at 10 s and waits 0.3 s for its own search
    iteration; the user touches the robot at ``touched_at`` and the FA's reaction (the
    latest) takes the speaker at once for 2.4 s; the EA speaks right after it."""
    tr = Trace()
    tr.start(9.8, "ea", 1, 1, command="ActiveSensingHuman", devices=("locomotion",))
    tr.event(10.0, "human-found")
    tr.request(10.0, "ea", 2, 2, text="Here you are.", reactive=True,
               devices=("speaker", "locomotion"))
    tr.end(10.3, "ea", 1, 1, command="ActiveSensingHuman", devices=("locomotion",))
    tr.event(touched_at, "touched")
    tr.request(touched_at, "fa", 3, 3, text="Hee-hee!", reactive=True, tree=1)
    tr.rows.sort(key=lambda r: r["t"])
    for seq, row in enumerate(tr.rows):
        row["seq"] = seq
    tr.start(touched_at, "fa", 3, 3, text="Hee-hee!", tree=1)
    tr.end(touched_at + 2.4, "fa", 3, 3, tree=1)
    tr.start(touched_at + 2.4, "ea", 2, 2, text="Here you are.",
             devices=("speaker", "locomotion"))
    return tr.judge()


def test_a_later_reaction_of_another_app_goes_first() -> None:
    """sample-08 swept: the touch comes at 10.2 s, while the EA still waits for its
    residual: the FA's reaction goes first (rule 4.2), the EA's words wait for it."""
    ea, fa = _found_then_touched(10.2).reactions
    assert (ea.app, ea.latency, ea.residual, ea.late) == ("ea", 2.6, 2.6, False)
    assert (fa.latency, fa.late) == (0.0, False)


def test_a_later_reaction_does_not_excuse_one_already_late() -> None:
    """The EA could have spoken at 10.3 s (allowed until 10.5 s) but did not; the FA's
    reaction to a touch at 11 s then takes the speaker: the EA's wait is still late."""
    ea, _fa = _found_then_touched(11.0).reactions
    assert (ea.residual, ea.late, ea.why) == (0.3, True, "started after 3.4 s (allowed 0.5 s)")


def test_the_first_utterance_may_wait_for_the_talk_residual() -> None:
    """sample-08: the FA's gesture starts at once on the free arm; its words wait for the
    EA's explanation under way (2 s), then may take the slack and a second more."""
    def touched(speaks_at: float) -> Report:
        tr = Trace()
        tr.speak(8.0, "ea", 1, 1, "A long explanation.", lasts=4.0)
        tr.event(10.0, "touched")
        tr.request(10.0, "fa", 2, [2, 3], tree=1, command="Gesture", reactive=True,
                   devices=("arm",))
        tr.start(10.0, "fa", 2, 2, tree=1, command="Gesture", devices=("arm",))
        tr.rows.sort(key=lambda r: (r["t"], r["kind"] != "end"))
        for seq, row in enumerate(tr.rows):
            row["seq"] = seq
        tr.speak(speaks_at, "fa", 3, 3, "Hee-hee!", tree=1, request=False)
        return tr.judge()

    [r] = touched(speaks_at=13.2).reactions
    assert (r.residual, r.talk_residual, r.latency, r.utterance_latency) == (0.0, 2.0, 0.0, 3.2)
    assert not r.late
    [r] = touched(speaks_at=13.4).reactions
    assert r.late and r.why == "spoke after 3.4 s (allowed 3.2 s)"


def _message_while_moving(turn_starts: float) -> Report:
    """The user's reception EA (its own TopologicalMove iterating, 0.5 s each) answers a
    message with an ASAP Speak; the connect-channel policy puts a FaceHuman before the
    words, and the turn waits for the move's iteration under way (until 70.34)."""
    loco = ("localization", "locomotion")
    turn = ("human-detection", "locomotion")
    tr = Trace()
    tr.start(69.84, "ea", 109, 5, command="TopologicalMove", devices=loco, iteration=101)
    tr.event(70.0, "message")
    tr.request(70.0, "ea", 110, 9, tree=2, text="A message.", reactive=True, reason="asap")
    tr.line(70.0, "request", app="ea", ab=111, tree=2, command="FaceHuman", reactive=True,
            reason="connect-channel", devices=list(turn),
            detail={"command_id": 10, "precedes": 9})
    tr.end(70.34, "ea", 109, 5, command="TopologicalMove", devices=loco, iteration=101)
    tr.start(turn_starts, "ea", 111, 10, tree=2, command="FaceHuman", devices=turn)
    tr.end(turn_starts + 3.04, "ea", 111, 10, tree=2, command="FaceHuman", devices=turn)
    tr.speak(turn_starts + 3.04, "ea", 110, 9, "A message.", tree=2, request=False)
    return tr.judge()


def test_a_policys_turn_before_the_first_command_counts_in_the_residual() -> None:
    """The turn is the reaction's first AB: it waits for what runs on its wheels (the
    app's own move iteration, never cut), not only for what runs on the speaker its
    first request names. The words wait for the turn: its end is their talk residual."""
    [r] = _message_while_moving(turn_starts=70.34).reactions
    assert (r.latency, r.residual, r.utterance_latency, r.talk_residual) == (
        0.34, 0.34, 3.38, 3.38)
    assert set(r.devices) == {"speaker", "human-detection", "locomotion"}
    assert not r.late
    [r] = _message_while_moving(turn_starts=70.6).reactions  # the wheels free since 70.34
    assert r.late and r.why == "started after 0.6 s (allowed 0.54 s)"


def test_a_policys_turn_requested_later_waits_for_what_runs_then() -> None:
    """The words are ready only when another app's sentence ends (2 s): the turn put
    before them then waits for the app's own search look under way (0.3 s more).
    Nothing ran on the wheels at the event; what runs there when the turn is put in
    line counts, while the reaction is not yet late."""
    def touched(ready: float) -> Report:
        """The turn is put in line at ``ready``; the look under way ends 0.3 s later."""
        turn = ("human-detection", "locomotion")
        tr = Trace()
        tr.speak(8.0, "ea", 1, 1, "A long explanation.", lasts=4.0, tree=1)
        tr.event(10.0, "touched")
        tr.request(10.0, "fa", 2, 2, tree=2, text="Hee-hee!", reactive=True)
        tr.start(ready - 0.2, "fa", 3, 3, command="ActiveSensingHuman", devices=turn)
        tr.rows.sort(key=lambda r: r["t"])
        for seq, row in enumerate(tr.rows):
            row["seq"] = seq
        tr.line(ready, "request", app="fa", ab=4, tree=2, command="FaceHuman",
                reactive=True, reason="connect-channel", devices=list(turn),
                detail={"command_id": 4, "precedes": 2})
        tr.end(ready + 0.3, "fa", 3, 3, command="ActiveSensingHuman", devices=turn)
        tr.start(ready + 0.3, "fa", 4, 4, tree=2, command="FaceHuman", devices=turn)
        tr.end(ready + 1.3, "fa", 4, 4, tree=2, command="FaceHuman", devices=turn)
        tr.speak(ready + 1.3, "fa", 2, 2, "Hee-hee!", tree=2, request=False)
        return tr.judge()

    [r] = touched(ready=12.0).reactions
    assert (r.residual, r.latency, r.talk_residual, r.late) == (2.3, 2.3, 3.3, False)
    # put in line at 12.5 s, past the bound (12.2 s): what runs then is no excuse
    [r] = touched(ready=12.5).reactions
    assert (r.residual, r.latency, r.late) == (2.0, 2.8, True)


def test_a_turn_after_the_first_utterance_does_not_excuse_it() -> None:
    """A reaction waves at once and says two sentences; its first words come 2 s late.
    The policy's turn before its second sentence is no wait of the first one."""
    turn = ("human-detection", "locomotion")
    tr = Trace()
    tr.event(10.0, "touched")
    tr.request(10.0, "fa", 1, [1, 2, 3], command="Gesture", reactive=True,
               devices=("arm",))
    tr.start(10.0, "fa", 1, 1, command="Gesture", devices=("arm",))
    tr.end(11.0, "fa", 1, 1, command="Gesture", devices=("arm",))
    tr.speak(12.0, "fa", 2, 2, "Hello.", request=False)
    tr.line(13.0, "request", app="fa", ab=4, command="FaceHuman", reactive=True,
            reason="connect-channel", devices=list(turn),
            detail={"command_id": 4, "precedes": 3})
    tr.start(13.0, "fa", 4, 4, command="FaceHuman", devices=turn)
    tr.end(16.0, "fa", 4, 4, command="FaceHuman", devices=turn)
    tr.speak(16.0, "fa", 3, 3, "Nice to see you.", request=False)
    [r] = tr.judge().reactions
    assert (r.talk_residual, r.utterance_latency) == (0.0, 2.0)
    assert r.late and r.why == "spoke after 2 s (allowed 1.2 s)"


def test_the_robot_arriving_somewhere_is_no_reaction_to_measure() -> None:
    tr = Trace()
    tr.event(10.0, "place-reached")
    tr.request(10.0, "ea", 1, 1, command="SetDirection", reactive=True, devices=("locomotion",))
    tr.start(10.0, "ea", 1, 1, command="SetDirection", devices=("locomotion",))
    tr.end(11.5, "ea", 1, 1, command="SetDirection", devices=("locomotion",))
    tr.speak(11.5, "ea", 2, 2, "Here is the book you searched for.")
    report = tr.judge()
    assert report.reactions == () and counts(report) == {}


def test_a_reaction_that_never_starts_is_late() -> None:
    tr = Trace()
    tr.event(1.0, "touched")
    tr.request(1.0, "fa", 1, 1, text="Yes?", reactive=True)
    tr.pose(5.0)
    report = tr.judge()
    (r,) = report.reactions
    assert (r.latency, r.late, r.why) == (None, True, "never started")
    assert counts(report) == {"late": 1}
    assert report.worst_lateness() == float("inf")


def test_a_reactions_first_utterance_may_come_a_second_later() -> None:
    tr = Trace()
    tr.event(1.0, "message")
    tr.request(1.0, "ea", 1, [1, 2], command="StopMoving", text="A message.", reactive=True,
               reason="asap", devices=("locomotion",))
    tr.start(1.0, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
    tr.end(1.0, "ea", 1, 1, command="StopMoving", devices=("locomotion",))
    tr.speak(2.2, "ea", 2, 2, "A message.", request=False)
    report = tr.judge()
    assert (report.reactions[0].latency, report.reactions[0].utterance_latency) == (0.0, 1.2)
    assert counts(report) == {}
    tr.rows[-2]["t"] = tr.rows[-3]["t"] = 2.3  # the utterance 0.1 s later
    report = tr.judge()
    assert report.reactions[0].why == "spoke after 1.3 s (allowed 1.2 s)"
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
    assert counts(report) == {}


def test_heard_speech_is_a_reaction_of_the_app_that_asked() -> None:
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Which book?", "The C Primer.", at=3.0)
    tr.request(3.0, "ea", 2, 2, text="Wait a minute.", reason="end-event", before=1)
    tr.speak(3.5, "ea", 2, 2, "Wait a minute.", request=False)
    report = tr.judge()
    (r,) = report.reactions
    assert (r.event, r.app, r.text, r.t, r.latency) == ("speech", "ea", "The C Primer.", 3.0, 0.5)
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


# ------------------------------------------------------------------ talking unfaced

def test_words_after_an_aiming_command_are_about_what_it_aims_at() -> None:
    """FA4 turns the way its user said, then asks "May I take a picture?": the words
    are about what the robot aims at, not unfaced; after a Gesture they are."""
    def after(command: str) -> int:
        tr = Trace()
        tr.user = {"x": 0.0, "y": 1.0, "heading": 0.0, "detectable": True}
        tr.start(0.0, "fa", 1, 1, command=command, devices=("locomotion",))
        tr.end(1.0, "fa", 1, 1, command=command, devices=("locomotion",))
        tr.start(1.0, "fa", 2, 2, text="May I take a picture?")
        tr.end(2.0, "fa", 2, 2)
        return len(tr.judge().unfaced)

    assert (after("Turn"), after("Gesture")) == (0, 1)


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
    tr.request(1.0, "fa", 1, 1, command=command, text="Hello.", devices=devices)
    tr.start(1.0, "fa", 1, 1, command=command, text="Hello.", devices=devices)
    tr.end(2.0, "fa", 1, 1, command=command, devices=devices)
    report = tr.judge()
    assert counts(report) == ({"unfaced": 1} if found else {})
    if found:
        (u,) = report.unfaced
        assert (u.seq, u.app, u.command, u.text) == (1, "fa", command, "Hello.")
        assert u.off > 30


def test_a_motion_with_no_words_is_not_talking() -> None:
    tr = Trace()
    tr.user = {"x": 0.0, "y": 1.0, "heading": 0.0, "detectable": True}
    tr.request(1.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    tr.start(1.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    tr.end(2.0, "fa", 1, 1, command="Turn", devices=("locomotion",))
    assert counts(tr.judge()) == {}


# ------------------------------------------------------------------ leaving while talking

def test_leaving_while_talking_counts_once_per_utterance() -> None:
    tr = Trace()
    tr.request(1.0, "ea", 1, 1, text="Come on.")
    tr.start(1.0, "ea", 1, 1, text="Come on.")
    for t, x in ((1.5, -0.2), (2.0, -0.4), (2.5, -0.6)):
        tr.robot = {"x": x, "y": 0.0, "heading": 0.0}
        tr.pose(t)
    tr.end(3.0, "ea", 1, 1)
    report = tr.judge()
    assert counts(report) == {"leaving": 1}
    (x,) = report.leaving
    assert (x.seq, x.at_seq, x.away) == (1, 3, 0.4)


def test_the_user_walking_away_is_not_the_robot_leaving() -> None:
    tr = Trace()
    tr.request(1.0, "ea", 1, 1, text="Come on.")
    tr.start(1.0, "ea", 1, 1, text="Come on.")
    tr.user = {**USER, "x": 3.0}
    tr.pose(2.0)
    tr.end(3.0, "ea", 1, 1)
    assert counts(tr.judge()) == {}


def test_moving_after_the_utterance_is_not_leaving_while_talking() -> None:
    tr = Trace()
    tr.speak(1.0, "ea", 1, 1, "Bye.")
    tr.robot = {"x": -2.0, "y": 0.0, "heading": 0.0}
    tr.pose(3.0)
    assert counts(tr.judge()) == {}


# ------------------------------------------------------------------ resumed elsewhere

@pytest.mark.parametrize("case, found", [
    ("here", 0),          # back where it was suspended before it speaks
    ("away", 1),          # resumes 2 m from there
    ("travels", 0),       # it resumed going somewhere of its own
    ("restored", 0),      # the restore-state policy's return took it back
    ("speaks-first", 1),  # the resume line follows the utterance's own start line
])
def test_resumed_elsewhere(case: str, found: int) -> None:
    """A suspended stream's first utterance after it resumes counts only when the
    robot is farther than 0.3 m from where it was when the stream was suspended
    and the stream did not itself go somewhere."""
    tr = Trace()
    tr.user = {**tr.user, "detectable": False}  # (not a matter of facing)
    tr.pose(0.5)
    tr.line(1.0, "suspend", app="ea", ab=2, tree=0, command="Speak", reason="reactivity")
    tr.robot = {**tr.robot, "x": 2.0}  # the other app's reaction moved the robot
    tr.pose(5.0)
    if case == "speaks-first":
        tr.start(6.0, "ea", 2, 2, text="Look at this figure.")
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
        tr.start(9.0, "ea", 2, 2, text="Look at this figure.")
        tr.end(10.0, "ea", 2, 2)
    report = tr.judge()
    assert counts(report) == ({"elsewhere": 1} if found else {})
    if found:
        (e,) = report.elsewhere
        assert (e.app, e.text, e.suspend_seq, e.away) == ("ea", "Look at this figure.", 1, 2.0)
        assert "from where its stream was suspended (seq 1)" in format_table([report])


# ------------------------------------------------------------------ split exchanges

def test_another_apps_utterance_between_an_answer_and_the_reply_splits_it() -> None:
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Which book?", "The C Primer.", at=3.0)
    tr.request(3.0, "ea", 2, 2, text="Wait a minute.", reason="end-event", before=1)
    tr.speak(3.0, "fa", 3, 3, "The video is set.", tree=1)
    tr.speak(4.0, "ea", 2, 2, "Wait a minute.", request=False)
    report = tr.judge()
    assert counts(report) == {"splits": 1}
    assert report.reactions[0].residual == 1.0  # fa's utterance, started the same instant
    (s,) = report.splits
    assert (s.kind, s.app, s.by, s.text, s.t) == ("answer", "ea", "fa", "The video is set.", 3.0)
    assert s.anchor_seq == 3  # the answered Q&A's end line


def test_no_reply_no_split() -> None:
    tr = Trace()
    tr.ask(0.0, "ea", 1, 1, "Which book?", "The C Primer.", at=3.0)
    tr.speak(3.0, "fa", 3, 3, "The video is set.", tree=1)
    assert counts(tr.judge()) == {}


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
    (s,) = report.splits
    assert (s.kind, s.app, s.by, s.anchor_seq) == ("stream", "fa", "ea", 0)


def test_a_reaction_may_speak_inside_another_apps_stream() -> None:
    tr = Trace()
    tr.line(1.0, "stream", app="fa", text="open", detail={"id": "video"})
    tr.event(2.0, "touched")
    tr.request(2.0, "ea", 2, 2, text="Yes?", reactive=True, tree=1)
    tr.speak(2.0, "ea", 2, 2, "Yes?", tree=1, request=False)
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
    assert (report.silences[0].seq, report.silences[0].gap) == (3, 2.5)
    assert counts(answered_then(reply_at=3.9, ends=8.0).judge(reaction_slack=5.0)) == {}


def test_no_output_until_the_end_is_a_silence_only_if_the_end_is_far() -> None:
    report = answered_then(reply_at=99.0, ends=4.5).judge()
    assert counts(report) == {"silences": 1} and report.silences[0].gap is None
    assert counts(answered_then(reply_at=99.0, ends=3.5).judge()) == {}


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
    (s,) = report.stuck
    assert (s.app, s.kind, s.t, s.since, s.command_id, s.seq) == ("fa", "loop", 60.0, 0.0, 2, 0)
    assert counts(search_loop(until=60.0).judge()) == {}  # 60 s, not more


def test_the_loop_must_run_back_to_back_for_the_whole_wait() -> None:
    """A pause in the search (its next iteration waited 5 s) starts the 60 s afresh."""
    tr = search_loop(until=110.0)
    for row in tr.rows:
        if row["t"] >= 30.0 and not (row["kind"] == "end" and row["t"] == 30.0):
            row["t"] += 5.0  # iterations from the 4th on start at 35, 45, ...
    report = tr.judge()
    assert [(s.kind, s.t) for s in report.stuck] == [("loop", 95.0)]
    tr.rows = [r for r in tr.rows if r["t"] <= 95.0]
    assert [(s.kind, s.t) for s in tr.judge().stuck] == [("end", 60.0)]


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
    (s,) = report.stuck
    assert (s.app, s.kind, s.t, s.since, s.command_id) == ("fa", "search", 90.0, 0.0, 1)
    assert counts(lone_search(until=90.0).judge()) == {}  # 90 s, not more
    assert counts(lone_search(until=70.0).judge(search_after=60)) == {"stuck": 1}


def test_a_sight_of_the_user_starts_the_search_afresh() -> None:
    assert counts(lone_search(until=115.0, seen_at=30.0).judge()) == {}
    [s] = lone_search(until=125.0, seen_at=30.0).judge().stuck
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
    (s,) = report.stuck
    assert (s.app, s.kind, s.t, s.command_id) == ("ea", "end", 60.0, 2)
    assert counts(search_loop(until=50.0, other_app=True).judge()) == {}


def test_a_cancelled_command_is_not_waiting() -> None:
    tr = search_loop(until=80.0, other_app=True)
    tr.line(5.0, "cancel", app="ea", ab=100, command="Speak", reason="asap",
            detail={"command_id": 2})
    tr.rows.sort(key=lambda r: r["t"])
    assert counts(tr.judge()) == {}


def test_an_unloaded_app_is_not_stuck() -> None:
    tr = search_loop(until=80.0, other_app=True)
    tr.line(80.0, "unload", app="ea", reason="unload")
    assert counts(tr.judge()) == {}


# ------------------------------------------------------------------ thresholds and reports

def test_thresholds_allow_what_they_say() -> None:
    tr = reaction_behind(speech_ends=12.0, reacts_at=12.4)
    assert not tr.judge().ok
    assert tr.judge(max_late=1).ok
    assert tr.judge(reaction_slack=0.5).ok


@pytest.mark.parametrize("bad", [{"max_late": -1}, {"silence": float("nan")},
                                 {"max_splits": 1.5}, {"leave_distance": "far"}])
def test_bad_thresholds_are_refused(bad: dict[str, Any]) -> None:
    with pytest.raises(ValueError):
        Thresholds(**bad)


def test_report_dict_has_stable_keys_and_is_json() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    d = report.to_dict()
    assert list(d) == ["name", "end", "lines", "thresholds", "counts", "reactions", "late",
                       "unfaced", "leaving", "elsewhere", "splits", "silences", "stuck",
                       "breaches", "ok"]
    assert d["counts"] == {"reactions": 1, "late": 1, "unfaced": 0, "leaving": 0,
                           "elsewhere": 0, "splits": 0, "silences": 0, "stuck": 0}
    assert json.loads(json.dumps(d)) == d


def test_the_table_shows_reactions_counts_and_a_summary() -> None:
    report = reaction_behind(speech_ends=12.0, reacts_at=12.4).judge()
    table = format_table([report])
    assert "touched" in table and "LATE: started after 2.4 s (allowed 2.2 s)" in table
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

def test_sample_05_has_exactly_its_split_exchange() -> None:
    report = judge_file(THESIS / "sample-05.xml")
    (s,) = report.splits
    assert (s.kind, s.app, s.by, s.text, s.t) == (
        "answer", "ea2-library", "fa5-video-timer", "The video setting succeeds.", 40.8)
    answered = next(r for r in report.reactions if r.text == "The C Primer.")
    assert answered.t == 40.8 and answered.app == "ea2-library"
    assert s.anchor_seq < s.seq < answered.first_start_seq  # answer, FA5, EA2's reply


def test_sample_05_with_an_explicit_stream_has_none() -> None:
    report = judge_file(THESIS / "sample-05-stream.xml")
    assert report.splits == ()


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


def test_cli_json(tmp_path: Path) -> None:
    late = write(tmp_path, reaction_behind(speech_ends=12.0, reacts_at=12.4))
    code, out, _ = cli("judge", "--format", "json", str(late))
    data = json.loads(out)
    assert code == 1 and data["ok"] is False and data["errors"] == 0
    assert data["runs"][0]["counts"]["late"] == 1


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
