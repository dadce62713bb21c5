"""What a simulator is built from (:class:`Setting`): the shape of a loaded scenario, so
that the simulator builds itself from one without importing the scenario package (which
reads the files, and imports the simulator's types)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from prima.sim._maps import WorldMap
    from prima.sim._records import Pose, ReplyRule, ScheduledEvent, Zone
    from prima.sim._user import UserScript

__all__ = ["Setting"]


class Setting(Protocol):
    """What a simulator is built from (:meth:`~._simulator.Simulator.from_scenario`): the
    world and what happens in it, as a loaded scenario (:class:`prima.scenario.Scenario`)
    holds them. The simulator reads no scenario file and imports no scenario."""

    @property
    def map(self) -> WorldMap: ...
    @property
    def robot(self) -> Pose: ...
    @property
    def user(self) -> UserScript | None: ...
    @property
    def events(self) -> tuple[ScheduledEvent, ...]: ...
    @property
    def replies(self) -> tuple[ReplyRule, ...]: ...
    @property
    def zones(self) -> tuple[Zone, ...]: ...
    @property
    def seed(self) -> int: ...
    @property
    def rate(self) -> int: ...
    @property
    def noise(self) -> float: ...
    @property
    def heading_noise(self) -> float: ...
