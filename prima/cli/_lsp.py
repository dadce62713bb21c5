"""``prima lsp``: the language server on stdio (:mod:`prima.lsp`)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TextIO

from prima.cli._common import Command, Commands, _missing_extra, _usage


def add(commands: Commands) -> None:
    lsp = commands.add_parser(
        "lsp",
        help="serve the language server protocol on stdio (for editors)",
        description="A language server for PXML documents, robot profiles, scenarios and "
                    "maps: diagnostics as prima validate words them, completion, hover and "
                    "go-to-definition (docs/editors.md). An editor starts it; it talks "
                    "the Language Server Protocol on stdin and stdout. Needs the lsp extra: "
                    "pip install 'prima[lsp]'.",
    )
    lsp.add_argument("--robot", metavar="PROFILE",
                     help="robot hardware profile documents are checked against, over a "
                          "scenario's (as prima validate --robot; default: the scenario's "
                          "that runs the document, else the home robot)")


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    problem = _missing_extra("pygls", "pygls", "lsp")
    if problem is None and args.robot is not None and not Path(args.robot).is_file():
        problem = f"no such file: {args.robot}"
    if problem:
        return _usage("lsp", problem, err)
    from prima.lsp import serve

    return serve(Path(args.robot).resolve() if args.robot else None, err=err)


COMMAND = Command("lsp", add, execute)
