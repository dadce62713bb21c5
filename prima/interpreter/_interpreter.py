"""Runs one PXML document: states, variables, handlers, timers, requests.

One :class:`Interpreter` per loaded application. It is the application's
:class:`~prima.mediator.interface.AppListener`: the mediator calls it with
events, end events and cancellations, and it answers by sending requests
through a :class:`MediatorPort`. Every event is handled to completion at
once (in no simulated time), so a request made while handling a Command's
end event always reaches the mediator promptly (docs/rules.md rule 6a).

A runtime error (a bad value, a goto loop) raises :class:`AppFailure` after
recording it; the run loop then unloads this application alone.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Final, NamedTuple, Protocol, get_args

from prima.catalog import Catalog, ParamKind
from prima.dsl import (
    STANDARD_GESTURES,
    Action,
    Assign,
    CancelTimer,
    CommandCall,
    Compiled,
    Document,
    Goto,
    Handler,
    HandlerKind,
    If,
    Loc,
    Log,
    Raise,
    Request,
    Scope,
    Send,
    StartTimer,
    State,
    to_text,
    truthy,
)
from prima.errors import AppFailure, ExecutionError, PrimaError
from prima.mediator import Call, Clock, CommandId, Event, Outcome
from prima.mediator import Request as MediatorRequest
from prima.vocab import (
    DEFAULT_BUDGETS,
    NEWS_EVENTS,
    PREDEFINED_EVENTS,
    SPEECH_EVENT,
    USER_ACTION_EVENTS,
    AppKind,
    Budgets,
    TraceKind,
    Value,
)

MAX_TRANSITIONS = 100
"""State changes allowed while handling one event (a goto loop is an error)."""
MAX_RAISED = 100
"""Own events allowed to pile up while handling one event."""
MAX_TIMERS_AT_ONCE = 100
"""Timer firings allowed at one simulated instant (a timer restarting itself with
``after="0"`` would otherwise never let time move on)."""


class MediatorPort(Protocol):
    """What an interpreter needs from the mediator."""

    def submit(self, request: MediatorRequest) -> tuple[CommandId, ...]: ...

    def open_stream(self, app: str, hold: float) -> None: ...

    def close_stream(self, app: str) -> None: ...

    def open_block(self, app: str, *, devices: frozenset[str] | None = None,
                   watchdog: float) -> None: ...

    def close_block(self, app: str) -> None: ...


_NO_DETAIL: Mapping[str, Value] = MappingProxyType({})


class Note(NamedTuple):
    """Something an interpreter tells the trace: a log line, a message sent, an error.

    A named tuple, not a frozen dataclass: one is made for every handler run and
    state entered, and a tuple is made five times faster."""

    time: float
    app: str
    kind: TraceKind
    """What it records: log, send, state, handler, timer, stream, block or error."""
    text: str
    detail: Mapping[str, Value] = _NO_DETAIL


def _handler_table(document: Document, state_id: str | None
                   ) -> dict[tuple[HandlerKind, str], tuple[Handler, ...]]:
    """The handlers active in a state, by (kind, key), in the order they are tried."""
    state = document.states.get(state_id or "")
    table: dict[tuple[HandlerKind, str], tuple[Handler, ...]] = {}
    for handler in (state.handlers if state else ()) + document.handlers:
        key = (handler.kind, handler.key)
        table[key] = (*table.get(key, ()), handler)
    return table


@dataclass(slots=True, init=False)
class _Handling:
    """What the current handling adds to requests (rules 5 and 6). (Its ``__init__`` is
    written out, as :class:`_Timer`'s: compiled, it runs at C speed, where the one
    ``dataclass`` writes runs as Python; one is made for every handler run.)"""

    reactive: bool = False
    follows: CommandId | None = None
    requested: bool = False
    user: bool = False
    """The event handled is the user's own action (docs/rules.md 7.1)."""

    def __init__(self, reactive: bool = False, follows: CommandId | None = None,
                 requested: bool = False, user: bool = False) -> None:
        self.reactive = reactive
        self.follows = follows
        self.requested = requested
        self.user = user


@dataclass(init=False)
class _Timer:
    due: float
    reactive: bool
    seq: int
    loc: Loc
    """The ``<timer>`` that started it."""

    def __init__(self, due: float, reactive: bool, seq: int, loc: Loc) -> None:
        self.due = due
        self.reactive = reactive
        self.seq = seq
        self.loc = loc


class Interpreter:
    """Runs one document against a mediator port."""

    def __init__(self, document: Document, app: str, port: MediatorPort, clock: Clock, *,
                 catalog: Catalog, robot_events: Mapping[str, bool] | None = None,
                 user_events: Collection[str] = (),
                 gestures: Collection[str] | None = None, budgets: Budgets | None = None,
                 note: Callable[[Note], None] | None = None,
                 send: Callable[[str, str, str], None] | None = None) -> None:
        self.document = document
        self.app = app
        self.port = port
        self.clock = clock
        self.catalog = catalog
        self.robot_events = dict(robot_events or {})
        self.user_events = frozenset(user_events) | USER_ACTION_EVENTS
        """The events that are the user's own action (a touch, always; and what the
        profile names): the reactions to them go first (docs/rules.md 7.1)."""
        self.gestures = frozenset(gestures) if gestures is not None else None
        """The robot's gestures (None: not checked here); an EA may use the common ones."""
        self.budgets = budgets or DEFAULT_BUDGETS[document.kind]
        self.last_request: Loc | None = None
        """Where the latest request was written (for failures found later)."""
        self._sent: deque[float] = deque()
        self._note = note or (lambda _n: None)
        self._send = send or (lambda _app, _to, _text: None)
        self.variables: dict[str, Value] = {}
        self.state: str | None = None
        self.stopped = False
        self._commands: dict[CommandId, CommandCall] = {}
        self._timers: dict[str, _Timer] = {}
        self._timer_seq = 0
        self._raised: list[str] = []
        self._handling = _Handling()
        self._fired_at, self._fired = -1.0, 0
        self._tables: dict[str | None, dict[tuple[HandlerKind, str], tuple[Handler, ...]]] = {}
        """Per state: its handlers and the document's, by kind and key (built when first asked)."""
        self._defaults: dict[str, tuple[tuple[str, Value], ...]] = {}
        """Per Command: the defaults a call that leaves an argument out gets (built when first
        asked: the catalog's parameters are looked through once, not at every call)."""

    # ------------------------------------------------------------ lifecycle

    def start(self) -> None:
        """Initialise the variables and enter the initial state."""
        self._guard(self._start)

    def _start(self) -> None:
        for var in self.document.variables.values():
            self.variables[var.name] = None if var.init is None else self._eval(var.init, var.loc)
        self._run_handling(_Handling(), lambda: self._transition(self.document.initial))

    def stop(self) -> None:
        """Stop handling anything (the application was unloaded)."""
        self.stopped = True
        self._timers.clear()

    # ------------------------------------------------------------ AppListener

    def event(self, event: Event) -> None:
        if self.stopped or not self._handlers(HandlerKind.EVENT, event.name):
            return  # most of the robot's events concern an application in few of its states
        data = {"name": event.name, **event.data}
        handlers = None
        if event.name == SPEECH_EVENT:  # the handlers whose always-on grammar took it
            handlers = self._listening(to_text(event.data.get("words")), data)
        self._guard(self._dispatch, HandlerKind.EVENT, event.name, data,
                    self._default_reactivity(event.name), None,
                    event.name in self.user_events or event.name == SPEECH_EVENT, handlers)

    def takes(self, words: str) -> bool:
        """Whether a ``<on event="speech">`` of the current state takes ``words``: its
        always-on grammar matches them, or it names none (it takes any words)."""
        if self.stopped:
            return False
        return bool(self._listening(words, {}))

    def answers(self, command_id: CommandId, words: str) -> bool | None:
        """Whether ``words`` answer the Q&A of ``command_id`` (its grammar takes them);
        None if that is no Q&A of this application's still under way."""
        call = self._commands.get(command_id)
        if self.stopped or call is None or not self.catalog[call.command].listens:
            return None
        return self.document.grammars[call.grammar or ""].match(words) is not None

    def _listening(self, words: str, data: dict[str, Value]) -> tuple[Handler, ...]:
        """The speech handlers that take ``words``, in the order they are tried; ``data``
        gets the first match's ``answer`` and ``grammar``."""
        out: list[Handler] = []
        for handler in self._handlers(HandlerKind.EVENT, SPEECH_EVENT):
            if handler.match is None:
                out.append(handler)
                continue
            answer = self.document.grammars[handler.match].match(words)
            if answer is not None:
                if "answer" not in data:
                    data["answer"], data["grammar"] = answer, handler.match
                out.append(handler)
        data.setdefault("answer", None)
        data.setdefault("grammar", None)
        return tuple(out)

    def command_ended(self, command_id: CommandId, outcome: Outcome) -> None:
        call = self._commands.pop(command_id, None)
        if self.stopped or call is None or call.label is None:
            return
        values = dict(outcome.values)
        if not self.catalog[call.command].listens:
            self._guard(lambda: self._dispatch(HandlerKind.END, call.label or "", values,
                                               False, command_id))
            return
        utterance = values.get("utterance")
        kind = HandlerKind.NOINPUT
        data: dict[str, Value] = {"name": kind._value_}
        if values.get("status") == "answered" and utterance is not None:
            grammar = self.document.grammars[call.grammar or ""]
            answer = grammar.match(to_text(utterance))
            kind = HandlerKind.NOMATCH if answer is None else HandlerKind.ANSWER
            data = {"name": kind._value_, "utterance": to_text(utterance), "answer": answer}
            if answer is not None and call.into:
                self.variables[call.into] = answer
        self._guard(lambda: self._dispatch(kind, call.label or "", data, False, command_id))

    def command_cancelled(self, command_id: CommandId) -> None:
        self._commands.pop(command_id, None)

    # ------------------------------------------------------------ timers

    def next_deadline(self) -> float | None:
        """When the next timer fires, if any."""
        if self.stopped or not self._timers:
            return None
        return min(t.due for t in self._timers.values())

    def advance(self) -> None:
        """Fire the timers due at the clock's time, oldest first.

        Only the timers due when this call begins fire; one restarted meanwhile
        fires on a later call. Too many firings at one instant is an error.
        """
        if not self._timers:
            return  # (asked at every report of the simulator: most often no timer runs)
        now = self.clock.now()
        due = sorted((t.due, t.seq, name) for name, t in self._timers.items() if t.due <= now)
        for _due, seq, name in due:
            timer = self._timers.get(name)
            if self.stopped or timer is None or timer.seq != seq:
                continue  # cancelled or restarted by an earlier handler
            del self._timers[name]
            if now != self._fired_at:
                self._fired_at, self._fired = now, 0
            self._fired += 1
            if self._fired > MAX_TIMERS_AT_ONCE:
                message = (f"{self._where(timer.loc)}more than {MAX_TIMERS_AT_ONCE} timers "
                           f"fired at t={now:g} s (a timer restarting itself with "
                           'after="0"?)')
                self._fail(message, ExecutionError(message))
            self._fire(name, timer.reactive)

    def _fire(self, name: str, reactive: bool) -> None:
        self._note(Note(self.clock.now(), self.app, TraceKind.TIMER, name))
        self._guard(lambda: self._dispatch(HandlerKind.EVENT, name, {"name": name}, reactive, None))

    # ------------------------------------------------------------ handling

    def _default_reactivity(self, name: str) -> bool:
        if name in PREDEFINED_EVENTS:
            return name not in NEWS_EVENTS
        if name in self.robot_events:
            return self.robot_events[name]
        declared = self.document.events.get(name)
        return bool(declared and declared.reactive)

    def _guard(self, work: Callable[..., None], *args: Any) -> None:
        try:
            work(*args)
        except AppFailure:
            raise
        except ExecutionError as exc:
            self._fail(str(exc), exc)
        except Exception as exc:  # noqa: BLE001 - a document must never take the run down
            self._fail(f"{self.document.path}: unexpected error: {type(exc).__name__}: {exc}", exc)

    def _fail(self, message: str, exc: Exception) -> None:
        self.stopped = True
        self._timers.clear()
        self._note(Note(self.clock.now(), self.app, TraceKind.ERROR, message))
        raise AppFailure(message) from exc

    def _dispatch(self, kind: HandlerKind, key: str, data: dict[str, Value],
                  reactive: bool, follows: CommandId | None, user: bool = False,
                  handlers: tuple[Handler, ...] | None = None) -> None:
        previous, self._handling = self._handling, _Handling(reactive, follows, user=user)
        try:
            self._handle(kind, key, data, handlers)
            self._drain_raised()
        finally:
            self._handling = previous

    def _run_handling(self, handling: _Handling, work: Callable[[], None]) -> None:
        previous, self._handling = self._handling, handling
        try:
            work()
            self._drain_raised()
        finally:
            self._handling = previous

    def _drain_raised(self) -> None:
        while self._raised and not self.stopped:
            name = self._raised.pop(0)
            self._dispatch(HandlerKind.EVENT, name, {"name": name},
                           self._default_reactivity(name), None)

    def _handle(self, kind: HandlerKind, key: str, data: dict[str, Value],
                handlers: tuple[Handler, ...] | None = None) -> None:
        if handlers is None:
            handlers = self._handlers(kind, key)
        if not handlers:
            return
        scope = self._scope(data)
        for handler in handlers:
            if handler.cond is None or truthy(self._eval(handler.cond, handler.loc, scope)):
                break
        else:
            return
        if kind is HandlerKind.EVENT and handler.reactive is not None:
            self._handling.reactive = handler.reactive
        tag = kind._value_
        self._note(Note(self.clock.now(), self.app, TraceKind.HANDLER, f"<{tag}> {key}",
                        {"handler": tag, "key": key, "state": self.state,
                         "line": handler.loc.line, "col": handler.loc.col}))
        leave = self._actions(handler.actions, scope)
        if leave is not None:
            self._transition(leave.state, leave.loc)

    def _handlers(self, kind: HandlerKind, key: str) -> tuple[Handler, ...]:
        """The handlers for ``kind``/``key`` in the order they are tried: the state's own
        first, then the document's, each in document order."""
        table = self._tables.get(self.state)
        if table is None:
            table = self._tables[self.state] = _handler_table(self.document, self.state)
        return table.get((kind, key), ())

    def _transition(self, target: str, goto: Loc | None = None) -> None:
        """Enter ``target`` (and the states its entries go to); ``goto``: the <goto> that
        led there, where a loop of them is reported."""
        for _ in range(MAX_TRANSITIONS):
            leave = self._enter(target)
            if leave is None:
                return
            target, goto = leave.state, leave.loc
        raise ExecutionError(f"{self._where(goto)}more than {MAX_TRANSITIONS} state changes "
                             "while handling one event (a <goto> loop?)")

    def _enter(self, target: str) -> Goto | None:
        """Enter ``target`` and run its entry actions: the <goto> among them that leaves
        it at once, if any."""
        old = self.document.states.get(self.state or "")
        new = self.document.states[target]
        self._switch_groups(old, new)
        self.state = target
        self._note(Note(self.clock.now(), self.app, TraceKind.STATE, target,
                        {"line": new.loc.line, "col": new.loc.col}))
        return self._actions(new.entry, self._scope(None))

    def _switch_groups(self, old: State | None, new: State) -> None:
        if old is not None and old.block is not None and old.block != new.block:
            self._group_note(TraceKind.BLOCK, "close", old.block)
            self.port.close_block(self.app)
        if old is not None and old.stream is not None and old.stream != new.stream:
            self._group_note(TraceKind.STREAM, "close", old.stream)
            self.port.close_stream(self.app)
        if new.stream is not None and (old is None or old.stream != new.stream):
            self._group_note(TraceKind.STREAM, "open", new.stream)
            self.port.open_stream(self.app, self.document.streams[new.stream].hold)
        if new.block is not None and (old is None or old.block != new.block):
            self._group_note(TraceKind.BLOCK, "open", new.block)
            block = self.document.blocks[new.block]
            self.port.open_block(self.app, devices=block.devices, watchdog=block.watchdog)

    def _group_note(self, kind: TraceKind, what: str, group: str) -> None:
        self._note(Note(self.clock.now(), self.app, kind, what, {"id": group}))

    # ------------------------------------------------------------ actions

    def _actions(self, actions: tuple[Action, ...], scope: Scope) -> Goto | None:
        """Run ``actions`` in order, up to a <goto>: the one that ends them, if any (it
        leaves the running handler: each caller passes it up, to the state change). (Not
        an exception: compiled, one costs a traceback entry in every frame it unwinds.)"""
        for action in actions:
            leave = _ACTIONS[type(action)](self, action, scope)
            if leave is not None:
                return leave
        return None

    def _assign(self, action: Assign, scope: Scope) -> None:
        self.variables[action.name] = self._eval(action.expr, action.loc, scope)

    def _if(self, action: If, scope: Scope) -> Goto | None:
        for cond, body in action.branches:
            if truthy(self._eval(cond, action.loc, scope)):
                return self._actions(body, scope)
        return self._actions(action.otherwise, scope)

    def _goto(self, action: Goto, _scope: Scope) -> Goto:
        return action

    def _send_action(self, action: Send, scope: Scope) -> None:
        text = self._text(self._eval(action.text, action.loc, scope), "a message", action.loc)
        now = self.clock.now()
        sent = self._sent
        while sent and sent[0] <= now - 1.0:
            sent.popleft()
        detail: dict[str, Value] = {"to": action.to}
        if len(sent) >= self.budgets.sends_per_second:
            most = self.budgets.sends_per_second
            detail["dropped"] = (f"more than {most:g} message{'s' if most != 1 else ''} in one "
                                 "second (its budget)")
            self._note(Note(now, self.app, TraceKind.SEND, text, detail))
            return
        sent.append(now)
        self._note(Note(now, self.app, TraceKind.SEND, text, detail))
        self._send(self.app, action.to, text)

    def _raise(self, action: Raise, _scope: Scope) -> None:
        if len(self._raised) >= MAX_RAISED:
            raise ExecutionError(f"{self._where(action.loc)}more than {MAX_RAISED} events "
                                 "raised while handling one event")
        self._raised.append(action.event)

    def _start_timer(self, action: StartTimer, scope: Scope) -> None:
        after = self._number(self._eval(action.after, action.loc, scope), "after", action.loc)
        self._timer_seq += 1
        self._timers[action.name] = _Timer(self.clock.after(max(0.0, float(after))),
                                           action.reactive, self._timer_seq, action.loc)

    def _cancel_timer(self, action: CancelTimer, _scope: Scope) -> None:
        self._timers.pop(action.name, None)

    def _log(self, action: Log, scope: Scope) -> None:
        text = self._text(self._eval(action.text, action.loc, scope), "a log line", action.loc)
        self._note(Note(self.clock.now(), self.app, TraceKind.LOG, text))

    def _request(self, request: Request, scope: Scope) -> None:
        self.last_request = request.loc
        calls = tuple(self._call(c, scope) for c in request.calls)
        handling = self._handling
        # Both flags go on the first request of a handling only (docs/rules.md rules 5
        # and 6a); later requests link after it (after-latest), in the same stream.
        first = not handling.requested
        reactive = handling.reactive and first
        follows = handling.follows if first else None
        handling.requested = True
        try:
            ids = self.port.submit(MediatorRequest(
                app=self.app, calls=calls, order=request.order, group=request.group,
                reactive=reactive, reaction=handling.reactive, follows=follows,
                face_user=request.face_user, on_interrupt=request.on_interrupt,
                user=handling.reactive and handling.user))
        except PrimaError as exc:  # the mediator refused it (e.g. a Command the robot lacks)
            raise ExecutionError(f"{self._where(request.loc)}request refused: {exc}") from exc
        for cid, call in zip(ids, request.calls, strict=True):
            self._commands[cid] = call

    def _call(self, call: CommandCall, scope: Scope) -> Call:
        command = call.command
        spec = self.catalog[command]
        loc = call.loc
        args: dict[str, Value] = {}
        for name, compiled in call.args.items():
            param = spec.param(name)
            kind = param.kind if param is not None else None
            value = self._eval(compiled, loc, scope)
            if kind is ParamKind.NUMBER:
                args[name] = self._number(value, command, loc, name)
            else:
                args[name] = text = self._text(value, command, loc, name)
                if kind is ParamKind.GESTURE:
                    self._check_gesture(text, loc)
        defaults = self._defaults.get(command)
        if defaults is None:
            defaults = self._defaults[command] = tuple(
                (p.name, p.default) for p in spec.params
                if p.default is not None and p.kind not in (ParamKind.GRAMMAR, ParamKind.VARIABLE))
        for name, default in defaults:
            if name not in args:
                args[name] = default
        extra = {name: self._eval(c, loc, scope) for name, c in call.extra.items()}
        return Call(command, args, extra, call.label)

    def _check_gesture(self, name: str, loc: Loc) -> None:
        """A gesture computed at run time passes the checks a literal one passes."""
        if self.gestures is not None and name not in self.gestures:
            raise ExecutionError(f"{self._where(loc)}unknown gesture {name!r} "
                                 f"(this robot knows: {', '.join(sorted(self.gestures))})")
        if self.document.kind is AppKind.EA and name not in STANDARD_GESTURES:
            raise ExecutionError(f"{self._where(loc)}gesture {name!r} is robot-specific; "
                                 "only an FA may use it")

    # ------------------------------------------------------------ values

    def _text(self, value: Value, what: str, loc: Loc, arg: str | None = None) -> str:
        """A value as text, within the application's text budget. (``what`` it is, or with
        ``arg``, the Command whose argument ``arg`` it is: its words are made only for an
        error.)"""
        text = to_text(value)
        if len(text) > self.budgets.text:
            raise ExecutionError(f"{self._where(loc)}{_what(what, arg)} is {len(text)} "
                                 f"characters long; the limit is {self.budgets.text} (its "
                                 "text budget)")
        return text

    def _scope(self, event: Mapping[str, Value] | None) -> Scope:
        """What an expression sees now: the variables, the event, the time (to the ms)."""
        return Scope(self.variables, event, round(self.clock.now(), 3))

    def _eval(self, compiled: Compiled, loc: Loc, scope: Scope | None = None) -> Value:
        try:
            return compiled.evaluate(scope or self._scope(None))
        except ExecutionError as exc:
            raise ExecutionError(f"{self._where(loc)}{exc} (in {compiled.source!r})") from exc

    def _number(self, value: Value, what: str, loc: Loc, arg: str | None = None) -> float | int:
        """A value that must be a number (``what`` and ``arg``: as for :meth:`_text`)."""
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ExecutionError(f"{self._where(loc)}{_what(what, arg)} must be a number, "
                                 f"got {value!r}")
        return value

    def _where(self, loc: Loc | None) -> str:
        return f"{self.document.path}:{loc.line}:{loc.col}: " if loc else f"{self.document.path}: "


def _what(what: str, arg: str | None) -> str:
    """What a value is, in an error: ``what``, or a Command's argument (``Speak 'text'``)."""
    return what if arg is None else f"{what} '{arg}'"


_ACTIONS: Final[Mapping[type, Callable[[Interpreter, Any, Scope], Goto | None]]] = {
    Request: Interpreter._request,
    Assign: Interpreter._assign,
    If: Interpreter._if,
    Goto: Interpreter._goto,
    Send: Interpreter._send_action,
    Raise: Interpreter._raise,
    StartTimer: Interpreter._start_timer,
    CancelTimer: Interpreter._cancel_timer,
    Log: Interpreter._log,
}
"""How each kind of action runs: one method per action type (what it returns: the
<goto> that leaves the running handler, if any)."""

if set(_ACTIONS) != set(get_args(Action)):  # pragma: no cover - a new action needs a method
    raise TypeError(f"Interpreter has no method for {set(get_args(Action)) - set(_ACTIONS)}")
