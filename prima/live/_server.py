"""The live page's server (aiohttp): one page, one WebSocket, one session at a time.

``GET /`` is the page, ``GET /plotly.js`` Plotly's script (from the installed Plotly:
the page fetches nothing from elsewhere), ``GET /ws`` the session's WebSocket, and
with Foxglove, ``GET /foxglove-layout.json`` the layout for it. The first page to
connect has the session; another gets a clear "in use" and is closed; when the page
goes, the run pauses and the next page takes it over. The server answers only
requests for the host and port it listens on (no other site's page can reach it
through the browser: a WebSocket from another origin is refused), never writes a path
the page gives (it gives none: a save goes where the command line said), and bounds
what a page may send (64 KiB a message, 20 inputs a second).

On the WebSocket, the server sends JSON objects: ``hello`` (the map as Plotly draws
it, the trace so far, the findings so far, what the page may offer), then ``rows`` (new
trace lines), ``pose``, ``status``, ``timeline`` (with ``covers``), ``findings``,
``saved`` or ``download``, ``refused``; the page sends ``act`` (an input), ``control``
(play, pause, step, speed), ``save``, and ``timeline`` when it can draw one: ``true``
(the window that follows the run: its last 90 s) or the window it shows, ``[from, to]``
in simulated seconds. It is sent a timeline once there is one it has not had: made from
a newer digest of the trace than its last (remade at most once a second), or of a
window its last did not cover. A timeline holds only what is seen in the window and in
a window's width either side of it, which ``covers`` says (so a small pan shows its bars
at once): what it costs to make, send and draw is bounded by the window, not by the
session's length, and the page draws one only so often.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import math
import re
import threading
import time
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from aiohttp import WSMsgType, web

from prima.dsl import Document
from prima.errors import OutputError
from prima.escape import json_line
from prima.live._judging import LiveJudge
from prima.live._page import page, plotly_script
from prima.live._session import LiveError, Session
from prima.output import Inputs, input_named, shown, written

if TYPE_CHECKING:
    from prima.show import Model

__all__ = ["MAX_MESSAGE", "Hints", "SaveTo", "Server", "check_save"]

MAX_MESSAGE = 64 * 1024
"""The largest message a page may send (bytes)."""
MAX_INPUTS_PER_SECOND = 20
"""How many inputs a page may send in a wall second (more are refused)."""
FOLLOWED = 90.0
"""The seconds of the run a page shows while it follows the run (``timeline: true``)."""
MAX_TIME = 1e9
"""How far from 0 (simulated seconds) a window a page asks a timeline of may reach."""
ROWS_PER_MESSAGE = 2000
"""Trace lines sent in one message at most (the trace so far goes in several)."""
_SEND_EVERY = 1 / 30
"""The least wall time (s) between two updates to the page."""


@dataclass(frozen=True)
class SaveTo:
    """Where the command line lets a save go: one file, rewritten at each save, or a
    folder, a new file in it at each save; neither: the page downloads the scenario."""

    file: Path | None = None
    folder: Path | None = None
    stem: str = "live"

    def target(self) -> Path | None:
        """Where the next save goes (a folder's first free ``STEM-live-N.xml``)."""
        if self.file is not None:
            return self.file
        if self.folder is None:
            return None
        n = 1
        while (self.folder / f"{self.stem}-live-{n}.xml").exists():
            n += 1
        return self.folder / f"{self.stem}-live-{n}.xml"


@dataclass(frozen=True)
class Hints:
    """What the page may offer the author: the answers each question takes, and the
    senders of the messages the applications listen for."""

    questions: Sequence[tuple[str, Sequence[str]]] = ()
    senders: Sequence[str] = ()
    foxglove: str = ""
    """Where Foxglove connects (``ws://HOST:PORT``), if it is served."""

    @classmethod
    def of(cls, documents: Sequence[Document], foxglove: str = "") -> Hints:
        """What the page may offer for these applications (:func:`prima.check.questions`,
        the senders :func:`prima.check.listens` for)."""
        from prima.check import listens, questions

        return cls(questions=[q for doc in documents for q in questions(doc)],
                   senders=list(dict.fromkeys(s for doc in documents
                                              for s in listens(doc, "message", "sender") if s)),
                   foxglove=foxglove)


def _json(value: object) -> str:
    return json_line(value)


Window = tuple[float, float]
"""A stretch of the run's time (from, to: simulated seconds) that a page shows."""


def _window(value: object) -> Window | None:
    """The window a page asks a timeline of: ``true``, the one that follows the run
    (None); else two numbers of simulated seconds within :data:`MAX_TIME` of 0, the
    first below the second."""
    if value is True:
        return None
    # (NaN is within no bound, and an int of any size is compared as it is)
    if not (isinstance(value, list) and len(value) == 2 and all(
            not isinstance(t, bool) and isinstance(t, (int, float)) and abs(t) <= MAX_TIME
            for t in value) and value[0] < value[1]):
        raise LiveError(f"timeline: give true, or the window shown as [from, to]: seconds "
                        f"within {MAX_TIME:,.0f} of 0, from before to")
    return float(value[0]), float(value[1])


def _inside(window: Window, covers: Window | None) -> bool:
    return covers is not None and covers[0] <= window[0] and window[1] <= covers[1]


def _timeline_message(digested: Model, window: Window) -> tuple[str, Window]:
    """The timeline message of ``window`` and a window's width either side of it (what
    it ``covers``): a page panned a little shows the bars there at once."""
    from prima.show import timeline_figure

    width = window[1] - window[0]
    covers = (window[0] - width, window[1] + width)
    return _json({"timeline": timeline_figure(digested, covers), "covers": covers}), covers


@dataclass
class _Owner:
    """The page that has the session, and what it has been sent."""

    ws: web.WebSocketResponse
    rows: int = 0
    findings: int = 0
    waiting: int = 0
    pose: tuple[float, Any, Any] | None = None
    timeline: int = -1
    """The digest its latest timeline was made from (:attr:`Server.digests`)."""
    wants_timeline: bool = False
    """The page asked for a timeline and has not been sent one since."""
    window: Window | None = None
    """The window it asked a timeline of (None: the one that follows the run)."""
    covers: Window | None = None
    """The stretch of the run its latest timeline covers."""
    status: str = ""
    inputs: list[float] = field(default_factory=list)


class Server:
    """Serves one :class:`Session` to one page at a time."""

    def __init__(self, session: Session, *, title: str, host: str = "127.0.0.1", port: int = 0,
                 save: SaveTo = SaveTo(), hints: Hints | None = None, autoplay: bool = True,
                 layout: str | None = None, judge: LiveJudge | None = None,
                 on_findings: Callable[[list[dict[str, Any]]], None] | None = None) -> None:
        self.session = session
        self.title = title
        self.host, self.port = host, port
        self.save_to = save
        self.hints = hints if hints is not None else Hints.of(session.run.documents())
        self.autoplay = autoplay
        self.layout = layout
        self.judge = judge or LiveJudge()
        self.on_findings = on_findings
        self.findings: list[dict[str, Any]] = []
        self.waiting = 0
        """Findings that wait for the run's end (not final yet)."""
        self.digest: Model | None = None
        """The trace so far, digested for the timelines (:func:`prima.show.digest`)."""
        self.digests = 0
        """How many digests were made (a page is sent a timeline of the latest)."""
        self.owner: _Owner | None = None
        self.saves = 0
        self.url = ""
        self._loop: asyncio.AbstractEventLoop | None = None
        self._changed: asyncio.Event | None = None
        self._pending = threading.Event()
        self._stopped: asyncio.Event | None = None
        self._allowed: set[str] = set()
        self._any_host = False

    # ------------------------------------------------------------ lifecycle

    def app(self) -> web.Application:
        app = web.Application(middlewares=[self._only_here], client_max_size=MAX_MESSAGE)
        app.router.add_get("/", self._page)
        app.router.add_get("/plotly.js", self._plotly)
        app.router.add_get("/ws", self._socket)
        if self.layout is not None:
            app.router.add_get("/foxglove-layout.json", self._layout)
        return app

    async def start(self) -> web.AppRunner:
        """Listen (``port`` 0: a free one), start the run and the judge; :attr:`url` says
        where the page is."""
        self._loop = asyncio.get_running_loop()
        self._changed = asyncio.Event()
        self._stopped = asyncio.Event()
        self.session.on_change = self._from_run
        runner = web.AppRunner(self.app(), handle_signals=False, access_log=None)
        await runner.setup()
        site = web.TCPSite(runner, self.host, self.port)
        await site.start()
        port = next(a[1] for a in runner.addresses if isinstance(a, tuple))
        self.port = port
        shown = f"[{self.host}]" if ":" in self.host else self.host
        self.url = f"http://{shown}:{port}/"
        self._allowed = {f"{shown}:{port}"}
        if self.host in ("127.0.0.1", "localhost", "::1"):
            self._allowed |= {f"localhost:{port}", f"127.0.0.1:{port}", f"[::1]:{port}"}
        self._any_host = self.host in ("0.0.0.0", "::", "")  # (every address: any name)
        self.session.start()
        return runner

    async def serve(self, ready: Callable[[str], None] | None = None) -> None:
        """Serve until :meth:`close` (or the task is cancelled: Ctrl-C)."""
        runner = await self.start()
        judging = asyncio.create_task(self._judging())
        try:
            if ready is not None:
                ready(self.url)
            assert self._stopped is not None
            await self._stopped.wait()
        finally:
            judging.cancel()
            if self.owner is not None:
                with contextlib.suppress(Exception):
                    await self.owner.ws.close()
            await runner.cleanup()
            await asyncio.to_thread(self.session.stop)

    def close(self) -> None:
        """Stop serving (thread-safe)."""
        if self._loop is not None and self._stopped is not None:
            self._loop.call_soon_threadsafe(self._stopped.set)

    def _from_run(self) -> None:
        """Called by the run's thread: wake the loop once for all that is new."""
        if self._loop is None or self._pending.is_set():
            return
        self._pending.set()
        with contextlib.suppress(RuntimeError):  # (the loop closed: nobody to tell)
            self._loop.call_soon_threadsafe(self._wake)

    def _wake(self) -> None:
        self._pending.clear()
        if self._changed is not None:
            self._changed.set()

    # ------------------------------------------------------------ requests

    @web.middleware
    async def _only_here(self, request: web.Request,
                         handler: Callable[[web.Request], Awaitable[web.StreamResponse]]
                         ) -> web.StreamResponse:
        """Requests for this host and port only: a page of another site that names this
        server by another name (DNS rebinding) is refused. (Served on every address,
        ``--host 0.0.0.0``, the server answers to any name it is reached by.)"""
        if request.host not in self._allowed and not self._any_host:
            return web.Response(status=403, text="prima live answers only on its own address")
        return await handler(request)

    async def _page(self, _request: web.Request) -> web.Response:
        return web.Response(text=page(self.title), content_type="text/html",
                            headers={"Cache-Control": "no-store"})

    async def _plotly(self, _request: web.Request) -> web.Response:
        return web.Response(text=plotly_script(), content_type="text/javascript",
                            headers={"Cache-Control": "max-age=3600"})

    async def _layout(self, _request: web.Request) -> web.Response:
        return web.Response(text=self.layout or "{}", content_type="application/json",
                            headers={"Content-Disposition":
                                     'attachment; filename="prima-live.foxglove-layout.json"'})

    async def _socket(self, request: web.Request) -> web.WebSocketResponse:
        origin = request.headers.get("Origin")
        if origin is not None and origin.split("://", 1)[-1] != request.host:
            raise web.HTTPForbidden(text="a page of another site may not use this session")
        ws = web.WebSocketResponse(max_msg_size=MAX_MESSAGE, heartbeat=20.0)
        await ws.prepare(request)
        if self.owner is not None:
            await ws.send_str(_json({"busy": "this session is in use in another tab or "
                                             "window: close that one, then reload this one"}))
            await ws.close()
            return ws
        owner = self.owner = _Owner(ws)
        sender: asyncio.Task[None] | None = None
        try:
            await self._hello(owner)
            # (only now: the hello sends the trace so far, and one sender at a time says
            # which lines the page has, or a page taking the session over got each twice)
            sender = asyncio.create_task(self._send(owner))
            if self.autoplay and self.session.state == "running":
                self.session.play()
            async for message in ws:
                if message.type == WSMsgType.TEXT:
                    await self._handle(owner, message.data)
                elif message.type == WSMsgType.ERROR:
                    break
        finally:
            if sender is not None:
                sender.cancel()
            self.owner = None
            self.session.pause()  # (the author left: the run waits for them)
        return ws

    async def _hello(self, owner: _Owner) -> None:
        session = self.session
        from prima.show import map_figure

        _t, robot, user = session.pose
        world = map_figure(session.world, robot, user)
        rows = len(session.rows)
        await owner.ws.send_str(_json({"hello": {
            "title": self.title, "map": world, "until": session.until, "hz": session.hz,
            "save": "file" if self.save_to.file or self.save_to.folder else "download",
            "questions": [[q, list(a)] for q, a in self.hints.questions],
            "senders": list(self.hints.senders), "foxglove": self.hints.foxglove,
            "layout": self.layout is not None, "status": session.status(),
            "findings": self.findings, "waiting": self.waiting}}))
        await self._rows(owner, rows)
        owner.findings, owner.waiting = len(self.findings), self.waiting

    async def _rows(self, owner: _Owner, upto: int) -> None:
        rows = self.session.rows
        while owner.rows < upto:
            start = owner.rows
            chunk = rows[start:min(upto, start + ROWS_PER_MESSAGE)]
            owner.rows += len(chunk)  # (before the wait to send: counted once, whoever asks)
            await owner.ws.send_str(_json({"rows": chunk, "from": start}))

    async def _send(self, owner: _Owner) -> None:
        """Send the page what is new, at most :data:`_SEND_EVERY` apart."""
        assert self._changed is not None
        with contextlib.suppress(ConnectionError, asyncio.CancelledError):
            while not owner.ws.closed:
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(self._changed.wait(), 0.25)
                self._changed.clear()
                await self._update(owner)
                await asyncio.sleep(_SEND_EVERY)

    async def _update(self, owner: _Owner) -> None:
        session = self.session
        await self._rows(owner, len(session.rows))
        if session.pose != owner.pose:
            owner.pose = session.pose
            t, robot, user = owner.pose
            await owner.ws.send_str(_json({"pose": [t, robot, user]}))
        status = _json(session.status())
        if status != owner.status:
            owner.status = status
            await owner.ws.send_str(f'{{"status":{status}}}')
        if len(self.findings) > owner.findings or self.waiting != owner.waiting:
            new = self.findings[owner.findings:]
            owner.findings, owner.waiting = len(self.findings), self.waiting
            await owner.ws.send_str(_json({"findings": new, "waiting": self.waiting}))
        digested = self.digest
        if owner.wants_timeline and digested is not None:
            window = owner.window if owner.window is not None else self._following()
            if owner.timeline != self.digests or not _inside(window, owner.covers):
                # (counted before the wait: a request that comes meanwhile is answered next)
                owner.timeline, owner.wants_timeline = self.digests, False
                message, owner.covers = await asyncio.to_thread(_timeline_message,
                                                                digested, window)
                await owner.ws.send_str(message)

    def _following(self) -> Window:
        """The window that follows the run, as the page shows it: its last
        :data:`FOLLOWED` seconds (its first 30, at first), and 3 s ahead."""
        t = self.session.reached()
        return max(0.0, t - FOLLOWED), max(t, 30.0) + 3.0

    async def _handle(self, owner: _Owner, data: str) -> None:
        try:
            message = json.loads(data)
            if not isinstance(message, dict):
                raise LiveError("send a JSON object")
            if "act" in message:
                self._rate(owner)
                self.session.act(message)
            elif "control" in message:
                self._control(message)
            elif "save" in message:
                await owner.ws.send_str(_json(await self._save()))
            elif "timeline" in message:
                owner.window, owner.wants_timeline = _window(message["timeline"]), True
                if self._changed is not None:
                    self._changed.set()
            else:
                raise LiveError("give act, control, save or timeline")
        except (LiveError, OutputError) as exc:
            await owner.ws.send_str(_json({"refused": str(exc)}))
        except (ValueError, RecursionError):  # (nested past the decoder's depth: no JSON)
            await owner.ws.send_str(_json({"refused": "send JSON"}))

    def _rate(self, owner: _Owner) -> None:
        now = time.monotonic()
        owner.inputs = [t for t in owner.inputs if now - t < 1.0]
        if len(owner.inputs) >= MAX_INPUTS_PER_SECOND:
            raise LiveError(f"at most {MAX_INPUTS_PER_SECOND} inputs a second")
        owner.inputs.append(now)

    def _control(self, message: dict[str, Any]) -> None:
        what = message.get("control")
        session = self.session
        if what == "play":
            session.play()
        elif what == "pause":
            session.pause()
        elif what in ("step", "speed"):
            value = message.get("seconds" if what == "step" else "speed")
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise LiveError(f"{what}: give a number")
            if isinstance(value, int) and abs(value) > 2**53:  # (past any step or speed; no float)
                value = math.inf if value > 0 else -math.inf
            (session.step if what == "step" else session.set_speed)(float(value))
        else:
            raise LiveError("control: play, pause, step or speed")
        if self._changed is not None:
            self._changed.set()

    async def _save(self) -> dict[str, Any]:
        """Save the session where the command line said, or hand it to the page."""
        target = self.save_to.target()
        folder = target.parent if target is not None else None
        text = await asyncio.to_thread(self.session.saved, folder)
        if target is None:
            stem = re.sub(r"[^A-Za-z0-9._-]+", "-", self.session.base.name).strip(".-") or "live"
            return {"download": {"name": f"{stem[:80]}-live.xml", "text": text}}
        found = input_named(target, self.session.base.inputs)  # (checked at the start too)
        if found is not None:
            raise LiveError(f"{shown(target)} is {found[0]} ({shown(found[1])}), which the "
                            "session reads: not saved")
        await asyncio.to_thread(_write, target, text)
        self.saves += 1
        return {"saved": target.name, "saves": self.saves}

    # ------------------------------------------------------------ the judge, the timeline

    async def _judging(self) -> None:
        """Judge the trace so far and digest it for the timelines, at most once a second
        and at most a fifth of the time (a long run's trace takes longer to judge and to
        digest: both are timed, in a thread)."""
        from prima.show import digest

        judged = drawn = -1
        while True:
            rows = self.session.rows
            n, over = len(rows), self.session.state != "running"
            began = time.monotonic()
            if n != judged or (over and judged >= 0 and self.waiting):
                judged = n
                new, self.waiting = await asyncio.to_thread(self.judge.update, rows[:n], over)
                if new:
                    self.findings += new
                    if self.on_findings is not None:
                        self.on_findings(new)
                if over:
                    self.waiting = 0
            if n != drawn:
                drawn = n
                self.digest = await asyncio.to_thread(digest, rows[:n])
                self.digests += 1
            if self._changed is not None:
                self._changed.set()
            took = time.monotonic() - began
            await asyncio.sleep(max(1.0, 4 * took))


def _write(target: Path, text: str) -> None:
    """Write a saved scenario whole or not at all (a temporary file beside it, renamed)."""
    with written(target) as out:
        out.write(text)


def check_save(save: SaveTo, inputs: Inputs) -> str | None:
    """What is wrong with where the command line lets saves go (an input of the session's
    among them), or None."""
    from prima.output import check_folder, check_target

    if save.file is not None:
        problem = check_target(save.file, inputs)
        return f"--save {problem}" if problem else None
    if save.folder is not None:
        problem = check_folder(save.folder, inputs)
        return f"--save-dir {problem}" if problem else None
    return None
