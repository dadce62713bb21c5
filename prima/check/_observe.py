"""What a check's worker notes of each run, beyond the judge's counts: whose each
failure is, and which of the EA's states, handlers, Commands and answers ran.

Both go into the run's record (a JSON object, the same on any worker): the failures of
each threshold the run exceeded, each with the application it is attributed to and
its role (``ea``: the EA under check, ``fa``, ``other``: another EA of the scenario),
the rule, the atomic behavior it waited for and where that application's document
asks for what it blames; and the EA's coverage as the trace shows it (states entered,
handlers run as ``line:col``, Commands started and Q&As ended, each as where its
request is written and its place in the request).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from prima.catalog import STANDARD_COMMANDS
from prima.judge import (
    MEASURES,
    BargeIn,
    Blame,
    Elsewhere,
    Finding,
    Ignored,
    Leaving,
    Reaction,
    Recovery,
    Report,
    Silence,
    Split,
    Stuck,
    Unfaced,
)

__all__ = ["MAX_FAILURES", "CheckAnalysis", "attribute"]

MAX_FAILURES = 5
"""Failures noted per measure exceeded, per run."""

_MOVES = frozenset(c.name for c in STANDARD_COMMANDS if c.travels or c.aims)
"""Commands that take the robot somewhere or turn it on purpose: one of another
application that holds the wheels keeps the robot from turning to its user."""


def _blame(b: Blame | None) -> str:
    return "" if b is None else str(b)


def _whose(f: Finding, wheels: Mapping[int, Blame]) -> tuple[str, str, str, str]:
    """A finding's culprit application, the rule it broke (in words that are the same
    from run to run: the finding itself has the figures), the atomic behavior it waited
    for, and where the culprit's document asks for what it did."""
    if isinstance(f, Reaction):
        waited = _blame(f.waits[0]) if f.waits else ""
        what = "late" if f.late else "never heard whole"
        if f.took is not None:  # another application's AB held its devices meanwhile
            return f.took.app, f"its {f.took.command} held the devices of {f.app}'s " \
                               f"reaction to {f.event} ({what})", waited, f.took.at
        held = f.waits[0] if f.waits else None
        if not f.late and held is not None and held.app != f.app:
            # never heard for what the rules let hold its devices: that application's doing
            return held.app, f"its {held.command} held the devices of {f.app}'s reaction " \
                             f"to {f.event} ({what})", waited, held.at
        return f.app, f"its reaction to {f.event} is {what}", waited, f.at
    if isinstance(f, Unfaced):
        held = wheels.get(f.seq) if f.during is None else f.turned_by
        if held is not None:  # the robot could not be turned to the user first
            return held.app, f"its {held.command} moved the robot: {f.app}'s {f.command} " \
                             "was said with the user off to the side", "", held.at
        return f.app, f"{f.command} \"{f.text}\" said with the user off to the side", "", f.at
    if isinstance(f, Leaving):
        if f.moved_by is not None:
            return f.moved_by.app, f"its {f.moved_by.command} took the robot away from the " \
                                   f"user while {f.app} spoke", "", f.moved_by.at
        return f.app, "moved away from the user while speaking", "", f.at
    if isinstance(f, Stuck):
        if f.kind == "end" and f.behind is not None and f.behind.app != f.app:
            return f.behind.app, f"its {f.behind.command} held the devices {f.app} waited " \
                                 "for until the end", _blame(f.behind), f.behind.at
        return f.app, f"stuck ({f.kind})", _blame(f.behind), f.at
    return _plain(f)


def _plain(f: Finding) -> tuple[str, str, str, str]:
    """The findings whose culprit they name themselves, as :func:`_whose` says."""
    if isinstance(f, Elsewhere):
        return f.app, "resumed speaking away from where its stream was suspended", "", f.at
    if isinstance(f, Split):
        return f.by, f"\"{f.text}\" split {f.app}'s exchange ({f.kind})", "", f.at
    if isinstance(f, Silence):
        return f.app, "said nothing after the user's answer", "", f.at
    if isinstance(f, BargeIn):
        return f.app, f"its {f.command} talked on over the user", "", f.at
    if isinstance(f, Ignored):
        what = "never answered them" if f.answered is None else "answered them late"
        return f.app, f"took the user's words and {what}", "", f.at
    if isinstance(f, Recovery):
        return f.app, f"its {f.command} did not go on after a false interruption", "", f.at
    raise TypeError(f"not a finding: {f!r}")  # (every kind of finding is above)


def attribute(report: Report, roles: Mapping[str, str],
              wheels: Mapping[int, Blame] | None = None) -> list[dict[str, Any]]:
    """The failures of each threshold a run exceeded, each attributed (its culprit's
    ``role`` from ``roles``, app name -> role; ``mediator`` when no application is;
    ``wheels``: for an utterance's start line, another application's AB that held the
    wheels then)."""
    out: list[dict[str, Any]] = []
    for m in MEASURES:
        found = report.of(m.key)
        if len(found) <= report.thresholds.limit(m.key):
            continue
        for f in found[:MAX_FAILURES]:
            app, rule, waited, at = _whose(f, wheels or {})
            out.append({"measure": m.key, "app": app, "role": roles.get(app, "mediator"),
                        "rule": rule, "waited": waited, "at": at, "finding": m.line(f)})
    return out


class _Observer:
    """One run's notes (see the module)."""

    def __init__(self, ea: str) -> None:
        self.ea = ea
        self.app: str | None = None
        """The EA's name in the run (its load line's)."""
        self.roles: dict[str, str] = {}
        self.states: set[str] = set()
        self.handlers: set[str] = set()
        self.where: dict[int, tuple[str, int]] = {}
        """Command id -> where its request is written (line:col) and its place in it."""
        self.commands: set[tuple[str, int]] = set()
        self.answers: set[tuple[str, int, str, str]] = set()
        self.asked: dict[int, str] = {}
        """Command id -> where its application's document asks for it (every app's)."""
        self.running: dict[int, Blame] = {}
        """The ABs that move or turn the robot now."""
        self.wheels: dict[int, Blame] = {}
        """An utterance's start line -> another application's AB moving or turning the
        robot then."""

    def feed(self, row: Mapping[str, Any]) -> None:
        kind, app = row["kind"], row.get("app")
        if kind in ("request", "start", "end"):
            self._wheels(row, kind, str(app))
        if kind == "load":
            detail = row.get("detail") or {}
            mine = detail.get("document") == self.ea and detail.get("role") == "ea"
            if mine:
                self.app = app
            self.roles[str(app)] = "ea" if mine else ("fa" if detail.get("role") == "fa"
                                                      else "other")
        if app is None or app != self.app:
            return
        detail = row.get("detail") or {}
        if kind == "state":
            self.states.add(str(row.get("text")))
        elif kind == "handler":
            self.handlers.add(f"{detail.get('line')}:{detail.get('col')}")
        elif kind == "request":
            self._request(row, detail)
        elif kind == "start":
            for cid in self._ids(row, detail):
                if cid in self.where:
                    self.commands.add(self.where[cid])
        elif kind == "end" and str(row.get("command") or "").split("+")[-1] == "QA":
            self._answer(row, detail)

    def _wheels(self, row: Mapping[str, Any], kind: str, app: str) -> None:
        """Who holds the wheels, for the utterances the robot could not turn first."""
        detail = row.get("detail") or {}
        ids = self._ids(row, detail)
        if kind == "request":
            for cid in ids:
                self.asked.setdefault(cid, str(detail.get("at") or ""))
            return
        ab = row.get("ab")
        if not isinstance(ab, int):
            return
        if kind == "end":
            self.running.pop(ab, None)
            return
        if row.get("text"):
            other = next((b for b in self.running.values() if b.app != app), None)
            if other is not None:
                self.wheels[int(row["seq"])] = other
        if "locomotion" in (row.get("devices") or ()) and \
                not _MOVES.isdisjoint(str(row.get("command") or "").split("+")):
            self.running[ab] = Blame(app, ab, str(row.get("command")),
                                     self.asked.get(ids[0], "") if ids else "", "on the wheels")

    @staticmethod
    def _ids(row: Mapping[str, Any], detail: Mapping[str, Any]) -> list[int]:
        ids = row.get("command_ids")
        if ids:
            return list(ids)
        cid = detail.get("command_id")
        return [cid] if isinstance(cid, int) else []

    def _request(self, row: Mapping[str, Any], detail: Mapping[str, Any]) -> None:
        at = str(detail.get("at") or "")
        if row.get("reason") == "restart" or "precedes" in detail \
                or not at.startswith(self.ea + ":"):
            return  # (a policy's AB, or a Command cut and asked for again)
        loc = at[len(self.ea) + 1:]
        for position, cid in enumerate(self._ids(row, detail)):
            self.where.setdefault(cid, (loc, position))

    def _answer(self, row: Mapping[str, Any], detail: Mapping[str, Any]) -> None:
        ids = self._ids(row, detail)
        where = self.where.get(ids[-1]) if ids else None
        result = str(detail.get("result") or "")
        if where is None or "status=" not in result:
            return
        status = result.split("status=", 1)[1].split(",", 1)[0]
        said = result.split("utterance=", 1)[1] if "utterance=" in result else ""
        self.answers.add((*where, status, said))

    def finish(self, report: Report) -> dict[str, Any]:
        return {
            "failures": attribute(report, self.roles, self.wheels),
            "coverage": {
                "states": sorted(self.states),
                "handlers": sorted(self.handlers),
                "commands": [list(c) for c in sorted(self.commands)],
                "answers": [list(a) for a in sorted(self.answers)],
            },
        }


_FAILURE = {"measure": str, "app": str, "role": str, "rule": str, "waited": str, "at": str,
            "finding": str}
SHAPE = {"failures": [_FAILURE],
         "coverage": {"states": [str], "handlers": [str], "commands": [(str, int)],
                      "answers": [(str, int, str, str)]}}
"""What a check's record says under ``check`` (:meth:`_Observer.finish`), as a shape
(:func:`prima.batch.shape_problem`): a resumed check's records are checked against it."""


@dataclass(frozen=True)
class CheckAnalysis:
    """``prima check``'s analysis of a run (:class:`prima.batch.Analysis`): the EA under
    check is the one whose document's file name is ``ea``."""

    ea: str
    key: str = "check"

    @property
    def shape(self) -> Any:
        return SHAPE

    def observer(self) -> _Observer:
        return _Observer(self.ea)
