"""``prima lsp``: a language server for PXML documents, robot profiles, scenarios and maps.

An editor starts ``prima lsp`` and talks to it over stdio (the Language Server
Protocol). The server

- checks each file as you type exactly as ``prima validate`` does (the same
  loader and validator, the same messages, did-you-mean included; a document
  with the first scenario of the workspace that runs it, so with that
  scenario's robot and map);
- completes the Commands of the robot in force inside ``<chain>`` (with their
  arguments, and the map's places, the robot's gestures, the document's grammars
  and variables as their values), state ids in ``<goto>``, events and their
  fields in ``<on event>`` and after ``event.``, Command ids in ``of``, the
  places of the scenario's map in a scenario, and the elements and attributes
  the schemas allow;
- shows on hover the documentation of every element, attribute and Command,
  from the schemas and the Command catalog (the one place each is written);
- goes to the definition of a state, a Command id (a label), a variable, a
  grammar, a timer, a place on the map, a file a scenario names.

A server, apart from the core: only ``prima lsp`` imports it, and it needs the
``lsp`` extra (``pip install 'prima[lsp]'``: pygls). Settings for VS Code and
Neovim: ``docs/editors.md``.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import IO, BinaryIO, TextIO

__all__ = ["serve"]


def serve(robot: Path | None = None, *, stdin: IO[bytes] | None = None,
          stdout: BinaryIO | None = None, err: TextIO | None = None) -> int:
    """Serve the protocol on stdin and stdout until the editor says exit (or the input
    ends); the exit status. What goes wrong with the client's messages is said on
    ``err``, one line each (``docs/editors.md``, *Bounds*)."""
    from prima.lsp._server import build_server
    from prima.lsp._stream import serve as serve_streams

    said = err or sys.stderr
    server = build_server(robot, err=said)
    return serve_streams(server, stdin or sys.stdin.buffer, stdout or sys.stdout.buffer,
                         said, server.diagnostics.run)
