"""PRIMA's error tree and the located problems every loader reports.

Every exception PRIMA raises on purpose derives from :class:`PrimaError`::

    PrimaError
    ├── LocatedError (ValueError)   an input file is unusable; carries Problems
    │   ├── DocumentError           a PXML document or robot profile
    │   │   └── ExpressionError     an expression or command chain inside one
    │   ├── ScenarioError           a scenario or map file
    │   ├── TraceError              a jsonl trace file (``prima judge``)
    │   └── ResultsError            a results file resumed (``--resume``)
    ├── ExecutionError              a running application did something impossible
    │   ├── AppFailure              ... and was stopped (the failure is already reported)
    │   └── CommandError            a Command's argument the robot cannot use
    ├── MediationError (ValueError) the mediator refused an operation
    ├── SimulationError (ValueError) the simulator was asked something impossible
    ├── RunError (RuntimeError)     a run cannot go on
    │   └── ClusterError            the cluster a batch's runs go to cannot take them
    └── OutputError (OSError)       a file a command writes cannot be written

Every error a user can cause in an input file carries one or more
:class:`Problem` objects, each printed as ``file:line:col: error: message`` so
that editors and CI logs can jump to the fault; a problem inside an expression
also carries its source line, so a caret can point at the character. Errors
from lxml, xmlschema and lark are wrapped at the boundary; none of theirs
reach the user.
"""

from __future__ import annotations

import enum
from collections.abc import Iterable
from dataclasses import dataclass, field

from prima.record import Record

__all__ = [
    "AppFailure",
    "ClusterError",
    "CommandError",
    "DocumentError",
    "ExecutionError",
    "ExpressionError",
    "LocatedError",
    "MediationError",
    "OutputError",
    "PrimaError",
    "Problem",
    "ResultsError",
    "RunError",
    "ScenarioError",
    "Severity",
    "SimulationError",
    "TraceError",
]


class Severity(str, enum.Enum):
    """How bad a :class:`Problem` is."""

    ERROR = "error"
    """The document cannot be used; validation exits 1."""
    WARNING = "warning"
    """The document works but probably not as its author meant."""


@dataclass(frozen=True, order=True, repr=False)
class Problem(Record):
    """One located finding about an input file."""

    file: str
    line: int
    col: int
    severity: Severity
    message: str
    source: str = field(default="", compare=False)
    """The source line the problem is on, when a caret under ``col`` helps
    (a fault inside an expression); empty otherwise."""

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: {self.severity.value}: {self.message}"

    def caret(self) -> str:
        """The source line and a caret under the column, or "" without a source line.

        Tabs before the column are kept, so the caret lines up in any terminal.
        """
        if not self.source:
            return ""
        line = self.source.rstrip("\r\n")
        pad = "".join(c if c == "\t" else " " for c in line[: max(self.col - 1, 0)])
        return f"    {line}\n    {pad}^"

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = {
            "file": self.file,
            "line": self.line,
            "col": self.col,
            "severity": self.severity.value,
            "message": self.message,
        }
        if self.source:
            out["source"] = self.source
        return out


class PrimaError(Exception):
    """Base class of every error PRIMA raises on purpose."""


class LocatedError(PrimaError, ValueError):
    """An input is unusable; ``problems`` says where and why (errors first)."""

    def __init__(self, problems: Iterable[Problem]) -> None:
        self.problems: tuple[Problem, ...] = tuple(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class DocumentError(LocatedError):
    """A PXML document or robot profile is malformed, invalid or meaningless."""


class ExpressionError(DocumentError):
    """An expression or command chain does not parse or compile.

    ``index`` is the character of the fault in ``text``, the expression's own
    source; a loader adds where the expression is written in its file. Raised
    on its own (by :func:`prima.dsl.compile_expression`, say), its problem is
    located in ``<expression>`` at the line and column of ``index`` in ``text``.
    """

    def __init__(self, index: int, message: str, text: str = "") -> None:
        self.index = index
        self.message = message
        self.text = text
        start = text.rfind("\n", 0, index) + 1
        end = text.find("\n", index)
        source = text[start: end if end >= 0 else len(text)]
        super().__init__([Problem("<expression>", text.count("\n", 0, index) + 1,
                                  index - start + 1, Severity.ERROR, message, source)])


class ScenarioError(LocatedError):
    """A scenario or map file is malformed, invalid or meaningless."""


class TraceError(LocatedError):
    """A jsonl trace file cannot be read: a line is not JSON, or lacks what a trace
    line has (``t``, ``seq``, ``kind``), or its time goes backwards."""


class ResultsError(LocatedError):
    """A results file cannot be resumed: it is of another batch (other documents, seed,
    jitter or thresholds), or a line of it is not a run's record."""


class ExecutionError(PrimaError):
    """A running application did something impossible (reported in the trace)."""


class AppFailure(ExecutionError):
    """An application failed and was stopped; its failure is already reported."""


class CommandError(ExecutionError):
    """A Command's argument the robot cannot use (an unknown place, a negative time).

    The simulator ends the Command's atomic behavior at once with an ``error``
    value; the application sees it in the Command's end event.
    """


class MediationError(PrimaError, ValueError):
    """The mediator refused an operation: unknown app or Command, a second FA or an
    EA past the bound, an unbalanced stream or block, a driver reporting an AB that
    is not running.

    Working memory is left unchanged when this is raised.
    """


class SimulationError(PrimaError, ValueError):
    """The simulator was asked for something impossible: time going back, an
    atomic behavior started twice, a rate it cannot step at."""


class RunError(PrimaError, RuntimeError):
    """A run cannot go on (the run loop stopped making progress)."""


class ClusterError(RunError):
    """The cluster a batch's runs go to cannot take them: its scheduler does not answer
    or went away, no worker joined it, or no run finished for too long. The runs done
    are kept (a results file resumes the batch)."""


class OutputError(PrimaError, OSError):
    """A file a command writes (a trace, a page, a picture, a golden trace, a sweep's
    worst runs) cannot be written: its folder is missing or not writable, the disk is
    full. Nothing is left half-written (:mod:`prima.output`)."""
