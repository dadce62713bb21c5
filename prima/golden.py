"""Golden traces: pin a scenario's behaviour, show a readable diff when it changes.

A scenario ``sample-03.xml`` has its golden trace beside it in
``sample-03.golden.txt``: the text trace of a reviewed run. :func:`check`
runs the scenario and compares; goldens are written only when asked
(``update=True``, ``prima test --update``), never as a side effect.
"""

from __future__ import annotations

import codecs
import contextlib
import difflib
import enum
import os
import re
import stat
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from prima.errors import Problem, Severity, TraceError
from prima.output import written
from prima.run import Run, Switches
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


_ABSOLUTE = re.compile(r"(?<![\w.])/[^\s:\"'()]+\.(?:pxml|xml)\b")
"""An absolute path to a document or scenario file, as an error in a trace names it."""


def portable(text: str, folder: Path) -> str:
    """``text`` with every absolute path to a file written relative to ``folder`` (the
    golden trace's): a golden pinning a runtime error (``/home/me/apps/a.pxml:3:5: ...``)
    reads the same on every checkout."""
    base = folder.resolve()
    return _ABSOLUTE.sub(lambda m: os.path.relpath(m.group(), base), text)


def check(scenario: Path, *, update: bool = False, switches: Switches | None = None) -> Result:
    """Run ``scenario`` and compare its trace with the golden one (or rewrite it);
    ``switches``: its FA, EA, robot or policies changed (``prima test --policy ...``)."""
    options = switches.run_options() if switches else {}
    run = Run(scenario, **options)
    apps = run.app_names()
    actual = portable(format_text(run.run(), apps), scenario.parent)
    golden = golden_path(scenario)
    if update:
        # (a named pipe is written to, not read first: reading it would wait for a writer;
        # a golden trace that cannot be read is rewritten)
        with contextlib.suppress(TraceError):
            if golden.is_file() and _golden_is(golden, actual):
                return Result(scenario, Status.SAME)
        with written(golden) as out:
            out.write(actual)
        return Result(scenario, Status.UPDATED)
    if not golden.exists():
        return Result(scenario, Status.MISSING)
    if _golden_is(golden, actual):
        return Result(scenario, Status.SAME)
    expected = _read_golden(golden)  # (the diff needs it whole)
    return Result(scenario, Status.DIFFERENT,
                  shifted_diff(expected, actual, str(golden), f"{scenario} (this run)"))


PIECE = 1 << 20
"""How many bytes of a golden trace are read at a time to compare it with a run's."""


def _golden_is(golden: Path, actual: str) -> bool:
    """Whether the golden trace's text is ``actual``, read and compared a piece at a time
    (:data:`PIECE` bytes): the golden trace of a long run is never held whole, and the
    reading stops at the first difference. What :func:`_read_golden` refuses raises the
    same :class:`~prima.errors.TraceError`."""
    decoder = codecs.getincrementaldecoder("utf-8")()
    at = 0
    with _opened(golden) as data:
        try:
            while piece := data.read(PIECE):
                text = decoder.decode(piece)
                if actual[at:at + len(text)] != text:
                    return False
                at += len(text)
            text = decoder.decode(b"", final=True)
        except OSError as exc:
            raise _unreadable(golden, exc) from exc
        except UnicodeDecodeError:  # (read whole, to say where; it is said as an error)
            return _read_golden(golden) == actual
    return actual[at:] == text


def _read_golden(golden: Path) -> str:
    """A golden trace's text. A named pipe, a device or a folder in its place, a file that
    cannot be read or is not UTF-8 raise :class:`~prima.errors.TraceError`, located (a
    named pipe is not opened: reading it would wait for a writer for ever)."""
    with _opened(golden) as file:
        try:
            data = file.read()
        except OSError as exc:
            raise _unreadable(golden, exc) from exc
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        before = data[:exc.start]
        raise _failed(golden, before.count(b"\n") + 1,
                      exc.start - (before.rfind(b"\n") + 1) + 1,
                      "the golden trace is not UTF-8 text") from exc


def _opened(golden: Path) -> BinaryIO:
    """A golden trace opened to be read. A named pipe, a device or a folder in its place,
    or a file that cannot be opened, raise :class:`~prima.errors.TraceError`, located (a
    named pipe is not opened: reading it would wait for a writer for ever)."""
    try:
        mode = os.stat(golden).st_mode
        if not stat.S_ISREG(mode):
            kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file"
            raise _failed(golden, 1, 1,
                          f"the golden trace is {kind}: PRIMA reads only regular files")
        return golden.open("rb")
    except OSError as exc:
        raise _unreadable(golden, exc) from exc


def _failed(golden: Path, line: int, col: int, message: str) -> TraceError:
    return TraceError([Problem(str(golden), line, col, Severity.ERROR, message)])


def _unreadable(golden: Path, exc: OSError) -> TraceError:
    return _failed(golden, 1, 1, f"cannot read the golden trace: {exc.strerror or exc}")


_ROW = re.compile(r"^(?P<no>\s*\d+) +(?P<t>\d+\.\d+)(?P<rest>   .*)$")
"""A text trace row: its number, its time and the rest."""


def _parts(line: str) -> tuple[str, float | None]:
    """A row without its number and time (what is compared), and its time."""
    m = _ROW.match(line)
    return (m.group("rest"), float(m.group("t"))) if m else (line, None)


def shifted_diff(expected: str, actual: str, fromfile: str, tofile: str) -> str:
    """A unified diff of two text traces in which a shift of every later time reads as
    one change: rows are compared without their numbers and times; where they match
    but their times moved, one hunk says by how much, for how many rows, with the
    first of them as it was and as it is."""
    old, new = expected.splitlines(), actual.splitlines()
    old_keys, new_keys = [_parts(x)[0] for x in old], [_parts(x)[0] for x in new]
    out = [f"--- {fromfile}\n", f"+++ {tofile}\n"]
    matcher = difflib.SequenceMatcher(None, old_keys, new_keys, autojunk=False)
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        if tag == "equal":
            out += _shifts(old, new, i1, i2, j1)
            continue
        out.append(f"@@ -{i1 + 1},{i2 - i1} +{j1 + 1},{j2 - j1} @@\n")
        out += [f"-{x}\n" for x in old[i1:i2]] + [f"+{x}\n" for x in new[j1:j2]]
    return "".join(out)


def _shifts(old: list[str], new: list[str], i1: int, i2: int, j1: int) -> list[str]:
    """For rows that match but for their times, one line per run of rows whose time
    moved by the same amount."""
    out: list[str] = []
    run: tuple[int, int, float] | None = None  # first row (new), last row, shift

    def close() -> None:
        if run is not None:
            first, last, shift = run
            rows = last - first + 1
            out.append(f"@@ +{first + 1},{rows} @@ {'every' if rows > 1 else 'the'} time "
                       f"{abs(shift):.2f} s {'later' if shift > 0 else 'earlier'}, "
                       f"otherwise the same{', as in' if rows > 1 else ''}:\n")
            out.append(f"-{old[first - j1 + i1]}\n+{new[first]}\n")
    for k in range(i2 - i1):
        t_old, t_new = _parts(old[i1 + k])[1], _parts(new[j1 + k])[1]
        shift = round(t_new - t_old, 2) if t_old is not None and t_new is not None else 0.0
        if run is not None and (shift != run[2] or run[1] != j1 + k - 1):
            close()
            run = None
        if shift:
            run = (run[0] if run else j1 + k, j1 + k, shift)
    close()
    return out
