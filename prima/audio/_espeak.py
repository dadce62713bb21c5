"""espeak-ng through its C library (``libespeak-ng.so.1``), with ctypes.

The library is Debian's ``libespeak-ng1`` (``apt-get install espeak-ng``); no
Python package stands between. It is used in synchronous mode: one synthesis
gives the whole utterance as 16-bit mono samples, with where each word starts
(from the library's word events). The library keeps global state, so every use
holds :data:`_LOCK` (and :func:`prima.audio.synthesise` says each utterance in a
fresh fork, so that what it said before does not change it).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import threading
from array import array
from dataclasses import dataclass

from prima.errors import PrimaError
from prima.escape import terminal

__all__ = ["LIBRARY", "RATE_MAX", "RATE_MIN", "Speech", "SpeechError", "available", "quoted"]

LIBRARY = "libespeak-ng.so.1"
"""The shared library loaded (Debian's ``libespeak-ng1``)."""

RATE_MIN, RATE_MAX = 80, 450
"""The speaking rates espeak-ng accepts, in words per minute."""

_SYNCHRONOUS = 2  # AUDIO_OUTPUT_SYNCHRONOUS
_CHARS_UTF8 = 1
_RATE = 1  # espeakRATE
_EVENT_WORD = 1
_EVENT_LIST_TERMINATED = 0


class SpeechError(PrimaError):
    """espeak-ng is not installed here, or failed."""


class _Id(ctypes.Union):
    _fields_ = [("number", ctypes.c_int), ("name", ctypes.c_char_p),
                ("string", ctypes.c_char * 8)]


class _Event(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("unique_identifier", ctypes.c_uint),
                ("text_position", ctypes.c_int), ("length", ctypes.c_int),
                ("audio_position", ctypes.c_int), ("sample", ctypes.c_int),
                ("user_data", ctypes.c_void_p), ("id", _Id)]


_CALLBACK = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_short), ctypes.c_int,
                             ctypes.POINTER(_Event))


@dataclass(frozen=True)
class Speech:
    """An utterance synthesised: its samples and where its words start."""

    samples: array[int]
    """16-bit mono samples."""
    rate: int
    """Samples per second."""
    words: tuple[tuple[int, int, int], ...]
    """Each word: (its first character in the text, its length, its first sample)."""

    @property
    def duration(self) -> float:
        return len(self.samples) / self.rate


class _Engine:
    def __init__(self) -> None:
        try:
            self.lib = ctypes.CDLL(LIBRARY)
        except OSError:
            found = ctypes.util.find_library("espeak-ng")
            if found is None:
                raise SpeechError(
                    f"espeak-ng is not installed ({LIBRARY} not found): on Debian or "
                    "Ubuntu, apt-get install espeak-ng") from None
            self.lib = ctypes.CDLL(found)
        lib = self.lib
        lib.espeak_Initialize.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_char_p,
                                          ctypes.c_int]
        lib.espeak_Synth.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_uint,
                                     ctypes.c_int, ctypes.c_uint, ctypes.c_uint,
                                     ctypes.POINTER(ctypes.c_uint), ctypes.c_void_p]
        lib.espeak_SetParameter.argtypes = [ctypes.c_int, ctypes.c_int, ctypes.c_int]
        lib.espeak_SetVoiceByName.argtypes = [ctypes.c_char_p]
        self.rate = lib.espeak_Initialize(_SYNCHRONOUS, 0, None, 0)
        if self.rate <= 0:
            raise SpeechError("espeak-ng could not start (no espeak-ng-data?)")
        if lib.espeak_SetVoiceByName(b"en") != 0:
            raise SpeechError("espeak-ng has no English voice")
        self.samples: array[int] = array("h")
        self.words: list[tuple[int, int, int]] = []
        self.callback = _CALLBACK(self._received)  # kept: the library holds the pointer
        lib.espeak_SetSynthCallback(self.callback)

    def _received(self, wav: ctypes._Pointer[ctypes.c_short], count: int,
                  events: ctypes._Pointer[_Event]) -> int:
        i = 0
        while events[i].type != _EVENT_LIST_TERMINATED:
            event = events[i]
            if event.type == _EVENT_WORD:
                at = round(event.audio_position * self.rate / 1000)
                self.words.append((event.text_position - 1, event.length, at))
            i += 1
        if count > 0 and wav:
            self.samples.extend(wav[:count])
        return 0

    def synth(self, text: str, wpm: int) -> Speech:
        self.samples, self.words = array("h"), []
        self.lib.espeak_SetParameter(_RATE, max(RATE_MIN, min(RATE_MAX, wpm)), 0)
        data = text.encode("utf-8") + b"\0"
        status = self.lib.espeak_Synth(data, len(data), 0, 0, 0, _CHARS_UTF8, None, None)
        self.lib.espeak_Synchronize()
        if status != 0:
            raise SpeechError(f"espeak-ng failed to say {quoted(text)} (status {status})")
        return Speech(self.samples, self.rate, tuple(self.words))


def quoted(text: str, limit: int = 60) -> str:
    """An utterance as an error message quotes it: on one line, escaped, its first
    ``limit`` characters (a forged utterance may be megabytes long)."""
    shown = terminal(text if len(text) <= limit else text[:limit] + "...")
    return f"'{shown}' ({len(text):,} characters)" if len(text) > limit else f"'{shown}'"


_LOCK = threading.Lock()
_ENGINE: list[_Engine] = []


def _engine() -> _Engine:
    if not _ENGINE:
        _ENGINE.append(_Engine())
    return _ENGINE[0]


def available() -> str | None:
    """None if espeak-ng can speak here; else why not."""
    try:
        with _LOCK:
            _engine()
    except SpeechError as exc:
        return str(exc)
    return None
