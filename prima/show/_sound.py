"""The page's sound: each utterance of the run synthesised (``prima show --audio``)."""

from __future__ import annotations

import base64
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from prima.audio import Clip, clip, utterances, wav


def clips(rows: Sequence[Mapping[str, Any]], scenario: str | Path | None) -> list[Clip]:
    """Every utterance of the trace, synthesised to last as long as the run says it, by
    the speech model of the scenario's robot (the home robot's without a scenario)."""
    from prima.dsl import default_profile, load_profile
    from prima.run import spec_from_profile
    from prima.sim import load_scenario

    profile = default_profile()
    if scenario is not None:
        loaded = load_scenario(scenario)
        if loaded.profile:
            profile = load_profile(loaded.resolve(loaded.profile))
    model = spec_from_profile(profile).speech_duration
    return [clip(u) for u in utterances(rows, model)]


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
