"""The live clock: simulated time paced to a wall clock.

The simulation stays in simulated time; this clock only says how far it may go now:
``speed`` simulated seconds per wall second while it plays, standing still while it
is paused, moved on by a step. The wall clock is injected (``time.monotonic`` by
default), so a test drives it by hand.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable

__all__ = ["MAX_SPEED", "LiveClock"]

MAX_SPEED = 1000.0
"""The fastest a session may go (simulated seconds per wall second)."""


class LiveClock:
    """How far simulated time may have gone now (not thread-safe: its owner locks)."""

    def __init__(self, speed: float = 1.0, wall: Callable[[], float] = time.monotonic,
                 paused: bool = True) -> None:
        if not 0 < speed <= MAX_SPEED:
            raise ValueError(f"speed must be above 0 and at most {MAX_SPEED:g}, not {speed}")
        self._wall = wall
        self.speed = speed
        self.paused = paused
        self._since = 0.0
        """The simulated time at :attr:`_wall_since`."""
        self._wall_since = wall()

    def now(self) -> float:
        """The simulated time (s) the run may have reached."""
        if self.paused:
            return self._since
        return self._since + (self._wall() - self._wall_since) * self.speed

    def _rebase(self) -> None:
        self._since, self._wall_since = self.now(), self._wall()

    def play(self) -> None:
        self._rebase()
        self.paused = False

    def pause(self) -> None:
        self._rebase()
        self.paused = True

    def step(self, seconds: float) -> None:
        """Let the run go ``seconds`` further (paused: it stops there again)."""
        self._rebase()
        self._since += max(0.0, seconds)

    def set_speed(self, speed: float) -> None:
        if not 0 < speed <= MAX_SPEED:
            raise ValueError(f"speed must be above 0 and at most {MAX_SPEED:g}, not {speed}")
        self._rebase()
        self.speed = speed

    def wait(self, until: float) -> float | None:
        """Wall seconds until the run may reach ``until`` (0: now; None: not while paused)."""
        ahead = until - self.now()
        if ahead <= 0:
            return 0.0
        if self.paused:
            return None
        return max(ahead / self.speed, 1e-4) if math.isfinite(ahead) else None
