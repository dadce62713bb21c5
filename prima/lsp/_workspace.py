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
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from prima.dsl import RobotProfile, default_profile, load_profile
from prima.errors import DocumentError, LocatedError, Problem
from prima.lsp._xml import Tag, XmlText, scan
from prima.xmlio import read_source, unsaved

__all__ = ["MAX_SCENARIOS", "Buffer", "Place", "Setting", "Workspace"]

MAX_SCENARIOS = 2_000
"""Most ``*.xml`` files looked into for scenarios in a workspace."""

SCENARIO_NS = "urn:prima:scenario:1"
_SKIPPED = frozenset({".git", ".hg", ".svn", ".venv", "venv", "node_modules", "__pycache__",
                      "build", "dist", ".tox", ".mypy_cache", ".pytest_cache"})
_ROLES = (("apps", "fa", "fa"), ("apps", "ea", "ea"), ("ea", "href", "ea"),
          ("zone", "ea", "zone"))
"""(element, attribute, role) of every application a scenario runs."""


@dataclass
class Buffer:
    """A file's text as read: from the editor, or from disk."""

    path: Path
    text: str
    xml: XmlText = field(init=False)

    def __post_init__(self) -> None:
        self.xml = scan(self.text)

    @property
    def namespace(self) -> str | None:
        root = self.xml.root
        return None if root is None else root.get("xmlns") or None

    @property
    def kind(self) -> str:
        """A PXML document's ``kind`` (``fa``, ``ea``; empty if not written)."""
        root = self.xml.root
        return "" if root is None else root.get("kind")


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


def _key(path: Path) -> Path:
    try:
        return path.resolve()
    except (OSError, RuntimeError):
        return path.absolute()


class Workspace:
    """The buffers, the workspace's folders, and the robot given to the server."""

    def __init__(self, roots: list[Path], robot: Path | None = None) -> None:
        self.roots = roots
        self.robot = robot
        """``prima lsp --robot``: the profile documents are checked against, as
        ``prima validate --robot`` does (over a scenario's)."""
        self.buffers: dict[Path, Buffer] = {}
        self._read: dict[Path, tuple[tuple[int, int], Buffer]] = {}
        self._scenarios: list[Path] | None = None
        self._profiles: dict[Path, tuple[object, RobotProfile | None]] = {}

    # ---- buffers and files

    def open(self, path: Path, text: str) -> Buffer:
        buffer = Buffer(path, text)
        self.buffers[_key(path)] = buffer
        if buffer.namespace == SCENARIO_NS:
            self.forget()
        return buffer

    def close(self, path: Path) -> None:
        self.buffers.pop(_key(path), None)

    def forget(self) -> None:
        """Files changed on disk (or a scenario in a buffer): look for scenarios again."""
        self._scenarios = None

    def buffer(self, path: Path) -> Buffer | None:
        """The file's text: the editor's, else the disk's (None if it cannot be read)."""
        key = _key(path)
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
            return cached[1]
        try:
            text = read_source(key, DocumentError).decode("utf-8-sig", "replace")
        except LocatedError:
            return None
        buffer = Buffer(path, text)
        self._read[key] = (stamp, buffer)
        return buffer

    @contextmanager
    def unsaved(self) -> Iterator[None]:
        """Everything read meanwhile reads the editor's buffers in place of their files."""
        with unsaved({p: b.text.encode("utf-8") for p, b in self.buffers.items()}):
            yield

    # ---- scenarios

    def scenarios(self) -> list[Path]:
        """The workspace's scenario files, in path order (as ``prima validate`` of its
        folders would meet them)."""
        if self._scenarios is None:
            found: set[Path] = set()
            for root in self.roots:
                found.update(self._walk(root))
            found.update(p for p, b in self.buffers.items() if b.namespace == SCENARIO_NS)
            self._scenarios = sorted(found)
        return [p for p in self._scenarios if self._is_scenario(p)]

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
                path = _key(Path(folder) / name)
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
                    out.append((role, _key(scenario.parent / tag.get(attribute)), tag, attribute))
        return out

    def scenario_for(self, path: Path) -> Path | None:
        """The first scenario that runs the document ``path``, if any."""
        key = _key(path)
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
        """What is in force for the file ``path``."""
        buffer = self.buffer(path)
        namespace = None if buffer is None else buffer.namespace
        scenario = _key(path) if namespace == SCENARIO_NS else (
            self.scenario_for(path) if namespace == "urn:prima:pxml:1" else None)
        profile_path = self.robot
        map_path: Path | None = None
        if scenario is not None:
            for role, target, _tag, _attr in self.references(scenario):
                if role == "profile" and self.robot is None:
                    profile_path = target
                elif role == "map" and map_path is None:
                    map_path = target
        if namespace == "urn:prima:map:1":
            map_path = _key(path)
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

    def problems(self, path: Path) -> list[Problem]:
        """The file's problems, as ``prima validate`` reports them: the file alone, or a
        document with the scenario that runs it (its robot, its map's places)."""
        from prima.cli import make_validation

        key = _key(path)
        buffer = self.buffer(path)
        items: list[tuple[Path, bool]] = [(path, True)]
        if buffer is not None and buffer.namespace == "urn:prima:pxml:1":
            scenario = self.scenario_for(path)
            if scenario is not None:
                items.insert(0, (scenario, True))
        profile = self.profile(self.robot) if self.robot is not None else default_profile()
        with self.unsaved():
            report = make_validation(profile, robot=self.robot is not None).run(items)
        return [p for p in report.problems if _key(Path(p.file)) == key]
