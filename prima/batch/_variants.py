"""A scenario's jittered variants, and the bundle of files its runs need.

Run ``i`` of a sweep shifts the scenario's timings by offsets drawn from
``random.Random`` seeded with the sweep's seed and ``i`` (:func:`jitter`): the
same run is the same variant on any machine, in any worker, in any order. A
:class:`Bundle` carries a scenario and every file it names (map, applications,
robot profile, zone EAs) as bytes, its file names rewritten to the bundle's own,
so a worker on another machine runs exactly what this one would.
"""

from __future__ import annotations

import copy
import hashlib
import os
import random
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from lxml import etree

from prima.errors import Problem, ScenarioError, Severity
from prima.escape import shown_path
from prima.output import written
from prima.scenario import FILE_ATTRIBUTES, SCHEDULED, USER_TIMED
from prima.xmlio import is_element, local_name, parse_xml, read_source

if TYPE_CHECKING:
    from prima.run import Switches

__all__ = ["MIN_ANSWER_DELAY", "Bundle", "bundle_scenario", "number", "repath", "rng",
           "shift_timings", "switched_root", "write_variant"]

MIN_ANSWER_DELAY = 0.1
"""The shortest delay (s) an answer rule keeps after jitter."""



def number(value: float) -> str:
    """A time as the scenario writes it: to the millisecond, no trailing zeros."""
    text = f"{value:.3f}".rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def rng(seed: int, index: int) -> random.Random:
    """Run ``index``'s random offsets."""
    return random.Random(f"prima-sweep:{seed}:{index}")


def shift_timings(root: etree._Element, draws: random.Random, amount: float) -> None:
    """Jitter a scenario's timings in place: one draw per timed element, in document
    order; a shifted action is never earlier than the one before it."""
    user = next((c for c in root if is_element(c) and local_name(c) == "user"), None)
    last = 0.0
    for el in user if user is not None else ():
        if not is_element(el):
            continue
        if local_name(el) == "answer":
            given = float(el.get("after", "1.0"))
            after = given + draws.uniform(-amount, amount)
            # an early answer (over the prompt) stays early, a late one late
            el.set("after", number(max(after, MIN_ANSWER_DELAY) if given >= 0
                                   else min(after, -MIN_ANSWER_DELAY)))
        elif local_name(el) in USER_TIMED:
            last = max(last, float(el.get("at", "0")) + draws.uniform(-amount, amount))
            el.set("at", number(last))
    last = 0.0
    for el in root:
        if is_element(el) and local_name(el) in SCHEDULED:
            last = max(last, float(el.get("at", "0")) + draws.uniform(-amount, amount))
            el.set("at", number(last))


def _named(root: etree._Element) -> list[tuple[etree._Element, str]]:
    """Every (element, attribute) of a scenario that names a file, in document order."""
    apps = [c for c in root if is_element(c) and local_name(c) == "apps"]
    more = [c for a in apps for c in a if is_element(c) and local_name(c) == "ea"]
    found = []
    for el in [*root, *more]:
        if not is_element(el):
            continue
        for attribute in FILE_ATTRIBUTES.get(local_name(el), ()):
            if el.get(attribute) is not None:
                found.append((el, attribute))
    return found


def repath(root: etree._Element, source: Path, relative_to: Path | None) -> None:
    """The file paths of the scenario ``root`` (read from ``source``) made absolute, or
    relative to the folder ``relative_to``, in place."""
    for el, attribute in _named(root):
        target = (source.parent / str(el.get(attribute))).resolve()
        if relative_to is not None:
            el.set(attribute, Path(os.path.relpath(target, relative_to.resolve())).as_posix())
        else:
            el.set(attribute, str(target))


def _switch(root: etree._Element, switches: Switches) -> None:
    """Write the command line's switches into a scenario: its FA and EA, its robot's
    profile (absolute paths, made relative with the others), its policy switches."""
    ns = etree.QName(root).namespace
    children = [c for c in root if is_element(c)]
    named = {local_name(c): c for c in children}
    apps = named.get("apps")
    if apps is None and (switches.fa or switches.ea) and "map" in named:
        apps = etree.Element(f"{{{ns}}}apps" if ns else "apps")  # (a scenario without apps)
        named["map"].addnext(apps)
    if apps is not None:
        for attribute, value in (("fa", switches.fa), ("ea", switches.ea)):
            if value is not None:
                apps.set(attribute, str(Path(value).resolve()))
    robot = named.get("robot")
    if robot is not None and switches.robot is not None:
        robot.set("profile", str(Path(switches.robot).resolve()))
    if robot is not None and switches.policies:
        # Over the scenario's own switches, as the command line's are: a switch it names
        # again replaces the scenario's (a scenario switches each policy once), and `all`
        # replaces every one of them (it switches every policy first).
        switched = {name for name, _on in switches.policies}
        for c in children:
            if local_name(c) == "policy" and ("all" in switched or c.get("name") in switched):
                root.remove(c)
        after = robot
        for c in root:
            if is_element(c) and local_name(c) == "policy":
                after = c
        for name, on in switches.policies:
            policy = etree.Element(f"{{{ns}}}policy" if ns else "policy",
                                   name=name, state="on" if on else "off")
            after.addnext(policy)
            after = policy


def switched_root(scenario: Path, switches: Switches | None) -> etree._Element:
    """A copy of the scenario's root with the command line's switches written in (raises
    ScenarioError for a file that cannot be read as XML)."""
    doc = parse_xml(read_source(scenario, ScenarioError), str(scenario), ScenarioError)
    root = copy.deepcopy(doc.root.getroottree()).getroot()
    if switches:
        _switch(root, switches)
    return root


def write_variant(scenario: str | Path, path: str | Path, *, seed: int, index: int,
                  jitter: float, absolute: bool = False,
                  switches: Switches | None = None) -> Path:
    """Write run ``index`` of a sweep of ``scenario`` as a scenario file at ``path``
    (with ``switches``: the command line's FA, EA, robot and policies written in).

    Its file paths are relative to ``path``'s folder (or absolute, with ``absolute``),
    so ``prima run`` replays it exactly.
    """
    source, path = Path(scenario), Path(path)
    root = switched_root(source, switches)
    shift_timings(root, rng(seed, index), jitter)
    repath(root, source, None if absolute else path.parent)
    before = [etree.tostring(c, encoding="unicode") for c in root.itersiblings(preceding=True)]
    named = shown_path(source.name).replace("--", "- -")  # (no '--' inside a comment)
    note = (f"<!-- prima sweep: run {index} of {named} (seed {seed}, jitter "
            f"{number(jitter)} s): the user's actions, answer delays and scheduled inputs "
            "shifted -->")
    text = "\n".join(['<?xml version="1.0" encoding="UTF-8"?>', *reversed(before), note,
                      etree.tostring(root, encoding="unicode")])
    with written(path) as out:
        out.write(text + "\n")
    return path


# ---------------------------------------------------------------------------- bundles

@dataclass(frozen=True)
class Bundle:
    """A scenario and every file it names, as bytes: what a worker anywhere needs to run
    it. The scenario's file names are the bundle's own (``f0/museum.xml``), each file
    keeping its own name (a trace names documents by it)."""

    scenario: bytes
    """The scenario's XML, its file names rewritten, the switches written in."""
    files: tuple[tuple[str, bytes], ...]
    """Each file the scenario names: its name in the bundle, and its bytes."""

    @property
    def digest(self) -> str:
        """A hash of everything in the bundle (a worker keeps one copy of each)."""
        h = hashlib.sha256(self.scenario)
        for name, data in self.files:
            h.update(b"\0" + name.encode("utf-8") + b"\0")
            h.update(hashlib.sha256(data).digest())
        return h.hexdigest()

    def unpack(self, folder: Path) -> Path:
        """Write the bundle into ``folder``; the scenario file's path."""
        for name, data in self.files:
            target = folder / name
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        scenario = folder / "scenario.xml"
        scenario.write_bytes(self.scenario)
        return scenario


def bundle_scenario(scenario: str | Path, switches: Switches | None = None) -> Bundle:
    """The bundle of ``scenario`` (with the command line's switches written in). Raises
    ScenarioError for a scenario that cannot be read, or a file it names that cannot."""
    source = Path(scenario)
    root = switched_root(source, switches)
    names: dict[Path, str] = {}
    files: list[tuple[str, bytes]] = []
    for el, attribute in _named(root):
        value = str(el.get(attribute))
        target = (source.parent / value).resolve()
        name = names.get(target)
        if name is None:
            try:
                data = target.read_bytes()
            except OSError as exc:
                line = getattr(el, "sourceline", None)
                raise ScenarioError([Problem(
                    str(source), line if isinstance(line, int) else 1, 1, Severity.ERROR,
                    f"cannot read '{shown_path(value)}': {exc.strerror or exc}")]) from exc
            name = names[target] = f"f{len(names)}/{target.name}"
            files.append((name, data))
        el.set(attribute, name)
    return Bundle(etree.tostring(root, encoding="UTF-8", xml_declaration=True), tuple(files))
