"""A stand-in for the mediator: perform Commands one after another on a simulator.

:class:`CommandRunner` is a scripted test double (it ships in the package so
tests, benchmarks and the ``python -m prima.sim run`` command can drive the
simulator without documents or a mediator). It starts one atomic behavior at
a time, repeats a feedback Command's iterations until one is terminal, and
records everything the simulator reports, in order, as :class:`TraceEntry`.
"""

from __future__ import annotations

import enum
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType

from prima.catalog import Catalog
from prima.errors import SimulationError
from prima.mediator import AtomicBehavior, Call, Event, Outcome
from prima.sim._records import UserAction, ZoneEntry
from prima.sim._simulator import Simulator
from prima.vocab import Value

__all__ = ["CommandRunner", "EntryKind", "TraceEntry"]


class EntryKind(str, enum.Enum):
    """What a :class:`TraceEntry` records."""

    END = "end"
    """An atomic behavior ended (``name``: its Command; ``data``: its values)."""
    EVENT = "event"
    """The simulator posted an event (``name``: the event; ``data``: its data)."""
    USER = "user"
    """The scripted user did something (``name``: the action; ``data``: text, target, heard)."""
    ZONE = "zone"
    """The robot entered a zone (``name``: the zone; ``data``: its EA)."""


@dataclass(frozen=True)
class TraceEntry:
    """One thing that happened, at simulated time ``time`` (s)."""

    time: float
    kind: EntryKind
    name: str
    """The Command (end), event name (event), user action (user) or zone (zone)."""
    data: Mapping[str, Value] = field(default_factory=dict)
    iteration: int = 0
    terminal: bool = True

    def to_dict(self) -> dict[str, object]:
        return {"time": self.time, "kind": self.kind.value, "name": self.name,
                "data": dict(self.data), "iteration": self.iteration,
                "terminal": self.terminal}

    def __str__(self) -> str:
        data = ", ".join(f"{k}={v!r}" for k, v in self.data.items())
        extra = f" #{self.iteration}" if self.kind is EntryKind.END and self.iteration else ""
        more = "" if self.terminal else " (more)"
        return f"{self.time:8.2f}  {self.kind.value:5}  {self.name}{extra}{more}  {data}"


class CommandRunner:
    """Performs queued Commands in order on ``sim``; records what happens.

    ``catalog`` gives the devices each Command occupies (default: the
    simulator's own catalog).
    """

    def __init__(self, sim: Simulator, catalog: Catalog | None = None) -> None:
        self.sim = sim
        self.catalog = catalog if catalog is not None else sim.catalog
        self.trace: list[TraceEntry] = []
        self._queue: deque[Call] = deque()
        self._ab = 0
        self._cid = 0
        self._current: tuple[Call, int, int] | None = None
        self._stopping = False
        sim.finished = self._finished
        sim.on_event = self._event
        sim.on_user = self._user
        sim.on_zone = self._zone

    def queue(self, *calls: Call) -> None:
        """Perform these Commands after the ones already queued."""
        self._queue.extend(calls)
        if self._current is None:
            self._next()

    def stop_loop(self) -> None:
        """End the running feedback Command after its current iteration (like a cancel)."""
        self._stopping = self._current is not None

    @property
    def busy(self) -> bool:
        return self._current is not None

    def run(self, until: float) -> list[TraceEntry]:
        """Advance the simulator event by event up to ``until``; return the trace."""
        sim = self.sim
        while True:
            t = sim.next_time()
            if t is None or t > until:
                break
            sim.advance_to(t)
        sim.advance_to(until)
        return self.trace

    def ends(self, command: str | None = None) -> list[TraceEntry]:
        return [e for e in self.trace if e.kind is EntryKind.END and command in (None, e.name)]

    def events(self, name: str | None = None) -> list[TraceEntry]:
        return [e for e in self.trace if e.kind is EntryKind.EVENT and name in (None, e.name)]

    # ---- callbacks ------------------------------------------------------------------

    def _devices(self, call: Call) -> frozenset[str]:
        spec = self.catalog.get(call.command)
        devices = spec.devices_for(call.args) if spec is not None else frozenset()
        return devices | call.extra_devices

    def _next(self) -> None:
        if not self._queue:
            self._current = None
            return
        call = self._queue.popleft()
        self._cid += 1
        self._start(call, self._cid, 0)

    def _start(self, call: Call, cid: int, iteration: int) -> None:
        self._ab += 1
        self._current = (call, cid, iteration)
        self.sim.start(AtomicBehavior(self._ab, "runner", 0, (call,), (cid,),
                                      self._devices(call), iteration))

    def _finished(self, ab: int, outcome: Outcome) -> None:
        if self._current is None:
            raise SimulationError(f"atomic behavior {ab} ended but the runner started none")
        call, cid, iteration = self._current
        self.trace.append(TraceEntry(self.sim.now(), EntryKind.END, call.command,
                                     MappingProxyType(dict(outcome.values)),
                                     iteration, outcome.terminal))
        if not outcome.terminal and not self._stopping:
            self._start(call, cid, iteration + 1)
        else:
            if not outcome.terminal:
                self.sim.abandon(cid)
            self._stopping = False
            self._next()

    def _event(self, event: Event) -> None:
        self.trace.append(TraceEntry(event.time, EntryKind.EVENT, event.name, event.data))

    def _user(self, action: UserAction) -> None:
        data: dict[str, Value] = {}
        if action.text is not None:
            data["text"] = action.text
        if action.target is not None:
            data["target"] = action.target
        if action.heard is not None:
            data["heard"] = action.heard
        self.trace.append(TraceEntry(action.time, EntryKind.USER, action.action.value, data))

    def _zone(self, entry: ZoneEntry) -> None:
        self.trace.append(TraceEntry(entry.time, EntryKind.ZONE, entry.zone, {"ea": entry.ea}))
