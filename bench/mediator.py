"""Mediator benchmark: decisions per second, and the cost of one decision as
working memory grows from 10 to 10,000 waiting ABs that cannot start.

Run: ``python bench/mediator.py`` (from the repository root). Workloads:

- ``free``: N ABs wait for the arm, held by a very long AB; an EA utterance is
  requested, started and ended over and over (request + start + end).
- ``blocked``: N ABs wait for the arm; each cycle adds one more AB that
  cannot start, then removes it again by an ASAP request of the same app
  (request + cancel + request decisions), so N stays constant.
- ``contended``: N ABs wait for the speaker; each cycle ends the running one,
  the best waiting AB starts, and one more waiting AB is added (end + start +
  request). Here the ABs that cannot start share the very device that frees.
- ``mixed``: two apps send random requests (chains, ASAP, reactive, groups,
  feedback Commands) through the scripted harness; all decisions counted.

The N waiting ABs are built with the public API: the FA's end handler for
one utterance requests N follow-ups (``follows``), which all join that
utterance's tree as siblings and enter the waiting list together.
"""

from __future__ import annotations

import random
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from prima.mediator import (  # noqa: E402
    AppKind,
    AtomicBehavior,
    Call,
    Catalog,
    ManualClock,
    Mediator,
    Outcome,
    Request,
    RunningOrder,
)
from prima.mediator.testing import Harness, ScriptedApp  # noqa: E402

SIZES = (10, 100, 1_000, 10_000)


class _Driver:
    def __init__(self) -> None:
        self.started: list[AtomicBehavior] = []

    def start(self, ab: AtomicBehavior) -> None:
        self.started.append(ab)

    def abandon(self, command_id: int) -> None:
        pass


def _speak(text: str = "x") -> Call:
    return Call("Speak", {"text": text})


def _point() -> Call:
    return Call("PointByHand", {"angle": 1.0})


def _setup(n: int, device_call: Call) -> tuple[Mediator, _Driver, int]:
    """N waiting ABs on ``device_call``'s devices, which a running AB holds."""
    driver = _Driver()
    clock = ManualClock()
    count = [0]
    m = Mediator(Catalog.standard(), driver, clock,
                 record=lambda d: count.__setitem__(0, count[0] + 1))

    def on_ended(cid: int, _o: Outcome) -> None:
        if cid == 2:
            for _ in range(n):
                m.submit(Request("fa", (device_call,), follows=2))

    m.register("fa", AppKind.FA, ScriptedApp("fa", on_ended=on_ended))
    m.register("ea", AppKind.EA, ScriptedApp("ea"))
    m.submit(Request("ea", (device_call,)))            # AB1 holds the device "forever"
    m.submit(Request("fa", (Call("MoveHead", {"pan": 1.0}),)))   # AB2 (Command 2)
    clock.set(0.1)
    m.finish(driver.started[-1].id)                     # -> N follow-ups, all waiting
    if len(m.snapshot().waiting) != n:
        raise RuntimeError("setup failed")
    return m, driver, count


def _timed(fn, m_count, cycles: int) -> tuple[float, int]:
    before = m_count[0]
    t0 = time.perf_counter()
    fn(cycles)
    dt = time.perf_counter() - t0
    return dt, m_count[0] - before


def bench_free(n: int, cycles: int = 3000) -> tuple[float, int]:
    m, driver, count = _setup(n, _point())

    def loop(k: int) -> None:
        for _ in range(k):
            m.submit(Request("ea", (_speak(),), order=RunningOrder.ASAP))
            m.finish(driver.started[-1].id)

    loop(50)
    return _timed(loop, count, cycles)


def bench_blocked(n: int, cycles: int = 3000) -> tuple[float, int]:
    m, driver, count = _setup(n, _point())
    # The EA's next requests: after its running AB1 (arm) -> they wait behind it.

    def loop(k: int) -> None:
        for _ in range(k):
            m.submit(Request("ea", (Call("Gesture", {"name": "bow"}),)))    # waits (arm busy)
            m.submit(Request("ea", (Call("Gesture", {"name": "nod"}),), order=RunningOrder.ASAP))

    loop(50)
    return _timed(loop, count, cycles)


def bench_contended(n: int, cycles: int = 3000) -> tuple[float, int]:
    m, driver, count = _setup(n, _speak())
    running = [driver.started[0].id]      # the EA's AB1 holds the speaker

    def loop(k: int) -> None:
        for _ in range(k):
            m.submit(Request("fa", (_speak(),), follows=2))     # one more waiting AB
            m.finish(running[0])                                # the best waiting one starts
            running[0] = driver.started[-1].id

    loop(50)
    return _timed(loop, count, cycles)


def bench_mixed(requests: int = 4000, seed: int = 7) -> tuple[float, int]:
    rnd = random.Random(seed)
    pool = [("Speak", {"text": "x"}), ("Turn", {"angle": 1.0}), ("MoveHead", {"pan": 1.0}),
            ("Gesture", {"name": "bow"}), ("FaceHumanAndSpeak", {"text": "x"}),
            ("QA", {"prompt": "?", "grammar": "g"}), ("TrackingHuman", {}),
            ("TopologicalMove", {"to": "room"}), ("PointByHand", {"angle": 1.0})]
    h = Harness(duration=lambda ab: 0.5 + (ab.id * 7919 % 13) / 4.0,
                outcome=lambda ab: Outcome(terminal=ab.iteration >= ab.id % 3))
    h.app("fa", AppKind.FA)
    h.app("ea", AppKind.EA)
    for i in range(requests):
        app = rnd.choice(("fa", "ea"))
        calls = tuple(Call(c, a) for c, a in rnd.sample(pool, rnd.randint(1, 3)))
        order = RunningOrder.ASAP if rnd.random() < 0.2 else RunningOrder.AFTER_LATEST
        r = Request(app, calls, order=order,
                    reactive=rnd.random() < 0.3)
        h.at(i * 0.8, lambda r=r: h.mediator.submit(r))
    t0 = time.perf_counter()
    h.run()
    return time.perf_counter() - t0, len(h.decisions)


def main() -> int:
    print(f"{'workload':<10} {'waiting':>8} {'decisions':>10} {'dec/s':>12} {'us/decision':>12}")
    worst = 0.0
    for name, fn in (("free", bench_free), ("blocked", bench_blocked),
                     ("contended", bench_contended)):
        for n in SIZES:
            dt, k = fn(n)
            us = dt / k * 1e6
            worst = max(worst, us)
            print(f"{name:<10} {n:>8} {k:>10} {k / dt:>12,.0f} {us:>12.2f}")
    dt, k = bench_mixed()
    print(f"{'mixed':<10} {'-':>8} {k:>10} {k / dt:>12,.0f} {dt / k * 1e6:>12.2f}"
          "   (includes the scripted harness)")
    print(f"worst us/decision over the sized workloads: {worst:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
