"""Sweep a scenario: run it many times with its timings jittered, judge every run.

A scenario is one situation at fixed times; the user and the building would
never keep them to the tenth of a second. :func:`sweep` re-runs a scenario N
times, each time with its user's timed actions (``at``), its answer rules'
delays (``after``) and its scheduled messages, sounds and events (``at``)
shifted by random offsets uniform in ±jitter, and judges each run
(:mod:`prima.judge`). The order the scenario gives is kept: a shifted user
action is never earlier than the previous shifted one (messages likewise among
themselves), no time goes below 0 and an answer's delay stays at least 0.1 s.

Run ``i``'s offsets come from ``random.Random`` seeded with the sweep's seed and
``i``, so results are the same whatever runs them (:mod:`prima.batch`: this
machine's processes or a Dask cluster) and however many workers. Each variant
is an ordinary scenario file (:func:`write_variant`): the worst runs can be
written out and replayed with ``prima run`` or ``prima judge`` (the command line's
policy switches written in; its runs are given them as ``prima run --policy`` gives
them, through :class:`~prima.scenario.Setup`). A sweep keeps no
run's report: each run's record goes to the results file (``results``) as it
comes, and the sweep keeps only the spread of each measure and its worst runs,
so its memory does not grow with the number of runs.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from prima.batch import (
    CPU,
    MIN_ANSWER_DELAY,
    Job,
    Pool,
    ResultsFile,
    bundle_scenario,
    collect,
    number,
    pool_for,
    write_variant,
)
from prima.judge import MEASURES, Thresholds
from prima.output import make_folder
from prima.scenario import load_scenario
from prima.term import BOLD, GREEN, PLAIN, RED, Cell, Paint, layout

if TYPE_CHECKING:
    from prima.run import Switches

__all__ = ["MIN_ANSWER_DELAY", "Spread", "Sweep", "SweepRun", "format_sweep", "progress_bar",
           "sweep", "write_variant"]

_number = number


# ---------------------------------------------------------------------------- runs

def _time(value: object) -> float:
    """A record's time: None stands for infinite (a reaction that never started)."""
    return math.inf if value is None else float(value)  # type: ignore[arg-type]


@dataclass(frozen=True)
class SweepRun:
    """One run of a sweep, judged: its record (:func:`prima.batch.record_of`)."""

    index: int
    record: Mapping[str, Any]

    @property
    def breaches(self) -> int:
        """How many thresholds it exceeded."""
        return len(self.record.get("breaches") or ())

    def exceeded(self) -> list[str]:
        """Each threshold exceeded, briefly (``late reactions 2 > 0``)."""
        return [b.split(" (seq")[0].replace(":", "") for b in self.record.get("breaches") or ()]

    def worst_lateness(self) -> float:
        """How long (s) its latest reaction was free to start beyond the slack."""
        return _time(self.record.get("worst_lateness"))

    @property
    def findings(self) -> int:
        """How many faults its measures found, all told."""
        return sum((self.record.get("counts") or {}).values())

    def rank(self) -> tuple[int, int, float, int]:
        """Worst first: most thresholds exceeded, then most faults, then latest reaction,
        then first run."""
        return (-self.breaches, -self.findings, -self.worst_lateness(), self.index)


@dataclass
class Spread:
    """Each measure's values over the runs, as how many runs had each value: exact
    quantiles in memory bounded by the values, not the runs."""

    values: dict[str, Counter[float]] = field(default_factory=dict)

    def add(self, record: Mapping[str, Any]) -> None:
        for m in _rows():
            self.values.setdefault(m.name, Counter())[m.value(record)] += 1

    def quantiles(self, name: str) -> tuple[float, float, float, float]:
        """Min, median, 95th percentile (nearest rank) and max of one measure."""
        counts = self.values.get(name) or Counter()
        ordered = sorted(counts.items())
        n = sum(counts.values())

        def at(k: int) -> float:
            for value, many in ordered:
                if k < many:
                    return value
                k -= many
            return ordered[-1][0]

        mid = at(n // 2) if n % 2 else (at(n // 2 - 1) + at(n // 2)) / 2
        return ordered[0][0], mid, at(max(math.ceil(0.95 * n) - 1, 0)), ordered[-1][0]

    def over(self, name: str, limit: float) -> int:
        """How many runs' value of one measure is over ``limit``."""
        return sum(k for v, k in (self.values.get(name) or Counter()).items() if v > limit)


@dataclass
class Sweep:
    """A sweep's outcome: how many runs were judged (fewer than asked if it was
    interrupted), the spread of each measure, and its worst runs."""

    scenario: Path
    name: str
    """The scenario's name."""
    asked: int
    jitter: float
    seed: int
    thresholds: Thresholds
    done: int = 0
    """Runs judged."""
    breached: int = 0
    """Runs that exceeded a threshold."""
    spread: Spread = field(default_factory=Spread)
    kept: list[SweepRun] = field(default_factory=list)
    """The worst runs, worst first (as many as the sweep was asked to keep)."""
    keep: int = 3
    interrupted: bool = False
    lost: list[int] = field(default_factory=list)
    """Runs whose worker died each time they ran, alone too (never judged)."""
    errors: list[tuple[int, str]] = field(default_factory=list)
    """Runs that failed, with why (the first 20)."""
    failed: int = 0
    """How many runs failed."""
    switches: Switches | None = None
    """The command line's FA, EA, robot and policies, if any (the worst runs' files
    have them written in)."""

    def add(self, record: Mapping[str, Any]) -> None:
        """Take one run's record in."""
        index = int(record["run"])
        if record.get("lost"):
            self.lost.append(index)
            return
        if "error" in record:
            self.failed += 1
            if len(self.errors) < 20:
                self.errors.append((index, str(record["error"])))
            return
        self.done += 1
        self.spread.add(record)
        run = SweepRun(index, record)
        if run.breaches:
            self.breached += 1
        if self.keep and (len(self.kept) < self.keep or run.rank() < self.kept[-1].rank()):
            run = SweepRun(index, {k: v for k, v in record.items() if k != CPU})  # (measures)
            self.kept = sorted([*self.kept, run], key=SweepRun.rank)[: self.keep]

    def worst(self, k: int) -> list[SweepRun]:
        """The ``k`` worst runs kept: most thresholds exceeded, then most faults, then
        latest reaction."""
        return self.kept[:k]

    def write_worst(self, k: int, folder: str | Path) -> list[Path]:
        """Write the ``k`` worst runs as scenario files in ``folder`` (made if need be)."""
        folder = Path(folder)
        make_folder(folder)
        width = len(str(max(self.asked - 1, 0)))
        return [write_variant(self.scenario, folder / (f"{self.scenario.stem}-run"
                                                       f"{run.index:0{width}d}-seed{self.seed}.xml"),
                              seed=self.seed, index=run.index, jitter=self.jitter,
                              switches=self.switches)
                for run in self.worst(k)]


def results_header(command: str, jobs: list[Job], names: list[str]) -> dict[str, Any]:
    """A results file's first line: what batch it is of (a resumed one must match)."""
    return {"prima": f"{command} results", "version": 1, "jobs": [
        {"scenario": name, "runs": job.runs, "seed": job.seed, "jitter": job.jitter,
         "thresholds": job.thresholds.to_dict(), "digest": job.digest}
        for name, job in zip(names, jobs, strict=True)]}


def check_documents(scenario: Path, switches: Switches | None) -> None:
    """Load the scenario and every document it runs, as a run would: a bad one stops the
    batch here, located (LocatedError), before any run, with the lines ``prima run``
    gives for it (``prima validate``'s, :func:`prima.scenario.checked_load`, unless the
    command line swaps its FA or EA)."""
    from prima.run import Run
    from prima.scenario import checked_load

    checked_load(scenario, switches.robot if switches else None,
                 lambda: Run(scenario, **(switches.run_options() if switches else {})),
                 swapped=bool(switches and (switches.fa or switches.ea)))


def sweep(scenario: str | Path, *, runs: int, jitter: float, seed: int = 0,
          jobs: int | None = None, thresholds: Thresholds = Thresholds(),
          progress: Callable[[int, int], None] | None = None,
          switches: Switches | None = None, pool: Pool | None = None,
          results: str | Path | None = None, resume: bool = False,
          keep: int = 3) -> Sweep:
    """Run ``scenario`` ``runs`` times with its timings jittered by up to ±``jitter`` s.

    Runs go to ``pool`` (default: ``jobs`` processes, every core; one: this process);
    ``progress(done, runs)`` is called as they finish. Each run's record is written to
    ``results`` (a jsonl file) as it comes; with ``resume``, the runs it holds already
    are read back and not run again. Ctrl-C stops the pool: the result then holds the
    runs done so far, with ``interrupted`` set. Raises LocatedError for a bad scenario
    or document, ResultsError for a results file of another sweep.
    """
    if runs < 1 or not (math.isfinite(jitter) and jitter >= 0):
        raise ValueError("runs must be 1 or more and jitter a number of seconds from 0 up")
    source, jitter = Path(scenario), float(jitter)
    check_documents(source, switches)  # a bad scenario stops here, located
    name = load_scenario(source).name
    # The policy switches go to each run as prima run --policy gives them (the bundle
    # keeps the scenario's own); the worst runs' files have them written in, to replay.
    files = dataclasses.replace(switches, policies=()) if switches else None
    job = Job(bundle_scenario(source, files), runs, seed, jitter, thresholds,
              policies=switches.policies if switches else ())
    result = Sweep(source, name, runs, jitter, seed, thresholds, keep=keep, switches=switches)
    out = ResultsFile(results, results_header("sweep", [job], [name])) if results else None
    result.interrupted = collect([job], result.add, out=out, resume=resume, progress=progress,
                                 pool=lambda left: pool or pool_for(None, jobs, left))
    return result


# ---------------------------------------------------------------------------- the summary

def _cell(value: float, seconds: bool) -> str:
    if math.isinf(value):
        return "never"
    return f"{value:.2f}" if seconds else f"{value:g}"


@dataclass(frozen=True)
class _Measure:
    name: str
    value: Callable[[Mapping[str, Any]], float]
    seconds: bool = False
    limit: Callable[[Thresholds], float] | None = None


def _count(key: str) -> Callable[[Mapping[str, Any]], float]:
    return lambda record: int(record["counts"][key])


def _field(key: str) -> Callable[[Mapping[str, Any]], float]:
    return lambda record: _time(record[key])


def _limit(key: str) -> Callable[[Thresholds], float]:
    return lambda thresholds: thresholds.limit(key)


_TIMES = (
    _Measure("worst lateness (s)", _field("worst_lateness"), seconds=True),
    _Measure("worst first start (s)", _field("worst_latency"), seconds=True),
)


def _rows() -> tuple[_Measure, ...]:
    """The rows of a sweep's table: two of times, then one per measure of the registry
    (:data:`prima.judge.MEASURES`: its title, its count, its threshold)."""
    return (*_TIMES, *(_Measure(m.title, _count(m.key), limit=_limit(m.key))
                       for m in MEASURES))


def format_sweep(result: Sweep, paint: Paint = PLAIN) -> str:
    """Min / median / p95 / max of each measure over the runs, and how many breached;
    each column as wide as its content (``paint``: the header and what exceeded a
    threshold in colour, for a terminal)."""
    head = (f"{result.scenario}: {result.done} of {result.asked} runs, jitter "
            f"±{_number(result.jitter)} s, seed {result.seed}")
    if result.interrupted:
        head += " (interrupted)"
    if result.lost:
        head += f" ({len(result.lost)} lost)"
    if result.failed:
        head += f" ({result.failed} failed)"
    if not result.done:
        return head + "\n"
    table: list[list[str | Cell]] = [
        [Cell(name, (BOLD,)) for name in ("measure", "min", "median", "p95", "max",
                                           "over max")]]
    for m in _rows():
        over = 0 if m.limit is None else result.spread.over(m.name, m.limit(result.thresholds))
        table.append([m.name, *(_cell(v, m.seconds) for v in result.spread.quantiles(m.name)),
                      Cell("" if m.limit is None else str(over), (RED, BOLD) if over else ())])
    breached = f"{result.breached} of {result.done}"
    rows = [head, "", *layout(table, right=range(1, 6), minimum=(22, 8, 8, 8, 8, 8),
                              indent="  ", paint=paint), "",
            "runs exceeding a threshold: " + paint(breached, RED if result.breached else GREEN)]
    return "\n".join(rows) + "\n"


def progress_bar(out: Callable[[str], object], width: int = 30,
                 live: bool = True) -> Callable[[int, int], None]:
    """A text progress bar through ``out``: redrawn in place (``\\r``) on a terminal
    (``live``); else (a log file, CI) a line at each tenth of the runs, no more."""
    shown = [-1]

    def draw(done: int, total: int) -> None:
        filled = width * done // max(total, 1)
        bar = f"[{'#' * filled}{'.' * (width - filled)}] {done}/{total} runs"
        if live:
            out(f"\r{bar}{chr(10) if done >= total else ''}")
            return
        tenth = 10 * done // max(total, 1)
        if tenth > shown[0]:
            shown[0] = tenth
            out(bar + "\n")

    return draw
