"""The live page: ``prima show``'s drawing (its map, timeline, bubbles and trace table,
:mod:`prima.show`'s ``draw.js`` and style), with what the author acts with (disabled until
the page has the session: ``live.js`` enables what can act)."""

from __future__ import annotations

import functools

from prima.escape import markup
from prima.shipped import packaged

__all__ = ["page", "plotly_script"]


@functools.cache
def plotly_script() -> str:
    """Plotly's script, from the installed Plotly (the page fetches nothing elsewhere)."""
    from plotly.offline import get_plotlyjs

    return str(get_plotlyjs())


@functools.cache
def _assets() -> tuple[str, str]:
    from prima.show import drawing, style

    script = drawing() + packaged("prima.live", "live.js").read_text(encoding="utf-8")
    css = style() + packaged("prima.live", "live.css").read_text(encoding="utf-8")
    return script, css


_SPEEDS = ("0.25", "0.5", "1", "2", "4", "8")


def page(title: str) -> str:
    """The page (all it shows comes over its WebSocket)."""
    script, css = _assets()
    name = markup(title)
    steps = "".join(f'<option value="{s}"{" selected" if s == "0.5" else ""}>{s} s</option>'
                    for s in ("0.1", "0.5", "1", "5"))
    speeds = "".join(f'<option value="{s}"{" selected" if s == "1" else ""}>{s}x</option>'
                     for s in _SPEEDS)
    return f"""<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<link rel="icon" href="data:,">
<title>prima live: {name}</title>
<style>
{css}</style>
</head>
<body>
<header>
<h1>{name}</h1>
<button id="play" type="button" title="play or pause simulated time (space)" disabled>Play</button>
<button id="step" type="button" title="paused: let this much simulated time go by"
 disabled>Step</button>
<select id="step-by" title="how far a step goes" disabled>{steps}</select>
<label>speed <select id="speed" disabled>{speeds}</select></label>
<span id="clock">0.00 s</span>
<span id="state"></span>
<span class="grow"></span>
<button id="save" type="button" title="keep what you did as a scenario" disabled>Save</button>
<a id="layout" href="/foxglove-layout.json" hidden>Foxglove layout</a>
</header>
<div id="banner" hidden></div>
<main>
<section id="top">
<div id="map-box"><div id="map"></div>
<p class="hint">Drag the user (orange) to walk; click the robot to touch it.</p></div>
<aside id="side">
<div id="asking" hidden><span>The robot asks:</span> <q id="prompt"></q>
<div id="answers"></div></div>
<form id="say-form" autocomplete="off">
<input id="say" type="text" maxlength="10000" placeholder="Say something to the robot (Enter)"
 disabled>
<button id="mic" type="button" title="speak (this browser's speech recognition)" hidden
 disabled>Mic</button>
<button type="submit" disabled>Say</button>
</form>
<div id="acts">
<button id="touch" type="button" disabled>Touch</button>
<button id="follow" type="button" disabled>Follow</button>
<button id="stop" type="button" disabled>Stop</button>
</div>
<form id="message-form" autocomplete="off">
<input id="sender" type="text" list="senders" placeholder="from" maxlength="200" disabled>
<input id="message" type="text" placeholder="a network message" maxlength="10000" disabled>
<button type="submit" disabled>Send</button>
<datalist id="senders"></datalist>
</form>
<p id="notice" role="status"></p>
<h2>Words</h2>
<ol id="words"></ol>
<h2>Findings <span id="waiting"></span></h2>
<ol id="findings"></ol>
</aside>
</section>
<section id="timeline-box"><div id="timeline"></div><div id="playhead"></div>
<button id="follow-time" type="button" hidden
 title="the timeline follows the run's last 90 s again (or double-click it)">Back to live</button>
</section>
<section id="table-box"><table id="trace"><thead><tr><th>No.</th><th>time</th><th>kind</th>
<th>app</th><th>AB</th><th>what</th><th>reason</th></tr></thead><tbody></tbody></table></section>
</main>
<script src="/plotly.js"></script>
<script>
{script}</script>
</body>
</html>
"""
