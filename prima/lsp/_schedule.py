"""When the open documents are checked: debounced, coalesced, after the input.

A change makes the documents it may change due :data:`DEBOUNCE` seconds later
(the document edited, and those whose check read it: :meth:`Workspace.affected
<prima.lsp._workspace.Workspace.affected>`); another change before then moves
that time on. A due document is checked only when nothing the client sent is
waiting to be read, so every request and change already sent is handled first:
a burst of changes ends in one check, of the latest version (a version
superseded before its check starts is never checked), and a request is never
queued behind the checks of a burst. Documents are checked one at a time, the
earliest due first, each check followed by a turn of the input; a check that a
change read meanwhile has made stale is not published (the document is due
again).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable, Iterable

__all__ = ["DEBOUNCE", "Diagnostics"]

DEBOUNCE = 0.040
"""Seconds a changed document waits, unchanged, before it is checked (keystrokes
30 ms apart are one check; one that comes late may start a check, whose
diagnostics are then dropped if the next keystroke is read while it runs)."""


class Diagnostics:
    """The documents due for a check, and the loop that checks them: ``check(uri)`` checks
    one and gives what publishes its diagnostics, which is done unless a change read
    while it was checked made it due again (its diagnostics would be stale)."""

    def __init__(self, check: Callable[[str], Callable[[], None] | None], *,
                 debounce: float = DEBOUNCE,
                 failed: Callable[[str, Exception], None] | None = None) -> None:
        self._check = check
        self._failed = failed
        self.debounce = debounce
        self._due: dict[str, float] = {}
        self._wake: asyncio.Event | None = None

    def due(self, uris: Iterable[str], delay: float | None = None) -> None:
        """Check these documents ``delay`` seconds from now (default: the debounce),
        however long they were due before."""
        now = _now()
        wait = self.debounce if delay is None else delay
        for uri in uris:
            self._due[uri] = now + wait
        if self._wake is not None:
            self._wake.set()

    def drop(self, uri: str) -> None:
        """No check of ``uri`` (it was closed)."""
        self._due.pop(uri, None)

    def waiting(self) -> list[str]:
        """The documents due, earliest first."""
        return [uri for uri, _at in sorted(self._due.items(), key=lambda d: (d[1], d[0]))]

    async def run(self, pending: Callable[[], bool]) -> None:
        """Check due documents for ever; ``pending()`` says whether input waits."""
        self._wake = asyncio.Event()
        while True:
            if not self._due:
                self._wake.clear()
                await self._wake.wait()
                continue
            uri, at = min(self._due.items(), key=lambda d: (d[1], d[0]))
            wait = at - _now()
            if wait > 0:
                self._wake.clear()
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(self._wake.wait(), wait)
                continue
            if pending():
                await asyncio.sleep(0)  # the loop reads and handles it first
                continue
            del self._due[uri]
            try:
                publish = self._check(uri)
                while pending():  # what came meanwhile first: it may make this one stale
                    await asyncio.sleep(0)
                if publish is not None and uri not in self._due:
                    publish()
            except BrokenPipeError:
                return
            except Exception as exc:  # noqa: BLE001 - said, and the other documents go on
                if self._failed is not None:
                    self._failed(uri, exc)
            await asyncio.sleep(0)


def _now() -> float:
    return asyncio.get_running_loop().time()
