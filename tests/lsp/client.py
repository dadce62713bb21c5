"""A language client for the tests: ``prima lsp`` in a process of its own, over stdio.

pygls's own client speaks the protocol; this wraps the few requests the tests
make and collects the diagnostics the server publishes.
"""

from __future__ import annotations

import asyncio
import sys
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

        @self.client.feature(types.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS)
        def published(params: types.PublishDiagnosticsParams) -> None:
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
