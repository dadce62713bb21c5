"""The device timeline drawn with matplotlib (the ``plot`` extra).

No pyplot and no global state: each picture is its own ``Figure``, saved with the
format its file's suffix names. An SVG is byte-identical across runs (a fixed
hash salt, no date), and so is a PNG or a PDF (no date or software version).
"""

from __future__ import annotations

import io
from collections.abc import Sequence
from pathlib import Path

import matplotlib
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from prima.escape import PLAIN_TEXT
from prima.output import written_bytes
from prima.plot._names import abbreviate
from prima.timeline import Bar, Timeline, ink, runs

__all__ = ["app_colors", "draw_timeline", "save_timeline", "timeline_figure"]


_PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b",
            "#e377c2", "#7f7f7f", "#bcbd22", "#17becf")
_WORLD_ROWS = ("user", "events")
_FONT = 7.0
_CHAR = 0.56
"""A character's width, in font sizes (an estimate, for fitting labels)."""
_METADATA = {".svg": {"Date": None}, ".pdf": {"CreationDate": None, "ModDate": None},
             ".png": {"Software": None}}


def app_colors(apps: Sequence[str]) -> dict[str, str]:
    """Each application's colour, in load order."""
    return {app: _PALETTE[i % len(_PALETTE)] for i, app in enumerate(apps)}


def _merged(spans: Sequence[tuple[float, float, str]]) -> list[tuple[float, float]]:
    """Bars of one Command that touch (its feedback iterations), as one (x, width)
    each: no seams between them; a seam stays where the Command changes."""
    out: list[tuple[float, float, str]] = []
    for t0, t1, command in sorted(spans, key=lambda s: s[0]):
        if out and command == out[-1][2] and t0 <= out[-1][1] + 1e-6:
            out[-1] = (out[-1][0], max(out[-1][1], t1), command)
        else:
            out.append((t0, t1, command))
    return [(t0, max(t1 - t0, 0.02)) for t0, t1, _ in out]


def _label(run: Sequence[Bar], room: float) -> str | None:
    """The longest label of a run that fits ``room`` points, if any."""
    first = run[0]
    command = first.command
    count = f" x{len(run)}" if len(run) > 1 else ""
    candidates = [f"{command}{count}", command, abbreviate(command), abbreviate(command, 1)]
    if first.text:
        words = first.text if len(first.text) <= 40 else first.text[:39] + "..."
        candidates.insert(0, f'{command} "{words}"')
    for text in dict.fromkeys(candidates):
        if len(text) * (_FONT - 1) * _CHAR + 2 <= room:
            return text
    return None


def draw_timeline(ax: Axes, tl: Timeline, *, width_pt: float, labels: bool = True,
                  world: bool = True, waits: bool = True) -> list[str]:
    """Draw ``tl`` on ``ax`` (``width_pt``: the axes' width in points, to fit labels);
    returns the row names, top to bottom (row i is drawn at y = -i)."""
    colors = app_colors(tl.apps)
    rows = ([*_WORLD_ROWS] if world else []) + list(tl.devices)
    waiting = [a for a in tl.apps if any(s.app == a for s in tl.spans)] if waits else []
    rows += [f"{a} waits" for a in waiting]
    y = {name: -i for i, name in enumerate(rows)}
    end = max(tl.end, 1.0)
    per_s = width_pt / end
    ax.set_xlim(0, end)
    ax.set_ylim(-max(len(rows), 1) + 0.5, 0.5)
    ax.set_yticks([-i for i in range(len(rows))], rows, fontsize=_FONT)
    ax.tick_params(axis="x", labelsize=_FONT)
    ax.set_xlabel(tl.time_axis(), fontsize=_FONT)
    ax.grid(axis="x", color="#dddddd", linewidth=0.5)
    ax.set_axisbelow(True)
    for i in range(len(rows) - 1):
        ax.axhline(-i - 0.5, color="#eeeeee", linewidth=0.5, zorder=0)

    for device in tl.devices:
        mine = [b for b in tl.bars if b.device == device]
        for i, app in enumerate(tl.apps):
            for blended in (False, True):
                spans = _merged([(b.t0, b.t1, b.command) for b in mine
                                 if b.app == app and b.blended == blended])
                if not spans:
                    continue
                # two applications blended on a device share its row: a half each
                low, height = ((0.0 if i % 2 == 0 else -0.4), 0.4) if blended else (-0.4, 0.8)
                ax.broken_barh(spans, (y[device] + low, height), facecolors=colors[app],
                               edgecolors="white", linewidth=0,
                               hatch="...." if blended else None)
        if not labels:
            continue
        for run in runs([b for b in mine if not b.blended]):
            t0, t1 = run[0].t0, run[-1].t1
            text = _label(run, (t1 - t0) * per_s)
            if text:
                ax.text((t0 + t1) / 2, y[device], text, ha="center", va="center",
                        fontsize=_FONT - 1, color=ink(colors[run[0].app]), clip_on=True)

    for span in tl.spans if waits else ():
        row = y[f"{span.app} waits"]
        hatch = "////" if span.kind == "suspend" else "xxxx"
        low = 0.0 if span.kind == "suspend" else -0.38
        ax.broken_barh([(span.t0, max(span.t1 - span.t0, 0.05))], (row + low, 0.36),
                       facecolors="none", edgecolors=colors[span.app], hatch=hatch,
                       linewidth=0.6)
        if labels:
            text = f"{span.kind} {span.command}".strip()
            if len(text) * _FONT * _CHAR <= (span.t1 - span.t0) * per_s:
                ax.text((span.t0 + span.t1) / 2, row + low + 0.18, text, ha="center", va="center",
                        fontsize=_FONT - 1, bbox={"facecolor": "white", "linewidth": 0,
                                                  "pad": 0.5})
    for mark in tl.marks if waits else ():
        if f"{mark.app} waits" in y:
            ax.plot([mark.t], [y[f"{mark.app} waits"]], marker="|", markersize=8,
                    color=colors[mark.app])
    if world:
        _world(ax, tl, y, per_s, labels)
    return rows


def _world(ax: Axes, tl: Timeline, y: dict[str, int], per_s: float, labels: bool) -> None:
    """The user's actions and the events: ticks, labelled in two lanes where they fit
    (the words said in quotes, an action by its name: ``walk``)."""
    for row, name, marker, color in (("user", "user", "v", "#333333"),
                                     ("event", "events", "d", "#555555")):
        ticks = [k for k in tl.ticks if k.row == row]
        if not ticks:
            continue
        ax.plot([k.t for k in ticks], [y[name] - 0.25] * len(ticks), linestyle="none",
                marker=marker, markersize=4, color=color)
        if not labels:
            continue
        lanes = [float("-inf"), float("-inf")]
        for tick in ticks:
            shown = tick.label if tick.text is not None or not tick.action else tick.action
            text = shown if len(shown) <= 32 else shown[:31] + '..."'
            width = (len(text) * (_FONT - 1) * _CHAR + 6) / per_s
            lane = next((i for i, free in enumerate(lanes) if tick.t >= free), None)
            if lane is None:
                continue
            lanes[lane] = tick.t + width
            ax.text(tick.t, y[name] + 0.3 - 0.28 * lane, " " + text, ha="left", va="center",
                    fontsize=_FONT - 1, color=color, clip_on=True)


def _legend(fig: Figure, tl: Timeline) -> None:
    colors = app_colors(tl.apps)
    handles: list[Patch | Line2D] = [Patch(facecolor=colors[a], label=a) for a in tl.apps]
    kinds = {s.kind for s in tl.spans}
    if "suspend" in kinds:
        handles.append(Patch(facecolor="none", edgecolor="#555555", hatch="////",
                             label="suspended"))
    if "hold" in kinds:
        handles.append(Patch(facecolor="none", edgecolor="#555555", hatch="xxxx",
                             label="held back"))
    if any(b.blended for b in tl.bars):
        handles.append(Patch(facecolor="#888888", edgecolor="white", linewidth=0,
                             hatch="....", label="blended (half a row)"))
    fig.legend(handles=handles, loc="upper right", ncols=len(handles), fontsize=_FONT,
               frameon=False, bbox_to_anchor=(0.99, 0.995))


def timeline_figure(tl: Timeline, title: str = "", width: float = 12.0) -> Figure:
    """The whole picture: the timeline, a title and a legend."""
    rows = 2 + len(tl.devices) + len({s.app for s in tl.spans})
    height = 1.1 + 0.3 * rows
    fig = Figure(figsize=(width, height))
    left, right = 1.35, 0.15
    bottom, top = 0.45, 0.4
    ax = fig.add_axes((left / width, bottom / height, 1 - (left + right) / width,
                       1 - (bottom + top) / height))
    draw_timeline(ax, tl, width_pt=(width - left - right) * 72)
    if title:
        fig.text(0.01, 0.995, title, ha="left", va="top", fontsize=_FONT + 2,
                 fontweight="bold")
    _legend(fig, tl)
    return fig


def save_timeline(tl: Timeline, path: str | Path, title: str = "") -> None:
    """Draw ``tl`` and save it; the format is the file's suffix (.svg, .png, .pdf)."""
    suffix = Path(path).suffix.lower()
    with matplotlib.rc_context({"svg.hashsalt": "prima", "svg.fonttype": "none",
                                "font.family": "DejaVu Sans", **PLAIN_TEXT}):
        fig = timeline_figure(tl, title)
        # drawn in memory, then written: a full disk under matplotlib's PDF writer fails in
        # its own clean-up (an AttributeError), not with the disk's OSError
        picture = io.BytesIO()
        fig.savefig(picture, format=suffix[1:], dpi=150, metadata=_METADATA.get(suffix))
        with written_bytes(path) as out:
            out.write(picture.getbuffer())
