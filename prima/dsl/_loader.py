"""Loading a PXML document: secure parse, then structure (XSD), then meaning.

:func:`check_document` returns every problem (errors and warnings);
:func:`load_document` returns a :class:`~prima.dsl.Document` or raises
:class:`~prima.errors.DocumentError`. Every problem is located at
``file:line:col``; inside an expression, at the character of the fault.
"""

from __future__ import annotations

import re
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Optional, Tuple

from lxml import etree

from prima.xmlio import validate
from prima.xmlio import XmlDocument, local_name, parse_xml, read_source
from prima.dsl._commands import bind_element, bind_step, compile_attribute, element_name
from prima.dsl._expr import Compiled, compile_expression, compile_template, parse_chain
from prima.dsl._model import (
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
from prima.catalog import ParamKind
from prima.vocab import MAX_BLOCK_WATCHDOG, MAX_STREAM_HOLD, PREDEFINED_EVENTS, AppKind, RunningOrder

NAMESPACE = "urn:prima:pxml:1"
_NS = f"{{{NAMESPACE}}}"

Spot = Tuple[etree._Element, Optional[str], int]
"""Where to point: (element, None | "#text" | attribute name, character index)."""



@dataclass
class _Refs:
    """References collected during the walk, checked once everything is known."""

    gotos: list[tuple[str, Spot]] = field(default_factory=list)
    variables: list[tuple[str, Spot]] = field(default_factory=list)
    grammars: list[tuple[str, Spot]] = field(default_factory=list)
    handlers: list[tuple[HandlerKind, str, Spot, bool | None]] = field(default_factory=list)
    raises: list[tuple[str, Spot]] = field(default_factory=list)
    cancels: list[tuple[str, Spot]] = field(default_factory=list)


class Builder:
    """Walks a schema-valid document, compiling it and collecting problems."""

    def __init__(self, doc: XmlDocument, profile: RobotProfile) -> None:
        self.doc = doc
        self.profile = profile
        self.catalog = profile.catalog()
        self.element_commands = {element_name(c.name): c.name for c in self.catalog
                                 if not c.robot_specific}
        self.kind = AppKind(doc.root.get("kind", "fa"))
        self.problems: list[Problem] = []
        self.refs = _Refs()
        self.variable_names = {v.get("name", "") for v in self._top("var")}
        self.labels: dict[str, CommandCall] = {}
        self.timers: dict[str, tuple[bool, Spot]] = {}
        self._state_elements: dict[str, etree._Element] = {}
        self.in_handler = False

    # ------------------------------------------------------------ reporting

    def position(self, spot: Spot) -> tuple[int, int]:
        el, where, index = spot
        if where is None:
            return self.doc.where.element(el)
        if where == "#text":
            return self.doc.where.text(el, index)
        return self.doc.where.attribute(el, where, index)

    def loc(self, spot: Spot) -> Loc:
        return Loc(*self.position(spot))

    def report(self, spot: Spot, message: str, severity: Severity, *, caret: bool = False) -> None:
        """A problem at ``spot``; with ``caret``, it carries its source line too."""
        line, col = self.position(spot)
        source = self.doc.where.line_text(line) if caret else ""
        self.problems.append(Problem(self.doc.name, line, col, severity, message, source))

    def fault(self, spot: Spot, fault: ExpressionError) -> None:
        """An expression's fault, located at its character in the expression written at ``spot``."""
        el, where, base = spot
        self.report((el, where, base + fault.index), fault.message, Severity.ERROR, caret=True)

    def error(self, spot: Spot, message: str) -> None:
        self.report(spot, message, Severity.ERROR)

    def warning(self, spot: Spot, message: str) -> None:
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
        if compiled.event_uses and not self.in_handler:
            self.error((el, where, base + compiled.event_uses[0]),
                       "'event' is only available inside an event handler")
        return compiled

    def expression(self, el: etree._Element, attr: str) -> Compiled | None:
        text = el.get(attr, "")
        return self.compile((el, attr, 0), lambda: compile_expression(text))

    def template(self, el: etree._Element, attr: str) -> Compiled | None:
        text = el.get(attr, "")
        return self.compile((el, attr, 0), lambda: compile_template(text))

    # ------------------------------------------------------------ references

    def check_gesture(self, name: str, spot: Spot) -> None:
        if name not in self.profile.gestures and name not in STANDARD_GESTURES:
            known = ", ".join(sorted(self.profile.gestures))
            self.error(spot, f"unknown gesture '{name}' (this robot knows: {known})")
        elif name not in STANDARD_GESTURES and self.kind is AppKind.EA:
            self.error(spot, f"gesture '{name}' is robot-specific; only an FA may use it "
                             f"(common gestures: {', '.join(sorted(STANDARD_GESTURES))})")

    def need_grammar(self, name: str, spot: Spot) -> None:
        self.refs.grammars.append((name, spot))

    def need_variable(self, name: str, spot: Spot) -> None:
        self.refs.variables.append((name, spot))

    def add_label(self, label: str, call: CommandCall, spot: Spot) -> None:
        if label in self.labels:
            first = self.labels[label].loc
            self.error(spot, f"duplicate Command id '{label}' (first used at line {first.line})")
        else:
            self.labels[label] = call

    def _top(self, tag: str) -> list[etree._Element]:
        return [c for c in self.doc.root if c.tag == _NS + tag]

    # ------------------------------------------------------------ the walk

    def build(self) -> Document | None:
        root = self.doc.root
        variables = self._variables()
        grammars = self._grammars()
        events = self._events()
        handlers: list[Handler] = []
        states: dict[str, State] = {}
        streams: dict[str, StreamBlock] = {}
        blocks: dict[str, AtomicBlock] = {}
        description = ""
        for el in root:
            if not isinstance(el.tag, str):
                continue
            tag = local_name(el)
            if tag == "description":
                description = " ".join((el.text or "").split())
            elif tag.startswith("on"):
                handlers.append(self._handler(el))
            elif tag in ("state", "stream", "block"):
                self._state_group(el, states, streams, blocks, None, None)
        self._check_references(events)
        initial = self._initial(states)
        self._check_reachable(states, handlers, initial)
        if any(p.severity is Severity.ERROR for p in self.problems):
            return None
        return Document(
            path=self.doc.name, kind=self.kind, name=root.get("name", ""),
            description=description, variables=variables, grammars=grammars, events=events,
            handlers=tuple(handlers), states=states, initial=initial or "",
            streams=streams, blocks=blocks, commands=dict(self.labels),
            timers=frozenset(self.timers),
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
            out[name] = Variable(name, init, self.loc((el, None, 0)))
        return out

    def _grammars(self) -> dict[str, Grammar]:
        out: dict[str, Grammar] = {}
        for el in self._top("grammar"):
            gid = el.get("id", "")
            if gid in out:
                self.error((el, "id", 0), f"grammar '{gid}' is declared twice")
                continue
            choices, patterns = [], []
            for item in el:
                if not isinstance(item.tag, str):
                    continue
                text = item.text or ""
                if local_name(item) == "choice":
                    phrases = tuple(tuple(words(p)) for p in text.split("|") if words(p))
                    if not phrases:
                        self.error((item, None, 0), "a choice needs at least one phrase "
                                                    "(synonyms separated by '|')")
                        continue
                    value = item.get("value") or " ".join(phrases[0])
                    choices.append(Choice(value, phrases))
                else:
                    pattern = self._pattern(item, text)
                    if pattern is not None:
                        patterns.append(pattern)
            out[gid] = Grammar(gid, tuple(choices), tuple(patterns), self.loc((el, None, 0)))
        return out

    def _pattern(self, el: etree._Element, text: str) -> Pattern | None:
        tokens = text.split()
        if not tokens or len(tokens) > 20:
            self.error((el, None, 0), "a pattern needs 1 to 20 words, '*' or '#'")
            return None
        parts = []
        for tok in tokens:
            if tok == "*":
                parts.append(r"(.*?)")
            elif tok == "#":
                parts.append(r"(-?[0-9]+(?:\.[0-9]+)?)")
            else:
                w = words(tok)
                if len(w) != 1:
                    self.error((el, "#text", text.find(tok)),
                               f"pattern word {tok!r} must be one word (letters, digits, ')")
                    return None
                parts.append(re.escape(w[0]))
        if sum(t in ("*", "#") for t in tokens) > 4:
            self.error((el, None, 0), "a pattern may capture at most 4 times ('*' or '#')")
            return None
        regex = re.compile(r"\s*" + r"\s*".join(parts) + r"\s*")
        return Pattern(text.strip(), regex)

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
            out[name] = EventDecl(name, el.get("reactive") in ("true", "1"), self.loc((el, None, 0)))
        return out

    def _state_group(self, el: etree._Element, states: dict[str, State],
                     streams: dict[str, StreamBlock], blocks: dict[str, AtomicBlock],
                     stream: etree._Element | None, block: etree._Element | None) -> list[str]:
        tag = local_name(el)
        if tag == "state":
            state = self._state(el, stream, block)
            self._state_elements.setdefault(state.id, el)
            if state.id in states:
                self.error((el, "id", 0), f"duplicate state id '{state.id}' "
                                          f"(first at line {states[state.id].loc.line})")
            else:
                states[state.id] = state
            return [state.id]
        if tag == "stream":
            if stream is not None:
                self.error((el, None, 0), "stream blocks cannot nest: this <stream> is inside "
                                          f"the <stream> at line {self.loc((stream, None, 0)).line}")
            if block is not None:
                self.error((el, None, 0), "a <stream> cannot be inside a <block>: the block is "
                                          "already one atomic behavior")
            inner_stream, inner_block = el, block
        else:
            if block is not None:
                self.error((el, None, 0), "blocks cannot nest: this <block> is inside the "
                                          f"<block> at line {self.loc((block, None, 0)).line}")
            inner_stream, inner_block = stream, el
            listed = el.get("devices") or ""
            for m in re.finditer(r"\S+", listed):
                dev = m.group()
                if dev not in self.catalog.devices:
                    self.error((el, "devices", m.start()), f"unknown device '{dev}' "
                                                   f"(devices: {', '.join(sorted(self.catalog.devices))})")
        gid = self._group_id(el)
        members: list[str] = []
        for child in el:
            if isinstance(child.tag, str):
                members += self._state_group(child, states, streams, blocks, inner_stream, inner_block)
        loc = self.loc((el, None, 0))
        table: dict = streams if tag == "stream" else blocks
        if gid in table:
            self.error((el, "id", 0), f"duplicate {tag} id '{gid}'")
        if tag == "stream":
            hold = float(el.get("hold", "10"))
            if hold > MAX_STREAM_HOLD:
                self.warning((el, "hold", 0), f"PRIMA holds a stream for at most "
                                              f"{MAX_STREAM_HOLD:g} s; hold={hold:g} acts as "
                                              f"{MAX_STREAM_HOLD:g}")
            streams[gid] = StreamBlock(gid, hold, tuple(members), loc)
        else:
            devices = el.get("devices")
            watchdog = float(el.get("watchdog", "30"))
            if watchdog > MAX_BLOCK_WATCHDOG:
                self.warning((el, "watchdog", 0), f"PRIMA ends a block after at most "
                                                  f"{MAX_BLOCK_WATCHDOG:g} s; watchdog={watchdog:g} "
                                                  f"acts as {MAX_BLOCK_WATCHDOG:g}")
            blocks[gid] = AtomicBlock(gid, watchdog,
                                      frozenset(devices.split()) if devices else None,
                                      tuple(members), loc)
        return members

    def _state(self, el: etree._Element, stream: etree._Element | None,
               block: etree._Element | None) -> State:
        entry: tuple[Action, ...] = ()
        handlers = []
        for child in el:
            if not isinstance(child.tag, str):
                continue
            if local_name(child) == "entry":
                entry = self._actions(child)
            else:
                handlers.append(self._handler(child))
        sid = el.get("id", "")
        return State(sid, el.get("initial") in ("true", "1"), entry, tuple(handlers),
                     self.loc((el, None, 0)),
                     stream=None if stream is None else self._group_id(stream),
                     block=None if block is None else self._group_id(block))

    def _group_id(self, el: etree._Element) -> str:
        """A stream's or block's id, or ``stream@LINE`` when it has none."""
        return el.get("id") or f"{local_name(el)}@{self.loc((el, None, 0)).line}"

    def _handler(self, el: etree._Element) -> Handler:
        kind = HandlerKind(local_name(el))
        key = el.get("event" if kind is HandlerKind.EVENT else "of", "")
        attr = "event" if kind is HandlerKind.EVENT else "of"
        reactive_attr = el.get("reactive")
        reactive = None if reactive_attr is None else reactive_attr in ("true", "1")
        self.refs.handlers.append((kind, key, (el, attr, 0), reactive))
        self.in_handler = True
        try:
            cond = self.expression(el, "cond") if el.get("cond") is not None else None
            actions = self._actions(el)
        finally:
            self.in_handler = False
        return Handler(kind, key, cond, reactive, actions, self.loc((el, None, 0)))

    def _actions(self, parent: etree._Element) -> tuple[Action, ...]:
        return self._sequence([c for c in parent if isinstance(c.tag, str)])

    def _sequence(self, elements: list[etree._Element]) -> tuple[Action, ...]:
        out: list[Action] = []
        goto: etree._Element | None = None
        warned = False
        for el in elements:
            if goto is not None and not warned:
                self.warning((el, None, 0), f"never runs: the <goto> at line "
                                            f"{self.loc((goto, None, 0)).line} leaves the state first")
                warned = True
            action = self._action(el)
            if action is not None:
                out.append(action)
            if goto is None and local_name(el) == "goto":
                goto = el
        return tuple(out)

    def _if(self, el: etree._Element) -> If | None:
        """``<if cond>`` actions ``<elseif cond/>`` actions ``<else/>`` actions ``</if>``."""
        conds: list[Compiled | None] = [self.expression(el, "cond")]
        bodies: list[list[etree._Element]] = [[]]
        otherwise: list[etree._Element] | None = None
        for child in (c for c in el if isinstance(c.tag, str)):
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
        if any(c is None for c in conds):
            return None
        return If(tuple(zip(conds, compiled)), rest, self.loc((el, None, 0)))  # type: ignore[arg-type]

    def _action(self, el: etree._Element) -> Action | None:
        tag = local_name(el)
        loc = self.loc((el, None, 0))
        if tag in ("request", "chain"):
            calls = self._request_calls(el)
            if calls is None:
                return None
            grouped = el.get("group") in ("true", "1")
            for call in calls if grouped else ():
                if self.catalog[call.command].feedback:
                    self.error((el, "group", 0), f"a grouped request cannot hold the feedback "
                                                 f"Command {call.command}: each of its loop "
                                                 "iterations is an atomic behavior of its own")
                    return None
            return Request(tuple(calls), RunningOrder(el.get("order", "after-latest")),
                           el.get("group") in ("true", "1"), loc)
        if tag == "assign":
            name = el.get("name", "")
            self.need_variable(name, (el, "name", 0))
            expr = self.expression(el, "expr")
            return Assign(name, expr, loc) if expr else None
        if tag == "if":
            return self._if(el)
        if tag == "goto":
            self.refs.gotos.append((el.get("state", ""), (el, "state", 0)))
            return Goto(el.get("state", ""), loc)
        if tag == "send":
            text = self.template(el, "text")
            return Send(el.get("to", ""), text, loc) if text else None
        if tag == "raise":
            self.refs.raises.append((el.get("event", ""), (el, "event", 0)))
            return Raise(el.get("event", ""), loc)
        if tag == "timer":
            name = el.get("name", "")
            reactive = el.get("reactive") in ("true", "1")
            if reactive and self.kind is AppKind.EA:
                self.error((el, "reactive", 0), "only an FA may mark its own events reactive")
            if name in self.timers and self.timers[name][0] != reactive:
                self.error((el, "reactive", 0), f"timer '{name}' is started elsewhere with a "
                                                "different reactive flag")
            self.timers.setdefault(name, (reactive, (el, "name", 0)))
            after = compile_attribute(self, ParamKind.NUMBER, el, "after")
            return StartTimer(name, after, reactive, loc) if after else None
        if tag == "cancel-timer":
            self.refs.cancels.append((el.get("name", ""), (el, "name", 0)))
            return CancelTimer(el.get("name", ""), loc)
        if tag == "log":
            text = self.template(el, "text")
            return Log(text, loc) if text else None
        self.error((el, None, 0), f"<{tag}> is not an action")
        return None

    def _request_calls(self, el: etree._Element) -> list[CommandCall] | None:
        calls: list[CommandCall] = []
        ok = True
        if local_name(el) == "chain":
            text = el.text or ""
            try:
                steps = parse_chain(text)
            except ExpressionError as fault:
                self.fault((el, "#text", 0), fault)
                return None
            for step in steps:
                call = bind_step(self, el, text, step)
                ok = ok and call is not None
                if call is not None:
                    calls.append(call)
        else:
            for child in el:
                if isinstance(child.tag, str):
                    call = bind_element(self, child)
                    ok = ok and call is not None
                    if call is not None:
                        calls.append(call)
        return calls if ok else None

    # ------------------------------------------------------------ checks

    def _check_references(self, events: dict[str, EventDecl]) -> None:
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
                self.error(spot, f"undeclared event '{name}' (declare it with <event name=\"{name}\"/>)")
        for name, spot in self.refs.cancels:
            if name not in self.timers:
                self.error(spot, f"no <timer name=\"{name}\"> is ever started")
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
        known = sorted(set(PREDEFINED_EVENTS) | set(events) | set(self.timers)
                       | (set(self.profile.events) if self.kind is AppKind.FA else set()))
        self.error(spot, f"unknown event '{name}' (known: {', '.join(known)})")

    def _hint(self, what: str, name: str) -> str:
        close = [v for v in self.variable_names if _similar(v, name)]
        return f"; did you mean '{close[0]}'?" if close else f" (declare it with <{what} name=\"{name}\"/>)"

    def _initial(self, states: dict[str, State]) -> str | None:
        initial = [s for s in states.values() if s.initial]
        if not states:
            self.error((self.doc.root, None, 0), "a document needs at least one <state>")
            return None
        if not initial:
            self.error((self.doc.root, None, 0), 'no initial state: mark one <state initial="true">')
            return None
        for extra in initial[1:]:
            self.error((self._state_elements[extra.id], "initial", 0), f"more than one initial state "
                                                f"('{initial[0].id}' and '{extra.id}')")
        return initial[0].id

    def _check_reachable(self, states: dict[str, State], handlers: list[Handler],
                         initial: str | None) -> None:
        for target, spot in self.refs.gotos:
            if target not in states:
                self.error(spot, f"no state has the id '{target}'")
        if initial is None:
            return
        everywhere = _goto_targets(a for h in handlers for a in h.actions)
        seen = {initial}
        todo = deque([initial])
        while todo:
            state = states[todo.popleft()]
            nexts = _goto_targets(list(state.entry) + [a for h in state.handlers for a in h.actions])
            for target in (nexts | everywhere) & states.keys():
                if target not in seen:
                    seen.add(target)
                    todo.append(target)
        for state in states.values():
            if state.id not in seen:
                self.warning((self._state_elements[state.id], None, 0),
                             f"state '{state.id}' is unreachable from the initial state "
                             f"'{initial}'")


def _goto_targets(actions) -> set[str]:  # type: ignore[no-untyped-def]
    out: set[str] = set()
    for a in actions:
        if isinstance(a, Goto):
            out.add(a.state)
        elif isinstance(a, If):
            for _c, body in a.branches:
                out |= _goto_targets(body)
            out |= _goto_targets(a.otherwise)
    return out


def _similar(a: str, b: str) -> bool:
    if a == b or abs(len(a) - len(b)) > 1:
        return False
    if len(a) == len(b):
        diffs = [i for i, (x, y) in enumerate(zip(a, b)) if x != y]
        swapped = len(diffs) == 2 and diffs[1] == diffs[0] + 1 and \
            a[diffs[0]] == b[diffs[1]] and a[diffs[1]] == b[diffs[0]]
        return len(diffs) == 1 or swapped
    short, long_ = sorted((a, b), key=len)
    return any(long_[:i] + long_[i + 1:] == short for i in range(len(long_)))


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
    if doc.root.tag != _NS + "pxml":
        return None, [doc.problem(doc.root, f"not a PXML document: the root must be "
                                            f'<pxml xmlns="{NAMESPACE}">, not <{local_name(doc.root)}>')]
    problems = validate(doc, "pxml.xsd", _hint_for(profile))
    if problems:
        return None, problems
    builder = Builder(doc, profile)
    document = builder.build()
    return document, sorted(builder.problems, key=lambda p: (p.line, p.col))


def load_document(path: str | Path, profile: RobotProfile | None = None) -> Document:
    """Load and check a PXML file; raise :class:`DocumentError` listing every error."""
    data = read_source(Path(path), DocumentError)
    document, problems = check_document(data, str(path), profile)
    if document is None:
        raise DocumentError(problems)
    return document
