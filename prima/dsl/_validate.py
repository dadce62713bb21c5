"""Validating files and folders: what ``prima validate`` does, as a library call.

Each file is dispatched on its root element's namespace: a PXML document, a
robot profile, or another kind the caller knows how to check (the CLI adds
scenarios and maps). Folders are searched for ``*.pxml`` and ``*.xml`` files.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path

from lxml import etree

from prima.dsl._loader import NAMESPACE as PXML_NS
from prima.dsl._loader import check_parsed
from prima.dsl._profile import NAMESPACE as ROBOT_NS
from prima.dsl._profile import RobotProfile, profile_from_xml
from prima.errors import DocumentError, PrimaError, Problem, Severity
from prima.xmlio import parse_xml, read_source


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


class PathNotFoundError(PrimaError, FileNotFoundError):
    """A path given to :func:`collect` does not exist."""


Checker = Callable[[Path], list[Problem]]
"""Checks one file of some other kind (e.g. a scenario) and returns its problems."""


def collect(paths: Iterable[str | Path]) -> list[tuple[Path, bool]]:
    """Files to validate, each with whether it was named explicitly.

    Folders are searched for ``*.pxml`` and ``*.xml``. Raises
    :class:`PathNotFoundError` (a FileNotFoundError) for a path that does not exist.
    """
    out: list[tuple[Path, bool]] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            found = sorted({*path.rglob("*.pxml"), *path.rglob("*.xml")})
            out.extend((f, False) for f in found)
        elif path.exists():
            out.append((path, True))
        else:
            raise PathNotFoundError(str(raw))
    return out


def root_namespace(data: bytes) -> str | None:
    """The namespace of the root element, read without parsing the whole file."""
    try:
        for _event, el in etree.iterparse(BytesIO(data), events=("start",), resolve_entities=False,
                                          load_dtd=False, no_network=True):
            return etree.QName(el).namespace
    except etree.XMLSyntaxError:
        return None
    return None


def check_file(path: Path, profile: RobotProfile | None = None,
               checkers: Mapping[str, Checker] | None = None, *,
               skip_unknown: bool = False) -> list[Problem] | None:
    """Every problem of one file: a PXML document, a robot profile, or a kind in ``checkers``.

    With ``skip_unknown`` (a file found in a folder), an ``.xml`` file of no
    known kind, or one that cannot be read, gives None: it is not ours.
    """
    skippable = skip_unknown and path.suffix != ".pxml"
    try:
        data = read_source(path, DocumentError)
    except DocumentError as exc:
        return None if skippable else list(exc.problems)
    namespace = root_namespace(data)
    checker = checkers.get(namespace) if checkers and namespace is not None else None
    if checker is not None:
        return checker(path)
    if skippable and namespace not in (PXML_NS, ROBOT_NS):
        return None
    try:
        doc = parse_xml(data, str(path), DocumentError)
        if namespace == ROBOT_NS:
            profile_from_xml(doc)
            return []
    except DocumentError as exc:
        return list(exc.problems)
    return check_parsed(doc, profile)[1]


def validate_paths(paths: Iterable[tuple[Path, bool] | Path], profile: RobotProfile | None = None,
                   checkers: Mapping[str, Checker] | None = None) -> Report:
    """Validate every file; files found in folders are skipped unless they are known kinds."""
    report = Report()
    for item in paths:
        path, explicit = item if isinstance(item, tuple) else (item, True)
        problems = check_file(path, profile, checkers, skip_unknown=not explicit)
        if problems is None:
            continue
        report.files.append(str(path))
        report.problems.extend(problems)
    return report
