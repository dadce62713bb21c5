"""Generated visits: a scenario for an EA beside an FA that neither author wrote.

A visit stages what a stranger's EA meets anywhere: the building's map (one that has
every place the EA can go to: :mod:`._places`), the robot at its entrance, and a visitor
who stands by it, follows it, answers both applications' questions from their own grammars,
touches the robot, walks away to the far end of the building and comes back; a
message from each sender the EA listens for, a server's reply to what either
application sends, a sound either one listens for, and words said of the visitor's
own accord to what either application hears at any time. Four visitors: a *willing* one
who answers every question at once, each time with the grammar's next choice (the
first, then the second, ..., then the last again), a *declining* one who goes
through the choices the other way round (the last first), a *hesitant* one who
first says something no grammar expects, then nothing, then answers as the willing
one, and a *silent* one who first says nothing, then something no grammar expects.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

from prima.dsl import Document, Grammar, Handler, HandlerKind, If, Request, Send
from prima.sim import WorldMap

__all__ = ["VISITS", "Visit", "beside", "listens", "questions", "sends", "starts",
           "visit_scenario"]

VISITS = ("willing", "declining", "hesitant", "silent")
"""The visitors a generated visit has, by name."""

NOMATCH = "Banana."
"""What the hesitant visitor first says: no grammar expects it."""

BACKCHANNEL = "Uh-huh."
"""What the hesitant visitor says of their own accord: a backchannel."""


@dataclass(frozen=True)
class Visit:
    """One generated visit: its visitor, and when things happen (s)."""

    visitor: str
    until: float = 180.0

    @property
    def name(self) -> str:
        return f"visit-{self.visitor}"


# ---------------------------------------------------------------------------- documents

def _actions(actions: Sequence[object]) -> Iterator[object]:
    for action in actions:
        yield action
        if isinstance(action, If):
            for _cond, branch in action.branches:
                yield from _actions(branch)
            yield from _actions(action.otherwise)


def handlers(document: Document) -> list[Handler]:
    """Every handler of a document: its document-scope ones, then each state's."""
    out = list(document.handlers)
    for state in document.states.values():
        out += state.handlers
    return out


def requests(document: Document) -> list[Request]:
    """Every request a document can make, in document order."""
    found: list[Request] = []
    lists = [document.handlers[i].actions for i in range(len(document.handlers))]
    for state in document.states.values():
        lists.append(state.entry)
        lists += [h.actions for h in state.handlers]
    for actions in lists:
        found += [a for a in _actions(actions) if isinstance(a, Request)]
    return sorted(found, key=lambda r: (r.loc.line, r.loc.col))


def sends(document: Document) -> list[Send]:
    lists = [h.actions for h in handlers(document)]
    lists += [s.entry for s in document.states.values()]
    return [a for actions in lists for a in _actions(actions) if isinstance(a, Send)]


_STRING = re.compile(r"'((?:[^'\\]|\\.)*)'|\"((?:[^\"\\]|\\.)*)\"")


def _literals(source: str) -> list[str]:
    return [a if a is not None else b for a, b in _STRING.findall(source)]


def _compared(source: str, field: str) -> list[str]:
    """The texts ``event.<field>`` is compared with in a condition (``==``)."""
    pattern = re.compile(rf"event\.{field}\s*==\s*(?:'([^']*)'|\"([^\"]*)\")")
    return [a or b for a, b in pattern.findall(source)]


def listens(document: Document, event: str, field: str) -> list[str]:
    """What ``event.<field>`` the document's handlers of ``event`` look for (a message's
    ``sender``, a sound's name), in document order; ``""`` when one takes any."""
    found: list[str] = []
    for h in handlers(document):
        if h.kind is not HandlerKind.EVENT or h.key != event:
            continue
        values = _compared(h.cond.source, field) if h.cond is not None else []
        for value in values or [""]:
            if value not in found:
                found.append(value)
    return found


def remarks(document: Document, visitor: str) -> list[str]:
    """What the visitor says of their own accord to what the document listens for at any
    time (its ``<on event="speech" match="G">`` handlers): for a handler that looks for
    some of G's answers (``event.answer == 'stop'``), one phrase of each; otherwise G's
    first choice (the declining visitor: its last). In document order, each once."""
    found: list[str] = []
    for h in handlers(document):
        if h.kind is not HandlerKind.EVENT or h.key != "speech" or h.match is None:
            continue
        grammar = document.grammars.get(h.match)
        if grammar is None:
            continue
        wanted = _compared(h.cond.source, "answer") if h.cond is not None else []
        choices = [c for c in grammar.choices if c.phrases
                   and (not wanted or c.value in wanted)]
        if not wanted:
            choices = choices[-1:] if visitor == "declining" else choices[:1]
        for choice in choices:
            said = " ".join(choice.phrases[0]).capitalize() + "."
            if said not in found:
                found.append(said)
    return found


def _hints(document: Document, sender: str) -> list[str]:
    """Texts a document's message handlers for ``sender`` look for in a message (other
    than the sender's name), in document order."""
    found: list[str] = []
    for h in handlers(document):
        if h.kind is HandlerKind.EVENT and h.key == "message" and h.cond is not None \
                and sender in _compared(h.cond.source, "sender"):
            found += [t for t in _literals(h.cond.source) if t != sender and t not in found]
    return found


# ---------------------------------------------------------------------------- answers

def prompt_text(source: str) -> str:
    """The longest literal part of a prompt as written (its quotes and ``{...}`` left out):
    what the visitor recognises the question by."""
    text = source.strip()
    if len(text) >= 2 and text[0] == text[-1] and text[0] in "'\"":
        text = text[1:-1].replace("\\'", "'").replace('\\"', '"')
    parts = re.split(r"\{[^}]*\}", text)
    return max((p.strip() for p in parts), key=len, default="")


def answers(grammar: Grammar, number: int = 3) -> list[str]:
    """What a visitor may say to a question of this grammar: one phrase per choice,
    then one per pattern (``*`` as a word, ``#`` as ``number``)."""
    out = [" ".join(choice.phrases[0]).capitalize() + "." for choice in grammar.choices
           if choice.phrases]
    for pattern in grammar.patterns:
        words = ["something" if i == "*" else str(number) if i == "#" else i
                 for i in pattern.items]
        out.append(" ".join(words).capitalize() + ".")
    return out


def questions(document: Document) -> list[tuple[str, list[str]]]:
    """Each Q&A of a document: what its prompt says, and the answers its grammar takes
    (a number a different one for each question, 3, 5, 7...: a visitor asked for a
    time to start and a time to end gives two)."""
    out: list[tuple[str, list[str]]] = []
    for request in requests(document):
        for call in request.calls:
            prompt = call.args.get("prompt")
            if call.command != "QA" or prompt is None:
                continue
            grammar = document.grammars.get(call.grammar or "")
            said = answers(grammar, 3 + 2 * (len(out) % 10)) if grammar is not None else []
            text = prompt_text(prompt.source)
            if text and said and all(text.lower() != t.lower() for t, _ in out):
                out.append((text, said))
    return out


# ---------------------------------------------------------------------------- the map

def _clear(world: WorldMap, x: float, y: float, fx: float, fy: float) -> bool:
    """Nothing of the map within 0.5 m of the way from (fx, fy) to (x, y), nor of (x, y)."""
    xs = [p[0] for p in world.outline()]
    ys = [p[1] for p in world.outline()]
    if xs and not (min(xs) + 0.5 <= x <= max(xs) - 0.5 and min(ys) + 0.5 <= y <= max(ys) - 0.5):
        return False
    for wall in world.walls:
        if _distance(wall.x1, wall.y1, wall.x2, wall.y2, x, y) < 0.5 or \
                _crosses((fx, fy), (x, y), (wall.x1, wall.y1), (wall.x2, wall.y2)):
            return False
    return True


def _distance(x1: float, y1: float, x2: float, y2: float, x: float, y: float) -> float:
    dx, dy = x2 - x1, y2 - y1
    length = dx * dx + dy * dy
    t = 0.0 if length == 0 else max(0.0, min(1.0, ((x - x1) * dx + (y - y1) * dy) / length))
    return math.hypot(x - (x1 + t * dx), y - (y1 + t * dy))


def _crosses(a: tuple[float, float], b: tuple[float, float], c: tuple[float, float],
             d: tuple[float, float]) -> bool:
    def side(p: tuple[float, float], q: tuple[float, float], r: tuple[float, float]) -> float:
        return (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])

    return (side(a, b, c) * side(a, b, d) < 0) and (side(c, d, a) * side(c, d, b) < 0)


def _start(world: WorldMap) -> tuple[str, float, float, float]:
    """Where the robot starts: the entrance (else the first place), facing as it faces."""
    place = next((p for p in world.places if p.kind.value == "entrance"), world.places[0])
    return place.name, place.x, place.y, place.facing or 0.0


def beside(world: WorldMap, x: float, y: float, heading: float) -> tuple[float, float]:
    """Where a visitor stands beside a robot at (x, y) heading ``heading``: 1 m from it,
    ahead of it if that is clear (else the first clear way round it)."""
    for turn in (0, 45, -45, 90, -90, 135, -135, 180):
        a = math.radians(heading + turn)
        ux, uy = round(x + math.cos(a), 2), round(y + math.sin(a), 2)
        if _clear(world, ux, uy, x, y):
            return ux, uy
    return x + 0.5, y


# ---------------------------------------------------------------------------- the scenario

def _answer_rules(qs: list[tuple[str, list[str]]], visitor: str) -> list[str]:
    rules = []
    for text, choices in qs:
        contains = quoteattr(text)
        said = choices[::-1] if visitor == "declining" else choices
        first = 1
        if visitor in ("hesitant", "silent"):
            nomatch = f"say={quoteattr(NOMATCH)}"
            rules.append(f"    <answer contains={contains} nth=\"1\" "
                         f"{nomatch if visitor == 'hesitant' else ''}".rstrip() + "/>")
            rules.append(f"    <answer contains={contains} nth=\"2\" "
                         f"{nomatch if visitor == 'silent' else ''}".rstrip() + "/>")
            first = 3
        for k, words in enumerate(said[:-1]):
            rules.append(f"    <answer contains={contains} nth=\"{first + k}\" "
                         f"say={quoteattr(words)}/>")
        rules.append(f"    <answer contains={contains} say={quoteattr(said[-1])}/>")
    return rules


def _user_actions(visit: Visit, far: str, said: list[str]) -> list[str]:
    """The visitor's actions in time order: follow, touch, walk away to ``far``, come back,
    touch again; and their own words (``said``) from 115 s on, 12 s apart, up to 10 s
    before the end (on a robot that hears at any time, often over what it is saying: a
    barge-in). The hesitant visitor's only words are "Uh-huh." (a backchannel), the
    silent one says nothing."""
    actions = [(2.0, "follow", ' distance="1.2"'), (30.0, "touch", ""),
               (75.0, "leave", f" to={quoteattr(far)}"),
               (100.0, "follow", ' distance="1.2"'), (135.0, "touch", "")]
    if visit.visitor == "hesitant":
        said = [BACKCHANNEL]
    elif visit.visitor == "silent":
        said = []
    for k, words in enumerate(said):
        if 115.0 + 12.0 * k > 170.0:
            break
        actions.append((115.0 + 12.0 * k, "say", f" text={quoteattr(words)}"))
    actions.sort(key=lambda a: a[0])  # (stable: a touch before words said at its time)
    t = visit.until / 180.0  # (the times are for a visit of 180 s)
    return [f'    <{kind} at="{at * t:g}"{rest}/>' for at, kind, rest in actions]


def starts(world: WorldMap) -> tuple[str, float, tuple[float, float, float]]:
    """Where a visit on ``world`` begins: the robot's place and heading (the entrance,
    else the first place, facing as it faces), and the visitor's position and heading
    (1 m from the robot, ahead of it where that is clear, facing it)."""
    place, x, y, heading = _start(world)
    ux, uy = beside(world, x, y, heading)
    return place, heading, (ux, uy, round(math.degrees(math.atan2(y - uy, x - ux)), 1))


def visit_scenario(visit: Visit, ea: Document, fa: Document, world: tuple[Path, WorldMap],
                   paths: tuple[Path, Path]) -> str:
    """The visit's scenario file (its file names absolute: ``paths`` are the EA's and the
    FA's documents, ``world`` the map's path and the map)."""
    map_path, plan = world
    ea_path, fa_path = paths
    place, heading, (ux, uy, facing) = starts(plan)
    start = plan.place(place)
    x, y = (start.x, start.y) if start is not None else (0.0, 0.0)
    far = max(plan.places, key=lambda p: math.hypot(p.x - x, p.y - y))
    t = visit.until / 180.0  # (the times below are for a visit of 180 s)
    lines = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f"<!-- prima check: a generated visit ({visit.visitor} visitor) for {ea.name} "
        f"beside {fa.name} -->",
        f'<scenario xmlns="urn:prima:scenario:1" name="{visit.name}" '
        f'until="{visit.until:g}" seed="0">',
        f"  <map href={quoteattr(str(map_path.resolve()))}/>",
        f"  <apps fa={quoteattr(str(fa_path.resolve()))} ea={quoteattr(str(ea_path.resolve()))}/>",
        f'  <robot place="{place}" heading="{heading:g}"/>',
        f'  <user x="{ux:g}" y="{uy:g}" heading="{facing:g}" speed="0.4">',
        *_answer_rules(questions(ea) + questions(fa), visit.visitor),
        *_user_actions(visit, far.name, [r for doc in (ea, fa)
                                         for r in remarks(doc, visit.visitor)]),
        "  </user>",
    ]
    inputs: list[tuple[float, str, str]] = []  # (listed in time order, as a scenario must)
    for k, sender in enumerate(s for s in listens(ea, "message", "sender") if s):
        text = f"A message for the visitor from {sender}."
        inputs.append(((45 + 40 * k) * t, "message",
                       f"sender={quoteattr(sender)} text={quoteattr(text)}"))
    for k, sound in enumerate(s for doc in (ea, fa) for s in listens(doc, "sound-heard", "sound")):
        inputs.append(((60 + 50 * k) * t, "sound", f"name={quoteattr(sound or 'tune')}"))
    for at, kind, attributes in sorted(inputs, key=lambda i: i[0]):  # (stable at one time)
        lines.append(f'  <{kind} at="{at:g}" {attributes}/>')
    for doc in (ea, fa):
        for to in dict.fromkeys(s.to for s in sends(doc)):
            hints = _hints(doc, to) if doc is ea and visit.visitor == "willing" else []
            text = f"{hints[0]}: {{text}}" if hints else "OK: {text}"
            lines.append(f"  <reply to={quoteattr(to)} after=\"2\" text={quoteattr(text)}/>")
    lines.append("</scenario>")
    return "\n".join(lines) + "\n"
