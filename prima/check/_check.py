"""``prima check``: an EA against every FA and robot it may meet, at any timing.

The matrix has a row per FA and a column per robot profile; a cell runs the EA beside
that FA on that robot, on the EA's own scenarios or on generated visits
(:mod:`._visits`), each swept with jittered timings (:mod:`prima.batch`, so on this
machine or a Dask cluster, with a results file and resuming). Every failure a run
shows is attributed (:mod:`._observe`): a cell fails *by the EA* when one of its
failures is the EA's, and only then does the check fail; a failure caused by the FA
is reported as the FA's.
"""

from __future__ import annotations

import tempfile
from collections import Counter
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from prima.batch import Job, Pool, ResultsFile, bundle_scenario, collect, pool_for
from prima.check._coverage import Coverage
from prima.check._observe import CheckAnalysis
from prima.check._places import Destination, destinations, known_places, map_for
from prima.check._visits import VISITS, Visit, visit_scenario
from prima.dsl import Document, load_document, load_profile, structure_problems
from prima.errors import DocumentError, LocatedError
from prima.judge import Thresholds
from prima.output import make_folder
from prima.scenario import load_map, load_scenario, scenario_references
from prima.sim import WorldMap
from prima.sweep import SweepRun, results_header, write_variant
from prima.xmlio import parse_xml, read_source

__all__ = ["Cell", "Check", "Failure", "Verdict", "check"]


class Verdict:
    """What a cell says (its first word in the matrix)."""

    OK = "ok"
    EA = "FAIL"
    """A failure attributed to the EA."""
    OTHER = "fail"
    """Failures, none of them the EA's (the FA's, another EA's, the mediator's)."""
    ERROR = "error"
    """Runs failed or were lost: nothing can be said."""
    NA = "n/a"
    """The FA cannot run on that robot, or beside the EA on its map."""


@dataclass
class Failure:
    """One kind of failure in a cell: the same measure, culprit, rule and place."""

    measure: str
    app: str
    role: str
    rule: str
    waited: str
    at: str
    finding: str
    """One such finding, as ``prima judge`` words it."""
    runs: int = 0


@dataclass
class _Scenario:
    path: Path
    name: str
    job: Job


@dataclass
class Cell:
    """The EA beside one FA on one robot."""

    fa: Path
    robot: Path
    problem: str = ""
    """Why the cell cannot run (empty: it ran)."""
    scenarios: list[_Scenario] = field(default_factory=list)
    asked: int = 0
    done: int = 0
    breached: int = 0
    by_ea: int = 0
    """Runs with a failure attributed to the EA."""
    measures: Counter[str] = field(default_factory=Counter)
    """Runs that exceeded each measure's threshold."""
    ea_measures: Counter[str] = field(default_factory=Counter)
    failures: dict[tuple[str, ...], Failure] = field(default_factory=dict)
    worst: list[tuple[tuple[int, int, int, float, int], int, SweepRun]] = field(
        default_factory=list)
    """The worst runs: (rank, scenario number, run)."""
    worst_start: float = 0.0
    """The latest first start of a reaction that started (s)."""
    worst_lateness: float = 0.0
    errors: list[str] = field(default_factory=list)
    failed: int = 0
    lost: int = 0
    written: list[Path] = field(default_factory=list)
    """The worst runs, written as scenario files."""
    maps: list[Path] = field(default_factory=list)
    """The maps its scenarios run on (one for generated visits), in their order."""
    cpu: float = 0.0
    """The CPU time (s) its runs took in their workers, summed (the runs this check ran:
    those read back from a resumed results file count nothing)."""

    @property
    def name(self) -> str:
        return f"{self.fa.stem} / {self.robot.stem}"

    @property
    def map_names(self) -> str:
        """Its maps by name (``office``; several: ``office, museum``; none known: ``?``)."""
        return ", ".join(dict.fromkeys(m.stem for m in self.maps)) or "?"

    @property
    def verdict(self) -> str:
        if self.problem:
            return Verdict.NA
        if self.by_ea:
            return Verdict.EA
        if self.failed or self.lost:
            return Verdict.ERROR
        return Verdict.OTHER if self.breached else Verdict.OK

    def worst_measure(self) -> str:
        """The measure most runs exceeded (the EA's first), as ``splits 12/50``; for a
        cell without failures, its worst first start."""
        counts = self.ea_measures or self.measures
        if counts:
            key, n = max(counts.items(), key=lambda kv: (kv[1], kv[0]))
            return f"{key} {n}/{self.done}"
        if self.verdict == Verdict.OK:
            return f"start <= {self.worst_start:.2f} s"
        return ""

    def add(self, scenario: int, record: Mapping[str, Any]) -> None:
        cpu = record.get("cpu")
        if isinstance(cpu, (int, float)):
            self.cpu += cpu
        if record.get("lost"):
            self.lost += 1
            return
        if "error" in record:
            self.failed += 1
            if len(self.errors) < 5:
                self.errors.append(f"run {record['run']}: {record['error']}")
            return
        self.done += 1
        run = SweepRun(int(record["run"]), record)
        latency = record.get("worst_latency")
        if latency is not None:  # (a reaction that never started and was not late: none)
            self.worst_start = max(self.worst_start, latency)
        self.worst_lateness = max(self.worst_lateness, run.worst_lateness())
        failures = (record.get("check") or {}).get("failures") or []
        if not run.breaches:
            return
        self.breached += 1
        self.measures.update({f["measure"] for f in failures})
        mine = {f["measure"] for f in failures if f["role"] == "ea"}
        self.ea_measures.update(mine)
        self.by_ea += bool(mine)
        seen: set[tuple[str, ...]] = set()
        for f in failures:  # (alike when the measure, culprit, rule and place are)
            key = (f["measure"], f["app"], f["role"], f["rule"], f["at"])
            kept = self.failures.setdefault(key, Failure(
                f["measure"], f["app"], f["role"], f["rule"], f["waited"], f["at"],
                f["finding"]))
            if key not in seen:
                kept.runs += 1
                seen.add(key)
        rank = (-len(mine), *run.rank())
        self.worst = sorted([*self.worst, (rank, scenario, run)])[:3]


@dataclass
class Check:
    """A check's outcome: the EA, its cells (rows FA, columns robot) and its coverage."""

    ea: Path
    document: Document
    fas: list[Path]
    robots: list[Path]
    cells: list[Cell]
    coverage: Coverage
    runs: int
    jitter: float
    seed: int
    interrupted: bool = False
    visits: bool = True
    """The scenarios were generated visits (not the EA's own)."""
    map: Path | None = None
    """The map of the generated visits (None: the EA's own scenarios, each its own)."""

    def cell(self, fa: Path, robot: Path) -> Cell:
        return next(c for c in self.cells if c.fa == fa and c.robot == robot)

    @property
    def failed_by_ea(self) -> list[Cell]:
        return [c for c in self.cells if c.verdict == Verdict.EA]

    @property
    def total_runs(self) -> int:
        return sum(c.done for c in self.cells)


def _profiled(path: Path, robot: Path, profiles: dict[Path, Any]) -> Document:
    profile = profiles.get(robot)
    if profile is None:
        profile = profiles[robot] = load_profile(robot)
    return load_document(path, profile)


def _a_document(path: Path) -> None:
    """Raise DocumentError (located) when ``path`` is no PXML document on any robot: not
    XML, or not what the schema allows. (What a robot lacks makes only its cells n/a.)"""
    doc = parse_xml(read_source(path, DocumentError), str(path), DocumentError)
    problems = structure_problems(doc)
    if problems:
        raise DocumentError(problems)


def _problem(exc: LocatedError) -> str:
    return str(exc.problems[0]) if exc.problems else str(exc)


def _maps(folder: Path | None) -> list[tuple[Path, WorldMap]]:
    return [(p, load_map(p)) for p in sorted(folder.glob("*.xml"))] if folder else []


_World = tuple[Path, WorldMap]


def _world(document: Document, folder: Path | None, given: Path | None) -> _World:
    """The map of the generated visits: ``given`` (``--map``), which must have every place
    the EA can go to that can be known; else the first map of ``folder`` that has them
    all, when every place the EA can go to can be known (:mod:`._places`). Raises
    ValueError saying which places are missing, or which Command goes where nobody can
    know, located in the EA."""
    found = destinations(document)
    places = known_places(found)
    if given is not None:
        world = load_map(given)
        missing = sorted(places - {p.name for p in world.places})
        if missing:
            raise ValueError(f"--map {given} lacks {_places_at(missing, found, document)}")
        return given, world
    unknown = [d for d in found if d.places is None]
    if unknown:
        first = unknown[0]
        more = f" (and {len(unknown) - 1} more Command(s))" if len(unknown) > 1 else ""
        raise ValueError(f"{first.where(document)}: {first.command} goes to a place nobody "
                         f"can know before it runs ({first.why}){more}: give --map MAP, a "
                         "map with the places it can go to (or --scenario)")
    candidates = _maps(folder)
    if not candidates:  # (an install without the shipped maps)
        where = f" (no {folder}/*.xml)" if folder else ""
        raise ValueError(f"no map to make visits on{where}: give --map or --scenario")
    chosen = map_for(document, candidates)
    if chosen is None:
        raise ValueError(f"no map in {folder} has every place {document.name} can go to "
                         f"({_places_at(sorted(places), found, document)}): give --map or "
                         "--scenario")
    return chosen


def _places_at(names: Sequence[str], found: Sequence[Destination], document: Document) -> str:
    """Places, each with the first Command that goes there (``panel-1 (ea.pxml:67:72:
    TopologicalMove)``)."""
    said = []
    for name in names:
        first = next(d for d in found if d.places is not None and name in d.places)
        said.append(f"{name} ({first.where(document)}: {first.command})")
    return ", ".join(said)


def _cell_scenarios(cell: Cell, ea: Path, scenarios: Sequence[Path], world: _World | None,
                    visits: Sequence[Visit], spec: tuple[int, int, float, Thresholds],
                    profiles: dict[Path, Any], scratch: Path) -> None:
    """The cell's jobs: its scenarios (or visits) with the FA, the EA and the robot in."""
    from prima.run import Run, Switches

    runs, seed, jitter, thresholds = spec
    cell.maps = [world[0]] if world is not None and not scenarios else [
        ref.path for path in scenarios for ref in scenario_references(path) if ref.role == "map"]
    try:
        ea_doc = _profiled(ea, cell.robot, profiles)
        fa_doc = _profiled(cell.fa, cell.robot, profiles)
    except LocatedError as exc:
        cell.problem = _problem(exc)
        return
    paths: list[Path] = list(scenarios)
    if not scenarios and world is not None:
        for visit in visits:
            path = scratch / f"{cell.fa.stem}-{visit.name}.xml"
            if not path.exists():
                path.write_text(visit_scenario(visit, ea_doc, fa_doc, world, (ea, cell.fa)),
                                encoding="utf-8")
            paths.append(path)
    switches = Switches(str(cell.fa), str(ea), str(cell.robot))
    analysis = CheckAnalysis(ea.name)
    for path in paths:
        try:
            name = load_scenario(path).name
            Run(path, **switches.run_options())  # the documents, on this map and robot
        except LocatedError as exc:
            cell.problem = _problem(exc)
            cell.scenarios = []
            return
        job = Job(bundle_scenario(path, switches), runs, seed, jitter, thresholds, analysis)
        cell.scenarios.append(_Scenario(path, name, job))
    cell.asked = runs * len(cell.scenarios)


def check(ea: str | Path, *, fas: Sequence[Path], robots: Sequence[Path],
          scenarios: Sequence[Path] = (), maps: Path | None = None, map_file: Path | None = None,
          runs: int = 20, jitter: float = 5.0, seed: int = 0, until: float = 180.0,
          thresholds: Thresholds = Thresholds(), pool: Pool | None = None,
          results: str | Path | None = None, resume: bool = False, out: Path | None = None,
          worst: int = 1, progress: Callable[[int, int], None] | None = None,
          visitors: Sequence[str] = VISITS) -> Check:
    """Check the EA ``ea`` beside every FA of ``fas`` on every robot of ``robots``, on its
    own ``scenarios`` or, without, on generated visits (on ``map_file``, else the first
    map in the folder ``maps`` that has every place the EA can go to): each swept ``runs``
    times with timings jittered by up to ``jitter`` s. The ``worst`` worst runs of each
    failing cell are written into ``out``. Raises LocatedError for an EA that cannot be
    loaded or an FA that is no PXML document, ValueError when no map has its places (or
    ``map_file`` lacks some, or nobody can know some before the EA runs and no
    ``map_file`` is given).
    ``visitors``: the generated visits' visitors (default: all of :data:`VISITS`)."""
    ea_path = Path(ea)
    document = _loaded(ea_path, robots)
    for fa in fas:  # (one that cannot run on a robot is that cell's n/a)
        _a_document(fa)
    for scenario in scenarios:  # a scenario of the EA's own with errors stops the check
        load_scenario(scenario)
    world = None if scenarios else _world(document, maps, map_file)
    visits = [Visit(v, until) for v in visitors]
    coverage = Coverage(document)
    cells = [Cell(fa, robot) for fa in fas for robot in robots]
    result = Check(ea_path, document, list(fas), list(robots), cells, coverage, runs,
                   float(jitter), seed, visits=not scenarios,
                   map=world[0] if world is not None else None)
    profiles: dict[Path, Any] = {}
    with tempfile.TemporaryDirectory(prefix="prima-check-") as scratch:
        for cell in cells:
            _cell_scenarios(cell, ea_path, scenarios, world, visits,
                            (runs, seed, float(jitter), thresholds), profiles, Path(scratch))
        _run(result, pool, results, resume, progress)
        if out is not None and worst:
            _write_worst(result, out, worst)
    return result


def _loaded(ea: Path, robots: Sequence[Path]) -> Document:
    """The EA loaded on the first robot it can run on: on another, its cells are n/a (a
    device that one robot lacks, say). Raises the first robot's LocatedError when it runs
    on none of them."""
    failed: list[LocatedError] = []
    for robot in robots:
        try:
            return load_document(ea, load_profile(robot))
        except LocatedError as exc:
            failed.append(exc)
    raise failed[0]


def _run(result: Check, pool: Pool | None, results: str | Path | None, resume: bool,
         progress: Callable[[int, int], None] | None) -> None:
    owners: list[tuple[Cell, int]] = []
    jobs: list[Job] = []
    names: list[str] = []
    for cell in result.cells:
        for number, scenario in enumerate(cell.scenarios):
            owners.append((cell, number))
            jobs.append(scenario.job)
            names.append(f"{cell.fa.name} {cell.robot.name} {scenario.name}")
    if not jobs:
        return
    out = ResultsFile(results, results_header("check", jobs, names)) if results else None

    def take(record: Mapping[str, Any]) -> None:
        cell, number = owners[int(record["job"])]
        cell.add(number, record)
        coverage = (record.get("check") or {}).get("coverage")
        if coverage:
            result.coverage.add(coverage)

    if collect(jobs, take, out=out, resume=resume, progress=progress,
               pool=lambda left: pool or pool_for(None, None, left)):
        result.interrupted = True


def _write_worst(result: Check, folder: Path, k: int) -> None:
    """Each failing cell's ``k`` worst runs as scenario files that replay them."""
    from prima.run import Switches

    for cell in result.cells:
        if cell.verdict not in (Verdict.EA, Verdict.OTHER):
            continue
        make_folder(folder)
        switches = Switches(str(cell.fa), str(result.ea), str(cell.robot))
        for _rank, number, run in cell.worst[:k]:
            scenario = cell.scenarios[number]
            name = (f"{cell.fa.stem}-{cell.robot.stem}-{scenario.name}-run{run.index}"
                    f"-seed{result.seed}.xml")
            cell.written.append(write_variant(scenario.path, folder / name, seed=result.seed,
                                              index=run.index, jitter=result.jitter,
                                              switches=switches))
