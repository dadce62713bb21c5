"""The wait-share budget: how long an application may keep the others waiting.

An application *keeps another waiting* while, on some device, another
application has a waiting AB whose priority is not lower than that of the
application's AB that holds the device (the AB running on it, or, on a free
device, the best-ranked waiting AB, which reserves it), or while one of its
stream holds or blocks, or a reaction's next AB that keeps its devices (docs/rules.md
7.1), parks another application's AB. Priority aside: an AB
that breaks the Communication Channel waiting for one that keeps it is the
channel rule at work, not a budget matter.

An application may keep the others waiting for at most ``wait_share``
seconds within any ``wait_window`` (the robot profile's budgets). Beyond it,
it loses its precedence for one window: its streams and blocks hold nothing,
and its ABs rank after the others' of the same priority (criterion
``wait-share``). However it combines running ABs, end-handler chains, stream
holds re-armed after every request and blocks left and re-entered, an
application cannot keep another's ready AB waiting longer than its share plus
one atomic behavior.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Mapping
from itertools import islice
from math import inf
from typing import Final

from prima.mediator._decisions import DecisionKind, Rule
from prima.mediator._holds import Holds
from prima.mediator._interface import Clock
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import App

__all__ = ["Fairness"]


_SLACK: Final = 1e-9
"""Seconds of a wait share that floating-point sums may leave over: below this, it
is spent (else its next check would fall on the very instant it is made)."""

_MARGIN: Final = 1e-6
"""Far more than the rounding of any sum of a share, relative to the times and budgets
summed: a share this much short of running out, or more, need not be summed."""


def _spent(used: float, limit: float) -> float:
    """Seconds of a share spent, ``used`` as summed: times summed in floating point, a
    share spent up to rounding (:data:`_SLACK`) is spent (or its deadline is now)."""
    return max(used, limit) if used >= limit - _SLACK else used


class _Share:
    """One application's record of keeping the others waiting."""

    __slots__ = ("app", "limit", "window", "horizon", "intervals", "lengths", "since",
                 "demoted_until", "bound", "bound_at", "due", "charges")

    def __init__(self, app: App) -> None:
        self.intervals: deque[tuple[float, float]] = deque()
        """Closed intervals, oldest first, within the last window (in a record not
        settled for a while, perhaps older ones too)."""
        self.lengths: deque[float] = deque()
        """Each interval's length (``end - begin``), in the same order."""
        self.charges: deque[tuple[float, float]] = deque()
        """Time charged at an instant, oldest first: (when, seconds). What the interrupt
        policy threw away when the app's reaction had another's AB cut (docs/rules.md
        7.3 (2)) counts against its share while the instant is within the window."""
        self.since: float | None = None
        """When the current interval began, if the app keeps others waiting now."""
        self.demoted_until: float | None = None
        self.bound = 0.0
        """At least what :meth:`total` sums at ``bound_at`` (up to rounding): no more is
        spent later while the app keeps nobody waiting, and at most the time since
        ``bound_at`` more while it does (the interval under way grows by the time
        passed, the older ones only drop out of the window)."""
        self.bound_at = 0.0
        self.due = inf
        """No settle before this instant can decide anything about the record
        (:meth:`plan`): infinity while its app keeps nobody waiting and has its
        precedence."""
        self.use(app)

    def use(self, app: App) -> None:
        """Settle the record with this registration (and its budgets, which never change:
        ``limit`` and ``window`` are its ``wait_share`` and ``wait_window``)."""
        self.app = app
        """The registration the record was last settled with."""
        budgets = app.budgets
        self.limit = limit = budgets.wait_share
        self.window = window = budgets.wait_window
        self.horizon = ((limit - _SLACK - max(window, 0.0)) / _MARGIN
                        - (1.0 + abs(window) + abs(limit)))
        """Before this instant (in absolute value), a whole window is short of the
        share by :data:`_MARGIN` and more: the share cannot be spent (see :meth:`plan`)."""

    def prune(self, now: float, window: float) -> None:
        """Forget the intervals that ended before ``[now - window, now]``."""
        start = now - window
        while self.intervals and self.intervals[0][1] <= start:
            self.intervals.popleft()
            self.lengths.popleft()
        charges = self.charges
        while charges and charges[0][0] <= start:
            charges.popleft()

    def open(self, now: float) -> None:
        """The app starts keeping others waiting: an interval begins."""
        self.since = self.bound_at = now
        # (``plan``, its usual cases inline: a demoted app's record stays due when its
        # precedence comes back, and a share that cannot be spent is never due)
        if self.demoted_until is None and not abs(now) < self.horizon:
            self.plan()

    def close(self, now: float) -> None:
        """The app stops keeping others waiting: the current interval is closed (and
        those that ended before the window are forgotten, as any later sum would: a
        record that is never settled, its share never near spent, stays as short)."""
        since = self.since
        if since is not None:
            if now > since:
                self.prune(now, self.window)
                self.intervals.append((since, now))
                self.lengths.append(now - since)
            self.bound += now - self.bound_at
            self.since = None
        self.due = inf if self.demoted_until is None else self.demoted_until

    def charged(self, now: float) -> bool:
        """Some time was charged within the window (the older charges are forgotten)."""
        charges = self.charges
        if charges:
            start = now - self.window
            while charges and charges[0][0] <= start:
                charges.popleft()
        return bool(charges)

    def none_within(self, now: float, window: float) -> bool:
        """No interval within the window: :meth:`total` would be 0 with ``since`` None
        (each interval left ends inside the window and lasted > 0 s), without the sum."""
        self.prune(now, window)
        return not self.intervals and not self.charges

    def dropped(self, at: float) -> bool:
        """A settle at ``at`` drops the record (or one did, at or before ``at``): its app
        keeps nobody waiting, has its precedence and kept nobody waiting within the
        window (:meth:`none_within`, without pruning: the last interval ends last)."""
        intervals = self.intervals
        charges = self.charges
        return (self.since is None and self.demoted_until is None
                and (not intervals or intervals[-1][1] <= at - self.window)
                and (not charges or charges[-1][0] <= at - self.window))

    def total(self, now: float, window: float) -> float:
        """Seconds spent keeping others waiting within ``[now - window, now]``."""
        self.prune(now, window)
        start = now - window
        intervals = self.intervals
        total: float = 0.0
        if intervals:
            # Only the oldest interval can begin before the window (they follow one
            # another), so the others count whole: their lengths are summed in C, in
            # the order and with the roundings of summing each interval's share.
            begin, end = intervals[0]
            total = sum(islice(self.lengths, 1, None), end - (start if start > begin else begin))
        since = self.since
        if since is not None:
            total += now - (start if start > since else since)
        if self.charges:
            total += sum(seconds for _at, seconds in self.charges)
        return total

    def plan(self) -> None:
        """Work out :attr:`due`: when a demoted app's precedence comes back; never for
        an app that keeps nobody waiting (it has nothing to spend); for one that does,
        when ``bound`` and the time since ``bound_at`` could come within
        :data:`_SLACK` of the share (when its sum could find it spent), less a margin
        (:data:`_MARGIN`, relative) far wider than any rounding of the sum, or never if
        a whole window is that much short of the share (no more is spent within one)."""
        until = self.demoted_until
        if until is not None:
            self.due = until
            return
        at = self.bound_at
        if self.since is None or abs(at) < self.horizon:
            self.due = inf
            return
        limit = self.limit
        margin = _MARGIN * (1.0 + abs(at) + abs(self.window) + abs(limit))
        if margin < inf:
            self.due = at + (limit - _SLACK - margin - self.bound)
        else:  # (budgets or times not finite: settled every time, as the rule says)
            self.due = -inf


class Fairness:
    """Measures each application's wait share and takes its precedence when it is spent.

    The rule settles every record at every observation that sees something new and
    at every deadline: a precedence comes back, a share is spent, when a share could
    run out next, records of apps idle for a whole window dropped (the order of the
    records is the order of the budget decisions made at one instant). Most of that
    finds nothing to do, so it is done only where it could find something, with
    the same outcome:

    - a record is settled only when it falls due (:meth:`_Share.plan` says why
      nothing can be decided before), which an app that starts keeping others waiting
      near its share may do at once; an app that stops is only closed;
    - when a share kept running could run out is worked out when asked
      (:meth:`next_deadline`), as of the last settle, as that settle would have: the
      same sum at the same instant;
    - a record the rule dropped at some settle (its app idle a whole window) is
      dropped when its app keeps others waiting again, or before every record is
      settled (a registration changed): it decides nothing meanwhile, and the order
      of the others is the same (:meth:`_Share.dropped`).
    """

    def __init__(self, apps: Mapping[str, App], wm: WorkingMemory, holds: Holds,
                 log: DecisionLog, clock: Clock) -> None:
        self._apps = apps
        self._wm = wm
        self._holds = holds
        self._log = log
        self._clock = clock
        self._shares: dict[str, _Share] = {}
        self._keepers: set[str] = set()
        """The apps that kept others waiting at the last observation."""
        self._changed = False
        """Apps were registered or unloaded since the last observation."""
        self._names: tuple[str, ...] = ()
        """The apps registered at the last observation that saw them change."""
        self._registered: tuple[App, ...] = ()
        """Their registrations (an app unloaded and registered again keeps its name)."""
        self._resync = False
        """A registration changed under the same name since the last settle: the next
        one settles every record, with the registrations of then."""
        self._at = -inf
        """The instant of the last settle."""
        self._due = inf
        """No record is due before this instant."""
        self._deadline: float | None = None
        self._deadline_stale = False
        """Something was settled since :attr:`_deadline` was worked out."""

    def registrations(self) -> None:
        """Apps were registered or unloaded (the mediator tells)."""
        self._changed = True

    # ---------------------------------------------------------------- observing
    def observe(self) -> bool:
        """After every operation: who keeps the others waiting now; a spent share
        takes the app's precedence at once. True if some precedence changed."""
        now = self._log.now  # (the operation's instant)
        # Who keeps another app's AB waiting (the rule in the module docstring), written
        # out: it runs after every operation. On each device another app's AB waits
        # for, the holder is the AB running there or, on a free device, the best ranked.
        wm = self._wm
        busy = wm.busy
        keeping = set(self._holds.keeping)
        for device, counts in wm.ranked.items():
            if not counts:
                continue
            holder = busy.get(device) or wm.index.top(device)
            if holder is None:
                continue
            name = holder.app.name
            if name in keeping:
                continue
            prio = holder.priority
            for app, p in counts:
                if app != name and p >= prio:
                    keeping.add(name)
                    break
        if self._changed:
            self._changed = False
            registered = tuple(self._apps.values())
            if registered != self._registered:
                self._registered = registered
                names = tuple(self._apps)
                if names != self._names:
                    self._names = names
                    return self._settle_all(now, keeping)
                self._resync = True
        # The same keepers and apps as at the last observation, at the instant of the
        # last settle: settling again would change nothing (it is idempotent).
        if keeping == self._keepers:
            if now == self._at:
                return False
            if self._resync:
                return self._settle_all(now, keeping)
            self._at = now
            self._deadline_stale = True
            return self._settle_due(now) if now >= self._due else False
        if self._resync:
            return self._settle_all(now, keeping)
        return self._flip(now, keeping)

    def _flip(self, now: float, keeping: set[str]) -> bool:
        """Settle an observation at which some apps started or stopped keeping others
        waiting (and registrations did not change)."""
        shares = self._shares
        last = self._at
        self._at = now
        self._deadline_stale = True
        before = self._keepers
        self._keepers = keeping
        # (each record's changes are its own: the sets are walked in any order, and
        # without building their differences)
        for name in before:
            if name not in keeping:
                share = shares.get(name)
                if share is not None:
                    share.close(now)
        due = self._due
        new: list[str] = []
        for name in keeping:
            if name in before:
                continue
            share = shares.get(name)
            if share is None or share.dropped(last):  # (no record, as the rule has it)
                if name in self._apps:
                    new.append(name)
                continue
            share.open(now)
            if share.due < due:
                due = share.due
        if new:
            # New records in registration order (never a set's order, which changes with
            # PYTHONHASHSEED): the order of the records is the order of the budget
            # decisions made at one instant.
            apps = self._apps
            for name in new if len(new) == 1 else [name for name in apps if name in new]:
                old = shares.pop(name, None)
                if old is None:
                    share = _Share(apps[name])
                else:  # (the dropped one made anew: its intervals ended before the window)
                    share = old
                    share.bound = 0.0
                shares[name] = share
                share.open(now)
                if share.due < due:
                    due = share.due
        self._due = due
        return self._settle_due(now) if now >= due else False

    def _settle_all(self, now: float, keeping: set[str] | None) -> bool:
        """Settle every record at ``now``, with the apps registered now, as the rule
        says; first, at an observation (``keeping``), start and close intervals."""
        apps = self._apps
        shares = self._shares
        for name in [name for name, share in shares.items() if share.dropped(self._at)]:
            del shares[name]  # (the rule dropped it at the last settle, or before)
        self._at = now
        self._resync = False
        self._deadline_stale = True
        if keeping is not None:
            self._keepers = keeping
            # New records in registration order (see ``_flip``). (An app gone keeps
            # nobody waiting any more.)
            if keeping:
                for name, app in apps.items():
                    if name in keeping and name not in shares:
                        shares[name] = _Share(app)
            for name, share in shares.items():
                if name in keeping:
                    if share.since is None:
                        share.open(now)
                elif share.since is not None:
                    share.close(now)
        for name in [name for name in shares if name not in apps]:
            del shares[name]  # (an app gone keeps nobody waiting any more)
        for name, share in shares.items():
            registered = apps[name]
            if share.app is not registered:
                share.use(registered)
            share.due = -inf  # (every record is due: settled in its order)
        return self._settle_due(now)

    def _settle_due(self, now: float) -> bool:
        """Settle the records due by ``now``, in their order."""
        shares = self._shares
        changed = False
        gone: list[str] = []
        due = inf
        for name, share in shares.items():
            if share.due <= now:
                changed |= self._settle(name, share, now, gone)
            if share.due < due:
                due = share.due
        for name in gone:
            del shares[name]
        self._due = due
        return changed

    def _settle(self, name: str, share: _Share, now: float, gone: list[str]) -> bool:
        """Settle one record at ``now`` (the rule); one to drop goes to ``gone``."""
        app = share.app
        limit, window = share.limit, share.window
        changed = False
        if share.demoted_until is not None and share.demoted_until <= now:
            share.demoted_until = None
            changed = self._set(app, False, "regains its precedence")
        if share.since is None and not share.charged(now):  # keeps nobody waiting: nothing to spend
            if share.demoted_until is None and share.none_within(now, window):
                gone.append(name)
            share.plan()
            return changed
        used = share.bound = share.total(now, window)
        share.bound_at = now
        used = _spent(used, limit)
        if used >= limit and share.demoted_until is None:
            share.demoted_until = self._clock.after(window)
            changed |= self._set(
                app, True, f"kept other applications waiting {used:g} s within "
                           f"{window:g} s: it loses its precedence until "
                           f"t={share.demoted_until:g} s")
        share.plan()
        return changed

    def _set(self, app: App, demoted: bool, detail: str) -> bool:
        if app.demoted is demoted:
            return False
        app.demoted = demoted
        self._wm.rerank_app(app)
        if demoted:
            self._holds.unpark_all()  # its holds hold nothing now
        else:
            self._holds.regained(app)
        self._log.emit(DecisionKind.BUDGET, Rule.WAIT_SHARE, app=app.name, detail=detail)
        return True

    def charge(self, app: App, seconds: float) -> None:
        """Charge ``seconds`` to ``app``'s share now (the time an AB its reaction had cut
        had run in vain: docs/rules.md 7.3 (2)); a share so spent takes its precedence at
        once."""
        now = self._log.now
        share = self._shares.get(app.name)
        if share is None:
            share = self._shares[app.name] = _Share(app)
        elif share.app is not app:
            share.use(app)
        share.charges.append((now, seconds))
        share.bound += seconds
        gone: list[str] = []
        self._settle(app.name, share, now, gone)
        for name in gone:
            del self._shares[name]
        if share.due < self._due:
            self._due = share.due
        self._deadline_stale = True

    # ---------------------------------------------------------------- deadlines
    def next_deadline(self) -> float | None:
        """When a share could run out, or a lost precedence comes back."""
        if self._deadline_stale:
            self._deadline_stale = False
            self._deadline = self._next_deadline()
        return self._deadline

    def _next_deadline(self) -> float | None:
        # A share being spent could run out ``limit - used`` after the last settle, on
        # the clock's grid: worked out as that settle would have.
        at = self._at
        clock = self._clock
        best: float | None = None
        for share in self._shares.values():
            t = share.demoted_until
            if t is not None and (best is None or t < best):
                best = t
            if share.since is not None:
                limit = share.limit
                used = _spent(share.total(at, share.window), limit)
                if used < limit:
                    t = clock.after(limit - used, at)
                    if best is None or t < best:
                        best = t
        return best

    def expire(self) -> bool:
        """Handle what fell due; True if some precedence changed."""
        now = self._log.now  # (the operation's instant)
        if self._resync or (self._changed and tuple(self._apps.values()) != self._registered):
            # (every record settles with the apps registered now, those of apps gone are
            # dropped; the next observation takes the registrations in)
            return self._settle_all(now, None)
        if now != self._at:
            self._at = now
            self._deadline_stale = True
        return self._settle_due(now) if now >= self._due else False
