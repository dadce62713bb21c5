"""The simulator: a world, a scripted user and the environment, driven by events.

:class:`Simulator` implements the mediator's :class:`~prima.mediator.Driver`
(``start`` one atomic behavior, ``abandon`` a feedback loop) and is a
:class:`~prima.mediator.Clock` (``now``). The run loop drives it with
``next_time()`` and ``advance_to(t)``; everything it has to say comes back
through four injected callbacks, each at the simulated time it happens:

* ``finished(ab_id, outcome)``: an atomic behavior ended (wire to ``Mediator.finish``);
* ``on_event(event)``: a predefined or robot-specific event (human-found, touched, ...);
* ``on_user(action)``: something the scripted user did (for the trace);
* ``on_zone(entry)``: the robot entered a zone; load its EA.

Physics is stepped at a fixed ``1 / hz`` only while something moves; idle
stretches are jumped over. The only randomness is a seeded ``random.Random``
(localization noise), so identical inputs give identical runs.
"""

from __future__ import annotations

import functools
import math
import random
from collections import deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from types import MappingProxyType
from typing import TYPE_CHECKING, Final

from prima.catalog import Blend, Catalog
from prima.errors import SimulationError
from prima.mediator import AtomicBehavior, Call, Event, Outcome
from prima.sim._behaviors import perform
from prima.sim._kernel import Kernel, Process, Room, Waker
from prima.sim._maps import Place, WorldMap
from prima.sim._records import (
    Picture,
    Pose,
    ReplyRule,
    ScheduledEvent,
    UserAction,
    Zone,
    ZoneEntry,
)
from prima.sim._spec import RobotSpec, SpeechTiming
from prima.sim._user import ADDED_ACTIONS, ScriptedUser, UserScript
from prima.sim._world import World
from prima.vocab import MAX_TEXT, Value

if TYPE_CHECKING:
    from prima.sim._setting import Setting

__all__ = ["Simulator"]

Finished = Callable[[int, Outcome], None]
RECORDS_KEPT = 1000
"""How many messages received and sent, and pictures taken, the simulator keeps
(the latest): memory stays flat over a run of any length."""
SENSE_HZ = 10
"""How often (per simulated second) sensors are read while something moves."""
_PASSING_SLACK: Final = 1.0
"""The places near the robot are looked up for this much (m) beyond the passing
radius, so that the answer holds until the robot has moved up to this far."""


def _ignore(*_: object) -> None:
    return None


_SPEAK_AT_ONCE: Final = frozenset({"Speak", "QA", "TurnAndSpeak", "ActiveSensingHuman"})
"""The Commands whose behaviors begin with their words (a Face Human and Speak turns
first)."""


class Simulator:
    """A deterministic simulated robot, its building and its user."""

    def __init__(self, world_map: WorldMap, *, spec: RobotSpec | None = None,
                 catalog: Catalog | None = None,
                 robot: Pose | None = None, user: UserScript | None = None,
                 events: Iterable[ScheduledEvent] = (), zones: Iterable[Zone] = (),
                 replies: Iterable[ReplyRule] = (),
                 seed: int = 0, hz: int = 50, noise: float = 0.0, heading_noise: float = 0.0,
                 finished: Finished | None = None,
                 on_event: Callable[[Event], None] | None = None,
                 on_user: Callable[[UserAction], None] | None = None,
                 on_zone: Callable[[ZoneEntry], None] | None = None) -> None:
        if hz <= 0 or hz % SENSE_HZ:
            raise SimulationError(f"hz must be a positive multiple of {SENSE_HZ}, not {hz}")
        robot = robot if robot is not None else Pose(0.0, 0.0, 0.0)
        self.map = world_map
        self.spec = spec or RobotSpec()
        self.catalog = catalog if catalog is not None else Catalog.standard()
        """The Commands the robot offers: argument defaults, robot-specific durations."""
        self.kernel = Kernel(hz)
        self.world = World(world_map, self.spec, hz, robot, user.start if user else None)
        self.random = random.Random(seed)
        self.noise = noise
        self.heading_noise = heading_noise
        self.finished: Finished = finished or _ignore
        self.on_event: Callable[[Event], None] = on_event or _ignore
        self.on_user: Callable[[UserAction], None] = on_user or _ignore
        self.on_zone: Callable[[ZoneEntry], None] = on_zone or _ignore
        self.replies: tuple[ReplyRule, ...] = tuple(replies)
        """How the environment's servers answer what the applications send them."""
        self._clear_records()
        self._sense_every = hz // SENSE_HZ
        self._poses: tuple[int, tuple[float, float, float], tuple[float, float, float] | None,
                           bool | None] = (-1, (0.0, 0.0, 0.0), None, None)
        """:meth:`poses` at a world version."""
        self._lose_ticks = self.kernel.ticks(self.spec.lose_after)
        self._zones = tuple(zones)
        self._inside = {z.name for z in self._zones if z.area.contains(robot.x, robot.y)}
        self._near = {p.name for p in self.map.places
                      if robot.distance_to(p.x, p.y) <= self.spec.passing_radius}
        self._passing_probe = (0.0, 0.0, -1.0)
        """Where the places near the robot were last looked up, and how far the robot
        may go from there before they can change (negative: look them up)."""
        self._goals: tuple[tuple[float, float, float], dict[str, float]] = ((0.0, 0.0, -1.0), {})
        """:meth:`route`'s last target (and radius) and the places it may be reached from
        straight (the walls stand still: a user walking to a robot that waits asks
        again and again)."""
        for ev in events:
            self.kernel.at(round(ev.at * hz), functools.partial(self._post, ev))
        self._room = Room(self.kernel, ADDED_ACTIONS, "input")
        """The insertion numbers kept for inputs added as the run goes (:meth:`add_event`)."""
        self.pace: Callable[[int], None] | None = None
        """Called with the tick the run may go on to, where it could wait for a wall clock
        (``prima live``): at each sensing tick while something moves, and before each jump
        over a still stretch. It may block, and add inputs (:meth:`add_event`,
        ``user.add``) after now; the simulator then looks at its agenda again. Pacing so
        changes nothing of the run."""
        self.user = ScriptedUser(user, self) if user is not None else None
        if self.user is not None:
            self.user.begin()

    def _clear_records(self) -> None:
        """What a new simulator has seen, said and counted: nothing yet (reports,
        messages, pictures, sensing, what runs and what it says, hearing, facing)."""
        self.reports = 0
        """How many reports (ends, events, user actions, zone entries) so far."""
        self.inbox: deque[Mapping[str, Value]] = deque(maxlen=RECORDS_KEPT)
        """The latest network messages received (sender, text)."""
        self.outbox: deque[Mapping[str, Value]] = deque(maxlen=RECORDS_KEPT)
        """The latest messages the applications sent to the environment's servers."""
        self.pictures: deque[Picture] = deque(maxlen=RECORDS_KEPT)
        """The latest camera captures."""
        self.picture_count = 0
        """Camera captures taken so far."""
        self.longest: dict[str, float] = {}
        """Application -> the longest atomic behavior it may start (its budget, s)."""
        self.sample_every = 0
        """Call ``on_sample`` every this many ticks (0: never); see :meth:`sample_poses`."""
        self.on_sample: Callable[[], None] = _ignore
        self._moved = False
        self._sampled = -1
        """With :meth:`sample_poses`'s ``moved``, the world's version at the last call of
        ``on_sample`` (-1: none yet, or every instant called)."""
        self.steps = 0
        """Physics steps taken so far (counted as each stretch of steps ends: up to date
        whenever the simulator has returned)."""
        self.skipped = 0
        """Wakes of processes that would have done nothing, skipped so far
        (:meth:`_skip_idle`)."""
        self.seen = False
        """Human detection's current belief: the user is in view."""
        self.navigating = 0
        """How many Topological Moves are running: they report the places they reach."""
        self._unseen_since: int | None = None
        self._announced: str | None = None
        self._sensing = 0
        self._sighted = False
        """The camera saw the user since sensing last began: only then can it lose them."""
        self._running: dict[int, AtomicBehavior] = {}
        self._procs: dict[int, Process] = {}
        """The process performing each running atomic behavior (to cut it)."""
        self.speech: SpeechTiming | None = None
        """Where utterances take their time and their words' ends from, if not from the
        speech rate (:meth:`speech_duration`)."""
        self._speech: dict[int, tuple[int, tuple[str, ...], int, tuple[int, ...] | None]] = {}
        """Command id -> what it is saying: the tick it began, its words, its ticks, and
        the tick (from its start) each word ends at when :attr:`speech` says so."""
        self._said: dict[int, tuple[float, float]] = {}
        """AB -> when its words began and ended (s), once it has ended (``said``)."""
        self._cutting: set[int] = set()
        self._hushed: set[int] = set()
        """Being cut for the user's words before their own words began (:meth:`utter`)."""
        self._driving: set[int] = set()
        """Running atomic behaviors performing a call that uses the wheels now."""
        self._blends: dict[int, Blend] = {}
        """Running atomic behaviors blended over another (the blend policy)."""
        self._loops: dict[int, dict[str, Value]] = {}
        self._mic: Waker | None = None
        self._prompting: dict[int, Waker] = {}
        """Command id -> the Q&A asking its prompt, which an early answer wakes."""
        self.hears_always = False
        """The robot hears its user at any time (the barge-in policy), not only while a
        Q&A listens: words said outside a Q&A are a ``speech`` event, and an answer said
        over a Q&A's prompt answers it, stopping the prompt at a word boundary."""
        self.backchannel: Callable[[str], bool] = _never
        """Whether words only show that the user follows (the robot profile's
        backchannels)."""
        self.answers_prompt: Callable[[int, str], bool] | None = None
        """Whether words said over the prompt of the Q&A of a Command id answer it (a run
        asks the Q&A's grammar, docs/rules.md 7.5: words it takes are its answer, never
        a backchannel); None: any words but a backchannel do."""
        self._facing: tuple[float, Callable[[], None]] | None = None
        """While words are said: the tolerance (degrees) beyond which the user is off to
        the side, and whom to tell when they go off (:meth:`watch_facing`)."""
        self._off = False
        """The user was found off to the side while words were said, and has not been
        faced since (told once per stretch)."""

    def send(self, to: str, text: str) -> None:
        """An application sends ``text`` to the environment's server ``to``.

        The first of the scenario's reply rules that matches schedules the
        server's answer, a ``message`` event, ``after`` seconds from now.
        """
        self.outbox.append(MappingProxyType({"time": self.now(), "to": to, "text": text}))
        for rule in self.replies:
            if rule.matches(to, text):
                # At least one step later: an app that sends on every reply must
                # not make time stand still.
                ticks = max(1, self.ticks(rule.after))
                answer = rule.text.replace("{text}", text)[:MAX_TEXT]  # no amplification
                reply = ScheduledEvent((self.kernel.tick + ticks) / self.kernel.hz, "message",
                                       {"sender": to, "text": answer})
                self.kernel.at(self.kernel.tick + ticks, functools.partial(self._post, reply))
                return

    def add_event(self, event: ScheduledEvent) -> None:
        """Post ``event`` at its time, after now, as if the scenario had listed it last
        among the inputs of that tick (a network message sent live, ``prima live``): a
        scenario with the same inputs at the same times makes the same run. Raises
        SimulationError for a time not after now, or past the bound."""
        self._room.add(event.at, functools.partial(self._post, event))

    @classmethod
    def from_scenario(cls, scenario: Setting, *, spec: RobotSpec | None = None,
                      catalog: Catalog | None = None,
                      finished: Finished | None = None,
                      on_event: Callable[[Event], None] | None = None,
                      on_user: Callable[[UserAction], None] | None = None,
                      on_zone: Callable[[ZoneEntry], None] | None = None) -> Simulator:
        """A simulator for a loaded scenario (``spec`` and ``catalog`` from the robot profile):
        anything with a :class:`~._setting.Setting`'s fields."""
        return cls(scenario.map, spec=spec, catalog=catalog, robot=scenario.robot,
                   user=scenario.user,
                   events=scenario.events, replies=scenario.replies, zones=scenario.zones,
                   seed=scenario.seed,
                   hz=scenario.rate, noise=scenario.noise,
                   heading_noise=scenario.heading_noise, finished=finished,
                   on_event=on_event, on_user=on_user, on_zone=on_zone)

    # ---- Clock -----------------------------------------------------------------

    def now(self) -> float:
        """Simulated time (s); during a callback, the time of what is reported."""
        return self.kernel.tick / self.kernel.hz

    def after(self, seconds: float, since: float | None = None) -> float:
        """The tick ``seconds`` after ``since`` (default: now): the duration rounded to
        the nearest tick, a positive one to at least one tick (``1 / rate`` seconds)."""
        k = self.kernel
        start = k.tick if since is None else round(since * k.hz)
        return (start + k.ticks(seconds)) / k.hz

    # ---- Driver ----------------------------------------------------------------

    def start(self, ab: AtomicBehavior) -> None:
        """Begin ``ab`` now; ``finished`` is called when it ends (never from inside here)."""
        if ab.id in self._running:
            raise SimulationError(f"atomic behavior {ab.id} is already running")
        self._running[ab.id] = ab
        if ab.blended:
            self._blend(ab)
        if "human-detection" in ab.devices:
            self._sensing += 1
        self._procs[ab.id] = self.kernel.spawn(perform(self, ab),
                                               lambda result: self._finish(ab, result))

    def _blend(self, ab: AtomicBehavior) -> None:
        """``ab`` runs blended with another on a device they share: the local motion
        over the global one, or the global one's next iteration under the local one.
        While the local motion runs, the global one goes at the blend's ``slowdown``
        and stops ahead of its bound from the user (the local AB is the blend's key)."""
        catalog = self.catalog
        mine = [catalog[c.command] for c in ab.calls if c.command in catalog]
        for other in self._running.values():
            shared = sorted(ab.blended & other.devices - other.blended)
            if other is ab or not shared:
                continue
            theirs = [catalog[c.command] for c in other.calls if c.command in catalog]
            found = catalog.blend(mine, theirs, shared[0])
            if found is None:
                continue
            if all(c.name in found.local for c in mine if found.devices & c.devices):
                self._blends[ab.id] = found
            elif all(c.name in found.local for c in theirs if found.devices & c.devices):
                self._blends[other.id] = found
        self._pace()

    def blended_locally(self, ab: AtomicBehavior, command: str) -> bool:
        """``command`` of ``ab`` is a local motion blended over a global one: it leaves
        the shared devices to the global motion."""
        found = self._blends.get(ab.id)
        return found is not None and command in found.local

    def _pace(self) -> None:
        slowest = min((b.slowdown for b in self._blends.values()), default=1.0)
        self.world.speed_limit(self.spec.max_speed * slowest)

    def performing(self, ab: AtomicBehavior, call: Call) -> None:
        """``ab`` goes on to ``call``: whether it drives the wheels now (a grouped
        atomic behavior that holds them for a later call does not keep a motion
        before it rolling)."""
        spec = self.catalog.commands.get(call.command)
        if spec is not None and not spec.perform and (
                "locomotion" in spec.devices or "locomotion" in spec.devices_for(call.args)):
            self._driving.add(ab.id)
        else:  # (no primitive of a <perform> drives the wheels: a sway swings the body
            self._driving.discard(ab.id)  # about whatever drives them)

    def blend_bound(self) -> float | None:
        """How far the robot may be from its user now (m): the tightest bound of the
        blends under way, or None."""
        bounds = [b.max_user_distance for b in self._blends.values()
                  if b.max_user_distance is not None]
        return min(bounds) if bounds else None

    def abandon(self, command_id: int) -> None:
        """Forget a feedback loop; if nothing else drives the wheels, hold still."""
        self._loops.pop(command_id, None)
        self._hold_still()

    def cut(self, ab_id: int) -> bool:
        """Stop a running atomic behavior early (the interrupt policy): speech at the
        end of the word under way, anything else at once. Its end is reported with
        ``interrupted``, ``spoken`` and ``unspoken``; an utterance already on its last
        word just ends (nothing is left to cut)."""
        ab = self._running.get(ab_id)
        if ab is None:
            return False
        if ab_id in self._cutting:
            return True
        boundary = self._boundary(ab)
        if boundary is None:
            return False
        self._cutting.add(ab_id)
        at, spoken, unspoken = boundary
        self.kernel.at(at, lambda: self._cut_now(ab, spoken, unspoken))
        return True

    def stop_words(self, ab_id: int) -> bool:
        """The user spoke over ``ab_id``: cut it at the end of the word under way if it
        is saying words now; if its words are still to come (it turns toward a panel
        first, say), it is cut as they would begin, before the first word. False if it
        says nothing, has said its words, or is on its last word."""
        ab = self._running.get(ab_id)
        if ab is None:
            return False
        if ab_id in self._cutting:
            return True
        now = self.kernel.tick
        started = False
        for cid in ab.command_ids:
            said = self._speech.get(cid)
            if said is not None and said[1]:
                started = True
                if said[0] <= now < said[0] + said[2]:
                    return self.cut(ab_id)
        if started or not self._words(ab):
            return False
        self._cutting.add(ab_id)
        self._hushed.add(ab_id)  # (:meth:`utter` cuts it as its words would begin)
        return True

    def _words(self, ab: AtomicBehavior) -> list[str]:
        """Every word ``ab`` says, in order (its Commands' words said, split)."""
        words: list[str] = []
        for call in ab.calls:
            spec = self.catalog.get(call.command)
            for text in spec.spoken(call.args) if spec is not None else ():
                words += text.split()
        return words

    def _boundary(self, ab: AtomicBehavior) -> tuple[int, str, str] | None:
        """When to cut ``ab`` and the words it will have said and not said then."""
        now = self.kernel.tick
        words = self._words(ab)
        for cid in ab.command_ids:
            said = self._speech.get(cid)
            if said is None:
                continue
            start, saying, ticks, ends = said
            if now >= start + ticks or not saying:
                if any(c.command in self.catalog and self.catalog[c.command].listens
                       for c in ab.calls):
                    return None  # a Q&A listening: the user's turn is never cut
                return now, " ".join(words), ""  # all said
            if ends is not None and len(ends) == len(saying):  # the synthesiser's words
                k = next((i + 1 for i, end in enumerate(ends) if end > now - start),
                         len(saying))
                if k >= len(saying):
                    return None
                return start + ends[k - 1], " ".join(saying[:k]), " ".join(saying[k:])
            per = ticks / len(saying)
            k = min(len(saying), int((now - start) // per) + 1)  # the word under way ends
            if k >= len(saying):
                return None
            return (start + math.ceil(k * per - 1e-9), " ".join(saying[:k]),
                    " ".join(saying[k:]))
        return now, "", " ".join(words)  # nothing said yet

    def _cut_now(self, ab: AtomicBehavior, spoken: str, unspoken: str) -> None:
        proc = self._procs.get(ab.id)
        if proc is None or not proc.alive or ab.id not in self._running:
            return  # it ended on its own
        self.kernel.kill(proc)
        if "speech-recognition" in ab.devices:
            self.close_mic()
        self._finish(ab, ({"interrupted": True, "spoken": spoken, "unspoken": unspoken},
                          True))

    def utter(self, command_id: int, text: str, ticks: int) -> None:
        """A behavior of this Command starts saying ``text`` over ``ticks``: a cut
        (the interrupt policy) waits for the end of the word under way; one the user's
        words asked for before this one's began ends it now, before its first word."""
        if self._hushed:
            ab = next((a for a in self._running.values()
                       if command_id in a.command_ids and a.id in self._hushed), None)
            if ab is not None:
                self._hushed.discard(ab.id)
                self._speech.pop(command_id, None)  # (nothing of it is said)
                words = " ".join(self._words(ab))
                self.kernel.at(self.kernel.tick, lambda: self._cut_now(ab, "", words))
                return
        ends = None
        if self.speech is not None:
            ends = tuple(min(ticks, self.ticks(at)) for at in self.speech.said(text)[1])
        self._speech[command_id] = (self.kernel.tick, tuple(text.split()), ticks, ends)
        self._off = False  # (new words: whether the user goes off is watched afresh)

    def speech_duration(self, text: str) -> float:
        """How long saying ``text`` takes: by :attr:`speech` if given, else by the speech
        rate (:meth:`RobotSpec.speech_duration`); never less than the shortest utterance."""
        if self.speech is None:
            return self.spec.speech_duration(text)
        return max(self.spec.min_utterance, self.speech.said(text)[0])

    # ---- discrete-event API -------------------------------------------------------

    def next_time(self) -> float | None:
        """When something next happens (at most one second ahead while anything moves)."""
        nxt = self._next_tick()
        return None if nxt is None else nxt / self.kernel.hz

    def _next_tick(self) -> int | None:
        """:meth:`next_time`, as a tick."""
        k = self.kernel
        nxt = k.next_tick()
        if self._moving():
            horizon = k.tick + k.hz
            nxt = horizon if nxt is None else min(nxt, horizon)
        return nxt

    def on_grid(self, t: float) -> float:
        """The time of the first tick at or after ``t`` (a time less than a millionth of
        a tick past one is that tick's): where :meth:`advance_until` stops."""
        return self._first_tick(t) / self.kernel.hz

    def _first_tick(self, t: float) -> int:
        return math.ceil(t * self.kernel.hz - 1e-6)

    def advance_until(self, t: float) -> None:
        """Run up to time ``t`` (the first tick at or after it: :meth:`on_grid`),
        returning as soon as anything is reported (as :meth:`advance_to` with
        ``stop_on_report``).

        On the way, the simulator wakes at its own times (:meth:`next_time`) and
        settles there as it would if a caller's loop woke it then: it runs what is
        due and, while human detection runs, looks for the user. So a caller whose
        loop has nothing to do at those times (a run's mediator and applications)
        sleeps through them, and the simulator sees the same at the same ticks.
        (Ticks are compared as whole numbers: a ``t`` a hair past a tick stops at that
        tick, not again and again short of ``t``.)
        """
        k = self.kernel
        self._run_to(max(self._first_tick(t), k.tick), True, True)

    def _wake_at(self, last: int) -> int:
        """Where :meth:`advance_until` runs on to from now, toward ``last``: the
        simulator's own next time (:meth:`next_time`), the wakes up to ``last`` of
        processes that would do nothing skipped first. (:meth:`_next_tick` and
        :meth:`_moving`, written out: it runs at every stop, and their calls cost a run
        0.5 to 0.8% more bytecodes.)"""
        k = self.kernel
        heap = k._heap
        w = self.world
        if w.mode or w.human_moving or k.tick < w.joints_until or w.swaying:
            own = min(heap[0][0], last) if heap else last
            return max(min(own, k.tick + k.hz), k.tick)
        if not heap:
            return max(last, k.tick)
        if k.idle_first(last):
            self._skip_idle(last)  # (wakes after now: nothing it does is due)
        return max(min(heap[0][0], last), k.tick)

    def advance_to(self, t: float, *, stop_on_report: bool = False) -> None:
        """Run up to time ``t``, reporting everything on the way at its own time.

        With ``stop_on_report``, return as soon as anything was reported (an
        AB's end, an event, a user action, a zone entry), so that a run loop
        can handle deadlines the report created before time moves on.
        """
        k = self.kernel
        target = math.floor(t * k.hz + 1e-6)
        if target < k.tick:
            raise SimulationError(f"cannot go back from {self.now()} to {t}")
        self._run_to(target, stop_on_report)

    def _run_to(self, last: int, stop_on_report: bool, own: bool = False) -> None:
        """:meth:`advance_to` the tick ``last`` (not before now); with ``own``, as
        :meth:`advance_until`: by the simulator's own times on the way (:meth:`_wake_at`),
        settling at each. The simulator settles again only if the last settling may
        have left something to do (:meth:`_settle`): between two, nothing else runs."""
        k = self.kernel
        world = self.world
        every = self._sense_every
        sample = self.sample_every
        grid = math.gcd(every, sample)
        heap = k._heap
        pace = self.pace
        before = self.reports if stop_on_report else -1
        target = self._wake_at(last) if own else last
        settled = False
        while True:
            if not settled:
                settled = self._settle()
            if stop_on_report and self.reports != before:
                return
            if k.tick >= target:
                if k.tick != target or target >= last:
                    return
                target = self._wake_at(last)  # (woken at one of its own times)
                continue
            settled = False
            if world.mode or world.human_moving or k.tick < world.joints_until or world.swaying:
                # (:meth:`_moving`, written out.) Between sensing and sample ticks (all
                # multiples of ``grid``), the agenda and the reports change only when a
                # motion ends: the steps between need only see that something still moves.
                start = tick = k.tick
                bound = min(min(tick - tick % grid + grid, target),  # (of two: a comparison,
                            heap[0][0] if heap else target)        # compiled)
                while True:
                    tick, done = world.run(tick, bound)  # (to the bound, or less if
                    k.tick = tick                        # a motion ended, or all stopped)
                    if done is None and tick < bound:
                        break  # nothing moves any more
                    if done is not None:
                        done()
                    if tick % every == 0:
                        self._sense()
                        if pace is not None:
                            pace(tick)
                    if sample and tick % sample == 0:
                        self._sample()
                    if (tick >= target or (heap and heap[0][0] <= tick)
                            or (stop_on_report and self.reports != before)):
                        break
                    bound = min(min(tick - tick % grid + grid, target),
                                heap[0][0] if heap else target)
                self.steps += tick - start
            else:
                self._jump(target)

    def _jump(self, target: int) -> None:
        """Nothing moves: go on to the agenda's next work, or to ``target`` if sooner."""
        k = self.kernel
        if k.idle_first(target):
            self._skip_idle(target)
        nxt = k.next_tick()
        jump = target if nxt is None or nxt > target else max(nxt, k.tick)
        pace = self.pace
        if pace is not None and jump > k.tick:
            pace(jump)
            nxt = k.next_tick()  # (an input added while it waited comes first)
            if nxt is not None and k.tick < nxt < jump:
                jump = nxt
        sample = self.sample_every
        if sample:  # nothing moves: the samples on the way see the same poses
            for tick in range((k.tick // sample + 1) * sample, jump + 1, sample):
                if self.world.version == self._sampled:
                    break  # (``moved``: the rest would see what the last one saw)
                k.tick = tick
                self._sample()
        k.tick = jump

    # ---- state -------------------------------------------------------------------

    def robot_pose(self) -> Pose:
        return self.world.robot_pose()

    def poses(self) -> tuple[tuple[float, float, float], tuple[float, float, float] | None,
                             bool | None]:
        """The robot's pose, the user's (None in a scenario without a user) as
        ``(x, y, heading)`` (:meth:`robot_pose` and :meth:`user_pose` as tuples), and
        whether the user is detectable (:meth:`user_detectable`; None without a user):
        kept while no body moves (the trace's lines of one instant, or of a still robot,
        ask again and again; none of the three depends on anything else)."""
        world = self.world
        kept = self._poses
        if kept[0] == world.version:
            return kept[1], kept[2], kept[3]
        x, y = world.robot_xy()
        robot = (x, y, math.degrees(world.robot_angle()) % 360.0)
        user = None
        detectable = None
        if world.has_user:
            x, y = world.user_xy()
            user = (x, y, math.degrees(world.user_angle()) % 360.0)
            detectable = self.user_detectable()
        self._poses = (world.version, robot, user, detectable)
        return robot, user, detectable

    def user_detectable(self) -> bool:
        """Whether human detection could see the user now, if the robot looked their
        way (in camera range, nothing in between)."""
        return self.world.sees_user(self.kernel.tick, any_direction=True)[0]

    def user_unfaced(self, tolerance: float) -> bool:
        """The user is detectable, and more than ``tolerance`` degrees off the robot's
        heading: the robot does not face them."""
        world = self.world
        if not world.has_user or not self.user_detectable() or world.user_distance() < 1e-9:
            return False
        return abs(math.degrees(world.user_bearing())) > tolerance

    def user_near(self, distance: float) -> bool:
        """The user is detectable and no farther than ``distance`` (m)."""
        world = self.world
        return world.has_user and self.user_detectable() and world.user_distance() <= distance

    def user_pose(self) -> Pose | None:
        """Where the user is, or None in a scenario without a user."""
        return self.world.user_pose() if self.world.has_user else None

    def localize(self) -> Pose:
        """The robot's pose as its localization reports it (with seeded noise, if any)."""
        p = self.world.robot_pose()
        if self.noise <= 0 and self.heading_noise <= 0:
            return p
        g = self.random.gauss
        return Pose(p.x + g(0.0, self.noise) if self.noise > 0 else p.x,
                    p.y + g(0.0, self.noise) if self.noise > 0 else p.y,
                    (p.heading + g(0.0, self.heading_noise)) % 360.0
                    if self.heading_noise > 0 else p.heading)

    def user_visible(self) -> bool:
        """Whether the camera sees the user right now (field of view, range, sight)."""
        return self.world.sees_user(self.kernel.tick)[0]

    # ---- services for behaviors and the scripted user -------------------------------

    def ticks(self, seconds: float) -> int:
        return self.kernel.ticks(seconds)

    def sample_poses(self, rate: float, on_sample: Callable[[], None], *,
                     moved: bool = False) -> None:
        """Call ``on_sample`` ``rate`` times per simulated second (rounded to whole
        ticks), at fixed instants, whether or not anything moves; ``rate`` 0: never.
        With ``moved``, the instants at which nothing moves are skipped once a call has
        seen the poses they would show (no body has moved since): however long the robot
        and the user stand still, at most one call, so that a run's cost follows what
        happens, not how long. Sampling never changes what happens."""
        self.on_sample = on_sample
        self.sample_every = max(1, round(self.kernel.hz / rate)) if rate > 0 else 0
        self._moved = moved
        self._sampled = -1

    def _sample(self) -> None:
        """Call ``on_sample`` (:meth:`sample_poses`)."""
        if self._moved:
            self._sampled = self.world.version
        self.on_sample()

    def longest_for(self, app: str) -> float:
        """The longest atomic behavior ``app`` may start (s); unbounded if not set."""
        return self.longest.get(app, math.inf)

    def emit(self, name: str, data: Mapping[str, Value]) -> None:
        """Post an event to the applications (through ``on_event``)."""
        self.reports += 1
        self.on_event(Event(name, MappingProxyType(dict(data)), self.now()))

    def report_user(self, action: UserAction) -> None:
        self.reports += 1
        self.on_user(action)

    def loop_state(self, command_id: int) -> dict[str, Value]:
        """Per-Command state kept across a feedback loop's iterations."""
        return self._loops.setdefault(command_id, {})

    def end_loop(self, command_id: int) -> None:
        self._loops.pop(command_id, None)

    def said(self, ab_id: int) -> tuple[float, float] | None:
        """When the words of the ended atomic behavior ``ab_id`` began and would have
        ended (s; a cut one stopped at its end), or None if it said nothing; asked
        once."""
        return self._said.pop(ab_id, None)

    def words_ahead(self, calls: Sequence[Call], command_ids: Sequence[int],
                    iteration: int = 0) -> float | None:
        """How long the words of the atomic behavior of ``calls`` (for ``command_ids``;
        its feedback ``iteration``, if any) take if it says them as soon as it starts
        (s): a Speak, a Q&A's prompt, a Turn and Speak, a search's prompt (in an
        iteration that says it), first in the atomic behavior; None otherwise (it says
        nothing, or says it after something else: a turn, an earlier Command of a
        group)."""
        call = calls[0] if calls else None
        if call is None or call.command not in _SPEAK_AT_ONCE:
            return None
        if iteration and self.quiet(command_ids[0]):
            return None
        spec = self.catalog.get(call.command)
        words = spec.spoken(call.args) if spec is not None else []
        if not words:
            return None
        return self.ticks(self.speech_duration(" ".join(words))) / self.kernel.hz

    def quiet(self, command_id: int) -> bool:
        """The next iteration of this feedback Command says none of its words (a
        search says ``say`` once per retry, in the retry's first iteration)."""
        return bool(self._loops.get(command_id, {}).get("quiet"))

    def asking(self, prompt: str, ticks: int = 0) -> None:
        """The robot starts asking ``prompt``, which takes ``ticks``."""
        if self.user is not None:
            self.user.begin_question(prompt, ticks)

    def ask(self, prompt: str) -> None:
        """The robot finished asking ``prompt`` and starts listening."""
        if self.user is not None:
            self.user.hear_question(prompt)

    def open_mic(self, waker: Waker) -> bool:
        self._mic = waker
        return True

    def close_mic(self) -> None:
        self._mic = None

    def listening(self) -> bool:
        """Whether a Q&A listens now (its prompt said)."""
        return self._mic is not None

    def hearable(self) -> bool:
        """Whether the robot would hear the user speak now: a Q&A listens, or it hears
        at any time, and the user is within hearing range."""
        return (self._mic is not None or self.hears_always) \
            and self.world.user_distance() <= self.spec.hearing_range

    def hear(self, text: str) -> bool:
        """The user says ``text``: True if the robot heard it. A listening Q&A takes it;
        else, if the robot hears at any time, words said over a Q&A's prompt that answer
        it (:attr:`answers_prompt`) stop the prompt and answer it, and anything else is a
        ``speech`` event with its ``words`` and whether it is a ``backchannel``. Blank
        words (empty, spaces, tabs) are no speech: never heard, they neither answer nor
        cut the robot."""
        if not self.hearable() or not text.strip():
            return False
        mic = self._mic
        if mic is not None:
            self._mic = None
            mic(text)
            return True
        backchannel = self.backchannel(text)
        # (a prompt whose words were hushed before they began is being cut: not asking)
        cid = next((c for c in self._prompting if c in self._speech), None) \
            if self._prompting else None
        if cid is not None and (not backchannel if self.answers_prompt is None
                                else self.answers_prompt(cid, text)):
            wake = self._prompting.pop(cid)
            wake((text, *self._stop_prompt(cid)))
            return True
        self.emit("speech", {"words": text, "backchannel": backchannel})
        return True

    def open_prompt(self, command_id: int, waker: Waker) -> bool:
        """A Q&A begins its prompt: an early answer wakes it (:meth:`hear`)."""
        if self.hears_always:
            self._prompting[command_id] = waker
        return True

    def close_prompt(self, command_id: int) -> None:
        self._prompting.pop(command_id, None)

    def _stop_prompt(self, command_id: int) -> tuple[int, str, str]:
        """An answer over a prompt: the tick its words stop (the end of the word under
        way), the words said and not said; its utterance is shortened to match."""
        start, saying, ticks, ends = self._speech[command_id]
        ab = next(a for a in self._running.values() if command_id in a.command_ids)
        boundary = self._boundary(ab)
        at, spoken, unspoken = boundary or (start + ticks, " ".join(saying), "")
        self._speech[command_id] = (start, saying, at - start, ends)
        return at, spoken, unspoken

    def announce_lost(self) -> None:
        """Post human-lost, unless it is the last of found/lost already posted."""
        if self._announced != "lost":
            self._announced = "lost"
            self.emit("human-lost", {})

    def search(self) -> None:
        """Start a fresh search: forget that the user was seen (no event)."""
        self.seen = False
        self._unseen_since = None

    def route(self, x: float, y: float, tx: float, ty: float,
              radius: float) -> list[tuple[float, float]]:
        """Waypoints from (x, y) to (tx, ty): straight if clear, else over the place graph."""
        world = self.world
        if world.clear(x, y, tx, ty, radius):
            return [(tx, ty)]
        places = self.map.places
        starts = {p.name: math.hypot(p.x - x, p.y - y) for p in places
                  if world.clear(x, y, p.x, p.y, radius)}
        target = (tx, ty, radius)
        if self._goals[0] != target:
            self._goals = (target, {p.name: math.hypot(p.x - tx, p.y - ty) for p in places
                                    if world.clear(p.x, p.y, tx, ty, radius)})
        goals = self._goals[1]
        path = self.map.shortest_path(starts, goals)
        if not path:
            return []
        points = []
        for name in path:
            place = self.map.place(name)
            if place is not None:
                points.append((place.x, place.y))
        return points + [(tx, ty)]

    def plan(self, goal: str) -> tuple[Place | None, list[Place]]:
        """The place the robot is at (if any) and the places still to visit to ``goal``."""
        x, y = self.world.robot_xy()
        tol = self.spec.place_tolerance
        near = [(math.hypot(p.x - x, p.y - y), i, p) for i, p in enumerate(self.map.places)]
        at = min(near)[2] if near and min(near)[0] <= tol else None
        if at is not None:
            starts = {at.name: 0.0}
        else:
            # off the map's places, the robot joins the map at a place it can drive to
            # straight and that passes no other place on the way (within ON_THE_WAY):
            # every place on its way is visited and reported
            radius = self.spec.radius / 2
            places = self.map.places
            starts = {p.name: d for d, _, p in near
                      if self.world.clear(x, y, p.x, p.y, radius)
                      and not any(_on_the_way(x, y, p, places[i]) for i in
                                  self.map.places_along(x, y, p.x, p.y, ON_THE_WAY))}
        names = self.map.shortest_path(starts, {goal: 0.0})
        if at is not None and names:
            names = names[1:]
        return at, [p for p in (self.map.place(n) for n in names) if p is not None]

    # ---- internals ------------------------------------------------------------------


    def _moving(self) -> bool:
        w = self.world
        return bool(w.mode or w.human_moving or self.kernel.tick < w.joints_until
                    or w.swaying)

    def _skip_idle(self, limit: int) -> None:
        """Skip the wakes up to ``limit`` of processes that would do nothing woken
        (:meth:`Kernel.skip_idle`). Asked only while no body moves: then nothing any
        process reads changes until the agenda's next other work, if that work changes
        nothing either: human detection would find nothing new and no predicate a
        process waits for holds. (Not while a live run keeps pace with the clock.)"""
        if self.pace is None and self._monitor_steady() and not self.kernel.polls_hold():
            self.skipped += self.kernel.skip_idle(limit)

    def _monitor_steady(self) -> bool:
        """Whether human detection's monitor, asked now, would change nothing
        (:meth:`_update_monitor`); with no body moving, until the agenda's next work."""
        if not self._sensing:
            return True
        seen, _distance = self.world.sees_user(self.kernel.tick)
        waiting = self.seen and self._sighted and self._unseen_since is None
        return waiting if seen else not waiting

    def _settle(self) -> bool:
        """Do what is due now, look for the user and resume the processes whose
        predicate holds, until nothing more is due. True if settling again would do
        nothing: its last round resumed no process (nothing is due, and human
        detection and the predicates, asked again, would find the same)."""
        k = self.kernel
        heap = k._heap
        while True:
            k.run_due()
            if self._sensing:
                self._update_monitor()
            woke = bool(k._polls) and k.check_polls()  # (mostly none: not asked)
            if not heap or heap[0][0] > k.tick:  # (:meth:`Kernel.due`, written out)
                return not woke

    def watch_facing(self, tolerance: float, off: Callable[[], None]) -> None:
        """While the robot says words, call ``off`` (a report) each time the user, being
        detectable, goes more than ``tolerance`` degrees off its heading: the user walked
        round it, or something turned it away (a run's mediator turns it back: docs/
        rules.md 7.6 (3)). Looked at with the other senses, while anything moves."""
        self._facing = (tolerance, off)

    def _watch_facing(self, facing: tuple[float, Callable[[], None]]) -> None:
        now = self.kernel.tick
        if not any(words and start <= now < start + ticks
                   for start, words, ticks, _ends in self._speech.values()):
            self._off = False
            return
        tolerance, off = facing
        if not self.user_unfaced(tolerance):
            self._off = False
        elif not self._off:
            self._off = True
            self.reports += 1
            off()

    def _sense(self) -> None:
        if self._facing is not None and self._speech:
            self._watch_facing(self._facing)
        if self._sensing:
            self._update_monitor()
        if self._zones and self.world.mode:
            self._check_zones()
        if self.world.mode:
            self._check_passing()
        self.kernel.check_polls()

    def _update_monitor(self) -> None:
        tick = self.kernel.tick
        seen, distance = self.world.sees_user(tick)
        if seen:
            self._sighted = True
            self._unseen_since = None
            if not self.seen:
                self.seen = True
                self._announced = "found"
                self.emit("human-found", {"distance": round(distance, 3)})
        elif self.seen and self._sighted:
            if self._unseen_since is None:
                self._unseen_since = tick
                self.kernel.at(tick + self._lose_ticks, _ignore)  # look again then
            elif tick - self._unseen_since >= self._lose_ticks:
                self.seen = False
                self._unseen_since = None
                self.announce_lost()

    def _check_passing(self) -> None:
        """Report places the robot passes while no Topological Move reports its route."""
        world = self.world
        x, y = world.robot_xy()
        px, py, clear = self._passing_probe
        if math.hypot(x - px, y - py) < clear:
            return  # no place can have come within the radius or left it
        found, clear = world.places_near(x, y, self.spec.passing_radius, _PASSING_SLACK)
        self._passing_probe = (x, y, clear)
        places = self.map.places
        near = self._near
        self._near = {places[i].name for i in found}
        for i in found:
            place = places[i]
            if place.name not in near and not self.navigating:
                self.emit("place-reached", {"place": place.name, "kind": place.kind.value})

    def _check_zones(self) -> None:
        x, y = self.world.robot_xy()
        for zone in self._zones:
            inside = zone.area.contains(x, y)
            if inside and zone.name not in self._inside:
                self._inside.add(zone.name)
                self.reports += 1
                self.on_zone(ZoneEntry(self.now(), zone.name, zone.ea))
            elif not inside:
                self._inside.discard(zone.name)

    def _post(self, ev: ScheduledEvent) -> None:
        if ev.name == "message":
            self.inbox.append(MappingProxyType(dict(ev.data)))
        self.emit(ev.name, ev.data)

    def _finish(self, ab: AtomicBehavior, result: tuple[dict[str, Value], bool]) -> None:
        values, terminal = result
        del self._running[ab.id]
        self._procs.pop(ab.id, None)
        if self.world.sway_owner and self.world.sway_owner in ab.command_ids:
            self.world.end_sway()  # (cut before its sway was over)
        self._cutting.discard(ab.id)
        self._hushed.discard(ab.id)
        self._driving.discard(ab.id)
        if self._blends.pop(ab.id, None) is not None:
            self._pace()
        for cid in ab.command_ids:
            said = self._speech.pop(cid, None)
            if said is not None and ab.id not in self._said:
                start, _words, ticks, _ends = said  # (as planned: a cut one's end earlier)
                self._said[ab.id] = (start / self.kernel.hz, (start + ticks) / self.kernel.hz)
        if "human-detection" in ab.devices:
            self._sensing -= 1
            if not self._sensing:  # forget how long the user was unseen, unless sensing
                self.kernel.at(self.kernel.tick + 1, self._sensing_stopped)  # goes on at once
        if "locomotion" in ab.devices and self.world.mode:
            self.kernel.at(self.kernel.tick + 1, self._hold_still)
        self.reports += 1
        self.finished(ab.id, Outcome(MappingProxyType(values), terminal))

    def _sensing_stopped(self) -> None:
        if not self._sensing:
            self._unseen_since = None
            self._sighted = False

    def _hold_still(self) -> None:
        """Stop the wheels unless a running atomic behavior drives them."""
        if self.world.mode and not any(ab in self._driving and ab not in self._blends
                                       for ab in self._running):
            self.world.stop()


ON_THE_WAY: Final = 0.5
"""A place this close (m) to the straight way from the robot to another place is on
the way: a Topological Move started off the map's places visits it first."""


def _on_the_way(x: float, y: float, to: Place, other: Place) -> bool:
    """Whether ``other`` lies on the straight way from (x, y) to ``to`` (not at its ends)."""
    if other.name == to.name:
        return False
    dx, dy = to.x - x, to.y - y
    length2 = dx * dx + dy * dy
    if length2 == 0.0:
        return False
    k = ((other.x - x) * dx + (other.y - y) * dy) / length2
    if not 0.0 < k < 1.0:
        return False
    return math.hypot(x + k * dx - other.x, y + k * dy - other.y) <= ON_THE_WAY


def _never(_text: str) -> bool:
    return False
