"""What the judge found in one trace, and how it is shown."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from prima.judge._findings import Finding, Reaction
from prima.judge._measures import MEASURES
from prima.judge._thresholds import Thresholds

__all__ = ["Report", "format_summary", "format_table"]


@dataclass(frozen=True)
class Report:
    """What :func:`prima.judge.judge` found in one trace: every reaction, and each
    measure's findings (:data:`~prima.judge.MEASURES`), by the measure's key."""

    name: str
    end: float
    """The trace's last time (s)."""
    lines: int
    thresholds: Thresholds
    reactions: tuple[Reaction, ...] = ()
    findings: Mapping[str, tuple[Finding, ...]] = field(default_factory=dict)
    """Each measure's findings, by key (a plain dict: reports go between processes)."""

    def of(self, key: str) -> tuple[Finding, ...]:
        """One measure's findings (``late``, ``unfaced``, ...)."""
        return self.findings.get(key, ())

    @property
    def late(self) -> tuple[Reaction, ...]:
        """The late reactions."""
        return tuple(r for r in self.reactions if r.late)

    def counts(self) -> dict[str, int]:
        """Every measure's count, by key, in the table's order."""
        return {m.key: len(self.of(m.key)) for m in MEASURES}

    def seqs(self, key: str) -> list[int]:
        """The trace lines (seq) of one measure's findings."""
        return [item.seq for item in self.of(key)]

    def breaches(self) -> list[str]:
        """Each threshold exceeded, readably (empty: the run passes)."""
        out = []
        for m in MEASURES:
            n, limit = len(self.of(m.key)), self.thresholds.limit(m.key)
            if n > limit:
                seqs = ", ".join(map(str, self.seqs(m.key)[:8]))
                more = ", ..." if n > 8 else ""
                out.append(f"{m.title}: {n} > {limit} (seq {seqs}{more})")
        return out

    def exceeded(self) -> list[str]:
        """Each threshold exceeded, briefly (``late reactions 2 > 0``)."""
        return [b.split(" (seq")[0].replace(":", "") for b in self.breaches()]

    @property
    def ok(self) -> bool:
        """No threshold exceeded."""
        return not self.breaches()

    def worst_lateness(self) -> float:
        """How long (s) the latest reaction was free to start beyond the slack (0: none
        late; infinite: one never started)."""
        worst = 0.0
        slack = self.thresholds.reaction_slack
        for r in self.reactions:
            if r.late and r.latency is None:
                return math.inf
            if r.late:
                worst = max(worst, round(max(r.free - slack, r.words_free - slack
                                             - self.thresholds.utterance_slack, 0.0), 3))
        return worst

    def worst_latency(self) -> float:
        """The longest time (s) from an event to its reaction's first start (infinite:
        one never started; 0 without reactions)."""
        return max((math.inf if r.latency is None else r.latency for r in self.reactions),
                   default=0.0)

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = {
            "name": self.name, "end": self.end, "lines": self.lines,
            "thresholds": self.thresholds.to_dict(),
            "counts": {"reactions": len(self.reactions), **self.counts()},
            "reactions": [r.to_dict() for r in self.reactions],
        }
        for m in MEASURES:
            out[m.key] = [f.to_dict() for f in self.of(m.key)]
        out["breaches"] = self.breaches()
        out["ok"] = self.ok
        return out


# ---------------------------------------------------------------------------- the table

def _num(value: float | None) -> str:
    return "-" if value is None else f"{value:.2f}"


def _short(text: str, width: int) -> str:
    text = " ".join(text.split())
    return text if len(text) <= width else text[: width - 3] + "..."


def _reaction_rows(report: Report) -> list[str]:
    width = max([len(r.app) for r in report.reactions] + [3])
    rows = [f"  {'time':>7}  {'event':<22} {'app':<{width}} {'start':>6} {'words':>6} "
            f"{'rules':>6} {'free':>6}  late"]
    for r in report.reactions:
        cause = f'speech "{_short(r.text, 13)}"' if r.event == "speech" else r.event
        late = f"LATE: {r.why}" if r.late else ("UNHEARD" if r.unheard else "")
        rows.append(f"  {r.t:7.2f}  {_short(cause, 22):<22} {r.app:<{width}} "
                    f"{_num(r.latency):>6} {_num(r.utterance_latency):>6} {r.residual:6.2f} "
                    f"{r.free:6.2f}  {late}".rstrip())
    return rows


def _block(report: Report) -> list[str]:
    rows = [f"{report.name}  ({report.end:g} s, {report.lines} lines, "
            f"{len(report.reactions)} reactions)"]
    rows += _reaction_rows(report)
    for m in MEASURES:
        items: Sequence[Finding] = report.of(m.key)
        limit = report.thresholds.limit(m.key)
        mark = "  > max " + str(limit) if len(items) > limit else ""
        rows.append(f"  {m.title:<22} {len(items)}{mark}")
        rows += [f"      {m.line(item)}" for item in items[:10]]
        if len(items) > 10:
            rows.append(f"      ... and {len(items) - 10} more")
    return rows


def format_summary(report: Report, width: int = 0) -> str:
    """One line: the run's counts and whether it passes (``width``: pad the name to it)."""
    counts = "  ".join(f"{key} {n:<2}" for key, n in report.counts().items())
    verdict = "ok" if report.ok else "FAIL: " + ", ".join(report.exceeded())
    return f"{report.name:<{width}}  reactions {len(report.reactions):<3} {counts}  {verdict}"


def format_table(reports: Iterable[Report]) -> str:
    """A block per run (its reactions, then each measure), then a summary line per run."""
    reports = list(reports)
    rows: list[str] = []
    for report in reports:
        rows += _block(report) + [""]
    width = max((len(r.name) for r in reports), default=0)
    rows += [format_summary(r, width) for r in reports]
    return "\n".join(rows) + "\n"
