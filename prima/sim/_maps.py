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
"""The side (m) of the squares a map files its places and walls by
(:meth:`WorldMap.places_along`, :meth:`WorldMap.walls_along`)."""
_LONG: Final = 64
"""A wall that reaches into more squares than this is not filed by square: each question
about the walls along a segment offers it (:meth:`WorldMap.walls_along`)."""
_ROUNDING: Final = 1e-6
"""A margin (m) for rounding: a segment's squares are found for a reach this much longer
(a map's numbers are at most 10,000 m, where a float's last bit is 2e-12 m)."""


def _squares(ax: float, ay: float, bx: float, by: float, reach: float,
             limit: int) -> list[tuple[int, int]] | None:
    """The squares of the grid that hold a point within ``reach`` of the segment from a
    to b, and maybe some more beside them; None when they are more than ``limit``, so
    that a long segment costs no more than a question to every thing filed. Where the
    segment's box (widened by ``reach``) has at most twice as many squares as it has
    columns and rows (a walk would find nearly as many), or the segment is upright, they
    are the box's squares; else, column by column, the rows the part of the segment over that
    column (widened by ``reach``) spans."""
    if ax > bx:
        ax, ay, bx, by = bx, by, ax, ay
    reach += _ROUNDING
    c0, c1 = math.floor((ax - reach) / _CELL), math.floor((bx + reach) / _CELL)
    low, high = (ay, by) if ay <= by else (by, ay)
    r0, r1 = math.floor((low - reach) / _CELL), math.floor((high + reach) / _CELL)
    if c1 - c0 >= limit or r1 - r0 >= limit:  # (each column holds one, and each row)
        return None
    cols, rows = c1 - c0 + 1, r1 - r0 + 1
    if cols * rows <= 2 * (cols + rows) or ax == bx:
        if cols * rows > limit:
            return None
        return [(cx, cy) for cx in range(c0, c1 + 1) for cy in range(r0, r1 + 1)]
    dx = bx - ax
    dy = by - ay
    found: list[tuple[int, int]] = []
    for cx in range(c0, c1 + 1):  # (the part of the segment within reach of the column)
        t0 = min(max((cx * _CELL - reach - ax) / dx, 0.0), 1.0)
        t1 = min(max(((cx + 1) * _CELL + reach - ax) / dx, 0.0), 1.0)
        y0, y1 = ay + dy * t0, ay + dy * t1
        if y0 > y1:
            y0, y1 = y1, y0
        low_row, high_row = math.floor((y0 - reach) / _CELL), math.floor((y1 + reach) / _CELL)
        if len(found) + high_row - low_row + 1 > limit:
            return None
        for cy in range(low_row, high_row + 1):
            found.append((cx, cy))
    return found


def _filed(grid: Mapping[tuple[int, int], tuple[int, ...]],
           squares: list[tuple[int, int]]) -> list[int]:
    """What ``grid`` files in ``squares``, each once, in the order first met."""
    found: dict[int, None] = {}
    for square in squares:
        for i in grid.get(square, ()):
            found[i] = None
    return list(found)


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
    _wall_grid: Mapping[tuple[int, int], tuple[int, ...]] = field(
        init=False, repr=False, compare=False)
    """The walls by the squares that hold a point of them (their indices), but those
    in :attr:`_long`."""
    _long: tuple[int, ...] = field(init=False, repr=False, compare=False)
    """The walls that reach into more than :data:`_LONG` squares (their indices)."""
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
        walls: dict[tuple[int, int], list[int]] = {}
        long = []
        for i, w in enumerate(self.walls):
            squares = _squares(w.x1, w.y1, w.x2, w.y2, w.thickness / 2, _LONG)
            if squares is None:
                long.append(i)
                continue
            for square in squares:
                walls.setdefault(square, []).append(i)
        object.__setattr__(self, "_wall_grid", {k: tuple(v) for k, v in walls.items()})
        object.__setattr__(self, "_long", tuple(long))

    def places_along(self, ax: float, ay: float, bx: float, by: float,
                     reach: float) -> list[int]:
        """The places within ``reach`` of the segment from a to b (a point when a is b),
        and maybe some more near it (their indices, each once, in no particular order):
        the candidates a search for the places near a point or a way measures. It looks
        only at the squares within reach of the segment, or at every place when they
        are more than the places."""
        squares = _squares(ax, ay, bx, by, reach, len(self.places))
        if squares is None:
            return list(range(len(self.places)))
        return _filed(self._grid, squares)

    def walls_along(self, ax: float, ay: float, bx: float, by: float,
                    reach: float) -> list[int]:
        """The walls that may come within ``reach`` of the segment from a to b (their
        indices, each once, in no particular order): those filed in the squares within
        reach of the segment, and the long ones; or every wall, when the squares are
        more than the walls. A wall is within reach when a point of it (its thickness
        included) is."""
        walls = len(self.walls)
        squares = _squares(ax, ay, bx, by, reach, walls)
        if squares is None:
            return list(range(walls))
        return [*self._long, *_filed(self._wall_grid, squares)]

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

