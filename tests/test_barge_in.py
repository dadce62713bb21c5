"""The user's voice (docs/rules.md 7.5): speech heard at any time, always-on grammars and
which application takes the words, barge-in and backchannels, restart/resume/drop of
what the user cut, false interruptions, news of a stream, and the judge's measures.

Each test runs a small scenario on the home robot (which hears at any time) with a
talking EA beside an FA, and reads the trace."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from prima.catalog import Catalog
from prima.judge import Thresholds, judge
from prima.mediator import (
    AppKind,
    Call,
    Event,
    MediatorConfig,
    Outcome,
    Request,
    RunningOrder,
)
from prima.mediator.testing import Harness
from prima.run import Run
from prima.trace import TraceLine

ROOT = Path(__file__).resolve().parents[1]

TALK = ("One two three four five six. Seven eight nine ten eleven twelve. "
        "Thirteen fourteen fifteen sixteen.")
"""16 words: 6.4 s at the home robot's 2.5 words per second (a word every 0.4 s)."""

EA = """<?xml version="1.0" encoding="UTF-8"?>
<pxml xmlns="urn:prima:pxml:1" kind="ea" name="guide">
  <grammar id="places"><choice value="toilet">toilet | restroom</choice></grammar>
  <grammar id="stop"><choice value="stop">stop | be quiet</choice></grammar>
  <on event="speech" match="places">
    <log text="took {event.words} as {event.answer}"/>
    <chain>Speak("Next to the door.")</chain>
  </on>
  <on event="speech" match="stop"><chain order="asap">Speak("All right.")</chain></on>
  <on event="interrupted"><log text="cut by {event.by}: {event.reason} {event.resumes}"/></on>
  <on event="nomatch"><log text="nobody took {event.words}"/></on>
  <state id="talk" initial="true">
    <entry><chain INTERRUPT>talk: Speak("TALK")</chain>ASK</entry>
  </state>
</pxml>
"""

FA = """<?xml version="1.0" encoding="UTF-8"?>
<pxml xmlns="urn:prima:pxml:1" kind="fa" name="home">
  <grammar id="name"><choice value="me">papero</choice></grammar>
  <on event="speech" match="name"><chain>Speak("Yes?")</chain></on>
  SUSPENDED
  <state id="calm" initial="true"/>
</pxml>
"""

SCENARIO = """<?xml version="1.0" encoding="UTF-8"?>
<scenario xmlns="urn:prima:scenario:1" name="t" until="30" seed="1">
  <map href="{root}/scenarios/maps/office.xml"/>
  <apps fa="{fa}" ea="{ea}"/>
  <robot x="3" y="3" heading="0"/>
  POLICY
  <user x="4.2" y="3" heading="180">{user}</user>
</scenario>
"""


def run(tmp_path: Path, user: str, *, interrupt: str = "", ask: str = "", policy: str = "",
        suspended: str = "", profile: str = "", grammars: str = "") -> list[TraceLine]:
    ea = tmp_path / "guide.pxml"
    ea.write_text(EA.replace("INTERRUPT", interrupt).replace("TALK", TALK)
                  .replace("ASK", ask)
                  .replace('<grammar id="stop">', grammars + '<grammar id="stop">'))
    fa = tmp_path / "home.pxml"
    fa.write_text(FA.replace("SUSPENDED", suspended))
    scenario = tmp_path / "s.xml"
    text = SCENARIO.format(root=ROOT, fa=fa, ea=ea, user=user).replace("POLICY", policy)
    if profile:
        text = text.replace('<robot x="3"', f'<robot profile="{profile}" x="3"')
    scenario.write_text(text)
    return Run(scenario).run()


def lines(trace: list[TraceLine], kind: str, reason: str | None = None) -> list[TraceLine]:
    return [x for x in trace if x.kind.value == kind and (reason is None or x.reason == reason)]


def logs(trace: list[TraceLine]) -> list[str]:
    return [str(x.text) for x in trace if x.kind.value == "log"]


def starts(trace: list[TraceLine], app: str) -> list[TraceLine]:
    return [x for x in lines(trace, "start") if x.app == app]


# ---------------------------------------------------------------- 1. speech at any time

def test_speech_outside_a_qa_is_an_event_for_the_app_whose_grammar_takes_it(
        tmp_path: Path) -> None:
    trace = run(tmp_path, '<say at="2" text="Excuse me, where is the restroom?"/>')
    heard = lines(trace, "event")
    assert [e.text for e in heard if e.text == "speech"] == ["speech"]
    (hear,) = lines(trace, "hear")
    assert (hear.app, hear.reason) == ("guide", "stream-runs")
    assert "took Excuse me, where is the restroom? as toilet" in logs(trace)
    reply = next(x for x in starts(trace, "guide") if x.text == "Next to the door.")
    assert reply.t < 2 + 0.4 + 1.0


def test_a_robot_that_hears_only_in_its_qas_does_not_hear_speech_outside_them(
        tmp_path: Path) -> None:
    trace = run(tmp_path, '<say at="2" text="Where is the restroom?"/>',
                policy='<policy name="barge-in" state="off"/>')
    (said,) = lines(trace, "user")
    assert said.detail.get("heard") is False
    assert not lines(trace, "hear") and not lines(trace, "interrupt")
    assert [x.text for x in starts(trace, "guide")] == [TALK]


def test_the_robots_own_words_are_never_heard_as_the_users(tmp_path: Path) -> None:
    trace = run(tmp_path, "")
    assert starts(trace, "guide")  # it talked all along, and heard nothing
    assert not [e for e in lines(trace, "event") if e.text in ("speech", "nomatch")]
    assert not lines(trace, "hear")


def test_an_answer_said_over_the_prompt_answers_the_qa_at_a_word_boundary(
        tmp_path: Path) -> None:
    ask = ('<chain>q: QA("Shall I tell you more about the robots of this lab?", '
           'places)</chain>')
    user = '<answer contains="tell you more" after="-2" say="The restroom, please."/>'
    trace = run(tmp_path, user, ask=ask)
    (qa,) = [x for x in lines(trace, "end") if x.command == "QA"]
    (say,) = lines(trace, "user")
    assert say.detail.get("heard") is True
    result = str(qa.detail.get("result"))
    assert "status=answered" in result and "utterance=The restroom, please." in result
    assert "unspoken=" in result and qa.t - say.t <= 0.4 + 1e-6  # the word under way
    assert float(qa.detail["words_end"]) == pytest.approx(qa.t)


def _asks_yes_or_no(tmp_path: Path, said: str) -> list[TraceLine]:
    """The guide asks a yes/no question (after its talk); the user says ``said`` 1 s
    before the end of its prompt."""
    ask = '<chain>q: QA("Shall I tell you more about the robots of this lab?", yesno)</chain>'
    user = f'<answer contains="tell you more" nth="1" after="-1" say="{said}"/>'
    return run(tmp_path, user, ask=ask, grammars='<grammar id="yesno"><choice value="yes">'
               'yes | sure</choice><choice value="no">no</choice></grammar>')


def test_an_answer_over_the_prompt_is_an_answer_never_a_backchannel(tmp_path: Path) -> None:
    """docs/rules.md 7.5: "Yes." is one of the robot's backchannels, but the question
    whose prompt it is said over takes it as its answer: the prompt stops at the word
    and the Q&A is answered at once, not asked again."""
    trace = _asks_yes_or_no(tmp_path, "Yes.")
    (qa,) = [x for x in lines(trace, "end") if x.command == "QA"]
    assert "status=answered" in str(qa.detail.get("result"))
    assert "utterance=Yes." in str(qa.detail.get("result"))
    assert not lines(trace, "hear", "backchannel")


def test_a_backchannel_the_question_does_not_take_is_one(tmp_path: Path) -> None:
    """docs/rules.md 7.5: "Uh-huh." answers no yes/no question: the robot talks on over
    it, and the Q&A then listens as usual (no answer: the user said nothing more)."""
    trace = _asks_yes_or_no(tmp_path, "Uh-huh.")
    (qa,) = [x for x in lines(trace, "end") if x.command == "QA"]
    assert "status=noinput" in str(qa.detail.get("result"))
    assert lines(trace, "hear", "backchannel")


def test_words_another_grammar_takes_over_a_prompt_are_heard_as_speech(
        tmp_path: Path) -> None:
    """docs/rules.md 7.5: "Where is the restroom?" is no answer to a yes/no question: the
    guide's always-on grammar takes it, the prompt is cut at the word for the answer,
    and the question is asked again after it."""
    trace = _asks_yes_or_no(tmp_path, "Where is the restroom?")
    (hear,) = lines(trace, "hear")
    assert hear.app == "guide"
    said = [x.text for x in starts(trace, "guide")]
    assert said[-3:] == ["Shall I tell you more about the robots of this lab?",
                         "Next to the door.",
                         "Shall I tell you more about the robots of this lab?"]


# ---------------------------------------------------------------- 2. who takes the words

def call(command: str, **args: str) -> Call:
    return Call(command, args)


def _catalog() -> Catalog:
    standard = Catalog.standard()
    return standard.interruptible(standard.usually_interruptible())


def _harness() -> tuple[Harness, dict[str, object]]:
    h = Harness(_catalog(), duration={"Speak": 4.0, "Gesture": 1.0},
                config=MediatorConfig(barge_in=True, interrupt=True, blend=True))
    apps = {name: h.app(name, kind) for name, kind in
            (("fa", AppKind.FA), ("ea", AppKind.EA), ("eb", AppKind.EA))}
    return h, apps


def _taker(h: Harness) -> tuple[str | None, str]:
    hear = [d for d in h.decisions if d.kind.value == "hear"][-1]
    return hear.app, hear.rule.value


def test_the_words_go_to_the_running_stream_then_the_suspended_then_any() -> None:
    h, apps = _harness()
    for app in apps.values():
        app.listens_for = ("stop",)  # type: ignore[attr-defined]
    m = h.mediator
    takers: list[tuple[str | None, str]] = []

    def hear(words: str) -> None:
        m.hear(Event("speech", {"words": words}))
        takers.append(_taker(h))

    def ea_deaf() -> None:
        apps["ea"].listens_for = ()  # type: ignore[attr-defined]

    hear("stop")  # nothing runs: the first that takes them, the FA
    # eb talks, twice: it takes the words, though the FA would too
    h.at(1.0, lambda: m.submit(Request("eb", (call("Speak", text="a b c"),
                                              call("Speak", text="d e f")))))
    h.at(2.0, lambda: hear("please stop"))
    # ea's reaction cuts eb's words and takes the speaker: eb's stream is suspended; ea,
    # talking, does not take the words: eb, suspended most recently, does
    h.at(2.5, ea_deaf)
    h.at(2.5, lambda: m.submit(Request("ea", (call("Speak", text="x"),), reactive=True,
                                       reaction=True)))
    h.at(3.0, lambda: hear("stop now"))
    h.at(3.5, lambda: hear("ahem"))  # nobody takes a cough: every app sees nomatch
    h.run(until=30.0)
    assert any(d.kind.value == "suspend" and d.app == "eb" and d.t == 2.5
               for d in h.decisions)
    assert takers == [("fa", "grammar"), ("eb", "stream-runs"), ("eb", "stream-suspended"),
                      (None, "nomatch")]
    for app in apps.values():
        assert "nomatch" in [e.name for e in app.events]  # type: ignore[attr-defined]


def test_what_a_handler_of_the_users_words_asks_after_its_first_request_follows_it() -> None:
    """The words' first request starts a stream of its own (7.5), also when it is made
    as soon as possible; what the handler asks next follows it in that stream: "All
    right." is said before the question, never after it."""
    h = Harness(_catalog(), duration={"Speak": 1.0, "QA": 2.0},
                config=MediatorConfig(barge_in=True, interrupt=True, blend=True))
    m = h.mediator

    def stop(e: Event) -> None:
        if e.name == "speech":
            m.submit(Request("ea", (call("StopMoving"), call("Speak", text="All right.")),
                             order=RunningOrder.ASAP, reactive=True, reaction=True,
                             user=True))
            m.submit(Request("ea", (call("QA", prompt="May I go on?", grammar="g"),),
                             reaction=True, user=True))

    ea = h.app("ea", AppKind.EA, on_event=stop)
    ea.listens_for = ("stop",)
    h.app("fa", AppKind.FA)
    m.submit(Request("ea", (call("TopologicalMove", to="panel-2"),)))
    h.at(0.5, lambda: m.hear(Event("speech", {"words": "stop"})))
    h.run(until=20.0)
    said = [(d.t, d.command, d.tree) for d in h.starts() if d.command in ("Speak", "QA")]
    assert [c for _t, c, _tree in said] == ["Speak", "QA"]
    assert said[0][2] == said[1][2]  # (one stream)


# ---------------------------------------------------------------- 3. barge-in

def test_user_speech_over_an_utterance_cuts_it_at_a_word_boundary(tmp_path: Path) -> None:
    trace = run(tmp_path, '<say at="1.1" text="Where is the restroom?"/>')
    (cut,) = lines(trace, "interrupt", "barge-in")
    assert cut.t == pytest.approx(1.1)
    (end,) = lines(trace, "end", "barge-in")
    assert end.t == pytest.approx(1.2)  # the third word ends at 1.2 s
    assert end.detail["spoken"] == "One two three"


@pytest.mark.parametrize("words", ["Uh-huh.", "Mm-hmm. Okay.", "yes"])
def test_a_backchannel_never_cuts(tmp_path: Path, words: str) -> None:
    trace = run(tmp_path, f'<say at="1.1" text="{words}"/><say at="3.1" text="{words}"/>')
    assert [x.reason for x in lines(trace, "hear")] == ["backchannel", "backchannel"]
    assert not lines(trace, "interrupt")
    (talk,) = [x for x in lines(trace, "end") if x.text == TALK]
    assert talk.reason == "completed"


def test_a_false_interruption_goes_on_after_the_robots_pause(tmp_path: Path) -> None:
    trace = run(tmp_path, '<say at="1.1" text="Ahem."/>')
    (hear,) = lines(trace, "hear")
    assert hear.reason == "nomatch" and "nobody took Ahem." in logs(trace)
    (end,) = lines(trace, "end", "barge-in")
    again = [x for x in starts(trace, "guide") if x.reason == "restart"]
    assert len(again) == 1 and again[0].t == pytest.approx(end.t + 0.6, abs=0.021)


def test_a_false_interruption_of_a_drop_request_goes_on_all_the_same(tmp_path: Path) -> None:
    trace = run(tmp_path, '<say at="3.5" text="Ahem."/>', interrupt='interrupt="drop"')
    (end,) = lines(trace, "end", "barge-in")
    assert end.detail.get("interrupt") == "to go on"  # (from where resume would)
    assert [x.text for x in starts(trace, "guide") if x.reason == "restart"] == \
        ["Seven eight nine ten eleven twelve. Thirteen fourteen fifteen sixteen."]


# ---------------------------------------------------------------- 4. resume, restart, drop

@pytest.mark.parametrize("interrupt, again", [
    ("", [TALK]),
    ('interrupt="restart"', [TALK]),
    ('interrupt="resume"', ["Seven eight nine ten eleven twelve. Thirteen fourteen fifteen "
                            "sixteen."]),
    ('interrupt="drop"', []),
    ('interrupt="never"', [TALK]),  # (the user's words still stop it)
])
def test_what_the_user_cut_goes_on_as_its_request_says(tmp_path: Path, interrupt: str,
                                                       again: list[str]) -> None:
    trace = run(tmp_path, '<say at="3.5" text="Where is the restroom?"/>', interrupt=interrupt)
    (end,) = lines(trace, "end", "barge-in")
    assert end.detail["spoken"] == "One two three four five six. Seven eight nine"
    assert [x.text for x in starts(trace, "guide") if x.reason == "restart"] == again
    replied = next(x for x in starts(trace, "guide") if x.text == "Next to the door.")
    assert all(x.t >= replied.t for x in starts(trace, "guide") if x.reason == "restart")
    assert f"cut by user: barge-in {'true' if 'resume' in interrupt else 'false'}" \
        in logs(trace)


def test_stop_drops_what_the_user_cut(tmp_path: Path) -> None:
    trace = run(tmp_path, '<say at="3.5" text="Stop."/>')
    (end,) = lines(trace, "end", "barge-in")
    assert end.detail.get("interrupt") == "dropped"
    assert [x.text for x in starts(trace, "guide")][1:] == ["All right."]


def test_the_bound_of_one_cut_is_for_other_apps_not_for_the_user() -> None:
    h = Harness(_catalog(), duration={"Speak": 4.0, "Gesture": 1.0}, cut_after=0.4,
                config=MediatorConfig(barge_in=True, interrupt=True, resume_pause=0.0, blend=True))
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.submit(Request("ea", (call("Speak", text="a b c d e f"),)))
    for t in (1.0, 2.0):  # the user cuts it, then its restart, again
        h.at(t, lambda: m.hear(Event("speech", {"words": "ahem"})))
    h.at(3.0, lambda: m.submit(Request("fa", (call("Speak", text="x"),), reactive=True,
                                       reaction=True)))
    h.at(6.0, lambda: m.submit(Request("fa", (call("Speak", text="y"),), reactive=True,
                                       reaction=True)))
    h.run(until=20.0)
    cuts = [(d.t, d.rule.value) for d in h.decisions if d.kind.value == "interrupt"]
    # the user cut twice; the FA's first reaction cut the restart once, its second none
    assert cuts == [(1.0, "barge-in"), (2.0, "barge-in"), (3.0, "interrupt")]


def test_a_reply_cut_by_words_no_app_took_goes_on_before_a_reaction() -> None:
    """7.4 with 7.5: the user's words over the reply to their answer were taken by no
    application (a false interruption); the reply goes on after the pause, still the
    reply: the touch reaction that came meanwhile waits for its end."""
    h = Harness(_catalog(), duration={"Speak": 4.0, "QA": 2.0}, cut_after=0.2,
                outcome=lambda ab: Outcome({"status": "answered", "utterance": "yes"}),
                config=MediatorConfig(barge_in=True, resume_pause=0.6, interrupt=True, blend=True))
    m = h.mediator
    asked: list[int] = []

    def replied(cid: int, _o: Outcome) -> None:
        if cid in asked:
            m.submit(Request("ea", (call("Speak", text="Nice to meet you, Hanako."),),
                             follows=cid))

    h.app("ea", AppKind.EA, on_ended=replied)
    h.app("fa", AppKind.FA)
    asked.extend(m.submit(Request("ea", (call("QA", prompt="Your name?", grammar="g"),))))
    h.at(3.0, lambda: m.hear(Event("speech", {"words": "ahem"})))
    h.at(3.3, lambda: m.submit(Request("fa", (call("Speak", text="That tickles."),),
                                       reactive=True, reaction=True, user=True)))
    h.run(until=20.0)
    said = [(round(d.t, 3), d.calls[0].args["text"]) for d in h.starts()
            if d.command == "Speak"]
    assert said == [(2.0, "Nice to meet you, Hanako."), (3.8, "Nice to meet you, Hanako."),
                    (7.8, "That tickles.")]


# ---------------------------------------------------------------- 5. news of a stream

NEWS = """
  <on event="suspended"><log text="suspended by {event.by} ({event.rule})"/></on>
  <on event="resumed"><log text="resumed ({event.rule})"/></on>
"""


def test_an_app_is_told_when_its_stream_is_suspended_and_resumed(tmp_path: Path) -> None:
    ea = tmp_path / "guide.pxml"
    ea.write_text(EA.replace("INTERRUPT", "").replace("TALK", TALK).replace("ASK", "")
                  .replace('<on event="nomatch">', NEWS + '<on event="nomatch">'))
    fa = tmp_path / "home.pxml"
    fa.write_text(FA.replace("SUSPENDED", '<on event="touched"><chain>Gesture(nod), '
                                          'Speak("Hee-hee.")</chain></on>'))
    scenario = tmp_path / "s.xml"
    scenario.write_text(SCENARIO.format(root=ROOT, fa=fa, ea=ea, user='<touch at="1"/>')
                        .replace("POLICY", ""))
    trace = Run(scenario).run()
    said = logs(trace)
    assert "suspended by home (user-first)" in said or any(
        s.startswith("suspended by home") for s in said), said
    assert any(s.startswith("resumed (") for s in said), said
    handled = [x for x in trace if x.kind.value == "handler" and x.app == "guide"
               and x.detail.get("key") in ("suspended", "resumed")]
    suspend = next(x for x in lines(trace, "suspend") if x.app == "guide")
    assert handled[0].t == suspend.t  # told at the instant it happened


# ---------------------------------------------------------------- 6. measures

def _judged(trace: list[TraceLine]) -> dict[str, int]:
    report = judge([line.to_dict() for line in trace], thresholds=Thresholds())
    return {m: len(report.of(m)) for m in ("barge_in", "ignored", "recovery")}


def test_the_judge_passes_a_robot_that_stops_answers_and_recovers(tmp_path: Path) -> None:
    for say in ("Where is the restroom?", "Ahem.", "Uh-huh."):
        trace = run(tmp_path, f'<say at="1.1" text="{say}"/>')
        assert _judged(trace) == {"barge_in": 0, "ignored": 0, "recovery": 0}, say


def test_the_judge_finds_a_robot_that_talks_on_over_its_user(tmp_path: Path) -> None:
    profile = tmp_path / "deaf-mouth.xml"
    text = (ROOT / "robots" / "home-robot.xml").read_text()
    profile.write_text(text.replace('<interruptible commands="Speak QA',
                                    '<interruptible commands="QA'))
    trace = run(tmp_path, '<say at="1.1" text="Where is the restroom?"/>',
                profile=str(profile))
    assert not lines(trace, "interrupt")  # it hears, but cannot stop its Speak
    assert _judged(trace)["barge_in"] == 1


def test_the_judge_finds_speech_an_app_took_and_ignored(tmp_path: Path) -> None:
    ea = EA.replace('<log text="took {event.words} as {event.answer}"/>\n'
                    '    <chain>Speak("Next to the door.")</chain>', "<log text='ignored'/>")
    path = tmp_path / "mute.pxml"
    path.write_text(ea.replace("INTERRUPT", "").replace("TALK", TALK).replace("ASK", ""))
    fa = tmp_path / "home.pxml"
    fa.write_text(FA.replace("SUSPENDED", ""))
    scenario = tmp_path / "s.xml"
    scenario.write_text(SCENARIO.format(root=ROOT, fa=fa, ea=path,
                                        user='<say at="1.1" text="The restroom?"/>')
                        .replace("POLICY", ""))
    trace = Run(scenario).run()
    assert [x.app for x in lines(trace, "hear")] == ["guide"]
    assert _judged(trace)["ignored"] == 1
    # it asked for nothing: the finding names the handler that took the words
    handler = next(x for x in lines(trace, "handler") if x.detail.get("key") == "speech")
    found = judge([line.to_dict() for line in trace]).of("ignored")[0]
    assert found.at == f"mute.pxml:{handler.detail['line']}:{handler.detail['col']}"


def test_the_judge_finds_a_false_interruption_not_recovered(tmp_path: Path) -> None:
    rows = [line.to_dict() for line in run(tmp_path, '<say at="1.1" text="Ahem."/>')]
    again = next(r for r in rows if r["kind"] == "start" and r.get("reason") == "restart")
    later = json.loads(json.dumps(rows))
    for r in later:
        if r["seq"] >= again["seq"]:
            r["t"] = round(r["t"] + 0.5, 3)  # it went on 0.5 s late
    report = judge(later, thresholds=Thresholds())
    assert len(report.of("recovery")) == 1
    assert len(judge(rows, thresholds=Thresholds()).of("recovery")) == 0


@pytest.mark.parametrize("name", ["barge-in-question", "barge-in-cough",
                                  "barge-in-backchannel", "guide-question"])
def test_the_voice_examples_keep_their_reviewed_traces(  # type: ignore[no-untyped-def]
        name: str, prima_golden) -> None:
    """The shipped examples of the user's voice, pinned (each read against its
    situation, and judged, before it was pinned)."""
    prima_golden(ROOT / "scenarios" / "examples" / f"{name}.xml")
