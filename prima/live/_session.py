"""A live session: one run of a scenario, paced to a wall clock, that the author acts in.

The run is an ordinary :class:`prima.run.Run` of the session's base scenario, in a
thread of its own. Its simulator calls :meth:`Session._pace` where it could wait
(``Simulator.pace``): there the thread waits for the live clock, and gives the
simulator what the author did since, each at the tick after the one the author saw
(never before the simulator's own), through the path a scenario's own inputs take
(``ScriptedUser.add``, ``Simulator.add_event``). A script of the same inputs at the
same ticks therefore makes the same run: :meth:`Session.saved` writes it.

Everything another thread asks of the run (a save, an input) is handed to the run's
thread at its next pace point, under one lock: the run itself is only ever touched
by its own thread.
"""

from __future__ import annotations

import concurrent.futures
import math
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

from prima.errors import LocatedError, PrimaError, SimulationError
from prima.escape import unshowable
from prima.live._clock import LiveClock
from prima.live._scenario import ACTIONS, Added, Base
from prima.run import Run
from prima.sim import ADDED_ACTIONS, TimedAction
from prima.trace import TraceLine
from prima.vocab import MAX_TEXT

__all__ = ["LiveError", "Session", "Stopped"]

MAX_SENDER = 200
"""The longest name of a message's sender (characters)."""
MAX_COORDINATE = 10_000.0
"""How far from the map's origin a walk may go (m), as a scenario's coordinates."""

_T = TypeVar("_T")


class LiveError(PrimaError):
    """An input or a request the session refuses: said to the page, nothing changes."""


class Stopped(BaseException):
    """The session is over (the server stops): the run's thread unwinds through the run.
    A BaseException, like Ctrl-C: nothing on the way catches it."""


@dataclass(frozen=True)
class _Input:
    """An input the author gave, waiting for the run's thread."""

    kind: str
    seen: int
    """The tick the live clock had reached when it came: it is played after it."""
    text: str | None = None
    x: float | None = None
    y: float | None = None
    sender: str | None = None


def _words(value: object, what: str, longest: int) -> str:
    """Words from the page: a non-empty string of at most ``longest`` characters with no
    control character, line or paragraph separator or bidirectional control (a scenario
    file can hold the rest as they are; a direction control would show the words, and
    what follows them on the page, in another order than they were said)."""
    if not isinstance(value, str) or not value.strip():
        raise LiveError(f"{what}: give some words")
    if len(value) > longest:
        raise LiveError(f"{what}: at most {longest:,} characters")
    c = unshowable(value)
    if c is not None:
        raise LiveError(f"{what}: no control or direction characters (U+{ord(c):04X})")
    return value


def _coordinate(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) \
            or abs(value) > MAX_COORDINATE or not math.isfinite(value):  # (ints of any size)
        raise LiveError(f"{what}: a number of metres within {MAX_COORDINATE:,g} of the origin")
    return round(float(value), 2)


class Session:
    """One live run: :meth:`start` it, :meth:`act` in it, :meth:`save` it, :meth:`stop` it.

    ``folder`` receives the base scenario's file (the run reads it); ``on_change`` is
    called, from the run's thread, whenever there is something new to show (lines, a
    pose, the end): it must only take note (the server wakes its loop); ``tee`` gets each
    trace line too, from the run's thread, as it is made (Foxglove's server)."""

    def __init__(self, base: Base, folder: Path, *, until: float, speed: float = 1.0,
                 wall: Callable[[], float] = time.monotonic,
                 on_change: Callable[[], None] = lambda: None,
                 tee: Callable[[TraceLine], None] | None = None) -> None:
        self.base = base
        self.tee = tee
        """Gets each trace line too (Foxglove's server), from the run's thread."""
        self.file = folder / "live.xml"
        self.file.write_text(base.text(until), encoding="utf-8")
        self.rows: list[dict[str, Any]] = []
        """The trace so far, as its jsonl records (appended by the run's thread only)."""
        self.run = Run(self.file, sink=self._line)
        self.hz = self.run.sim.kernel.hz
        self.until = self.run.until
        self.world = self.run.scenario.map
        self.clock = LiveClock(speed, wall, paused=True)
        self.added: list[Added] = []
        """What the author did, as played (appended by the run's thread only)."""
        self.state = "ready"
        """``ready``, ``running``, ``ended`` (the run reached its end), ``stopped`` or
        ``failed`` (:attr:`error` says why)."""
        self.error = ""
        self.pose: tuple[float, Any, Any] = (0.0, None, None)
        """The latest (time, robot, user) the run's thread showed: (x, y, heading)."""
        self.on_change = on_change
        self.idle = False
        """The run's thread waits for the live clock (:meth:`caught_up` says whether it
        has gone as far as the clock lets it)."""
        self.behind = 0.0
        """The most the run has been behind the live clock while it played (simulated s): a
        run that keeps real time stays within a few milliseconds."""
        self.points = self.late = 0
        """Where the run could wait for the clock while it played, and where it was more
        than 0.05 s behind it."""
        self._waits_for = 0.0
        """When idle, the time the run waits to reach."""
        self._lock = threading.Lock()
        """Guards what other threads hand the run's thread (inputs, calls, the clock)."""
        self._wake = threading.Event()
        """Set when the run's thread should look again (an input, a call, the clock)."""
        self._changed = threading.Condition()
        self._inputs: list[_Input] = []
        self._calls: list[tuple[Callable[[], Any], concurrent.futures.Future[Any]]] = []
        self._stopping = False
        self._thread: threading.Thread | None = None
        robot, user, _seen = self.run.sim.poses()
        self.pose = (0.0, robot, user)
        if self.run.sim.user is None:
            raise PrimaError("a live session needs a user in its scenario")

    # ------------------------------------------------------------ the run's thread

    def start(self) -> None:
        """Start the run (the clock stays paused until :meth:`play`)."""
        self.run.sim.pace = self._pace
        self.state = "running"
        self._thread = threading.Thread(target=self._main, name="prima-live-run", daemon=True)
        self._thread.start()

    def _main(self) -> None:
        try:
            self.run.run()
            self.state = "ended"
        except Stopped:
            self.state = "stopped"
        except (LocatedError, PrimaError) as exc:
            self.state, self.error = "failed", str(exc)
        except Exception as exc:  # noqa: BLE001 - whatever the run did, the server goes on
            self.state, self.error = "failed", f"{type(exc).__name__}: {exc}"
        finally:
            with self._lock:
                calls, self._calls = self._calls, []
            for call, future in calls:  # (what was asked of the run, answered without it)
                _answer(call, future)
            self._notify()

    def _line(self, line: TraceLine) -> None:
        self.rows.append(line.to_dict())
        if self.tee is not None:
            self.tee(line)

    def _pace(self, tick: int) -> None:
        """The simulator may go on to ``tick``: wait for the live clock, and give it what
        the author did meanwhile."""
        sim = self.run.sim
        robot, user, _seen = sim.poses()
        self.pose = (sim.now(), robot, user)
        first = True
        while True:
            self._wake.clear()  # (before looking: a change made after it wakes the wait)
            with self._lock:
                if self._stopping:
                    raise Stopped
                if first and not self.clock.paused:
                    late = self.clock.now() - self.pose[0]
                    self.behind = max(self.behind, late)
                    self.points += 1
                    self.late += late > 0.05
                    first = False
                added = self._give()
                calls, self._calls = self._calls, []
                wait = 0.0 if added else self.clock.wait(tick / self.hz)
            for call, future in calls:
                _answer(call, future)
            if wait == 0.0:
                break
            if not self.idle:
                self.idle, self._waits_for = True, tick / self.hz
                self._notify()
            self._wake.wait(wait)
        self.idle = False
        self._notify()

    def _give(self) -> bool:
        """Give the simulator the inputs waiting (the lock held): each at the tick after
        the one the author saw, and after the simulator's own; True if any was given."""
        sim = self.run.sim
        given = False
        for waiting in self._inputs:
            tick = max(waiting.seen, sim.kernel.tick) + 1
            added = Added(tick, waiting.kind, waiting.text, waiting.x, waiting.y, waiting.sender)
            real = added.given(self.hz)
            try:
                if isinstance(real, TimedAction):
                    assert sim.user is not None  # (checked when the session was made)
                    sim.user.add(real)
                else:
                    sim.add_event(real)
            except SimulationError:  # (the bound: refused when it was given)
                continue
            self.added.append(added)
            given = True
        self._inputs = []
        return given

    def _ask(self, call: Callable[[], _T]) -> concurrent.futures.Future[_T]:
        """Have the run's thread do ``call`` at its next pace point (at once, here, when the
        run is not going)."""
        future: concurrent.futures.Future[_T] = concurrent.futures.Future()
        with self._lock:
            if self._thread is not None and self._thread.is_alive() and not self._stopping:
                self._calls.append((call, future))
                self._wake.set()
                return future
        _answer(call, future)
        return future

    # ------------------------------------------------------------ what the page asks

    def act(self, message: Mapping[str, object]) -> None:
        """An input from the page (``{"act": "say", "text": ...}``, ``touch``, ``walk``
        with ``x`` and ``y``, ``follow``, ``stop``, ``message`` with ``sender`` and
        ``text``); raises LiveError for one the session refuses."""
        kind = message.get("act")
        if kind not in ACTIONS:
            raise LiveError(f"no such action: give one of {', '.join(ACTIONS)}")
        kind = str(kind)
        text = x = y = sender = None
        if kind == "say":
            text = _words(message.get("text"), "say", MAX_TEXT)
        elif kind == "message":
            sender = _words(message.get("sender"), "the message's sender", MAX_SENDER)
            text = _words(message.get("text"), "the message", MAX_TEXT)
        elif kind == "walk":
            x, y = _coordinate(message.get("x"), "x"), _coordinate(message.get("y"), "y")
        with self._lock:
            if self.state != "running" or self._stopping:
                raise LiveError(f"the run is over ({self.state}): it takes no more input")
            if len(self.added) + len(self._inputs) >= ADDED_ACTIONS:
                raise LiveError(f"a session takes at most {ADDED_ACTIONS:,} inputs")
            seen = math.floor(self.clock.now() * self.hz + 1e-6)
            self._inputs.append(_Input(kind, seen, text, x, y, sender))
            self._wake.set()

    def play(self) -> None:
        with self._lock:
            self.clock.play()
            self._wake.set()

    def pause(self) -> None:
        with self._lock:
            self.clock.pause()
            self._wake.set()

    def step(self, seconds: float) -> None:
        """Paused, let the run go ``seconds`` of simulated time further."""
        if not (math.isfinite(seconds) and 0 < seconds <= 60):
            raise LiveError("a step is more than 0 and at most 60 simulated seconds")
        with self._lock:
            if not self.clock.paused:
                self.clock.pause()
            self.clock.step(seconds)
            self._wake.set()

    def set_speed(self, speed: float) -> None:
        with self._lock:
            try:
                self.clock.set_speed(speed)
            except ValueError as exc:
                raise LiveError(str(exc)) from None
            self._wake.set()

    def status(self) -> dict[str, object]:
        """Where the session is: the run's time, the clock's, paused, speed, state."""
        with self._lock:
            clock, paused, speed = self.clock.now(), self.clock.paused, self.clock.speed
        return {"t": round(self.reached(), 3), "clock": round(min(clock, self.until), 3),
                "paused": paused, "speed": speed, "state": self.state, "error": self.error,
                "until": self.until, "added": len(self.added), "idle": self.caught_up(),
                "behind": round(self.behind, 4), "points": self.points, "late": self.late}

    def saved(self, folder: Path | None) -> str:
        """The session so far as a scenario (paths relative to ``folder``; absolute without
        one), ending at the tick after both the run's and the author's last input: made
        by the run's thread, after what the author did before it was asked."""
        def make() -> str:
            last = max((a.tick for a in self.added), default=0)
            reached = math.floor(self.reached() * self.hz + 1e-6)
            until_tick = min(max(self.run.sim.kernel.tick, reached, last) + 1,
                             round(self.until * self.hz))
            return self.base.saved(list(self.added), until_tick, folder)
        return self._ask(make).result()

    def stop(self, timeout: float = 10.0) -> None:
        """End the run (its thread unwinds) and wait for its thread."""
        with self._lock:
            self._stopping = True
            self._wake.set()
        if self._thread is not None:
            self._thread.join(timeout)

    def reached(self) -> float:
        """How far the run has gone, in simulated seconds: while it waits for the live
        clock, the clock's time up to the tick it waits to go on to (nothing changes
        before that tick: the simulator skips the time in between), else the time of
        its latest pose."""
        with self._lock:
            if self.state == "ended":
                return self.until
            if self.idle:
                return max(self.pose[0], min(self.clock.now(), self._waits_for, self.until))
            return self.pose[0]

    def caught_up(self) -> bool:
        """Whether the run has gone as far as the live clock lets it, with nothing waiting
        for it (or is over)."""
        if self.state != "running":
            return True
        with self._lock:
            return (self.idle and self.clock.now() < self._waits_for and not self._inputs
                    and not self._calls)

    def wait_for(self, ready: Callable[[], bool], timeout: float) -> bool:
        """Block until ``ready()`` holds (asked whenever the run shows something new, and
        when it is over); False if ``timeout`` wall seconds pass first."""
        deadline = time.monotonic() + timeout
        with self._changed:
            while not ready():
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._changed.wait(left)
        return True

    def _notify(self) -> None:
        with self._changed:
            self._changed.notify_all()
        self.on_change()


def _answer(call: Callable[[], _T], future: concurrent.futures.Future[_T]) -> None:
    try:
        future.set_result(call())
    except Exception as exc:  # noqa: BLE001 - handed to whoever waits for it
        future.set_exception(exc)

