"""PRIMA's shared vocabulary: value types, roles, running orders, events, bounds.

Every package speaks these words, so they live here, in a module that imports
nothing heavy (no lxml, lark or pymunk): loading a document does not import the
mediator, and the mediator does not import the DSL, to learn what an EA is.
"""

from __future__ import annotations

import enum
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from types import MappingProxyType

from prima.record import Record

__all__ = [
    "TraceKind",
    "MAX_BLOCK_WATCHDOG",
    "MAX_EAS",
    "MAX_NUMBER",
    "MAX_RUN_TIME",
    "MAX_SEED",
    "MAX_STREAM_HOLD",
    "MAX_TEXT",
    "EVENT_FIELDS",
    "PREDEFINED_EVENTS",
    "INTERRUPTED_EVENT",
    "NEWS_EVENTS",
    "MAX_NEWS_PER_INSTANT",
    "SPEECH_EVENT",
    "NOMATCH_EVENT",
    "ANSWERED",
    "OnInterrupt",
    "DEFAULT_BUDGETS",
    "FACE_TOLERANCE",
    "RESTORE_ANGLE",
    "RESTORE_DISTANCE",
    "POLICIES",
    "AppKind",
    "Budgets",
    "Policy",
    "policy_settings",
    "registered_policy",
    "RunningOrder",
    "Value",
]

Value = str | float | int | bool | None
"""A runtime value: what expressions produce and Commands take as arguments."""


class AppKind(str, enum.Enum):
    """Which role an application plays."""

    FA = "fa"
    """Familiarity-oriented: the robot's own, resident application."""
    EA = "ea"
    """Environment-oriented: loaded from the building the robot visits."""


class TraceKind(str, enum.Enum):
    """What a run records besides the mediator's decisions (which keep their own
    kinds: load, unload, request, start, end, cancel, suspend, resume, hold,
    release, failure, budget). Applications report some of these through their
    interpreter (state, handler, timer, stream, block, send, log, error)."""

    EVENT = "event"
    """PRIMA posted an event to the applications (a reactive cause)."""
    USER = "user"
    """The user did something (``action``: say, touch, walk, ...)."""
    ERROR = "error"
    """An application failed; it is unloaded, the others go on."""
    SEND = "send"
    """An application sent a message to the environment's server."""
    LOG = "log"
    """An application's ``<log>`` line."""
    POSE = "pose"
    """Where the robot and the user are, sampled at a fixed rate."""
    STATE = "state"
    """An application entered a state."""
    HANDLER = "handler"
    """One of an application's handlers ran (which, and where it is written)."""
    TIMER = "timer"
    """One of an application's timers fired."""
    STREAM = "stream"
    """An application entered (``open``) or left (``close``) an explicit stream."""
    BLOCK = "block"
    """An application entered (``open``) or left (``close``) a begin/end block."""
    ZONE = "zone"
    """The robot entered a zone of the scenario (which loads its EA)."""


class RunningOrder(str, enum.Enum):
    """How a request links to the application's earlier requests (thesis 4.2(5))."""

    AFTER_LATEST = "after-latest"
    """Run after the app's latest Command if that is still in working memory."""
    ASAP = "asap"
    """Cancel the app's own trees that share a device, then start as soon as possible."""


PREDEFINED_EVENTS: Mapping[str, str] = MappingProxyType({
    "human-found": "the camera sees the user (data: distance)",
    "human-lost": "the camera lost sight of the user",
    "sound-heard": "a sound the robot recognises, e.g. a tune (data: sound)",
    "message": "a network message arrived from the environment's server (data: sender, text)",
    "place-reached": "a place on the map was reached while moving (data: place, kind)",
    "interrupted": "one of the application's own atomic behaviors was cut, for the other "
                   "application's reaction or by the user speaking over it (data: command, "
                   "label, spoken, unspoken, restarts, resumes, by, reason); not reactive",
    "speech": "the user said something outside a Q&A that this application's always-on "
              "grammar took (data: words, answer, grammar); the user's own action",
    "nomatch": "the user said something that no application took (data: words); every "
               "application sees it; not reactive",
    "suspended": "the application's stream lost its devices to another application's "
                 "atomic behavior (data: by, rule); not reactive",
    "resumed": "the application's suspended stream goes on (data: rule); not reactive",
    "held": "one of the application's atomic behaviors is held back by another "
            "application (data: by, rule); not reactive",
})
"""Events every robot posts, FA and EA alike; all are reactive but the news of
:data:`NEWS_EVENTS`."""

ANSWERED = "answered"
"""The ``status`` with which a Command that listens (a Q&A) ends when the user
answered it (the others: ``noinput``); its ``utterance`` holds the words."""

EVENT_FIELDS = frozenset({
    # every event, and the predefined events' data
    "name", "distance", "sound", "sender", "text", "place", "kind", "command", "label",
    "spoken", "unspoken", "restarts", "resumes", "by", "reason", "rule", "words",
    "grammar",
    # a Q&A's answer
    "utterance", "answer", "status",
    # what Commands end with (their end handlers' event)
    "error", "result", "angle", "blended", "blocked", "duration", "found", "gesture", "goal",
    "heading", "lost", "pan", "picture", "reached", "remaining", "saw_user", "sways", "tilt",
    "toward", "turned", "unseen", "waiting", "x", "y",
})
"""Every field an event of PRIMA's own carries (``event.field``): a field outside them
is null unless a scenario's ``<event>`` sends it, so ``prima validate`` warns of it (a
misspelling: ``event.eror == null`` is always true)."""

INTERRUPTED_EVENT = "interrupted"
"""The event an application gets when the interrupt policy or the user's barge-in cut
one of its atomic behaviors (news about the application's own Command: not reactive)."""

TOUCH_EVENT = "touched"
"""The event a touch sensor posts (a robot-specific event the simulator raises when the
user touches the robot): always the user's own action (docs/rules.md 7.1), whatever a
profile says."""

USER_ACTION_EVENTS = frozenset({TOUCH_EVENT})
"""Events that are the user's own action on every robot: a profile may name more
(``<event user="true">``), never fewer (docs/rules.md 7.1)."""

SPEECH_EVENT = "speech"
"""What the robot heard the user say outside a Q&A, given to the one application whose
always-on grammar takes it (docs/rules.md 7.5): reactive, the user's own action."""

NOMATCH_EVENT = "nomatch"
"""What the robot heard the user say that no application took: every application
sees it, not reactive."""

MAX_NEWS_PER_INSTANT = 20
"""Most news events (suspended, resumed, held) one application is told at one simulated
instant: an application whose news handlers make requests that are held or suspended
again cannot keep the robot at that instant forever; later news of that instant is
not told (its decisions are in the trace all the same)."""

NEWS_EVENTS = frozenset({INTERRUPTED_EVENT, NOMATCH_EVENT, "suspended", "resumed", "held"})
"""The predefined events that are not reactive: news about the application's own
Commands and stream, or speech no application took."""


class OnInterrupt(str, enum.Enum):
    """What a request says of its atomic behaviors under the interrupt policy and the
    user's barge-in."""

    RESTART = "restart"
    """They may be cut for another application's reaction, and then start again
    from their beginning after it (the default)."""
    RESUME = "resume"
    """They may be cut, and then go on after the reaction from the beginning of the
    sentence their first unspoken word falls in."""
    DROP = "drop"
    """They may be cut, and then are dropped: their Command ends, interrupted."""
    NEVER = "never"
    """They are never cut."""

MAX_STREAM_HOLD = 30.0
"""Upper bound on an explicit stream's hold (s), whatever a document asks: the
other application's response speed stays bounded (rule 6c)."""

MAX_ANSWER_HOLD = 30.0
"""Upper bound (s) on how long a reaction to the user's own action keeps the streams it
interrupted waiting on every device before it has said its first words (docs/rules.md
7.6 (1)): a reaction whose words never come cannot hold the others for ever."""

MAX_BLOCK_WATCHDOG = 60.0
"""Upper bound on a begin/end block's watchdog (s), whatever a document asks: a
runaway block cannot starve the other application (rule 3)."""

MAX_EAS = 4
"""Most EAs running at once (a building's guide beside a shop's app), besides the
one FA. Each EA has its own budgets (one EA's), so what all of them may consume
together stays bounded; a scenario or a zone asking for more is an error."""

MAX_TEXT = 10_000
"""Longest text an application may build or say (characters)."""

MAX_RUN_TIME = 1_000_000.0
"""Longest simulated run (s, about eleven and a half days): a scenario's ``until``."""

MAX_SEED = 2**63 - 1
"""Largest random seed (a scenario's ``seed``, ``--seed``)."""

MAX_NUMBER = 2.0 ** 53
"""Largest magnitude of a number (beyond it, integers lose exactness anyway)."""


@dataclass(frozen=True, repr=False, eq=False)
class Budgets(Record):
    """What one application may consume; a robot profile's ``<budgets>`` sets them.

    An EA is written by a stranger, so every resource an application can use is
    bounded. Exceeding a budget is a trace line with its reason; the other
    application goes on. Every field has a documented default (docs/robot-profile.md).
    """

    text: int = MAX_TEXT
    """Longest text one application may say, send or log (characters), literal
    or computed; at most :data:`MAX_TEXT`. Longer: the application fails."""
    sends_per_second: float = 5.0
    """Messages an application may send to the environment's servers per simulated
    second (counted over the last second). More: the message is dropped."""
    waiting: int = 200
    """Commands one application may have in working memory, not yet ended. More:
    the application fails."""
    longest_ab: float = 60.0
    """Longest single atomic behavior (s): an utterance, a Q&A's wait for an
    answer, one motion. Longer: the Command ends at once with an error."""
    wait_share: float = 30.0
    """Seconds, within any ``wait_window``, that an application's running behaviors,
    holds, blocks and streams may keep another application's ready behaviors
    waiting (priority aside). Beyond it, the application loses its precedence for
    one window: its holds are released and its behaviors rank after the others'."""
    wait_window: float = 60.0
    """The window of ``wait_share`` (s)."""
    starts_per_instant: int = 100
    """Atomic behaviors one application may start at one simulated instant
    (Commands that take no time, requested again and again). More: it fails."""


DEFAULT_BUDGETS: Mapping[AppKind, Budgets] = MappingProxyType({
    AppKind.FA: Budgets(wait_share=300.0, wait_window=360.0),
    AppKind.EA: Budgets(),
})
"""The budgets of each role when the robot profile sets none. The EA, written by a
stranger, may keep the FA waiting 30 s a minute; the FA, the robot's own acting
for its user (following them, say), five minutes out of six."""


@dataclass(frozen=True, repr=False, eq=False)
class Policy(Record):
    """A mediation policy (docs/rules.md 7.3): one of the thesis' future functions,
    switched by the robot profile, the scenario and ``prima run --policy``."""

    name: str
    default: bool
    """On unless switched off."""
    summary: str
    config: str | None = None
    """The field of the mediator's configuration (:class:`prima.mediator.MediatorConfig`)
    it switches, if any: :func:`prima.scenario.mediator_config` maps every policy there,
    and the field defaults to :attr:`default` (``prima.mediator``'s ``policy_default``)."""
    sim: str | None = None
    """The simulator's switch it sets, if any (:class:`prima.run.Run` sets it)."""


_POLICIES: dict[str, Policy] = {p.name: p for p in (
    Policy("restore-state", True, "a suspended stream, resumed with the robot moved "
                                  "away, first returns to the pose it was suspended in "
                                  "(thesis Sec. 5.3 (1))",
           config="restore_state"),
    Policy("interrupt", False, "a reaction cuts the other application's running atomic "
                               "behavior (an utterance at a word boundary, a gesture, a "
                               "feedback iteration); it restarts after the reaction. On "
                               "by default on a robot whose profile declares "
                               "<interruptible> (thesis Sec. 5.3 (2))",
           config="interrupt"),
    Policy("blend", False, "declared local motions run over a global motion, and "
                           "speech over quieter sound, on a shared device, the robot "
                           "staying within a bound of its user; on by default on a "
                           "robot whose profile declares <blend> (thesis Sec. 5.3 (5))",
           config="blend"),
    Policy("streams", True, "explicit stream blocks in the applications' documents keep "
                            "a Communication Stream together (thesis Sec. 5.3 (3))",
           config="streams"),
    Policy("connect-channel", True, "before an utterance would start facing away from a "
                                    "detectable user, the robot turns to them first "
                                    "(thesis Sec. 5.3 (4))",
           config="connect_channel"),
    Policy("reactions", True, "a reaction keeps the devices its next atomic behavior "
                              "needs, and a reaction to the user's own action (a touch, "
                              "heard speech) goes before another application's later "
                              "reaction to a perception or network event until it has "
                              "said its first words",
           config="reactions"),
    Policy("barge-in", False, "the robot hears its user at any time, not only while a "
                              "Q&A listens: what it hears goes to the application whose "
                              "always-on grammar takes it, and speech over the robot's "
                              "utterance cuts it at a word boundary (a backchannel does "
                              "not); on by default on a robot whose profile declares "
                              '<hearing always="true"> (thesis Sec. 5.3: stop and answer '
                              "at once)",
           config="barge_in", sim="hears_always"),
    Policy("exchange", True, "the words with which an application replies to the answer "
                             "of its own Q&A go before every other application's talk, "
                             "reactions included, and are never cut",
           config="exchange"),
)}

POLICIES: Mapping[str, Policy] = MappingProxyType(_POLICIES)
"""Every policy, by name: the registry every reader of policies goes through (the
profile's and the scenario's switches, ``--policy``, the mediator's configuration
(:attr:`Policy.config`), the simulator's switches (:attr:`Policy.sim`)). ``all`` names
them together in a switch; :func:`registered_policy` adds one for a while."""


@contextmanager
def registered_policy(policy: Policy) -> Iterator[None]:
    """While inside, ``policy`` is a policy like the others (after them): ``--policy``
    switches it, runs layer it, and it switches its :attr:`~Policy.config` field and its
    :attr:`~Policy.sim` switch. For a policy tried out, or a test's scratch one."""
    if policy.name in _POLICIES or policy.name == "all":
        raise ValueError(f"there is a policy {policy.name!r} already")
    _POLICIES[policy.name] = policy
    try:
        yield
    finally:
        del _POLICIES[policy.name]

FACE_TOLERANCE = 30.0
"""Degrees between the robot's heading and its bearing to the user beyond which it
does not face them (the connect-channel policy, and the judge's talking unfaced)."""


RESTORE_DISTANCE = 0.3
"""Metres the robot may have moved since a stream was suspended before the
restore-state policy drives it back when the stream resumes."""

RESTORE_ANGLE = 20.0
"""Degrees the robot may have turned since a stream was suspended before the
restore-state policy turns it back when the stream resumes."""


def policy_settings(*layers: Mapping[str, bool]) -> dict[str, bool]:
    """Every policy's state: the defaults, then each layer of switches in turn (a
    profile's, a scenario's, the command line's); ``all`` in a layer switches every
    policy before that layer's named ones. Names are checked where they are read."""
    out = {name: p.default for name, p in POLICIES.items()}
    for layer in layers:
        if "all" in layer:
            out = dict.fromkeys(out, layer["all"])
        out.update((name, on) for name, on in layer.items() if name in out)
    return out
