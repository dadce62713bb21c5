"""A batch's results file: one JSON object per line, a header, then every run's record
in the order of the runs.

Records are written as the runs finish (put back in order), so a batch keeps none of
them in memory, and what it writes is the same whatever ran it. A batch stopped
half-way (Ctrl-C, a machine lost) leaves its first runs' records: resumed
(:meth:`ResultsFile.previous`), it checks the header is its own, reads them back,
drops a last line cut short, and goes on from the next run, so the file ends as
the one an uninterrupted batch writes.

The file is written in place, each record flushed as it is written
(:class:`prima.output.Log`): a batch killed outright (SIGKILL, a machine lost) keeps
the records of the runs it finished, to go on from with ``--resume``. A record that
cannot be written (a full disk) stops the batch with an
:class:`~prima.errors.OutputError` that says how many runs' records the file keeps.
"""

from __future__ import annotations

import json
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from prima.batch._records import (
    MAX_LINE,
    Unreadable,
    decode,
    field_column,
    record_shape,
    shape_problem,
    shown,
)
from prima.batch._work import Job
from prima.errors import OutputError, Problem, ResultsError, Severity
from prima.escape import json_line
from prima.output import Log, shown as shown_file
from prima.signals import deferred

__all__ = ["ResultsFile"]


def _problem(path: Path, line: int, message: str, col: int = 1) -> ResultsError:
    return ResultsError([Problem(str(path), line, col, Severity.ERROR, message)])


def _differs(found: Any, wanted: Any, where: str = "") -> str:
    """Where a header differs, readably: its innermost field that does (``jobs[0].seed``,
    the first job's seed), with both values."""
    if isinstance(found, dict) and isinstance(wanted, dict):
        for key in [*wanted, *(k for k in found if k not in wanted)]:
            if found.get(key) != wanted.get(key):
                return _differs(found.get(key), wanted.get(key),
                                f"{where}.{key}" if where else str(key))
    if isinstance(found, list) and isinstance(wanted, list) and len(found) == len(wanted):
        for i, (a, b) in enumerate(zip(found, wanted, strict=True)):
            if a != b:
                return _differs(a, b, f"{where}[{i}]")
    if isinstance(found, list) and isinstance(wanted, list):
        return f"it has {len(found)} {where or 'entries'}, not {len(wanted)}"
    said = f"its {where or 'header'} is {shown(found)}, not {shown(wanted)}"
    if where.endswith(".digest"):
        said += " (the scenario, or a document it runs, changed)"
    return said


class ResultsFile:
    """The results file at ``path`` of the batch whose header is ``header``."""

    def __init__(self, path: str | Path, header: Mapping[str, Any]) -> None:
        self.path = Path(path)
        self.header: dict[str, Any] = json.loads(json_line(dict(header)))
        self.kept = 0
        """Bytes of the file that hold the header and whole records (resumed)."""
        self._kept_records = 0
        self.records = 0
        """The runs whose records the file holds."""
        self._out: Log | None = None

    def previous(self, jobs: Sequence[Job]) -> Iterator[dict[str, Any]]:
        """The records of the runs of ``jobs`` done, in order, checked (a missing file:
        none). Raises ResultsError, located at the line and the field, for a file of
        another batch, a line that is no JSON within bounds (:mod:`._records`), a record
        that is not the next run's or a field of the wrong type or size."""
        try:
            source = self.path.open("rb")
        except FileNotFoundError:
            return
        except OSError as exc:
            raise _problem(self.path, 1, f"cannot read: {exc.strerror or exc}") from exc
        with source:
            self.kept = self._kept_records = 0
            order = _runs([j.runs for j in jobs])
            for number, raw in enumerate(iter(lambda: source.readline(MAX_LINE + 1), b""),
                                         start=1):
                if not raw.endswith(b"\n") and len(raw) <= MAX_LINE:
                    return  # cut short as it was written: run again
                try:
                    row = decode(raw.removesuffix(b"\n"))
                except Unreadable as exc:
                    raise _problem(self.path, number, str(exc), exc.col) from None
                if not isinstance(row, dict):
                    raise _problem(self.path, number, "not a JSON object")
                if number == 1:
                    if row != self.header:
                        raise _problem(self.path, 1, "these are the results of another "
                                       f"batch: {_differs(row, self.header)}")
                else:
                    yield self._record(raw, number, row, next(order, None), jobs)
                    self._kept_records += 1
                self.kept += len(raw)

    def _record(self, raw: bytes, number: int, row: dict[str, Any],
                expected: tuple[int, int] | None, jobs: Sequence[Job]) -> dict[str, Any]:
        """A line's record, checked: the next run's, every field as a worker writes it."""
        line = raw.decode("utf-8")
        for key in ("job", "run"):
            wrong = shape_problem(row.get(key), int, key) if key in row else (key, "is missing")
            if wrong is not None:
                raise _problem(self.path, number, f"field '{wrong[0]}' {wrong[1]}",
                               field_column(line, key))
        if expected is None:
            raise _problem(self.path, number, "a record after the last run of the batch")
        if (row["job"], row["run"]) != expected:
            raise _problem(self.path, number, f"not the next run's record (job {expected[0]}, "
                                              f"run {expected[1]})")
        wrong = shape_problem(row, record_shape(row, jobs[row["job"]].analysis))
        if wrong is not None:
            field, message = wrong
            raise _problem(self.path, number, f"field '{field}' {message}",
                           field_column(line, field))
        return row

    def open(self, *, resume: bool) -> None:
        """Start writing: a new file with its header, or (``resume``) after the records
        :meth:`previous` read."""
        going_on = resume and self.kept > 0
        self._out = Log(self.path, keep=self.kept if going_on else 0)
        self.records = self._kept_records if going_on else 0
        if not going_on:
            self._write(json_line(self.header) + "\n", header=True)

    def write(self, record: Mapping[str, Any]) -> None:
        """One run's record, at the end of the file (flushed: a stop keeps it)."""
        self._write(json_line(dict(record)) + "\n")
        self.records += 1

    def _write(self, line: str, header: bool = False) -> None:
        if self._out is None:
            raise RuntimeError("the results file is not open")
        try:
            with deferred():  # (Ctrl-C keeps a record whole: after it, not in it)
                self._out.write(line)
        except OSError as exc:
            reason = exc.strerror or str(exc)
            said = f"cannot write {shown_file(self.path)}: {reason[:1].lower() + reason[1:]}"
            if header:
                raise OutputError(said) from exc
            raise OutputError(f"{said}; the batch stopped, the records of its first "
                              f"{self.records} run(s) are kept in it: go on with --resume "
                              "once there is room") from exc

    def close(self) -> None:
        """Close the file: it holds every record written so far (a batch stopped
        half-way goes on from them with ``--resume``)."""
        if self._out is not None:
            out, self._out = self._out, None
            out.close()


def _runs(counts: Sequence[int]) -> Iterator[tuple[int, int]]:
    """Every run of jobs of these many runs, in order, as (job, run)."""
    for job, n in enumerate(counts):
        for run in range(n):
            yield job, run
