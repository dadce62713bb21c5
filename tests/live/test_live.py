"""``prima live``: a run paced to a wall clock that the author acts in, kept as a scenario.

Every test drives simulated time by the session's own steps (paused, a step lets the
run go so far and no further) and waits for conditions with generous timeouts: none
depends on how fast the machine is. What is compared is simulated: the trace the page
received, and the trace ``prima run`` makes of the saved scenario.
"""

from __future__ import annotations

import asyncio
import contextlib
import io
import json
import math
import os
import random
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import AsyncIterator, Callable
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("aiohttp", reason="prima live needs the live extra (aiohttp)")
pytest.importorskip("plotly", reason="prima live draws with Plotly (the live extra)")

import aiohttp  # noqa: E402 - after the skip

from prima.cli import main  # noqa: E402
from prima.live import (  # noqa: E402
    LiveError,
    Options,
    SaveTo,
    Server,
    Session,
    base_of,
    check_save,
)

ROOT = Path(__file__).parents[2]
VISIT = ROOT / "tests" / "data" / "live" / "museum-visit.xml"
SAMPLE_03 = ROOT / "scenarios" / "thesis" / "sample-03.xml"
FA1 = ROOT / "apps" / "fa" / "fa1-emotions.pxml"
EA1 = ROOT / "apps" / "ea" / "ea1-museum.pxml"
WAIT = 120.0
"""The longest wait (wall seconds) for what a test waits for: generous, never a pace."""


def _session(tmp_path: Path, *inputs: Path, script: bool = True, **options: Any) -> Session:
    given = Options(inputs=inputs, script=script and inputs[0].suffix == ".xml",
                    maps=ROOT / "scenarios" / "maps", **options)
    folder = tmp_path / f"run{len(list(tmp_path.glob('run*')))}"
    folder.mkdir()
    return Session(base_of(given), folder, until=options.get("until", 600.0))


def _caught_up(session: Session, t: float) -> Callable[[], bool]:
    return lambda: session.caught_up() and (session.state != "running"
                                            or session.clock.now() >= t)


def _step(session: Session, seconds: float) -> None:
    """Let the run go ``seconds`` of simulated time further, and wait until it has."""
    target = session.clock.now() + seconds
    session.step(seconds)
    assert session.wait_for(_caught_up(session, target - 1e-9), WAIT)


def _replay(text: str, path: Path) -> list[dict[str, Any]]:
    """``prima run`` of a saved session, as its jsonl records."""
    path.write_text(text, encoding="utf-8")
    out = path.with_suffix(".jsonl")
    assert main(["run", str(path), "--format", "jsonl", "--out", str(out)]) == 0
    return [json.loads(line) for line in out.read_text(encoding="utf-8").splitlines()]


def _until(text: str) -> float:
    from lxml import etree

    return float(etree.fromstring(text.split("\n", 2)[2].encode("utf-8")).get("until", "0"))


def _same_trace(live: list[dict[str, Any]], text: str, path: Path) -> int:
    """The saved session replays to the live trace (every line before its end)."""
    until = _until(text)
    replayed = [r for r in _replay(text, path) if r["t"] < until]
    assert [r for r in live if r["t"] < until] == replayed
    return len(replayed)


_WORDS = ["Excuse me, where is the toilet?", "Stop it.", "Yes.", "No.", "Hey robot!",
          "Uh-huh.", "Say that again?", "Prof. Kidode's room.", "What is that <b>&amp;?",
          "Coffee, please."]


def _random_input(draw: random.Random, session: Session) -> dict[str, Any]:
    kind = draw.choice(["say", "say", "say", "touch", "walk", "follow", "stop", "message"])
    if kind == "say":
        return {"act": "say", "text": draw.choice(_WORDS)}
    if kind == "walk":
        outline = session.world.outline()
        xs, ys = [p[0] for p in outline], [p[1] for p in outline]
        return {"act": "walk", "x": draw.uniform(min(xs), max(xs)),
                "y": draw.uniform(min(ys), max(ys))}
    if kind == "message":
        return {"act": "message", "sender": draw.choice(["host", "library", "video"]),
                "text": "A message: " + draw.choice(_WORDS)}
    return {"act": kind}


# ------------------------------------------------------------------ the session itself

@pytest.mark.parametrize(("inputs", "script", "seed"), [
    ((VISIT,), True, 1), ((VISIT,), False, 2), ((SAMPLE_03,), False, 3), ((FA1, EA1), False, 4),
], ids=["visit-scripted", "visit-unscripted", "sample-03", "apps-alone"])
def test_what_the_author_does_is_saved_as_a_scenario_that_replays_the_session(
        tmp_path: Path, inputs: tuple[Path, ...], script: bool, seed: int) -> None:
    """Inputs at random simulated times, of every kind, some at the same tick and some
    while the robot speaks: ``prima run`` of the saved scenario makes the live trace,
    line for line; the scenario validates; a second save carries on from the first."""
    session = _session(tmp_path, *inputs, script=script)
    draw = random.Random(seed)
    session.start()
    try:
        texts = []
        for k in range(24):
            _step(session, draw.choice([0.02, 0.3, 1.0, 2.5, 6.0]))
            for _ in range(draw.choice([1, 1, 1, 2, 3])):  # (several at one tick, too)
                session.act(_random_input(draw, session))
            if k in (11, 23):
                _step(session, 1.0)
                texts.append(session.saved(tmp_path))
    finally:
        session.stop()
    assert len(session.added) >= 24
    first, second = texts
    assert _until(first) < _until(second)
    lines = _same_trace(session.rows, second, tmp_path / "second.xml")
    assert lines > 100
    _same_trace(session.rows, first, tmp_path / "first.xml")
    err = io.StringIO()
    assert main(["validate", str(tmp_path / "second.xml")], err=err) == 0, err.getvalue()
    assert "0 warning(s)" in err.getvalue()
    pinned = str(tmp_path / "second.xml")  # and pinned as a golden trace
    assert main(["test", "--update", pinned], out=io.StringIO()) == 0
    out = io.StringIO()
    assert main(["test", pinned], out=out) == 0 and "same" in out.getvalue()
    said = [r for r in session.rows if r["kind"] == "user" and r.get("action") == "say"]
    assert said, "the session's words are in its trace"


def test_an_input_is_played_at_the_tick_after_the_one_the_author_saw(tmp_path: Path) -> None:
    session = _session(tmp_path, VISIT)
    session.start()
    try:
        _step(session, 3.0)  # the guide says "I'm going to start the tour of the museum."
        seen = session.clock.now()
        session.act({"act": "say", "text": "Excuse me, where is the toilet?"})
        _step(session, 0.5)
    finally:
        session.stop()
    said = next(r for r in session.rows if r["kind"] == "user" and r.get("action") == "say")
    assert seen < said["t"] <= session.rows[-1]["t"]
    assert said["t"] - seen <= 0.1 + 1e-9  # (the run is at most a sensing period ahead)
    assert session.added[0].tick == round(said["t"] * session.hz)


def test_a_session_refuses_what_it_cannot_keep_and_changes_nothing(tmp_path: Path) -> None:
    session = _session(tmp_path, VISIT)
    for bad, said in [({"act": "dance"}, "no such action"), ({"act": "say", "text": ""}, "words"),
                      ({"act": "say", "text": "a\x00b"}, "control"),
                      ({"act": "say", "text": "\u202eevil rtl"}, r"direction characters \(U\+202E"),
                      ({"act": "say", "text": "one\u2028two"}, "U\\+2028"),
                      ({"act": "say", "text": "x" * 10_001}, "at most"),
                      ({"act": "walk", "x": "1", "y": 2}, "number"),
                      ({"act": "walk", "x": float("nan"), "y": 2}, "number"),
                      ({"act": "walk", "x": 1e9, "y": 2}, "metres"),
                      ({"act": "walk", "x": 10**400, "y": 2}, "metres"),
                      ({"act": "message", "sender": "", "text": "hi"}, "sender")]:
        with pytest.raises(LiveError, match=said):
            session.act(bad)
    with pytest.raises(LiveError, match="over"):  # (not started: it takes no input)
        session.act({"act": "touch"})
    assert session.added == [] and session.rows == []


# ------------------------------------------------------------------ the page's WebSocket

class _Page:
    """What a page receives on the WebSocket, as the page keeps it."""

    def __init__(self, ws: aiohttp.ClientWebSocketResponse) -> None:
        self.ws = ws
        self.rows: list[dict[str, Any]] = []
        self.status: dict[str, Any] = {}
        self.findings: list[dict[str, Any]] = []
        self.replies: list[dict[str, Any]] = []
        self.hello: dict[str, Any] = {}

    async def read(self) -> dict[str, Any]:
        message = await asyncio.wait_for(self.ws.receive(), WAIT)
        if message.type != aiohttp.WSMsgType.TEXT:
            raise ConnectionError(f"the server closed the page's WebSocket ({message.type})")
        data: dict[str, Any] = json.loads(message.data)
        if "hello" in data:
            self.hello = data["hello"]
            self.status = data["hello"]["status"]
        if "rows" in data:
            assert data["from"] == len(self.rows)
            self.rows += data["rows"]
        self.status = data.get("status", self.status)
        self.findings += data.get("findings", [])
        if {"refused", "saved", "download", "busy"} & data.keys():
            self.replies.append(data)
        return data

    async def until(self, ready: Callable[[], bool]) -> None:
        while not ready():
            await self.read()

    async def send(self, message: dict[str, Any]) -> None:
        await self.ws.send_str(json.dumps(message))

    async def step(self, seconds: float) -> None:
        target = self.status["clock"] + seconds - 1e-9
        await self.send({"control": "step", "seconds": seconds})
        await self.until(lambda: self.status["state"] != "running" or (
            self.status["idle"] and self.status["clock"] >= target))

    async def reply(self) -> dict[str, Any]:
        before = len(self.replies)
        await self.until(lambda: len(self.replies) > before)
        return self.replies[-1]


@contextlib.asynccontextmanager
async def _served(session: Session, **options: Any) -> AsyncIterator[Server]:
    server = Server(session, title="test", port=0, autoplay=False, **options)
    ready = asyncio.Event()
    task = asyncio.create_task(server.serve(lambda _url: ready.set()))
    await asyncio.wait_for(ready.wait(), WAIT)
    try:
        yield server
    finally:
        server.close()
        await asyncio.wait_for(task, WAIT)


@contextlib.asynccontextmanager
async def _page(server: Server, **headers: str) -> AsyncIterator[_Page]:
    async with aiohttp.ClientSession() as client, \
            client.ws_connect(f"{server.url}ws", headers=headers) as ws:
        page = _Page(ws)
        await page.until(lambda: bool(page.hello))
        yield page


def test_the_page_receives_the_run_and_a_downloaded_save_replays_it(tmp_path: Path) -> None:
    session = _session(tmp_path, VISIT)

    async def visit() -> str:
        async with _served(session) as server, _page(server) as page:
            assert page.hello["save"] == "download" and page.hello["map"]["data"]
            assert ["May I repeat the explanation?", ["Yes.", "No."]] in page.hello["questions"]
            await page.step(3.0)
            await page.send({"act": "say", "text": "Excuse me, where is the toilet?"})
            await page.step(5.0)
            await page.send({"act": "touch"})
            await page.step(4.0)
            await page.send({"act": "message", "sender": "host", "text": "<hello> & bye"})
            await page.step(2.0)
            await page.send({"save": True})
            saved = await page.reply()
            await page.until(lambda: len(page.rows) >= len(session.rows))
            assert page.rows == session.rows[:len(page.rows)]
            text: str = saved["download"]["text"]
            assert saved["download"]["name"] == "museum-visit-live.xml"
            return text

    text = asyncio.run(visit())
    assert 'href="/' in text  # (downloaded: its paths are absolute)
    assert _same_trace(session.rows, text, tmp_path / "saved.xml") > 50
    heard = [r for r in session.rows if r["kind"] == "hear"]
    assert heard and "ea1-museum takes it" in heard[0]["text"]


def test_one_page_has_the_session_and_the_next_takes_it_over(tmp_path: Path) -> None:
    session = _session(tmp_path, VISIT)

    async def visits() -> None:
        async with _served(session) as server:
            async with _page(server) as first:
                await first.step(2.0)
                async with aiohttp.ClientSession() as client, \
                        client.ws_connect(f"{server.url}ws") as ws:
                    busy = json.loads((await ws.receive()).data)
                    assert "in use" in busy["busy"]
                    assert (await ws.receive()).type in (aiohttp.WSMsgType.CLOSE,
                                                         aiohttp.WSMsgType.CLOSED)
                await first.send({"control": "play"})
                await first.until(lambda: not first.status["paused"])
            # the page closed: the run pauses, and waits for its author
            assert session.wait_for(lambda: session.clock.paused, WAIT)
            async with _page(server) as second:
                await second.until(lambda: len(second.rows) >= len(session.rows))
                assert second.rows == session.rows[:len(second.rows)]
                assert second.status["paused"]

    asyncio.run(visits())


class _Socket:
    """A page's WebSocket as the server sees it: what was sent on it."""

    def __init__(self) -> None:
        self.sent: list[dict[str, Any]] = []
        self.sizes: list[int] = []
        """Each message's size (bytes)."""

    async def send_str(self, text: str) -> None:
        await asyncio.sleep(0)  # (the socket's wait to send: another sender goes on)
        self.sent.append(json.loads(text))
        self.sizes.append(len(text.encode("utf-8")))


def test_a_page_is_sent_each_line_once_whoever_sends_it(tmp_path: Path) -> None:
    """The page's first lines (the hello's) and what is new (the sender's) may be sent
    at once, each waiting on the socket in turn: every line goes once, in order (a page
    taking a long session over got a chunk of 2,000 lines twice, then missed the newest)."""
    from prima.live._server import ROWS_PER_MESSAGE, _Owner

    session = _session(tmp_path, VISIT)
    session.rows += [{"t": 0.0, "seq": k, "kind": "pose"} for k in range(3 * ROWS_PER_MESSAGE)]
    server = Server(session, title="test", port=0, autoplay=False)
    socket = _Socket()
    owner = _Owner(socket)  # type: ignore[arg-type]

    async def both() -> None:
        n = len(session.rows)
        await asyncio.gather(server._rows(owner, n), server._rows(owner, n))

    asyncio.run(both())
    got = [row for message in socket.sent for row in message["rows"]]
    assert [m["from"] for m in socket.sent] == list(range(0, len(session.rows),
                                                          ROWS_PER_MESSAGE))
    assert got == session.rows and owner.rows == len(session.rows)


class _Asking:
    """A page's requests for timelines, as the server answers them: each asked (or not)
    and the page's next update made at once, on a :class:`_Socket`."""

    def __init__(self, server: Server) -> None:
        from prima.live._server import _Owner

        self.server, self.socket = server, _Socket()
        self.owner = _Owner(self.socket)  # type: ignore[arg-type]

    async def sent(self, *asked: object) -> list[dict[str, Any]]:
        """The timelines and refusals sent at the next update, once ``asked`` (a request's
        ``timeline``; none: nothing asked)."""
        before = len(self.socket.sent)
        for window in asked:
            await self.server._handle(self.owner, json.dumps({"timeline": window}))
        await self.server._update(self.owner)
        return [m for m in self.socket.sent[before:] if {"timeline", "refused"} & m.keys()]


def _digested(server: Server, rows: list[dict[str, Any]]) -> None:
    """A digest of the trace so far, as the judging loop makes one (at most once a second)."""
    from prima.show import digest

    server.digest, server.digests = digest(rows), server.digests + 1


def _points(message: dict[str, Any]) -> dict[str, list[Any]]:
    """A timeline message's bars, waits and marks: by trace (its meta and name), each
    point as it is drawn."""
    drawn: dict[str, list[Any]] = {}
    for trace in message["timeline"]["data"]:
        keys = [k for k in ("y", "base", "x", "text", "hovertext", "customdata") if k in trace]
        points = zip(*(trace[k] if isinstance(trace[k], list) else [trace[k]] * len(trace["y"])
                       for k in keys), strict=True)
        drawn[f"{trace['meta']} {trace['name']}"] = [list(point) for point in points]
    return drawn


def test_a_page_is_sent_the_latest_timeline_once_it_asks_for_one(tmp_path: Path) -> None:
    """A long session's timeline is long to draw: the page asks for one when it can draw
    it, and is sent one of the latest digest of the trace, once; none it did not ask for
    (the server made a timeline a second and sent each, which the page could not draw).
    ``true`` asks for the window that follows the run (a run not started: its first 30 s,
    with a window's width either side)."""
    from prima.show import read_rows

    rows = read_rows(VISIT)
    server = Server(_session(tmp_path, VISIT), title="test", port=0, autoplay=False)
    page = _Asking(server)

    async def visit() -> None:
        assert await page.sent() == []
        _digested(server, rows[:100])
        assert await page.sent() == []  # (not asked)
        [first] = await page.sent(True)
        assert first["covers"] == [-33.0, 66.0]
        _digested(server, rows[:200])
        _digested(server, rows[:300])
        assert await page.sent() == []
        [latest] = await page.sent(True)  # (the latest only)
        assert latest != first and page.owner.timeline == server.digests
        assert await page.sent(True) == []  # (none newer yet: sent once there is)
        _digested(server, rows)
        assert len(await page.sent()) == 1
        assert await page.sent() == []

    asyncio.run(visit())


def test_a_page_that_shows_another_window_is_sent_its_timeline_with_no_new_line(
        tmp_path: Path) -> None:
    """Panned or zoomed out of what its timeline covers, the page asks for the window it
    shows and is sent its timeline, though the trace has not grown (a new window is a
    reason to send); a window inside what it covers brings none. Its bars are those
    seen there (one begun before it too) and a window's width either side; ``true``,
    the window that follows the run, is another."""
    from prima.show import read_rows

    rows = read_rows(VISIT)
    server = Server(_session(tmp_path, VISIT), title="test", port=0, autoplay=False)
    page = _Asking(server)
    _digested(server, rows)

    async def visit() -> None:
        [following] = await page.sent([0, 33])
        assert following["covers"] == [-33.0, 66.0]
        assert await page.sent([20, 30]) == []  # (zoomed in: it has it)
        [panned] = await page.sent([100, 110])
        assert panned["covers"] == [90.0, 120.0]
        assert await page.sent([100, 110]) == []
        [back] = await page.sent(True)
        assert back["covers"] == [-33.0, 66.0]
        assert server.digest is not None
        bars = server.digest.timeline.bars
        drawn = {ab for trace in panned["timeline"]["data"] if trace["meta"] == "bars"
                 for ab in trace["customdata"]}
        assert {b.ab for b in bars if b.t0 <= 120 and b.t1 >= 90} <= drawn
        assert any(b.t0 < 90 < b.t1 for b in bars if b.ab in drawn)  # (begun before)
        assert len(drawn) < len({b.ab for b in bars}) / 2

    asyncio.run(visit())


def _apps_alone(tmp_path: Path, until: float) -> list[dict[str, Any]]:
    """The trace of FA1 beside EA1 alone, for ``until`` s (run at once, not live): the
    guide, blocked by the user before it, tries again every second or so."""
    from prima.run import Run

    base = base_of(Options(inputs=(FA1, EA1), script=False, maps=ROOT / "scenarios" / "maps"))
    scenario = tmp_path / f"apps-{until:g}.xml"
    scenario.write_text(base.text(until), encoding="utf-8")
    rows: list[dict[str, Any]] = []
    Run(scenario, rows=rows.append).run()
    return rows


def test_the_timeline_of_the_window_shown_does_not_grow_with_the_session(
        tmp_path: Path) -> None:
    """At 4,000 s, a session's whole timeline held 9,700 bars, a megabyte of JSON that
    the page took a second and more to draw, of which it showed 90 s. The page is sent
    what is seen in the window it shows (its last 90 s) and a window's width either side:
    at the end of a session of 4,000 s, as many bars and bytes as at the end of one of
    1,000 s (within a fifth), where the whole timeline grew fourfold."""
    sent = {}
    for until in (1000.0, 4000.0):
        rows = _apps_alone(tmp_path, until)
        server = Server(_session(tmp_path, FA1, EA1), title="test", port=0, autoplay=False)
        _digested(server, rows)
        page = _Asking(server)
        [message] = asyncio.run(page.sent([until - 90, until + 3]))
        assert message["covers"] == [until - 183, until + 96]
        bars = sum(len(points) for points in _points(message).values())
        assert server.digest is not None
        sent[until] = (bars, page.socket.sizes[-1], len(server.digest.timeline.bars))
    (short, short_bytes, short_all), (long, long_bytes, long_all) = sent.values()
    assert long_all > 3.5 * short_all  # (the session's bars grew with it)
    assert 100 < long < 1.2 * short and long_bytes < 1.2 * short_bytes, sent


def test_a_window_is_drawn_as_the_whole_timeline_draws_it_there() -> None:
    """``prima show``'s timeline with a window: its layout as the whole run's, and its
    traces (by meta and name) too, but for the labels of runs of iterations none of which
    is seen; of each trace, what is seen in the window (a bar begun before it too) drawn
    as in the whole figure, and what reaches lowest and highest across the rows, seen or
    not (Plotly lays the rows out by it: a row with nothing seen in the window stays)."""
    from prima.show import digest, read_rows, timeline_figure

    digested = digest(read_rows(SAMPLE_03))
    longest = max(digested.timeline.bars, key=lambda b: b.t1 - b.t0)
    t0 = (longest.t0 + longest.t1) / 2
    t1 = t0 + 5.0
    whole = {"timeline": timeline_figure(digested)}
    part = {"timeline": timeline_figure(digested, (t0, t1))}
    assert part["timeline"]["layout"] == whole["timeline"]["layout"]
    everything, drawn = _points(whole), _points(part)
    assert list(drawn) == [k for k in everything if k in drawn]
    assert {k for k in everything if k not in drawn} <= {"runs ea3-navigate"}
    rows = digested.timeline.devices
    seen = 0
    for trace, points in everything.items():
        inside = [p for p in points if (t0 <= p[1] <= t1 if trace.startswith("marks")
                                        else p[1] <= t1 and p[1] + p[2] >= t0)]
        shown = drawn.get(trace, [])
        assert [p for p in shown if p in inside] == inside
        assert all(p in points for p in shown)
        if not trace.startswith("runs"):
            reached = {rows.index(p[0]) for p in points}
            assert {min(reached), max(reached)} <= {rows.index(p[0]) for p in shown}
        seen += len(inside)
    assert longest.ab in {p[5] for p in drawn[f"bars {longest.app}"]}
    assert 0 < seen < sum(map(len, drawn.values())) < 0.5 * sum(map(len, everything.values()))


def test_a_window_a_page_cannot_show_is_refused(tmp_path: Path) -> None:
    """A window is two numbers of seconds, the first below the second, within a billion
    seconds of 0: anything else is refused as an input is (said, nothing changed), and
    the page's next request is answered."""
    from prima.show import read_rows

    server = Server(_session(tmp_path, VISIT), title="test", port=0, autoplay=False)
    _digested(server, read_rows(VISIT))
    page = _Asking(server)

    async def visit() -> None:
        for bad in [[1], [1, 2, 3], [9, 1], [5, 5], ["0", "9"], [True, 9], [0, math.nan],
                    [-math.inf, 0], [-1e300, 1e300], [0, 10**400], False, None, "0-9",
                    {"from": 0, "to": 9}]:
            [refused] = await page.sent(bad)
            assert "window shown" in refused.get("refused", ""), bad
            assert page.owner.window is None and not page.owner.wants_timeline
        [answered] = await page.sent([-1e9, 1e9])
        assert answered["covers"] == [-3e9, 3e9]

    asyncio.run(visit())


def test_the_run_has_gone_as_far_as_the_clock_while_nothing_moves(tmp_path: Path) -> None:
    """FA1 alone waits to be touched: stepped 5 s three times, the run is at 15 s, not
    at its last pose's 0 s (the page showed 0.00 s; a poses' line comes only when a pose
    changes), and a save replays to there."""
    session = _session(tmp_path, FA1)

    async def steps() -> list[float]:
        async with _served(session) as server, _page(server) as page:
            reached = []
            for _ in range(3):
                await page.step(5.0)
                reached.append(page.status["t"])
            await page.send({"save": True})
            saved = await page.reply()
            assert 'until="15.02"' in saved["download"]["text"]
            return reached

    assert asyncio.run(steps()) == [5.0, 10.0, 15.0]
    assert session.rows[-1]["t"] < 1.0  # (nothing happened since)


def test_a_closed_page_loses_no_saved_session(tmp_path: Path) -> None:
    session = _session(tmp_path, VISIT)
    target = tmp_path / "kept" / "visit.xml"

    async def visit() -> None:
        async with _served(session, save=SaveTo(file=target)) as server:
            async with _page(server) as page:
                await page.step(3.0)
                await page.send({"act": "say", "text": "Stop it."})
                await page.step(1.0)
                await page.send({"save": True})
                assert (await page.reply())["saved"] == "visit.xml"
            assert target.is_file()
            async with _page(server) as page:  # a second save rewrites it, whole
                await page.step(2.0)
                await page.send({"save": True})
                assert (await page.reply())["saves"] == 2

    asyncio.run(visit())
    text = target.read_text(encoding="utf-8")
    map_href = re.search(r'<map href="([^"]+)"', text)
    assert map_href is not None and not map_href.group(1).startswith("/")  # (relative)
    assert (target.parent / map_href.group(1)).resolve() == \
        (ROOT / "scenarios" / "maps" / "museum.xml").resolve()
    assert main(["validate", str(target)], err=io.StringIO()) == 0
    assert _until(text) >= 6.0
    assert not list(target.parent.glob(".prima-*"))  # (no temporary file left beside it)


def test_saves_go_where_the_command_line_said_and_never_over_an_input(tmp_path: Path) -> None:
    base = base_of(Options(inputs=(VISIT,), script=True))
    assert "is the scenario (" in (check_save(SaveTo(file=VISIT), base.inputs) or "")
    map_file = ROOT / "scenarios" / "maps" / ".." / "maps" / "museum.xml"
    assert "is the map (" in (check_save(SaveTo(file=map_file), base.inputs) or "")
    link = tmp_path / "visit.xml"  # (another name for the same file)
    link.hardlink_to(VISIT)
    assert "is the scenario (" in (check_save(SaveTo(file=link), base.inputs) or "")
    assert "is a file: an EA (" in (check_save(SaveTo(folder=EA1), base.inputs) or "")
    assert "is a folder" in (check_save(SaveTo(file=tmp_path), base.inputs) or "")
    assert check_save(SaveTo(folder=tmp_path / "new"), base.inputs) is None
    folder = SaveTo(folder=tmp_path, stem="visit")
    first = folder.target()
    assert first == tmp_path / "visit-live-1.xml"
    first.write_text("x")
    assert folder.target() == tmp_path / "visit-live-2.xml"  # (never over an earlier one)


def test_what_a_page_may_not_do(tmp_path: Path) -> None:
    session = _session(tmp_path, VISIT)

    async def attempts() -> None:
        async with _served(session) as server:
            async with aiohttp.ClientSession() as client:
                # another site's page, through the author's browser
                with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
                    await client.ws_connect(f"{server.url}ws",
                                            headers={"Origin": "http://evil.example"})
                assert refused.value.status == 403
                # this server, named otherwise (DNS rebinding)
                async with client.get(f"{server.url}", headers={"Host": "evil.example"}) as r:
                    assert r.status == 403
                async with client.get(server.url) as r:
                    assert r.status == 200 and "prima live" in await r.text()
            async with _page(server, Origin=server.url.rstrip("/")) as page:
                for bad in ["not json", "[1]", json.dumps({"act": "say", "text": "\x1b[2J"}),
                            json.dumps({"act": "walk", "x": 1}), json.dumps({"nothing": 1}),
                            json.dumps({"control": "speed", "speed": 0}),
                            json.dumps({"control": "step", "seconds": 1e9}),
                            "[" * 50_000,  # (deeper than the JSON decoder goes)
                            json.dumps({"control": "step", "seconds": 10**400}),
                            json.dumps({"control": "speed", "speed": -10**400}),
                            json.dumps({"act": "walk", "x": 10**400, "y": 1}),
                            json.dumps({"timeline": [0, 10**400]}),
                            json.dumps({"timeline": [9, float("nan")]}),
                            json.dumps({"save": True, "path": "/etc/passwd"})]:
                    await page.ws.send_str(bad)
                    reply = await page.reply()
                    if "download" not in reply:  # (a save is a save: the path is not read)
                        assert "refused" in reply, bad
                await page.step(0.5)
                for _ in range(25):
                    await page.send({"act": "stop"})
                assert any("a second" in r.get("refused", "") for r in page.replies) or \
                    await _refused_soon(page)
            async with _page(server) as page:  # too large a message closes the page, only
                await page.ws.send_str(json.dumps({"act": "say", "text": "x" * 70_000}))
                with pytest.raises(ConnectionError):
                    while True:
                        await page.read()
            async with _page(server) as page:
                await page.step(0.5)
                assert page.status["state"] == "running"

    asyncio.run(attempts())
    assert len(session.added) <= 20
    assert all(a.kind == "stop" for a in session.added)
    saves = [p for p in tmp_path.rglob("*") if p.name not in ("live.xml",) and p.is_file()]
    assert saves == []  # (downloads only: the server wrote nothing)


async def _refused_soon(page: _Page) -> bool:
    reply = await page.reply()
    return "a second" in reply.get("refused", "")


# ------------------------------------------------------------------ the command line

@pytest.mark.parametrize(("argv", "said"), [
    (["live", "nowhere.xml"], "no such file"),
    (["live", str(FA1), "--script"], "--script"),
    (["live", str(VISIT), "--map", str(ROOT / "scenarios" / "maps" / "museum.xml")], "--map"),
    (["live", str(VISIT), str(FA1)], "one scenario"),
    (["live", str(VISIT), "--speed", "0"], "--speed"),
    (["live", str(VISIT), "--until", "-1"], "--until"),
    (["live", str(VISIT), "--port", "70000"], "--port"),
    (["live", str(VISIT), "--save", "a.xml", "--save-dir", "d"], "not both"),
    (["live", str(VISIT), "--save", str(VISIT)], "which this command reads"),
    (["live", str(VISIT), "--policy", "nope=on"], "no policy"),
], ids=["missing", "script-with-apps", "map-with-scenario", "both", "speed", "until", "port",
        "save-twice", "save-over-input", "policy"])
def test_the_command_line_is_checked_before_anything_runs(argv: list[str], said: str) -> None:
    err = io.StringIO()
    assert main(argv, out=io.StringIO(), err=err) == 2
    assert said in err.getvalue() and "Traceback" not in err.getvalue()


def test_applications_alone_run_on_a_map_with_their_places(tmp_path: Path) -> None:
    session = _session(tmp_path, FA1, EA1)
    assert session.world.name == "museum"
    assert session.run.app_names() == ["fa1-emotions", "ea1-museum"]
    lost = tmp_path / "lost.pxml"  # the guide, sent to a place no shipped map has
    lost.write_text(EA1.read_text(encoding="utf-8").replace("panel-2", "moon-base"),
                    encoding="utf-8")
    err = io.StringIO()
    assert main(["live", str(lost), "--port", "0"], out=io.StringIO(), err=err) == 1
    assert "no map has every place the applications name (moon-base, panel-1)" in \
        err.getvalue()


def test_a_port_in_use_is_said_in_one_line() -> None:
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = str(taken.getsockname()[1])
        for argv in (["--port", port], ["--port", "0", "--foxglove", port]):
            err = io.StringIO()
            assert main(["live", str(FA1), *argv], out=io.StringIO(), err=err) == 1
            said = err.getvalue().strip().splitlines()
            assert len(said) == 1 and "in use" in said[0], said
            assert said[0].startswith("prima live: error: cannot serve")
            assert "Traceback" not in err.getvalue()


def _started(*argv: str) -> tuple[subprocess.Popen[str], str]:
    """``prima live`` in a process of its own; the URL its first line gives."""
    process = subprocess.Popen(
        [sys.executable, "-m", "prima", "live", *argv, "--port", "0"], cwd=ROOT,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),  # noqa: PLW1509
        env={**os.environ, "PYTHONUNBUFFERED": "1"})
    assert process.stdout is not None
    first = process.stdout.readline()
    assert first.startswith("prima live: http://127.0.0.1:"), first + process.stderr.read()
    return process, first.split()[2]


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["ctrl-c", "sigterm"])
def test_ctrl_c_and_sigterm_end_it_cleanly_in_one_line(signum: int) -> None:
    process, url = _started(str(VISIT), "--paused")
    try:
        assert url.endswith("/")
        process.send_signal(signum)
        _out, err = process.communicate(timeout=WAIT)
    finally:
        process.kill()
    assert process.returncode == 0, err
    lines = err.splitlines()
    assert len(lines) == 1 and re.fullmatch(
        r"prima live: stopped at 0\.\d\d s of simulated time \(stopped\); 0 input\(s\); "
        "not saved", lines[0]), err


# ------------------------------------------------------------------ the judge, live

@pytest.mark.parametrize(("name", "policies", "waits"), [
    ("thesis/sample-06.xml", {"all": False}, True), ("thesis/sample-10.xml", {"all": False},
                                                     False),
    ("policies/restore-state-off.xml", {}, False),
    ("examples/museum-cafe.xml", {"all": False}, True),
], ids=["sample-06-all-off", "sample-10-all-off", "restore-state-off", "museum-cafe-all-off"])
def test_a_finding_is_shown_once_it_is_final_and_never_taken_back(
        name: str, policies: dict[str, bool], waits: bool) -> None:
    """Judged every half second of its trace, as a live session judges it: each finding
    shown before the end is in the whole run's report, word for word; the ones that
    wait for the end (a reaction not started yet, words not heard yet) are shown then,
    and by the end every finding has been shown. (Where ``waits``, these runs have late
    reactions that had not started yet, unheard words or stuck applications on the way;
    sample-10's, with every policy off, are all final as soon as they happen, and so are
    restore-state-off's: EA1's words, kept while FA2 follows the user, are not unheard
    on the way, as the time spent following does not count.)"""
    from prima.judge import MEASURES, judge
    from prima.live import LiveJudge
    from prima.run import Run

    rows: list[dict[str, Any]] = []
    Run(ROOT / "scenarios" / name, policies=policies, rows=rows.append).run()
    whole = judge(rows)
    report = {(m.key, f.seq): m.line(f) for m in MEASURES for f in whole.of(m.key)}
    live = LiveJudge()
    shown: list[dict[str, Any]] = []
    waited = 0
    end, k, t = rows[-1]["t"], 0, 0.5
    while t < end:
        while k < len(rows) and rows[k]["t"] <= t:
            k += 1
        new, waiting = live.update(rows[:k], over=False)
        shown += new
        waited = max(waited, waiting)
        t += 0.5
    before_the_end = {(f["key"], f["seq"]): f["line"] for f in shown}
    assert before_the_end.items() <= report.items()
    new, waiting = live.update(rows, over=True)
    assert waiting == 0
    assert {(f["key"], f["seq"]): f["line"] for f in shown + new} == report
    assert (waited > 0) == waits


# ------------------------------------------------------------------ Foxglove, live

def _decoder(channel: dict[str, Any]) -> Callable[[bytes], Any]:
    """How a Foxglove client decodes a channel's messages: PRIMA's JSON, Foxglove's own
    schemas as protobuf (their file descriptors, advertised in base64)."""
    if channel["encoding"] == "json":
        return json.loads
    import base64

    from google.protobuf import descriptor_pb2, descriptor_pool, message_factory

    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for file in files.file:
        pool.Add(file)
    kind = message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))
    return kind.FromString  # type: ignore[no-any-return]


def test_foxglove_gets_the_recordings_channels_and_decodes_them_as_a_run_plays(
        tmp_path: Path) -> None:
    """A WebSocket client speaking Foxglove's protocol is advertised the recording's
    channels (the same topics and schemas as ``prima run --format mcap``), subscribes,
    and decodes every message it gets while the run plays; the server's time is the
    run's."""
    pytest.importorskip("foxglove", reason="Foxglove's server is the mcap extra")
    pytest.importorskip("google.protobuf")
    from prima.live._foxglove import FoxgloveLive

    session = _session(tmp_path, VISIT)
    fox = FoxgloveLive(session.world, host="127.0.0.1", port=0)
    session.tee = fox.line
    session.start()
    wanted = {"/map", "/bodies", "/tf", "/robot/pose", "/user/pose", "/words", "/mediator",
              "/events", "/user", "/devices/speaker", "/apps/ea1-museum/state",
              "/robot/path"}

    async def client() -> tuple[dict[str, dict[str, Any]], dict[str, list[Any]], int]:
        channels: dict[int, dict[str, Any]] = {}
        decoded: dict[str, list[Any]] = {}
        clock = 0
        async with aiohttp.ClientSession() as http, http.ws_connect(
                f"ws://127.0.0.1:{fox.port}", protocols=["foxglove.sdk.v1"]) as ws:
            done = threading.Event()

            def play() -> None:  # (until the client has had every topic it wants)
                while not done.is_set() and session.state == "running":
                    _step(session, 1.0)

            stepping = asyncio.create_task(asyncio.to_thread(play))
            try:
                while not wanted <= decoded.keys():
                    message = await asyncio.wait_for(ws.receive(), WAIT)
                    if message.type == aiohttp.WSMsgType.TEXT:
                        data = json.loads(message.data)
                        if data.get("op") == "advertise":
                            new = [c for c in data["channels"] if c["id"] not in channels]
                            channels.update({c["id"]: c for c in new})
                            await ws.send_str(json.dumps({"op": "subscribe", "subscriptions": [
                                {"id": c["id"], "channelId": c["id"]} for c in new]}))
                    elif message.type == aiohttp.WSMsgType.BINARY:
                        raw = message.data
                        if raw[0] == 1:  # message data: subscription, log time, payload
                            channel = channels[int.from_bytes(raw[1:5], "little")]
                            decoded.setdefault(channel["topic"], []).append(
                                _decoder(channel)(raw[13:]))
                        elif raw[0] == 2:  # the server's time
                            clock = max(clock, int.from_bytes(raw[1:9], "little"))
                    else:
                        raise ConnectionError(f"Foxglove's server closed ({message.type})")
            finally:
                done.set()
            await stepping
        return {c["topic"]: c for c in channels.values()}, decoded, clock

    try:
        channels, decoded, clock = asyncio.run(client())
    finally:
        session.stop()
        fox.stop()
    from prima.mcap import TOPICS

    patterns = [re.escape(t).replace("DEVICE", "[^/]+").replace("APP", "[^/]+") for t in TOPICS]
    assert all(any(re.fullmatch(p, topic) for p in patterns) for topic in channels)
    assert {t for t in TOPICS if "DEVICE" not in t and "APP" not in t} <= channels.keys()
    schemas = {topic: c["schemaName"] for topic, c in channels.items()}
    assert schemas["/map"] == "foxglove.SceneUpdate" and schemas["/tf"] == \
        "foxglove.FrameTransforms" and schemas["/mediator"] == "prima.Decision"
    assert channels["/words"]["encoding"] == "protobuf"
    assert channels["/mediator"]["encoding"] == "json"
    # (what was logged before the client's subscriptions took effect, it did not get)
    said = {r["text"] for r in session.rows if r.get("text") and r["kind"] in ("start", "user")}
    assert decoded["/words"] and {w.message for w in decoded["/words"]} <= said
    decisions = decoded["/mediator"]
    assert {"kind", "reason", "what", "seq"} <= decisions[0].keys()
    assert all(session.rows[d["seq"]]["kind"] == d["kind"] for d in decisions)
    assert len(decoded["/map"][0].entities) > 3  # (walls, edges, places)
    assert 0 < clock <= round(session.rows[-1]["t"] * 1e9)


# ------------------------------------------------------------------ the page, in a browser

@pytest.fixture
def browser() -> Any:
    from tests.browser import headless_chromium

    yield from headless_chromium()


def _page_wait(driver: Any, script: str, what: str) -> Any:
    """Wait (generously) until ``script`` returns something true in the page."""
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, WAIT, poll_frequency=0.05).until(
        lambda d: d.execute_script(script), message=f"the page never showed {what}")


def _steps(driver: Any, by: str, times: int) -> None:
    """Click Step ``times`` times, ``by`` seconds each, each time until the run caught up."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import Select

    Select(driver.find_element(By.ID, "step-by")).select_by_value(by)
    for _ in range(times):
        clock = driver.execute_script("return window.primaLive.status().clock")
        driver.find_element(By.ID, "step").click()
        _page_wait(driver, f"const s = window.primaLive.status(); return s.idle && "
                           f"(s.clock >= {clock} + {by} - 1e-6 || s.state !== 'running')",
                   f"the run {by} s further")


def _rows(driver: Any) -> list[dict[str, Any]]:
    rows: list[dict[str, Any]] = driver.execute_script("return window.primaLive.rows()")
    return rows


def test_the_author_asks_over_an_explanation_touches_and_saves_and_prima_run_replays_it(
        browser: Any, tmp_path: Path) -> None:
    """The acceptance: in real headless Chromium, the page shows the run; typed over the
    guide's explanation, a question stops the robot at the word (within 0.3 s and the
    word under way, simulated) and the guide answers; a touch is felt; Save writes the
    session where the command line said, and ``prima run`` of it makes the lines the
    page showed. Hostile words are shown as words."""
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    process, url = _started(str(VISIT), "--script", "--paused", "--save-dir", str(tmp_path))
    try:
        browser.get(url)
        _page_wait(browser, "return window.primaLive.ready() && window.primaLive.status()",
                   "the session")
        _steps(browser, "5", 7)
        _steps(browser, "1", 2)  # 37 s: "Take attention to this upper figure. Our ..."
        speaking = [r for r in _rows(browser) if r["kind"] == "start" and r.get("text")]
        assert speaking[-1]["text"].startswith("Take attention to this upper figure.")
        box = browser.find_element(By.ID, "say")
        box.send_keys("Excuse me, where is the toilet?" + Keys.ENTER)
        _page_wait(browser, "return window.primaLive.rows().some(r => r.kind === 'hear')",
                   "the words heard")
        _steps(browser, "1", 4)
        rows = _rows(browser)
        said = next(r for r in rows if r["kind"] == "user" and r.get("action") == "say")
        cut = next(r for r in rows if r["kind"] == "end" and r.get("reason") == "barge-in")
        detail = cut["detail"]
        words = len(str(detail["spoken"]).split()) + len(str(detail["unspoken"]).split())
        word = (detail["words_end"] - detail["words_start"]) / words
        planned = next(r for r in rows if r["kind"] == "start" and r.get("ab") == cut["ab"])
        assert planned["t"] < said["t"] < cut["t"] <= said["t"] + 0.3 + word + 1e-9
        answer = next(r for r in rows if r["kind"] == "start" and r.get("text") ==
                      "The toilets are next to the museum door.")
        assert answer["t"] - said["t"] < 2.0
        # the words as the page shows them, a stranger's markup shown as text
        box.send_keys('<img src=x onerror="window.hacked=1">' + Keys.ENTER)
        browser.find_element(By.ID, "touch").click()
        _steps(browser, "1", 3)
        for _ in range(20):  # (the user walks up to the robot first)
            if any(r["kind"] == "event" and r.get("text") == "touched" for r in _rows(browser)):
                break
            _steps(browser, "1", 1)
        assert any(r["kind"] == "event" and r.get("text") == "touched" for r in _rows(browser))
        words_shown = browser.find_element(By.ID, "words").text
        assert '<img src=x onerror="window.hacked=1">' in words_shown
        assert not browser.execute_script("return document.querySelector('#words img') || "
                                          "window.hacked")
        browser.find_element(By.ID, "save").click()
        _page_wait(browser, "return document.getElementById('notice').textContent"
                            ".startsWith('saved as')", "the save")
        saved = tmp_path / "museum-visit-live-1.xml"
        assert saved.is_file()
        text = saved.read_text(encoding="utf-8")
        until = _until(text)
        _steps(browser, "1", 2)  # (the page has every line before the save's end)
        page_rows = _rows(browser)
        assert page_rows[-1]["t"] >= until
        errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=WAIT)
    assert _same_trace(page_rows, text, tmp_path / "replayed.xml") > 100
    assert main(["validate", str(saved)], err=io.StringIO()) == 0


def test_the_user_walks_where_dragged_the_robot_is_touched_where_clicked_one_tab_at_a_time(
        browser: Any, tmp_path: Path) -> None:
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    process, url = _started(str(VISIT), "--paused")
    try:
        browser.get(url)
        _page_wait(browser, "return window.primaLive.ready() && window.primaLive.pose()",
                   "the session")
        _steps(browser, "1", 2)
        drag = browser.find_element(By.CSS_SELECTOR, "#map .nsewdrag")

        def at(x: float, y: float) -> tuple[int, int]:  # a map point, from the layer's centre
            dx, dy = browser.execute_script(
                "const d = document.getElementById('map'), l = d._fullLayout, r = "
                "d.querySelector('.nsewdrag').getBoundingClientRect(); return "
                "[l.xaxis.c2p(arguments[0]) - r.width / 2, l.yaxis.c2p(arguments[1]) - "
                "r.height / 2];", x, y)
            return round(dx), round(dy)

        _t, robot, user = browser.execute_script("return window.primaLive.pose()")
        ActionChains(browser).move_to_element_with_offset(drag, *at(user[0], user[1])) \
            .click_and_hold().move_to_element_with_offset(drag, *at(9.5, 4.0)).release() \
            .perform()
        _page_wait(browser, "return window.primaLive.rows().some(r => r.kind === 'user' && "
                            "r.action === 'walk')", "the walk")
        walk = next(r for r in _rows(browser) if r["kind"] == "user" and r["action"] == "walk")
        x, y = (float(v) for v in walk["detail"]["target"].strip("()").split(","))
        assert abs(x - 9.5) < 0.2 and abs(y - 4.0) < 0.2
        ActionChains(browser).move_to_element_with_offset(drag, *at(robot[0], robot[1])) \
            .click().perform()
        _page_wait(browser, "return window.primaLive.status().added === 2", "the touch")
        _steps(browser, "5", 4)
        touch = [r for r in _rows(browser) if r["kind"] == "user" and r["action"] == "touch"]
        assert touch, "the user walked up to the robot and touched it"
        # a second tab is told the session is in use; when the first goes, it takes over
        first = browser.current_window_handle
        browser.switch_to.new_window("tab")
        browser.get(url)
        _page_wait(browser, "return !document.getElementById('banner').hidden && "
                            "document.getElementById('banner').textContent.includes('in use')",
                   "the session in use")
        assert not any(_enabled(browser).values()), "the tab without the session acts in nothing"
        second = browser.current_window_handle
        browser.switch_to.window(first)
        browser.close()
        browser.switch_to.window(second)
        browser.refresh()
        _page_wait(browser, "return window.primaLive.ready() && "
                            "window.primaLive.rows().length > 50", "the session taken over")
        assert browser.find_element(By.ID, "banner").get_attribute("hidden") is not None
        assert _enabled(browser)["touch"] and _enabled(browser)["save"]
    finally:
        process.send_signal(signal.SIGTERM)
        _out, err = process.communicate(timeout=WAIT)
    assert "2 input(s)" in err


_CONTROLS = ("play", "step-by", "speed", "save", "say", "touch", "follow", "stop", "sender",
             "message")


def _enabled(driver: Any) -> dict[str, bool]:
    """Which of the page's controls can be used (Step only while paused)."""
    enabled: dict[str, bool] = driver.execute_script(
        "return Object.fromEntries(arguments[0].map(id => "
        "[id, !document.getElementById(id).disabled]))", list(_CONTROLS))
    return enabled


def _notice(driver: Any) -> str:
    notice: str = driver.execute_script("return document.getElementById('notice').textContent")
    return notice


def test_the_space_bar_plays_a_click_touches_and_a_refusal_keeps_the_words_until_one_goes(
        browser: Any, tmp_path: Path) -> None:
    """The space bar plays and pauses wherever the focus is (the button just clicked is
    not clicked again) but in a box one types in; a click near both the robot and the user
    touches the robot, never walks; a refused input is said until a later one goes
    through, and refused words stay in their box."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    process, url = _started(str(VISIT), "--paused")
    try:
        browser.get(url)
        _page_wait(browser, "return window.primaLive.ready() && window.primaLive.pose()",
                   "the session")
        browser.find_element(By.ID, "touch").click()
        _page_wait(browser, "return window.primaLive.status().added === 1", "the touch")
        ActionChains(browser).send_keys(" ").perform()  # (the focus on Touch)
        _page_wait(browser, "return !window.primaLive.status().paused", "the run played")
        ActionChains(browser).send_keys(" ").perform()
        _page_wait(browser, "return window.primaLive.status().paused", "the run paused")
        box = browser.find_element(By.ID, "say")
        box.send_keys("a b")  # (typed: spaces, not Play)
        assert box.get_attribute("value") == "a b"
        assert browser.execute_script("return window.primaLive.status()")["paused"]
        box.clear()
        assert browser.execute_script("return window.primaLive.status().added") == 1
        # the robot at the museum door, the user 0.8 m behind it: a click between them
        _t, robot, user = browser.execute_script("return window.primaLive.pose()")
        x, y = (robot[0] + user[0]) / 2, (robot[1] + user[1]) / 2
        browser.execute_script(
            "const d = document.getElementById('map'), l = d._fullLayout, r = "
            "d.querySelector('.nsewdrag').getBoundingClientRect(), o = {bubbles: true, "
            "clientX: r.left + l.xaxis.c2p(arguments[0]), clientY: r.top + "
            "l.yaxis.c2p(arguments[1])}; d.dispatchEvent(new MouseEvent('mousedown', o)); "
            "window.dispatchEvent(new MouseEvent('mouseup', o));", x, y)
        _page_wait(browser, "return window.primaLive.status().added === 2", "the click")
        _steps(browser, "0.1", 1)
        acts = [r["action"] for r in _rows(browser) if r["kind"] == "user"]
        assert acts == ["touch", "touch"]
        # refused, then corrected: the notice goes once the corrected input goes through
        browser.find_element(By.ID, "sender").clear()
        message = browser.find_element(By.ID, "message")
        message.send_keys("shelf-b" + Keys.ENTER)
        _page_wait(browser, "return document.getElementById('notice').textContent"
                            ".includes(\"sender: give some words\")", "the refusal")
        assert message.get_attribute("value") == "shelf-b"
        browser.find_element(By.ID, "sender").send_keys("library")
        message.send_keys(Keys.ENTER)
        _page_wait(browser, "return window.primaLive.status().added === 3 && "
                            "!document.getElementById('notice').textContent", "the notice gone")
        assert message.get_attribute("value") == ""
        box.send_keys("   " + Keys.ENTER)  # (blank: said, not sent)
        assert "type some words" in _notice(browser) and box.get_attribute("value") == ""
        # more than 20 inputs a second: the refused words stay in the box
        browser.execute_script("for (let i = 0; i < 25; i++) { const b = document."
                               "getElementById('say'); b.value = 'Hey robot ' + i; "
                               "b.form.requestSubmit(); }")
        _page_wait(browser, "return document.getElementById('notice').textContent"
                            ".includes('inputs a second')", "the rate refused")
        assert box.get_attribute("value") == "Hey robot 24"
        while box.get_attribute("value"):  # (again, until the second is over)
            time.sleep(0.1)
            box.send_keys(Keys.ENTER)
            _page_wait(browser, "return document.getElementById('say').value || "
                                "!document.getElementById('notice').textContent",
                       "the words taken or refused")
        added = browser.execute_script("return window.primaLive.status().added")
        errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []
    finally:
        process.send_signal(signal.SIGTERM)
        _out, err = process.communicate(timeout=WAIT)
    assert f" {added} input(s)" in err


def test_the_timeline_follows_the_run_again_bubbles_stay_apart_and_an_ended_run_keeps_save(
        browser: Any, tmp_path: Path) -> None:
    """Panned, the timeline stays where it was put; double-clicked, or with its button, it
    follows the run again. The user's bubble and the robot's never cover each other. Once
    the run has ended, only Save is left to act with."""
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By
    from selenium.webdriver.common.keys import Keys

    process, url = _started(str(VISIT), "--script", "--paused", "--until", "40")
    shown_range = "return document.getElementById('timeline').layout.xaxis.range.map(Number)"
    redrawn = ("const d = document.getElementById('timeline').data; "
               "return d.length && !d.seen")
    try:
        browser.get(url)
        _page_wait(browser, "return window.primaLive.ready() && window.primaLive.status()",
                   "the session")
        _steps(browser, "5", 6)
        _steps(browser, "1", 4)  # 34 s: the guide explains the first panel
        browser.find_element(By.ID, "say").send_keys("Excuse me, where is the toilet?" +
                                                     Keys.ENTER)
        _steps(browser, "0.5", 1)
        _page_wait(browser, "return document.querySelectorAll('#map .annotation').length >= 2",
                   "the bubbles")
        boxes = browser.execute_script(
            "return [...document.querySelectorAll('#map .annotation')].map(a => {"
            "const r = a.querySelector('.annotation-text-g').getBoundingClientRect(); "
            "return [a.textContent, r.left, r.top, r.right, r.bottom]; })")
        mine = [b for b in boxes if b[0] == "Excuse me, where is the toilet?"]
        theirs = [b for b in boxes if b[0] != mine[0][0]]
        assert mine and theirs, boxes
        for b in theirs:  # (apart: one is left of, right of, above or below the other)
            assert (b[3] <= mine[0][1] or mine[0][3] <= b[1] or b[4] <= mine[0][2]
                    or mine[0][4] <= b[2]), (mine, b)
        # (the user higher on the map: its bubbles go up, the robot's down)
        sides = browser.execute_script(
            "return document.getElementById('map').layout.annotations.map(a => "
            "[a.bordercolor === '#e67e22' ? 'user' : 'robot', Math.sign(a.ay)])")
        assert {side for who, side in sides if who == "user"} == {-1}, sides
        assert {side for who, side in sides if who == "robot"} == {1}, sides
        # panned to the start, the timeline stays there while the run goes on
        _page_wait(browser, redrawn, "the timeline")
        browser.execute_script("Plotly.relayout('timeline', {'xaxis.range[0]': 0, "
                               "'xaxis.range[1]': 10});")
        assert browser.find_element(By.ID, "follow-time").is_displayed()
        browser.execute_script("document.getElementById('timeline').data.seen = true;")
        _steps(browser, "1", 1)
        _page_wait(browser, redrawn, "the timeline redrawn")
        assert browser.execute_script(shown_range) == [0, 10]
        area = browser.find_element(By.CSS_SELECTOR, "#timeline .nsewdrag")
        ActionChains(browser).double_click(area).perform()
        _page_wait(browser, f"const r = ({shown_range.removeprefix('return ')}); "
                            "return r[0] === 0 && r[1] > 36", "the timeline following")
        assert not browser.find_element(By.ID, "follow-time").is_displayed()
        browser.execute_script("Plotly.relayout('timeline', {'xaxis.range[0]': 5, "
                               "'xaxis.range[1]': 10});")
        browser.find_element(By.ID, "follow-time").click()
        _page_wait(browser, f"return ({shown_range.removeprefix('return ')})[1] > 36",
                   "the timeline following again")
        assert not browser.find_element(By.ID, "follow-time").is_displayed()
        # the end: what cannot act any more is disabled; Save is left
        assert all(_enabled(browser).values())
        _steps(browser, "5", 1)
        _page_wait(browser, "return window.primaLive.status().state === 'ended'", "the end")
        _page_wait(browser, "return document.getElementById('touch').disabled", "disabled")
        enabled = _enabled(browser)
        assert enabled.pop("save") and not any(enabled.values()), enabled
        assert browser.find_element(By.ID, "step").get_attribute("disabled") is not None
        paused = browser.execute_script("return window.primaLive.status().paused")
        ActionChains(browser).send_keys(" ").perform()
        browser.find_element(By.ID, "save").click()
        _page_wait(browser, "return window.primaLive.downloaded", "the download")
        assert browser.execute_script("return window.primaLive.status().paused") == paused
        assert "the run is over" not in _notice(browser)
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=WAIT)


_SOCKETS = """
window.primaSockets = [];
window.WebSocket = class extends WebSocket {  // (the page's, kept: what it asks, what comes)
  constructor(...args) {
    super(...args);
    window.primaSockets.push(this);
    this.asked = this.timelines = 0;
    this.addEventListener("message", (e) => {
      if ("timeline" in JSON.parse(e.data)) this.timelines++;
    });
  }
  send(data) {
    if ("timeline" in JSON.parse(data)) this.asked++;
    super.send(data);
  }
};
"""
"""Before the page's own script: its WebSocket counts the timelines it asks for and gets."""

_DRAWN = """
window.drawn = [];
const react = Plotly.react;
Plotly.react = function (div, data, layout) {  // (each timeline drawn, by its title)
  if (div.id === "timeline") window.drawn.push((layout.title && layout.title.text) || "run");
  return react.apply(this, arguments);
};
"""

_BURST = """
const socket = window.primaSockets[0];
for (let k = 0; k < arguments[0]; k++) {  // (all at once: come while the page was busy)
  socket.onmessage({data: JSON.stringify({timeline: {
    data: [{type: "bar", orientation: "h", y: ["speaker"], base: [k], x: [1]}],
    layout: {title: {text: "burst " + k}, xaxis: {range: [0, 40]}}, config: {}},
    covers: [-33, 66]})});
}
"""


def test_the_page_draws_the_latest_timeline_not_each_and_asks_for_one_when_it_can(
        browser: Any) -> None:
    """A long session's timeline takes long to draw, and a click waits behind each redraw:
    at 100x, a Pause took 16 s and more, the page drawing every timeline the server sent,
    one after the other. Of timelines come while the page was busy, it draws the latest
    once, not each; it asks the server for a timeline when it can draw one, and gets none
    it did not ask for. (Counted, not timed: how long a redraw takes is the machine's.)"""
    process, url = _started(str(VISIT), "--script", "--paused")
    try:
        browser.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": _SOCKETS})
        browser.get(url)
        _page_wait(browser, "return window.primaLive.ready() && window.primaLive.status()",
                   "the session")
        browser.execute_script(_DRAWN)
        _steps(browser, "5", 2)
        _page_wait(browser, "return window.drawn.length", "the run's timeline")
        burst = 30
        browser.execute_script(_BURST, burst)
        _page_wait(browser, f"return window.drawn.includes('burst {burst - 1}')",
                   "the burst's last timeline")
        drawn = [d for d in browser.execute_script("return window.drawn") if d != "run"]
        assert len(drawn) <= 2 and drawn[-1] == f"burst {burst - 1}", drawn
        # the run goes on: its next timeline is drawn, and came only as asked for
        _steps(browser, "5", 1)
        _page_wait(browser, "return window.drawn[window.drawn.length - 1] === 'run'",
                   "the run's timeline again")
        socket = browser.execute_script("const s = window.primaSockets[0]; "
                                        "return [s.timelines, s.asked]")
        assert 2 <= socket[0] <= socket[1], socket
        errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=WAIT)


_COVERED = """
const t = window.primaLive.time(), shown = document.getElementById("timeline").layout.xaxis;
const r = shown.range.map(Number), c = window.primaLive.timelines().covers;
return c && c[0] <= r[0] && r[1] <= c[1] && """
"""Whether the timeline drawn covers the range shown, and (what follows) the range is as
said (``r``: the range, ``t``: the clock)."""


def test_a_quiet_sessions_timeline_follows_the_clock_and_a_pan_is_filled_in(
        browser: Any) -> None:
    """FA1 alone waits to be touched: stepped a minute at a time, its trace does not grow,
    and no timeline of new lines comes (the range shown stayed at the first 33 s while the
    clock went on). Following, the range moves on with the clock, and once past what its
    timeline covers, the page asks for the window it shows and is sent it; panned back,
    likewise. Counted, not timed: a timeline for each window left, none for each step."""
    from selenium.webdriver.common.by import By

    process, url = _started(str(FA1), "--paused")
    step = "window.primaSockets[0].send(JSON.stringify({control: 'step', seconds: 60}));"
    try:
        browser.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": _SOCKETS})
        browser.get(url)
        _page_wait(browser, "return window.primaLive.ready() && window.primaLive.status() && "
                            "window.primaLive.timelines().drawn", "the first timeline")
        _page_wait(browser, "return window.primaLive.timelines().asked", "the next asked for")
        lines = len(_rows(browser))
        first = browser.execute_script("return window.primaLive.timelines().received")
        for minute in range(1, 5):
            browser.execute_script(step)
            _page_wait(browser, "const s = window.primaLive.status(); return s.idle && "
                                f"s.clock >= {60 * minute} - 1e-6", f"minute {minute}")
        _page_wait(browser, _COVERED + "r[0] <= t && t <= r[1]", "the timeline following")
        assert len(_rows(browser)) == lines  # (quiet: not a line since)
        received = browser.execute_script("return window.primaLive.timelines().received")
        assert 1 <= received - first <= 3, (first, received)  # (240 s: 2 windows of 93 s left)
        browser.execute_script("Plotly.relayout('timeline', {'xaxis.range[0]': 10, "
                               "'xaxis.range[1]': 20});")
        _page_wait(browser, _COVERED + "r[0] === 10 && r[1] === 20", "the pan filled in")
        browser.find_element(By.ID, "follow-time").click()
        _page_wait(browser, _COVERED + "r[0] <= t && t <= r[1]", "following again")
        errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
        assert errors == []
    finally:
        process.send_signal(signal.SIGTERM)
        process.communicate(timeout=WAIT)


def test_only_the_live_command_imports_the_live_page() -> None:
    """A server apart from the core: only ``prima live``'s handler imports it, lazily, and
    it is imported by nothing else (aiohttp with it)."""
    import ast

    importers = []
    for path in sorted((ROOT / "prima").rglob("*.py")):
        inside = path.relative_to(ROOT / "prima").parts[0]
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            if inside != "live" and any(n == "prima.live" or n.startswith(
                    ("prima.live.", "aiohttp")) for n in names):
                importers.append((inside, node.col_offset > 0))
    assert set(importers) == {("cli", True)}
