"""Judging a trace: every measure over one pass (:func:`judge`), a file or a scenario
(:func:`judge_file`), the scenarios in a folder (:func:`find_scenarios`)."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

from prima.errors import TraceError
from prima.judge._context import Context
from prima.judge._measures import MEASURES, Finder
from prima.judge._reactions import analyse
from prima.judge._reading import as_rows, read_trace
from prima.judge._report import Report
from prima.judge._thresholds import Thresholds

if TYPE_CHECKING:
    from prima.run import Switches

__all__ = ["find_scenarios", "judge", "judge_file"]


def judge(trace: Iterable[object], *, thresholds: Thresholds | None = None,
          name: str = "") -> Report:
    """Measure a trace's naturalness: TraceLine objects or jsonl dicts, in trace order."""
    th = thresholds if thresholds is not None else Thresholds()
    ctx = Context(th)
    finders = [(m, m.finder()) for m in MEASURES]
    fed: dict[str, list[Finder]] = {}  # the finders each kind of line goes to, in order
    for row in as_rows(trace):
        ctx.feed(row)
        kind = row["kind"]
        those = fed.get(kind)
        if those is None:
            those = fed[kind] = [f for _m, f in finders if f.kinds is None or kind in f.kinds]
        for finder in those:
            finder.feed(row, ctx)
        ctx.fed(row)
    reactions = analyse(ctx, ctx.t)
    findings = {m.key: tuple(finder.finish(ctx, reactions)) for m, finder in finders}
    return Report(name, ctx.t, ctx.lines, th, tuple(reactions), findings)


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
    return judge(Run(path, **options).run(), thresholds=thresholds, name=name)


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
