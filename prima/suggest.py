"""Did you mean ...? The name a misspelt one is closest to, for every place a name is
looked up: Commands, states, elements, command-line options, debugger breakpoints.

Imports nothing of PRIMA (any module may use it).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Iterable, Sequence
from typing import Any, NoReturn

__all__ = ["SuggestingParser", "did_you_mean", "similar", "unrecognized"]


def close(a: str, b: str) -> bool:
    """Whether ``a`` may be a misspelling of ``b``: one character added, dropped or
    changed, or two neighbours swapped."""
    if a == b or abs(len(a) - len(b)) > 1:
        return False
    if len(a) == len(b):
        diffs = [i for i, (x, y) in enumerate(zip(a, b, strict=False)) if x != y]
        swapped = len(diffs) == 2 and diffs[1] == diffs[0] + 1 and \
            a[diffs[0]] == b[diffs[1]] and a[diffs[1]] == b[diffs[0]]
        return len(diffs) == 1 or swapped
    short, long_ = sorted((a, b), key=len)
    return any(long_[:i] + long_[i + 1:] == short for i in range(len(long_)))


def similar(name: str, names: Iterable[str]) -> str | None:
    """The first of ``names`` that ``name`` may be a misspelling of (the same but for case,
    or :func:`close` to a name of two characters or more), if any."""
    folded = name.casefold()
    return next((n for n in names if (n != name and n.casefold() == folded)
                 or (len(name) >= 2 and close(n, name))), None)


def did_you_mean(name: str, names: Iterable[str], quote: str = "'") -> str:
    """``"; did you mean 'x'?"`` for the name ``name`` may be a misspelling of, else ""."""
    found = similar(name, names)
    return f"; did you mean {quote}{found}{quote}?" if found is not None else ""


def _options(parser: argparse.ArgumentParser) -> list[str]:
    return [o for action in parser._actions for o in action.option_strings if o.startswith("--")]


def unrecognized(extra: Sequence[str], parser: argparse.ArgumentParser) -> str:
    """argparse's message for arguments ``parser`` does not know, with the option each
    misspelt one may be (``--jiter``: ``--jitter``; ``--jitter=5`` too)."""
    options = _options(parser)
    hints = []
    for word in extra:
        name = word.split("=", 1)[0]
        meant = similar(name, options) if name.startswith("-") else None
        if meant is None and name.startswith("-") and not name.startswith("--"):
            meant = similar("-" + name, options)  # -jitter: --jitter
        if meant is not None:
            hints.append(f"{name}: did you mean {meant}?")
    said = f"unrecognized arguments: {' '.join(extra)}"
    return said + (f" ({'; '.join(hints)})" if hints else "")


class SuggestingParser(argparse.ArgumentParser):
    """An argument parser whose errors say which name a misspelt one may be: an option
    given (``--jiter 5`` leaves ``--jitter`` missing: did you mean it?) and a choice
    (``prima valdiate``, ``--format jsnol``). ``given`` is the command line, set before
    parsing; ``error_word`` the word its error messages begin with (coloured for a
    terminal)."""

    given: Sequence[str] = ()
    error_word = "error"
    escape: Callable[[str], str] | None = None
    """What makes an error message safe for a terminal (what it quotes of the command
    line, a file's name, may hold an escape sequence), set with ``error_word``."""

    def error(self, message: str) -> NoReturn:
        if message.startswith("the following arguments are required"):
            unknown = [w for w in self.given if w.startswith("-")
                       and w.split("=", 1)[0] not in _options(self)]
            hint = unrecognized(unknown, self) if unknown else ""
            if "did you mean" in hint:
                message += hint[hint.index(" ("):]
        if self.escape is not None:
            message = self.escape(message)
        self.print_usage(sys.stderr)
        self.exit(2, f"{self.prog}: {self.error_word}: {message}\n")

    def _check_value(self, action: argparse.Action, value: Any) -> None:
        try:
            super()._check_value(action, value)
        except argparse.ArgumentError as exc:
            hint = did_you_mean(value, map(str, action.choices or ())) \
                if isinstance(value, str) else ""
            raise argparse.ArgumentError(action, exc.message + hint) from None
