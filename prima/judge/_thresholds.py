"""How much of each fault a run may show, and the measures' parameters.

This module is what ``prima --help`` and tab completion read (the threshold options of
``prima judge`` and ``prima sweep`` are made from :data:`LIMITS` and :data:`PARAMETERS`):
it imports nothing of the judge itself."""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from prima.vocab import FACE_TOLERANCE, RESTORE_DISTANCE

__all__ = ["LIMITS", "PARAMETERS", "Limit", "Parameter", "Thresholds"]


@dataclass(frozen=True)
class Limit:
    """What one measure of naturalness is called and what its threshold counts (its
    finder is :class:`prima.judge.Measure`'s)."""

    key: str
    """The report's key, the threshold ``max_<key>`` and the option ``--max-<key>``."""
    title: str
    """Its name in reports and ``prima sweep``'s table (its row)."""
    allowed: str
    """What its threshold counts (``--help``)."""
    finds: str
    """What it finds, in a sentence (the docs)."""

    @property
    def limit(self) -> str:
        """Its threshold's name, a keyword of :class:`Thresholds`."""
        return f"max_{self.key}"

    @property
    def option(self) -> str:
        return f"--max-{self.key.replace('_', '-')}"


LIMITS: tuple[Limit, ...] = (
    Limit("late", "late reactions", "late reactions allowed",
          "a reaction that starts, or says its first words, later than the mediation "
          "rules allow: free to start for more than the slack"),
    Limit("unheard", "unheard reactions", "reactions never heard allowed",
          "a reaction whose words are never heard whole (cut and never said again, or "
          "never said)"),
    Limit("unfaced", "talking unfaced", "utterances unfaced allowed",
          "an utterance said while the user is detectable and more than the tolerance "
          "off the robot's heading: at its start, or for more than a second in a row "
          "while its words run"),
    Limit("leaving", "leaving while talking", "leavings while talking allowed",
          "the robot moving away from the user on its own while words addressed to "
          "them run (following the user is not leaving)"),
    Limit("elsewhere", "resumed elsewhere",
          "streams resumed away from where they were suspended allowed",
          "a resumed stream's first utterance spoken away from where it was suspended"),
    Limit("splits", "split exchanges", "split exchanges allowed",
          "another application's utterance inside an exchange (7.4) or an explicit "
          "stream"),
    Limit("silences", "silences", "silences after an answer allowed",
          "no robot output for longer than the silence after a user's answer"),
    Limit("barge_in", "talking over the user", "utterances run on over the user allowed",
          "the robot's words running on after its user began to speak over them for more "
          "than the barge-in slack plus the word under way (a backchannel excepted)"),
    Limit("ignored", "ignored speech", "ignored user speech allowed",
          "user speech an application took and did not answer: its first words in reply "
          "began more than the answer slack after what the rules put before them"),
    Limit("recovery", "unrecovered interruptions", "false interruptions not recovered "
          "allowed",
          "an utterance cut by user speech that no application took (a false "
          "interruption: a cough) that did not go on within the robot's pause plus the "
          "slack"),
    Limit("stuck", "stuck", "stuck applications allowed",
          "an application whose Commands cannot start, that searches for a user it "
          "never sees, or an atomic behavior that never ends"),
)
"""Every measure, in the order reports show them (:data:`prima.judge.MEASURES` gives
each its finder)."""


@dataclass(frozen=True)
class Parameter:
    """One parameter of the measures: a keyword of :class:`Thresholds` and an option of
    ``prima judge`` and ``prima sweep``."""

    name: str
    default: float | None
    metavar: str
    help: str

    @property
    def option(self) -> str:
        return "--" + self.name.replace("_", "-")


PARAMETERS: tuple[Parameter, ...] = (
    Parameter("reaction_slack", 0.2, "SECONDS",
              "a reaction's first start may come this long after what the rules let it "
              "wait for (default 0.2)"),
    Parameter("utterance_slack", 1.0, "SECONDS",
              "and its first words this much later still (default 1.0)"),
    Parameter("react_within", None, "SECONDS",
              "a fixed bound for the first start instead of the rules' residual + slack "
              "(e.g. 0.2)"),
    Parameter("face_tolerance", FACE_TOLERANCE, "DEGREES",
              "largest angle to the user still counted as facing (default 30)"),
    Parameter("unfaced_for", 1.0, "SECONDS",
              "how long, in a row, the user may be off to the side while the robot's "
              "words run (default 1)"),
    Parameter("leave_distance", 0.3, "METRES",
              "how far the robot may move away from the user while talking (default 0.3)"),
    Parameter("resume_distance", RESTORE_DISTANCE, "METRES",
              "how far from where it was suspended a stream may resume speaking "
              "(default 0.3)"),
    Parameter("barge_in_slack", 0.3, "SECONDS",
              "how long the robot may talk on over its user besides the word under way "
              "(default 0.3)"),
    Parameter("answer_slack", 1.0, "SECONDS",
              "how long after what the rules put first an application that took user "
              "speech may begin to answer it (default 1)"),
    Parameter("recovery_slack", 0.2, "SECONDS",
              "how long after the robot's pause an utterance cut by a false interruption "
              "may go on (default 0.2)"),
    Parameter("silence", 2.0, "SECONDS",
              "longest pause without output after an answer (default 2)"),
    Parameter("stuck_after", 60.0, "SECONDS",
              "how long a Command may wait, or an atomic behavior run, before its "
              "application is stuck (default 60)"),
    Parameter("search_after", 90.0, "SECONDS",
              "how long a search may go on without a sight of the user (default 90): one "
              "full turn of the thesis' Turn-and-Search takes about 67 s"),
)
"""Every parameter, in the order ``--help`` lists them."""


def _number(name: str, value: object, *, whole: bool = False) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name} must be a number, not {value!r}")
    if not math.isfinite(value) or value < 0:
        raise ValueError(f"{name} must be a number from 0 up, not {value!r}")
    if whole and int(value) != value:
        raise ValueError(f"{name} must be a whole number, not {value!r}")
    return float(value)


class Thresholds:
    """How much of each fault a run may show (``max_<measure>``, one per entry of the
    table of measures, 0 by default: no fault allowed), and the measures'
    parameters (:data:`PARAMETERS`)."""

    __slots__ = ("answer_slack", "barge_in_slack", "face_tolerance", "leave_distance",
                 "limits", "react_within", "reaction_slack", "recovery_slack",
                 "resume_distance", "search_after", "silence", "stuck_after",
                 "unfaced_for", "utterance_slack")

    reaction_slack: float
    utterance_slack: float
    barge_in_slack: float
    answer_slack: float
    recovery_slack: float
    react_within: float | None
    face_tolerance: float
    unfaced_for: float
    leave_distance: float
    resume_distance: float
    silence: float
    stuck_after: float
    search_after: float
    limits: Mapping[str, int]
    """Each measure's limit, by its ``max_`` name (``max_late``)."""

    def __init__(self, **given: object) -> None:
        known = [m.limit for m in LIMITS]
        params = {p.name: p for p in PARAMETERS}
        limits: dict[str, int] = dict.fromkeys(known, 0)
        for name, value in given.items():
            if name in params:
                if value is None and params[name].default is None:
                    continue
                number = _number(name, value)
                object.__setattr__(self, name, number)
            elif name in limits:
                limits[name] = int(_number(name, value, whole=True))
            else:
                near = difflib.get_close_matches(name, [*known, *params], n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                raise ValueError(f"no threshold {name!r}{hint} (known: "
                                 f"{', '.join([*known, *params])})")
        for p in PARAMETERS:
            if p.name not in given or (given[p.name] is None and p.default is None):
                object.__setattr__(self, p.name, p.default)
        object.__setattr__(self, "limits", MappingProxyType(limits))

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError("Thresholds are immutable")

    def limit(self, measure: str) -> int:
        """How many findings of ``measure`` (its key: ``late``) a run may show."""
        return self.limits[f"max_{measure}"]

    def replace(self, **changes: object) -> Thresholds:
        """The same thresholds with some changed."""
        return Thresholds(**{**self.to_dict(), **changes})

    def to_dict(self) -> dict[str, object]:
        out: dict[str, object] = dict(self.limits)
        out.update({p.name: getattr(self, p.name) for p in PARAMETERS})
        return out

    def __reduce__(self) -> tuple[object, tuple[dict[str, object]]]:
        return (_rebuilt, (self.to_dict(),))  # (pickled for a sweep's worker processes)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Thresholds) and self.to_dict() == other.to_dict()

    def __hash__(self) -> int:
        return hash(tuple(self.to_dict().items()))

    def __repr__(self) -> str:
        changed = {k: v for k, v in self.to_dict().items()
                   if v != Thresholds._default(k)}
        return f"Thresholds({', '.join(f'{k}={v!r}' for k, v in changed.items())})"

    @staticmethod
    def _default(name: str) -> object:
        for p in PARAMETERS:
            if p.name == name:
                return p.default
        return 0


def _rebuilt(values: dict[str, object]) -> Thresholds:
    return Thresholds(**values)
