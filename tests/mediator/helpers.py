"""Small builders shared by the mediator tests."""

from __future__ import annotations

from collections.abc import Mapping

from prima.mediator import Call, Decision, DecisionKind, Request, RunningOrder, Rule
from prima.mediator.testing import Harness
from prima.vocab import Value


def call(command: str, **args: object) -> Call:
    return Call(command, dict(args))  # type: ignore[arg-type]


def speak(text: str = "...") -> Call:
    return Call("Speak", {"text": text})


def req(app: str, *calls: Call, asap: bool = False, reactive: bool = False,
        group: bool = False, follows: int | None = None) -> Request:
    return Request(app, tuple(calls),
                   order=RunningOrder.ASAP if asap else RunningOrder.AFTER_LATEST,
                   group=group, reactive=reactive, follows=follows)


def started(h: Harness) -> list[int]:
    """AB ids in start order."""
    return [d.ab for d in h.starts() if d.ab is not None]


def start_of(h: Harness, ab: int) -> Decision:
    for d in h.starts():
        if d.ab == ab:
            return d
    raise KeyError(f"AB{ab} never started")


def start_time(h: Harness, ab: int) -> float:
    return start_of(h, ab).t


def rules(h: Harness, kind: DecisionKind) -> list[Rule]:
    return [d.rule for d in h.decisions if d.kind is kind]


def ghost(h: Harness, *calls: Call, asap: bool = False) -> None:
    """Occupy devices with ABs no loaded app owns.

    A temporary EA requests ``calls`` and is unloaded at once: its running ABs
    finish normally (never cut), its waiting ones are cancelled. Call this before
    the real EA registers.
    """
    from prima.mediator import AppKind
    from prima.mediator.testing import ScriptedApp

    h.mediator.register("ghost", AppKind.EA, ScriptedApp("ghost"))
    for c in calls:
        h.mediator.submit(req("ghost", c, asap=True))
    h.mediator.unregister("ghost")


class Facing:
    """A robot that faces away until it turns to the user (FaceHuman): a test sets
    ``faced`` where the robot would; ``asked`` counts the mediator's questions."""

    def __init__(self, faced: bool = False) -> None:
        self.faced = faced
        self.asked = 0

    def unfaced(self) -> bool:
        self.asked += 1
        return not self.faced

    def near(self, distance: float) -> bool:
        return True

    def pose(self) -> Mapping[str, Value]:
        return {"x": 0.0, "y": 0.0, "heading": 0.0}

    def displaced(self, pose: Mapping[str, Value]) -> bool:
        return False
