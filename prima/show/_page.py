"""The page: Plotly draws the map and the timeline; ``player.js`` drives the playhead."""

from __future__ import annotations

import io
import shutil
from array import array
from collections.abc import Callable, Iterable, Iterator
from itertools import chain, islice
from typing import Any, TextIO, TypeVar

import plotly.graph_objects as go
import plotly.io as pio
from plotly.colors import qualitative

from prima.escape import markup, script_json
from prima.shipped import packaged
from prima.show._model import Model
from prima.sim import WorldMap
from prima.timeline import Bar, Timeline, ink, runs
from prima.trace import Pose

INSTANT = 0.05
"""The least width (s) of a bar: an atomic behavior that took no time is still seen."""

Window = tuple[float, float]
"""A stretch of the run's time (from, to: simulated seconds) that a timeline shows."""

_SPAN_STYLE = {"suspend": ("/", "#555", "suspended"), "hold": ("x", "#222", "held back")}
"""A wait's hatch, its colour (greys, never an application's) and its name in the legend."""
_MARK_STYLE = {
    "release": ("line-ns-open", "#222", "hold released"),
    "interrupt": ("star-triangle-down", "#8e44ad", "cut"),
    "cancel": ("x", "#7f8c8d", "cancelled"),
}
_SOUND_TOGGLE = ('<label title="the words, heard at 0.5x to 4x"><input id="sound" '
                 'type="checkbox" checked> sound</label>')
"""With sound in the page: a switch for it beside the playback controls."""
_PIECE = 4096
"""The items of a long JSON array written at a time (:func:`_write_json`)."""
_T = TypeVar("_T")
_CONFIG = {"displaylogo": False, "responsive": True, "modeBarButtonsToRemove": ["select2d",
                                                                               "lasso2d"]}


def drawing() -> str:
    """The script both pages draw with (``draw.js``: ``PrimaDraw``)."""
    return packaged("prima.show", "draw.js").read_text(encoding="utf-8")


def style() -> str:
    """The style both pages share (``show.css``)."""
    return packaged("prima.show", "show.css").read_text(encoding="utf-8")


def figure_json(fig: go.Figure) -> dict[str, Any]:
    """A figure as Plotly.newPlot and Plotly.react take it: its traces and its layout
    (with its template), the one way both pages write a figure."""
    return {"data": [trace.to_plotly_json() for trace in fig.data],
            "layout": go.Figure(layout=fig.layout).to_dict()["layout"], "config": _CONFIG}


def _esc(text: str) -> str:
    """Text shown as itself (Plotly reads some HTML in its labels, a forged trace's
    device names too)."""
    return markup(text)


def _label(bar: Bar) -> str:
    return f'{bar.command} "{bar.text}"' if bar.text else bar.command


def _colours(apps: list[str]) -> dict[str, str]:
    palette = qualitative.Plotly
    return {app: palette[i % len(palette)] for i, app in enumerate(apps)}


def _bounds(model: Model, world: WorldMap | None) -> tuple[float, float, float, float]:
    xs, ys = array("d"), array("d")  # (a long run's points, never held as tuples)
    for x, y in chain(world.outline() if world is not None else [],
                      ((pose[0], pose[1]) for _, pose in chain(model.robot, model.user))):
        xs.append(x)
        ys.append(y)
    if not xs:
        return (0.0, 1.0, 0.0, 1.0)
    return (min(xs) - 0.5, max(xs) + 0.5, min(ys) - 0.5, max(ys) + 0.5)


def _angle(heading: float) -> float:
    """Plotly's marker angle (clockwise from up) for a heading (anticlockwise from east)."""
    return round((90.0 - heading) % 360.0, 1)


def map_figure(model: Model, world: WorldMap | None) -> tuple[go.Figure, dict[str, int]]:
    """The map, the paths walked, and the robot's and the user's markers (at t=0)."""
    fig = go.Figure()
    shapes: list[dict[str, Any]] = []
    if world is not None:
        for area in world.areas:
            shapes.append({"type": "rect", "x0": area.x1, "y0": area.y1, "x1": area.x2,
                           "y1": area.y2, "line": {"width": 0}, "layer": "below",
                           "fillcolor": "rgba(52, 152, 219, 0.08)"})
        fig.add_trace(go.Scatter(
            x=[(a.x1 + a.x2) / 2 for a in world.areas],
            y=[max(a.y1, a.y2) - 0.2 for a in world.areas],
            text=[_esc(a.name) for a in world.areas], mode="text", name="areas",
            textfont={"color": "#2980b9", "size": 11}, hoverinfo="skip"))
        wx: list[float | None] = []
        wy: list[float | None] = []
        for w in world.walls:
            wx += [w.x1, w.x2, None]
            wy += [w.y1, w.y2, None]
        fig.add_trace(go.Scatter(x=wx, y=wy, mode="lines", name="walls",
                                 line={"color": "#34495e", "width": 3}, hoverinfo="skip"))
        fig.add_trace(go.Scatter(
            x=[p.x for p in world.places], y=[p.y for p in world.places],
            text=[_esc(p.name) for p in world.places], mode="markers+text", name="places",
            textposition="bottom center", textfont={"size": 9, "color": "#7f8c8d"},
            marker={"size": 5, "color": "#95a5a6"},
            hovertext=[_esc(f"{p.name} ({p.kind.value})") for p in world.places], hoverinfo="text"))
    for who, poses, colour in (("robot", model.robot, "#2c3e50"),
                               ("user", model.user, "#e67e22")):
        fig.add_trace(go.Scatter(x=[p[0] for _, p in poses], y=[p[1] for _, p in poses],
                                 mode="lines", name=f"{who}'s path", hoverinfo="skip",
                                 line={"color": colour, "width": 1, "dash": "dot"},
                                 opacity=0.35))
    index: dict[str, int] = {}
    for who, poses, colour, symbol in (("robot", model.robot, "#2c3e50", "triangle-up"),
                                       ("user", model.user, "#e67e22", "arrow-up")):
        _t, first = poses[0] if poses else (0.0, (0.0, 0.0, 0.0))
        index[who] = len(fig.data)
        fig.add_trace(go.Scatter(x=[first[0]], y=[first[1]], mode="markers", name=who,
                                 marker={"size": 18, "color": colour, "symbol": symbol,
                                         "angle": _angle(first[2]),
                                         "line": {"width": 1, "color": "white"}},
                                 visible=bool(poses), hoverinfo="name"))
    x0, x1, y0, y1 = _bounds(model, world)
    fig.update_layout(
        shapes=shapes, showlegend=False, margin={"l": 30, "r": 10, "t": 30, "b": 30},
        height=360, plot_bgcolor="white", dragmode="pan",
        xaxis={"range": [x0, x1], "showgrid": False, "zeroline": False},
        yaxis={"range": [y0, y1], "scaleanchor": "x", "showgrid": False, "zeroline": False})
    return fig, index


def _width(t0: float, t1: float) -> float:
    """A bar's width, at least :data:`INSTANT` (an atomic behavior that took no time)."""
    return round(max(t1 - t0, INSTANT), 3)


def _shows(t0: float, t1: float, window: Window | None) -> bool:
    """Whether what is drawn from ``t0`` to ``t1`` (at least :data:`INSTANT` wide) is seen
    in ``window`` (None: the whole run), in part or whole."""
    return window is None or (t0 <= window[1] and max(t1, t0 + INSTANT) >= window[0])


def _kept(items: list[_T], window: Window | None, when: Callable[[_T], tuple[float, float]],
          reach: Callable[[_T], tuple[float, float]]) -> list[_T]:
    """Of a trace's ``items``, in their order, those seen in ``window`` (``when``: from,
    to; all, without a window), and, seen or not, the first (the legend draws the trace's
    swatch like it) and those that reach lowest and highest across the rows (``reach``:
    from, to, in rows): Plotly lays the rows out by how far the traces reach, so they
    stay where the whole run's figure has them, none dropped for having nothing seen."""
    if window is None:
        return items
    ends = {id(items[0]), id(min(items, key=lambda x: reach(x)[0])),
            id(max(items, key=lambda x: reach(x)[1]))}
    return [x for x in items if id(x) in ends or _shows(*when(x), window)]


def _rows(tl: Timeline) -> dict[str, int]:
    """Each device's row, from the bottom (the first device is drawn at the top)."""
    return {device: k for k, device in enumerate(reversed(tl.devices))}


def _across(bar: Bar, i: int) -> tuple[float, float]:
    """Where a bar of the ``i``-th application lies across its row (offset, width): two
    applications blended on a device share its row, a half each."""
    return ((0.0 if i % 2 else -0.4), 0.4) if bar.blended else (-0.4, 0.8)


def _reach(row: dict[str, int], i: int) -> Callable[[Bar], tuple[float, float]]:
    """How far a bar of the ``i``-th application reaches across the rows (from, to)."""
    def reach(bar: Bar) -> tuple[float, float]:
        offset, width = _across(bar, i)
        return row[bar.device] + offset, row[bar.device] + offset + width
    return reach


def timeline_figure(model: Model, window: Window | None = None
                    ) -> tuple[go.Figure, dict[str, list[int]]]:
    """One row per device: the ABs' bars by application (blended ones on half a row,
    dotted), suspensions and holds hatched, releases, cuts and cancels marked; and which
    traces are bars, waits and marks (:func:`_drawn`). With ``window`` (from, to: simulated
    seconds), only what is seen in it, each whole (:func:`_timeline_traces`)."""
    fig = _timeline_layout(model.timeline)
    for trace in _timeline_traces(model, window):
        fig.add_trace(trace)
    return fig, _drawn([trace.meta for trace in fig.data])


def _timeline_traces(model: Model, window: Window | None = None
                     ) -> Iterator[go.Bar | go.Scatter]:
    """The timeline's traces, made one at a time (:func:`write_page` writes each and lets
    it go before the next is made): each application's bars, the waits, the marks. With
    ``window``, only the bars, waits and marks seen in it, each whole (one begun before it
    too), and what keeps the rows and the legend as the whole run's (:func:`_kept`): the
    traces are the whole run's, but for the labels of runs of iterations none of which
    is seen, and a run is labelled by its length in the whole run."""
    return chain(_bars(model.timeline, window), _spans(model, window), _marks(model, window))


def _drawn(metas: list[str]) -> dict[str, list[int]]:
    """Which of the timeline's traces (by their ``meta``) are bars, waits and marks."""
    return {"bars": [k for k, meta in enumerate(metas) if meta == "bars"],
            "spans": [k for k, meta in enumerate(metas) if meta in _SPAN_STYLE],
            "marks": [k for k, meta in enumerate(metas) if meta == "marks"]}


def _timeline_layout(tl: Timeline) -> go.Figure:
    """A figure with no traces yet, laid out as the timeline: a row per device, the run's
    time across."""
    fig = go.Figure()
    fig.update_layout(
        uniformtext={"mode": "hide", "minsize": 8},  # no label shrunk past reading
        barmode="overlay", height=max(200, 60 + 34 * len(tl.devices)),
        margin={"l": 140, "r": 10, "t": 30, "b": 40}, plot_bgcolor="white",
        legend={"orientation": "h", "y": -0.25 if len(tl.devices) > 3 else -0.5},
        xaxis={"title": tl.time_axis(), "range": [0, max(tl.end, 1.0)],
               "showgrid": True, "gridcolor": "#eee"},
        yaxis={"categoryorder": "array", "categoryarray": [_esc(d) for d in tl.devices[::-1]],
               "type": "category", "fixedrange": True},
        dragmode="pan")
    return fig


def _bars(tl: Timeline, window: Window | None = None) -> Iterator[go.Bar]:
    """Each application's bars (a feedback Command's run of iterations labelled once);
    with ``window``, those seen in it (:func:`_kept`)."""
    colours = _colours(tl.apps)
    row = _rows(tl)
    for i, app in enumerate(tl.apps):
        # non-blended first: the legend's swatch is drawn like the first bar
        bars = sorted((b for b in tl.bars if b.app == app), key=lambda b: b.blended)
        if not bars:
            continue
        # a run of a feedback Command's iterations is labelled once (below), not each bar
        repeated = [run for run in runs(b for b in bars if not b.blended) if len(run) > 1]
        in_runs = {id(b) for run in repeated for b in run}
        bars = _kept(bars, window, lambda b: (b.t0, b.t1), _reach(row, i))
        repeated = [r for r in repeated if _shows(r[0].t0, r[-1].t1, window)]
        yield go.Bar(
            name=_esc(app), orientation="h", y=[_esc(b.device) for b in bars],
            base=[b.t0 for b in bars], x=[_width(b.t0, b.t1) for b in bars],
            width=[_across(b, i)[1] for b in bars], offset=[_across(b, i)[0] for b in bars],
            customdata=[b.ab for b in bars],
            text=["" if id(b) in in_runs else _esc(b.command) for b in bars],
            hovertext=[f"AB {b.ab} {_esc(_label(b))}<br>{b.t0:.2f}-{b.t1:.2f} s"
                       + (" (blended)" if b.blended else "") for b in bars],
            hoverinfo="text", textposition="inside", insidetextanchor="start", textangle=0,
            textfont={"size": 10}, marker={"color": colours[app], "pattern": {
                "shape": ["." if b.blended else "" for b in bars], "fgcolor": "white"}},
            meta="bars")
        if repeated:  # over a run's bars, one bar without seams, labelled once; hovers and
            # clicks go through it to the iteration under the pointer
            yield go.Bar(
                name=_esc(app), orientation="h", y=[_esc(r[0].device) for r in repeated],
                base=[r[0].t0 for r in repeated],
                x=[_width(r[0].t0, r[-1].t1) for r in repeated], width=0.8, offset=-0.4,
                text=[f"{_esc(r[0].command)} x{len(r)}" for r in repeated],
                textposition="inside", insidetextanchor="start", textangle=0,
                textfont={"size": 10, "color": ink(colours[app])},
                marker={"color": colours[app]}, hoverinfo="skip", showlegend=False,
                meta="runs")


def _spans(model: Model, window: Window | None = None) -> Iterator[go.Bar]:
    """Suspensions and holds, hatched; with ``window``, those seen in it (:func:`_kept`)."""
    tl = model.timeline
    row = _rows(tl)
    for kind, (shape, colour, what) in _SPAN_STYLE.items():
        spans = [(s, d) for s in tl.spans if s.kind == kind for d in s.devices]
        if not spans:
            continue
        spans = _kept(spans, window, lambda sd: (sd[0].t0, sd[0].t1),
                      lambda sd: (row[sd[1]], row[sd[1]]))
        yield go.Bar(
            name=what, orientation="h", y=[_esc(d) for _, d in spans],
            base=[s.t0 for s, _ in spans], x=[_width(s.t0, s.t1) for s, _ in spans],
            customdata=[model.table[s.line] for s, _ in spans],
            hovertext=[f"{_esc(s.app)}: AB {s.ab} {what} {s.t0:.2f}-{s.t1:.2f} s"
                       + (f" ({_esc(s.reason)})" if s.reason else "") for s, _ in spans],
            hoverinfo="text",
            marker={"color": "rgba(0,0,0,0)", "line": {"width": 1, "color": colour},
                    "pattern": {"shape": shape, "fgcolor": colour, "size": 6}},
            meta=kind)


def _marks(model: Model, window: Window | None = None) -> Iterator[go.Scatter]:
    """Releases, cuts and cancels, marked; with ``window``, those seen in it
    (:func:`_kept`)."""
    tl = model.timeline
    row = _rows(tl)
    for kind, (symbol, colour, what) in _MARK_STYLE.items():
        marks = [(m, d) for m in tl.marks if m.kind == kind for d in m.devices
                 if d in tl.devices]
        if not marks:
            continue
        marks = _kept(marks, window, lambda md: (md[0].t, md[0].t),
                      lambda md: (row[md[1]], row[md[1]]))
        yield go.Scatter(
            name=what, x=[m.t for m, _ in marks], y=[_esc(d) for _, d in marks],
            customdata=[model.table[m.line] for m, _ in marks], mode="markers",
            marker={"symbol": symbol, "size": 12, "color": colour, "line": {"width": 2,
                                                                            "color": colour}},
            hovertext=[f"{_esc(m.app)}: {what}" + (f" (AB {m.ab})" if m.ab is not None else "")
                       + f" at {m.t:.2f} s" for m, _ in marks],
            hoverinfo="text", meta="marks")


def page(model: Model, world: WorldMap | None, title: str, sounds: str = "") -> str:
    """The whole self-contained page (Plotly's JavaScript inlined); ``sounds``: the
    utterances' audio elements (``prima show --audio``), if any."""
    out = io.StringIO()
    write_page(model, world, title, out, sounds=sounds)
    return out.getvalue()


def _write_json(value: Any, out: TextIO) -> None:
    """``value`` as :func:`~prima.escape.script_json` writes it, each long array a piece at
    a time: a long run's trace of bars is never held as one JSON text."""
    if isinstance(value, dict) and all(isinstance(key, str) for key in value):
        out.write("{")
        for k, (key, item) in enumerate(value.items()):
            out.write(("," if k else "") + script_json(key) + ":")
            _write_json(item, out)
        out.write("}")
    elif isinstance(value, (list, tuple)):
        _write_array(value, out)
    else:
        out.write(script_json(value))


def _write_array(items: Iterable[Any], out: TextIO) -> None:
    """A JSON array of ``items`` as :func:`~prima.escape.script_json` writes it,
    :data:`_PIECE` items at a time."""
    items = iter(items)
    out.write("[")
    comma = ""
    while piece := list(islice(items, _PIECE)):
        out.write(comma + script_json(piece)[1:-1])
        comma = ","
    out.write("]")


def _write_poses(poses: Iterable[tuple[float, Pose]], out: TextIO) -> None:
    """Pose samples as the player reads them, ``[[t, x, y, heading], ...]``."""
    _write_array(([t, *pose] for t, pose in poses), out)


def _write_figure(div_id: str, traces: Iterable[go.Bar | go.Scatter], fig: go.Figure,
                  out: TextIO) -> list[str]:
    """The div of a figure of ``traces`` laid out as ``fig`` (its traces are not drawn)
    and the script that draws it, as ``plotly.io.to_html`` writes them (without Plotly's
    JavaScript), a piece at a time: each trace is written and let go before the next one
    is made, and a long run's timeline is never held as one JSON text (Plotly's own
    writer holds it three times over). Returns each trace's ``meta``."""
    out.write(f'<div style="height:100%; width:100%;"><div id="{div_id}" '
              'class="plotly-graph-div" style="height:100%; width:100%;"></div><script>'
              'window.PLOTLYENV=window.PLOTLYENV || {};'
              f'if (document.getElementById("{div_id}")) {{Plotly.newPlot("{div_id}",[')
    metas: list[str] = []
    for k, trace in enumerate(traces):
        metas.append(trace.meta)
        out.write("," if k else "")
        _write_json(trace.to_plotly_json(), out)
        del trace  # (not held here while the next one is made)
    layout = go.Figure(layout=fig.layout).to_dict()["layout"]  # with its template
    out.write(f"],{script_json(layout)},{script_json({**_CONFIG, 'responsive': True})})}};"
              "</script></div>")
    return metas


def write_page(model: Model, world: WorldMap | None, title: str, out: TextIO,
               spool: TextIO | None = None, sounds: str = "") -> None:
    """Write the page to ``out`` piece by piece; the table's rows are ``model.rows``, or
    the JSON :func:`~prima.show._model.build` spooled (copied in chunks, never read
    whole); ``sounds``: the utterances' audio elements (``prima show --audio``), if
    any."""
    map_fig, who = map_figure(model, world)
    map_html = pio.to_html(map_fig, include_plotlyjs=True, full_html=False, div_id="map",
                           config=_CONFIG)
    del map_fig
    player = drawing() + packaged("prima.show", "player.js").read_text(encoding="utf-8")
    css = style()
    speeds = "".join(f'<option value="{s}"{" selected" if s == "1" else ""}>{s}x</option>'
                     for s in ("0.5", "1", "2", "4", "8", "16", "32"))
    name = markup(title)
    out.write(f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>prima show: {name}</title>
<style>
{css}</style>
</head>
<body>
<header>
<h1>{name}</h1>
<button id="play" type="button">Play</button>
<label>speed <select id="speed">{speeds}</select></label>
<input id="scrub" type="range" min="0" max="{model.timeline.end}" step="0.01" value="0">
<span id="clock">0.00 s</span>
{_SOUND_TOGGLE if sounds else ""}
</header>
<main>
<section id="top">
<div id="map-box">""")
    out.write(map_html)
    del map_html
    out.write("""</div>
<aside id="details"><p class="hint">Click a bar of the timeline or a line of the trace
to jump there and see why the mediator decided it.</p></aside>
</section>
<section id="timeline-box">""")
    traces = _drawn(_write_figure("timeline", _timeline_traces(model),
                                  _timeline_layout(model.timeline), out))
    out.write("""<div id="playhead"></div></section>
<section id="table-box"><table id="trace"><thead><tr><th>No.</th><th>time</th><th>kind</th>
<th>app</th><th>AB</th><th>what</th><th>reason</th></tr></thead><tbody></tbody></table></section>
<div id="sounds" hidden>""")
    out.write(sounds)
    out.write("""</div>
</main>
<script>
const PRIMA_SHOW = {"end":""")
    out.write(script_json(model.timeline.end) + ',"rows":[')
    if spool is None:
        out.write(",".join(script_json(row) for row in model.rows))
    else:
        spool.seek(0)
        shutil.copyfileobj(spool, out)
    out.write('],"robot":')
    _write_poses(model.robot, out)
    out.write(',"user":')
    _write_poses(model.user, out)
    out.write(f',"bubbles":{script_json([[b.who, b.start, b.end, b.text] for b in model.bubbles])},'
              '"abs":')
    for piece in model.ab_json():
        out.write(piece)
    rest = {"robotTrace": who["robot"], "userTrace": who["user"], "traces": traces,
            "colours": _colours(model.timeline.apps)}
    out.write("," + script_json(rest)[1:] + f""";
</script>
<script>
{player}</script>
</body>
</html>
""")
