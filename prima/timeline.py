"""The device timeline of a run, as data: what ``prima show`` and ``prima plot`` draw.

Pure Python (no drawing library): a run's jsonl records (``TraceLine.to_dict()``,
or :func:`prima.tracefile.read_trace`), in trace order, become

- bars: one per atomic behavior and device it occupied, from its ``start`` to its
  ``end`` (or the trace's end, ``ended=False``); an AB that occupied no device has
  one bar on the :data:`NO_DEVICE` row; ``blended`` where its start's ``over``
  detail says it shared the device (the blend policy);
- wait spans: ``suspend``, from a ``suspend`` line until its stream (the tree)
  resumes or the AB it was suspended at starts, ends or is cancelled; ``hold``,
  from a ``hold`` line until that AB starts, ends or is cancelled, or is held anew
  (another reason, another holder), or (a stream hold, a block) its holder releases;
- marks: instant decisions (release, cancel, interrupt, failure, error, unload);
- ticks: what the user did and the events posted;
- the robot's and the user's poses, and the trace's end.

Both viewers draw from this one digest, so they cannot disagree on what a trace
means.
"""

from __future__ import annotations

import re
from array import array
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, overload

from prima.trace import Pose, user_words

__all__ = ["JOIN", "MAX_ROWS", "NO_DEVICE", "Bar", "Builder", "Mark", "Poses", "Span", "Tick",
           "Timeline", "blended_devices", "ink", "runs", "timeline"]

Row = Mapping[str, Any]

NO_DEVICE = "(no device)"
"""The row of an atomic behavior that occupies no device (last of the devices)."""

MAX_ROWS = 64
"""Devices a timeline draws at most, in the order first occupied (a robot has a dozen; a
trace that names thousands, forged or not, would make a picture of gigabytes): the rest
are counted in :attr:`Timeline.hidden` and said under the picture."""

JOIN = 0.05
"""Seconds between two bars of one run (:func:`runs`) at most."""

_OVER = re.compile(r" on ([^,\s]+)")
"""The devices in a blended start's ``over`` detail (``over AB12 on locomotion``)."""
_FREED = re.compile(r" on (.+)$")
"""The devices a release frees, in its text (``block on arm, camera``)."""
_KEPT_FOR = re.compile(r"devices kept for ([^\s']+)|while (\S+) answers the user")
"""The holder of a stream hold, a block, a reaction's next AB or an answer to the user, in
its ``hold`` line's text."""
_NOT_RELEASED = frozenset({"keep-channel", "answering", "reserved"})
"""Holds no ``release`` line ends: the channel rule's, one while another reaction answers
the user, one for a reaction's next AB (they end with their AB, or its next hold)."""
_ENDS_WAIT = frozenset({"start", "end", "cancel"})
"""What ends the waits of an AB: it starts, ends, or is cancelled."""
_MARKS = frozenset({"release", "cancel", "interrupt", "failure", "error", "unload"})
"""Instant decisions, marked where they happened."""


@dataclass(frozen=True, slots=True)
class Bar:
    """An atomic behavior on one device, from its ``start`` to its ``end``."""

    ab: int
    device: str
    app: str
    command: str
    t0: float
    t1: float
    text: str | None = None
    blended: bool = False
    """It shared this device with another AB (the blend policy)."""
    ended: bool = True
    """False: still running when the trace ended (``t1`` is the trace's end)."""


@dataclass(frozen=True, slots=True)
class Span:
    """A while an application's AB waited: ``suspend`` (its stream lost a device) or
    ``hold`` (another application's hold, or the channel rule, kept it back)."""

    kind: str
    app: str
    ab: int | None
    command: str
    t0: float
    t1: float
    reason: str = ""
    devices: tuple[str, ...] = ()
    """The devices the AB waited for (:data:`NO_DEVICE` if none)."""
    line: int = 0
    """The index of the ``suspend`` or ``hold`` line among the rows."""
    holder: str = ""
    """A hold's holder: the app whose stream hold, block, reaction's next AB or answer to
    the user kept the devices, as its line names it (empty: unnamed, the channel
    rule's, or a suspension)."""


@dataclass(frozen=True, slots=True)
class Mark:
    """An instant decision: release, cancel, interrupt, failure, error or unload."""

    kind: str
    t: float
    app: str
    ab: int | None
    devices: tuple[str, ...]
    """The devices of its AB, those a release frees; none for an application's own."""
    line: int
    """The index of its line among the rows."""
    reason: str = ""


@dataclass(frozen=True, slots=True)
class Tick:
    """A moment on a top row: ``user`` (what the user did) or ``event``."""

    row: str
    t: float
    label: str
    """What the user did as the text trace words it (``"words"``, ``walks to hall``),
    or the event's name."""
    text: str | None = None
    """The words, when the user said something."""
    action: str = ""
    """What the user did (``say``, ``walk``, ``touch``, ...); empty for an event."""


class Poses(Sequence[tuple[float, Pose]]):
    """Pose samples in time order, each ``(t, (x, y, heading))``, kept as one array of
    floats, four a sample: a long run has hundreds of thousands of them, which as tuples
    of floats took five times the room."""

    def __init__(self, samples: Iterable[tuple[float, Pose]] = ()) -> None:
        self.floats = array("d")
        """t, x, y and heading of each sample, one after the other."""
        for sample in samples:
            self.append(sample)

    def append(self, sample: tuple[float, Pose]) -> None:
        t, pose = sample
        self.floats.extend((t, *pose))

    def __len__(self) -> int:
        return len(self.floats) // 4

    @overload
    def __getitem__(self, index: int) -> tuple[float, Pose]: ...

    @overload
    def __getitem__(self, index: slice) -> list[tuple[float, Pose]]: ...

    def __getitem__(self, index: int | slice) -> tuple[float, Pose] | list[tuple[float, Pose]]:
        if isinstance(index, slice):
            return [self[k] for k in range(*index.indices(len(self)))]
        k = index + len(self) if index < 0 else index
        if not 0 <= k < len(self):
            raise IndexError("pose sample out of range")
        t, x, y, heading = self.floats[4 * k:4 * k + 4]
        return (t, (x, y, heading))

    def __iter__(self) -> Iterator[tuple[float, Pose]]:
        floats = self.floats
        for k in range(0, len(floats), 4):
            yield (floats[k], (floats[k + 1], floats[k + 2], floats[k + 3]))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Sequence) and list(self) == list(other)

    def __repr__(self) -> str:
        return f"Poses({list(self)!r})"


@dataclass
class Timeline:
    """A run's device timeline."""

    devices: list[str] = field(default_factory=list)
    """The devices ABs occupied, in the order first occupied; then those ABs only
    waited for or were cancelled on, in the order first named; then
    :data:`NO_DEVICE`, if an AB had no device."""
    apps: list[str] = field(default_factory=list)
    """In the order they were loaded (or first seen)."""
    bars: list[Bar] = field(default_factory=list)
    """By start, AB and device."""
    spans: list[Span] = field(default_factory=list)
    """By start, application and line."""
    marks: list[Mark] = field(default_factory=list)
    """In trace order."""
    ticks: list[Tick] = field(default_factory=list)
    """In trace order."""
    robot: Poses = field(default_factory=Poses)
    user: Poses = field(default_factory=Poses)
    """The poses on every line that has them, in time order (of a run of equal ones, the
    first and the last)."""
    end: float = 0.0
    """The time of the trace's last line."""
    hidden: int = 0
    """Devices beyond :data:`MAX_ROWS`, not drawn (nor what ran on them)."""

    def time_axis(self) -> str:
        """The time axis's title, which says how many devices are not drawn, if any."""
        more = f"; {self.hidden:,} more devices not drawn" if self.hidden else ""
        return f"simulated time (s){more}"

    def speech(self) -> list[Bar]:
        """The robot's words: the first bar of each AB with text."""
        seen: set[int] = set()
        out = []
        for bar in self.bars:
            if bar.text and bar.ab not in seen:
                seen.add(bar.ab)
                out.append(bar)
        return out


def runs(bars: Iterable[Bar], join: float = JOIN) -> list[list[Bar]]:
    """Bars that follow one another on one device, of one application and Command and
    without words, at most ``join`` s apart: a feedback Command's iterations (a move,
    tracking), which a viewer labels once (``TopologicalMove x54``). By device, then
    start; a bar that follows nothing is a run of its own."""
    out: list[list[Bar]] = []
    for bar in sorted(bars, key=lambda b: (b.device, b.t0, b.ab)):
        last = out[-1][-1] if out else None
        if (last is not None and last.device == bar.device and last.app == bar.app
                and last.command == bar.command and not bar.text and not last.text
                and bar.t0 - last.t1 <= join):
            out[-1].append(bar)
        else:
            out.append([bar])
    return out


def ink(colour: str) -> str:
    """The text colour that reads on a bar of ``colour`` (``#rrggbb``), as both viewers
    label an application's bars: black on a light one, else white."""
    r, g, b = (int(colour[k:k + 2], 16) / 255 for k in (1, 3, 5))
    return "black" if 0.299 * r + 0.587 * g + 0.114 * b > 0.6 else "white"


def blended_devices(over: object) -> frozenset[str]:
    """The devices a start's ``over`` detail names (the blend policy), if any."""
    return frozenset(_OVER.findall(str(over or "")))


def _pose(value: Any) -> Pose | None:
    if not isinstance(value, Mapping):
        return None
    try:
        return (float(value["x"]), float(value["y"]), float(value.get("heading", 0.0)))
    except (KeyError, TypeError, ValueError):
        return None


def _devices(row: Row) -> tuple[str, ...]:
    return tuple(str(d) for d in row.get("devices") or ()) or (NO_DEVICE,)


def _detail(row: Row) -> Mapping[str, Any]:
    detail = row.get("detail")
    return detail if isinstance(detail, Mapping) else {}


_Wait = tuple[str, str, int | None]
"""A wait's key: (``suspend`` or ``hold``, the waiting app, the AB it is about)."""


def _holder(hold: Row) -> str:
    """The app a ``hold`` line says keeps the devices ("": it names none)."""
    holder = _KEPT_FOR.match(str(hold.get("text") or ""))
    return (holder.group(1) or holder.group(2)) if holder else ""


class Builder:
    """Builds a :class:`Timeline` line by line (``feed``), so a trace need not be held
    whole; ``finish`` closes what is still open."""

    def __init__(self) -> None:
        self.out = Timeline()
        self.running: dict[int, Row] = {}
        """AB -> its start line, while it runs."""
        self.waiting: dict[_Wait, tuple[int, Row]] = {}
        """(kind, app, ab) -> the index and the line of the suspend or hold that began it."""
        self.streams: dict[tuple[str, object], list[tuple[_Wait, int]]] = {}
        """(app, tree) -> the suspensions its resume ends, as (key, line): some perhaps
        ended already (a wait is still under way while ``waiting`` has its line)."""
        self.holders: dict[str, list[tuple[_Wait, int]]] = {}
        """A holder ("": one its hold line does not name) -> the holds its release ends,
        as (key, line), the same way."""
        self.apps: dict[str, None] = {}
        """The apps, in the order first seen (a dict as an ordered set)."""
        self.occupied: dict[str, None] = {}
        """The devices ABs occupied, in the order first occupied."""
        self.names: dict[str, str] = {}
        self.still: dict[str, tuple[float, Pose]] = {}
        """Robot or user -> the last sample of a run of equal poses, not yet kept."""
        self.named: dict[str, None] = {}
        """The devices of the ABs' lines (:data:`NO_DEVICE` for none), in the order first
        named."""

    def app(self, name: object) -> str:
        app = self.name(str(name)) if name is not None else "?"
        self.apps[app] = None
        return app

    def name(self, text: str) -> str:
        """One string for all equal names and words: a long trace repeats the same few
        (a parsed line's strings are each new)."""
        return self.names.setdefault(text, text)

    def feed(self, i: int, row: Row) -> None:
        t = float(row["t"])
        self.out.end = max(self.out.end, t)
        kind = str(row["kind"])
        for who, poses in (("robot", self.out.robot), ("user", self.out.user)):
            pose = _pose(row.get(who))
            if pose is not None:
                self.posed(who, poses, t, pose)
        ab = row.get("ab")
        ab = ab if isinstance(ab, int) else None
        app = None if row.get("app") is None else self.app(row.get("app"))
        if app is not None:
            self.ends_waits(kind, app, ab, row, t)
        if kind == "start" and ab is not None:
            self.running[ab] = row
            devices = _devices(row)
            self.named.update(dict.fromkeys(devices))
            self.occupied.update(dict.fromkeys(d for d in devices if d != NO_DEVICE))
        elif kind == "end" and ab is not None:
            start = self.running.pop(ab, None)
            if start is not None:
                self.bars(start, t, ended=True)
        elif kind in ("suspend", "hold") and app is not None:
            self.wait((kind, app, ab), i, row)
            self.named.update(dict.fromkeys(_devices(row)))
        elif kind == "user":
            action = str(row.get("action") or "")
            said = row.get("text") if action == "say" else None
            self.out.ticks.append(Tick("user", t, user_words(action, said, _detail(row)),
                                       None if said is None else str(said), action))
        elif kind == "event":
            self.out.ticks.append(Tick("event", t, str(row.get("text") or "event")))
        if kind in _MARKS and app is not None:
            self.mark(i, row, kind, app, ab, t)

    def posed(self, who: str, poses: Poses, t: float, pose: Pose) -> None:
        """A pose sample; of a run of equal ones, only the first and the last are kept
        (what lies between them is the same pose, however it is interpolated)."""
        if poses and poses[-1][1] == pose:
            self.still[who] = (t, pose)  # the run's last, for now
            return
        last = self.still.pop(who, None)
        if last is not None:
            poses.append(last)
        poses.append((t, pose))

    def wait(self, key: _Wait, i: int, row: Row) -> None:
        """A suspend or hold line begins a wait (unless that AB's is under way; a hold for
        another reason or holder ends the one under way and begins its own)."""
        under_way = self.waiting.get(key)
        if under_way is not None:
            was = under_way[1]
            if key[0] == "suspend" or (was.get("reason"), was.get("text")) == (
                    row.get("reason"), row.get("text")):
                return
            self.close(key, float(row["t"]))
        self.waiting[key] = (i, row)
        if key[0] == "suspend":
            self.streams.setdefault((key[1], row.get("tree")), []).append((key, i))
        elif row.get("reason") not in _NOT_RELEASED:
            # ("": unnamed, any release ends it)
            self.holders.setdefault(_holder(row), []).append((key, i))

    def ends_waits(self, kind: str, app: str, ab: int | None, row: Row, t: float) -> None:
        """Close the waits this line ends: the waiting AB starts, ends or is cancelled; a
        suspended stream (its tree) resumes; a holder releases (the channel rule's holds
        end only with their AB). Each wait is found by its key, never by a scan."""
        waiting = self.waiting
        if kind in _ENDS_WAIT:
            if ab is not None:
                for own in (("suspend", app, ab), ("hold", app, ab)):
                    if own in waiting:
                        self.close(own, t)
            return
        if kind == "resume":
            ended = self.streams.pop((app, row.get("tree")), [])
        elif kind == "release":
            ended = self.holders.pop(app, []) + self.holders.pop("", [])
        else:
            return
        for key, i in ended:
            if key in waiting and waiting[key][0] == i:
                self.close(key, t)

    def mark(self, i: int, row: Row, kind: str, app: str, ab: int | None, t: float) -> None:
        if ab is not None:
            devices = _devices(row)
            self.named.update(dict.fromkeys(devices))
        else:
            freed = _FREED.search(str(row.get("text") or "")) if kind == "release" else None
            devices = tuple(freed.group(1).split(", ")) if freed else ()
        self.out.marks.append(Mark(kind, t, app, ab, devices, i, str(row.get("reason") or "")))

    def close(self, key: _Wait, t: float) -> None:
        i, row = self.waiting.pop(key)
        holder = _holder(row) if key[0] == "hold" else ""
        self.out.spans.append(Span(key[0], key[1], key[2], str(row.get("command") or ""),
                                   float(row["t"]), t, str(row.get("reason") or ""),
                                   _devices(row), i, holder))

    def bars(self, start: Row, t1: float, ended: bool) -> None:
        blended = blended_devices(_detail(start).get("over"))
        text = start.get("text")
        app = self.app(start.get("app"))
        command = self.name(str(start.get("command") or "AB"))
        said = self.name(str(text)) if text else None
        for device in _devices(start):
            self.out.bars.append(Bar(
                ab=int(start["ab"]), device=self.name(device), app=app, command=command,
                t0=float(start["t"]), t1=t1, text=said, blended=device in blended,
                ended=ended))

    def finish(self) -> Timeline:
        out = self.out
        for who, poses in (("robot", out.robot), ("user", out.user)):
            last = self.still.pop(who, None)
            if last is not None:
                poses.append(last)
        for start in self.running.values():
            self.bars(start, out.end, ended=False)
        self.running.clear()
        for key in list(self.waiting):
            self.close(key, out.end)
        out.apps = list(self.apps)
        named = [d for d in self.named if d not in self.occupied]
        out.devices = [*self.occupied, *sorted(named, key=lambda d: d == NO_DEVICE)]  # (last)
        if len(out.devices) > MAX_ROWS:
            _keep_rows(out)
        place = {d: i for i, d in enumerate(out.devices)}
        out.bars.sort(key=lambda b: (b.t0, b.ab, place[b.device]))
        out.spans.sort(key=lambda s: (s.t0, s.app, s.line))
        return out


def _keep_rows(out: Timeline) -> None:
    """Keep the first :data:`MAX_ROWS` devices, and what ran or waited on them."""
    out.hidden = len(out.devices) - MAX_ROWS
    out.devices = out.devices[:MAX_ROWS]
    kept = set(out.devices)
    out.bars = [b for b in out.bars if b.device in kept]
    out.spans = [replace(s, devices=tuple(d for d in s.devices if d in kept))
                 for s in out.spans]
    out.marks = [replace(m, devices=tuple(d for d in m.devices if d in kept))
                 for m in out.marks]


def timeline(rows: Iterable[Row]) -> Timeline:
    """The timeline of a run's jsonl records, in trace order."""
    builder = Builder()
    for i, row in enumerate(rows):
        builder.feed(i, row)
    return builder.finish()
