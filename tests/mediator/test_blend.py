"""The blend policy (thesis Sec. 5.3 (5), docs/rules.md 7.3 (5)): a robot profile may
declare Commands that run together on a shared device, a local motion over a global
one (a dance step while it guides) or speech over quieter sound; blended ABs are never
cut, and the robot stays within the blend's bound of its user."""

from __future__ import annotations

from collections.abc import Mapping

from prima.catalog import Blend, Catalog
from prima.mediator import AppKind, DecisionKind, MediatorConfig, Outcome, Request, Rule
from prima.mediator.testing import Harness
from prima.vocab import Value
from tests.mediator.helpers import call, req

DANCE = Blend(frozenset({"Turn", "SetSpeedAndTime"}), frozenset({"TopologicalMove"}),
              frozenset({"locomotion"}), max_user_distance=2.5, slowdown=0.5)


class User:
    """How far the user is: within the bound or not."""

    def __init__(self, near: bool = True) -> None:
        self.close = near

    def unfaced(self) -> bool:
        return False

    def near(self, distance: float) -> bool:
        return self.close

    def pose(self) -> Mapping[str, Value]:
        return {"x": 0.0, "y": 0.0, "heading": 0.0}

    def displaced(self, pose: Mapping[str, Value]) -> bool:
        return False


def guide_and_dance(blends: tuple[Blend, ...] = (DANCE,), user: User | None = None,
                    config: MediatorConfig = MediatorConfig(interrupt=True, blend=True)) -> Harness:
    """The EA guides (a move of four 0.5 s iterations); at 0.7 s the FA dances
    (a 1 s Turn, reactive)."""
    h = Harness(Catalog.standard().with_blends(blends),
                duration={"TopologicalMove": 0.5, "Turn": 1.0, "*": 1.0},
                outcome=lambda ab: Outcome(terminal=ab.iteration >= 3),
                channel=user or User(), config=config)
    h.app("ea", AppKind.EA)
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("ea", call("TopologicalMove", to="panel-2")))
    h.at(0.7, lambda: h.mediator.submit(Request("fa", (call("Turn", angle=45.0),),
                                                reactive=True, reaction=True)))
    h.run(until=20.0)
    return h


def starts(h: Harness) -> list[tuple[float, str, int, Rule]]:
    return [(d.t, d.command or "", d.iteration, d.rule) for d in h.starts()]


def test_a_dance_step_blends_over_the_move_and_the_move_goes_on_under_it() -> None:
    h = guide_and_dance()
    assert starts(h) == [
        (0.0, "TopologicalMove", 0, Rule.FREE_DEVICES),
        (0.5, "TopologicalMove", 1, Rule.FREE_DEVICES),
        (0.7, "Turn", 0, Rule.BLEND),             # over the move's iteration, at once
        (1.0, "TopologicalMove", 2, Rule.BLEND),  # the move's next one, under the dance
        (1.5, "TopologicalMove", 3, Rule.BLEND)]  # (the dance ends at 1.7)
    turn = h.starts()[2]
    assert turn.detail == "over AB2 on locomotion"
    assert not h.kinds(DecisionKind.INTERRUPT) and not h.kinds(DecisionKind.SUSPEND)
    assert h.mediator.snapshot().busy == ()  # everything ended; nothing left behind


def test_no_blend_undeclared_off_or_beyond_the_bound() -> None:
    """Without a declared blend, with the policy off, or with the user farther than
    the bound, the dance waits for the move's iteration (and the move for it)."""
    for h in (guide_and_dance(blends=()),
              guide_and_dance(config=MediatorConfig(blend=False, interrupt=True)),
              guide_and_dance(user=User(near=False))):
        assert Rule.BLEND not in [r for *_x, r in starts(h)]
        assert starts(h)[2][:2] == (1.0, "Turn")
