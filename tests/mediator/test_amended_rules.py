"""docs/rules.md 7.1, 7.3 (2) and 7.4 as amended: one test per mechanism, each written so
that it fails when its mechanism is taken out (checked once by taking it out).

- 7.1: a reaction keeps the devices its next AB needs, also while that AB waits for
  the reaction's own StopMoving or for a turn to the user put before it, but not from
  the application whose block holds the reaction back;
- 7.1: a reaction to the user's own action is not overtaken by another application's
  later reaction to a perception event until its first words are said in full;
- 7.4: words that reply to an answer go before every other application's talk,
  reactions included, and are never cut; a reply that is a question goes after the
  reaction that arrived meanwhile;
- 7.3 (2): an AB is cut at most once, the time a cut throws away counts against the
  cutting application's wait share, and a restart is turned to the user like any
  utterance.
"""

from __future__ import annotations

from collections.abc import Mapping

from prima.catalog import Catalog
from prima.mediator import (
    AppKind,
    AtomicBehavior,
    DecisionKind,
    Event,
    MediatorConfig,
    Outcome,
    Request,
    Rule,
    RunningOrder,
    Value,
)
from prima.mediator.testing import Harness
from prima.vocab import DEFAULT_BUDGETS, AppKind as Role, Budgets
from tests.mediator.helpers import Facing, call, speak

CUTS = Catalog.standard().interruptible(Catalog.standard().usually_interruptible())
"""A robot that cuts utterances, Q&A prompts, gestures and feedback iterations."""
SPEECH_CUTS = Catalog.standard().interruptible(["Speak"])
"""A robot that cuts Speak only (the harness's driver cuts a Q&A while it listens)."""


def text_starts(h: Harness, app: str) -> list[tuple[float, str]]:
    return [(d.t, str(d.calls[0].args.get("text") or d.calls[0].args.get("prompt")))
            for d in h.starts() if d.app == app and d.calls
            and (d.calls[0].args.get("text") or d.calls[0].args.get("prompt"))]


def first(h: Harness, app: str, words: str) -> float:
    return next(t for t, said in text_starts(h, app) if said == words)



# ---------------------------------------------------------------- 7.1: the next AB's devices

def ea_asks_on(h: Harness, first: Request | None = None, face_user: bool = True) -> None:
    """The EA does ``first`` (by default it explains), then asks question after
    question, each right after the last (about its panel, unless ``face_user``)."""
    m = h.mediator

    def more(cid: int, _o: Outcome) -> None:
        m.submit(Request("ea", (call("QA", prompt="May I go on?", grammar="g"),),
                         follows=cid, face_user=face_user))

    h.app("ea", AppKind.EA, on_ended=more)
    m.submit(first or Request("ea", (speak("This panel shows research points."),)))


def test_a_reactions_words_keep_the_speaker_while_its_stop_moving_waits() -> None:
    """7.1: the message's StopMoving waits for the EA's move on the wheels (to 2.0); the
    EA's first question is ready on the free speaker when the move ends. The speaker
    stays kept for the reaction's words (its next AB): the question does not slip in
    while the StopMoving runs. (A reaction to a message: one to the user's own action
    would hold the EA's whole stream meanwhile, 7.6 (1).)"""
    h = Harness(duration={"StopMoving": 0.2, "QA": 3.0, "*": 2.0})
    m = h.mediator

    def react(e: Event) -> None:
        if e.name == "message":
            m.submit(Request("fa", (call("StopMoving"), speak("Yes? What is it?")),
                             reactive=True, reaction=True))

    h.app("fa", AppKind.FA, on_event=react)
    ea_asks_on(h, Request("ea", (call("TopologicalMove", to="room"),)))
    h.at(1.8, lambda: m.post(Event("message")))
    h.run(until=12.0)
    words = first(h, "fa", "Yes? What is it?")
    asked = [t for t, said in text_starts(h, "ea") if said == "May I go on?"]
    assert words == 2.2  # the move (to 2.0), then the StopMoving (0.2)
    assert asked and asked[0] >= words + 2.0  # after the reaction's words, never between
    held = [d for d in h.kinds(DecisionKind.HOLD) if d.rule is Rule.RESERVED]
    assert held and held[0].app == "ea" and held[0].t == 2.0


def test_a_reactions_words_keep_the_speaker_while_the_robot_turns_to_the_user() -> None:
    """7.1 with 7.3 (4): the touch's words wait for a turn to the user the mediator put
    before them; the EA's next question (about its panel: no turn before it), ready on
    the free speaker during the turn, waits for the words."""
    facing = Facing()
    h = Harness(duration={"FaceHuman": 1.5, "QA": 3.0, "*": 2.0}, channel=facing)
    m = h.mediator

    def react(_e: Event) -> None:
        m.submit(Request("fa", (speak("Yes? What is it?"),), reactive=True, reaction=True,
                         user=True))

    h.app("fa", AppKind.FA, on_event=react)
    facing.faced = True  # (the EA's first words are faced)
    ea_asks_on(h, face_user=False)
    h.at(1.0, lambda: setattr(facing, "faced", False))
    h.at(1.0, lambda: m.post(Event("touched")))
    h.run(until=12.0)
    turn = next(d for d in h.starts() if d.rule is Rule.CONNECT_CHANNEL and d.app == "fa")
    words = first(h, "fa", "Yes? What is it?")
    asked = [t for t, said in text_starts(h, "ea") if said == "May I go on?"]
    assert turn.t == 2.0 and words == 3.5  # the EA's words end at 2.0; the turn takes 1.5
    assert asked[0] >= words + 2.0


def test_a_reaction_held_by_a_block_keeps_nothing_from_the_blocks_app() -> None:
    """7.1 beside 6c: the EA's reaction to a message arrives inside the FA's block (FA4's
    picture dialogue): its first words are held until the block closes, so its next AB
    keeps the speaker from the other apps meanwhile, but not from the FA, whose block
    must go on for the reaction to start at all (else each waits for the other until
    the EA's wait share runs out, the check's fa4-picture cell beside the cafe EA)."""
    h = Harness(duration=2.0)
    m = h.mediator

    def react(e: Event) -> None:
        if e.name == "message":  # (not the news of its own words held)
            m.submit(Request("ea", (speak("A word from the cafe."),
                                    speak("Shall I keep a table?")),
                             reactive=True, reaction=True))

    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA, on_event=react)
    m.open_block("fa", watchdog=100.0)
    m.submit(Request("fa", (speak("Which direction should I turn?"),)))
    h.at(1.0, lambda: m.post(Event("message")))
    h.at(2.5, lambda: m.submit(Request("fa", (speak("I just sent a picture."),))))
    h.at(6.0, lambda: m.close_block("fa"))
    h.run(until=20.0)
    assert first(h, "fa", "I just sent a picture.") == 2.5
    assert text_starts(h, "ea") == [(6.0, "A word from the cafe."),
                                    (8.0, "Shall I keep a table?")]
    assert [d.app for d in h.kinds(DecisionKind.HOLD)] == ["ea"]  # (the block, once)


# ---------------------------------------------------------------- 7.1: the user's own action

def test_the_users_own_action_is_answered_before_a_later_perception_reaction() -> None:
    """7.1: the FA's touch reaction waits 2 s for the EA's uncut utterance; 0.5 s after
    the touch, the EA sees the user and reacts with a long explanation. The touch's
    words go first; the EA's later reaction goes after them."""
    h = Harness(duration={"QA": 3.0, "*": 2.0})
    m = h.mediator

    def fa_react(e: Event) -> None:
        if e.name == "touched":
            m.submit(Request("fa", (speak("Yes? What is it?"),), reactive=True,
                             reaction=True, user=True))

    def ea_react(e: Event) -> None:
        if e.name == "human-found":
            m.submit(Request("ea", (speak("This panel shows research points."),
                                    speak("Take attention to this upper figure.")),
                             reactive=True, reaction=True))

    h.app("fa", AppKind.FA, on_event=fa_react)
    h.app("ea", AppKind.EA, on_event=ea_react)
    m.submit(Request("ea", (speak("I'm going to start the tour."),)))
    h.at(1.0, lambda: m.post(Event("touched")))
    h.at(1.5, lambda: m.post(Event("human-found")))
    h.run(until=20.0)
    assert first(h, "fa", "Yes? What is it?") == 2.0
    assert first(h, "ea", "This panel shows research points.") == 4.0
    start = next(d for d in h.starts() if d.app == "fa")
    assert start.rule is Rule.USER_FIRST


def test_a_later_reaction_to_the_user_still_goes_first() -> None:
    """Of two reactions to the user's own actions, the later one wins (rule 4.2)."""
    h = Harness(duration=2.0)
    m = h.mediator

    def react(app: str, words: str) -> None:
        m.submit(Request(app, (speak(words),), reactive=True, reaction=True, user=True))

    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(Request("ea", (speak("I'm going to start the tour."),)))
    h.at(1.0, lambda: react("fa", "That tickles."))
    h.at(1.5, lambda: react("ea", "Where is the toilet? Over there."))
    h.run(until=20.0)
    assert first(h, "ea", "Where is the toilet? Over there.") == 2.0
    assert first(h, "fa", "That tickles.") == 4.0


# ---------------------------------------------------------------- 7.4: the exchange

def exchange(reply: str, *, cuts: bool = False, message: float = 2.0,
             config: MediatorConfig = MediatorConfig(interrupt=True, blend=True)) -> Harness:
    """The EA asks (3 s); the FA's reaction to a message arrives while it listens (at
    ``message``); the user answers at 3 s; the EA replies at once with ``reply`` (words
    or a question). With ``cuts``, the robot cuts Speak (after 0.3 s)."""
    h = Harness(SPEECH_CUTS if cuts else None, duration={"QA": 3.0, "*": 2.0}, cut_after=0.3,
                outcome=lambda ab: Outcome({"status": "answered", "utterance": "yes"}),
                config=config)
    m = h.mediator
    asked: list[int] = []

    def replied(cid: int, _o: Outcome) -> None:
        if cid in asked:
            calls = (call("QA", prompt="Anything else?", grammar="g"),) if reply == "question" \
                else (speak("Nice to meet you, Hanako."),)
            m.submit(Request("ea", calls, follows=cid))

    def react(_e: Event) -> None:
        m.submit(Request("fa", (speak("I've just got a message."),), reactive=True,
                         reaction=True))

    h.app("ea", AppKind.EA, on_ended=replied)
    h.app("fa", AppKind.FA, on_event=react)
    asked.extend(m.submit(Request("ea", (call("QA", prompt="What's your name?",
                                             grammar="g"),))))
    h.at(message, lambda: m.post(Event("message")))
    h.run(until=20.0)
    return h


def test_words_that_reply_to_an_answer_go_before_a_reaction_and_are_never_cut() -> None:
    """7.4: the FA's reaction came during the Q&A (the listening is never cut); the
    EA's acknowledgement goes first, uncut, and the reaction right after it."""
    h = exchange("words")
    assert first(h, "ea", "Nice to meet you, Hanako.") == 3.0
    assert first(h, "fa", "I've just got a message.") == 5.0
    assert not h.kinds(DecisionKind.INTERRUPT)
    reply = next(d for d in h.starts() if d.app == "ea" and d.t == 3.0)
    assert reply.rule is Rule.EXCHANGE


def test_a_reaction_during_the_reply_does_not_cut_it() -> None:
    """7.3 (2) with 7.4: on a robot that cuts utterances, a reaction that arrives while
    the reply is said waits for its end: a reply's words are never cut."""
    h = exchange("words", cuts=True, message=3.5)
    assert first(h, "ea", "Nice to meet you, Hanako.") == 3.0
    assert first(h, "fa", "I've just got a message.") == 5.0
    assert not h.kinds(DecisionKind.INTERRUPT)
    # the same robot cuts the EA's words when they are no reply
    h = Harness(SPEECH_CUTS, duration=2.0, cut_after=0.3)
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA, on_event=lambda _e: h.mediator.submit(Request(
        "fa", (speak("I've just got a message."),), reactive=True, reaction=True)))
    h.mediator.submit(Request("ea", (speak("Nice to meet you, Hanako."),)))
    h.at(0.5, lambda: h.mediator.post(Event("message")))
    h.run(until=10.0)
    assert first(h, "fa", "I've just got a message.") == 0.5 + 0.3


def test_a_reply_goes_first_even_when_its_app_lost_its_precedence() -> None:
    """7.4 with the wait share: the reaction waits for the listening, so that with a
    share of 0.5 s the EA loses its precedence at 2.5 s, before the user answers. Its
    reply still goes first (one AB per answer, which the user paces) and is not cut;
    the reaction follows it."""
    budgets = {Role.FA: DEFAULT_BUDGETS[Role.FA],
               Role.EA: Budgets(wait_share=0.5, wait_window=60.0)}
    h = exchange("words", cuts=True,
                 config=MediatorConfig(budgets=budgets, interrupt=True, blend=True))
    lost = [d for d in h.kinds(DecisionKind.BUDGET) if d.app == "ea"]
    assert lost and lost[0].t == 2.5
    assert first(h, "ea", "Nice to meet you, Hanako.") == 3.0
    assert first(h, "fa", "I've just got a message.") == 5.0
    assert not h.kinds(DecisionKind.INTERRUPT)


def test_a_reply_that_is_a_question_goes_after_the_reaction() -> None:
    """7.4: when the app replies with its next question, the exchange ended with the
    answer: the reaction that arrived meanwhile goes first, and the question follows."""
    h = exchange("question")
    assert first(h, "fa", "I've just got a message.") == 3.0
    assert first(h, "ea", "Anything else?") == 5.0


def test_the_exchange_policy_off_lets_the_reaction_cut_in() -> None:
    """With the exchange policy off (the thesis' PRIMA), the reaction (the latest)
    takes the speaker at the answer."""
    h = Harness(duration={"QA": 3.0, "*": 2.0},
                config=MediatorConfig(exchange=False, interrupt=True, blend=True),
                outcome=lambda ab: Outcome({"status": "answered", "utterance": "yes"}))
    m = h.mediator
    asked: list[int] = []

    def replied(cid: int, _o: Outcome) -> None:
        if cid in asked:
            m.submit(Request("ea", (speak("Nice to meet you, Hanako."),), follows=cid))

    h.app("ea", AppKind.EA, on_ended=replied)
    h.app("fa", AppKind.FA, on_event=lambda _e: m.submit(Request(
        "fa", (speak("I've just got a message."),), reactive=True, reaction=True)))
    asked.extend(m.submit(Request("ea", (call("QA", prompt="What's your name?",
                                             grammar="g"),))))
    h.at(2.0, lambda: m.post(Event("message")))
    h.run(until=20.0)
    assert first(h, "fa", "I've just got a message.") == 3.0


class Moved(Facing):
    """A robot that faces its user and has always moved since a stream was suspended
    (restore-state puts a return before the stream's next words)."""

    def __init__(self) -> None:
        super().__init__()
        self.faced = True

    def displaced(self, pose: Mapping[str, Value]) -> bool:
        return True


def test_a_return_put_before_a_reply_ranks_as_the_reply() -> None:
    """7.4 with restore-state: the EA's stream was suspended before its listening (the
    FA's reaction spoke first), so a return (SetPosition, LOW) goes before the reply's
    words. The return ranks as the reply does: the EA's own other stream, a HIGH
    TrackingHuman loop on the wheels, does not keep it (and the words) waiting iteration
    after iteration."""
    def outcome(ab: AtomicBehavior) -> Outcome:
        if ab.calls[0].command == "QA":
            return Outcome({"status": "answered", "utterance": "Hanako"})
        return Outcome(terminal=ab.calls[0].command != "TrackingHuman" or ab.iteration >= 4)

    h = Harness(duration={"QA": 3.0, "*": 2.0}, outcome=outcome, channel=Moved())
    m = h.mediator
    asked: list[int] = []

    def ended(cid: int, _o: Outcome) -> None:
        if cid == said[0]:  # it asks its question (listening only: it said it already)
            asked.extend(m.submit(Request("ea", (call("QA", prompt="", grammar="g"),),
                                          follows=cid)))
        elif cid in asked:
            m.submit(Request("ea", (speak("Nice to meet you, Hanako."),), follows=cid))

    h.app("ea", AppKind.EA, on_ended=ended)
    h.app("fa", AppKind.FA)
    said = m.submit(Request("ea", (speak("What's your name?"),)))
    h.at(1.0, lambda: m.submit(Request("fa", (speak("I've just got a message."),),
                                       reactive=True, reaction=True)))
    h.at(4.5, lambda: m.submit(Request("ea", (call("TrackingHuman"),),
                                       order=RunningOrder.ASAP)))
    h.run(until=40.0)
    suspended = [d for d in h.kinds(DecisionKind.SUSPEND) if d.app == "ea"]
    assert suspended and suspended[0].t == 2.0
    ret = next(d for d in h.starts() if d.rule is Rule.RESTORE_STATE)
    loop = [d.t for d in h.starts() if d.app == "ea" and d.command == "TrackingHuman"]
    assert loop[:2] == [4.5, 6.5]  # (the wheels were free: the loop runs)
    assert ret.t == 8.5  # the return, right after the iteration under way at the answer
    assert first(h, "ea", "Nice to meet you, Hanako.") == 10.5
    assert loop[2] == 10.5  # (the loop goes on after the return)


# ---------------------------------------------------------------- 7.3 (2): interrupting

def pinging(h: Harness, every: float = 3.0, until: float = 60.0) -> None:
    """An EA that reacts every ``every`` seconds with a short word (a server it pings)."""
    m = h.mediator
    h.app("ea", AppKind.EA)
    t = 1.0
    while t < until:
        h.at(t, lambda: m.submit(Request("ea", (speak("Hey."),), reactive=True,
                                         reaction=True)))
        t += every


def test_an_ab_is_cut_at_most_once() -> None:
    """7.3 (2): a reaction every 3 s cannot keep the FA's 9 s story from being said: it
    is cut once; its restart is not cut again."""
    h = Harness(CUTS, duration=lambda ab: 9.0 if ab.app == "fa" else 0.5, cut_after=0.2)
    h.app("fa", AppKind.FA)
    pinging(h)
    h.mediator.submit(Request("fa", (speak("Once upon a time, a robot told a story."),)))
    h.run(until=80.0)
    cuts = h.kinds(DecisionKind.INTERRUPT)
    assert len(cuts) == 1
    ends = [d for d in h.kinds(DecisionKind.END) if d.app == "fa"]
    assert [d.rule for d in ends] == [Rule.INTERRUPT, Rule.COMPLETED]


def test_the_time_a_cut_throws_away_counts_against_the_cutting_apps_share() -> None:
    """7.3 (2): the 8 s the FA's cut story had run are charged to the EA that cut it:
    with a share of 5 s it loses its precedence at once."""
    budgets = {Role.FA: DEFAULT_BUDGETS[Role.FA],
               Role.EA: Budgets(wait_share=5.0, wait_window=60.0)}
    h = Harness(CUTS, duration=lambda ab: 10.0 if ab.app == "fa" else 0.5, cut_after=0.0,
                config=MediatorConfig(budgets=budgets, interrupt=True, blend=True))
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    h.mediator.submit(Request("fa", (speak("Once upon a time, a robot told a story."),)))
    h.at(8.0, lambda: h.mediator.submit(Request("ea", (speak("Hey."),), reactive=True,
                                                reaction=True)))
    h.run(until=40.0)
    budget = [d for d in h.kinds(DecisionKind.BUDGET) if d.app == "ea"]
    assert budget and budget[0].t == 8.0 and "loses its precedence" in budget[0].detail


def test_a_restart_is_turned_to_the_user_like_any_utterance() -> None:
    """7.3 (2) with (4): the cut story starts again facing the user: the mediator puts a
    turn to the user before the restart as before any utterance."""
    facing = Facing()
    facing.faced = True
    h = Harness(CUTS, duration=lambda ab: 9.0 if ab.app == "fa" and ab.calls[0].command ==
                "Speak" else 1.0, cut_after=0.2, channel=facing)
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.submit(Request("fa", (speak("Once upon a time, a robot told a story."),)))

    def ea_turns_away() -> None:
        facing.faced = False  # (the EA's reaction turns the robot to its panel)
        m.submit(Request("ea", (speak("Look over there."),), reactive=True, reaction=True,
                         face_user=False))

    h.at(2.0, ea_turns_away)
    h.run(until=40.0)
    restart = next(d for d in h.starts() if d.rule is Rule.RESTART)
    turn = [d for d in h.starts() if d.app == "fa" and d.rule is Rule.CONNECT_CHANNEL]
    assert any(2.0 < d.t <= restart.t for d in turn)
