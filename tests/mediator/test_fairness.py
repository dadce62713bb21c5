"""The wait share's bookkeeping decides as the rule settled everywhere.

``Fairness`` settles a record only when it could decide something, works a share's
deadline out when asked and drops idle records late (see its docstring). ``Plain``
below is the rule as first written (every observation that sees something new and
every deadline settle every record, and keep each one's deadline): the two must
make the same decisions, at the same instants, and give the same deadlines, to the
last bit.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping
from itertools import islice
from types import SimpleNamespace

import pytest

import prima.mediator._mediator as mediator_module
from prima.catalog import Catalog
from prima.mediator import (
    AppKind,
    AtomicBehavior,
    Decision,
    DecisionKind,
    ManualClock,
    MediatorConfig,
    Outcome,
    Request,
)
from prima.mediator._decisions import Rule
from prima.mediator._fairness import _SLACK
from prima.mediator._holds import Holds
from prima.mediator._interface import Clock
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import App
from prima.mediator.random_driver import _Run, scenario
from prima.mediator.testing import Harness, ScriptedApp
from prima.vocab import Budgets
from tests.mediator.helpers import call, req, speak


class _PlainShare:
    def __init__(self) -> None:
        self.intervals: deque[tuple[float, float]] = deque()
        self.since: float | None = None
        self.demoted_until: float | None = None
        self.check_at: float | None = None
        self.charges: deque[tuple[float, float]] = deque()

    def total(self, now: float, window: float) -> float:
        start = now - window
        while self.intervals and self.intervals[0][1] <= start:
            self.intervals.popleft()
        while self.charges and self.charges[0][0] <= start:
            self.charges.popleft()
        total: float = 0
        if self.intervals:
            begin, end = self.intervals[0]
            lengths = (e - b for b, e in islice(self.intervals, 1, None))
            total = sum(lengths, end - max(start, begin))
        if self.since is not None:
            total += now - max(start, self.since)
        return total + sum(seconds for _at, seconds in self.charges)


class Plain:
    """The wait share as the rule is written: every record settled every time."""

    def __init__(self, apps: Mapping[str, App], wm: WorkingMemory, holds: Holds,
                 log: DecisionLog, clock: Clock) -> None:
        self._apps, self._wm, self._holds, self._log, self._clock = apps, wm, holds, log, clock
        self._shares: dict[str, _PlainShare] = {}
        self._observed: tuple[float, frozenset[str], tuple[str, ...]] | None = None

    def registrations(self) -> None:
        pass

    def charge(self, app: App, seconds: float) -> None:
        share = self._shares.setdefault(app.name, _PlainShare())
        share.charges.append((self._clock.now(), seconds))
        self._observed = None  # (settled anew: a spent share takes its precedence at once)
        self.expire()

    def observe(self) -> bool:
        now = self._clock.now()
        keeping = set(self._holds.keeping)
        for device, counts in self._wm.ranked.items():
            if not counts:
                continue
            holder = self._wm.busy.get(device) or self._wm.index.top(device)
            if holder is not None and any(app != holder.app.name and p >= holder.priority
                                          for app, p in counts):
                keeping.add(holder.app.name)
        seen = (now, frozenset(keeping), tuple(self._apps))
        if seen == self._observed:
            return False
        self._observed = seen
        for name in self._apps:
            if name in keeping and name not in self._shares:
                self._shares[name] = _PlainShare()
        for name, share in self._shares.items():
            if name in keeping:
                if share.since is None:
                    share.since = now
            else:
                if share.since is not None and now > share.since:
                    share.intervals.append((share.since, now))
                share.since = None
        return self.expire()

    def expire(self) -> bool:
        now = self._clock.now()
        changed = False
        gone = []
        for name, share in self._shares.items():
            app = self._apps.get(name)
            if app is None:
                gone.append(name)
                continue
            limit, window = app.budgets.wait_share, app.budgets.wait_window
            if share.demoted_until is not None and share.demoted_until <= now:
                share.demoted_until = None
                changed |= self._set(app, False, "regains its precedence")
            used = share.total(now, window)
            if share.since is None and not share.charges:
                share.check_at = None
                if share.demoted_until is None and not share.intervals:
                    gone.append(name)
                continue
            if used >= limit - _SLACK:
                used = max(used, limit)
            if used >= limit and share.demoted_until is None:
                share.demoted_until = self._clock.after(window)
                changed |= self._set(
                    app, True, f"kept other applications waiting {used:g} s within "
                               f"{window:g} s: it loses its precedence until "
                               f"t={share.demoted_until:g} s")
            share.check_at = self._clock.after(limit - used) \
                if used < limit and share.since is not None else None
        for name in gone:
            del self._shares[name]
        return changed

    def _set(self, app: App, demoted: bool, detail: str) -> bool:
        if app.demoted is demoted:
            return False
        app.demoted = demoted
        self._wm.rerank_app(app)
        if demoted:
            self._holds.unpark_all()
        else:
            self._holds.regained(app)
        self._log.emit(DecisionKind.BUDGET, Rule.WAIT_SHARE, app=app.name, detail=detail)
        return True

    def next_deadline(self) -> float | None:
        times = [t for s in self._shares.values() for t in (s.demoted_until, s.check_at)
                 if t is not None]
        return min(times, default=None)


Deadlines = list[tuple[float, float | None]]


def _both(play: Callable[[Deadlines], list[Decision]],
          monkeypatch: pytest.MonkeyPatch) -> list[Decision]:
    """Play twice, with ``Fairness`` and with ``Plain``: the same decisions and deadlines."""
    kept: Deadlines = []
    decisions = play(kept)
    with monkeypatch.context() as patch:
        patch.setattr(mediator_module, "Fairness", Plain)
        plain: Deadlines = []
        assert play(plain) == decisions
    assert kept == plain
    return decisions


def _watching(m: mediator_module.Mediator, clock: Callable[[], float],
              deadlines: Deadlines) -> None:
    """Record every deadline the mediator gives (with the instant it is asked)."""
    ask = m.next_deadline

    def asked() -> float | None:
        t = ask()
        deadlines.append((clock(), t))
        return t
    m.next_deadline = asked  # type: ignore[method-assign]


ORDERED = (70, 1484, 1755, 4086, 4703)
"""Seeds in which an app's record dropped and made again (its app idle a whole window)
orders two budget decisions at one instant."""


@pytest.mark.pure
def test_random_scenarios_decide_as_the_rule_settled_everywhere(
        monkeypatch: pytest.MonkeyPatch) -> None:
    budgets = 0
    for seed in (*ORDERED, *range(3_000, 3_400)):
        def play(deadlines: Deadlines, seed: int = seed) -> list[Decision]:
            run = _Run(scenario(seed), 1e-6)
            _watching(run.m, run.h.clock.now, deadlines)
            run.play()
            return run.h.decisions
        decisions = _both(play, monkeypatch)
        budgets += any(d.kind is DecisionKind.BUDGET for d in decisions)
    assert budgets >= 40  # (the seeds do spend shares)


TIGHT = MediatorConfig(budgets={AppKind.FA: Budgets(wait_share=2.0, wait_window=5.0),
                                AppKind.EA: Budgets(wait_share=1.0, wait_window=3.0)})


@pytest.mark.pure
def test_an_app_registered_again_under_its_name_within_one_operation(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The new registration takes the record over from the next settle on."""
    def play(deadlines: Deadlines) -> list[Decision]:
        h = Harness(duration=0.75, config=TIGHT)
        m = h.mediator
        _watching(m, h.clock.now, deadlines)
        chained = [0]

        def chain(cid: int, _o: Outcome) -> None:
            chained[0] += 1
            if chained[0] == 4:  # (inside the finish: one operation)
                m.unregister("ea")
                m.register("ea", AppKind.FA if h.clock.now() < 0 else AppKind.EA,
                           ScriptedApp("ea", on_ended=chain))
            m.submit(Request("ea", (speak("and"),), follows=cid if chained[0] != 4 else None))

        h.app("fa", AppKind.FA)
        h.app("ea", AppKind.EA, on_ended=chain)
        m.submit(req("ea", speak("first")))
        h.at(0.5, lambda: m.submit(req("fa", speak("me"))))
        h.at(4.0, lambda: m.submit(req("fa", speak("me again"))))
        h.run(until=20.0)
        return h.decisions
    decisions = _both(play, monkeypatch)
    assert any(d.kind is DecisionKind.BUDGET for d in decisions)


@pytest.mark.pure
def test_a_deadline_asked_after_time_moved_on_is_the_last_settle_s(
        monkeypatch: pytest.MonkeyPatch) -> None:
    def play(deadlines: Deadlines) -> list[Decision]:
        h = Harness(duration=0.3, config=TIGHT)
        m = h.mediator
        _watching(m, h.clock.now, deadlines)

        def chain(cid: int, _o: Outcome) -> None:
            m.submit(Request("ea", (speak("and"),), follows=cid))

        h.app("fa", AppKind.FA)
        h.app("ea", AppKind.EA, on_ended=chain)
        m.submit(req("ea", speak("first")))
        h.at(0.1, lambda: m.submit(req("fa", speak("me"))))
        for until in (0.2, 0.45, 0.7, 1.05, 1.3, 2.0, 3.7, 9.0):
            h.run(until=until)  # (the clock is set to ``until``: no operation then)
            m.submit(req("fa", call("MoveHead", pan=until)))
            h.clock.set(until + 1 / 3)
            m.next_deadline()
        return h.decisions
    decisions = _both(play, monkeypatch)
    assert any(d.kind is DecisionKind.BUDGET for d in decisions)


SLIDING = MediatorConfig(budgets={AppKind.FA: Budgets(),
                                   AppKind.EA: Budgets(wait_share=1.0, wait_window=1.5)})


@pytest.mark.pure
def test_deadlines_follow_a_share_sliding_out_of_its_window(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The EA keeps the FA waiting, stops, and keeps it waiting again while the FA
    moves its head (operations at new instants, the same keepers): as its first
    interval slides out of the window, its share runs out later and later."""
    lengths = {"a": 0.35, "f1": 0.3, "b": 5.0}

    def play(deadlines: Deadlines) -> list[Decision]:
        h = Harness(duration=lambda ab: lengths.get(str(ab.calls[0].args.get("text")), 0.05),
                    config=SLIDING)
        m = h.mediator
        _watching(m, h.clock.now, deadlines)
        h.app("fa", AppKind.FA)
        h.app("ea", AppKind.EA)
        m.submit(req("ea", speak("a")))
        h.at(0.05, lambda: m.submit(req("fa", speak("f1"))))
        h.at(1.0, lambda: m.submit(req("ea", speak("b"))))
        h.at(1.05, lambda: m.submit(req("fa", speak("f2"))))
        for i in range(1, 12):
            h.at(1.05 + i * 0.1, lambda: m.submit(req("fa", call("MoveHead", pan=0.1))))
        h.run(until=2.5)
        # Asked only after time moved on: as of the last operation.
        m.submit(req("fa", call("MoveHead", pan=0.2)))
        h.clock.set(2.5 + 1 / 3)
        m.next_deadline()
        return h.decisions
    decisions = _both(play, monkeypatch)
    budget = [d for d in decisions if d.kind is DecisionKind.BUDGET]
    assert [d.app for d in budget] == ["ea"] and budget[0].t == pytest.approx(2.05)


@pytest.mark.pure
def test_a_record_dropped_is_made_again_after_the_others(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The EA ``ea`` kept the FA waiting at 0 s, then nobody for a whole window: the rule
    drops its record. The EA ``eb`` spends its share at 1.5 s. At 2 s ``ea`` keeps
    ``eb`` waiting again, in the operation in which the FA registers a third EA (every
    record is settled): its new record comes after ``eb``'s, so at 2.5 s ``eb`` regains
    its precedence before ``ea`` loses its own."""
    lengths = {"e0": 0.1, "x": 0.1, "e1": 0.5, "y": 0.5}
    config = MediatorConfig(budgets={AppKind.FA: Budgets(),
                                     AppKind.EA: Budgets(wait_share=0.5, wait_window=1.0)})

    def play(deadlines: Deadlines) -> list[Decision]:
        h = Harness(duration=lambda ab: lengths.get(str(ab.calls[0].args.get("text")), 5.0),
                    config=config)
        m = h.mediator
        _watching(m, h.clock.now, deadlines)

        def registering(_cid: int, _o: Outcome) -> None:
            if h.clock.now() == 2.0:
                m.register("ec", AppKind.EA, ScriptedApp("ec"))

        h.app("fa", AppKind.FA, on_ended=registering)
        h.app("ea", AppKind.EA)
        h.app("eb", AppKind.EA)
        m.submit(req("ea", speak("e0")))
        m.submit(req("fa", speak("x")))
        h.at(1.0, lambda: (m.submit(req("eb", speak("e1"))), m.submit(req("fa", speak("y")))))
        h.at(1.6, lambda: (m.submit(req("ea", speak("e2"))), m.submit(req("eb", speak("e3")))))
        h.run(until=3.0)
        return h.decisions
    decisions = _both(play, monkeypatch)
    budget = [(d.t, d.app, d.detail[:7]) for d in decisions if d.kind is DecisionKind.BUDGET]
    assert budget == [(1.5, "eb", "kept ot"), (2.5, "eb", "regains"), (2.5, "ea", "kept ot")]


def test_a_record_never_near_its_share_keeps_only_the_window() -> None:
    """An app that keeps another waiting now and then, over and over, with a share it
    never comes near spending, is never settled (and here no deadline is asked, which
    would sum it): closing an interval forgets those that ended before the window, so
    its record stays as short as the window."""
    config = MediatorConfig(budgets={AppKind.FA: Budgets(),
                                     AppKind.EA: Budgets(wait_share=1e6, wait_window=10.0)})
    clock = ManualClock()
    started: list[AtomicBehavior] = []
    driver = SimpleNamespace(start=started.append, abandon=lambda _cid: None,
                             cut=lambda _ab: False)
    m = mediator_module.Mediator(Catalog.standard(), driver, clock, config=config)
    for name, kind in (("fa", AppKind.FA), ("ea", AppKind.EA)):
        m.register(name, kind, ScriptedApp(name))
    for i in range(400):  # the EA talks while the FA waits for it, then the FA talks
        clock.set(i * 2.0)
        m.submit(req("ea", speak("mine")))
        clock.set(i * 2.0 + 0.1)
        m.submit(req("fa", speak("me")))
        clock.set(i * 2.0 + 0.5)
        m.finish(started[-1].id)
        clock.set(i * 2.0 + 1.0)
        m.finish(started[-1].id)
    share = m._fairness._shares["ea"]
    assert 4 <= len(share.intervals) <= 6  # (one per 2 s, within 10 s)
    assert len(share.lengths) == len(share.intervals)
