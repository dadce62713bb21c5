"""PRIMA's error tree and the located problems every loader reports.

Every error a user can cause carries one or more :class:`Problem` objects,
each printed as ``file:line:col: error: message`` so that editors and CI logs
can jump to the fault. Errors from lxml, xmlschema and lark are wrapped at the
boundary; none of theirs reach the user.
"""

from __future__ import annotations

import enum
from dataclasses import dataclass
from typing import Iterable


class Severity(str, enum.Enum):
    """How bad a :class:`Problem` is."""

    ERROR = "error"
    """The document cannot be used; validation exits 1."""
    WARNING = "warning"
    """The document works but probably not as its author meant."""


@dataclass(frozen=True, order=True)
class Problem:
    """One located finding about an input file."""

    file: str
    line: int
    col: int
    severity: Severity
    message: str

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}: {self.severity.value}: {self.message}"

    def to_dict(self) -> dict[str, object]:
        return {
            "file": self.file,
            "line": self.line,
            "col": self.col,
            "severity": self.severity.value,
            "message": self.message,
        }


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
    """An expression or command chain inside a document does not parse."""


class ScenarioError(LocatedError):
    """A scenario file is malformed or invalid."""


class ExecutionError(PrimaError):
    """A running application did something impossible (reported in the trace)."""


class MediationError(PrimaError, ValueError):
    """The mediator refused an operation: unknown app or Command, a second EA,
    an unbalanced stream or block, a driver reporting an AB that is not running.

    Working memory is left unchanged when this is raised.
    """
