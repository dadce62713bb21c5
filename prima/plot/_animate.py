"""A run animated as a GIF (the ``plot`` extra): the map with the robot and the user
moving, the words being said, and the device timeline with a playhead.

Frames are drawn on one matplotlib figure (no pyplot), every ``step`` simulated
seconds, and written by Pillow with one palette for the whole animation, so the
file stays small and the same run always gives the same bytes.
"""

from __future__ import annotations

import bisect
import io
import math
import textwrap
from collections.abc import Sequence
from pathlib import Path

import matplotlib
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Patch
from PIL import Image

from prima.escape import PLAIN_TEXT
from prima.output import written_bytes
from prima.plot._draw import app_colors, draw_timeline
from prima.sim import WorldMap
from prima.timeline import Timeline
from prima.trace import Pose

__all__ = ["pose_at", "save_animation"]

_WIDTH, _HEIGHT, _DPI = 6.4, 5.6, 80
_SAID_FOR = 2.5
"""How long (s) the user's words stay on screen."""
_ROBOT, _USER = "#222222", "#2ca02c"


def pose_at(poses: Sequence[tuple[float, Pose]], t: float) -> Pose | None:
    """The pose at ``t``, interpolated between the two nearest known poses."""
    if not poses:
        return None
    times = [p[0] for p in poses]
    i = bisect.bisect_right(times, t)
    if i == 0:
        return poses[0][1]
    if i == len(poses):
        return poses[-1][1]
    (t0, a), (t1, b) = poses[i - 1], poses[i]
    f = 0.0 if t1 <= t0 else (t - t0) / (t1 - t0)
    turn = (b[2] - a[2] + 180.0) % 360.0 - 180.0
    return (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]), (a[2] + f * turn) % 360.0)


def _bounds(tl: Timeline, world: WorldMap | None) -> tuple[float, float, float, float]:
    points = (world.outline() if world is not None else []) + [
        (pose[0], pose[1]) for _, pose in [*tl.robot, *tl.user]]
    xs, ys = [x for x, _ in points], [y for _, y in points]
    if not xs:
        return (0.0, 1.0, 0.0, 1.0)
    return (min(xs) - 0.6, max(xs) + 0.6, min(ys) - 0.6, max(ys) + 0.6)


def _draw_map(ax: matplotlib.axes.Axes, world: WorldMap | None) -> None:
    if world is None:
        return
    for w in world.walls:
        ax.plot([w.x1, w.x2], [w.y1, w.y2], color="#555555", linewidth=2,
                solid_capstyle="projecting", zorder=1)
    for p in world.places:
        ax.plot([p.x], [p.y], marker="+", color="#999999", markersize=5, zorder=1)
        ax.text(p.x, p.y - 0.25, p.name, fontsize=6, color="#888888", ha="center", va="top",
                zorder=1)


def _caption(text: str, width: int = 70) -> str:
    lines = textwrap.wrap(text, width)
    return "\n".join(lines[:2]) + (" ..." if len(lines) > 2 else "")


def _short(words: str, most: int = 26) -> str:
    return words if len(words) <= most else words[:most - 4] + '..."'


class _Frames:
    """The figure and the artists each frame moves."""

    def __init__(self, tl: Timeline, world: WorldMap | None, title: str) -> None:
        self.tl = tl
        self.colors = app_colors(tl.apps)
        self.speech = tl.speech()
        self.said = [k for k in tl.ticks if k.row == "user" and k.text]
        fig = self.fig = Figure(figsize=(_WIDTH, _HEIGHT), dpi=_DPI)
        fig.text(0.02, 0.985, title, fontsize=9, fontweight="bold", va="top")
        self.clock = fig.text(0.98, 0.985, "", fontsize=9, ha="right", va="top")
        ax = fig.add_axes((0.02, 0.36, 0.96, 0.58))
        x0, x1, y0, y1 = _bounds(tl, world)
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        _draw_map(ax, world)
        (self.trail,) = ax.plot([], [], color="#bbbbbb", linewidth=1, zorder=2)
        self.robot = Circle((0, 0), 0.25, facecolor=_ROBOT, zorder=4)
        self.user = Circle((0, 0), 0.2, facecolor=_USER, zorder=3)
        ax.add_patch(self.robot)
        ax.add_patch(self.user)
        (self.robot_nose,) = ax.plot([], [], color=_ROBOT, linewidth=2, zorder=4)
        (self.user_nose,) = ax.plot([], [], color=_USER, linewidth=1.5, zorder=3)
        ax.legend(handles=[Circle((0, 0), 1, color=_ROBOT, label="robot"),
                           Circle((0, 0), 1, color=_USER, label="user"),
                           *(Patch(color=self.colors[a], label=a) for a in tl.apps)],
                  loc="upper left", fontsize=6, frameon=False)
        self.bubble = ax.text(0, 0, "", fontsize=6, ha="left", va="bottom", zorder=5,
                              clip_on=False, bbox={"boxstyle": "round,pad=0.3",
                                                   "facecolor": "white", "linewidth": 0.8})
        self.user_bubble = ax.text(0, 0, "", fontsize=6, ha="right", va="top", zorder=5,
                                   color=_USER, clip_on=False,
                                   bbox={"boxstyle": "round,pad=0.3", "facecolor": "white",
                                         "edgecolor": _USER, "linewidth": 0.8})
        self.robot_says = fig.text(0.02, 0.335, "", fontsize=7, va="top")
        self.user_says = fig.text(0.02, 0.275, "", fontsize=7, va="top", color=_USER)
        strip = fig.add_axes((0.25, 0.06, 0.73, 0.17))
        draw_timeline(strip, tl, width_pt=0.73 * _WIDTH * 72, labels=False, world=False,
                      waits=False)
        strip.tick_params(labelsize=5)
        strip.xaxis.label.set_fontsize(5)
        self.playhead = strip.axvline(0, color="red", linewidth=1)

    def draw(self, t: float) -> Image.Image:
        self.clock.set_text(f"t = {t:5.1f} s")
        for pose, body, nose, reach in ((pose_at(self.tl.robot, t), self.robot,
                                         self.robot_nose, 0.45),
                                        (pose_at(self.tl.user, t), self.user,
                                         self.user_nose, 0.35)):
            body.set_visible(pose is not None)
            nose.set_visible(pose is not None)
            if pose is not None:
                x, y, heading = pose
                body.center = (x, y)
                a = math.radians(heading)
                nose.set_data([x, x + reach * math.cos(a)], [y, y + reach * math.sin(a)])
        past = [p for time, p in self.tl.robot if time <= t]
        self.trail.set_data([p[0] for p in past], [p[1] for p in past])
        words = next((b for b in self.speech if b.t0 <= t < b.t1), None)
        robot = pose_at(self.tl.robot, t)
        if words is not None and words.text:
            color = self.colors.get(words.app, _ROBOT)
            self.robot_says.set_text(_caption(f'robot ({words.app}): "{words.text}"'))
            self.robot_says.set_color(color)
            self.bubble.set_text(_short(f'"{words.text}"'))
            self.bubble.get_bbox_patch().set_edgecolor(color)  # type: ignore[union-attr]
        else:
            self.robot_says.set_text("")
            self.bubble.set_text("")
        self.bubble.set_visible(words is not None and robot is not None)
        if robot is not None:
            self.bubble.set_position((robot[0] + 0.3, robot[1] + 0.35))
        heard = next((k for k in reversed(self.said) if k.t <= t < k.t + _SAID_FOR), None)
        self.user_says.set_text(_caption(f"user: {heard.label}") if heard else "")
        user = pose_at(self.tl.user, t)
        self.user_bubble.set_visible(heard is not None and user is not None)
        if heard is not None and user is not None:
            self.user_bubble.set_text(_short(heard.label))
            self.user_bubble.set_position((user[0] - 0.25, user[1] - 0.3))
        self.playhead.set_xdata([t, t])
        raw = io.BytesIO()
        self.fig.savefig(raw, format="rgba", dpi=_DPI)
        size = (round(_WIDTH * _DPI), round(_HEIGHT * _DPI))
        return Image.frombytes("RGBA", size, raw.getvalue()).convert("RGB")


def save_animation(tl: Timeline, path: str | Path, world: WorldMap | None = None, *,
                   title: str = "", step: float = 1.0, fps: float = 5.0) -> int:
    """Write the run as a GIF, a frame every ``step`` simulated seconds shown at ``fps``
    frames per second; returns the number of frames."""
    count = int(math.floor(tl.end / step + 1e-9)) + 1
    with matplotlib.rc_context({"font.family": "DejaVu Sans", **PLAIN_TEXT}):
        frames = _Frames(tl, world, title)
        images = [frames.draw(i * step) for i in range(count)]
    # one palette for every frame: taken from a strip of frames from the whole run
    sample = [images[i * (count - 1) // 4] for i in range(5)] if count > 1 else images
    strip = Image.new("RGB", (sample[0].width, sample[0].height * len(sample)))
    for i, image in enumerate(sample):
        strip.paste(image, (0, i * image.height))
    palette = strip.quantize(colors=64, method=Image.Quantize.MEDIANCUT)
    indexed = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in images]
    with written_bytes(path) as out:
        indexed[0].save(out, format="GIF", save_all=True, append_images=indexed[1:],
                        duration=max(20, round(1000 / fps)), loop=0, optimize=False)
    return count
