"""A run's utterances, when each was said, and each synthesised to fill that time.

The trace says when each atomic behavior with words started and ended; the
words fill part of it (a Q&A listens after its prompt; a FaceHumanAndSpeak
turns before it speaks). :func:`utterances` finds the span of the words
themselves, from the speech model the run used (``RobotSpec.speech_duration``,
2.5 words a second on the home robot) and what the trace records: a spoken
atomic behavior's ``duration`` result, and a cut one's ``spoken`` words
(the interrupt policy cuts at the end of a word). :func:`clip` synthesises an
utterance's words with espeak-ng at the rate that fills its span, and makes the
samples exactly as long as the span: the page plays them in time with its
playhead. A cut utterance (by the interrupt policy, or by the user speaking over
it: its end line has ``spoken`` and ``unspoken``) is the words spoken before the
cut at their natural pace, over the time they took, so its sound stops at the
cut word.

What is synthesised is bounded, whoever wrote the trace: an utterance's sound is
at most :data:`MAX_SECONDS` long and says at most :data:`MAX_WORDS` words (of at
most :data:`MAX_CHARACTERS` characters); a longer utterance's sound is its
beginning, at its own pace, and its clip says it was shortened. A page holds at
most :data:`MAX_SOUND` seconds of sound in :data:`MAX_CLIPS` utterances
(:mod:`prima.show` says which have none).
"""

from __future__ import annotations

import math
import os
import pickle
import re
import struct
import sys
from array import array
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from prima.audio._espeak import (
    RATE_MAX,
    RATE_MIN,
    Speech,
    SpeechError,
    _engine,
    _LOCK,
    quoted,
)
from prima.catalog import Catalog

__all__ = ["MAX_CHARACTERS", "MAX_CLIPS", "MAX_SECONDS", "MAX_SOUND", "MAX_WORDS",
           "OUTPUT_RATE", "Clip", "Ends", "SynthesisedTiming", "Utterance", "clip", "synthesise",
           "utterances", "wav"]

OUTPUT_RATE = 11_025
"""Samples per second of the page's sound (espeak-ng's 22,050 halved: its voice is
well below 5 kHz, and the page half as heavy)."""

MAX_SECONDS = 120.0
"""The longest sound made for one utterance (s): a longer one sounds its first two
minutes (a forged trace's 99,999 s utterance would need gigabytes of samples)."""

MAX_WORDS = 300
"""The most words synthesised for one utterance (two minutes at the home robot's 2.5
words a second): a longer one sounds its first words."""

MAX_CHARACTERS = 3_000
"""The most characters synthesised for one utterance (a 'word' of a million letters
is cut too)."""

MAX_SOUND = 1_800.0
"""The most sound one page holds (s, half an hour: 40 MB of samples); later utterances
have none."""

MAX_CLIPS = 1_000
"""The most utterances one page holds the sound of."""

_SILENCE = 64
"""A sample this quiet (of 32,767) counts as silence at an utterance's ends."""

Row = Mapping[str, Any]


@dataclass(frozen=True)
class Utterance:
    """Words the robot said, and when."""

    ab: int
    app: str
    command: str
    start: float
    end: float
    text: str
    """The words said (a cut utterance: those before the cut)."""
    whole: str
    """The utterance as requested."""
    cut: bool = False

    @property
    def duration(self) -> float:
        return round(self.end - self.start, 6)


@dataclass(frozen=True)
class Clip:
    """An utterance's sound: 16-bit mono samples at :data:`OUTPUT_RATE`, exactly as long
    as the utterance (at most :data:`MAX_SECONDS`); ``words``: where each word starts
    (s from the clip's start)."""

    utterance: Utterance
    samples: array[int]
    words: tuple[float, ...]
    shortened: bool = False
    """The utterance is longer than a clip may be (:data:`MAX_SECONDS`,
    :data:`MAX_WORDS`, :data:`MAX_CHARACTERS`): this is its beginning."""

    @property
    def duration(self) -> float:
        return len(self.samples) / OUTPUT_RATE


def _result(row: Row) -> dict[str, str]:
    """An end line's ``result`` detail (``duration=3.6, x=1.0``) as a mapping."""
    detail = row.get("detail") or {}
    text = str(detail.get("result") or "")
    out = {}
    for part in text.split(", "):
        key, sep, value = part.partition("=")
        if sep:
            out[key] = value
    return out


def _speaks_last(command: str) -> bool:
    """Whether the words of an atomic behavior of these Commands (``A+B+Speak``) end
    with it: the last Command says them, and does not listen after them."""
    last = Catalog.standard().get(command.split("+")[-1])
    return last is not None and not last.listens and "speaker" in last.devices


_CUT = ("interrupt", "barge-in")
"""The reasons of an end line whose utterance was cut: for another application's
reaction, or because the user spoke over it."""

Ends = Callable[[str], Sequence[float]]
"""When each word of a text ends, from its start (s): a synthesiser's word boundaries."""


def _said(start: Row, end: Row, model: Callable[[str], float],
          ends: Ends | None = None) -> Utterance | None:
    whole = " ".join(str(start["text"]).split(" / "))
    t0, t1 = float(start["t"]), float(end["t"])
    ab, app, command = int(start["ab"]), str(start.get("app") or ""), str(start.get("command"))
    full = model(whole)
    detail = end.get("detail") or {}
    if end.get("reason") in _CUT or "spoken" in detail or "unspoken" in detail:
        spoken = str(detail.get("spoken") or "")
        k, n = len(spoken.split()), len(whole.split())
        if not k or not n:
            return None  # cut before its first word
        bounds = ends(whole) if ends is not None else ()
        took = bounds[k - 1] if len(bounds) == n else full * k / n
        return Utterance(ab, app, command, max(t0, round(t1 - took, 6)), t1, spoken, whole,
                         cut=True)
    said = _result(end).get("duration")
    if said is not None and _speaks_last(command):
        duration = float(said)
        return Utterance(ab, app, command, max(t0, round(t1 - duration, 6)), t1, whole, whole)
    return Utterance(ab, app, command, t0, round(min(t1, t0 + full), 6), whole, whole)


def utterances(rows: Iterable[Row], model: Callable[[str], float],
               ends: Ends | None = None) -> list[Utterance]:
    """Every utterance of a run's trace rows, by start; ``model`` gives how long saying a
    text takes (the robot's ``speech_duration``), ``ends`` when each of its words ends
    (None: evenly, as the speech rate has it). An utterance still under way when the
    trace ends is kept up to there."""
    running: dict[int, Row] = {}
    out: list[Utterance] = []
    last = 0.0
    for row in rows:
        last = max(last, float(row["t"]))
        ab = row.get("ab")
        if row["kind"] == "start" and row.get("text") and isinstance(ab, int):
            running[ab] = row
        elif row["kind"] == "end" and isinstance(ab, int) and ab in running:
            found = _said(running.pop(ab), row, model, ends)
            if found is not None and found.end > found.start:
                out.append(found)
    for start in running.values():
        found = _said(start, {"t": last, "detail": {}}, model, ends)
        if found is not None and found.end > found.start:
            out.append(found)
    return sorted(out, key=lambda u: (u.start, u.ab))


# ---------------------------------------------------------------- sound

def synthesise(text: str, wpm: int) -> Speech:
    """``text`` said by espeak-ng, the same for the same text and rate.

    espeak-ng's synthesis depends on what it said before in the process (a comma's
    pause varies by tens of milliseconds), so each utterance is said in a process
    forked from one where the library is ready but has said nothing yet: the result
    is what a fresh process would say. Where there is no fork, it is said here.
    """
    with _LOCK:
        engine = _engine()
        if not hasattr(os, "fork"):
            return engine.synth(text, wpm)
        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child: say it, send it, leave at once
            try:
                os.close(read)
                said = engine.synth(text, wpm)
                payload = pickle.dumps((said.samples.tobytes(), said.rate, said.words))
                with os.fdopen(write, "wb") as out:
                    out.write(payload)
            finally:
                os._exit(0)
        os.close(write)
        with os.fdopen(read, "rb") as got:
            payload = got.read()
        os.waitpid(pid, 0)
    if not payload:
        raise SpeechError(f"espeak-ng failed to say {quoted(text)}")
    raw, rate, words = pickle.loads(payload)  # noqa: S301 - our own child's bytes
    samples = array("h")
    samples.frombytes(raw)
    return Speech(samples, rate, tuple(words))


def _voiced(samples: array[int]) -> int:
    """How many samples there are up to the last one that is not silence."""
    end = len(samples)
    while end and abs(samples[end - 1]) < _SILENCE:
        end -= 1
    return end


def _halve(samples: array[int]) -> array[int]:
    """22,050 to 11,025 samples a second: each pair averaged (a gentle low-pass)."""
    return array("h", [(a + b) // 2 for a, b in zip(samples[0::2], samples[1::2],
                                                      strict=False)])


def _rate(wpm: float) -> int:
    return max(RATE_MIN, min(RATE_MAX, round(wpm)))


def clip(utterance: Utterance, timing: SynthesisedTiming | None = None) -> Clip:
    """The utterance's words synthesised to last exactly its span: said at the rate that
    fills it (espeak-ng's words per minute, 80 to 450; a second try corrects the first
    guess), then the silence at its end trimmed or padded; what is still too long is cut
    with a 20 ms fade. With ``timing`` (the run was timed by the synthesiser), the whole
    utterance as ``timing`` said it, up to the end of its span (a cut one: its cut word)."""
    duration = min(utterance.duration, MAX_SECONDS)
    target = max(1, round(duration * OUTPUT_RATE))
    text, shortened = _bounded(utterance.text, utterance.duration)
    if timing is not None:
        speech = timing.speech(utterance.whole)
    else:
        wpm = _rate(60 * max(1, len(text.split())) / duration)
        speech = synthesise(text, wpm)
        better = _rate(wpm * _voiced(speech.samples) / speech.rate / duration)
        if better != wpm:
            speech = synthesise(text, better)
    samples = _halve(speech.samples[:_voiced(speech.samples)])
    if len(samples) >= target:
        samples = samples[:target]
        fade = min(target, OUTPUT_RATE // 50)
        for i in range(fade):
            samples[target - fade + i] = samples[target - fade + i] * (fade - i) // fade
    else:
        samples.extend([0] * (target - len(samples)))
    words = tuple(round(at / speech.rate, 3) for _, _, at in speech.words)
    return Clip(utterance, samples, words, shortened or utterance.duration > MAX_SECONDS)


def _bounded(text: str, duration: float) -> tuple[str, bool]:
    """The words of an utterance a clip says (at most :data:`MAX_WORDS`, the share of
    them that fits in :data:`MAX_SECONDS`, at most :data:`MAX_CHARACTERS` characters),
    and whether that is fewer than it has."""
    words = text.split()
    keep = min(len(words), MAX_WORDS)
    if duration > MAX_SECONDS:
        keep = min(keep, max(1, math.ceil(len(words) * MAX_SECONDS / duration)))
    said = " ".join(words[:keep])[:MAX_CHARACTERS]
    return said, said != " ".join(words)


class SynthesisedTiming:
    """Utterances timed by espeak-ng (``prima show --speech-timing tts``): saying a text
    takes as long as espeak-ng's voice takes at the robot's speech rate (2.5 words a
    second: 150 words a minute), and its words end where the voice ends them. A
    :class:`~prima.sim.SpeechTiming` for the simulator; each text is synthesised once."""

    def __init__(self, words_per_second: float) -> None:
        self.wpm = _rate(60 * words_per_second)
        self._said: dict[str, tuple[Speech, float, tuple[float, ...]]] = {}

    def _say(self, text: str) -> tuple[Speech, float, tuple[float, ...]]:
        if text not in self._said:
            speech = synthesise(text, self.wpm)
            voiced = _voiced(speech.samples) / speech.rate
            self._said[text] = (speech, voiced, _word_ends(text, speech, voiced))
        return self._said[text]

    def speech(self, text: str) -> Speech:
        """``text`` as the voice says it."""
        return self._say(text)[0]

    def said(self, text: str) -> tuple[float, tuple[float, ...]]:
        _speech, voiced, ends = self._say(text)
        return voiced, ends


def _word_ends(text: str, speech: Speech, voiced: float) -> tuple[float, ...]:
    """When each word of ``text`` (split on white space) ends in ``speech``: where the
    voice begins the next one (its word events, by character), the last at the end."""
    starts = [m.start() for m in re.finditer(r"\S+", text)]
    events = sorted(speech.words)
    out = []
    for nxt in starts[1:]:
        at = next((sample for char, _length, sample in events if char >= nxt), None)
        out.append(voiced if at is None else min(voiced, at / speech.rate))
    if starts:
        out.append(voiced)
    for i in range(1, len(out)):  # never backwards
        out[i] = max(out[i], out[i - 1])
    return tuple(round(t, 6) for t in out)


def wav(samples: array[int], rate: int = OUTPUT_RATE) -> bytes:
    """A WAV file of 16-bit mono samples (little-endian, as RIFF has them)."""
    data = array("h", samples)
    if sys.byteorder == "big":
        data.byteswap()
    header = struct.pack("<4sI4s4sIHHIIHH4sI", b"RIFF", 36 + 2 * len(data), b"WAVE", b"fmt ",
                         16, 1, 1, rate, rate * 2, 2, 16, b"data", 2 * len(data))
    return header + data.tobytes()
