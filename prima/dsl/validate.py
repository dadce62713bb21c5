"""Validating files and folders: what ``prima validate`` does, as a library call.

Each file is dispatched on its root element: a PXML document or a robot
profile. Folders are searched for ``*.pxml`` documents.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable

from lxml import etree

from prima._xml import parse_xml, read_source
from prima.dsl.loader import check_parsed
from prima.dsl.profile import NAMESPACE as ROBOT_NS
from prima.dsl.profile import RobotProfile, profile_from_xml
from prima.errors import DocumentError, Problem, Severity


@dataclass
class Report:
    """The outcome of validating some files."""

    files: list[str] = field(default_factory=list)
    problems: list[Problem] = field(default_factory=list)

    @property
    def errors(self) -> int:
        return sum(p.severity is Severity.ERROR for p in self.problems)

    @property
    def warnings(self) -> int:
        return sum(p.severity is Severity.WARNING for p in self.problems)

    def to_dict(self) -> dict[str, object]:
        return {
            "files": self.files,
            "errors": self.errors,
            "warnings": self.warnings,
            "problems": [p.to_dict() for p in self.problems],
        }


def collect(paths: Iterable[str | Path]) -> list[Path]:
    """Files to validate: files as given, folders searched for ``*.pxml``.

    Raises FileNotFoundError for a path that does not exist.
    """
    out: list[Path] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            out.extend(sorted(path.rglob("*.pxml")))
        elif path.exists():
            out.append(path)
        else:
            raise FileNotFoundError(str(raw))
    return out


def check_file(path: Path, profile: RobotProfile | None = None) -> list[Problem]:
    """Every problem of one file (a PXML document or a robot profile)."""
    try:
        doc = parse_xml(read_source(path, DocumentError), str(path), DocumentError)
        if etree.QName(doc.root).namespace == ROBOT_NS:
            profile_from_xml(doc)
            return []
    except DocumentError as exc:
        return list(exc.problems)
    return check_parsed(doc, profile)[1]


def validate_paths(paths: Iterable[Path], profile: RobotProfile | None = None) -> Report:
    """Validate every file; problems are sorted by file, then position."""
    report = Report()
    for path in paths:
        report.files.append(str(path))
        report.problems.extend(check_file(path, profile))
    return report
