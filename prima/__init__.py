"""PRIMA: mediation of two robot applications sharing one personal robot.

Subpackages, in the direction data flows:

- ``prima.dsl``: PXML documents and robot profiles in, validated models out.
- ``prima.interpreter``: runs one document, sends requests to the mediator.
- ``prima.mediator``: schedules atomic behaviors onto devices (the heart).
- ``prima.sim``: the pymunk world that implements the mediator's drivers.
"""

__version__ = "0.1.0"
