"""What the judge found in one trace, and how it is shown."""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

from prima.escape import terminal
from prima.judge._findings import Finding, Reaction
from prima.judge._measures import MEASURES
from prima.judge._thresholds import Thresholds
from prima.term import BOLD, GREEN, PLAIN, RED, YELLOW, Cell, Paint, layout

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


EVENT_WIDTH = 22
"""The event column of the reactions' table, a speech's words cut to fit (a terminal
wider than the table gives it more)."""


def _cause(reaction: Reaction, width: int) -> str:
    if reaction.event == "speech":  # (speech "...": 9 characters besides the words)
        return _short(f'speech "{_short(reaction.text, width - 9)}"', width)
    return _short(reaction.event, width)


def _reaction_rows(report: Report, paint: Paint, columns: int | None) -> list[str]:
    def rows(width: int, paint: Paint) -> list[str]:
        table: list[list[str | Cell]] = [[Cell(h, (BOLD,)) for h in (
            "time", "event", "app", "start", "words", "rules", "free", "late")]]
        for r in report.reactions:
            late = Cell(f"LATE: {r.why}", (RED,)) if r.late else \
                Cell("UNHEARD", (YELLOW,)) if r.unheard else ""
            table.append([f"{r.t:.2f}", _cause(r, width), r.app, _num(r.latency),
                          _num(r.utterance_latency), f"{r.residual:.2f}", f"{r.free:.2f}",
                          late])
        return layout(table, right=(0, 3, 4, 5, 6), minimum=(7, width, 3, 6, 6, 6, 6),
                      sep=("  ", " ", " ", " ", " ", " ", "  "), indent="  ", paint=paint)

    width = EVENT_WIDTH
    if columns is not None and report.reactions:  # a terminal: the room it has left
        room = columns - max(map(len, rows(width, PLAIN)))
        longest = max(len(_cause(r, 10_000)) for r in report.reactions)
        width = max(width, min(width + room, longest))
    return rows(width, paint)


_TITLES = max(len(m.title) for m in MEASURES)
"""How wide a run's block sets its measures' titles (each count in one column)."""


def _count_style(n: int, limit: int) -> tuple[str, ...]:
    return (RED, BOLD) if n > limit else (YELLOW,) if n else ()


def _block(report: Report, paint: Paint, columns: int | None) -> list[str]:
    rows = [f"{paint(terminal(report.name), BOLD)}  ({report.end:g} s, {report.lines} lines, "
            f"{len(report.reactions)} reactions)"]
    rows += _reaction_rows(report, paint, columns)
    for m in MEASURES:
        items: Sequence[Finding] = report.of(m.key)
        limit = report.thresholds.limit(m.key)
        mark = "  > max " + str(limit) if len(items) > limit else ""
        rows += layout([[m.title, Cell(f"{len(items)}{mark}",
                                       _count_style(len(items), limit))]],
                       minimum=(_TITLES,), indent="  ", paint=paint)
        # (escaped, as the tables' cells are: an app's name, its words, where it is written)
        rows += [f"      {terminal(m.line(item))}" for item in items[:10]]
        if len(items) > 10:
            rows.append(f"      ... and {len(items) - 10} more")
    return rows


def _summary_rows(reports: Sequence[Report], width: int, paint: Paint) -> list[str]:
    """A line per run: its counts and whether it passes, in columns as wide as the
    longest name and the largest counts."""
    table: list[list[str | Cell]] = []
    for report in reports:
        row: list[str | Cell] = [report.name, "reactions", str(len(report.reactions))]
        for key, n in report.counts().items():
            row += [key, Cell(str(n), _count_style(n, report.thresholds.limit(key)))]
        row.append(Cell("ok", (GREEN,)) if report.ok else
                   Cell("FAIL: " + ", ".join(report.exceeded()), (RED, BOLD)))
        table.append(row)
    keys = len(MEASURES)
    return layout(table, minimum=(width, 0, 3, *(0, 2) * keys),
                  sep=("  ", " ", " ", *(" ", "  ") * keys), paint=paint)


def format_summary(report: Report, width: int = 0) -> str:
    """One line: the run's counts and whether it passes (``width``: pad the name to it)."""
    return _summary_rows([report], width, PLAIN)[0]


def format_table(reports: Iterable[Report], paint: Paint = PLAIN,
                 columns: int | None = None) -> str:
    """A block per run (its reactions, then each measure), then a summary line per run;
    columns as wide as their content (``paint``: colour for a terminal, ``columns``: its
    width, which a long utterance may fill)."""
    reports = list(reports)
    rows: list[str] = []
    for report in reports:
        rows += _block(report, paint, columns) + [""]
    rows += _summary_rows(reports, 0, paint)
    return "\n".join(rows) + "\n"
