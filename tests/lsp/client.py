"""A language client for the tests: ``prima lsp`` in a process of its own, over stdio.

pygls's own client speaks the protocol; this wraps the few requests the tests
make and collects the diagnostics the server publishes.
"""

from __future__ import annotations

import asyncio
import contextlib
import fcntl
import json
import sys
import time
from pathlib import Path
from typing import Any

from lsprotocol import types
from pygls.lsp.client import LanguageClient
from pygls.uris import from_fs_path

TIMEOUT = 300.0
"""Seconds a test waits at most for the server's answer (its first diagnostics import
xmlschema): a bound against a server that never answers, not a speed it must keep."""


def uri(path: Path) -> str:
    return from_fs_path(str(path.resolve())) or str(path)


class Session:
    """One server, started in ``root`` (its workspace folder)."""

    def __init__(self, root: Path, *args: str) -> None:
        self.root = root
        self.args = args
        self.client = LanguageClient("prima-tests", "1")
        self.diagnostics: dict[str, list[types.Diagnostic]] = {}
        self._published: dict[str, asyncio.Event] = {}
        self.versions: dict[str, int] = {}
        self.log: list[tuple[str, int | None, float]] = []
        """Every publication: the document, its version, when it arrived (perf_counter)."""

        @self.client.feature(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        def published(params: types.PublishDiagnosticsParams) -> None:
            self.log.append((params.uri, params.version, time.perf_counter()))
            self.diagnostics[params.uri] = list(params.diagnostics)
            self._event(params.uri).set()

    def _event(self, key: str) -> asyncio.Event:
        return self._published.setdefault(key, asyncio.Event())

    async def __aenter__(self) -> Session:
        await self.client.start_io(sys.executable, "-m", "prima", "lsp", *self.args)
        snippets = types.CompletionClientCapabilities(
            completion_item=types.ClientCompletionItemOptions(snippet_support=True))
        await asyncio.wait_for(self.client.initialize_async(types.InitializeParams(
            capabilities=types.ClientCapabilities(
                text_document=types.TextDocumentClientCapabilities(completion=snippets)),
            root_uri=uri(self.root),
            workspace_folders=[types.WorkspaceFolder(uri(self.root), self.root.name)])),
            TIMEOUT)
        self.client.initialized(types.InitializedParams())
        return self

    async def __aexit__(self, *exc: object) -> None:
        await asyncio.wait_for(self.client.shutdown_async(None), TIMEOUT)
        self.client.exit(None)
        await self.client.stop()

    async def open(self, path: Path, text: str | None = None) -> list[types.Diagnostic]:
        """Open a file (its text on disk, or ``text``); its first diagnostics."""
        key = uri(path)
        self._event(key).clear()
        self.versions[key] = 1
        self.client.text_document_did_open(types.DidOpenTextDocumentParams(
            types.TextDocumentItem(key, "xml", 1,
                                   path.read_text(encoding="utf-8") if text is None else text)))
        return await self.wait(key)

    async def change(self, path: Path, text: str) -> list[types.Diagnostic]:
        """Replace the whole buffer, as one keystroke would change it; the new diagnostics."""
        key = uri(path)
        self._event(key).clear()
        self.versions[key] += 1
        self.client.text_document_did_change(types.DidChangeTextDocumentParams(
            types.VersionedTextDocumentIdentifier(self.versions[key], key),
            [types.TextDocumentContentChangeWholeDocument(text)]))
        return await self.wait(key)

    def edit(self, path: Path, start: tuple[int, int], end: tuple[int, int], text: str) -> int:
        """Send one keystroke, as an editor does: the range replaced and its new text; the
        document's new version (its diagnostics are not awaited)."""
        key = uri(path)
        self._event(key).clear()
        self.versions[key] += 1
        self.client.text_document_did_change(types.DidChangeTextDocumentParams(
            types.VersionedTextDocumentIdentifier(self.versions[key], key),
            [types.TextDocumentContentChangePartial(
                types.Range(types.Position(*start), types.Position(*end)), text)]))
        return self.versions[key]

    async def version(self, path: Path, version: int) -> list[types.Diagnostic]:
        """The diagnostics of ``version`` of the document, once published."""
        key = uri(path)
        while True:
            self._event(key).clear()
            if any(u == key and v == version for u, v, _t in self.log):
                return self.diagnostics[key]
            await self.wait(key)

    async def wait(self, key: str) -> list[types.Diagnostic]:
        await asyncio.wait_for(self._event(key).wait(), TIMEOUT)
        return self.diagnostics[key]

    async def complete(self, path: Path, line: int, character: int) -> list[types.CompletionItem]:
        found: Any = await asyncio.wait_for(self.client.text_document_completion_async(
            types.CompletionParams(types.TextDocumentIdentifier(uri(path)),
                                   types.Position(line, character))), TIMEOUT)
        return list(found.items if isinstance(found, types.CompletionList) else found or [])

    async def hover(self, path: Path, line: int, character: int) -> types.Hover | None:
        found: types.Hover | None = await asyncio.wait_for(
            self.client.text_document_hover_async(types.HoverParams(
                types.TextDocumentIdentifier(uri(path)), types.Position(line, character))),
            TIMEOUT)
        return found

    async def definition(self, path: Path, line: int, character: int) -> list[types.Location]:
        found: Any = await asyncio.wait_for(self.client.text_document_definition_async(
            types.DefinitionParams(types.TextDocumentIdentifier(uri(path)),
                                   types.Position(line, character))), TIMEOUT)
        if found is None:
            return []
        return list(found) if isinstance(found, list) else [found]


def where(text: str, needle: str, shift: int = 0) -> tuple[int, int]:
    """The line and character (0-based; the text is ASCII there) of ``needle`` + ``shift``."""
    offset = text.index(needle) + shift
    line = text.count("\n", 0, offset)
    return line, offset - (text.rfind("\n", 0, offset) + 1)


def frame(message: dict[str, Any]) -> bytes:
    """One message as the base protocol sends it."""
    body = json.dumps(message).encode("utf-8")
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


PIPE_BYTES = 1 << 20
"""How much the pipe to the server holds (Linux's default most, for anyone): a burst
written at once is then in the pipe whole before the server reads any of it."""


class Raw:
    """``prima lsp`` driven byte by byte: messages written as the test frames them (a
    burst of them in one write, or bytes no client should send), and every message the
    server writes read back in order."""

    def __init__(self, root: Path, *args: str) -> None:
        self.root = root
        self.args = args
        self.proc: asyncio.subprocess.Process | None = None
        self.ids = 0
        self.stderr = b""
        self._err_task: asyncio.Task[bytes] | None = None

    async def __aenter__(self) -> Raw:
        self.proc = await asyncio.create_subprocess_exec(
            sys.executable, "-m", "prima", "lsp", *self.args, stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE, cwd=self.root)
        assert self.proc.stdin is not None and self.proc.stderr is not None
        pipe = self.proc.stdin.transport.get_extra_info("pipe")
        with contextlib.suppress(OSError):
            fcntl.fcntl(pipe.fileno(), 1031, PIPE_BYTES)  # F_SETPIPE_SZ
        self._err_task = asyncio.ensure_future(self.proc.stderr.read())
        ident = self.request("initialize", {
            "processId": None, "rootUri": uri(self.root), "capabilities": {},
            "workspaceFolders": [{"uri": uri(self.root), "name": self.root.name}]})
        await self.response(ident)
        self.send({"jsonrpc": "2.0", "method": "initialized", "params": {}})
        return self

    async def __aexit__(self, *exc: object) -> None:
        proc = self.proc
        assert proc is not None and proc.stdin is not None
        if proc.returncode is None and not proc.stdin.is_closing():
            with contextlib.suppress(ConnectionError, asyncio.TimeoutError):
                await asyncio.wait_for(self.response(self.request("shutdown", None)), TIMEOUT)
                self.send({"jsonrpc": "2.0", "method": "exit"})
        await self.finish()

    async def finish(self) -> int:
        """Wait for the server to end; its exit status (its stderr is then in ``stderr``)."""
        proc = self.proc
        assert proc is not None and proc.stdin is not None and self._err_task is not None
        if not proc.stdin.is_closing():
            proc.stdin.close()
        self.stderr = await asyncio.wait_for(self._err_task, TIMEOUT)
        return await asyncio.wait_for(proc.wait(), TIMEOUT)

    def write(self, data: bytes) -> None:
        assert self.proc is not None and self.proc.stdin is not None
        self.proc.stdin.write(data)

    def send(self, *messages: dict[str, Any]) -> None:
        """Write these messages in one write."""
        self.write(b"".join(frame(m) for m in messages))

    def request(self, method: str, params: Any) -> int:
        self.ids += 1
        self.send(self.call(method, params, self.ids))
        return self.ids

    def call(self, method: str, params: Any, ident: int | None = None) -> dict[str, Any]:
        """A request message (a new id, unless given), not sent."""
        if ident is None:
            self.ids += 1
            ident = self.ids
        return {"jsonrpc": "2.0", "id": ident, "method": method, "params": params}

    async def read(self) -> dict[str, Any]:
        """The next message the server writes."""
        assert self.proc is not None and self.proc.stdout is not None
        out = self.proc.stdout
        length = None
        while True:
            line = await asyncio.wait_for(out.readline(), TIMEOUT)
            if not line:
                raise EOFError("the server closed its output")
            if line in (b"\r\n", b"\n"):
                break
            name, _, value = line.decode("ascii").partition(":")
            if name.lower() == "content-length":
                length = int(value)
        assert length is not None
        message: dict[str, Any] = json.loads(await asyncio.wait_for(out.readexactly(length),
                                                                    TIMEOUT))
        return message

    async def response(self, ident: int | None) -> dict[str, Any]:
        """Read up to the answer to request ``ident`` (the messages before it are dropped)."""
        while True:
            message = await self.read()
            if "method" not in message and message.get("id") == ident:
                return message


def did_change(path: Path, version: int, text: str) -> dict[str, Any]:
    """A didChange notification replacing the whole text."""
    return {"jsonrpc": "2.0", "method": "textDocument/didChange", "params": {
        "textDocument": {"uri": uri(path), "version": version},
        "contentChanges": [{"text": text}]}}


def did_open(path: Path, text: str | None = None) -> dict[str, Any]:
    return {"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {
        "textDocument": {"uri": uri(path), "languageId": "xml", "version": 1,
                         "text": path.read_text(encoding="utf-8") if text is None else text}}}
