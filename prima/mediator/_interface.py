"""The mediator's contracts: requests from applications, drivers for devices.

Applications (through their interpreters) send :class:`Request` objects and
receive events, end events and cancellations through an :class:`AppListener`.
Devices are driven through a :class:`Driver`, which starts one
:class:`AtomicBehavior` at a time per device set and reports its end with an
:class:`Outcome`. Time comes from an injected :class:`Clock`; the mediator
never reads the wall clock.

Nothing here knows about XML documents or physics.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import NamedTuple, Protocol

from prima.errors import MediationError
from prima.vocab import OnInterrupt, RunningOrder, Value

__all__ = [
    "AbId",
    "AppListener",
    "AtomicBehavior",
    "Call",
    "Channel",
    "Clock",
    "CommandId",
    "Driver",
    "Event",
    "ManualClock",
    "Outcome",
    "Request",
    "TreeId",
]

EMPTY: Mapping[str, Value] = MappingProxyType({})


def _empty() -> Mapping[str, Value]:
    return EMPTY


CommandId = int
"""Mediator-wide id of one requested Command (increasing from 1)."""

AbId = int
"""Mediator-wide id of one atomic behavior (increasing from 1)."""

TreeId = int
"""Mediator-wide id of one AB tree (increasing from 0)."""


@dataclass(frozen=True, init=False)
class Call:
    """One Command with its arguments, as an application requests it. (This record,
    :class:`Outcome` and :class:`Event` have their ``__init__`` written out: compiled, it
    runs at C speed, where the one ``dataclass`` writes runs as Python.)"""

    command: str
    args: Mapping[str, Value] = field(default_factory=_empty, hash=False)
    extra: Mapping[str, Value] = field(default_factory=_empty, hash=False)
    """Additional (hardware) arguments; only an FA may pass them."""
    label: str | None = None
    """The author's id for this Command, if any (shown in traces)."""
    extra_devices: frozenset[str] = frozenset()
    """Devices occupied beyond the catalog's (e.g. the speaker for a sensing prompt)."""

    def __init__(self, command: str, args: Mapping[str, Value] = EMPTY,
                 extra: Mapping[str, Value] = EMPTY, label: str | None = None,
                 extra_devices: frozenset[str] = frozenset()) -> None:
        object.__setattr__(self, "command", command)
        object.__setattr__(self, "args", args)
        object.__setattr__(self, "extra", extra)
        object.__setattr__(self, "label", label)
        object.__setattr__(self, "extra_devices", extra_devices)


class Request(NamedTuple):
    """A request: one Command or a chain of Commands (root first).

    An immutable record (a named tuple: applications build one per request, on
    the mediator's hot path, and a frozen dataclass takes several times longer).
    """

    app: str
    calls: tuple[Call, ...]
    order: RunningOrder = RunningOrder.AFTER_LATEST
    group: bool = False
    """Run the whole chain as one atomic behavior (thesis 4.1 (2))."""
    reactive: bool = False
    """The first Commands requested while handling a reactive event (rule 5); such a
    request also starts a reaction (see ``reaction``)."""
    reaction: bool = False
    """Requested while handling a reactive event (docs/rules.md 7.1): its tree takes over
    as a reaction, and keeps its precedence until it leaves working memory."""
    follows: CommandId | None = None
    """Made while handling this Command's end event or Q&A answer (rule 6a/6b):
    the request stays in that Command's tree and carries no reactivity."""
    face_user: bool = True
    """Its utterances are for the user: with the connect-channel policy, the mediator
    may turn the robot to the user first. False: they are about something else."""
    on_interrupt: OnInterrupt = OnInterrupt.RESTART
    """What the interrupt policy may do to its ABs: cut and restart them, cut and
    drop them, or never cut them."""
    user: bool = False
    """With ``reaction``: the reactive event was the user's own action (a touch, heard
    speech), not a perception or network event (docs/rules.md 7.1): the reaction is not
    overtaken by another application's later reaction to such an event until its
    first utterance has been said in full."""


class AtomicBehavior(NamedTuple):
    """What a driver is asked to perform: one AB, never cut once started.

    An immutable record (a named tuple: one is built for every start, on the
    mediator's hot path).
    """

    id: AbId
    app: str
    tree: TreeId
    calls: tuple[Call, ...]
    """One Call normally; several for a grouped request, run in order."""
    command_ids: tuple[CommandId, ...]
    devices: frozenset[str]
    iteration: int = 0
    """For a feedback Command, which loop iteration this is (0, 1, 2, ...)."""
    reactive: bool = False
    blended: frozenset[str] = frozenset()
    """Devices it shares with another running AB (the blend policy): a local motion
    over a global one, speech over quieter sound."""


@dataclass(frozen=True, init=False)
class Outcome:
    """How an atomic behavior ended, as the driver reports it."""

    values: Mapping[str, Value] = field(default_factory=_empty, hash=False)
    """Results: e.g. ``status``/``utterance`` of a Q&A, ``place`` reached."""
    terminal: bool = True
    """For a feedback iteration: True when the Command's loop is done."""

    def __init__(self, values: Mapping[str, Value] = EMPTY, terminal: bool = True) -> None:
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "terminal", terminal)


@dataclass(frozen=True, init=False)
class Event:
    """Something PRIMA posts to every loaded application (rule 5)."""

    name: str
    data: Mapping[str, Value] = field(default_factory=_empty, hash=False)
    time: float = 0.0

    def __init__(self, name: str, data: Mapping[str, Value] = EMPTY, time: float = 0.0
                 ) -> None:
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "time", time)


class Clock(Protocol):
    """Simulated time in seconds; injected, never the wall clock."""

    def now(self) -> float: ...

    def after(self, seconds: float, since: float | None = None) -> float:
        """The instant ``seconds`` after ``since`` (default: now), on the clock's grid.

        A clock that steps (the simulator) rounds the duration to the nearest
        step, and a positive duration to at least one step, so that every
        deadline is an instant the clock reaches exactly, once.
        """
        ...


class ManualClock:
    """A clock that moves only when told to; for tests and the run loop."""

    def __init__(self, start: float = 0.0) -> None:
        self._t = start

    def now(self) -> float:
        return self._t

    def after(self, seconds: float, since: float | None = None) -> float:
        """Continuous time: exactly ``seconds`` after ``since`` (default: now)."""
        return (self._t if since is None else since) + seconds

    def set(self, t: float) -> None:
        if t < self._t:
            raise MediationError(f"time cannot go back from {self._t} to {t}")
        self._t = t


class Driver(Protocol):
    """The devices' side: the simulator implements this (a scripted double ships too)."""

    def start(self, ab: AtomicBehavior) -> None:
        """Begin performing ``ab``; report its end later via ``Mediator.finish``."""

    def abandon(self, command_id: CommandId) -> None:
        """A feedback Command was cancelled between iterations: drop its loop state."""

    def cut(self, ab_id: AbId) -> bool:
        """Stop the running ``ab_id`` early (the interrupt policy): speech at its next
        word boundary, anything else at once. Report its end via ``Mediator.finish``
        (never from inside here) with ``interrupted=True`` and the words ``spoken``
        and ``unspoken`` in its outcome. False if it will not be cut (it is on its
        last word, or not running): it ends on its own, as usual."""

    def stop_words(self, ab_id: AbId) -> bool:
        """Cut the running ``ab_id`` at the end of the word under way, if it is saying
        words now (the user spoke over it: docs/rules.md 7.5), as :meth:`cut` does. False
        if it says nothing now (it turns before its words, say) or is on its last word."""


class Channel(Protocol):
    """What the connect-channel and restore-state policies ask of the robot (the run
    answers from the simulator): the mediator never looks at poses itself."""

    def unfaced(self) -> bool:
        """The user is detectable, and the robot does not face them (beyond the
        policy's tolerance): an utterance now would be spoken with its back turned."""

    def near(self, distance: float) -> bool:
        """The user is detectable no farther than ``distance`` (m) from the robot (the
        blend policy's bound)."""

    def pose(self) -> Mapping[str, Value]:
        """The robot's pose now, as the arguments of the Command that returns it there
        (``RESTORE_COMMAND``: ``x``, ``y``, ``heading``)."""

    def displaced(self, pose: Mapping[str, Value]) -> bool:
        """The robot is now farther from ``pose`` than the restore-state policy's
        tolerance: in position, or in heading if ``pose`` has one."""


class AppListener(Protocol):
    """The application's side: an interpreter implements this.

    Calls may re-enter the mediator (``submit`` and friends); the mediator
    defers its selection until the callback returns.
    """

    def event(self, event: Event) -> None:
        """A predefined or robot-specific event was posted."""

    def command_ended(self, command_id: CommandId, outcome: Outcome) -> None:
        """A requested Command finished (its last AB ended)."""

    def command_cancelled(self, command_id: CommandId) -> None:
        """A requested Command was cancelled before it started."""

    def takes(self, words: str) -> bool:
        """Whether this application takes what the user said outside a Q&A (an
        always-on grammar of its current state matches ``words``: docs/rules.md 7.5). The
        mediator asks before it gives the words to one application."""
