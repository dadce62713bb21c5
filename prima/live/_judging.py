"""The judge's findings on a live run, each shown once it is final.

The judge (:func:`prima.judge.judge`) reads a whole trace; a live run has only the
trace so far. Judged on such a prefix, some findings hold whatever comes next (an
utterance started unfaced, another application's words inside an exchange, a silence
already over 2 s, a reaction that started late and has said its words); others are
about what has *not* happened yet and may be undone by a later line (a reaction that
has not started or not said its words yet, speech not answered yet, an utterance cut
by a cough that may still go on, words that may still be heard whole, an application
still waiting). :func:`final` tells them apart from each finding's own fields; the
second kind is shown only when the run is over. (Judging every half second of every
shipped scenario's prefixes, none of the findings :func:`final` passes was later
changed or withdrawn: ``tests/live/test_live.py``.)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from prima.judge import (
    MEASURES,
    BargeIn,
    Finding,
    Ignored,
    Reaction,
    Recovery,
    Stuck,
    Thresholds,
    judge,
)

__all__ = ["LiveJudge", "final"]

_AT_THE_END = frozenset({"unheard", "stuck"})
"""Measures whose findings say that something never happened: only the end decides."""


def final(key: str, finding: Finding, end: float) -> bool:
    """Whether ``finding`` (of the measure ``key``), found on a trace that goes up to
    ``end`` (s), stays the same whatever lines come after."""
    if key in _AT_THE_END or isinstance(finding, Stuck):
        return False
    if isinstance(finding, Reaction):  # late: its start, and its words if it has any
        return finding.first_start is not None and (
            not finding.words or finding.first_utterance is not None)
    if isinstance(finding, BargeIn):  # the words went on past what was allowed
        return finding.stopped is not None or end >= finding.t + finding.allowed
    if isinstance(finding, Ignored):  # (unanswered yet: a later answer may be in time)
        return finding.answered is not None
    if isinstance(finding, Recovery):
        return finding.resumed is not None
    return True  # unfaced, leaving, elsewhere, splits, silences: decided at their line


class LiveJudge:
    """Judges a growing trace again and again, and says each final finding once."""

    def __init__(self, thresholds: Thresholds | None = None) -> None:
        self.thresholds = thresholds or Thresholds()
        self.shown: dict[tuple[str, int], dict[str, Any]] = {}
        """(measure, seq) -> the finding as shown, for each finding shown."""

    def update(self, rows: Sequence[Mapping[str, Any]], over: bool
               ) -> tuple[list[dict[str, Any]], int]:
        """Judge ``rows`` (the trace so far; ``over``: the whole run): the final findings
        not shown before, in time order, and how many others wait for the run's end."""
        if not rows:
            return [], 0
        end = float(rows[-1]["t"])
        report = judge(rows, thresholds=self.thresholds, name="live")
        new: list[dict[str, Any]] = []
        waiting = 0
        for measure in MEASURES:
            for finding in report.of(measure.key):
                key = (measure.key, int(finding.seq))
                if key in self.shown:
                    continue
                if not over and not final(measure.key, finding, end):
                    waiting += 1
                    continue
                shown = {"key": measure.key, "title": measure.title, "t": float(finding.t),
                         "seq": int(finding.seq), "app": str(finding.app),
                         "line": measure.line(finding)}
                self.shown[key] = shown
                new.append(shown)
        return sorted(new, key=lambda f: (f["t"], f["seq"])), waiting
