"""The mediator's configuration: one default per policy, the registry's."""

from __future__ import annotations

import dataclasses

from prima.mediator import MediatorConfig
from prima.vocab import POLICIES


def test_every_policy_switch_defaults_as_its_registry_entry() -> None:
    """A mediator made without a configuration mediates as a run whose profile and
    scenario switch no policy: each field a policy switches defaults to that policy's
    default in :data:`prima.vocab.POLICIES`, and every switch of the configuration is
    some policy's."""
    config = MediatorConfig()
    switched = {p.config: p for p in POLICIES.values() if p.config is not None}
    for field, policy in switched.items():
        assert getattr(config, field) is policy.default, policy.name
    switches = {f.name for f in dataclasses.fields(MediatorConfig) if f.type in (bool, "bool")}
    assert switches == set(switched)
