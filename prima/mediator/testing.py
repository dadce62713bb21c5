"""Scripted test doubles: drive the mediator without a simulator.

- :class:`ScriptedDriver`: AB durations and outcomes from a number, a table
  (by Command name) or a function; it refuses to start two ABs on one device.
- :class:`ScriptedApp`: an :class:`AppListener` that records what it is told
  and runs optional handlers (which may call back into the mediator).
- :class:`Harness`: a tiny deterministic discrete-event loop: a
  :class:`ManualClock`, pending AB ends, scheduled actions and the mediator's
  own deadlines, processed in time order.
- :func:`plain_scan`: the selection rule written the slow, obvious way, as an
  oracle for tests.

Example::

    h = Harness(duration={"Speak": 2.0})
    fa = h.app("fa", AppKind.FA)
    h.mediator.submit(Request("fa", (Call("Speak", {"text": "hi"}),)))
    h.run()
    assert h.clock.now() == 2.0
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Mapping

from prima.catalog import Catalog
from prima.errors import RunError, SimulationError
from prima.mediator._decisions import Decision, DecisionKind, Rule
from prima.mediator._interface import (
    AbId,
    AtomicBehavior,
    Channel,
    CommandId,
    Event,
    ManualClock,
    Outcome,
)
from prima.mediator._config import MediatorConfig
from prima.mediator._mediator import Mediator
from prima.mediator._ranking import outranks, rank
from prima.mediator._state import Node, NodeState
from prima.vocab import AppKind, Value

__all__ = ["CUTS_AND_BLENDS", "Harness", "ScriptedApp", "ScriptedDriver",
           "feedback_iterations", "plain_scan"]

CUTS_AND_BLENDS = MediatorConfig(interrupt=True, blend=True)
"""The configuration a :class:`Harness` mediates with unless given one: the interrupt and
blend policies on (a robot's profile switches them on where it declares
``<interruptible>`` and ``<blend>``; off, they are off by default), so that a test's
catalog alone says what may be cut and what blends, as the mediator's tests were
written."""

Durations = float | Mapping[str, float] | Callable[[AtomicBehavior], float]


def feedback_iterations(n: int | Mapping[str, int], values: Mapping[str, Value] | None = None,
                        ) -> Callable[[AtomicBehavior], Outcome]:
    """An outcome function: a feedback Command ends after ``n`` iterations."""
    def outcome(ab: AtomicBehavior) -> Outcome:
        count = n if isinstance(n, int) else n.get(ab.calls[0].command, 1)
        return Outcome(values=dict(values or {}), terminal=ab.iteration + 1 >= count)
    return outcome


class ScriptedDriver:
    """A driver whose ABs take scripted times and end with scripted outcomes."""

    def __init__(self, duration: Durations = 1.0,
                 outcome: Callable[[AtomicBehavior], Outcome] | None = None) -> None:
        self._duration = duration
        self._outcome = outcome
        self.started: list[AtomicBehavior] = []
        self.abandoned: list[CommandId] = []
        self.running: dict[AbId, AtomicBehavior] = {}
        self.on_start: Callable[[AtomicBehavior], None] | None = None
        self.cuts: list[AbId] = []
        """The ABs the mediator asked to cut, in order."""
        self.on_cut: Callable[[AtomicBehavior], None] | None = None

    def duration_of(self, ab: AtomicBehavior) -> float:
        d = self._duration
        if callable(d):
            return float(d(ab))
        if isinstance(d, Mapping):
            return float(d.get(ab.calls[0].command, d.get("*", 1.0)))
        return float(d)

    def outcome_of(self, ab: AtomicBehavior) -> Outcome:
        if self._outcome is None:
            return Outcome()
        return self._outcome(ab)

    def start(self, ab: AtomicBehavior) -> None:
        for other in self.running.values():
            shared = (ab.devices - ab.blended) & (other.devices - other.blended)
            if shared:
                raise SimulationError(
                    f"AB{ab.id} started on {sorted(shared)} held by running AB{other.id}")
        self.started.append(ab)
        self.running[ab.id] = ab
        if self.on_start is not None:
            self.on_start(ab)

    def abandon(self, command_id: CommandId) -> None:
        self.abandoned.append(command_id)

    def cut(self, ab_id: AbId) -> bool:
        ab = self.running.get(ab_id)
        if ab is None:
            return False
        self.cuts.append(ab_id)
        if self.on_cut is not None:
            self.on_cut(ab)
        return True

    def stop_words(self, ab_id: AbId) -> bool:
        """As :meth:`cut`, for an AB that says words (this driver keeps no time: they are
        always under way)."""
        ab = self.running.get(ab_id)
        if ab is None or not any(c.args.get(k) for c in ab.calls for k in _SAID):
            return False
        return self.cut(ab_id)

    def ended(self, ab_id: AbId) -> AtomicBehavior:
        return self.running.pop(ab_id)


class ScriptedApp:
    """An application listener that records everything and runs optional handlers."""

    def __init__(self, name: str,
                 on_event: Callable[[Event], None] | None = None,
                 on_ended: Callable[[CommandId, Outcome], None] | None = None,
                 on_cancelled: Callable[[CommandId], None] | None = None) -> None:
        self.name = name
        self.on_event = on_event
        self.on_ended = on_ended
        self.on_cancelled = on_cancelled
        self.events: list[Event] = []
        self.ended: list[tuple[CommandId, Outcome]] = []
        self.cancelled: list[CommandId] = []
        self.listens_for: tuple[str, ...] = ()
        """What it takes when the user speaks outside a Q&A (lower-case fragments)."""

    def event(self, event: Event) -> None:
        self.events.append(event)
        if self.on_event is not None:
            self.on_event(event)

    def command_ended(self, command_id: CommandId, outcome: Outcome) -> None:
        self.ended.append((command_id, outcome))
        if self.on_ended is not None:
            self.on_ended(command_id, outcome)

    def command_cancelled(self, command_id: CommandId) -> None:
        self.cancelled.append(command_id)
        if self.on_cancelled is not None:
            self.on_cancelled(command_id)

    def takes(self, words: str) -> bool:
        """Whether it takes the user's ``words`` (any of :attr:`listens_for` in them)."""
        return any(w in words.lower() for w in self.listens_for)

    @property
    def ended_ids(self) -> list[CommandId]:
        return [cid for cid, _ in self.ended]


class Harness:
    """A deterministic discrete-event loop around one mediator."""

    def __init__(self, catalog: Catalog | None = None, *, duration: Durations = 1.0,
                 outcome: Callable[[AtomicBehavior], Outcome] | None = None,
                 config: MediatorConfig = CUTS_AND_BLENDS, immediate: bool = False,
                 keep: bool = True, channel: Channel | None = None,
                 cut_after: float = 0.0) -> None:
        self.clock = ManualClock()
        self.decisions: list[Decision] = []
        self.driver = ScriptedDriver(duration, outcome)
        self.driver.on_start = self._scheduled_end
        self.driver.on_cut = self._scheduled_cut
        self.cut_after = cut_after
        """Seconds from a cut's request to the cut AB's end (the word under way)."""
        self.immediate = immediate
        """Zero-length ABs end from inside ``driver.start`` (re-entrant ``finish``)."""
        self.mediator = Mediator(catalog or Catalog.standard(), self.driver, self.clock,
                                 config=config,
                                 record=self.decisions.append if keep else None,
                                 channel=channel)
        self._queue: list[tuple[float, int, Callable[[], object]]] = []
        self._order = 0

    def app(self, name: str, kind: AppKind, *,
            on_event: Callable[[Event], None] | None = None,
            on_ended: Callable[[CommandId, Outcome], None] | None = None,
            on_cancelled: Callable[[CommandId], None] | None = None) -> ScriptedApp:
        """Register a :class:`ScriptedApp` (handlers as in its constructor)."""
        listener = ScriptedApp(name, on_event, on_ended, on_cancelled)
        self.mediator.register(name, kind, listener)
        return listener

    def _push(self, t: float, action: Callable[[], object]) -> None:
        self._order += 1
        heapq.heappush(self._queue, (t, self._order, action))

    def _scheduled_end(self, ab: AtomicBehavior) -> None:
        d = self.driver.duration_of(ab)
        if d <= 0 and self.immediate:
            self._finish(ab)
        else:
            self._push(self.clock.now() + max(d, 0.0), lambda: self._finish(ab))

    def _finish(self, ab: AtomicBehavior, outcome: Outcome | None = None) -> None:
        if ab.id not in self.driver.running:
            return  # cut before its scripted end
        self.driver.ended(ab.id)
        self.mediator.finish(ab.id, self.driver.outcome_of(ab) if outcome is None else outcome)

    def _scheduled_cut(self, ab: AtomicBehavior) -> None:
        cut = Outcome({"interrupted": True, "spoken": "", "unspoken": ""})
        self._push(self.clock.now() + self.cut_after, lambda: self._finish(ab, cut))

    def at(self, t: float, action: Callable[[], object]) -> None:
        """Run ``action`` when the clock reaches ``t``."""
        self._push(t, action)

    def step(self) -> bool:
        """Process the next instant's first item; False when nothing is left."""
        tq = self._queue[0][0] if self._queue else None
        td = self.mediator.next_deadline()
        options = [t for t in (tq, td) if t is not None]
        if not options:
            return False
        t = max(min(options), self.clock.now())
        self.clock.set(t)
        if td is not None and td <= t:
            self.mediator.advance()
            return True
        _t, _o, action = heapq.heappop(self._queue)
        action()
        return True

    def run(self, until: float | None = None, max_steps: int = 1_000_000) -> None:
        """Process events (up to time ``until``, if given)."""
        for _ in range(max_steps):
            if until is not None:
                tq = self._queue[0][0] if self._queue else None
                td = self.mediator.next_deadline()
                nxt = min((t for t in (tq, td) if t is not None), default=None)
                if nxt is None or nxt > until:
                    self.clock.set(max(until, self.clock.now()))
                    return
            if not self.step():
                return
        raise RunError(f"harness did not settle within {max_steps} steps")

    # ------------------------------------------------------------ inspection
    def kinds(self, *kinds: DecisionKind) -> list[Decision]:
        return [d for d in self.decisions if d.kind in kinds]

    def starts(self) -> list[Decision]:
        return self.kinds(DecisionKind.START)


def plain_scan(mediator: Mediator) -> list[AbId]:
    """The ABs a plain rank-order walk of the whole waiting list would start now.

    An oracle for tests: after any operation it must be empty (the mediator
    already started everything that could start).
    """
    wm = mediator._wm  # this module belongs to the package: it may look inside
    waiting = [n for n in wm.nodes.values() if n.state is NodeState.WAITING]
    waiting.sort(key=lambda n: rank(n, wm.pjf))
    busy = set(wm.busy)
    # the next ABs of reactions (and replies) keep their devices (docs/rules.md 7.1)
    nexts = [n for n in wm.nodes.values()
             if n.state is NodeState.PENDING and n.parent is not None
             and (n.tree.reaction is not None or n.protected or n.deferred)
             and (p := wm.nodes.get(n.parent)) is not None
             and (p.state in (NodeState.WAITING, NodeState.RUNNING)
                  or p.state is NodeState.PENDING and p.deferred)]
    reserved: set[str] = set()
    out: list[AbId] = []
    for n in waiting:
        held = mediator._holds.holder(n)
        if held is not None and held[0] is not Rule.KEEP_CHANNEL:
            continue  # held by a block or stream hold: it reserves nothing
        kept = any((r.app is not n.app or (r.app is n.taker and r.tree is not n.tree))
                   and r.devices & n.devices and outranks(r, n)
                   and not _behind_hold(mediator, r, n) for r in nexts)
        if n.devices & busy or n.devices & reserved or held is not None or kept:
            reserved |= n.devices
            continue
        out.append(n.id)
        busy |= n.devices
    return out


def _behind_hold(mediator: Mediator, r: Node, n: Node) -> bool:
    """The next AB ``r`` waits behind an AB that ``n``'s app's block or stream hold
    keeps: it keeps nothing from that app."""
    before = mediator._wm.nodes.get(r.parent) if r.parent is not None else None
    return before is not None and before.state is NodeState.WAITING \
        and mediator._holds.holds_back(n.app, before)


_SAID = ("text", "prompt", "say")
"""The arguments that are words said (of the common Commands)."""
