"""Where a batch's runs go: one :class:`concurrent.futures.Executor` seam.

A :class:`Pool` hands out an executor: this process (:class:`Inline`), worker
processes on this machine (:class:`Processes`, the default), or a Dask cluster
(``prima.batch._dask``, imported only when asked for). :func:`dispatch` sends the
jobs' runs to it in chunks, and yields every run's record in the order of the runs,
whatever order they finish in, so that what a batch writes is the same whatever
runs it. A chunk whose worker is lost (killed, out of memory, its machine gone) is
sent again; lost again, each of its runs is sent alone; a run lost even alone is a
record that says so (``"lost": true``) and the others go on.
"""

from __future__ import annotations

import heapq
import itertools
import concurrent.futures
import concurrent.futures.process
import math
import multiprocessing
import shutil
import signal
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any, Protocol

from prima.batch._results import ResultsFile
from prima.batch._work import CPU, Chunk, Job, forget_unpacked, run_chunk, unpack_in
from prima.errors import ClusterError
from prima.escape import shown_path
from prima.signals import deferred, sticky

__all__ = ["CHUNK", "RECYCLE", "Inline", "Pool", "Processes", "chunk_size", "collect", "dispatch",
           "plan"]

CHUNK = 50
"""Runs per task at most: a Dask task costs about 3 ms against a run's 50-130 ms."""

Record = dict[str, Any]


class Pool(Protocol):
    """Where runs go: an executor, and how to recover when it breaks."""

    @property
    def workers(self) -> int:
        """How many runs it runs at once."""

    @property
    def chunk(self) -> int:
        """The most runs it takes in one task."""

    def executor(self) -> concurrent.futures.Executor:
        """An executor to submit to (a fresh one once the last is broken)."""

    def broken(self, exc: BaseException) -> bool:
        """Whether ``exc``, a task's failure, left the executor unable to take more."""

    @property
    def poll(self) -> float | None:
        """Seconds between two calls of :meth:`watch` while no task finishes (None: it
        is never called; the pool's own tasks always end)."""

    def watch(self, idle: float) -> None:
        """No task finished for ``idle`` seconds: raise ClusterError if the pool cannot
        finish them (a cluster gone, without workers, or stalled)."""

    def stop(self) -> None:
        """Stop now (Ctrl-C): cancel what has not started, end what runs."""

    def close(self) -> None:
        """Done: let the workers go."""


class _Now(concurrent.futures.Executor):
    """An executor that runs each task as it is submitted, in this process."""

    def submit(self, fn: Callable[..., Any], /, *args: Any,
               **kwargs: Any) -> concurrent.futures.Future[Any]:
        future: concurrent.futures.Future[Any] = concurrent.futures.Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as exc:  # noqa: BLE001 - a task's failure goes in its future
            future.set_exception(exc)
        return future


class Inline:
    """Every run in this process, one after another (``--jobs 1``)."""

    workers = 1
    chunk = 1
    poll = None

    def executor(self) -> concurrent.futures.Executor:
        return _Now()

    def broken(self, exc: BaseException) -> bool:
        return False

    def watch(self, idle: float) -> None:
        pass

    def stop(self) -> None:
        forget_unpacked()  # (the runs' folder: Ctrl-C or SIGTERM ends the process bare)

    def close(self) -> None:
        forget_unpacked()


def _worker(scratch: str) -> None:
    """Workers leave Ctrl-C to the parent, which stops the pool, and SIGTERM ends them
    at once, without a word (as the parent's :meth:`Processes.stop` does; they are
    forked with the parent's handlers, which note these signals meanwhile:
    :func:`prima.signals.deferred`). They unpack their bundles in the pool's
    ``scratch`` folder."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    unpack_in(scratch)


RECYCLE = 10
"""Tasks a worker process takes before fresh ones take over (a pool's worth of such
tasks per pool). What a run leaves behind in a process (C libraries' memory, which
grows a little with every run, and pages the allocator never gives back) goes with
it: a sweep's memory stays flat in its number of runs. At 50 runs a task, a fresh
process costs one fork per 500 runs."""


STOPPING = 2.0
"""Seconds :meth:`Processes.stop` waits for a worker it sent SIGTERM to exit before it
kills it (so that the workers' folder is deleted after them)."""


class _Recycling(concurrent.futures.Executor):
    """Worker processes that are replaced after :data:`RECYCLE` tasks each: the tasks
    go to one pool of ``workers`` processes until it has taken ``workers * RECYCLE``;
    the next task waits until that pool has finished what it took and its processes
    have exited, and a fresh pool takes it. The two never overlap: the whole process
    tree holds at most ``workers`` workers at any time, so its memory stays flat however
    many pools a batch goes through (a retiring pool that went on beside the fresh one
    held twice the workers while its last tasks ran). What this costs is the last tasks'
    unevenness, once per pool: the workers that finish first wait for the last one."""

    def __init__(self, workers: int, recycle: int, scratch: str) -> None:
        self.workers = workers
        self.limit = workers * recycle
        self.scratch = scratch
        self._pool: concurrent.futures.ProcessPoolExecutor | None = None
        self._taken = 0
        self._futures: list[concurrent.futures.Future[Any]] = []

    def submit(self, fn: Callable[..., Any], /, *args: Any,
               **kwargs: Any) -> concurrent.futures.Future[Any]:
        if self._pool is None or self._taken >= self.limit:
            self._retire()
            self._pool = concurrent.futures.ProcessPoolExecutor(
                self.workers, mp_context=multiprocessing.get_context(), initializer=_worker,
                initargs=(self.scratch,))
            self._taken = 0
        with deferred():  # (a new pool forks its workers here)
            future = self._pool.submit(fn, *args, **kwargs)
        self._taken += 1
        self._futures.append(future)
        return future

    def _retire(self) -> None:
        """Let the current pool finish what it took, and wait for its processes to exit.
        (The tasks' results stay in their futures, for the batch to collect; Ctrl-C
        meanwhile stops the pool as it would any time, :meth:`Processes.stop`.)"""
        pool = self._pool
        if pool is None:
            return
        concurrent.futures.wait(self._futures)
        pool.shutdown()  # (it waits for its processes to exit)
        self._pool, self._futures = None, []

    def pools(self) -> list[concurrent.futures.ProcessPoolExecutor]:
        """The pool that may have processes (none, or the current one)."""
        return [self._pool] if self._pool else []

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        for pool in self.pools():
            pool.shutdown(wait=wait, cancel_futures=cancel_futures)
        self._pool, self._futures = None, []


class Processes:
    """``jobs`` worker processes on this machine, replaced by fresh ones every
    :data:`RECYCLE` tasks. A worker that dies breaks its pool (every task it took and
    did not finish fails with it): a fresh pool takes the work on.

    The workers unpack their runs' files in one temporary folder of the batch's, which
    :meth:`close` and :meth:`stop` delete: a worker killed outright (out of memory,
    SIGKILL) cannot delete its own, and would leave them in the system's."""

    chunk = CHUNK
    poll = None

    def __init__(self, jobs: int, recycle: int = RECYCLE) -> None:
        self.workers = jobs
        self.recycle = recycle
        self._pool: _Recycling | None = None
        self._broken = False
        self._scratch: str | None = None

    def executor(self) -> concurrent.futures.Executor:
        if self._pool is None or self._broken:
            if self._pool is not None:
                self._pool.shutdown(wait=False, cancel_futures=True)
            if self._scratch is None:
                with deferred():  # (a signal once it is made, before it is noted, left it)
                    self._scratch = tempfile.mkdtemp(prefix="prima-sweep-")
            self._pool = _Recycling(self.workers, self.recycle, self._scratch)
            self._broken = False
        return self._pool

    def broken(self, exc: BaseException) -> bool:
        if isinstance(exc, concurrent.futures.process.BrokenProcessPool):
            self._broken = True
        return self._broken

    def watch(self, idle: float) -> None:
        pass

    def stop(self) -> None:
        pool, self._pool = self._pool, None
        stopping = [process for each in (pool.pools() if pool is not None else [])
                    for process in list((getattr(each, "_processes", None) or {}).values())]
        if pool is not None:  # (its processes taken first: its shutdown forgets them)
            pool.shutdown(wait=False, cancel_futures=True)
        for process in stopping:
            process.terminate()
        for process in stopping:  # (SIGTERM ends a worker at once, once _worker has run;
            process.join(STOPPING)  # one forked a moment before notes it and goes on)
            if process.is_alive():
                process.kill()
                process.join()
        self._forget_scratch()  # (made even if its pool was not: Ctrl-C in between)

    def close(self) -> None:
        if self._pool is not None:  # (kept until its processes have exited: stop() ends
            self._pool.shutdown()   # them if a Ctrl-C comes while it waits)
            self._pool = None
        self._forget_scratch()

    def _forget_scratch(self) -> None:
        """Delete the workers' folder (their processes have all exited)."""
        with deferred():  # (a signal meanwhile would leave it half deleted)
            scratch, self._scratch = self._scratch, None
            if scratch is not None:
                shutil.rmtree(scratch, ignore_errors=True)


def chunk_size(runs: int, workers: int, largest: int = CHUNK) -> int:
    """Runs per task: at most ``largest``, and small enough that every worker gets
    several tasks (a progress bar moves, a lost task costs little)."""
    return max(1, min(largest, math.ceil(runs / max(1, workers * 4))))


def plan(jobs: Sequence[Job], size: int, skip: int = 0) -> list[Chunk]:
    """The jobs' runs in chunks of ``size``, in order, the first ``skip`` runs of the
    whole batch left out (done already)."""
    out: list[Chunk] = []
    for number, job in enumerate(jobs):
        start = min(job.runs, max(0, skip))
        skip -= job.runs
        for first in range(start, job.runs, size):
            out.append(Chunk(number, job, first, min(size, job.runs - first)))
    return out


class _Order:
    """Records put back in the order of the runs: each job's runs in turn."""

    def __init__(self, jobs: Sequence[Job], skip: int) -> None:
        self.offsets: list[int] = []
        total = 0
        for job in jobs:
            self.offsets.append(total)
            total += job.runs
        self.total = total
        self.next = skip
        self.waiting: dict[int, Record] = {}

    def position(self, chunk: Chunk) -> int:
        return self.offsets[chunk.job] + chunk.first

    def add(self, records: Sequence[Record]) -> Iterator[Record]:
        for record in records:
            self.waiting[self.offsets[record["job"]] + record["run"]] = record
        while self.next in self.waiting:
            yield self.waiting.pop(self.next)
            self.next += 1


_ALONE = 2
"""The attempt from which a chunk's runs are sent one at a time, each alone."""
_LOST = 3
"""The attempt at which a run is given up for lost."""


class _Flight:
    """A batch's chunks: those to send (the first run's first), and those out."""

    def __init__(self, jobs: Sequence[Job], pool: Pool, size: int, skip: int,
                 check: Callable[[], None]) -> None:
        self.pool = pool
        self.check = check
        """Raises a signal that came and was lost (:func:`prima.signals.sticky`): called
        after each wait."""
        self.order = _Order(jobs, skip)
        self.queue: list[tuple[int, int, int, Chunk]] = []
        """(position, attempt, count, chunk): the chunks to send, the first run's first."""
        self.pushed = itertools.count()
        for chunk in plan(jobs, size, skip):
            self.push(chunk, 0)
        self.window = 2 * pool.workers if pool.workers > 1 else 1
        self.ahead = self.window * size * 4
        self.flying: dict[concurrent.futures.Future[list[Record]], tuple[int, Chunk]] = {}
        self.executor = pool.executor()
        self.since = time.monotonic()
        """When a task last finished (or the first was sent)."""

    def push(self, chunk: Chunk, attempt: int) -> None:
        heapq.heappush(self.queue, (self.order.position(chunk), attempt, next(self.pushed),
                                    chunk))

    def again(self, chunk: Chunk, attempt: int) -> list[Record]:
        """Send a lost chunk again: whole, then each run alone; lost alone, it is lost."""
        if attempt >= _LOST:
            return [{"job": chunk.job, "run": chunk.first, "lost": True}]
        for one in chunk.single() if attempt >= _ALONE else [chunk]:
            self.push(one, attempt)
        return []

    def send(self) -> None:
        """Send chunks while the window allows: at most ``window`` out, none too far
        ahead of the first run not finished, a chunk sent alone alone."""
        while self.queue and len(self.flying) < self.window:
            position, attempt, _, chunk = self.queue[0]
            alone = attempt >= _ALONE
            if self.flying and (alone or position >= self.order.next + self.ahead):
                return
            entry = heapq.heappop(self.queue)
            try:
                self.flying[self.executor.submit(run_chunk, chunk)] = (attempt, chunk)
            except Exception as exc:  # noqa: BLE001 - the executor broke meanwhile
                if not self.pool.broken(exc):
                    raise
                heapq.heappush(self.queue, entry)
                self.executor = self.pool.executor()
                continue
            if alone:
                return

    def collect(self) -> list[Record]:
        """Wait for a chunk to finish: the records of every chunk finished (a lost one's
        runs sent again)."""
        while True:  # (a pool that may never finish its tasks is watched meanwhile)
            done, _ = concurrent.futures.wait(self.flying, timeout=self.pool.poll,
                                              return_when=concurrent.futures.FIRST_COMPLETED)
            self.check()
            if done:
                break
            self.pool.watch(time.monotonic() - self.since)
        self.since = time.monotonic()
        broke = False
        records: list[Record] = []
        for future in done:
            attempt, chunk = self.flying.pop(future)
            try:
                records += future.result()
            except Exception as exc:  # noqa: BLE001 - its worker was lost: again
                broke = self.pool.broken(exc) or broke
                records += self.again(chunk, attempt + 1)
        if broke:  # every task still out fails with the broken pool: take them back
            for future, (attempt, chunk) in self.flying.items():
                future.cancel()
                records += self.again(chunk, attempt + 1)
            self.flying.clear()
            self.executor = self.pool.executor()
        return records


def dispatch(jobs: Sequence[Job], pool: Pool, *, size: int, skip: int = 0,
             progress: Callable[[int], None] | None = None) -> Iterator[Record]:
    """Every run's record of ``jobs`` after the first ``skip``, in the order of the runs.

    Chunks of ``size`` runs go to ``pool``, at most twice its workers at once (and never
    so far ahead of the first run not finished that many records wait to be put in
    order). ``progress(finished)`` is called as runs finish. Ctrl-C stops the pool; the
    records yielded so far are the batch's first runs, in order.
    """
    finished = skip
    try:
        with sticky() as stop_if_signalled:  # (a Ctrl-C a finalizer dropped stops it too)
            flight = _Flight(jobs, pool, size, skip, stop_if_signalled)
            while flight.queue or flight.flying:
                flight.send()
                records = flight.collect()
                yield from flight.order.add(records)
                finished += len(records)
                if records and progress is not None:
                    progress(finished)
            pool.close()  # (Ctrl-C while it waits for the workers to exit: they are stopped)
    except BaseException:  # Ctrl-C, or a fault of the batch's own: stop the workers now
        with deferred():  # (a second Ctrl-C meanwhile is noted, and the stop finishes)
            pool.stop()
        raise


def collect(jobs: Sequence[Job], take: Callable[[Record], None], *,
            pool: Callable[[int], Pool], out: ResultsFile | None = None,
            resume: bool = False,
            progress: Callable[[int, int], None] | None = None) -> bool:
    """Every run's record of ``jobs`` to ``take``, in the order of the runs, and to the
    results file ``out`` as it comes; with ``resume``, the records ``out`` holds already
    are taken first and their runs not run again (a record run now says its run's CPU
    time, :data:`~._work.CPU`, which is not written). ``pool(runs_left)`` gives the pool;
    ``progress(done, total)`` is called as runs finish. True if Ctrl-C stopped it
    (what was taken is the batch's first runs)."""
    total = sum(j.runs for j in jobs)
    skip = 0
    if out is not None and resume:
        for record in out.previous(jobs):
            take(record)
            skip += 1
    done = skip
    if out is not None:
        out.open(resume=resume)
    try:
        chosen = pool(total - skip)
        size = chunk_size(total - skip, chosen.workers, chosen.chunk)
        for record in dispatch(jobs, chosen, size=size, skip=skip,
                               progress=None if progress is None
                               else (lambda finished: progress(finished, total))):
            take(record)
            if out is not None:
                out.write({k: v for k, v in record.items() if k != CPU})
            done += 1
    except KeyboardInterrupt:
        return True
    except ClusterError as exc:
        if out is None:
            raise
        kept = shown_path(out.path)
        raise ClusterError(f"{exc}; the {done} run(s) done are in {kept}: --resume {kept} "
                           "goes on with the others") from exc
    finally:
        if out is not None:
            out.close()
    return False
