"""Rules 1, 2 and 4: continuity, exclusive devices, and the selection order.

Each test builds the smallest scenario where removing its rule changes who
starts (see the comment "without the rule" in each).
"""

from __future__ import annotations

import pytest

from prima.mediator import AppKind, DecisionKind, Rule
from prima.mediator._index import WaitIndex
from prima.mediator._state import Node, NodeState
from prima.mediator.testing import Harness, plain_scan

from tests.mediator.helpers import call, ghost, req, speak, start_of, start_time


def _apps(h: Harness) -> Harness:
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    return h


def test_a_started_ab_is_never_cut() -> None:
    """Rule 1. Without it a reactive request would cut the running utterance at t=1."""
    h = _apps(Harness(duration={"Speak": 5.0}))
    h.mediator.submit(req("ea", speak("long explanation")))
    h.at(1.0, lambda: h.mediator.submit(req("fa", speak("what's up?"), reactive=True)))
    h.run()
    assert [(d.t, d.ab) for d in h.starts()] == [(0.0, 1), (5.0, 2)]
    assert h.kinds(DecisionKind.CANCEL) == []


def test_shared_device_in_turn_disjoint_devices_in_parallel() -> None:
    """Rule 2. Without it the Turn would start at t=0 on the moving wheels
    (the scripted driver raises on a double booking); without parallelism the
    Speak would wait for the move."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("ea", call("TopologicalMove", to="room")))   # AB1 locomotion+localization
    m.submit(req("fa", speak("hello")))                       # AB2 speaker: parallel
    m.submit(req("fa", call("Turn", angle=30.0), asap=True))   # AB3 locomotion: new tree, waits
    assert [d.ab for d in h.starts()] == [1, 2]
    assert m.snapshot().waiting == (3,)
    h.run()
    assert start_of(h, 3).t == 2.0


def test_priority_first() -> None:
    """Rule 4.1. Without it the older, reactive CC-breaking move would win at t=2."""
    h = Harness(duration=2.0)
    ghost(h, call("StopMoving"))                                                   # AB1 0-2
    _apps(h)
    m = h.mediator
    m.submit(req("ea", call("TopologicalMove", to="room"), reactive=True))         # AB2 LOW
    m.submit(req("fa", call("Turn", angle=10.0)))                                  # AB3 HIGH
    h.run(until=2.0)
    d = start_of(h, 3)
    assert (d.t, d.rule) == (2.0, Rule.PRIORITY)
    assert m.snapshot().waiting == (2,)


def test_latest_reactive_first() -> None:
    """Rule 4.2. Without it the older reactive Gesture (waiting for the neck)
    would reserve the arm and the newer reactive pointing would wait."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", call("MoveHead", pan=5.0)))                             # AB1 neck 0-2
    m.submit(req("ea", call("Gesture", name="bow"), reactive=True))             # AB2 arm+neck
    m.submit(req("fa", call("PointByHand", angle=3.0), reactive=True, asap=True))  # AB3 arm
    d = start_of(h, 3)
    assert (d.t, d.rule) == (0.0, Rule.REACTIVITY)
    assert m.snapshot().waiting == (2,)


def test_reactive_beats_parent_finished() -> None:
    """Rule 4.2 over 4.3. Without reactivity the chain's next AB would keep the speaker."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", speak("a"), speak("b")))                                 # AB1 -> AB2
    h.at(1.0, lambda: m.submit(req("ea", speak("message!"), reactive=True)))   # AB3
    h.run(until=2.0)
    assert (start_of(h, 3).t, start_of(h, 3).rule) == (2.0, Rule.REACTIVITY)


def test_parent_finished_beats_oldest() -> None:
    """Rule 4.3. Without it the older EA request would take the speaker at t=2
    and cut the FA's stream."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", speak("f0")))                                   # AB1 0-2
    h.at(0.5, lambda: m.submit(req("ea", speak("older"))))             # AB2 waits (request 2)
    h.at(1.0, lambda: m.submit(req("fa", speak("f1"))))                # AB3 after AB1 (request 3)
    h.run(until=2.0)
    d = start_of(h, 3)
    assert (d.t, d.rule) == (2.0, Rule.PARENT_FINISHED)
    assert m.snapshot().waiting == (2,)


def test_resume_stream_beats_oldest() -> None:
    """Rule 4.4. The FA's tree lost the speaker to a reactive AB at t=2 and was
    suspended; at t=4 it resumes before the EA's older (but never suspended)
    TurnAndSpeak. Without the rule the oldest request would win."""
    h = _apps(Harness(duration={"Speak": 2.0, "PointByHand": 1.0, "MoveHead": 0.5}))
    m = h.mediator
    m.submit(req("ea", speak("e0"), call("PointByHand", angle=1.0),
                 call("TurnAndSpeak", angle=90.0, text="P")))        # AB1 -> AB2 -> AB3 (request 1)
    m.submit(req("fa", speak("S")))                                   # AB4 waits (request 2)
    m.submit(req("fa", call("MoveHead", pan=1.0), asap=True))         # AB5 neck, new tree, 0-0.5
    h.at(1.0, lambda: m.submit(req("fa", speak("W"), reactive=True)))  # AB6: new tree (AB5 ended)
    h.run(until=2.0)
    assert start_of(h, 6).rule is Rule.REACTIVITY
    suspend = h.kinds(DecisionKind.SUSPEND)
    assert [(d.t, d.ab, d.rule) for d in suspend] == [(2.0, 4, Rule.REACTIVITY)]
    h.run(until=4.0)
    d = start_of(h, 4)
    assert (d.t, d.rule) == (4.0, Rule.RESUME_STREAM)
    assert [(r.t, r.ab) for r in h.kinds(DecisionKind.RESUME)] == [(4.0, 4)]
    assert m.snapshot().waiting == (3,)


def test_oldest_request_first() -> None:
    """Rule 4.4, last criterion: nothing else separates the two; the oldest wins."""
    h = Harness(duration=2.0)
    ghost(h, speak("nobody's"))                         # AB1 speaker 0-2
    _apps(h)
    m = h.mediator
    m.submit(req("ea", speak("older")))                 # AB2
    m.submit(req("fa", speak("newer")))                 # AB3
    h.run(until=2.0)
    d = start_of(h, 2)
    assert (d.t, d.rule) == (2.0, Rule.OLDEST)
    assert m.snapshot().waiting == (3,)


def test_non_conflicting_waiting_abs_start_together() -> None:
    """Rule 4: every waiting AB that conflicts with nothing starts in the same round."""
    h = Harness(duration=2.0)
    ghost(h, call("Gesture", name="wave"))             # AB1 arm+neck 0-2
    _apps(h)
    m = h.mediator
    m.submit(req("fa", call("MoveHead", pan=1.0)))     # AB2 neck
    m.submit(req("ea", call("PointByHand", angle=1.0)))  # AB3 arm
    h.run(until=2.0)
    assert sorted(d.ab for d in h.starts() if d.t == 2.0) == [2, 3]
    assert all(d.rule is Rule.FREE_DEVICES for d in h.starts() if d.t == 2.0)


def test_a_better_ab_that_cannot_start_reserves_its_devices() -> None:
    """No priority inversion. The reactive FaceHumanAndSpeak waits for the speaker;
    without reservation the later plain StopMoving would take the wheels it needs."""
    h = Harness(duration={"Speak": 4.0, "*": 1.0})
    ghost(h, speak("long"))                                                    # AB1 speaker 0-4
    _apps(h)
    m = h.mediator
    m.submit(req("ea", call("FaceHumanAndSpeak", text="hi"), reactive=True))    # AB2 waits
    h.at(1.0, lambda: m.submit(req("fa", call("StopMoving"))))                 # AB3 locomotion
    h.run(until=3.0)
    assert m.snapshot().waiting == (2, 3)
    h.run()
    assert start_of(h, 2).t == 4.0 and start_of(h, 3).t == 5.0


def test_first_start_is_free_devices() -> None:
    h = _apps(Harness())
    h.mediator.submit(req("fa", speak()))
    assert start_of(h, 1).rule is Rule.FREE_DEVICES


@pytest.mark.parametrize("n", [4, 40])
def test_incremental_selection_matches_a_plain_scan(n: int) -> None:
    """After every step nothing is left that a plain rank-order scan would start."""
    h = _apps(Harness(duration=lambda ab: 1.0 + (ab.id % 3)))
    m = h.mediator
    cmds = [lambda: speak(), lambda: call("Turn", angle=1.0), lambda: call("MoveHead", pan=1.0),
            lambda: call("Gesture", name="x"), lambda: call("FaceHumanAndSpeak", text="y")]
    for i in range(n):
        app = "fa" if i % 2 else "ea"
        h.at(i * 0.7, lambda i=i, app=app: m.submit(
            req(app, cmds[i % 5](), cmds[(i * 3) % 5](), reactive=i % 4 == 0, asap=i % 7 == 3)))
    while h.step():
        assert plain_scan(m) == []
    assert m.snapshot().waiting == ()


def test_a_cc_breaking_move_waits_while_the_other_app_talks_with_the_user() -> None:
    """The channel rule (thesis Sec. 3.3, Fig. 5.3 line 7: "The robot stopped and
    said ..."). Without it the EA's next leg (no shared device) would start at
    t=0 and the robot would drive away in the middle of the FA's question."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", call("QA", prompt="What's the matter with you?", timeout=5.0)))  # AB1 0-2
    m.submit(req("ea", call("TopologicalMove", to="room")))                              # AB2 LOW
    m.submit(req("ea", call("Speak", text="on the way")))                          # AB3, chained
    h.run(until=10.0)
    assert start_time(h, 2) == 2.0  # only once the FA's talk ended
    [hold] = [d for d in h.decisions if d.kind is DecisionKind.HOLD]
    assert (hold.ab, hold.rule, hold.t) == (2, Rule.KEEP_CHANNEL, 0.0)


def test_an_app_may_talk_while_it_moves_itself() -> None:
    """The channel rule is about the other application: the EA itself may say
    hello while navigating (docs/rules.md rule 2)."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("ea", call("Speak", text="Follow me.")))                             # AB1 0-2
    m.submit(req("ea", call("TopologicalMove", to="room"), asap=True))               # AB2 LOW
    h.run(until=10.0)
    assert start_time(h, 2) == 0.0
    assert not [d for d in h.decisions if d.kind is DecisionKind.HOLD]


def test_found_by_the_random_driver_a_remade_slot_never_ties_with_its_stale_entries() -> None:
    """Seed 2102 of ``bench/random_driver.py``: a tree's slot in the waiting index was
    dropped and made again on the same device and group, and the new slot's entry tied
    with the old slot's stale one on (keys, tree, version): the heap compared the two
    slots and ``finish`` raised a TypeError (slot versions now come from one counter).
    The seed's FA request was reactive; since a reaction's whole tree outranks the
    EA (docs/rules.md 7.1) that takes another path, so here it is not."""
    h = Harness(duration=lambda ab: 0.25 if ab.id % 2 else 1.5)
    m = h.mediator
    gesture = call("Gesture", name="bow")

    def fa_ended(cid: int, _o: object) -> None:
        if cid == 2:  # the FA's Turn: a follow-up 0.25 s later, within the end grace
            h.at(h.clock.now() + 0.25, lambda: m.submit(
                req("fa", call("FaceHumanAndSpeak", text="x"), follows=cid)))

    def ea_ended(cid: int, _o: object) -> None:
        if cid % 2 == 0:  # the EA's Q&A, then each utterance: a follow-up at once
            m.submit(req("ea", speak(), follows=cid))

    h.app("fa", AppKind.FA, on_ended=fa_ended)
    h.app("ea", AppKind.EA, on_ended=ea_ended)
    m.submit(req("ea", call("TurnAndSpeak", angle=1.0, text="x")))
    h.at(0.5, lambda: m.submit(req("fa", call("Turn", angle=1.0),
                                   call("SetPosition", x=1.0, y=1.0))))
    h.at(0.5, lambda: m.submit(req("ea", call("QA", prompt="?", grammar="g"), gesture)))
    h.at(3.0, lambda: m.submit(req("ea", gesture, asap=True)))
    h.run(until=4.0)
    assert start_time(h, 7) == 3.75  # the FA's FaceHumanAndSpeak resumes its tree
    assert plain_scan(m) == []


def test_a_device_answer_changes_only_with_the_index_serial(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """What a round keeps of a device's best (``_rounds._Round._best``) relies on it:
    while the index's serial stays and the AB it answered still waits unparked (same
    version), the index answers the same AB for the device. Checked at every ask."""
    original = WaitIndex.top
    last: dict[tuple[int, str], tuple[Node | None, int, int]] = {}
    asked = 0

    def top(self: WaitIndex, device: str) -> Node | None:
        nonlocal asked
        found = original(self, device)
        kept = last.get((id(self), device))
        if kept is not None:
            node, version, serial = kept
            if serial == self.serial and (node is None or (
                    node.state is NodeState.WAITING and node.version == version)):
                assert found is node
                asked += 1
        last[(id(self), device)] = (found, -1 if found is None else found.version,
                                    self.serial)
        return found

    monkeypatch.setattr(WaitIndex, "top", top)
    test_incremental_selection_matches_a_plain_scan(40)
    assert asked > 0
