"""Words a run carries, made safe for each place they are written to: one module for
every writer.

An application's utterances, a trace's names and a file's own name come from
strangers. Each writer passes them through the function for its medium, so no
text can forge a line, drive a terminal, end a script element or be read as markup
or mathematics:

- :func:`terminal`: a line of text for a terminal or a text file (the text trace,
  ``prima debug``, messages): C0 and C1 control characters, DEL, the Unicode line
  and paragraph separators, the bidirectional controls (U+202E, U+200F, ...: they
  would reorder the rest of a row) and undecodable bytes of a file name as escapes;
- :func:`json_line`: one JSON value on one line (the jsonl trace, the Chrome
  trace): nothing any reader takes for a line break (U+0085, U+2028, U+2029 are
  escaped, as JSON allows), nothing a UTF-8 file cannot hold;
- :func:`script_json`: JSON inside an HTML ``<script>`` element (``prima show``):
  no ``<``, ``>`` or ``&``, so neither ``</script>`` nor ``<!--`` can end or
  swallow the element;
- :func:`markup`: text inside HTML or Plotly's labels (which read some HTML);
- :data:`PLAIN_TEXT` (matplotlib's settings: ``$...$`` is not mathematics).

Imports nothing of PRIMA (any module may use it).
"""

from __future__ import annotations

import functools
import json
import os
import re
from typing import Any

__all__ = ["PLAIN_TEXT", "json_line", "markup", "script_json", "shown_path", "terminal",
           "unshowable"]

_TERMINAL = ("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u2028-\u202e\u2066-\u2069"
             "\ud800-\udfff]")
"""What :func:`terminal` escapes: C0, DEL and C1 controls, the line and paragraph
separators, the bidirectional controls (U+061C, U+200E, U+200F, U+202A to U+202E,
U+2066 to U+2069: they reorder what a terminal shows after them) and undecodable bytes.

(This module's patterns are compiled on their first use (:func:`_re`): every command
imports this module, and compiling them all would cost each command's start about a
millisecond, most of them never used.)"""
_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


@functools.cache
def _re(source: str) -> re.Pattern[str]:
    """``source`` compiled, on its first use: ``re.sub(source, ...)`` would find it in
    :mod:`re`'s own cache, but by Python code that costs each call as much as the
    search (a text trace escapes every row)."""
    return re.compile(source)


def _escape_one(match: re.Match[str]) -> str:
    c = match.group()
    if c in _NAMED:
        return _NAMED[c]
    code = ord(c)
    if 0xDC80 <= code <= 0xDCFF:  # a byte of a file name that is not UTF-8 (surrogateescape)
        return f"\\x{code - 0xDC00:02x}"
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}"


def unshowable(text: str) -> str | None:
    """The first character of ``text`` that :func:`terminal` escapes (a control, a line
    or paragraph separator, a bidirectional control, an undecodable byte), or None: a
    place that takes words to show as they are refuses them."""
    if text.isprintable():  # (no character :func:`terminal` escapes: see there)
        return None
    found = _re(_TERMINAL).search(text)
    return found.group() if found else None


def terminal(text: str) -> str:
    """``text`` on one line, safe for a terminal: control characters (C0, DEL, C1), the
    line and paragraph separators, the bidirectional controls and undecodable bytes as
    ``\\n``, ``\\x1b``, ``\\u2028``, ``\\u202e``, ``\\xff``... A document cannot forge a
    line, reorder one or send an escape sequence."""
    # (Every character it escapes is one Python calls unprintable: a control, a format
    # character, a separator or a surrogate. A text with none, almost every one, is
    # returned as it is at once: the pattern's search looks at each character in turn,
    # some 8,000 instructions for one row of the text trace.)
    if text.isprintable():
        return text
    return _re(_TERMINAL).sub(_escape_one, text)


def shown_path(path: str | os.PathLike[str]) -> str:
    """A file's name as a message shows it: a name that is not UTF-8 keeps its other
    characters, its bytes shown as ``\\xff``."""
    return terminal(os.fspath(path))


_JSON_UNSAFE = "[\u0085\u2028\u2029\ud800-\udfff]"
_SCRIPT_UNSAFE = "[<>&\u0085\u2028\u2029\ud800-\udfff]"


def _u(match: re.Match[str]) -> str:
    return f"\\u{ord(match.group()):04x}"


def json_line(value: object) -> str:
    """``value`` as JSON on one line (no newline at its end): non-ASCII kept as itself but
    for what a reader might split a line at or a UTF-8 file cannot hold."""
    return _re(_JSON_UNSAFE).sub(_u, json.dumps(value, ensure_ascii=False))


def script_json(value: object) -> str:
    """``value`` as compact JSON safe inside an HTML ``<script>`` element."""
    text = json.dumps(value, ensure_ascii=False, separators=(",", ":"))
    return _re(_SCRIPT_UNSAFE).sub(_u, text)


_SURROGATE = "[\ud800-\udfff]"


def markup(text: str) -> str:
    """Text shown as itself inside HTML (or a Plotly label); undecodable bytes of a file
    name as ``\\xff``."""
    import html  # (its entities table is large: only the pages and pictures need it)

    return html.escape(_re(_SURROGATE).sub(_escape_one, text))


PLAIN_TEXT: dict[Any, Any] = {"text.parse_math": False, "text.usetex": False}
"""matplotlib settings under which every text is drawn as itself: ``$x$`` is not
typeset (nor a parse error), whoever wrote it."""
