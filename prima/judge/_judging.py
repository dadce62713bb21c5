"""Judging a trace: every measure over one pass (:func:`judge`), a file or a scenario
(:func:`judge_file`), the scenarios in a folder (:func:`find_scenarios`)."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TYPE_CHECKING, Final

from prima.errors import TraceError
from prima.judge._context import Context, Feed, Route
from prima.judge._measures import MEASURES
from prima.judge._reactions import analyse
from prima.judge._reading import Row, as_rows, read_trace
from prima.judge._report import Report
from prima.judge._thresholds import Thresholds

if TYPE_CHECKING:
    from prima.run import Switches

__all__ = ["Judging", "find_scenarios", "judge", "judge_file"]


HELD: Final = 4096
"""Lines :meth:`Judging.feed` holds at most before the judge reads them: a run judged as
it goes holds no more of its trace, however long it is."""


class Judging:
    """A trace judged as it is made: :meth:`feed` each of its lines (a jsonl dict, in
    trace order), then take the :meth:`report`. A run judged so holds at most
    :data:`HELD` of its lines (:func:`judge_file` of a scenario, a sweep's and a check's
    runs): what it keeps is the judge's own, however long the run."""

    def __init__(self, thresholds: Thresholds | None = None, name: str = "") -> None:
        self.th = thresholds if thresholds is not None else Thresholds()
        self.name = name
        self.ctx = Context(self.th)
        self.finders = [(m, m.finder()) for m in MEASURES]
        self._routes: dict[str, Route] = {}
        """What each kind of line goes to: the context's handling, then the finders
        (:meth:`_feeders`), in order."""
        self._held: list[Row] = []
        """Lines fed and not yet read (:meth:`feed`)."""

    def feed(self, row: Row) -> None:
        """One line of the trace, after the ones before it (read in batches of at most
        :data:`HELD` lines: the judge's loop is at its fastest so): a dict, its mappings
        dicts too (:data:`~prima.tracefile.Row`; :func:`judge` makes them so)."""
        held = self._held
        held.append(row)
        if len(held) >= HELD:
            self.feed_all(held)
            held.clear()

    def feed_all(self, rows: Iterable[Row]) -> None:
        """Lines of the trace, in order, after the ones before them (the judge's one
        loop: a trace judged whole goes through it once)."""
        self.ctx.feed_all(rows, self._routes, self._feeders)

    def _feeders(self, kind: str) -> list[Feed]:
        """What each line of ``kind`` is fed to, in the measures' order: the finders that
        look at that kind, each through its ``feeder`` for it if it has one (its own
        handling of that kind alone, without asking the line's kind again; None: it has
        nothing to do with it), else its ``feed``."""
        out: list[Feed] = []
        for _m, finder in self.finders:
            if finder.kinds is None or kind in finder.kinds:
                feeder: Callable[[str], Feed | None] | None = getattr(finder, "feeder", None)
                feed = finder.feed if feeder is None else feeder(kind)
                if feed is not None:
                    out.append(feed)
        return out

    def report(self) -> Report:
        """What the lines fed show."""
        self.feed_all(self._held)
        self._held.clear()
        ctx = self.ctx
        reactions = analyse(ctx, ctx.t)
        findings = {m.key: tuple(finder.finish(ctx, reactions)) for m, finder in self.finders}
        return Report(self.name, ctx.t, ctx.lines, self.th, tuple(reactions), findings)


def judge(trace: Iterable[object], *, thresholds: Thresholds | None = None,
          name: str = "") -> Report:
    """Measure a trace's naturalness: TraceLine objects or jsonl dicts, in trace order."""
    judging = Judging(thresholds, name)
    judging.feed_all(as_rows(trace))
    return judging.report()


def judge_file(path: str | Path, *, thresholds: Thresholds | None = None,
               name: str | None = None, switches: Switches | None = None) -> Report:
    """Judge a jsonl trace file, or run a scenario file in-process (writing nothing; with
    ``switches``: its FA, EA, robot or policies changed) and judge its trace. Raises
    :class:`~prima.errors.LocatedError` for a bad file."""
    path = Path(path)
    name = str(path) if name is None else name
    if path.suffix == ".jsonl":  # streamed: a long trace is never held whole
        return judge(read_trace(path), thresholds=thresholds, name=name)
    from prima.run import Run  # only now: the whole stack comes with it

    options = switches.run_options() if switches else {}
    judging = Judging(thresholds, name)
    Run(path, rows=judging.feed, **options).run()  # (judged as it goes: few lines held)
    return judging.report()


def find_scenarios(folder: str | Path) -> list[Path]:
    """The scenario files in a folder and its subfolders (maps and profiles left out;
    a file that is not even XML is kept, so that judging it reports its problem)."""
    from lxml import etree

    from prima.errors import LocatedError
    from prima.scenario import SCENARIO_NS
    from prima.xmlio import parse_xml, read_source

    found = []
    for path in sorted(Path(folder).rglob("*.xml")):
        try:
            doc = parse_xml(read_source(path, TraceError), str(path), TraceError)
        except LocatedError:
            found.append(path)
            continue
        if etree.QName(doc.root).namespace == SCENARIO_NS:
            found.append(path)
    return found
