"""A simulated run: documents, interpreters, the mediator and the simulator joined.

Data flows one way at a time (docs/rules.md section 2): the simulator's events
go to the mediator, which posts them to the interpreters; their requests go to
the mediator, which starts atomic behaviors on the simulator's devices; the
simulator reports each end back. The simulator is the clock. Every decision,
event, user action and application note becomes a :class:`TraceLine`.

This module is the only place that knows all four parts.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from prima.catalog import Catalog, ParamKind
from prima.dsl import Document
from prima.errors import AppFailure, DocumentError, LocatedError, Problem, RunError, Severity
from prima.interpreter import Interpreter, Note
from prima.mediator import (
    AppKind,
    Call,
    Decision,
    DecisionKind,
    Event,
    Mediator,
    Outcome,
    Request,
    Rule,
)
from prima.scenario import Loaded, Scenario, Setup, Switches, spec_from_profile
from prima.signals import stop_if_signalled
from prima.sim import Simulator, SpeechTiming, UserAction, ZoneEntry
from prima.trace import Kind, Pose, RecordKind, TraceLine, rounded, rounded_pose, row_of
from prima.vocab import (
    FACE_TOLERANCE,
    MAX_EAS,
    POLICIES,
    RESTORE_ANGLE,
    RESTORE_DISTANCE,
    SPEECH_EVENT,
    Budgets,
    OnInterrupt,
    Value,
)

__all__ = ["MAX_IDLE_ROUNDS", "POSE_RATE", "Loaded", "Run", "Setup", "Switches",
           "spec_from_profile"]

MAX_IDLE_ROUNDS: Final = 10_000
"""Loop rounds allowed without simulated time moving (a stuck loop is a bug)."""

POSE_RATE = 2.0
"""Pose samples per simulated second in the trace, by default (at most: a sample that
would repeat the poses of the line with poses before it is left out)."""

_Posed = tuple[Pose, Pose | None, bool | None]
"""The robot's pose, the user's and whether they are detectable (``Simulator.poses``)."""

_Made = tuple[tuple[object, ...], dict[str, object], dict[str, Value], bool]
"""A decision's fields but its time, number, kind, AB and iteration, its row before its
poses, the part of its detail those fields decide, and for a start, whether the interrupt
policy may cut its Commands (:meth:`Run._ab_row`)."""

_SHOWN_KEPT: Final = 1024
"""How many calls' words and shown arguments a run keeps (:meth:`Run._shown`)."""

_POSED: Final = frozenset({DecisionKind.START, DecisionKind.END, Kind.USER, Kind.EVENT, Kind.POSE})
"""Lines that carry the robot's and the user's poses."""

# The members a run's lines are told apart by, as constants: compiled, a Final name is a C
# static, where ``DecisionKind.START`` is a lookup in the module's dict and one on an enum
# class (through its metaclass's ``__getattr__``: some 700 instructions), at every line.
_REQUEST: Final = DecisionKind.REQUEST
_START: Final = DecisionKind.START
_END: Final = DecisionKind.END
_CANCEL: Final = DecisionKind.CANCEL
_FAILURE: Final = DecisionKind.FAILURE
_LOAD: Final = DecisionKind.LOAD
_ERROR: Final = Kind.ERROR
_POSE: Final = Kind.POSE
_EVENT: Final = Kind.EVENT
_USER: Final = Kind.USER
_BLEND: Final = Rule.BLEND
_RESTART: Final = Rule.RESTART
_CUTS: Final = frozenset({Rule.INTERRUPT, Rule.BARGE_IN})
"""The rules that cut an AB short (its end line says what was said and not)."""
_WORDED: Final = frozenset({DecisionKind.START, DecisionKind.REQUEST, DecisionKind.END})
"""Decisions whose line's text is their words (else: their detail, if any)."""
_NEVER: Final = OnInterrupt.NEVER
_FIXED: Final = frozenset({"command_id", "args", "label", "precedes", "over"})
"""What a start's or an end's detail says that its decision's fields but its time, number,
AB and iteration decide (:meth:`Run._ab_row`): the rest is the line's own."""
_TEXT: Final = ParamKind.TEXT
_OWN: Final = ("t", "seq", "kind", "ab", "iteration")
"""A decision's fields that differ from one iteration's start (or end) to the next's: the
rest, sliced out of the tuple (:data:`_SAME_A` to :data:`_SAME_C`), must be the same for
a row to be made from the last one (:meth:`Run._ab_row`)."""
_SAME_A: Final = slice(3, 5)
_SAME_B: Final = slice(6, 12)
_SAME_C: Final = slice(13, None)


@dataclass
class _App:
    name: str
    role: AppKind
    interpreter: Interpreter
    failed: bool = False


class _Channel:
    """The connect-channel and restore-state policies' questions, answered by the
    simulator from the robot's true pose."""

    def __init__(self, sim: Simulator) -> None:
        self._sim = sim

    def unfaced(self) -> bool:
        return self._sim.user_unfaced(FACE_TOLERANCE)

    def near(self, distance: float) -> bool:
        return self._sim.user_near(distance)

    def pose(self) -> Mapping[str, Value]:
        p = self._sim.robot_pose()
        return {"x": rounded(p.x, 2), "y": rounded(p.y, 2), "heading": rounded(p.heading, 1)}

    def displaced(self, pose: Mapping[str, Value]) -> bool:
        p = self._sim.robot_pose()
        x, y = (float(pose[k] or 0.0) for k in ("x", "y"))
        if math.hypot(p.x - x, p.y - y) > RESTORE_DISTANCE:
            return True
        heading = pose.get("heading")
        return heading is not None and \
            abs((p.heading - float(heading) + 180.0) % 360.0 - 180.0) > RESTORE_ANGLE


class _Port:
    """What an interpreter may ask of the mediator, and nothing more."""

    def __init__(self, run: Run) -> None:
        self._run = run

    def submit(self, request: Request) -> tuple[int, ...]:
        self._run.requesting = request
        try:
            return self._run.mediator.submit(request)
        finally:
            self._run.requesting = None

    def open_stream(self, app: str, hold: float) -> None:
        self._run.mediator.open_stream(app, hold)

    def close_stream(self, app: str) -> None:
        self._run.mediator.close_stream(app)

    def open_block(self, app: str, *, devices: frozenset[str] | None = None,
                   watchdog: float) -> None:
        self._run.mediator.open_block(app, devices=devices, watchdog=watchdog)

    def close_block(self, app: str) -> None:
        self._run.mediator.close_block(app)


class Run:
    """One simulated run of a scenario with its FA and its EAs.

    The trace goes to ``sink`` line by line as the run goes, if one is given
    (then :attr:`lines` stays empty and memory stays flat however long the run);
    otherwise it is kept in :attr:`lines`. With ``rows``, each line goes there as its
    jsonl dict instead (:func:`prima.trace.row_of`), and no :class:`TraceLine` is made:
    what a judged run that writes no trace needs. Runs given the same ``files`` share
    the profiles and documents they load.
    """

    def __init__(self, scenario: str | Path | Setup, *, fa: str | Path | None = None,
                 ea: str | Path | None = None, robot: str | Path | None = None,
                 seed: int | None = None, until: float | None = None,
                 sink: Callable[[TraceLine], None] | None = None,
                 pose_rate: float = POSE_RATE,
                 policies: Mapping[str, bool] | None = None,
                 speech: SpeechTiming | None = None, files: Loaded | None = None,
                 rows: Callable[[dict[str, object]], None] | None = None) -> None:
        if isinstance(scenario, Setup):
            if fa or ea or robot or seed is not None or until is not None or policies \
                    or files is not None:
                raise TypeError("a Setup is made ready already: change it with Setup.load")
            setup = scenario
        else:
            setup = Setup.load(scenario, fa=fa, ea=ea, robot=robot, seed=seed, until=until,
                               policies=policies, files=files)
        self.setup = setup
        self._files = setup.files
        """Where maps, profiles and documents are loaded (shared by a sweep's runs)."""
        loaded = setup.scenario
        self.scenario: Scenario = loaded
        self._folder = os.path.abspath(os.path.dirname(loaded.source))
        self._named: dict[str, str] = {}
        """A file's path as an error names it -> as the trace names it: relative to the
        scenario's folder (a golden trace reads the same on every machine)."""
        for read in setup.read:
            self._name(read)
        self.until = setup.until
        self.profile = setup.profile
        self.policies: Mapping[str, bool] = setup.policies
        """Every mediation policy's state (:attr:`Setup.policies`)."""
        self.fa_path = setup.fa_path
        self.ea_path = setup.ea_path
        self.ea_paths: list[Path] = list(setup.ea_paths)
        """The EAs running from the start (``<apps ea>`` or ``ea=``, then ``<apps><ea>``)."""
        self._documents: dict[Path, Document] = dict(setup.documents)
        self._recording(sink, rows)
        self.budgets: Mapping[AppKind, Budgets] = self.profile.budgets
        self.apps: dict[str, _App] = {}
        self._paths: dict[str, Path] = {}
        """Each loaded application's document."""
        self._file_names: dict[str, str] = {}
        """Each loaded application's document's file name (a request line's ``at``)."""
        self._outcomes: dict[int, Outcome] = {}
        self._said: dict[int, tuple[float, float]] = {}
        """An ended AB's words: when they began and ended (for its end line)."""
        self.requesting: Request | None = None
        """The request an application is making (its Commands' lines say where it is
        written, and whether they may be cut)."""
        self._requested: dict[int, tuple[str, bool]] = {}
        """Command id -> where its request is written (``doc.pxml:line:col``) and whether
        the interrupt policy may cut it (the request did not say ``never``), while it is
        in working memory."""
        self._elsewhere: set[int] = set()
        """Commands whose request said their words are about something else
        (``face_user`` false), while they are in working memory."""
        self.catalog = setup.catalog
        self.sim = Simulator.from_scenario(loaded, spec=setup.spec, catalog=self.catalog)
        self.until = self.sim.on_grid(self.until)  # (the run ends at a tick)
        self.sim.speech = speech  # None: the profile's speech rate times every utterance
        for policy in POLICIES.values():  # (barge-in: the robot hears at any time, else
            if policy.sim is not None:      # only while a Q&A listens)
                setattr(self.sim, policy.sim, self.policies[policy.name])
        self.sim.backchannel = self.profile.hearing.backchannel
        self.sim.answers_prompt = self._answers_prompt
        self.mediator = Mediator(self.catalog, self.sim, self.sim, record=self._decision,
                                 config=setup.config, channel=_Channel(self.sim))
        if setup.config.connect_channel:  # (the robot keeps facing its user while it
            self.sim.watch_facing(FACE_TOLERANCE, self.mediator.regard)  # talks: 7.6 (3))
        self.sim.finished = self._finished
        self.sim.on_event = self._event
        self.sim.on_user = self._user
        self.sim.on_zone = self._zone
        self.sim.sample_poses(pose_rate, self._sample, moved=True)  # (a still instant
        # would repeat the poses of the line before it: ``_sample`` writes no line)
        self._port = _Port(self)

    def _recording(self, sink: Callable[[TraceLine], None] | None,
                   rows: Callable[[dict[str, object]], None] | None) -> None:
        """Where the trace's lines go, and what making them keeps as the run goes."""
        self.lines: list[TraceLine] = []
        self._sink = sink or self.lines.append
        self._rows = rows
        self._count = 0
        self._posed: tuple[object, float] = (None, -1.0)
        """The poses the last line with poses carried (:meth:`Simulator.poses`), and when."""
        self._shown_calls: dict[int, tuple[Call, tuple[str, ...], tuple[str, ...]]] = {}
        """Calls shown in the trace -> their words and their arguments as shown."""
        self._starts: dict[int, _Made] = {}
        self._quiet: dict[int, _Made] = {}
        self._ends: dict[int, _Made] = {}
        """Command id -> the last start (one of an iteration that says nothing; end) row
        of an AB of it (:meth:`_ab_row`; at most :data:`_SHOWN_KEPT` Commands kept)."""

    # ------------------------------------------------------------ the loop

    def run(self) -> list[TraceLine]:
        """Run to the end; returns the trace (empty when it went to a sink)."""
        self._begin()
        sim = self.sim
        mediator = self.mediator
        apps = self.apps
        until = self.until
        idle, last = 0, -1.0
        now = sim.now()
        # (an iteration for about every AB end of a run: the earliest deadline found
        # without a list of deadlines made)
        while now < until:
            # To the next deadline of the mediator or an application, or the first
            # report (the simulator's own wake-ups on the way concern neither).
            to = until
            t = mediator.next_deadline()
            if t is not None and t < to:
                to = t
            for a in apps.values():  # (asking changes no application)
                t = a.interpreter.next_deadline()
                if t is not None and t < to:
                    to = t
            sim.advance_until(to)
            mediator.advance()
            for app in list(apps.values()):
                self._guard(app, app.interpreter.advance)
            now = sim.now()
            idle = idle + 1 if now == last else 0
            last = now
            if idle > MAX_IDLE_ROUNDS:
                raise RunError(f"run loop stuck at t={last}")
        if self.sim.sample_every and self._posed[1] < sim.now():
            self._line(Kind.POSE)  # (where everyone ends, even if still: the trace's end)
        return self.lines

    def _begin(self) -> None:
        """Load the applications that run from the start; the first pose sample."""
        if self.fa_path is not None:
            self._load(self.fa_path, AppKind.FA)
        for path in self.ea_paths:
            self._load(path, AppKind.EA)
        if self.sim.sample_every:
            self._sample()  # where everyone starts (unless a line said it); samples follow

    # ------------------------------------------------------------ applications

    def documents(self) -> list[Document]:
        """The documents this run may run: those running from the start, then the zones'
        EAs (loaded now; one that cannot be loaded is left out, as it fails on entry)."""
        found = list(self._documents.values())
        for zone in self.scenario.zones:
            try:
                found.append(self._files.document(self._files.resolve(self.scenario, zone.ea),
                                                  self.profile))
            except LocatedError:
                continue
        return found

    def app_names(self) -> list[str]:
        """The names of the applications this run may load (the text trace's app column
        is as wide as the longest)."""
        return [document.name for document in self.documents()]

    def _name(self, path: str | Path) -> None:
        """Note a file the run reads: an error line names it relative to the scenario's
        folder (:meth:`_portable`)."""
        key = str(path)
        if key and key not in self._named:
            self._named[key] = self._files.relative(key, self._folder)

    def _portable(self, text: str) -> str:
        """An error's text with every file the run read named relative to the scenario's
        folder, as ``prima validate`` of the scenario's folder names it: no absolute path
        in a trace line."""
        named = sorted((p for p, r in self._named.items() if p != r and p in text),
                       key=len, reverse=True)
        if not named:
            return text
        pattern = re.compile("|".join(re.escape(f"{p}:") for p in named))  # (one pass)
        return pattern.sub(lambda m: f"{self._named[m.group()[:-1]]}:", text)

    def _checked(self, path: Path, role: AppKind) -> Document:
        """A document loaded for ``role`` and checked (:meth:`Setup.document`); each file
        it reads named as the trace names it."""
        read: list[str] = []
        try:
            return self.setup.document(path, role, read)
        finally:
            for name in read:
                self._name(name)

    def _load(self, path: Path, role: AppKind) -> None:
        document = self._documents.get(path) or self._checked(path, role)
        self._documents[path] = document
        name = document.name
        if name in self.apps:
            raise DocumentError([Problem(str(path), 1, 1, Severity.ERROR,
                                         f"an application named '{name}' is already loaded; "
                                         "each application needs a name of its own")])
        budgets = self.budgets[role]
        interpreter = Interpreter(document, name, self._port, self.sim,
                                  catalog=self.catalog, robot_events=self.profile.events,
                                  user_events=self.profile.user_events,
                                  gestures=self.profile.gestures, budgets=budgets,
                                  note=self._note,
                                  send=lambda _app, to, text: self.sim.send(to, text))
        self.sim.longest[name] = budgets.longest_ab
        app = _App(name, role, interpreter)
        self._loading = path
        self.mediator.register(name, role, interpreter)  # its load decision is traced
        self.apps[name] = app
        self._paths[name] = path
        self._file_names[name] = path.name
        self._guard(app, interpreter.start)

    def _guard(self, app: _App, work: Callable[[], None]) -> None:
        """Run an interpreter call outside the mediator's callbacks; a failure unloads it."""
        if app.failed:
            return
        try:
            work()
        except AppFailure:
            self._fail(app)
            if app.name in self.mediator.apps():
                self.mediator.unregister(app.name)

    def _fail(self, app: _App) -> None:
        app.failed = True
        app.interpreter.stop()
        self.apps.pop(app.name, None)

    def _zone(self, entry: ZoneEntry) -> None:
        """The robot entered a zone: its EA replaces the EAs running, or, with
        ``join="true"``, joins them (at most :data:`MAX_EAS`); an EA already running
        stays as it is."""
        zone = next((z for z in self.scenario.zones if z.name == entry.zone), None)
        join = zone is not None and zone.join
        self._line(Kind.ZONE, text=entry.zone,
                   detail={"ea": entry.ea, "join": True} if join else {"ea": entry.ea})
        path = self._files.resolve(self.scenario, entry.ea)
        running = [a for a in self.apps.values() if a.role is AppKind.EA]
        if not join:
            for current in running:
                if self._paths[current.name] != path:
                    current.interpreter.stop()
                    self.apps.pop(current.name, None)
                    self.mediator.unregister(current.name)
            running = [a for a in running if self._paths[a.name] == path]
        if any(self._paths[a.name] == path for a in running):
            return
        if len(running) >= MAX_EAS:
            problem = Problem(self.scenario.source, zone.line if zone else 1,
                              zone.col if zone else 1, Severity.ERROR,
                              f"zone '{entry.zone}': {len(running)} EAs are running "
                              f"({', '.join(a.name for a in running)}); at most {MAX_EAS} "
                              f"run at once: '{entry.ea}' is not loaded")
            self._line(Kind.ERROR, text=str(problem), detail={"zone": entry.zone})
            return
        self.ea_path = path
        try:
            self._load(path, AppKind.EA)
        except LocatedError as exc:  # a bad EA in the building: the run goes on without it
            self._line(Kind.ERROR, text=str(exc.problems[0]), detail={"zone": entry.zone})
        except Exception as exc:  # noqa: BLE001 - whatever a stranger's file does
            self._line(Kind.ERROR, text=f"{path}: cannot load: {type(exc).__name__}: {exc}",
                       detail={"zone": entry.zone})

    # ------------------------------------------------------------ recording

    def _line(self, kind: RecordKind, **fields: Any) -> None:
        stop_if_signalled()  # (a Ctrl-C a finalizer dropped stops the run here)
        if kind is _ERROR:
            fields["text"] = self._portable(str(fields.get("text") or ""))
        now = self.sim.now()
        if kind in _POSED:
            posed = self.sim.poses()
            self._posed = (posed, now)
            fields["robot"], user, detectable = posed
            if user is not None:
                fields["user"] = user
                fields["detectable"] = detectable
        if self._rows is not None:
            self._rows(row_of(now, self._count, kind, fields))
        else:
            self._sink(TraceLine.made(now, self._count, kind, fields))
        self._count += 1

    def _sample(self) -> None:
        """A pose sample, unless it would repeat the poses of the line with poses before
        it: while the robot and the user stand still, time passes without a line (a
        trace's length follows what happens, not how long; a reader holds each line's
        poses until the next line with poses). For ``rows``, its dict is made at once:
        the same as :func:`~prima.trace.row_of` makes of its fields, key for key and in
        its order (a judged run's third most frequent line, after starts and ends)."""
        posed = self.sim.poses()
        if posed == self._posed[0]:
            return
        rows = self._rows
        if rows is None:
            self._line(_POSE)
            return
        stop_if_signalled()
        now = self.sim.now()
        row: dict[str, object] = {"t": rounded(now, 3), "seq": self._count, "kind": "pose"}
        self._with_poses(row, posed, now)
        rows(row)
        self._count += 1

    def _with_poses(self, row: dict[str, object], posed: _Posed, now: float) -> None:
        """Put the robot's and the user's poses (:meth:`Simulator.poses`) in a line's
        row, last of its fields, as :func:`~prima.trace.row_of` does; they are the
        poses the next pose sample compares with."""
        self._posed = (posed, now)
        robot, user, detectable = posed
        row["robot"] = rounded_pose(robot, 0)
        if user is not None:
            row["user"] = rounded_pose(user, 1, detectable)

    def _decision(self, d: Decision) -> None:
        kind = d.kind
        if (kind is _START or kind is _END) and (rows := self._rows) is not None \
                and d.ab is not None and (cid := d.command_id) is not None:
            self._ab_row(rows, d, cid)  # (most decisions: first)
        elif kind is _FAILURE:
            app = self.apps.get(d.app or "")
            if app is None or not app.failed:  # not an error the interpreter already reported
                self._line(_ERROR, app=d.app, text=self._located(app, d.detail),
                           reason=d.rule._value_)
            if app is not None:
                self._fail(app)
        elif kind is _LOAD:
            self._line(kind, app=d.app, detail={"document": self._loading.name,
                                                "role": d.detail.lower()})
        elif (rows := self._rows) is not None:
            self._decision_row(rows, d, *self._decision_fields(d))
        else:
            self._decision_line(d, *self._decision_fields(d))

    def _decision_fields(self, d: Decision) -> tuple[str | None, dict[str, Value]]:
        """A decision's line's text and detail (the rest of its fields are the
        decision's own)."""
        kind = d.kind
        detail: dict[str, Value] = {}
        if d.command_id is not None:
            detail["command_id"] = d.command_id
        if kind is _REQUEST:
            self._where(d, detail)
        elif kind is _START:
            self._starting(d, detail)
        if kind is _END and d.ab is not None:
            self._ended(d, detail)
        elif kind is _CANCEL:
            for cid in d.command_ids:
                self._requested.pop(cid, None)
                self._elsewhere.discard(cid)
        if len(d.calls) == 1:
            spoken, others = self._shown(d.calls[0])
        else:
            shown = [self._shown(c) for c in d.calls]
            spoken = tuple(words for said, _args in shown for words in said)
            others = tuple(arg for _said, args in shown for arg in args)
        text = " / ".join(spoken) if spoken else None
        if (kind is _START and d.iteration and d.command_id is not None
                and self.sim.quiet(d.command_id)):
            text = None  # an iteration that says nothing (a search's watch)
        if others:
            detail["args"] = " ".join(others)
        if d.calls and d.calls[0].label:
            detail["label"] = d.calls[0].label
        if d.iteration:
            detail["iteration"] = d.iteration
        if d.precedes is not None:
            detail["precedes"] = d.precedes
        if d.rule is _BLEND and d.detail:
            detail["over"] = d.detail
        if d.detail and kind not in _WORDED:
            text = d.detail
        return text, detail

    def _decision_line(self, d: Decision, text: str | None, detail: dict[str, Value]) -> None:
        self._line(d.kind, app=d.app, ab=d.ab, tree=d.tree, command=d.command, text=text,
                   devices=tuple(d.devices) if d.devices else None,
                   reactive=d.reactive if d.ab is not None else None,
                   reason=d.rule._value_, detail=detail, before=d.before,
                   command_ids=d.command_ids if len(d.command_ids) > 1 else None)

    def _decision_row(self, rows: Callable[[dict[str, object]], None], d: Decision,
                      text: str | None, detail: dict[str, Value]) -> dict[str, object]:
        """What :meth:`_line` hands ``rows`` for a decision's line, made from the decision
        at once: the same dict as :func:`~prima.trace.row_of` makes of the line's fields,
        key for key and in its order (``bench/same_traces.py`` compares them), without
        the fields gathered first (a judged run's most frequent lines: starts and ends).
        Returns the row as it was before its poses (:meth:`_ab_row` keeps it)."""
        stop_if_signalled()
        now = self.sim.now()
        kind = d.kind
        row: dict[str, object] = {"t": rounded(now, 3), "seq": self._count, "kind": kind._value_}
        if d.app is not None:
            row["app"] = d.app
        ab = d.ab
        if ab is not None:
            row["ab"] = ab
        if d.tree is not None:
            row["tree"] = d.tree
        if d.command is not None:
            row["command"] = d.command
        if text is not None:
            row["text"] = text
        if ab is not None:
            row["reactive"] = d.reactive
        row["reason"] = d.rule._value_
        if d.devices:
            row["devices"] = list(d.devices)
        if len(d.command_ids) > 1:
            row["command_ids"] = list(d.command_ids)
        if d.before is not None:
            row["before"] = d.before
        if detail:
            row["detail"] = dict(sorted(detail.items())) if len(detail) > 1 else detail
        made = row
        if kind is _START or kind is _END:  # (lines with poses)
            made = row.copy()
            self._with_poses(row, self.sim.poses(), now)
        rows(row)
        self._count += 1
        return made

    def _ab_row(self, rows: Callable[[dict[str, object]], None], d: Decision, cid: int) -> None:
        """A start's or an end's row, for a Command's AB: a copy of the row of the last
        one of its Command (:meth:`_decision_row`'s, kept), where it is the same decision
        but for its time, number, AB and iteration (a loop's iterations, one after the
        other), with these set and its detail made again from the part that stays
        (:data:`_FIXED`) and the line's own (words, result, iteration). Setting a key a
        dict has keeps its place: the same dict as :meth:`_decision_row` makes, key for
        key and in its order, for a fraction of its work (a judged run's most frequent
        lines, a loop's ends and starts)."""
        start = d.kind is _START
        if not start:
            made = self._ends
        elif d.iteration and self.sim.quiet(cid):  # (an iteration that says nothing)
            made = self._quiet
        else:
            made = self._starts
        fields: tuple[object, ...] = d
        same = fields[_SAME_A] + fields[_SAME_B] + fields[_SAME_C]  # (all but :data:`_OWN`)
        kept = made.get(cid)
        if kept is None or kept[0] != same:
            text, detail = self._decision_fields(d)
            row = self._decision_row(rows, d, text, detail)
            if len(made) >= _SHOWN_KEPT:
                made.clear()
            made[cid] = (same, row, {k: v for k, v in detail.items() if k in _FIXED},
                         start and self._cuts(d))
            return
        stop_if_signalled()
        now = self.sim.now()
        row = kept[1].copy()
        row["t"] = rounded(now, 3)
        row["seq"] = self._count
        row["ab"] = d.ab
        if d.devices:
            row["devices"] = list(d.devices)  # (a list of its own, as every row has)
        if len(d.command_ids) > 1:
            row["command_ids"] = list(d.command_ids)
        detail = kept[2].copy()
        if start:
            self._starting(d, detail, kept[3])
        else:
            self._ended(d, detail)
        if d.iteration:
            detail["iteration"] = d.iteration
        row["detail"] = dict(sorted(detail.items()))
        self._with_poses(row, self.sim.poses(), now)
        rows(row)
        self._count += 1

    def _shown(self, call: Call) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """A call's words and its arguments as the trace shows them (:func:`_shown_args`),
        kept for the call: a loop's iterations and its restarts show the same calls again
        and again. (At most :data:`_SHOWN_KEPT` calls are kept, so that a long run's
        memory stays flat.)"""
        kept = self._shown_calls.get(id(call))
        if kept is not None and kept[0] is call:
            return kept[1], kept[2]
        shown = (tuple(self.catalog[call.command].spoken(call.args)),
                 tuple(_shown_args(self.catalog, call)))
        if len(self._shown_calls) >= _SHOWN_KEPT:
            self._shown_calls.clear()
        self._shown_calls[id(call)] = (call, *shown)
        return shown

    def _ended(self, d: Decision, detail: dict[str, Value]) -> None:
        """An end line says the AB's result (a cut one's words said and not), when its
        words ran; its Commands are forgotten once they are over."""
        outcome = self._outcomes.pop(d.ab or 0, None)
        if outcome is not None and outcome.values:
            detail["result"] = ", ".join([f"{k}={v}" for k, v in sorted(outcome.values.items())])
            if "error" in outcome.values:
                detail["error"] = outcome.values["error"]
            if d.rule in _CUTS:
                detail["interrupt"] = d.detail
                detail["spoken"] = outcome.values.get("spoken")
                detail["unspoken"] = outcome.values.get("unspoken")
        said = self._said.pop(d.ab or 0, None)
        if said is not None:
            detail["words_start"], detail["words_end"] = rounded(said[0], 3), rounded(said[1], 3)
        if d.detail not in ("not terminal", "to restart", "to go on"):  # its Commands are over
            for cid in d.command_ids:
                self._requested.pop(cid, None)
                self._elsewhere.discard(cid)

    def _where(self, d: Decision, detail: dict[str, Value]) -> None:
        """A request line says where it is written (``at``): the application's request
        being made, or, for a policy's request or a restart, the Command it is for."""
        ids = d.command_ids or ((d.command_id,) if d.command_id is not None else ())
        request = self.requesting
        app = self.apps.get(d.app or "")
        mine = d.rule is not _RESTART and d.precedes is None
        if mine and request is not None and app is not None and request.app == d.app:
            loc = app.interpreter.last_request
            at = f"{self._file_names[app.name]}:{loc.line}:{loc.col}" if loc else ""
            cuttable = request.on_interrupt is not _NEVER
            for cid in ids:
                self._requested[cid] = (at, cuttable)
            if not request.face_user:
                self._elsewhere.update(ids)
        else:
            for_command = d.precedes if d.precedes is not None else d.command_id
            at, _cuttable = self._requested.get(for_command or 0, ("", True))
            for cid in ids:
                self._requested.setdefault(cid, (at, True))
            if d.rule is _RESTART and for_command in self._elsewhere:
                self._elsewhere.update(ids)  # (said again, its words are still about that)
        found = self._requested.get(ids[0]) if ids else None
        if found is not None and found[0]:
            detail["at"] = found[0]
        if ids and ids[0] in self._elsewhere:
            detail["face_user"] = False  # (its words are about something else)

    def _starting(self, d: Decision, detail: dict[str, Value], cuts: bool | None = None) -> None:
        """A start line says whether the interrupt policy may cut the AB (its Commands
        are interruptible on this robot, ``cuts`` if known (:meth:`_cuts`), and their
        request allows it) and, for words said as it starts, when they end (the judge's
        cuts, listening and talking)."""
        ids = d.command_ids or ((d.command_id,) if d.command_id is not None else ())
        if cuts is None:
            cuts = self._cuts(d)
        if cuts and all(self._requested.get(cid, ("", True))[1] for cid in ids):
            detail["cuttable"] = True
        if d.ab is not None:
            ahead = self.sim.words_ahead(d.calls, ids, d.iteration)
            if ahead is not None:
                now = self.sim.now()
                detail["words_start"] = rounded(now, 3)
                detail["words_end"] = rounded(now + ahead, 3)

    def _cuts(self, d: Decision) -> bool:
        """The interrupt policy may cut the AB's Commands on this robot (their requests
        may still say ``never``): the same for every iteration of a loop."""
        return bool(self.setup.config.interrupt and d.calls
                    and all(self.catalog.commands[c.command].interruptible for c in d.calls))

    @staticmethod
    def _located(app: _App | None, message: str) -> str:
        """A failure the mediator found, located at the app's latest request."""
        loc = app.interpreter.last_request if app is not None else None
        if app is None or loc is None:
            return message
        return f"{app.interpreter.document.path}:{loc.line}:{loc.col}: {message}"

    def _finished(self, ab: int, outcome: Outcome) -> None:
        self._outcomes[ab] = outcome
        said = self.sim.said(ab)
        if said is not None:
            self._said[ab] = said
        self.mediator.finish(ab, outcome)

    def _answers_prompt(self, command_id: int, words: str) -> bool:
        """Whether words said over the prompt of the Q&A of ``command_id`` answer it
        (docs/rules.md 7.5): its grammar takes them (then they are no backchannel); else
        they do unless they are a backchannel or some application's always-on grammar
        takes them (words no grammar takes answer it, as its no-match)."""
        apps = list(self.apps.values())
        for app in apps:
            takes = app.interpreter.answers(command_id, words)
            if takes is not None:
                if takes:
                    return True
                break
        if self.profile.hearing.backchannel(words):
            return False
        return not any(app.interpreter.takes(words) for app in apps)

    def _event(self, event: Event) -> None:
        self._line(_EVENT, text=event.name, detail=dict(event.data))
        if event.name == SPEECH_EVENT:
            self.mediator.hear(event)  # to one application (docs/rules.md 7.5)
        else:
            self.mediator.post(event)

    def _user(self, action: UserAction) -> None:
        detail: dict[str, object] = {}
        if action.target is not None:
            detail["target"] = action.target
        if action.heard is not None:
            detail["heard"] = action.heard
        self._line(_USER, action=action.action._value_, text=action.text, detail=detail)

    def _note(self, note: Note) -> None:
        if note.kind is _ERROR:
            app = self.apps.get(note.app)
            if app is not None:
                app.failed = True  # the mediator's own failure decision adds nothing
        self._line(note.kind, app=note.app, text=note.text, detail=dict(note.detail))


def _shown_args(catalog: Catalog, call: Call) -> list[str]:
    """A call's arguments as the trace shows them: ``name=value``, words said aside (a
    text not said, such as a label a robot's own Command prints, is ``name="text"``)."""
    spec = catalog[call.command]
    said = bool(spec.spoken(call.args))
    out = []
    for name, value in call.args.items():
        param = spec.param(name)
        if param is None or (param.shown and param.kind is not _TEXT):
            out.append(f"{name}={value}")
        elif param.shown and not said and value:
            out.append(f'{name}="{value}"')
    out += [f"{name}={value}" for name, value in call.extra.items()]  # (a profile's extras)
    return out
