"""Run one PXML document: its states, variables, timers and handlers.

One :class:`Interpreter` per loaded application; it talks to the mediator
through the small :class:`MediatorPort` interface only.
"""

from prima.interpreter.interpreter import (
    MAX_RAISED,
    MAX_TRANSITIONS,
    AppFailure,
    Interpreter,
    MediatorPort,
    Note,
)

__all__ = ["MAX_RAISED", "MAX_TRANSITIONS", "AppFailure", "Interpreter", "MediatorPort", "Note"]
