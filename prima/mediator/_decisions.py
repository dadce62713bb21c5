"""The decision record: every start, cancel, suspend and resume names its rule.

The mediator emits one :class:`Decision` per thing it decides, in order
(``seq`` increases by one). The interpreter/runner turns them into trace
lines, and golden files serialize :meth:`Decision.to_dict`, so the names of
:class:`Rule` and :class:`DecisionKind` members are part of the contract.
"""

from __future__ import annotations

import enum
from typing import NamedTuple

from prima.mediator._interface import AbId, Call, CommandId, TreeId

__all__ = ["Decision", "DecisionKind", "Rule"]


class DecisionKind(str, enum.Enum):
    """What the mediator decided."""

    LOAD = "load"
    """An application was registered (loaded)."""
    UNLOAD = "unload"
    """An application was unregistered (unloaded: EA swap, or it failed)."""
    REQUEST = "request"
    """A request was accepted: its Commands joined a tree (``rule`` says how)."""
    START = "start"
    """An AB was handed to the driver (``rule`` says why it won)."""
    END = "end"
    """The driver reported an AB's end."""
    CANCEL = "cancel"
    """A Command was cancelled before it started (or between feedback iterations)."""
    SUSPEND = "suspend"
    """A tree lost a device to another tree's AB and was pushed on the suspended stack."""
    RESUME = "resume"
    """An AB of a suspended tree started; the tree left the suspended stack."""
    HOLD = "hold"
    """Another app's stream hold or block keeps a waiting AB from its devices, or the
    channel rule keeps a CC-breaking AB waiting while the other app talks."""
    RELEASE = "release"
    """A stream hold or a block reservation ended."""
    FAILURE = "failure"
    """An application failed (its callback raised, or it overran a budget that
    fails it); the application is removed."""
    INTERRUPT = "interrupt"
    """A reaction's AB had the driver cut another application's running AB (the
    interrupt policy); the cut AB's end follows at a word boundary."""
    HEAR = "hear"
    """The robot heard its user outside a Q&A (docs/rules.md 7.5): which application takes
    the words (``rule`` says why), or that none does."""
    BUDGET = "budget"
    """An application's share of the others' waiting ran out (it loses its
    precedence for a while), or came back."""


class Rule(str, enum.Enum):
    """Why the mediator decided what it did (docs/rules.md section 5)."""

    # --- how a request joined working memory (rule 3, rule 6) ---------------
    NEW_TREE = "new-tree"
    """After latest, but the app's latest Command had left working memory: a new tree (CS)."""
    AFTER_LATEST = "after-latest"
    """Linked after the app's latest Command, still in working memory."""
    ASAP = "asap"
    """As soon as possible: the app's own trees sharing a device were cancelled."""
    END_EVENT = "end-event"
    """Made while handling a Command's end (``follows``), within the grace: same tree."""
    STREAM = "stream"
    """Inside an explicit stream or a begin/end block: continues its tree."""
    # --- why an AB started (rule 4) -----------------------------------------
    FREE_DEVICES = "free-devices"
    """The AB's devices were free and no other waiting AB wanted them."""
    PRIORITY = "priority"
    """It keeps the Communication Channel; the AB it beat breaks it."""
    EXCHANGE = "exchange"
    """It is an application's spoken reply to the answer of its own Q&A: it belongs to
    the exchange and goes before every other application's AB, reactions included
    (docs/rules.md 7.4)."""
    USER_FIRST = "user-first"
    """It belongs to a reaction to the user's own action (a touch, heard speech) that
    has not yet said its first utterance in full: another application's later reaction
    to a perception or network event does not overtake it (docs/rules.md 7.1)."""
    REACTIVITY = "reactivity"
    """It is the latest reactive AB (response speed)."""
    ANSWERING = "answering"
    """Its stream waits, on every device, while a reaction to the user's own action that
    interrupted it says its first words (a suspension, or a hold of a stream not yet
    under way; docs/rules.md 7.6 (1)): a guide does not drive on while it answers."""
    PARENT_FINISHED = "parent-finished"
    """Its before node just finished: it continues the active stream."""
    RESUME_STREAM = "resume-stream"
    """Its tree is the most recently suspended stream."""
    OLDEST = "oldest"
    """It belongs to the oldest request."""
    # --- policies (docs/mediator.md, Policies) --------------------------------
    INTERRUPT = "interrupt"
    """A reaction's AB cuts another application's running interruptible AB (an
    interrupt decision, and the cut AB's end)."""
    RESTART = "restart"
    """A cut AB starts again, from its beginning or, if its request says ``resume``,
    from the sentence it was cut in (its request and its start)."""
    BARGE_IN = "barge-in"
    """The user spoke over the robot's utterance: it is cut at a word boundary (an
    interrupt decision, and the cut AB's end; docs/rules.md 7.5)."""
    # --- who takes what the user says (docs/rules.md 7.5) ----------------------------
    STREAM_RUNS = "stream-runs"
    """The words go to the application whose stream runs, whose grammar takes them."""
    STREAM_SUSPENDED = "stream-suspended"
    """The words go to the application whose stream was suspended most recently, of
    those whose grammar takes them."""
    GRAMMAR = "grammar"
    """The words go to the first application (the FA, then the EAs as loaded) whose
    grammar takes them."""
    NOMATCH = "nomatch"
    """No application takes the words: every application sees a ``nomatch`` event; an
    utterance they cut goes on after the robot's pause (a false interruption)."""
    BACKCHANNEL = "backchannel"
    """The user only showed they follow (the robot profile's backchannels): the robot
    talks on."""
    BLEND = "blend"
    """An AB started over another running AB on a device they share, as the robot
    profile declares (a local motion over a global one, speech over quieter sound)."""
    RESTORE_STATE = "restore-state"
    """The mediator returns the robot to the pose a stream was suspended in before
    the stream resumes, in that stream (a request and a start of its own)."""
    CONNECT_CHANNEL = "connect-channel"
    """The mediator turns the robot to the user before an utterance that would start
    facing away from them, in the same stream (a request and a start of its own)."""
    # --- ends -----------------------------------------------------------------
    COMPLETED = "completed"
    """The driver reported the AB done (terminal, or not for a feedback iteration)."""
    # --- holds and blocks (rule 3 grouping, rule 6c) --------------------------
    STREAM_HOLD = "stream-hold"
    """Another app's open stream holds the devices while it waits (non-reactive ABs wait)."""
    HOLD_TIMEOUT = "hold-timeout"
    """A stream hold ended: the stream stayed idle for its hold time."""
    STREAM_CLOSE = "stream-close"
    """A stream hold ended: the app closed the stream."""
    BLOCK = "block"
    """Another app's begin/end block reserves the devices (reactive ABs wait too)."""
    RESERVED = "reserved"
    """Its devices are kept for the next AB of another application's reaction (or
    reply) that outranks it, even while that next AB cannot start yet: it waits for
    the reaction's own StopMoving, or for a turn to the user (docs/rules.md 7.1)."""
    KEEP_CHANNEL = "keep-channel"
    """It would break the Communication Channel while another app talks with the user:
    it waits until that talk ends (thesis Sec. 3.3, Fig. 3.3)."""
    BLOCK_CLOSE = "block-close"
    """A block reservation ended: the app closed the block."""
    WATCHDOG = "watchdog"
    """A block reservation ended: the block ran longer than its watchdog."""
    # --- applications (rule 7) ----------------------------------------------
    REGISTER = "register"
    """The application was loaded."""
    UNLOAD = "unload"
    """The application was unloaded: its waiting work is cancelled, holds freed."""
    APP_FAILURE = "app-failure"
    """The application's callback raised; it is unloaded, the other app goes on."""
    # --- budgets (the robot profile's <budgets>) -------------------------------
    WAIT_SHARE = "wait-share"
    """The application kept the others waiting beyond its wait share: it loses its
    precedence for one window (its ABs rank after the others', its holds hold
    nothing); or it regains it. As a start's reason: the AB won because the other
    application had lost its precedence."""
    STARTS_PER_INSTANT = "starts-per-instant"
    """The application started more ABs at one instant than its budget allows
    (Commands that take no time, requested again and again): it is unloaded."""


class Decision(NamedTuple):
    """One decision, with the rule that made it.

    An immutable record, built with keywords. A named tuple rather than a frozen
    dataclass: the mediator makes one for everything it decides, on its hot
    path, and a named tuple is built three times faster.
    """

    t: float
    seq: int
    kind: DecisionKind
    rule: Rule
    app: str | None = None
    ab: AbId | None = None
    tree: TreeId | None = None
    command: str | None = None
    """Command name; ``A+B`` for a grouped AB."""
    command_id: CommandId | None = None
    """The first (usually only) Command of the AB."""
    command_ids: tuple[CommandId, ...] = ()
    devices: tuple[str, ...] = ()
    """Sorted device names."""
    reactive: bool = False
    iteration: int = 0
    label: str | None = None
    """The author's label of the (first) Command, if any."""
    detail: str = ""
    calls: tuple[Call, ...] = ()
    """The AB's Commands with their arguments (a request: all its Commands); not part
    of ``to_dict``."""
    before: AbId | None = None
    """A request: the AB its root follows (its before node), if any. A hold for a
    reaction's next AB (rule ``reserved``): that next AB."""
    precedes: CommandId | None = None
    """A policy's request: the Command it was put before (it runs first)."""

    def to_dict(self) -> dict[str, object]:
        """A JSON-ready dict with a stable key order."""
        return {
            "t": self.t,
            "seq": self.seq,
            "kind": self.kind.value,
            "rule": self.rule.value,
            "app": self.app,
            "ab": self.ab,
            "tree": self.tree,
            "command": self.command,
            "command_id": self.command_id,
            "command_ids": list(self.command_ids),
            "devices": list(self.devices),
            "reactive": self.reactive,
            "iteration": self.iteration,
            "label": self.label,
            "detail": self.detail,
        }

    def __str__(self) -> str:
        parts = [f"t={self.t:g}", self.kind.value]
        if self.app is not None:
            parts.append(self.app)
        if self.ab is not None:
            parts.append(f"AB{self.ab}")
        if self.command is not None:
            parts.append(self.command)
        if self.iteration:
            parts.append(f"#{self.iteration}")
        parts.append(f"[{self.rule.value}]")
        if self.detail:
            parts.append(self.detail)
        return " ".join(parts)
