"""Explicit stream blocks (rule 6c), begin/end blocks, and their deadlines.

A stream hold is *armed* when the app has nothing waiting or running inside an
open stream: other apps' non-reactive ABs that need the stream's devices wait.
It lapses as soon as the app is busy again (its own ABs then compete as usual,
the stream's continuation ranking as "parent just finished"), and is
released by ``close_stream``, by the hold timeout, or by unloading the app.

A block reserves its devices for its app alone, reactive requests included,
from its first AB's start until ``close_block``, the watchdog, or unloading.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from prima.errors import MediationError
from prima.mediator.decisions import DecisionKind, Rule
from prima.mediator.requests import IN_MEMORY
from prima.mediator.state import NodeState, _App, _Block, _Stream

if TYPE_CHECKING:
    from prima.mediator.core import Mediator

__all__ = ["HoldsMixin"]


class HoldsMixin:
    """Streams, blocks and deadlines for :class:`~prima.mediator.core.Mediator`."""

    # ======================================================== streams, blocks
    def _app(self: Mediator, name: str) -> _App:
        app = self._apps.get(name)
        if app is None:
            raise MediationError(f"unknown application {name!r}")
        return app

    def open_stream(self: Mediator, app: str, hold: float) -> None:
        """Begin an explicit stream block (rule 6c): one CS, held while the app waits."""
        a = self._app(app)
        if a.stream is not None:
            raise MediationError(f"{app}: a stream is already open")
        if hold < 0:
            raise MediationError(f"{app}: stream hold must be >= 0, got {hold}")
        with self._op():
            latest = a.latest.node if a.latest is not None else None
            tree = latest.tree if latest is not None and latest.state in IN_MEMORY else None
            st = _Stream(min(hold, self._config.max_stream_hold), tree)
            for t in a.trees.values():
                for n in t.nodes.values():
                    if n.state is NodeState.RUNNING:
                        st.devices.update(n.devices)
            a.stream = st

    def close_stream(self: Mediator, app: str) -> None:
        """End the explicit stream block; its hold (if any) is released."""
        a = self._app(app)
        if a.stream is None:
            raise MediationError(f"{app}: no stream is open")
        with self._op():
            self._end_stream(a, Rule.STREAM_CLOSE)

    def _end_stream(self: Mediator, app: _App, rule: Rule) -> None:
        st = app.stream
        app.stream = None
        if st is not None and st.armed:
            self._wm.dirty.update(st.devices)
            self._unpark_all()
            self._emit(DecisionKind.RELEASE, rule, app=app.name,
                       detail="stream hold on " + ", ".join(sorted(st.devices)))

    def open_block(self: Mediator, app: str, *, devices: frozenset[str] | None = None,
                   watchdog: float) -> None:
        """Begin a begin/end block: one IU, its devices reserved once it starts."""
        a = self._app(app)
        if a.block is not None:
            raise MediationError(f"{app}: a block is already open")
        if watchdog <= 0:
            raise MediationError(f"{app}: block watchdog must be > 0, got {watchdog}")
        devs = self._catalog.devices if devices is None else frozenset(devices)
        unknown = devs - self._catalog.devices
        if unknown:
            raise MediationError(f"{app}: block names unknown devices {sorted(unknown)}")
        with self._op():
            latest = a.latest.node if a.latest is not None else None
            tree = latest.tree if latest is not None and latest.state in IN_MEMORY else None
            a.block = _Block(devs, min(watchdog, self._config.max_block_watchdog),
                             self._next_command, tree)

    def close_block(self: Mediator, app: str) -> None:
        """Conclude the block (also fine after its watchdog fired)."""
        a = self._app(app)
        if a.block is None:
            raise MediationError(f"{app}: no block is open")
        with self._op():
            self._end_block(a, Rule.BLOCK_CLOSE)

    def _end_block(self: Mediator, app: _App, rule: Rule) -> None:
        blk = app.block
        app.block = None
        if blk is not None and blk.reserving:
            self._wm.dirty.update(blk.devices)
            self._unpark_all()
            self._emit(DecisionKind.RELEASE, rule, app=app.name,
                       detail="block on " + ", ".join(sorted(blk.devices)))

    # ============================================================== deadlines
    def next_deadline(self: Mediator) -> float | None:
        """The earliest pending hold timeout or watchdog, if any."""
        best: float | None = None
        for app in self._apps.values():
            st, blk = app.stream, app.block
            if st is not None and st.armed and (best is None or st.deadline < best):
                best = st.deadline
            if blk is not None and blk.reserving and (best is None or blk.deadline < best):
                best = blk.deadline
        return best

    def advance(self: Mediator) -> None:
        """Handle every deadline that has passed, then run selection."""
        with self._op():
            now = self._clock.now()
            for app in list(self._apps.values()):
                st, blk = app.stream, app.block
                if st is not None and st.armed and st.deadline <= now:
                    st.armed = False
                    st.lapsed = True
                    self._wm.dirty.update(st.devices)
                    self._unpark_all()
                    self._emit(DecisionKind.RELEASE, Rule.HOLD_TIMEOUT, app=app.name,
                               detail="stream hold on " + ", ".join(sorted(st.devices)))
                if blk is not None and blk.reserving and blk.deadline <= now:
                    blk.expired = True
                    self._wm.dirty.update(blk.devices)
                    self._unpark_all()
                    self._emit(DecisionKind.RELEASE, Rule.WATCHDOG, app=app.name,
                               detail="block on " + ", ".join(sorted(blk.devices)))
