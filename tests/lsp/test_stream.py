"""The base protocol's framing, in this process: the same messages however the stream
is cut into reads, and every fault read past up to the next header."""

from __future__ import annotations

import random

import pytest

pytest.importorskip("pygls")

from prima.lsp._stream import Framer, request_id  # noqa: E402


def frame(body: bytes) -> bytes:
    return b"Content-Length: %d\r\n\r\n" % len(body) + body


def read(stream: bytes, cuts: list[int], limit: int = 100) -> list[tuple[str, object]]:
    out: list[tuple[str, object]] = []
    framer = Framer(lambda body: out.append(("message", body)),
                    lambda length, head: out.append(("refused", (length, request_id(head)))),
                    lambda reason: out.append(("skipped", reason)), limit=limit)
    at = 0
    for cut in [*sorted(cuts), len(stream)]:
        framer.feed(stream[at:cut])
        at = cut
    out.append(("ended", framer.ended()))
    return out


LONG = b'{"jsonrpc": "2.0", "id": 7, "method": "m", "params": "' + b"x" * 300 + b'"}'
STREAM = b"".join([
    frame(b'{"a": 1}'),
    b"Content-Length: 5\r\nContent-Type: application/json\r\n\r\n[1,2]",
    frame(LONG),
    b"\r\n",  # a blank line between messages
    b"Content-Length: 1000000000000\r\n\r\n{\"jsonrpc\": \"2.0\", \"id\": \"q\", \"method\": \"m\"",
    frame(b'{"b": 2}'),
    b"no colon here\r\n",
    frame(b'{"c": 3}'),
    b"Content-Length: 9\r\n",
])
EXPECTED = [
    ("message", b'{"a": 1}'),
    ("message", b"[1,2]"),
    ("refused", (len(LONG), 7)),
    ("refused", (1000000000000, "q")),
    ("message", b'{"b": 2}'),
    ("skipped", "a header line that is not 'Name: value' ('no colon here')"),
    ("message", b'{"c": 3}'),
    ("ended", "the client's stream ended inside a message's headers"),
]


def test_the_same_messages_however_the_stream_is_cut() -> None:
    assert read(STREAM, []) == EXPECTED
    rng = random.Random(1)
    for _ in range(300):
        cuts = rng.sample(range(len(STREAM)), rng.randint(1, 40))
        assert read(STREAM, cuts) == EXPECTED, cuts
    assert read(STREAM, list(range(len(STREAM)))) == EXPECTED  # a byte a read


def test_a_long_header_line_is_skipped_and_a_body_cut_short_is_said() -> None:
    stream = b"X" * 5000 + frame(b"{}") + b"Content-Length: 10\r\n\r\n{}"
    assert read(stream, [100, 4500]) == [
        ("skipped", "a header line longer than 4,096 bytes"),
        ("message", b"{}"),
        ("ended", "the client's stream ended inside a message (2 of 10 bytes)"),
    ]


def test_a_request_id_is_read_only_at_the_top_level_of_a_request() -> None:
    assert request_id(b'{"jsonrpc": "2.0", "method": "m", "id": 3, "params": {}}') == 3
    assert request_id(b'{"params": {"id": 5}, "method": "m", "id": "x"}') == "x"
    assert request_id(b'{"params": {"id": 5}, "method": "m"}') is None  # a notification
    assert request_id(b'{"id": 5, "result": {}}') is None  # a response
    assert request_id(b'{"method": "m", "params": "\\"id\\": 9", "id": true}') is None
    assert request_id(b'{"method": "m", "id": 8, "params": {"text": "a cut ') == 8  # a head
