"""Shell completion of ``prima``'s command line (argcomplete): commands, options, their
choices, policy names and the files each argument takes.

The shell runs ``prima`` itself at each Tab, with ``_ARGCOMPLETE`` and the line so
far in its environment (the code ``prima completion SHELL`` prints installs that);
:func:`prima.cli.main` then calls :func:`autocomplete` before it parses anything,
which answers and exits. Only then is this module (and argcomplete) imported: a
command that runs does not pay for it.
"""

from __future__ import annotations

import argparse
import os

import argcomplete
from argcomplete.shell_integration import shellcode as _shellcode
from collections.abc import Callable, Iterable, Sequence
from typing import TextIO

from prima.vocab import POLICIES

__all__ = ["Files", "attach", "autocomplete", "policies", "shellcode"]


class Files:
    """Completes the files whose names end in one of ``suffixes`` (any file without
    them), and folders to go into."""

    def __init__(self, *suffixes: str, folders_only: bool = False) -> None:
        self.suffixes = suffixes
        self.folders_only = folders_only

    def __call__(self, prefix: str, **_: object) -> list[str]:
        folder, start = os.path.split(prefix)
        try:
            names = sorted(os.listdir(os.path.expanduser(folder) or "."))
        except OSError:
            return []
        out = []
        for name in names:
            if not name.startswith(start) or (name.startswith(".") and not start):
                continue
            path = os.path.join(folder, name)
            if os.path.isdir(os.path.expanduser(path)):
                out.append(path + "/")
            elif not self.folders_only and (not self.suffixes or name.endswith(self.suffixes)):
                out.append(path)
        return out


def policies(prefix: str, **_: object) -> list[str]:
    """``--policy``'s values: each policy (and ``all``), on and off."""
    return [f"{name}={state}" for name in ("all", *POLICIES) for state in ("on", "off")
            if f"{name}={state}".startswith(prefix)]


Completer = Callable[..., Iterable[str]]

_ANY = Files()
_SCENARIO = Files(".xml")
_DOCUMENT = Files(".pxml")
_RUN = Files(".jsonl", ".xml")
_BY_METAVAR: dict[str, Completer] = {
    "SCENARIO": _SCENARIO, "DOC": _DOCUMENT, "PROFILE": Files(".xml"), "MAP": Files(".xml"),
    "RUN": _RUN, "INPUT": _RUN, "FILE": _ANY, "DIR": Files(folders_only=True),
    "NAME=on|off": policies,
}
"""What an argument takes, by the name its help gives its value."""
_BY_COMMAND: dict[tuple[str, str], Completer] = {
    ("validate", "paths"): Files(".pxml", ".xml"),
    ("test", "paths"): _SCENARIO,
    ("judge", "paths"): _RUN,
    ("show", "out"): Files(".html"),
    ("plot", "out"): Files(".svg", ".png", ".pdf", ".gif"),
    ("live", "inputs"): Files(".xml", ".pxml"),
}
"""Where one command's argument takes files of its own."""


def attach(parser: argparse.ArgumentParser) -> None:
    """Give every argument of ``parser``'s commands that takes a file or a policy its
    completer (argcomplete reads an action's ``completer``)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                for each in sub._actions:
                    completer = _BY_COMMAND.get((name, each.dest)) or \
                        _BY_METAVAR.get(str(each.metavar))
                    if completer is not None:
                        each.completer = completer


def autocomplete(parser: argparse.ArgumentParser, exit_method: Callable[[int], object] = os._exit,
                 output: TextIO | None = None) -> None:
    """Answer the shell's completion request in the environment, then exit (argcomplete;
    options are offered once a ``-`` is typed; ``exit_method`` and ``output``: for a
    test)."""
    attach(parser)
    argcomplete.autocomplete(parser, always_complete_options=False, exit_method=exit_method,
                             output_stream=output)


def shellcode(shell: str, executables: Sequence[str] = ("prima",)) -> str:
    """The code that makes ``shell`` complete ``prima`` (argcomplete's)."""
    return _shellcode(list(executables), shell=shell)
