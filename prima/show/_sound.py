"""The page's sound: each utterance of the run synthesised (``prima show --audio``)."""

from __future__ import annotations

import base64
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from prima.audio import (
    MAX_CHARACTERS,
    MAX_CLIPS,
    MAX_SECONDS,
    MAX_SOUND,
    MAX_WORDS,
    Clip,
    SynthesisedTiming,
    clip,
    utterances,
    wav,
)
from prima.dsl import RobotProfile
from prima.escape import terminal


def _profile(scenario: str | Path | None) -> RobotProfile:
    """The scenario's robot (the home robot without a scenario, or without a profile)."""
    from prima.dsl import default_profile, load_profile
    from prima.scenario import load_scenario

    if scenario is not None:
        loaded = load_scenario(scenario)
        if loaded.profile:
            return load_profile(loaded.resolve(loaded.profile))
    return default_profile()


def speech_timing(scenario: str | Path) -> SynthesisedTiming:
    """Utterances timed by espeak-ng at the speech rate of the scenario's robot."""
    return SynthesisedTiming(_profile(scenario).speech_rate)


def clips(rows: Sequence[Mapping[str, Any]], scenario: str | Path | None,
          timing: SynthesisedTiming | None = None,
          warn: Callable[[str], object] | None = None) -> list[Clip]:
    """Every utterance of the trace, synthesised to last as long as the run says it: by
    the speech model of the scenario's robot (the home robot's without a scenario), or
    by ``timing`` when the run was timed by the synthesiser. What is made is bounded
    (:data:`~prima.audio.MAX_SECONDS` and :data:`~prima.audio.MAX_WORDS` an utterance,
    :data:`~prima.audio.MAX_SOUND` and :data:`~prima.audio.MAX_CLIPS` a page); ``warn``
    is told which utterances were shortened, and how many have no sound."""
    from prima.run import spec_from_profile

    spec = spec_from_profile(_profile(scenario))
    if timing is None:
        said = utterances(rows, spec.speech_duration)
    else:
        said = utterances(rows, lambda text: max(spec.min_utterance, timing.said(text)[0]),
                          lambda text: timing.said(text)[1])
    made: list[Clip] = []
    total, silent, shortened = 0.0, 0, 0
    first_silent = 0.0
    for u in said:
        if len(made) >= MAX_CLIPS or total + min(u.duration, MAX_SECONDS) > MAX_SOUND:
            first_silent = first_silent if silent else u.start
            silent += 1
            continue
        made.append(clip(u, timing))
        total += made[-1].duration
        if made[-1].shortened:
            shortened += 1
            if warn is not None and shortened <= _TOLD:
                warn(f"the utterance at {u.start:.1f} s ({terminal(u.app)}, AB {u.ab}) says "
                     f"{len(u.text.split()):,} word(s), {len(u.text):,} characters, over "
                     f"{u.duration:.1f} s: its sound is its beginning, "
                     f"{made[-1].duration:.1f} s (a clip says at most {MAX_WORDS} words, "
                     f"{MAX_CHARACTERS:,} characters, in {MAX_SECONDS:g} s)")
    if warn is not None and shortened > _TOLD:
        warn(f"{shortened - _TOLD} more utterance(s) shortened likewise")
    if warn is not None and silent:
        warn(f"{silent} utterance(s) from {first_silent:g} s on have no sound: a "
             f"page holds at most {MAX_SOUND:g} s of sound, in {MAX_CLIPS} utterances")
    return made


_TOLD = 3
"""Shortened utterances told one by one; the others are counted."""


def elements(found: Sequence[Clip]) -> str:
    """The page's audio elements, one per utterance, its WAV inside."""
    out = []
    for c in found:
        u = c.utterance
        data = base64.b64encode(wav(c.samples)).decode("ascii")
        out.append(f'<audio preload="auto" data-start="{u.start:.6g}" data-end="{u.end:.6g}" '
                   f'data-ab="{u.ab}" data-cut="{str(u.cut).lower()}" '
                   f'data-duration="{c.duration:.6f}" src="data:audio/wav;base64,{data}"></audio>')
    return "\n".join(out)
