"""How a check is shown: the matrix and its failures, the coverage, JUnit XML for CI,
a short Markdown summary."""

from __future__ import annotations

from xml.sax.saxutils import escape, quoteattr

from prima.check._check import Cell, Check, Verdict
from prima.check._coverage import KINDS, spans
from prima.check._visits import VISITS
from prima.escape import terminal

__all__ = ["cell_line", "format_check", "format_coverage", "junit", "markdown"]

_ROLE = {"ea": "the EA's", "fa": "the FA's", "other": "another EA's",
         "mediator": "no application's"}
_SHOWN = 3
"""Failures shown per cell."""


def _cell_text(cell: Cell) -> str:
    if cell.verdict == Verdict.NA:
        return "n/a"
    if cell.verdict == Verdict.ERROR:
        return f"error ({cell.failed + cell.lost} runs)"
    whose = {Verdict.EA: " EA", Verdict.OTHER: " FA"}.get(cell.verdict, "")
    if cell.verdict == Verdict.OTHER and any(f.role != "fa" for f in cell.failures.values()):
        whose = " other"
    return f"{cell.verdict}{whose}  {cell.worst_measure()}".rstrip()


def matrix(result: Check) -> list[str]:
    """Rows FA, columns robot: each cell's verdict and its worst measure."""
    head = ["FA \\ robot", *(r.stem for r in result.robots)]
    rows = [[fa.stem, *(_cell_text(result.cell(fa, r)) for r in result.robots)]
            for fa in result.fas]
    widths = [max(len(row[i]) for row in [head, *rows]) for i in range(len(head))]
    out = []
    for row in [head, *rows]:
        out.append("  " + "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)).rstrip())
    return out


def _failures(cell: Cell) -> list[str]:
    ranked = sorted(cell.failures.values(), key=lambda f: (f.role != "ea", -f.runs, f.measure,
                                                           f.at, f.rule))
    rows = []
    for f in ranked[:_SHOWN]:
        rows.append(f"    {f.measure} in {f.runs} run(s): {_ROLE.get(f.role, f.role)}, "
                    f"{f.app}{' ' + f.at if f.at else ''}: {f.rule}")
        if f.waited:
            rows.append(f"      waited for {f.waited}")
    if len(ranked) > _SHOWN:
        rows.append(f"    ... and {len(ranked) - _SHOWN} more kind(s) of failure")
    return rows


def _where(result: Check) -> str:
    """What the cells ran on: the generated visits' map, or the EA's own scenarios."""
    if result.visits and result.map is not None:
        return (f"generated visits ({', '.join(VISITS)}) on the map {result.map.stem} "
                f"({terminal(str(result.map))})")
    return "its own scenarios, each on its own map"


def _seconds(cell: Cell) -> str:
    return f"{cell.cpu:.1f} s" if cell.cpu >= 0.05 or not cell.cpu else f"{cell.cpu:.3f} s"


def cell_line(cell: Cell) -> str:
    """One cell: its FA, robot and map, its verdict, its runs and their CPU time."""
    runs = "" if cell.verdict == Verdict.NA else f"; {cell.done} run(s) judged, {_seconds(cell)}"
    return (f"{cell.fa.stem} on {cell.robot.stem}, map {terminal(cell.map_names)}: "
            f"{_cell_text(cell)}{runs}")


def format_check(result: Check) -> str:
    """The matrix, a line per cell (its FA, robot and map), each failing cell's failures
    and worst runs, the coverage."""
    head = (f"{terminal(str(result.ea))}: {result.document.name} beside {len(result.fas)} FA(s) "
            f"on {len(result.robots)} robot(s), {_where(result)}, {result.runs} runs each, "
            f"jitter ±{result.jitter:g} s, seed {result.seed}"
            + (" (interrupted)" if result.interrupted else ""))
    rows = [head, "", *matrix(result), "", *(cell_line(c) for c in result.cells), ""]
    for cell in result.cells:
        if cell.verdict == Verdict.NA:
            rows.append(f"{cell.name}: n/a: {terminal(cell.problem)}")
        elif cell.verdict == Verdict.ERROR:
            rows += [f"{cell.name}: {cell.failed} run(s) failed, {cell.lost} lost"]
            rows += [f"    {terminal(e)}" for e in cell.errors]
        elif cell.verdict in (Verdict.EA, Verdict.OTHER):
            whose = (f"{cell.by_ea} of them the EA's" if cell.by_ea
                     else "none of them the EA's")
            rows.append(f"{cell.name}: {cell.breached} of {cell.done} runs failed, {whose}")
            rows += _failures(cell)
            rows += [f"    worst run: {terminal(str(p))}" for p in cell.written]
            if cell.failed or cell.lost:  # (shown too: a run that failed judges nothing)
                rows += [f"    and {cell.failed} run(s) failed, {cell.lost} lost"]
                rows += [f"    {terminal(e)}" for e in cell.errors]
    rows += ["", *format_coverage(result).rstrip("\n").splitlines()]
    failing = len(result.failed_by_ea)
    others = sum(c.verdict == Verdict.OTHER for c in result.cells)
    rows += ["", f"{len(result.cells)} cell(s), {result.total_runs} runs: {failing} failed by "
                 f"the EA, {others} by others only"]
    return "\n".join(rows) + "\n"


def format_coverage(result: Check) -> str:
    """How much of the EA the check exercised, by kind, with what it never exercised."""
    cov = result.coverage
    name = result.ea.name
    rows = [f"coverage of {name}: {cov.percent:.0f}% ({len(cov.items) - len(cov.missed())} of "
            f"{len(cov.items)})"]
    for kind in KINDS:
        every, missed = cov.of(kind), cov.missed(kind)
        rows.append((f"  {kind:<9} {len(every) - len(missed):>3}/{len(every):<3}"
                     + (f" never: {', '.join(f'{i.label} ({i.line})' for i in missed[:6])}"
                        if missed else "")
                     + (f", ... {len(missed) - 6} more" if len(missed) > 6 else "")).rstrip())
    lines = cov.lines()
    rows.append(f"  lines not wholly exercised: {spans(lines)}" if lines
                else "  every line wholly exercised")
    return "\n".join(rows) + "\n"


def junit(results: list[Check]) -> str:
    """JUnit XML: a test suite per EA, a test case per cell (a cell the EA fails is a
    failure; one failed by others only passes, with what failed in its output)."""
    suites = [line for result in results for line in _suite(result)]
    return "\n".join(['<?xml version="1.0" encoding="UTF-8"?>', "<testsuites>", *suites,
                      "</testsuites>"]) + "\n"


def _properties(cell: Cell) -> str:
    """A test case's FA, robot and map(s), as JUnit properties (the files' paths)."""
    named = [("fa", cell.fa), ("robot", cell.robot), *(("map", m) for m in
                                                      dict.fromkeys(cell.maps))]
    return "<properties>" + "".join(f"<property name={quoteattr(k)} value={quoteattr(str(v))}/>"
                                    for k, v in named) + "</properties>"


def _suite(result: Check) -> list[str]:
    cases = []
    failures = errors = skipped = 0
    for cell in result.cells:
        name = quoteattr(f"{cell.fa.stem} on {cell.robot.stem}, map {cell.map_names}")
        body = ""
        text = "\n".join(_failures(cell))
        if cell.verdict == Verdict.EA:
            failures += 1
            body = (f'<failure message={quoteattr(_cell_text(cell))} type="ea">'
                    f"{escape(text)}</failure>")
        elif cell.verdict == Verdict.ERROR:
            errors += 1
            body = f'<error message={quoteattr(_cell_text(cell))}>' \
                   f"{escape(chr(10).join(cell.errors))}</error>"
        elif cell.verdict == Verdict.NA:
            skipped += 1
            body = f"<skipped message={quoteattr(cell.problem)}/>"
        elif cell.verdict == Verdict.OTHER:
            body = f"<system-out>{escape(_cell_text(cell) + chr(10) + text)}</system-out>"
        cases.append(f'    <testcase classname={quoteattr("prima.check." + result.document.name)} '
                     f'name={name} time="{cell.cpu:.3f}">{_properties(cell)}{body}</testcase>')
    suite = (f'  <testsuite name={quoteattr("prima check " + result.document.name)} '
             f'tests="{len(result.cells)}" failures="{failures}" errors="{errors}" '
             f'skipped="{skipped}" time="{sum(c.cpu for c in result.cells):.3f}">')
    return [suite, *cases, "  </testsuite>"]


def _md(text: str) -> str:
    return text.replace("|", "\\|")


def markdown(result: Check) -> str:
    """A short Markdown summary: the matrix as a table, the failures, the coverage."""
    rows = [f"### prima check: {result.document.name}", "",
            f"{_md(_where(result))}; {result.runs} runs per scenario, jitter "
            f"±{result.jitter:g} s, seed {result.seed}; coverage "
            f"{result.coverage.percent:.0f}%", "",
            "| FA | " + " | ".join(r.stem for r in result.robots) + " |",
            "|---|" + "---|" * len(result.robots)]
    for fa in result.fas:
        cells = [_md(_cell_text(result.cell(fa, r))) for r in result.robots]
        rows.append(f"| {fa.stem} | " + " | ".join(cells) + " |")
    rows += ["", "| FA | robot | map | verdict | runs | CPU |", "|---|---|---|---|---|---|"]
    for cell in result.cells:
        rows.append(f"| {cell.fa.stem} | {cell.robot.stem} | {_md(cell.map_names)} | "
                    f"{_md(_cell_text(cell))} | {cell.done} | {_seconds(cell)} |")
    for cell in result.cells:
        if cell.verdict in (Verdict.EA, Verdict.OTHER):
            rows += ["", f"**{cell.name}**: {cell.breached} of {cell.done} runs failed", ""]
            rows += [f"- {_md(line.strip())}" for line in _failures(cell)]
    missed = result.coverage.lines()
    if missed:
        rows += ["", f"Lines not wholly exercised: {spans(missed)}"]
    return "\n".join(rows) + "\n"
