"""The page's sound: each utterance of the run synthesised (``prima show --audio``)."""

from __future__ import annotations

import base64
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from prima.audio import Clip, SynthesisedTiming, clip, utterances, wav
from prima.dsl import RobotProfile


def _profile(scenario: str | Path | None) -> RobotProfile:
    """The scenario's robot (the home robot without a scenario, or without a profile)."""
    from prima.dsl import default_profile, load_profile
    from prima.sim import load_scenario

    if scenario is not None:
        loaded = load_scenario(scenario)
        if loaded.profile:
            return load_profile(loaded.resolve(loaded.profile))
    return default_profile()


def speech_timing(scenario: str | Path) -> SynthesisedTiming:
    """Utterances timed by espeak-ng at the speech rate of the scenario's robot."""
    return SynthesisedTiming(_profile(scenario).speech_rate)


def clips(rows: Sequence[Mapping[str, Any]], scenario: str | Path | None,
          timing: SynthesisedTiming | None = None) -> list[Clip]:
    """Every utterance of the trace, synthesised to last as long as the run says it: by
    the speech model of the scenario's robot (the home robot's without a scenario), or
    by ``timing`` when the run was timed by the synthesiser."""
    from prima.run import spec_from_profile

    spec = spec_from_profile(_profile(scenario))
    if timing is None:
        said = utterances(rows, spec.speech_duration)
    else:
        said = utterances(rows, lambda text: max(spec.min_utterance, timing.said(text)[0]),
                          lambda text: timing.said(text)[1])
    return [clip(u, timing) for u in said]


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
