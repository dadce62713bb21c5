"""Loading a PXML document: secure parse, then structure (XSD), then meaning.

:func:`check_document` returns every problem (errors and warnings);
:func:`load_document` returns a :class:`~prima.dsl.Document` or raises
:class:`~prima.errors.DocumentError`. Every problem is located at
``file:line:col``; inside an expression, at the character of the fault.
"""

from __future__ import annotations

import dataclasses
import re
from collections import deque
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from lxml import etree

from prima.record import Record
from prima.suggest import did_you_mean, similar
from prima.catalog import ParamKind
from prima.dsl._binder import Refs, Spot
from prima.dsl._commands import (
    bind_chain,
    bind_element,
    check_number,
    compile_attribute,
    element_name,
)
from prima.dsl._elements import elements, flag
from prima.dsl._kept import kept_now
from prima.dsl._expr import (
    MAX_CHAIN_COMMANDS,
    Compiled,
    compile_expression,
    compile_template,
    parse_chain,
)
from prima.dsl._model import (
    MAX_PATTERN_CAPTURES,
    MAX_PATTERN_ITEMS,
    MAX_PATTERNS,
    MAX_PHRASE_WORDS,
    Action,
    Assign,
    AtomicBlock,
    CancelTimer,
    Choice,
    CommandCall,
    Document,
    EventDecl,
    Goto,
    Grammar,
    Handler,
    HandlerKind,
    If,
    Loc,
    Log,
    Pattern,
    PlaceRef,
    Raise,
    Request,
    Send,
    StartTimer,
    State,
    StreamBlock,
    Variable,
    words,
)
from prima.dsl._profile import STANDARD_GESTURES, RobotProfile, default_profile
from prima.errors import DocumentError, ExpressionError, Problem, Severity
from prima.vocab import (
    MAX_BLOCK_WATCHDOG,
    MAX_NUMBER,
    MAX_STREAM_HOLD,
    EVENT_FIELDS,
    PREDEFINED_EVENTS,
    SPEECH_EVENT,
    AppKind,
    OnInterrupt,
    RunningOrder,
)
from prima.xmlio import (
    MAX_PROBLEMS,
    XmlDocument,
    is_element,
    limit,
    local_name,
    parse_xml,
    read_source,
    validate,
)

NAMESPACE = "urn:prima:pxml:1"
_NS = f"{{{NAMESPACE}}}"

MAX_CARET_LINE = 1_000
"""Longest source line shown under a problem with a caret (characters)."""

_ON_INTERRUPT = {m.value: m for m in OnInterrupt}
"""``interrupt`` values (the schema refuses others)."""


class Builder:
    """Walks a schema-valid document, compiling it and collecting problems."""

    def __init__(self, doc: XmlDocument, profile: RobotProfile) -> None:
        self.doc = doc
        self.profile = profile
        self.catalog = profile.catalog()
        self.element_commands = {element_name(c.name): c.name for c in self.catalog
                                 if not c.robot_specific}
        self.kind = AppKind(doc.root.get("kind", "fa"))
        self.max_text = profile.budgets[self.kind].text
        """Longest literal text (characters): the robot's budget, at most MAX_TEXT."""
        self.problems: list[Problem] = []
        self.refs = Refs()
        self.variable_names = dict.fromkeys(v.get("name", "") for v in self._top("var"))
        """Every declared variable, in document order."""
        self.variable_key = frozenset(self.variable_names)
        self.kept = kept_now()
        """Where chains and states are kept and replayed from, if anywhere."""
        self.labels: dict[str, CommandCall] = {}
        self.timers: dict[str, tuple[bool, Spot]] = {}
        self.states: dict[str, State] = {}
        self.streams: dict[str, StreamBlock] = {}
        self.blocks: dict[str, AtomicBlock] = {}
        self._state_elements: dict[str, etree._Element] = {}
        self._goto_elements: dict[Goto, etree._Element] = {}
        """Each <goto> read, by the action it became."""
        self.goto_log: list[tuple[Goto, etree._Element]] = []
        self.label_log: list[tuple[str, CommandCall, Spot]] = []
        self.timer_log: list[tuple[str, bool, Spot, Spot]] = []
        """Every <goto>, Command id and timer start, in the order read (states kept and
        replayed, :class:`KeptState`, replay them)."""
        self.in_handler = False
        self._carets: set[int] = set()
        self._hints = 0
        self._known: dict[str, str] = {}
        self.places: list[tuple[str, Spot, str, str]] = []
        """Places written by name as Command arguments: name, where, Command, argument."""

    # ------------------------------------------------------------ reporting

    def position(self, spot: Spot) -> tuple[int, int]:
        """The line and column ``spot`` points at."""
        el, where, index = spot
        if where is None:
            return self.doc.where.element(el)
        if where == "#text":
            return self.doc.where.text(el, index)
        return self.doc.where.attribute(el, where, index)

    def loc(self, spot: Spot) -> Loc:
        """Where ``spot`` points, as the model records it."""
        return Loc(*self.position(spot))

    def loc_of(self, el: etree._Element) -> Loc:
        """Where an element's start tag begins."""
        return self.loc((el, None, 0))

    def report(self, spot: Spot, message: str, severity: Severity, *, caret: bool = False) -> None:
        """A problem at ``spot``; with ``caret``, it will carry its source line too.

        The source line is added only to the problems reported (see :meth:`reported`):
        a long line copied into each of thousands of problems would cost quadratic time.
        """
        line, col = self.position(spot)
        problem = Problem(self.doc.name, line, col, severity, message)
        self.problems.append(problem)
        if caret:
            self._carets.add(id(problem))

    def reported(self) -> list[Problem]:
        """The problems in source order, at most MAX_PROBLEMS of them (then a line counting
        the rest); those inside an expression carry their source line, if it is not too long."""
        kept = limit(sorted(self.problems, key=lambda p: (p.line, p.col)), self.doc.name)
        return [dataclasses.replace(p, source=self.doc.where.line_text(p.line))
                if id(p) in self._carets and self.doc.where.line_length(p.line) <= MAX_CARET_LINE
                else p for p in kept]

    def fault(self, spot: Spot, fault: ExpressionError) -> None:
        """An expression's fault, located at its character in the expression written at ``spot``."""
        el, where, base = spot
        self.report((el, where, base + fault.index), fault.message, Severity.ERROR, caret=True)

    def error(self, spot: Spot, message: str) -> None:
        """An error at ``spot``: the document will not load."""
        self.report(spot, message, Severity.ERROR)

    def warning(self, spot: Spot, message: str) -> None:
        """A warning at ``spot``: the document loads, but probably does not do what is meant."""
        self.report(spot, message, Severity.WARNING)

    def compile(self, spot: Spot, make: Callable[[], Compiled]) -> Compiled | None:
        """Compile with ``make``; faults and references are located from ``spot``."""
        try:
            compiled = make()
        except ExpressionError as fault:
            self.fault(spot, fault)
            return None
        el, where, base = spot
        for name, index in compiled.names:
            self.refs.variables.append((name, (el, where, base + index)))
        fields = sorted(compiled.event_fields, key=lambda f: f[1]) if compiled.event_fields \
            else ()
        for name, index in fields:
            if name not in EVENT_FIELDS:
                self.warning((el, where, base + index),
                             f"event field '{name}' is not one PRIMA's events carry: it is "
                             "null unless a scenario's <event> sends it"
                             + (did_you_mean(name, sorted(EVENT_FIELDS))
                                or " (fields: docs/pxml.md)"))
        if compiled.event_uses and not self.in_handler:
            self.error((el, where, base + compiled.event_uses[0]),
                       "'event' is only available inside an event handler")
        return compiled

    def expression(self, el: etree._Element, attr: str) -> Compiled | None:
        """The expression written in attribute ``attr``, or None after a fault."""
        text = el.get(attr, "")
        return self.compile((el, attr, 0),
                            lambda: compile_expression(text, max_text=self.max_text))

    def template(self, el: etree._Element, attr: str) -> Compiled | None:
        """The text with ``{expression}`` parts written in attribute ``attr``, or None."""
        text = el.get(attr, "")
        return self.compile((el, attr, 0), lambda: compile_template(text, max_text=self.max_text))

    def known(self, what: str, names: Callable[[], Iterable[str]]) -> str:
        """``names``, sorted and joined, computed once per ``what``: an error message lists
        them, and a document may make that error many times."""
        if what not in self._known:
            self._known[what] = ", ".join(sorted(names()))
        return self._known[what]

    # ------------------------------------------------------------ references

    def check_gesture(self, name: str, spot: Spot) -> None:
        """A gesture must be one the robot knows; an EA may use only the common ones (and
        only those this robot offers: a profile should offer them all, but may not)."""
        if name not in self.profile.gestures:
            known = self.known("gestures", lambda: self.profile.gestures)
            common = " (a common gesture, but not one this robot offers; it knows: " \
                if name in STANDARD_GESTURES else " (this robot knows: "
            self.error(spot, f"unknown gesture '{name}'{common}{known})")
        elif name not in STANDARD_GESTURES and self.kind is AppKind.EA:
            self.error(spot, f"gesture '{name}' is robot-specific; only an FA may use it "
                             f"(common gestures: {', '.join(sorted(STANDARD_GESTURES))})")

    def literal_place(self, name: str, spot: Spot, command: str, param: str) -> None:
        """A place written by name as a Command's argument (the map checks it, if known)."""
        self.places.append((name, spot, command, param))

    def need_grammar(self, name: str, spot: Spot) -> None:
        """The document must declare this grammar (checked once all is read)."""
        self.refs.grammars.append((name, spot))

    def need_variable(self, name: str, spot: Spot) -> None:
        """The document must declare this variable (checked once all is read)."""
        self.refs.variables.append((name, spot))

    def add_label(self, label: str, call: CommandCall, spot: Spot) -> None:
        """Record a Command's id, which handlers refer to; ids are unique in a document."""
        self.label_log.append((label, call, spot))
        if label in self.labels:
            first = self.labels[label].loc
            self.error(spot, f"duplicate Command id '{label}' (first used at line {first.line})")
        else:
            self.labels[label] = call

    def _top(self, tag: str) -> list[etree._Element]:
        return [c for c in self.doc.root if is_element(c) and c.tag == _NS + tag]

    # ------------------------------------------------------------ the walk

    def build(self) -> Document | None:
        """The document, or None when it has errors (they are in :attr:`problems`)."""
        root = self.doc.root
        variables = self._variables()
        grammars = self._grammars()
        events = self._events()
        handlers: list[Handler] = []
        description = ""
        tops = elements(root)
        starts = [self.doc.where.offset(el) for el in tops]
        head = self.doc.where.source[:starts[0] or 0] if starts else ""
        for i, el in enumerate(tops):
            tag = local_name(el)
            if tag == "description":
                description = " ".join((el.text or "").split())
            elif tag.startswith("on"):
                handlers.append(self._handler(el))
            elif tag == "state" and starts[i] is not None and self.kept is not None:
                after = starts[i + 1] if i + 1 < len(starts) else None
                self._add_kept_state(el, head, self.doc.where.source[starts[i]:after])
            elif tag in ("state", "stream", "block"):
                self._state_group(el, None, None)
        self._check_references(events)
        initial = self._initial()
        self._check_gotos()
        self._check_entry_loops()
        self._check_reachable(handlers, initial)
        if any(p.severity is Severity.ERROR for p in self.problems):
            return None
        return Document(
            path=self.doc.name, kind=self.kind, name=root.get("name", ""),
            description=description, variables=variables, grammars=grammars, events=events,
            handlers=tuple(handlers), states=self.states, initial=initial or "",
            streams=self.streams, blocks=self.blocks, commands=dict(self.labels),
            timers=frozenset(self.timers),
            places=tuple(sorted((PlaceRef(name, self.loc(spot), command, param)
                                 for name, spot, command, param in self.places),
                                key=lambda p: (p.loc.line, p.loc.col))),
        )

    def _variables(self) -> dict[str, Variable]:
        out: dict[str, Variable] = {}
        for el in self._top("var"):
            name = el.get("name", "")
            if name in out:
                self.error((el, "name", 0), f"variable '{name}' is declared twice "
                                            f"(first at line {out[name].loc.line})")
                continue
            init = None
            if el.get("expr") is not None:
                before = len(self.refs.variables)
                init = self.expression(el, "expr")
                for used, spot in self.refs.variables[before:]:
                    if used not in out and used in self.variable_names:
                        self.error(spot, f"variable '{used}' is used before it is declared")
            out[name] = Variable(name, init, self.loc_of(el))
        return out

    def _grammars(self) -> dict[str, Grammar]:
        out: dict[str, Grammar] = {}
        for el in self._top("grammar"):
            gid = el.get("id", "")
            if gid in out:
                self.error((el, "id", 0), f"grammar '{gid}' is declared twice")
                continue
            choices: list[Choice] = []
            patterns: list[Pattern] = []
            for item in elements(el):
                if local_name(item) == "choice":
                    choice = self._choice(item)
                    if choice is not None:
                        choices.append(choice)
                elif len(patterns) == MAX_PATTERNS:
                    self.error((item, None, 0), f"a grammar may hold at most {MAX_PATTERNS} "
                                                "patterns")
                    break
                else:
                    pattern = self._pattern(item, item.text or "")
                    if pattern is not None:
                        patterns.append(pattern)
            out[gid] = Grammar(gid, tuple(choices), tuple(patterns), self.loc_of(el))
        return out

    def _choice(self, el: etree._Element) -> Choice | None:
        phrases = tuple(tuple(words(p)) for p in (el.text or "").split("|") if words(p))
        if not phrases:
            self.error((el, None, 0), "a choice needs at least one phrase "
                                      "(synonyms separated by '|')")
            return None
        if max(len(p) for p in phrases) > MAX_PHRASE_WORDS:
            self.error((el, None, 0), f"a synonym may have at most {MAX_PHRASE_WORDS} words")
            return None
        return Choice(el.get("value") or " ".join(phrases[0]), phrases)

    def _pattern(self, el: etree._Element, text: str) -> Pattern | None:
        tokens = text.split()
        if not tokens or len(tokens) > MAX_PATTERN_ITEMS:
            self.error((el, None, 0), f"a pattern needs 1 to {MAX_PATTERN_ITEMS} words, "
                                      "'*' or '#'")
            return None
        items = []
        for tok in tokens:
            if tok in ("*", "#"):
                items.append(tok)
                continue
            w = words(tok)
            if len(w) != 1:
                self.error((el, "#text", text.find(tok)),
                           f"pattern word {tok!r} must be one word (letters, digits, ')")
                return None
            items.append(w[0])
        if sum(t in ("*", "#") for t in tokens) > MAX_PATTERN_CAPTURES:
            self.error((el, None, 0), f"a pattern may capture at most {MAX_PATTERN_CAPTURES} "
                                      "times ('*' or '#')")
            return None
        return Pattern(text.strip(), tuple(items))

    def _events(self) -> dict[str, EventDecl]:
        out: dict[str, EventDecl] = {}
        for el in self._top("event"):
            name = el.get("name", "")
            spot: Spot = (el, "name", 0)
            if self.kind is AppKind.EA:
                self.error((el, None, 0), "only an FA may define its own events")
            elif name in PREDEFINED_EVENTS or name in self.profile.events:
                self.error(spot, f"'{name}' is already an event of the robot; pick another name")
            elif name in out:
                self.error(spot, f"event '{name}' is declared twice")
            out[name] = EventDecl(name, flag(el, "reactive"), self.loc_of(el))
        return out

    # ------------------------------------------------------------ states, streams, blocks

    def _state_group(self, el: etree._Element, stream: etree._Element | None,
                     block: etree._Element | None) -> list[str]:
        """The ids of the states ``el`` holds: a state, or a stream or block of them.

        ``stream`` and ``block`` are the stream and block ``el`` is inside, if any.
        """
        tag = local_name(el)
        if tag == "state":
            return [self._add_state(el, stream, block)]
        if tag == "stream":
            self._check_stream_nesting(el, stream, block)
            members = self._members(el, el, block)
            self._add_stream(el, members)
        else:
            self._check_block_nesting(el, block)
            members = self._members(el, stream, el)
            self._add_block(el, members)
        return members

    def _members(self, el: etree._Element, stream: etree._Element | None,
                 block: etree._Element | None) -> list[str]:
        return [sid for child in elements(el) for sid in self._state_group(child, stream, block)]

    def _add_kept_state(self, el: etree._Element, head: str, written: str) -> None:
        """A state written at the top level, built, or replayed from the same text
        written at the same place in the same setting (see :class:`KeptState`)."""
        kept = self.kept
        if kept is None or len(written) > MAX_KEPT_STATE:
            self._add_state(el, None, None)
            return
        line, col = self.position((el, None, 0))
        key = (written, line, col, head, self.kind, self.max_text, self.variable_key)
        found = kept.states.get(key)
        if isinstance(found, KeptState) and found.profile is self.profile:
            self._register_state(el, found.replay(self, el))
            return
        marks = _Marks.of(self)
        state = self._state(el, None, None)
        if len(self.problems) == marks.problems:
            made = KeptState.record(self, el, state, marks)
            if made is not None:
                kept.states.put(key, made, len(written))
        self._register_state(el, state)

    def _add_state(self, el: etree._Element, stream: etree._Element | None,
                   block: etree._Element | None) -> str:
        return self._register_state(el, self._state(el, stream, block))

    def _register_state(self, el: etree._Element, state: State) -> str:
        self._state_elements.setdefault(state.id, el)
        if state.id in self.states:
            self.error((el, "id", 0), f"duplicate state id '{state.id}' "
                                      f"(first at line {self.states[state.id].loc.line})")
        else:
            self.states[state.id] = state
        return state.id

    def _check_stream_nesting(self, el: etree._Element, stream: etree._Element | None,
                              block: etree._Element | None) -> None:
        if stream is not None:
            self.error((el, None, 0), "stream blocks cannot nest: this <stream> is inside "
                                      f"the <stream> at line {self.loc_of(stream).line}")
        if block is not None:
            self.error((el, None, 0), "a <stream> cannot be inside a <block>: the block is "
                                      "already one atomic behavior")

    def _check_block_nesting(self, el: etree._Element, block: etree._Element | None) -> None:
        if block is not None:
            self.error((el, None, 0), "blocks cannot nest: this <block> is inside the "
                                      f"<block> at line {self.loc_of(block).line}")
        for m in re.finditer(r"\S+", el.get("devices") or ""):
            if m.group() not in self.catalog.devices:
                known = self.known("devices", lambda: self.catalog.devices)
                self.error((el, "devices", m.start()),
                           f"unknown device '{m.group()}' (devices: {known})")

    def _add_stream(self, el: etree._Element, members: list[str]) -> None:
        gid = self._group_id(el)
        if gid in self.streams:
            self.error((el, "id", 0), f"duplicate stream id '{gid}'")
        hold = self._seconds(el, "hold", 10.0)
        if hold > MAX_STREAM_HOLD:
            self.warning((el, "hold", 0), f"PRIMA holds a stream for at most "
                                          f"{MAX_STREAM_HOLD:g} s; hold={hold:g} acts as "
                                          f"{MAX_STREAM_HOLD:g}")
        self.streams[gid] = StreamBlock(gid, hold, tuple(members), self.loc_of(el))

    def _add_block(self, el: etree._Element, members: list[str]) -> None:
        gid = self._group_id(el)
        if gid in self.blocks:
            self.error((el, "id", 0), f"duplicate block id '{gid}'")
        watchdog = self._seconds(el, "watchdog", 30.0)
        if watchdog > MAX_BLOCK_WATCHDOG:
            self.warning((el, "watchdog", 0), f"PRIMA ends a block after at most "
                                              f"{MAX_BLOCK_WATCHDOG:g} s; watchdog={watchdog:g} "
                                              f"acts as {MAX_BLOCK_WATCHDOG:g}")
        devices = el.get("devices")
        self.blocks[gid] = AtomicBlock(gid, watchdog,
                                       frozenset(devices.split()) if devices else None,
                                       tuple(members), self.loc_of(el))

    def _seconds(self, el: etree._Element, attr: str, default: float) -> float:
        """A positive duration (the schema's decimal), which must stay positive and finite as a
        float: a hold of 1 and 400 zeros is infinite, 0. and 400 zeros is 0."""
        raw = el.get(attr)
        value = default if raw is None else float(raw)
        if not 0 < value <= MAX_NUMBER:
            shown = raw if raw is None or len(raw) <= 20 else raw[:17] + "..."
            self.error((el, attr, 0), f"{attr}={shown!r} is not a usable number of seconds "
                                      "(it must be more than 0, and finite)")
            return default
        return value

    def _state(self, el: etree._Element, stream: etree._Element | None,
               block: etree._Element | None) -> State:
        entry: tuple[Action, ...] = ()
        handlers = []
        for child in elements(el):
            if local_name(child) == "entry":
                entry = self._actions(child)
            else:
                handlers.append(self._handler(child))
        return State(el.get("id", ""), flag(el, "initial"), entry, tuple(handlers),
                     self.loc_of(el),
                     stream=None if stream is None else self._group_id(stream),
                     block=None if block is None else self._group_id(block))

    def _group_id(self, el: etree._Element) -> str:
        """A stream's or block's id, or ``stream@LINE`` when it has none."""
        return el.get("id") or f"{local_name(el)}@{self.loc_of(el).line}"

    # ------------------------------------------------------------ handlers and actions

    def _handler(self, el: etree._Element) -> Handler:
        kind = HandlerKind(local_name(el))
        attr = "event" if kind is HandlerKind.EVENT else "of"
        key = el.get(attr, "")
        reactive = None if el.get("reactive") is None else flag(el, "reactive")
        self.refs.handlers.append((kind, key, (el, attr, 0), reactive))
        self.in_handler = True
        try:
            cond = self.expression(el, "cond") if el.get("cond") is not None else None
            actions = self._actions(el)
        finally:
            self.in_handler = False
        match = el.get("match") if kind is HandlerKind.EVENT else None
        if match is not None:
            if key != SPEECH_EVENT:
                self.error((el, "match", 0), 'match is an always-on grammar: it belongs on '
                                             f'<on event="{SPEECH_EVENT}">, not on '
                                             f'<on event="{key}">')
            self.refs.grammars.append((match, (el, "match", 0)))
        return Handler(kind, key, cond, reactive, actions, self.loc_of(el), match)

    def _actions(self, parent: etree._Element) -> tuple[Action, ...]:
        return self._sequence(elements(parent))

    def _sequence(self, actions: list[etree._Element]) -> tuple[Action, ...]:
        out: list[Action] = []
        goto: etree._Element | None = None
        warned = False
        for el in actions:
            if goto is not None and not warned:
                self.warning((el, None, 0), f"never runs: the <goto> at line "
                                            f"{self.loc_of(goto).line} leaves the state first")
                warned = True
            tag = local_name(el)
            action = self._action(el, tag)
            if action is not None:
                out.append(action)
            if goto is None and tag == "goto":
                goto = el
        return tuple(out)

    def _action(self, el: etree._Element, tag: str) -> Action | None:
        read = _ACTIONS.get(tag)
        if read is None:
            self.error((el, None, 0), f"<{tag}> is not an action")
            return None
        return read(self, el)

    def _request(self, el: etree._Element) -> Request | None:
        calls = self._request_calls(el)
        if calls is None:
            return None
        grouped = flag(el, "group")
        for call in calls if grouped else ():
            if self.catalog[call.command].feedback:
                self.error((el, "group", 0), f"a grouped request cannot hold the feedback "
                                             f"Command {call.command}: each of its loop "
                                             "iterations is an atomic behavior of its own")
                return None
        return Request(tuple(calls), RunningOrder(el.get("order", "after-latest")), grouped,
                       self.loc_of(el), face_user=flag(el, "face-user", default=True),
                       on_interrupt=_ON_INTERRUPT.get(el.get("interrupt") or "",
                                                      OnInterrupt.RESTART))

    def _request_calls(self, el: etree._Element) -> list[CommandCall] | None:
        """The Commands of a request or chain; None if one of them has an error."""
        if local_name(el) == "chain":
            text = el.text or ""
            try:
                steps = parse_chain(text)
            except ExpressionError as fault:
                self.fault((el, "#text", 0), fault)
                return None
            calls = bind_chain(self, el, text, steps)
        else:
            children = elements(el)
            if len(children) > MAX_CHAIN_COMMANDS:
                self.error((children[MAX_CHAIN_COMMANDS], None, 0),
                           f"a request may hold at most {MAX_CHAIN_COMMANDS} Commands")
                return None
            calls = [bind_element(self, child) for child in children]
        bound = [call for call in calls if call is not None]
        return bound if len(bound) == len(calls) else None

    def _assign(self, el: etree._Element) -> Assign | None:
        name = el.get("name", "")
        self.need_variable(name, (el, "name", 0))
        expr = self.expression(el, "expr")
        return Assign(name, expr, self.loc_of(el)) if expr else None

    def _if(self, el: etree._Element) -> If | None:
        """``<if cond>`` actions ``<elseif cond/>`` actions ``<else/>`` actions ``</if>``."""
        conds: list[Compiled | None] = [self.expression(el, "cond")]
        bodies: list[list[etree._Element]] = [[]]
        otherwise: list[etree._Element] | None = None
        for child in elements(el):
            tag = local_name(child)
            if tag == "elseif":
                conds.append(self.expression(child, "cond"))
                bodies.append([])
            elif tag == "else":
                otherwise = []
            else:
                (bodies[-1] if otherwise is None else otherwise).append(child)
        compiled = [self._sequence(body) for body in bodies]
        rest = self._sequence(otherwise or [])
        known = [c for c in conds if c is not None]
        if len(known) < len(conds):
            return None
        return If(tuple(zip(known, compiled, strict=True)), rest, self.loc_of(el))

    def _goto(self, el: etree._Element) -> Goto:
        self.refs.gotos.append((el.get("state", ""), (el, "state", 0)))
        goto = Goto(el.get("state", ""), self.loc_of(el))
        self._goto_elements[goto] = el
        self.goto_log.append((goto, el))
        return goto

    def _send(self, el: etree._Element) -> Send | None:
        text = self.template(el, "text")
        return Send(el.get("to", ""), text, self.loc_of(el)) if text else None

    def _raise(self, el: etree._Element) -> Raise:
        self.refs.raises.append((el.get("event", ""), (el, "event", 0)))
        return Raise(el.get("event", ""), self.loc_of(el))

    def _timer(self, el: etree._Element) -> StartTimer | None:
        name = el.get("name", "")
        reactive = flag(el, "reactive")
        if reactive and self.kind is AppKind.EA:
            self.error((el, "reactive", 0), "only an FA may mark its own events reactive")
        self.note_timer(name, reactive, (el, "reactive", 0), (el, "name", 0))
        after = compile_attribute(self, ParamKind.NUMBER, el, "after")
        if after is None or not check_number(self, after, (el, "after", 0), "after"):
            return None  # (a constant that is no number: the interpreter would refuse it)
        return StartTimer(name, after, reactive, self.loc_of(el))

    def note_timer(self, name: str, reactive: bool, flag_at: Spot, name_at: Spot) -> None:
        """A timer started: every start of one timer gives it the same reactive flag."""
        self.timer_log.append((name, reactive, flag_at, name_at))
        if name in self.timers and self.timers[name][0] != reactive:
            self.error(flag_at, f"timer '{name}' is started elsewhere with a "
                                "different reactive flag")
        self.timers.setdefault(name, (reactive, name_at))

    def _cancel_timer(self, el: etree._Element) -> CancelTimer:
        self.refs.cancels.append((el.get("name", ""), (el, "name", 0)))
        return CancelTimer(el.get("name", ""), self.loc_of(el))

    def _log(self, el: etree._Element) -> Log | None:
        text = self.template(el, "text")
        return Log(text, self.loc_of(el)) if text else None

    # ------------------------------------------------------------ checks

    def _check_references(self, events: dict[str, EventDecl]) -> None:
        """Names used before their declaration was known: variables, grammars, events, timers."""
        for name, spot in self.refs.variables:
            if name not in self.variable_names:
                self.error(spot, f"undefined variable '{name}'{self._hint('var', name)}")
        grammars = {g.get("id", "") for g in self._top("grammar")}
        for name, spot in self.refs.grammars:
            if name not in grammars:
                self.error(spot, f"undefined grammar '{name}'")
        for name, spot in self.refs.raises:
            if self.kind is AppKind.EA:
                self.error((spot[0], None, 0), "only an FA may raise its own events")
            elif name not in events:
                self.error(spot, f"undeclared event '{name}' "
                                 f"(declare it with <event name=\"{name}\"/>)")
        for name, spot in self.refs.cancels:
            if name not in self.timers:
                self.error(spot, f"no <timer name=\"{name}\"> is ever started")
        self._check_handlers(events)

    def _check_handlers(self, events: dict[str, EventDecl]) -> None:
        """What each handler listens to: an event, or a labelled Command's end or answer."""
        for kind, key, spot, reactive in self.refs.handlers:
            if kind is HandlerKind.EVENT:
                self._check_event(key, spot, reactive, events)
                continue
            call = self.labels.get(key)
            if call is None:
                self.error(spot, f"no Command has the id '{key}'")
            elif kind is not HandlerKind.END and not self.catalog[call.command].listens:
                self.error(spot, f"<{kind.value}> needs a Q&A, but '{key}' is a {call.command}")

    def _check_event(self, name: str, spot: Spot, reactive: bool | None,
                     events: dict[str, EventDecl]) -> None:
        if name in PREDEFINED_EVENTS:
            return
        if name in self.profile.events:
            if self.kind is AppKind.EA:
                self.error(spot, f"'{name}' is a robot-specific event; only an FA may use it")
            return
        if name in events:
            return
        if name in self.timers:
            if reactive and self.kind is AppKind.EA:
                self.error((spot[0], "reactive", 0), "only an FA may mark its own events reactive")
            return
        known = self.known("events", lambda: set(PREDEFINED_EVENTS) | set(events)
                           | set(self.timers)
                           | (set(self.profile.events) if self.kind is AppKind.FA else set()))
        self.error(spot, f"unknown event '{name}' (known: {known})")

    def _hint(self, what: str, name: str) -> str:
        close = self.similar(name, self.variable_names)
        if close is not None:
            return f"; did you mean '{close}'?"
        return f" (declare it with <{what} name=\"{name}\"/>)"

    def similar(self, name: str, names: Iterable[str]) -> str | None:
        """The first of ``names`` that ``name`` may be a misspelling of (one character
        added, dropped, changed, or two neighbours swapped; or the same but for case), if any.

        Looking for one costs a pass over ``names``: only for as many unknown names as a
        file reports, so that thousands of them stay linear.
        """
        self._hints += 1
        if self._hints > MAX_PROBLEMS:
            return None
        return similar(name, names)

    def _initial(self) -> str | None:
        initial = [s for s in self.states.values() if s.initial]
        if not self.states:
            self.error((self.doc.root, None, 0), "a document needs at least one <state>")
            return None
        if not initial:
            self.error((self.doc.root, None, 0),
                       'no initial state: mark one <state initial="true">')
            return None
        for extra in initial[1:]:
            self.error((self._state_elements[extra.id], "initial", 0),
                       f"more than one initial state ('{initial[0].id}' and '{extra.id}')")
        return initial[0].id

    def _check_gotos(self) -> None:
        for target, spot in self.refs.gotos:
            if target not in self.states:
                self.error(spot, f"no state has the id '{target}'"
                                 + did_you_mean(target, self.states))

    def _check_entry_loops(self) -> None:
        """States whose ``<entry>`` goes on to the next without a condition, round to the
        first, loop forever once entered (a run stops the application after 100 state
        changes): an error at the ``<goto>`` of each loop's first state. Each state is
        followed once: linear in the states."""
        passes: dict[str, Goto] = {}
        for state in self.states.values():
            goto = next((a for a in state.entry if isinstance(a, Goto)), None)
            if goto is not None and goto.state in self.states:
                passes[state.id] = goto
        order = {name: i for i, name in enumerate(self.states)}
        done: set[str] = set()
        for start in self.states:
            path: dict[str, None] = {}
            here = start
            while here in passes and here not in done and here not in path:
                path[here] = None
                here = passes[here].state
            if here in path:  # a loop not seen before: from ``here`` round to it
                names = list(path)
                loop = names[names.index(here):]
                first = min(loop, key=order.__getitem__)
                turn = loop.index(first)
                shown = " -> ".join(f"'{n}'" for n in [*loop[turn:], *loop[:turn], first])
                who = ("this state's <entry> goes to itself" if len(loop) == 1 else
                       "these states' <entry> go to one another")
                self.error((self._goto_elements[passes[first]], "state", 0),
                           f"{who} without a condition, forever once entered: {shown} "
                           "(put the <goto> under an <if>, or in a handler)")
            done.update(path)

    def _check_reachable(self, handlers: list[Handler], initial: str | None) -> None:
        if initial is None:
            return
        # document-scope handlers can go anywhere from any state: reachable from the initial one
        everywhere = _goto_targets(a for h in handlers for a in h.actions)
        seen = {initial}
        todo = deque([initial, *(t for t in everywhere if t in self.states and t != initial)])
        seen.update(todo)
        while todo:
            state = self.states[todo.popleft()]
            nexts = _goto_targets([*state.entry, *(a for h in state.handlers for a in h.actions)])
            for target in nexts & self.states.keys():
                if target not in seen:
                    seen.add(target)
                    todo.append(target)
        for state in self.states.values():
            if state.id not in seen:
                self.warning((self._state_elements[state.id], None, 0),
                             f"state '{state.id}' is unreachable from the initial state "
                             f"'{initial}'")


MAX_KEPT_STATE = 4096
"""Longest state (characters, from its ``<state`` to the next element at the top
level) whose building is kept (:func:`~prima.dsl._kept.keeping`)."""


class _Marks(NamedTuple):
    """How much the builder had collected before a state was read."""

    problems: int
    refs: tuple[int, ...]
    places: int
    labels: int
    timers: int
    gotos: int

    @classmethod
    def of(cls, b: Builder) -> _Marks:
        return cls(len(b.problems), tuple(len(getattr(b.refs, f)) for f in _REFS),
                   len(b.places), len(b.label_log), len(b.timer_log), len(b.goto_log))


_REFS = ("gotos", "variables", "grammars", "handlers", "raises", "cancels")
"""The lists of :class:`_Refs`, each of entries that end in a spot but ``handlers``'."""

Where = tuple[int, str | None, int]
"""A spot inside a kept state: (the element's index in the state's tree, where, index)."""


@dataclass(frozen=True, repr=False, eq=False)
class KeptState(Record):
    """A top-level state built without a problem, and what building it asked the builder
    to check later, its spots as indexes in the state's own tree. The same text written
    at the same line and column, in the same setting, is the same state: its model (every
    location the same) is used again, and what it asked is asked again for the new tree,
    where the checks that look across states (Command ids, timers' flags) run again."""

    profile: RobotProfile
    state: State
    refs: tuple[tuple[tuple[Any, ...], ...], ...]
    places: tuple[tuple[str, Where, str, str], ...]
    labels: tuple[tuple[str, CommandCall, Where], ...]
    timers: tuple[tuple[str, bool, Where, Where], ...]
    gotos: tuple[tuple[Goto, int], ...]

    @classmethod
    def record(cls, b: Builder, el: etree._Element, state: State,
               marks: _Marks) -> KeptState | None:
        index = {node: i for i, node in enumerate(el.iter())}

        def where(spot: Spot) -> Where:
            node, what, at = spot
            return index[node], what, at

        try:
            refs = []
            for name, mark in zip(_REFS, marks.refs, strict=True):
                entries = getattr(b.refs, name)[mark:]
                refs.append(tuple((k, key, where(spot), r) for k, key, spot, r in entries)
                            if name == "handlers" else
                            tuple((value, where(spot)) for value, spot in entries))
            return cls(
                b.profile, state, tuple(refs),
                tuple((n, where(spot), c, p) for n, spot, c, p in b.places[marks.places:]),
                tuple((label, call, where(spot))
                      for label, call, spot in b.label_log[marks.labels:]),
                tuple((n, r, where(f), where(a)) for n, r, f, a in b.timer_log[marks.timers:]),
                tuple((goto, index[node]) for goto, node in b.goto_log[marks.gotos:]))
        except KeyError:  # a spot outside the state's own tree: not kept
            return None

    def replay(self, b: Builder, el: etree._Element) -> State:
        nodes = list(el.iter())

        def spot(at: Where) -> Spot:
            return nodes[at[0]], at[1], at[2]

        for name, entries in zip(_REFS, self.refs, strict=True):
            into = getattr(b.refs, name)
            if name == "handlers":
                into.extend((k, key, spot(at), r) for k, key, at, r in entries)
            else:
                into.extend((value, spot(at)) for value, at in entries)
        b.places.extend((n, spot(at), c, p) for n, at, c, p in self.places)
        for label, call, at in self.labels:
            b.add_label(label, call, spot(at))
        for name, reactive, flag_at, name_at in self.timers:
            b.note_timer(name, reactive, spot(flag_at), spot(name_at))
        for goto, at_node in self.gotos:
            b._goto_elements[goto] = nodes[at_node]
            b.goto_log.append((goto, nodes[at_node]))
        return self.state


_ACTIONS: Mapping[str, Callable[[Builder, etree._Element], Action | None]] = {
    "request": Builder._request,
    "chain": Builder._request,
    "assign": Builder._assign,
    "if": Builder._if,
    "goto": Builder._goto,
    "send": Builder._send,
    "raise": Builder._raise,
    "timer": Builder._timer,
    "cancel-timer": Builder._cancel_timer,
    "log": Builder._log,
}
"""How each action element is read."""


def _goto_targets(actions: Iterable[Action]) -> set[str]:
    out: set[str] = set()
    for a in actions:
        if isinstance(a, Goto):
            out.add(a.state)
        elif isinstance(a, If):
            for _c, body in a.branches:
                out |= _goto_targets(body)
            out |= _goto_targets(a.otherwise)
    return out


# ---------------------------------------------------------------- entry points

def _hint_for(profile: RobotProfile) -> Callable[[etree._Element, str, str], str | None]:
    catalog = profile.catalog()
    kinds = {element_name(c.name): {p.name: p.kind for p in c.params} for c in catalog}

    def hint(el: etree._Element, attr: str, value: str) -> str | None:
        kind = kinds.get(local_name(el), {}).get(attr)
        if local_name(el) == "timer" and attr == "after":
            kind = ParamKind.NUMBER
        if kind is ParamKind.NUMBER:
            return "expected a number, or {expression}"
        if kind in (ParamKind.PLACE, ParamKind.GESTURE):
            return f"expected a bare {kind.value} name, or {{expression}}"
        if attr in ("cond", "expr"):
            return "expected an expression"
        return None

    return hint


def check_document(data: bytes, name: str,
                   profile: RobotProfile | None = None) -> tuple[Document | None, list[Problem]]:
    """Every problem of a document, and the document itself if it has no errors."""
    try:
        doc = parse_xml(data, name, DocumentError)
    except DocumentError as exc:
        return None, list(exc.problems)
    return check_parsed(doc, profile)


def check_parsed(doc: XmlDocument,
                 profile: RobotProfile | None = None) -> tuple[Document | None, list[Problem]]:
    """Like :func:`check_document`, for a document already parsed securely."""
    profile = profile or default_profile()
    problems = structure_problems(doc, profile)
    if problems:
        return None, problems
    builder = Builder(doc, profile)
    document = builder.build()
    return document, builder.reported()


def structure_problems(doc: XmlDocument,
                       profile: RobotProfile | None = None) -> list[Problem]:
    """What is wrong with a parsed document on any robot: a root that is not ``<pxml>``,
    or what the schema does not allow (``profile`` only words the hints). None of them:
    it is a PXML document, which may still use what a robot lacks."""
    if doc.root.tag != _NS + "pxml":
        return [doc.problem(doc.root, f'not a PXML document: the root must be <pxml xmlns='
                                      f'"{NAMESPACE}">, not <{local_name(doc.root)}>')]
    return validate(doc, "pxml.xsd", _hint_for(profile or default_profile()))


def load_document(path: str | Path, profile: RobotProfile | None = None) -> Document:
    """Load and check a PXML file; raise :class:`DocumentError` listing every error."""
    data = read_source(Path(path), DocumentError)
    document, problems = check_document(data, str(path), profile)
    if document is None:
        raise DocumentError(problems)
    return document
