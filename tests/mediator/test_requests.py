"""Rule 3 and CS exceptions (a)/(b): how requests become AB trees."""

from __future__ import annotations

import pytest

from prima.errors import MediationError
from prima.mediator import AppKind, Call, DecisionKind, NodeState, Outcome, Rule
from prima.mediator.testing import Harness, feedback_iterations

from tests.mediator.helpers import call, ghost, req, speak, start_of


def _apps(h: Harness, **fa_handlers) -> Harness:
    h.fa = h.app("fa", AppKind.FA, **fa_handlers)  # type: ignore[attr-defined]
    h.ea = h.app("ea", AppKind.EA)  # type: ignore[attr-defined]
    return h


def test_after_latest_links_to_the_latest_command_still_in_memory() -> None:
    """Without the link the MoveHead (a free device) would start at once, in a new tree."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", speak("hello")))                  # AB1
    h.at(1.0, lambda: m.submit(req("fa", call("MoveHead", pan=10.0))))   # AB2
    h.run(until=1.0)
    node = m.snapshot().node(2)
    assert node is not None and node.parent == 1 and node.state is NodeState.PENDING
    assert node.tree == m.snapshot().node(1).tree
    assert h.kinds(DecisionKind.REQUEST)[-1].rule is Rule.AFTER_LATEST
    h.run()
    assert start_of(h, 2).t == 2.0


def test_after_latest_roots_a_new_tree_once_the_latest_has_left_memory() -> None:
    """The app's requests ran out: its CS ended; the next request is a new tree."""
    h = _apps(Harness(duration=1.0))
    m = h.mediator
    m.submit(req("fa", speak("one")))
    h.run()
    m.submit(req("fa", speak("two")))
    reqs = h.kinds(DecisionKind.REQUEST)
    assert [d.rule for d in reqs] == [Rule.NEW_TREE, Rule.NEW_TREE]
    assert reqs[0].tree != reqs[1].tree


def test_a_list_is_a_chain_in_one_tree() -> None:
    h = _apps(Harness(duration=1.0))
    m = h.mediator
    ids = m.submit(req("fa", speak("a"), call("Turn", angle=5.0), call("MoveHead", pan=1.0)))
    assert ids == (1, 2, 3)
    snap = m.snapshot()
    (tree,) = snap.trees
    assert [(n.ab, n.parent) for n in tree.nodes] == [(1, None), (2, 1), (3, 2)]
    h.run()
    # One after the other although their devices are disjoint.
    assert [(d.t, d.ab) for d in h.starts()] == [(0.0, 1), (1.0, 2), (2.0, 3)]
    assert h.fa.ended_ids == [1, 2, 3]  # type: ignore[attr-defined]


def test_a_grouped_list_is_one_ab() -> None:
    """Grouping: one AB on the union of the devices; one end event per Command, in order."""
    h = _apps(Harness(duration=3.0))
    m = h.mediator
    ids = m.submit(req("fa", speak("a"), call("Gesture", name="bow"), group=True))
    assert ids == (1, 2)
    (ab,) = h.driver.started
    assert ab.command_ids == (1, 2) and [c.command for c in ab.calls] == ["Speak", "Gesture"]
    assert ab.devices == frozenset({"speaker", "arm", "neck"})
    # The EA cannot slip in between the two Commands.
    h.at(1.0, lambda: m.submit(req("ea", speak("x"), reactive=True)))
    h.run()
    assert h.fa.ended_ids == [1, 2]  # type: ignore[attr-defined]
    assert [d.ab for d in h.starts()] == [1, 2]


def test_a_grouped_request_takes_the_lowest_priority() -> None:
    h = _apps(Harness())
    h.mediator.submit(req("fa", speak("go"), call("SetPosition", x=1.0, y=2.0), group=False))
    h2 = _apps(Harness())
    with pytest.raises(MediationError, match="cannot be grouped"):
        h2.mediator.submit(req("fa", speak("go"), call("SetPosition", x=1.0, y=2.0), group=True))
    h2.mediator.submit(req("fa", speak("go"), call("TurnAndSpeak", angle=1.0, text="x"),
                           group=True))
    assert h2.mediator.snapshot().running[0][0] == 1


# ----------------------------------------------------------------------- ASAP
def test_asap_cancels_own_waiting_trees_that_share_a_device() -> None:
    """'Stop moving' ASAP cancels the waiting move; the cancelled Command is its before node."""
    h = Harness(duration=2.0)
    ghost(h, call("Turn", angle=1.0))                          # AB1 locomotion 0-2
    _apps(h)
    m = h.mediator
    m.submit(req("fa", call("SetSpeedAndTime", speed=0.3, time=30.0), speak("after")))  # AB2->AB3
    m.submit(req("fa", call("StopMoving"), asap=True))         # AB4
    snap = m.snapshot()
    assert snap.node(2) is None and snap.node(3) is None       # cancelled, out of memory
    assert h.fa.cancelled == [2, 3]  # type: ignore[attr-defined]  (Command 1 was the ghost's)
    assert [(d.command_id, d.rule) for d in h.kinds(DecisionKind.CANCEL)] == [
        (2, Rule.ASAP), (3, Rule.ASAP)]
    assert snap.node(4).parent == 3                            # the latest cancelled node
    assert snap.node(4).state is NodeState.WAITING
    assert h.kinds(DecisionKind.REQUEST)[-1].rule is Rule.ASAP
    h.run()
    assert start_of(h, 4).t == 2.0


def test_asap_never_cuts_a_running_ab_it_waits_for_it() -> None:
    h = _apps(Harness(duration={"SetSpeedAndTime": 5.0, "*": 1.0}))
    m = h.mediator
    m.submit(req("fa", call("SetSpeedAndTime", speed=0.3, time=5.0), speak("then")))  # AB1 -> AB2
    h.at(1.0, lambda: m.submit(req("fa", call("StopMoving"), asap=True)))              # AB3
    h.run(until=1.0)
    snap = m.snapshot()
    assert snap.node(2) is None                                 # the waiting Speak is cancelled
    assert snap.node(3).parent == 1 and snap.node(3).state is NodeState.PENDING
    h.run()
    assert start_of(h, 3).t == 5.0
    assert h.fa.ended_ids == [1, 3]  # type: ignore[attr-defined]


def test_asap_leaves_trees_without_a_shared_device_alone() -> None:
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", speak("a"), speak("b")))                 # AB1 -> AB2 (speaker)
    m.submit(req("fa", call("Turn", angle=10.0), asap=True))     # AB3 locomotion: new tree
    snap = m.snapshot()
    assert snap.node(2).state is NodeState.PENDING
    assert snap.node(3).state is NodeState.RUNNING and snap.node(3).tree != snap.node(1).tree
    assert h.kinds(DecisionKind.CANCEL) == []


def test_asap_abandons_a_feedback_loop_between_iterations() -> None:
    h = Harness(duration=1.0, outcome=feedback_iterations(100))
    _apps(h)
    m = h.mediator
    m.submit(req("fa", call("TrackingHuman")))                   # AB1 iteration 0
    h.at(2.5, lambda: m.submit(req("fa", call("StopMoving"), asap=True)))
    h.run(until=2.5)
    # t=2.5: iteration 2 is running; the loop stops when it ends (never cut).
    assert [d.iteration for d in h.starts()] == [0, 1, 2]
    h.run()
    assert h.driver.abandoned == [1]
    assert h.fa.cancelled == [1]  # type: ignore[attr-defined]
    stop = [d for d in h.starts() if d.command == "StopMoving"]
    assert [d.t for d in stop] == [3.0]
    assert not [d for d in h.starts() if d.command == "TrackingHuman" and d.t >= 3.0]


def test_asap_cancels_a_pending_iteration_and_abandons_the_loop() -> None:
    h = Harness(duration={"TrackingHuman": 1.0, "*": 3.0}, outcome=feedback_iterations(100))
    _apps(h)
    m = h.mediator
    m.submit(req("fa", call("TrackingHuman")))                          # AB1 iteration 0: 0-1
    h.at(0.5, lambda: m.submit(req("ea", call("Turn", angle=1.0), reactive=True)))  # AB2 0.5 waits
    h.run(until=1.0)
    # t=1: iteration 1 (AB3) waits behind the reactive EA Turn.
    assert m.snapshot().waiting == (3,)
    m.submit(req("fa", call("StopMoving"), asap=True))
    assert h.driver.abandoned == [1] and h.fa.cancelled == [1]  # type: ignore[attr-defined]
    assert m.snapshot().node(3) is None


# ------------------------------------------------------- CS exceptions (a)(b)
def test_a_request_from_an_end_handler_stays_in_the_tree_and_carries_no_reactivity() -> None:
    """Exception (a). Without it the follow-up would root a new tree, and, being
    reactive, would lose its place to nothing; here it beats the EA's waiting
    request because its parent just finished."""
    h = Harness(duration=2.0)
    box: dict[str, int] = {}

    def on_ended(cid: int, _o: Outcome) -> None:
        if cid == 1:
            box["ids"] = h.mediator.submit(req("fa", speak("and then"), reactive=True, follows=1))

    _apps(h, on_ended=on_ended)
    m = h.mediator
    m.submit(req("fa", speak("first")))                          # AB1 0-2
    h.at(1.0, lambda: m.submit(req("ea", speak("waiting"))))     # AB2 waits
    h.run(until=2.0)
    d = start_of(h, 3)
    assert (d.t, d.rule, d.reactive) == (2.0, Rule.PARENT_FINISHED, False)
    req_d = h.kinds(DecisionKind.REQUEST)[-1]
    assert req_d.rule is Rule.END_EVENT and req_d.tree == h.kinds(DecisionKind.REQUEST)[0].tree
    node = m.snapshot().node(3)
    assert node.parent == 1 and not node.reactive


def test_a_late_follow_up_after_the_grace_roots_a_new_tree() -> None:
    """A handler that waits (timer, polling) is not in time: the CS ended."""
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", speak("first")))
    h.at(2.0 + m.config.end_grace + 0.1,
         lambda: m.submit(req("fa", speak("late"), reactive=True, follows=1)))
    h.run()
    first, late = h.kinds(DecisionKind.REQUEST)
    assert late.rule is Rule.NEW_TREE and late.tree != first.tree
    assert start_of(h, 2).reactive  # the usual rule applies, reactivity included


def test_follow_up_within_the_grace_from_a_timer_is_still_in_time() -> None:
    h = _apps(Harness(duration=2.0))
    m = h.mediator
    m.submit(req("fa", speak("first")))
    h.at(2.2, lambda: m.submit(req("fa", speak("soon"), follows=1)))
    h.run()
    assert h.kinds(DecisionKind.REQUEST)[-1].rule is Rule.END_EVENT


def test_qa_is_one_ab_and_the_reply_stays_in_its_stream() -> None:
    """Exception (b): prompt + listening are one AB on speaker and speech recognition;
    the EA's reactive input waits until the Q&A times out; the FA's reply stays in
    the Q&A's tree (but the reactive input, being reactive, goes first)."""
    h = Harness(duration={"QA": 8.0, "*": 1.0})

    def on_ended(cid: int, outcome: Outcome) -> None:
        if cid == 1:
            h.mediator.submit(req("fa", speak("O.K."), follows=1))

    _apps(h, on_ended=on_ended)
    m = h.mediator
    m.submit(req("fa", call("QA", prompt="Video timer?", grammar="yesno")))   # AB1 0-8
    h.at(3.0, lambda: m.submit(req("ea", speak("message from host"), reactive=True)))  # AB2
    h.run()
    qa = h.driver.started[0]
    assert qa.devices == frozenset({"speaker", "speech-recognition"})
    assert [(d.t, d.ab) for d in h.starts()] == [(0.0, 1), (8.0, 2), (9.0, 3)]
    reply = h.kinds(DecisionKind.REQUEST)[-1]
    assert reply.rule is Rule.END_EVENT and reply.tree == h.kinds(DecisionKind.REQUEST)[0].tree


# ------------------------------------------------------------------ errors
@pytest.mark.parametrize("bad, match", [
    (req("nobody", speak()), "unknown application"),
    (req("fa", Call("Fly")), "unknown Command 'Fly'"),
    (req("fa"), "at least one Command"),
    (req("fa", Call("Speak", {"text": "x"}, extra_devices=frozenset({"jetpack"}))),
     "unknown devices"),
], ids=["unknown-app", "unknown-command", "empty", "unknown-device"])
def test_bad_requests_are_refused_without_changing_memory(bad, match) -> None:
    h = _apps(Harness())
    m = h.mediator
    m.submit(req("fa", speak("a"), speak("b")))
    before, decisions = m.snapshot(), len(h.decisions)
    with pytest.raises(MediationError, match=match):
        m.submit(bad)
    assert isinstance(MediationError("x"), ValueError)
    assert m.snapshot() == before and len(h.decisions) == decisions
    # Command ids are not consumed by a refused request.
    assert m.submit(req("fa", speak("c"))) == (3,)


def test_ea_may_not_use_robot_specific_commands_or_extra_arguments() -> None:
    from prima.mediator import Catalog, CommandSpec

    camera = CommandSpec("CaptureImage", frozenset({"camera"}), robot_specific=True)
    cat = Catalog.standard().extended([camera], ["camera"])
    h = _apps(Harness(cat))
    m = h.mediator
    with pytest.raises(MediationError, match="robot-specific"):
        m.submit(req("ea", Call("CaptureImage")))
    with pytest.raises(MediationError, match="FA-only"):
        m.submit(req("ea", Call("Speak", {"text": "x"}, extra={"volume": 3})))
    m.submit(req("fa", Call("CaptureImage")))
    assert h.driver.started[0].devices == frozenset({"camera"})


def test_asap_in_an_end_handler_still_cancels_the_apps_waiting_work() -> None:
    """Rule 3 (asap) holds inside CS exception (a): the newer request wins."""
    from prima.mediator import AppKind, DecisionKind
    from prima.mediator.testing import Harness
    from tests.mediator.helpers import req, speak

    h = Harness(duration=2.0)
    m = h.mediator
    first: list[int] = []

    def on_ended(cid: int, _outcome: object) -> None:
        if first and cid == first[0]:
            m.submit(req("fa", speak("urgent"), asap=True, follows=cid))

    h.app("fa", AppKind.FA, on_ended=on_ended)
    first.extend(m.submit(req("fa", speak("X"))))
    m.submit(req("fa", speak("queued 1"), speak("queued 2")))
    h.run()
    cancelled = [d.calls[0].args["text"] for d in h.decisions if d.kind is DecisionKind.CANCEL]
    started = [d.calls[0].args["text"] for d in h.decisions if d.kind is DecisionKind.START]
    assert cancelled == ["queued 1", "queued 2"] and started == ["X", "urgent"]


def test_ended_commands_are_not_kept_beyond_the_end_grace() -> None:
    from prima.mediator import AppKind
    from prima.mediator.testing import Harness
    from tests.mediator.helpers import req, speak

    h = Harness(duration=1.0)
    h.app("fa", AppKind.FA)
    for i in range(200):
        h.at(i * 1.0, lambda: h.mediator.submit(req("fa", speak("tick"))))
    h.run()
    intake = h.mediator._intake  # white box: the cache of ended Commands stays bounded
    assert len(intake._recent) <= 1 and len(intake._recent_q) <= 1


def test_active_sensing_with_a_prompt_also_occupies_the_speaker() -> None:
    """The catalog says which arguments add devices; the mediator books them."""
    h = Harness(duration=5.0)
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("fa", call("ActiveSensingHuman", say="Where are you?")))
    h.mediator.submit(req("fa", call("ActiveSensingHuman", say="")))
    snap = h.mediator.snapshot()
    assert snap.running == ((1, ("human-detection", "localization", "locomotion", "speaker")),)
    assert snap.node(2).devices == ("human-detection", "localization", "locomotion")
