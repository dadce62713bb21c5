"""The mechanisms of the mediation policies that act when the selector weighs an AB
(docs/rules.md 7.3): restore-state and connect-channel put an AB of the mediator's own
before a ready one; blend lets one share devices with a running AB; interrupt has
the driver cut a running one. What the interrupt policy does when the cut AB ends
is the mediator's (:meth:`Mediator._interrupted`): it needs the applications.

The run answers the questions about the robot (:class:`Channel`); the mediator
never looks at poses itself.
"""

from __future__ import annotations


from prima.catalog import (
    BODY_DEVICE,
    CONNECT_COMMAND,
    RESTORE_COMMAND,
    RESTORE_POSITION_COMMAND,
    Catalog,
    Priority,
)
from prima.mediator._config import MediatorConfig
from prima.mediator._decisions import DecisionKind, Rule
from prima.mediator._holds import Holds
from prima.mediator._intake import Intake
from prima.mediator._interface import Call, Channel, Driver
from prima.mediator._log import DecisionLog
from prima.mediator._memory import WorkingMemory
from prima.mediator._ranking import preempts
from prima.mediator._state import Node, Tree
from prima.vocab import OnInterrupt


__all__ = ["Policies"]


class Policies:
    """What the policies decide about one AB the selector weighs; each decision is a
    decision record with the policy's own rule."""

    def __init__(self, catalog: Catalog, config: MediatorConfig, channel: Channel | None,
                 wm: WorkingMemory, intake: Intake, holds: Holds, log: DecisionLog,
                 driver: Driver) -> None:
        self._catalog = catalog
        self._config = config
        self._channel = channel
        """Asked when a stream is suspended and before a resumed stream or an utterance
        starts (restore-state, connect-channel), and for a blend's bound; None: those
        policies are off."""
        self._wm = wm
        self._intake = intake
        self._holds = holds
        self._log = log
        self._driver = driver
        self._cuts = config.interrupt and any(
            c.interruptible for c in catalog.commands.values())
        """The interrupt policy is on and the catalog has Commands it may cut: else
        it never acts (:meth:`cuttable` is false for every AB)."""
        self._blends = config.blend and bool(catalog.blends)
        """The blend policy is on and the catalog declares blends."""
        self.on_busy = self._blends or self._cuts
        """Some policy may act on busy devices for some AB (:meth:`acts_on_busy` is
        false for every AB otherwise)."""
        self._blend_devices = frozenset().union(*(b.devices for b in catalog.blends)) \
            if self._blends else frozenset()
        """The devices a declared blend shares (no other is ever shared)."""

    def suspending(self, tree: Tree) -> None:
        """A tree is suspended: remember where the robot is (restore-state)."""
        if self._channel is not None and self._config.restore_state:
            tree.pose = self._channel.pose()

    def prepare(self, x: Node) -> bool:
        """The ready AB ``x`` is about to start: put a policy's AB before it? True if it
        now waits for one (a return to the pose its stream was suspended in, then a
        turn to the user)."""
        tree = x.tree
        if x.looked != tree.suspensions:
            x.looked = tree.suspensions  # its stream was suspended since it was last looked
            x.turnable = x.faces  # at: whether it faces the user, anew
        elif x.faced_at is not None and x.faced_at < self._log.now:
            # It waited (for the speaker) after its turn: the user may have walked off
            # meanwhile. Face first, or wait (docs/rules.md 7.6 (3)): looked at anew, once.
            x.faced_at = None
            if not x.relooked:
                x.relooked = True
                x.turnable = x.faces
        if tree.pose is not None and self._restore(x):
            return True
        if x.turnable and self._connect(x):
            return True  # (the pose is looked at again when the turn has been made)
        if tree.pose is not None and x.speaks:
            tree.pose = None  # the resumed stream's first words start here
        return False

    def _restore(self, x: Node) -> bool:
        """The restore-state policy: ``x`` resumes its suspended stream with the robot
        moved away from where it was suspended, so a return to that pose goes first,
        in the stream. Not before an AB that takes the robot somewhere itself (a move,
        following the user), and once per suspension. Before an AB that turns or aims
        the robot itself (a FaceHumanAndSpeak, a SetDirection toward its panel), only
        the position is restored. The return waits
        for the wheels like any AB of the resumed stream. Before an utterance that the
        connect-channel policy may turn the robot to the user for, likewise."""
        pose = x.tree.pose
        if pose is None or self._channel is None:
            return False
        if any(c.spec.travels for c in x.commands):
            x.tree.pose = None  # the stream takes the robot somewhere itself
            return False
        if not x.speaks:
            return False  # (a StopMoving, a gesture: the pose is looked at before its words)
        command = RESTORE_COMMAND
        if BODY_DEVICE in x.devices or x.faces or any(c.spec.aims for c in x.commands):
            # it turns or aims the robot itself (at its panel, say), or the connect-channel
            # policy will turn it to the user before its words: the heading it had then
            # does not matter, where it stood does
            command = RESTORE_POSITION_COMMAND
            pose = {k: v for k, v in pose.items() if k != "heading"}
        spec = self._catalog.get(command)
        if spec is None or not self._channel.displaced(pose):
            return False
        x.tree.pose = None  # (once per suspension)
        call = Call(command, pose)
        self._intake.insert_before(x, call, spec, Rule.RESTORE_STATE,
                                   f"returns to the pose its stream was suspended in "
                                   f"before AB{x.id}")
        return True

    def _connect(self, x: Node) -> bool:
        """The connect-channel policy: before the ready utterance ``x`` starts facing
        away from a detectable user, put a turn to the user before it, in its stream
        (once per AB). Face first, or wait (docs/rules.md 7.6 (3)): an utterance never
        starts unfaced to be early. The turn waits for the wheels in line, as any AB of
        its stream; a reaction's turn cuts what the interrupt policy lets it cut there
        (:meth:`cuttable`). True if it now waits for the turn."""
        x.turnable = False
        spec = self._catalog.get(CONNECT_COMMAND)
        if self._channel is None or spec is None or not self._config.connect_channel \
                or not (self._channel.unfaced() or self._driven_away(x, spec.devices)):
            return False
        self._intake.insert_before(x, Call(CONNECT_COMMAND), spec, Rule.CONNECT_CHANNEL,
                                   f"turns to the user before AB{x.id}")
        return True

    def _driven_away(self, x: Node, wheels: frozenset[str]) -> bool:
        """Whether another application's AB that breaks the channel (a move, a return to
        a pose) holds the wheels the turn to the user needs: faced now, the robot would
        be turned away while ``x``'s words run, so they face first, or wait (docs/rules.md
        7.6 (3))."""
        busy = self._wm.busy
        for d in wheels:
            y = busy.get(d)
            if y is not None and y.app is not x.app and y.priority is Priority.LOW:
                return True
        return False

    def keep_facing(self) -> tuple[Node, Node] | None:
        """The connect-channel policy while words run (docs/rules.md 7.6 (3): the robot
        keeps facing the user while its words run): the user went off to the side while
        an utterance addressed to them is under way; if the wheels are free, a turn to
        the user runs beside its words, in its stream. The words' AB and the turn, if
        put, are returned."""
        spec = self._catalog.get(CONNECT_COMMAND)
        if self._channel is None or spec is None or not self._config.connect_channel:
            return None
        busy = self._wm.busy
        if any(d in busy for d in spec.devices):
            return None  # (what holds the wheels turns the robot as it will: its doing)
        talking = sorted({n.id: n for n in busy.values() if n.speaks and n.faces}.items())
        if not talking or not self._channel.unfaced():
            return None
        x = talking[0][1]
        return x, self._intake.beside(x, Call(CONNECT_COMMAND), spec, Rule.CONNECT_CHANNEL,
                                      f"keeps facing the user while AB{x.id} speaks")

    def acts_on_busy(self, x: Node) -> bool:
        """Whether a policy may act for ``x`` on busy devices: share them (blend) or
        cut what runs there (interrupt, for a reaction's AB)."""
        return self._blends or (self._cuts and x.tree.reaction is not None)

    def may_act_on(self, device: str) -> bool:
        """Whether a policy could act for an AB waiting for the busy ``device``, as far
        as that device goes: blend it over what runs there (a declared blend shares
        the device) or cut what runs there (its Commands are all interruptible). When
        False, neither :meth:`blend` nor :meth:`cut` does anything for an AB that needs
        the device, whichever it is."""
        if device in self._blend_devices:
            return True
        return self._cuts and all(c.spec.interruptible
                                  for c in self._wm.busy[device].commands)

    def blend(self, x: Node) -> tuple[frozenset[str], bool] | None:
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

    def cut(self, x: Node) -> None:
        """The interrupt policy: the reaction's AB ``x`` ranks best on its devices but
        some are busy. If every AB running on them is another application's and may
        be cut (its Commands are interruptible on this robot, its request allows it,
        no block of its application keeps its devices), have the driver cut them."""
        if not self._cuts:
            return
        busy = self._wm.busy
        running = sorted({busy[d] for d in x.devices if d in busy}, key=lambda y: y.id)
        if not running or not all(self.cuttable(y, x) for y in running):
            return
        for y in running:
            if not y.cutting and self._driver.cut(y.id):
                y.cutting = True
                y.cut_by, y.cut_for = x.app, x
                self._log.emit(DecisionKind.INTERRUPT, Rule.INTERRUPT, y,
                               detail=f"for {x.app.name}'s reaction (AB{x.id})", before=x.id)

    def cuttable(self, y: Node, x: Node) -> bool:
        """Whether the reaction's AB ``x`` may cut the running ``y`` (docs/rules.md 7.3 (2)):
        another application's, outranked, of interruptible Commands its request lets
        be cut, in no block, not blended; never a reply to an answer (7.4), and never
        twice by another application (a restart is not cut again). A reaction to the
        user's own action turning to the user may cut its own application's other
        stream there too (7.6 (1) and (3): a search's sweep, a gesture). A feedback
        iteration whose loop its own application stopped (with an as-soon-as-possible
        request that now waits behind it) may be cut all the same: 7.3 (2) lets a
        reaction cut a feedback iteration whatever waits behind it, and the cut ends the
        loop there, as the iteration's own end would have (it is not started again)."""
        if y.once or y.protected or not preempts(x, y):
            return False
        if y.app is x.app and not (y.tree is not x.tree and x.tree.user
                                   and x.commands[0].internal is Rule.CONNECT_CHANNEL):
            return False
        if y.blended or any(d in self._wm.blending for d in y.devices):
            return False  # blended ABs are never cut
        if not all(c.spec.interruptible and c.on_interrupt is not OnInterrupt.NEVER
                   for c in y.commands):
            return False
        block = self._holds.block(y.app)
        return block is None or not (block.devices & y.devices)
