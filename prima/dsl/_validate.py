"""Validating files and folders: what ``prima validate`` does, as a library call.

Each file is dispatched on its root element's namespace: a PXML document, a
robot profile, or another kind the caller knows how to check (the CLI adds
scenarios and maps). Folders are searched for ``*.pxml`` and ``*.xml`` files.
A :class:`Validation` checks each file once, however many times it is given
or named (a scenario names its map, robot profile and applications).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from io import BytesIO
from pathlib import Path
from typing import NamedTuple

from lxml import etree

from prima.dsl._loader import NAMESPACE as PXML_NS
from prima.dsl._loader import check_parsed
from prima.dsl._model import PlaceRef
from prima.dsl._profile import NAMESPACE as ROBOT_NS
from prima.dsl._profile import (
    STANDARD_GESTURES,
    RobotProfile,
    default_profile,
    profile_from_xml,
)
from prima.errors import DocumentError, PrimaError, Problem, Severity
from prima.record import Record
from prima.xmlio import XmlDocument, parse_xml, read_source


@dataclass(repr=False)
class Report(Record):
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


class Header(NamedTuple):
    """What a file's root says: its namespace and, for a PXML document, its ``kind`` and
    ``name`` (as written; empty otherwise)."""

    namespace: str
    kind: str = ""
    name: str = ""


def check_file(path: Path, profile: RobotProfile | None = None,
               checkers: Mapping[str, Checker] | None = None, *,
               skip_unknown: bool = False) -> list[Problem] | None:
    """Every problem of one file: a PXML document, a robot profile, or a kind in ``checkers``.

    With ``skip_unknown`` (a file found in a folder), an ``.xml`` file of no
    known kind, or one that cannot be read, gives None: it is not ours.
    """
    return _check(path, profile, checkers.get if checkers else None, skip_unknown)[0]


class _Checked(NamedTuple):
    problems: list[Problem] | None
    header: Header | None
    """The file's header, when its root element could be read."""
    places: tuple[PlaceRef, ...] | None = None
    """A document without errors: the places it names literally."""


def _check(path: Path, profile: RobotProfile | None,
           checker_for: Callable[[str], Checker | None] | None,
           skip_unknown: bool,
           robot_for: Callable[[Path], RobotProfile | str | None] | None = None) -> _Checked:
    """:func:`check_file`, with the file's header and, for a document without errors, its
    literal places; ``checker_for`` gives the checker of a namespace of another kind, if any;
    ``robot_for`` the profile a document names in its ``robot`` attribute (None: it has
    errors; a text: why it cannot be read), checked against instead of ``profile``."""
    skippable = skip_unknown and path.suffix != ".pxml"
    try:
        data = read_source(path, DocumentError)
    except DocumentError as exc:
        return _Checked(None if skippable else list(exc.problems), None)
    # Parsed once, securely (most files are documents); the namespace of a file
    # that does not parse is read from its root element alone.
    doc: XmlDocument | None = None
    unparsed: list[Problem] = []
    try:
        doc = parse_xml(data, str(path), DocumentError)
    except DocumentError as exc:
        unparsed = list(exc.problems)
    namespace = root_namespace(data) if doc is None else etree.QName(doc.root).namespace
    header = None if namespace is None else Header(namespace)
    checker = checker_for(namespace) if checker_for and namespace is not None else None
    if checker is not None:
        return _Checked(checker(path), header)
    if skippable and namespace not in (PXML_NS, ROBOT_NS):
        return _Checked(None, None)
    if doc is None:
        return _Checked(unparsed, header)
    if namespace == ROBOT_NS:
        try:
            robot = profile_from_xml(doc)
        except DocumentError as exc:
            return _Checked(list(exc.problems), header)
        return _Checked(_missing_gestures(doc, robot), header)
    declared: list[Problem] = []
    if namespace == PXML_NS:
        header = Header(namespace, doc.root.get("kind", ""), doc.root.get("name", ""))
        written = doc.root.get("robot")
        if written is not None and robot_for is not None:
            found = robot_for(path.parent / written)
            if isinstance(found, str):
                declared.append(doc.problem(doc.root, found, attribute="robot"))
            elif found is None:  # its own problems are reported in its own file
                return _Checked(declared, header)
            else:
                profile = found
    document, problems = check_parsed(doc, profile)
    problems = declared + problems
    return _Checked(problems, header, None if document is None else document.places)


def _missing_gestures(doc: XmlDocument, robot: RobotProfile) -> list[Problem]:
    """A warning for each common gesture the profile does not offer: an EA may play it,
    and would fail validation (and a run) on this robot."""
    return [doc.problem(doc.root, f"no gesture '{name}': it is a common gesture an EA may "
                        "play, and such an EA fails on this robot", severity=Severity.WARNING)
            for name in sorted(STANDARD_GESTURES - set(robot.gestures))]


class Validation:
    """Checks files into one :class:`Report`, each file once (by its resolved path).

    ``checkers`` check other kinds of file (the CLI adds scenarios and maps);
    a checker may call back into the validation to check the files its file
    names (:meth:`document`, :meth:`robot`, :meth:`claim`). ``more_checkers``,
    if given, is called once, the first time a file of another kind than a
    document, a robot profile or those of ``checkers`` is met; the checkers it
    returns are added (so what checks them is imported only when needed).
    """

    def __init__(self, profile: RobotProfile | None = None,
                 checkers: Mapping[str, Checker] | None = None, *,
                 more_checkers: Callable[[], Mapping[str, Checker]] | None = None,
                 follow_declared: bool = True) -> None:
        self.profile = profile
        self.follow_declared = follow_declared
        """Whether a document is checked against the robot its ``robot`` attribute names
        (unless a scenario runs it on another): not when a profile is given for all."""
        """The robot profile documents are checked against, unless one is named for them."""
        self.checkers: dict[str, Checker] = dict(checkers or {})
        self._more_checkers = more_checkers
        self.report = Report()
        self._seen: set[Path] = set()
        self._checking: set[Path] = set()
        """Files being checked: a file that names itself (a scenario as its own map) is
        not checked again from inside its own check."""
        self._headers: dict[Path, Header] = {}
        self._robots: dict[Path, RobotProfile | None] = {}
        self._places: dict[Path, tuple[str, tuple[PlaceRef, ...]]] = {}

    def claim(self, path: Path) -> bool:
        """Whether ``path`` is still to be checked; if so, it is now counted as checked."""
        key = _key(path)
        if key in self._seen or key in self._checking:
            return False
        self._seen.add(key)
        self.report.files.append(str(path))
        return True

    def add(self, path: Path, *, explicit: bool = True,
            profile: RobotProfile | None = None) -> None:
        """Check ``path`` (unless it was already checked); a file found in a folder
        (not ``explicit``) that is not a PRIMA file is skipped."""
        key = _key(path)
        if key in self._seen or key in self._checking:
            return
        # a checker may check the files this one names: this one is reported before them
        files_at, problems_at = len(self.report.files), len(self.report.problems)
        self._checking.add(key)
        declared = self._declared if profile is None and self.follow_declared else None
        try:
            problems, header, places = _check(path, profile or self.profile, self._checker,
                                              skip_unknown=not explicit, robot_for=declared)
        finally:
            self._checking.discard(key)
        if problems is None or key in self._seen:
            return
        if header is not None:
            self._headers[key] = header
        if places is not None:
            self._places[key] = (str(path), places)
        self._seen.add(key)
        self.report.files.insert(files_at, str(path))
        self.report.problems[problems_at:problems_at] = problems

    def _declared(self, path: Path) -> RobotProfile | str | None:
        """The robot profile a document names as the robot it is written for (checked
        once); None if it has errors, or why it cannot be used."""
        if not path.is_file():
            return f"robot profile '{path}' not found (the robot attribute names it, " \
                   "relative to the document)"
        return self.robot(path)

    def _checker(self, namespace: str) -> Checker | None:
        """The checker of a file whose root is in ``namespace``, if another kind's."""
        if namespace in (PXML_NS, ROBOT_NS):
            return self.checkers.get(namespace)
        if namespace not in self.checkers and self._more_checkers is not None:
            more, self._more_checkers = self._more_checkers, None
            self.checkers.update(more())
        return self.checkers.get(namespace)

    def document(self, path: Path, profile: RobotProfile | None = None) -> Header | None:
        """Check a document another file names (once); its header, if its root could be read."""
        self.add(path, profile=profile)
        return self._headers.get(_key(path))

    def places(self, path: Path) -> tuple[str, tuple[PlaceRef, ...]] | None:
        """For a document checked here without errors, the name its problems are reported
        under and the places it names literally (:func:`~prima.dsl.literal_places`);
        else None."""
        return self._places.get(_key(path))

    def robot(self, path: Path) -> RobotProfile | None:
        """Check a robot profile another file names (once); the profile, or None if it has
        errors (they are reported in the profile's own file)."""
        key = _key(path)
        if key not in self._robots:
            try:
                doc = parse_xml(read_source(path, DocumentError), str(path), DocumentError)
                loaded = profile_from_xml(doc)
                robot: RobotProfile | None = loaded
                problems = _missing_gestures(doc, loaded)
            except DocumentError as exc:
                robot, problems = None, list(exc.problems)
            if self.claim(path):
                self.report.problems.extend(problems)
            self._robots[key] = robot
            if robot is not None:
                self._headers.setdefault(key, Header(ROBOT_NS))
        return self._robots[key]

    def run(self, paths: Iterable[tuple[Path, bool] | Path]) -> Report:
        """Check every path (``(path, explicit)`` pairs from :func:`collect`, or paths).

        PXML documents are checked last, after the scenarios, maps and robot profiles,
        so that a document a scenario names is checked against the scenario's robot
        however the paths are ordered (``apps scenarios`` as ``scenarios apps``), and
        whatever the document's file is called.
        """
        items = [item if isinstance(item, tuple) else (item, True) for item in paths]
        items.sort(key=lambda item: _is_document(item[0]))  # stable: otherwise as given
        for path, explicit in items:
            self.add(path, explicit=explicit)
        return self.report


def _is_document(path: Path) -> bool:
    """Whether ``path`` holds a PXML document: a ``.pxml`` file, or another whose root
    element is one (read for that alone; one that cannot be read is not, and its own
    check says why)."""
    if path.suffix == ".pxml":
        return True
    try:
        return root_namespace(read_source(path, DocumentError)) == PXML_NS
    except DocumentError:
        return False


def _key(path: Path) -> Path:
    try:
        return path.resolve()
    except (OSError, RuntimeError):  # a symlink loop: the path itself will fail to read
        return path.absolute()


def validate_paths(paths: Iterable[tuple[Path, bool] | Path], profile: RobotProfile | None = None,
                   checkers: Mapping[str, Checker] | None = None) -> Report:
    """Validate every file, each once; files found in folders are skipped unless they are
    known kinds."""
    return Validation(profile or default_profile(), checkers).run(paths)


def unknown_places(file: str, places: Sequence[PlaceRef], names: Sequence[str],
                   map_name: str, source: str = "") -> list[Problem]:
    """A problem in the document ``file`` at each of its literal ``places`` that is not
    among the map's place ``names``: the closest name if one is close, else the map's
    places if they are few (``source``: where the map is, named when they are many). At
    most MAX_PROBLEMS of them (then a line counting the rest), each hint worked out once.
    ``prima validate`` of a scenario and a run's loading both check with it."""
    import difflib

    from prima.xmlio import MAX_PROBLEMS, limit

    known = set(names)
    if len(names) <= _FEW_PLACES:
        listed = f" (known: {', '.join(sorted(names))})" if names else " (it has no places)"
    else:
        listed = f" ({len(names)} places; see {source or 'its file'})"
    hints: dict[str, str] = {}
    out: list[Problem] = []
    unknown = [p for p in places if p.name not in known]
    for place in unknown[:MAX_PROBLEMS + 1]:
        if place.name not in hints:
            close = difflib.get_close_matches(place.name, names, n=1, cutoff=0.75)
            hints[place.name] = f" (did you mean '{close[0]}'?)" if close else listed
        out.append(Problem(file, place.loc.line, place.loc.col, Severity.ERROR,
                           f"unknown place '{place.name}' on map '{map_name}'"
                           f"{hints[place.name]}"))
    return limit(out, file, len(unknown))


_FEW_PLACES = 12
"""A map with at most this many places lists them under an unknown place's error."""
