"""A run written as MCAP, with Foxglove's well-known schemas where one fits.

Each trace line becomes the messages it means, at its own time (log time:
simulated nanoseconds from the run's start): poses become transforms and
poses, utterances and heard words log lines, starts and ends state changes of
the devices, decisions records of the mediator with their reasons; at the end,
the judge's findings and the paths walked. See :data:`TOPICS`.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
from collections.abc import Mapping
from pathlib import Path
from types import TracebackType
from typing import IO, Any

import foxglove
from foxglove import messages as fm
from foxglove.channels import (
    FrameTransformsChannel,
    LogChannel,
    PoseInFrameChannel,
    PosesInFrameChannel,
    SceneUpdateChannel,
)
from foxglove.mcap import MCAPWriteOptions, MCAPWriter

from prima.errors import OutputError
from prima.judge import Report, judge
from prima.mcap._layout import ATTACHMENT, HOME_DEVICES, layout
from prima.mediator import DecisionKind
from prima.output import Staged, shown
from prima.sim import WorldMap
from prima.trace import TraceLine, describe

__all__ = ["TOPICS", "Recorder"]

TOPICS: Mapping[str, str] = {
    "/map": "foxglove.SceneUpdate: walls, places (with their names), the place graph's "
            "edges and areas; once, at 0",
    "/bodies": "foxglove.SceneUpdate: the robot and the user, in their own frames; once, at 0",
    "/tf": "foxglove.FrameTransforms: map -> robot and map -> user, at every pose of the trace",
    "/robot/pose": "foxglove.PoseInFrame: the robot's pose, likewise",
    "/user/pose": "foxglove.PoseInFrame: the user's pose, likewise",
    "/robot/path": "foxglove.PosesInFrame: the robot's whole path; once, at 0",
    "/user/path": "foxglove.PosesInFrame: the user's whole path; once, at 0",
    "/words": "foxglove.Log: what the robot says (name: the application) and the user says "
              "(name: user), when they start saying it",
    "/devices/DEVICE": "prima.DeviceState (JSON): which application's Command holds the "
                       "device (state: 'app: Command', or 'idle'), at each start and end",
    "/apps/APP/state": "prima.AppState (JSON): the application's PXML state, at each change",
    "/mediator": "prima.Decision (JSON): every decision of the mediator (request, start, end, "
                 "suspend, resume, hold, release, cancel, interrupt, ...) with its reason",
    "/events": "prima.Event (JSON): the events posted to the applications, with their data",
    "/user": "prima.UserAction (JSON): what the user did (says, walks, touches, ...)",
    "/judge": "foxglove.Log: each finding of prima judge (a late reaction, talking unfaced, "
              "...) at its time, and a summary at the end",
}
"""Every topic a recording has (DEVICE and APP: one topic each)."""

_PALETTE = ("#636efa", "#ef553b", "#00cc96", "#ab63fa", "#ffa15a", "#19d3f3", "#ff6692")
"""Application colours, in the order they are loaded (as prima show's)."""

_SCHEMAS: Mapping[str, Mapping[str, Any]] = {
    "prima.DeviceState": {"state": "string", "app": "string", "command": "string",
                          "ab": "integer", "text": "string"},
    "prima.AppState": {"state": "string", "app": "string"},
    "prima.Decision": {"kind": "string", "app": "string", "ab": "integer", "tree": "integer",
                       "command": "string", "reason": "string", "text": "string",
                       "devices": "array", "what": "string", "seq": "integer",
                       "detail": "object"},
    "prima.Event": {"name": "string", "data": "object", "seq": "integer"},
    "prima.UserAction": {"action": "string", "what": "string", "text": "string",
                         "seq": "integer"},
}
"""PRIMA's own JSON messages: field -> JSON type."""


def _nanos(t: float) -> int:
    return round(t * 1e9)


def _stamp(t: float) -> fm.Timestamp:
    return fm.Timestamp(sec=int(t), nsec=round((t - int(t)) * 1e9) % 1_000_000_000)


def _rotation(heading: float) -> fm.Quaternion:
    half = math.radians(heading) / 2
    return fm.Quaternion(x=0.0, y=0.0, z=math.sin(half), w=math.cos(half))


def _pose(x: float, y: float, heading: float = 0.0, z: float = 0.0) -> fm.Pose:
    return fm.Pose(position=fm.Vector3(x=x, y=y, z=z), orientation=_rotation(heading))


def _colour(hex_colour: str, alpha: float = 1.0) -> fm.Color:
    r, g, b = (int(hex_colour[k:k + 2], 16) / 255 for k in (1, 3, 5))
    return fm.Color(r=r, g=g, b=b, a=alpha)


def _json_schema(name: str) -> foxglove.Schema:
    fields = {key: {"type": kind} for key, kind in _SCHEMAS[name].items()}
    schema = {"title": name, "type": "object", "properties": fields}
    return foxglove.Schema(name=name, encoding="jsonschema",
                           data=json.dumps(schema, sort_keys=True).encode("utf-8"))


def _xyz(value: object) -> tuple[float, float, float] | None:
    if not isinstance(value, Mapping):
        return None
    return float(value["x"]), float(value["y"]), float(value.get("heading", 0.0))


class _Guarded:
    """The recording's file as foxglove's writer sees it: a write that fails (a full
    disk) is remembered, and what follows dropped, instead of raised into the writer
    (which would print an error of its own for every message after it). Its position is
    kept here, so the writer's seeks agree with its writes either way."""

    def __init__(self, file: IO[bytes]) -> None:
        self.file = file
        self.error: OSError | None = None
        self.position = 0
        self.size = 0

    def _do(self, work: Any, *args: Any) -> None:
        if self.error is None:
            try:
                work(*args)
            except OSError as exc:
                self.error = exc

    def write(self, data: bytes | bytearray) -> int:
        self._do(self.file.write, data)
        self.position += len(data)
        self.size = max(self.size, self.position)
        return len(data)

    def seek(self, offset: int, whence: int = os.SEEK_SET) -> int:
        base = {os.SEEK_SET: 0, os.SEEK_CUR: self.position, os.SEEK_END: self.size}[whence]
        self.position = base + offset
        self._do(self.file.seek, self.position)
        return self.position

    def flush(self) -> None:
        self._do(self.file.flush)


class Recorder:
    """Writes a run's trace lines as an MCAP file, as the run makes them; ``close()``
    adds what needs the whole run (the judge's findings, the paths) and finishes the
    file. Use it as a context manager.

    The recording is written beside ``path`` and put in its place once finished
    (:class:`prima.output.Staged`): a run that fails, a full disk or a killed process
    leaves the file that was there as it was. A run stopped by Ctrl-C (between two
    lines) is finished and kept. A write that fails is an
    :class:`~prima.errors.OutputError` at the next line."""

    def __init__(self, path: str | Path | None, world: WorldMap | None = None, *,
                 robot_radius: float = 0.2, context: foxglove.Context | None = None) -> None:
        self.path = Path(path) if path is not None else None
        self.context = context or foxglove.Context()
        """Where the messages go: the file's writer, and whatever else listens to it (the
        WebSocket server of ``prima live --foxglove``, which gives ``path`` None: no
        file)."""
        self._staged = (Staged(path, binary=True, seekable=True) if path is not None
                        else None)
        self._file = _Guarded(self._staged.file) if self._staged is not None else None
        self.writer: MCAPWriter | None = None
        if self._file is not None:
            try:
                self.writer = foxglove.open_mcap(
                    self._file, context=self.context,
                    writer_options=MCAPWriteOptions(profile="", compression_threads=0))
            except BaseException:
                self._discard()
                raise
        ctx = self.context
        self.map = SceneUpdateChannel("/map", context=ctx)
        self.bodies = SceneUpdateChannel("/bodies", context=ctx)
        self.tf = FrameTransformsChannel("/tf", context=ctx)
        self.poses = {who: PoseInFrameChannel(f"/{who}/pose", context=ctx)
                      for who in ("robot", "user")}
        self.paths = {who: PosesInFrameChannel(f"/{who}/path", context=ctx)
                      for who in ("robot", "user")}
        self.words = LogChannel("/words", context=ctx)
        self.findings = LogChannel("/judge", context=ctx)
        self.mediator = self._json("/mediator", "prima.Decision")
        self.events = self._json("/events", "prima.Event")
        self.user = self._json("/user", "prima.UserAction")
        self.devices: dict[str, foxglove.Channel] = {}
        self.apps: dict[str, foxglove.Channel] = {}
        self.colours: dict[str, str] = {}
        self.holders: dict[str, dict[int, dict[str, Any]]] = {}
        """Device -> the ABs holding it now (more than one while blended), by AB."""
        self.walked: dict[str, list[tuple[float, tuple[float, float, float]]]] = {
            "robot": [], "user": []}
        self.lines: list[TraceLine] = []
        self.end = 0.0
        self._scene(world, robot_radius)

    def _json(self, topic: str, schema: str) -> foxglove.Channel:
        return foxglove.Channel(topic, schema=_json_schema(schema), message_encoding="json",
                                context=self.context)

    # ---------------------------------------------------------------- the scene

    def _scene(self, world: WorldMap | None, radius: float) -> None:
        entities = [] if world is None else self._map_entities(world)
        self.scene = (fm.SceneUpdate(entities=entities), fm.SceneUpdate())
        """The map's scene and the bodies' (logged once at 0; again for a live view)."""
        self.map.log(self.scene[0], log_time=0)
        robot = fm.SceneEntity(
            timestamp=_stamp(0), frame_id="robot", id="robot", frame_locked=True,
            cylinders=[fm.CylinderPrimitive(pose=_pose(0, 0, z=0.15),
                                            size=fm.Vector3(x=2 * radius, y=2 * radius, z=0.3),
                                            bottom_scale=1.0, top_scale=1.0,
                                            color=_colour("#2c3e50"))],
            arrows=[fm.ArrowPrimitive(pose=_pose(0, 0, z=0.32), shaft_length=radius,
                                      shaft_diameter=0.05, head_length=0.12,
                                      head_diameter=0.12, color=_colour("#ecf0f1"))])
        user = fm.SceneEntity(
            timestamp=_stamp(0), frame_id="user", id="user", frame_locked=True,
            cylinders=[fm.CylinderPrimitive(pose=_pose(0, 0, z=0.85),
                                            size=fm.Vector3(x=0.35, y=0.25, z=1.7),
                                            bottom_scale=1.0, top_scale=1.0,
                                            color=_colour("#e67e22", 0.9))],
            arrows=[fm.ArrowPrimitive(pose=_pose(0, 0, z=1.75), shaft_length=0.2,
                                      shaft_diameter=0.05, head_length=0.1,
                                      head_diameter=0.1, color=_colour("#e67e22"))])
        self.scene = (self.scene[0], fm.SceneUpdate(entities=[robot, user]))
        self.bodies.log(self.scene[1], log_time=0)

    def scene_again(self) -> None:
        """Log the map's and the bodies' scenes again, at the latest time (a live view that
        subscribes after the start has them so)."""
        self.map.log(self.scene[0], log_time=_nanos(self.end))
        self.bodies.log(self.scene[1], log_time=_nanos(self.end))

    def _map_entities(self, world: WorldMap) -> list[fm.SceneEntity]:
        stamp = _stamp(0)
        walls = [fm.CubePrimitive(
            pose=_pose((w.x1 + w.x2) / 2, (w.y1 + w.y2) / 2,
                       math.degrees(math.atan2(w.y2 - w.y1, w.x2 - w.x1)), 0.5),
            size=fm.Vector3(x=math.hypot(w.x2 - w.x1, w.y2 - w.y1) + w.thickness,
                            y=w.thickness, z=1.0),
            color=_colour("#34495e", 0.8)) for w in world.walls]
        places = {p.name: p for p in world.places}
        edges = fm.LinePrimitive(
            type=fm.LinePrimitiveLineType.LineList, thickness=0.03,
            points=[fm.Point3(x=places[n].x, y=places[n].y, z=0.01)
                    for edge in world.edges for n in edge if n in places],
            color=_colour("#95a5a6", 0.7))
        out = [fm.SceneEntity(timestamp=stamp, frame_id="map", id="walls", cubes=walls),
               fm.SceneEntity(timestamp=stamp, frame_id="map", id="edges", lines=[edges])]
        for p in world.places:
            out.append(fm.SceneEntity(
                timestamp=stamp, frame_id="map", id=f"place/{p.name}",
                metadata=[fm.KeyValuePair(key="kind", value=p.kind.value)],
                spheres=[fm.SpherePrimitive(pose=_pose(p.x, p.y, z=0.05),
                                            size=fm.Vector3(x=0.12, y=0.12, z=0.12),
                                            color=_colour("#7f8c8d"))],
                texts=[fm.TextPrimitive(pose=_pose(p.x, p.y, z=0.3), billboard=True,
                                        font_size=14, scale_invariant=True,
                                        color=_colour("#2c3e50"), text=p.name)]))
        for a in world.areas:
            corners = [(a.x1, a.y1), (a.x2, a.y1), (a.x2, a.y2), (a.x1, a.y2)]
            out.append(fm.SceneEntity(
                timestamp=stamp, frame_id="map", id=f"area/{a.name}",
                lines=[fm.LinePrimitive(type=fm.LinePrimitiveLineType.LineLoop, thickness=0.04,
                                        points=[fm.Point3(x=x, y=y, z=0.02) for x, y in corners],
                                        color=_colour("#2980b9", 0.8))],
                texts=[fm.TextPrimitive(pose=_pose((a.x1 + a.x2) / 2, max(a.y1, a.y2) - 0.3,
                                                   z=0.05), billboard=True, font_size=12,
                                        scale_invariant=True, color=_colour("#2980b9"),
                                        text=a.name)]))
        return out

    # ---------------------------------------------------------------- the lines

    def write(self, line: TraceLine) -> None:
        """Record one trace line (in trace order)."""
        self._check()
        self.lines.append(line)
        row: dict[str, Any] = line.to_dict()
        t = line.t
        self.end = max(self.end, t)
        at = _nanos(t)
        self._poses(row, t, at)
        kind = str(row["kind"])
        app = row.get("app")
        if app is not None and app not in self.colours:
            self.colours[app] = _PALETTE[len(self.colours) % len(_PALETTE)]
        if kind in ("start", "end"):
            self._devices(row, kind, at)
        if kind == "start" and row.get("text"):
            self.words.log(fm.Log(timestamp=_stamp(t), level=fm.LogLevel.Info,
                                  message=str(row["text"]), name=str(app or "robot")),
                           log_time=at)
        elif kind == "user":
            action = str(row.get("action") or "")
            what = describe(line)
            self.user.log({"action": action, "what": what, "text": str(row.get("text") or ""),
                           "seq": line.seq}, log_time=at)
            if action == "say":
                self.words.log(fm.Log(timestamp=_stamp(t), level=fm.LogLevel.Info,
                                      message=str(row.get("text") or ""), name="user"),
                               log_time=at)
        elif kind == "event":
            self.events.log({"name": str(row.get("text") or ""),
                             "data": dict(row.get("detail") or {}), "seq": line.seq},
                            log_time=at)
        elif kind == "state" and app is not None:
            self._app(str(app)).log({"state": str(row.get("text") or ""), "app": str(app)},
                                    log_time=at)
        if _is_decision(kind):
            self.mediator.log({
                "kind": kind, "app": str(app or ""), "ab": row.get("ab", -1),
                "tree": row.get("tree", -1), "command": str(row.get("command") or ""),
                "reason": str(row.get("reason") or ""), "text": str(row.get("text") or ""),
                "devices": list(row.get("devices") or []), "what": describe(line),
                "seq": line.seq, "detail": dict(row.get("detail") or {})}, log_time=at)

    def _app(self, app: str) -> foxglove.Channel:
        if app not in self.apps:
            self.apps[app] = self._json(f"/apps/{app}/state", "prima.AppState")
        return self.apps[app]

    def _poses(self, row: Mapping[str, Any], t: float, at: int) -> None:
        transforms = []
        for who in ("robot", "user"):
            pose = _xyz(row.get(who))
            walked = self.walked[who]
            if pose is None or (walked and walked[-1] == (t, pose)):
                continue
            walked.append((t, pose))
            x, y, heading = pose
            transforms.append(fm.FrameTransform(
                timestamp=_stamp(t), parent_frame_id="map", child_frame_id=who,
                translation=fm.Vector3(x=x, y=y, z=0.0), rotation=_rotation(heading)))
            self.poses[who].log(fm.PoseInFrame(timestamp=_stamp(t), frame_id="map",
                                               pose=_pose(x, y, heading)), log_time=at)
        if transforms:
            self.tf.log(fm.FrameTransforms(transforms=transforms), log_time=at)

    def _devices(self, row: Mapping[str, Any], kind: str, at: int) -> None:
        ab = row.get("ab")
        if not isinstance(ab, int):
            return
        for device in row.get("devices") or ():
            holders = self.holders.setdefault(str(device), {})
            if kind == "start":
                holders[ab] = dict(row)
            else:
                holders.pop(ab, None)
            if device not in self.devices:
                self.devices[device] = self._json(f"/devices/{device}", "prima.DeviceState")
            holder = next(reversed(holders.values()), None)
            if holder is None:
                message = {"state": "idle", "app": "", "command": "", "ab": -1, "text": ""}
            else:
                message = {"state": f"{holder.get('app')}: {holder.get('command')}",
                           "app": str(holder.get("app") or ""),
                           "command": str(holder.get("command") or ""),
                           "ab": int(holder["ab"]), "text": str(holder.get("text") or "")}
            self.devices[device].log(message, log_time=at)

    # ---------------------------------------------------------------- the end

    def judged(self) -> Report:
        """The judge's report of the lines written so far."""
        return judge(self.lines, name="run")

    def finding(self, t: float, measure: str, message: str) -> None:
        """Log one of the judge's findings at its time (``/judge``)."""
        self.findings.log(fm.Log(timestamp=_stamp(t), level=fm.LogLevel.Warning,
                                 message=message, name=measure), log_time=_nanos(t))

    def paths_so_far(self, kept: int = 2000) -> None:
        """Log the robot's and the user's paths walked so far (their latest ``kept``
        poses), at the latest time: what a live view draws as it goes."""
        for who, walked in self.walked.items():
            if walked:
                self.paths[who].log(fm.PosesInFrame(
                    timestamp=_stamp(self.end), frame_id="map",
                    poses=[_pose(x, y, h) for _t, (x, y, h) in walked[-kept:]]),
                    log_time=_nanos(self.end))

    def layout(self) -> str:
        """The Foxglove layout of this run (its devices and applications), as JSON."""
        return layout(list(self.devices) or HOME_DEVICES, list(self.apps)).to_json()

    def close(self) -> None:
        """Add the judge's findings, the paths and the layout, and finish the file (put it
        in its place)."""
        report = self.judged()
        for t, measure, message in _findings(report):
            self.finding(t, measure, message)
        counts = ", ".join(f"{n} {key}" for key, n in report.counts().items())
        self.findings.log(fm.Log(timestamp=_stamp(self.end),
                                 level=fm.LogLevel.Info if report.ok else fm.LogLevel.Warning,
                                 message=f"prima judge: {counts}", name="summary"),
                          log_time=_nanos(self.end))
        for who, walked in self.walked.items():
            if walked:
                self.paths[who].log(fm.PosesInFrame(
                    timestamp=_stamp(0), frame_id="map",
                    poses=[_pose(x, y, h) for _t, (x, y, h) in walked]), log_time=0)
        self._finish()
        if self._staged is not None:
            self._staged.commit()

    def _discard(self) -> None:
        if self._staged is not None:
            self._staged.discard()

    def _check(self) -> None:
        """An OutputError if a write has failed."""
        if self._file is not None and self._file.error is not None:
            self._finish()
            self._discard()
            error = self._file.error
            reason = error.strerror or str(error)
            raise OutputError(f"cannot write {shown(self.path or '')}: "
                              f"{reason[:1].lower() + reason[1:]}") from error

    def _finish(self) -> None:
        """Finish the writer's file (the run's layout attached, its summary, its index),
        once."""
        if self.writer is None:
            return
        writer, self.writer = self.writer, None
        try:
            writer.attach(log_time=0, create_time=0, name=ATTACHMENT,
                          media_type="application/json", data=self.layout().encode("utf-8"))
            writer.close()
        except RuntimeError as exc:  # foxglove's own error: never the user's traceback
            self._discard()
            raise OutputError(f"cannot write {shown(self.path or '')}: the MCAP writer failed "
                              f"({exc})") from exc
        self._check()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if kind is None or issubclass(kind, KeyboardInterrupt):
            self.close()  # (Ctrl-C comes between two lines: the recording is whole)
            return
        with contextlib.suppress(Exception):  # the run failed: its error is the one told
            self._finish()
        self._discard()


_DECISIONS = frozenset(kind.value for kind in DecisionKind)
"""The kinds of the mediator's decision lines (the ``/prima/decisions`` topic)."""


def _is_decision(kind: str) -> bool:
    return kind in _DECISIONS


def _findings(report: Report) -> list[tuple[float, str, str]]:
    """(time, measure, what) of every finding, in time order: each measure's findings as
    its own line of ``prima judge``'s table says them (the judge's table of measures)."""
    from prima.judge import MEASURES

    out = [(float(f.t), m.key, m.line(f))
           for m in MEASURES for f in report.of(m.key)]
    return sorted(out, key=lambda f: f[0])
