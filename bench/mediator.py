"""Mediator benchmark: the cost of one operation as the waiting list grows from
10 to 10,000 ABs, in workloads whose operations touch those waiting ABs.

Run: ``python bench/mediator.py [--sizes 10,100,1000,10000] [--repeats 15]
[--robot robots/home-robot.xml]`` (from the repository root; ``--robot``: that
robot's Commands and the policies a run on it has, instead of the standard
Commands). Measured as every benchmark here measures
(``bench/_measure.py``): CPU time, the median of interleaved rounds (one round
runs every size once), each size as a ratio to N=10 measured in the same rounds
(flat is 1.00x).

Three applications (the FA ``fa`` and the EAs ``ea`` and ``eb``) keep N waiting
ABs in several trees (Communication Streams) each, all wanting devices that a
running AB holds; the budgets are raised so that one app may keep 10,000. An
*operation* is one public call (``submit`` or ``finish``, with the selection
round it triggers). Workloads:

- ``contend``: N ABs of a dozen trees wait for the speaker. Each cycle an app
  requests a head move (ASAP: a new tree), which starts; its end requests one
  more utterance into that tree; the utterance on the speaker ends and the
  best waiting one starts (request, start, end, request, start, end).
- ``react``: an EA's stream holds half the waiting ABs (the other half are
  the other apps'). Each cycle the FA reacts (a reactive utterance), the EA's
  utterance ends (its end handler continues the stream), the reaction starts
  and suspends the EA's stream; the reaction ends and the stream resumes.
- ``asap``: the EA, whose own trees hold half the waiting ABs (arm), asks
  again and again, as soon as possible and as a reaction, for an utterance:
  each request cancels the last one and takes the speaker's top rank from the
  other apps' N/2 waiting utterances (cancel, request).
- ``hold``: the EA talks in an explicit stream, between its utterances its
  stream's hold arms (and lapses at its next request) while N moves of the
  other apps wait for the wheels (request, start, end, arm, lapse).
- ``free``: N ABs wait for the arm; the EA says something and it ends, over
  and over, on the free speaker (operations that never touch the waiting ABs:
  the peer of the others).
- ``burst``: one ``finish()`` whose end handler requests N follow-ups that all
  wait (the speaker is busy; 30 ABs of other apps wait too): the cost per
  released AB, which must not grow with N (the burst linear in N).

The script asserts that each workload keeps N waiting ABs. The targets we hold
it to: every workload's operations flat within a factor of 2 from N=10 to
N=10,000 and at most 20 us each (median); the burst's cost per AB flat within
a factor of 2.
"""

from __future__ import annotations

import argparse
import dataclasses
import gc
import sys
from collections.abc import Callable, Sequence
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _measure import cpu, fmt_time, interleaved, interpreter, report  # noqa: E402

from prima.mediator import (  # noqa: E402
    AppKind,
    AtomicBehavior,
    Call,
    Catalog,
    CommandId,
    Event,
    ManualClock,
    Mediator,
    MediatorConfig,
    Outcome,
    Request,
    RunningOrder,
)
from prima.dsl import load_profile  # noqa: E402
from prima.errors import PrimaError  # noqa: E402
from prima.vocab import Budgets, policy_settings  # noqa: E402

SIZES = (10, 100, 1_000, 10_000)
FLAT = 2.0
"""Acceptance: the largest per-operation median at most this many times the smallest."""
LIMIT = 20e-6
"""Acceptance: each median at most this (seconds per operation)."""

_BIG = Budgets(waiting=10**7, starts_per_instant=10**7, wait_share=10**6, wait_window=60.0)
CONFIG = MediatorConfig(budgets={AppKind.FA: _BIG, AppKind.EA: _BIG},
                        interrupt=True, blend=True)
"""One app may keep 10,000 ABs waiting, and never loses its precedence; the interrupt and
blend policies on (off by default), so that ``--robot``'s blends and interruptible
Commands give them work."""
CATALOG = Catalog.standard()
"""The Commands the workloads request (``--robot``: a robot profile's, whose blends
and interruptible Commands give the blend and interrupt policies work to weigh)."""

SPEAK = Call("Speak", {"text": "x"})
POINT = Call("PointByHand", {"angle": 1.0})
HEAD = Call("MoveHead", {"pan": 1.0})
TURN = Call("Turn", {"angle": 1.0})
FACE = Call("FaceHuman")


class _Driver:
    """Starts nothing itself: the world finishes ABs when a workload says so."""

    def __init__(self) -> None:
        self.running: dict[int, AtomicBehavior] = {}
        self.on: dict[str, int] = {}
        """Device -> the running AB on it."""

    def start(self, ab: AtomicBehavior) -> None:
        self.running[ab.id] = ab
        for d in ab.devices:
            self.on[d] = ab.id

    def abandon(self, command_id: CommandId) -> None:
        pass

    def cut(self, ab_id: int) -> bool:
        return False

    def stop_words(self, ab_id: int) -> bool:
        return False


class _App:
    """A listener whose end handler requests what ``World.plans`` says."""

    def __init__(self, world: World, name: str) -> None:
        self.world = world
        self.name = name

    def event(self, event: Event) -> None:
        pass

    def command_ended(self, command_id: CommandId, outcome: Outcome) -> None:
        plan = self.world.plans.pop(command_id, None)
        if plan:
            for call in plan:
                self.world.m.submit(Request(self.name, (call,), follows=command_id))

    def command_cancelled(self, command_id: CommandId) -> None:
        pass

    def takes(self, words: str) -> bool:
        return False


class World:
    """A mediator with three apps, a scripted driver and a clock that steps 1 s per cycle."""

    def __init__(self) -> None:
        self.clock = ManualClock()
        self.driver = _Driver()
        self.decisions = 0
        self.plans: dict[CommandId, Sequence[Call]] = {}
        self.m = Mediator(CATALOG, self.driver, self.clock, config=CONFIG,
                          record=self._count)
        for name, kind in (("fa", AppKind.FA), ("ea", AppKind.EA), ("eb", AppKind.EA)):
            self.m.register(name, kind, _App(self, name))

    def _count(self, _decision: object) -> None:
        self.decisions += 1

    def submit(self, app: str, call: Call, **kw: object) -> CommandId:
        return self.m.submit(Request(app, (call,), **kw))[0]  # type: ignore[arg-type]

    def finish(self, ab_id: int) -> None:
        ab = self.driver.running.pop(ab_id)
        for d in ab.devices:
            if self.driver.on.get(d) == ab_id:
                del self.driver.on[d]
        self.m.finish(ab_id)

    def finish_on(self, device: str) -> None:
        self.finish(self.driver.on[device])

    def tick(self) -> None:
        self.clock.set(self.clock.now() + 1.0)

    def tree(self, app: str, calls: Sequence[Call], *, seed: Call = HEAD,
             **kw: object) -> None:
        """A new tree of ``app`` whose first AB (``seed``, on a free device) ends at
        once and releases ``calls``, which wait (their devices are busy)."""
        cid = self.submit(app, seed, order=RunningOrder.ASAP, **kw)
        self.plans[cid] = calls
        self.finish(self.driver.on[next(iter(self.m.catalog[seed.command].devices))])

    def waiting(self) -> int:
        return len(self.m.snapshot().waiting)


def _spread(n: int, trees: int) -> list[int]:
    """``n`` ABs over at most ``trees`` trees."""
    trees = min(trees, n)
    return [n // trees + (i < n % trees) for i in range(trees)]


class Workload:
    """One workload at one size: ``cycle()`` runs ``ops`` public operations and
    leaves N ABs waiting."""

    ops = 1

    def __init__(self, n: int) -> None:
        self.n = n
        self.w = World()

    def cycle(self) -> None:
        raise NotImplementedError

    def check(self) -> None:
        if self.w.waiting() != self.n:
            raise RuntimeError(f"{type(self).__name__}({self.n}): "
                               f"{self.w.waiting()} ABs waiting, not {self.n}")


class Contend(Workload):
    ops = 3

    def __init__(self, n: int) -> None:
        super().__init__(n)
        w = self.w
        w.submit("eb", SPEAK)                           # holds the speaker
        for i, k in enumerate(_spread(n, 12)):
            w.tree(("fa", "ea", "eb")[i % 3], [SPEAK] * k)
        self.turn = 0
        self.check()

    def cycle(self) -> None:
        w = self.w
        w.tick()
        self.turn += 1
        app = ("fa", "ea", "eb")[self.turn % 3]
        cid = w.submit(app, HEAD, order=RunningOrder.ASAP)   # a new tree; starts
        w.plans[cid] = (SPEAK,)
        w.finish_on("neck")                                   # -> one more utterance waits
        w.finish_on("speaker")                                # the best waiting one starts


class React(Workload):
    ops = 3

    def __init__(self, n: int) -> None:
        super().__init__(n)
        w = self.w
        w.submit("eb", SPEAK)                            # holds the speaker
        half = n // 2
        # the EA's stream (oldest): its first utterance starts once the speaker frees
        w.tree("ea", [SPEAK] * (half + 1))
        for k in _spread(n - half, 4):
            w.tree("eb", [SPEAK] * k)
        w.finish_on("speaker")
        self.check()

    def cycle(self) -> None:
        w = self.w
        w.tick()
        stream = w.driver.on["speaker"]
        w.submit("fa", SPEAK, reactive=True)               # waits for the EA's utterance
        w.plans[w.driver.running[stream].command_ids[0]] = (SPEAK,)
        w.finish(stream)               # the stream goes on, but the reaction starts: suspended
        w.finish_on("speaker")         # the reaction ends: the stream resumes


class Asap(Workload):
    ops = 1

    def __init__(self, n: int) -> None:
        super().__init__(n)
        w = self.w
        w.submit("fa", POINT)                            # holds the arm
        w.submit("eb", SPEAK)                            # holds the speaker
        half = n // 2
        for k in _spread(half, 4):
            w.tree("ea", [POINT] * k)
        for i, k in enumerate(_spread(n - half - 1, 8)):
            w.tree(("fa", "eb")[i % 2], [SPEAK] * k)
        w.submit("ea", SPEAK, order=RunningOrder.ASAP, reactive=True)
        self.check()

    def cycle(self) -> None:
        self.w.tick()
        self.w.submit("ea", SPEAK, order=RunningOrder.ASAP, reactive=True)


class Hold(Workload):
    ops = 2

    def __init__(self, n: int) -> None:
        super().__init__(n)
        w = self.w
        w.submit("eb", TURN)                             # holds the wheels
        for i, k in enumerate(_spread(n, 12)):
            w.tree(("fa", "eb")[i % 2], [FACE] * k)
        w.m.open_stream("ea", hold=5.0)
        w.submit("ea", SPEAK)
        w.finish_on("speaker")                           # idle: the hold arms
        self.check()

    def cycle(self) -> None:
        w = self.w
        w.tick()
        w.submit("ea", SPEAK)          # the stream goes on (its hold lapses); it starts
        w.finish_on("speaker")         # idle again: the hold arms


class Free(Workload):
    ops = 2

    def __init__(self, n: int) -> None:
        super().__init__(n)
        w = self.w
        w.submit("eb", POINT)                            # holds the arm
        for i, k in enumerate(_spread(n, 12)):
            w.tree(("fa", "eb")[i % 2], [POINT] * k)
        self.check()

    def cycle(self) -> None:
        w = self.w
        w.tick()
        w.submit("ea", SPEAK, order=RunningOrder.ASAP)
        w.finish_on("speaker")


WORKLOADS: dict[str, type[Workload]] = {
    "contend": Contend, "react": React, "asap": Asap, "hold": Hold, "free": Free,
}


def burst(n: int) -> Callable[[], float]:
    """A case: CPU seconds per AB of one ``finish()`` whose end handler requests
    ``n`` follow-ups (a fresh mediator each time; building it is not timed)."""
    def case() -> float:
        w = World()
        w.submit("eb", SPEAK)                             # holds the speaker
        for i in range(3):
            w.tree(("fa", "eb", "ea")[i], [SPEAK] * 10)
        cid = w.submit("ea", HEAD, order=RunningOrder.ASAP)
        w.plans[cid] = [SPEAK] * n
        ab = w.driver.on["neck"]
        gc.collect()
        spent = cpu(lambda: w.finish(ab))
        if w.waiting() != n + 30:
            raise RuntimeError(f"burst({n}): {w.waiting()} waiting, not {n + 30}")
        return spent / n
    return case


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sizes", default=",".join(map(str, SIZES)),
                   help="waiting ABs, comma-separated; the first is the peer")
    p.add_argument("--repeats", type=int, default=15, help="interleaved rounds")
    p.add_argument("--cycles", type=int, default=200, help="cycles per round and size")
    p.add_argument("--only", default="", help="comma-separated workloads (default: all)")
    p.add_argument("--robot", type=Path, default=None,
                   help="a robot profile (robots/*.xml): its Commands, and its policies as "
                        "a run sets them (default: the standard Commands, every policy on)")
    args = p.parse_args(argv)
    if args.robot is not None:
        try:
            _use_robot(args.robot)
        except PrimaError as exc:
            print(exc, file=sys.stderr)
            return 2
    sizes = [int(s) for s in args.sizes.split(",")]
    names = [s for s in args.only.split(",") if s] or [*WORKLOADS, "burst"]
    peer = f"N={sizes[0]}"
    verdicts: list[tuple[str, float, float, bool]] = []
    for name in names:
        if name == "burst":
            reps = max(3, args.repeats // 3)
            medians = interleaved({f"N={n}": burst(n) for n in sizes}, reps)
            report("burst: one finish() releasing N follow-ups, per released AB", medians,
                   peer, repeats=reps)
            verdicts.append(_verdict(name, medians, limit=None, peer=peer))
            continue
        loads = {n: WORKLOADS[name](n) for n in sizes}
        for load in loads.values():     # warm up (and settle what the setup left)
            for _ in range(20):
                load.cycle()
        peer_load = loads[sizes[0]]
        before = peer_load.w.decisions
        for _ in range(20):
            peer_load.cycle()
        decisions = (peer_load.w.decisions - before) / (20 * peer_load.ops)
        cases = {f"N={n}": _case(load, args.cycles) for n, load in loads.items()}
        medians = interleaved(cases, args.repeats)
        for load in loads.values():
            load.check()
        report(f"{name}: per operation ({loads[sizes[0]].ops} per cycle)", medians, peer,
               repeats=args.repeats)
        verdicts.append(_verdict(name, medians, limit=LIMIT, decisions=decisions))
        del loads
        gc.collect()
    print()
    print(f"Acceptance: each workload flat within {FLAT:g}x from N={sizes[0]} to "
          f"N={sizes[-1]} (largest median / smallest) and at most {fmt_time(LIMIT)} per "
          f"operation; the burst linear in N (no size's cost per AB above {FLAT:g}x "
          f"N={sizes[0]}'s)")
    ok = True
    for v in verdicts:
        ok &= v.met
        print(f"  {v}")
    print(interpreter())
    return 0 if ok else 1


def _use_robot(path: Path) -> None:
    """Run the workloads on a robot profile's Commands, with the policies a run on that
    robot has by default (no channel here: connect-channel and restore-state ask none)."""
    global CATALOG, CONFIG
    profile = load_profile(path)
    policies = policy_settings(profile.policies)
    CATALOG = profile.catalog()
    CONFIG = dataclasses.replace(CONFIG, interrupt=policies["interrupt"],
                                 blend=policies["blend"])
    print(f"robot: {path} (interrupt {'on' if CONFIG.interrupt else 'off'}, "
          f"blend {'on' if CONFIG.blend else 'off'}; {len(CATALOG.blends)} blend(s))")


def _case(load: Workload, cycles: int) -> Callable[[], float]:
    def run() -> None:
        for _ in range(cycles):
            load.cycle()
    return lambda: cpu(run) / (cycles * load.ops)


class _Verdict:
    """One workload's figures against the two targets: flat, and fast enough."""

    def __init__(self, name: str, spread: float, worst: float, flat: bool,
                 fast: bool | None, decisions: float | None) -> None:
        self.name, self.spread, self.worst = name, spread, worst
        self.flat, self.fast, self.decisions = flat, fast, decisions

    @property
    def met(self) -> bool:
        return self.flat and self.fast is not False

    def __str__(self) -> str:
        def verdict(ok: bool) -> str:
            return "met" if ok else "NOT MET"
        if self.fast is None or self.decisions is None:
            return f"{self.name:<8} per AB grows {self.spread:4.2f}x: {verdict(self.flat)}"
        return (f"{self.name:<8} spread {self.spread:4.2f}x: {verdict(self.flat):<7}  "
                f"worst {fmt_time(self.worst):>8} per operation: {verdict(self.fast):<7}  "
                f"({self.decisions:.1f} decisions, {fmt_time(self.worst / self.decisions)} "
                "each)")


def _verdict(name: str, medians: dict[str, float], *, limit: float | None,
             decisions: float | None = None, peer: str | None = None) -> _Verdict:
    values = list(medians.values())
    if peer is not None:    # linear: no size costs more per AB than FLAT times the peer
        growth = max(values) / medians[peer]
        return _Verdict(name, growth, max(values), growth <= FLAT, None, None)
    spread = max(values) / min(values)
    worst = max(values)
    return _Verdict(name, spread, worst, spread <= FLAT,
                    None if limit is None else worst <= limit, decisions)


if __name__ == "__main__":
    sys.exit(main())
