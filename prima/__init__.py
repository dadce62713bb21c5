"""PRIMA: mediation of two robot applications sharing one personal robot.

Subpackages, in the direction data flows:

- ``prima.dsl``: PXML documents and robot profiles in, validated models out.
- ``prima.interpreter``: runs one document, sends requests to the mediator.
- ``prima.mediator``: schedules atomic behaviors onto devices (the heart).
- ``prima.sim``: the pymunk world that implements the mediator's drivers.
"""

from importlib.util import find_spec

__version__ = "0.1.0"


def compiled() -> bool:
    """Whether this is the compiled build (``PRIMA_MYPYC=1``, see ``setup.py``): its hot
    modules are C extensions made by mypyc, not Python source. (Asked of
    :mod:`prima.trace`, one of them that imports nothing heavy.)"""
    spec = find_spec("prima.trace")
    return spec is not None and spec.origin is not None and not spec.origin.endswith(".py")
