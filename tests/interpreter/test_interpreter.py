"""The interpreter against a recording port: states, handlers, request flags, errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from prima.dsl import check_document, default_profile
from prima.interpreter import AppFailure, Interpreter, Note
from prima.mediator import Event, ManualClock, Outcome, Request, RunningOrder
from prima.vocab import Budgets, TraceKind


class Port:
    """Records what the interpreter asks of the mediator."""

    def __init__(self) -> None:
        self.requests: list[Request] = []
        self.calls: list[tuple[str, object]] = []
        self.next_id = 0

    def submit(self, request: Request) -> tuple[int, ...]:
        self.requests.append(request)
        ids = tuple(range(self.next_id + 1, self.next_id + 1 + len(request.calls)))
        self.next_id += len(request.calls)
        return ids

    def open_stream(self, app: str, hold: float) -> None:
        self.calls.append(("open_stream", hold))

    def close_stream(self, app: str) -> None:
        self.calls.append(("close_stream", None))

    def open_block(self, app: str, *, devices: frozenset[str] | None = None,
                   watchdog: float) -> None:
        self.calls.append(("open_block", (devices, watchdog)))

    def close_block(self, app: str) -> None:
        self.calls.append(("close_block", None))


def make(body: str, kind: str = "fa", tmp: Path | None = None):  # type: ignore[no-untyped-def]
    source = f'<pxml xmlns="urn:prima:pxml:1" kind="{kind}" name="t">{body}</pxml>'.encode()
    document, problems = check_document(source, "t.pxml")
    assert document is not None, [str(p) for p in problems]
    port, clock, notes, sent = Port(), ManualClock(), [], []
    interp = Interpreter(document, "app", port, clock, catalog=default_profile().catalog(),
                         robot_events=default_profile().events, note=notes.append,
                         send=lambda app, to, text: sent.append((to, text)))
    interp.start()
    return interp, port, clock, notes, sent


def texts(port: Port) -> list[list[str]]:
    return [[str(c.args.get("text") or c.args.get("prompt") or c.command) for c in r.calls]
            for r in port.requests]


def test_initial_state_entry_runs_and_variables_initialise() -> None:
    interp, port, *_ = make('<var name="n" expr="2 + 3"/><state id="s" initial="true"><entry>'
                            '<chain>Speak("n is {n}"), Turn(n * 10)</chain></entry></state>')
    [request] = port.requests
    assert [c.command for c in request.calls] == ["Speak", "Turn"]
    assert request.calls[0].args["text"] == "n is 5" and request.calls[1].args["angle"] == 50
    assert not request.reactive and request.follows is None
    assert request.order is RunningOrder.AFTER_LATEST
    assert interp.state == "s"


def test_now_is_the_simulated_time_when_the_expression_runs() -> None:
    """An app schedules by the clock: a reminder 40 s after it learnt of it."""
    interp, port, clock, *_ = make(
        '<var name="due" expr="null"/><state id="s" initial="true">'
        '<on event="message"><assign name="due" expr="now() + 40"/>'
        '<timer name="remind" after="{due - now()}"/></on>'
        '<on event="remind"><chain>Speak("Due at {due} s; now {now()} s.")</chain></on></state>')
    clock.set(7.25)
    interp.event(Event("message", {"sender": "x", "text": "y"}))
    assert interp.variables["due"] == 47.25 and interp.next_deadline() == 47.25
    clock.set(47.25)
    interp.advance()
    assert texts(port) == [["Due at 47.25 s; now 47.25 s."]]


def test_first_request_of_a_reactive_event_is_reactive_and_only_the_first() -> None:
    interp, port, *_ = make(
        '<state id="s" initial="true"><on event="touched"><chain order="asap">StopMoving()</chain>'
        '<goto state="t"/></on></state>'
        '<state id="t"><entry><chain>Speak("second")</chain></entry></state>')
    interp.event(Event("touched"))
    first, second = port.requests
    assert first.reactive and first.order is RunningOrder.ASAP
    assert not second.reactive  # requested in the entry of the state the handling entered
    assert interp.state == "t"


def test_a_goto_ends_its_handler_and_its_entry_however_deep() -> None:
    """A <goto> inside an <if> leaves the handler (or the entry) at once: nothing after
    it runs, in its branch or after the <if>; the state it names is entered, and its
    entry's own <goto> goes on from there."""
    interp, port, *_ = make(
        '<var name="n" expr="0"/>'
        '<state id="s" initial="true"><on event="touched"><if cond="n == 0">'
        '<assign name="n" expr="1"/><goto state="t"/><assign name="n" expr="2"/></if>'
        '<chain>Speak("after the if")</chain></on></state>'
        '<state id="t"><entry><if cond="true"><goto state="u"/></if>'
        '<chain>Speak("in t")</chain></entry></state>'
        '<state id="u"><entry><chain>Speak("in u")</chain></entry></state>')
    interp.event(Event("touched"))
    assert interp.state == "u" and interp.variables["n"] == 1
    assert texts(port) == [["in u"]]


def test_a_touch_is_the_users_own_action_on_any_robot() -> None:
    """docs/rules.md 7.1: the interpreter is given no user events by its robot here, yet
    what it requests while handling a touch is a reaction to the user's own action; a
    perception event's is not."""
    interp, port, *_ = make(
        '<state id="s" initial="true"><on event="touched"><chain>Speak("Hee-hee!")</chain>'
        '</on><on event="human-found"><chain>Speak("Hello.")</chain></on></state>')
    interp.event(Event("touched"))
    interp.event(Event("human-found"))
    touched, found = port.requests
    assert touched.user and touched.reaction
    assert not found.user and found.reaction


def test_handler_can_turn_reactivity_off_and_timers_follow_their_flag() -> None:
    interp, port, clock, *_ = make(
        '<state id="s" initial="true"><entry><timer name="tick" after="5" reactive="true"/>'
        '<timer name="tock" after="7"/></entry>'
        '<on event="message" reactive="false"><chain>Speak("m")</chain></on>'
        '<on event="tick"><chain>Speak("tick")</chain></on>'
        '<on event="tock"><chain>Speak("tock")</chain></on></state>')
    interp.event(Event("message", {"sender": "x", "text": "y"}))
    assert interp.next_deadline() == 5
    clock.set(5)
    interp.advance()
    assert interp.next_deadline() == 7
    clock.set(7)
    interp.advance()
    assert [(r.calls[0].args["text"], r.reactive) for r in port.requests] == [
        ("m", False), ("tick", True), ("tock", False)]
    assert interp.next_deadline() is None


def test_end_event_requests_follow_the_finished_command() -> None:
    interp, port, *_ = make(
        '<state id="s" initial="true"><entry><chain>nav: TopologicalMove(hall)</chain></entry>'
        '<on-end of="nav"><chain>Speak("Here we are, {event.place}.")</chain></on-end></state>')
    [nav_id] = (1,)
    interp.command_ended(nav_id, Outcome({"place": "hall"}))
    request = port.requests[-1]
    assert request.follows == nav_id and not request.reactive
    assert request.calls[0].args["text"] == "Here we are, hall."


@pytest.mark.parametrize("outcome, expected", [
    ({"status": "answered", "utterance": "Prof. Kidode's room"}, "answer kidode-room"),
    ({"status": "answered", "utterance": "the kitchen"}, "nomatch the kitchen"),
    ({"status": "noinput"}, "noinput"),
])
def test_qa_outcomes_dispatch_to_answer_nomatch_noinput(outcome: dict, expected: str) -> None:
    interp, port, *_ = make(
        '<var name="goal"/>'
        '<grammar id="rooms"><choice value="kidode-room">Kidode</choice></grammar>'
        '<state id="s" initial="true"><entry><chain>q: QA("Where?", rooms, goal)</chain></entry>'
        '<on-answer of="q"><log text="answer {goal}"/><chain>Speak("ok")</chain></on-answer>'
        '<on-nomatch of="q"><log text="nomatch {event.utterance}"/></on-nomatch>'
        '<on-noinput of="q"><log text="noinput"/></on-noinput></state>')
    notes: list[Note] = []
    interp._note = notes.append
    interp.command_ended(1, Outcome(outcome))
    assert [n.text for n in notes if n.kind == "log"] == [expected]
    if expected.startswith("answer"):
        assert port.requests[-1].follows == 1


def test_streams_and_blocks_open_and_close_with_their_states() -> None:
    interp, port, *_ = make(
        '<state id="a" initial="true"><on event="touched"><goto state="b"/></on></state>'
        '<stream hold="12"><state id="b"><on event="touched"><goto state="c"/></on></state>'
        '<state id="c"><on event="touched"><goto state="d"/></on></state></stream>'
        '<block watchdog="20" devices="camera">'
        '<state id="d"><on event="touched"><goto state="a"/></on></state></block>')
    for _ in range(4):
        interp.event(Event("touched"))
    assert port.calls == [("open_stream", 12.0), ("close_stream", None),
                          ("open_block", (frozenset({"camera"}), 20.0)), ("close_block", None)]


def test_send_and_raise() -> None:
    interp, port, _c, notes, sent = make(
        '<event name="dance" reactive="true"/>'
        '<state id="s" initial="true"><on event="sound-heard" reactive="false">'
        '<send to="host" text="heard {event.sound}"/><raise event="dance"/></on>'
        '<on event="dance"><chain>Gesture(dance)</chain></on></state>')
    interp.event(Event("sound-heard", {"sound": "tune"}))
    assert sent == [("host", "heard tune")]
    [request] = port.requests
    assert request.calls[0].args["name"] == "dance" and request.reactive


def test_runtime_error_is_recorded_and_stops_the_application() -> None:
    interp, port, _c, notes, _s = make(
        '<var name="n" expr="0"/><state id="s" initial="true">'
        '<on event="touched"><assign name="n" expr="10 / n"/></on></state>')
    with pytest.raises(AppFailure):
        interp.event(Event("touched"))
    [error] = [n for n in notes if n.kind == "error"]
    assert error.text.startswith("t.pxml:1:") and "by zero" in error.text
    interp.event(Event("touched"))  # stopped: ignored, no second error
    assert [n.kind for n in notes].count("error") == 1


def _at(prefix: str, body: str) -> str:
    """Where (in ``make``'s one-line document) the last ``prefix`` in ``body`` starts."""
    head = '<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t">'
    return f"t.pxml:1:{len(head) + body.rindex(prefix) + 1}: "


def test_goto_loop_is_bounded_and_located_at_a_goto_of_the_loop() -> None:
    # (under an <if>, which validation cannot see through: a plain loop is refused there)
    body = ('<state id="a" initial="true"><on event="touched"><goto state="b"/></on></state>'
            '<state id="b"><entry><if cond="true"><goto state="c"/></if></entry></state>'
            '<state id="c"><entry><if cond="true"><goto state="b"/></if></entry></state>')
    interp, *_rest = make(body)
    with pytest.raises(AppFailure) as failure:
        interp.event(Event("touched"))
    where, said = str(failure.value).split("more than 100 state changes")[0], str(failure.value)
    assert where in (_at('<goto state="c"/>', body), _at('<goto state="b"/>', body)), said


def test_number_argument_of_the_wrong_type_is_a_runtime_error() -> None:
    interp, *_rest = make('<var name="a" expr="\'left\'"/><state id="s" initial="true">'
                          '<on event="touched"><chain>Turn({a})</chain></on></state>')
    with pytest.raises(AppFailure, match="Turn 'angle' must be a number"):
        interp.event(Event("touched"))


def test_a_computed_argument_longer_than_the_text_budget_is_a_runtime_error() -> None:
    source = (b'<pxml xmlns="urn:prima:pxml:1" kind="fa" name="t"><var name="a" expr="\'ab\'"/>'
              b'<state id="s" initial="true"><on event="touched"><chain>Speak("{a}{a}{a}")'
              b'</chain></on></state></pxml>')
    document, problems = check_document(source, "t.pxml")
    assert document is not None, [str(p) for p in problems]
    interp = Interpreter(document, "app", Port(), ManualClock(),
                         catalog=default_profile().catalog(), budgets=Budgets(text=5))
    interp.start()
    with pytest.raises(AppFailure, match="Speak 'text' is 6 characters long; the limit is 5"):
        interp.event(Event("touched"))


def test_a_call_gets_the_defaults_of_the_arguments_it_leaves_out_every_time() -> None:
    _i, port, *_ = make('<state id="s" initial="true"><entry><chain>ActiveSensingHuman(), '
                        'ActiveSensingHuman("Here?"), ActiveSensingHuman()</chain></entry>'
                        '</state>')
    assert [c.args for c in port.requests[0].calls] == [
        {"say": "", "turn": 90.0}, {"say": "Here?", "turn": 90.0}, {"say": "", "turn": 90.0}]


def test_active_sensing_passes_its_prompt_and_the_default_turn() -> None:
    _i, port, *_ = make('<state id="s" initial="true"><entry>'
                        '<chain>ActiveSensingHuman("Where are you?"), ActiveSensingHuman()</chain>'
                        '</entry></state>')
    with_prompt, without = port.requests[0].calls
    assert with_prompt.args["say"] == "Where are you?" and without.args["say"] == ""
    assert with_prompt.args["turn"] == 90.0


def test_only_the_first_request_of_an_end_handler_follows_the_ended_command() -> None:
    interp, port, *_ = make(
        '<grammar id="g"><choice>right</choice></grammar>'
        '<state id="s" initial="true"><entry><chain>q: QA("Which way?", g)</chain></entry>'
        '<on-answer of="q"><chain>Turn(-90)</chain><goto state="t"/></on-answer></state>'
        '<state id="t"><entry><chain>QA("May I take a picture?", g)</chain></entry></state>')
    interp.command_ended(1, Outcome({"status": "answered", "utterance": "right"}))
    turn, ask = port.requests[1:]
    assert turn.follows == 1
    assert ask.follows is None and ask.order is RunningOrder.AFTER_LATEST  # after the Turn


def test_a_timer_restarting_itself_at_once_is_bounded_and_located() -> None:
    body = ('<state id="s" initial="true"><entry><timer name="tick" after="1"/></entry>'
            '<on event="tick"><timer name="tick" after="0"/></on></state>')
    interp, port, clock, notes, _s = make(body)
    clock.set(1.0)
    for _ in range(200):  # what the run loop does: advance while a timer is due now
        if interp.next_deadline() is None:
            break
        try:
            interp.advance()
        except AppFailure:
            break
    assert interp.stopped
    [error] = [n.text for n in notes if n.kind == "error"]
    assert error.startswith(_at('<timer name="tick" after="0"/>', body)
                            + "more than 100 timers fired"), error


def test_an_unexpected_exception_becomes_a_located_app_failure() -> None:
    interp, port, *_ = make('<state id="s" initial="true"><on event="touched">'
                            '<chain>Speak("x")</chain></on></state>')

    def explode(_request: object) -> tuple[int, ...]:
        raise RuntimeError("boom")

    port.submit = explode  # type: ignore[method-assign]
    with pytest.raises(AppFailure, match="unexpected error: RuntimeError: boom"):
        interp.event(Event("touched"))
    assert interp.stopped


def test_a_chain_says_whether_its_words_are_for_the_user() -> None:
    """``face-user="false"``: the words are about something else (the connect-channel
    policy leaves the robot as it is); by default they are for the user."""
    _interp, port, *_ = make(
        '<state id="s" initial="true"><entry>'
        '<chain>Speak("Hello.")</chain>'
        '<chain face-user="false">Speak("This panel shows our robot.")</chain>'
        '</entry></state>')
    assert [r.face_user for r in port.requests] == [True, False]


def test_the_state_s_handlers_are_tried_before_the_document_s_each_in_order() -> None:
    interp, _p, _c, notes, _s = make(
        '<var name="n" expr="0"/><event name="e"/>'
        '<on event="e"><log text="document {n}"/></on>'
        '<state id="s" initial="true">'
        '<on event="e" cond="n == 1"><log text="first {n}"/></on>'
        '<on event="e" cond="n &lt; 2"><log text="second {n}"/><assign name="n" expr="n + 1"/>'
        '</on><on event="e" cond="n == 5"><goto state="t"/></on></state>'
        '<state id="t"><on event="e"><log text="in t"/></on></state>')
    for n in (None, None, 2, 5, None):  # None: n as the handlers left it
        if n is not None:
            interp.variables["n"] = n
        interp.event(Event("e"))
    logs = [note.text for note in notes if note.kind is TraceKind.LOG]
    assert logs == ["second 0", "first 1", "document 2", "in t"]
    assert interp.state == "t"
