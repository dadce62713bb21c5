"""The base protocol on stdin and stdout, read with bounds.

A message is headers (``Content-Length: N``), an empty line, and N bytes of
JSON. :class:`Framer` cuts the client's byte stream into messages, holding at
most :data:`MAX_MESSAGE` bytes of one: a longer message is read past (never
held) and refused with an error, answered under the request's own id when its
first bytes name one. What cannot be a message (a header line longer than
:data:`MAX_HEADER_LINE`, one that is not ``Name: value``, headers without a
length) is skipped up to the next ``Content-Length`` header, and said on stderr.
Reading past a message also stops at such a header line: in valid JSON
``Content-Length: N`` can only be inside a string, and a string holds no raw
line break, so a client that declared more bytes than it sent is
understood again from its next message (a message's body is followed by the
next one's ``Content-Length`` header, on no line of its own). The only thing
that cannot be read again is a stream that ends inside a message: the server
says so and exits.

:func:`serve` runs a pygls server on it, on one thread: every message is
handled as it is read, and the diagnostics wait (:mod:`prima.lsp._schedule`)
for the input to be read first.
"""

from __future__ import annotations

import asyncio
import json
import logging
import re
import select
import threading
from collections.abc import Awaitable, Callable
from typing import IO, Any, BinaryIO, TextIO

from pygls.exceptions import JsonRpcException
from pygls.io_ import StdoutWriter
from pygls.lsp.server import LanguageServer

__all__ = ["MAX_HEADER_LINE", "MAX_MESSAGE", "Framer", "request_id", "serve"]

MAX_MESSAGE = 8 << 20
"""Most bytes of one message's body (8 MiB): room for the largest document PRIMA
reads (1 MiB) however a client escapes it in JSON."""

MAX_HEADER_LINE = 4096
"""Most bytes of one header line."""

_RESYNC = re.compile(rb"content-length:[ \t]*\d{1,18}[ \t]*\r?\n", re.I)
"""A header line: in a JSON body, ``Content-Length`` is in a string or an error, and a
string holds no raw line break, so this never matches inside a valid message."""
_TAIL = 64
"""Bytes kept back while reading past: the start of a header line cut between reads."""
_HEAD = 4096
"""How many first bytes of a refused message are kept, to find its id."""

INVALID_REQUEST = -32600
PARSE_ERROR = -32700


class Framer:
    """Cuts a byte stream into message bodies.

    ``message(body)`` is called with each body of at most :data:`MAX_MESSAGE`
    bytes; ``refused(length, head)`` for a longer one, with its first bytes (up
    to 4 KiB, once they are in); ``skipped(reason)`` when bytes that are no
    message begin to be skipped.
    """

    def __init__(self, message: Callable[[bytes], None], refused: Callable[[int, bytes], None],
                 skipped: Callable[[str], None], limit: int = MAX_MESSAGE) -> None:
        self._message = message
        self._refused = refused
        self._skipped = skipped
        self.limit = limit
        self._buf = bytearray()
        self._state = "headers"
        """``headers``, ``body``, ``refuse`` (reading past a long message) or ``skip``."""
        self._length: int | None = None
        self._headers = False
        self._left: int | None = None
        """Bytes still to read past (``refuse``); None while skipping to a header."""
        self._declared = 0
        self._head = bytearray()
        self._told = False

    def feed(self, data: bytes) -> None:
        """Take the next bytes of the stream; handle every message they complete."""
        self._buf += data
        while self._step():
            pass

    def ended(self) -> str | None:
        """What the stream's end cut short, if anything."""
        if self._state == "body":
            return (f"the client's stream ended inside a message ({len(self._buf):,} of "
                    f"{self._length or 0:,} bytes)")
        if self._state == "refuse":
            return "the client's stream ended inside a refused message"
        if self._state == "headers" and (self._headers or self._buf.strip()):
            return "the client's stream ended inside a message's headers"
        return None

    # ---- states

    def _step(self) -> bool:
        if self._state == "headers":
            return self._header()
        if self._state == "body":
            return self._body()
        return self._skip()

    def _header(self) -> bool:
        buf = self._buf
        end = buf.find(b"\n")
        if end < 0:
            if len(buf) > MAX_HEADER_LINE:
                self._start_skip(f"a header line longer than {MAX_HEADER_LINE:,} bytes")
                return True
            return False
        line = bytes(buf[:end]).rstrip(b"\r")
        del buf[:end + 1]
        if not line.strip():
            if not self._headers:
                return True  # a blank line between messages
            if self._length is None:
                self._start_skip("a message without a Content-Length header")
            elif self._length > self.limit:
                self._state, self._left, self._declared = "refuse", self._length, self._length
                self._head.clear()
                self._told = False
            else:
                self._state = "body"
            return True
        name, colon, value = line.partition(b":")
        if not colon or len(line) > MAX_HEADER_LINE:
            self._start_skip(f"a header line that is not 'Name: value' ({_shown(line)})")
            return True
        self._headers = True
        if name.strip().lower() == b"content-length":
            digits = value.strip()
            if not digits.isdigit() or len(digits) > 18:
                self._start_skip(f"Content-Length {_shown(digits)} is not a number of bytes")
                return True
            self._length = int(digits)
        return True

    def _body(self) -> bool:
        length = self._length or 0
        if len(self._buf) < length:
            return False
        body = bytes(self._buf[:length])
        del self._buf[:length]
        self._reset()
        self._message(body)
        return True

    def _start_skip(self, reason: str) -> None:
        self._skipped(reason)
        self._state, self._left = "skip", None
        self._length, self._headers = None, False

    def _skip(self) -> bool:
        buf = self._buf
        if self._left == 0:
            self._done_skipping()
            return True
        window = len(buf) if self._left is None else min(len(buf), self._left)
        if window == 0:
            return False
        found = _RESYNC.search(buf, 0, window)
        if found is not None:
            self._consume(found.start())
            self._done_skipping()
            return True
        keep = 0 if window == self._left else min(window, _TAIL)
        if window - keep <= 0:
            return False
        self._consume(window - keep)
        return True

    def _consume(self, n: int) -> None:
        if n <= 0:
            return
        if self._state == "refuse" and not self._told:
            self._head += self._buf[:min(n, _HEAD - len(self._head))]
            if len(self._head) >= _HEAD:
                self._tell()
        del self._buf[:n]
        if self._left is not None:
            self._left -= n

    def _tell(self) -> None:
        """Refuse the message being read past, once (as soon as its first bytes are in)."""
        if not self._told:
            self._told = True
            self._refused(self._declared, bytes(self._head))

    def _done_skipping(self) -> None:
        if self._state == "refuse":
            self._tell()
        self._reset()

    def _reset(self) -> None:
        self._state, self._length, self._headers, self._left = "headers", None, False, None
        self._head.clear()


def _shown(raw: bytes) -> str:
    text = raw[:40].decode("utf-8", "replace")
    return repr(text + ("..." if len(raw) > 40 else ""))


_TOKEN = re.compile(rb'"(?:[^"\\]|\\.)*"|[{}\[\]:,]|[^"{}\[\]:,\s]+|\s+', re.S)


def request_id(head: bytes) -> int | str | None:
    """The id of the request whose body begins with ``head``, when its first bytes give
    it at the top level beside a ``method`` (a notification or a response: None)."""
    depth = 0
    keys: dict[bytes, bytes] = {}
    key: bytes | None = None
    expect_value = False
    for m in _TOKEN.finditer(head):
        tok = m.group()
        if tok.isspace():
            continue
        if tok in (b"{", b"["):
            if depth == 1 and expect_value and key is not None:
                keys.setdefault(key, b"")
            depth += 1
            expect_value = False
        elif tok in (b"}", b"]"):
            depth -= 1
        elif depth == 1 and tok == b":":
            expect_value = True
        elif depth == 1 and tok == b",":
            key, expect_value = None, False
        elif depth == 1 and expect_value and key is not None:
            keys.setdefault(key, tok)
            expect_value = False
        elif depth == 1 and tok.startswith(b'"'):
            key = tok
    if b'"method"' not in keys:
        return None
    raw = keys.get(b'"id"', b"")
    try:
        value = json.loads(raw) if raw else None
    except ValueError:
        return None
    return value if isinstance(value, (int, str)) and not isinstance(value, bool) else None


class _Connection:
    """The server's side of the stream: messages in, error answers out."""

    def __init__(self, server: LanguageServer, writer: StdoutWriter, err: TextIO) -> None:
        self.server = server
        self.writer = writer
        self.err = err
        self.framer = Framer(self.message, self.refused, self.skipped)

    def say(self, text: str) -> None:
        print(f"prima lsp: {text}", file=self.err, flush=True)

    def answer_error(self, ident: int | str | None, code: int, message: str) -> None:
        body = json.dumps({"jsonrpc": "2.0", "id": ident,
                           "error": {"code": code, "message": message}}).encode("utf-8")
        self.writer.write(b"Content-Length: %d\r\n\r\n" % len(body) + body)

    def message(self, body: bytes) -> None:
        protocol = self.server.protocol
        try:
            message = json.loads(body, object_hook=protocol.structure_message)
        except JsonRpcException as exc:
            plain = _plain(body)
            if plain is not None and "method" in plain and "params" not in plain:
                self.message(json.dumps({**plain, "params": None}).encode())  # (allowed)
                return
            ident = _request_id_of(plain)
            self.say(f"a message the protocol does not allow: {exc.message}")
            if ident is not None:
                self.answer_error(ident, exc.code, exc.message)
            return
        except (ValueError, RecursionError) as exc:
            self.say(f"a message that is not JSON: {str(exc)[:200]}")
            self.answer_error(None, PARSE_ERROR, "not JSON")
            return
        if not hasattr(message, "jsonrpc"):
            self.say("a message that is not a JSON-RPC 2.0 message")
            self.answer_error(None, INVALID_REQUEST, "not a JSON-RPC 2.0 message")
            return
        try:
            protocol.handle_message(message)
        except (SystemExit, KeyboardInterrupt, BrokenPipeError):
            raise
        except Exception as exc:  # noqa: BLE001 - one line, and the server reads on
            self.say(f"a message could not be handled: {type(exc).__name__}: {exc}")

    def refused(self, length: int, head: bytes) -> None:
        text = (f"a message of {length:,} bytes refused: prima lsp reads messages of at most "
                f"{self.framer.limit:,} bytes (docs/editors.md)")
        self.say(text)
        self.answer_error(request_id(head), INVALID_REQUEST, text)

    def skipped(self, reason: str) -> None:
        self.say(f"{reason}: skipped up to the next Content-Length header")


def _plain(body: bytes) -> dict[str, Any] | None:
    """A message's JSON object, read without pygls's types (None: not one)."""
    try:
        data = json.loads(body)
    except (ValueError, RecursionError):
        return None
    return data if isinstance(data, dict) else None


def _request_id_of(data: dict[str, Any] | None) -> int | str | None:
    ident = data.get("id") if data is not None and "method" in data else None
    return ident if isinstance(ident, (int, str)) and not isinstance(ident, bool) else None


class _Pipe(asyncio.Protocol):
    def __init__(self, feed: Callable[[bytes], None], done: asyncio.Future[None]) -> None:
        self.feed = feed
        self.done = done
        self.transport: asyncio.BaseTransport | None = None

    def data_received(self, data: bytes) -> None:
        self.feed(data)
        if self.done.done() and self.transport is not None:
            self.transport.close()

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        self.transport = transport

    def connection_lost(self, exc: Exception | None) -> None:
        if not self.done.done():
            self.done.set_result(None)


class _Input:
    """Where the client's bytes come from: a pipe the event loop watches, or (a regular
    file, a test's bytes) a thread that reads it."""

    def __init__(self, stdin: IO[bytes]) -> None:
        self.stdin = stdin
        self.fd: int | None = None
        self.failed = ""
        """What went wrong reading the input, if anything did."""

    async def start(self, feed: Callable[[bytes], None], done: asyncio.Future[None]) -> None:
        loop = asyncio.get_running_loop()

        def finish() -> None:
            if not done.done():
                done.set_result(None)

        def fed(data: bytes) -> None:
            try:
                feed(data)
            except BrokenPipeError:  # the client is gone: nothing more to answer
                finish()
            except Exception as exc:  # noqa: BLE001 - a fault of ours: said, and the end
                self.failed = f"{type(exc).__name__}: {exc}"
                finish()
        try:
            await loop.connect_read_pipe(lambda: _Pipe(fed, done), self.stdin)
            self.fd = self.stdin.fileno()
            return
        except (ValueError, OSError, AttributeError):
            pass

        def read() -> None:
            reader: Any = self.stdin
            chunk = getattr(reader, "read1", reader.read)
            try:
                while True:
                    data = chunk(65536)
                    if not data:
                        break
                    loop.call_soon_threadsafe(fed, data)
            except (OSError, ValueError):
                pass
            loop.call_soon_threadsafe(finish)

        threading.Thread(target=read, name="prima-lsp-stdin", daemon=True).start()

    def pending(self) -> bool:
        """Whether the client has sent bytes not read yet (a pipe only)."""
        if self.fd is None:
            return False
        try:
            return bool(select.select([self.fd], [], [], 0)[0])
        except (OSError, ValueError):
            return False


class _OneLine(logging.Formatter):
    def format(self, record: logging.LogRecord) -> str:
        lines = record.getMessage().splitlines()  # (pygls puts tracebacks in some messages)
        return f"prima lsp: {lines[0] if lines else ''}"


_LOGS = ("pygls", "asyncio")


def _quiet_logs(err: TextIO) -> logging.Handler:
    """pygls's and asyncio's warnings as one line each on stderr, never a traceback."""
    handler = logging.StreamHandler(err)
    handler.setFormatter(_OneLine())
    handler.setLevel(logging.WARNING)
    for name in _LOGS:
        log = logging.getLogger(name)
        log.addHandler(handler)
        log.propagate = False
    return handler


def serve(server: LanguageServer, stdin: IO[bytes], stdout: BinaryIO, err: TextIO,
          background: Callable[[Callable[[], bool]], Awaitable[None]]) -> int:
    """Serve ``server`` on the streams until the client says exit or the input ends;
    the exit status (the input's end: 0, or 1 inside a message). ``background(pending)``
    runs beside the reading (the diagnostics), told whether input waits to be read."""
    writer = StdoutWriter(stdout)
    server.protocol.set_writer(writer)
    connection = _Connection(server, writer, err)
    source = _Input(stdin)
    handler = _quiet_logs(err)

    async def run() -> None:
        done: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        await source.start(connection.framer.feed, done)
        task = asyncio.ensure_future(background(source.pending))
        try:
            await done
        finally:
            task.cancel()
        await asyncio.gather(task, return_exceptions=True)
        cut = connection.framer.ended() or (
            f"the input could not be read ({source.failed})" if source.failed else None)
        if cut:
            connection.say(f"{cut}: stopping")
        raise SystemExit(1 if cut else 0)

    try:
        asyncio.run(run())
    except SystemExit as stop:
        return stop.code if isinstance(stop.code, int) else 1
    except BrokenPipeError:
        connection.say("the client closed its end of the pipe: stopping")
        return 1
    except KeyboardInterrupt:
        return 130
    finally:
        for name in _LOGS:
            logging.getLogger(name).removeHandler(handler)
    return 0
