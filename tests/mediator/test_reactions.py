"""docs/rules.md 7.1 and 7.2: a reaction takes over as a stream; a stream hold never
splits a question from its reply, nor holds back a reaction."""

from __future__ import annotations

from prima.catalog import Catalog
from prima.mediator import AppKind, DecisionKind, Event, Outcome, Request, Rule
from prima.mediator.testing import Harness, feedback_iterations
from prima.vocab import OnInterrupt
from tests.mediator.helpers import call, req, speak


def starts(h: Harness) -> list[tuple[float, str, str]]:
    return [(d.t, d.app or "", d.command or "") for d in h.starts()]


def start_of(h: Harness, app: str, text: str) -> float:
    return next(d.t for d in h.starts()
                if d.app == app and d.calls and d.calls[0].args.get("text") == text)


def dialogue(h: Harness, app: str, turns: int) -> None:
    """``app`` talks on and on: each utterance follows the last one's end (rule 6a)."""
    m = h.mediator
    count = [0]

    def more(cid: int, _o: Outcome) -> None:
        if count[0] < turns:
            count[0] += 1
            m.submit(Request(app, (speak(f"and then {count[0]}"),), follows=cid))

    h.app(app, AppKind.EA, on_ended=more)


def test_a_reaction_keeps_its_precedence_after_its_first_command() -> None:
    """7.1: the reaction's first Command (a StopMoving on free wheels) starts at once;
    its speech must still take over at the EA's next IU boundary, not wait for the
    EA's whole dialogue (sample-04: the host's message waited 13.7 s)."""
    h = Harness(duration={"StopMoving": 0.2, "*": 2.0})
    m = h.mediator
    dialogue(h, "ea", turns=10)

    def react(_e: Event) -> None:
        m.submit(Request("fa", (call("StopMoving"), speak("What's the matter?")),
                         reactive=True, reaction=True))

    h.app("fa", AppKind.FA, on_event=react)
    m.submit(req("ea", speak("let me explain")))
    h.at(3.0, lambda: m.post(Event("touched")))
    h.run(until=60.0)
    assert start_of(h, "fa", "What's the matter?") == 4.0  # the EA's utterance under way ends
    assert start_of(h, "ea", "and then 2") > 4.0


def test_what_a_reaction_chains_from_its_end_handlers_keeps_its_precedence() -> None:
    """7.1: the reaction's Q&A (1-5 s) is answered while the EA looks around (head moves
    on the neck, each following the last); the nod the reaction chains from its answer
    needs the neck. When the EA's head move under way ends (6 s), the EA's next one
    'just had its parent finish', yet the reaction's nod takes the neck."""
    h = Harness(duration={"QA": 4.0, "Gesture": 1.0, "MoveHead": 2.0})
    m = h.mediator
    asked: list[int] = []

    def look_again(cid: int, _o: Outcome) -> None:
        m.submit(Request("ea", (call("MoveHead", pan=10.0),), follows=cid))

    def react(_e: Event) -> None:
        asked.extend(m.submit(Request("fa", (call("QA", prompt="What?", grammar="g"),),
                                      reactive=True, reaction=True)))

    def nod(cid: int, _o: Outcome) -> None:
        if cid in asked:
            m.submit(Request("fa", (call("Gesture", name="nod"),), follows=cid))

    h.app("ea", AppKind.EA, on_ended=look_again)
    h.app("fa", AppKind.FA, on_event=react, on_ended=nod)
    m.submit(req("ea", call("MoveHead", pan=10.0)))
    h.at(1.0, lambda: m.post(Event("touched")))
    h.run(until=9.0)
    assert [(t, app, c) for t, app, c in starts(h) if 5.0 <= t < 7.0] == [
        (6.0, "fa", "Gesture")]


def test_of_two_reactions_the_latest_wins() -> None:
    h = Harness(duration=2.0)
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(req("ea", speak("busy")))                                       # 0-2
    m.submit(Request("fa", (speak("first reaction"), speak("first, more")),
                     reactive=True, reaction=True))
    m.submit(Request("ea", (speak("second reaction"), speak("second, more")),
                     reactive=True, reaction=True))
    h.run(until=20.0)
    order = [d.calls[0].args["text"] for d in h.starts()]
    assert order == ["busy", "second reaction", "second, more", "first reaction",
                     "first, more"]


def test_a_stream_hold_never_splits_a_question_from_its_reply() -> None:
    """7.2: the EA's Q&A was asked before the FA's stream hold armed (on the arm and
    the neck its gesture used); the EA's reply to the answer (a nod, then words)
    continues the EA's stream under way: the hold does not delay it."""
    h = Harness(duration={"QA": 4.0, "*": 1.0})
    m = h.mediator
    asked: list[int] = []

    def reply(cid: int, _o: Outcome) -> None:
        if cid in asked:
            m.submit(Request("ea", (call("Gesture", name="nod"), speak("Here it is.")),
                             follows=cid))

    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA, on_ended=reply)
    asked.extend(m.submit(req("ea", call("QA", prompt="Which book?", grammar="g"))))  # 0-4
    m.open_stream("fa", hold=20.0)
    m.submit(req("fa", call("Gesture", name="wave")))  # 0-1; then the FA waits: hold on
    h.run(until=60.0)
    assert next(d.t for d in h.starts() if d.app == "ea" and d.command == "Gesture") == 4.0
    assert h.mediator.snapshot().holds == ()  # (its hold timed out at 21 s, long after)


def test_a_stream_hold_never_holds_back_a_reaction_past_its_first_command() -> None:
    """7.2: every AB of the reaction passes the hold, not only its first."""
    h = Harness(duration=1.0)
    m = h.mediator
    h.app("fa", AppKind.FA)

    def react(_e: Event) -> None:
        m.submit(Request("ea", (call("Gesture", name="nod"), speak("A message for you.")),
                         reactive=True, reaction=True))

    h.app("ea", AppKind.EA, on_event=react)
    m.open_stream("fa", hold=20.0)
    m.submit(req("fa", speak("Connecting...")))  # 0-1, then the FA waits: the hold arms
    h.at(2.0, lambda: m.post(Event("message")))
    h.run(until=60.0)
    assert start_of(h, "ea", "A message for you.") == 3.0


def test_a_stream_hold_still_delays_the_other_apps_new_stream() -> None:
    h = Harness(duration=1.0)
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.open_stream("fa", hold=10.0)
    m.submit(req("fa", speak("Connecting...")))   # 0-1; then the hold arms until 11
    h.at(2.0, lambda: m.submit(req("ea", speak("Please tell me a title."))))
    h.run(until=60.0)
    assert start_of(h, "ea", "Please tell me a title.") == 11.0


def test_a_reaction_behind_a_held_ab_takes_it_along() -> None:
    """7.1 and 7.2 (found by the random driver): the EA's new stream is held by the FA's
    stream hold; a reaction the EA then requests joins that stream (after its latest),
    so the whole tree becomes a reaction and the held AB goes at once, the reaction
    right after it, instead of both waiting out the hold."""
    h = Harness(duration=1.0)
    m = h.mediator
    h.app("fa", AppKind.FA)

    def react(e: Event) -> None:
        if e.name == "message":  # (not the news that its AB is held)
            m.submit(Request("ea", (speak("A message for you."),), reactive=True,
                             reaction=True))

    h.app("ea", AppKind.EA, on_event=react)
    m.open_stream("fa", hold=20.0)
    m.submit(req("fa", speak("Connecting...")))  # 0-1, then the FA waits: the hold arms
    h.at(2.0, lambda: m.submit(req("ea", speak("Welcome."))))  # held: a new stream
    h.at(3.0, lambda: m.post(Event("message")))
    h.run(until=60.0)
    assert start_of(h, "ea", "Welcome.") == 3.0
    assert start_of(h, "ea", "A message for you.") == 4.0


def test_a_stream_hold_delays_the_resumption_of_a_suspended_stream() -> None:
    """7.2 and Fig. 5.9's fix (sample-05-stream): the EA's dialogue was suspended by the
    FA's reaction; while the FA waits inside its explicit stream (for the video server),
    the EA resuming its dialogue would take the floor anew, so the hold delays it."""
    h = Harness(duration=1.0)
    m = h.mediator
    h.app("ea", AppKind.EA)

    def react(_e: Event) -> None:
        m.open_stream("fa", hold=10.0)
        m.submit(Request("fa", (speak("Connecting the video server."),), reactive=True,
                         reaction=True))

    h.app("fa", AppKind.FA, on_event=react)
    m.submit(req("ea", speak("Please tell me"), speak("a title.")))  # 0-1, 1-2 ...
    h.at(0.5, lambda: m.post(Event("touched")))  # the FA's reaction suspends it at 1
    h.run(until=60.0)
    assert start_of(h, "fa", "Connecting the video server.") == 1.0
    assert start_of(h, "ea", "a title.") == 12.0  # the hold armed at 2 for 10 s


def test_a_hold_says_why_an_ab_kept_for_a_later_reactions_loop_waits_on() -> None:
    """7.1 and 7.5: ea's reaction (its words, then a FaceHumanAndSpeak) loses the speaker
    to fa's later reaction ("I found you.", then following the user); ea's
    FaceHumanAndSpeak is held for fa's TrackingHuman, its next AB (``reserved``). When the
    TrackingHuman starts, that hold is over, yet its iterations go on winning the wheels
    for as long as fa's reaction is in working memory: a hold line says so, once, with
    the rule that put them first, and ea is told it is held."""
    h = Harness(Catalog.standard().interruptible(["Speak"]),
                duration={"Speak": 2.0, "TrackingHuman": 0.5, "*": 1.0},
                outcome=feedback_iterations(1000))
    m = h.mediator
    events: list[Event] = []
    h.app("ea", AppKind.EA, on_event=events.append)
    h.app("fa", AppKind.FA)
    m.submit(Request("ea", (speak("Oh."), call("FaceHumanAndSpeak", text="There you are.")),
                     reactive=True, reaction=True, on_interrupt=OnInterrupt.NEVER))
    h.at(0.5, lambda: m.submit(Request("fa", (speak("I found you."), call("TrackingHuman")),
                                       reactive=True, reaction=True)))
    h.run(until=20.0)
    holds = [(d.t, d.app, d.command, d.rule, d.before) for d in h.kinds(DecisionKind.HOLD)]
    track = next(d.ab for d in h.starts() if d.command == "TrackingHuman")
    assert holds == [(2.0, "ea", "FaceHumanAndSpeak", Rule.RESERVED, track),
                     (4.0, "ea", "FaceHumanAndSpeak", Rule.REACTIVITY, track)]
    assert "FaceHumanAndSpeak" not in [d.command for d in h.starts()]
    assert [(e.data["by"], e.data["rule"]) for e in events if e.name == "held"] == [
        ("fa", "reserved"), ("fa", "reactivity")]
