"""Many runs at once (prima.batch): the records are the same whatever runs them and in
whatever order the runs finish; a results file is written in the order of the runs,
resumed where it stopped, refused when it is another batch's; a chunk whose worker is
lost is sent again; a sweep keeps no run's report."""

from __future__ import annotations

import concurrent.futures
import io
import json
import math
import random
import statistics
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import prima.batch._dispatch
import prima.batch._work
from prima.batch import Chunk, Inline, Job, Processes, bundle_scenario, dispatch, plan
from prima.cli import main
from prima.judge import MEASURES, Thresholds
from prima.sweep import Spread, sweep

ROOT = Path(__file__).parents[2]
SHORT = ROOT / "scenarios" / "thesis" / "fig5-7.xml"
"""A 60-second scenario: a run takes a fraction of a second."""
TOUCHED = ROOT / "scenarios" / "thesis" / "sample-08.xml"
"""Two applications, touches, answers: the records differ from run to run."""


def cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    code = main(list(argv), out=out, err=err)
    return code, out.getvalue(), err.getvalue()


def job(runs: int = 6, scenario: Path = SHORT) -> Job:
    return Job(bundle_scenario(scenario), runs, 5, 3.0, Thresholds())


# ------------------------------------------------------------ a worker's chunks

@pytest.mark.pure  # (it counts the loader's calls: compiled, Setup calls it directly)
def test_a_jobs_chunks_in_one_worker_load_its_documents_once(
        monkeypatch: pytest.MonkeyPatch) -> None:
    import prima.scenario._setup

    loads: list[str] = []
    real = prima.scenario._setup.load_document

    def counted(path: Any, profile: Any) -> Any:
        loads.append(Path(path).name)
        return real(path, profile)

    monkeypatch.setattr(prima.scenario._setup, "load_document", counted)
    prima.batch._work._last.kept = None
    short, touched = job(4), job(2, TOUCHED)
    first = prima.batch._work.run_chunk(Chunk(0, short, 0, 2))
    folder = prima.batch._work._last.kept.folder
    once = list(loads)
    assert once and len(set(once)) == len(once)  # (each document of the job, once)
    second = prima.batch._work.run_chunk(Chunk(0, short, 2, 2))
    assert loads == once
    prima.batch._work.run_chunk(Chunk(1, touched, 0, 2))
    assert len(loads) > len(once) and not folder.exists()  # (the last job's folder: gone)
    whole = prima.batch._work.run_chunk(Chunk(0, short, 0, 4))
    strip = [{k: v for k, v in r.items() if k != prima.batch._work.CPU} for r in whole]
    assert strip == [{k: v for k, v in r.items() if k != prima.batch._work.CPU}
                     for r in first + second]


# ------------------------------------------------------------ the order of the runs

class _Backwards(concurrent.futures.Executor):
    """Runs every task at once but finishes them in reverse order, four at a time (and
    the last ones when the ``total``-th task comes)."""

    def __init__(self, total: int) -> None:
        self.held: list[tuple[concurrent.futures.Future[Any], Any]] = []
        self.left = total

    def submit(self, fn: Callable[..., Any], /, *args: Any,
               **kwargs: Any) -> concurrent.futures.Future[Any]:
        future: concurrent.futures.Future[Any] = concurrent.futures.Future()
        self.held.append((future, fn(*args, **kwargs)))
        self.left -= 1
        if len(self.held) == 4 or not self.left:
            self.release()
        return future

    def release(self) -> None:
        for future, value in reversed(self.held):
            future.set_result(value)
        self.held = []


class _BackwardsPool(Inline):
    """Inline's pool, with two workers whose tasks finish in the wrong order."""

    workers = 2

    def __init__(self, total: int) -> None:
        self.made = _Backwards(total)

    def executor(self) -> concurrent.futures.Executor:
        return self.made


def test_records_come_in_the_order_of_the_runs_whatever_order_they_finish() -> None:
    jobs = [job(3), job(2)]
    pool = _BackwardsPool(5)
    got = [(r["job"], r["run"]) for r in dispatch(jobs, pool, size=1)]
    assert got == [(0, 0), (0, 1), (0, 2), (1, 0), (1, 1)]


def test_a_plan_skips_the_runs_done_and_never_spans_two_jobs() -> None:
    jobs = [job(5), job(3)]
    chunks = plan(jobs, 2, skip=3)
    assert [(c.job, c.first, c.count) for c in chunks] == [(0, 3, 2), (1, 0, 2), (1, 2, 1)]
    assert sum(c.count for c in plan(jobs, 50)) == 8


# ------------------------------------------------------------ the same whatever runs it

def _results(tmp_path: Path, name: str, **options: Any) -> bytes:
    target = tmp_path / name
    result = sweep(TOUCHED, runs=6, jitter=5.0, seed=2, results=target, **options)
    assert result.done == 6
    return target.read_bytes()


def test_the_results_are_the_same_in_this_process_and_in_worker_processes(
        tmp_path: Path) -> None:
    inline = _results(tmp_path, "inline.jsonl", pool=Inline())
    processes = _results(tmp_path, "processes.jsonl", pool=Processes(2))
    assert inline == processes
    records = [json.loads(line) for line in inline.splitlines()[1:]]
    assert [r["run"] for r in records] == list(range(6))
    assert len({json.dumps(r["counts"]) + str(r["worst_latency"]) for r in records}) > 1


def test_the_results_are_the_same_on_a_dask_cluster(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    from prima.batch._dask import Dask

    inline = _results(tmp_path, "inline.jsonl", pool=Inline())
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        on_dask = _results(tmp_path, "dask.jsonl", pool=Dask(cluster.scheduler_address))
    assert on_dask == inline


def test_a_task_lost_on_a_dask_cluster_is_sent_again(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    distributed = pytest.importorskip("distributed")
    from prima.batch._dask import Dask

    inline = _results(tmp_path, "inline.jsonl", pool=Inline())
    real = prima.batch._dispatch.run_chunk
    mark = tmp_path / "lost"  # (a file: Dask may copy the function and what it holds)

    def flaky(chunk: Chunk) -> list[dict[str, Any]]:
        if chunk.first == 0 and not mark.exists():  # as a worker killed once too often
            mark.write_text("x")
            raise distributed.comm.CommClosedError("the worker went away")
        return real(chunk)

    monkeypatch.setattr(prima.batch._dispatch, "run_chunk", flaky)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=None) as cluster:
        on_dask = _results(tmp_path, "dask.jsonl", pool=Dask(cluster.scheduler_address))
    assert mark.exists() and on_dask == inline


# ------------------------------------------------------------ results files, resumed

def _counting(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    ran: list[int] = []
    real = prima.batch._work.run_one

    def counted(spec: Job, index: int, root: Any, folder: Path, *files: Any) -> dict[str, Any]:
        ran.append(index)
        return real(spec, index, root, folder, *files)

    monkeypatch.setattr(prima.batch._work, "run_one", counted)
    return ran


def test_a_resumed_sweep_runs_only_the_rest_and_writes_the_same_file(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    whole = _results(tmp_path, "whole.jsonl", pool=Inline())
    target = tmp_path / "stopped.jsonl"

    def stop(done: int, total: int) -> None:
        if done == 4:
            raise KeyboardInterrupt

    first = sweep(TOUCHED, runs=6, jitter=5.0, seed=2, results=target, pool=Inline(),
                  progress=stop)
    assert first.interrupted and first.done == 4
    with target.open("ab") as torn:  # a record cut short as the machine went down
        torn.write(b'{"job": 0, "run": 4, "en')
    ran = _counting(monkeypatch)
    rest = sweep(TOUCHED, runs=6, jitter=5.0, seed=2, results=target, resume=True,
                 pool=Inline())
    assert ran == [4, 5] and rest.done == 6 and not rest.interrupted
    assert target.read_bytes() == whole
    assert rest.spread == sweep(TOUCHED, runs=6, jitter=5.0, seed=2, pool=Inline()).spread


def test_resuming_the_results_of_another_sweep_is_refused(tmp_path: Path) -> None:
    target = tmp_path / "seed1.jsonl"
    assert cli("sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--seed", "1", "--jobs",
               "1", "--worst", "0", "--results", str(target))[0] == 0
    code, _, err = cli("sweep", str(SHORT), "--runs", "2", "--jitter", "1", "--seed", "2",
                       "--jobs", "1", "--worst", "0", "--resume", str(target))
    assert code == 1 and "Traceback" not in err
    assert (f"{target}:1:1: error: these are the results of another batch: its "
            "jobs[0].seed is 1, not 2") in err


@pytest.mark.parametrize("found, wanted, said", [
    ({"v": 1, "jobs": [{"runs": 2}]}, {"v": 1, "jobs": [{"runs": 3}]},
     "its jobs[0].runs is 2, not 3"),
    ({"jobs": [{}, {}]}, {"jobs": [{}]}, "it has 2 jobs, not 1"),
    ({"v": 1, "extra": "x"}, {"v": 1}, 'its extra is "x", not null'),
    ({"s": "a" * 100}, {"s": "b"}, 'its s is "' + "a" * 76 + '..., not "b"'),
    ({"jobs": [{"digest": "1f"}]}, {"jobs": [{"digest": "2e"}]},
     'its jobs[0].digest is "1f", not "2e" (the scenario, or a document it runs, changed)'),
])
def test_a_header_that_differs_is_named_by_its_innermost_field(
        found: dict[str, object], wanted: dict[str, object], said: str) -> None:
    from prima.batch._results import _differs

    assert _differs(found, wanted) == said


def test_a_line_that_is_not_the_next_record_is_located(tmp_path: Path) -> None:
    target = tmp_path / "r.jsonl"
    assert cli("sweep", str(SHORT), "--runs", "3", "--jitter", "1", "--jobs", "1",
               "--worst", "0", "--results", str(target))[0] == 0
    lines = target.read_text().splitlines(keepends=True)
    target.write_text(lines[0] + lines[2] + lines[1])
    code, _, err = cli("sweep", str(SHORT), "--runs", "3", "--jitter", "1", "--jobs", "1",
                       "--worst", "0", "--resume", str(target))
    assert code == 1 and f"{target}:2:1: error: not the next run's record" in err


FORGED = [  # (what is done to the first record's line, the error, the field it points at)
    (lambda r: r.replace('"late": 0', '"late": 1' + "0" * 400),
     "field 'counts.late' is 10000000000000000...: too large a number", '"late"'),
    (lambda r: r.replace('"counts": {', '"counts": [{').replace('}, "worst_lateness"',
                                                                 '}], "worst_lateness"'),
     "field 'counts' must be an object, not [{", '"counts"'),
    (lambda r: "[" * 100_000 + "]" * 100_000,
     "not a JSON object: nested more than 16 levels deep", 17),
    (lambda r: r.replace('"worst_lateness": 0.0', '"worst_lateness": "soon"'),
     "field 'worst_lateness' must be a number, not \"soon\"", '"worst_lateness"'),
    (lambda r: r.replace('"worst_lateness": 0.0, ', ""), "field 'worst_lateness' is missing",
     1),
    (lambda r: r.replace('"run": 0', '"run": false'),
     "field 'run' must be a whole number from 0", '"run"'),
    (lambda r: r.replace('"end": 60.0', '"end": NaN'), "field 'end' is NaN, not a number",
     '"end"'),
    (lambda r: r.replace('"end": 60.0', '"end": 1e400'), "field 'end' is 1e400: too large",
     '"end"'),
    (lambda r: r.replace('"breaches": []', '"breaches": [1]'),
     "field 'breaches[0]' must be a text, not 1", '"breaches"'),
    (lambda r: r.replace('"late": 0', '"late": 0, "later": 1'),
     "field 'counts.later' is not a field of this record", '"later"'),
    (lambda r: '{"job": 0, "run": 0, "lost": 1}', "field 'lost' must be true, not 1",
     '"lost"'),
    (lambda r: '{"job": 0, "run": 0, "error": {"a": 1}}', "field 'error' must be a text",
     '"error"'),
    (lambda r: r + " !", "not a JSON object: Extra data", "!"),
]


@pytest.mark.parametrize("forge, said, at", FORGED, ids=[
    "count-10e400", "counts-array", "deep", "lateness-soon", "lateness-missing", "run-false",
    "end-nan", "end-1e400", "breach-number", "unknown-count", "lost-1", "error-object",
    "extra-data"])
def test_a_forged_record_is_located_at_its_field(
        tmp_path: Path, forge: Callable[[str], str], said: str, at: str | int) -> None:
    """A resumed results file is read by one validating reader: a record's numbers are
    bounded, its types checked, its nesting bounded; what is wrong is one located line
    that names the field, never an exception of the code that reads the records."""
    target = tmp_path / "r.jsonl"
    sweep_ = ("sweep", str(SHORT), "--runs", "3", "--jitter", "1", "--jobs", "1",
              "--worst", "0")
    assert cli(*sweep_, "--results", str(target))[0] == 0
    head, first, *_ = target.read_text().splitlines()
    forged = forge(first)
    target.write_text(f"{head}\n{forged}\n")
    code, _, err = cli(*sweep_, "--resume", str(target))
    col = forged.index(at) + 1 if isinstance(at, str) else at
    assert code == 1 and "Traceback" not in err
    assert f"{target}:2:{col}: error: {said}" in err, err
    assert len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("extra, fragment", [
    (["--executor", "spark://x:1"], "--executor spark://x:1: give processes"),
    (["--executor", "dask://host:99999"], "the port must be from 1 to 65535"),
    (["--results", "a.jsonl", "--resume", "a.jsonl"], "give it alone"),
    (["--resume", "no/such.jsonl"], "--resume: no such file"),
    (["--results", "tests"], "--results tests is a folder"),
])
def test_batch_usage_errors_exit_2(extra: list[str], fragment: str) -> None:
    code, _, err = cli("sweep", str(SHORT), "--runs", "2", "--jitter", "1", *extra)
    assert code == 2 and fragment in err, err


# ------------------------------------------------------------ memory flat in the runs

def test_the_spread_gives_the_same_quantiles_as_every_value_kept() -> None:
    draws = random.Random(4)
    for n in (1, 2, 3, 10, 101):
        values = [round(draws.choice([0.0, 0.5, 1.25, math.inf, draws.random()]), 3)
                  for _ in range(n)]
        spread = Spread()
        for v in values:
            spread.add({"counts": {m.key: 0 for m in MEASURES},
                        "worst_lateness": None if math.isinf(v) else v, "worst_latency": 0})
        ordered = sorted(values)
        p95 = ordered[max(math.ceil(0.95 * n) - 1, 0)]
        assert spread.quantiles("worst lateness (s)") == (
            min(values), statistics.median(values), p95, max(values))


def test_a_sweep_keeps_its_worst_runs_and_no_other(tmp_path: Path) -> None:
    result = sweep(TOUCHED, runs=6, jitter=5.0, seed=2, pool=Inline(), keep=2)
    assert result.done == 6 and len(result.kept) == 2
    assert sum(result.spread.values["late reactions"].values()) == 6
    ranked = sorted(result.kept, key=lambda r: r.rank())
    assert result.kept == ranked



def _wait_for_ever(started: str) -> None:
    """A task that says it started, then never ends (until its worker is stopped)."""
    import time

    Path(started).write_text("x", encoding="utf-8")
    while True:
        time.sleep(60)


def test_stopping_the_processes_ends_their_workers_then_deletes_their_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C or SIGTERM stops a batch's workers at once, busy or not (SIGTERM, then
    SIGKILL after a while), and only then deletes the folder they unpack their runs in:
    deleted under a worker still unpacking, it was left behind, in part."""
    import tempfile
    import time

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    processes = Processes(1)
    started = tmp_path / "started"
    processes.executor().submit(_wait_for_ever, str(started))
    assert processes._pool is not None
    workers = [p for each in processes._pool.pools() for p in each._processes.values()]
    try:
        deadline = time.monotonic() + 300  # (a bound, not a measure: the worker forks)
        while not started.exists() and time.monotonic() < deadline:
            time.sleep(0.01)
        assert started.exists() and [w.is_alive() for w in workers] == [True]
        processes.stop()
        assert [w.is_alive() for w in workers] == [False]
        assert not list(tmp_path.glob("prima-sweep-*"))
    finally:
        for worker in workers:
            worker.kill()


def test_stopped_while_its_pool_is_made_the_processes_leave_no_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C after the workers' folder is made and before their pool is: stopping
    deletes the folder all the same (an empty prima-sweep-* folder was left in /tmp)."""
    import tempfile

    def interrupted(*_args: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(prima.batch._dispatch, "_Recycling", interrupted)
    processes = Processes(1)
    with pytest.raises(KeyboardInterrupt):
        processes.executor()
    assert list(tmp_path.glob("prima-sweep-*"))
    processes.stop()
    assert not list(tmp_path.glob("prima-sweep-*"))


def test_a_signal_as_the_workers_folder_is_made_leaves_no_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C just as the workers' folder is made, before the processes have noted it
    (a sweep signalled as it starts: an empty prima-sweep-* folder was left in /tmp now
    and then): it is raised once the folder is noted, and stopping deletes it."""
    import os
    import signal
    import tempfile

    made = tempfile.mkdtemp

    def signalled(*args: Any, **kwargs: Any) -> str:
        folder = made(*args, **kwargs)
        os.kill(os.getpid(), signal.SIGINT)  # (its handler runs before this returns)
        return folder

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    monkeypatch.setattr(tempfile, "mkdtemp", signalled)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    processes = Processes(1)
    try:
        with pytest.raises(KeyboardInterrupt):
            processes.executor()
    finally:
        signal.signal(signal.SIGINT, previous)
    processes.stop()
    assert not list(tmp_path.glob("prima-sweep-*"))


def test_a_signal_as_the_batch_ends_stops_its_workers_and_leaves_no_folder(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Ctrl-C while a finished batch waits for its workers to exit: they are stopped, and
    their folder deleted after them (it was left behind, the workers too)."""
    import tempfile

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))
    waited = prima.batch._dispatch._Recycling.shutdown
    workers: list[Any] = []

    def interrupted(self: Any, wait: bool = True, **kwargs: Any) -> None:
        if wait:  # (the end's wait, not the stop's)
            workers.extend(p for each in self.pools() for p in each._processes.values())
            raise KeyboardInterrupt
        waited(self, wait, **kwargs)

    monkeypatch.setattr(prima.batch._dispatch._Recycling, "shutdown", interrupted)
    with pytest.raises(KeyboardInterrupt):
        list(dispatch([job(2)], Processes(2), size=1))
    assert workers and not any(w.is_alive() for w in workers)
    assert not list(tmp_path.glob("prima-sweep-*"))
