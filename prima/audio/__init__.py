"""A run you can hear: each utterance synthesised by espeak-ng, as long as the run says it.

:func:`utterances` finds in a trace when each of the robot's utterances was said
(a cut one: up to the cut word); :func:`clip` synthesises its words with
espeak-ng to last exactly that long; :func:`wav` makes a WAV file of the samples.
``prima show --audio`` puts one in its page for each utterance and plays them
with the playhead. :class:`SynthesisedTiming` times a run's utterances by the
synthesiser instead of the speech rate (``--speech-timing tts``). :func:`synthesise`
and :class:`Speech` are the library itself: the words' samples and where each word
starts.

Apart from the core: only ``prima show --audio`` imports it. espeak-ng is
reached through its C library (``libespeak-ng.so.1``, Debian's
``libespeak-ng1``: ``apt-get install espeak-ng``) with ctypes, so the ``audio``
extra adds no Python package; :func:`available` says whether it is there.
"""

from prima.audio._espeak import RATE_MAX, RATE_MIN, Speech, SpeechError, available
from prima.audio._speech import (
    MAX_CHARACTERS,
    MAX_CLIPS,
    MAX_SECONDS,
    MAX_SOUND,
    MAX_WORDS,
    OUTPUT_RATE,
    Clip,
    SynthesisedTiming,
    Utterance,
    clip,
    synthesise,
    utterances,
    wav,
)

__all__ = ["MAX_CHARACTERS", "MAX_CLIPS", "MAX_SECONDS", "MAX_SOUND", "MAX_WORDS",
           "OUTPUT_RATE", "RATE_MAX", "RATE_MIN", "Clip", "Speech", "SpeechError",
           "SynthesisedTiming", "Utterance", "available", "clip", "synthesise", "utterances",
           "wav"]
