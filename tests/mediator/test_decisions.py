"""The decision record and the snapshot are stable, comparable data."""

from __future__ import annotations

import json

from prima.mediator import AppKind, Decision, DecisionKind, Rule
from prima.mediator.testing import Harness

from tests.mediator.helpers import call, req, speak


def test_every_rule_and_kind_has_a_docstring_and_a_kebab_name() -> None:
    import inspect

    src = inspect.getsource(Rule) + inspect.getsource(DecisionKind)
    for member in list(Rule) + list(DecisionKind):
        assert member.value == member.value.lower() and " " not in member.value
        assert f'{member.name} = "{member.value}"\n    """' in src, member


def test_decisions_serialize_stably() -> None:
    h = Harness(duration=1.0)
    h.app("fa", AppKind.FA)
    h.mediator.submit(req("fa", speak("hi"), call("Gesture", name="bow"), group=True))
    h.run()
    start = h.starts()[0]
    assert start == Decision(t=0.0, seq=3, kind=DecisionKind.START, rule=Rule.FREE_DEVICES,
                             app="fa", ab=1, tree=0, command="Speak+Gesture", command_id=1,
                             command_ids=(1, 2), devices=("arm", "neck", "speaker"),
                             calls=(speak("hi"), call("Gesture", name="bow")))
    d = start.to_dict()
    assert list(d) == ["t", "seq", "kind", "rule", "app", "ab", "tree", "command", "command_id",
                       "command_ids", "devices", "reactive", "iteration", "label", "detail"]
    json.dumps([x.to_dict() for x in h.decisions])
    assert [x.seq for x in h.decisions] == list(range(1, len(h.decisions) + 1))
    assert str(start) == "t=0 start fa AB1 Speak+Gesture [free-devices]"


def test_snapshots_compare_by_value() -> None:
    def build() -> Harness:
        h = Harness(duration=1.0)
        h.app("fa", AppKind.FA)
        h.mediator.submit(req("fa", speak("a"), speak("b")))
        return h

    a, b = build(), build()
    assert a.mediator.snapshot() == b.mediator.snapshot()
    b.run()
    assert a.mediator.snapshot() != b.mediator.snapshot()
    assert b.mediator.snapshot().trees == ()
