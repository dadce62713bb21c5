"""Scenario and map files: loading, validation (XSD, then meaning), the Scenario record.

Loading is two-stage, like documents: the XSD checks structure, then the
meaning checks look at what the schema cannot (unknown places, a wall across a
graph edge, actions out of time order, an answer pattern outside the safe
subset, a number the simulator cannot use). Every problem is a
:class:`~prima.errors.Problem` with ``file:line:col``; all of a file's
problems (at most 50, then a line counting the rest) are raised together as
one :class:`~prima.errors.ScenarioError`.

Every number is checked as the simulator will use it: a decimal the schema
accepts can be infinite or zero as a float (``1`` and 400 zeros), and times,
sizes, speeds and coordinates have the documented ranges of :data:`BOUNDS`.
"""

from __future__ import annotations

import dataclasses
import heapq
import math
import os
import re
import stat
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import MappingProxyType

import pymunk
from lxml import etree

from prima.errors import Problem, ScenarioError, Severity
from prima.sim import (
    SENSE_HZ,
    AnswerRule,
    Area,
    Place,
    PlaceKind,
    Pose,
    ReplyRule,
    ScheduledEvent,
    TimedAction,
    UserActionKind,
    UserScript,
    Wall,
    WorldMap,
    Zone,
)
from prima.vocab import MAX_EAS, MAX_RUN_TIME, MAX_SEED
from prima.xmlio import (
    Bound,
    XmlDocument,
    integer,
    is_element,
    limit,
    local_name,
    number,
    parse_xml,
    read_source,
    validate,
)

__all__ = ["BOUNDS", "FILE_ATTRIBUTES", "MAP_NS", "SCENARIO_NS", "SCHEDULED", "USER_TIMED",
           "Reference", "Scenario", "late_inputs", "load_map", "load_scenario",
           "safe_pattern", "scenario_references"]

MAP_NS = "urn:prima:map:1"
SCENARIO_NS = "urn:prima:scenario:1"

MAX_UNTIL = MAX_RUN_TIME
"""Longest run (s); every time in a scenario is at most this."""

MAX_RATE = 1_000
"""Most physics steps per simulated second (a multiple of 10)."""

MAX_NTH = 1_000_000
"""Largest ``nth`` of an answer rule."""

MAX_MATCHES = 200
"""Longest answer pattern (``matches``, characters)."""

_TIME = Bound(MAX_UNTIL, "s", positive=False)
_COORDINATE = Bound(10_000.0, "m", -10_000.0, positive=False)
_HEADING = Bound(360.0, "deg", -360.0, positive=False)
_SPEED = Bound(100.0, "m/s")
_SIZE = Bound(10_000.0, "m")

BOUNDS: Mapping[str, Bound] = {
    "until": Bound(MAX_UNTIL, "s"),
    "at": _TIME, "after": Bound(_TIME.high, "s", -60.0, positive=False),
    "x": _COORDINATE, "y": _COORDINATE,
    "x1": _COORDINATE, "y1": _COORDINATE, "x2": _COORDINATE, "y2": _COORDINATE,
    "heading": _HEADING, "facing": _HEADING,
    "speed": _SPEED,
    "distance": _SIZE, "thickness": Bound(100.0, "m"),
    "noise": Bound(100.0, "m", positive=False),
    "heading-noise": Bound(360.0, "deg", positive=False),
}
"""The range of every number of a scenario or map, by attribute name."""


@dataclass(frozen=True)
class Scenario:
    """A loaded scenario. Paths are kept as written (relative to the scenario file)."""

    name: str
    source: str
    """The scenario file's path."""
    map: WorldMap
    robot: Pose
    until: float
    """The run ends at this simulated time (s)."""
    seed: int = 0
    rate: int = 50
    """Physics steps per simulated second."""
    noise: float = 0.0
    """Localization noise: standard deviation of x and y (m)."""
    heading_noise: float = 0.0
    """Localization noise: standard deviation of the heading (deg)."""
    profile: str | None = None
    """Robot hardware profile path; the run loop turns it into a RobotSpec."""
    fa: str | None = None
    ea: str | None = None
    """The EA running from the start (more may be loaded on entering zones)."""
    eas: tuple[str, ...] = ()
    """More EAs running from the start beside ``ea`` (``<apps><ea href/></apps>``), in
    document order; with ``ea``, at most :data:`~prima.vocab.MAX_EAS`."""
    user: UserScript | None = None
    events: tuple[ScheduledEvent, ...] = ()
    replies: tuple[ReplyRule, ...] = ()
    """How the environment's servers answer what the applications send them."""
    zones: tuple[Zone, ...] = ()
    description: str = ""
    policies: Mapping[str, bool] = field(default_factory=dict)
    """Mediation policies the scenario switches (``all`` first), over the robot
    profile's; the run joins them (the simulator itself has no use for them)."""

    def resolve(self, path: str) -> Path:
        """A path written in the scenario, relative to the scenario file's folder."""
        return (Path(self.source).parent / path).resolve()

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name, "source": self.source, "map": self.map.name,
            "robot": self.robot.to_dict(), "until": self.until, "seed": self.seed,
            "rate": self.rate, "noise": self.noise, "heading_noise": self.heading_noise,
            "profile": self.profile, "fa": self.fa, "ea": self.ea,
            "user": None if self.user is None else self.user.to_dict(),
            "events": [e.to_dict() for e in self.events],
            "replies": [r.to_dict() for r in self.replies],
            "zones": [z.to_dict() for z in self.zones],
            "policies": dict(self.policies),
        } | ({"eas": list(self.eas)} if self.eas else {})


# ---- shared helpers ----------------------------------------------------------------------

def _parse(path: Path, schema: str, namespace: str, root: str) -> XmlDocument:
    doc = parse_xml(read_source(path, ScenarioError), str(path), ScenarioError)
    if etree.QName(doc.root).namespace != namespace or local_name(doc.root) != root:
        raise ScenarioError([doc.problem(
            doc.root, f"expected a <{root}> element in namespace {namespace!r}, "
                      f"found <{local_name(doc.root)}>"
                      f" in {etree.QName(doc.root).namespace or 'no namespace'!r}")])
    problems = validate(doc, schema)
    if problems:
        raise ScenarioError(problems)
    return doc


def _children(el: etree._Element) -> Iterator[etree._Element]:
    return (c for c in el if is_element(c))


class _Numbers:
    """Reads the numbers of a scenario or map file, collecting their problems."""

    def __init__(self, doc: XmlDocument) -> None:
        self.doc = doc
        self.problems: list[Problem] = []

    def get(self, el: etree._Element, name: str, default: float = 0.0) -> float:
        """Attribute ``name`` within its :data:`BOUNDS` range; ``default`` if absent or bad."""
        value = number(self.doc, el, name, BOUNDS[name], default)
        if isinstance(value, Problem):
            self.problems.append(value)
            return default
        return value

    def maybe(self, el: etree._Element, name: str) -> float | None:
        """Like :meth:`get`, or None when the attribute is absent."""
        return None if el.get(name) is None else self.get(el, name)

    def whole(self, el: etree._Element, name: str, high: int, default: int) -> int:
        """A whole number at most ``high``; ``default`` if absent or bad."""
        value = integer(self.doc, el, name, high, default)
        if isinstance(value, Problem):
            self.problems.append(value)
            return default
        return value


def _shown(path: Path) -> str:
    """Where a file a scenario names was looked for: the absolute path, dots resolved
    (the name as written is already in the message)."""
    return os.path.normpath(path.absolute())


def _unusable(path: Path) -> str | None:
    """Why a file a scenario names cannot be read (missing, not a regular file), or None."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return "not found"
    return None if stat.S_ISREG(mode) else "is not a regular file"


def _text(el: etree._Element) -> str:
    return " ".join((el.text or "").split())


# ---- maps --------------------------------------------------------------------------------

def load_map(path: str | Path) -> WorldMap:
    """Load and check a map file; raise ScenarioError with located problems."""
    path = Path(path)
    doc = _parse(path, "map.xsd", MAP_NS, "map")
    walls: list[Wall] = []
    places: list[Place] = []
    edges: list[tuple[str, str]] = []
    areas: list[Area] = []
    num = _Numbers(doc)
    problems = num.problems
    place_at: dict[str, etree._Element] = {}
    area_names: set[str] = set()
    edge_els: list[etree._Element] = []
    for el in _children(doc.root):
        tag = local_name(el)
        if tag == "wall":
            walls.append(Wall(num.get(el, "x1"), num.get(el, "y1"), num.get(el, "x2"),
                              num.get(el, "y2"), num.get(el, "thickness", 0.1)))
        elif tag == "place":
            name = el.get("name", "")
            if name in place_at:
                line = doc.where.element(place_at[name])[0]
                problems.append(doc.problem(el, f"place {name!r} is already defined on line {line}",
                                            attribute="name"))
                continue
            place_at[name] = el
            places.append(Place(name, PlaceKind(el.get("kind", "point")), num.get(el, "x"),
                                num.get(el, "y"), num.maybe(el, "facing")))
        elif tag == "edge":
            edge_els.append(el)
        elif tag == "area":
            name = el.get("name", "")
            if name in area_names:
                problems.append(doc.problem(el, f"area {name!r} is already defined",
                                            attribute="name"))
                continue
            area_names.add(name)
            areas.append(Area(name, *(num.get(el, a) for a in ("x1", "y1", "x2", "y2"))))
    space = _wall_space(walls)
    by_name = {p.name: p for p in places}
    known = _known(by_name)  # once: a map may name thousands of unknown places
    for el in edge_els:
        a, b = el.get("from", ""), el.get("to", "")
        bad = False
        for attr, name in (("from", a), ("to", b)):
            if name not in by_name:
                problems.append(doc.problem(el, f"unknown place {name!r}{known}",
                                            attribute=attr))
                bad = True
        if bad:
            continue
        if a == b:
            problems.append(doc.problem(el, f"edge joins place {a!r} to itself"))
            continue
        pa, pb = by_name[a], by_name[b]
        hit = space.segment_query_first((pa.x, pa.y), (pb.x, pb.y), 0.0, pymunk.ShapeFilter())
        if hit is not None:
            problems.append(doc.problem(
                el, f"edge {a} -> {b} crosses a wall at ({hit.point.x:.2f}, {hit.point.y:.2f})"))
            continue
        edges.append((a, b))
    if problems:
        raise ScenarioError(limit(sorted(problems), str(path)))
    name = doc.root.get("name", path.stem)
    return WorldMap(name, tuple(walls), tuple(places), tuple(edges), tuple(areas),
                    source=str(path))


def _wall_space(walls: list[Wall]) -> pymunk.Space:
    space = pymunk.Space()
    for w in walls:
        space.add(pymunk.Segment(space.static_body, (w.x1, w.y1), (w.x2, w.y2), w.thickness / 2))
    return space


def _known(names: Iterable[str]) -> str:
    """A hint listing up to 12 of ``names`` (empty if there are none)."""
    shown = heapq.nsmallest(13, names)
    if not shown:
        return ""
    more = "" if len(shown) <= 12 else ", ..."
    return f" (known: {', '.join(shown[:12])}{more})"


# ---- scenarios --------------------------------------------------------------------------------

_ACTIONS = {k.value: k for k in (UserActionKind.SAY, UserActionKind.TOUCH, UserActionKind.WALK,
                                 UserActionKind.LEAVE, UserActionKind.FOLLOW,
                                 UserActionKind.STOP)}

USER_TIMED = frozenset(_ACTIONS)
"""The user's timed actions (children of ``<user>`` with ``at``)."""


class _Loader:
    def __init__(self, doc: XmlDocument, path: Path,
                 maps: Callable[[Path], WorldMap] = load_map) -> None:
        self.maps = maps
        self.replies: list[ReplyRule] = []
        self.doc = doc
        self.path = path
        self.num = _Numbers(doc)
        self.problems = self.num.problems
        self.map: WorldMap | None = None
        self._hints: dict[str, str] = {}
        self._areas: dict[str, Area] | None = None

    def hint(self, what: str, names: Callable[[], Iterable[str]]) -> str:
        """:func:`_known` of ``names``, computed once per ``what`` (a scenario may name
        thousands of unknown places)."""
        if what not in self._hints:
            self._hints[what] = _known(names())
        return self._hints[what]

    def area(self, name: str) -> Area | None:
        """The map's first area called ``name`` (looked up, not searched)."""
        if self._areas is None:
            self._areas = {}
            for a in self.map.areas if self.map is not None else ():
                self._areas.setdefault(a.name, a)
        return self._areas.get(name)

    def bad(self, el: etree._Element, message: str, attribute: str | None = None) -> None:
        self.problems.append(self.doc.problem(el, message, attribute=attribute))

    def blank(self, el: etree._Element, attribute: str, message: str) -> None:
        """An error at ``attribute`` when it is given but blank (empty, spaces, tabs)."""
        value = el.get(attribute)
        if value is not None and not value.strip():
            self.bad(el, message, attribute)

    def place(self, el: etree._Element, attribute: str) -> Place | None:
        name = el.get(attribute)
        if name is None or self.map is None:
            return None
        place = self.map.place(name)
        if place is None:
            places = self.map.places
            known = self.hint("places", lambda: (p.name for p in places))
            self.bad(el, f"unknown place {name!r} on map {self.map.name!r}{known}", attribute)
        return place

    def where(self, el: etree._Element, attribute: str = "place") -> Pose:
        """A pose given as a place name, or as x and y; heading from the element or the place."""
        has_xy = el.get("x") is not None or el.get("y") is not None
        if el.get(attribute) is not None and has_xy:
            self.bad(el, f"give either '{attribute}' or 'x' and 'y', not both", attribute)
        elif el.get(attribute) is None and (el.get("x") is None or el.get("y") is None):
            self.bad(el, f"<{local_name(el)}> needs '{attribute}' or both 'x' and 'y'")
            return Pose(0.0, 0.0)
        place = self.place(el, attribute)
        heading = self.num.maybe(el, "heading")
        if place is not None:
            return Pose(place.x, place.y, heading if heading is not None else place.facing or 0.0)
        return Pose(self.num.get(el, "x"), self.num.get(el, "y"), heading or 0.0)

    def load(self) -> Scenario:
        root = self.doc.root
        kids = {local_name(c): c for c in _children(root)}
        map_el = kids["map"]
        href = map_el.get("href", "")
        map_path = self.path.parent / href
        unusable = _unusable(map_path)
        if unusable is not None:
            self.bad(map_el, f"map file {href!r} {unusable} (looked for {_shown(map_path)})",
                     "href")
            raise ScenarioError(self.problems)
        self.map = self.maps(map_path)
        robot_el = kids["robot"]
        robot = self.where(robot_el)
        apps = kids.get("apps")
        self.exists(robot_el, "profile")
        eas: tuple[str, ...] = ()
        if apps is not None:
            self.exists(apps, "fa")
            self.exists(apps, "ea")
            eas = self.more_eas(apps)
        for zone_el in (c for c in _children(root) if local_name(c) == "zone"):
            self.exists(zone_el, "ea")
        user = self.user(kids["user"]) if "user" in kids else None
        events, zones = self.environment(root)
        until, seed, rate = self.num.get(root, "until", 1.0), self.seed(root), self.rate(root)
        policies = self.policies(root)
        noise = self.num.get(robot_el, "noise")
        heading_noise = self.num.get(robot_el, "heading-noise")
        if self.problems:
            raise ScenarioError(limit(sorted(self.problems), str(self.path)))
        return Scenario(
            name=root.get("name", self.path.stem), source=str(self.path), map=self.map,
            robot=robot, until=until, seed=seed, rate=rate, noise=noise,
            heading_noise=heading_noise,
            profile=robot_el.get("profile"),
            fa=apps.get("fa") if apps is not None else None,
            ea=apps.get("ea") if apps is not None else None, eas=eas,
            user=user, events=events, replies=tuple(self.replies), zones=zones,
            description=_text(kids["description"]) if "description" in kids else "",
            policies=policies)

    def more_eas(self, apps: etree._Element) -> tuple[str, ...]:
        """The ``<ea href>`` children of ``<apps>``: EAs running from the start beside
        the ``ea`` attribute's, each file once, at most :data:`MAX_EAS` in all."""
        out: list[str] = []
        first = apps.get("ea")
        seen = {os.path.normpath(self.path.parent / first)} if first else set()
        for el in (c for c in _children(apps) if local_name(c) == "ea"):
            href = el.get("href", "")
            self.exists(el, "href")
            named = os.path.normpath(self.path.parent / href)
            if named in seen:
                self.bad(el, f"the EA {href!r} is already running from the start", "href")
            elif len(seen) >= MAX_EAS:
                self.bad(el, f"at most {MAX_EAS} EAs run at once; this would be EA "
                             f"{len(seen) + 1}", "href")
            else:
                out.append(href)
            seen.add(named)
        return tuple(out)

    def exists(self, el: etree._Element, attribute: str) -> None:
        """A file the scenario names (a document, a profile) must be a regular file; it is not
        opened here (``prima validate`` checks it too)."""
        value = el.get(attribute)
        if value is None:
            return
        unusable = _unusable(self.path.parent / value)
        if unusable is not None:
            self.bad(el, f"file {value!r} {unusable} (looked for "
                         f"{_shown(self.path.parent / value)})", attribute)

    def policies(self, root: etree._Element) -> Mapping[str, bool]:
        out: dict[str, bool] = {}
        for el in (c for c in _children(root) if local_name(c) == "policy"):
            name = el.get("name", "")
            if name in out:
                self.bad(el, f"a second <policy name={name!r}>: switch each policy once", "name")
            out[name] = el.get("state") == "on"
        return MappingProxyType(out)

    def seed(self, root: etree._Element) -> int:
        return self.num.whole(root, "seed", MAX_SEED, 0)

    def rate(self, root: etree._Element) -> int:
        """Steps per second: a multiple of the simulator's sensing rate, at most MAX_RATE."""
        rate = self.num.whole(root, "rate", MAX_RATE, 50)
        if rate % SENSE_HZ or rate <= 0:
            self.bad(root, f"rate must be a multiple of {SENSE_HZ} steps per second, not {rate}",
                     "rate")
            return 50
        return rate

    def user(self, el: etree._Element) -> UserScript:
        start = self.where(el)
        speed = self.num.get(el, "speed", 0.3)
        actions: list[TimedAction] = []
        answers: list[AnswerRule] = []
        last = -math.inf
        for child in _children(el):
            tag = local_name(child)
            if tag == "answer":
                answers.append(self.answer(child))
                continue
            at = self.num.get(child, "at")
            if at < last:
                self.bad(child, f"<{tag}> at {at:g} s comes after an action at {last:g} s; "
                                "list the user's actions in time order", "at")
            last = max(last, at)
            kind = _ACTIONS[tag]
            if kind is UserActionKind.SAY:
                self.blank(child, "text", "<say> says nothing: blank words are no speech (the "
                                          "robot never hears them); give words, or leave the "
                                          "<say> out")
            place = None
            if kind in (UserActionKind.WALK, UserActionKind.LEAVE):
                has_xy = child.get("x") is not None or child.get("y") is not None
                if child.get("to") is not None and has_xy:
                    self.bad(child, "give either 'to' or 'x' and 'y', not both", "to")
                elif child.get("to") is None and (child.get("x") is None or child.get("y") is None):
                    self.bad(child, f"<{tag}> needs 'to' (a place) or both 'x' and 'y'")
                found = self.place(child, "to")
                place = found.name if found is not None else None
            num = self.num
            actions.append(TimedAction(
                at=at, action=kind, text=child.get("text"), place=place,
                x=num.maybe(child, "x"), y=num.maybe(child, "y"), speed=num.maybe(child, "speed"),
                distance=num.get(child, "distance", 1.0)))
        return UserScript(start, speed, tuple(actions), tuple(answers))

    def answer(self, el: etree._Element) -> AnswerRule:
        contains, pattern = el.get("contains"), el.get("matches")
        if contains is not None and pattern is not None:
            self.bad(el, "give either 'contains' or 'matches', not both", "matches")
        if pattern is not None:
            fault = safe_pattern(pattern)
            if fault is None:
                try:  # never expected: the subset is made of valid regular expressions
                    re.compile(pattern)
                except re.error as exc:
                    fault = 0, f"matches: bad regular expression: {exc.msg}"
            if fault is not None:
                index, message = fault
                self.problems.append(self.doc.problem(el, message, attribute="matches",
                                                      index=index))
                pattern = None
        self.blank(el, "say", "say is blank: blank words are no answer (the robot never "
                              "hears them); leave say out to stay silent")
        nth = self.num.whole(el, "nth", MAX_NTH, 1) if el.get("nth") is not None else None
        return AnswerRule(say=el.get("say"), contains=contains, pattern=pattern,
                          after=self.num.get(el, "after", 1.0), nth=nth)

    def environment(self, root: etree._Element) -> tuple[tuple[ScheduledEvent, ...],
                                                          tuple[Zone, ...]]:
        events: list[ScheduledEvent] = []
        zones: list[Zone] = []
        zone_names: set[str] = set()
        last = -math.inf
        for el in _children(root):
            tag = local_name(el)
            if tag in ("message", "sound", "event"):
                at = self.num.get(el, "at")
                if at < last:
                    self.bad(el, f"<{tag}> at {at:g} s comes after one at {last:g} s; list "
                                 "messages, sounds and events in time order", "at")
                last = max(last, at)
                if tag == "message":
                    events.append(ScheduledEvent(at, "message", {
                        "sender": el.get("sender", ""), "text": el.get("text", "")}))
                elif tag == "sound":
                    events.append(ScheduledEvent(at, "sound-heard", {"sound": el.get("name", "")}))
                else:
                    data = {d.get("name", ""): d.get("value", "") for d in _children(el)}
                    events.append(ScheduledEvent(at, el.get("name", ""), data))
            elif tag == "reply":
                self.replies.append(ReplyRule(el.get("to", ""), el.get("text", ""),
                                              self.num.get(el, "after", 1.0), el.get("contains")))
            elif tag == "zone":
                zone = self.zone(el)
                if zone is not None:
                    if zone.name in zone_names:
                        self.bad(el, f"zone {zone.name!r} is already defined", "name")
                    zone_names.add(zone.name)
                    zones.append(zone)
        return tuple(events), tuple(zones)

    def zone(self, el: etree._Element) -> Zone | None:
        zone = self._zone(el)
        if zone is None:
            return None
        line, col = self.doc.where.attribute(el, "ea")
        return dataclasses.replace(zone, join=el.get("join", "false") in ("true", "1"),
                                   line=line, col=col)

    def _zone(self, el: etree._Element) -> Zone | None:
        name, ea = el.get("name", ""), el.get("ea", "")
        rect = [el.get(a) for a in ("x1", "y1", "x2", "y2")]
        area_name = el.get("area")
        if area_name is not None:
            if any(v is not None for v in rect):
                self.bad(el, "give either 'area' or x1, y1, x2, y2, not both", "area")
                return None
            area = self.area(area_name)
            if area is None:
                areas = self.map.areas if self.map is not None else ()
                known = self.hint("areas", lambda: (a.name for a in areas))
                self.bad(el, f"unknown area {area_name!r}{known}", "area")
                return None
            return Zone(name, ea, area)
        if any(v is None for v in rect):
            self.bad(el, "a zone needs 'area' or all of x1, y1, x2, y2")
            return None
        return Zone(name, ea, Area(name, *(self.num.get(el, a) for a in ("x1", "y1", "x2", "y2"))))


_FORBIDDEN = {"*": "repetition", "+": "repetition", "?": "repetition", "{": "repetition",
              "}": "repetition", "(": "a group", ")": "a group", "[": "a character class",
              "]": "a character class"}


def safe_pattern(pattern: str) -> tuple[int, str] | None:
    """Where and why ``pattern`` is outside the safe subset of regular expressions, or None.

    The subset: alternatives separated by ``|``, each literal text in which
    ``.`` is any character, ``\\b`` a word boundary, ``\\d`` ``\\w`` ``\\s`` a digit,
    word character or space, a backslash escapes punctuation, and ``^`` and
    ``$`` anchor at the start and end of an alternative. With no repetition,
    groups or classes, each alternative matches a fixed number of characters
    and ``re.search`` never backtracks: its cost is the prompt's length times
    the pattern's, at most :data:`MAX_MATCHES` characters.
    """
    if len(pattern) > MAX_MATCHES:
        return MAX_MATCHES, f"matches: longer than {MAX_MATCHES} characters"
    i, n, first = 0, len(pattern), True
    while i < n:
        ch = pattern[i]
        if ch == "\\":
            escaped = pattern[i + 1 : i + 2]
            if not escaped or (escaped.isalnum() and escaped not in "bdws"):
                return i, ("matches: a backslash must escape punctuation or be \\b, \\d, \\w "
                           "or \\s")
            i, first = i + 2, False
            continue
        if ch in _FORBIDDEN:
            return i, (f"matches: {_FORBIDDEN[ch]} ({ch!r}) is not in the safe subset of "
                       "regular expressions (docs/scenarios.md)")
        if (ch == "^" and not first) or (ch == "$" and pattern[i + 1 : i + 2] not in ("", "|")):
            return i, f"matches: {ch!r} anchors only at the start ('^') or end ('$') of an " \
                      "alternative"
        first = ch == "|"
        i += 1
    return None


@dataclass(frozen=True)
class Reference:
    """A file a scenario names, and where it names it."""

    role: str
    """``map``, ``profile``, ``fa``, ``ea`` (the EA from the start) or ``zone`` (a zone's EA)."""
    path: Path
    """The file: the scenario's folder joined with ``value`` (normalised, not resolved)."""
    value: str
    """The path as the scenario writes it."""
    line: int
    col: int
    """Where the attribute's value is written in the scenario file."""


_REFERENCES = (("map", "href", "map", ""), ("robot", "profile", "profile", ""),
               ("apps", "fa", "fa", ""), ("apps", "ea", "ea", ""), ("apps", "href", "ea", "ea"),
               ("zone", "ea", "zone", ""))
"""(element, attribute, role, child) of every file a scenario may name: the attribute of
the element itself, or of its ``child`` elements (``<apps><ea href/></apps>``)."""

FILE_ATTRIBUTES: Mapping[str, tuple[str, ...]] = MappingProxyType({
    element: tuple(a for t, a, _r, c in _REFERENCES if (c or t) == element)
    for element in dict.fromkeys(c or t for t, _a, _r, c in _REFERENCES)})
"""Element -> its attributes that name files, relative to the scenario file (those of
:data:`_REFERENCES`, each element by its own name: ``<apps fa ea>``, ``<ea href>``)."""


def scenario_references(path: str | Path) -> list[Reference]:
    """The files a scenario names, in document order; read from its XML alone, so that
    they can be checked even when the scenario itself has errors. Empty if it cannot be
    read or parsed, or is not a scenario."""
    path = Path(path)
    try:
        doc = parse_xml(read_source(path, ScenarioError), str(path), ScenarioError)
    except ScenarioError:
        return []
    if etree.QName(doc.root).namespace != SCENARIO_NS:
        return []
    found = []
    for el in _children(doc.root):
        nested = list(_children(el)) if local_name(el) == "apps" else []
        for tag, attribute, role, inner in _REFERENCES:
            for named_by in (c for c in nested if local_name(c) == inner) if inner else (el,):
                value = named_by.get(attribute)
                if local_name(el) == tag and value:
                    named = Path(os.path.normpath(path.parent / value))
                    found.append(Reference(role, named, value,
                                           *doc.where.attribute(named_by, attribute)))
    return found


SCHEDULED = ("message", "sound", "event")
"""A scenario's inputs scheduled at a time (``at``): the environment's, children of
``<scenario>``."""


def late_inputs(path: str | Path) -> list[Problem]:
    """A warning for each message, sound, event or user action a scenario times at or after
    its ``until``: the run ends before it, so it never happens (read from the XML alone;
    empty if the file cannot be read or its times are not numbers)."""
    path = Path(path)
    try:
        doc = parse_xml(read_source(path, ScenarioError), str(path), ScenarioError)
        until = float(doc.root.get("until", "inf"))
    except (ScenarioError, ValueError):
        return []
    if etree.QName(doc.root).namespace != SCENARIO_NS:
        return []
    timed = [el for el in _children(doc.root) if local_name(el) in SCHEDULED]
    for user in (el for el in _children(doc.root) if local_name(el) == "user"):
        timed += [el for el in _children(user) if el.get("at") is not None]
    out = []
    users = {id(el) for user in _children(doc.root) if local_name(user) == "user"
             for el in _children(user)}
    order = {id(e): i for i, e in enumerate(doc.root.iter())}
    for el in sorted(timed, key=lambda e: order[id(e)]):
        try:
            at = float(el.get("at", ""))
        except ValueError:
            continue
        if at >= until:
            what = "the user's" if id(el) in users else "this"
            out.append(doc.problem(
                el, f"{what} <{local_name(el)}> at {at:g} s is timed at or after the run ends "
                    f"(until={until:g} s): it never happens", severity=Severity.WARNING,
                attribute="at"))
    return out


def load_scenario(path: str | Path,
                  maps: Callable[[Path], WorldMap] = load_map) -> Scenario:
    """Load and check a scenario file (and its map: by ``maps``, which may keep the maps
    it loaded for the runs of a sweep); raise ScenarioError on any problem."""
    path = Path(path)
    doc = _parse(path, "scenario.xsd", SCENARIO_NS, "scenario")
    return _Loader(doc, path, maps).load()
