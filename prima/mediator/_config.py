"""The mediator's tunable bounds and policy switches: in a module of their own, which
the mediator's parts (intake, policies, rounds) read without importing the mediator.

Each policy switch defaults to its policy's default in the registry
(:data:`prima.vocab.POLICIES`, :func:`policy_default`): a mediator made without a
configuration mediates as a run whose profile and scenario switch no policy."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from prima.vocab import (
    DEFAULT_BUDGETS,
    MAX_ANSWER_HOLD,
    MAX_BLOCK_WATCHDOG,
    MAX_EAS,
    MAX_STREAM_HOLD,
    POLICIES,
    AppKind,
    Budgets,
)

__all__ = ["MediatorConfig", "policy_default"]


def policy_default(config: str) -> bool:
    """The default of the policy that switches the configuration's field ``config``
    (:attr:`prima.vocab.Policy.config`): the one place a policy's default is written."""
    found = [p.default for p in POLICIES.values() if p.config == config]
    if len(found) != 1:
        raise LookupError(f"{len(found)} policies switch the mediator's {config!r}")
    return found[0]


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

    max_answer_hold: float = MAX_ANSWER_HOLD
    """Upper bound on how long a reaction to the user's own action keeps the streams it
    interrupted waiting on every device before its first words have been said
    (docs/rules.md 7.6 (1)): words that never come cannot hold the others for ever."""

    max_block_watchdog: float = MAX_BLOCK_WATCHDOG
    """Upper bound on a begin/end block's watchdog, whatever the document asks:
    a runaway block cannot starve the other application (rule 3)."""

    streams: bool = policy_default("streams")
    """The streams policy (docs/rules.md 6c): explicit stream blocks keep a Communication
    Stream together. Off, :meth:`Mediator.open_stream` and :meth:`Mediator.close_stream`
    do nothing: stream blocks are plain sequences (the thesis' PRIMA, which had begin/end
    blocks of an AB, thesis Sec. 4.1 (2), but no explicit Communication Streams)."""

    connect_channel: bool = policy_default("connect_channel")
    """The connect-channel policy (docs/rules.md 7.3 (4)), when there is a channel."""

    restore_state: bool = policy_default("restore_state")
    """The restore-state policy (docs/rules.md 7.3 (1)), when there is a channel."""

    blend: bool = policy_default("blend")
    """The blend policy (docs/rules.md 7.3 (5)): on the blends the catalog declares (the
    robot profile's ``<blend>``)."""

    interrupt: bool = policy_default("interrupt")
    """The interrupt policy (docs/rules.md 7.3 (2)): on the Commands the catalog says are
    interruptible (the robot profile's ``<interruptible>``)."""

    reactions: bool = policy_default("reactions")
    """The reactions policy (docs/rules.md 7.1): a reaction keeps the devices its next AB
    needs; a reaction to the user's own action goes first until it has said its first
    words."""

    exchange: bool = policy_default("exchange")
    """The exchange policy (docs/rules.md 7.4): an application's spoken reply to the answer
    of its own Q&A goes before every other application's AB on its devices, and is
    never cut."""

    barge_in: bool = policy_default("barge_in")
    """The barge-in policy (docs/rules.md 7.5): what the user says outside a Q&A
    (:meth:`Mediator.hear`) cuts the robot's utterance under way at a word boundary,
    unless it is a backchannel."""

    resume_pause: float = 0.6
    """Seconds after which an utterance cut by words no application took goes on (a
    false interruption: the robot profile's ``<hearing resume-after>``)."""

    max_eas: int = MAX_EAS
    """Most EAs registered at once (besides the one FA): each has its own budgets."""

    budgets: Mapping[AppKind, Budgets] = field(default_factory=lambda: DEFAULT_BUDGETS)
    """What one application of each role may consume (the robot profile's
    ``<budgets>``): the mediator enforces ``waiting``, ``starts_per_instant`` and
    the wait share."""
