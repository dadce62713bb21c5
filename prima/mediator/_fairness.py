"""The wait-share budget: how long an application may keep the others waiting.

An application *keeps another waiting* while, on some device, another
application has a waiting AB whose priority is not lower than that of the
application's AB that holds the device (the AB running on it, or, on a free
device, the best-ranked waiting AB, which reserves it), or while one of its
stream holds or blocks parks another application's AB. Priority aside: an AB
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

from prima.mediator._decisions import DecisionKind, Rule
from prima.mediator._holds import Holds
from prima.mediator._interface import Clock
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._state import App

__all__ = ["Fairness"]


_SLACK = 1e-9
"""Seconds of a wait share that floating-point sums may leave over: below this, it
is spent (else its next check would fall on the very instant it is made)."""

class _Share:
    """One application's record of keeping the others waiting."""

    __slots__ = ("intervals", "lengths", "since", "demoted_until", "check_at")

    def __init__(self) -> None:
        self.intervals: deque[tuple[float, float]] = deque()
        """Closed intervals, oldest first, within the last window."""
        self.lengths: deque[float] = deque()
        """Each interval's length (``end - begin``), in the same order."""
        self.since: float | None = None
        """When the current interval began, if the app keeps others waiting now."""
        self.demoted_until: float | None = None
        self.check_at: float | None = None
        """When its share could next run out (a deadline)."""

    def prune(self, now: float, window: float) -> None:
        """Forget the intervals that ended before ``[now - window, now]``."""
        start = now - window
        while self.intervals and self.intervals[0][1] <= start:
            self.intervals.popleft()
            self.lengths.popleft()

    def close(self, now: float) -> None:
        """The app stops keeping others waiting: the current interval is closed."""
        if self.since is not None and now > self.since:
            self.intervals.append((self.since, now))
            self.lengths.append(now - self.since)
        self.since = None

    def none_within(self, now: float, window: float) -> bool:
        """No interval within the window: :meth:`total` would be 0 with ``since`` None
        (each interval left ends inside the window and lasted > 0 s), without the sum."""
        self.prune(now, window)
        return not self.intervals

    def total(self, now: float, window: float) -> float:
        """Seconds spent keeping others waiting within ``[now - window, now]``."""
        self.prune(now, window)
        start = now - window
        intervals = self.intervals
        total: float = 0
        if intervals:
            # Only the oldest interval can begin before the window (they follow one
            # another), so the others count whole: their lengths are summed in C, in
            # the order and with the roundings of summing each interval's share.
            begin, end = intervals[0]
            total = sum(islice(self.lengths, 1, None), end - (start if start > begin else begin))
        since = self.since
        if since is not None:
            total += now - (start if start > since else since)
        return total


class Fairness:
    """Measures each application's wait share and takes its precedence when it is spent."""

    def __init__(self, apps: Mapping[str, App], wm: WorkingMemory, holds: Holds,
                 log: DecisionLog, clock: Clock) -> None:
        self._apps = apps
        self._wm = wm
        self._holds = holds
        self._log = log
        self._clock = clock
        self._shares: dict[str, _Share] = {}
        self._observed: tuple[float, frozenset[str], tuple[str, ...]] | None = None
        """The instant, the apps keeping others waiting and the apps registered at the
        last observation: the same again changes nothing (settling is idempotent)."""

    # ---------------------------------------------------------------- observing
    def observe(self) -> bool:
        """After every operation: who keeps the others waiting now; a spent share
        takes the app's precedence at once. True if some precedence changed."""
        now = self._clock.now()
        keeping = self._keeping()
        apps = self._apps
        seen = (now, keeping, tuple(apps))
        if seen == self._observed:
            return False
        self._observed = seen
        shares = self._shares
        # New records in registration order (never a set's order, which changes with
        # PYTHONHASHSEED): the order of the records is the order of the budget
        # decisions made at one instant. (An app gone keeps nobody waiting any more.)
        if keeping:
            for name in apps:
                if name in keeping and name not in shares:
                    shares[name] = _Share()
        for name, share in shares.items():
            if name in keeping:
                if share.since is None:
                    share.since = now
            elif share.since is not None:
                share.close(now)
        return self._settle_shares(now) if shares else False

    def _keeping(self) -> frozenset[str]:
        """The apps that keep another app's ready AB waiting now."""
        wm = self._wm
        busy = wm.busy
        top = wm.index.top
        out = set(self._holds.keeping)
        for device, counts in wm.ranked.items():
            if not counts:
                continue
            holder = busy.get(device) or top(device)
            if holder is None:
                continue
            name = holder.app.name
            if name in out:
                continue
            prio = holder.priority
            for app, p in counts:
                if app != name and p >= prio:
                    out.add(name)
                    break
        return frozenset(out)

    def _settle_shares(self, now: float) -> bool:
        changed = False
        apps = self._apps
        gone: list[str] = []  # (records of apps gone, or idle for a whole window)
        for name, share in self._shares.items():
            app = apps.get(name)
            if app is None:
                gone.append(name)
                continue
            budgets = app.budgets
            limit, window = budgets.wait_share, budgets.wait_window
            if share.demoted_until is not None and share.demoted_until <= now:
                share.demoted_until = None
                changed |= self._set(app, False, "regains its precedence")
            if share.since is None:  # keeps nobody waiting: nothing to spend, or check
                share.check_at = None
                if share.demoted_until is None and share.none_within(now, window):
                    gone.append(name)
                continue
            used = share.total(now, window)
            if used >= limit - _SLACK:  # (times summed in floating point: a share spent
                used = max(used, limit)  # up to rounding is spent, or its deadline is now)
            if used >= limit and share.demoted_until is None:
                share.demoted_until = self._clock.after(window)
                changed |= self._set(
                    app, True, f"kept other applications waiting {used:g} s within "
                               f"{window:g} s: it loses its precedence until "
                               f"t={share.demoted_until:g} s")
            share.check_at = self._clock.after(limit - used) if used < limit else None
        for name in gone:
            del self._shares[name]
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

    # ---------------------------------------------------------------- deadlines
    def next_deadline(self) -> float | None:
        """When a share could run out, or a lost precedence comes back."""
        times = [t for s in self._shares.values() for t in (s.demoted_until, s.check_at)
                 if t is not None]
        return min(times, default=None)

    def expire(self) -> bool:
        """Handle what fell due; True if some precedence changed."""
        return self._settle_shares(self._clock.now())

