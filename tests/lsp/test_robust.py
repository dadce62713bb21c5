"""``prima lsp`` against any client: bytes no client should send, and bursts of changes.

Each test drives a real server process over its stdin and stdout, byte by byte
(:class:`tests.lsp.client.Raw`). None measures time: a burst is written to the
server in one write (the pipe holds it whole), so what the server does with it
never depends on how fast the machine is; what is asserted is the order of the
server's messages and how many it publishes.
"""

from __future__ import annotations

import asyncio
import json
import shutil
import subprocess
import sys
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("pygls")

from prima.lsp._stream import MAX_MESSAGE  # noqa: E402
from tests.lsp.client import Raw, did_change, did_open, frame, uri, where  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
EA = ROOT / "apps" / "ea" / "ea3-navigate.pxml"
PUBLISH = "textDocument/publishDiagnostics"


def run(root: Path, test: Callable[[Raw], Awaitable[None]]) -> None:
    async def session() -> None:
        async with Raw(root) as raw:
            await test(raw)

    asyncio.run(session())


def hover(path: Path, text: str, needle: str, shift: int = 2) -> dict[str, Any]:
    line, character = where(text, needle, shift)
    return {"textDocument": {"uri": uri(path)}, "position": {"line": line,
                                                             "character": character}}


async def published(raw: Raw, key: str, version: int,
                    *more: tuple[str, int]) -> list[dict[str, Any]]:
    """Read until ``key``'s diagnostics of ``version`` (and those of each of ``more``)
    are published; every publication read on the way, in order."""
    wanted = {(key, version), *more}
    seen = []
    while wanted:
        message = await raw.read()
        if message.get("method") == PUBLISH:
            params = message["params"]
            seen.append(params)
            wanted.discard((params["uri"], params.get("version")))
    return seen


def test_an_oversized_message_is_refused_and_the_server_answers_the_next(tmp_path: Path) -> None:
    path = tmp_path / "ea3.pxml"
    text = EA.read_text(encoding="utf-8")
    path.write_text(text, encoding="utf-8")

    async def test(raw: Raw) -> None:
        raw.send(did_open(path))
        await published(raw, uri(path), 1)
        # a request one byte over the bound, sent whole: refused under its own id
        big = raw.call("textDocument/hover", hover(path, text, 'Speak("Come on'))
        big["params"]["padding"] = "x" * MAX_MESSAGE
        raw.send(big)
        refused = await raw.response(big["id"])
        assert refused["error"]["code"] == -32600
        assert f"at most {MAX_MESSAGE:,} bytes" in refused["error"]["message"]
        # a length no client could send, and a body far shorter: read past up to the
        # next message's header, which is answered
        raw.write(b"Content-Length: 999999999999999999\r\n\r\n{\"jsonrpc\": \"2.0\", ")
        answer = await raw.response(raw.request("textDocument/hover", hover(
            path, text, 'Speak("Come on')))
        assert "Speak" in answer["result"]["contents"]["value"]

    run(tmp_path, test)


def _stream(*parts: bytes) -> bytes:
    init = {"jsonrpc": "2.0", "id": 1, "method": "initialize",
            "params": {"processId": None, "rootUri": None, "capabilities": {}}}
    return frame(init) + b"".join(parts)


BAD_STREAM = _stream(
    b"X-Nothing\r\n\r\n",                                        # a header with no colon
    frame({"jsonrpc": "2.0", "id": 2, "method": "prima/none"}),  # (an unknown method)
    b"Content-Length: twelve\r\n\r\n{}\r\n",                     # a length not a number
    b"Content-Length: 9\r\n\r\n{\"id\": 3,",                     # not JSON
    frame({"jsonrpc": "2.0", "id": 4, "method": "shutdown"}),
    b"Content-Length: 4000\r\n\r\n{\"jsonrpc\":",                # cut short: the stream ends
)


@pytest.mark.parametrize("via", ["pipe", "file"])
def test_bytes_no_client_sends_are_said_in_one_line_and_the_server_exits_cleanly(
        tmp_path: Path, via: str) -> None:
    """Every fault is one line on stderr, the messages between them are answered, and a
    stream that ends inside a message ends the server with status 1: no traceback."""
    source = tmp_path / "input.bin"
    source.write_bytes(BAD_STREAM)
    with source.open("rb") as stdin:
        done = subprocess.run(
            [sys.executable, "-m", "prima", "lsp"], cwd=tmp_path, timeout=120,
            capture_output=True, check=False, **(
                {"stdin": stdin} if via == "file" else {"input": BAD_STREAM}))
    err = done.stderr.decode()
    assert "Traceback" not in err, err
    assert done.returncode == 1, err
    lines = err.splitlines()
    assert all(line.startswith("prima lsp: ") for line in lines), err
    assert any("not 'Name: value'" in line for line in lines), err
    assert any("Content-Length 'twelve' is not a number of bytes" in line for line in lines)
    assert any("not JSON" in line for line in lines), err
    assert lines[-1] == "prima lsp: the client's stream ended inside a message (11 of 4,000 " \
                        "bytes): stopping", err
    answers = {m.get("id"): m for m in _messages(done.stdout)}
    assert "capabilities" in answers[1]["result"]  # initialize, before the faults
    assert answers[2]["error"]["code"] == -32601  # between them
    assert answers[None]["error"]["code"] == -32700  # not JSON: said to the client too
    assert "result" in answers[4]  # shutdown, after them


def _messages(out: bytes) -> list[dict[str, Any]]:
    found = []
    while out:
        head, _, rest = out.partition(b"\r\n\r\n")
        length = int(head.split(b"\r\n")[0].split(b":")[1])
        found.append(json.loads(rest[:length]))
        out = rest[length:]
    return found


def _workspace(folder: Path, others: int) -> tuple[Path, Path, Path, list[Path]]:
    """A scenario that runs an FA and an EA on the office map, and ``others`` documents
    it does not run."""
    (folder / "maps").mkdir()
    shutil.copy(ROOT / "scenarios" / "maps" / "office.xml", folder / "maps" / "office.xml")
    fa = folder / "fa.pxml"
    shutil.copy(ROOT / "apps" / "fa" / "fa2-follow.pxml", fa)
    ea = folder / "guide.pxml"
    shutil.copy(EA, ea)
    scenario = folder / "visit.xml"
    scenario.write_text(SCENARIO.format(until=60), encoding="utf-8")
    rest = []
    source = EA.read_text(encoding="utf-8")
    for i in range(others):
        other = folder / "others" / f"ea-{i:02d}.pxml"
        other.parent.mkdir(exist_ok=True)
        other.write_text(source.replace('name="', f'name="other{i}-', 1), encoding="utf-8")
        rest.append(other)
    return scenario, fa, ea, rest


SCENARIO = ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<scenario xmlns="urn:prima:scenario:1" name="visit" until="{until}">\n'
            '  <map href="maps/office.xml"/>\n'
            '  <apps fa="fa.pxml" ea="guide.pxml"/>\n'
            '  <robot place="entrance"/>\n'
            '</scenario>\n')


def test_a_burst_of_scenario_changes_never_starves_a_request(tmp_path: Path) -> None:
    """300 changes of a scenario with 20 documents open, then a hover, in one write: the
    hover is answered before any diagnostics of the burst; then the scenario is checked
    once, at its last version, and of the other documents only those it runs."""
    scenario, fa, ea, rest = _workspace(tmp_path, 17)
    ea_text = ea.read_text(encoding="utf-8")
    opened = [scenario, fa, ea, *rest]
    assert len(opened) == 20

    async def test(raw: Raw) -> None:
        for path in opened:
            raw.send(did_open(path))
            await published(raw, uri(path), 1)
        burst = [did_change(scenario, v, SCENARIO.format(until=60 + v % 7))
                 for v in range(2, 302)]
        ask = raw.call("textDocument/hover", hover(ea, ea_text, 'Speak("Come on'))
        raw.send(*burst, ask)
        before = []
        while True:
            message = await raw.read()
            if message.get("method") == PUBLISH:
                before.append(message["params"]["uri"])
                assert len(before) <= 20, "the hover waits behind the burst's checks"
            elif message.get("id") == ask["id"]:
                break
        assert before == []
        assert "Speak" in message["result"]["contents"]["value"]
        # then one check of the scenario, at its last version, and of the documents it
        # runs; a change after it is a barrier: all the burst's checks come before its own
        first = await published(raw, uri(scenario), 301, (uri(fa), 1), (uri(ea), 1))
        raw.send(did_change(scenario, 302, SCENARIO.format(until=60)))
        later = await published(raw, uri(scenario), 302, (uri(fa), 1), (uri(ea), 1))
        keys = [p["uri"] for p in first + later]
        assert set(keys) == {uri(scenario), uri(fa), uri(ea)}, keys
        assert [p["version"] for p in first + later if p["uri"] == uri(scenario)] == [301, 302]
        assert keys.count(uri(fa)) == keys.count(uri(ea)) == 2  # once per round

    run(tmp_path, test)


def test_a_scenario_change_rechecks_only_the_documents_it_runs(tmp_path: Path) -> None:
    scenario, fa, ea, rest = _workspace(tmp_path, 3)

    async def test(raw: Raw) -> None:
        for path in (scenario, fa, ea, *rest):
            raw.send(did_open(path))
            await published(raw, uri(path), 1)
        raw.send(did_change(scenario, 2, SCENARIO.format(until=61)))
        seen = await published(raw, uri(scenario), 2, (uri(fa), 1), (uri(ea), 1))
        raw.send(did_change(scenario, 3, SCENARIO.format(until=60)))  # the barrier
        seen += await published(raw, uri(scenario), 3, (uri(fa), 1), (uri(ea), 1))
        assert sorted({p["uri"] for p in seen}) == sorted({uri(scenario), uri(fa), uri(ea)})
        assert len(seen) == 6

    run(tmp_path, test)


def test_only_the_latest_version_is_checked(tmp_path: Path) -> None:
    path = tmp_path / "ea3.pxml"
    text = EA.read_text(encoding="utf-8")
    path.write_text(text, encoding="utf-8")
    typo = text.replace('Speak("O.K.")', 'Speak("O.K."', 1)

    async def test(raw: Raw) -> None:
        raw.send(did_open(path))
        await published(raw, uri(path), 1)
        raw.send(*(did_change(path, v, typo if v % 2 else text) for v in range(2, 52)))
        seen = await published(raw, uri(path), 51)
        assert [(p["uri"], p["version"]) for p in seen] == [(uri(path), 51)]
        assert seen[0]["diagnostics"] and "')'" in str(seen[0]["diagnostics"])  # 51: typo
        raw.send(did_change(path, 52, text))
        assert [p["version"] for p in await published(raw, uri(path), 52)] == [52]

    run(tmp_path, test)


def test_a_document_change_rechecks_the_scenario_that_runs_it_and_no_other(
        tmp_path: Path) -> None:
    """An EA turned into an FA: the scenario that runs it as its EA says so; the FA and
    the documents no scenario runs are not checked again."""
    scenario, fa, ea, rest = _workspace(tmp_path, 2)
    ea_text = ea.read_text(encoding="utf-8")

    async def test(raw: Raw) -> None:
        for path in (scenario, fa, ea, *rest):
            raw.send(did_open(path))
            await published(raw, uri(path), 1)
        raw.send(did_change(ea, 2, ea_text.replace('kind="ea"', 'kind="fa"', 1)))
        seen = await published(raw, uri(ea), 2, (uri(scenario), 1))
        raw.send(did_change(ea, 3, ea_text))  # the barrier
        seen += await published(raw, uri(ea), 3)
        keys = {p["uri"] for p in seen}
        assert keys == {uri(ea), uri(scenario)}, keys
        wrong = [p for p in seen if p["uri"] == uri(scenario)][0]["diagnostics"]
        assert any("it cannot run as the EA" in d["message"] for d in wrong)

    run(tmp_path, test)


def _said(root: Path, test: Callable[[Raw], Awaitable[None]]) -> list[str]:
    """What the server said on stderr, line by line, in a session that ``test`` drives."""
    said: list[bytes] = []

    async def session() -> None:
        async with Raw(root) as raw:
            await test(raw)
        said.append(raw.stderr)

    asyncio.run(session())
    return said[0].decode().splitlines()


def test_a_document_edits_make_longer_than_the_bound_is_no_longer_held(
        tmp_path: Path) -> None:
    """A document is held of at most MAX_MESSAGE bytes however the editor grows it: the
    edit that takes it past the bound drops it (one line on stderr; requests about it are
    answered empty, its later changes read past); opened again, it is checked as any."""
    path = tmp_path / "notes.xml"
    text = '<?xml version="1.0"?>\n<notes/>\n'
    chunk = "<!--" + "x" * (3 << 20) + "-->\n"

    def grow(version: int) -> dict[str, Any]:
        return {"jsonrpc": "2.0", "method": "textDocument/didChange", "params": {
            "textDocument": {"uri": uri(path), "version": version},
            "contentChanges": [{"range": {"start": {"line": 1, "character": 0},
                                          "end": {"line": 1, "character": 0}},
                                "text": chunk}]}}

    async def test(raw: Raw) -> None:
        raw.send(did_open(path, text))
        await published(raw, uri(path), 1)
        raw.send(grow(2), grow(3), grow(4), grow(5))  # 3, 6, 9 MiB: dropped; read past
        ask = raw.call("textDocument/hover", {"textDocument": {"uri": uri(path)},
                                              "position": {"line": 1, "character": 2}})
        raw.send(ask)
        while (message := await raw.read()).get("id") != ask["id"]:
            pass
        assert message["result"] is None
        raw.send(did_open(path, text))
        await published(raw, uri(path), 1)

    assert 3 * len(chunk) > MAX_MESSAGE > 2 * len(chunk)
    assert _said(tmp_path, test) == [
        f"prima lsp: {uri(path)} grew past {MAX_MESSAGE:,} bytes: it is not held nor "
        "checked (close it, then open it again)"]


@pytest.mark.slow
def test_documents_opened_beyond_the_bound_are_not_held(tmp_path: Path) -> None:
    """At most MAX_OPEN documents are held open: one opened beyond them is not checked,
    its changes are read past, and one line on stderr says so (once, however many come);
    once another is closed, it is opened and checked as any."""
    from prima.lsp._server import MAX_OPEN

    paths = [tmp_path / f"notes-{i}.xml" for i in range(MAX_OPEN + 2)]
    text = '<?xml version="1.0"?>\n<notes/>\n'

    async def test(raw: Raw) -> None:
        raw.send(*(did_open(path, text) for path in paths[:MAX_OPEN]))
        seen: set[str] = set()
        while len(seen) < MAX_OPEN:
            message = await raw.read()
            if message.get("method") == PUBLISH:
                seen.add(message["params"]["uri"])
        over, also = paths[MAX_OPEN:]
        raw.send(did_open(over, text), did_change(over, 2, text), did_open(also, text))
        ask = raw.call("textDocument/hover", {"textDocument": {"uri": uri(over)},
                                              "position": {"line": 1, "character": 2}})
        raw.send(ask)
        while (message := await raw.read()).get("id") != ask["id"]:
            assert message.get("method") != PUBLISH or message["params"]["uri"] not in (
                uri(over), uri(also))
        assert message["result"] is None
        raw.send({"jsonrpc": "2.0", "method": "textDocument/didClose",
                  "params": {"textDocument": {"uri": uri(paths[0])}}}, did_open(over, text))
        await published(raw, uri(over), 1)

    assert _said(tmp_path, test) == [
        f"prima lsp: {MAX_OPEN:,} documents are open: {uri(paths[MAX_OPEN])} and any opened "
        "after it are not checked (close one, then open them again)"]
