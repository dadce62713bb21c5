"""Rule 6c (explicit stream blocks) and begin/end blocks (rule 3, grouping)."""

from __future__ import annotations

import pytest

from prima.errors import MediationError
from prima.mediator import AppKind, DecisionKind, MediatorConfig, Rule
from prima.mediator.testing import Harness
from prima.vocab import Budgets

from tests.mediator.helpers import call, ghost, req, speak, start_of


def _h(**kw) -> Harness:
    h = Harness(**kw)
    h.fa = h.app("fa", AppKind.FA)  # type: ignore[attr-defined]
    h.ea = h.app("ea", AppKind.EA)  # type: ignore[attr-defined]
    return h


# --------------------------------------------------------------- streams
def _library(h: Harness, hold: float = 10.0) -> None:
    """EA2 (Fig. 5.9): say 'Wait a minute', wait 3 s for the library server, go on."""
    m = h.mediator
    m.open_stream("ea", hold=hold)
    m.submit(req("ea", speak("Wait a minute.")))                 # AB1 0-1
    h.at(4.0, lambda: m.submit(req("ea", speak("Are you searching 'The C Primer'?"))))
    h.at(5.0, lambda: m.close_stream("ea"))


def test_a_stream_keeps_one_tree_while_the_app_waits() -> None:
    """Without the stream the request after the server reply would root a new tree."""
    h = _h(duration=1.0)
    _library(h)
    h.run()
    first, second = h.kinds(DecisionKind.REQUEST)
    assert second.rule is Rule.STREAM and second.tree == first.tree


def test_a_stream_holds_its_devices_against_the_other_apps_plain_requests() -> None:
    """Fig. 5.9's failure: without the hold the FA's utterance would cut in at t=2."""
    h = _h(duration=1.0)
    _library(h)
    h.at(2.0, lambda: h.mediator.submit(req("fa", speak("The video setting succeeds."))))
    h.run()
    assert [(d.t, d.app) for d in h.starts()] == [(0.0, "ea"), (4.0, "ea"), (5.0, "fa")]
    (hold,) = h.kinds(DecisionKind.HOLD)
    assert (hold.t, hold.app, hold.rule) == (2.0, "fa", Rule.STREAM_HOLD)
    assert start_of(h, 3).rule is Rule.PARENT_FINISHED  # the stream continues first


def test_reactive_input_is_not_held() -> None:
    h = _h(duration=1.0)
    _library(h)
    h.at(2.0, lambda: h.mediator.submit(req("fa", speak("What's the matter?"), reactive=True)))
    h.run()
    assert start_of(h, 2).t == 2.0 and h.kinds(DecisionKind.HOLD) == []


def test_with_the_streams_policy_off_a_stream_block_is_a_plain_sequence() -> None:
    """The streams policy switches the mediator's own stream blocks (its registry entry's
    ``config``): off, the mediator never hears of them (no hold, no stream tree), as in
    the thesis' PRIMA, and closing one is no misuse."""
    h = _h(duration=1.0, config=MediatorConfig(streams=False))
    _library(h)
    h.run()
    first, second = h.kinds(DecisionKind.REQUEST)
    assert second.rule is not Rule.STREAM and second.tree != first.tree
    assert h.mediator.snapshot().holds == ()
    h.mediator.close_stream("ea")


def test_the_hold_times_out() -> None:
    """Without the timeout a stream that waits forever would starve the other app."""
    h = _h(duration=1.0)
    m = h.mediator
    m.open_stream("ea", hold=2.5)
    m.submit(req("ea", speak("Connecting...")))                    # AB1 0-1, idle from t=1
    h.at(1.5, lambda: m.submit(req("fa", speak("hi"))))            # AB2 held
    h.run()
    release = h.kinds(DecisionKind.RELEASE)
    assert [(d.t, d.rule) for d in release] == [(3.5, Rule.HOLD_TIMEOUT)]
    assert start_of(h, 2).t == 3.5
    assert m.snapshot().holds == ()


def test_close_stream_releases_the_hold() -> None:
    h = _h(duration=1.0)
    m = h.mediator
    m.open_stream("ea", hold=100.0)
    m.submit(req("ea", speak("Connecting...")))
    h.at(1.5, lambda: m.submit(req("fa", speak("hi"))))
    h.at(2.0, lambda: m.close_stream("ea"))
    h.run()
    assert [(d.t, d.rule) for d in h.kinds(DecisionKind.RELEASE)] == [(2.0, Rule.STREAM_CLOSE)]
    assert start_of(h, 2).t == 2.0


def test_stream_and_block_misuse_is_refused() -> None:
    h = _h()
    m = h.mediator
    with pytest.raises(MediationError, match="no stream"):
        m.close_stream("fa")
    with pytest.raises(MediationError, match="no block"):
        m.close_block("fa")
    m.open_stream("fa", hold=1.0)
    with pytest.raises(MediationError, match="already open"):
        m.open_stream("fa", hold=1.0)
    m.open_block("fa", watchdog=5.0)
    with pytest.raises(MediationError, match="already open"):
        m.open_block("fa", watchdog=5.0)
    with pytest.raises(MediationError, match="watchdog"):
        m.open_block("ea", watchdog=0.0)
    with pytest.raises(MediationError, match="unknown devices"):
        m.open_block("ea", devices=frozenset({"jetpack"}), watchdog=1.0)


# ---------------------------------------------------------------- blocks
def _picture(h: Harness, watchdog: float = 100.0, devices=None) -> None:
    """FA4 (Fig. 5.10): a block from 'Which direction?' to 'May I take another?'."""
    m = h.mediator
    m.open_block("fa", devices=devices, watchdog=watchdog)
    m.submit(req("fa", call("QA", prompt="Which direction should I turn?", grammar="dir")))
    h.at(3.0, lambda: m.submit(req("fa", call("Turn", angle=-90.0))))     # after a gap


def test_a_block_reserves_its_devices_even_against_reactive_requests() -> None:
    """Without the block the EA's reactive utterance would slip in at t=1 (the gap)."""
    h = _h(duration=1.0)
    _picture(h, devices=frozenset({"speaker", "speech-recognition", "locomotion"}))
    h.at(1.5, lambda: h.mediator.submit(req("ea", speak("Panel 1..."), reactive=True)))
    h.at(1.5, lambda: h.mediator.submit(req("ea", call("MoveHead", pan=1.0), asap=True)))
    h.at(5.0, lambda: h.mediator.close_block("fa"))
    h.run()
    speak_ab = next(d for d in h.starts() if d.command == "Speak")
    head = next(d for d in h.starts() if d.command == "MoveHead")
    assert speak_ab.t == 5.0                  # after close_block
    assert head.t == 1.5                      # the neck is not in the block
    hold = h.kinds(DecisionKind.HOLD)
    assert [(d.t, d.rule, d.command) for d in hold] == [(1.5, Rule.BLOCK, "Speak")]
    assert [(d.t, d.rule) for d in h.kinds(DecisionKind.RELEASE)] == [(5.0, Rule.BLOCK_CLOSE)]
    # Everything inside the block is one tree.
    fa_reqs = [d for d in h.kinds(DecisionKind.REQUEST) if d.app == "fa"]
    assert len({d.tree for d in fa_reqs}) == 1 and fa_reqs[1].rule is Rule.STREAM


def test_a_block_watchdog_ends_the_reservation_without_cutting() -> None:
    h = _h(duration={"QA": 3.0, "*": 1.0})
    _picture(h, watchdog=2.0)
    h.at(0.5, lambda: h.mediator.submit(req("ea", speak("Panel 1..."), reactive=True)))
    h.run()
    assert [(d.t, d.rule) for d in h.kinds(DecisionKind.RELEASE)] == [(2.0, Rule.WATCHDOG)]
    # The Q&A runs to its end (t=3): nothing is cut; then the EA speaks, and the FA's
    # Turn (no longer inside a reserving block) roots a new tree on the free wheels.
    assert [(d.t, d.command) for d in h.starts()] == [(0.0, "QA"), (3.0, "Speak"), (3.0, "Turn")]
    h.mediator.close_block("fa")   # closing after the watchdog is fine
    assert h.kinds(DecisionKind.RELEASE)[-1].rule is Rule.WATCHDOG


def test_unregistering_concludes_blocks_and_streams() -> None:
    h = _h(duration=1.0)
    m = h.mediator
    m.open_block("fa", watchdog=100.0)
    m.submit(req("fa", call("QA", prompt="Which direction should I turn?", grammar="dir")))
    m.open_stream("fa", hold=50.0)
    h.at(1.5, lambda: m.submit(req("ea", speak("x"))))
    h.at(2.0, lambda: m.unregister("fa"))
    h.run()
    assert [(d.t, d.rule) for d in h.kinds(DecisionKind.RELEASE)] == [
        (2.0, Rule.UNLOAD), (2.0, Rule.UNLOAD)]
    assert start_of(h, 2).t == 2.0
    assert m.next_deadline() is None


def test_an_ab_held_by_a_block_does_not_hold_up_the_block_itself() -> None:
    """The other app's reactive AB, held by the block, outranks the block's next AB
    on the speaker; it must not reserve the speaker against the block (which
    would leave the device idle until the watchdog, then let the other app in)."""
    from prima.mediator import AppKind, DecisionKind
    from prima.mediator.testing import Harness
    from tests.mediator.helpers import req, speak

    h = Harness(duration=2.0)
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.open_block("fa", devices=frozenset({"speaker"}), watchdog=30.0)
    m.submit(req("fa", speak("block 1")))
    h.at(0.5, lambda: m.submit(req("ea", speak("ea reactive"), reactive=True)))
    h.at(1.0, lambda: m.submit(req("fa", speak("block 2"))))
    h.at(5.0, lambda: m.close_block("fa"))
    h.run(until=60)
    starts = [(d.t, d.calls[0].args["text"]) for d in h.decisions if d.kind is DecisionKind.START]
    assert starts == [(0.0, "block 1"), (2.0, "block 2"), (5.0, "ea reactive")]


def test_a_documents_watchdog_and_hold_are_capped() -> None:
    """Rules 3 and 6c: PRIMA, not the (untrusted) author, bounds blocks and holds."""
    from prima.mediator import AppKind, DecisionKind, Rule
    from prima.mediator.testing import Harness
    from tests.mediator.helpers import req, speak

    h = Harness(duration=1.0)
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.open_block("ea", watchdog=1_000_000.0)
    m.submit(req("ea", speak("hog")))
    h.run(until=1000)
    [release] = [d for d in h.decisions if d.kind is DecisionKind.RELEASE]
    assert (release.rule, release.t) == (Rule.WATCHDOG, 60.0)


def test_a_block_keeps_the_other_app_waiting_only_for_its_wait_share() -> None:
    """The wait-share budget: a block that parks the other app's speech loses its force
    after 30 s of keeping it waiting (the default share), long before its watchdog."""
    from prima.mediator import AppKind, DecisionKind, Rule
    from prima.mediator.testing import Harness
    from tests.mediator.helpers import req, speak

    h = Harness(duration=1.0)
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m = h.mediator
    m.open_block("ea", watchdog=1_000_000.0)
    m.submit(req("ea", speak("hog")))
    h.at(2.0, lambda: m.submit(req("fa", speak("let me talk"), reactive=True)))
    h.run(until=1000)
    budget = [d for d in h.decisions if d.kind is DecisionKind.BUDGET]
    assert [(d.app, d.rule, d.t) for d in budget][0] == ("ea", Rule.WAIT_SHARE, 32.0)
    assert [d.t for d in h.decisions if d.kind is DecisionKind.START][-1] == 32.0


def test_found_by_the_random_driver_an_ab_steps_aside_as_soon_as_a_block_holds_it() -> None:
    """The EA's FaceHumanAndSpeak waits for the wheels and so reserves the free
    speaker. The FA's block on the wheels then takes force (its first AB starts):
    the EA's AB is held and must step aside at once, not when the wheels free up,
    so the FA's own utterance starts now (seed 11446 of bench/random_driver.py)."""
    h = Harness(duration={"Turn": 1.0, "*": 0.5})
    m = h.mediator
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.submit(req("fa", call("Turn", angle=90.0)))                   # AB1: the wheels
    m.submit(req("ea", call("FaceHumanAndSpeak", text="look")))     # AB2: waits, reserves
    m.open_block("fa", devices=frozenset({"locomotion"}), watchdog=10.0)
    m.submit(req("fa", call("PointByHand", angle=10.0), asap=True))  # AB3: the block starts
    m.submit(req("fa", speak("here"), asap=True))                   # AB4: the free speaker
    assert [(d.ab, d.t) for d in h.starts()] == [(1, 0.0), (3, 0.0), (4, 0.0)]
    [held] = h.kinds(DecisionKind.HOLD)
    assert (held.ab, held.rule, held.t) == (2, Rule.BLOCK, 0.0)



def test_an_ab_steps_aside_again_when_the_blocks_app_regains_its_precedence() -> None:
    """The FA's block holds the EA's group, until the FA overruns its wait share
    (t=1): its block then holds nothing, and the group takes its place again,
    waiting for the arm (a ghost's). When the FA regains its precedence (t=4), its
    block holds the group again, which must step aside at once: the FA's utterance
    at t=4.5 must not wait for the arm."""
    budgets = {AppKind.FA: Budgets(wait_share=1.0, wait_window=3.0), AppKind.EA: Budgets()}
    h = Harness(duration={"PointByHand": 20.0, "*": 0.5},
                config=MediatorConfig(budgets=budgets))
    m = h.mediator
    ghost(h, call("PointByHand", angle=1.0))                         # AB1: the arm, 0-20
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    m.open_block("fa", devices=frozenset({"locomotion"}), watchdog=50.0)
    m.submit(req("fa", call("Turn", angle=1.0)))                      # AB2: the block starts
    m.submit(req("ea", call("Gesture", name="bow"), speak("x"), call("Turn", angle=1.0),
                 group=True))                                        # AB3: held
    h.at(4.5, lambda: m.submit(req("fa", speak("mine"), asap=True)))  # AB4
    h.run(until=5.0)
    budget = [(d.t, d.detail) for d in h.kinds(DecisionKind.BUDGET)]
    assert [t for t, _ in budget][:2] == [1.0, 4.0]
    assert start_of(h, 4).t == 4.5
