"""What a worker does: run a chunk of a job's runs, judge each, and say what it found as
a record (a JSON object) that is the same on any machine, in any worker.

A :class:`Job` is one scenario swept: its :class:`~._variants.Bundle`, how many runs,
the seed and jitter of their timings, the thresholds they are judged by, and what
else each record says (an :class:`Analysis`: ``prima check`` adds whose each failure
is and what of the EA ran). A :class:`Chunk` is some of a job's runs, sent to a worker
as one task (:func:`run_chunk`).
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import shutil
import tempfile
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from multiprocessing.util import Finalize
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

from lxml import etree

from prima.batch._variants import Bundle, rng, shift_timings
from prima.collecting import fewer_collections
from prima.errors import LocatedError
from prima.judge import Report, Thresholds

if TYPE_CHECKING:
    from prima.run import Loaded  # (imported where runs are made, as Run is)

__all__ = ["CPU", "Analysis", "Chunk", "Job", "Observer", "record_of", "run_chunk", "run_one",
           "forget_unpacked", "unpack_in"]


class Observer(Protocol):
    """Sees every line of one run's trace (as its jsonl dict), then its judged report."""

    def feed(self, row: Mapping[str, Any]) -> None: ...

    def finish(self, report: Report) -> Any:
        """What the run's record says under the analysis' key (JSON)."""


class Analysis(Protocol):
    """What a job's records say beyond the judge's counts (picklable: it goes to the
    workers with the job)."""

    @property
    def key(self) -> str:
        """The record's key for what it finds."""

    @property
    def shape(self) -> Any:
        """What a record says under :attr:`key`, as a shape (``prima.batch.shape_problem``):
        a resumed results file's records are checked against it."""

    def observer(self) -> Observer:
        """A fresh observer for one run."""


@dataclass(frozen=True)
class Job:
    """One scenario swept: ``runs`` runs, run ``i`` jittered by ``(seed, i)``."""

    bundle: Bundle
    runs: int
    seed: int
    jitter: float
    thresholds: Thresholds
    analysis: Analysis | None = None
    policies: tuple[tuple[str, bool], ...] = ()
    """The command line's policy switches, over the profile's and the scenario's: each
    run is given them as ``prima run --policy`` gives them (``Run(policies=...)``)."""

    @property
    def digest(self) -> str:
        """A hash of what the runs run: the bundle, and the policy switches if any (a
        results file's header names it; a resumed batch must match it)."""
        if not self.policies:
            return self.bundle.digest
        h = hashlib.sha256(self.bundle.digest.encode())
        h.update(b"\0policies\0" + json.dumps(list(self.policies)).encode())
        return h.hexdigest()


@dataclass(frozen=True)
class Chunk:
    """Runs ``first`` to ``first + count - 1`` of job number ``job``: one task."""

    job: int
    spec: Job
    first: int
    count: int

    def single(self) -> list[Chunk]:
        """The chunk as chunks of one run each."""
        return [Chunk(self.job, self.spec, i, 1) for i in range(self.first,
                                                                 self.first + self.count)]


def _finite(value: float) -> float | None:
    """A time for JSON: None stands for infinite (a reaction that never started)."""
    return None if math.isinf(value) else value


def record_of(report: Report) -> dict[str, Any]:
    """What a sweep keeps of a judged run: each measure's count, the worst times, the
    thresholds exceeded."""
    return {
        "end": report.end,
        "reactions": len(report.reactions),
        "counts": report.counts(),
        "worst_lateness": _finite(report.worst_lateness()),
        "worst_latency": _finite(report.worst_latency()),
        "breaches": report.breaches(),
    }


def run_one(job: Job, index: int, root: etree._Element, folder: Path,
            files: Loaded | None = None) -> dict[str, Any]:
    """Run ``index`` of ``job`` (its scenario's parsed ``root``, unpacked in ``folder``),
    judged: its record (without its job's number). A run that fails is a record with
    its ``error``. Runs given the same ``files`` load the job's documents once."""
    from prima.judge import Judging
    from prima.run import Run

    variant = copy.deepcopy(root)
    shift_timings(variant, rng(job.seed, index), job.jitter)
    path = folder / f"run-{index}.xml"
    path.write_bytes(etree.tostring(variant, encoding="UTF-8", xml_declaration=True))
    record: dict[str, Any] = {"run": index}
    try:
        judging = Judging(job.thresholds, f"run {index}")
        observer = job.analysis.observer() if job.analysis is not None else None

        feed: Callable[[dict[str, Any]], None] = judging.feed  # (few lines are kept)
        if observer is not None:
            watch, judged = observer.feed, judging.feed

            def feed(row: dict[str, Any]) -> None:
                watch(row)
                judged(row)

        Run(path, files=files, rows=feed, policies=dict(job.policies)).run()
        report = judging.report()
        record.update(record_of(report))
        if observer is not None and job.analysis is not None:
            record[job.analysis.key] = observer.finish(report)
    except LocatedError as exc:
        record["error"] = str(exc.problems[0]) if exc.problems else str(exc)
    except Exception as exc:  # noqa: BLE001 - a run's fault is its record, not the batch's
        record["error"] = f"{type(exc).__name__}: {exc}"
    finally:
        path.unlink(missing_ok=True)
    return record


CPU = "cpu"
"""The key of a record that says how long its run took: the CPU seconds of the thread
that ran it (a worker process', or one of a Dask worker's threads). It differs from
machine to machine and run to run, so it is never written to a results file (which is
the same whatever runs it): :func:`prima.batch.collect` gives it to whoever takes the
record, then drops it."""


def run_chunk(chunk: Chunk) -> list[dict[str, Any]]:
    """Run a chunk's runs in order (in a worker, or in this process): their records,
    each with its job's number and its :data:`CPU` time."""
    spec = chunk.spec
    with fewer_collections():
        folder, root, files = _unpacked(spec.bundle)
        out = []
        for index in range(chunk.first, chunk.first + chunk.count):
            start = time.thread_time()
            record = run_one(spec, index, root, folder, files)
            out.append({"job": chunk.job, **record,
                        CPU: round(time.thread_time() - start, 6)})
        return out


_scratch: str | None = None
"""The folder this process unpacks bundles in (:func:`unpack_in`); None: the system's
temporary folder."""


def unpack_in(folder: str | None) -> None:
    """Unpack this process' bundles in ``folder`` from now on: a worker process of this
    machine's pool unpacks in a folder its sweep owns, which the sweep deletes at its end,
    so that a worker killed outright (which deletes nothing) leaves nothing behind."""
    global _scratch
    _scratch = folder


class _Unpacked:
    """A bundle unpacked in a folder of its own, its scenario parsed, and the
    :class:`~prima.run.Loaded` its runs load their documents through."""

    def __init__(self, bundle: Bundle) -> None:
        from prima.run import Loaded  # (imported where runs are made, as Run is)

        self.digest = bundle.digest
        self.folder = Path(tempfile.mkdtemp(prefix="prima-runs-", dir=_scratch))
        self.delete = Finalize(self, shutil.rmtree, args=(self.folder,),
                               kwargs={"ignore_errors": True}, exitpriority=0)
        """Deletes the folder: once, when called, when the object is dropped (its thread
        ended), or as the process ends (a worker process too: multiprocessing runs
        these, where it skips ``atexit``)."""
        self.root = etree.fromstring(bundle.unpack(self.folder).read_bytes())
        self.files = Loaded(unchanging=True)  # (nothing else writes in the folder)


_last = threading.local()
"""Each thread's last bundle unpacked (:func:`_unpacked`)."""


def forget_unpacked() -> None:
    """Delete the folder of this thread's last bundle unpacked, now. A batch run in this
    process (``--jobs 1``) calls it as it ends, however it ends: a command a signal ended
    ends its process without the exit handlers that would delete it."""
    kept: _Unpacked | None = getattr(_last, "kept", None)
    if kept is not None:
        _last.kept = None
        kept.delete()


def _unpacked(bundle: Bundle) -> tuple[Path, etree._Element, Loaded]:
    """``bundle`` unpacked, its scenario parsed, and its documents' :class:`Loaded`:
    the same as for this thread's last chunk if that chunk was of the same bundle. A
    sweep's job is several chunks (``prima sweep --runs 20`` on one worker is four of
    five runs), and most go to the same worker one after another: they load and check
    the documents once, not once a chunk (each time about a fifth of a run on sample 10).

    Kept per thread (a Dask worker runs chunks in several threads at once, each in a
    folder of its own) and one bundle at a time, so a long sweep's memory stays flat;
    the folder of the bundle before is deleted as the next is unpacked (and the last
    one when the process ends)."""
    kept: _Unpacked | None = getattr(_last, "kept", None)
    if kept is None or kept.digest != bundle.digest:
        if kept is not None:
            _last.kept = None
            kept.delete()
        kept = _last.kept = _Unpacked(bundle)
    return kept.folder, kept.root, kept.files
