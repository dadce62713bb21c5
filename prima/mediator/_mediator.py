"""The mediator: one facade over small collaborators, each with its own state.

- :class:`~._memory.WorkingMemory`: trees, the waiting list and its index,
  running ABs, device occupancy, the suspended stack;
- :class:`~._intake.Intake`: checks requests and links them (rules 3, 6);
- :class:`~._holds.Holds`: explicit streams, blocks and the channel rule;
- :class:`~._rounds.Selector`: selection rounds (rule 4), suspend and resume;
- :class:`~._fairness.Fairness`: the wait-share budget;
- :class:`~._log.DecisionLog`: numbers and records every decision.

Every public method is one *operation*. Operations may nest: an
application's listener or the driver may call back into the mediator while
it is calling them. Working memory is updated at once, but selection runs
only when the outermost operation completes, round after round until nothing
more can start, so the result does not depend on how callbacks nest.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import TracebackType

from prima.catalog import (
    BODY_DEVICE,
    CONNECT_COMMAND,
    RESTORE_COMMAND,
    RESTORE_POSITION_COMMAND,
    Catalog,
)
from prima.errors import MediationError
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
from prima.mediator._ranking import preempts
from prima.mediator._rounds import Selector
from prima.mediator._snapshot import Snapshot, take
from prima.mediator._state import IN_MEMORY, App, Command, Node, NodeState, Tree
from prima.vocab import (
    DEFAULT_BUDGETS,
    INTERRUPTED_EVENT,
    MAX_BLOCK_WATCHDOG,
    MAX_EAS,
    MAX_STREAM_HOLD,
    AppKind,
    Budgets,
    OnInterrupt,
)

__all__ = ["Mediator", "MediatorConfig"]


@dataclass(frozen=True)
class MediatorConfig:
    """Tunable bounds of the mediation rules."""

    end_grace: float = 0.5
    """Seconds after a Command's end within which a ``follows`` request stays in
    its tree (CS exceptions (a)/(b)). A handler that requests at once is always
    in time; one that waits on a timer or polls is not."""

    max_stream_hold: float = MAX_STREAM_HOLD
    """Upper bound on an explicit stream's hold, whatever the document asks: the
    other application's response speed stays bounded (rule 6c)."""

    max_block_watchdog: float = MAX_BLOCK_WATCHDOG
    """Upper bound on a begin/end block's watchdog, whatever the document asks:
    a runaway block cannot starve the other application (rule 3)."""

    connect_channel: bool = True
    """The connect-channel policy (MISSION.md 7.3 (4)), when there is a channel."""

    restore_state: bool = True
    """The restore-state policy (MISSION.md 7.3 (1)), when there is a channel."""

    blend: bool = True
    """The blend policy (MISSION.md 7.3 (5)): on the blends the catalog declares (the
    robot profile's ``<blend>``)."""

    interrupt: bool = True
    """The interrupt policy (MISSION.md 7.3 (2)): on the Commands the catalog says are
    interruptible (the robot profile's ``<interruptible>``)."""

    max_eas: int = MAX_EAS
    """Most EAs registered at once (besides the one FA): each has its own budgets."""

    budgets: Mapping[AppKind, Budgets] = field(default_factory=lambda: DEFAULT_BUDGETS)
    """What one application of each role may consume (the robot profile's
    ``<budgets>``): the mediator enforces ``waiting``, ``starts_per_instant`` and
    the wait share."""


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

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        m = self._m
        m._depth -= 1
        if exc_type is None and self._outer:
            m._settle()


class Mediator:
    """PRIMA's mediator (MISSION.md sections 3-5)."""

    def __init__(self, catalog: Catalog, driver: Driver, clock: Clock, *,
                 config: MediatorConfig = MediatorConfig(),
                 record: Callable[[Decision], None] | None = None,
                 channel: Channel | None = None) -> None:
        self._catalog = catalog
        self._channel = channel
        """Asked when a stream is suspended and before a resumed stream or an utterance
        starts (the restore-state and connect-channel policies); None: both off."""
        self._driver = driver
        self._clock = clock
        self._config = config
        self._apps: dict[str, App] = {}
        self._app_order = 0
        self._wm = WorkingMemory()
        self._log = DecisionLog(clock, record)
        self._holds = Holds(self._apps, self._wm, self._log, catalog, clock)
        self._intake = Intake(catalog, self._apps, self._wm, self._holds, self._log, driver,
                              config)
        self._selector = Selector(self._wm, self._holds, self._log, driver, clock,
                                  self._overrun, self._prepare, self._suspending, self._cut,
                                  self._blend)
        self._fairness = Fairness(self._apps, self._wm, self._holds, self._log, clock)
        self._depth = 0
        self._settling = False

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
            self._log.emit(DecisionKind.LOAD, Rule.REGISTER, app=app, detail=kind.name)

    def unregister(self, app: str) -> None:
        """Unload an application: cancel its waiting work, free its holds; running ABs finish."""
        a = self._app(app)
        with self._operation():
            self._unload(a, Rule.UNLOAD)

    def _unload(self, app: App, rule: Rule) -> None:
        now = self._clock.now()
        app.alive = False
        self._apps.pop(app.name, None)
        for tree in sorted(app.trees.values(), key=lambda t: t.id):
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
            if app.alive:
                self._log.emit(DecisionKind.FAILURE, Rule.APP_FAILURE, app=app.name,
                               detail=f"{what}: {type(exc).__name__}: {exc}")
                self._unload(app, Rule.APP_FAILURE)

    # ================================================================ requests
    def submit(self, request: Request) -> tuple[CommandId, ...]:
        """Accept a request; returns one Command id per Call (MISSION.md rule 3)."""
        app, specs = self._intake.check(request)
        with self._operation():
            ids, cancelled = self._intake.accept(app, request, specs, self._clock.now())
            self._tell_cancelled(cancelled)
            return ids

    def _blend(self, x: Node) -> tuple[frozenset[str], bool] | None:
        """The blend policy: the busy devices the ready ``x`` may share with what runs
        there, if it may share every one: each is held by an AB that is no blend
        itself and has none over it, of Commands a declared blend lets ``x``'s run
        over there; and the user is within the blend's bound. With them, whether every
        blend used bounds the distance to the user. None otherwise."""
        catalog = self._catalog
        if not self._config.blend or not catalog.blends:
            return None
        wm = self._wm
        shared: set[str] = set()
        bounded = True
        for d in x.sorted_devices:
            y = wm.busy.get(d)
            if y is None:
                continue
            if y.blended or d in wm.blending or y.cutting:
                return None
            b = catalog.blend([c.spec for c in x.commands], [c.spec for c in y.commands], d)
            if b is None or (b.max_user_distance is not None and (
                    self._channel is None or not self._channel.near(b.max_user_distance))):
                return None
            shared.add(d)
            bounded = bounded and b.max_user_distance is not None
        return (frozenset(shared), bounded) if shared else None

    def _cut(self, x: Node) -> None:
        """The interrupt policy: the reaction's AB ``x`` ranks best on its devices but
        some are busy. If every AB running on them is another application's and may
        be cut (its Commands are interruptible on this robot, its request allows it,
        no block of its application keeps its devices), have the driver cut them."""
        if not self._config.interrupt:
            return
        busy = self._wm.busy
        running = sorted({busy[d] for d in x.devices if d in busy}, key=lambda y: y.id)
        if not running or not all(self._cuttable(y, x) for y in running):
            return
        for y in running:
            if not y.cutting and self._driver.cut(y.id):
                y.cutting = True
                self._log.emit(DecisionKind.INTERRUPT, Rule.INTERRUPT, y,
                               detail=f"for {x.app.name}'s reaction (AB{x.id})")

    def _cuttable(self, y: Node, x: Node) -> bool:
        if y.app is x.app or not preempts(x, y):
            return False
        if y.blended or any(d in self._wm.blending for d in y.devices):
            return False  # blended ABs are never cut
        if not all(c.spec.interruptible and c.on_interrupt is not OnInterrupt.NEVER
                   and not c.cut for c in y.commands):
            return False
        block = self._holds.block(y.app)
        return block is None or not (block.devices & y.devices)

    def _interrupted(self, node: Node, outcome: Outcome) -> None:
        """A cut AB ended at a word boundary: start it again from its beginning, in its
        place in its tree (it waits, and the reaction that cut it outranks it), or, if
        its request said so, drop it (its Commands end, interrupted). Its application
        gets an ``interrupted`` event either way, before anything else of it."""
        now = self._clock.now()
        wm = self._wm
        children = wm.end(node, now)
        self._holds.ended(node)
        app = node.app
        # (an unloaded app's AB still running is cut for good: nobody would restart it)
        drop = not app.alive or any(c.on_interrupt is OnInterrupt.DROP for c in node.commands)
        self._log.emit(DecisionKind.END, Rule.INTERRUPT, node,
                       detail="dropped" if drop else "to restart")
        ended: tuple[Command, ...] = ()
        if drop:
            ended = node.commands
            self._intake.ended(ended, now)
            if node.feedback:
                self._driver.abandon(node.commands[0].id)
            for child in children:
                if child.state is NodeState.PENDING:
                    wm.enter_waiting(child, parent_finished=True)
        else:
            again = wm.new_node(app, node.tree, node.commands, node.devices, node.priority,
                                node.reactive, node.seq, node.iteration)
            again.restarts = node.id
            again.parent = node.id
            again.children = children
            for c in children:
                c.parent = again.id
            self._log.emit(DecisionKind.REQUEST, Rule.RESTART, again,
                           detail=f"starts AB{node.id} again from its beginning",
                           before=node.id)
            wm.enter_waiting(again, parent_finished=False)
        wm.leave(node)
        values = outcome.values
        event = Event(INTERRUPTED_EVENT, {
            "command": node.name, "label": node.commands[0].call.label or "",
            "spoken": str(values.get("spoken") or ""),
            "unspoken": str(values.get("unspoken") or ""), "restarts": not drop}, now)
        self._call(app, lambda listener: listener.event(event), "event")
        for cmd in ended:
            if not cmd.internal:
                self._tell(app, cmd.id, outcome)

    def _suspending(self, tree: Tree) -> None:
        """A tree is suspended: remember where the robot is (restore-state)."""
        if self._channel is not None and self._config.restore_state:
            tree.pose = self._channel.pose()

    def _prepare(self, x: Node) -> bool:
        """The ready AB ``x`` is about to start: put a policy's AB before it? True if it
        now waits for one (a return to the pose its stream was suspended in, then a
        turn to the user)."""
        if x.tree.pose is not None and x.tree.suspended is not None and self._restore(x):
            return True
        return x.turnable and self._connect(x)

    def _restore(self, x: Node) -> bool:
        """The restore-state policy: ``x`` resumes its suspended stream with the robot
        moved away from where it was suspended, so a return to that pose goes first,
        in the stream. Not before an AB that takes the robot somewhere itself (a move,
        following the user), and once per suspension. Before an AB that turns the robot
        itself (a FaceHumanAndSpeak), only the position is restored. The return waits
        for the wheels like any AB of the resumed stream."""
        pose, x.tree.pose = x.tree.pose, None
        if pose is None or self._channel is None or any(c.spec.travels for c in x.commands):
            return False
        command = RESTORE_COMMAND
        if BODY_DEVICE in x.devices:
            command = RESTORE_POSITION_COMMAND
            pose = {k: v for k, v in pose.items() if k != "heading"}
        spec = self._catalog.get(command)
        if spec is None or not self._channel.displaced(pose):
            return False
        call = Call(command, pose)
        self._intake.insert_before(x, call, spec, Rule.RESTORE_STATE,
                                   f"returns to the pose its stream was suspended in "
                                   f"before AB{x.id}")
        return True

    def _connect(self, x: Node) -> bool:
        """The connect-channel policy: before the ready utterance ``x`` starts facing
        away from a detectable user, put a turn to the user before it, in its stream
        (once per AB). Only when the turn's devices are free, or will be within a
        control period with the turn first in line (:meth:`_turn_waits_for`): an
        utterance is never kept waiting for anything else on the wheels (a search's
        turn, a 5 s drive), which a later reaction could take first. True if it now
        waits for the turn."""
        x.turnable = False
        spec = self._catalog.get(CONNECT_COMMAND)
        if self._channel is None or spec is None or not self._config.connect_channel:
            return False
        busy = self._wm.busy
        if any(d in busy and not self._turn_waits_for(busy[d], x) for d in spec.devices) \
                or not self._channel.unfaced():
            return False
        self._intake.insert_before(x, Call(CONNECT_COMMAND), spec, Rule.CONNECT_CHANNEL,
                                   f"turns to the user before AB{x.id}")
        return True

    def _turn_waits_for(self, y: Node, x: Node) -> bool:
        """A turn to the user before ``x`` may wait for the running ``y`` on the wheels:
        an iteration of a move that breaks the channel (it ends within a control
        period, and the turn, keeping the channel, outranks the move's next one); for
        a reaction's utterance, another application's iteration with the body still
        (a search's watch: one control period, and the reaction outranks its next
        one), or an AB the interrupt policy will cut for the turn."""
        if not y.feedback:
            return x.tree.reaction is not None and self._config.interrupt \
                and self._cuttable(y, x)
        if y.priority < x.priority:
            return True
        if x.tree.reaction is None or y.app is x.app:
            return False
        return (self._channel is not None and self._channel.still()) or \
            (self._config.interrupt and self._cuttable(y, x))

    def _tell_cancelled(self, commands: list[Command]) -> None:
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
        """The driver reports an AB's end (MISSION.md rule 3, feedback iterations)."""
        node = self._wm.nodes.get(ab_id)
        if node is None or node.state is not NodeState.RUNNING:
            raise MediationError(f"AB{ab_id} is not running")
        with self._operation():
            self._end(node, outcome)

    def _end(self, node: Node, outcome: Outcome) -> None:
        if node.cutting and outcome.values.get("interrupted") is True \
                and not node.commands[0].cut:
            self._interrupted(node, outcome)
            return
        now = self._clock.now()
        wm = self._wm
        children = wm.end(node, now)
        self._holds.ended(node)
        detail = ""
        if node.feedback:
            detail = "terminal" if outcome.terminal else "not terminal"
        self._log.emit(DecisionKind.END, Rule.COMPLETED, node, detail=detail)
        app = node.app
        cmd0 = node.commands[0]
        ended: tuple[Command, ...] = ()
        cancelled: Command | None = None
        if node.feedback and not outcome.terminal and not cmd0.cut:
            children = [self._next_iteration(node, children)]
        elif node.feedback and not outcome.terminal:
            cancelled = cmd0
            cmd0.cancelled = True
            self._log.emit(DecisionKind.CANCEL, Rule.ASAP if app.alive else Rule.UNLOAD, node,
                           detail="feedback loop stopped between iterations")
            self._driver.abandon(cmd0.id)
        else:
            ended = node.commands
            self._intake.ended(ended, now)
        for child in children:
            if child.state is NodeState.PENDING:
                wm.enter_waiting(child, parent_finished=True)
        wm.leave(node)
        if cancelled is not None:
            self._tell_cancelled([cancelled])
        for cmd in ended:
            if not cmd.internal:
                self._tell(app, cmd.id, outcome)

    def _next_iteration(self, node: Node, children: list[Node]) -> Node:
        """Insert a feedback Command's next iteration between ``node`` and its children."""
        nxt = self._wm.new_node(node.app, node.tree, node.commands, node.devices,
                                node.priority, False, node.seq, node.iteration + 1)
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

    # ======================================================== streams, blocks
    def open_stream(self, app: str, hold: float) -> None:
        """Begin an explicit stream block (rule 6c): one CS, held while the app waits."""
        a = self._app(app)
        if self._holds.stream(a) is not None:
            raise MediationError(f"{app}: a stream is already open")
        if hold < 0:
            raise MediationError(f"{app}: stream hold must be >= 0, got {hold}")
        with self._operation():
            self._holds.open_stream(a, min(hold, self._config.max_stream_hold),
                                    self._latest_tree(a))

    def close_stream(self, app: str) -> None:
        """End the explicit stream block; its hold (if any) is released."""
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
        """The earliest pending hold timeout, watchdog or budget deadline, if any."""
        times = (self._holds.next_deadline(), self._fairness.next_deadline())
        return min((t for t in times if t is not None), default=None)

    def advance(self) -> None:
        """Handle every deadline that has passed, then run selection."""
        with self._operation():
            self._holds.expire(self._clock.now())
            self._fairness.expire()

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
