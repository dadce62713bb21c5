"""Discrete-event kernel: integer ticks, a time-ordered agenda, generator processes.

Simulated time is an integer tick count (``tick / hz`` seconds), so repeated
runs never drift apart through float rounding. Work is kept in a heap ordered
by (tick, insertion number): two runs that schedule the same things in the
same order do the same things in the same order.

Behaviors and the scripted user are generator *processes* that yield a
:class:`Wait`: sleep for some ticks, wait until a predicate holds (polled at
sensing times), or start something (a motion, listening) and wait until it
calls back. A process is resumed with the value that woke it. It ends when it
returns, or when it yields :func:`finish` (the same, for less in the compiled build).
"""

from __future__ import annotations

import heapq
from collections.abc import Callable, Generator
from typing import Any, Final

from prima.errors import SimulationError

__all__ = ["Kernel", "ProcGen", "Process", "Room", "Wait", "Waker", "finish", "idle", "signal",
           "sleep", "until"]

Waker = Callable[[Any], None]


class Wait:
    """What a process waits for; whichever comes first resumes it."""

    __slots__ = ("ticks", "pred", "start", "timeout", "unchanged", "until")

    def __init__(self, ticks: int | None = None, pred: Callable[[], bool] | None = None,
                 start: Callable[[Waker], bool] | None = None, timeout: Any = None,
                 unchanged: Callable[[], bool] | None = None, until: int | None = None) -> None:
        self.ticks = ticks
        """Resume with ``timeout`` after this many ticks."""
        self.pred = pred
        """Resume with True as soon as this holds (checked at sensing times)."""
        self.start = start
        """Called with a waker; return False if there is nothing to wait for."""
        self.timeout = timeout
        """What it resumes with when ``ticks`` pass; of a wait for nothing (:func:`finish`),
        what the process returns."""
        self.unchanged = unchanged
        """An idle sleep (:func:`idle`): whether the process would, woken now, do nothing."""
        self.until = until
        """An idle sleep: the tick before which the process sleeps ``ticks`` again and
        again while it does nothing (at that tick it does something: it ends)."""


def sleep(ticks: int) -> Wait:
    """Resume after ``ticks`` ticks (zero: later in the same tick)."""
    wait = _SLEEPS.get(ticks)
    if wait is None:
        wait = Wait(ticks=max(0, ticks))
        if len(_SLEEPS) < _SLEEPS_KEPT:
            _SLEEPS[ticks] = wait
    return wait


_SLEEPS: Final[dict[int, Wait]] = {}
"""The waits of :func:`sleep` by length (the kernel never changes a wait: processes
share them; a behavior sleeps its control period again and again)."""
_SLEEPS_KEPT: Final = 1024


def idle(ticks: int, unchanged: Callable[[], bool], until: int | None = None) -> Wait:
    """Sleep ``ticks`` (at least one), as a process that polls something and has just
    found nothing to do: while ``unchanged()`` holds, waking it would do nothing again,
    and it would sleep ``ticks`` again (up to ``until``, where it would end). The
    kernel may then skip such wakes (:meth:`Kernel.skip_idle`): it keeps the process on
    its grid, as if it had woken, without waking it."""
    return Wait(ticks=max(1, ticks), unchanged=unchanged,
                until=until if until is not None else _NEVER)


_NEVER: Final = 1 << 60
"""An idle sleep's ``until`` when it has none: never (a tick no run reaches)."""


def until(pred: Callable[[], bool], ticks: int | None = None) -> Wait:
    """Resume with True when ``pred()`` holds, or with False after ``ticks``."""
    return Wait(ticks=ticks, pred=pred, timeout=False)


def signal(start: Callable[[Waker], bool], ticks: int | None = None,
           timeout: Any = None) -> Wait:
    """Call ``start(waker)``; resume with what the waker is given, or ``timeout``."""
    return Wait(ticks=ticks, start=start, timeout=timeout)


def finish(value: Any) -> Wait:
    """End the process with ``value``, as ``return value`` would (its ``exit`` gets it at the
    same point): a wait for nothing, after which it is never resumed. For the compiled
    build, where a generator's return raises a StopIteration with a traceback (some 4,000
    instructions, several times the rest of a wake)."""
    return Wait(timeout=value)


ProcGen = Generator[Wait, Any, Any]


class Process:
    """A running generator with a token that invalidates stale wake-ups."""

    __slots__ = ("gen", "token", "alive", "exit", "idle")

    def __init__(self, gen: ProcGen, exit: Callable[[Any], None] | None) -> None:
        self.gen = gen
        self.token = 0
        self.alive = True
        self.exit = exit
        self.idle: Wait | None = None
        """The idle sleep (:func:`idle`) it sleeps in, if it sleeps in one."""


class Kernel:
    """The agenda and the processes; ``tick`` only moves forward."""

    def __init__(self, hz: int) -> None:
        self.hz = hz
        self.tick = 0
        self._heap: list[tuple[int, int, Any, tuple[int, Any] | None]] = []
        """(tick, insertion number, what, wake): a function to call (``wake`` None) or a
        process to resume with ``wake``'s (token, value)."""
        self._seq = 0
        self._polls: list[tuple[Process, int, Callable[[], bool]]] = []

    def ticks(self, seconds: float) -> int:
        """A duration in whole ticks (nearest; at least one for a positive duration)."""
        n = round(seconds * self.hz)
        return max(1, n) if seconds > 0 else 0

    def at(self, tick: int, fn: Callable[[], None]) -> None:
        """Do ``fn`` at ``tick`` (never earlier than now)."""
        self._seq += 1
        heapq.heappush(self._heap, (max(tick, self.tick), self._seq, fn, None))

    def reserve(self, n: int) -> range:
        """Keep ``n`` insertion numbers for work added later (:meth:`at_reserved`): within
        its tick, such work goes where work scheduled now goes, before what is scheduled
        after this call. What a live user does (``prima live``) is played so in the place
        a scripted user's actions have: the same run as a script of it makes."""
        first = self._seq + 1
        self._seq += n
        return range(first, first + n)

    def at_reserved(self, tick: int, number: int, fn: Callable[[], None]) -> None:
        """Do ``fn`` at ``tick`` (never earlier than now) in the order of ``number``, one of
        the insertion numbers :meth:`reserve` kept (each used once)."""
        heapq.heappush(self._heap, (max(tick, self.tick), number, fn, None))

    def _wake(self, tick: int, proc: Process, token: int, value: Any) -> None:
        """Resume ``proc`` with ``value`` at ``tick`` (not earlier than now), unless it
        was resumed since ``token``: what :meth:`at` does with a function that fires it,
        without making one (a process wakes again and again)."""
        self._seq += 1
        heapq.heappush(self._heap, (max(tick, self.tick), self._seq, proc, (token, value)))

    def next_tick(self) -> int | None:
        return self._heap[0][0] if self._heap else None

    def polls_hold(self) -> bool:
        """Whether a predicate a process waits for (:func:`until`) holds now. (The
        predicates only read: asking is harmless.)"""
        return any(pred() for proc, token, pred in self._polls
                   if proc.alive and proc.token == token)

    def idle_first(self, limit: int) -> bool:
        """Whether the agenda's first work, due by ``limit``, wakes a process that
        sleeps in an idle sleep (:meth:`skip_idle` may skip it)."""
        heap = self._heap
        if not heap:
            return False
        tick, _seq, what, wake = heap[0]
        return wake is not None and tick <= limit and what.idle is not None

    def due(self) -> bool:
        return bool(self._heap) and self._heap[0][0] <= self.tick

    def run_due(self) -> bool:
        """Do everything scheduled up to now; True if anything ran."""
        heap = self._heap
        ran = False
        while heap and heap[0][0] <= self.tick:
            _tick, _seq, what, wake = heapq.heappop(heap)
            if wake is None:
                what()
            else:
                self._fire(what, *wake)
            ran = True
        return ran

    def skip_idle(self, limit: int) -> int:
        """Skip the wakes, up to the tick ``limit``, of processes that sleep in an idle
        sleep (:func:`idle`) and would do nothing: each is put to sleep again as its
        wake would (the same ticks, in the same order), without waking it. Only the
        first wake of the agenda is looked at, again and again: nothing else is due
        before it. The caller knows that nothing a process reads changes meanwhile (the
        simulator: no body moves); returns how many wakes were skipped.

        A process whose next wake would come first again is asked once: ``unchanged``
        only reads, and nothing it reads changes meanwhile, so its answer would be the
        same. Its wakes up to the agenda's next other work are skipped at once (the
        same ticks, tokens and insertion numbers as one by one)."""
        heap = self._heap
        skipped = 0
        while heap:
            tick, _seq, proc, wake = heap[0]
            if wake is None or tick > limit:
                break
            wait = proc.idle
            if (wait is None or not proc.alive or proc.token != wake[0] or tick >= wait.until
                    or not wait.unchanged()):
                break
            # (it comes first again at a tick before the others' first: a tie goes to
            # them, numbered earlier; there the same checks would skip it again)
            bound = min(limit + 1, wait.until)
            if len(heap) > 1:
                bound = min(bound, heap[1][0])  # (of two: compiled, a comparison)
                if len(heap) > 2:
                    bound = min(bound, heap[2][0])
            # (one sleep at least, then as many as reach ``bound``: all but the last end
            # before it, so before ``until``, and whole; the last is cut at ``until``)
            every = wait.ticks
            n = max(1, (bound - tick + every - 1) // every)
            tick = min(tick + n * every, wait.until)
            proc.token += n
            self._seq += n
            heapq.heapreplace(heap, (tick, self._seq, proc, (proc.token, wait.timeout)))
            skipped += n
        return skipped

    def check_polls(self) -> bool:
        """Resume processes whose awaited predicate now holds; True if any was."""
        if not self._polls:
            return False
        polls, self._polls = self._polls, []
        keep = []
        woke = False
        for entry in polls:
            proc, token, pred = entry
            if not proc.alive or proc.token != token:
                continue
            if pred():
                self._fire(proc, token, True)
                woke = True
            else:
                keep.append(entry)
        self._polls = keep + self._polls  # waits begun by the processes just resumed
        return woke

    def spawn(self, gen: ProcGen, exit: Callable[[Any], None] | None = None) -> Process:
        """Start a process later in the current tick; ``exit`` gets its return value."""
        proc = Process(gen, exit)
        self._wake(self.tick, proc, 0, None)
        return proc

    def kill(self, proc: Process | None) -> None:
        """Stop a process for good (its ``exit`` is not called)."""
        if proc is not None and proc.alive:
            proc.alive = False
            proc.token += 1
            proc.gen.close()

    def _fire(self, proc: Process, token: int, value: Any) -> None:
        if not proc.alive or proc.token != token:
            return
        proc.token += 1
        try:
            wait = proc.gen.send(value)
        except StopIteration as stop:
            self._ended(proc, stop.value)
            return
        token = proc.token
        proc.idle = wait if wait.unchanged is not None else None
        if wait.start is not None:
            def waker(v: Any = True) -> None:
                self._wake(self.tick, proc, token, v)
            if wait.start(waker) is False:
                self._wake(self.tick, proc, token, True)
                return
        if wait.ticks is None:
            if wait.start is None and wait.pred is None:  # a wait for nothing: :func:`finish`
                self._ended(proc, wait.timeout)
                return
        else:
            self._wake(self.tick + wait.ticks, proc, token, wait.timeout)
        if wait.pred is not None:
            self._polls.append((proc, token, wait.pred))

    @staticmethod
    def _ended(proc: Process, value: Any) -> None:
        """The process is over, by returning ``value`` or yielding :func:`finish`."""
        proc.alive = False
        if proc.exit is not None:
            proc.exit(value)

class Room:
    """Insertion numbers a kernel keeps (:meth:`Kernel.reserve`) for work added as a run
    goes (a live user's actions, a network message sent live): each is done at its time,
    after now, where the work scheduled for that tick beforehand goes."""

    def __init__(self, kernel: Kernel, n: int, what: str) -> None:
        self._kernel = kernel
        self._numbers = iter(kernel.reserve(n))
        self._n = n
        self._what = what
        """What is added, for the errors (``input``, ``action``)."""

    def add(self, at: float, fn: Callable[[], None]) -> None:
        """Do ``fn`` at ``at`` (s). Raises SimulationError for a time not after now, or
        past the number kept."""
        k = self._kernel
        tick = round(at * k.hz)
        if tick <= k.tick:
            raise SimulationError(f"an {self._what} added at {at:g} s comes too late: the "
                                  f"run is at {k.tick / k.hz:g} s")
        number = next(self._numbers, None)
        if number is None:
            raise SimulationError(f"at most {self._n} {self._what}s may be added to a run")
        k.at_reserved(tick, number, fn)
