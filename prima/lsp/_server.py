"""The protocol: pygls serves :class:`~prima.lsp._features.Features` and the
workspace's diagnostics (:mod:`prima.lsp._schedule`) over stdio (:mod:`prima.lsp._stream`).

Offsets inside PRIMA are Python string indices; the protocol counts lines (at
``\\n``, ``\\r\\n`` or ``\\r``) and UTF-16 code units by default. A buffer's line
starts are found once per version; pygls's position codec converts the
characters of the one line concerned, so a line with an emoji or a CJK character
still lands on the right character, and no request walks the whole buffer.
"""

from __future__ import annotations

import re
import sys
from bisect import bisect_right
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, TextIO
from urllib.parse import unquote

from lsprotocol import types
from pygls.lsp.server import LanguageServer
from pygls.protocol import LanguageServerProtocol
from pygls.protocol.language_server import lsp_method
from pygls.uris import from_fs_path, to_fs_path
from pygls.workspace import PositionCodec

from prima import __version__
from prima.collecting import settle
from prima.errors import Problem, Severity
from prima.lsp._features import Features, Item, Target
from prima.lsp._schedule import DEBOUNCE, Diagnostics
from prima.lsp._stream import MAX_MESSAGE
from prima.lsp._workspace import Buffer, Workspace, resolved

__all__ = ["MAX_OPEN", "TRIGGERS", "PrimaServer", "build_server"]

MAX_OPEN = 1_000
"""Documents the server holds open at once (each of at most ``MAX_MESSAGE`` bytes): one
the editor opens beyond them is not held nor checked (one line on stderr says so) until
another is closed; requests about it are answered empty, as for any file not open."""

TRIGGERS = ["<", '"', "'", "(", ",", ".", "=", " ", ":", "[", "{"]
"""Characters after which an editor asks for completions on its own."""

_KINDS = {
    "command": types.CompletionItemKind.Function,
    "function": types.CompletionItemKind.Function,
    "argument": types.CompletionItemKind.Property,
    "attribute": types.CompletionItemKind.Property,
    "field": types.CompletionItemKind.Field,
    "value": types.CompletionItemKind.Value,
    "variable": types.CompletionItemKind.Variable,
    "event": types.CompletionItemKind.Event,
    "state": types.CompletionItemKind.EnumMember,
    "label": types.CompletionItemKind.Reference,
    "place": types.CompletionItemKind.Constant,
    "element": types.CompletionItemKind.Class,
    "keyword": types.CompletionItemKind.Keyword,
    "file": types.CompletionItemKind.File,
}
_SEVERITY = {Severity.ERROR: types.DiagnosticSeverity.Error,
             Severity.WARNING: types.DiagnosticSeverity.Warning}
_SNIPPET = re.compile(r"\$\{\d+:([^}]*)\}|\$\d+")
_TOKEN = re.compile(r"[\w\-.:]+")
_LINE_END = re.compile(r"[\r\n]")


class _Protocol(LanguageServerProtocol):
    """pygls's protocol, holding at most :data:`MAX_OPEN` documents open."""

    _server: PrimaServer

    @lsp_method(types.TEXT_DOCUMENT_DID_OPEN)
    def lsp_text_document__did_open(self, params: types.DidOpenTextDocumentParams
                                    ) -> Iterator[Any]:
        held = self.workspace.text_documents
        uri = params.text_document.uri
        if unquote(uri) not in held and len(held) >= MAX_OPEN:
            self._server.refused(uri)
            return
        yield from super().lsp_text_document__did_open(params)

    @lsp_method(types.TEXT_DOCUMENT_DID_CHANGE)
    def lsp_text_document__did_change(self, params: types.DidChangeTextDocumentParams
                                      ) -> Iterator[Any]:
        uri = params.text_document.uri
        held = self.workspace.text_documents
        if unquote(uri) in held:  # (else: refused)
            yield from super().lsp_text_document__did_change(params)
            doc = held.get(unquote(uri))
            if doc is not None and _outgrown(doc.source):
                self.workspace.remove_text_document(uri)
                self._server.outgrown(uri)


class PrimaServer(LanguageServer):
    """A language server with PRIMA's workspace, and its diagnostics' schedule."""

    def __init__(self, robot: Path | None, *, debounce: float = DEBOUNCE,
                 err: TextIO | None = None) -> None:
        super().__init__("prima", __version__, protocol_cls=_Protocol,
                         text_document_sync_kind=types.TextDocumentSyncKind.Incremental)
        self.robot = robot
        self.err = err or sys.stderr
        """Where what goes wrong is said, one line each."""
        self.prima: Workspace | None = None
        self._features: Features | None = None
        self.diagnostics = Diagnostics(self.check, debounce=debounce, failed=self._failed)
        self.keys: dict[str, Path] = {}
        """Each open document's resolved path."""
        self.depends: dict[str, frozenset[Path]] = {}
        """What each open document's last check depended on."""
        self._settled = False
        self._refusing = False
        """A document was opened beyond :data:`MAX_OPEN` since one was last closed."""

    def files(self) -> Workspace:
        """PRIMA's view of the workspace, made on first need (after initialize)."""
        if self.prima is None:
            roots = [Path(to_fs_path(f.uri) or ".") for f in self.workspace.folders.values()]
            if not roots and self.workspace.root_path:
                roots = [Path(self.workspace.root_path)]
            self.prima = Workspace(roots, self.robot)
        return self.prima

    def features(self) -> Features:
        if self._features is None:
            self._features = Features(self.files())
        return self._features

    def buffer(self, uri: str) -> Buffer | None:
        """An open document's buffer, in step with the editor's text (None: not open)."""
        doc = self.workspace.text_documents.get(uri)
        if doc is None:
            return None
        return self.files().open(_path(uri), doc.source)

    # ---- diagnostics

    def changed(self, uri: str, delay: float | None = None) -> None:
        """``uri`` changed: check it and the open documents whose problems it may change."""
        files = self.files()
        affected = files.affected(_path(uri), [(self.keys[u], on) for u, on
                                                in self.depends.items() if u in self.keys])
        self.diagnostics.due([u for u, key in self.keys.items() if key in affected], delay)

    def check(self, uri: str) -> Callable[[], None] | None:
        """Check the open document ``uri`` as it is now; what publishes its problems."""
        doc = self.workspace.text_documents.get(uri)
        buffer = self.buffer(uri)
        if doc is None or buffer is None:
            return None
        checked = self.files().check(_path(uri))
        if not self._settled:  # what the first check loaded stays: never scanned again
            self._settled = True
            settle()
        self.depends[uri] = checked.depends
        codec, version = doc.position_codec, doc.version
        found = [diagnostic(buffer, p, codec) for p in checked.problems]

        def publish() -> None:
            if uri in self.keys:  # (not closed meanwhile)
                self.text_document_publish_diagnostics(types.PublishDiagnosticsParams(
                    uri=uri, version=version, diagnostics=found))
        return publish

    def closed(self, uri: str) -> None:
        """``uri`` is closed: its diagnostics cleared, the documents that read it checked
        again (they now read the file on disk)."""
        path = _path(uri)
        self._refusing = False
        self.files().close(path)
        self.features().drop(path)
        self.diagnostics.drop(uri)
        self.depends.pop(uri, None)
        if self.keys.pop(uri, None) is not None:
            self.changed(uri)
        self.text_document_publish_diagnostics(types.PublishDiagnosticsParams(
            uri=uri, diagnostics=[]))

    def snippets(self) -> bool:
        """Whether the client takes completions as snippets."""
        caps: Any = self.client_capabilities.text_document
        return bool(caps and caps.completion and caps.completion.completion_item
                    and caps.completion.completion_item.snippet_support)

    def refused(self, uri: str) -> None:
        """The editor opened ``uri`` beyond :data:`MAX_OPEN` documents: said once until a
        document is closed."""
        if not self._refusing:
            self._refusing = True
            print(f"prima lsp: {MAX_OPEN:,} documents are open: {uri} and any opened after "
                  "it are not checked (close one, then open them again)", file=self.err,
                  flush=True)

    def outgrown(self, uri: str) -> None:
        """The editor's changes made ``uri`` longer than :data:`MAX_MESSAGE` bytes: it is
        no longer held nor checked (as if closed) until it is opened again."""
        print(f"prima lsp: {uri} grew past {MAX_MESSAGE:,} bytes: it is not held nor "
              "checked (close it, then open it again)", file=self.err, flush=True)
        self.closed(uri)

    def _failed(self, uri: str, exc: Exception) -> None:
        print(f"prima lsp: checking {uri} failed: {type(exc).__name__}: {exc}",
              file=self.err, flush=True)


def _outgrown(source: str) -> bool:
    """A document's text is longer than :data:`MAX_MESSAGE` bytes (as UTF-8)."""
    return len(source) > MAX_MESSAGE // 4 and len(source.encode("utf-8", "surrogatepass")) \
        > MAX_MESSAGE


def _path(uri: str) -> Path:
    return Path(to_fs_path(uri) or uri)


def position(buffer: Buffer, offset: int, codec: PositionCodec) -> types.Position:
    """An offset of the buffer as the protocol counts it (lines; the client's units)."""
    starts = buffer.line_starts
    offset = min(max(offset, 0), len(buffer.text))
    line = bisect_right(starts, offset) - 1
    return types.Position(line, codec.client_num_units(buffer.text[starts[line]:offset]))


def offset(buffer: Buffer, at: types.Position, codec: PositionCodec) -> int:
    """A position the client gives as an offset of the buffer."""
    starts, text = buffer.line_starts, buffer.text
    if at.line >= len(starts):
        return len(text)
    start = starts[at.line]
    end = starts[at.line + 1] if at.line + 1 < len(starts) else len(text)
    line = text[start:end].rstrip("\r\n")
    found = codec.position_from_client_units([line], types.Position(0, at.character))
    return start + min(found.character, len(line))


def _range(buffer: Buffer, start: int, end: int, codec: PositionCodec) -> types.Range:
    return types.Range(position(buffer, start, codec), position(buffer, end, codec))


def diagnostic(buffer: Buffer, problem: Problem, codec: PositionCodec) -> types.Diagnostic:
    """A problem as the protocol says it: from its line and column (code points) to the
    end of the word there."""
    text = buffer.text
    at = buffer.offset_of(problem.line, problem.col)
    newline = _LINE_END.search(text, at)
    line_end = newline.start() if newline else len(text)
    word = _TOKEN.match(text, at + (1 if text[at:at + 1] == "<" else 0), line_end)
    end = min(max(word.end() if word else at + 1, at + 1), line_end) if line_end > at else at
    return types.Diagnostic(range=_range(buffer, at, end, codec), message=problem.message,
                            severity=_SEVERITY[problem.severity], source="prima")


def _plain(snippet: str) -> str:
    return _SNIPPET.sub(lambda m: m.group(1) or "", snippet)


def _completion(buffer: Buffer, item: Item, at: int, snippets: bool, rank: int,
                codec: PositionCodec) -> types.CompletionItem:
    text = item.insert if item.insert is not None else item.label
    snippet = item.snippet and snippets
    if item.snippet and not snippets:
        text = _plain(text)
    return types.CompletionItem(
        label=item.label, kind=_KINDS.get(item.kind), detail=item.detail or None,
        documentation=types.MarkupContent(types.MarkupKind.Markdown, item.doc)
        if item.doc else None,
        text_edit=types.TextEdit(_range(buffer, item.start, at, codec), text),
        insert_text_format=types.InsertTextFormat.Snippet if snippet
        else types.InsertTextFormat.PlainText,
        sort_text=f"{rank:04d}")


def _location(ls: PrimaServer, target: Target, codec: PositionCodec) -> types.Location:
    uri = from_fs_path(str(target.path)) or str(target.path)
    buffer = ls.files().buffer(target.path)  # read within PRIMA's bound, if not open
    if buffer is None:
        return types.Location(uri, types.Range(types.Position(0, 0), types.Position(0, 0)))
    return types.Location(uri, _range(buffer, target.start, target.end, codec))


def build_server(robot: Path | None = None, *, debounce: float = DEBOUNCE,
                 err: TextIO | None = None) -> PrimaServer:
    """The server: diagnostics as ``prima validate`` words them, completion, hover and
    go-to-definition for PXML documents, robot profiles, scenarios and maps."""
    server = PrimaServer(robot, debounce=debounce, err=err)

    @server.feature(types.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: PrimaServer, params: types.DidOpenTextDocumentParams) -> None:
        uri = params.text_document.uri
        ls.keys[uri] = resolved(_path(uri))
        ls.buffer(uri)
        ls.changed(uri, delay=0.0)

    @server.feature(types.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: PrimaServer, params: types.DidChangeTextDocumentParams) -> None:
        uri = params.text_document.uri
        if uri in ls.keys:
            ls.buffer(uri)
            ls.changed(uri)

    @server.feature(types.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls: PrimaServer, params: types.DidSaveTextDocumentParams) -> None:
        ls.files().forget()  # (a file saved for the first time may be a new scenario)

    @server.feature(types.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: PrimaServer, params: types.DidCloseTextDocumentParams) -> None:
        ls.closed(params.text_document.uri)

    @server.feature(types.WORKSPACE_DID_CHANGE_WATCHED_FILES)
    def watched(ls: PrimaServer, params: types.DidChangeWatchedFilesParams) -> None:
        ls.files().forget()
        for change in params.changes:
            ls.changed(change.uri)

    @server.feature(types.TEXT_DOCUMENT_COMPLETION,
                    types.CompletionOptions(trigger_characters=TRIGGERS))
    def completion(ls: PrimaServer, params: types.CompletionParams) -> types.CompletionList:
        uri = params.text_document.uri
        buffer = ls.buffer(uri)
        if buffer is None:
            return types.CompletionList(is_incomplete=False, items=[])
        codec = ls.workspace.position_codec
        at = offset(buffer, params.position, codec)
        items = ls.features().complete(_path(uri), at)
        snippets = ls.snippets()
        return types.CompletionList(is_incomplete=False, items=[
            _completion(buffer, item, at, snippets, rank, codec)
            for rank, item in enumerate(items)])

    @server.feature(types.TEXT_DOCUMENT_HOVER)
    def hover(ls: PrimaServer, params: types.HoverParams) -> types.Hover | None:
        uri = params.text_document.uri
        buffer = ls.buffer(uri)
        if buffer is None:
            return None
        codec = ls.workspace.position_codec
        found = ls.features().hover(_path(uri), offset(buffer, params.position, codec))
        if found is None:
            return None
        return types.Hover(types.MarkupContent(types.MarkupKind.Markdown, found.text),
                           _range(buffer, found.start, found.end, codec))

    @server.feature(types.TEXT_DOCUMENT_DEFINITION)
    def definition(ls: PrimaServer, params: types.DefinitionParams) -> list[types.Location]:
        uri = params.text_document.uri
        buffer = ls.buffer(uri)
        if buffer is None:
            return []
        codec = ls.workspace.position_codec
        targets = ls.features().definition(_path(uri), offset(buffer, params.position, codec))
        return [_location(ls, t, codec) for t in targets]

    return server
