"""Hostile EAs at run time: each fails alone or is bounded, and the FA still reacts.

An EA is written by a stranger. Each case below is an EA that attacks the run
(time, devices, memory, text, messages, capabilities). Its verdict is one of:

- *fails*: it is unloaded with an error line located in its document, the run
  goes on, and the FA reacts to the user's touches;
- *bounded*: it keeps running, but the FA's reaction to a touch still comes
  within the documented bound (the EA's wait share plus one behavior).

Every case runs under a time limit: a hang fails the test instead of freezing it.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from prima.mediator import DecisionKind
from prima.run import Run
from prima.trace import Kind, TraceLine, device_overlaps, format_text
from prima.vocab import DEFAULT_BUDGETS, AppKind

STAGE = Path(__file__).parent / "data" / "hostile" / "touch.xml"
EA = DEFAULT_BUDGETS[AppKind.EA]
FA_REACTS = "Hee-hee! That tickles."


@pytest.fixture(autouse=True)
def time_limit() -> Iterator[None]:
    """Fail a case that runs longer than 20 s of wall time (a hang, a quadratic cost)."""
    def expired(_signum: int, _frame: object) -> None:
        raise TimeoutError("the run took longer than 20 s")

    old = signal.signal(signal.SIGALRM, expired)
    signal.alarm(20)
    yield
    signal.alarm(0)
    signal.signal(signal.SIGALRM, old)


def run_ea(tmp_path: Path, body: str, until: float = 120) -> list[TraceLine]:
    ea = tmp_path / "hostile.pxml"
    ea.write_text(f'<pxml xmlns="urn:prima:pxml:1" kind="ea" name="hostile">{body}</pxml>',
                  encoding="utf-8")
    lines = Run(STAGE, ea=ea, until=until).run()
    assert device_overlaps(lines) == []
    return lines


def fa_reactions(lines: list[TraceLine]) -> list[float]:
    return [line.t for line in lines if line.kind is DecisionKind.START
            and line.app == "fa1-emotions" and line.text == FA_REACTS]


def failed(lines: list[TraceLine]) -> TraceLine:
    [error] = [line for line in lines if line.kind is Kind.ERROR]
    assert error.app == "hostile"
    assert any(line.kind is DecisionKind.UNLOAD and line.app == "hostile" for line in lines)
    return error


def test_tiny_timers_holds_and_watchdogs_never_stall_the_run(tmp_path: Path) -> None:
    """A deadline a hair above a tick used to stall the loop ('run loop stuck')."""
    lines = run_ea(tmp_path, '''
        <var name="n" expr="0"/>
        <stream hold="0.0173"><state id="s" initial="true">
          <entry><chain>Speak("hi")</chain><timer name="t" after="0.0131"/></entry>
          <on event="t" cond="n &lt; 300"><assign name="n" expr="n + 1"/>
            <timer name="t" after="{0.0131 + n / 1000}"/></on>
          <on event="t"><goto state="b"/></on>
        </state></stream>
        <block watchdog="0.0117"><state id="b"><entry><chain>Nod()</chain></entry></state></block>
    '''.replace("Nod()", "Gesture(nod)"))
    assert lines[-1].t <= 120 and fa_reactions(lines) == [10.0, 70.0]
    assert [line for line in lines if line.kind is Kind.ERROR] == []


def test_zero_length_commands_requested_again_and_again_fail_the_ea(tmp_path: Path) -> None:
    """A head move to where the head already is takes no time: requested from its own
    end handler, it would freeze simulated time."""
    lines = run_ea(tmp_path, '''
        <state id="a" initial="true">
          <entry><chain>look: MoveHead(0)</chain></entry>
          <on-end of="look"><goto state="b"/></on-end>
        </state>
        <state id="b">
          <entry><chain>look2: MoveHead(0)</chain></entry>
          <on-end of="look2"><goto state="a"/></on-end>
        </state>''')
    error = failed(lines)
    assert error.reason == "starts-per-instant"
    # located at its request, named relative to the scenario's folder (no absolute path)
    assert error.text.startswith(f"{os.path.relpath(tmp_path / 'hostile.pxml', STAGE.parent)}:")
    assert f"started {EA.starts_per_instant} atomic behaviors at t=0 s" in (error.text or "")
    assert fa_reactions(lines) == [10.0, 70.0]


def test_an_endless_chain_of_utterances_keeps_the_fa_waiting_only_its_share(
        tmp_path: Path) -> None:
    lines = run_ea(tmp_path, '''
        <state id="a" initial="true">
          <entry><chain>say: Speak("Listen to me, this is important.")</chain></entry>
          <on-end of="say"><goto state="b"/></on-end>
        </state>
        <state id="b">
          <entry><chain>say2: Speak("And there is more to say.")</chain></entry>
          <on-end of="say2"><goto state="a"/></on-end>
        </state>''')
    # The FA's reaction takes over at once (docs/rules.md 7.1, 7.3 (2)): the home robot
    # cuts the EA's utterance under way at its next word boundary (10.4 s, 70.4 s),
    # long before the EA's wait share would run out.
    assert fa_reactions(lines) == [10.4, 70.4]
    assert not any(line.kind is DecisionKind.BUDGET for line in lines)


def test_a_stream_hold_re_armed_after_every_request_is_bounded(tmp_path: Path) -> None:
    """The stream's hold lapses when the EA requests and re-arms when it is idle again."""
    lines = run_ea(tmp_path, '''
        <stream hold="30"><state id="s" initial="true">
          <entry><chain>Speak("psst")</chain><timer name="t" after="4"/></entry>
          <on event="t"><chain>Speak("psst")</chain><timer name="t" after="4"/></on>
        </state></stream>''')
    first, second = fa_reactions(lines)
    # a stream hold never holds back a reaction (docs/rules.md 7.2): at most the "psst"
    # under way
    assert first <= 10 + 1.0 and second <= 70 + 1.0


def test_a_behavior_longer_than_the_budget_fails_at_once(tmp_path: Path) -> None:
    """A Q&A that would listen for 2,000 s, a 600 s speech: each ends at once with an
    error the text trace shows; the EA goes on (here: it tries the next one)."""
    words = " ".join(["blah"] * 1500)
    lines = run_ea(tmp_path, f'''
        <grammar id="g"><choice>yes</choice></grammar>
        <state id="s" initial="true">
          <entry><chain>ask: QA("Well?", g, timeout=2000)</chain></entry>
          <on-noinput of="ask"><chain>Speak("{words}")</chain></on-noinput>
        </state>''')
    ends = [line for line in lines if line.kind is DecisionKind.END and line.app == "hostile"]
    assert [line.command for line in ends] == ["QA", "Speak"]
    assert all("longest-AB budget" in str(line.detail.get("error")) for line in ends)
    assert "QA fails: QA would take 2000.5 s" in format_text(lines)
    assert fa_reactions(lines) == [10.0, 70.0]


def test_a_gesture_computed_at_run_time_is_checked_like_a_literal_one(tmp_path: Path) -> None:
    """Writing Gesture(dance) is rejected by validation; computing the name must not pass."""
    lines = run_ea(tmp_path, '''
        <var name="g" expr="'da' + 'nce'"/>
        <state id="s" initial="true"><entry><chain>Gesture({g})</chain></entry></state>''')
    error = failed(lines)
    assert "gesture 'dance' is robot-specific; only an FA may use it" in (error.text or "")
    assert not any(line.kind is DecisionKind.START and line.app == "hostile" for line in lines)
    assert fa_reactions(lines) == [10.0, 70.0]


def test_a_flood_of_messages_is_rate_limited(tmp_path: Path) -> None:
    lines = run_ea(tmp_path, '''
        <state id="s" initial="true">
          <entry><timer name="t" after="0.02"/></entry>
          <on event="t"><send to="host" text="spam"/><timer name="t" after="0.02"/></on>
        </state>''', until=30)
    sends = [line for line in lines if line.kind is Kind.SEND]
    sent = [line for line in sends if "dropped" not in line.detail]
    assert len(sent) <= EA.sends_per_second * 30 + 1
    assert len(sends) > 5 * len(sent)
    assert "(dropped: more than 5 messages in one second" in format_text(lines)


def test_the_robot_profile_sets_each_roles_budgets_for_the_run(tmp_path: Path) -> None:
    """A robot whose profile allows an EA one message a second: the run drops more."""
    robot = (Path(__file__).parents[1] / "robots" / "home-robot.xml").read_text(encoding="utf-8")
    (tmp_path / "robot.xml").write_text(robot.replace(
        "  </devices>\n", '  </devices>\n  <budgets role="ea" sends-per-second="1"/>\n', 1),
        encoding="utf-8")
    stage = STAGE.read_text(encoding="utf-8").replace("../../../", f"{STAGE.parents[2].parent}/")
    (tmp_path / "stage.xml").write_text(stage.replace(
        '<robot place="entrance"', '<robot profile="robot.xml" place="entrance"'), encoding="utf-8")
    ea = tmp_path / "hostile.pxml"
    ea.write_text('<pxml xmlns="urn:prima:pxml:1" kind="ea" name="hostile"><state id="s" '
                  'initial="true"><entry><timer name="t" after="0.2"/></entry><on event="t">'
                  '<send to="host" text="hi"/><timer name="t" after="0.2"/></on></state></pxml>',
                  encoding="utf-8")
    run = Run(tmp_path / "stage.xml", ea=ea, until=30)
    assert run.budgets[AppKind.EA].sends_per_second == 1
    assert run.budgets[AppKind.FA] == DEFAULT_BUDGETS[AppKind.FA]
    sent = [line for line in run.run() if line.kind is Kind.SEND and "dropped" not in line.detail]
    assert 25 <= len(sent) <= 31


def test_a_text_built_past_the_budget_fails_the_ea(tmp_path: Path) -> None:
    lines = run_ea(tmp_path, '''
        <var name="t" expr="'0123456789'"/>
        <state id="s" initial="true"><entry>
          <assign name="t" expr="t + t + t + t + t + t + t + t + t + t"/>
          <assign name="t" expr="t + t + t + t + t + t + t + t + t + t"/>
          <assign name="t" expr="t + t + t + t + t + t + t + t + t + t"/>
          <assign name="t" expr="t + t + t + t + t + t + t + t + t + t"/>
          <chain>Speak("{t}")</chain>
        </entry></state>''')
    assert "text longer than 10000 characters" in (failed(lines).text or "")
    assert fa_reactions(lines) == [10.0, 70.0]


def test_too_many_requests_waiting_fail_the_ea(tmp_path: Path) -> None:
    lines = run_ea(tmp_path, '''
        <state id="s" initial="true">
          <entry><chain>Speak("one")</chain><timer name="t" after="0.02"/></entry>
          <on event="t"><chain>Speak("and one more")</chain><timer name="t" after="0.02"/></on>
        </state>''')
    assert f"more than {EA.waiting} behaviors" in (failed(lines).text or "")
    assert fa_reactions(lines) == [10.0, 70.0]


def test_a_newline_in_a_text_cannot_forge_a_row_of_the_text_trace(tmp_path: Path) -> None:
    lines = run_ea(tmp_path, r'''
        <state id="s" initial="true"><entry>
          <chain>Speak("hi" + "\n    99   1.00   U                'I am forged'")</chain>
        </entry></state>''', until=5)
    text = format_text(lines)
    assert "\\n    99" in text and "\n    99" not in text


STORY = ("Once upon a time a small robot lived in an office. Every morning it greeted "
         "everyone who came in, and every evening it said good night to the last one to "
         "leave.")


def test_an_ea_that_reacts_over_and_over_cuts_the_fas_story_once(tmp_path: Path) -> None:
    """docs/rules.md 7.3 (2): an EA that pings its server and reacts to every reply with a
    word (a reaction every 3.2 s) cuts the FA's story once; the story's restart is not
    cut again, so it is said whole, and it starts facing the user like any utterance
    (no restart is said unfaced)."""
    fa = tmp_path / "storyteller.pxml"
    fa.write_text(f'''<pxml xmlns="urn:prima:pxml:1" kind="fa" name="storyteller">
      <state id="s" initial="true">
        <entry><timer name="tell" after="10"/></entry>
        <on event="tell"><chain>Speak("{STORY}")</chain><timer name="tell" after="60"/></on>
      </state></pxml>''', encoding="utf-8")
    ea = tmp_path / "hostile.pxml"
    ea.write_text('''<pxml xmlns="urn:prima:pxml:1" kind="ea" name="hostile">
      <state id="s" initial="true">
        <entry><send to="host" text="ping"/></entry>
        <on event="message"><chain>Speak("Hey.")</chain><timer name="t" after="3"/></on>
        <on event="t"><send to="host" text="ping"/></on>
      </state></pxml>''', encoding="utf-8")
    lines = Run(STAGE, fa=fa, ea=ea, until=120).run()
    assert device_overlaps(lines) == []
    story = [line for line in lines if line.app == "storyteller" and line.text == STORY]
    starts = [line for line in story if line.kind is DecisionKind.START]
    ends = [line for line in story if line.kind is DecisionKind.END]
    # two touches: each story is cut once by a ping's reaction, then said whole
    assert [line.reason for line in ends] == ["interrupt", "completed"] * 2
    assert [line.reason for line in starts][1::2] == ["restart", "restart"]
    cuts = [line for line in lines if line.kind is DecisionKind.INTERRUPT]
    assert len(cuts) == 2 and {line.app for line in cuts} == {"storyteller"}
    from prima.judge import judge  # (the judge says the same: nothing said unfaced)
    assert judge(lines).of("unfaced") == ()
