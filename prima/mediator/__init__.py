"""The mediator: working memory, atomic-behavior trees and the mediation rules.

It imports neither the simulator nor the DSL: applications reach it through
:class:`Request` and :class:`AppListener`, devices through :class:`Driver`.
"""

from prima.catalog import (
    STANDARD_COMMANDS,
    STANDARD_DEVICES,
    Catalog,
    CommandSpec,
    Param,
    ParamKind,
    Priority,
    Value,
)
from prima.mediator.core import Mediator, MediatorConfig
from prima.mediator.decisions import Decision, DecisionKind, Rule
from prima.mediator.interface import (
    PREDEFINED_EVENTS,
    AppKind,
    AppListener,
    AtomicBehavior,
    Call,
    Clock,
    Driver,
    Event,
    ManualClock,
    Outcome,
    Request,
    RunningOrder,
)
from prima.mediator.snapshot import HoldView, NodeView, Snapshot, TreeView
from prima.mediator.state import NodeState

__all__ = [
    "PREDEFINED_EVENTS",
    "STANDARD_COMMANDS",
    "STANDARD_DEVICES",
    "AppKind",
    "AppListener",
    "AtomicBehavior",
    "Call",
    "Catalog",
    "Clock",
    "CommandSpec",
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
    "Snapshot",
    "TreeView",
    "Value",
]
