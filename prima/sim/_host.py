"""What the simulator gives the parts it drives: the behaviours that perform Commands
(:class:`Body`) and the scripted user (:class:`Stage`). Each is typed by what it may
read and do, not by the whole :class:`~._simulator.Simulator`, which satisfies both:
the simulator imports the behaviours and the user, and neither imports it back."""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from prima.catalog import Catalog
    from prima.mediator import AtomicBehavior, Call
    from prima.sim._kernel import Kernel, Waker
    from prima.sim._maps import Place, WorldMap
    from prima.sim._records import Picture, Pose, UserAction
    from prima.sim._spec import RobotSpec
    from prima.sim._world import World
    from prima.vocab import Value

__all__ = ["Body", "Stage"]


class Stage(Protocol):
    """The simulator as the scripted user sees it: the world it walks in, the clock,
    what it reports, and whether the robot hears it."""

    kernel: Kernel
    world: World
    map: WorldMap
    spec: RobotSpec
    reports: int

    def now(self) -> float: ...

    def report_user(self, action: UserAction) -> None: ...

    def emit(self, name: str, data: Mapping[str, Value]) -> None: ...

    def hear(self, text: str) -> bool: ...

    def hearable(self) -> bool: ...

    def listening(self) -> bool: ...

    def route(self, x: float, y: float, tx: float, ty: float,
              radius: float) -> list[tuple[float, float]]: ...


class Body(Stage, Protocol):
    """The simulator as a behaviour sees it (one performing a Command): the robot's
    world, devices and senses, and the reports its Command makes."""

    catalog: Catalog
    seen: bool
    navigating: int
    picture_count: int
    pictures: deque[Picture]

    def ticks(self, seconds: float) -> int: ...

    def speech_duration(self, text: str) -> float: ...

    def utter(self, command_id: int, text: str, ticks: int) -> None: ...

    def loop_state(self, command_id: int) -> dict[str, Value]: ...

    def end_loop(self, command_id: int) -> None: ...

    def longest_for(self, app: str) -> float: ...

    def localize(self) -> Pose: ...

    def search(self) -> None: ...

    def plan(self, goal: str) -> tuple[Place | None, list[Place]]: ...

    def performing(self, ab: AtomicBehavior, call: Call) -> None: ...

    def blended_locally(self, ab: AtomicBehavior, command: str) -> bool: ...

    def blend_bound(self) -> float | None: ...

    def open_prompt(self, command_id: int, waker: Waker) -> bool: ...

    def close_prompt(self, command_id: int) -> None: ...

    def open_mic(self, waker: Waker) -> bool: ...

    def close_mic(self) -> None: ...

    def asking(self, prompt: str, ticks: int = 0) -> None: ...

    def ask(self, prompt: str) -> None: ...

    def announce_lost(self) -> None: ...
