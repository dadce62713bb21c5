"""The mediator: one facade over small collaborators, each with its own state.

- :class:`~._memory.WorkingMemory`: trees, the waiting list and its index,
  running ABs, device occupancy, the suspended stack;
- :class:`~._intake.Intake`: checks requests and links them (rules 3, 6);
- :class:`~._holds.Holds`: explicit streams, blocks and the channel rule;
- :class:`~._rounds.Selector`: selection rounds (rule 4), suspend and resume;
- :class:`~._policies.Policies`: the mediation policies (docs/rules.md 7.3) at work
  on an AB the selector weighs (restore-state, connect-channel, blend, interrupt);
- :class:`~._fairness.Fairness`: the wait-share budget;
- :class:`~._log.DecisionLog`: numbers and records every decision.

Every public method is one *operation*. Operations may nest: an
application's listener or the driver may call back into the mediator while
it is calling them. Working memory is updated at once, but selection runs
only when the outermost operation completes, round after round until nothing
more can start, so the result does not depend on how callbacks nest.

The clock is read when an operation begins (a nested one reads it again): its
decisions, and those of the selection after it, carry that instant
(``DecisionLog.now``). Whoever moves the clock does so between operations, or
makes an operation after moving it.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from types import TracebackType
from typing import Final

from prima.catalog import BODY_DEVICE, CONNECT_COMMAND, SPEAKER, Catalog, ParamKind
from prima.errors import MediationError
from prima.mediator._config import MediatorConfig
from prima.mediator._decisions import Decision, DecisionKind, Rule
from prima.mediator._fairness import Fairness
from prima.mediator._holds import Holds
from prima.mediator._intake import Intake
from prima.mediator._interface import (
    AbId,
    AppListener,
    Call,
    Channel,
    Clock,
    CommandId,
    Driver,
    Event,
    Outcome,
    Request,
)
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._policies import Policies
from prima.mediator._rounds import Selector
from prima.mediator._snapshot import Snapshot, take
from prima.mediator._state import IN_MEMORY, App, Command, Node, NodeState, Tree
from prima.vocab import (
    ANSWERED,
    DEFAULT_BUDGETS,
    INTERRUPTED_EVENT,
    MAX_NEWS_PER_INSTANT,
    NOMATCH_EVENT,
    SPEECH_EVENT,
    AppKind,
    OnInterrupt,
)

__all__ = ["Mediator", "MediatorConfig"]

# (enum members read once on the hot paths: reading one from its class goes through the
# enum's metaclass, many times slower than a global)
_PENDING: Final = NodeState.PENDING
_RUNNING: Final = NodeState.RUNNING
_END: Final = DecisionKind.END
_COMPLETED: Final = Rule.COMPLETED
_CONNECT_CHANNEL: Final = Rule.CONNECT_CHANNEL


class _Operation:
    """One public operation: selection runs when the outermost one completes."""

    __slots__ = ("_m", "_outer")

    def __init__(self, mediator: Mediator) -> None:
        self._m = mediator
        self._outer = False

    def __enter__(self) -> None:
        m = self._m
        self._outer = m._depth == 0 and not m._settling
        m._depth += 1
        m._quiet = False
        m._log.now = m._clock.now()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        m = self._m
        m._depth -= 1
        if exc_type is None and self._outer:
            m._settle()
            if m._log.news:
                m._tell_news()
            m._quiet = True


class Mediator:
    """PRIMA's mediator (docs/rules.md sections 3-5)."""

    def __init__(self, catalog: Catalog, driver: Driver, clock: Clock, *,
                 config: MediatorConfig = MediatorConfig(),
                 record: Callable[[Decision], None] | None = None,
                 channel: Channel | None = None) -> None:
        self._catalog = catalog
        self._driver = driver
        self._clock = clock
        self._config = config
        self._apps: dict[str, App] = {}
        self._app_order = 0
        self._wm = WorkingMemory(keep_next=config.reactions)
        self._log = DecisionLog(record)
        self._resting: list[Node] = []
        self._beside: dict[AbId, Node] = {}
        """Words -> the turn to the user running beside them (7.6 (3)): it ends with them."""
        """Restarts that wait out the pause after a false interruption (``not_before``)."""
        self._holds = Holds(self._apps, self._wm, self._log, catalog, clock, self._resting)
        # (whether the connect-channel policy can act: what Policies._connect requires)
        turns = (channel is not None and config.connect_channel
                 and catalog.get(CONNECT_COMMAND) is not None)
        self._intake = Intake(catalog, self._apps, self._wm, self._holds, self._log, driver,
                              config, turns)
        self._policies = Policies(catalog, config, channel, self._wm, self._intake,
                                  self._holds, self._log, driver)
        self._selector = Selector(self._wm, self._holds, self._log, driver, self._overrun,
                                  self._policies)
        self._fairness = Fairness(self._apps, self._wm, self._holds, self._log, clock)
        self._depth = 0
        self._settling = False
        self._quiet = False
        """No operation began since the last outermost one completed, settled (a round
        found nothing left to start and the wait share observed it): nothing changed
        since, but for the time (:meth:`advance`)."""
        self._telling = False
        self._told: dict[str, int] = {}
        self._told_at = -1.0
        """News told per application at ``_told_at`` (:data:`MAX_NEWS_PER_INSTANT`)."""

    # ================================================================ looking
    @property
    def catalog(self) -> Catalog:
        return self._catalog

    @property
    def config(self) -> MediatorConfig:
        return self._config

    @property
    def decisions(self) -> int:
        """How many decisions were made so far."""
        return self._log.count

    def apps(self) -> tuple[str, ...]:
        """Registered applications, in registration order."""
        return tuple(self._apps)

    def snapshot(self) -> Snapshot:
        """A frozen, comparable view of working memory."""
        return take(self._clock.now(), self._wm, self._holds)

    # ============================================================ applications
    def register(self, app: str, kind: AppKind, listener: AppListener) -> None:
        """Load an application: one FA, at most ``config.max_eas`` EAs at once."""
        kind = AppKind(kind)
        if not app:
            raise MediationError("an application needs a name")
        if app in self._apps:
            raise MediationError(f"application {app!r} is already registered")
        same = [other.name for other in self._apps.values() if other.kind is kind]
        if kind is AppKind.FA and same:
            raise MediationError(
                f"cannot register {app!r}: FA {same[0]!r} is loaded "
                f"(one FA at a time; unregister {same[0]!r} first)")
        if kind is AppKind.EA and len(same) >= self._config.max_eas:
            raise MediationError(
                f"cannot register {app!r}: {len(same)} EAs are loaded ({', '.join(same)}); "
                f"at most {self._config.max_eas} EAs at once")
        with self._operation():
            self._app_order += 1
            self._apps[app] = App(app, kind, listener, self._app_order,
                                  self._config.budgets.get(kind, DEFAULT_BUDGETS[kind]))
            self._fairness.registrations()
            self._log.emit(DecisionKind.LOAD, Rule.REGISTER, app=app, detail=kind.name)

    def unregister(self, app: str) -> None:
        """Unload an application: cancel its waiting work, free its holds; running ABs finish."""
        a = self._app(app)
        with self._operation():
            self._unload(a, Rule.UNLOAD)

    def _unload(self, app: App, rule: Rule) -> None:
        now = self._log.now
        app.alive = False
        self._apps.pop(app.name, None)
        self._fairness.registrations()
        for tree in sorted(app.trees.values(), key=lambda t: t.id):
            self._wm.heard(tree)  # (an app gone answers nobody: what it held may go, 7.6 (1))
            for node in list(tree.nodes.values()):
                if node.state is NodeState.RUNNING:
                    if node.feedback:
                        node.commands[0].cut = True
                else:
                    self._intake.cancel(node, Rule.UNLOAD, now)
        self._holds.close_stream(app, Rule.UNLOAD)
        self._holds.close_block(app, Rule.UNLOAD)
        self._log.emit(DecisionKind.UNLOAD, rule, app=app.name)

    def _overrun(self, app: App, detail: str) -> None:
        """An app overran a budget that fails it (called between selection rounds)."""
        if app.alive:
            self._log.emit(DecisionKind.FAILURE, Rule.STARTS_PER_INSTANT, app=app.name,
                           detail=detail)
            self._unload(app, Rule.STARTS_PER_INSTANT)

    def _app(self, name: str) -> App:
        app = self._apps.get(name)
        if app is None:
            raise MediationError(f"unknown application {name!r}")
        return app

    def _call(self, app: App, callback: Callable[[AppListener], None], what: str) -> None:
        """Call an app's listener; an exception removes the app, never the mediator."""
        if not app.alive:
            return
        try:
            callback(app.listener)
        except Exception as exc:  # noqa: BLE001 - a failing app must not stop the robot
            self._failed(app, what, exc)

    def _failed(self, app: App, what: str, exc: Exception) -> None:
        """An app's listener raised: the app is removed (once)."""
        if app.alive:
            self._log.emit(DecisionKind.FAILURE, Rule.APP_FAILURE, app=app.name,
                           detail=f"{what}: {type(exc).__name__}: {exc}")
            self._unload(app, Rule.APP_FAILURE)

    # ================================================================ requests
    def submit(self, request: Request) -> tuple[CommandId, ...]:
        """Accept a request; returns one Command id per Call (docs/rules.md rule 3). One
        that fails its check changes nothing."""
        # (what ``with self._operation():`` does, written out: the hottest operation)
        outer = self._depth == 0 and not self._settling
        self._depth += 1
        self._quiet = False
        self._log.now = now = self._clock.now()
        try:
            ids, cancelled = self._intake.accept(request, now)
            if cancelled:
                self._tell_cancelled(cancelled)
        finally:
            self._depth -= 1
        if outer:
            self._settle()
            if self._log.news:
                self._tell_news()
            self._quiet = True
        return ids

    def _interrupted(self, node: Node, outcome: Outcome) -> None:
        """A cut AB ended at a word boundary: start it again in its place in its tree (it
        waits, and the reaction that cut it outranks it), from its beginning or, if its
        request says ``resume``, from the sentence it was cut in; or, if its request
        says ``drop``, drop it (its Commands end, interrupted). Cut by words of the user's
        that no application took (a false interruption), it goes on after the robot's
        pause, and is never dropped. Its application gets an ``interrupted`` event
        either way, before anything else of it."""
        now = self._log.now
        wm = self._wm
        children = wm.end(node, now)
        self._holds.ended(node)
        app = node.app
        by_user = node.by_user
        false_cut = by_user and node.taker is None
        modes = {c.on_interrupt for c in node.commands}
        # (an unloaded app's AB still running is cut for good: nobody would restart it)
        drop = not app.alive or node.dropped or (OnInterrupt.DROP in modes and not false_cut)
        values = outcome.values
        resumed = None
        if not drop and (OnInterrupt.RESUME in modes
                         or (false_cut and OnInterrupt.DROP in modes)):
            resumed = _resumed(node, str(values.get("spoken") or ""),
                               str(values.get("unspoken") or ""))
        reason = Rule.BARGE_IN if by_user else Rule.INTERRUPT
        self._log.ab(DecisionKind.END, reason, node,
                     "dropped" if drop else "to go on" if resumed is not None else "to restart")
        ended: tuple[Command, ...] = ()
        if drop:
            ended = node.commands
            self._intake.ended(ended, now)
            if node.feedback:
                self._driver.abandon(node.commands[0].id)
            for child in children:
                if child.state is NodeState.PENDING:
                    wm.enter_waiting(child, True)  # (its parent just finished)
        else:
            self._restart(node, children, resumed, false_cut)
        wm.leave(node)
        cutter = node.cut_by
        if cutter is not None and cutter.alive and cutter is not app \
                and now > node.started_at:
            # the time the cut throws away counts against the cutting app's wait share
            # (an app's own stream, cut for its turn to the user, is no budget matter)
            self._fairness.charge(cutter, now - node.started_at)
        by = "user" if by_user else (cutter.name if cutter is not None else "")
        event = Event(INTERRUPTED_EVENT, {
            "command": node.name, "label": node.commands[0].call.label or "",
            "spoken": str(values.get("spoken") or ""),
            "unspoken": str(values.get("unspoken") or ""), "restarts": not drop,
            "resumes": resumed is not None, "by": by, "reason": reason.value}, now)
        self._call(app, lambda listener: listener.event(event), "event")
        # (what the app's own as-soon-as-possible request drops as it is cut is cancelled
        # by the app, as its waiting Commands are: no end event, no Q&A's no-input)
        told = None if node.dropped else outcome
        for cmd in ended:
            if not cmd.internal:
                self._tell(app, cmd.id, told)

    def _restart(self, node: Node, children: list[Node],
                 resumed: tuple[tuple[Call, ...], str] | None, false_cut: bool) -> None:
        """A cut AB requested again in its place in its tree (:meth:`_interrupted`): from
        its beginning, or from ``resumed`` (its calls from the sentence it was cut in);
        after the robot's pause when no application took the user's words."""
        wm = self._wm
        app = node.app
        by_user = node.by_user
        again = wm.new_node(app, node.tree, node.commands, node.devices, node.priority,
                            node.reactive, node.seq, node.iteration)
        again.restarts = node.id
        again.once = node.once or not by_user  # (one cut by another app at most)
        again.cut_for = None if by_user else node.cut_for
        again.taker = node.taker if by_user else None  # (it waits for its reaction)
        if again.cut_for is not None:
            wm.after_reactions[again.id] = again
        # it starts like any other AB: turned to the user first, where it applies
        again.turnable = again.faces = node.faces
        again.parent = node.id
        again.children = children
        for c in children:
            c.parent = again.id
        detail = f"starts AB{node.id} again from its beginning"
        if resumed is not None:
            again.calls = resumed[0]
            again.plain = again.facts + ("", again.calls, None, None)
            detail = f"AB{node.id} goes on from {resumed[1]!r}"
        if false_cut:
            again.protected = node.protected  # (the exchange goes on: 7.4)
            again.not_before = self._clock.after(self._config.resume_pause)
            detail += (f" after {self._config.resume_pause:g} s (no application took "
                       "the user's words)")
            self._resting.append(again)
        self._log.emit(DecisionKind.REQUEST, Rule.RESTART, again, detail=detail,
                       before=node.id)
        wm.enter_waiting(again, False)  # (its parent has not)

    def _tell_cancelled(self, commands: Sequence[Command]) -> None:
        for cmd in commands:
            if not cmd.internal:
                self._tell(cmd.app, cmd.id, None)

    def _tell(self, app: App, command_id: CommandId, outcome: Outcome | None) -> None:
        """Tell an app that its Command ended (with ``outcome``) or was cancelled (None)."""
        if outcome is None:
            self._call(app, lambda listener: listener.command_cancelled(command_id),
                       "command_cancelled")
        else:
            self._call(app, lambda listener: listener.command_ended(command_id, outcome),
                       "command_ended")

    # ================================================================= driver
    def finish(self, ab_id: AbId, outcome: Outcome = Outcome()) -> None:
        """The driver reports an AB's end (docs/rules.md rule 3, feedback iterations)."""
        node = self._wm.nodes.get(ab_id)
        if node is None or node.state is not _RUNNING:
            raise MediationError(f"AB{ab_id} is not running")
        # (what ``with self._operation():`` does, written out: the other hot operation)
        outer = self._depth == 0 and not self._settling
        self._depth += 1
        self._quiet = False
        self._log.now = self._clock.now()
        try:
            if self._beside:
                turn = self._beside.pop(ab_id, None)
                if turn is not None and turn.state is _RUNNING:
                    self._driver.cut(turn.id)  # (a turn beside words ends with them: 7.6 (3))
            self._end(node, outcome)
        finally:
            self._depth -= 1
        if outer:
            self._settle()
            if BODY_DEVICE in node.devices and SPEAKER in self._wm.busy \
                    and node.commands[0].internal is not Rule.CONNECT_CHANNEL:
                # (the wheels are free while words run, after something else than a turn
                # to the user moved the robot: 7.6 (3))
                self._depth += 1
                try:
                    self._keep_facing()
                finally:
                    self._depth -= 1
                self._settle()
            if self._log.news:
                self._tell_news()
            self._quiet = True

    def _end(self, node: Node, outcome: Outcome) -> None:
        if node.cutting and outcome.values.get("interrupted") is True \
                and not node.commands[0].cut:
            self._interrupted(node, outcome)
            return
        now = self._log.now
        wm = self._wm
        children = wm.end(node, now)
        self._holds.ended(node)
        detail = ""
        looping = False  # (a feedback iteration that does not end its loop)
        if node.feedback:
            detail = "terminal" if outcome.terminal else "not terminal"
            looping = not outcome.terminal
        self._log.ab(_END, _COMPLETED, node, detail)
        app = node.app
        ended: tuple[Command, ...] = ()
        cancelled: Command | None = None
        replaced = False
        if looping:
            cmd0 = node.commands[0]
            if not cmd0.cut:
                children = [self._next_iteration(node, children)]
                replaced = True
            else:
                cancelled = cmd0
                cmd0.cancelled = True
                if app.latest is not cmd0:
                    cmd0.node = None  # (forgotten: see ``Intake._recent``)
                self._log.emit(DecisionKind.CANCEL, Rule.ASAP if app.alive else Rule.UNLOAD,
                               node, detail="feedback loop stopped between iterations")
                self._driver.abandon(cmd0.id)
        else:
            ended = node.commands
            for cmd in ended:
                if cmd.spec.listens:
                    cmd.answered = outcome.values.get("status") == ANSWERED
            self._intake.ended(ended, now)
        self._done(node, children)
        for child in children:
            if child.state is _PENDING:
                wm.enter_waiting(child, True)  # (its parent just finished)
        wm.leave(node, replaced)
        if cancelled is not None:
            self._tell_cancelled([cancelled])
        for cmd in ended:
            if not cmd.internal and app.alive:
                try:  # (``_tell``, written out)
                    app.listener.command_ended(cmd.id, outcome)
                except Exception as exc:  # noqa: BLE001 - a failing app must not stop the robot
                    self._failed(app, "command_ended", exc)

    def _done(self, node: Node, children: list[Node]) -> None:
        """What the end of ``node`` tells its tree: a reaction to the user has said its
        first utterance in full (docs/rules.md 7.1); the robot faces the user for the ABs
        after a turn to the user, whatever happened before it."""
        tree = node.tree
        if tree.user and node.seq >= tree.user_since and node.speaks:
            self._wm.heard(tree)
        if tree.answered_since and node.seq >= tree.answered_since and node.speaks:
            self._wm.replied(tree)
        if node.commands[0].internal is _CONNECT_CHANNEL:
            for child in children:
                child.looked = tree.suspensions
                child.faced_at = self._log.now

    def _next_iteration(self, node: Node, children: list[Node]) -> Node:
        """Insert a feedback Command's next iteration between ``node`` and its children."""
        nxt = self._wm.next_iteration(node)
        if node.commands[0].internal is not None:
            nxt.protected = node.protected  # (a return put before a reply is part of it;
            # a reply's own next iteration comes after its words: the exchange is over)
        nxt.parent = node.id
        nxt.children = children
        for c in children:
            c.parent = nxt.id
        return nxt

    # ================================================================= events
    def post(self, event: Event) -> None:
        """Broadcast a predefined or robot event to every registered app (rule 5)."""
        with self._operation():
            for app in list(self._apps.values()):
                self._call(app, lambda listener: listener.event(event), "event")

    def hear(self, event: Event) -> None:
        """The robot heard its user outside a Q&A (docs/rules.md 7.5): ``event`` carries the
        ``words`` and whether they are a ``backchannel``. One application takes them:
        the one whose stream runs (on the speaker first), else the one whose stream was
        suspended most recently, else the first (the FA, then the EAs as loaded), of
        those whose always-on grammar takes them (:meth:`AppListener.takes`); it gets a
        reactive ``speech`` event. If none takes them, every application gets a
        ``nomatch`` event. With the barge-in policy, words over the robot's utterance
        cut it at a word boundary, unless they are a backchannel: cut for a taker, it
        waits for the taker's reaction; cut for nothing (a false interruption), it goes
        on after the robot's pause."""
        with self._operation():
            now = self._log.now
            words = str(event.data.get("words") or "")
            shown = _quoted(words)
            talking = self._talking() if self._config.barge_in else []
            if talking and event.data.get("backchannel"):
                self._log.emit(DecisionKind.HEAR, Rule.BACKCHANNEL,
                               detail=f"{shown}: the robot talks on")
                return
            taker, rule = self._taker(words)
            self._log.emit(DecisionKind.HEAR, rule, app=taker.name if taker else None,
                           detail=(f"{shown}: {taker.name} takes it" if taker is not None
                                   else f"{shown}: no application takes it"))
            for y in talking:
                if not y.cutting and self._driver.stop_words(y.id):
                    y.cutting = y.by_user = True
                    y.taker = taker
                    y.cut_by = y.cut_for = None
                    self._log.ab(DecisionKind.INTERRUPT, Rule.BARGE_IN, y,
                                 "as the user spoke over it" + (
                                     "" if taker is not None else
                                     f"; it goes on after {self._config.resume_pause:g} s"))
            if taker is not None:
                heard = Event(SPEECH_EVENT, {"words": words}, now)
                taker.fresh = True
                try:
                    self._call(taker, lambda listener: listener.event(heard), "event")
                finally:
                    taker.fresh = False
                return
            self.post(Event(NOMATCH_EVENT, {"words": words}, now))  # (every app sees it)

    def regard(self) -> None:
        """The user went off to the side while the robot says words (what the run's
        Channel answers changed): an utterance addressed to them keeps facing them
        (docs/rules.md 7.6 (3)): a turn to the user runs beside its words if the wheels
        are free now (connect-channel); one that cannot start at once is cancelled."""
        with self._operation():
            self._keep_facing()

    def _keep_facing(self) -> None:
        """A turn to the user beside the words under way, if the policy puts one in (the
        wheels are free and the user off to the side); cancelled if it cannot start at
        once."""
        put = self._policies.keep_facing()
        if put is not None:
            words, turn = put
            self._settle()
            if turn.state is NodeState.WAITING:
                self._intake.cancel(turn, Rule.CONNECT_CHANNEL, self._log.now)
            elif turn.state is _RUNNING:
                self._beside[words.id] = turn

    def _talking(self) -> list[Node]:
        """The running ABs with words this robot can stop (an interruptible Command that
        says them), oldest first: the driver stops those saying them now."""
        seen = {n.id: n for n in self._wm.busy.values()}
        return [n for _id, n in sorted(seen.items())
                if any(c.spec.interruptible and c.spec.spoken(call.args)
                       for c, call in zip(n.commands, n.calls, strict=True))]

    def _taker(self, words: str) -> tuple[App | None, Rule]:
        """Who takes the user's ``words`` (docs/rules.md 7.5), and why."""
        busy = self._wm.busy
        speaking = busy.get(SPEAKER)
        running = sorted({n.app.name: n.app for n in busy.values()}.values(),
                         key=lambda a: (speaking is None or a is not speaking.app, a.order))
        asked: set[str] = set()
        for app in running:
            asked.add(app.name)
            if app.alive and self._takes(app, words):
                return app, Rule.STREAM_RUNS
        for tree in self._wm.stack():
            app = tree.app
            if app.name not in asked:
                asked.add(app.name)
                if app.alive and self._takes(app, words):
                    return app, Rule.STREAM_SUSPENDED
        for app in sorted(self._apps.values(), key=lambda a: (a.kind is not AppKind.FA,
                                                               a.order)):
            if app.name not in asked and self._takes(app, words):
                return app, Rule.GRAMMAR
        return None, Rule.NOMATCH

    def _takes(self, app: App, words: str) -> bool:
        try:
            return bool(app.listener.takes(words))
        except Exception as exc:  # noqa: BLE001 - a failing app must not stop the robot
            self._failed(app, "takes", exc)
            return False

    def _tell_news(self) -> None:
        """Tell applications what happened to their streams in the operation that just
        settled (suspended, resumed, held back: docs/rules.md 7.5), in order; what they
        request meanwhile settles as usual, and its own news is told after. At most
        :data:`MAX_NEWS_PER_INSTANT` news per application and instant."""
        if self._telling:
            return
        self._telling = True
        try:
            news = self._log.news
            while news:
                name, what, data = news.pop(0)
                app = self._apps.get(name)
                if app is None:
                    continue
                now = self._clock.now()
                if now != self._told_at:
                    self._told_at, self._told = now, {}
                told_here = self._told[name] = self._told.get(name, 0) + 1
                if told_here > MAX_NEWS_PER_INSTANT:
                    continue  # (its handlers keep making news: enough for this instant)
                told = Event(what, dict(data), self._clock.now())
                with self._operation():
                    self._call(app, functools.partial(_tell_event, told), "event")
        finally:
            self._telling = False

    # ======================================================== streams, blocks
    def open_stream(self, app: str, hold: float) -> None:
        """Begin an explicit stream block (rule 6c): one CS, held while the app waits.
        With the streams policy off, nothing: the block is a plain sequence."""
        if not self._config.streams:
            return
        a = self._app(app)
        if self._holds.stream(a) is not None:
            raise MediationError(f"{app}: a stream is already open")
        if hold < 0:
            raise MediationError(f"{app}: stream hold must be >= 0, got {hold}")
        with self._operation():
            self._holds.open_stream(a, min(hold, self._config.max_stream_hold),
                                    self._latest_tree(a))

    def close_stream(self, app: str) -> None:
        """End the explicit stream block; its hold (if any) is released. With the
        streams policy off, nothing."""
        if not self._config.streams:
            return
        a = self._app(app)
        if self._holds.stream(a) is None:
            raise MediationError(f"{app}: no stream is open")
        with self._operation():
            self._holds.close_stream(a, Rule.STREAM_CLOSE)

    def open_block(self, app: str, *, devices: frozenset[str] | None = None,
                   watchdog: float) -> None:
        """Begin a begin/end block: one IU, its devices reserved once it starts."""
        a = self._app(app)
        if self._holds.block(a) is not None:
            raise MediationError(f"{app}: a block is already open")
        if watchdog <= 0:
            raise MediationError(f"{app}: block watchdog must be > 0, got {watchdog}")
        devs = self._catalog.devices if devices is None else frozenset(devices)
        unknown = devs - self._catalog.devices
        if unknown:
            raise MediationError(f"{app}: block names unknown devices {sorted(unknown)}")
        with self._operation():
            self._holds.open_block(a, devs, min(watchdog, self._config.max_block_watchdog),
                                   self._intake.next_command, self._latest_tree(a))

    def close_block(self, app: str) -> None:
        """Conclude the block (also fine after its watchdog fired)."""
        a = self._app(app)
        if self._holds.block(a) is None:
            raise MediationError(f"{app}: no block is open")
        with self._operation():
            self._holds.close_block(a, Rule.BLOCK_CLOSE)

    @staticmethod
    def _latest_tree(app: App) -> Tree | None:
        latest = app.latest.node if app.latest is not None else None
        return latest.tree if latest is not None and latest.state in IN_MEMORY else None

    # ============================================================== deadlines
    def next_deadline(self) -> float | None:
        """The earliest pending hold timeout, watchdog, budget deadline, end of a pause
        after a false interruption, or end of an answer's hold (7.6 (1)), if any."""
        # (the earliest of those that are not None, written out: asked at every wake of
        # a run, and most often only the wait share's is set)
        best = self._holds.next_deadline()
        t = self._fairness.next_deadline()
        if t is not None and (best is None or t < best):
            best = t
        if self._resting:
            t = self._rest_deadline()
            if t is not None and (best is None or t < best):
                best = t
        if self._wm.answering:
            t = self._answer_deadline()
            if t is not None and (best is None or t < best):
                best = t
        return best

    def _answer_deadline(self) -> float | None:
        """When the first reaction to the user's own action that has not said its first
        words stops keeping the streams it interrupted waiting (its bound: docs/rules.md
        7.6 (1)), if one is later than now."""
        answering = self._wm.answering
        if not answering:
            return None
        now = self._clock.now()
        return min((t.answers_until for t in answering.values() if t.answers_until > now),
                   default=None)

    def _rest_deadline(self) -> float | None:
        resting = self._resting
        if resting:
            resting[:] = [n for n in resting if n.state is NodeState.WAITING]
        return min((n.not_before for n in resting), default=None)

    def advance(self) -> None:
        """Handle every deadline that has passed, then run selection."""
        wm = self._wm
        if self._quiet and not (wm.answering or self._resting or wm.new or wm.dirty
                                or wm.pjf or wm.unreserved or wm.answered):
            self._log.now = now = self._clock.now()
            if not self._holds.opened or not self._holds.due(now):
                # Nothing changed since the last operation settled, and nothing but the
                # wait share has a deadline that passed: what the operation would do
                # past handling the wait share's deadlines is a round that finds nothing
                # to look at (an open stream's hold is armed or lapsed as the last
                # round left it: no app went idle or busy since) and an observation
                # that finds the same apps keeping others waiting, at the instant the
                # wait share just settled (which changes nothing). (The run asks at
                # every report of the simulator, most often with nothing due.)
                if self._fairness.expire():  # (a precedence changed: others may start)
                    with self._operation():
                        pass
                return
        with self._operation():
            now = self._log.now
            self._holds.expire(now)
            self._fairness.expire()
            if any(t.answers_until <= now for t in self._wm.answering.values()):
                self._wm.answered = True  # (a bound passed: what it held may go)
            if self._resting:
                over = [n for n in self._resting if n.not_before <= now]
                for node in over:
                    self._resting.remove(node)
                    if node.state is NodeState.WAITING:
                        self._wm.dirty.update(node.devices)  # (its pause is over)
                if over:  # (its app's talk goes on or ends: what the pause held may go)
                    self._holds.refile_talk()

    # ================================================================ plumbing
    def _operation(self) -> _Operation:
        return _Operation(self)

    def _settle(self) -> None:
        self._settling = True
        try:
            self._selector.settle()
            while self._fairness.observe():  # a precedence changed: others may start
                self._selector.settle()
        finally:
            self._settling = False


_SENTENCE_END = (".", "!", "?")


def _resumed(node: Node, spoken: str, unspoken: str) -> tuple[tuple[Call, ...], str] | None:
    """The calls with which a cut utterance goes on, from the beginning of the sentence
    its first unspoken word falls in, and those words; None if it says everything
    again (the cut fell in its first sentence, or its words are in several texts). A
    grouped AB goes on with its other Commands as they were (a turn toward a panel
    that the robot already faces takes no time)."""
    if not unspoken:
        return None
    said = spoken.split()
    back = len(said)
    while back > 0 and not said[back - 1].endswith(_SENTENCE_END):
        back -= 1
    if back == 0:
        return None  # (the first sentence: from the beginning)
    rest = " ".join(said[back:] + unspoken.split())
    said_by = [(i, [p.name for p in c.spec.params
                    if p.kind is ParamKind.TEXT and call.args.get(p.name)])
               for i, (c, call) in enumerate(zip(node.commands, node.calls, strict=True))
               if c.spec.spoken(call.args)]
    if len(said_by) != 1 or len(said_by[0][1]) != 1:
        return None  # (words in more than one Command: said again from the beginning)
    i, (name,) = said_by[0]
    call = node.calls[i]
    again = Call(call.command, {**call.args, name: rest}, call.extra, call.label,
                 call.extra_devices)
    return node.calls[:i] + (again,) + node.calls[i + 1:], rest


def _quoted(words: str) -> str:
    """The user's words in a decision's detail (long ones shortened)."""
    return repr(words if len(words) <= 60 else words[:57] + "...")


def _tell_event(event: Event, listener: AppListener) -> None:
    listener.event(event)
