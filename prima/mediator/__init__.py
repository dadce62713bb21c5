"""The mediator: working memory, atomic-behavior trees and the mediation rules.

It imports neither the simulator nor the DSL: applications reach it through
:class:`Request` and :class:`AppListener`, devices through :class:`Driver`,
time through a :class:`Clock`. Scripted test doubles (a driver, an app, a
discrete-event harness) are in :mod:`prima.mediator.testing`.
"""

from prima.catalog import (
    STANDARD_COMMANDS,
    STANDARD_DEVICES,
    Blend,
    Catalog,
    CommandSpec,
    Param,
    ParamKind,
    Priority,
)
from prima.mediator._decisions import Decision, DecisionKind, Rule
from prima.mediator._interface import (
    AbId,
    AppListener,
    AtomicBehavior,
    Call,
    Channel,
    Clock,
    CommandId,
    Driver,
    Event,
    ManualClock,
    Outcome,
    Request,
    TreeId,
)
from prima.mediator._config import MediatorConfig
from prima.mediator._mediator import Mediator
from prima.mediator._ranking import CRITERIA, Criterion, Scope
from prima.mediator._snapshot import HoldView, NodeView, Snapshot, TreeView
from prima.mediator._state import NodeState
from prima.vocab import PREDEFINED_EVENTS, AppKind, RunningOrder, Value

__all__ = [
    "CRITERIA",
    "PREDEFINED_EVENTS",
    "STANDARD_COMMANDS",
    "STANDARD_DEVICES",
    "AbId",
    "AppKind",
    "AppListener",
    "AtomicBehavior",
    "Call",
    "Blend",
    "Catalog",
    "Channel",
    "Clock",
    "CommandId",
    "CommandSpec",
    "Criterion",
    "Decision",
    "DecisionKind",
    "Driver",
    "Event",
    "HoldView",
    "ManualClock",
    "Mediator",
    "MediatorConfig",
    "NodeState",
    "NodeView",
    "Outcome",
    "Param",
    "ParamKind",
    "Priority",
    "Request",
    "Rule",
    "RunningOrder",
    "Scope",
    "Snapshot",
    "TreeId",
    "TreeView",
    "Value",
]
