"""Sweep a scenario: run it many times with its timings jittered, judge every run.

A scenario is one situation at fixed times; the user and the building would
never keep them to the tenth of a second. :func:`sweep` re-runs a scenario N
times, each time with its user's timed actions (``at``), its answer rules'
delays (``after``) and its scheduled messages, sounds and events (``at``)
shifted by random offsets uniform in ±jitter, and judges each run
(:mod:`prima.judge`). The order the scenario gives is kept: a shifted user
action is never earlier than the previous shifted one (messages likewise among
themselves), no time goes below 0 and an answer's delay stays at least 0.1 s (an
early answer, said over the prompt, stays at least 0.1 s before the prompt's end).

Run ``i``'s offsets come from ``random.Random`` seeded with the sweep's seed and
``i``, so results are the same whatever the number of parallel jobs. Each
variant is an ordinary scenario file (:func:`write_variant`): the worst runs can
be written out and replayed with ``prima run`` or ``prima judge``.
"""

from __future__ import annotations

import concurrent.futures
import concurrent.futures.process
import copy
import math
import multiprocessing
import os
import random
import signal
import statistics
import tempfile
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from prima.errors import ScenarioError
from prima.escape import shown_path
from prima.judge import MEASURES, Report, Thresholds, judge
from prima.output import make_folder, written
from prima.sim import load_scenario
from prima.term import BOLD, GREEN, PLAIN, RED, Cell, Paint, layout
from prima.xmlio import local_name, parse_xml, read_source

if TYPE_CHECKING:
    from prima.run import Switches

__all__ = ["MIN_ANSWER_DELAY", "Sweep", "SweepRun", "format_sweep", "progress_bar", "sweep",
           "write_variant"]

MIN_ANSWER_DELAY = 0.1
"""The shortest delay (s) an answer rule keeps after jitter."""

_TIMED = frozenset({"say", "touch", "walk", "leave", "follow", "stop"})
"""The user's timed actions (children of ``<user>`` with ``at``)."""
_SCHEDULED = frozenset({"message", "sound", "event"})
"""The environment's scheduled inputs (children of ``<scenario>`` with ``at``)."""
_PATHS = {"map": ("href",), "apps": ("fa", "ea"), "ea": ("href",), "robot": ("profile",),
          "zone": ("ea",)}
"""Attributes that name files, relative to the scenario file."""


# ---------------------------------------------------------------------------- variants

def _number(value: float) -> str:
    """A time as the scenario writes it: to the millisecond, no trailing zeros."""
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def _jitter(root: etree._Element, rng: random.Random, jitter: float) -> None:
    """Jitter a scenario's timings in place: one draw per timed element, in document
    order; a shifted action is never earlier than the one before it."""
    user = next((c for c in root if isinstance(c.tag, str) and local_name(c) == "user"), None)
    last = 0.0
    for el in user if user is not None else ():
        if not isinstance(el.tag, str):
            continue
        if local_name(el) == "answer":
            given = float(el.get("after", "1.0"))
            after = given + rng.uniform(-jitter, jitter)
            # an early answer (over the prompt) stays early, a late one late
            el.set("after", _number(max(after, MIN_ANSWER_DELAY) if given >= 0
                                    else min(after, -MIN_ANSWER_DELAY)))
        elif local_name(el) in _TIMED:
            last = max(last, float(el.get("at", "0")) + rng.uniform(-jitter, jitter))
            el.set("at", _number(last))
    last = 0.0
    for el in root:
        if isinstance(el.tag, str) and local_name(el) in _SCHEDULED:
            last = max(last, float(el.get("at", "0")) + rng.uniform(-jitter, jitter))
            el.set("at", _number(last))


def _repath(root: etree._Element, source: Path, relative_to: Path | None) -> None:
    """File paths made absolute, or relative to ``relative_to``."""
    apps = [c for c in root if isinstance(c.tag, str) and local_name(c) == "apps"]
    more = [c for a in apps for c in a if isinstance(c.tag, str) and local_name(c) == "ea"]
    for el in [*root, *more]:
        if not isinstance(el.tag, str):
            continue
        for attribute in _PATHS.get(local_name(el), ()):
            value = el.get(attribute)
            if value is None:
                continue
            target = (source.parent / value).resolve()
            if relative_to is not None:
                el.set(attribute, Path(os.path.relpath(target, relative_to.resolve())).as_posix())
            else:
                el.set(attribute, str(target))


def _rng(seed: int, index: int) -> random.Random:
    return random.Random(f"prima-sweep:{seed}:{index}")


def _switch(root: etree._Element, switches: Switches) -> None:
    """Write the command line's switches into a scenario: its FA and EA, its robot's
    profile (absolute paths, made relative with the others), its policy switches."""
    ns = etree.QName(root).namespace
    children = [c for c in root if isinstance(c.tag, str)]
    named = {local_name(c): c for c in children}
    apps = named.get("apps")
    if apps is not None:
        for attribute, value in (("fa", switches.fa), ("ea", switches.ea)):
            if value is not None:
                apps.set(attribute, str(Path(value).resolve()))
    robot = named.get("robot")
    if robot is not None and switches.robot is not None:
        robot.set("profile", str(Path(switches.robot).resolve()))
    if robot is not None and switches.policies:
        after = robot
        for c in children:
            if local_name(c) == "policy":
                after = c
        for name, on in switches.policies:
            policy = etree.Element(f"{{{ns}}}policy" if ns else "policy",
                                   name=name, state="on" if on else "off")
            after.addnext(policy)
            after = policy


def write_variant(scenario: str | Path, path: str | Path, *, seed: int, index: int,
                  jitter: float, absolute: bool = False,
                  switches: Switches | None = None) -> Path:
    """Write run ``index`` of a sweep of ``scenario`` as a scenario file at ``path``
    (with ``switches``: the command line's FA, EA, robot and policies written in).

    Its file paths are relative to ``path``'s folder (or absolute, with ``absolute``),
    so ``prima run`` replays it exactly.
    """
    source, path = Path(scenario), Path(path)
    doc = parse_xml(read_source(source, ScenarioError), str(source), ScenarioError)
    root = copy.deepcopy(doc.root.getroottree()).getroot()
    _jitter(root, _rng(seed, index), jitter)
    if switches:
        _switch(root, switches)
    _repath(root, source, None if absolute else path.parent)
    before = [etree.tostring(c, encoding="unicode") for c in root.itersiblings(preceding=True)]
    named = shown_path(source.name).replace("--", "- -")  # (no '--' inside a comment)
    note = (f"<!-- prima sweep: run {index} of {named} (seed {seed}, jitter "
            f"{_number(jitter)} s): the user's actions, answer delays and scheduled inputs "
            "shifted -->")
    text = "\n".join(['<?xml version="1.0" encoding="UTF-8"?>', *reversed(before), note,
                      etree.tostring(root, encoding="unicode")])
    with written(path) as out:
        out.write(text + "\n")
    return path


# ---------------------------------------------------------------------------- runs

@dataclass(frozen=True)
class SweepRun:
    """One run of a sweep, judged."""

    index: int
    report: Report

    @property
    def breaches(self) -> int:
        """How many thresholds it exceeded."""
        return len(self.report.breaches())


@dataclass(frozen=True)
class _Task:
    scenario: Path
    folder: Path
    seed: int
    index: int
    jitter: float
    thresholds: Thresholds
    switches: Switches | None = None


def _work(task: _Task) -> SweepRun:
    """Write one variant, run it, judge it (in a worker process, or in this one)."""
    from prima.run import Run

    path = write_variant(task.scenario, task.folder / f"run-{task.index}.xml", seed=task.seed,
                         index=task.index, jitter=task.jitter, absolute=True,
                         switches=task.switches)
    report = judge(Run(path).run(), thresholds=task.thresholds, name=f"run {task.index}")
    path.unlink()
    return SweepRun(task.index, report)


def _quiet() -> None:
    """Workers leave Ctrl-C to the parent, which stops the pool."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _pool(jobs: int) -> concurrent.futures.Executor:
    """Where a sweep's runs go: ``jobs`` worker processes (the seam for another
    :class:`concurrent.futures.Executor`)."""
    return concurrent.futures.ProcessPoolExecutor(
        jobs, mp_context=multiprocessing.get_context(), initializer=_quiet)


def _stop(pool: concurrent.futures.Executor) -> None:
    """Stop a pool now: cancel what has not started, end the workers (they ignore
    Ctrl-C), wait for nothing."""
    pool.shutdown(wait=False, cancel_futures=True)
    processes = getattr(pool, "_processes", None) or {}
    for process in list(processes.values()):
        process.terminate()


def _round(tasks: dict[int, _Task], jobs: int) -> Iterator[SweepRun]:
    """Run ``tasks`` on a pool of ``jobs`` workers, each result as it comes (its task
    taken out of ``tasks``); a worker that dies breaks the pool: the round ends there,
    its unfinished tasks left in ``tasks``."""
    pool = _pool(min(jobs, len(tasks)))
    try:
        futures = [pool.submit(_work, task) for task in tasks.values()]
        for future in concurrent.futures.as_completed(futures):
            try:
                result = future.result()
            except concurrent.futures.process.BrokenProcessPool:
                continue  # a worker died: every run not finished is lost with it
            del tasks[result.index]
            yield result
    except BaseException:  # Ctrl-C, a run's own error: stop the workers now
        _stop(pool)
        raise
    pool.shutdown()


def _results(tasks: list[_Task], jobs: int, lost: list[int]) -> Iterator[SweepRun]:
    """Every task's run, as each finishes. A worker process that dies (killed, out of
    memory) takes the runs not finished with it: they are run again in a fresh pool;
    if a worker dies again, each run still not finished is run alone, and one whose
    worker dies even so is named in ``lost`` (the others finish)."""
    if jobs <= 1 or len(tasks) <= 1:
        yield from map(_work, tasks)
        return
    pending = {task.index: task for task in tasks}
    for _ in range(2):
        yield from _round(pending, jobs)
        if not pending:
            return
    for index, task in sorted(pending.items()):
        alone = {index: task}
        yield from _round(alone, 1)
        if alone:
            lost.append(index)


@dataclass(frozen=True)
class Sweep:
    """A sweep's runs, in run order (fewer than asked if it was interrupted)."""

    scenario: Path
    name: str
    """The scenario's name."""
    asked: int
    jitter: float
    seed: int
    thresholds: Thresholds
    runs: tuple[SweepRun, ...] = ()
    interrupted: bool = False
    lost: tuple[int, ...] = ()
    """Runs whose worker process died each time they ran, alone too (never judged)."""
    switches: Switches | None = None
    """The command line's FA, EA, robot and policies, if any (the worst runs' files
    have them written in)."""

    @property
    def breached(self) -> int:
        """How many runs exceeded a threshold."""
        return sum(1 for run in self.runs if run.breaches)

    def worst(self, k: int) -> list[SweepRun]:
        """The ``k`` worst runs: most thresholds exceeded, then latest reaction."""
        ranked = sorted(self.runs, key=lambda r: (-r.breaches, -r.report.worst_lateness(),
                                                  r.index))
        return ranked[:k]

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


def sweep(scenario: str | Path, *, runs: int, jitter: float, seed: int = 0,
          jobs: int | None = None, thresholds: Thresholds = Thresholds(),
          progress: Callable[[int, int], None] | None = None,
          switches: Switches | None = None) -> Sweep:
    """Run ``scenario`` ``runs`` times with its timings jittered by up to ±``jitter`` s.

    Runs go in parallel on ``jobs`` processes (default: every core); ``progress(done,
    runs)`` is called after each. Ctrl-C stops the pool: the result then holds the runs
    done so far, with ``interrupted`` set. Raises ScenarioError for a bad scenario.
    """
    if runs < 1 or not (math.isfinite(jitter) and jitter >= 0):
        raise ValueError("runs must be 1 or more and jitter a number of seconds from 0 up")
    source = Path(scenario)
    name = load_scenario(source).name  # a bad scenario stops here, located
    jobs = min(jobs or os.cpu_count() or 1, runs)  # never more workers than runs
    done: dict[int, SweepRun] = {}
    lost: list[int] = []
    interrupted = False
    with tempfile.TemporaryDirectory(prefix="prima-sweep-") as folder:
        tasks = [_Task(source, Path(folder), seed, i, jitter, thresholds, switches)
                 for i in range(runs)]
        try:
            for result in _results(tasks, jobs, lost):
                done[result.index] = result
                if progress is not None:
                    progress(len(done), runs)
        except KeyboardInterrupt:
            interrupted = True
    return Sweep(source, name, runs, jitter, seed, thresholds,
                 tuple(done[i] for i in sorted(done)), interrupted, tuple(lost), switches)


# ---------------------------------------------------------------------------- the summary

def _p95(values: list[float]) -> float:
    """The 95th percentile, nearest rank."""
    ordered = sorted(values)
    return ordered[max(math.ceil(0.95 * len(ordered)) - 1, 0)]


def _cell(value: float, seconds: bool) -> str:
    if math.isinf(value):
        return "never"
    return f"{value:.2f}" if seconds else f"{value:g}"


@dataclass(frozen=True)
class _Measure:
    name: str
    value: Callable[[Report], float]
    seconds: bool = False
    limit: Callable[[Thresholds], float] | None = None


def _count(key: str) -> Callable[[Report], float]:
    return lambda report: len(report.of(key))


def _limit(key: str) -> Callable[[Thresholds], float]:
    return lambda thresholds: thresholds.limit(key)


_MEASURES = (
    _Measure("worst lateness (s)", Report.worst_lateness, seconds=True),
    _Measure("worst first start (s)", Report.worst_latency, seconds=True),
    *(_Measure(m.title, _count(m.key), limit=_limit(m.key)) for m in MEASURES),
)
"""The rows of a sweep's table: two of times, then one per measure (its table's row)."""


def format_sweep(result: Sweep, paint: Paint = PLAIN) -> str:
    """Min / median / p95 / max of each measure over the runs, and how many breached;
    each column as wide as its content (``paint``: the header and what exceeded a
    threshold in colour, for a terminal)."""
    head = (f"{result.scenario}: {len(result.runs)} of {result.asked} runs, jitter "
            f"±{_number(result.jitter)} s, seed {result.seed}")
    if result.interrupted:
        head += " (interrupted)"
    if result.lost:
        head += f" ({len(result.lost)} lost)"
    if not result.runs:
        return head + "\n"
    table: list[list[str | Cell]] = [
        [Cell(name, (BOLD,)) for name in ("measure", "min", "median", "p95", "max",
                                           "over max")]]
    reports = [run.report for run in result.runs]
    for m in _MEASURES:
        values = [float(m.value(r)) for r in reports]
        over = 0 if m.limit is None else sum(v > m.limit(result.thresholds) for v in values)
        table.append([m.name, *(_cell(f(values), m.seconds) for f in
                                (min, statistics.median, _p95, max)),
                      Cell("" if m.limit is None else str(over), (RED, BOLD) if over else ())])
    breached = f"{result.breached} of {len(result.runs)}"
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
