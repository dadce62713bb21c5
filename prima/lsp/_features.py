"""Completion, hover and go-to-definition, in offsets of a buffer: no protocol here.

Every text shown comes from where PRIMA already keeps it: a Command and its
arguments from the Command catalog (the robot profile's for the robot's own
Commands), an element or an attribute from its schema's documentation, an
event from the vocabulary's list of predefined events or the robot profile's
``doc``, a place from the map in force. :mod:`prima.lsp._server` turns these
answers into the protocol's messages.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from prima.catalog import CommandSpec, Param, ParamKind
from prima.dsl import CLOCK_FUNCTIONS, FUNCTIONS, STANDARD_GESTURES, element_name
from prima.lsp._chain import At, ChainContext, calls, context, labels, token_at
from prima.lsp._schemas import AttributeInfo, ElementInfo, element_info
from prima.lsp._workspace import Buffer, Place, Setting, Workspace
from prima.lsp._xml import Attr, Tag, Where, locate
from prima.shipped import packaged
from prima.vocab import PREDEFINED_EVENTS

__all__ = ["MAX_KEPT", "Features", "Hover", "Item", "Target", "event_fields"]

MAX_KEPT = 256
"""Most buffers whose index and setting are kept between requests."""

PXML = "urn:prima:pxml:1"
SCENARIO = "urn:prima:scenario:1"
ROBOT = "urn:prima:robot:1"
MAP = "urn:prima:map:1"

_DATA = re.compile(r"\(data: ([^)]*)\)")
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_WORD = re.compile(r"[\w\-.]*$")
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_EXPRESSIONS = frozenset({"cond", "expr"})
_TEMPLATES = {("send", "text"), ("log", "text")}
_PLACE_ATTRIBUTES = {("robot", "place"), ("user", "place"), ("walk", "to"), ("leave", "to")}
_FILES = {("map", "href"): ".xml", ("apps", "fa"): ".pxml", ("apps", "ea"): ".pxml",
          ("ea", "href"): ".pxml", ("zone", "ea"): ".pxml", ("robot", "profile"): ".xml"}
"""Attributes of a scenario that name a file, and the kind of file."""
_ANSWERS = {"on-answer": ("answer", "utterance"), "on-nomatch": ("utterance",)}


def event_fields(name: str) -> tuple[str, ...]:
    """The fields of a predefined event's data, as its description lists them."""
    found = _DATA.search(PREDEFINED_EVENTS.get(name, ""))
    return tuple(f.strip() for f in found.group(1).split(",")) if found else ()


@dataclass(frozen=True)
class Item:
    """A completion: ``insert`` (a snippet, if ``snippet``) replaces from ``start`` to
    the cursor."""

    label: str
    kind: str
    """``command``, ``argument``, ``value``, ``variable``, ``function``, ``field``,
    ``event``, ``state``, ``label``, ``place``, ``element``, ``attribute``, ``keyword``,
    ``file``."""
    start: int
    detail: str = ""
    doc: str = ""
    insert: str | None = None
    snippet: bool = False


@dataclass(frozen=True)
class Hover:
    text: str
    """Markdown."""
    start: int
    end: int


@dataclass(frozen=True)
class Target:
    path: Path
    start: int
    end: int


class _Index:
    """What a PXML buffer declares, read forgivingly (its Command ids on first need: they
    take reading every chain)."""

    def __init__(self, doc: _Doc) -> None:
        self._doc = doc
        self.states: dict[str, Attr] = {}
        self.variables: dict[str, Tag] = {}
        self.grammars: dict[str, Attr] = {}
        self.events: dict[str, Attr] = {}
        self.timers: dict[str, Attr] = {}
        root = doc.buffer.xml.root
        for tag in doc.buffer.xml.tags:
            if tag.name == "state":
                _first(self.states, tag.attr("id"))
            elif tag.name == "var" and tag.parent is root:
                name = tag.get("name")
                if name and name not in self.variables:
                    self.variables[name] = tag
            elif tag.name == "grammar":
                _first(self.grammars, tag.attr("id"))
            elif tag.name == "event" and tag.parent is root:
                _first(self.events, tag.attr("name"))
            elif tag.name == "timer":
                _first(self.timers, tag.attr("name"))

    @cached_property
    def labels(self) -> dict[str, tuple[int, int, str]]:
        """label -> where it is written (start, end) and its Command."""
        doc = self._doc
        found: dict[str, tuple[int, int, str]] = {}
        elements = {element_name(c.name): c.name for c in doc.setting.profile.catalog()}
        for tag in doc.buffer.xml.tags:
            if tag.name == "chain":
                start, text = tag.text(doc.source)
                commands = {label: name for name, _at, label in calls(text) if label}
                for label, at in labels(text):
                    found.setdefault(label, (start + at, start + at + len(label),
                                             commands.get(label, "")))
            if tag.parent is not None and tag.parent.name == "request":
                ident = tag.attr("id")
                command = tag.get("name") if tag.name == "command" else elements.get(tag.name, "")
                if ident is not None and ident.value_start >= 0:
                    found.setdefault(ident.value, (ident.value_start, ident.value_end, command))
        return found


class _Doc:
    """One request's view of a buffer: its text, its index, what is in force."""

    def __init__(self, workspace: Workspace, buffer: Buffer) -> None:
        self.workspace = workspace
        self.buffer = buffer
        self.generation = workspace.generation
        self.source = buffer.text
        self.namespace = buffer.namespace
        self._setting: Setting | None = None
        self._index: _Index | None = None

    @property
    def setting(self) -> Setting:
        if self._setting is None:
            self._setting = self.workspace.setting(self.buffer.path)
        return self._setting

    @property
    def catalog_specs(self) -> dict[str, CommandSpec]:
        """The Commands this document may use: an EA only the common ones."""
        catalog = self.setting.profile.catalog()
        ea = self.buffer.kind == "ea"
        return {c.name: c for c in catalog if not (ea and c.robot_specific)}

    @property
    def index(self) -> _Index:
        if self._index is None:
            self._index = self._build_index()
        return self._index

    def _build_index(self) -> _Index:
        return _Index(self)

    def element(self, tag: Tag) -> ElementInfo | None:
        return element_info(self.namespace, tag.path())

    def command_of(self, tag: Tag) -> CommandSpec | None:
        """The Command an element of a request is (or a ``<command name>``, ``<extra>``'s
        parent's)."""
        specs = self.setting.profile.catalog()
        if tag.name == "command":
            return specs.get(tag.get("name"))
        return next((c for c in specs if element_name(c.name) == tag.name
                     and not c.robot_specific), None)

    def handler(self, tag: Tag | None) -> Tag | None:
        """The handler an element is inside, if any."""
        while tag is not None and not tag.name.startswith("on"):
            tag = tag.parent
        return tag

    def events(self) -> dict[str, str]:
        """The events this document may handle, with what each is."""
        out = dict(PREDEFINED_EVENTS)
        if self.buffer.kind != "ea":
            docs = self.robot_event_docs()
            out.update({name: docs.get(name, "an event of the robot") + " (robot-specific)"
                        for name in self.setting.profile.events})
        out.update({name: "an event of this application's own" for name in self.index.events})
        out.update({name: "this application's timer" for name in self.index.timers})
        return out

    def robot_event_docs(self) -> dict[str, str]:
        path = self.profile_file()
        buffer = None if path is None else self.workspace.buffer(path)
        if buffer is None:
            return {}
        return {t.get("name"): t.get("doc") for t in buffer.xml.named("event") if t.get("doc")}

    def profile_file(self) -> Path | None:
        if self.setting.profile_path is not None:
            return self.setting.profile_path
        ref = packaged("prima.robots", "home-robot.xml")
        return ref if ref.is_file() else None

    def gestures(self) -> list[str]:
        names = list(self.setting.profile.gestures)
        return [g for g in names if g in STANDARD_GESTURES] if self.buffer.kind == "ea" \
            else names


def _first(into: dict[str, Attr], attr: Attr | None) -> None:
    if attr is not None and attr.value and attr.value_start >= 0:
        into.setdefault(attr.value, attr)


def _word_start(value: str, k: int) -> int:
    """Where the name (letters, digits, ``_ - .``) ending at index ``k`` begins."""
    found = _WORD.search(value[:k])
    return k - len(found.group()) if found else k


def _template_at(value: str, k: int) -> int | None:
    """In a text with ``{expression}`` parts: where the expression the index ``k`` is in
    begins, or None when ``k`` is in the literal text."""
    depth, start, i = 0, None, 0
    while i < k:
        if value.startswith(("{{", "}}"), i) and depth == 0:
            i += 2
            continue
        if value[i] == "{":
            depth += 1
            if depth == 1:
                start = i + 1
        elif value[i] == "}" and depth:
            depth -= 1
        i += 1
    return start if depth else None


def _quoted(name: str, in_string: bool) -> str:
    """A name as a chain writes it: bare if it can be, else quoted (``"kidode-room"``)."""
    return name if in_string or _NAME.match(name) else f'"{name}"'


def _signature_snippet(spec: CommandSpec) -> str:
    required = [p for p in spec.params if p.required]
    inner = ", ".join(f"${{{i}:{p.name}}}" for i, p in enumerate(required, 1))
    return f"{spec.name}({inner})"


def _place_doc(place: Place) -> str:
    what = "area" if place.area else f"{place.kind} at ({place.x}, {place.y})"
    return f"{what} on the map {place.file.name}"


class Features:
    """Completion, hover and definition over a workspace's buffers.

    What a buffer declares (its states, variables, labels...) and what is in force
    for it are worked out once per version of the buffer and generation of the
    workspace, and kept for the requests that follow.
    """

    def __init__(self, workspace: Workspace) -> None:
        self.workspace = workspace
        self._docs: dict[Path, _Doc] = {}

    def _doc(self, path: Path) -> _Doc | None:
        buffer = self.workspace.buffer(path)
        if buffer is None:
            return None
        kept = self._docs.get(path)
        if kept is not None and kept.buffer is buffer \
                and kept.generation == self.workspace.generation:
            return kept
        if len(self._docs) >= MAX_KEPT:
            self._docs.clear()
        made = self._docs[path] = _Doc(self.workspace, buffer)
        return made

    def drop(self, path: Path) -> None:
        """Forget what was worked out for ``path`` (closed)."""
        self._docs.pop(path, None)

    # ---------------------------------------------------------------- completion

    def complete(self, path: Path, offset: int) -> list[Item]:
        doc = self._doc(path)
        if doc is None:
            return []
        spot = locate(doc.buffer.xml, offset)
        tag = spot.tag
        if spot.where is Where.TAG_NAME and tag is not None:
            return self._elements(doc, tag.parent, tag.start + 1)
        if spot.where is Where.ATTR_NAME and tag is not None:
            start = spot.attr.name_start if spot.attr is not None else offset
            return self._attributes(doc, tag, start)
        if spot.where is Where.ATTR_VALUE and tag is not None and spot.attr is not None:
            return self._value(doc, tag, spot.attr, spot.index)
        if spot.where is Where.TEXT and tag is not None and tag.name == "chain" \
                and doc.namespace == PXML:
            start, text = tag.text(doc.source)
            if offset - start <= len(text):
                return self._chain(doc, tag, text, offset - start, start)
        return []

    def _elements(self, doc: _Doc, parent: Tag | None, start: int) -> list[Item]:
        if parent is None:
            root = {PXML: "pxml", ROBOT: "robot", SCENARIO: "scenario", MAP: "map"}
            return [Item(name, "element", start) for name in root.values()]
        info = doc.element(parent)
        if info is None:
            return []
        out = []
        for name in info.children:
            child = element_info(doc.namespace, [*parent.path(), name])
            out.append(Item(name, "element", start, doc=child.doc if child else ""))
        return out

    def _attributes(self, doc: _Doc, tag: Tag, start: int) -> list[Item]:
        info = doc.element(tag)
        if info is None:
            return []
        written = {a.name for a in tag.attrs}
        return [Item(a.name, "attribute", start, "required" if a.required else "", a.doc,
                     f'{a.name}="$1"', snippet=True)
                for a in info.attributes.values() if a.name not in written]

    def _value(self, doc: _Doc, tag: Tag, attr: Attr, k: int) -> list[Item]:
        value, base = attr.raw, attr.value_start
        start = base + _word_start(value, k)
        if doc.namespace == PXML:
            found = self._pxml_value(doc, tag, attr, k, start)
            if found is not None:
                return found
        elif doc.namespace == SCENARIO and (tag.name, attr.name) in _PLACE_ATTRIBUTES:
            return [Item(p.name, "place", start, p.kind, _place_doc(p))
                    for p in doc.setting.places if not p.area]
        elif doc.namespace == SCENARIO and (tag.name, attr.name) == ("zone", "area"):
            return [Item(p.name, "place", start, "area", _place_doc(p))
                    for p in doc.setting.places if p.area]
        elif doc.namespace == SCENARIO and (tag.name, attr.name) in _FILES:
            return self._files(doc, value[:k], base, _FILES[(tag.name, attr.name)])
        elif doc.namespace == MAP and tag.name == "edge":
            return [Item(t.get("name"), "place", start, t.get("kind", "point"))
                    for t in doc.buffer.xml.named("place") if t.get("name")]
        elif doc.namespace == ROBOT and attr.name in ("local", "over", "commands"):
            return [Item(c.name, "command", start, c.signature(), c.describe())
                    for c in doc.setting.profile.catalog()]
        info = doc.element(tag)
        known = None if info is None else info.attributes.get(attr.name)
        if known is None:
            return []
        return [Item(v, "value", base, known.name, known.doc) for v in known.values]

    def _pxml_value(self, doc: _Doc, tag: Tag, attr: Attr, k: int,
                    start: int) -> list[Item] | None:
        index, name, value = doc.index, attr.name, attr.raw
        if name in _EXPRESSIONS:
            return self._expression(doc, tag, value, k, attr.value_start, chain=False)
        spec = doc.command_of(tag) if tag.name != "command" or name != "name" else None
        param = spec.param(name) if spec is not None else None
        template = param is not None and param.kind in (ParamKind.TEXT, ParamKind.NUMBER) \
            or (tag.name, name) in _TEMPLATES or (tag.name, name) == ("timer", "after")
        if template or (param is not None and value.startswith("{")):
            inner = _template_at(value, k)
            if inner is None:
                return []
            return self._expression(doc, tag, value[inner:], k - inner,
                                    attr.value_start + inner, chain=False)
        if param is not None:
            return self._kind_values(doc, param, start, in_string=True)
        if (tag.name, name) == ("goto", "state"):
            return [Item(s, "state", start) for s in index.states]
        if (tag.name, name) in (("on", "event"), ("raise", "event")):
            events = doc.events() if tag.name == "on" else \
                {e: "an event of this application's own" for e in index.events}
            return [Item(e, "event", start, doc=d) for e, d in events.items()]
        if name == "of" and tag.name.startswith("on-"):
            specs = doc.setting.profile.catalog()
            return [Item(label, "label", start, command)
                    for label, (_s, _e, command) in index.labels.items()
                    if tag.name == "on-end" or (command in specs and specs[command].listens)]
        if (tag.name, name) in (("cancel-timer", "name"), ("timer", "name")):
            return [Item(t, "event", start, "timer") for t in index.timers]
        if (tag.name, name) == ("assign", "name"):
            return [Item(v, "variable", start) for v in index.variables]
        if (tag.name, name) == ("command", "name"):
            return [Item(c.name, "command", start, c.signature(), c.describe())
                    for c in doc.catalog_specs.values() if c.robot_specific]
        if (tag.name, name) in (("extra", "name"), ("arg", "name")) and tag.parent is not None:
            owner = doc.command_of(tag.parent)
            if owner is None:
                return []
            params = owner.params if name == "name" and tag.name == "arg" else \
                tuple(doc.setting.profile.extras.get(owner.name, {}).values())
            return [Item(p.name, "argument", start, p.kind.value, p.describe()) for p in params]
        if (tag.name, name) == ("block", "devices"):
            return [Item(d, "value", start, "device")
                    for d in sorted(doc.setting.profile.catalog().devices)]
        return None

    def _kind_values(self, doc: _Doc, param: Param, start: int, *,
                     in_string: bool) -> list[Item]:
        kind = param.kind
        if kind is ParamKind.PLACE:
            return [Item(p.name, "place", start, p.kind, _place_doc(p),
                         _quoted(p.name, in_string)) for p in doc.setting.places if not p.area]
        if kind is ParamKind.GESTURE:
            gestures = doc.setting.profile.gestures
            return [Item(g, "value", start, f"gesture, {gestures[g]:g} s", insert=_quoted(
                g, in_string)) for g in doc.gestures()]
        if kind is ParamKind.GRAMMAR:
            return [Item(g, "value", start, "grammar") for g in doc.index.grammars]
        if kind is ParamKind.VARIABLE:
            return [Item(v, "variable", start) for v in doc.index.variables]
        return []

    def _chain(self, doc: _Doc, tag: Tag, text: str, k: int, base: int) -> list[Item]:
        ctx = context(text, k)
        start = base + ctx.prefix_start
        specs = doc.catalog_specs
        if ctx.at is At.COMMAND:
            return [Item(c.name, "command", start, c.signature(), c.describe(),
                         _signature_snippet(c), snippet=True) for c in specs.values()]
        spec = specs.get(ctx.command or "")
        if ctx.at is At.EXTRA:
            extras = doc.setting.profile.extras.get(ctx.command or "", {})
            return [Item(p.name, "argument", start, p.kind.value, p.describe(), f"{p.name}=")
                    for p in extras.values() if p.name not in ctx.given]
        if ctx.at in (At.ARGUMENT, At.VALUE) and spec is not None:
            return self._arguments(doc, tag, spec, ctx, start)
        return self._expression_items(doc, tag, ctx, start)

    def _arguments(self, doc: _Doc, tag: Tag, spec: CommandSpec, ctx: ChainContext,
                   start: int) -> list[Item]:
        param = spec.param(ctx.name) if ctx.name else (
            spec.params[ctx.index] if ctx.index < len(spec.params) and not ctx.given else None)
        out: list[Item] = []
        if param is not None:
            out += self._kind_values(doc, param, start, in_string=ctx.in_string)
        if ctx.in_string:
            return out
        if ctx.at is At.ARGUMENT:
            out += [Item(f"{p.name}=", "argument", start, p.kind.value, p.describe())
                    for p in spec.params[ctx.index if not ctx.given else 0:]
                    if p.name not in ctx.given]
        if param is None or param.kind in (ParamKind.TEXT, ParamKind.NUMBER):
            out += self._expression_items(doc, tag, ctx, start)
        return out

    def _expression(self, doc: _Doc, tag: Tag, text: str, k: int, base: int, *,
                    chain: bool) -> list[Item]:
        ctx = context(text, k, chain=chain)
        return self._expression_items(doc, tag, ctx, base + ctx.prefix_start)

    def _expression_items(self, doc: _Doc, tag: Tag, ctx: ChainContext,
                          start: int) -> list[Item]:
        if ctx.in_string:
            return []
        if ctx.at is At.FIELD:
            return [Item(f, "field", start, event, doc_)
                    for f, event, doc_ in self._fields(doc, tag)]
        out = [Item(v, "variable", start, "variable", _var_doc(t, doc.source))
               for v, t in doc.index.variables.items()]
        out += [Item(name, "function", start, f"{name}()", info[-1], f"{name}($1)",
                     snippet=True) for name, info in FUNCTIONS.items()]
        out += [Item(name, "function", start, f"{name}()", info[-1], f"{name}()")
                for name, info in CLOCK_FUNCTIONS.items()]
        if doc.handler(tag) is not None:
            out.append(Item("event", "keyword", start, "the event being handled",
                            "Its name; event.FIELD is a field of its data."))
        out += [Item(w, "keyword", start) for w in ("true", "false", "null", "and", "or",
                                                    "not")]
        return out

    def _fields(self, doc: _Doc, tag: Tag) -> list[tuple[str, str, str]]:
        """The fields ``event.`` may name in the handler ``tag`` is inside."""
        handler = doc.handler(tag)
        if handler is None:
            return []
        if handler.name in _ANSWERS:
            return [(f, handler.name, "") for f in _ANSWERS[handler.name]]
        if handler.name != "on":
            return []
        name = handler.get("event")
        return [(f, name, PREDEFINED_EVENTS.get(name, "")) for f in event_fields(name)]

    def _files(self, doc: _Doc, typed: str, base: int, suffix: str) -> list[Item]:
        folder, _, _name = typed.rpartition("/")
        here = doc.buffer.path.parent / folder
        start = base + (len(folder) + 1 if folder else 0)
        try:
            entries = sorted(here.iterdir())[:500]
        except OSError:
            return []
        return [Item(e.name + ("/" if e.is_dir() else ""), "file", start)
                for e in entries if e.is_dir() or e.suffix == suffix]

    # ---------------------------------------------------------------- hover

    def hover(self, path: Path, offset: int) -> Hover | None:
        doc = self._doc(path)
        if doc is None:
            return None
        spot = locate(doc.buffer.xml, offset)
        tag = spot.tag
        if tag is None:
            return None
        if spot.where in (Where.TAG_NAME, Where.END_TAG_NAME):
            info = doc.element(tag)
            if info is None or not info.doc:
                return None
            return Hover(_element_markdown(info), tag.name_start, tag.name_end)
        if spot.where is Where.ATTR_NAME and spot.attr is not None:
            info = doc.element(tag)
            known = None if info is None else info.attributes.get(spot.attr.name)
            if known is None:
                return None
            return Hover(_attribute_markdown(tag.name, known), spot.attr.name_start,
                         spot.attr.name_end)
        if spot.where is Where.ATTR_VALUE and spot.attr is not None:
            return self._value_hover(doc, tag, spot.attr, spot.index)
        if spot.where is Where.TEXT and tag.name == "chain" and doc.namespace == PXML:
            start, text = tag.text(doc.source)
            if offset - start <= len(text):
                return self._chain_hover(doc, tag, text, offset - start, start)
        return None

    def _value_hover(self, doc: _Doc, tag: Tag, attr: Attr, k: int) -> Hover | None:
        value = attr.value
        at, end = attr.value_start, attr.value_end
        if doc.namespace == PXML and attr.name in ("event",) and value in doc.events():
            return Hover(f"**event {value}**\n\n{doc.events()[value]}", at, end)
        if doc.namespace == PXML and (tag.name, attr.name) == ("command", "name"):
            spec = doc.setting.profile.catalog().get(value)
            return None if spec is None else Hover(_command_markdown(spec), at, end)
        place = self._place_named(doc, tag, attr)
        if place is not None:
            return Hover(f"**{place.name}**: {_place_doc(place)}", at, end)
        if doc.namespace == PXML and (attr.name in _EXPRESSIONS or "{" in attr.raw):
            return self._name_hover(doc, tag, attr.raw, k, at)
        return None

    def _place_named(self, doc: _Doc, tag: Tag, attr: Attr) -> Place | None:
        """The map's place an attribute's value names, if it names one."""
        names = {p.name: p for p in doc.setting.places}
        if doc.namespace == PXML:
            spec = doc.command_of(tag)
            param = None if spec is None else spec.param(attr.name)
            if param is None or param.kind is not ParamKind.PLACE:
                return None
        elif doc.namespace == SCENARIO:
            if (tag.name, attr.name) not in _PLACE_ATTRIBUTES | {("zone", "area")}:
                return None
        else:
            return None
        return names.get(attr.value)

    def _name_hover(self, doc: _Doc, tag: Tag, text: str, k: int, base: int) -> Hover | None:
        """A variable, a function or an event's field under index ``k`` of an expression."""
        for m in _IDENT.finditer(text):
            if m.start() <= k <= m.end():
                name = m.group()
                before = text[:m.start()].rstrip()
                at, end = base + m.start(), base + m.end()
                if before.endswith("event."):
                    fields = {f: (e, d) for f, e, d in self._fields(doc, tag)}
                    if name in fields:
                        event, what = fields[name]
                        return Hover(f"**event.{name}**: a field of {event}"
                                     + (f"\n\n{what}" if what else ""), at, end)
                    return None
                if name in doc.index.variables:
                    source = _var_doc(doc.index.variables[name], doc.source)
                    fence = _fence(source)
                    return Hover(f"**variable {name}**\n\n{fence}xml\n{source}\n{fence}",
                                 at, end)
                if name in FUNCTIONS:
                    return Hover(f"**{name}()**: {FUNCTIONS[name][-1]}", at, end)
                if name in CLOCK_FUNCTIONS:
                    return Hover(f"**{name}()**: {CLOCK_FUNCTIONS[name][-1]}", at, end)
                return None
        return None

    def _chain_hover(self, doc: _Doc, tag: Tag, text: str, k: int, base: int) -> Hover | None:
        tok, ctx = token_at(text, k)
        if tok is None:
            return None
        at, end = base + tok.start, base + tok.end
        specs = doc.setting.profile.catalog()
        after = text[tok.end:].lstrip()
        if tok.kind == "name" and ctx.at is At.COMMAND and after.startswith("("):
            spec = specs.get(tok.text)
            return None if spec is None else Hover(_command_markdown(spec), at, end)
        if tok.kind == "name" and ctx.at is At.COMMAND and after.startswith(":"):
            return Hover(f"**{tok.text}**: the id of the Command after it "
                         "(`<on-end of=\"...\">` names it)", at, end)
        spec = specs.get(ctx.command or "")
        if tok.kind == "name" and spec is not None and after.startswith("=") \
                and not after.startswith("==") and ctx.at in (At.ARGUMENT, At.VALUE):
            param = spec.param(tok.text)
            if param is not None:
                return Hover(f"**{spec.name}({param.name}=...)**: {param.describe()}", at, end)
        if ctx.at in (At.ARGUMENT, At.VALUE) and spec is not None:
            param = spec.param(ctx.name) if ctx.name else (
                spec.params[ctx.index] if ctx.index < len(spec.params) else None)
            if param is not None and param.kind is ParamKind.PLACE:
                name = tok.text.strip("\"'")
                place = next((p for p in doc.setting.places if p.name == name), None)
                if place is not None:
                    return Hover(f"**{place.name}**: {_place_doc(place)}", at, end)
        if tok.kind == "name":
            return self._name_hover(doc, tag, text, k, base)
        return None

    # ---------------------------------------------------------------- definition

    def definition(self, path: Path, offset: int) -> list[Target]:
        doc = self._doc(path)
        if doc is None:
            return []
        spot = locate(doc.buffer.xml, offset)
        tag, attr = spot.tag, spot.attr
        if tag is None:
            return []
        if spot.where is Where.ATTR_VALUE and attr is not None:
            return self._value_definition(doc, tag, attr, spot.index)
        if spot.where is Where.TEXT and tag.name == "chain" and doc.namespace == PXML:
            start, text = tag.text(doc.source)
            tok, ctx = token_at(text, offset - start)
            if tok is None:
                return []
            return self._chain_definition(doc, tok.text, ctx)
        return []

    def _value_definition(self, doc: _Doc, tag: Tag, attr: Attr, k: int) -> list[Target]:
        here = doc.buffer.path
        index = doc.index if doc.namespace == PXML else None
        value = attr.value
        if doc.namespace == SCENARIO and (tag.name, attr.name) in _FILES:
            target = here.parent / value
            return [Target(target.resolve(), 0, 0)] if target.is_file() else []
        place = self._place_named(doc, tag, attr)
        if place is not None:
            return [Target(place.file, place.offset, place.offset + len(place.name))]
        if index is None:
            return []
        found: Attr | None = None
        if (tag.name, attr.name) == ("goto", "state"):
            found = index.states.get(value)
        elif attr.name == "of" and value in index.labels:
            start, end, _command = index.labels[value]
            return [Target(here, start, end)]
        elif (tag.name, attr.name) in (("on", "event"), ("cancel-timer", "name"),
                                       ("raise", "event")):
            found = index.timers.get(value) or index.events.get(value)
        elif (tag.name, attr.name) in (("assign", "name"), ("qa", "into")):
            return self._variable(doc, value)
        elif (tag.name, attr.name) == ("qa", "grammar"):
            found = index.grammars.get(value)
        elif attr.name in _EXPRESSIONS or "{" in attr.raw:
            for m in _IDENT.finditer(attr.raw):
                if m.start() <= k <= m.end() and not attr.raw[:m.start()].rstrip() \
                        .endswith("."):
                    return self._variable(doc, m.group())
        if found is None:
            return []
        return [Target(here, found.value_start, found.value_end)]

    def _variable(self, doc: _Doc, name: str) -> list[Target]:
        tag = doc.index.variables.get(name)
        attr = None if tag is None else tag.attr("name")
        if attr is None:
            return []
        return [Target(doc.buffer.path, attr.value_start, attr.value_end)]

    def _chain_definition(self, doc: _Doc, name: str, ctx: ChainContext) -> list[Target]:
        bare = name.strip("\"'")
        spec = doc.setting.profile.catalog().get(ctx.command or "")
        if spec is not None and ctx.at in (At.ARGUMENT, At.VALUE):
            param = spec.param(ctx.name) if ctx.name else (
                spec.params[ctx.index] if ctx.index < len(spec.params) else None)
            if param is not None and param.kind is ParamKind.PLACE:
                place = next((p for p in doc.setting.places if p.name == bare), None)
                if place is not None:
                    return [Target(place.file, place.offset, place.offset + len(place.name))]
            if param is not None and param.kind is ParamKind.GRAMMAR:
                found = doc.index.grammars.get(bare)
                return [] if found is None else [
                    Target(doc.buffer.path, found.value_start, found.value_end)]
        if bare in doc.index.labels:
            start, end, _command = doc.index.labels[bare]
            return [Target(doc.buffer.path, start, end)]
        return self._variable(doc, bare)


def _var_doc(tag: Tag, source: str) -> str:
    return source[tag.start:tag.end]


def _fence(source: str) -> str:
    """A Markdown code fence that no line of ``source`` closes: more backticks than its
    longest run of them (a document's ```` ``` ```` line would end a fence of three, and
    what follows it would be read as Markdown: headings, links, remote images)."""
    longest = max((len(run) for run in re.findall("`+", source)), default=0)
    return "`" * max(3, longest + 1)


def _element_markdown(info: ElementInfo) -> str:
    lines = [f"**<{info.name}>**", "", info.doc]
    if info.attributes:
        lines += ["", "Attributes: " + ", ".join(
            f"`{a.name}`" + (" (required)" if a.required else "")
            for a in info.attributes.values())]
    return "\n".join(lines)


def _attribute_markdown(element: str, info: AttributeInfo) -> str:
    head = f"**{info.name}** of `<{element}>`"
    notes = []
    if info.required:
        notes.append("required")
    if info.default is not None:
        notes.append(f"default `{info.default}`")
    if info.values:
        notes.append("one of " + ", ".join(f"`{v}`" for v in info.values))
    return head + (f" ({'; '.join(notes)})" if notes else "") + f"\n\n{info.doc}"


def _command_markdown(spec: CommandSpec) -> str:
    lines = [f"**{spec.signature()}**", "", spec.describe()]
    if spec.params:
        lines += ["", *(f"- `{p.name}`: {p.describe()}" for p in spec.params)]
    return "\n".join(lines)
