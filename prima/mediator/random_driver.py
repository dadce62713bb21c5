"""A random driver of the mediator, checked by the independent :mod:`.oracle`.

:func:`scenario` builds one random scenario from a seed (a plain
:class:`random.Random`, so a million run fast and each replays exactly):
an FA and an EA (a second EA may be swapped in; in about a third of the seeds,
another EA runs beside them all along) that request single Commands,
chains, groups, ASAP and reactive requests, requests that follow their latest
ended Command; end handlers that request follow-ups, at once or a little later
(inside or past the end grace), some endlessly; posted events their handlers
react to (a first, reactive request and a second that is part of the same
reaction); streams with holds, blocks with watchdogs, EA swaps, listeners that
raise, zero-length ABs that end from inside ``driver.start``, feedback Commands
with random iteration counts, and budgets that are sometimes tiny.

:func:`play` runs it in the scripted :class:`~.testing.Harness` and has the
oracle check every step; :func:`replay` prints what a seed does.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import random
from collections.abc import Mapping
from dataclasses import dataclass, field

from prima.errors import MediationError
from prima.mediator import (
    AppKind,
    AtomicBehavior,
    Call,
    CommandId,
    Event,
    MediatorConfig,
    Outcome,
    Request,
    RunningOrder,
    Value,
)
from prima.mediator.oracle import Oracle
from prima.mediator.testing import Harness
from prima.catalog import Blend, Catalog
from prima.vocab import ANSWERED, NEWS_EVENTS, Budgets, OnInterrupt

__all__ = ["Act", "AppScript", "Result", "Scenario", "play", "replay", "scenario"]

ARGS: Mapping[str, Mapping[str, Value]] = {
    "ActiveSensingHuman": {},
    "FaceHuman": {},
    "QA": {"prompt": "?", "grammar": "g"},
    "TrackingHuman": {},
    "FaceHumanAndSpeak": {"text": "x"},
    "TurnAndSpeak": {"angle": 1.0, "text": "x"},
    "SetDirection": {"heading": 90.0},
    "Turn": {"angle": 1.0},
    "SetSpeedAndTime": {"speed": 0.5, "time": 1.0},
    "StopMoving": {},
    "Speak": {"text": "x"},
    "MoveHead": {"pan": 1.0},
    "PointByHand": {"angle": 1.0},
    "Gesture": {"name": "bow"},
    "TopologicalMove": {"to": "room"},
    "SetPosition": {"x": 1.0, "y": 1.0},
    "SetPositionAndDirection": {"x": 1.0, "y": 1.0, "heading": 0.0},
    "ActiveSensingHuman+say": {"say": "where are you?"},
}
"""Each Command with valid arguments (``+say`` adds the speaker to Active Sensing)."""

POOL = tuple(ARGS)
COMMON = ("Speak", "Speak", "Turn", "MoveHead", "Gesture", "FaceHumanAndSpeak", "QA",
          "TopologicalMove", "TrackingHuman", "PointByHand")
"""Drawn more often, so that requests compete for the same devices."""
DEVICES = ("human-detection", "locomotion", "localization", "speaker", "speech-recognition",
           "neck", "arm")
DURATIONS = (0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0)
EVENTS = ("human-found", "touched", "message")
USER_EVENTS = frozenset({"touched", "speech"})
"""The user's own actions among them (docs/rules.md 7.1)."""
FEEDBACK = frozenset({"ActiveSensingHuman", "ActiveSensingHuman+say", "TrackingHuman",
                      "TopologicalMove", "SetPosition", "SetPositionAndDirection"})


def call(name: str) -> Call:
    return Call(name.split("+")[0], ARGS[name])


@dataclass(frozen=True)
class AppScript:
    """How one application's listener behaves."""

    follow_every: int = 0
    """Every Command whose id this divides gets a follow-up from its end handler (0: none)."""
    follow_delay: float = 0.0
    """The follow-up is requested this long after the end (0: inside the handler)."""
    follow: str = "Speak"
    endless: bool = False
    """Every ended Command gets a follow-up (until the scenario's horizon)."""
    react: tuple[str, ...] = ()
    """Requested, reactive, on each event (nothing if empty)."""
    react_asap: bool = False
    raise_on: str = ""
    """``event``, ``ended`` or ``cancelled``: that callback raises ..."""
    raise_at: int = 1
    """... the ``raise_at``-th time."""
    takes: bool = False
    """It takes the user's words (an always-on grammar that matches: docs/rules.md 7.5),
    but a cough."""
    reply: str = ""
    """Requested at once from the end handler of each of its Q&As the user answered
    (docs/rules.md 7.4: words reply within the exchange; a question ends it); nothing
    if empty."""


@dataclass(frozen=True)
class Act:
    """One scenario action at time ``t``."""

    t: float
    role: str
    """``fa``, ``ea`` (the EA loaded at the time) or ``eb`` (the EA beside it)."""
    kind: str
    """``submit``, ``event``, ``speech`` (the user says ``commands[0]``), ``regard`` (the
    user goes off to the side), ``stream`` or ``block`` (open, or close if open),
    ``swap``."""
    commands: tuple[str, ...] = ()
    asap: bool = False
    reactive: bool = False
    group: bool = False
    follows: bool = False
    """``follows=`` the app's latest ended Command."""
    hold: float = 0.0
    """A stream's hold or a block's watchdog (s)."""
    devices: tuple[str, ...] | None = None
    """A block's devices (None: all)."""
    on_interrupt: str = "restart"
    """What its request lets the interrupt policy do (``restart``, ``drop``, ``never``)."""

    def __str__(self) -> str:
        if self.kind == "speech":
            return f"t={self.t:g} user says {self.commands[0]!r}"
        if self.kind == "regard":
            return f"t={self.t:g} user goes off to the side"
        if self.kind != "submit":
            extra = "" if self.kind in ("event", "swap") else f" {self.hold:g}s"
            devs = f" {list(self.devices)}" if self.devices else ""
            return f"t={self.t:g} {self.role} {self.kind}{extra}{devs}"
        flags = [f for f, on in (("asap", self.asap), ("reactive", self.reactive),
                                 ("group", self.group), ("follows", self.follows)) if on]
        if self.on_interrupt != "restart":
            flags.append(f"interrupt={self.on_interrupt}")
        return f"t={self.t:g} {self.role} submit {'+'.join(self.commands)} {' '.join(flags)}"


@dataclass(frozen=True)
class Scenario:
    """Everything one run does, drawn from its seed."""

    seed: int
    acts: tuple[Act, ...]
    scripts: tuple[AppScript, AppScript, AppScript]
    """The FA's, the first EA's, and the one swapped in (alternating with the first)."""
    durations: tuple[float, ...]
    iterations: tuple[int, ...]
    immediate: bool
    """Zero-length ABs end from inside ``driver.start``."""
    config: MediatorConfig
    horizon: float
    """Handlers request nothing after this time (so that everything drains)."""
    beside: AppScript | None = None
    """A second EA, ``eb``, running beside the FA and the first EA all along (three
    apps: acts of role ``eb`` are its), or None (two apps)."""
    interrupt: bool = False
    """The interrupt policy: reactions cut utterances, gestures and feedback
    iterations, which end ``cut_after`` seconds after the cut is asked for."""
    cut_after: float = 0.0
    hearing: bool = False
    """The barge-in policy: acts of kind ``speech`` have the user speak outside a Q&A;
    words over an utterance cut it (utterances are interruptible then)."""
    blends: tuple[Blend, ...] = ()
    """The blend policy: what the robot runs together on shared devices."""

    @property
    def longest(self) -> float:
        """L: the longest scripted AB."""
        return max(self.durations)

    def duration(self, ab: AtomicBehavior) -> float:
        return self.durations[(ab.id * 7 + ab.iteration) % len(self.durations)]

    @property
    def facing(self) -> int:
        """The connect-channel policy: 0, off; else the robot faces its user at one
        question in ``facing`` (a third of the seeds; derived from the seed alone, so
        that the other draws stay as they were)."""
        return (self.seed // 3) % 3 + 2 if self.seed % 3 == 0 else 0

    def outcome(self, ab: AtomicBehavior) -> Outcome:
        n = self.iterations[ab.command_ids[0] % len(self.iterations)]
        if any(c.command == "QA" for c in ab.calls):  # the user answers two Q&As in three
            return Outcome({"status": ANSWERED if ab.id % 3 else "noinput",
                            "utterance": "yes"}, terminal=ab.iteration + 1 >= n)
        return Outcome(terminal=ab.iteration + 1 >= n)

    def __str__(self) -> str:
        lines = [f"seed {self.seed}: durations {self.durations}, iterations {self.iterations}, "
                 f"immediate {self.immediate}, end_grace {self.config.end_grace:g}, "
                 f"horizon {self.horizon:g}"]
        lines += [f"  budgets {k.value}: {b}" for k, b in self.config.budgets.items()]
        lines += [f"  script {i}: {s}" for i, s in enumerate(self.scripts)]
        if self.beside is not None:
            lines += [f"  script eb: {self.beside}"]
        if self.interrupt:
            lines += [f"  interrupt: cuts end after {self.cut_after:g} s"]
        if self.hearing:
            lines += [f"  barge-in: resumes after {self.config.resume_pause:g} s"]
        lines += [f"  blend: {b}" for b in self.blends]
        lines += [f"  {a}" for a in self.acts]
        return "\n".join(lines)


# ---------------------------------------------------------------- generating
def _budgets(r: random.Random) -> Budgets:
    if r.random() < 0.6:
        return Budgets(wait_share=300.0, wait_window=360.0) if r.random() < 0.5 else Budgets()
    share = r.choice((0.25, 0.5, 1.0, 2.0, 4.0))
    return Budgets(wait_share=share, wait_window=share + r.choice((0.5, 1.0, 3.0, 8.0)),
                   waiting=r.choice((2, 4, 8, 200)),
                   starts_per_instant=r.choice((1, 3, 10, 100)))


def _script(r: random.Random) -> AppScript:
    return AppScript(
        follow_every=r.choice((0, 0, 1, 2, 3)),
        follow_delay=r.choice((0.0, 0.0, 0.25, 0.5, 0.75)),
        follow=r.choice(("Speak", "MoveHead", "TopologicalMove", "FaceHumanAndSpeak")),
        endless=r.random() < 0.08,
        react=tuple(r.choice(COMMON) for _ in range(r.choice((0, 1, 1, 2)))),
        react_asap=r.random() < 0.3,
        raise_on=r.choice(("",) * 6 + ("event", "ended", "cancelled")),
        raise_at=r.randint(1, 4),
    )


def _commands(r: random.Random) -> tuple[str, ...]:
    n = r.choice((1, 1, 1, 2, 3))
    return tuple(r.choice(COMMON) if r.random() < 0.7 else r.choice(POOL) for _ in range(n))


def _act(r: random.Random, t: float) -> Act:
    role = r.choice(("fa", "ea"))
    kind = r.choice(("submit",) * 7 + ("event", "stream", "stream", "block", "swap"))
    if kind == "submit":
        cmds = _commands(r)
        group = len(cmds) > 1 and r.random() < 0.3 and (
            not FEEDBACK.intersection(cmds) or r.random() < 0.1)  # sometimes refused
        return Act(t, role, kind, cmds, asap=r.random() < 0.2, reactive=r.random() < 0.25,
                   group=group, follows=r.random() < 0.2)
    devices = None
    if kind == "block" and r.random() < 0.6:
        devices = tuple(sorted(r.sample(DEVICES, r.randint(1, 3))))
    return Act(t, role, kind, hold=r.choice((0.0, 0.5, 1.0, 2.0, 5.0)), devices=devices)


def scenario(seed: int) -> Scenario:
    """The scenario of one seed."""
    r = random.Random(seed)
    horizon = r.choice((1.0, 3.0, 6.0, 12.0))
    grid = int(horizon * 4)
    acts = sorted((_act(r, r.randint(0, grid) / 4) for _ in range(r.randint(1, 14))),
                  key=lambda a: a.t)
    durations = tuple(r.choice(DURATIONS) for _ in range(r.randint(1, 4)))
    config = MediatorConfig(
        interrupt=True, blend=True,  # (what is cut and blends: the scenario's catalog)
        end_grace=r.choice((0.5, 0.5, 0.0, 1.0)),
        max_stream_hold=r.choice((30.0, 30.0, 1.0)),
        max_block_watchdog=r.choice((60.0, 60.0, 2.0)),
        budgets={AppKind.FA: _budgets(r), AppKind.EA: _budgets(r)},
    )
    sc = Scenario(
        seed=seed, acts=tuple(acts), scripts=(_script(r), _script(r), _script(r)),
        durations=durations if max(durations) > 0 or r.random() < 0.5 else durations + (1.0,),
        iterations=tuple(r.randint(1, 5) for _ in range(r.randint(1, 3))),
        immediate=r.random() < 0.3, config=config, horizon=horizon,
    )
    return _regarding(_hearing(_replying(_blending(_interrupting(_beside(sc))))))


REPLIES = ("Speak", "Speak", "FaceHumanAndSpeak", "QA", "Gesture", "")


def _replying(sc: Scenario) -> Scenario:
    """In about half the seeds, apps reply to their answered Q&As at once, from the end
    handler: with words (an exchange, 7.4), with their next question, or with a
    gesture. From a generator of its own (the other draws stay)."""
    r = random.Random(f"prima-reply:{sc.seed}")
    if r.random() >= 0.5:
        return sc
    scripts = tuple(dataclasses.replace(s, reply=r.choice(REPLIES)) for s in sc.scripts)
    beside = None if sc.beside is None else dataclasses.replace(sc.beside,
                                                                reply=r.choice(REPLIES))
    return dataclasses.replace(sc, scripts=scripts, beside=beside)  # type: ignore[arg-type]


BLENDS = (
    Blend(frozenset({"Turn", "SetSpeedAndTime", "Gesture", "MoveHead"}),
          frozenset({"TopologicalMove", "TrackingHuman", "SetPosition"}),
          frozenset({"locomotion", "neck"})),
    Blend(frozenset({"Speak", "FaceHumanAndSpeak"}), frozenset({"QA", "Speak"}),
          frozenset({"speaker"}), max_user_distance=2.0),
)
"""Blends a random robot declares: local motions over global ones, and speech over
speech (ducking; bounded, so the channel's ``near`` decides)."""


def _blending(sc: Scenario) -> Scenario:
    """In about one seed in three, the robot declares blends (the blend policy). From
    a generator of its own (the other draws stay)."""
    r = random.Random(f"prima-blend:{sc.seed}")
    if r.random() >= 0.33:
        return sc
    return dataclasses.replace(sc, blends=tuple(b for b in BLENDS if r.random() < 0.7))


def _interrupting(sc: Scenario) -> Scenario:
    """In about two seeds in five, the interrupt policy is on: reactions cut the
    others' utterances, gestures and feedback iterations; a request now and then says
    ``drop`` or ``never``. From a generator of its own (the other draws stay)."""
    r = random.Random(f"prima-interrupt:{sc.seed}")
    if r.random() >= 0.4:
        return sc
    acts = tuple(dataclasses.replace(a, on_interrupt=r.choice(("restart",) * 3
                                                              + ("drop", "never", "resume")))
                 if a.kind == "submit" else a for a in sc.acts)
    return dataclasses.replace(sc, acts=acts, interrupt=True,
                               cut_after=r.choice((0.0, 0.1, 0.25, 0.4)))


WORDS = ("stop", "stop", "ahem", "uh-huh")
"""What the user says outside a Q&A: words an app may take, a cough no app takes, a
backchannel."""


def _hearing(sc: Scenario) -> Scenario:
    """In about three seeds in ten, the robot hears its user at any time (the barge-in
    policy): about half the events become the user speaking (``speech`` acts), and
    each app takes words or not. From a generator of its own (the other draws stay)."""
    r = random.Random(f"prima-hearing:{sc.seed}")
    if r.random() >= 0.3:
        return sc
    acts = [dataclasses.replace(a, kind="speech", commands=(r.choice(WORDS),))
            if a.kind == "event" and r.random() < 0.6 else a for a in sc.acts]
    grid = int(sc.horizon * 4)
    acts += [Act(r.randint(0, grid) / 4, "fa", "speech", (r.choice(WORDS),))
             for _ in range(r.randint(1, 4))]  # (the user speaks whatever the robot does)
    acts.sort(key=lambda a: a.t)
    fa, ea, eb = (dataclasses.replace(s, takes=r.random() < 0.5) for s in sc.scripts)
    scripts = (fa, ea, eb)
    beside = dataclasses.replace(sc.beside, takes=r.random() < 0.5) if sc.beside else None
    config = dataclasses.replace(sc.config, barge_in=True,
                                 resume_pause=r.choice((0.0, 0.25, 0.6)))
    return dataclasses.replace(sc, acts=tuple(acts), scripts=scripts, beside=beside,
                               config=config, hearing=True)


def _regarding(sc: Scenario) -> Scenario:
    """In half the seeds whose robot turns to its user (connect-channel), the user goes
    off to the side at a few moments, whatever the robot does (``regard`` acts: the run
    tells the mediator, which keeps an utterance under way facing them, docs/rules.md
    7.6 (3)). From a generator of its own (the other draws stay)."""
    r = random.Random(f"prima-regard:{sc.seed}")
    if not sc.facing or r.random() >= 0.5:
        return sc
    grid = int(sc.horizon * 4)
    acts = [*sc.acts, *(Act(r.randint(0, grid) / 4, "fa", "regard")
                        for _ in range(r.randint(1, 3)))]
    acts.sort(key=lambda a: a.t)
    return dataclasses.replace(sc, acts=tuple(acts))


def _beside(sc: Scenario) -> Scenario:
    """In about a third of the seeds, a second EA runs beside the first all along and
    takes about half the EA's acts: three apps suspend and resume each other's streams.
    Drawn from a generator of its own, so that the other draws stay as they were."""
    r = random.Random(f"prima-beside:{sc.seed}")
    if r.random() >= 0.35:
        return sc
    acts = tuple(dataclasses.replace(a, role="eb") if a.role == "ea" and a.kind != "swap"
                 and r.random() < 0.5 else a for a in sc.acts)
    return dataclasses.replace(sc, acts=acts, beside=_script(r))


# ---------------------------------------------------------------- playing
@dataclass
class Result:
    """What one run did."""

    seed: int
    decisions: int = 0
    steps: int = 0
    violations: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    """Overruns of the literal wait-share bound that the oracle excuses (by design)."""


class _Listener:
    """One application: its script's handlers, reporting its callbacks to the oracle."""

    def __init__(self, run: _Run, name: str, script: AppScript) -> None:
        self.run = run
        self.name = name
        self.script = script
        self.calls = {"event": 0, "ended": 0, "cancelled": 0}

    def _maybe_raise(self, what: str) -> None:
        self.calls[what] += 1
        if self.script.raise_on == what and self.calls[what] == self.script.raise_at:
            raise RuntimeError(f"{self.name}: scripted failure in its {what} handler")

    def event(self, event: Event) -> None:
        if event.name in NEWS_EVENTS:
            return  # (news of its own stream: not reactive, it requests nothing here)
        self._maybe_raise("event")
        s = self.script
        if s.react and self.run.live():
            # like a handler with two chains: the first is reactive, the second is
            # part of the same reaction (docs/rules.md 7.1)
            first, rest = (s.react, ()) if s.react_asap else (s.react[:1], s.react[1:])
            user = event.name in USER_EVENTS
            self.run.submit(Request(self.name, tuple(call(c) for c in first), reactive=True,
                                    order=RunningOrder.ASAP if s.react_asap
                                    else RunningOrder.AFTER_LATEST, user=user))
            if rest:
                self.run.submit(Request(self.name, tuple(call(c) for c in rest),
                                        reaction=True, user=user))

    def takes(self, words: str) -> bool:
        return self.script.takes and words != "ahem"

    def command_ended(self, command_id: CommandId, outcome: Outcome) -> None:
        self.run.told(self.name, command_id, "ended")
        self.run.latest_ended[self.name] = command_id
        if outcome.values.get("status") == ANSWERED:
            self.run.answered.add(command_id)
        self._maybe_raise("ended")
        s = self.script
        if s.reply and self.run.live() and outcome.values.get("status") == ANSWERED:
            self.run.submit(Request(self.name, (call(s.reply),), follows=command_id))
            return
        if not self.run.live() or not (
                s.endless or (s.follow_every and command_id % s.follow_every == 0)):
            return
        if s.follow_delay == 0:
            self.run.submit(Request(self.name, (call(s.follow),), follows=command_id))
        else:
            h = self.run.h
            h.at(h.clock.now() + s.follow_delay,
                 lambda: self.run.guarded(Request(self.name, (call(s.follow),),
                                                  follows=command_id)))

    def command_cancelled(self, command_id: CommandId) -> None:
        self.run.told(self.name, command_id, "cancelled")
        self._maybe_raise("cancelled")


class _Facing:
    """A robot that faces its user at every ``period``-th question (connect-channel),
    and has moved since a stream was suspended but at every ``period``-th question
    (restore-state)."""

    def __init__(self, period: int) -> None:
        self.period = period
        self.asked = 0
        self.poses = 0

    def unfaced(self) -> bool:
        self.asked += 1
        return self.asked % self.period != 0

    def near(self, distance: float) -> bool:
        self.asked += 1
        return self.asked % self.period != 1

    def pose(self) -> Mapping[str, Value]:
        self.poses += 1
        return {"x": float(self.poses), "y": 0.0, "heading": 0.0}

    def displaced(self, pose: Mapping[str, Value]) -> bool:
        self.asked += 1
        return self.asked % self.period != 0


class _Run:
    """One scenario in the scripted harness, with the oracle watching."""

    MAX_STEPS = 20_000

    def __init__(self, sc: Scenario, tolerance: float) -> None:
        self.sc = sc
        standard = Catalog.standard()
        catalog = standard.interruptible(standard.usually_interruptible()) \
            if sc.interrupt or sc.hearing else standard
        catalog = catalog.with_blends(sc.blends)
        self.h = Harness(catalog, duration=sc.duration, outcome=sc.outcome, config=sc.config,
                         immediate=sc.immediate,
                         channel=_Facing(sc.facing) if sc.facing else None,
                         cut_after=sc.cut_after)
        self.m = self.h.mediator
        self.oracle = Oracle(self.m.catalog, sc.config, longest=sc.longest,
                             tolerance=tolerance)
        self.names = {"fa": "fa", "ea": "ea", "eb": "eb"}
        self.swaps = 0
        self.latest_ended: dict[str, CommandId] = {}
        self.answered: set[CommandId] = set()
        """The Q&As the user answered (a request that follows one may reply: 7.4)."""
        self.streams: set[str] = set()
        self.blocks: set[str] = set()
        self.register("fa", AppKind.FA, sc.scripts[0])
        self.register("ea", AppKind.EA, sc.scripts[1])
        if sc.beside is not None:
            self.register("eb", AppKind.EA, sc.beside)

    def register(self, name: str, kind: AppKind, script: AppScript) -> None:
        self.m.register(name, kind, _Listener(self, name, script))

    def live(self) -> bool:
        """Handlers still request (the scenario is not over)."""
        return self.h.clock.now() < self.sc.horizon

    def told(self, app: str, command: CommandId, what: str) -> None:
        self.oracle.callback(app, command, what, app in self.m.apps())

    def submit(self, request: Request) -> None:
        """Submit (errors go to the caller: inside a handler, they fail the app)."""
        self.oracle.requested(request.app, self.m.submit(request),
                              reaction=request.reactive or request.reaction,
                              first=request.reactive,
                              user=request.user, answer=request.follows in self.answered)

    def guarded(self, request: Request) -> None:
        """Submit from the scenario: a refused request is fine (nothing changes)."""
        if request.app in self.m.apps():
            with contextlib.suppress(MediationError):
                self.submit(request)

    # ------------------------------------------------------------ actions
    def act(self, a: Act) -> None:
        name = self.names[a.role]
        if a.kind == "swap":
            self.swap(a.role)
        elif a.kind == "regard":  # (the user goes off to the side, whatever runs)
            self.m.regard()
        elif a.kind == "speech":  # (the user, whoever is loaded)
            words = a.commands[0]
            self.m.hear(Event("speech", {"words": words, "backchannel": words == "uh-huh"}))
        elif name not in self.m.apps():
            return
        elif a.kind == "submit":
            follows = self.latest_ended.get(name) if a.follows else None
            self.guarded(Request(name, tuple(call(c) for c in a.commands),
                                 order=RunningOrder.ASAP if a.asap else RunningOrder.AFTER_LATEST,
                                 group=a.group, reactive=a.reactive, follows=follows,
                                 on_interrupt=OnInterrupt(a.on_interrupt)))
        elif a.kind == "event":
            self.m.post(Event(EVENTS[len(self.h.decisions) % len(EVENTS)]))
        elif a.kind == "stream":
            self.toggle_stream(name, a.hold)
        elif a.kind == "block":
            self.toggle_block(name, a)

    def toggle_stream(self, name: str, hold: float) -> None:
        if name in self.streams:
            self.streams.discard(name)
            self.m.close_stream(name)
        else:
            self.streams.add(name)
            self.m.open_stream(name, hold=hold)

    def toggle_block(self, name: str, a: Act) -> None:
        if name in self.blocks:
            self.blocks.discard(name)
            self.m.close_block(name)
        else:
            self.blocks.add(name)
            self.m.open_block(name, devices=None if a.devices is None else frozenset(a.devices),
                              watchdog=max(a.hold, 0.25))

    def swap(self, role: str) -> None:
        if role != "ea":
            return
        old = self.names["ea"]
        if old in self.m.apps():
            self.m.unregister(old)
        self.swaps += 1
        name = self.names["ea"] = f"ea{self.swaps}"
        self.register(name, AppKind.EA, self.sc.scripts[1 + self.swaps % 2])

    # ------------------------------------------------------------ the run
    def play(self) -> Result:
        h, m, oracle = self.h, self.m, self.oracle
        for a in self.sc.acts:
            h.at(a.t, functools.partial(self.act, a))
        result = Result(self.sc.seed)
        oracle.observe(h.decisions, m.snapshot())
        try:
            while h.step():
                result.steps += 1
                oracle.observe(h.decisions, m.snapshot())
                if result.steps >= self.MAX_STEPS:
                    oracle.fail(f"t={h.clock.now():g}: still busy after {result.steps} steps")
                    break
            # Apps unloaded by the mediator (failures) no longer hold streams or blocks.
            oracle.conclude(m.snapshot(), m.apps())
        except Exception as exc:  # noqa: BLE001 - the mediator or the driver broke: report it
            oracle.fail(f"t={h.clock.now():g}: {type(exc).__name__}: {exc}")
        result.decisions = len(h.decisions)
        result.violations = oracle.violations
        result.notes = oracle.notes
        return result


def play(seed: int, *, tolerance: float = 1e-6) -> Result:
    """Play the scenario of ``seed`` with the oracle watching."""
    return _Run(scenario(seed), tolerance).play()


def replay(seed: int) -> str:
    """The scenario of ``seed``, its decisions and what the oracle found (for a person)."""
    sc = scenario(seed)
    run = _Run(sc, 1e-6)
    result = run.play()
    lines = [str(sc), "decisions:"]
    lines += [f"  {d}" for d in run.h.decisions]
    lines += ["violations:"] + [f"  {v}" for v in result.violations] if result.violations \
        else ["no violation"]
    lines += [f"note (excused): {n}" for n in result.notes]
    return "\n".join(lines)


if __name__ == "__main__":  # pragma: no cover - python -m prima.mediator.random_driver SEED
    import sys

    print(replay(int(sys.argv[1]) if len(sys.argv) > 1 else 0))
