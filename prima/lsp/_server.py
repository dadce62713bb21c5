"""The protocol: pygls serves :class:`~prima.lsp._features.Features` and the
workspace's diagnostics over stdio.

Offsets inside PRIMA are Python string indices; the protocol counts UTF-16 code
units by default. pygls's document position codec converts both ways, so a
line with an emoji or a CJK character still lands on the right character.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from lsprotocol import types
from pygls.lsp.server import LanguageServer
from pygls.uris import from_fs_path, to_fs_path
from pygls.workspace import TextDocument

from prima import __version__
from prima.errors import Problem, Severity
from prima.lsp._features import Features, Item, Target
from prima.lsp._workspace import Workspace

__all__ = ["TRIGGERS", "build_server"]

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


class PrimaServer(LanguageServer):
    """A language server with PRIMA's workspace."""

    def __init__(self, robot: Path | None) -> None:
        super().__init__("prima", __version__,
                         text_document_sync_kind=types.TextDocumentSyncKind.Incremental)
        self.robot = robot
        self.prima: Workspace | None = None

    def files(self) -> Workspace:
        """PRIMA's view of the workspace, made on first need (after initialize)."""
        if self.prima is None:
            roots = [Path(to_fs_path(f.uri) or ".") for f in self.workspace.folders.values()]
            if not roots and self.workspace.root_path:
                roots = [Path(self.workspace.root_path)]
            self.prima = Workspace(roots, self.robot)
        return self.prima

    def features(self) -> Features:
        return Features(self.files())


def _path(uri: str) -> Path:
    return Path(to_fs_path(uri) or uri)


def _position(doc: TextDocument, offset: int) -> types.Position:
    return doc.client_position_at_offset(offset)


def _range(doc: TextDocument, start: int, end: int) -> types.Range:
    return types.Range(_position(doc, start), _position(doc, end))


def diagnostic(doc: TextDocument, problem: Problem) -> types.Diagnostic:
    """A problem as the protocol says it: from its line and column (code points) to the
    end of the word there."""
    lines = doc.lines
    line = min(max(problem.line - 1, 0), max(len(lines) - 1, 0))
    text = lines[line].rstrip("\r\n") if lines else ""
    col = min(max(problem.col - 1, 0), len(text))
    word = _TOKEN.match(text, col + (1 if text[col:col + 1] == "<" else 0))
    end = max(word.end() if word else col + 1, col + 1)
    start_at = types.Position(line, col)
    end_at = types.Position(line, min(end, len(text)) if text else col)
    codec = doc.position_codec
    return types.Diagnostic(
        range=types.Range(codec.position_to_client_units(lines, start_at),
                          codec.position_to_client_units(lines, end_at)),
        message=problem.message, severity=_SEVERITY[problem.severity], source="prima")


def _plain(snippet: str) -> str:
    return _SNIPPET.sub(lambda m: m.group(1) or "", snippet)


def _completion(doc: TextDocument, item: Item, offset: int, snippets: bool,
                rank: int) -> types.CompletionItem:
    text = item.insert if item.insert is not None else item.label
    snippet = item.snippet and snippets
    if item.snippet and not snippets:
        text = _plain(text)
    return types.CompletionItem(
        label=item.label, kind=_KINDS.get(item.kind), detail=item.detail or None,
        documentation=types.MarkupContent(types.MarkupKind.Markdown, item.doc)
        if item.doc else None,
        text_edit=types.TextEdit(_range(doc, item.start, offset), text),
        insert_text_format=types.InsertTextFormat.Snippet if snippet
        else types.InsertTextFormat.PlainText,
        sort_text=f"{rank:04d}")


def _location(ls: PrimaServer, target: Target) -> types.Location:
    uri = from_fs_path(str(target.path)) or str(target.path)
    doc = ls.workspace.get_text_document(uri)
    if not doc.source and target.path.is_file():
        doc = TextDocument(uri, target.path.read_text(encoding="utf-8"))
    return types.Location(uri, _range(doc, target.start, target.end))


def build_server(robot: Path | None = None) -> PrimaServer:
    """The server: diagnostics as ``prima validate`` words them, completion, hover and
    go-to-definition for PXML documents, robot profiles, scenarios and maps."""
    server = PrimaServer(robot)

    def publish(ls: PrimaServer, uris: Iterable[str]) -> None:
        files = ls.files()
        for uri in uris:
            doc = ls.workspace.get_text_document(uri)
            files.open(_path(uri), doc.source)
            problems = files.problems(_path(uri))
            ls.text_document_publish_diagnostics(types.PublishDiagnosticsParams(
                uri=uri, version=doc.version,
                diagnostics=[diagnostic(doc, p) for p in problems]))

    def changed(ls: PrimaServer, uri: str) -> None:
        files = ls.files()
        doc = ls.workspace.get_text_document(uri)
        buffer = files.open(_path(uri), doc.source)
        others = [u for u in ls.workspace.text_documents if u != uri]
        # a scenario, a map or a profile changes what is in force for the open documents
        publish(ls, [uri, *(others if buffer.namespace != "urn:prima:pxml:1" else [])])

    @server.feature(types.TEXT_DOCUMENT_DID_OPEN)
    def did_open(ls: PrimaServer, params: types.DidOpenTextDocumentParams) -> None:
        changed(ls, params.text_document.uri)

    @server.feature(types.TEXT_DOCUMENT_DID_CHANGE)
    def did_change(ls: PrimaServer, params: types.DidChangeTextDocumentParams) -> None:
        changed(ls, params.text_document.uri)

    @server.feature(types.TEXT_DOCUMENT_DID_SAVE)
    def did_save(ls: PrimaServer, params: types.DidSaveTextDocumentParams) -> None:
        ls.files().forget()
        changed(ls, params.text_document.uri)

    @server.feature(types.TEXT_DOCUMENT_DID_CLOSE)
    def did_close(ls: PrimaServer, params: types.DidCloseTextDocumentParams) -> None:
        ls.files().close(_path(params.text_document.uri))
        ls.text_document_publish_diagnostics(types.PublishDiagnosticsParams(
            uri=params.text_document.uri, diagnostics=[]))

    @server.feature(types.WORKSPACE_DID_CHANGE_WATCHED_FILES)
    def watched(ls: PrimaServer, params: types.DidChangeWatchedFilesParams) -> None:
        ls.files().forget()
        publish(ls, list(ls.workspace.text_documents))

    @server.feature(types.TEXT_DOCUMENT_COMPLETION,
                    types.CompletionOptions(trigger_characters=TRIGGERS))
    def completion(ls: PrimaServer, params: types.CompletionParams) -> types.CompletionList:
        uri = params.text_document.uri
        doc = ls.workspace.get_text_document(uri)
        ls.files().open(_path(uri), doc.source)
        offset = doc.offset_at_position(params.position)
        caps: Any = ls.client_capabilities.text_document
        snippets = bool(caps and caps.completion and caps.completion.completion_item
                        and caps.completion.completion_item.snippet_support)
        items = ls.features().complete(_path(uri), offset)
        return types.CompletionList(is_incomplete=False, items=[
            _completion(doc, item, offset, snippets, rank) for rank, item in enumerate(items)])

    @server.feature(types.TEXT_DOCUMENT_HOVER)
    def hover(ls: PrimaServer, params: types.HoverParams) -> types.Hover | None:
        uri = params.text_document.uri
        doc = ls.workspace.get_text_document(uri)
        ls.files().open(_path(uri), doc.source)
        found = ls.features().hover(_path(uri), doc.offset_at_position(params.position))
        if found is None:
            return None
        return types.Hover(types.MarkupContent(types.MarkupKind.Markdown, found.text),
                           _range(doc, found.start, found.end))

    @server.feature(types.TEXT_DOCUMENT_DEFINITION)
    def definition(ls: PrimaServer, params: types.DefinitionParams) -> list[types.Location]:
        uri = params.text_document.uri
        doc = ls.workspace.get_text_document(uri)
        ls.files().open(_path(uri), doc.source)
        targets = ls.features().definition(_path(uri), doc.offset_at_position(params.position))
        return [_location(ls, t) for t in targets]

    return server

