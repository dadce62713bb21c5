"""A building's map: walls, named places, the topological place graph, areas.

Pure data plus graph search; the simulator builds its pymunk world from it,
and :func:`prima.scenario.load_map` reads it from a map file.
"""

from __future__ import annotations

import enum
import heapq
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Final

from prima.errors import SimulationError

__all__ = ["Area", "Place", "PlaceKind", "Wall", "WorldMap"]


class PlaceKind(str, enum.Enum):
    """What a named place on the map is (reported with ``place-reached``)."""

    ENTRANCE = "entrance"
    """Where visitors come in."""
    HALL = "hall"
    """An open hall or lobby."""
    CORRIDOR = "corridor"
    """A point along a corridor."""
    CORNER = "corner"
    """A corner where the route turns."""
    DOOR = "door"
    """A doorway between two areas."""
    ROOM = "room"
    """A room (for example, a professor's office)."""
    POSTER = "poster"
    """A poster on a wall."""
    PANEL = "panel"
    """A museum display panel."""
    SHELF = "shelf"
    """A library bookshelf."""
    COUNTER = "counter"
    """A service counter."""
    POINT = "point"
    """Any other named point."""


@dataclass(frozen=True)
class Place:
    """A named place: where the robot stands when it is there."""

    name: str
    kind: PlaceKind
    x: float
    y: float
    facing: float | None = None
    """Heading (deg) toward the thing at this place (a panel, a shelf), if any."""

    def to_dict(self) -> dict[str, object]:
        return {"name": self.name, "kind": self.kind.value, "x": self.x, "y": self.y,
                "facing": self.facing}


@dataclass(frozen=True)
class Wall:
    """A straight wall (or shelf, or panel board): it blocks motion and sight."""

    x1: float
    y1: float
    x2: float
    y2: float
    thickness: float = 0.1

    def to_dict(self) -> dict[str, float]:
        return {"x1": self.x1, "y1": self.y1, "x2": self.x2, "y2": self.y2,
                "thickness": self.thickness}


@dataclass(frozen=True)
class Area:
    """A named axis-aligned rectangle (a room, an exhibition); zones refer to areas."""

    name: str
    x1: float
    y1: float
    x2: float
    y2: float

    def contains(self, x: float, y: float) -> bool:
        return (min(self.x1, self.x2) <= x <= max(self.x1, self.x2)
                and min(self.y1, self.y2) <= y <= max(self.y1, self.y2))

    def to_dict(self) -> dict[str, object]:
        return {"name": self.name, "x1": self.x1, "y1": self.y1, "x2": self.x2, "y2": self.y2}


_CELL: Final = 2.0
"""The side (m) of the squares a map files its places by (:meth:`WorldMap.places_in`)."""


@dataclass(frozen=True)
class WorldMap:
    """Walls, places, undirected place-graph edges and areas of one building."""

    name: str
    walls: tuple[Wall, ...] = ()
    places: tuple[Place, ...] = ()
    edges: tuple[tuple[str, str], ...] = ()
    areas: tuple[Area, ...] = ()
    source: str = ""
    """The file it was loaded from, if any."""
    _index: Mapping[str, Place] = field(init=False, repr=False, compare=False)
    _adjacent: Mapping[str, tuple[tuple[str, float], ...]] = field(
        init=False, repr=False, compare=False)
    _grid: Mapping[tuple[int, int], tuple[int, ...]] = field(
        init=False, repr=False, compare=False)
    """The places by the square of :data:`_CELL` metres they are in (their indices)."""
    _order: Mapping[str, int] = field(init=False, repr=False, compare=False)
    """Each place's index in :attr:`places` (the search's tie-break)."""
    _routes: dict[tuple[str, str], tuple[Place, ...]] = field(
        init=False, repr=False, compare=False)
    """:meth:`route` by its two places, once asked (a move asks again at each of its
    iterations; the map never changes)."""

    def outline(self) -> list[tuple[float, float]]:
        """The points that span the map: the walls' ends and the places (to frame it)."""
        points = [(w.x1, w.y1) for w in self.walls] + [(w.x2, w.y2) for w in self.walls]
        return points + [(p.x, p.y) for p in self.places]

    def __post_init__(self) -> None:
        # (a map file's numbers are bounded already: this is for a map built in Python)
        for x, y in self.outline():
            if not (math.isfinite(x) and math.isfinite(y)):
                raise SimulationError(f"map {self.name!r}: a wall or a place is not at a "
                                      f"finite position ({x}, {y})")
        index = {p.name: p for p in self.places}
        if len(index) != len(self.places):
            raise SimulationError(f"map {self.name!r} has duplicate place names")
        adjacent: dict[str, list[tuple[str, float]]] = {name: [] for name in index}
        for a, b in self.edges:
            if a not in index or b not in index:
                raise SimulationError(f"map {self.name!r}: edge {a}-{b} names an unknown place")
            d = math.hypot(index[a].x - index[b].x, index[a].y - index[b].y)
            adjacent[a].append((b, d))
            adjacent[b].append((a, d))
        object.__setattr__(self, "_index", index)
        object.__setattr__(self, "_order", {p.name: i for i, p in enumerate(self.places)})
        object.__setattr__(self, "_routes", {})
        object.__setattr__(self, "_adjacent",
                           {k: tuple(v) for k, v in adjacent.items()})
        grid: dict[tuple[int, int], list[int]] = {}
        for i, p in enumerate(self.places):
            grid.setdefault((math.floor(p.x / _CELL), math.floor(p.y / _CELL)), []).append(i)
        object.__setattr__(self, "_grid", {k: tuple(v) for k, v in grid.items()})

    def places_in(self, x1: float, y1: float, x2: float, y2: float) -> list[int]:
        """The places in the box from (x1, y1) to (x2, y2), edges included, and maybe
        some more near it (their indices, in no particular order): the candidates a
        search for the places near a point measures. It looks only at the squares the
        box covers, or at every place when they are fewer."""
        cx1, cx2 = math.floor(x1 / _CELL), math.floor(x2 / _CELL)
        cy1, cy2 = math.floor(y1 / _CELL), math.floor(y2 / _CELL)
        if (cx2 - cx1 + 1) * (cy2 - cy1 + 1) > len(self.places):
            return list(range(len(self.places)))
        grid = self._grid
        found: list[int] = []
        for cx in range(cx1, cx2 + 1):
            for cy in range(cy1, cy2 + 1):
                found.extend(grid.get((cx, cy), ()))
        return found

    def place(self, name: str) -> Place | None:
        """The place called ``name``, or None."""
        return self._index.get(name)

    def area(self, name: str) -> Area | None:
        for a in self.areas:
            if a.name == name:
                return a
        return None

    def shortest_path(self, starts: Mapping[str, float],
                      goals: Mapping[str, float]) -> list[str]:
        """Cheapest place path from a start to a goal over the place graph.

        ``starts`` and ``goals`` map place names to the cost of getting onto
        and off the graph there. Returns the place names, start and goal
        included; empty if no goal is reachable. Ties are broken by place
        order in the map, so plans are deterministic.
        """
        order = self._order
        best: dict[str, float] = {}
        back: dict[str, str | None] = {}
        heap: list[tuple[float, int, int, str, str | None]] = []
        seq = 0
        for name, cost in starts.items():
            if name in order:
                seq += 1
                heapq.heappush(heap, (cost, order[name], seq, name, None))
        while heap:
            cost, _, _, name, prev = heapq.heappop(heap)
            if name in best:
                continue
            best[name] = cost
            back[name] = prev
            for other, d in self._adjacent[name]:
                if other not in best:
                    seq += 1
                    heapq.heappush(heap, (cost + d, order[other], seq, other, name))
        reachable = [(best[g] + c, order[g], g) for g, c in goals.items() if g in best]
        if not reachable:
            return []
        path: list[str] = []
        node: str | None = min(reachable)[2]
        while node is not None:
            path.append(node)
            node = back[node]
        return path[::-1]

    def route(self, start: str, goal: str) -> tuple[Place, ...]:
        """The places of the cheapest path from the place ``start`` to the place ``goal``
        (:meth:`shortest_path` with no cost to get on or off the graph), both included;
        empty if ``goal`` is unreachable or either is no place. Worked out once per pair."""
        key = (start, goal)
        found = self._routes.get(key)
        if found is None:
            index = self._index
            found = tuple(index[n] for n in self.shortest_path({start: 0.0}, {goal: 0.0}))
            self._routes[key] = found
        return found

    def to_dict(self) -> dict[str, object]:
        return {
            "name": self.name,
            "walls": [w.to_dict() for w in self.walls],
            "places": [p.to_dict() for p in self.places],
            "edges": [list(e) for e in self.edges],
            "areas": [a.to_dict() for a in self.areas],
        }

