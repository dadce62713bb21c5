"""Q&A: speak, then listen until the user's answer or the timeout."""

from __future__ import annotations

import pytest

from prima.sim import AnswerRule, EntryKind, Pose, TimedAction, UserActionKind

from tests.sim.helpers import call, runner

ROBOT, USER = Pose(9.5, 4, 0), Pose(11, 4, 180)


def test_an_answer_rule_answers_after_its_delay() -> None:
    r = runner("museum", ROBOT, USER,
               answers=(AnswerRule("Prof. Kidode's room.", contains="where are you going",
                                   after=1.5),))
    r.queue(call("QA", prompt="Where are you going?", grammar="g"))
    r.run(30)
    [end] = r.ends("QA")
    prompt_time = 4 / 2.5
    assert end.time == pytest.approx(prompt_time + 1.5)
    assert dict(end.data) == {"status": "answered", "utterance": "Prof. Kidode's room."}
    [said] = [e for e in r.trace if e.kind is EntryKind.USER]
    assert said.name == "say" and said.data["heard"] is True and said.time == end.time


def test_no_matching_rule_means_no_input_after_the_timeout() -> None:
    r = runner("museum", ROBOT, USER, answers=(AnswerRule("Yes.", contains="reply"),))
    r.queue(call("QA", prompt="Which direction should I turn?", grammar="g", timeout=5))
    r.run(30)
    [end] = r.ends("QA")
    assert dict(end.data) == {"status": "noinput"}
    assert end.time == pytest.approx(5 / 2.5 + 5)


def test_silent_rule_and_nth_rule() -> None:
    rules = (AnswerRule("No.", contains="repeat", nth=2),
             AnswerRule(None, contains="repeat"),  # otherwise: stay silent
             AnswerRule("Yes.", pattern=r"next\s+panel"))
    r = runner("museum", ROBOT, USER, answers=rules)
    r.queue(call("QA", prompt="May I repeat the explanation?", grammar="g", timeout=3),
            call("QA", prompt="May I repeat the explanation?", grammar="g", timeout=3),
            call("QA", prompt="May I go to the next panel?", grammar="g", timeout=3))
    r.run(60)
    assert [e.data.get("utterance") for e in r.ends("QA")] == [None, "No.", "Yes."]


def test_nth_counts_every_asking_a_rule_matches_whichever_rule_answered() -> None:
    """The first asking is the first rule's; the second is the second rule's second (it
    was counted when the first rule answered); the third, the last rule's."""
    rules = (AnswerRule("Not yet.", contains="did you", nth=1),
             AnswerRule(None, contains="did you", nth=2),  # silent the second time
             AnswerRule("Yes, I did.", contains="did you"))
    r = runner("museum", ROBOT, USER, answers=rules)
    r.queue(*[call("QA", prompt="Did you take your pills?", grammar="g", timeout=3)] * 3)
    r.run(60)
    assert [e.data.get("utterance") for e in r.ends("QA")] == ["Not yet.", None, "Yes, I did."]


def test_an_unexpected_answer_is_passed_on_verbatim() -> None:
    r = runner("museum", ROBOT, USER, answers=(AnswerRule("Banana!", contains="channel"),))
    r.queue(call("QA", prompt="Please select a TV channel.", grammar="g"))
    r.run(30)
    assert r.ends("QA")[0].data["utterance"] == "Banana!"  # the interpreter decides no-match


def test_speech_outside_listening_is_not_heard() -> None:
    r = runner("museum", ROBOT, USER, TimedAction(0.5, UserActionKind.SAY, text="Hello"),
               TimedAction(3.0, UserActionKind.SAY, text="Video timer."))
    r.queue(call("QA", prompt="What's the matter with you?", grammar="g", timeout=4))
    r.run(30)
    said = [e for e in r.trace if e.kind is EntryKind.USER]
    assert [(e.data["text"], e.data["heard"]) for e in said] == [
        ("Hello", False), ("Video timer.", True)]
    assert r.ends("QA")[0].data["utterance"] == "Video timer."


def test_a_user_out_of_earshot_does_not_answer() -> None:
    r = runner("museum", ROBOT, Pose(15, 7, 0),  # 6.2 m away, beyond hearing range
               answers=(AnswerRule("Yes.", contains="ready"),))
    r.queue(call("QA", prompt="Are you ready?", grammar="g", timeout=3))
    r.run(30)
    assert r.ends("QA")[0].data["status"] == "noinput"


@pytest.mark.parametrize("blank", ["", " ", "\t", " \t\n "])
def test_blank_words_are_never_heard(blank: str) -> None:
    """Blank words are no speech: a Q&A that listens does not take them as its answer
    (it times out), and a robot that hears at any time gets no ``speech`` event from
    them (nothing to cut its words by barge-in)."""
    r = runner("museum", ROBOT, USER, TimedAction(0.5, UserActionKind.SAY, text=blank),
               answers=(AnswerRule(blank, contains="ready", after=0.5),))
    r.sim.hears_always = True
    r.queue(call("Speak", text="Welcome to the museum, we hope you enjoy your visit."),
            call("QA", prompt="Are you ready?", grammar="g", timeout=3))
    r.run(30)
    assert r.ends("QA")[0].data["status"] == "noinput"
    assert not r.events("speech")
    said = [e for e in r.trace if e.kind is EntryKind.USER]
    assert [(e.data["text"], e.data["heard"]) for e in said] == [(blank, False)] * 2
    assert "cut" not in str(r.ends("Speak")[0].data)
