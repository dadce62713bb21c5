"""The scenario a live session plays, and the scenario it saves.

A session plays a *base* scenario: the scenario the author named, with the command
line's switches written in and, unless its script is kept (``--script``), without
its user's timed actions, answer rules and timed messages, sounds and events (the
author is the user now); or one made for applications alone (:func:`for_apps`). What
the author does is an :class:`Added` input at the tick it was played. Saved
(:meth:`Base.saved`), the base gets those inputs as timed elements at their ticks,
merged with the script's own in the order the simulator plays them, and ends where
the session was: ``prima run`` of it is the live run.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from lxml import etree

from prima.batch import number, repath, switched_root
from prima.dsl import Document
from prima.errors import PrimaError
from prima.escape import markup
from prima.run import Switches
from prima.scenario import SCENARIO_NS, SCHEDULED, USER_TIMED, load_scenario
from prima.sim import ScheduledEvent, TimedAction, UserActionKind, WorldMap
from prima.xmlio import is_element, local_name

__all__ = ["ACTIONS", "Added", "Base", "for_apps", "from_scenario", "user_spot"]

ACTIONS = ("say", "touch", "walk", "follow", "stop", "message")
"""What the author may do from the page: the user's own actions, and a network
message from the environment's server."""



@dataclass(frozen=True)
class Added:
    """An input the author gave, played at ``tick`` (the simulator's ``1 / rate`` s)."""

    tick: int
    kind: str
    """One of :data:`ACTIONS`."""
    text: str | None = None
    """The words said (``say``) or the message's text (``message``)."""
    x: float | None = None
    y: float | None = None
    """Where the user walks to (``walk``; to the centimetre)."""
    sender: str | None = None
    """Who sent the message (``message``)."""

    def given(self, hz: int) -> TimedAction | ScheduledEvent:
        """The input as the simulator takes it, as the scenario loader makes it of the
        element :meth:`element` writes."""
        at = self.tick / hz
        if self.kind == "message":
            return ScheduledEvent(at, "message", {"sender": self.sender or "",
                                                  "text": self.text or ""})
        return TimedAction(at=at, action=UserActionKind(self.kind), text=self.text,
                           x=self.x, y=self.y)

    def element(self, hz: int) -> etree._Element:
        """The input as a scenario writes it."""
        attributes = {"at": number(self.tick / hz)}
        if self.kind == "message":
            attributes.update(sender=self.sender or "", text=self.text or "")
        elif self.kind == "say":
            attributes["text"] = self.text or ""
        elif self.kind == "walk":
            attributes.update(x=number(self.x or 0.0), y=number(self.y or 0.0))
        return etree.Element(f"{{{SCENARIO_NS}}}{self.kind}", attributes)


def _children(el: etree._Element) -> list[etree._Element]:
    return [c for c in el if is_element(c)]


def _child(root: etree._Element, name: str) -> etree._Element | None:
    return next((c for c in _children(root) if local_name(c) == name), None)


def _tick(el: etree._Element, hz: int) -> int:
    return round(float(el.get("at", "0")) * hz)


class Base:
    """The scenario a session plays: its XML (every path in it absolute), its name, its
    physics rate, and the files it names."""

    def __init__(self, root: etree._Element, name: str, rate: int,
                 inputs: Iterable[tuple[str, Path]], note: str) -> None:
        self.root = root
        self.name = name
        self.rate = rate
        self.inputs = tuple(inputs)
        """The files the session reads, each with what it is (``("the map", path)``): a
        save never goes over one (:func:`prima.output.check_target`)."""
        self.note = note
        """What the saved scenario is, said in a comment at its head."""

    def text(self, until: float) -> str:
        """The base scenario's file, ending at ``until`` (s)."""
        root = copy.deepcopy(self.root)
        root.set("until", number(until))
        return _document(root, self.note)

    def saved(self, added: Sequence[Added], until_tick: int, folder: Path | None) -> str:
        """The session as a scenario: the base with ``added`` at their ticks, ending at
        ``until_tick``; its paths relative to ``folder`` (absolute without one)."""
        hz = self.rate
        root = copy.deepcopy(self.root)
        root.set("until", number(until_tick / hz))
        user = _child(root, "user")
        if user is None:  # (a base always has its user: for_apps, from_scenario)
            raise PrimaError("the session has no user to save")
        own = [c for c in _children(user) if local_name(c) in USER_TIMED]
        for el in own:
            user.remove(el)
        mine = [a for a in added if a.kind != "message"]
        for el in _merged(own, mine, hz, until_tick):
            user.append(el)
        scheduled = [c for c in _children(root) if local_name(c) in SCHEDULED]
        for el in scheduled:
            root.remove(el)
        after = user
        for el in _merged(scheduled, [a for a in added if a.kind == "message"], hz, until_tick):
            after.addnext(el)
            after = el
        if folder is not None:  # (the base's paths are absolute: read from anywhere)
            repath(root, Path("/"), folder)
        return _document(root, self.note.replace("SAVED", f"saved at {number(until_tick / hz)} s"))


def _merged(own: list[etree._Element], added: Sequence[Added], hz: int,
            until_tick: int) -> list[etree._Element]:
    """The script's own timed elements and the added inputs, in the order the simulator
    plays them: by tick, the script's own first within a tick, then the added ones as
    they were played; those at or after the end left out (they never happen)."""
    both = [(_tick(el, hz), 0, k, el) for k, el in enumerate(own)]
    both += [(a.tick, 1, k, a.element(hz)) for k, a in enumerate(added)]
    return [el for tick, _mine, _k, el in sorted(both, key=lambda e: e[:3]) if tick < until_tick]


def _document(root: etree._Element, note: str) -> str:
    etree.indent(root, space="  ")
    body = etree.tostring(root, encoding="unicode")
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<!-- {note} -->\n{body}\n'


def _comment(text: str) -> str:
    return text.replace("--", "- -")  # (no '--' inside a comment)


def from_scenario(path: Path, switches: Switches, *, seed: int | None, script: bool,
                  user_at: tuple[float, float, float] | None = None) -> Base:
    """The base of a session of the scenario ``path``: its map, robot, applications (the
    command line's switches written in), replies and zones, and with ``script`` its
    user's actions and answers and its timed inputs. A scenario without a user gets one
    at ``user_at`` (x, y, heading). Raises the scenario's located errors."""
    loaded = load_scenario(path)  # (its problems, located, before anything else)
    root = switched_root(path, switches)
    repath(root, path, None)
    if seed is not None:
        root.set("seed", str(seed))
    user = _child(root, "user")
    if not script:
        if user is not None:
            for el in _children(user):
                if local_name(el) in USER_TIMED or local_name(el) == "answer":
                    user.remove(el)
        for el in _children(root):
            if local_name(el) in SCHEDULED:
                root.remove(el)
    if user is None:
        x, y, heading = user_at or (loaded.robot.x + 1.0, loaded.robot.y, 180.0)
        user = etree.Element(f"{{{SCENARIO_NS}}}user", x=number(x), y=number(y),
                             heading=number(heading))
        last = [c for c in _children(root) if local_name(c) in ("robot", "policy")][-1]
        last.addnext(user)
    inputs = [("the scenario", path), *_named(root)]
    kept = "its user's script kept, " if script else ""
    note = _comment(f"prima live: a session of {path.name} ({kept}the user's actions as "
                    "they were played), SAVED; prima run replays it")
    return Base(root, f"{loaded.name}", loaded.rate, inputs, note)


_WHAT = {("map", "href"): "the map", ("apps", "fa"): "the FA", ("apps", "ea"): "an EA",
         ("ea", "href"): "an EA", ("robot", "profile"): "the robot profile",
         ("zone", "ea"): "a zone's EA"}
"""What each file a scenario names is, by element and attribute."""


def _named(root: etree._Element) -> list[tuple[str, Path]]:
    """The files a (base) scenario names, each with what it is: its paths are absolute."""
    out = []
    for el in root.iter():
        if not is_element(el):
            continue
        for (tag, attribute), what in _WHAT.items():
            value = el.get(attribute)
            if value and local_name(el) == tag:
                out.append((what, Path(value)))
    return out


def for_apps(documents: Sequence[tuple[Path, Document]], world: tuple[Path, WorldMap],
             robot: Path | None, seed: int | None,
             starts: tuple[str, float, tuple[float, float, float]],
             replies: Sequence[str]) -> Base:
    """The base of a session of applications alone: on the map ``world`` (one with every
    place they name), the robot at ``starts``' place and the user beside it, the FA and
    the EAs running from the start, a reply to each server they send to (``replies``:
    their names)."""
    map_path, plan = world
    fa = [p for p, d in documents if d.kind.value == "fa"]
    eas = [p for p, d in documents if d.kind.value == "ea"]
    place, heading, (ux, uy, facing) = starts
    apps = "".join(f" {role}={quoteattr(str(p.resolve()))}"
                   for role, p in (("fa", fa[0] if fa else None), ("ea", eas[0] if eas else None))
                   if p is not None)
    more = "".join(f"<ea href={quoteattr(str(p.resolve()))}/>" for p in eas[1:])
    profile = f" profile={quoteattr(str(robot.resolve()))}" if robot is not None else ""
    names = [d.name for _p, d in documents]
    text = (f'<scenario xmlns="{SCENARIO_NS}" name={quoteattr("live-" + "-".join(names))} '
            f'until="3600" seed="{seed or 0}">'
            f"<description>{markup('prima live: ' + ', '.join(names) + ' on ' + plan.name)}"
            f"</description><map href={quoteattr(str(map_path.resolve()))}/>"
            f"<apps{apps}>{more}</apps>"
            f'<robot place={quoteattr(place)} heading="{number(heading)}"{profile}/>'
            f'<user x="{number(ux)}" y="{number(uy)}" heading="{number(facing)}" speed="0.4"/>'
            + "".join(f"<reply to={quoteattr(to)} after=\"2\" text=\"OK: {{text}}\"/>"
                      for to in replies) + "</scenario>")
    root = etree.fromstring(text.encode("utf-8"))
    files = [("the map", map_path),
             *((f"the {d.kind.name}" if d.kind.value == "fa" else "an EA", p)
               for p, d in documents),
             *([("the robot profile", robot)] if robot else [])]
    note = _comment(f"prima live: a session of {', '.join(names)} on {plan.name} (the "
                    "user's actions as they were played), SAVED; prima run replays it")
    return Base(root, root.get("name", "live"), 50, files, note)


def user_spot(world: WorldMap, x: float, y: float, heading: float
              ) -> tuple[float, float, float]:
    """Where a user stands beside a robot at (x, y): :func:`prima.check.beside`, facing
    the robot."""
    from prima.check import beside

    ux, uy = beside(world, x, y, heading)
    return ux, uy, round(math.degrees(math.atan2(y - uy, x - ux)), 1)
