"""Run one PXML document: its states, variables, timers and handlers.

One :class:`Interpreter` per loaded application; it talks to the mediator
through the small :class:`MediatorPort` interface only.
"""

from prima.errors import AppFailure
from prima.interpreter._interpreter import (
    MAX_RAISED,
    MAX_TIMERS_AT_ONCE,
    MAX_TRANSITIONS,
    Interpreter,
    MediatorPort,
    Note,
)

__all__ = [
    "MAX_RAISED",
    "MAX_TIMERS_AT_ONCE",
    "MAX_TRANSITIONS",
    "AppFailure",
    "Interpreter",
    "MediatorPort",
    "Note",
]
