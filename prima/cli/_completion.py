"""``prima completion``: the code that makes a shell complete prima's command lines."""

from __future__ import annotations

import argparse
from typing import TextIO

from prima.cli._common import EXIT_OK, Command, Commands, _usage


def add(commands: Commands) -> None:
    completion = commands.add_parser(
        "completion",
        help="print the code that makes a shell complete prima's command lines",
        description="Print the code that makes SHELL complete prima's commands, options, "
                    "their values (policy names among them) and the files each argument "
                    "takes (argcomplete). Load it from the shell's start-up file: "
                    "eval \"$(prima completion bash)\" in ~/.bashrc (zsh: in ~/.zshrc, "
                    "after compinit); prima completion fish | source in fish's "
                    "config.fish.",
    )
    completion.add_argument("shell", choices=SHELLS, metavar="SHELL",
                            help=f"the shell: {', '.join(SHELLS)}")


SHELLS = ("bash", "zsh", "fish")
"""The shells ``prima completion`` writes the code for."""


def execute(args: argparse.Namespace, out: TextIO, err: TextIO) -> int:
    try:
        from prima.completion import shellcode
    except ImportError:
        return _usage("completion", "argcomplete is not installed (PRIMA needs it to "
                                    "complete): pip install argcomplete", err)
    out.write(shellcode(args.shell))
    return EXIT_OK


COMMAND = Command("completion", add, execute)
