"""The thesis' own situations (docs/rules.md section 6), pinned and checked.

Every scenario in scenarios/thesis has a reviewed golden trace, checked with
the same ``prima_golden`` fixture application authors use. The mediated
samples of Figs. 5.3, 5.9 and 5.12 are also checked line by line, in order,
from the trace records.
"""

from __future__ import annotations

from functools import cache
from pathlib import Path
from collections.abc import Callable

import pytest

from prima.run import Run
from prima.mediator import DecisionKind
from prima.trace import Kind, TraceLine, device_overlaps

THESIS = Path(__file__).parents[1] / "scenarios" / "thesis"
SCENARIOS = sorted(THESIS.glob("*.xml"))


@cache
def run(name: str, baseline: bool = False) -> tuple[tuple[TraceLine, ...], float, float]:
    """A thesis scenario's run: with the default policies, or, as ``baseline``, with
    every policy off (the thesis' PRIMA, which reproduces its figures in order)."""
    r = Run(THESIS / f"{name}.xml", policies={"all": False} if baseline else None)
    lines = tuple(r.run())
    return lines, r.sim.now(), r.until


def test_every_thesis_situation_is_staged() -> None:
    names = {p.stem for p in SCENARIOS}
    assert {"fig5-1", "fig5-2", "fig5-7", "fig5-8", "fig5-10", "fig5-11"} <= names
    assert {f"sample-{i:02d}" for i in range(1, 11)} | {"sample-05-stream"} <= names


@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda p: p.stem)
def test_trace_matches_its_reviewed_golden(scenario: Path, prima_golden) -> None:  # type: ignore[no-untyped-def]
    prima_golden(scenario)


@pytest.mark.parametrize("baseline", [False, True], ids=["defaults", "all-off"])
@pytest.mark.parametrize("scenario", SCENARIOS, ids=lambda p: p.stem)
def test_runs_to_its_end_without_errors_or_shared_devices(scenario: Path, baseline: bool) -> None:
    lines, end, until = run(scenario.stem, baseline)
    assert end == until
    assert [line for line in lines if line.kind is Kind.ERROR] == []
    assert device_overlaps(lines) == []


# ---------------------------------------------------------------- figure orders

Step = Callable[[TraceLine], bool]


def start(app: str, command: str, text: str = "", **detail: object) -> Step:
    def match(line: TraceLine) -> bool:
        return (line.kind is DecisionKind.START and line.app == app and line.command == command
                and (line.text or "").startswith(text)
                and all(line.detail.get(k) == v for k, v in detail.items()))
    match.__doc__ = f"{app} starts {command} {text!r}"
    return match


def says(text: str) -> Step:
    def match(line: TraceLine) -> bool:
        return line.kind is Kind.USER and line.action == "say" and line.text == text
    match.__doc__ = f"user says {text!r}"
    return match


def user(action: str) -> Step:
    def match(line: TraceLine) -> bool:
        return line.kind is Kind.USER and line.action == action
    match.__doc__ = f"user {action}"
    return match


def event(name: str, **data: object) -> Step:
    def match(line: TraceLine) -> bool:
        return line.kind is Kind.EVENT and line.text == name and all(
            line.detail.get(k) == v for k, v in data.items())
    match.__doc__ = f"event {name} {data}"
    return match


def decision(kind: DecisionKind, app: str, command: str, reason: str | None = None) -> Step:
    def match(line: TraceLine) -> bool:
        return (line.kind is kind and line.app == app and line.command == command
                and (reason is None or line.reason == reason))
    match.__doc__ = f"{kind.value} {app} {command} [{reason}]"
    return match


def assert_in_order(lines: tuple[TraceLine, ...], steps: list[Step]) -> list[TraceLine]:
    """Each step matches a later line than the previous one; returns the matches."""
    found = []
    i = 0
    for step in steps:
        while i < len(lines) and not step(lines[i]):
            i += 1
        assert i < len(lines), f"not found in order: {step.__doc__} (after {found[-1:]})"
        found.append(lines[i])
        i += 1
    return found


EA3, FA2 = "ea3-navigate", "fa2-follow"


def test_sample_03_follows_figure_5_3() -> None:
    """The thesis' PRIMA (every policy off) tells Fig. 5.3's story in order. With the
    default policies the robot turns to its user before it speaks, so it finds them
    at once and the story goes on differently (read in sample-03.golden.txt)."""
    lines, *_ = run("sample-03", baseline=True)
    m = assert_in_order(lines, [
        start(EA3, "QA", "Where are you going?"),                      # 1
        says("Prof. Kidode's room."),                                  # 2
        start(EA3, "Speak", "Come on, let's go."),                     # 3
        start(EA3, "TopologicalMove"),                                 # 4
        user("touch"),                                                 # 6
        start(FA2, "QA", "What's the matter with you?"),               # 7 ...
        decision(DecisionKind.HOLD, EA3, "TopologicalMove", "keep-channel"),  # ... it stopped
        says("Come on, follow me."),                                   # 8
        start(FA2, "ActiveSensingHuman", "Where are you?"),            # 9
        event("message", sender="host"),                               # 10
        start(EA3, "StopMoving"),                                      # 11
        decision(DecisionKind.SUSPEND, FA2, "ActiveSensingHuman", "reactivity"),
        start(EA3, "Speak", "I've just got a message."),
        start(EA3, "Speak", "I'm Kidode"),                             # 12
        start(EA3, "QA", "Do you have a reply?"),                      # 13
        says("Yes. I see. I'll wait in your room."),                   # 14
        start(EA3, "Speak", "O.K. I'll send your message."),           # 15
        decision(DecisionKind.RESUME, FA2, "ActiveSensingHuman", "priority"),  # 16: CC kept
        event("human-found"),                                          # 17
        start(FA2, "Speak", "I found you, I'll start following you."),  # 18
        start(FA2, "TrackingHuman"),                                   # 19-20
        user("touch"),                                                 # 23
        start(FA2, "QA", "May I stop following you?"),                 # 24
        says("Yes."),                                                  # 25
        start(FA2, "Speak", "O.K. I'll finish following you."),        # 26
        decision(DecisionKind.RESUME, EA3, "TopologicalMove"),                 # 27
        event("place-reached", place="kidode-room"),                   # 28
        start(EA3, "Speak", "I've just reached the goal."),            # 29
    ])
    stop_move, reactive_stop = m[10], m[10].reactive
    assert reactive_stop, "the host's message is a reactive event"
    assert stop_move.t < m[18].t


FA5, EA2 = "fa5-video-timer", "ea2-library"


def _video_dialogue(fa: str) -> list[Step]:
    return [
        start(fa, "QA", "What's the matter with you?"), says("Video Timer."),
        start(fa, "QA", "Please select a TV channel."), says("12."),
        start(fa, "QA", "Please tell me a time to start."), says("18."),
        start(fa, "QA", "Please tell me a time to end."), says("19."),
        start(fa, "QA", "May I set the video timer to record the 12th channel from 18 o'clock "
                        "to 19 o'clock?"),
        says("Yes."),
        start(fa, "Speak", "Connecting the video server."),
    ]


@pytest.mark.parametrize("baseline", [False, True], ids=["defaults", "all-off"])
def test_sample_05_follows_figure_5_9(baseline: bool) -> None:
    """The thesis' PRIMA tells Fig. 5.9's story line by line. With the default policies
    the touch cuts EA2's question at once (the interrupt policy) instead of waiting for
    it, and EA2's "Wait a minute.", its reply to "The C Primer.", goes before FA5's
    reaction to the video server's message that came while EA2 listened (the exchange
    policy: lines 18 and 19 swap)."""
    lines, *_ = run("sample-05", baseline)
    result = start(FA5, "Speak", "The video setting succeeds.")               # 18
    wait = start(EA2, "Speak", "Wait a minute.")                              # 19
    m = assert_in_order(lines, [
        start(EA2, "QA", "Please tell me a title or an author of a book."),   # 1
        user("touch"),                                                        # 2
        *_video_dialogue(FA5),                                                # 4-14
        start(EA2, "QA", "Please tell me a title or an author of a book."),   # 15: cut in
        event("message", sender="video"),                                     # 16
        says("The C Primer."),                                                # 17
        *((result, wait) if baseline else (wait, result)),                    # 18, 19
        event("message", sender="library"),                                   # 20
        start(EA2, "QA", "Are you searching 'The C Primer'"),                 # 21
        says("Yes."),                                                         # 22
        start(EA2, "Speak", "O.K. Come on."),                                 # 23
        start(EA2, "TopologicalMove"),                                        # 24
        event("place-reached", kind="shelf"),                                 # 25
        start(EA2, "Speak", "Here is the book you searched for."),            # 26
    ])
    first_question, touch, matter = m[0], m[1], m[2]
    assert first_question.t < touch.t
    if baseline:
        # line 3: no reaction for a few seconds: the touch waits until the EA's Q&A ends
        assert matter.t - touch.t > 3
    else:
        # the question is cut at a word boundary; FA5's StopMoving and question follow
        cut = next(ln for ln in lines if ln.kind.value == "end" and ln.reason == "interrupt")
        assert (cut.app, cut.t) == (EA2, matter.t)
        assert matter.t - touch.t <= 0.2 + 0.4


def test_sample_05_with_an_explicit_stream_keeps_the_video_exchange_together() -> None:
    fa = "fa5-video-timer-stream"
    lines, *_ = run("sample-05-stream")
    m = assert_in_order(lines, [
        start(EA2, "QA", "Please tell me a title or an author of a book."),
        *_video_dialogue(fa),
        decision(DecisionKind.HOLD, EA2, "QA", "stream-hold"),
        start(fa, "Speak", "The video setting succeeds."),
        start(EA2, "QA", "Please tell me a title or an author of a book."),  # resumes after
        says("The C Primer."),
        start(EA2, "Speak", "Here is the book you searched for."),
    ])
    assert m[-4].t < m[-3].t  # "The video setting succeeds." strictly before the question


EA1, FA4 = "ea1-museum", "fa4-picture"


def test_sample_10_follows_figure_5_12() -> None:
    """The thesis' PRIMA (every policy off) tells Fig. 5.12's story in order; the
    default policies' turns shift its timings (read in sample-10.golden.txt)."""
    lines, *_ = run("sample-10", baseline=True)
    m = assert_in_order(lines, [
        start(EA1, "Speak", "I'm going to start the tour of the museum."),     # 1
        start(EA1, "TopologicalMove"),                                          # 2
        event("place-reached", place="panel-1"),                                # 3
        start(EA1, "ActiveSensingHuman"),                                       # 4
        event("human-found"),                                                   # 5
        start(EA1, "FaceHumanAndSpeak", "This panel shows research points"),    # 6
        user("touch"),                                                          # 7
        start(FA4, "QA", "What's the matter with you?"),                        # 9
        says("Take a picture."),                                                # 10
        start(FA4, "QA", "Which direction should I turn?"),                     # 11
        says("Turn to your right."),                                            # 12
        start(FA4, "Turn"),                                                     # 13
        start(FA4, "QA", "May I take a picture?"),                              # 14
        says("Yes."),                                                           # 15
        start(FA4, "TakePicture"),                                              # 16
        start(FA4, "Speak", "I just sent a picture."),                          # 17
        start(FA4, "QA", "May I take another picture?"),                        # 18
        says("No."),                                                            # 19
        start(FA4, "Speak", "O.K. Bye-bye."),                                   # 20
        start(EA1, "SetDirection+PointByHand+Speak", "Take attention"),         # 21
        start(EA1, "ActiveSensingHuman"),                                       # 22
        event("human-found"),                                                   # 23
        start(EA1, "FaceHumanAndSpeak", "In addition"),                         # 24
        start(EA1, "QA", "May I repeat the explanation?"),                      # 25
        says("No."),                                                            # 26
        start(EA1, "QA", "May I go to the next panel?"),                        # 27
        says("Yes."),                                                           # 28
        start(EA1, "Speak", "O.K."),                                            # 29
        start(EA1, "TopologicalMove", args="to=panel-2"),
    ])
    explanation, touch, matter = m[5], m[6], m[7]
    assert explanation.t < touch.t < matter.t  # touched while Explanation-1-1 was spoken


def test_a_search_says_its_words_once_per_retry() -> None:
    """ActiveSensingHuman iterates once per control period; only the first iteration
    of each retry (a watch, then a turn) says ``say``, and only it shows the words."""
    lines, *_ = run("sample-03", baseline=True)
    previous: dict[object, str] = {}  # command id -> its last iteration's result
    said = quiet = 0
    for ln in lines:
        if ln.app != FA2 or ln.command != "ActiveSensingHuman":
            continue
        detail = ln.detail or {}
        cid = detail.get("command_id")
        if ln.kind is DecisionKind.END:
            previous[cid] = str(detail.get("result"))
        elif ln.kind is DecisionKind.START:
            retry = cid not in previous or "turned" in previous[cid]
            assert ln.text == ("Where are you?" if retry else None), ln
            said, quiet = said + retry, quiet + (not retry)
    assert said >= 2 and quiet >= 10 * said
