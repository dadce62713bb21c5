"""The files the language server knows: the buffers an editor holds, and what is in
force for each: its scenario, its robot, its map.

A PXML document alone knows no robot and no map. As ``prima validate apps
scenarios`` does, a document is checked against the first scenario (in path
order) of the workspace that runs it (as its FA, an EA or a zone's EA): that
scenario's robot profile and map are in force for it, for diagnostics and for
completion; a document no scenario runs is checked against the profile the
server was started with (``prima lsp --robot``), else the home robot, and its
places against no map. Unsaved buffers are read in place of their files
(:func:`prima.xmlio.unsaved`), the files a scenario names included.
"""

from __future__ import annotations

import os
import re
from collections import OrderedDict
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

from prima.collecting import no_collections
from prima.dsl import Kept, RobotProfile, default_profile, keeping, load_profile
from prima.errors import DocumentError, LocatedError, Problem
from prima.lsp._xml import Tag, XmlText, first_tag, rescan, scan
from prima.xmlio import read_source, unsaved

if TYPE_CHECKING:
    from prima.dsl import Validation

__all__ = ["MAX_READ", "MAX_SCENARIOS", "Buffer", "Checked", "Place", "Setting", "Workspace",
           "resolved"]

MAX_SCENARIOS = 2_000
"""Most ``*.xml`` files looked into for scenarios in a workspace."""

MAX_READ = 256
"""Most files not open in the editor whose text is kept (the least recently read go)."""

SCENARIO_NS = "urn:prima:scenario:1"
PXML_NS = "urn:prima:pxml:1"
_SKIPPED = frozenset({".git", ".hg", ".svn", ".venv", "venv", "node_modules", "__pycache__",
                      "build", "dist", ".tox", ".mypy_cache", ".pytest_cache"})
_ROLES = (("apps", "fa", "fa"), ("apps", "ea", "ea"), ("ea", "href", "ea"),
          ("zone", "ea", "zone"))
"""(element, attribute, role) of every application a scenario runs."""


class Buffer:
    """A file's text as read: from the editor, or from disk. What is read of it is read
    once, on first need: its tags (for completion, hover and definition), its lines."""

    def __init__(self, path: Path, text: str, before: XmlText | None = None) -> None:
        self.path = path
        self.text = text
        self._before = before
        """An earlier version's scan, to take over (:func:`~prima.lsp._xml.rescan`)."""

    @cached_property
    def xml(self) -> XmlText:
        before, self._before = self._before, None
        return scan(self.text) if before is None else rescan(before, self.text)

    def hand_over(self) -> XmlText | None:
        """This version's scan (or the one it was to take over), given up to the next
        version; asked again, this buffer scans its text anew."""
        made: XmlText | None = self.__dict__.pop("xml", None)
        if made is None:
            made, self._before = self._before, None
        return made

    @cached_property
    def _root(self) -> Tag | None:
        return first_tag(self.text)

    @property
    def namespace(self) -> str | None:
        root = self._root
        return None if root is None else root.get("xmlns") or None

    @property
    def kind(self) -> str:
        """A PXML document's ``kind`` (``fa``, ``ea``; empty if not written)."""
        root = self._root
        return "" if root is None else root.get("kind")

    @property
    def declared_robot(self) -> str | None:
        """Its root's ``robot`` attribute, as written (a document's declared robot)."""
        root = self._root
        found = None if root is None else root.attr("robot")
        return None if found is None else found.value

    @cached_property
    def line_starts(self) -> list[int]:
        """Where each line begins, as the protocol counts lines (``\\n``, ``\\r\\n``,
        ``\\r``)."""
        return [0, *(m.end() for m in _BREAK.finditer(self.text))]

    @cached_property
    def _newline_starts(self) -> list[int]:
        return [0, *(m.end() for m in re.finditer("\n", self.text))]

    def offset_of(self, line: int, col: int) -> int:
        """The offset of a problem's 1-based line and column (``prima validate`` counts
        lines at ``\\n`` and columns in characters, after a byte-order mark)."""
        starts = self._newline_starts
        index = min(max(line - 1, 0), len(starts) - 1)
        at = starts[index]
        end = starts[index + 1] - 1 if index + 1 < len(starts) else len(self.text)
        bom = 1 if index == 0 and self.text.startswith("\ufeff") else 0
        return min(at + max(col - 1, 0) + bom, end)


_BREAK = re.compile(r"\r\n|\r|\n")


@dataclass(frozen=True)
class Place:
    """A place (or an area) of a map, and where the map declares it."""

    name: str
    kind: str
    x: str
    y: str
    file: Path
    offset: int
    """Where its name is written in the map file."""
    area: bool = False


@dataclass
class Setting:
    """What is in force for a file: the scenario that runs it, its robot, its map."""

    scenario: Path | None
    profile: RobotProfile
    profile_path: Path | None
    map_path: Path | None
    places: list[Place]


def resolved(path: Path) -> Path:
    """A path as the workspace keys it: resolved (absolute, if it cannot be)."""
    try:
        return path.resolve()
    except (OSError, RuntimeError):
        return path.absolute()


class Checked(NamedTuple):
    """A file's check: its problems, and the files they depend on (resolved paths)."""

    problems: list[Problem]
    depends: frozenset[Path]


def _validation(profile: RobotProfile, robot: bool) -> Validation:
    """A validation exactly as ``prima validate`` makes one (its scenario checks included):
    :func:`prima.scenario.make_validation`, the one place where that is made."""
    from prima.scenario import make_validation

    return make_validation(profile, robot=robot)


class Workspace:
    """The buffers, the workspace's folders, and the robot given to the server.

    :attr:`generation` counts the changes that may change what is in force for a file
    (a buffer that is not a PXML document changed, a buffer closed, files changed on
    disk): what is worked out from them is kept until it moves on.
    """

    def __init__(self, roots: list[Path], robot: Path | None = None) -> None:
        self.roots = roots
        self.robot = robot
        """``prima lsp --robot``: the profile documents are checked against, as
        ``prima validate --robot`` does (over a scenario's)."""
        self.buffers: dict[Path, Buffer] = {}
        self.generation = 0
        self._read: OrderedDict[Path, tuple[tuple[int, int], Buffer]] = OrderedDict()
        self._walked: list[Path] | None = None
        self._profiles: dict[Path, tuple[object, RobotProfile | None]] = {}
        self._settings: dict[Path, tuple[int, Setting]] = {}
        self.kept = Kept()
        """What the checks keep from one version of a document to the next (chains and
        states unchanged are replayed, not built again: :func:`prima.dsl.keeping`)."""

    # ---- buffers and files

    def open(self, path: Path, text: str) -> Buffer:
        """The editor's text of ``path`` (the buffer held, if the text is the same)."""
        key = resolved(path)
        held = self.buffers.get(key)
        if held is not None and (held.text is text or held.text == text):
            return held
        buffer = Buffer(path, text, None if held is None else held.hand_over())
        self.buffers[key] = buffer
        if held is None or buffer.namespace != PXML_NS or held.namespace != PXML_NS:
            self.generation += 1  # (a PXML document's text changes nothing in force)
        return buffer

    def close(self, path: Path) -> None:
        if self.buffers.pop(resolved(path), None) is not None:
            self.generation += 1

    def forget(self) -> None:
        """Files changed on disk: look for scenarios again, read what is in force again."""
        self._walked = None
        self.generation += 1

    def buffer(self, path: Path) -> Buffer | None:
        """The file's text: the editor's, else the disk's (None if it cannot be read)."""
        key = resolved(path)
        held = self.buffers.get(key)
        if held is not None:
            return held
        try:
            info = key.stat()
        except OSError:
            return None
        stamp = (info.st_mtime_ns, info.st_size)
        cached = self._read.get(key)
        if cached is not None and cached[0] == stamp:
            self._read.move_to_end(key)
            return cached[1]
        try:
            text = read_source(key, DocumentError).decode("utf-8-sig", "replace")
        except LocatedError:
            return None
        buffer = Buffer(path, text)
        self._read[key] = (stamp, buffer)
        while len(self._read) > MAX_READ:
            self._read.popitem(last=False)
        return buffer

    @contextmanager
    def unsaved(self) -> Iterator[None]:
        """Everything read meanwhile reads the editor's buffers in place of their files."""
        with unsaved({p: b.text.encode("utf-8") for p, b in self.buffers.items()}):
            yield

    # ---- scenarios

    def scenarios(self) -> list[Path]:
        """The workspace's scenario files, in path order (as ``prima validate`` of its
        folders would meet them), the editor's buffers included."""
        if self._walked is None:
            found: set[Path] = set()
            for root in self.roots:
                found.update(self._walk(root))
            self._walked = sorted(found)
        held = {p for p, b in self.buffers.items() if b.namespace == SCENARIO_NS}
        return sorted(p for p in {*self._walked, *held} if self._is_scenario(p))

    def _walk(self, root: Path) -> Iterator[Path]:
        seen = 0
        for folder, dirs, files in os.walk(root):
            dirs[:] = sorted(d for d in dirs if d not in _SKIPPED and not d.startswith("."))
            for name in sorted(files):
                if not name.endswith(".xml"):
                    continue
                seen += 1
                if seen > MAX_SCENARIOS:
                    return
                path = resolved(Path(folder) / name)
                if self._is_scenario(path):
                    yield path

    def _is_scenario(self, path: Path) -> bool:
        buffer = self.buffer(path)
        return buffer is not None and buffer.namespace == SCENARIO_NS

    def references(self, scenario: Path) -> list[tuple[str, Path, Tag, str]]:
        """The files a scenario names: (role, the file, the tag, the attribute)."""
        buffer = self.buffer(scenario)
        if buffer is None:
            return []
        out = []
        for tag in buffer.xml.tags:
            for element, attribute, role in (*_ROLES, ("map", "href", "map"),
                                             ("robot", "profile", "profile")):
                if tag.name == element and tag.attr(attribute) is not None:
                    named = resolved(scenario.parent / tag.get(attribute))
                    out.append((role, named, tag, attribute))
        return out

    def scenario_for(self, path: Path) -> Path | None:
        """The first scenario that runs the document ``path``, if any."""
        key = resolved(path)
        for scenario in self.scenarios():
            if any(role in ("fa", "ea", "zone") and target == key
                   for role, target, _tag, _attr in self.references(scenario)):
                return scenario
        return None

    # ---- what is in force

    def profile(self, path: Path | None) -> RobotProfile:
        """The robot profile at ``path`` (the home robot if None or it has errors)."""
        if path is None:
            return default_profile()
        buffer = self.buffer(path)
        stamp: object = None if buffer is None else buffer.text
        cached = self._profiles.get(path)
        if cached is None or cached[0] != stamp:
            try:
                with self.unsaved():
                    loaded: RobotProfile | None = load_profile(path)
            except LocatedError:
                loaded = None
            cached = self._profiles[path] = (stamp, loaded)
        return cached[1] or default_profile()

    def setting(self, path: Path) -> Setting:
        """What is in force for the file ``path`` (worked out once a generation)."""
        key = resolved(path)
        kept = self._settings.get(key)
        if kept is not None and kept[0] == self.generation:
            return kept[1]
        found = self._setting(path)
        if len(self._settings) > MAX_READ:
            self._settings.clear()
        self._settings[key] = (self.generation, found)
        return found

    def _setting(self, path: Path) -> Setting:
        buffer = self.buffer(path)
        namespace = None if buffer is None else buffer.namespace
        scenario = resolved(path) if namespace == SCENARIO_NS else (
            self.scenario_for(path) if namespace == PXML_NS else None)
        profile_path = self.robot
        map_path: Path | None = None
        if scenario is not None:
            for role, target, _tag, _attr in self.references(scenario):
                if role == "profile" and self.robot is None:
                    profile_path = target
                elif role == "map" and map_path is None:
                    map_path = target
        if namespace == "urn:prima:map:1":
            map_path = resolved(path)
        places = self.places(map_path) if map_path is not None else []
        return Setting(scenario, self.profile(profile_path), profile_path, map_path, places)

    def places(self, map_path: Path) -> list[Place]:
        """The places and areas a map file declares (read forgivingly: as written)."""
        buffer = self.buffer(map_path)
        if buffer is None:
            return []
        out = []
        for tag in buffer.xml.tags:
            name = tag.attr("name")
            if tag.name in ("place", "area") and name is not None and name.value_start >= 0:
                out.append(Place(name.value, tag.get("kind", "point"), tag.get("x"),
                                 tag.get("y"), map_path, name.value_start,
                                 area=tag.name == "area"))
        return out

    # ---- diagnostics

    def depends(self, path: Path) -> frozenset[Path]:
        """The files the problems of ``path`` depend on: itself; a scenario's, every file
        it names; a document's, the scenario that runs it with its map and robot
        profile, and the profile the document names (not the scenario's other
        applications: what they say is the scenario's to report)."""
        key = resolved(path)
        out = {key} | ({resolved(self.robot)} if self.robot is not None else set())
        buffer = self.buffer(path)
        namespace = None if buffer is None else buffer.namespace
        if namespace == SCENARIO_NS:
            out.update(target for _role, target, _tag, _attr in self.references(key))
        elif namespace == PXML_NS and buffer is not None:
            scenario = self.scenario_for(key)
            if scenario is not None:
                out.add(scenario)
                out.update(target for role, target, _tag, _attr in self.references(scenario)
                           if role in ("map", "profile"))
            declared = buffer.declared_robot
            if declared:
                out.add(resolved(key.parent / declared))
        return frozenset(out)

    def affected(self, path: Path, depends: Iterable[tuple[Path, frozenset[Path]]]) -> set[Path]:
        """The files whose problems a change of ``path`` may change: itself, those whose
        last check depended on it (``depends``: each file checked and what it depended
        on), and, for a scenario, the documents it names now (it may now be the scenario
        that runs them)."""
        key = resolved(path)
        out = {key, *(checked for checked, on in depends if key in on)}
        buffer = self.buffer(key)
        if buffer is not None and buffer.namespace == SCENARIO_NS:
            out.update(target for _role, target, _tag, _attr in self.references(key))
        return out

    def check(self, path: Path) -> Checked:
        """The file's problems, as ``prima validate`` reports them: the file alone, or a
        document with the scenario that runs it (its robot, its map's places); and what
        they depend on."""
        key = resolved(path)
        buffer = self.buffer(path)
        items: list[tuple[Path, bool]] = [(path, True)]
        if buffer is not None and buffer.namespace == PXML_NS:
            scenario = self.scenario_for(path)
            if scenario is not None:
                items.insert(0, (scenario, True))
        profile = self.profile(self.robot) if self.robot is not None else default_profile()
        with self.unsaved(), no_collections(), keeping(self.kept):
            report = _validation(profile, self.robot is not None).run(items)
        names: dict[str, bool] = {}
        problems = []
        for problem in report.problems:
            mine = names.get(problem.file)
            if mine is None:
                mine = names[problem.file] = resolved(Path(problem.file)) == key
            if mine:
                problems.append(problem)
        return Checked(problems, self.depends(path))

    def problems(self, path: Path) -> list[Problem]:
        """The file's problems, as ``prima validate`` reports them."""
        return self.check(path).problems
