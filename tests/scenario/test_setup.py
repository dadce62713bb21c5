"""A scenario made ready to run (:class:`prima.scenario.Setup`): every policy mapped once,
from its registry entry."""

from __future__ import annotations

from pathlib import Path

from prima.scenario import Setup
from prima.vocab import POLICIES

ROOT = Path(__file__).resolve().parents[2]
SCENARIO = ROOT / "scenarios" / "thesis" / "sample-05-stream.xml"


def test_every_policy_switches_what_its_entry_names() -> None:
    """Each policy switches the mediator's field or the simulator's switch its entry
    names (``config``, ``sim``), and nothing is switched by hand elsewhere: a policy
    with neither would be switched nowhere."""
    for policy in POLICIES.values():
        assert policy.config is not None or policy.sim is not None, policy.name
        for on in (True, False):
            setup = Setup.load(SCENARIO, policies={policy.name: on})
            assert setup.policies[policy.name] is on
            if policy.config is not None:
                assert getattr(setup.config, policy.config) is on, policy.name
