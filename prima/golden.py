"""Golden traces: pin a scenario's behaviour, show a readable diff when it changes.

A scenario ``sample-03.xml`` has its golden trace beside it in
``sample-03.golden.txt``: the text trace of a reviewed run. :func:`check`
runs the scenario and compares; goldens are written only when asked
(``update=True``, ``prima test --update``), never as a side effect.
"""

from __future__ import annotations

import difflib
import enum
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

from prima.output import written
from prima.run import Run
from prima.trace import format_text

SUFFIX = ".golden.txt"


def golden_path(scenario: Path) -> Path:
    """Where a scenario's golden trace lives."""
    return scenario.with_name(scenario.stem + SUFFIX)


def scenarios_with_goldens(paths: Iterable[str | Path]) -> list[Path]:
    """Scenario files that have a golden trace beside them (folders searched recursively)."""
    found: list[Path] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            found.extend(p for p in sorted(path.rglob("*.xml")) if golden_path(p).exists())
        elif path.exists():
            found.append(path)
        else:
            raise FileNotFoundError(str(raw))
    return found


class Status(str, enum.Enum):
    """How a scenario's run compared with its golden trace."""

    SAME = "same"
    """The trace is the golden trace."""
    DIFFERENT = "different"
    """The trace differs (``Result.diff`` shows how)."""
    MISSING = "missing"
    """The scenario has no golden trace yet."""
    UPDATED = "updated"
    """The golden trace was (re)written with this run's trace."""


@dataclass(frozen=True)
class Result:
    """How one scenario compared with its golden trace."""

    scenario: Path
    status: Status
    diff: str = ""


def check(scenario: Path, *, update: bool = False) -> Result:
    """Run ``scenario`` and compare its trace with the golden one (or rewrite it)."""
    actual = format_text(Run(scenario).run())
    golden = golden_path(scenario)
    if update:
        if golden.exists() and golden.read_text(encoding="utf-8") == actual:
            return Result(scenario, Status.SAME)
        with written(golden) as out:
            out.write(actual)
        return Result(scenario, Status.UPDATED)
    if not golden.exists():
        return Result(scenario, Status.MISSING)
    expected = golden.read_text(encoding="utf-8")
    if expected == actual:
        return Result(scenario, Status.SAME)
    diff = "".join(difflib.unified_diff(
        expected.splitlines(keepends=True), actual.splitlines(keepends=True),
        fromfile=str(golden), tofile=f"{scenario} (this run)", n=2))
    return Result(scenario, Status.DIFFERENT, diff)
