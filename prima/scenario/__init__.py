"""Scenarios: the file (read, bounded, the files it names located), its checks, and a
scenario made ready to run.

- :func:`load_scenario` reads a scenario file (and :func:`load_map` a map file) into a
  :class:`Scenario`, every number bounded (:data:`BOUNDS`); :func:`scenario_references`
  locates the files it names, :func:`late_inputs` what it times after its end.
- :func:`make_validation` is the one validation of scenarios, maps and the files they
  name: ``prima validate`` and ``prima lsp`` report its problems, and ``prima run`` and
  ``prima sweep``, when a scenario does not load, stop on them (:func:`checked_load`,
  :func:`check_scenario`, through :func:`scenario_problems`): the same problem for the
  same file, at the same place.
- :class:`Setup` is a scenario made ready to run (profile, catalog, documents, every
  policy layered and mapped once into the mediator's configuration);
  :class:`~prima.run.Run` takes one.
- :data:`FILE_ATTRIBUTES`, :data:`SCHEDULED` and :data:`USER_TIMED` are the scenario's
  tables, which the sweep's variants read.
- :func:`main` is ``python -m prima.sim``: check scenario files, or run one headless.

The simulator never imports this package: it is built from a :class:`Scenario` as from
any :class:`~prima.sim.Setting`. Each part is imported when first used, so that
checking a document imports no simulator.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from prima.scenario._checks import (
        check_scenario,
        checked_load,
        make_validation,
        scenario_checkers,
        scenario_problems,
    )
    from prima.scenario._cli import main
    from prima.scenario._file import (
        BOUNDS,
        FILE_ATTRIBUTES,
        MAP_NS,
        SCENARIO_NS,
        SCHEDULED,
        USER_TIMED,
        Reference,
        Scenario,
        late_inputs,
        load_map,
        load_scenario,
        safe_pattern,
        scenario_references,
    )
    from prima.scenario._setup import (
        Loaded,
        Setup,
        Switches,
        check_slot,
        mediator_config,
        spec_from_profile,
    )

__all__ = ["BOUNDS", "FILE_ATTRIBUTES", "MAP_NS", "SCENARIO_NS", "SCHEDULED", "USER_TIMED",
           "Loaded", "Reference", "Scenario", "Setup", "Switches", "check_scenario", "check_slot",
           "checked_load",
           "late_inputs", "load_map", "load_scenario", "main", "make_validation",
           "mediator_config", "safe_pattern", "scenario_checkers", "scenario_problems",
           "scenario_references", "spec_from_profile"]

_WHERE = {
    **dict.fromkeys(("check_scenario", "checked_load", "make_validation", "scenario_checkers",
                     "scenario_problems"), "_checks"),
    "main": "_cli",
    **dict.fromkeys(("BOUNDS", "FILE_ATTRIBUTES", "MAP_NS", "SCENARIO_NS", "SCHEDULED",
                     "USER_TIMED", "Reference", "Scenario", "late_inputs", "load_map",
                     "load_scenario", "safe_pattern", "scenario_references"), "_file"),
    **dict.fromkeys(("Loaded", "Setup", "Switches", "check_slot", "mediator_config",
                     "spec_from_profile"), "_setup"),
}


def __getattr__(name: str) -> object:
    """Each part is imported when first used: the checks of a document need neither the
    simulator nor the mediator."""
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value
